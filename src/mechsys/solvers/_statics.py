r"""Multipliers of a fully constrained system: statics, kinematic loads, inverse dynamics.

With ``n`` coordinates and ``m = n`` equations, the multipliers follow from

.. math::

    \text{static:} \quad & \Phi_q^T \lambda = Q(t, q, 0, \lambda) \\
    \text{kinematic:} \quad & \Phi_q^T \lambda = Q(t, q, \dot q, \lambda) \\
    \text{dynamic:} \quad & \Phi_q^T \lambda = Q(t, q, \dot q, \lambda) + Q_v(q, \dot q)
        - M(q) \ddot q

solved in the unit-free form of the Jacobian (:math:`B = R^{-1} \Phi_q D`, positions in units of
the model's length, each equation divided by its row scale; a sweep's own scaling, else
``Scaling.of`` at ``q``):

.. math::

    B^T (R \lambda) = D\, \mathrm{rhs}

so that the conditioning, hence the refusal of a singular Jacobian, does not depend on the
unit of length (unscaled, a mechanism modelled in micrometres was refused as singular).

Linear in ``lambda`` unless loads depend on the multipliers (friction); then Newton on
:math:`R(\lambda) = \Phi_q^T \lambda - \mathrm{rhs}(\lambda)` with Jacobian ``Phi_q^T - dQ/dlambda`` from
``lambda_guess`` (default 1 for every multiplier, as in Mech).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps

from .._errors import ConvergenceError, ModelError, OptionError, option_fields
from . import _jit_multipliers
from ._linalg import Scaling, factor, pattern_slots
from ._patterns import multiplier_newton_pattern
from ._position import describe_singular
from ._tolerances import SPARSE_THRESHOLD, Singular

MODES = ("static", "kinematic", "dynamic")


@option_fields
@dataclass(frozen=True)
class MultiplierOptions:
    """tol: residual tolerance of the multiplier Newton (relative to the size of the terms of
    the residual, unit-free: see :func:`solve_multipliers`), positive and finite;
    max_iterations: positive int; lambda_guess: scalar or (m,) finite starting values
    (nonlinear case)."""

    tol: float = 1e-10
    max_iterations: int = 50
    lambda_guess: object = 1.0

    def __post_init__(self):
        f = self.tol
        if isinstance(f, bool) or not isinstance(f, (int, float, np.integer, np.floating)) \
                or not np.isfinite(f) or f <= 0:
            raise OptionError(f"MultiplierOptions: tol must be a positive finite number, got {f!r}")
        k = self.max_iterations
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise OptionError("MultiplierOptions: max_iterations must be a positive integer, "
                              f"got {k!r}")
        try:
            g = np.asarray(self.lambda_guess, dtype=float)
        except (TypeError, ValueError):
            g = np.array([np.nan])
        if g.ndim > 1 or not np.all(np.isfinite(g)):
            raise OptionError("MultiplierOptions: lambda_guess must be a finite number or a vector "
                              f"of finite numbers, got {self.lambda_guess!r}")


def solve_multipliers(system, dyn, t, q, qd, qdd, p, mode: str = "dynamic",
                      options: MultiplierOptions | None = None, J=None, scaling=None):
    """Multipliers ``lambda`` (m,) and the Newton iteration count at one state. ``scaling``:
    the unit-free form's column scales (default ``Scaling.of`` at ``q``; a sweep passes its
    own). Loads that depend on the multipliers: Newton on ``R = Phi_q^T lambda - b(lambda)``
    until ``max_j c_j |R_j| <= tol max_j c_j (sum_i |Phi_ij lambda_i| + |b_j|)`` (``c`` the
    column scales: each generalized force in units of force times length, so the test is
    relative to the size of the residual's terms whatever the units)."""
    opt = options or MultiplierOptions()
    n, m = system.n, system.m
    if J is None:
        # large models: the sparse Jacobian, as their sweeps (a dense LU of a chain of 363
        # coordinates cost 5 ms a point); friction's Newton then goes through its matrix's
        # pattern too (_newton_values)
        J = system.jacobian(t, q, p, n > SPARSE_THRESHOLD)
    if not np.all(np.isfinite(J.data if sps.issparse(J) else J)):
        raise ModelError(f"{mode} load solve at t = {t:.6g}: the constraint Jacobian is not "
                         "finite at this state (a coordinate or parameter is NaN or inf)")
    qd_eff = np.zeros(n) if (mode == "static" or qd is None) else qd
    lam = np.broadcast_to(np.asarray(opt.lambda_guess, dtype=float), (m,)).copy()
    sc = Scaling.of(system, q, J) if scaling is None else scaling
    r = sc.rows(J)
    try:
        if sps.issparse(J):
            # the Jacobian's own factorisation (through its pattern, analysed once: banded
            # LU for chains), solved transposed
            fac = sc.factor(J, r)
            solve = fac.solve_transposed
        else:
            fac = factor(sc.scaled(J, r).T)
            solve = lambda b: fac.solve(sc.columns * b) / r       # noqa: E731
    except Singular:
        raise describe_singular(system, J, t, q, f"{mode} load solve", scaling=sc) from None

    qdd_eff = qdd if mode == "dynamic" else None

    def rhs(lam):
        M, Q, Qv = dyn.terms(t, q, qd_eff, lam, p, qdd_eff)
        b = Q + Qv - M @ qdd if mode == "dynamic" else Q
        if not np.all(np.isfinite(b)):
            bad = ", ".join(system.layout.q_names[i] for i in np.flatnonzero(~np.isfinite(b)))
            what = "forces Q + Qv - M qdd" if mode == "dynamic" else "applied loads"
            raise ModelError(
                f"{mode} load solve at t = {t:.6g}: the {what} are not finite on coordinate(s) "
                f"{bad}: a load expression divides by zero or a parameter is NaN or inf at this "
                "time; check the loads and the parameter values")
        return b

    if not dyn.depends_on_lambda:
        return solve(rhs(lam)), 0
    # converged when the residual is small against its own terms, unit-free (each generalized
    # force times its coordinate's scale: a force times L, a moment times 1):
    #   max_j c_j |R_j| <= tol max_j c_j (sum_i |Phi_ij lambda_i| + |b_j|)
    # (not tol (1 + max |b|): for loads far below one unit of force that was an absolute test
    # and ended Newton on a wrong answer, e.g. a part of a few micrograms)
    c = sc.columns
    sparse = sps.issparse(J)
    JT = J.T.tocsr() if sparse else np.ascontiguousarray(J.T)
    absJT = abs(JT) if sparse else None
    history = []
    for it in range(1, opt.max_iterations + 1):
        b = rhs(lam)
        R = JT @ lam - b
        err = np.abs(c * R).max()
        history.append(err)
        terms = absJT @ np.abs(lam) if sparse else np.abs(JT * lam).sum(axis=1)
        if err <= opt.tol * (c * (terms + np.abs(b))).max():
            return lam, it - 1
        try:
            # (unit-free as the linear solve: D K R^-1 (R dlambda) = D R)
            if n > SPARSE_THRESHOLD and m == n:
                # large models: through the matrix's fixed pattern, analysed once (banded LU
                # for chains) instead of a dense LU per iteration
                rows, cols, pattern = multiplier_newton_pattern(system)
                K = _newton_values(system, dyn, J, t, q, qd_eff, lam, p, qdd_eff)
                fac = pattern.factor((c[rows] * K) / r[cols])
            else:
                K = JT - dyn.dQ_dlam(t, q, qd_eff, lam, p, qdd_eff)
                fac = factor((sc.columns[:, None] * K) / r[None, :])
            lam = lam - fac.solve(sc.columns * R) / r
        except Singular:
            raise ConvergenceError(
                f"{mode} load solve at t = {t:.6g}: the multiplier Newton matrix "
                "(Phi_q^T - dQ/dlambda) is singular; friction this large can lock the joint. "
                "Try lambda_guess= near the expected reactions.", time=t,
                history=tuple(history)) from None
    raise ConvergenceError(
        f"{mode} load solve at t = {t:.6g} did not converge in {opt.max_iterations} iterations "
        f"(residual {history[-1]:.3e}). Loads depend on the reactions (friction): either the "
        "mechanism self-locks here (no finite reaction can drive it with this friction), or "
        "the start is poor: give lambda_guess= closer to the expected multipliers "
        "(Mech's LambdaGuess).", time=t, residuals=R, history=tuple(history))


def _newton_values(system, dyn, J, t, q, qd, lam, p, qdd):
    """The values of ``Phi_q^T - dQ/dlambda`` at the entries of its pattern
    (:func:`~._patterns.multiplier_newton_pattern`, CSC order), from ``J`` (sparse CSC: its
    stored entries placed through slots found once; dense: gathered) and ``dQ/dlambda``'s
    nonzero values."""
    rows, cols, _ = multiplier_newton_pattern(system)
    dvals = dyn.f_dQ_dlam(dyn.pack(t, q, qd, lam, p, qdd))
    if not sps.issparse(J):
        sD = pattern_slots(rows, cols, system.n, dyn.dQ_rows, dyn.dQ_cols)
        return np.ascontiguousarray(J.T)[rows, cols] - np.bincount(sD, dvals, rows.size)
    key = (J.indptr.tobytes(), J.indices.tobytes())
    got = dyn.__dict__.get("_multiplier_slots")
    if got is None or got[0] is not system or got[1] != key:
        jcols = np.repeat(np.arange(J.shape[1]), np.diff(J.indptr))
        got = (system, key, pattern_slots(rows, cols, system.n, jcols, J.indices),
               pattern_slots(rows, cols, system.n, dyn.dQ_rows, dyn.dQ_cols))
        dyn.__dict__["_multiplier_slots"] = got
    return np.bincount(got[2], J.data, rows.size) - np.bincount(got[3], dvals, rows.size)


def multipliers_over(system, times, Q, QD, QDD, p, mode: str = "dynamic", lambda_guess=1.0,
                     scaling=None, points: int | None = None):
    """Multipliers ``(N, m)`` at each point of a solved sweep (``Q``, ``QD``, ``QDD`` (N, n);
    ``QD``/``QDD`` None where the sweep did not compute them). The loop
    (``_jit_multipliers.multipliers``, compiled or interpreted: decision 0081) takes the
    points; where it stops (a point needing care: a singular Jacobian, loads that are not
    finite, friction's Newton not converging) :func:`solve_multipliers` takes that point,
    with its diagnostics, and the loop resumes from the next one; each point's
    ``lambda_guess`` (Newton, loads that depend on the multipliers) is the previous point's
    multipliers. Where the loop solves nothing (a stretch of points needing care, or a job
    it cannot take: see ``_jit_multipliers.multipliers``), the Python code takes the next
    ``2^misses`` points (at most :data:`RESUME_SKIP`) before the loop is asked again.
    ``scaling``: the unit-free form's column scales for every point (the sweep's; default
    ``Scaling.of`` at the first point). ``points``: the size of the whole job (a multistage
    sweep's), for the loop's tier (``_jit_runtime.tier``)."""
    N = len(times)
    lam = np.empty((N, system.m))
    if N and scaling is None:
        scaling = Scaling.of(system, Q[0], system.jacobian(times[0], Q[0], p))
    opt = MultiplierOptions()
    dyn = system.dynamics
    columns = None if scaling is None else scaling.columns
    job = N if points is None else points
    k, misses, ask = 0, 0, 0
    while k < N:
        guess = lambda_guess if k == 0 else lam[k - 1]
        if k >= ask:
            done = _jit_multipliers.multipliers(
                system, times[k:], Q[k:], None if QD is None else QD[k:],
                None if QDD is None else QDD[k:], p, mode, lam[k:], guess, opt.tol,
                opt.max_iterations, columns, job)
            k += done
            misses = 0 if done else misses + 1
            if k >= N:
                break
            guess = lambda_guess if k == 0 else lam[k - 1]
        qd = None if QD is None else QD[k]
        qdd = None if QDD is None else QDD[k]
        lam[k], _ = solve_multipliers(system, dyn, times[k], Q[k], qd, qdd, p, mode,
                                      MultiplierOptions(lambda_guess=guess), scaling=scaling)
        k += 1
        if misses and k >= ask:
            ask = k + min(RESUME_SKIP, 2 ** (misses - 1)) - 1
    return lam


#: where the multiplier loop solves nothing, the Python code takes up to this many points
#: before the loop is asked again (:func:`multipliers_over`)
RESUME_SKIP = 64
