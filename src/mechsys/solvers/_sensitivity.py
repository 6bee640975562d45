r"""Parameter sensitivities by implicit differentiation (pure numerics on a System and its
compiled tangent kernels, ``compile/_sensitivity.py``).

For parameters ``p_1..p_k`` and a solution that satisfies, at every time,

.. math::

    \Phi(t, q, p) = 0, \quad \Phi_q \dot q + \Phi_t = 0, \quad \Phi_q \ddot q - \gamma = 0,
    \quad \Phi_q^T \lambda - Q - Q_v + M \ddot q = 0

differentiating with respect to ``p_i`` gives, level after level, linear equations with the
matrices of the solution itself (so the Jacobian is factorised once per time point):

.. math::

    \Phi_q s_q &= -\Phi_p e_i \\
    \Phi_q s_{\dot q} &= -(V_q s_q + V_p e_i), \qquad V = \Phi_q \dot q + \Phi_t \\
    \Phi_q s_{\ddot q} &= -(A_q s_q + A_{\dot q} s_{\dot q} + A_p e_i),
        \qquad A = \Phi_q \ddot q - \gamma \\
    (\Phi_q^T - Q_\lambda)\, s_\lambda &= -(R_q s_q + R_{\dot q} s_{\dot q}
        + R_{\ddot q} s_{\ddot q} + R_p e_i)

with ``s_q = dq/dp_i`` and so on; ``R`` is the load balance of the solution (statics:
:math:`\Phi_q^T \lambda - Q` at rest; inverse dynamics: :math:`\Phi_q^T \lambda - (Q + Q_v - M \ddot q)`).
Free motion (``free_tangent``) differentiates the augmented system instead:

.. math::

    \begin{bmatrix} M - Q_{\ddot q} & \Phi_q^T - Q_\lambda \\ \Phi_q & 0 \end{bmatrix}
    \begin{bmatrix} s_{\ddot q} \\ s_\lambda \end{bmatrix} =
    -\begin{bmatrix} R_q s_q + R_{\dot q} s_{\dot q} + R_p e_i \\
    A_q s_q + A_{\dot q} s_{\dot q} + A_p e_i \end{bmatrix}

the forward sensitivity equations :math:`\frac{d}{dt} s_q = s_{\dot q}`, :math:`\frac{d}{dt} s_{\dot q} =
s_{\ddot q}` of the
index-1 (acceleration level) form that the free-motion integrator solves.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dgesv as _dgesv

from .._errors import SingularJacobianError
from ._linalg import Scaling, factor
from ._position import describe_singular
from ._tolerances import Singular


class Tangent:
    """Packs argument rows ``[t, q, qd, qdd, lam, p, dq, dqd, dqdd, dlam, dp]`` for the
    tangent kernels of one system and ``k`` parameters and evaluates them in one batch."""

    def __init__(self, kernels):
        self.kernels = kernels
        s = kernels.system
        self.n, self.m, self.k = s.n, s.m, len(kernels.params)
        self.np = len(s.layout.p_symbols)

    def base(self, t, q, qd, qdd, lam, p) -> np.ndarray:
        """``(N, 1 + 3n + m + np)`` from arrays over N points (``None``: zeros)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        N, n, m = len(t), self.n, self.m
        X = np.zeros((N, 1 + 3 * n + m + self.np))
        X[:, 0] = t
        for off, a in ((1, q), (1 + n, qd), (1 + 2 * n, qdd)):
            if a is not None:
                X[:, off : off + n] = np.reshape(a, (N, n))
        if lam is not None:
            X[:, 1 + 3 * n : 1 + 3 * n + m] = np.reshape(lam, (N, m))
        X[:, 1 + 3 * n + m :] = p
        return X

    def directions(self, N, sq=None, sqd=None, sqdd=None, slam=None) -> np.ndarray:
        """``(N, k, 3n + m + k)``: the given sensitivities ``(N, k, n)`` (or ``(N, k, m)``)
        and the unit parameter direction ``e_i`` in row ``i``."""
        n, m, k = self.n, self.m, self.k
        D = np.zeros((N, k, 3 * n + m + k))
        for off, a, w in ((0, sq, n), (n, sqd, n), (2 * n, sqdd, n), (3 * n, slam, m)):
            if a is not None:
                D[:, :, off : off + w] = a
        D[:, np.arange(k), 3 * n + m + np.arange(k)] = 1.0
        return D

    def evaluate(self, f, X, D) -> np.ndarray:
        """``f`` over every (point, parameter): ``(N, k, outputs)``."""
        N, k = D.shape[0], D.shape[1]
        rows = np.concatenate((np.repeat(X, k, axis=0), D.reshape(N * k, -1)), axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            out = f.batch(rows)
        return out.reshape(N, k, -1)


def _factor_at(system, t, q, p, what):
    J = system.jacobian(t, q, p)
    sc = Scaling.of(system, q, J)
    try:
        return J, sc.factor(J)
    except Singular:
        raise describe_singular(system, J, t, q, what, sc) from None


def kinematic_sensitivities(tan: Tangent, t, q, qd, qdd, lam, p, orders: int,
                            mode: str | None = None, at_rest: bool = False):
    """``(sq, sqd, sqdd, slam)``, each ``(N, k, n)`` (``slam``: ``(N, k, m)``) or ``None``
    for the levels not asked: ``orders`` 0 (positions), 1 (and velocities), 2 (and
    accelerations); ``mode`` ``"static"``, ``"kinematic"`` or ``"dynamic"`` adds the
    multipliers. ``at_rest`` (statics): velocities and accelerations are zero."""
    K = tan.kernels
    system = K.system
    N = len(t)
    X = tan.base(t, q, None if at_rest else qd, None if at_rest else qdd, lam, p)
    facs, Js = [], []
    for j in range(N):
        J, fac = _factor_at(system, t[j], q[j], p, "sensitivity (implicit differentiation, "
                            "Phi_q dq/dp = -Phi_p)")
        facs.append(fac)
        Js.append(J)

    def level(name, **given):
        rhs = tan.evaluate(K.kernel(name), X, tan.directions(N, **given))
        out = np.empty((N, tan.k, tan.n))
        for j in range(N):
            for i in range(tan.k):
                out[j, i] = facs[j].solve(-rhs[j, i])
        return out

    sq = level("position")
    sqd = sqdd = slam = None
    if orders >= 1 and not at_rest:
        sqd = level("velocity", sq=sq)
    if orders >= 2 and not at_rest:
        sqdd = level("acceleration", sq=sq, sqd=sqd)
    if mode is not None:
        name = "dynamics" if mode == "dynamic" else "loads"
        rhs = tan.evaluate(K.kernel(name), X, tan.directions(N, sq=sq, sqd=sqd, sqdd=sqdd))
        dyn = system.dynamics
        slam = np.empty((N, tan.k, tan.m))
        for j in range(N):
            A = Js[j].T
            if dyn.depends_on_lambda:
                zero = np.zeros(tan.n)
                A = A - dyn.dQ_dlam(t[j], q[j], zero if (at_rest or qd is None) else qd[j],
                                    lam[j], p, None if (mode != "dynamic") else qdd[j])
            try:
                fac = factor(A)
            except Singular:
                raise describe_singular(system, Js[j], t[j], q[j],
                                        f"sensitivity of the {mode} multipliers") from None
            for i in range(tan.k):
                slam[j, i] = fac.solve(-rhs[j, i])
    return sq, sqd, sqdd, slam


def free_tangent(tan: Tangent, t, q, qd, qdd, lam, p, sq, sqd):
    """``(sqdd, slam)`` of free motion at one state for sensitivities ``sq, sqd`` ``(k, n)``
    (see the module docstring)."""
    K = tan.kernels
    system = K.system
    dyn = system.dynamics
    n, m = tan.n, tan.m
    X = tan.base([t], q, qd, qdd, lam, p)
    D = tan.directions(1, sq=sq[None], sqd=sqd[None])
    r1 = tan.evaluate(K.kernel("dynamics"), X, D)[0]
    r2 = tan.evaluate(K.kernel("acceleration"), X, D)[0] if m else np.zeros((tan.k, 0))
    M, _, _ = dyn.terms(t, q, qd, lam, p, qdd)
    A = np.zeros((n + m, n + m))
    A[:n, :n] = M - dyn.dQ_dqdd(t, q, qd, lam, p, qdd)
    if m:
        J = system.jacobian(t, q, p)
        A[:n, n:] = J.T - dyn.dQ_dlam(t, q, qd, lam, p, qdd)
        A[n:, :n] = J
    rhs = -np.concatenate((r1, r2), axis=1).T            # (n + m, k)
    # LAPACK gesv directly, as the free-motion solver does (scipy's lu_solve wrapper costs
    # milliseconds a call here)
    _, _, x, info = _dgesv(A, np.ascontiguousarray(rhs))
    big = np.abs(x).max(initial=0.0)
    if info != 0 or not big < 1e15 * (1.0 + np.abs(rhs).max(initial=0.0)):
        raise SingularJacobianError(
            f"free-motion sensitivity at t = {t:.6g}: the augmented matrix [[M, Phi_q^T], "
            "[Phi_q, 0]] is singular (a lock-up, redundant kept constraints or a massless "
            "free motion); the trajectory's sensitivity is not defined there", time=t,
            dependent=[], rank=None)
    return x[:n].T, x[n:].T


def held_least_squares(system, J, scaling: Scaling, b, hold) -> np.ndarray:
    """The smallest (unit-free) ``x`` with ``J x = -b`` and ``x[hold] = 0``, for each column
    of ``b`` ``(m, k)``: how the coordinates a projection does not hold follow a change of
    the constraints (the sensitivity of :func:`~mechsys.solvers._free.project_holding`)."""
    r = scaling.rows(J)
    Js = np.array(scaling.scaled(J, r), dtype=float)
    Js[:, list(hold)] = 0.0
    dx = np.linalg.lstsq(Js, -b / r[:, None], rcond=1e-12)[0]
    return (scaling.columns[:, None] * dx).T
