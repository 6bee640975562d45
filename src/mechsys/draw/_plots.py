r"""Plots of outputs over a solution: time histories and phase plots.

An *output* is any of:

* a SymPy expression or column (evaluated by :meth:`Solution.eval`; a column gives one
  curve per component, labelled ``[x]``, ``[y]``, ``[z]``);
* a coordinate name (``"crank.th"``, ``"x3"``) or ``"t"``;
* a callable ``f(solution) -> (N,)`` or ``(N, k)`` array (e.g.
  ``lambda s: s.velocity(p)[:, 0]``);
* an array of ``N`` values.

Outputs are passed as one output, a list, or a ``{label: output}`` dict.

Axis labels carry the unit of what they show when mechsys knows it: time and position
coordinates in the model's declared units (``m.set_units(length="mm", time="s")``), planar
angles in rad (``crank.th [rad]``, ``t [s]``). An explicit ``xlabel``/dict label is kept
as given, with the unit added when known.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import sympy as sp

from .._errors import ModelError
from ._eval import as_solution

_COMPONENTS = ("x", "y", "z")


def _label_of(spec) -> str:
    if isinstance(spec, str):
        return spec
    if isinstance(spec, (sp.Basic, sp.MatrixBase)):
        s = str(list(spec) if isinstance(spec, sp.MatrixBase) else spec)
        return s if len(s) <= 48 else s[:45] + "..."
    name = getattr(spec, "__name__", None)
    if name and name != "<lambda>":
        return name
    return "output"


def _values(sol, spec, label: str) -> list[tuple[str, np.ndarray]]:
    N = len(sol.t)
    if isinstance(spec, str):
        if spec == "t":
            v = np.asarray(sol.t, dtype=float)
        else:
            v = np.asarray(sol[spec], dtype=float)
    elif isinstance(spec, (sp.Basic, sp.MatrixBase)):
        v = np.asarray(sol.eval(spec), dtype=float)
    elif callable(spec):
        v = np.asarray(spec(sol), dtype=float)
    else:
        v = np.asarray(spec, dtype=float)
    if v.ndim == 0 or v.shape[0] != N:
        n = v.shape[0] if v.ndim else 1
        raise ModelError(f"output {label!r} has {n} values for {N} time points")
    v = v.reshape(N, -1)
    if v.shape[1] == 1:
        return [(label, v[:, 0])]
    names = _COMPONENTS if v.shape[1] <= 3 else [str(i) for i in range(v.shape[1])]
    return [(f"{label} [{names[i]}]", v[:, i]) for i in range(v.shape[1])]


def _unit(sol, spec) -> str | None:
    """The unit of a time or coordinate output (``"t"``, ``"crank.th"``): from the model's
    declared units, ``rad`` for a planar angle; ``None`` when not known (an expression, a
    callable, an array, a model variable, or no declared unit)."""
    from ..results._tables import _translational, unit_text

    units = getattr(sol.model, "units", None)
    rate = 0
    if isinstance(spec, sp.Symbol):
        # a coordinate's symbol, or its velocity or acceleration symbol (``m.omega(b)`` of a
        # planar body is ``th3_d``): the coordinate's unit per time unit
        lay = sol.system.layout
        for k, syms in enumerate((lay.q_symbols, lay.qd_symbols, lay.qdd_symbols)):
            if spec in syms:
                spec, rate = lay.q_names[list(syms).index(spec)], k
                break
        else:
            return None
    if not isinstance(spec, str):
        return None
    if spec == "t":
        return unit_text((0, 0, 1), units)
    try:
        j = sol.system.layout.index(spec)
    except (KeyError, ValueError, IndexError, ModelError):
        return None
    dim = sol.model.space.dim
    kind = _translational(sol.system)[j]
    if kind is None or (not kind and dim != 2):   # a 3D Euler parameter has no unit
        return None
    return unit_text((1 if kind else 0, 0, -rate), units, angle=not kind)


def _with_unit(label: str, unit: str | None) -> str:
    return f"{label} [{unit}]" if unit and not label.endswith("]") else label


def _outputs(outputs) -> list[tuple[str, object]]:
    if isinstance(outputs, Mapping):
        return [(str(k), v) for k, v in outputs.items()]
    if isinstance(outputs, (list, tuple)):
        return [(_label_of(o), o) for o in outputs]
    return [(_label_of(outputs), outputs)]


def plot(solution, outputs, x=None, ax=None, overlay=False, title=None, xlabel=None,
         figsize=None, grid=True):
    """Time histories of outputs with labelled axes; returns the matplotlib Figure.

    ``x``: the abscissa (default time ``t``), any output (e.g. the crank angle).
    ``overlay``: all curves in one axes (default: one axes per output, sharing x).
    """
    import matplotlib.pyplot as plt

    sol = as_solution(solution)
    specs = _outputs(outputs)
    if not specs:
        raise ModelError("plot: no outputs given")
    if x is None:
        xv, xl = np.asarray(sol.t, dtype=float), "t"
    else:
        (xl, xv), *rest = _values(sol, x, _label_of(x))
        if rest:
            raise ModelError("plot: x must be a scalar output")
    xl = _with_unit(xlabel or xl, _unit(sol, "t" if x is None else x))
    groups = [_values(sol, s, lab) for lab, s in specs]
    n = 1 if overlay or ax is not None else len(groups)
    if ax is not None:
        fig, axes = ax.figure, [ax]
    else:
        if figsize is None:
            figsize = (7.0, min(2.4 * n + 0.8, 10.0))
        fig, axes = plt.subplots(n, 1, figsize=figsize, sharex=True, squeeze=False)
        axes = list(axes[:, 0])
    for i, group in enumerate(groups):
        a = axes[0 if n == 1 else i]
        for lab, v in group:
            a.plot(xv, v, label=lab)
        if n > 1 or len(groups) == 1:
            a.set_ylabel(_with_unit(specs[i][0], _unit(sol, specs[i][1])))
        if len(group) > 1 or (n == 1 and len(groups) > 1):
            a.legend(fontsize=8, loc="best")
        if grid:
            a.grid(True, alpha=0.3)
    axes[-1].set_xlabel(xl)
    if title:
        (axes[0].set_title if n == 1 else fig.suptitle)(title)
    if ax is None:
        fig.tight_layout()
    return fig


def phase_plot(solution, x, y, ax=None, arrows=6, title=None, figsize=(5.5, 5.0), grid=True,
               xlabel=None, ylabel=None):
    """``y`` against ``x`` (outputs, e.g. a coordinate and its velocity), with the start
    marked and arrows showing the direction of motion; returns the Figure. ``xlabel``,
    ``ylabel``: the axis labels (default the outputs' names, with their units when known)."""
    import matplotlib.pyplot as plt

    sol = as_solution(solution)
    (xl, xv), *r1 = _values(sol, x, _label_of(x))
    (yl, yv), *r2 = _values(sol, y, _label_of(y))
    if r1 or r2:
        raise ModelError("phase_plot: x and y must be scalar outputs")
    if ax is None:
        fig, ax = plt.subplots(figsize=figsize)
    else:
        fig = ax.figure
    (line,) = ax.plot(xv, yv)
    ax.plot(xv[:1], yv[:1], "o", color=line.get_color(), label="start")
    n = len(xv)
    if arrows and n > 2:
        for k in np.linspace(0, n - 2, int(arrows) + 2)[1:-1].astype(int):
            ax.annotate("", xy=(xv[k + 1], yv[k + 1]), xytext=(xv[k], yv[k]),
                        arrowprops=dict(arrowstyle="->", color=line.get_color(), lw=1.5))
    ax.set_xlabel(_with_unit(xlabel or xl, _unit(sol, x)))
    ax.set_ylabel(_with_unit(ylabel or yl, _unit(sol, y)))
    if title:
        ax.set_title(title)
    if grid:
        ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    return fig
