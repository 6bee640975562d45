r"""Velocity constraints inside the stages of switches in free motion (issue 36 item 1,
decision 0063): a knife edge that touches down or lifts off at a stage change.

The body is the Chaplygin sleigh of ``examples/chaplygin_sleigh.py`` (mass ``m``, inertia
``I`` about the centroid ``G``, the blade's contact ``P`` a distance ``a`` behind ``G`` on
the body's axis ``e1``; ``e2`` across it). With the blade along ``e1`` (no velocity of ``P``
along ``e2``) the rigid-body kinematics ``v_P = v_G - a w e2`` give the row
``v_G . e2 - a w = 0``.

**Touch-down (the plastic impulse).** An impulse ``P_n e2`` at ``P`` changes
``m v_G`` by ``P_n e2`` and ``I w`` by ``(-a e1) x (P_n e2) = -a P_n``. The lateral
velocity of the contact before, ``s = v_G . e2 - a w``, is removed when
``s + P_n / m + a^2 P_n / I = 0``: ``P_n = -m_e s`` with ``m_e = m I / (I + m a^2)``.
The velocity along the blade ``v_G . e1`` is kept, ``w+ = w - a P_n / I``, and the kinetic
energy lost is ``m_e s^2 / 2`` (``m s^2 / 2`` for a blade under the centroid, ``a = 0``).
Afterwards the sleigh moves by its minimal equations ``u' = a w^2``,
``(I + m a^2) w' = -m a u w`` (solved here by SciPy, independently of mechsys).

**Lift-off.** The rows just drop: the velocities are kept and the body slides freely, the
centroid in a straight line at its velocity and the heading at constant spin.

**A blade that turns across** (``v_P . e1 = 0`` after): the impulse along ``e1`` at ``P``
passes through ``G`` (no moment), so ``w`` is kept, the speed ``u`` of ``P`` along ``e1`` is
removed and ``m u^2 / 2`` lost; then ``v_G = (v_P . e2 + a w) e2`` with ``m (v_G . e2)' = 0``
and ``I w' = 0`` (the force along ``e1`` at ``P`` has no moment about ``G``): the centroid
runs on a circle of radius ``sigma / w`` at the speed ``sigma = a w`` with the edge's force
``m sigma w`` towards the centre.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechsys as ms
from conftest import load_example

_example = load_example("chaplygin_sleigh")
MASS, INERTIA, OFFSET, W0 = _example.MASS, _example.INERTIA, _example.OFFSET, _example.W0
START = _example.START
J = INERTIA + MASS * OFFSET**2


def _body():
    m = ms.Model2D()
    b = m.add_body("sleigh", points={"P": (-OFFSET, 0.0)}, guess=START, mass=MASS,
                   inertia=INERTIA)
    return m, b, m.velocity(b.point("P"))


def _blade(b, v, along=(1, 0)):
    """A knife edge at P along the body direction ``along`` (no velocity of P across it)."""
    return ms.Orthogonal1(v, b.vector((-along[1], along[0])))


def _minimal(t, s):
    """The sleigh on its blade, minimal equations (``x, y`` of G, heading, ``u``, ``w``)."""
    x, y, th, u, w = s
    c, sn = np.cos(th), np.sin(th)
    return [u * c - OFFSET * w * sn, u * sn + OFFSET * w * c, w, OFFSET * w * w,
            -MASS * OFFSET * u * w / J]


def _frame(th):
    return np.c_[np.cos(th), np.sin(th)], np.c_[-np.sin(th), np.cos(th)]


def _energy(sol):
    return 0.5 * MASS * (sol.qd[:, 0]**2 + sol.qd[:, 1]**2) + 0.5 * INERTIA * sol.qd[:, 2]**2


def test_sliding_sleigh_whose_blade_touches_down_at_a_time_switch():
    m, b, v = _body()
    # stage 1 dropped (free sliding), stage 2 the blade: it touches down at t = 1
    m.add(ms.TimeSwitch(_blade(b, v), 1.0, _blade(b, v)), name="edge")
    fs = m.free(drop=[("edge", 1)])
    t = np.linspace(0, 2.5, 26)
    qd0 = np.array([0.5, 0.8, 1.0])
    ic = dict(zip(("sleigh.x_d", "sleigh.y_d", "sleigh.th_d"), qd0))
    # the blade meets a lateral velocity: an impact the model does not describe by itself
    with pytest.raises(ms.ModelError, match="switch 'edge' changes from stage \\[1\\] to \\[2\\]"
                       " at t = 1 with velocities its new stage does not allow"):
        fs.simulate(t, initial_condition=ic, rtol=1e-11, atol=1e-13)
    sol = fs.simulate(t, initial_condition=ic, at_switch="project", rtol=1e-11, atol=1e-13)
    (ev,) = sol.extra["events"]
    assert ev["t"] == pytest.approx(1.0, abs=1e-12) and ev["policy"] == "project"
    before, after = t < 1, t >= 1
    q0 = np.array([*START[0], START[1]])
    # free sliding before: constant velocities, no multiplier (the row is not in effect)
    assert np.abs(sol.q[before] - (q0 + np.outer(t[before], qd0))).max() < 1e-12
    assert np.abs(sol.qd[before] - qd0).max() < 1e-12
    assert sol.extra["velocity_multipliers"] == ["edge.stage2[0]"]
    assert np.isnan(sol.extra["mu"][before]).all() and np.isfinite(sol.extra["mu"][after]).all()
    assert list(sol.extra["stages"]["edge"]) == [1] * 10 + [2] * 16
    # the plastic impulse (module docstring): lateral slip s removed, u kept
    th1 = START[1] + qd0[2]
    e1, e2 = _frame(np.array([th1]))
    u1 = float(qd0[:2] @ e1[0])
    s = float(qd0[:2] @ e2[0]) - OFFSET * qd0[2]
    me = MASS * INERTIA / J
    Pn = -me * s
    w1 = qd0[2] - OFFSET * Pn / INERTIA
    assert ev["energy_lost"] == pytest.approx(0.5 * me * s**2, rel=1e-12)
    assert ev["impulse"] == pytest.approx([-Pn], rel=1e-12)   # (K [qd; x] = [M qd-; .]: x = -P)
    # after: the Chaplygin sleigh from (G, th1, u1, w1), an independent ODE
    G1 = q0[:2] + qd0[:2]
    ref = solve_ivp(_minimal, (1.0, 2.5), [*G1, th1, u1, w1], t_eval=t[after], rtol=1e-12,
                    atol=1e-14, method="DOP853").y.T
    th = sol["sleigh.th"]
    e1, e2 = _frame(th)
    u = np.sum(sol.qd[:, :2] * e1, axis=1)
    w = sol.qd[:, 2]
    err = {"q": np.abs(sol.q[after] - ref[:, :3]).max(), "u": np.abs(u[after] - ref[:, 3]).max(),
           "w": np.abs(w[after] - ref[:, 4]).max()}
    assert max(err.values()) < 1e-9, err
    assert np.abs(np.sum(sol.qd[after, :2] * e2[after], axis=1) - OFFSET * w[after]).max() < 1e-13
    # the edge's force -mu e2 at P: Newton across the body, m (u w + a w') = -mu
    F = MASS * (u * w + OFFSET * sol.qdd[:, 2])
    mu = sol.extra["mu"][:, 0]
    assert np.abs(mu[after] + F[after]).max() < 1e-9
    # sol.reaction of the switch: nothing while sliding, then the blade's force -mu e2 at P
    # and its moment (P - G) x F = a mu about the centroid
    Fr, Mr = sol.reaction("edge", b)
    assert np.abs(Fr[before]).max() == 0 and np.abs(Mr[before]).max() == 0
    np.testing.assert_allclose(Fr[after], -mu[after, None] * e2[after], atol=1e-14)
    np.testing.assert_allclose(Mr[after], OFFSET * mu[after], atol=1e-14)
    # an ideal blade does no work: no power before (dropped) nor after (-mu^T A qd = 0)
    np.testing.assert_allclose(sol.power("edge"), 0.0, atol=1e-12)
    E = _energy(sol)
    assert np.abs(E[after] - (E[0] - ev["energy_lost"])).max() < 1e-10
    assert sol.extra["accuracy"]["nonholonomic"] < 1e-12
    # restitution applies to position rows (a stop); a blade that starts grips: the same
    # plastic touch-down, not a sideways rebound
    grip = fs.simulate(t, initial_condition=ic, at_switch=("restitution", 0.5), rtol=1e-11,
                       atol=1e-13)
    (ev2,) = grip.extra["events"]
    assert ev2["policy"] == "project" and ev2["stage_after"] == [2]
    assert np.abs(grip.qd - sol.qd).max() < 1e-12


def test_knife_edge_released_at_a_heading_event_slides_on_freely():
    STOP = START[1] + 0.5
    m, b, v = _body()
    # the blade lifts off when the heading reaches STOP (stage 2 dropped: free sliding)
    m.add(ms.StageSwitch((b.q[2] < STOP, _blade(b, v)), (True, _blade(b, v))), name="lift")
    fs = m.free(drop=[("lift", 2)])
    t = np.linspace(0, 1.2, 13)
    sol = fs.simulate(t, initial_condition={"th2_d": W0}, rtol=1e-11, atol=1e-13)
    (ev,) = sol.extra["events"]
    # the Chaplygin closed form (examples/chaplygin_sleigh.py) up to the event
    k = OFFSET * W0 * np.sqrt(MASS / J)
    te = 2 * np.arctanh(np.tan(0.25 * k / W0)) / k      # th0 + (W0 / k) gd(k te) = STOP
    assert ev["t"] == pytest.approx(te, abs=1e-9)
    assert ev["policy"] == "compatible" and abs(ev["energy_lost"]) < 1e-12
    assert "impulse" not in ev
    u_cf, w_cf, th_cf, P_cf = _example.closed_form(np.array([*t[t < te], te]))
    before, after = t < te, t > te
    th, w = sol["sleigh.th"], sol.qd[:, 2]
    e1, e2 = _frame(th)
    u = np.sum(sol.qd[:, :2] * e1, axis=1)
    assert np.abs(th[before] - th_cf[:-1]).max() < 1e-9
    assert np.abs(u[before] - u_cf[:-1]).max() < 1e-9 and np.abs(w[before] - w_cf[:-1]).max() < 1e-9
    # lift-off keeps the velocities: the centroid goes on straight at v_G(te) = u e1 + a w e2,
    # the heading at the constant spin w(te)
    ce, se = np.cos(STOP), np.sin(STOP)
    Ge = P_cf[-1] + OFFSET * np.array([ce, se])
    vGe = u_cf[-1] * np.array([ce, se]) + OFFSET * w_cf[-1] * np.array([-se, ce])
    dt = t[after] - te
    assert np.abs(sol.q[after, :2] - (Ge + np.outer(dt, vGe))).max() < 1e-9
    assert np.abs(th[after] - (STOP + w_cf[-1] * dt)).max() < 1e-9
    assert np.abs(sol.qd[after, :2] - vGe).max() < 1e-9
    assert np.abs(sol.qdd[after]).max() < 1e-12
    # the multiplier columns: the blade of stage 1 in effect before, NaN after
    assert sol.extra["velocity_multipliers"] == ["lift.stage1[0]"]
    mu = sol.extra["mu"][:, 0]
    assert np.isfinite(mu[before]).all() and np.isnan(mu[after]).all()
    F = MASS * (u * w + OFFSET * sol.qdd[:, 2])
    assert np.abs(mu[before] + F[before]).max() < 1e-9
    E = _energy(sol)
    assert np.ptp(E) < 1e-10 * E[0]


def test_blade_turning_across_at_a_time_switch_columns_and_reset():
    # stage 1: the sleigh's blade along e1; stage 2 (t >= 1): a blade at P along e2. Every
    # row has its column in mu, NaN while its stage is not in effect
    m, b, v = _body()
    m.add(ms.TimeSwitch(_blade(b, v), 1.0, _blade(b, v, along=(0, 1))), name="edge")
    fs = m.free()
    t = np.linspace(0, 2, 11)
    with pytest.raises(ms.ModelError, match="switch 'edge'.*at t = 1 with velocities"):
        fs.simulate(t, initial_condition={"th2_d": W0}, rtol=1e-11, atol=1e-13)
    sol = fs.simulate(t, initial_condition={"th2_d": W0}, at_switch="project", rtol=1e-11,
                      atol=1e-13)
    assert sol.extra["velocity_multipliers"] == ["edge.stage1[0]", "edge.stage2[0]"]
    mu = sol.extra["mu"]
    one, two = t < 1, t >= 1
    assert np.isfinite(mu[one, 0]).all() and np.isnan(mu[one, 1]).all()
    assert np.isnan(mu[two, 0]).all() and np.isfinite(mu[two, 1]).all()
    (ev,) = sol.extra["events"]
    u_cf, w_cf, th_cf, P_cf = _example.closed_form(np.array([0.0, 1.0]))
    ue, we, the = u_cf[-1], w_cf[-1], th_cf[-1]
    # the impulse along e1 at P passes through G: w kept, u removed, m u^2 / 2 lost
    assert ev["energy_lost"] == pytest.approx(0.5 * MASS * ue**2, rel=1e-9)
    # then a circle: speed sigma = a w along e2, heading at constant w
    sigma = OFFSET * we
    Ge = P_cf[-1] + OFFSET * np.array([np.cos(the), np.sin(the)])
    th = the + we * (t[two] - 1.0)
    G = Ge + (sigma / we) * np.c_[np.cos(th) - np.cos(the), np.sin(th) - np.sin(the)]
    assert np.abs(sol.q[two, :2] - G).max() < 1e-9
    assert np.abs(sol["sleigh.th"][two] - th).max() < 1e-9
    assert np.abs(sol.qd[two, 2] - we).max() < 1e-9
    # the row of stage 2 is v_P . n with n = -e1 (the blade along e2), its force on the body
    # -mu n = mu e1; Newton: m d(sigma e2)/dt = -m sigma w e1 (towards the circle's centre)
    assert np.abs(mu[two, 1] + MASS * sigma * we).max() < 1e-9
    E = _energy(sol)
    assert np.abs(E[two] - (E[0] - ev["energy_lost"])).max() < 1e-10


def test_outside_and_inside_rows_share_the_reset_and_the_columns():
    # the sleigh's own blade outside the switch (every stage) and a second blade under the
    # centroid that touches down at t = 0.5: the plastic impact onto {no slip at P and at
    # G} stops the spin and keeps u (the metric is diagonal in u, v_G . e2, w): J w^2 / 2 lost
    m, b = _example.sleigh()
    vG = m.velocity(b.point(0))
    m.add(ms.TimeSwitch(ms.Orthogonal1(vG, b.vector((0, 1))), 0.5,
                        ms.Orthogonal1(vG, b.vector((0, 1)))), name="front")
    fs = m.free(drop=[("front", 1)])
    t = np.linspace(0, 1, 5)
    sol = fs.simulate(t, initial_condition={"th2_d": W0}, at_switch="project", rtol=1e-11,
                      atol=1e-13)
    assert sol.extra["velocity_multipliers"] == ["knife[0]", "front.stage2[0]"]
    mu = sol.extra["mu"]
    assert np.isfinite(mu[:, 0]).all() and np.isnan(mu[:2, 1]).all()
    (ev,) = sol.extra["events"]
    assert len(ev["impulse"]) == 2                  # the outside blade's row, then the new one
    u_cf, w_cf, th_cf, _ = _example.closed_form(np.array([0.0, 0.5]))
    assert ev["energy_lost"] == pytest.approx(0.5 * J * w_cf[-1]**2, rel=1e-9)
    e1, _ = _frame(sol["sleigh.th"])
    u = np.sum(sol.qd[:, :2] * e1, axis=1)
    assert np.abs(u[2:] - u_cf[-1]).max() < 1e-9 and np.abs(sol.qd[2:, 2]).max() < 1e-12
    # straight on: no force on either blade; before, the sleigh's blade (outside the switch:
    # sol.reaction evaluated stage by stage) carries -mu e2 at P
    assert np.abs(mu[2:]).max() < 1e-12
    th = sol["sleigh.th"]
    Fr, Mr = sol.reaction("knife", b)
    np.testing.assert_allclose(Fr, -mu[:, :1] * np.c_[-np.sin(th), np.cos(th)], atol=1e-14)
    np.testing.assert_allclose(Mr, OFFSET * mu[:, 0], atol=1e-14)
    assert np.abs(sol.reaction("front", b)[0]).max() < 1e-12
    # one state in each stage (FreeSystem.solve): the same columns
    one = fs.solve(0.25, initial_condition={"th2_d": W0})
    assert one.extra["mu"].shape == (1, 2) and np.isnan(one.extra["mu"][0, 1])
    names = ["sleigh.x", "sleigh.y", "sleigh.th", "sleigh.x_d", "sleigh.y_d", "sleigh.th_d"]
    two = fs.solve(0.75, initial_condition=dict(zip(names, np.r_[sol.q[3], sol.qd[3]])))
    assert np.isfinite(two.extra["mu"]).all()
    assert two.extra["mu"][0] == pytest.approx(mu[3], abs=1e-12)
    # a spin the two blades do not allow, given as held: refused by name
    with pytest.raises(ms.ModelError, match=r"velocities \['sleigh.th_d'\] are not allowed"):
        fs.solve(0.75, initial_condition={"th2_d": W0})


def test_blade_that_lifts_as_a_heading_lock_takes_over():
    # stage 1 the sleigh's blade, stage 2 (t >= 1) a lock of the heading at its value then:
    # a velocity row ends and a position row starts (the stages differ in position rows).
    # The lock's impulse is a pure moment: w is removed, v_G kept, I w^2 / 2 lost; then
    # the centroid runs straight on at v_G(1) = u e1 + a w e2
    u_cf, w_cf, th_cf, P_cf = _example.closed_form(np.array([0.0, 1.0]))
    ue, we, the = u_cf[-1], w_cf[-1], th_cf[-1]
    m, b, v = _body()
    m.add(ms.TimeSwitch(_blade(b, v), 1.0, ms.RotationLock1(b, the)), name="edge")
    fs = m.free()
    t = np.linspace(0, 1.5, 4)
    with pytest.raises(ms.ModelError, match="switch 'edge'.*at t = 1 with velocities"):
        fs.simulate(t, initial_condition={"th2_d": W0}, rtol=1e-11, atol=1e-13)
    sol = fs.simulate(t, initial_condition={"th2_d": W0}, at_switch="project", rtol=1e-11,
                      atol=1e-13)
    (ev,) = sol.extra["events"]
    assert ev["energy_lost"] == pytest.approx(0.5 * INERTIA * we**2, rel=1e-9)
    two = t >= 1
    e1 = np.array([np.cos(the), np.sin(the)])
    e2 = np.array([-np.sin(the), np.cos(the)])
    vG = ue * e1 + OFFSET * we * e2
    Ge = P_cf[-1] + OFFSET * e1
    assert np.abs(sol.q[two, :2] - (Ge + np.outer(t[two] - 1, vG))).max() < 1e-9
    assert np.abs(sol.q[two, 2] - the).max() < 1e-12 and np.abs(sol.qd[two, 2]).max() < 1e-12
    mu = sol.extra["mu"][:, 0]
    assert np.isfinite(mu[~two]).all() and np.isnan(mu[two]).all()
    # the lock's multiplier column (zero while the blade holds: no such row in stage 1) and
    # its moment (none needed to go straight on)
    assert sol.lam.shape == (4, 1) and np.abs(sol.lam).max() < 1e-12
    Fr, Mr = sol.reaction("edge", b)
    th = sol["sleigh.th"]
    np.testing.assert_allclose(Fr[~two], -mu[~two, None] * np.c_[-np.sin(th), np.cos(th)][~two],
                               atol=1e-14)
    assert np.abs(Fr[two]).max() < 1e-12 and np.abs(Mr[two]).max() < 1e-12


def test_linearize_in_the_stage_its_tests_choose():
    # straight on at speed u along the heading: free sliding before the blade touches down
    # (a free body: every eigenvalue zero), on the blade after: the spin decays at the rate
    # m a u / J (from (I + m a^2) w' = -m a u w), the eigenvalue the closed form gives
    m, b, v = _body()
    m.add(ms.TimeSwitch(_blade(b, v), 1.0, _blade(b, v)), name="edge")
    fs = m.free(drop=[("edge", 1)])
    u = 0.7
    state = {"sleigh.x_d": u * np.cos(START[1]), "sleigh.y_d": u * np.sin(START[1]),
             "sleigh.th_d": 0.0}
    cyc = ["sleigh.x", "sleigh.y"]
    sliding = fs.linearize(state, t=0.5, cyclic=cyc)
    assert np.abs(sliding.eigenvalues).max() < 1e-12
    on = fs.linearize(state, t=1.5, coordinates=[*cyc, "sleigh.th"], cyclic=cyc)
    lam = np.sort(on.eigenvalues.real)
    assert lam[0] == pytest.approx(-MASS * OFFSET * u / J, rel=1e-12)
    assert np.abs(lam[1:]).max() < 1e-12 and np.abs(on.eigenvalues.imag).max() < 1e-12


def test_touch_down_the_same_in_millimetres():
    """The blade's touch-down at a time switch written in metres and in millimetres (lengths
    times 1000, the inertia times 10^6): the same motion, the same event, and the blade's
    multiplier (a force) times 1000, to rounding."""

    def run(k):
        m = ms.Model2D()
        b = m.add_body("sleigh", points={"P": (-OFFSET * k, 0.0)},
                       guess=((START[0][0] * k, START[0][1] * k), START[1]), mass=MASS,
                       inertia=INERTIA * k * k)
        v = m.velocity(b.point("P"))
        m.add(ms.TimeSwitch(_blade(b, v), 1.0, _blade(b, v)), name="edge")
        ic = {"sleigh.x_d": 0.5 * k, "sleigh.y_d": 0.8 * k, "sleigh.th_d": 1.0}
        return m.free(drop=[("edge", 1)]).simulate(np.linspace(0, 2.5, 11), initial_condition=ic,
                                                   at_switch="project")

    a, b = run(1.0), run(1000.0)
    unit = np.array([1000.0, 1000.0, 1.0])
    assert np.abs(b.q / unit - a.q).max() <= 1e-12 * np.abs(a.q).max()
    assert np.abs(b.qd / unit - a.qd).max() <= 1e-12 * np.abs(a.qd).max()
    assert [e["t"] for e in a.extra["events"]] == [e["t"] for e in b.extra["events"]]
    mu_a, mu_b = a.extra["mu"], b.extra["mu"]
    assert np.array_equal(np.isnan(mu_a), np.isnan(mu_b))
    ok = ~np.isnan(mu_a)
    assert np.abs(mu_b[ok] / 1000 - mu_a[ok]).max() <= 1e-12 * np.abs(mu_a[ok]).max()
