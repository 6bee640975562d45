r"""The design loop in a notebook: sliders for a model's parameters that re-solve the model and
redraw its picture on every change (ipywidgets, optional).

Each change sets the parameter (``m.set_parameters``), solves the model over the given times
starting from the previous solution's first configuration (so that the mechanism stays on
the assembly branch it was on), and redraws. A change the mechanism cannot follow (a
four-bar whose links no longer close) keeps the last good picture and says why, in the
status line; it never raises inside the notebook's event loop.

Example (a four-bar's coupler curve following its link lengths)::

    m = ms.Model2D()
    a = m.parameter("crank", 1.0); b = m.parameter("coupler", 4.0)
    ...                                   # bodies and constraints using a and b
    ex = ms.draw.explore(m, t=np.linspace(0, 2 * np.pi, 73),
                         parameters={"crank": (0.5, 1.5), "coupler": (3.0, 5.0)},
                         graphics=[ms.draw.LocusPlot(coupler_point)])
    ex                                    # the sliders and the picture, in Jupyter
    ex.set(crank=1.2)                     # the same from code
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping

import numpy as np

from .._errors import MechError, ModelError


def _widgets():
    try:
        import ipywidgets
    except ImportError:
        raise ModelError("explore needs ipywidgets: pip install ipywidgets "
                         "(or pip install mechsys[docs])") from None
    return ipywidgets


class Explorer:
    """Sliders for parameters of ``model``; see :func:`explore`.

    Attributes: ``sliders`` (``{name: FloatSlider}``), ``widget`` (the whole panel),
    ``solution`` and ``figure`` (the last good ones), ``message`` (the status line),
    ``redraws`` (how many pictures were drawn)."""

    def __init__(self, model, t, parameters=None, graphics=None, solution: str = "acceleration",
                 draw: Callable | None = None, continuous_update: bool = False, steps: int = 100):
        w = _widgets()
        self.model = model
        self.t = np.atleast_1d(np.asarray(t, dtype=float))
        self.kind = solution
        self.graphics = list(graphics or [])
        self._draw = draw
        self.redraws = 0
        self.solution = None
        self.figure = None
        self.message = ""
        ranges = self._ranges(parameters, steps)
        self.sliders = {}
        for name, (lo, hi, step) in ranges.items():
            s = w.FloatSlider(value=model.parameters[name], min=lo, max=hi, step=step,
                              description=name, continuous_update=continuous_update,
                              readout_format=".4g", style={"description_width": "initial"})
            s.observe(self._changed, names="value")
            self.sliders[name] = s
        self.status = w.HTML()
        self.output = w.Output()
        self.widget = w.VBox([*self.sliders.values(), self.status, self.output])
        self._update()
        if self.solution is None:
            raise MechError(f"explore: the model cannot be solved at its present parameter "
                            f"values: {self.message}")

    def _ranges(self, parameters, steps):
        have = self.model.parameters
        if not have:
            raise ModelError("explore: the model has no parameters; declare the values to vary "
                             "with m.parameter(name, value)")
        if parameters is None:  # every parameter, from half to one and a half times its value
            parameters = {n: (0.5 * v, 1.5 * v) if v else (-1.0, 1.0) for n, v in have.items()}
        if not isinstance(parameters, Mapping) or not parameters:
            raise ModelError("explore: parameters must be a mapping {name: (min, max)} or "
                             "{name: (min, max, step)}")
        out = {}
        for name, rng in parameters.items():
            key = getattr(name, "name", name)
            if key not in have:
                raise ModelError(f"explore: {key!r} is not a parameter of the model; its "
                                 f"parameters are {sorted(have)}")
            try:
                vals = [float(x) for x in rng]
            except (TypeError, ValueError):
                raise ModelError(f"explore: the range of {key!r} must be (min, max) or "
                                 f"(min, max, step), got {rng!r}") from None
            if len(vals) not in (2, 3) or not np.all(np.isfinite(vals)):
                raise ModelError(f"explore: the range of {key!r} must be two or three finite "
                                 f"numbers, got {rng!r}")
            lo, hi = vals[:2]
            step = vals[2] if len(vals) == 3 else (hi - lo) / steps
            if not lo < hi or step <= 0:
                raise ModelError(f"explore: the range of {key!r} needs min < max and a positive "
                                 f"step, got {rng!r}")
            if not lo <= have[key] <= hi:
                raise ModelError(f"explore: the value of {key!r} ({have[key]:g}) is outside its "
                                 f"range [{lo:g}, {hi:g}]")
            out[key] = (lo, hi, step)
        return out

    # -- the loop -------------------------------------------------------------------------
    def set(self, **values) -> Explorer:
        """Move sliders from code (each move re-solves and redraws, as a drag does)."""
        for name in values:
            if name not in self.sliders:
                raise ModelError(f"explore.set: no slider {name!r}; the sliders are "
                                 f"{list(self.sliders)}")
        self._held = True  # several sliders moved together: one solve, one picture
        try:
            for name, v in values.items():
                self.sliders[name].value = float(v)
        finally:
            self._held = False
        self._update()
        return self

    _held = False

    def _changed(self, change) -> None:
        if not self._held:
            self._update()

    def _update(self) -> None:
        values = {n: s.value for n, s in self.sliders.items()}
        old = self.model.parameters
        guess = self.solution.state(0) if self.solution is not None else None
        start = time.perf_counter()
        try:
            self.model.set_parameters(**values)
            sol = self.model.solve(self.t, solution=self.kind, guess=guess)
        except MechError as exc:  # keep the last good picture and say why
            self.model.set_parameters(**{n: old[n] for n in values})
            self.message = f"cannot solve at {_fmt(values)}: {exc}"
            self.status.value = f"<span style='color:#b00'>{_escape(self.message)}</span>"
            return
        took = time.perf_counter() - start
        self.solution = sol
        self._redraw()
        self.message = f"solved {len(sol.t)} points in {1e3 * took:.0f} ms at {_fmt(values)}"
        self.status.value = _escape(self.message)

    def _redraw(self) -> None:
        import matplotlib.pyplot as plt

        from . import snapshot

        if self.figure is not None:
            plt.close(self.figure)
        fig = self._draw(self.solution) if self._draw is not None else \
            snapshot(self.solution, graphics=self.graphics or None)
        self.figure = fig
        self.redraws += 1
        try:
            from IPython import get_ipython
            from IPython.display import clear_output, display
        except ImportError:  # pragma: no cover - ipywidgets brings IPython
            return
        if getattr(get_ipython(), "kernel", None) is None:  # no notebook: nothing to show in
            return
        with self.output:
            clear_output(wait=True)
            display(fig)

    def _repr_mimebundle_(self, **kw):
        return self.widget._repr_mimebundle_(**kw)

    def __repr__(self) -> str:
        return f"<Explorer of {list(self.sliders)}: {self.message}>"


def _fmt(values) -> str:
    return ", ".join(f"{k}={v:.4g}" for k, v in values.items())


def _escape(text: str) -> str:
    import html

    return html.escape(text)


def explore(model, t, parameters=None, graphics=None, solution: str = "acceleration",
            draw: Callable | None = None, continuous_update: bool = False) -> Explorer:
    """Sliders for ``parameters`` of ``model`` (``{name: (min, max)}`` or ``(min, max,
    step)``; default every parameter from half to one and a half times its value) that set
    the parameter, solve the model at times ``t`` (continuing from the last solution's first
    configuration, to stay on its assembly branch) and redraw: the snapshot at the first time
    with ``graphics`` (e.g. a :class:`LocusPlot` of a coupler point draws its curve), or
    ``draw(solution)`` returning a matplotlib figure. ``continuous_update``: re-solve while a
    slider is dragged (default: when it is released). Needs ipywidgets. Returns an
    :class:`Explorer`, which shows itself in Jupyter."""
    return Explorer(model, t, parameters=parameters, graphics=graphics, solution=solution,
                    draw=draw, continuous_update=continuous_update)
