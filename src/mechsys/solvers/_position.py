r"""Position analysis: damped Newton on :math:`\Phi(q, t) = 0`.

Each iteration solves :math:`\Phi_q dq = -\Phi` and takes the longest step ``a dq``
(:math:`a = 1, 1/2, 1/4 \dots`) that reduces the scaled residual (Armijo test), which keeps poor
guesses from diverging. All decisions are taken on the unit-free equations of
:class:`~mechsys.solvers._linalg.Scaling` (:math:`\hat\Phi = R^{-1} \Phi`, coordinates in units of
the characteristic length ``L``), so they do not depend on the unit of length: converged when

.. math::  \max_i |\Phi_i| / r_i \le \mathrm{ftol}\,(1 + \max|x| / L)

after at least one update, with ``r_i`` the size of row ``i`` of :math:`\Phi_q D` and ``max|x|``
the largest position coordinate of the reference configuration (the rounding of coordinates
far from the origin). ``ftol`` is thus a relative position error (positions in units of
``L``) or an angle error in radians; the singularity test uses the condition number of the
scaled Jacobian.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._errors import ConvergenceError, ModelError, SingularJacobianError, option_fields
from ._diagnostics import Iteration, Stopped, diagnose_convergence
from ._linalg import Scaling
from ._tolerances import CHORD_RATE, RCOND_MIN, SPARSE_THRESHOLD, Singular


@option_fields
@dataclass(frozen=True)
class PositionOptions:
    """Options of the position Newton solver.

    ftol: tolerance of the scaled residual (relative position error in units of the model's
    characteristic length, or radians; see :mod:`mechsys.solvers._position`), positive and
    finite; max_iterations: positive int; damping: bool, halve steps that do not reduce the
    residual.
    """

    ftol: float = 1e-12
    max_iterations: int = 50
    damping: bool = True

    def __post_init__(self):
        f = self.ftol
        if isinstance(f, bool) or not isinstance(f, (int, float, np.integer, np.floating)) \
                or not math.isfinite(f) or f <= 0:
            raise ModelError(f"PositionOptions: ftol must be a positive finite number, got {f!r}")
        k = self.max_iterations
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ModelError("PositionOptions: max_iterations must be a positive integer, "
                             f"got {k!r}")
        if not isinstance(self.damping, (bool, np.bool_)):
            raise ModelError(f"PositionOptions: damping must be True or False, got {self.damping!r}")


_DEFAULT = PositionOptions()



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
    #: row scales r (m,) of the unit-free equations used by this solve
    rows: np.ndarray | None = None
    #: at a singular instant of a sweep: ``(t, q)`` of the regular instant just before it
    #: from which the position was approached (see ``solvers._kinematics``)
    approach: tuple | None = None


def _label(owner) -> str:
    return owner.label() if hasattr(owner, "label") else str(owner)


@dataclass(frozen=True)
class Dependency:
    """Rank diagnosis of a constraint Jacobian (on its unit-free scaled form).

    rank; deficiency: the fewest equations that must go (``min(m, n) - rank`` for a square
    or tall Jacobian); rows: the dependent equations (pivoted QR picks which); owners: their
    constraints; involved: every constraint taking part in the dependency; text: the rank
    and the dependent equations by constraint and equation number.
    """

    rank: int
    deficiency: int
    rows: tuple
    owners: list
    involved: list
    text: str


def dependency(system, J, scaling: Scaling | None = None, q=None) -> Dependency:
    """Which equations of ``J`` (at ``q``) depend on the others (unit-invariant)."""
    sc = scaling or Scaling.of(system, system.guess if q is None else q, J)
    m = J.shape[0]
    rank, dep = sc.dependent_rows(J) if m else (0, [])
    lay = system.layout
    owners = lay.owners_of(dep)
    involved = lay.owners_of(sc.involved_rows(J, rank)) if dep else []
    parts = []
    for o in owners:
        eqs = [lay.eq_index[i] + 1 for i in dep if lay.eq_owner[i] is o]
        which = "equation" + ("s " if len(eqs) > 1 else " ") + ", ".join(map(str, eqs))
        parts.append(f"{which} of {_label(o)}")
    text = f"(rank {rank} of {m} equations, {system.n} coordinates)."
    if dep:
        text += f" {len(dep)} dependent equation(s): {'; '.join(parts)}."
        if len(involved) > len(owners):
            text += " The dependency involves: " + ", ".join(_label(o) for o in involved) + "."
    return Dependency(rank, len(dep), tuple(dep), owners, involved, text)


def describe_singular(system, J, t, q, what: str,
                      scaling: Scaling | None = None) -> SingularJacobianError:
    """A :class:`SingularJacobianError` naming the dependent equations of ``J`` at ``(t, q)``."""
    d = dependency(system, J, scaling, q)
    where = f" at t = {t:.6g}" if t is not None else ""
    if d.deficiency == 0:
        # the factorisation's condition estimate was below RCOND_MIN, yet the rank-revealing
        # QR finds every equation independent: not a redundancy, an ill-conditioned iterate
        msg = (f"{what}: the constraint Jacobian{where} is too ill-conditioned to solve with "
               f"(reciprocal condition number below {RCOND_MIN:.0e} in its unit-free form), "
               f"although no equation depends on the others {d.text} The coordinates there "
               "are close to a lock-up/toggle position, or far from any assembled position: "
               "check the guess (a wrong angle or length, a point on the wrong side).")
    else:
        msg = f"{what}: the constraint Jacobian is singular{where} {d.text}"
        msg += (
            " Either these constraints are redundant (remove or relax as many equations as "
            "are dependent), or the mechanism is at a lock-up/toggle position where it cannot "
            "be driven as specified."
        )
    return SingularJacobianError(msg, time=t, dependent=d.owners, rank=d.rank)


def _checked_start(system, start):
    """``start`` of :func:`solve_position` as ``(Phi (m,), Phi_q (m, n))``, or a
    :class:`ModelError` saying what is wrong with it."""
    m, n = system.m, system.n
    try:
        F, J = start
        F = np.asarray(F, dtype=float)
        shape = J.shape
    except (TypeError, ValueError, AttributeError):
        raise ModelError("solve_position: start must be the pair (Phi, Phi_q) at the guess, "
                         f"a vector of {m} residuals and a ({m}, {n}) Jacobian") from None
    if F.shape != (m,) or shape != (m, n):
        raise ModelError(f"solve_position: start has shapes {F.shape} and {shape}; the "
                         f"residuals at the guess must be ({m},) and the Jacobian ({m}, {n})")
    return F, J


def solve_position(system, t: float, guess, options: PositionOptions | None = None,
                   p=None, scaling: Scaling | None = None, hooks=None,
                   chord=None, start=None, _again: bool = False) -> PositionResult:
    r"""Solve :math:`\Phi(q, t) = 0` for ``q`` by damped Newton from ``guess`` (shape ``(n,)``).

    ``chord``: a factorisation (:class:`~mechsys.solvers._linalg.ScaledFactor`) of a nearby
    Jacobian ``J_c`` (a sweep passes its previous point's). The iteration then starts with
    chord steps ``q <- q - J_c^-1 Phi(q)``, each kept while it reduces the scaled residual by
    at least the factor ``CHORD_RATE``; the first one that does not is discarded and damped
    Newton continues from the last kept iterate with the Jacobian there. A chord step costs
    an evaluation and a solve, a Newton step also a factorisation and its condition
    estimate. Close to the solution (a sweep's predictor) a chord step multiplies the error
    by about ``|J_c^-1 (Phi_q - J_c)|`` where Newton's squares it; so that the result is at
    rounding, not merely within ``ftol``, a solve given a chord converges only after a step
    that started within the tolerance: when the step that reached it started outside, one
    more step with the last factorisation (the chord, or Newton's own) is taken, kept while
    the residual stays within the tolerance (not at ``max_iterations``). Without ``chord`` the
    iteration is plain damped Newton. ``start``: ``(Phi, Phi_q)`` at ``guess``, when the caller
    has evaluated them already (a sweep's first point, for its scaling); counted here.

    ``scaling`` (a :class:`~mechsys.solvers._linalg.Scaling`) fixes the unit-free form of
    the equations; by default it is taken at the system's own guess (so a wild starting
    guess cannot loosen the tolerance). ``PositionResult.residual`` and ``history`` are
    the scaled residual ``max |Phi_i| / r_i``.

    Raises :class:`ConvergenceError` (with per-equation residuals, the iteration history
    and a :class:`~mechsys.solvers._diagnostics.ConvergenceDiagnosis`) or
    :class:`SingularJacobianError` (naming dependent constraints). ``hooks`` (a
    :class:`~mechsys.solvers._diagnostics.Hooks`): ``post_iterate`` is called after each
    iteration; returning False stops the solve (``Stopped``).

    Angle equations that also hold half a turn off (``system.branch_guard``, decision 0033):
    a guess more than a quarter turn from an asked angle is first turned onto it, and a
    solution on the wrong root is turned by pi and solved again (the counts add up); one
    still on it raises :class:`ConvergenceError` naming the constraint.
    """
    opt = options or _DEFAULT
    sparse = system.n > SPARSE_THRESHOLD
    q = np.array(guess, dtype=float)
    guard = getattr(system, "branch_guard", None)
    if guard is not None and np.all(np.isfinite(q)):
        # an angle equation holds at the asked angle and half a turn off: a guess more than a
        # quarter turn from the asked angle starts from that angle instead (decision 0033)
        aligned = guard.align(t, q, p)
        if aligned is not None:
            q, start = aligned, None
    q_start = q.copy()
    post = hooks.post_iterate if hooks is not None else None
    if start is None:
        F, J = system.residual_and_jacobian(t, q, p, sparse)
    else:
        F, J = _checked_start(system, start)
    evals = 1
    if scaling is None:
        g0 = getattr(system, "guess", None)
        if g0 is not None and np.shape(g0) == q.shape and np.all(np.isfinite(g0)):
            scaling = Scaling.of(system, g0, system.jacobian(t, g0, p, sparse))
            evals += 1
        else:
            scaling = Scaling.of(system, q, J)
    # the row scales are fixed before iterating: the line search and the convergence test
    # compare residuals in one metric, and a diverging iterate cannot loosen its own test
    rows = scaling.rows(J)
    tol = opt.ftol * (1.0 + scaling.offset)
    history = []
    norm = np.abs(F / rows).max() if F.size else 0.0
    history.append(norm)
    it = 0
    polish = chord is not None   # a sweep's solve: converged to rounding, see the docstring
    last = chord                 # the last factorisation used
    prev = np.inf                # the scaled residual before the last step
    while True:
        if not np.all(np.isfinite(F)):
            bad = system.layout.owners_of(np.flatnonzero(~np.isfinite(F)))
            raise ConvergenceError(
                f"position solve at t = {t:.6g}: constraint equations are not finite "
                "(a coordinate left the domain of an expression, or a division by zero) in "
                + ", ".join(_label(o) for o in bad)
                + ("; check their expressions at this time and the guess" if it == 0 else
                   f" after {it} Newton iteration(s); give a better guess"), time=t,
                residuals=F.copy(), history=tuple(history))
        if norm <= tol and it > 0:
            if polish and prev > tol and it < opt.max_iterations:
                # the step that reached tol started outside it: one more step with the last
                # factorisation takes the error from within tol to rounding, as Newton's
                # squaring does from close enough (kept while within tol: at rounding the
                # residual only scatters, and the count must not depend on that scatter)
                dq = -last.solve(F)
                qn = q + dq
                Fn, Jn = system.residual_and_jacobian(t, qn, p, sparse)
                evals += 1
                nn = np.abs(Fn / rows).max() if Fn.size else 0.0
                if nn <= tol:
                    q, F, J, norm = qn, Fn, Jn, nn
                    it += 1
                    history.append(norm)
                    if post is not None:
                        _post(post, system, t, it, q, norm, dq)
            res = PositionResult(q, True, 0, "converged", it, evals, norm, tuple(history), rows)
            return res if guard is None else _on_branch(system, guard, t, res, opt, p, scaling,
                                                        hooks, _again)
        if it >= opt.max_iterations:
            break
        if chord is not None:
            dq = -chord.solve(F)
            qn = q + dq
            Fn, Jn = system.residual_and_jacobian(t, qn, p, sparse)
            evals += 1
            nn = np.abs(Fn / rows).max() if Fn.size else 0.0
            if nn <= CHORD_RATE * norm:
                prev, q, F, J, norm = norm, qn, Fn, Jn, nn
                it += 1
                history.append(norm)
                if post is not None:
                    _post(post, system, t, it, q, norm, dq)
                continue
            chord = None            # too slow (or not finite): Newton from q with its own J
        try:
            last = scaling.factor(J, rows)
            dq = -last.solve(F)
        except Singular:
            raise describe_singular(system, J, t, q, "position solve", scaling) from None
        a = 1.0
        while True:
            qn = q + a * dq
            Fn, Jn = system.residual_and_jacobian(t, qn, p, sparse)
            evals += 1
            nn = np.abs(Fn / rows).max() if Fn.size else 0.0
            if not opt.damping or nn <= (1 - 1e-4 * a) * norm or a < 1e-3 or norm <= tol:
                break
            a *= 0.5
        prev, q, F, J, norm = norm, qn, Fn, Jn, nn
        it += 1
        history.append(norm)
        if post is not None:
            _post(post, system, t, it, q, norm, a * dq)
    diag = diagnose_convergence(system, t, q_start, q, F, rows, scaling, history)
    raise ConvergenceError(
        f"position solve at t = {t:.6g} did not converge in {opt.max_iterations} iterations "
        f"(max residual {np.abs(F).max():.3e}, scaled {norm:.3e} > {tol:.1e}). Largest "
        f"residuals:\n{_residual_table(system, F, rows)}\n{diag.text}\n"
        "Give a better initial guess (add_body(..., guess=...) or guess=), or check that the "
        "mechanism can assemble at this time.",
        time=t, residuals=F.copy(), history=tuple(history), diagnosis=diag)


def _on_branch(system, guard, t, res, opt, p, scaling, hooks, again) -> PositionResult:
    """``res`` when every angle equation converged to its asked angle; else the solve again
    from the solution turned onto it (once), or a :class:`ConvergenceError`."""
    bad = guard.wrong(t, res.q, p)
    if not bad:
        return res
    turned = None if again else guard.align(t, res.q, p)
    if turned is None:
        raise ConvergenceError(guard.describe(bad, t), time=t, history=res.history)
    got = solve_position(system, t, turned, opt, p, scaling, hooks, _again=True)
    return PositionResult(got.q, True, 0, "converged", res.iterations + got.iterations,
                          res.evaluations + got.evaluations, got.residual,
                          res.history + got.history, got.rows)


def _post(post, system, t, it, q, norm, step) -> None:
    """Call the ``post_iterate`` hook; ``Stopped`` when it returns False."""
    if post(Iteration(float(t), it, q.copy(), float(norm), step,
                      tuple(system.layout.q_names))) is False:
        raise Stopped("post_iterate", float(t), it)


def _residual_table(system, F, rows=None, k: int = 8) -> str:
    """The ``k`` largest residuals (largest scaled ones first when ``rows`` are given)."""
    order = np.argsort(-np.abs(F if rows is None else F / rows))[:k]
    return "\n".join(f"  {system.layout.row_label(i)}: {F[i]:+.3e}" for i in order)
