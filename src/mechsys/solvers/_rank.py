r"""Rank-revealing and rank-tolerant pieces: singular instants of free motion and of
kinematic sweeps, redundant but consistent constraints. Every decision is taken on the
unit-free scaled Jacobian :math:`\hat J = R^{-1} \Phi_q D` (:class:`~mechsys.solvers._linalg.Scaling`),
so it does not depend on the unit of length. Choices and measurements:
``docs/decisions/0012-singular-and-redundant.md``.

Free motion near a singular instant (``s_min / s_max`` of ``J^`` below ``ZONE``):

* :func:`zone_guard` checks each free-acceleration solution (a cheap multiplier test, then
  :func:`in_zone`) and replaces it by :func:`kkt_regularized`, the augmented system with a
  ``-KAPPA I`` block: exact where ``s^2 >> KAPPA``, softened (not amplified) along the
  dependent direction at the instant;
* :func:`project_regularized`: mass-orthogonal, regularised projections (those of the
  augmented-Lagrangian index-3 methods) where the ordinary projection raises
  :class:`InZone`;
* :func:`kkt_rank_tolerant`: at an exactly singular state outside an integration, the
  null-space solution with the truncated SVD (singular values below ``RANK_TOL s_1`` are
  zero) and minimum-norm multipliers.

Kinematic sweeps through an exactly singular sample: :func:`continue_position`
(Gauss-Newton with minimum-norm steps from a prediction on the branch) and
:func:`continue_rates` (the solution of the rank-deficient rate equations nearest to the
predicted one).

Redundant constraints: :func:`min_norm_multipliers` and :func:`expand_multipliers` share
the constraint forces of the independent equations over all equations (minimum norm).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from ._linalg import factor
from ._tolerances import ZONE, Singular

#: singular values of the scaled Jacobian below RANK_TOL * s_max count as zero
RANK_TOL = 1e-8
#: regularisation of the acceleration solve and weight 1 / KAPPA of the projections there
KAPPA = 1e-6


def _dense(A) -> np.ndarray:
    return A.toarray() if sps.issparse(A) else np.asarray(A, dtype=float)


def truncated_svd(A, tol: float = RANK_TOL):
    """``(U_r, s_r, Vt_r)`` of the dense SVD of ``A`` keeping ``s_i > tol s_1``."""
    A = _dense(A)
    if A.size == 0:
        return np.zeros((A.shape[0], 0)), np.zeros(0), np.zeros((0, A.shape[1]))
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    r = int((s > tol * s[0]).sum()) if s.size and s[0] > 0 else 0
    return U[:, :r], s[:r], Vt[:r]


def kkt_rank_tolerant(M, J, F, gamma, rows, columns, tol: float = RANK_TOL):
    r"""``(qdd, lambda, rank)`` of the free acceleration with a rank-deficient (or nearly so)
    ``J``, by the null-space method on the truncated SVD of the scaled Jacobian.

    In scaled unknowns ``qdd = D x``, ``lambda = R^-1 mu`` with ``J^ = R^-1 J D = U S V^T``
    truncated to rank ``r`` and ``N`` an orthonormal basis of the rest of the coordinate
    space (the free motions, including the directions the dependent equations leave)::

        x = V_r S_r^-1 U_r^T (R^-1 gamma) + N z,    (N^T M^ N) z = N^T (F^ - M^ x_p)
        mu = U_r S_r^-1 V_r^T (F^ - M^ x)            (minimum norm)

    with ``M^ = D M D``, ``F^ = D F``. Amplification is bounded by ``1 / (tol s_1)``, where
    the augmented matrix would square it. Raises :class:`~mechsys.solvers._tolerances.Singular`
    when ``N^T M^ N`` is singular (``M`` singular on the free motions)."""
    M, J = _dense(M), _dense(J)
    Js = (J * columns) / rows[:, None]
    U, s, Vt = np.linalg.svd(Js, full_matrices=True)
    r = int((s > tol * s[0]).sum()) if s.size and s[0] > 0 else 0
    Ur, sr, Vr, N = U[:, :r], s[:r], Vt[:r].T, Vt[r:].T
    Ms = (M * columns) * columns[:, None]
    Fs = columns * F
    x = Vr @ ((Ur.T @ (gamma / rows)) / sr)
    if N.shape[1]:
        x = x + N @ factor(N.T @ Ms @ N).solve(N.T @ (Fs - Ms @ x))
    mu = Ur @ ((Vr.T @ (Fs - Ms @ x)) / sr)
    return columns * x, mu / rows, r


def kkt_regularized(M, J, F, gamma, rows, columns, kappa: float = KAPPA):
    r"""``(qdd, lambda)`` of the regularised augmented system (unit-free)::

        [ M^   J^^T    ] [ x  ]   [ F^      ]
        [ J^   -kappa I ] [ mu ] = [ gamma^  ]

    with ``M^ = D M D / m0``, ``F^ = D F / m0`` (``m0`` the largest diagonal entry of
    ``D M D``), ``J^ = R^-1 J D``, ``gamma^ = R^-1 gamma``. Constraint directions with
    ``s^2 >> kappa`` are enforced exactly as in the index-1 equations (relative change
    ``kappa / s^2``); the ones with ``s^2 <~ kappa`` (an instant of dependency) are softened
    instead of amplified: the noise of a state a little off the constraints enters with at
    most ``1 / (2 sqrt(kappa))`` instead of ``1 / s_min``."""
    M, J = _dense(M), _dense(J)
    n, m = J.shape[1], J.shape[0]
    Js = (J * columns) / rows[:, None]
    Ms = (M * columns) * columns[:, None]
    m0 = float(np.abs(np.diag(Ms)).max(initial=0.0)) or 1.0
    K = np.zeros((n + m, n + m))
    K[:n, :n] = Ms / m0
    K[:n, n:] = Js.T
    K[n:, :n] = Js
    K[n:, n:] = -kappa * np.eye(m)
    x = factor(K).solve(np.concatenate((columns * F / m0, gamma / rows)))
    return columns * x[:n], m0 * x[n:] / rows


def project_regularized(system, t, q, qd, p, scaling, alpha: float = 1 / KAPPA,
                        tol: float = 1e-12,
                        max_iterations: int = 12):
    r"""Mass-orthogonal, regularised projection of ``(q, qd)`` onto the constraints (the
    projections of the augmented-Lagrangian index-3 methods): positions by
    Levenberg-Marquardt steps in the metric of ``M^`` (unit-free as
    :func:`kkt_regularized`)::

        (M^ + alpha J^^T J^) dx = -alpha J^^T Phi^

    then velocities ``(M^ + alpha J^^T J^) v = M^ v* + alpha J^^T rhs^``. Directions with
    ``alpha s^2 >> 1`` are projected exactly; a dependent direction at a singular instant
    (``s -> 0``) is left as it is rather than moved by ``1 / s``."""
    c = scaling.columns
    M = system.dynamics.terms(t, q, qd, np.zeros(system.m), p)[0]
    Ms = (M * c) * c[:, None]
    Ms = Ms / (float(np.abs(np.diag(Ms)).max(initial=0.0)) or 1.0)
    q = np.array(q, dtype=float)
    for _ in range(max_iterations):
        F, J = system.residual_and_jacobian(t, q, p)
        J = _dense(J)
        r = scaling.rows(J)
        Fs = F / r
        if np.abs(Fs).max(initial=0.0) <= tol * (1.0 + scaling.offset):
            break
        Js = (J * c) / r[:, None]
        q = q - c * factor(Ms + alpha * Js.T @ Js).solve(alpha * Js.T @ Fs)
    J, rhs = system.velocity_rhs(t, q, p)
    J = _dense(J)
    r = scaling.rows(J)
    Js = (J * c) / r[:, None]
    v = np.asarray(qd, dtype=float) / c
    v = factor(Ms + alpha * Js.T @ Js).solve(Ms @ v + alpha * Js.T @ (rhs / r))
    return q, c * v


class InZone(Exception):
    """Internal: a projection met a (nearly) singular Jacobian (reciprocal condition of
    ``J^ J^T`` below ``ZONE^2``); the caller uses :func:`project_regularized`."""


def in_zone(J, scaling) -> bool:
    """Whether the scaled ``J^`` has ``s_min / s_max`` below about ``ZONE``."""
    if J.shape[0] == 0:
        return False
    Js = scaling.scaled(J)
    try:
        return factor(Js @ Js.T).rcond < ZONE**2
    except Singular:
        return True


def zone_guard(system, scaling, rows):
    r"""A check ``guard(K, rhs, x)`` of a free-acceleration solution ``x = (qdd, lambda)`` of
    the augmented system ``K x = rhs`` (``x = None``: ``K`` is singular): ``None`` when the
    state is regular, else the regularised solution :func:`kkt_regularized`
    ``(qdd, lambda)``. ``rows``: row scales of the Jacobian at the start of the motion.

    Cheap first test: near a singular instant the multipliers grow like ``1 / s_min`` while
    the constraint forces ``Phi_q^T lambda`` stay bounded, so the ratio (unit-free)
    ``max |r lambda| / max |D Phi_q^T lambda|`` is at most about ``1 / s_min`` and large only
    near one; above ``1 / ZONE`` the reciprocal condition of ``J^ J^T`` decides
    (:func:`in_zone`). Row scales change with the configuration by bounded factors, which
    only move the cheap test's threshold."""
    n = system.n
    c = scaling.columns

    def guard(K, rhs, x):
        if x is None:                  # the augmented matrix is singular
            J = K[n:, :n]
            if not (np.all(np.isfinite(rhs)) and in_zone(J, scaling)):
                return None
            try:
                return solve_in_zone(scaling, K, rhs, n)
            except Singular:           # the mass matrix too: the caller's diagnosis
                return None
        lam = x[n:]
        big = np.abs(rows * lam).max(initial=0.0)
        if big == 0.0:
            return None
        force = np.abs(c * (K @ np.concatenate((np.zeros(n), lam)))[:n]).max(initial=0.0)
        if big < force / ZONE and np.isfinite(big):
            return None
        if not in_zone(K[n:, :n], scaling):
            return None
        return solve_in_zone(scaling, K, rhs, n)

    return guard


def solve_in_zone(scaling, K, rhs, n):
    """:func:`kkt_regularized` from the blocks of the augmented system ``K``, ``rhs``."""
    K = _dense(K)
    J = K[n:, :n]
    return kkt_regularized(K[:n, :n], J, rhs[:n], rhs[n:], scaling.rows(J), scaling.columns)


def min_norm_truncated(A, b, tol: float = RANK_TOL) -> np.ndarray:
    """Minimum-norm least-squares ``x`` of ``A x = b``, singular values below ``tol s_1``
    dropped: ``x = V_r S_r^-1 U_r^T b``."""
    U, s, Vt = truncated_svd(A, tol)
    return Vt.T @ ((U.T @ np.asarray(b, dtype=float)) / s)


def continue_position(system, t, guess, p, scaling, ftol: float = 1e-12,
                      max_iterations: int = 50):
    r"""Position at a singular instant of a kinematic sweep, from the sweep's prediction
    ``guess`` (on the branch the previous points followed): Gauss-Newton with minimum-norm
    steps on the truncated SVD of the scaled Jacobian, ``dq = -D pinv(J^) R^-1 Phi``. The
    dependent equations are consistent there (the mechanism assembles), so it converges to
    the solution nearest the prediction: the continuation of the branch. Returns ``(q,
    iterations, evaluations, residual)``; ``None`` when it does not converge."""
    q = np.array(guess, dtype=float)
    F, J = system.residual_and_jacobian(t, q, p)
    rows = scaling.rows(J)
    tol = ftol * (1.0 + scaling.offset)
    for it in range(max_iterations + 1):
        norm = np.abs(F / rows).max(initial=0.0)
        if norm <= tol and it > 0:
            return q, it, it + 1, norm
        if not np.isfinite(norm):
            return None
        q = q - scaling.columns * min_norm_truncated(scaling.scaled(_dense(J), rows), F / rows)
        F, J = system.residual_and_jacobian(t, q, p)
    return None


def continue_rates(J, b, predicted, scaling, rows) -> np.ndarray:
    r"""Velocities (or accelerations) at a singular instant of a sweep: of the solutions of
    the consistent, rank-deficient ``J x = b``, the one nearest (unit-free) to ``predicted``
    (extrapolated from the previous points): ``x = p + D pinv(J^) R^-1 (b - J p)``. The
    components the equations do not fix are those of the continuous branch."""
    predicted = np.asarray(predicted, dtype=float)
    res = (np.asarray(b, dtype=float) - _dense(J) @ predicted) / rows
    return predicted + scaling.columns * min_norm_truncated(scaling.scaled(_dense(J), rows), res)


# -- redundant but consistent constraints ---------------------------------------------------
def min_norm_multipliers(J_full, force, scaling) -> np.ndarray:
    r"""The minimum-norm multipliers ``lambda`` (unit-free: ``mu = R lambda`` of least norm)
    with ``Phi_q^T lambda = force`` for a Jacobian ``J_full`` with dependent rows::

        mu = pinv((R^-1 J D)^T) (D force),   lambda = R^-1 mu

    The components along rows that take no part in a dependency are unique (the
    determinate reactions, exact); the others are the minimum-norm share of an
    indeterminate set."""
    J = _dense(J_full)
    r = scaling.rows(J)
    Js = (J * scaling.columns) / r[:, None]
    return min_norm_truncated(Js.T, scaling.columns * np.asarray(force, dtype=float),
                              RANK_TOL) / r


def expand_multipliers(J_full, J_kept, lam_kept, scaling) -> np.ndarray:
    """Multipliers of every equation from those of the independent equations: the same
    constraint forces ``J_kept^T lam_kept``, shared by :func:`min_norm_multipliers`."""
    return min_norm_multipliers(J_full, _dense(J_kept).T @ np.asarray(lam_kept, dtype=float),
                                scaling)


def constraint_names(owners) -> list:
    """Names of the constraints among equation owners (the Euler-parameter normalisations,
    whose owner is a text label, left out)."""
    return [o.name for o in owners if not isinstance(o, str)]
