"""Independent references for the kinematic sweep and the multiplier solves (decision 0081).

Every regular point of a sweep is the loop's (``_jit_sweep_loop``, compiled or the same code
interpreted), so comparing ``MECHSYS_JIT=0`` with ``1`` compares the loop with itself. These
checks do not run the loop, nor the Python code's LAPACK calls:

* positions: the loop-closure residual :math:`\\Phi(t_k, q_k)` at every point;
* velocities and accelerations: :math:`\\Phi_q \\dot q = -\\Phi_t` and
  :math:`\\Phi_q \\ddot q = \\gamma` solved by ``numpy.linalg.solve`` (dense, unscaled) at the
  well-conditioned points (about a dozen of them above 60 unknowns), and the central
  differences of ``q`` and ``qd`` over the sweep's
  times (a check of the kinematic equations themselves, independent of the kernels' ``qd``
  and ``gamma``);
* multipliers: the load balance :math:`\\Phi_q^T \\lambda = Q + Q_v - M \\ddot q` solved by
  ``numpy.linalg.solve`` on the same terms (``dynamics.terms``).

Example::

    sol = model.solve(t)
    check_sweep(sol)
"""

from __future__ import annotations

import numpy as np


def _dense(J):
    return np.asarray(J.toarray() if hasattr(J, "toarray") else J, dtype=float)


def _points(n: int, N: int) -> range:
    """The points the dense solves check: every one for small models; for large ones (a
    dense solve of hundreds of unknowns costs milliseconds) about a dozen, evenly spread."""
    return range(0, N, 1 if n <= 60 else max(1, N // 12))


def check_sweep(sol, position_tol: float = 1e-9, rate_tol: float = 1e-8, rcond_min: float = 1e-6,
                differences: bool = True, difference_tol: float = 1e-9) -> None:
    r"""Assert the sweep ``sol`` (a ``Solution`` over times) against the references of the
    module docstring. ``position_tol``: the largest residual allowed (times ``1 +`` the
    model's length scale); ``rate_tol``: relative to the largest velocity (acceleration);
    points whose condition estimate is below ``rcond_min`` skip the dense solves (near a
    toggle the rates are amplified by the condition number). ``differences``: also compare
    ``qd`` with the fourth-order central differences of ``q`` (and ``qdd`` with those of
    ``qd``) at interior points of an evenly sampled sweep: their error,
    :math:`h^4 |X^{(5)}| / 30`, estimated by the fourth differences of ``qd`` (``qdd``) with a
    margin of 10, plus ``difference_tol`` relative to the largest velocity (acceleration)."""
    s, p, t = sol.system, sol.p, np.asarray(sol.t, dtype=float)
    Q = np.asarray(sol.q, dtype=float)
    scale = 1.0 + np.abs(Q).max()
    for k in range(len(t)):
        r = np.abs(s.residual(t[k], Q[k], p)).max()
        assert r <= position_tol * scale, f"loop closure at t = {t[k]:.6g}: residual {r:.3e}"
    if sol.qd is None:
        return
    QD = np.asarray(sol.qd, dtype=float)
    QDD = None if sol.qdd is None else np.asarray(sol.qdd, dtype=float)
    rc = np.asarray(sol.extra["rcond"], dtype=float)
    vmax, amax = np.abs(QD).max() + 1e-300, (0.0 if QDD is None else np.abs(QDD).max()) + 1e-300
    for k in _points(s.n, len(t)):
        if not rc[k] >= rcond_min:
            continue
        J, rhs = s.velocity_rhs(t[k], Q[k], p, False)
        b = rhs if QDD is None else np.column_stack([rhs, s.gamma_values(t[k], Q[k], QD[k], p)])
        x = np.linalg.solve(_dense(J), b)
        v = x if QDD is None else x[:, 0]
        assert np.abs(v - QD[k]).max() <= rate_tol * vmax, f"velocity at t = {t[k]:.6g}"
        if QDD is not None:
            assert np.abs(x[:, 1] - QDD[k]).max() <= rate_tol * amax, \
                f"acceleration at t = {t[k]:.6g}"
    if not differences or len(t) < 5:
        return
    h = np.diff(t)
    assert np.allclose(h, h[0], rtol=1e-9, atol=0), "central differences need even steps"
    ok = rc >= rcond_min
    good = np.flatnonzero(ok[:-4] & ok[1:-3] & ok[2:-2] & ok[3:-1] & ok[4:])
    for X, D, top in ((Q, QD, vmax), (QD, QDD, amax)):
        if D is None or not good.size:
            continue
        # the fourth-order central difference: error h^4 |X^(5)| / 30
        fd = (X[:-4] - 8 * X[1:-3] + 8 * X[3:-1] - X[4:]) / (12 * h[0])
        err = np.abs(fd - D[2:-2])[good].max()
        # that error estimated from the data (h^4 X^(5) ~ the fourth differences of D), with
        # a margin of 10
        tol = 10 * np.abs(np.diff(D, 4, axis=0))[good].max() / 30 + difference_tol * top
        assert err <= tol, f"central differences: {err:.3e} > {tol:.3e}"


def check_multipliers(sol, mode: str = "dynamic", tol: float = 1e-9, rcond_min: float = 1e-6) -> None:
    """Assert the multipliers ``sol.lam`` of ``sol`` solve the load balance
    :math:`\\Phi_q^T \\lambda = Q(t, q, \\dot q, \\lambda) + Q_v - M \\ddot q` (``mode``
    ``"dynamic"``; ``"kinematic"``: without the inertial terms; ``"static"``: ``qd = 0``) at
    every well-conditioned point, ``numpy.linalg.solve`` on the dense Jacobian, to ``tol``
    relative to the largest multiplier. Loads that depend on the multipliers are evaluated
    at the solution's own (a fixed-point check of the balance)."""
    s, p, t = sol.system, sol.p, np.asarray(sol.t, dtype=float)
    dyn = s.dynamics
    lam = np.asarray(sol.lam, dtype=float)
    rc = np.asarray(sol.extra["rcond"], dtype=float) if "rcond" in sol.extra else np.ones(len(t))
    top = np.abs(lam).max() + 1e-300
    for k in _points(s.n, len(t)):
        if not rc[k] >= rcond_min:
            continue
        q = np.asarray(sol.q[k], dtype=float)
        qd = np.zeros_like(q) if mode == "static" else np.asarray(sol.qd[k], dtype=float)
        qdd = np.asarray(sol.qdd[k], dtype=float) if mode == "dynamic" else None
        M, Qa, Qv = dyn.terms(t[k], q, qd, lam[k], p, qdd)
        b = Qa + Qv - M @ qdd if mode == "dynamic" else Qa
        J = _dense(s.jacobian(t[k], q, p, False))
        want = np.linalg.solve(J.T, b)
        assert np.abs(want - lam[k]).max() <= tol * top, f"multipliers at t = {t[k]:.6g}"
