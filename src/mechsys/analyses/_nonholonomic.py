r"""Velocity (nonholonomic) constraints in free motion (issue 36 item 1, decision 0053).

A free system whose model holds velocity constraints ``psi(q, qd, t) = 0`` linear in the
rates, :math:`\psi = A(q, t)\,\dot q + b(q, t)` (the rolling contacts, a user ``Constraint``
of velocity expressions), moves by

.. math::

    \begin{bmatrix} M & \Phi_q^T & A^T \\ \Phi_q & 0 & 0 \\ A & 0 & 0 \end{bmatrix}
    \begin{bmatrix} \ddot q \\ \lambda \\ \mu \end{bmatrix} =
    \begin{bmatrix} Q + Q_v \\ \gamma \\ -\rho \end{bmatrix}, \qquad
    \rho = \psi_q \dot q + \psi_t

(:math:`\dot\psi = A \ddot q + \rho = 0`). The multipliers :math:`\mu` are the velocity
constraints' reactions: the generalized force they apply is :math:`-A^T \mu`. The state is
projected (after each step and at the start) onto :math:`\Phi = 0` and then, with the
smallest scaled velocity change, onto :math:`\Phi_q \dot q + \Phi_t = 0` and
:math:`A \dot q + b = 0` together.

This is the Python path only: the compiled stepper does not know the rows ``A``
(``FreeStepper.plan`` returns ``None`` for these systems, ``sol.extra["compiled_steps"]``
is 0).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from .._errors import ModelError, SingularJacobianError
from .._symbols import T
from ..compile import compile_exprs
from ..constraints import velocity_rows
from ..solvers._free import _solve_fast, project_positions
from ..solvers._tolerances import SPARSE_THRESHOLD, Singular


def velocity_constraints(model, dropped=()) -> list:
    """The model's constraints (not in ``dropped``) that are velocity constraints: ``order ==
    1`` (the rolling classes) or equations that use the rates (a ``Constraint`` or
    ``Orthogonal1`` of velocity expressions). (Equations are cached per constraint.)"""
    rates = set(model.velocity_symbols().values())
    return [c for c in model._constraints if all(c is not d for d in dropped) and (
        getattr(c, "order", 0) == 1
        or any(e.free_symbols & rates for e in c.equations(model.space)))]


class VelocityRows:
    r"""The compiled rows :math:`A(q, t)` (k, n), :math:`b(q, t)` (k,) and :math:`\rho(q,
    \dot q, t)` (k,) of the velocity constraints ``constraints`` on ``system`` (the free
    system's holonomic part: the same coordinates, in its order). ``owners[i]`` is the
    constraint of row ``i``. A constraint whose equations are not linear in the rates raises
    :class:`ModelError` naming it."""

    def __init__(self, model, system, constraints):
        lay = system.layout
        q, qd = list(lay.q_symbols), list(lay.qd_symbols)
        allowed = set(q) | set(qd) | set(lay.p_symbols) | {T}
        gen = model._gen_substitution()
        psi, owners = [], []
        for c in constraints:
            eqs = [e.xreplace(gen) if gen else e for e in c.equations(model.space)]
            for e in eqs:
                extra = e.free_symbols - allowed
                if extra:
                    raise ModelError(f"{c.label()} uses unknown symbol(s) "
                                     f"{sorted(map(str, extra))}")
            if not velocity_rows(eqs, q, qd, rho=False).linear:
                raise ModelError(
                    f"free(): the velocity constraint {c.label()} is not linear in the "
                    "velocities, so it has no form A(q, t) qd + b(q, t) = 0 that free motion "
                    "can hold; write it linear in the rates (e.g. a component of a velocity "
                    "along a direction), or use a path system (m.path) for it")
            psi += eqs
            owners += [c] * len(eqs)
        rows = velocity_rows(psi, q, qd)
        self.k, self.n = len(psi), system.n
        self.owners = owners
        self.constraints = list(constraints)
        self.system = system
        self._f = compile_exprs(lay.args(), list(rows.A) + list(rows.b) + list(rows.rho),
                                system.backend)

    def evaluate(self, t, q, qd, p):
        """``(A (k, n), b (k,), rho (k,))`` at ``(t, q, qd)``."""
        out = np.asarray(self._f(self.system.pack(t, q, qd, p)), dtype=float).ravel()
        k, n = self.k, self.n
        return out[:k * n].reshape(k, n), out[k * n:k * n + k], out[k * n + k:]

    def residual(self, t, q, qd, p) -> np.ndarray:
        """:math:`A \\dot q + b` (k,)."""
        A, b, _ = self.evaluate(t, q, qd, p)
        return A @ qd + b


def nonholonomic_acceleration(system, rows: VelocityRows, t, q, qd, p):
    r"""``(qdd (n,), multipliers (m + k,))`` of the free motion with velocity rows: the
    augmented system of the module docstring, solved dense (LAPACK). The multipliers are
    :math:`(\lambda, \mu)`. A singular matrix (dependent rows, or mass missing on a free
    motion) raises :class:`SingularJacobianError` naming the velocity constraints."""
    n, m, k = system.n, system.m, rows.k
    kern = system.dynamics.free_kernel(n + m > SPARSE_THRESHOLD)
    K0, rhs0 = kern(t, q, qd, np.zeros(m), p)
    K0 = K0.toarray() if sps.issparse(K0) else np.asarray(K0)
    A, _, rho = rows.evaluate(t, q, qd, p)
    N = n + m + k
    K = np.zeros((N, N))
    K[:n + m, :n + m] = K0
    K[:n, n + m:] = A.T
    K[n + m:, :n] = A
    rhs = np.concatenate((rhs0, -rho))
    try:
        x = _solve_fast(K, rhs)
    except Singular:
        names = ", ".join(sorted({c.label() for c in rows.constraints}))
        raise SingularJacobianError(
            f"free acceleration at t = {t:.6g}: the augmented system with the velocity "
            f"constraints ({names}) is singular: their rows are dependent on each other or on "
            "the holonomic constraints (e.g. a no-slip row that is the derivative of a kept "
            "position constraint), or a free motion carries no mass; remove the redundant "
            "constraint or give the bodies mass and inertia", time=t) from None
    return x[:n], x[n:]


def velocity_matrix(system, rows: VelocityRows, t, q, p):
    """``(G (m + k, n), g (m + k,))``: the velocity equations ``G qd = g`` of the holonomic
    (``Phi_q qd = -Phi_t``) and the velocity constraints (``A qd = -b``) stacked."""
    if system.m:
        J, rhs = system.velocity_rhs(t, q, p)
        J = J.toarray() if sps.issparse(J) else np.asarray(J, dtype=float)
    else:                   # (no holonomic rows: a free body on a knife edge)
        J, rhs = np.zeros((0, system.n)), np.zeros(0)
    A, b, _ = rows.evaluate(t, q, np.zeros(system.n), p)
    return np.vstack((J, A)), np.concatenate((np.asarray(rhs, dtype=float), -b))


def project_velocities(system, rows: VelocityRows, t, q, qd, p, scaling, hold=()):
    r"""The smallest scaled change of ``qd`` (``hold``: indices kept as given) onto
    :math:`\Phi_q \dot q + \Phi_t = 0` and :math:`A \dot q + b = 0` (least squares in the
    unit-free columns of ``scaling``, each row divided by its scale). Returns ``(qd, left)``,
    ``left`` the scaled residual after the change (relative to the largest scaled rate)."""
    G, g = velocity_matrix(system, rows, t, q, p)
    r = scaling.rows(G)
    Gs = np.asarray(scaling.scaled(G, r), dtype=float).copy()
    Gs[:, list(hold)] = 0.0
    dx = np.linalg.lstsq(Gs, -(G @ qd - g) / r, rcond=1e-12)[0]
    qd = qd + scaling.columns * dx
    left = np.abs((G @ qd - g) / r).max(initial=0.0)
    return qd, left / (1.0 + np.abs(qd / scaling.columns).max(initial=0.0))


def project_state(system, rows: VelocityRows, t, q, qd, p, scaling, rank_tolerant=False):
    """``(q, qd)`` projected: positions onto ``Phi = 0``
    (:func:`~mechsys.solvers._free.project_positions`), then velocities by
    :func:`project_velocities`."""
    q = project_positions(system, t, q, p, scaling=scaling, rank_tolerant=rank_tolerant)
    qd, _ = project_velocities(system, rows, t, q, np.asarray(qd, dtype=float), p, scaling)
    return q, qd


def velocity_drift(system, rows: VelocityRows, t, q, qd, p, scaling) -> float:
    r"""The largest scaled velocity-constraint residual :math:`\max_i |(A \dot q + b)_i| /
    r_i` over the largest scaled rate (the ``accuracy["nonholonomic"]`` of a run)."""
    A, b, _ = rows.evaluate(t, q, qd, p)
    r = scaling.rows(A)
    rate = np.abs(qd / scaling.columns).max(initial=0.0)
    v = np.abs((A @ qd + b) / r).max(initial=0.0)
    return float(v / rate) if rate > 0 else float(v)
