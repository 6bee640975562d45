"""Free motion through stage changes (issue 14): events located on the integrator's dense
output, the velocity policy at a switch, switched loads in free motion; against the elliptic
integral of the pendulum, energy conservation, Newton's restitution law and closed forms."""

import importlib.util
import pathlib

import numpy as np
import pytest
from scipy.special import ellipkinc

import mechsys as ms
from mechsys import T

_spec = importlib.util.spec_from_file_location(
    "latching_pendulum", pathlib.Path(__file__).parents[1] / "examples" / "latching_pendulum.py")
lp = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(lp)

TOL = dict(rtol=1e-10, atol=1e-12)


def _elliptic_time(beta):
    # released at rest from the horizontal (90 degrees from the bottom): the time to the angle
    # psi = pi/2 - beta from the bottom, sin(psi/2) = sin(pi/4) sin(u)
    w0 = np.sqrt(lp.MASS * 9.81 * lp.C / lp.I_O)
    u = np.arcsin(np.sin((np.pi / 2 - beta) / 2) / np.sin(np.pi / 4))
    return (ellipkinc(np.pi / 2, 0.5) - ellipkinc(u, 0.5)) / w0


def _free():
    m = lp.build()
    m.solve(0.0, solution="location")
    return m, m.free(drop=[("latch", 1)])


def _energy(sol):
    x, y, th = sol.q.T
    xd, yd, thd = sol.qd.T
    return 0.5 * lp.MASS * (xd**2 + yd**2) + 0.5 * lp.I_CM * thd**2 + lp.MASS * 9.81 * y


def test_latching_pendulum_event_time_energy_and_projection():
    m, fs = _free()
    t = np.linspace(0, 0.8, 17)
    sol = fs.simulate(t, at_switch="project", **TOL)
    (ev,) = sol.extra["events"]
    t_stop = _elliptic_time(lp.BETA)
    assert ev["t"] == pytest.approx(t_stop, abs=1e-9)
    assert ev["switch"] == "latch" and ev["from"] == [1] and ev["to"] == [2]
    before = t < ev["t"]
    np.testing.assert_array_equal(sol.stage("latch"), np.where(before, 1, 2))
    # energy conserved before the switch (zero at release), to the integration tolerance
    np.testing.assert_allclose(_energy(sol)[before], 0.0, atol=1e-8)
    # projection: the latch allows no velocity; the whole kinetic energy m g c sin(beta) is lost
    np.testing.assert_allclose(sol.qd[~before], 0.0, atol=1e-12)
    np.testing.assert_allclose(sol["rod.th"][~before], -lp.BETA, atol=1e-13)
    ke = lp.MASS * 9.81 * lp.C * np.sin(lp.BETA)
    assert ev["kinetic_energy_before"] == pytest.approx(ke, rel=1e-8)
    assert ev["energy_lost"] == pytest.approx(ke, rel=1e-8)
    assert ev["kinetic_energy_after"] == pytest.approx(0.0, abs=1e-20)
    # latched: the latch carries the weight's moment m g c cos(beta), the pivot the weight
    _, M = sol.reaction("latch", "rod")
    np.testing.assert_allclose(M[~before], lp.MASS * 9.81 * lp.C * np.cos(lp.BETA), rtol=1e-10)
    F, _ = sol.reaction("pivot", "rod")
    np.testing.assert_allclose(F[~before], [[0.0, lp.MASS * 9.81]] * int((~before).sum()),
                               atol=1e-9)
    # while free the latch carries nothing (dropped stage: zero multipliers)
    np.testing.assert_allclose(M[before], 0.0, atol=1e-14)


def test_impact_is_never_silently_ignored():
    m, fs = _free()
    with pytest.raises(ms.ModelError, match=r"switch 'latch' changes from stage \[1\] to \[2\] at "
                                            r"t = 0\.38449.*at_switch='project'"):
        fs.simulate((0.0, 1.0))
    for bad in ("keep", ("restitution", 1.5), ("restitution",), 0.5):
        with pytest.raises(ms.ModelError, match=r"at_switch"):
            fs.simulate((0.0, 1.0), at_switch=bad)


def test_restitution_rebounds_off_the_stop():
    m, fs = _free()
    e = 0.5
    sol = fs.simulate((0.0, 1.2), at_switch=("restitution", e), **TOL)
    first, second = sol.extra["events"][:2]
    assert first["stage_after"] == [1]           # rebounds: the free stage continues
    assert first["kinetic_energy_after"] == pytest.approx(e**2 * first["kinetic_energy_before"],
                                                          rel=1e-9)
    # the rebound rises to where the potential energy equals e^2 of the impact's kinetic
    # energy and returns to the stop with the same speed (energy conserved in between)
    assert second["kinetic_energy_before"] == pytest.approx(first["kinetic_energy_after"],
                                                            rel=1e-7)
    i = np.flatnonzero(sol.t > first["t"])[0]
    thd = sol.coordinate("rod.th", 1)
    assert thd[i] > 0                           # moving back up after the impact
    # the rebounds settle: each keeps e^2 of the kinetic energy until the approach speed is
    # 1e-6 of the first (energy 1e-12), then the rod latches; it then rests on the stop, having
    # lost exactly the kinetic energy of the first impact, m g c sin(beta)
    sol = fs.simulate((0.0, 2.0), at_switch=("restitution", e), **TOL)
    evs = sol.extra["events"]
    assert [ev["policy"] for ev in evs] == ["restitution e=0.5"] * (len(evs) - 1) + ["project"]
    ratios = [ev["kinetic_energy_after"] / ev["kinetic_energy_before"] for ev in evs[:-1]]
    np.testing.assert_allclose(ratios, e**2, rtol=1e-6)
    assert evs[-1]["kinetic_energy_before"] <= 1e-12 * evs[0]["kinetic_energy_before"] / e**2
    assert sum(ev["energy_lost"] for ev in evs) == pytest.approx(
        lp.MASS * 9.81 * lp.C * np.sin(lp.BETA), rel=1e-8)
    assert sol.stage("latch")[-1] == 2
    np.testing.assert_allclose(sol.qd[-1], 0.0, atol=1e-12)


def pushed_slider():
    """A free slider on a frictionless track pushed by F = 3 from t = 1 to t = 2 (a
    TimeSwitch of loads): ``x = F/(2m) (t-1)^2`` for 1 <= t <= 2, then uniform motion at
    ``F/m`` (its free system)."""
    m = ms.Model2D()
    s = m.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0), mass=2.0, inertia=1.0)
    pin = s.point("pin")
    m.add(ms.RelativeX1(pin, T), name="drive")
    m.add(ms.RotationLock1(s, 0), name="no rotation")
    m.add(ms.RelativeY1(pin, 0), name="track")
    m.add_load(ms.TimeSwitch(1.0, ms.Force(pin, (1, 0), 3.0), 2.0))
    m.solve(0.0, solution="location")
    return m.free(drop=["drive"])


def test_time_switch_load_in_free_motion_is_an_event():
    t = np.linspace(0, 3, 13)
    sol = pushed_slider().simulate(t, **TOL)
    a = 3.0 / 2.0
    x = np.where(t < 1, 0, np.where(t < 2, a / 2 * (t - 1) ** 2, a / 2 + a * (t - 2)))
    np.testing.assert_allclose(sol["slider.x"], x, atol=1e-10)
    assert [round(e["t"], 12) for e in sol.extra["events"]] == [1.0, 2.0]
    assert all(e["kind"] == "load" for e in sol.extra["events"])


def test_time_switch_constraint_in_free_motion_compatible_velocities():
    # a slider pushed at constant force along a track whose stage 2 is the same line: the
    # stage changes at t = 1 with compatible velocities, nothing to choose, nothing lost
    m = ms.Model2D()
    s = m.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0), mass=1.0, inertia=1.0)
    pin = s.point("pin")
    m.add(ms.RelativeX1(pin, T), name="drive")
    m.add(ms.RotationLock1(s, 0), name="no rotation")
    m.add(ms.TimeSwitch(ms.RelativeY1(pin, 0), 1.0, ms.PointOnLine1(pin, m.ground.axis(
        (0, 0), (1, 0)))), name="track")
    m.add_load(ms.Force(pin, (1, 0), 2.0))
    m.solve(0.0, solution="location")
    sol = m.free(drop=["drive"]).simulate(np.linspace(0, 2, 5), **TOL)
    np.testing.assert_allclose(sol["slider.x"], np.linspace(0, 2, 5) ** 2, atol=1e-10)
    (ev,) = sol.extra["events"]
    assert ev["t"] == pytest.approx(1.0, abs=1e-14) and ev["policy"] == "compatible"
    assert ev["energy_lost"] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_array_equal(sol.stage("track"), [1, 1, 2, 2, 2])


def test_free_motion_with_switches_bad_options_are_named():
    m, fs = _free()
    with pytest.raises(ms.ModelError, match=r"method='adams'.*events are located on the Runge-Kutta"):
        fs.simulate((0.0, 1.0), method="adams", at_switch="project")
    with pytest.raises(ms.ModelError, match=r"switch 'latch'.*has stages 1\.\.2, got stage 3"):
        m.free(drop=[("latch", 3)])
    with pytest.raises(ms.ModelError, match=r"free\(solution='static'\) of a model with stage"):
        m.free(drop=[("latch", 1)], solution="static")
    with pytest.raises(ms.ModelError, match=r"max_events must be a positive integer"):
        fs.simulate((0.0, 1.0), at_switch="project", max_events=0)
    # switch times given by parameters are checked when the motion is integrated
    m2 = ms.Model2D()
    s2 = m2.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0), mass=1.0, inertia=1.0)
    pin = s2.point("pin")
    m2.add(ms.RotationLock1(s2, 0), name="no rotation")
    m2.add(ms.RelativeY1(pin, 0), name="track")
    t1 = m2.parameter("t1", 1.0)
    m2.add(ms.RelativeX1(pin, T), name="drive")
    ld = m2.add_load(ms.TimeSwitch(ms.Force(pin, (1, 0), 1.0), t1, ms.Force(pin, (1, 0), 2.0),
                                   2.0))
    free2 = m2.free(drop=["drive"])
    m2.set_parameters(t1=3.0)
    with pytest.raises(ms.ModelError, match=rf"load '{ld.name}' \(TimeSwitch of loads\): switch "
                                            r"times must increase"):
        free2.simulate((0.0, 1.0))
    with pytest.raises(ms.ConvergenceError, match=r"more than max_events = 1 events"):
        fs.simulate((0.0, 1.2), at_switch=("restitution", 0.5), max_events=1, **TOL)


def test_free_acceleration_at_one_state_uses_the_stage_in_effect():
    m, fs = _free()
    # released at the horizontal: alpha = m g c / I_O (stage 1 dropped: the rod is free)
    one = fs.solve(0.0)
    assert one.stage("latch") == 1
    assert one.qdd[0, 2] == pytest.approx(-lp.MASS * 9.81 * lp.C / lp.I_O, rel=1e-12)
    # at rest on the latch: no acceleration, the latch holds the moment m g c cos(beta)
    latched = fs.solve(0.0, initial_condition={"rod.th": -lp.BETA - 1e-9})
    assert latched.stage("latch") == 2
    np.testing.assert_allclose(latched.qdd, 0.0, atol=1e-12)
    assert latched.reaction("latch", "rod")[1] == pytest.approx(
        lp.MASS * 9.81 * lp.C * np.cos(lp.BETA), rel=1e-8)   # the given angle is held


def test_starting_step_size_through_stage_changes():
    # Mech's StartingStepSize: the run's first step; after the event the integrator chooses
    m, fs = _free()
    sol = fs.simulate((0.0, 0.8), at_switch="project", starting_step_size=1e-4, **TOL)
    assert sol.t[1] - sol.t[0] == pytest.approx(1e-4, rel=1e-12)
    ref = fs.simulate((0.0, 0.8), at_switch="project", **TOL)
    assert ref.t[1] - ref.t[0] != pytest.approx(1e-4, rel=1e-3)
    (ev,) = sol.extra["events"]
    assert ev["t"] == pytest.approx(ref.extra["events"][0]["t"], abs=1e-10)
    assert ev["t"] == pytest.approx(_elliptic_time(lp.BETA), abs=1e-9)
    with pytest.raises(ms.ModelError, match="longer than the interval"):
        fs.simulate((0.0, 0.8), at_switch="project", starting_step_size=1.0)
    with pytest.raises(ms.ModelError, match="starting_step_size must be a positive"):
        fs.simulate((0.0, 0.8), at_switch="project", starting_step_size=-1e-3)
