"""Multistage mechanisms (Mech chapter 5): StageSwitch, TimeSwitch, sweeps across stage
changes, FindSwitchTime and FindTime, each against an independent (closed-form) computation."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T
from mechsys.models import slider_crank

V, XJ, BETA = 0.5, 2.0, np.radians(30)


def _slider(m):
    s = m.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0))
    m.add(ms.RelativeX1(s.point("pin"), V * T), name="drive")
    m.add(ms.RotationLock1(s, 0), name="no rotation")
    return s


def _ramp(m, s):
    return ms.PointOnLine1(s.point("pin"), m.ground.axis((XJ, 0), (np.cos(BETA), np.sin(BETA))))


def _jog_stage():
    m = ms.Model2D()
    s = _slider(m)
    m.add(ms.StageSwitch((s.q[0] < XJ, ms.RelativeY1(s.point("pin"), 0)), (True, _ramp(m, s))),
          name="jog")
    return m, s


def _jog_time(t_switch):
    m = ms.Model2D()
    s = _slider(m)
    m.parameter("ts", t_switch)
    m.add(ms.TimeSwitch(ms.RelativeY1(s.point("pin"), 0), sp.Symbol("ts"), _ramp(m, s)),
          name="jog")
    return m, s


def test_stage_switch_sweep_follows_the_track_and_records_stages():
    m, s = _jog_stage()
    t = np.linspace(0, 8, 41)
    sol = m.solve(t)
    x = V * t
    np.testing.assert_allclose(sol["slider.x"], x, atol=1e-14)
    y_exact = np.where(x < XJ, 0.0, (x - XJ) * np.tan(BETA))
    np.testing.assert_allclose(sol["slider.y"], y_exact, atol=1e-13)
    # velocities and accelerations of the stage in effect (one-sided at the corner)
    vy_exact = np.where(x < XJ, 0.0, V * np.tan(BETA))
    np.testing.assert_allclose(sol.coordinate("slider.y", 1), vy_exact, atol=1e-13)
    np.testing.assert_allclose(sol.coordinate("slider.y", 2), 0.0, atol=1e-12)
    np.testing.assert_array_equal(sol.stage("jog"), np.where(x < XJ, 1, 2))
    np.testing.assert_array_equal(sol.stage(), sol.stage(m.constraint("jog")))
    assert m.solve(1.0).stage() == 1 and m.solve(6.0).stage() == 2


def test_switch_is_one_constraint_of_the_model():
    m, s = _jog_stage()
    sw = m.constraint("jog")
    assert isinstance(sw, ms.StageSwitch) and sw.number == 3
    assert m.constraint(3) is sw
    assert int(m.dof()) == 0
    assert "jog" in m.compile().layout.row_label(2)


def test_time_switch_and_find_switch_time_against_closed_form():
    m, s = _jog_time(3.0)  # a wrong switch time: the motion jumps at t = 3
    sol = m.solve(np.linspace(0, 8, 17))
    np.testing.assert_array_equal(sol.stage("jog"), np.where(sol.t < 3.0, 1, 2))
    y = sol["slider.y"]
    assert y[sol.t == 3.0][0] == pytest.approx((1.5 - XJ) * np.tan(BETA), abs=1e-13)
    ts = ms.FindSwitchTime(m, "jog", 1)
    assert ts == pytest.approx(XJ / V, abs=1e-12)
    # the other selection of Mech's RequiredEquations: ramp side in effect, track row 1 tested
    assert ms.find_switch_time(m, "jog", 1, t_range=(0, 8), required_equations=(1, "all")) == \
        pytest.approx(XJ / V, abs=1e-12)
    m.set_parameters(ts=ts)
    sol = m.solve(np.linspace(0, 8, 17))
    x = V * sol.t
    np.testing.assert_allclose(sol["slider.y"], np.where(x < XJ, 0, (x - XJ) * np.tan(BETA)),
                               atol=1e-13)


def test_find_time_slider_crank_piston_position():
    crank, rod, speed = 2.0, 6.0, 2 * np.pi
    m = slider_crank(crank=crank, rod=rod, speed=speed)
    piston = m.body("piston")
    target = 6.0
    # x = r cos th + sqrt(L^2 - r^2 sin^2 th) = x*  <=>  cos th = (x*^2 + r^2 - L^2) / (2 x* r)
    t_exact = np.arccos((target**2 + crank**2 - rod**2) / (2 * target * crank)) / speed
    t_found = ms.FindTime(m, sp.Eq(piston.q[0], target), (0, 0.5))
    assert t_found == pytest.approx(t_exact, abs=1e-12)
    # a point reaching a position: the crank pin at x = 0 (a quarter turn)
    pin_x = m.location(m.body("crank").point("pin"))[0]
    assert ms.find_time(m, pin_x, (0.1, 0.4)) == pytest.approx(0.25, abs=1e-12)


def _geneva(turns_stages=True):
    c = 2.0
    lam = np.sin(np.pi / 4)
    m = ms.Model2D()
    crank = m.add_body("crank", points={"pin": (lam * c, 0)}, guess=((0, 0), -np.pi))
    wheel = m.add_body("wheel", guess=((c, 0), np.pi / 4))
    m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)))
    m.add(ms.Revolute2(m.ground.point((c, 0)), wheel.point(0)))
    m.add(ms.RotationLock1(crank, T - np.pi))
    th, pin, q4 = crank.q[2], crank.point("pin"), np.pi / 4
    m.add(ms.StageSwitch(
        (th < -q4, ms.RotationLock1(wheel, q4)),
        (th <= q4, ms.PointOnLine1(pin, wheel.axis((0, 0), (1, 0)))),
        (th < 2 * sp.pi - q4, ms.RotationLock1(wheel, -q4)),
        (th <= 2 * sp.pi + q4, ms.PointOnLine1(pin, wheel.axis((0, 0), (0, 1)))),
        (True, ms.RotationLock1(wheel, -3 * q4))), name="geneva")
    return m, crank, wheel, lam


def test_geneva_drive_four_slots():
    m, crank, wheel, lam = _geneva()
    t = np.linspace(0, 4 * np.pi, 251)  # no sample exactly at a switch angle
    sol = m.solve(t)
    theta, phi_w, stage = sol.angle(crank), sol.angle(wheel), sol.stage()
    # independent: the stage from the crank angle alone
    th = t - np.pi
    expect = np.select([th < -np.pi / 4, th <= np.pi / 4, th < 1.75 * np.pi, th <= 2.25 * np.pi],
                       [1, 2, 3, 4], 5)
    np.testing.assert_array_equal(stage, expect)
    for s, mid, off in ((2, 0.0, 0.0), (4, -np.pi / 2, 2 * np.pi)):
        k = stage == s
        rel = theta[k] - off
        phi = np.arctan(np.sin(rel) / (1 / lam - np.cos(rel)))  # tan phi = sin / (1/lam - cos)
        np.testing.assert_allclose(phi_w[k], mid - phi, atol=1e-12)
        # engagement over a quarter of the crank turn
        assert rel.min() >= -np.pi / 4 - 1e-15 and rel.max() <= np.pi / 4 + 1e-15
    # zero wheel motion while locked, 90 degrees per crank revolution
    for s in (1, 3, 5):
        assert np.ptp(phi_w[stage == s]) == 0.0
        np.testing.assert_allclose(sol.coordinate("wheel.th", 1)[stage == s], 0.0, atol=1e-15)
    assert phi_w[stage == 3][0] - phi_w[stage == 1][0] == pytest.approx(-np.pi / 2, abs=1e-13)
    assert phi_w[stage == 5][0] - phi_w[stage == 3][0] == pytest.approx(-np.pi / 2, abs=1e-13)
    # continuity where the mechanism is continuous: no step of the wheel exceeds its largest
    # speed (mid-engagement, dphi/dtheta = lam / (1 - lam)) times the time step
    assert np.abs(np.diff(phi_w)).max() <= lam / (1 - lam) * (t[1] - t[0]) * (1 + 1e-9)
    # switch times: the pin enters at theta = -pi/4 and leaves at pi/4, tangentially
    t_in = ms.FindSwitchTime(m, "geneva", 1, t_range=(0.1, 3.0), tangent=True)
    t_out = ms.FindSwitchTime(m, "geneva", 2, t_range=(2.5, 5.0), tangent=True)
    assert t_in == pytest.approx(0.75 * np.pi, abs=1e-10)
    assert t_out - t_in == pytest.approx(np.pi / 2, abs=1e-10)
    with pytest.raises(ms.ConvergenceError, match=r"no crossing in the range searched, t in \[0.1, 3\]"):
        ms.FindSwitchTime(m, "geneva", 1, t_range=(0.1, 3.0))


def test_variables_inside_a_switch_are_held_in_stages_that_do_not_use_them():
    # the pin on the parabola y = s^2, x = s (a variable s) until x = 1, then on y = 1
    m = ms.Model2D()
    s_body = m.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0))
    m.add(ms.RelativeX1(s_body.point("pin"), V * T), name="drive")
    m.add(ms.RotationLock1(s_body, 0), name="no rotation")
    s = sp.Symbol("s")
    x, y = s_body.q[0], s_body.q[1]
    parabola = ms.Constraint([x - s, y - s**2], {s: 0.0})
    m.add(ms.StageSwitch((x < 1, parabola), (True, ms.RelativeY1(s_body.point("pin"), 1))),
          name="track")
    t = np.linspace(0, 4, 21)
    sol = m.solve(t)
    xs = V * t
    stage = sol.stage()
    np.testing.assert_array_equal(stage, np.where(xs < 1, 1, 2))
    np.testing.assert_allclose(sol["slider.y"], np.where(xs < 1, xs**2, 1.0), atol=1e-13)
    last_on_parabola = xs[xs < 1][-1]
    np.testing.assert_allclose(sol["s"], np.where(xs < 1, xs, last_on_parabola), atol=1e-13)
    np.testing.assert_allclose(sol.coordinate("s", 1), np.where(xs < 1, V, 0.0), atol=1e-13)


def test_time_switch_with_three_stages_and_parameter_times():
    m = ms.Model2D()
    s = _slider(m)
    m.parameter("t1", 1.0)
    m.parameter("t2", 2.0)
    pin = s.point("pin")
    m.add(ms.TimeSwitch(ms.RelativeY1(pin, 0), sp.Symbol("t1"), ms.RelativeY1(pin, T - 1),
                        sp.Symbol("t2"), ms.RelativeY1(pin, 1)), name="lift")
    sol = m.solve([0.5, 1.0, 1.5, 2.0, 2.5])
    np.testing.assert_array_equal(sol.stage(), [1, 2, 2, 3, 3])
    np.testing.assert_allclose(sol["slider.y"], [0, 0, 0.5, 1, 1], atol=1e-14)
    assert ms.FindSwitchTime(m, "lift", 2, t_range=(1.2, 2.7)) == pytest.approx(2.0, abs=1e-12)


# -- bad input -----------------------------------------------------------------------------
def test_test_that_is_not_boolean_names_the_switch():
    m = ms.Model2D()
    s = _slider(m)
    m.add(ms.StageSwitch((s.q[0] - 1, ms.RelativeY1(s.point("pin"), 0)),
                         (True, _ramp(m, s))), name="jog")
    with pytest.raises(ms.ModelError, match=r"switch 'jog'.*stage 1 \(x2 - 1\) gave .*not True or False"):
        m.solve(0.0)


def test_no_test_true_names_the_switch():
    m = ms.Model2D()
    s = _slider(m)
    m.add(ms.StageSwitch((s.q[0] < 1, ms.RelativeY1(s.point("pin"), 0)),
                         (s.q[0] > 3, _ramp(m, s))), name="gap")
    assert m.solve(0.0).stage() == 1
    with pytest.raises(ms.ModelError, match=r"switch 'gap'.*no test is true at t = 4"):
        m.solve([0.0, 4.0])


def test_stages_removing_different_dof_name_the_switch():
    m = ms.Model2D()
    s = _slider(m)
    bad = ms.StageSwitch((True, ms.RelativeY1(s.point("pin"), 0)),
                         (True, ms.Revolute2(s.point("pin"), m.ground.point((0, 0)))))
    with pytest.raises(ms.ModelError, match=r"StageSwitch 'bad'.*stage 1 removes 1, stage 2 removes 2"):
        m.add(bad, name="bad")
    assert len(m.constraints) == 2


def test_switch_times_not_increasing():
    m = ms.Model2D()
    s = _slider(m)
    pin = s.point("pin")
    with pytest.raises(ms.ModelError, match=r"switch times must increase.*switch time 2 \(1\)"):
        ms.TimeSwitch(ms.RelativeY1(pin, 0), 2.0, ms.RelativeY1(pin, 1), 1.0, ms.RelativeY1(pin, 2))
    m.parameter("t1", 1.0)
    m.parameter("t2", 2.0)
    m.add(ms.TimeSwitch(ms.RelativeY1(pin, 0), sp.Symbol("t1"), ms.RelativeY1(pin, 1),
                        sp.Symbol("t2"), ms.RelativeY1(pin, 2)), name="steps")
    m.set_parameters(t2=0.5)
    with pytest.raises(ms.ModelError, match=r"switch 'steps'.*switch times must increase"):
        m.solve(0.0)


def test_find_switch_time_without_crossing_says_the_range():
    m, s = _jog_time(3.0)
    with pytest.raises(ms.ConvergenceError, match=r"FindSwitchTime\('jog', 1\): no crossing in the "
                       r"range searched, t in \[5, 8\]"):
        ms.FindSwitchTime(m, "jog", 1, t_range=(5, 8))
    with pytest.raises(ms.ModelError, match=r"n must be a switch time number 1..1"):
        ms.FindSwitchTime(m, "jog", 2, t_range=(0, 8))
    with pytest.raises(ms.ConvergenceError, match=r"FindTime: no crossing .* t in \[0, 1\]"):
        ms.FindTime(m, sp.Eq(s.q[1], 5), (0, 1))


def test_inconsistent_tests_name_the_switch():
    # solved in stage 1 (y = 1) the test says stage 2; solved there (y = 0) it says stage 1
    m = ms.Model2D()
    s = _slider(m)
    pin = s.point("pin")
    m.add(ms.StageSwitch((s.q[1] < 0.5, ms.RelativeY1(pin, 1)), (True, ms.RelativeY1(pin, 0))),
          name="flip")
    with pytest.raises(ms.ModelError, match=r"switch 'flip'.*tests are inconsistent at t = 0"):
        m.solve(0.0)


def test_stage_chosen_by_a_parameter_without_recompiling():
    # Mech 5.1.1's "whichtrack": the pin in one of two tracks, y = 0 or y = x / 2
    m = ms.Model2D()
    which = m.parameter("whichtrack", 1)
    s = _slider(m)
    pin = s.point("pin")
    m.add(ms.StageSwitch((sp.Eq(which, 1), ms.RelativeY1(pin, 0)),
                         (sp.Eq(which, 2), ms.PointOnLine1(pin, m.ground.axis((0, 0), (2, 1))))),
          name="track")
    t = np.linspace(0, 4, 5)
    np.testing.assert_allclose(m.solve(t)["slider.y"], 0.0, atol=1e-14)
    system = m.compile()
    m.set_parameters(whichtrack=2)
    sol = m.solve(t)
    assert m.compile() is system
    np.testing.assert_array_equal(sol.stage("track"), 2)
    np.testing.assert_allclose(sol["slider.y"], V * t / 2, atol=1e-14)
    m.set_parameters(whichtrack=3)
    with pytest.raises(ms.ModelError, match=r"switch 'track'.*no test is true"):
        m.solve(t)


def test_switch_in_a_3d_model():
    m = ms.Model3D()
    b = m.add_body("slider", points={"pin": (0, 0, 0)}, guess=((0, 0, 0), (1, 0, 0, 0)))
    pin = b.point("pin")
    m.add(ms.RotationLock3(b), name="no rotation")
    m.add(ms.RelativeX1(pin, V * T), name="drive")
    m.add(ms.RelativeZ1(pin, 0), name="plane")
    m.add(ms.StageSwitch((b.q[0] < XJ, ms.RelativeY1(pin, 0)),
                         (True, ms.RelativeY1(pin, (V * T - XJ) * sp.tan(sp.pi / 6)))), name="jog")
    t = np.linspace(0, 8, 17)
    sol = m.solve(t)
    x = V * t
    np.testing.assert_allclose(sol["slider.y"], np.where(x < XJ, 0, (x - XJ) * np.tan(BETA)),
                               atol=1e-13)
    np.testing.assert_array_equal(sol.stage(), np.where(x < XJ, 1, 2))
    assert ms.FindSwitchTime(m, "jog", 1, t_range=(1, 6)) == pytest.approx(XJ / V, abs=1e-12)


def test_replace_by_a_switch_checks_its_stages():
    m, s = _jog_stage()
    bad = ms.StageSwitch((True, ms.RelativeY1(s.point("pin"), 0)),
                         (True, ms.Revolute2(s.point("pin"), m.ground.point((0, 0)))))
    with pytest.raises(ms.ModelError, match=r"StageSwitch 'jog'.*different numbers of degrees"):
        m.replace("jog", bad)


def test_path_motion_with_a_switch_is_refused_not_wrong():
    m, s = _jog_stage()
    with pytest.raises(ms.ModelError,
                       match=r"path motion of a model with stage or time switches \('jog'\) is not "
                             r"supported"):
        m._system_without([m.constraint("drive")], loads=[])


def test_stage_without_solution_past_its_end_hands_over_to_the_next():
    # the pin on the unit circle (upper half) while x < 1, then on the line y = 0; past x = 1
    # the circle has no point at all, so the sweep must not insist on it
    m = ms.Model2D()
    s = m.add_body("slider", points={"pin": (0, 0)}, guess=((-0.9, 0.4), 0))
    pin = s.point("pin")
    m.add(ms.RelativeX1(pin, T - 1), name="drive")
    m.add(ms.RotationLock1(s, 0), name="no rotation")
    m.add(ms.StageSwitch((s.q[0] < 1, ms.RelativeDistance1(pin, m.ground.point((0, 0)), 1)),
                         (True, ms.RelativeY1(pin, 0))), name="track")
    t = np.linspace(0.1, 2.9, 15)
    sol = m.solve(t)
    x = t - 1
    np.testing.assert_array_equal(sol.stage(), np.where(x < 1, 1, 2))
    np.testing.assert_allclose(sol["slider.y"], np.sqrt(np.clip(1 - x**2, 0, None)), atol=1e-12)
