"""Issue 34, rotations: angle equations that also hold half a turn off reach the asked angle
(decision 0033)."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T


def _angle_of(p):
    return np.arctan2(p[..., 1], p[..., 0])


def _same_angle(a, b):
    """Angles equal modulo 2 pi (to 1e-9)."""
    return np.allclose(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))), 0, atol=1e-9)


def crank3d(angle, guess=((0, 0, 0), (1, 0, 0, 0))):
    m = ms.Model3D()
    g = m.ground
    c = m.add_body("crank", points={"pin": (1, 0, 0)}, guess=guess)
    m.add(ms.Revolute5(g.axis((0, 0, 0), (0, 0, 1)), c.axis((0, 0, 0), (0, 0, 1))))
    m.add(ms.RotationLock1(c.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)),
                           g.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)), angle), name="drive")
    return m, c


def slider_crank2d(angle, form="axis", orientation="angle"):
    """Crank 1, rod 3, piston on x; the crank angle asked through ``form``."""
    m = ms.Model2D(orientation=orientation)
    g = m.ground
    c = m.add_body("crank", points={"pin": (1, 0)}, guess=((0, 0), 0))
    r = m.add_body("rod", points={"a": (0, 0), "b": (3, 0)}, guess=((1, 0), 0))
    s = m.add_body("piston", guess=((4, 0), 0))
    m.add(ms.Revolute2(g.point((0, 0)), c.point(0)))
    m.add(ms.Revolute2(c.point("pin"), r.point("a")))
    m.add(ms.Revolute2(r.point("b"), s.point(0)))
    m.add(ms.Translate2(g.axis((0, 0), (1, 0)), s.axis((0, 0), (1, 0))))
    if form == "axis":
        m.add(ms.RotationLock1(c.axis((0, 0), (1, 0)), g.axis((0, 0), (1, 0)), angle), name="drive")
    elif form == "body":
        m.add(ms.RotationLock1(c, angle), name="drive")
    else:
        m.add(ms.RelativeAngle1(c.vector((1, 0)), g.vector((1, 0)), angle), name="drive")
    return m, c, s


@pytest.mark.parametrize("deg", [100, 180, 200, 279, -135])
def test_3d_axis_form_reaches_the_asked_angle_from_a_far_guess(deg):
    m, c = crank3d(sp.rad(deg))
    pin = m.solve(solution="location").location(c.point("pin"))
    assert np.allclose(pin, [np.cos(np.radians(deg)), np.sin(np.radians(deg)), 0], atol=1e-9)


@pytest.mark.parametrize("form,orientation", [("axis", "angle"), ("axis", "euler"),
                                              ("body", "euler"), ("relative", "angle")])
@pytest.mark.parametrize("deg", [180, 200, -120])
def test_2d_forms_reach_the_asked_angle(form, orientation, deg):
    m, c, s = slider_crank2d(sp.rad(deg), form, orientation)
    sol = m.solve(solution="location")
    pin = sol.location(c.point("pin"))
    a = np.radians(deg)
    assert np.allclose(pin, [np.cos(a), np.sin(a)], atol=1e-9)
    # the piston closes the loop on the same branch as the guess (x > 0): closed form
    x = np.cos(a) + np.sqrt(9 - np.sin(a) ** 2)
    assert sol.location(s.point(0))[0] == pytest.approx(x, abs=1e-9)


@pytest.mark.parametrize("jit", ["0", "1"])
@pytest.mark.parametrize("solution", ["location", "velocity", "acceleration"])
@pytest.mark.parametrize("offset", [2.0, np.pi, -2.5])
def test_crank_driven_by_2_pi_t_plus_offset_is_never_half_a_turn_off(monkeypatch, jit, solution,
                                                                      offset):
    monkeypatch.setenv("MECHSYS_JIT", jit)
    t = np.linspace(0, 1, 21)
    m, c, s = slider_crank2d(2 * sp.pi * T + offset)
    sol = m.solve(t, solution=solution)
    assert _same_angle(_angle_of(sol.location(c.point("pin"))), 2 * np.pi * t + offset)
    m3, c3 = crank3d(2 * sp.pi * T + offset)
    sol3 = m3.solve(t, solution=solution)
    assert _same_angle(_angle_of(sol3.location(c3.point("pin"))), 2 * np.pi * t + offset)
    if solution != "location":   # the velocity follows the driver: 2 pi
        assert np.allclose(sol3.omega(c3)[:, 2], 2 * np.pi, atol=1e-9)


@pytest.mark.parametrize("jit", ["0", "1"])
def test_coarse_half_turn_steps_stay_on_the_driver(monkeypatch, jit):
    # location-only: no velocity to predict with, the first step starts from the previous
    # point, where the driver's equation holds half a turn off
    monkeypatch.setenv("MECHSYS_JIT", jit)
    t = np.array([0.0, 0.5, 1.0, 1.25])
    m3, c3 = crank3d(2 * sp.pi * T + 0.3)
    sol = m3.solve(t, solution="location")
    assert _same_angle(_angle_of(sol.location(c3.point("pin"))), 2 * np.pi * t + 0.3)


def test_a_guess_given_as_a_state_far_from_the_driver():
    m, c = crank3d(2 * sp.pi * T)
    first = m.solve(0.0)
    sol = m.solve(0.55, guess=first)       # 198 deg from the guess
    assert _same_angle(_angle_of(sol.location(c.point("pin"))), 2 * np.pi * 0.55)


# -- matrices that are not rotations, and the one rule for nested lists ----------------------

ROT = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])     # 90 deg about z
NOT_ROTATIONS = {
    "reflection": np.diag([1.0, 1.0, -1.0]),
    "reflected rotation": -ROT,
    "shear": np.array([[1.0, 0.3, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    "2 I": 2 * np.eye(3),
    "NaN": np.array([[np.nan, 0, 0], [0, 1, 0], [0, 0, 1]]),
    "rounded to 3 digits": np.round(ms.rotation_matrix((0.7, (1, 2, 3))), 3),
}


def _rotation_uses(R):
    """Every entry point that takes a rotation, given ``R``."""
    def guess():
        ms.Model3D().add_body("b", guess=((0, 0, 0), R))

    def lock3():
        m = ms.Model3D()
        m.add(ms.RotationLock3(m.add_body("b"), R))

    def lock3_in_sequence():
        m = ms.Model3D()
        m.add(ms.RotationLock3(m.add_body("b"), (0.3, (0, 0, 1)), R))

    return {"euler_parameters": lambda: ms.euler_parameters(R),
            "rotation_matrix": lambda: ms.rotation_matrix(R),
            "rotation": lambda: ms.rotation(R),
            "virtual_rotation": lambda: ms.virtual_rotation(R),
            "parallel_axis": lambda: ms.parallel_axis((0, 0, 0), 1.0, (1, 2, 3), R),
            "body guess": guess, "RotationLock3": lock3, "RotationLock3 sequence": lock3_in_sequence}


@pytest.mark.parametrize("kind", list(NOT_ROTATIONS))
@pytest.mark.parametrize("use", list(_rotation_uses(None)))
def test_matrices_that_are_not_rotations_are_refused(kind, use):
    R = NOT_ROTATIONS[kind]
    for given in (R, sp.Matrix(R)) if kind != "NaN" else (R,):
        with pytest.raises(ms.GeometryError, match="not a rotation|reflection|not finite") as e:
            _rotation_uses(given)[use]()
        if use == "body guess":
            assert "'b'" in str(e.value)


def test_rotation_matrices_are_still_taken_everywhere():
    R = ms.rotation_matrix((0.7, (1, 2, 3)))
    e = ms.euler_parameters(R)
    np.testing.assert_allclose(ms.rotation_matrix(e), R, atol=1e-14)
    # printed to 8 digits is still a rotation (within the documented 1e-6)
    np.testing.assert_allclose(ms.euler_parameters(np.round(R, 8)), e, atol=1e-7)
    m = ms.Model3D()
    b = m.add_body("b", guess=((0, 0, 0), sp.Matrix(R)))
    np.testing.assert_allclose(m.guess()[3:], e, atol=1e-14)
    # a RotationLock3 given the matrix holds the body at it
    m.add(ms.OriginLock3(b))
    m.add(ms.RotationLock3(b, R))
    m.set_guess(np.array([0, 0, 0, 1.0, 0, 0, 0]))
    sol = m.solve(solution="location")
    np.testing.assert_allclose(ms.rotation_matrix(np.ravel(sol.q)[3:]), R, atol=1e-12)


@pytest.mark.parametrize("bad", [(np.nan, 0, 0, 0), (0, 0, 0, 0), (np.inf, (0, 0, 1)),
                                 (0.0, np.nan, 0.0)])
def test_non_finite_or_zero_rotations_are_refused(bad):
    with pytest.raises(ms.GeometryError):
        ms.euler_parameters(bad)
    with pytest.raises(ms.GeometryError, match="'b'"):
        ms.Model3D().add_body("b", guess=((0, 0, 0), bad))


@pytest.mark.parametrize("nested", [ROT.tolist(), tuple(map(tuple, ROT)), np.eye(3).tolist(),
                                    [list(r) for r in np.round(ms.rotation_matrix((1, (1, 1, 0))), 4)],
                                    [np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0])]])
def test_a_nested_3x3_list_is_refused_the_same_way_everywhere(nested):
    # the same text could be a matrix (loads.md's old rule) or three rotation vectors
    # (spatial.md's): one rule, a refusal saying how to write each
    for use, call in _rotation_uses(nested).items():
        with pytest.raises(ms.ModelError, match="ambiguous") as e:
            call()
        assert "np.array" in str(e.value) and "(angle, (x, y, z))" in str(e.value), use


def test_the_two_unambiguous_spellings_mean_what_they_say():
    R = ROT
    np.testing.assert_allclose(ms.rotation_matrix(np.array(R)), R, atol=1e-15)
    seq = [(1.0, (1, 0, 0)), (1.0, (0, 1, 0)), (1.0, (0, 0, 1))]   # three rotations of 1 rad
    expect = (ms.rotation_matrix((1.0, (1, 0, 0))) @ ms.rotation_matrix((1.0, (0, 1, 0)))
              @ ms.rotation_matrix((1.0, (0, 0, 1))))
    np.testing.assert_allclose(ms.rotation_matrix(seq), expect, atol=1e-14)
    # parallel_axis reads the matrix as the inertia transformation R J R^T
    J = ms.parallel_axis((0, 0, 0), 1.0, (1.0, 2.0, 3.0), np.array(R))
    np.testing.assert_allclose(J[:3], [2.0, 1.0, 3.0], atol=1e-14)


def test_free_motion_starts_on_the_driven_angle():
    # a driver kept in free motion: the initial positions are projected onto the
    # constraints from the guess (0), half a turn from the asked 200 degrees
    m, c = crank3d(2 * sp.pi * T + sp.rad(200))
    c.mass, c.inertia = 1.0, (1.0, 1.0, 1.0)
    sol = m.free().simulate(t=(0, 0.25))
    a = _angle_of(sol.location(c.point("pin")))
    assert _same_angle(a, 2 * np.pi * np.asarray(sol.t) + np.radians(200))


@pytest.mark.parametrize("deg", [100, 180, 200, -170])
def test_one_axis_form_measured_from_rest(deg):
    # RotationLock1(axis, angle): from the same axis on ground at rest
    m = ms.Model3D()
    c = m.add_body("crank", points={"pin": (0, 1, 0)})
    m.add(ms.Revolute5(m.ground.axis((0, 0, 0), (1, 0, 0)), c.axis((0, 0, 0), (1, 0, 0))))
    m.add(ms.RotationLock1(c.axis((0, 0, 0), (1, 0, 0), (0, 1, 0)), sp.rad(deg)), name="drive")
    pin = m.solve(solution="location").location(c.point("pin"))
    a = np.radians(deg)       # about +x, y turns towards z
    assert np.allclose(pin, [0, np.cos(a), np.sin(a)], atol=1e-9)


@pytest.mark.parametrize("jit", ["0", "1"])
def test_three_turns_at_coarse_steps_in_a_location_sweep(monkeypatch, jit):
    monkeypatch.setenv("MECHSYS_JIT", jit)
    t = np.linspace(0, 3, 13)                 # quarter and more of a turn per step
    m, c, s = slider_crank2d(2 * sp.pi * T * 1.1 + 1.0)
    sol = m.solve(t, solution="location")
    a = 2 * np.pi * 1.1 * t + 1.0
    assert _same_angle(_angle_of(sol.location(c.point("pin"))), a)
    x = np.cos(a) + np.sqrt(9 - np.sin(a) ** 2)
    np.testing.assert_allclose(sol.location(s.point(0))[:, 0], x, atol=1e-9)


# -- angle drivers inside the stages of a switch (each stage system has its own guard) --------

def _switched(model, crank_axis, ground_axis):
    """Stage 1 (T < 1): 200 deg + 90 deg/s from a guess of 0; stage 2: back to 200 deg, half a
    turn from where stage 1 ends, so the switch point starts on the wrong root too."""
    drive = ms.StageSwitch(
        (T < 1, ms.RotationLock1(crank_axis(), ground_axis(), sp.rad(200) + sp.pi / 2 * T)),
        (True, ms.RotationLock1(crank_axis(), ground_axis(), sp.rad(200))))
    model.add(drive, name="drive")


def _switched_angle(t):
    t = np.asarray(t, dtype=float)
    return np.radians(200) + np.where(t < 1, np.pi / 2 * t, 0.0)


def switched_slider_crank2d():
    m, c, s = slider_crank2d(0.0)
    m.remove("drive")
    _switched(m, lambda: c.axis((0, 0), (1, 0)), lambda: m.ground.axis((0, 0), (1, 0)))
    return m, c, s


def switched_crank3d():
    m, c = crank3d(0.0)
    m.remove("drive")
    _switched(m, lambda: c.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)),
              lambda: m.ground.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)))
    return m, c


@pytest.mark.parametrize("jit", ["0", "1"])
def test_angle_drivers_inside_a_stage_switch_reach_the_asked_angle(monkeypatch, jit):
    monkeypatch.setenv("MECHSYS_JIT", jit)
    t = np.array([0.0, 0.4, 0.8, 1.0, 1.3, 1.6])
    a = _switched_angle(t)
    m, c, s = switched_slider_crank2d()
    for ti, ai in zip(t[[0, 4]], a[[0, 4]]):      # single solves from the guess (0 deg)
        pin = m.solve(float(ti), solution="location").location(c.point("pin"))
        assert _same_angle(_angle_of(pin), ai)
    for solution in ("location", "velocity"):
        sol = m.solve(t, solution=solution)
        assert _same_angle(_angle_of(sol.location(c.point("pin"))), a)
        # the rod closes the loop on the guess's branch (piston at x > 0): closed form
        x = np.cos(a) + np.sqrt(9 - np.sin(a) ** 2)
        np.testing.assert_allclose(sol.location(s.point(0))[:, 0], x, atol=1e-9)
        np.testing.assert_array_equal(sol.stage("drive"), np.where(t < 1, 1, 2))
    m3, c3 = switched_crank3d()
    pin = m3.solve(0.0, solution="location").location(c3.point("pin"))
    assert _same_angle(_angle_of(pin), a[0])
    sol3 = m3.solve(t, solution="velocity")
    assert _same_angle(_angle_of(sol3.location(c3.point("pin"))), a)
    np.testing.assert_allclose(sol3.omega(c3)[:, 2], np.where(t < 1, np.pi / 2, 0.0), atol=1e-9)


def test_each_stage_system_tests_its_own_drivers():
    m, c, s = switched_slider_crank2d()
    from mechsys.compile._stages import stage_system

    labels = [stage_system(m, (k,)).branch_guard.labels for k in (0, 1)]
    assert [lab[0].endswith(f"stage {k + 1} (RotationLock1)") for k, lab in enumerate(labels)] \
        == [True, True]
    assert all("switch 'drive'" in lab[0] for lab in labels)


# -- bodies driven through a Gen joint (generalized coordinates, Mech ch. 11) -----------------

def gen_slider_crank2d(angle):
    """The slider-crank with the crank a Gen slave of ground and the rod a Gen slave of the
    crank: their poses are functions of the joint angles ``phi``, ``psi`` (guesses 0)."""
    m = ms.Model2D()
    g = m.ground
    c = m.add_body("crank", points={"pin": (1, 0)})
    r = m.add_body("rod", points={"b": (3, 0)})
    s = m.add_body("piston", guess=((4, 0), 0))
    m.add(ms.GenRevolute2(c.axis((0, 0), (1, 0)), g.axis((0, 0), (1, 0)), ("phi", 0.0)))
    m.add(ms.GenRevolute2(r.axis((0, 0), (1, 0)), c.axis("pin", (1, 0)), ("psi", 0.0)))
    m.add(ms.Revolute2(r.point("b"), s.point(0)))
    m.add(ms.Translate2(g.axis((0, 0), (1, 0)), s.axis((0, 0), (1, 0))))
    m.add(ms.RotationLock1(c.axis((0, 0), (1, 0)), g.axis((0, 0), (1, 0)), angle), name="drive")
    return m, c, s


def gen_crank3d(angle):
    m = ms.Model3D()
    g = m.ground
    c = m.add_body("crank", points={"pin": (1, 0, 0)})
    m.add(ms.GenRevolute5(c.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)),
                          g.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)), ("phi", 0.0)))
    m.add(ms.RotationLock1(c.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)),
                           g.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)), angle), name="drive")
    return m, c


@pytest.mark.parametrize("deg", [200, 180, -120])
def test_a_gen_joint_slave_is_turned_onto_the_asked_angle(deg):
    a = np.radians(deg)
    m, c, s = gen_slider_crank2d(sp.rad(deg))
    sol = m.solve(solution="location")
    assert _same_angle(_angle_of(sol.location(c.point("pin"))), a)
    # the rod (the crank's own slave) kept its orientation while the crank was turned, so
    # the loop closes on the guess's branch: closed form
    assert sol.location(s.point(0))[0] == pytest.approx(np.cos(a) + np.sqrt(9 - np.sin(a) ** 2),
                                                        abs=1e-9)
    m3, c3 = gen_crank3d(sp.rad(deg + 80))
    pin = m3.solve(solution="location").location(c3.point("pin"))
    assert _same_angle(_angle_of(pin), np.radians(deg + 80))


@pytest.mark.parametrize("jit", ["0", "1"])
def test_gen_joint_sweeps_at_quarter_turn_steps(monkeypatch, jit):
    # steps of exactly a quarter turn: each prediction sits where the angle equation's
    # derivative vanishes (Newton could not start); it is turned onto the driver first
    monkeypatch.setenv("MECHSYS_JIT", jit)
    t = np.linspace(0, 1, 5)
    a = 2 * np.pi * t + 2.0
    m3, c3 = gen_crank3d(2 * sp.pi * T + 2.0)
    sol = m3.solve(t, solution="location")
    assert _same_angle(_angle_of(sol.location(c3.point("pin"))), a)
    m, c, s = gen_slider_crank2d(2 * sp.pi * T + 2.0)
    sol = m.solve(t, solution="velocity")
    assert _same_angle(_angle_of(sol.location(c.point("pin"))), a)
    np.testing.assert_allclose(sol.location(s.point(0))[:, 0],
                               np.cos(a) + np.sqrt(9 - np.sin(a) ** 2), atol=1e-9)


def test_an_angle_no_body_carries_is_refused_saying_why():
    # the angle of a vector between points of two bodies: nothing to turn onto the asked
    # angle, so the wrong root is an error that says so (not "turning did not reach it")
    from mechsys.geometry._points import Vector

    m = ms.Model2D()
    c = m.add_body("crank", points={"pin": (1, 0)}, guess=((0, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), c.point(0)))
    m.add(ms.RelativeAngle1(Vector(m.ground.point((0, 0)), c.point("pin")),
                            m.ground.vector((1, 0)), sp.rad(200)), name="drive")
    with pytest.raises(ms.ConvergenceError, match=r"'drive'.*no single moving body carries"):
        m.solve(0.0, solution="location")


def test_free_motion_starts_on_a_stage_drivers_angle():
    # a switch's driver kept in free motion: the initial projection uses the stage system's
    # guard (stage 1 asks 200 deg, the guess is 0)
    m, c = switched_crank3d()
    c.mass, c.inertia = 1.0, (1.0, 1.0, 1.0)
    sol = m.free().simulate(t=(0, 0.3))
    assert _same_angle(_angle_of(sol.location(c.point("pin"))), _switched_angle(sol.t))
