r"""Multipliers of a fully constrained system: statics, kinematic loads, inverse dynamics.

With ``n`` coordinates and ``m = n`` equations, the multipliers follow from::

    static:     Phi_q^T lambda = Q(t, q, 0, lambda)
    kinematic:  Phi_q^T lambda = Q(t, q, qd, lambda)
    dynamic:    Phi_q^T lambda = Q(t, q, qd, lambda) + Qv(q, qd) - M(q) qdd

Linear in ``lambda`` unless loads depend on the multipliers (friction); then Newton on
``R(lambda) = Phi_q^T lambda - rhs(lambda)`` with Jacobian ``Phi_q^T - dQ/dlambda`` from
``lambda_guess`` (default 1 for every multiplier, as in Mech).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import ConvergenceError
from ._linalg import Singular, factor
from ._position import describe_singular

MODES = ("static", "kinematic", "dynamic")


@dataclass(frozen=True)
class MultiplierOptions:
    """tol: residual tolerance of the multiplier Newton (relative to 1 + max|Q|);
    max_iterations; lambda_guess: scalar or (m,) starting values (nonlinear case)."""

    tol: float = 1e-10
    max_iterations: int = 50
    lambda_guess: object = 1.0


def solve_multipliers(system, dyn, t, q, qd, qdd, p, mode: str = "dynamic",
                      options: MultiplierOptions | None = None, J=None):
    """Multipliers ``lambda`` (m,) and the Newton iteration count at one state."""
    opt = options or MultiplierOptions()
    n, m = system.n, system.m
    if J is None:
        J = system.jacobian(t, q, p)
    qd_eff = np.zeros(n) if (mode == "static" or qd is None) else qd
    lam = np.broadcast_to(np.asarray(opt.lambda_guess, dtype=float), (m,)).copy()
    try:
        fac = factor(J.T)
    except Singular:
        raise describe_singular(system, J, t, q, f"{mode} load solve") from None

    qdd_eff = qdd if mode == "dynamic" else None

    def rhs(lam):
        M, Q, Qv = dyn.terms(t, q, qd_eff, lam, p, qdd_eff)
        if mode == "dynamic":
            return Q + Qv - M @ qdd
        return Q

    if not dyn.depends_on_lambda:
        return fac.solve(rhs(lam)), 0
    history = []
    for it in range(1, opt.max_iterations + 1):
        b = rhs(lam)
        R = J.T @ lam - b
        err = np.abs(R).max()
        history.append(err)
        if err <= opt.tol * (1 + np.abs(b).max()):
            return lam, it - 1
        K = J.T - dyn.dQ_dlam(t, q, qd_eff, lam, p, qdd_eff)
        try:
            lam = lam - factor(K).solve(R)
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
