r"""Drivers (and load histories) from tabulated or measured data.

``tabulated(times, values)`` is the cubic interpolating spline of the table
(:func:`~mechsys.SplineFit` with ``knots=times``) as a SymPy expression of the time ``T``
(or of any other variable): a ``Piecewise`` of cubics that the model differentiates
exactly, so a driver made from it has a velocity ``s'(T)`` and an acceleration ``s''(T)``
consistent with its position (C2: continuous through the knots)::

    RotationLock1(crank, tabulated(t_meas, angle_meas))
    RelativeX1(slider.point(0), tabulated(t, x, end_conditions=((v0,), (v1,))))
    Force(point, (1, 0), tabulated(t, F))

Outside ``[times[0], times[-1]]`` the end cubics continue (or a ``"periodic"`` table
repeats); give a table that covers the times you solve.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._errors import ModelError
from .._symbols import T
from ._curves import SplineFunction


def tabulated(times, values, variable=T, end_conditions="natural") -> sp.Expr:
    """The cubic spline through ``(times[i], values[i])`` as an expression of ``variable``
    (default the time ``T``). ``end_conditions``: ``"natural"`` (zero second derivative at
    the ends, the default), ``"closed"``, ``"periodic"`` (the table repeats with period
    ``times[-1] - times[0]``) or the two end slopes ``(v0, v1)`` (a clamped spline: give the
    measured start and end velocities). ``times`` strictly increasing, one value each.

    Example::

        t = [0, 0.5, 1.0, 1.5, 2.0]
        x = [0, 0.2, 0.9, 1.2, 1.25]
        m.add(ms.RelativeX1(slider.point(0), ms.tabulated(t, x)), name="measured drive")
    """
    try:
        t = np.asarray(times, dtype=float)
        y = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"tabulated: times and values must be numbers, got {times!r} and "
                         f"{values!r}") from None
    if t.ndim != 1 or y.ndim != 1 or t.shape != y.shape:
        raise ModelError(f"tabulated: times and values must be 1-D and of equal length, got "
                         f"shapes {t.shape} and {y.shape}")
    var = sp.sympify(variable)
    if not isinstance(var, sp.Expr) or var.is_number:
        raise ModelError(f"tabulated: variable must be a symbol or expression (T), got {variable!r}")
    ends = end_conditions
    if not isinstance(ends, str):
        try:
            ends = np.asarray(end_conditions, dtype=float).reshape(2, 1).tolist()
        except (TypeError, ValueError):
            raise ModelError(f"tabulated: end_conditions must be 'natural', 'closed', "
                             f"'periodic' or two end slopes (v0, v1), got {end_conditions!r}") from None
    spline = SplineFunction(y, ends, knots=t)
    return spline(var)


__all__ = ["tabulated"]
