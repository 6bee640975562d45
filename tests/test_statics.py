"""Static solutions: virtual work and hand-derived Newton-Euler reactions."""

import numpy as np
import pytest

import mechsys as ms
from mechsys import models


@pytest.fixture
def loaded_crank():
    r, L, F = 2.0, 6.0, -150.0
    m = models.slider_crank(crank=r, rod=L)
    m.add_load(ms.Force(m.body("piston").point(0), (1, 0), F))
    t = np.linspace(0.02, 0.98, 25)
    return m, m.solve(t, solution="static"), r, L, F, t


def test_crank_torque_by_virtual_work(loaded_crank):
    m, sol, r, L, F, t = loaded_crank
    th = 2 * np.pi * t
    s = -r * np.sin(th)
    dxdth = -r * np.sin(th) + s * (-r * np.cos(th)) / np.sqrt(L**2 - s**2) * -1
    # x = r cos th + sqrt(L^2 - r^2 sin^2 th)  ->  dx/dth = -r sin th - r^2 sin th cos th / root
    dxdth = -r * np.sin(th) - r**2 * np.sin(th) * np.cos(th) / np.sqrt(L**2 - (r * np.sin(th)) ** 2)
    # virtual work: tau dth + F dx = 0, tau = torque the driver applies to the crank
    tau = -F * dxdth
    _, moment = sol.reaction("drive", "crank")
    np.testing.assert_allclose(moment, tau, rtol=1e-9, atol=1e-9)
    # the driver's multiplier is minus that torque (reaction = -Phi_q^T lambda)
    np.testing.assert_allclose(sol.generalized("drive")[:, 0], -tau, atol=1e-9)


def test_joint_reactions_by_newton_euler(loaded_crank):
    m, sol, r, L, F, t = loaded_crank
    pin = sol.location(m.body("crank").point("pin"))
    piston = sol.location(m.body("piston").point(0))
    u = (piston - pin) / L                      # rod direction, crank pin -> piston
    f = -F / u[:, 0]                            # rod (two-force member) tension on piston: f u
    f_on_piston = f[:, None] * u
    # wrist pin on the piston
    Fp, Mp = sol.reaction("wrist pin", "piston")
    np.testing.assert_allclose(Fp, f_on_piston, atol=1e-8)
    # the rod gets the opposite at b, and +f u at a from the crank
    Fr_b, _ = sol.reaction("wrist pin", "rod")
    Fr_a, _ = sol.reaction("crank-rod", "rod")
    np.testing.assert_allclose(Fr_b, -f_on_piston, atol=1e-8)
    np.testing.assert_allclose(Fr_a, f_on_piston, atol=1e-8)
    # slider: normal force only, no moment about the piston origin
    Fs, Ms = sol.reaction("slider", "piston")
    np.testing.assert_allclose(Fs[:, 0], 0, atol=1e-8)
    np.testing.assert_allclose(Fs[:, 1], -f * u[:, 1], atol=1e-8)
    np.testing.assert_allclose(Ms, 0, atol=1e-8)
    # ground pivot on the crank balances the rod's push
    Fg, _ = sol.reaction("crank pin", "crank")
    np.testing.assert_allclose(Fg, f_on_piston, atol=1e-8)
    # reaction on ground is the opposite (third law)
    Fground, _ = sol.reaction("crank pin", m.ground)
    np.testing.assert_allclose(Fground, -f_on_piston, atol=1e-8)
    # moment of the rod's reaction about the rod's own point b vanishes (two-force member)
    _, Mb = sol.reaction("crank-rod", "rod", at=m.body("rod").point("b"))
    np.testing.assert_allclose(Mb, 0, atol=1e-8)


def test_local_coordinates_rotate_the_force(loaded_crank):
    m, sol, *_ = loaded_crank
    Fg, _ = sol.reaction("crank-rod", "rod")
    Fl, _ = sol.reaction("crank-rod", "rod", coordinates="local")
    th = sol.angle("rod")
    c, s = np.cos(th), np.sin(th)
    np.testing.assert_allclose(Fl[:, 0], c * Fg[:, 0] + s * Fg[:, 1], atol=1e-9)
    np.testing.assert_allclose(Fl[:, 1], -s * Fg[:, 0] + c * Fg[:, 1], atol=1e-9)


def test_gravity_static_pendulum_reaction():
    m = ms.Model2D()
    bar = m.add_body("bar", mass=3.0, centroid=(0.5, 0), inertia=0.1, guess=((0, 0), -1.0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), bar.point(0)), name="pivot")
    m.add(ms.RotationLock1(bar, -1.0), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    sol = m.solve(0.0, solution="static")
    F, M = sol.reaction("pivot", "bar")
    np.testing.assert_allclose(F, [0, 3 * 9.81], atol=1e-10)
    _, Mh = sol.reaction("hold", "bar")
    # weight at 0.5 (cos -1, sin -1) produces moment -0.5 cos(1) m g about the pivot
    np.testing.assert_allclose(Mh, 0.5 * np.cos(-1.0) * 3 * 9.81, atol=1e-10)
    # potential energy of gravity
    assert np.isclose(sol.potential_energy(), 3 * 9.81 * 0.5 * np.sin(-1.0))


def test_spring_static_balance():
    # slider on x axis held by a driver, spring to a ground point: driver balances spring
    m = ms.Model2D()
    s = m.add_body("slider", guess=((1.0, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), s.axis((0, 0), (1, 0))), name="slide")
    m.add(ms.RelativeX1(s.point(0), 1.0 + ms.T), name="pos")
    m.add_load(ms.Spring(s.point(0), (0, 0), stiffness=200.0, free_length=0.5))
    sol = m.solve([0.0, 0.5], solution="static")
    F, _ = sol.reaction("pos", "slider")
    x = np.array([1.0, 1.5])
    np.testing.assert_allclose(F[:, 0], 200.0 * (x - 0.5), atol=1e-9)
    np.testing.assert_allclose(sol.potential_energy(), 0.5 * 200 * (x - 0.5) ** 2)


@pytest.mark.parametrize("solution", ["static", "dynamic"])
def test_large_model_multipliers_solve_sparse(solution):
    """Above ``SPARSE_THRESHOLD`` coordinates the multiplier solve factorises the sparse
    Jacobian (through its pattern, as the sweep) and solves it transposed: the same
    multipliers as the dense solve of the same equations, and the load balance
    ``Phi_q^T lambda = Q + Qv - M qdd``."""
    from mechsys.solvers import solve_multipliers
    from mechsys.solvers._tolerances import SPARSE_THRESHOLD

    m = models.four_bar_chain(30)
    for b in m.bodies:
        if not b.is_ground:
            m.set_mass_properties(b.name, mass=1.0, centroid=(0.5, 0), inertia=0.1)
    m.add_load(ms.Gravity((0, -1), 9.81))
    s = m.compile()
    assert s.n > SPARSE_THRESHOLD
    sol = m.solve(np.linspace(0.1, 0.5, 3), solution=solution)
    for k in range(len(sol.t)):
        t, q = sol.t[k], sol.q[k]
        qd = None if sol.qd is None else sol.qd[k]
        qdd = None if sol.qdd is None else sol.qdd[k]
        J = s.jacobian(t, q, sol.p)                     # dense: the dense path
        dense, _ = solve_multipliers(s, s.dynamics, t, q, qd, qdd, sol.p, solution, J=J)
        scale = np.abs(dense).max()
        assert scale > 1.0 and np.abs(sol.lam[k] - dense).max() <= 1e-10 * scale
        M, Q, Qv = s.dynamics.terms(t, q, np.zeros(s.n) if qd is None else qd, sol.lam[k],
                                    sol.p, qdd)
        b = Q if solution == "static" else Q + Qv - M @ qdd
        np.testing.assert_allclose(J.T @ sol.lam[k], b, atol=1e-9 * np.abs(b).max())


def test_large_model_with_friction_newton_through_its_pattern(monkeypatch):
    """Above ``SPARSE_THRESHOLD`` coordinates the multiplier Newton of loads that depend on
    the multipliers (joint friction) factorises ``Phi_q^T - dQ/dlambda`` through its fixed
    pattern (rows matched, banded LU): the multipliers of the dense Newton, and the load
    balance with the friction loads at those multipliers."""
    from mechsys.solvers import _patterns, _statics
    from mechsys.solvers._tolerances import SPARSE_THRESHOLD

    m = models.four_bar_chain(30)
    for b in m.bodies:
        if not b.is_ground:
            m.set_mass_properties(b.name, mass=1.0, centroid=(0.5, 0), inertia=0.1)
    m.add_load(ms.Gravity((0, -1), 9.81))
    for k in range(31):
        m.add_load(ms.JointFriction(f"pivot{k}", mu=0.2, radius=0.05, v_eps=1e-3))
    s = m.compile()
    assert s.n > SPARSE_THRESHOLD and s.dynamics.depends_on_lambda
    t = np.linspace(0.1, 0.5, 3)
    sol = m.solve(t, solution="dynamic")
    rows, cols, pattern = _patterns.multiplier_newton_pattern(s)
    assert pattern.banded
    monkeypatch.setattr(_statics, "SPARSE_THRESHOLD", 10**6)
    dense = m.solve(t, solution="dynamic")
    np.testing.assert_allclose(sol.lam, dense.lam, rtol=0, atol=1e-9 * np.abs(dense.lam).max())
    for k in range(len(t)):
        M, Q, Qv = s.dynamics.terms(t[k], sol.q[k], sol.qd[k], sol.lam[k], sol.p, sol.qdd[k])
        J = s.jacobian(t[k], sol.q[k], sol.p)
        res = J.T @ sol.lam[k] - (Q + Qv - M @ sol.qdd[k])
        assert np.abs(res).max() <= 1e-8 * np.abs(J.T @ sol.lam[k]).max()
