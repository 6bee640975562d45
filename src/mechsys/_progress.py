"""Progress bars (tqdm) for long runs: sweeps, free-motion runs, renders, ``mechsys run``.

:class:`Progress` is a thin wrapper over ``tqdm.auto`` (a widget in Jupyter, a text bar with
rate and ETA on a terminal), with the library's rule for when a bar appears: ``enabled=True``
always, ``False`` never, ``None`` only for jobs of ``min_total`` units or more written to a
terminal. ``delay`` (seconds) shows the bar only once a run has taken that long, so short
runs print nothing.

The solvers never call it per point or per step: the compiled loops run in chunks and the
bar is advanced between them (decision 0039), so a bar costs what a run without one costs.
"""

from __future__ import annotations

import sys
import time


class Progress:
    """``Progress(total, label, enabled)``; ``update(done)`` (the count so far, not an
    increment); ``close()``."""

    def __init__(self, total: int, label: str = "", enabled=None, stream=None,
                 unit: str = "frames", delay: float = 0.0, min_total: int = 60):
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", lambda: False)
            enabled = total >= min_total and bool(isatty())
        self.enabled = bool(enabled)
        self.total, self.label, self.unit = max(int(total), 1), label, unit
        self.start = time.monotonic()
        self.done = 0
        self._bar = None
        if self.enabled:
            from tqdm.auto import tqdm

            # unit "": a percentage (the free-motion runs count permille of the time span)
            fmt = None if unit else "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]"
            self._bar = tqdm(total=self.total, desc=label, unit=unit or "it", file=self.stream,
                             delay=delay, bar_format=fmt, dynamic_ncols=True, leave=True)

    def update(self, done: int) -> None:
        if self._bar is None:
            return
        done = min(int(done), self.total)
        if done > self.done:
            self._bar.update(done - self.done)
            self.done = done

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None





def check_progress(progress, where: str) -> bool:
    """Whether ``progress`` is a callable; :class:`~mechsys.ModelError` naming ``where`` when
    it is neither that nor ``True``/``False``/``None``."""
    if progress is None or isinstance(progress, bool) or type(progress).__name__ == "bool_":
        return False
    if callable(progress):
        return True
    from ._errors import ModelError

    raise ModelError(f"{where}: progress must be True, False, None or a callable "
                     f"progress(done, total), got {progress!r}")


def reporter(progress, total, label: str, unit: str, where: str, delay: float = 0.0,
             min_total: int = 60, steps: int | None = None):
    """``(report, close)`` for a run's ``progress`` argument: ``report(done)`` advances it,
    ``close()`` ends it. ``progress``: ``True``/``False``/``None`` (a :class:`Progress` bar on
    stderr; ``None``: only on a terminal) or a callable ``progress(done, total)``, called at
    the same moments (between the compiled loops' chunks). Anything else raises
    :class:`~mechsys.ModelError` naming ``where``. A callable may raise ``KeyboardInterrupt``
    to stop the run: the run ends as after Ctrl-C. ``steps``: the bar counts ``steps`` units
    for ``total`` (a free-motion run: permille of its time span), default ``total``."""
    if check_progress(progress, where):
        def report(done):
            progress(done, total)

        return report, (lambda: None)
    bar = Progress(total if steps is None else steps, label, enabled=progress, unit=unit,
                   delay=delay, min_total=min_total)
    if not bar.enabled:
        return None, bar.close
    if steps is None:
        return bar.update, bar.close
    factor = steps / (total or 1.0)
    return (lambda done: bar.update(int(done * factor))), bar.close
__all__ = ["Progress", "check_progress", "reporter"]
