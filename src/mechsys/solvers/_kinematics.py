r"""Velocity, acceleration and kinematic sweeps of a fully constrained system.

Velocity ``Phi_q qd = -Phi_t``; acceleration ``Phi_q qdd = gamma``. A sweep over times
``t_0 < t_1 < ...`` solves each position by Newton from a Taylor predictor of the previous
point (``q + qd dt + qdd dt^2 / 2``, as far as solved), so it follows one assembly branch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import ConvergenceError, SingularJacobianError
from ._linalg import SPARSE_THRESHOLD, Singular, factor
from ._position import PositionOptions, describe_singular, solve_position

ORDERS = {"location": 0, "velocity": 1, "acceleration": 2}

#: below this reciprocal condition number of Phi_q a sweep warns (near a toggle position)
RCOND_WARN = 1e-6


def solve_velocity(system, t: float, q, p=None) -> np.ndarray:
    """Velocities ``qd`` (n,) from ``Phi_q qd = -Phi_t`` at ``(t, q)``."""
    J, rhs = system.velocity_rhs(t, q, p, system.n > SPARSE_THRESHOLD)
    try:
        return factor(J).solve(rhs)
    except Singular:
        raise describe_singular(system, J, t, q, "velocity solve") from None


def solve_acceleration(system, t: float, q, qd, p=None, J=None) -> np.ndarray:
    """Accelerations ``qdd`` (n,) from ``Phi_q qdd = gamma`` at ``(t, q, qd)``."""
    if J is None:
        J = system.jacobian(t, q, p, system.n > SPARSE_THRESHOLD)
    g = system.gamma_values(t, q, qd, p)
    try:
        return factor(J).solve(g)
    except Singular:
        raise describe_singular(system, J, t, q, "acceleration solve") from None


@dataclass(frozen=True)
class SweepResult:
    """Raw arrays of a sweep: t (N,), q/qd/qdd (N, n) (None when not solved),
    iterations (N,) Newton iterations per point, evaluations (total function calls)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray | None
    qdd: np.ndarray | None
    iterations: np.ndarray
    evaluations: int
    order: int
    rcond: np.ndarray | None = None


def sweep(system, times, guess, order: int = 2, options: PositionOptions | None = None,
          p=None) -> SweepResult:
    """Kinematic solution at each of ``times`` (1D, any order; continuation follows the
    given order). ``order`` 0 = location, 1 = + velocity, 2 = + acceleration."""
    times = np.atleast_1d(np.asarray(times, dtype=float))
    n, N = system.n, len(times)
    sparse = n > SPARSE_THRESHOLD
    Q = np.empty((N, n))
    QD = np.empty((N, n)) if order >= 1 else None
    QDD = np.empty((N, n)) if order >= 2 else None
    its = np.zeros(N, dtype=int)
    rconds = np.full(N, np.nan) if order >= 1 else None
    evals = 0
    q_prev = np.asarray(guess, dtype=float)
    qd_prev = qdd_prev = None
    t_prev = None
    for k, t in enumerate(times):
        g = q_prev
        if t_prev is not None and qd_prev is not None:
            dt = t - t_prev
            g = q_prev + qd_prev * dt
            if qdd_prev is not None:
                g = g + 0.5 * qdd_prev * dt * dt
        try:
            res = solve_position(system, t, g, options, p)
        except (ConvergenceError, SingularJacobianError):
            if g is q_prev:
                raise
            # the Taylor predictor can throw the guess far away where velocities are huge
            # (near a toggle): start again from the previous position
            res = solve_position(system, t, q_prev, options, p)
        q = res.q
        its[k] = res.iterations
        evals += res.evaluations
        Q[k] = q
        if order >= 1:
            J, rhs = system.velocity_rhs(t, q, p, sparse)
            try:
                fac = factor(J)
            except Singular:
                err = describe_singular(system, J, t, q, "velocity solve")
                raise SingularJacobianError(
                    f"{err} Sweep stopped at point {k} of {N}.", time=t,
                    dependent=err.dependent, rank=err.rank) from None
            qd = fac.solve(rhs)
            QD[k] = qd
            rconds[k] = fac.rcond
            evals += 1
            if order >= 2:
                qdd = fac.solve(system.gamma_values(t, q, qd, p))
                QDD[k] = qdd
                evals += 1
            else:
                qdd = None
        else:
            qd = qdd = None
        q_prev, qd_prev, qdd_prev, t_prev = q, qd, qdd, t
    if rconds is not None and np.nanmin(rconds, initial=1.0) < RCOND_WARN:
        import warnings

        from .._errors import NearSingularWarning

        bad = times[rconds < RCOND_WARN]
        warnings.warn(NearSingularWarning(
            f"the constraint Jacobian is nearly singular at {len(bad)} time point(s), first at "
            f"t = {bad[0]:.6g} (reciprocal condition {np.nanmin(rconds):.1e}): the mechanism is "
            "close to a lock-up or toggle position; velocities and accelerations there are large "
            "and sensitive. Solution.extra['rcond'] has the value at every point."), stacklevel=3)
    return SweepResult(times, Q, QD, QDD, its, evals, order, rconds)
