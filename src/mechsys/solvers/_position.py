r"""Position analysis: damped Newton on ``Phi(q, t) = 0``.

Each iteration solves ``Phi_q dq = -Phi`` and takes the longest step ``a dq``
(``a = 1, 1/2, 1/4 ...``) that reduces ``||Phi||`` (Armijo test), which keeps poor guesses
from diverging. Converged when ``||Phi||_inf <= ftol * (1 + max|q|)`` (lengths scale the
distance equations) after at least one update.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import ConvergenceError, SingularJacobianError
from ._linalg import SPARSE_THRESHOLD, Singular, dependent_rows, factor, involved_rows


@dataclass(frozen=True)
class PositionOptions:
    """ftol: residual tolerance (scaled by 1 + max|q|); max_iterations; damping: line search."""

    ftol: float = 1e-12
    max_iterations: int = 50
    damping: bool = True


@dataclass(frozen=True)
class PositionResult:
    q: np.ndarray
    success: bool
    status: int
    message: str
    iterations: int
    evaluations: int
    residual: float
    history: tuple


def describe_singular(system, J, t, q, what: str) -> SingularJacobianError:
    rank, dep = dependent_rows(J)
    owners = system.layout.owners_of(dep)
    names = ", ".join(o.label() if hasattr(o, "label") else str(o) for o in owners)
    where = f" at t = {t:.6g}" if t is not None else ""
    msg = (
        f"{what}: the constraint Jacobian is singular{where} (rank {rank} of {system.m} equations, "
        f"{system.n} coordinates). "
    )
    if dep:
        msg += f"Dependent equations come from: {names}. "
        involved = system.layout.owners_of(involved_rows(J, rank))
        if len(involved) > len(owners):
            msg += ("The dependency involves: "
                    + ", ".join(o.label() if hasattr(o, "label") else str(o) for o in involved)
                    + ". ")
    msg += (
        "Either these constraints are redundant (remove or relax one), or the mechanism is at "
        "a lock-up/toggle position where it cannot be driven as specified."
    )
    return SingularJacobianError(msg, time=t, dependent=owners, rank=rank)


def solve_position(system, t: float, guess, options: PositionOptions | None = None,
                   p=None) -> PositionResult:
    """Solve ``Phi(q, t) = 0`` for ``q`` by damped Newton from ``guess`` (shape ``(n,)``).

    Raises :class:`ConvergenceError` (with per-equation residuals and the iteration history)
    or :class:`SingularJacobianError` (naming dependent constraints).
    """
    opt = options or PositionOptions()
    sparse = system.n > SPARSE_THRESHOLD
    q = np.array(guess, dtype=float)
    F, J = system.residual_and_jacobian(t, q, p, sparse)
    evals = 1
    history = []
    norm = np.abs(F).max() if F.size else 0.0
    history.append(norm)
    it = 0
    # The scale is fixed before iterating (a diverging iterate must not loosen its own
    # tolerance) and capped by the model's own guess (a wild sweep predictor must not either).
    scale = np.abs(q).max(initial=0.0)
    g0 = getattr(system, "guess", None)
    if g0 is not None and np.size(g0) and np.abs(g0).max() > 0:
        scale = min(scale, np.abs(g0).max())
    tol = opt.ftol * (1.0 + scale)
    while True:
        if not np.all(np.isfinite(F)):
            raise ConvergenceError(
                f"position solve at t = {t:.6g}: constraint equations are not finite "
                "(a coordinate left the domain of an expression)", time=t,
                residuals=_residual_table(system, F), history=tuple(history))
        if norm <= tol and it > 0:
            return PositionResult(q, True, 0, "converged", it, evals, norm, tuple(history))
        if it >= opt.max_iterations:
            break
        try:
            dq = -factor(J).solve(F)
        except Singular:
            raise describe_singular(system, J, t, q, "position solve") from None
        a = 1.0
        while True:
            qn = q + a * dq
            Fn, Jn = system.residual_and_jacobian(t, qn, p, sparse)
            evals += 1
            nn = np.abs(Fn).max() if Fn.size else 0.0
            if not opt.damping or nn <= (1 - 1e-4 * a) * norm or a < 1e-3 or norm <= tol:
                break
            a *= 0.5
        q, F, J, norm = qn, Fn, Jn, nn
        it += 1
        history.append(norm)
    raise ConvergenceError(
        f"position solve at t = {t:.6g} did not converge in {opt.max_iterations} iterations "
        f"(max residual {norm:.3e}). Largest residuals:\n{_residual_table(system, F)}\n"
        "Give a better initial guess (add_body(..., guess=...) or guess=), or check that the "
        "mechanism can assemble at this time.",
        time=t, residuals=F.copy(), history=tuple(history))


def _residual_table(system, F, k: int = 8) -> str:
    order = np.argsort(-np.abs(F))[:k]
    return "\n".join(f"  {system.layout.row_label(i)}: {F[i]:+.3e}" for i in order)
