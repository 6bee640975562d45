r"""Underconstrained (free) systems: free acceleration, equilibrium configuration and
equilibrium velocity. Pure numerics on a System and its Dynamics.

Free acceleration (``m < n`` equations), the augmented system::

    [ M      Phi_q^T ] [ qdd    ]   [ Q(t, q, qd, lambda) + Qv(q, qd) ]
    [ Phi_q  0       ] [ lambda ] = [ gamma(t, q, qd)                 ]

linear unless ``Q`` depends on ``lambda`` (friction): then Newton on ``(qdd, lambda)`` with
the Jacobian ``[[M, Phi_q^T - dQ/dlambda], [Phi_q, 0]]``.

Equilibrium configuration (static loads), unknowns ``(q, lambda)``::

    Phi(q, t) = 0,    Phi_q^T lambda - Q(t, q, 0, lambda) = 0

Equilibrium velocity (velocity-dependent loads, inertial terms excluded), unknowns
``(qd, lambda)`` at fixed ``q``::

    Phi_q qd + Phi_t = 0,    Phi_q^T lambda - Q(t, q, qd, lambda) = 0
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps
from scipy.linalg.lapack import dgesv as _dgesv

from .._errors import ConvergenceError
from ._linalg import SPARSE_THRESHOLD, Singular, factor
from ._position import describe_singular


def _augmented(M, J, D=None):
    n, m = M.shape[0], J.shape[0]
    JT = J.T if D is None else J.T - D
    if n + m > SPARSE_THRESHOLD:
        return sps.bmat([[sps.csc_matrix(M), sps.csc_matrix(JT)],
                         [sps.csc_matrix(J), None]], format="csc")
    K = np.zeros((n + m, n + m))
    K[:n, :n] = M
    K[:n, n:] = JT
    K[n:, :n] = J
    return K


def free_acceleration(system, t, q, qd, p, lam_guess=None, tol=1e-10, max_iterations=30):
    """``(qdd (n,), lambda (m,), iterations)`` of a free system at ``(t, q, qd)``."""
    dyn = system.dynamics
    n, m = system.n, system.m
    if not (dyn.depends_on_lambda or dyn.depends_on_qdd):
        kern = dyn.free_kernel(n + m > SPARSE_THRESHOLD)
        K, rhs = kern(t, q, qd, _ZERO_LAM.get(m) if m in _ZERO_LAM else _zeros(m), p)
        try:
            x = _solve_fast(K, rhs)
        except Singular:
            raise _singular_free(system, system.jacobian(t, q, p), t, q) from None
        return x[:n], x[n:], 0
    J = system.jacobian(t, q, p)
    g = system.gamma_values(t, q, qd, p)
    lam = np.ones(m) if lam_guess is None else np.array(lam_guess, dtype=float)
    qdd = np.zeros(n)
    Mm, Q, Qv = dyn.terms(t, q, qd, lam, p, qdd)
    for it in range(1, max_iterations + 1):
        r1 = Mm @ qdd + J.T @ lam - Q - Qv
        r2 = J @ qdd - g
        err = max(np.abs(r1).max(initial=0), np.abs(r2).max(initial=0))
        if err <= tol * (1 + np.abs(Q).max(initial=0)) and it > 1:
            return qdd, lam, it - 1
        D = dyn.dQ_dlam(t, q, qd, lam, p, qdd)
        Meff = Mm - dyn.dQ_dqdd(t, q, qd, lam, p, qdd)
        try:
            dx = factor(_augmented(Meff, J, D)).solve(-np.concatenate((r1, r2)))
        except Singular:
            raise _singular_free(system, J, t, q) from None
        qdd, lam = qdd + dx[:n], lam + dx[n:]
        Mm, Q, Qv = dyn.terms(t, q, qd, lam, p, qdd)
    raise ConvergenceError(
        f"free acceleration at t = {t:.6g}: the loads that depend on multipliers (friction) or "
        f"accelerations did not converge in {max_iterations} iterations (residual {err:.3e}); "
        "try lambda_guess=.",
        time=t)


_ZERO_LAM: dict = {}


def _zeros(m):
    _ZERO_LAM[m] = np.zeros(m)
    return _ZERO_LAM[m]


def _solve_fast(K, rhs):
    """Solve the augmented system; LAPACK gesv for dense (a singular matrix raises), SuperLU
    for sparse. A non-finite answer is treated as singular."""
    if sps.issparse(K):
        return factor(K).solve(rhs)
    _, _, x, info = _dgesv(K, rhs)
    if info != 0:
        raise Singular("singular augmented matrix")
    big = np.abs(x).max(initial=0.0)
    if not big < 1e15 * (1.0 + np.abs(rhs).max(initial=0.0)):   # also catches NaN
        raise Singular("ill-conditioned augmented matrix")
    return x


def _singular_free(system, J, t, q):
    err = describe_singular(system, J, t, q, "free acceleration")
    msg = (str(err) + " If the constraints are independent, the mass matrix may be singular on "
           "the free motions: a massless body (or zero inertia) whose motion no constraint "
           "determines. Give it mass/inertia or constrain it.")
    err.args = (msg,)
    return err


def project_positions(system, t, q, p, tol=1e-12, max_iterations=8):
    """Minimum-norm correction of ``q`` onto ``Phi(q, t) = 0``: ``dq = -J^T (J J^T)^-1 Phi``,
    iterated."""
    q = np.array(q, dtype=float)
    if system.m == 0:
        return q
    sparse = system.n > SPARSE_THRESHOLD
    for _ in range(max_iterations):
        F, J = system.residual_and_jacobian(t, q, p, sparse)
        if np.abs(F).max(initial=0.0) <= tol:
            break
        q -= J.T @ factor(J @ J.T).solve(F)
    return q


def project(system, t, q, qd, p, tol=1e-12, max_iterations=8):
    """Project ``(q, qd)`` onto the constraints: positions by :func:`project_positions`,
    then ``dqd = -J^T (J J^T)^-1 (J qd + Phi_t)``."""
    q = project_positions(system, t, q, p, tol, max_iterations)
    sparse = system.n > SPARSE_THRESHOLD
    J, rhs = system.velocity_rhs(t, q, p, sparse)
    JJt = J @ J.T
    qd = qd - J.T @ factor(JJt).solve(J @ qd - rhs)
    return q, qd


def _damped_newton(evaluate, x, n, t, what, hint, tol=1e-10, max_iterations=50):
    """Newton with Armijo backtracking on ``R(x) = 0``; ``evaluate(x) -> (R, K)``."""
    history = []
    for it in range(max_iterations + 1):
        R, K = evaluate(x)
        err = np.abs(R).max(initial=0.0)
        history.append(err)
        if err <= tol * (1 + np.abs(x).max()):
            return x, it
        try:
            dx = factor(K).solve(-R)
        except Singular:
            raise ConvergenceError(
                f"{what} at t = {t:.6g}: singular Jacobian (residual {err:.3e}); {hint}",
                time=t, history=tuple(history)) from None
        a = 1.0
        while a > 1e-3:
            xn = x + a * dx
            Rn, _ = evaluate(xn)
            if np.abs(Rn).max(initial=0.0) < (1 - 1e-4 * a) * err:
                break
            a *= 0.5
        x = xn
    raise ConvergenceError(
        f"{what} at t = {t:.6g} did not converge in {max_iterations} iterations "
        f"(residual {history[-1]:.3e}); start from a better guess (e.g. the previous solution).",
        time=t, history=tuple(history))


def equilibrium_configuration(eq, system, t, q0, lam0, p, tol=1e-10, max_iterations=50):
    """Newton on ``(q, lambda)`` for the static equilibrium (``eq`` the compiled residual
    ``R(q, lambda)`` and its Jacobian, from ``compile._free``). Returns ``(q, lam, its)``."""
    n = system.n
    x, its = _damped_newton(
        lambda x: eq.evaluate(t, x[:n], x[n:], p), np.concatenate((q0, lam0)), n, t,
        "equilibrium", "the loads may not fix the free coordinates (a neutral direction, e.g. "
        "no load along a free motion) or the guess is at a maximum of potential.", tol,
        max_iterations)
    return x[:n], x[n:], its


def equilibrium_velocity(eqv, system, t, q, qd0, lam0, p, tol=1e-10, max_iterations=50):
    """Newton on ``(qd, lambda)`` for the velocity equilibrium at fixed ``q``."""
    n = system.n
    x, its = _damped_newton(
        lambda x: eqv.evaluate(t, q, x[:n], x[n:], p), np.concatenate((qd0, lam0)), n, t,
        "equilibrium velocity", "the velocity-dependent loads may not determine the free "
        "velocities.", tol, max_iterations)
    return x[:n], x[n:], its
