"""Gear constraints (Mech 6.2) against closed forms: speed ratios, Willis' formula, rack,
lead screw, bevel and belt ratios, the tooth force of a static solution, free motion with
reflected inertia, and bad input."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T
from mechsys._errors import GeometryError, MechError, ModelError

W = 1.3  # driver speed [rad/s]
TIMES = np.linspace(0.0, 2.0, 9)


def _pinned(m, name, centre, guess_angle=0.0, **kw):
    b = m.add_body(name, guess=(centre, guess_angle), **kw)
    m.add(ms.Revolute2(m.ground.point(centre), b.point(0)), name=f"{name} bearing")
    return b


def _pair(kind, r1, r2, c2, *extra):
    m = ms.Model2D()
    g1 = _pinned(m, "g1", (0.0, 0.0))
    g2 = _pinned(m, "g2", c2)
    mesh = m.add(kind(g1.point(0), r1, g2.point(0), r2, *extra, 0.0), name="mesh")
    m.add(ms.RotationLock1(g1, W * T), name="drive")
    return m, g1, g2, mesh


def test_spur_pair_ratio_is_minus_r1_over_r2():
    m, g1, g2, _ = _pair(ms.TwoGears1, 1.0, 2.5, (3.5, 0.0))
    sol = m.solve(TIMES)
    np.testing.assert_allclose(sol.omega(g2), -W * 1.0 / 2.5, atol=1e-12)
    # phase: r1 e1 + r2 e2 = C = 0 with e_i = theta_i (centre line along +x)
    np.testing.assert_allclose(sol.angle(g2), -W * TIMES / 2.5, atol=1e-10)
    np.testing.assert_allclose(sol.alpha(g2), 0.0, atol=1e-10)


def test_internal_pair_turns_the_same_way_at_r1_over_r2():
    # a pinion of radius 1 inside a ring of radius 3 (negative radius): centres 2 apart
    m, g1, g2, _ = _pair(ms.TwoGears1, 1.0, -3.0, (-2.0, 0.0))
    sol = m.solve(TIMES)
    np.testing.assert_allclose(sol.omega(g2), W / 3.0, atol=1e-12)


def test_belt_pair_ratio_is_plus_r1_over_r2():
    m, g1, g2, _ = _pair(ms.TwoPulleys1, 0.5, 2.0, (0.0, 4.0), 4.0)
    sol = m.solve(TIMES)
    np.testing.assert_allclose(sol.omega(g2), W * 0.5 / 2.0, atol=1e-12)
    # phase: C = r1 e1 - r2 e2 = 0, e_i = theta_i - pi/2 (the centre line is along +y)
    np.testing.assert_allclose(sol.angle(g2), np.pi / 2 + (W * TIMES - np.pi / 2) / 4.0, atol=1e-10)


def test_twogears2_places_the_centre_and_tracks_the_centre_line():
    # gear 2 is free: TwoGears2 puts it |r1 + r2| from gear 1 and a rotation lock fixes its
    # angle, so the centre line (the variable) turns: r1 (th1 - Th) + r2 (th2 - Th) = C
    m = ms.Model2D()
    g1 = _pinned(m, "g1", (0.0, 0.0))
    g2 = m.add_body("g2", guess=((3.0, 0.2), 0.0))
    mesh = m.add(ms.TwoGears2(g1.point(0), 1.0, ("Th", 0.1), g2.point(0), 2.0, 0.5))
    m.add(ms.RotationLock1(g1, W * T))
    m.add(ms.RotationLock1(g2, 0.0))
    sol = m.solve(TIMES)
    th = sol.coordinate("Th")
    # with th2 = 0: Th = (r1 th1 - C) / (r1 + r2)
    np.testing.assert_allclose(th, (W * TIMES - 0.5) / 3.0, atol=1e-10)
    c2 = sol.location(g2.point(0))
    np.testing.assert_allclose(c2, 3.0 * np.column_stack([np.cos(th), np.sin(th)]), atol=1e-10)
    assert mesh.alpha == sp.Symbol("Th")


def test_epicyclic_train_obeys_willis():
    # sun r=1 and ring r=3 (internal) turn about the origin, driven; the planet r=1 meshes
    # with both; its centre line (TwoGears2's variable) is the carrier angle.
    ws, wr = 1.0, 0.4
    m = ms.Model2D()
    sun = _pinned(m, "sun", (0.0, 0.0))
    ring = _pinned(m, "ring", (0.0, 0.0))
    planet = m.add_body("planet", guess=((2.0, 0.0), 0.0))
    m.add(ms.TwoGears2(sun.point(0), 1.0, ("carrier", 0.0), planet.point(0), 1.0, 0.0))
    m.add(ms.TwoGears1(planet.point(0), 1.0, ("phi", np.pi), ring.point(0), -3.0, 0.0))
    m.add(ms.RotationLock1(sun, ws * T))
    m.add(ms.RotationLock1(ring, wr * T))
    assert m.dof() == 0
    t = np.linspace(0, 10, 41)      # the carrier turns more than half a revolution
    sol = m.solve(t)
    carrier = sol.coordinate("carrier")
    # Willis: (ws - wc) / (wr - wc) = -N_ring / N_sun = -3
    wc = (ws + 3 * wr) / 4
    # assembly phase: both C = 0 give th_p = 2 Th and th_p + 2 (Th + pi) = 0, so Th = -pi/2
    np.testing.assert_allclose(carrier, -np.pi / 2 + wc * t, atol=1e-9)
    # planet spin: (wp - wc) = -(ws - wc) r_sun / r_planet
    np.testing.assert_allclose(sol.omega(planet), wc - (ws - wc), atol=1e-10)
    # the planet centre goes round on radius 2
    p = sol.location(planet.point(0))
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), 2.0, atol=1e-10)


def test_rack_and_pinion_travel_is_r_theta():
    r = 0.75
    m = ms.Model2D()
    pinion = _pinned(m, "pinion", (0.0, r))
    rack = m.add_body("rack", guess=((0.0, 0.0), 0.0))
    m.add(ms.Translate2(rack.axis(0, (1, 0)), m.ground.axis((0, 0), (1, 0))))
    m.add(ms.RackAndPinion1(pinion.point(0), r, rack.axis(0, (1, 0)), 0.0))
    m.add(ms.RotationLock1(pinion, W * T))
    sol = m.solve(TIMES)
    np.testing.assert_allclose(sol.location(rack.point(0))[:, 0], r * W * TIMES, atol=1e-10)


def test_rolling_pinion_on_a_ground_rack():
    r, Cc = 0.5, 0.2
    m = ms.Model2D()
    pinion = m.add_body("pinion", guess=((0.2, 0.5), 0.0))
    m.add(ms.RackAndPinion2(pinion.point(0), r, m.ground.axis((0, 0), (1, 0)), Cc))
    m.add(ms.RotationLock1(pinion, W * T))
    sol = m.solve(TIMES)
    c = sol.location(pinion.point(0))
    np.testing.assert_allclose(c[:, 1], r, atol=1e-12)
    np.testing.assert_allclose(c[:, 0], Cc - r * W * TIMES, atol=1e-10)


def _revolute_3d(m, name, direction, guess_rot=(1, 0, 0, 0), ref=None):
    b = m.add_body(name, guess=((0, 0, 0), guess_rot))
    m.add(ms.Revolute5(b.axis(0, direction, ref), m.ground.axis((0, 0, 0), direction, ref)),
          name=f"{name} bearing")
    return b


def test_lead_screw_travel_is_pitch_theta_over_two_pi():
    pitch, Cc = 0.004, 0.01
    m = ms.Model3D()
    screw = _revolute_3d(m, "screw", (0, 0, 1))
    nut = m.add_body("nut", guess=((0, 0, -Cc), (1, 0, 0, 0)))
    m.add(ms.LeadScrew5(screw.axis(0, (0, 0, 1)), ("a", 0.0), nut.axis(0, (0, 0, 1)), pitch, Cc))
    m.add(ms.RotationLock1(nut.axis(0, (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)), 0))
    m.add(ms.RotationLock1(screw.axis(0, (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)), W * T))
    assert m.dof() == 0
    t = np.linspace(0, 6, 13)          # more than a turn
    sol = m.solve(t)
    # right-hand screw turning +W t in a nut that cannot turn: s = z_screw - z_nut = C + p a/2pi
    z = sol.location(nut.point(0))[:, 2]
    np.testing.assert_allclose(z, -(Cc + pitch * W * t / (2 * np.pi)), atol=1e-12)
    np.testing.assert_allclose(sol.velocity(nut.point(0))[:, 2], -pitch * W / (2 * np.pi), atol=1e-12)


def test_bevel_gears_ratio_is_teeth1_over_teeth2():
    t1, t2 = 12, 30
    m = ms.Model3D()
    g1 = _revolute_3d(m, "g1", (0, 0, 1))
    g2 = m.add_body("g2", guess=((0, 0, 0), (1, 0, 0, 0)))
    m.add(ms.OrthogonalGears5(g1.axis(0, (0, 0, 1)), t1, g2.axis(0, (1, 0, 0)), t2, 0.0))
    m.add(ms.Orthogonal1(g2.vector((1, 0, 0)), (0, 1, 0)))   # keeps axis 2 along x
    m.add(ms.RotationLock1(g1.axis(0, (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)), W * T))
    assert m.dof() == 0
    sol = m.solve(TIMES)
    w2 = sol.omega(g2)
    np.testing.assert_allclose(w2[:, 0], -W * t1 / t2, atol=1e-10)
    np.testing.assert_allclose(w2[:, 1:], 0.0, atol=1e-10)


def test_worm_set_with_offset():
    # one-start worm on z, wheel of 40 teeth on x, axes 0.3 apart along u1 x u2 = y
    m = ms.Model3D()
    worm = _revolute_3d(m, "worm", (0, 0, 1))
    wheel = m.add_body("wheel", guess=((0, -0.3, 0), (1, 0, 0, 0)))
    c = m.add(ms.OrthogonalGears5(worm.axis(0, (0, 0, 1)), 1, ("a", 0.0), wheel.axis(0, (1, 0, 0)),
                                  40, 0.3, 0.0))
    m.add(ms.Orthogonal1(wheel.vector((1, 0, 0)), (0, 1, 0)))
    m.add(ms.RotationLock1(worm.axis(0, (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)), W * T))
    sol = m.solve(TIMES)
    np.testing.assert_allclose(sol.omega(wheel)[:, 0], -W / 40, atol=1e-12)
    # origin of the worm lies 0.3 along (z x x) = y from the wheel's: wheel centre at -0.3 y
    np.testing.assert_allclose(sol.location(wheel.point(0)), [[0, -0.3, 0]] * len(TIMES), atol=1e-12)
    assert c.count_removed(m.space) == 5


def test_static_tooth_force_is_torque_over_pitch_radius():
    r1, r2, M2 = 0.4, 1.0, 6.0
    m, g1, g2, mesh = _pair(ms.TwoGears1, r1, r2, (r1 + r2, 0.0))
    m.remove("drive")
    m.add(ms.RotationLock1(g1, 0.0), name="drive")
    m.add_load(ms.Moment(g2, M2))                    # resisting moment on gear 2
    sol = m.solve(0.0, solution="static")
    # hand balance: the tooth force F on gear 2 at the pitch point balances M2: F r2 = M2, so
    # the driver must supply tau = F r1 on gear 1 (opposite sense for an external pair)
    F = M2 / r2
    pitch = m.ground.point((r1, 0.0))
    f2, mom2 = sol.reaction("mesh", "g2", at=g2.point(0))
    np.testing.assert_allclose(np.ravel(f2), [0.0, F], atol=1e-9)    # tangential (along y)
    np.testing.assert_allclose(np.ravel(mom2), -M2, atol=1e-9)       # balances M2
    # about the pitch point the mesh applies a pure force: no couple
    _, mom_pitch = sol.reaction("mesh", "g2", at=pitch)
    np.testing.assert_allclose(np.ravel(mom_pitch), 0.0, atol=1e-9)
    f1, _ = sol.reaction("mesh", "g1", at=pitch)
    np.testing.assert_allclose(np.ravel(f1), [0.0, -F], atol=1e-9)  # third law at the mesh
    _, tau = sol.reaction("drive", "g1")
    np.testing.assert_allclose(np.ravel(tau), F * r1, atol=1e-9)     # driving torque = F r1


def test_free_motion_with_reflected_inertia():
    r1, r2, J1, J2, tau = 0.5, 1.5, 0.2, 0.9, 2.0
    m = ms.Model2D()
    g1 = _pinned(m, "g1", (0.0, 0.0), mass=1.0, inertia=J1)
    g2 = _pinned(m, "g2", (r1 + r2, 0.0), mass=1.0, inertia=J2)
    m.add(ms.TwoGears1(g1.point(0), r1, g2.point(0), r2, 0.0))
    m.add(ms.RotationLock1(g1, 0.0), name="hold")
    m.add_load(ms.Moment(g1, tau))
    m.solve(0.0)
    t = np.linspace(0, 1.5, 7)
    sol = m.free(drop=["hold"]).simulate(t)
    acc = tau / (J1 + J2 * (r1 / r2) ** 2)            # reflected inertia
    np.testing.assert_allclose(sol.angle(g1), 0.5 * acc * t**2, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(sol.angle(g2), -(r1 / r2) * 0.5 * acc * t**2, rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("make,what", [
    (lambda m, a, b: ms.TwoGears2(a.point(0), 0, b.point(0), 1, 0), "TwoGears2 rad1"),
    (lambda m, a, b: ms.TwoGears1(a.point(0), 1, b.point(0), 0.0, 0), "TwoGears1 rad2"),
    (lambda m, a, b: ms.TwoGears2(a.point(0), 1, b.point(0), -1, 0), "TwoGears2: rad1 + rad2 = 0"),
    (lambda m, a, b: ms.TwoPulleys2(a.point(0), 1, b.point(0), 1, 3, 0), "RotationLock1"),
    (lambda m, a, b: ms.RackAndPinion2(a.point(0), 0, b.axis(0, (1, 0)), 0), "RackAndPinion2 rad"),
])
def test_bad_planar_input_names_the_constraint(make, what):
    m = ms.Model2D()
    a, b = m.add_body("a"), m.add_body("b")
    with pytest.raises(ModelError, match=what.replace("+", r"\+")):
        make(m, a, b)


@pytest.mark.parametrize("make,err,what", [
    (lambda a, b: ms.OrthogonalGears5(a.axis(0, (0, 0, 1)), 0, b.axis(0, (1, 0, 0)), 30, 0),
     ModelError, "OrthogonalGears5 teeth1"),
    (lambda a, b: ms.ParallelGears5(a.axis(0, (0, 0, 1)), -0.5, b.axis(0, (0, 0, 1)), 0, 0),
     ModelError, "ParallelGears5 rad2"),
    (lambda a, b: ms.LeadScrew5(a.axis(0, (0, 0, 1)), b.axis(0, (0, 0, 1)), 0, 0),
     ModelError, "LeadScrew5 pitch"),
    (lambda a, b: ms.LeadScrew5(((0, 0, 0), (0, 0, 0)), b.axis(0, (0, 0, 1)), 0.1, 0),
     GeometryError, "LeadScrew5 axis1"),
    (lambda a, b: ms.ParallelGears5(a.axis(0, (0, 0, 1)), 1, ((1, 0, 0), (0, 0, 0)), 1, 0),
     GeometryError, "ParallelGears5 axis2"),
    (lambda a, b: ms.RackAndPinion5(a.axis(0, (0, 0, 1)), 0, b.axis(0, (0, 0, 1)), 0),
     ModelError, "RackAndPinion5 rad"),
])
def test_bad_spatial_input_names_the_constraint(make, err, what):
    m = ms.Model3D()
    a, b = m.add_body("a"), m.add_body("b")
    with pytest.raises(err, match=what):
        make(a, b)


def test_wrong_argument_count_and_kind():
    m = ms.Model2D()
    a, b = m.add_body("a"), m.add_body("b")
    with pytest.raises(ModelError, match="TwoGears2 takes"):
        ms.TwoGears2(a.point(0), 1, b.point(0), 2)
    m3 = ms.Model3D()
    c = m3.add_body("c")
    with pytest.raises(MechError, match="TwoGears2"):
        m3.add(ms.TwoGears2(c.point(0), 1, m3.ground.point((0, 0, 0)), 2, 0))


def test_default_variable_guess_follows_the_bodies():
    # centre line pointing down: the default guess of Theta is -pi/2, so the second equation
    # of TwoGears1 starts on the right branch (Theta, not Theta + pi)
    m = ms.Model2D()
    g1 = _pinned(m, "g1", (0.0, 0.0))
    g2 = _pinned(m, "g2", (0.0, -3.0))
    c = m.add(ms.TwoGears1(g1.point(0), 1.0, g2.point(0), 2.0, 0.0))
    (v,) = c.new_variables()
    assert v.symbol.name == "Theta_g1_g2"
    assert v.guess == pytest.approx(-np.pi / 2)


def test_parallel_gears_in_space_ratio_and_phase():
    r1, r2, Cc = 1.0, 2.0, 0.3
    m = ms.Model3D()
    g1 = _revolute_3d(m, "g1", (0, 0, 1))
    g2 = m.add_body("g2", guess=((3.0, 0, 0), (1, 0, 0, 0)))
    c = m.add(ms.ParallelGears5(g1.axis(0, (0, 0, 1)), r1, g2.axis(0, (0, 0, 1)), r2, Cc))
    m.add(ms.RelativeY1(g2.point(0), 0.0))           # the centre stays on the x axis
    m.add(ms.RotationLock1(g1.axis(0, (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)), W * T))
    assert m.dof() == 0
    sol = m.solve(TIMES)
    np.testing.assert_allclose(sol.location(g2.point(0))[:, 0], 3.0, atol=1e-12)
    np.testing.assert_allclose(sol.omega(g2)[:, 2], -W * r1 / r2, atol=1e-12)
    # e_i = spin of gear i from the centre line (+x): r1 e1 + r2 e2 = C, alpha = e1
    alpha = sol.coordinate(c.alpha.name)
    np.testing.assert_allclose(alpha, W * TIMES, atol=1e-10)
    x2 = np.array([sol.location(g2.point((1, 0, 0)))[k] - sol.location(g2.point(0))[k]
                   for k in range(len(TIMES))])
    e2 = np.arctan2(x2[:, 1], x2[:, 0])
    np.testing.assert_allclose(r1 * W * TIMES + r2 * e2, Cc, atol=1e-10)


def test_rack_and_pinion_in_space_travel():
    # pinion about z at the origin; rack teeth along z, travel along x, pitch plane y = -r
    r = 0.6
    m = ms.Model3D()
    pinion = _revolute_3d(m, "pinion", (0, 0, 1))
    rack = m.add_body("rack", guess=((0, -r, 0), (1, 0, 0, 0)))
    m.add(ms.RackAndPinion5(pinion.axis(0, (0, 0, 1), (1, 0, 0)), r, ("a", 0.0),
                            rack.axis(0, (0, 0, 1), (1, 0, 0)), 0.0))
    # the rack cannot swing round the pinion: its travel stays along x
    m.add(ms.RotationLock1(rack.axis(0, (0, 0, 1), (1, 0, 0)),
                           m.ground.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)), 0.0))
    m.add(ms.RotationLock1(pinion.axis(0, (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)), W * T))
    assert m.dof() == 0
    sol = m.solve(TIMES)
    # pinion at k2 = z x x = +y side of the rack; g2 . (r1 - r2) = -x_rack = C - r alpha
    np.testing.assert_allclose(sol.location(rack.point(0)),
                               np.column_stack([r * W * TIMES, -r + 0 * TIMES, 0 * TIMES]), atol=1e-12)


def test_variable_keyword_equals_mech_position():
    m = ms.Model2D()
    a, b = m.add_body("a"), m.add_body("b")
    c1 = ms.TwoGears2(a.point(0), 1, ("s", 0.4), b.point(0), 2, 0)
    c2 = ms.TwoGears2(a.point(0), 1, b.point(0), 2, 0, variable=("s", 0.4))
    assert (c1.alpha, c1.variable().guess) == (c2.alpha, c2.variable().guess) == (sp.Symbol("s"), 0.4)
    with pytest.raises(ModelError, match="given twice"):
        ms.TwoGears2(a.point(0), 1, ("s", 0.4), b.point(0), 2, 0, variable=("t", 0))
    import inspect

    assert list(inspect.signature(ms.TwoPulleys2.__init__).parameters)[1:] == [
        "point1", "rad1", "point2", "rad2", "dist", "C", "variable"]


def test_inverse_dynamics_drive_torque_is_reflected_inertia_times_acceleration():
    r1, r2, J1, J2, acc = 0.5, 1.5, 0.2, 0.9, 3.0
    m = ms.Model2D()
    g1 = _pinned(m, "g1", (0.0, 0.0), mass=1.0, inertia=J1)
    g2 = _pinned(m, "g2", (r1 + r2, 0.0), mass=1.0, inertia=J2)
    m.add(ms.TwoGears1(g1.point(0), r1, g2.point(0), r2, 0.0), name="mesh")
    m.add(ms.RotationLock1(g1, 0.5 * acc * T**2), name="drive")
    t = np.array([0.0, 0.4, 1.1])
    sol = m.solve(t, solution="dynamic")
    _, tau = sol.reaction("drive", "g1")
    np.testing.assert_allclose(np.ravel(tau), (J1 + J2 * (r1 / r2) ** 2) * acc, rtol=1e-10)
    # the tooth force accelerates gear 2: F r2 = J2 * acc * r1 / r2
    f2, _ = sol.reaction("mesh", "g2", at=m.ground.point((r1, 0.0)))
    np.testing.assert_allclose(np.abs(np.asarray(f2)[:, 1]), J2 * acc * r1 / r2 / r2, rtol=1e-10)


def test_two_default_variables_on_the_same_bodies_are_refused():
    # a planet meshing with two gears fixed to ground would share "Theta_planet_ground":
    # silently one variable for two centre lines; Model.add refuses, naming the constraint
    m = ms.Model2D()
    p = _pinned(m, "planet", (0.0, 0.0))
    m.add(ms.TwoGears1(p.point(0), 1.0, m.ground.point((2.0, 0.0)), 1.0, 0.0), name="mesh A")
    with pytest.raises(ModelError, match=r"mesh B.*Theta_planet_ground.*\(sym, guess\)"):
        m.add(ms.TwoGears1(p.point(0), 1.0, m.ground.point((0.0, 3.0)), 2.0, 0.0), name="mesh B")
    m.add(ms.TwoGears1(p.point(0), 1.0, ("phi_b", 1.5), m.ground.point((0.0, 3.0)), 2.0, 0.0))


def test_pulleys_in_space_turn_the_same_way_at_r1_over_r2():
    r1, r2, dist, Cc = 1.0, 2.5, 4.0, 0.2
    m = ms.Model3D()
    p1 = _revolute_3d(m, "p1", (0, 0, 1))
    p2 = m.add_body("p2", guess=((dist, 0, 0), (1, 0, 0, 0)))
    c = m.add(ms.TwoPulleys5(p1.axis(0, (0, 0, 1)), r1, p2.axis(0, (0, 0, 1)), r2, dist, Cc))
    m.add(ms.RelativeY1(p2.point(0), 0.0))
    m.add(ms.RotationLock1(p1.axis(0, (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)), W * T))
    assert m.dof() == 0
    sol = m.solve(TIMES)
    np.testing.assert_allclose(sol.location(p2.point(0))[:, 0], dist, atol=1e-12)
    np.testing.assert_allclose(sol.omega(p2)[:, 2], W * r1 / r2, atol=1e-12)
    # C = r1 e1 - r2 e2 with e_i measured from the centre line (+x)
    x2 = sol.location(p2.point((1, 0, 0))) - sol.location(p2.point(0))
    e2 = np.arctan2(x2[:, 1], x2[:, 0])
    np.testing.assert_allclose(r1 * sol.coordinate(c.alpha.name) - r2 * e2, Cc, atol=1e-10)
    with pytest.raises(ms.ModelError, match="TwoPulleys5 dist"):
        ms.TwoPulleys5(p1.axis(0, (0, 0, 1)), r1, p2.axis(0, (0, 0, 1)), r2, 0.0, Cc)
