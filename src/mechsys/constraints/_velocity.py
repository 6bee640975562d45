r"""Velocity (nonholonomic) constraints in the form :math:`A(q, t) \dot q + b(q, t) = 0`.

A velocity constraint's equations :math:`\psi(q, \dot q, t) = 0` are ordinary SymPy expressions of the
coordinates ``q``, their rates ``qd`` (the symbols ``x2_d``, ``e12_d``, ...) and time. When they
are linear in the rates they split into

.. math::

    \psi = A(q, t)\,\dot q + b(q, t), \qquad A = \psi_{\dot q}, \quad b = \psi|_{\dot q = 0},

and their time derivative, the acceleration-level rows used by path systems (and, later, by
free motion with velocity constraints), is

.. math::

    \dot\psi = A\,\ddot q + \rho, \qquad \rho = \psi_q\,\dot q + \psi_t .

:func:`velocity_rows` computes ``A``, ``b`` and ``rho`` once, symbolically; it is shared by
the path systems (``analyses/_path.py``) and the conformance checks of the rolling
constraints, so both test the same derivatives.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .._errors import ModelError
from .._symbols import T


@dataclass(frozen=True)
class VelocityRows:
    r"""The rows of velocity equations :math:`\psi = A \dot q + b` (``k`` equations, ``n`` rates).

    ``A`` (k, n) and ``b`` (k, 1) are SymPy matrices, ``rho`` (k, 1) the velocity-dependent
    part of :math:`d \psi / dt = A \ddot q + \rho`; ``linear`` says whether ``A`` is free of the rates
    (when it is not, ``A`` is the Jacobian ``psi_qd`` at the current rates and ``b`` the rest
    at zero rates, which no longer add up to ``psi``)."""

    A: sp.Matrix
    b: sp.Matrix
    rho: sp.Matrix
    linear: bool


def velocity_rows(equations, q, qd, rho: bool = True) -> VelocityRows:
    r"""``A = psi_qd``, ``b = psi(qd = 0)`` and :math:`\rho = \psi_q \dot q + \psi_t` of the velocity
    equations ``psi`` (a list of SymPy expressions) with coordinates ``q`` and rates ``qd``
    (lists of symbols, in the same order). ``rho=False`` leaves ``rho`` empty (its
    derivatives are the expensive part).

    Example::

        rows = velocity_rows([x_d - r * th_d], [x, th], [x_d, th_d])
        rows.A   # Matrix([[1, -r]])
    """
    psi = sp.Matrix(list(equations))
    A = psi.jacobian(list(qd)) if len(psi) else sp.zeros(0, len(qd))
    zero = {v: 0 for v in qd}
    b = psi.xreplace(zero) if len(psi) else sp.zeros(0, 1)
    rows = []
    for e in (psi if rho else ()):
        free = e.free_symbols
        r = sp.diff(e, T) if T in free else sp.S.Zero
        for a, v in zip(q, qd):
            if a in free:     # (each equation only against the coordinates it contains)
                r += sp.diff(e, a) * v
        rows.append(r)
    qd_set = set(qd)
    linear = all(not (x.free_symbols & qd_set) for x in A)
    return VelocityRows(A, b, sp.Matrix(rows) if rows else sp.zeros(0, 1), linear)


def linear_velocity_form(constraint, model) -> tuple[sp.Matrix, sp.Matrix]:
    r"""``(A, b)`` with :math:`\psi = A(q, t) \dot q + b(q, t)` for the equations of a velocity
    constraint on ``model``; the columns of ``A`` follow the model's coordinates (the order of
    ``m.location(ms.All)`` and of a solution's ``q``). Raises :class:`ModelError` when the
    equations are not linear in the rates.

    Example::

        A, b = ms.linear_velocity_form(roll, m)
    """
    rates = model.velocity_symbols()
    q = list(model._coordinate_symbols())
    qd = [rates[s] for s in q]
    rows = velocity_rows(constraint.equations(model.space), q, qd, rho=False)
    if not rows.linear:
        raise ModelError(f"{constraint.label()}: its equations are not linear in the "
                         "velocities, so they have no form A(q, t) qd + b(q, t) = 0")
    return rows.A, rows.b
