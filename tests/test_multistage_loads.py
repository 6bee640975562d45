"""Multistage loads (Mech 7.4.1) and static / inverse-dynamic solutions of models with stage
switches, against hand-computed equilibria."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T

V, XJ, BETA, W = 0.5, 2.0, np.radians(30), 20.0


def _driven_slider(mass=0.0):
    m = ms.Model2D()
    s = m.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0), mass=mass, inertia=1.0)
    pin = s.point("pin")
    m.add(ms.RelativeX1(pin, T), name="drive")
    m.add(ms.RotationLock1(s, 0), name="no rotation")
    m.add(ms.RelativeY1(pin, 0), name="track")
    return m, s, pin


def test_time_switch_of_loads_with_leading_and_trailing_times():
    # Phi_q^T lambda = Q on the driven slider: lambda_drive = Q_x, lambda_track = Q_y
    m, s, pin = _driven_slider()
    m.add_load(ms.TimeSwitch(1.0, ms.Force(pin, (1, 0), 3.0), 2.0,
                             [ms.Force(pin, (1, 0), 5.0), ms.Force(pin, (0, 1), 7.0)], 3.0))
    t = np.array([0.5, 1.0, 1.5, 2.0, 2.5, 2.999, 3.0, 3.5])
    sol = m.solve(t, solution="static")
    # nothing before the leading time 1, set 1 on [1, 2), set 2 on [2, 3), nothing from 3 on
    np.testing.assert_allclose(sol.generalized("drive")[:, 0], [0, 3, 3, 5, 5, 5, 0, 0], atol=1e-12)
    np.testing.assert_allclose(sol.generalized("track")[:, 0], [0, 0, 0, 7, 7, 7, 0, 0], atol=1e-12)


def test_time_switch_of_loads_without_leading_time_applies_the_first_set_before():
    m, s, pin = _driven_slider()
    m.add_load(ms.TimeSwitch(ms.Force(pin, (1, 0), 3.0), 1.0, ms.Force(pin, (1, 0), -4.0)))
    sol = m.solve([0.0, 0.5, 1.0, 9.0], solution="static")
    np.testing.assert_allclose(sol.generalized("drive")[:, 0], [3, 3, -4, -4], atol=1e-12)


def test_stage_switch_of_loads_is_cumulative_several_or_none():
    # inverse dynamics of the slider at constant speed: lambda_drive = Q_x (no acceleration)
    m, s, pin = _driven_slider(mass=2.0)
    which = m.parameter("which", 1)
    m.add_load(ms.StageSwitch((s.q[0] < 1.2, ms.Force(pin, (1, 0), 10.0)),
                              (sp.Eq(which, 2), [ms.Force(pin, (1, 0), 100.0)]),
                              (T > 10, ms.Force(pin, (1, 0), 1000.0))))
    t = np.array([0.5, 1.0, 1.5, 2.0])
    sol = m.solve(t, solution="dynamic")
    np.testing.assert_allclose(sol.generalized("drive")[:, 0], [10, 10, 0, 0], atol=1e-12)
    m.set_parameters(which=2)   # now two sets at once where x < 1.2
    sol = m.solve(t, solution="dynamic")
    np.testing.assert_allclose(sol.generalized("drive")[:, 0], [110, 110, 100, 100], atol=1e-12)


def test_switched_load_bad_input_names_the_switch():
    m, s, pin = _driven_slider()
    with pytest.raises(ms.ModelError, match=r"StageSwitch of loads, set 1: test .* is not True or "
                                            r"False"):
        ms.StageSwitch((s.q[0] + 1, ms.Force(pin, (1, 0), 1.0)))
    with pytest.raises(ms.ModelError, match=r"TimeSwitch of loads.*must increase"):
        ms.TimeSwitch(ms.Force(pin, (1, 0), 1.0), 2.0, ms.Force(pin, (1, 0), 2.0), 1.0)
    with pytest.raises(ms.ModelError, match=r"load set is a load or a list of loads"):
        ms.StageSwitch((True, ms.Force(pin, (1, 0), 1.0)), (True, ms.RelativeY1(pin, 0)))
    with pytest.raises(ms.ModelError, match=r"TimeSwitch of loads.*add it with m\.add_load"):
        m.add(ms.TimeSwitch(ms.Force(pin, (1, 0), 1.0), 1.0, ms.Force(pin, (1, 0), 2.0)))
    # parameter times are checked at solve time, with the parameters then
    t1 = m.parameter("t1", 1.0)
    ld = m.add_load(ms.TimeSwitch(ms.Force(pin, (1, 0), 1.0), t1, ms.Force(pin, (1, 0), 2.0), 2.0))
    m.solve(0.0, solution="static")
    m.set_parameters(t1=3.0)
    with pytest.raises(ms.ModelError, match=rf"load '{ld.name}' \(TimeSwitch of loads\): switch "
                                            r"times must increase"):
        m.solve(0.0, solution="static")


def _jog(mass=0.0):
    m = ms.Model2D()
    s = m.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0), mass=mass, inertia=1.0)
    pin = s.point("pin")
    m.add(ms.RelativeX1(pin, V * T), name="drive")
    m.add(ms.RotationLock1(s, 0), name="no rotation")
    ramp = ms.PointOnLine1(pin, m.ground.axis((XJ, 0), (np.cos(BETA), np.sin(BETA))))
    m.add(ms.StageSwitch((s.q[0] < XJ, ms.RelativeY1(pin, 0)), (True, ramp)), name="jog")
    return m, s


def test_statics_with_a_stage_switch_uses_each_points_stage():
    # weight W on the pin: on the flat track the track carries W, the drive nothing; on the
    # ramp the normal force N = W / cos(beta) and the drive pushes W tan(beta) along X
    m, s = _jog()
    m.add_load(ms.Force(s.point("pin"), (0, -1), W))
    t = np.linspace(0, 8, 9)
    sol = m.solve(t, solution="static")
    ramp = V * t >= XJ
    np.testing.assert_array_equal(sol.stage("jog"), np.where(ramp, 2, 1))
    F, M = sol.reaction("jog", "slider")
    N = np.where(ramp, W / np.cos(BETA), W)
    np.testing.assert_allclose(F[:, 0], np.where(ramp, -N * np.sin(BETA), 0), atol=1e-12)
    np.testing.assert_allclose(F[:, 1], np.where(ramp, N * np.cos(BETA), W), atol=1e-12)
    Fd, _ = sol.reaction("drive", "slider")
    np.testing.assert_allclose(Fd[:, 0], np.where(ramp, W * np.tan(BETA), 0), atol=1e-12)
    # the balance Phi_q^T lambda = Q holds point by point with each stage's Jacobian
    J, lam, Q = sol.jacobian(ms.All, ms.All), sol.generalized(ms.All), sol.loads(ms.All)
    np.testing.assert_allclose(np.einsum("kij,ki->kj", J, lam), Q, atol=1e-12)
    one = m.solve(5.0, solution="static")
    assert one.stage("jog") == 2
    np.testing.assert_allclose(one.reaction("jog", "slider")[0], F[5], atol=1e-12)


def test_inverse_dynamics_with_a_stage_switch_drive_power():
    # mass 2 at constant drive speed: no inertia force on either straight track, so the drive
    # delivers the power to lift the weight on the ramp, W V tan(beta)
    m, s = _jog(mass=2.0)
    m.add_load(ms.Force(s.point("pin"), (0, -1), W))
    t = np.array([1.0, 3.0, 5.0, 7.0])
    sol = m.solve(t, solution="dynamic")
    np.testing.assert_allclose(sol.power("drive"), np.where(V * t >= XJ, W * V * np.tan(BETA), 0),
                               atol=1e-12)


def test_switched_loads_and_stage_switch_in_a_3d_model():
    # 3D: the slider on the X axis (then, as a stage, on a 30 degree ramp in the XZ plane),
    # a weight along -Z switched on at t = 1 by a TimeSwitch of loads
    m = ms.Model3D()
    b = m.add_body("slider", points={"pin": (0, 0, 0)}, guess=((0, 0, 0), (1, 0, 0, 0)),
                   mass=1.0, inertia=(1, 1, 1))
    pin = b.point("pin")
    m.add(ms.RotationLock3(b), name="no rotation")
    m.add(ms.RelativeX1(pin, V * T), name="drive")
    m.add(ms.RelativeY1(pin, 0), name="plane")
    m.add(ms.StageSwitch((b.q[0] < XJ, ms.RelativeZ1(pin, 0)),
                         (True, ms.RelativeZ1(pin, (V * T - XJ) * sp.tan(BETA)))), name="jog")
    m.add_load(ms.TimeSwitch(1.0, ms.Force(pin, (0, 0, -1), W)))
    t = np.array([0.5, 2.0, 6.0])
    sol = m.solve(t, solution="static")
    np.testing.assert_array_equal(sol.stage("jog"), [1, 1, 2])
    # the Z driver (either stage) carries the weight once it is on; nothing pushes along X
    F, _ = sol.reaction("jog", "slider")
    np.testing.assert_allclose(F[:, 2], [0, W, W], atol=1e-12)
    np.testing.assert_allclose(sol.reaction("drive", "slider")[0][:, 0], 0, atol=1e-12)
    # free motion (drive dropped): the weight switches on at t = 1 as an event; on the flat
    # stage it presses on the track only, the slider keeps its speed V
    m.solve(0.0, solution="velocity")
    free = m.free(drop=["drive"]).simulate(np.linspace(0, 3, 7), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(free["slider.x"], V * np.linspace(0, 3, 7), atol=1e-10)
    assert [round(e["t"], 12) for e in free.extra["events"]] == [1.0]
    Fz = free.reaction("jog", "slider")[0][:, 2]
    np.testing.assert_allclose(Fz, np.where(np.linspace(0, 3, 7) >= 1, W, 0), atol=1e-9)
