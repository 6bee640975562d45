"""A small text progress bar for long renders, written to stderr."""

from __future__ import annotations

import sys
import time


class Progress:
    """``Progress(total, label, enabled)``; ``update(done)``; ``close()``.

    ``enabled=None`` turns it on only for long jobs (``total >= 60``) on a terminal.
    """

    def __init__(self, total: int, label: str = "", enabled=None, stream=None, width: int = 30,
                 unit: str = "frames"):
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", lambda: False)
            enabled = total >= 60 and bool(isatty())
        self.enabled = bool(enabled)
        self.total, self.label, self.width = max(int(total), 1), label, width
        self.unit = unit  # "" shows a percentage instead of "done/total unit"
        self.start = time.monotonic()
        self._last = -1

    def update(self, done: int) -> None:
        if not self.enabled:
            return
        filled = int(self.width * done / self.total)
        if filled == self._last and done < self.total:
            return
        self._last = filled
        bar = "#" * filled + "." * (self.width - filled)
        el = time.monotonic() - self.start
        count = f"{done}/{self.total} {self.unit}" if self.unit else f"{100 * done // self.total:3d} %"
        self.stream.write(f"\r{self.label} [{bar}] {count} {el:5.1f} s")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()
