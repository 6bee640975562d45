"""Free motion with velocity (nonholonomic) constraints (issue 36 item 1, decision 0053).

Checks against closed forms: the Chaplygin sleigh (a knife edge at distance ``a`` behind the
centroid: ``u' = a w^2``, ``(I + m a^2) w' = -m a u w``, so from ``u(0) = 0``
``w = w0 sech(k t)``, ``u = U tanh(k t)``, ``U = |w0| sqrt(J/m)``, ``k = a |w0| sqrt(m/J)``,
``J = I + m a^2``; Neimark & Fufaev, *Dynamics of Nonholonomic Systems*, ch. III, and
docs/nonholonomic.md for the derivation) and the steady turning of a rolling disk (lean
``beta``, heading rate ``W``, spin ``sigma = w . axis``:
``m R g sin(beta) + W cos(beta) ((I_a + m R^2) sigma - I_d W sin(beta)) = 0``).
"""

from __future__ import annotations

import numpy as np
import pytest

import mechsys as ms

MASS, INERTIA, OFFSET, W0 = 2.0, 0.3, 0.4, 2.0


def sleigh():
    m = ms.Model2D()
    b = m.add_body("sleigh", points={"P": (-OFFSET, 0.0)}, guess=((0.1, -0.2), 0.3),
                   mass=MASS, inertia=INERTIA)
    # the knife edge at P: no velocity across the body's x axis
    m.add(ms.Orthogonal1(m.velocity(b.point("P")), b.vector((0, 1))), name="knife")
    return m, b


def test_chaplygin_sleigh_closed_form_energy_and_reaction():
    m, b = sleigh()
    fs = m.free()
    assert fs.dof == 2 and fs.velocity_constraints[0].name == "knife"
    sol = fs.simulate(np.linspace(0, 3, 31), initial_condition={"th2_d": W0}, rtol=1e-10,
                      atol=1e-12)
    assert sol.extra["compiled_steps"] == 0 and sol.extra["compiled_solver"] is None
    th, w = sol["sleigh.th"], sol.omega(b)
    vP = sol.velocity(b.point("P"))
    u = vP[:, 0] * np.cos(th) + vP[:, 1] * np.sin(th)      # forward speed of the edge
    lateral = -vP[:, 0] * np.sin(th) + vP[:, 1] * np.cos(th)
    J = INERTIA + MASS * OFFSET**2
    U, k = W0 * np.sqrt(J / MASS), OFFSET * W0 * np.sqrt(MASS / J)
    assert np.abs(w - W0 / np.cosh(k * sol.t)).max() < 1e-8
    assert np.abs(u - U * np.tanh(k * sol.t)).max() < 1e-8
    assert np.abs(lateral).max() < 1e-12
    E = 0.5 * MASS * (sol.qd[:, 0]**2 + sol.qd[:, 1]**2) + 0.5 * INERTIA * w**2
    assert np.ptp(E) < 1e-8 * E[0] and E[0] == pytest.approx(0.5 * J * W0**2)
    # mu: the edge's lateral force on the body is -mu (along the body's y axis); Newton's
    # law across the body: F = m (u w + a w')
    mu = sol.extra["mu"][:, 0]
    assert sol.lam.shape == (31, 1) and sol.extra["velocity_multipliers"] == ["knife[0]"]
    F = MASS * (u * w + OFFSET * sol.qdd[:, 2])
    assert np.abs(-mu - F).max() < 1e-8 * np.abs(F).max()
    # the same through sol.reaction: the force -mu e_y at P, its moment about the centroid
    # (the body origin) (P - G) x F = a mu; on ground the opposite
    Fr, Mr = sol.reaction("knife", b)
    np.testing.assert_allclose(Fr, -mu[:, None] * np.c_[-np.sin(th), np.cos(th)], atol=1e-13)
    np.testing.assert_allclose(Mr, OFFSET * mu, atol=1e-13)
    np.testing.assert_allclose(sol.reaction("knife", m.ground)[0], -Fr, atol=1e-13)
    assert sol.extra["accuracy"]["nonholonomic"] < 1e-12


def test_drift_control_of_the_velocity_rows(monkeypatch):
    """Projected after each step (the default) the no-slip row holds to rounding; without the
    projection it drifts by the integration error, which the run reports (and warns about
    above its bound)."""
    m, b = sleigh()
    fs = m.free()
    kw = dict(initial_condition={"th2_d": W0}, rtol=1e-4, atol=1e-6)
    held = fs.simulate((0, 20), **kw).extra["accuracy"]["nonholonomic"]
    free = fs.simulate((0, 20), constraint_correction=False, **kw).extra["accuracy"]
    assert held < 1e-14 and 1e-8 < free["nonholonomic"] < 1e-3 and "warned" not in free
    # the warning's bound (max(DRIFT_WARNING, DRIFT_FACTOR tol), 1e-3 here) lowered below
    # that drift: the run says so
    from mechsys.analyses import _free

    monkeypatch.setattr(_free, "DRIFT_WARNING", 1e-9)
    monkeypatch.setattr(_free, "DRIFT_FACTOR", 0.0)
    with pytest.warns(ms.DegradedAccuracyWarning, match="velocity constraints have drifted"):
        sol = fs.simulate((0, 20), constraint_correction=False, **kw)
    assert sol.extra["accuracy"]["warned"] == "nonholonomic"


def test_free_solve_one_state_and_refusals():
    m, b = sleigh()
    one = m.free().solve(0.0, initial_condition={"th2_d": W0})
    # at u = 0 (the projected start): u' = a w^2, w' = 0, and the centroid's acceleration
    th = one.q[0, 2] if one.q.ndim == 2 else one.q[2]
    qdd = np.ravel(one.qdd)
    assert np.ravel(one.qd)[2] == W0
    a_G = qdd[:2]                            # the centroid's acceleration
    ex, ey = np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])
    # centroid: d/dt (u ex + a w ey) = u' ex - a w^2 ex at u = 0, w' = 0  ->  0
    assert abs(a_G @ ex) < 1e-12 and abs(a_G @ ey) < 1e-12
    assert qdd[2] == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(ms.ModelError, match="static.*velocity constraints.*knife"):
        m.free(solution="static")
    # linearised about straight sliding at speed U (decision 0054): J w' = -m a U w
    U, th0 = 1.5, 0.3
    lin = m.free().linearize({"sleigh.x_d": U * np.cos(th0), "sleigh.y_d": U * np.sin(th0)},
                             cyclic=["sleigh.x", "sleigh.y", "sleigh.th"],
                             speeds=["sleigh.x", "sleigh.th"])
    assert lin.states == ("sleigh.x_d", "sleigh.th_d")
    s = np.sort(lin.eigenvalues.real)
    assert s == pytest.approx([-MASS * OFFSET * U / (INERTIA + MASS * OFFSET**2), 0.0],
                              rel=1e-10, abs=1e-12)
    m.parameter("c", 1.0)
    with pytest.raises(ms.ModelError, match="sensitivity.*velocity constraints.*knife"):
        m.sensitivity(["c"], free=m.free())


def test_start_velocities_projected_with_the_velocity_rows():
    m, b = sleigh()
    fs = m.free()
    assert "velocity constraints knife" in repr(fs)
    # only the spin given: the centroid's velocity follows (smallest change) so that the edge
    # does not slip; the spin is kept
    one = fs.solve(0.0, initial_condition={"th2_d": W0, "x2_d": 0.0})
    qd, th = np.ravel(one.qd), np.ravel(one.q)[2]
    assert qd[2] == W0 and qd[0] == 0.0
    vP = qd[:2] + OFFSET * W0 * np.array([np.sin(th), -np.cos(th)])   # v_G + w x (P - G)
    assert abs(vP @ np.array([-np.sin(th), np.cos(th)])) < 1e-13
    # every velocity given, slipping: the constraint cannot be met while they are kept
    with pytest.raises(ms.ModelError, match=r"velocities \['sleigh.x_d', 'sleigh.y_d', "
                       r"'sleigh.th_d'\] are not allowed"):
        fs.solve(0.0, initial_condition={"th2_d": W0, "x2_d": 0.0, "y2_d": 0.0})


def test_dependent_velocity_rows_are_named():
    m, b = sleigh()
    m.add(ms.Orthogonal1(m.velocity(b.point("P")), b.vector((0, 2))), name="again")
    with pytest.raises(ms.SingularJacobianError, match="again.*knife|knife.*again"):
        m.free().solve(0.0, initial_condition={"th2_d": W0})


def test_switched_loads_with_velocity_constraints_refused():
    # (the event-driven stepper of switched models does not hold the velocity rows yet)
    m, b = sleigh()
    m.add_load(ms.TimeSwitch(ms.Force(b.point(0), (1, 0), 1.0), 1.0,
                             ms.Force(b.point(0), (1, 0), 2.0)))
    with pytest.raises(ms.ModelError, match="velocity constraints.*knife.*switches"):
        m.free()


def test_nonlinear_velocity_constraint_refused_by_name():
    m = ms.Model2D()
    b = m.add_body("b", guess=((0, 0), 0), mass=1, inertia=1)
    v = m.velocity(b.point(0))
    m.add(ms.Constraint([v[0] ** 2 - v[1]]), name="quadratic")
    with pytest.raises(ms.ModelError, match="quadratic.*not linear in the velocities"):
        m.free()


def test_rolling_disk_steady_turning_energy_and_constraints():
    R, g, beta, sigma = 0.3, 9.81, 0.3, 5.0
    Ia, Id = R**2 / 2, R**2 / 4                     # unit mass: a thin disk
    sb, cb = np.sin(beta), np.cos(beta)
    roots = np.roots([-Id * sb * cb, cb * (Ia + R**2) * sigma, R * g * sb])
    W = float(roots[np.argmin(abs(roots))].real)   # the slow steady turn
    m = ms.Model3D()
    # lean beta about the heading x: the axis (local y) at (0, cos, sin), contact at the origin
    disk = m.add_body("disk", guess=((0, -R * sb, R * cb), (np.cos(beta / 2), np.sin(beta / 2),
                                                            0, 0)), mass=1.0, inertia=(Id, Ia, Id))
    roll = ms.RollingDisk2(m.ground.axis((0, 0, 0), (0, 0, 1)), disk.axis(0, (0, 1, 0)), R)
    m.add(roll.holonomic(), name="touch")
    m.add(roll, name="roll")
    m.add_load(ms.Gravity((0, 0, -1), g))
    axis = np.array([0, cb, sb])
    w0 = W * np.array([0, 0, 1.0]) + (sigma - W * sb) * axis
    fs = m.free()
    assert fs.dof == 3
    sol = fs.simulate(np.linspace(0, 2, 21), initial_condition={("omega", "disk"): w0},
                      rtol=1e-10, atol=1e-12)
    assert sol.extra["compiled_steps"] == 0
    np.testing.assert_allclose(sol.velocity(disk.point(0))[0], [R * sigma, 0, 0], atol=1e-12)
    E = sol.body_energy() + sol.potential_energy()
    assert np.ptp(E) < 1e-8 * E[0]
    # constraints at position and velocity level
    acc = sol.extra["accuracy"]
    assert acc["position"] < 1e-10 and acc["velocity"] < 1e-10 and acc["nonholonomic"] < 1e-10
    assert np.abs(sol.eval(roll.slip_velocity())).max() < 1e-10
    # steady: lean, spin about the axis and heading rate stay those of the closed form
    e0, e1, e2, e3 = sol.q[:, 3:7].T
    a = np.c_[2 * (e1 * e2 - e0 * e3), e0**2 - e1**2 + e2**2 - e3**2, 2 * (e2 * e3 + e0 * e1)]
    assert np.abs(a[:, 2] - sb).max() < 1e-8
    assert np.abs(np.einsum("ij,ij->i", sol.omega(disk), a) - sigma).max() < 1e-8
    heading = np.unwrap(np.arctan2(a[:, 1], a[:, 0]))
    assert np.abs(heading - heading[0] - W * sol.t).max() < 1e-8
    # the contact forces: normal from the holonomic part's reaction, tangential -mu along the
    # plane's in-surface directions (here x, y); together they turn the centroid: m a_G = F + m g
    F_n, _ = sol.reaction("touch", disk)
    mu = sol.extra["mu"]
    assert sol.extra["velocity_multipliers"] == ["roll[0]", "roll[1]"]
    aG = sol.acceleration(disk.point(0))
    F = F_n + roll.tangential_force(sol)
    np.testing.assert_allclose(sol.reaction("roll", disk)[0], roll.tangential_force(sol),
                               atol=1e-12)
    np.testing.assert_allclose(F + np.array([0, 0, -g]), aG, atol=1e-8)
    # (the friction force is -(mu_1 h_1 + mu_2 f_1), h_1, f_1 the plane's directions of the
    # no-slip rows: for the normal z, h_1 = y and f_1 = -x)
    np.testing.assert_allclose(roll.tangential_force(sol)[:, :2], np.c_[mu[:, 1], -mu[:, 0]],
                               atol=1e-14)
    with pytest.raises(ms.ModelError, match="no multipliers of this constraint"):
        roll.tangential_force(m.free(drop=["roll"]).solve(0.0))


def test_rolling_circle_free_motion_matches_rack_and_pinion():
    """A second formulation: planar rolling integrates, so an eccentric wheel rocking on the
    ground under gravity moves the same with RollingCircle1 (velocity row, mu) as with
    RackAndPinion2 (position rows, lambda); the friction forces agree too."""
    rad, th0, t = 0.5, 0.5, np.linspace(0, 1.5, 16)

    def wheel_model():
        m = ms.Model2D()
        w = m.add_body("wheel", guess=((0.2, rad), th0), mass=1.0, inertia=0.05,
                       centroid=(0.15, 0.0))
        m.add_load(ms.Gravity((0, -1), 9.81))
        return m, w

    m, w = wheel_model()
    roll = ms.RollingCircle1(w.point(0), rad, m.ground.axis((0, 0), (1, 0)))
    m.add(roll.holonomic(), name="touch")
    m.add(roll, name="roll")
    fs = m.free()
    assert fs.dof == 1
    a = fs.simulate(t, rtol=1e-11, atol=1e-12)
    m2, w2 = wheel_model()
    m2.add(ms.RackAndPinion2(w2.point(0), rad, m2.ground.axis((0, 0), (1, 0)), 0.2 + rad * th0),
           name="rack")
    b = m2.free().simulate(t, rtol=1e-11, atol=1e-12)
    assert np.ptp(b.q[:, 2]) > 0.5                   # it rocks
    np.testing.assert_allclose(a.q, b.q, atol=1e-8)
    np.testing.assert_allclose(a.qd, b.qd, atol=1e-8)
    Fb, _ = b.reaction("rack", w2)
    Fa, _ = a.reaction("touch", w)
    np.testing.assert_allclose(Fa[:, 1], Fb[:, 1], atol=1e-7)        # normal force
    np.testing.assert_allclose(roll.tangential_force(a)[:, 0], Fb[:, 0], atol=1e-7)
    E = a.body_energy() + a.potential_energy()
    assert np.ptp(E) < 1e-9 * np.abs(E).max()
