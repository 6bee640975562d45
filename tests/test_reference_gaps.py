"""Issue 10, section 5: small gaps against Mech's function reference, each checked against an
independent calculation (closed-form kinematics, hand-computed geometry, SciPy rotations,
Newton-Euler by hand)."""

import numpy as np
import pytest
import sympy as sp
from scipy.spatial.transform import Rotation

import mechsys as ms
from mechsys import T, models

CRANK, ROD, W = 2.0, 6.0, 2 * np.pi


def slider_crank_closed_form(t):
    """Crank pin A, wrist pin B (on the x axis) and rod angle of the slider-crank."""
    th = W * t
    A = np.array([CRANK * np.cos(th), CRANK * np.sin(th)])
    xb = A[0] + np.sqrt(ROD**2 - A[1] ** 2)
    phi = np.arctan2(-A[1], xb - A[0])
    return th, A, xb, phi


# -- 1. InstantCenter, Coordinates -> Local ----------------------------------------------------

def test_instant_center_global_and_local_against_closed_form():
    m = models.slider_crank(crank=CRANK, rod=ROD, speed=W)
    t = np.array([0.1, 0.3, 0.6, 0.85])
    sol = m.solve(t, solution="velocity")
    ic_g = sol.instant_center("rod")
    ic_l = sol.instant_center("rod", coordinates="local")
    for k, tk in enumerate(t):
        th, A, xb, phi = slider_crank_closed_form(tk)
        # the rod's instant centre: the crank line O-A meets the normal to the slide at B
        expected = np.array([xb, xb * np.tan(th)])
        np.testing.assert_allclose(ic_g[k], expected, rtol=1e-9)
        c, s = np.cos(phi), np.sin(phi)
        local = np.array([[c, s], [-s, c]]) @ (expected - A)    # rod origin is the pin A
        np.testing.assert_allclose(ic_l[k], local, rtol=1e-9, atol=1e-9)


def test_instant_center_local_symbolic_is_a_point_of_zero_velocity():
    m = models.slider_crank()
    s_loc = m.instant_center("rod", "local")        # symbolic, in the rod's frame
    rod = m.body("rod")
    sx, sy = sp.symbols("sx sy")
    vel = m.velocity(rod.point((sx, sy)))            # velocity of a general rod point
    vs = m.velocity_symbols()
    vals = {rod.q[0]: 1.3, rod.q[1]: -0.4, rod.q[2]: 0.7,
            vs[rod.q[0]]: 0.9, vs[rod.q[1]]: -2.1, vs[rod.q[2]]: 1.7}
    ic = [float(c.subs(vals)) for c in s_loc]
    v_ic = [float(v.subs(vals).subs({sx: ic[0], sy: ic[1]})) for v in vel]
    np.testing.assert_allclose(v_ic, 0, atol=1e-12)
    assert abs(float(vel[0].subs(vals).subs({sx: ic[0] + 1, sy: ic[1]}))) > 0.1


def test_instant_axis_local_3d_has_velocity_along_omega():
    m = ms.Model3D()
    b = m.add_body("b")
    pt, d = m.instant_center(b, coordinates="local")
    vs = m.velocity_symbols()
    e = np.array([0.3, -0.5, 0.6, 0.2])
    e /= np.linalg.norm(e)
    w = np.array([0.4, -1.2, 0.9])                   # angular velocity, global
    E = np.array([[-e[1], e[0], -e[3], e[2]], [-e[2], e[3], e[0], -e[1]],
                  [-e[3], -e[2], e[1], e[0]]])      # omega = 2 E e_dot (global)
    ed = 0.5 * E.T @ w
    vals = dict(zip(b.q, [0.5, 1.0, -2.0, *e]))
    vals.update(dict(zip([vs[s] for s in b.q], [1.0, 0.2, -0.7, *ed])))
    pt_n = np.array([float(c.subs(vals)) for c in pt])
    d_n = np.array([float(c.subs(vals)) for c in d])
    A = Rotation.from_quat([e[1], e[2], e[3], e[0]]).as_matrix()
    np.testing.assert_allclose(A @ d_n, w, atol=1e-12)          # direction: omega in body axes
    v_p = np.array([1.0, 0.2, -0.7]) + np.cross(w, A @ pt_n)   # velocity of that body point
    np.testing.assert_allclose(np.cross(v_p, w), 0, atol=1e-12)
    with pytest.raises(ms.ModelError, match="coordinates"):
        m.instant_center(b, coordinates="body")


# -- 2. IntersectionPoint[axis1, axis2, offset] (2D) -------------------------------------------

def _left_distance(p, origin, u):
    u = np.asarray(u, float) / np.linalg.norm(u)
    return np.array([-u[1], u[0]]) @ (np.asarray(p, float) - np.asarray(origin, float))


@pytest.mark.parametrize("offset", [1.0, 0.25, -0.5])
def test_intersection_point_offset_is_left_of_both_axes(offset):
    m = ms.Model2D()
    g = m.ground
    u1, u2 = (2.0, 0.5), (-1.0, 3.0)
    p = ms.intersection_point(g.axis((0, 0), u1), g.axis((5, 1), u2), offset)
    assert _left_distance(p, (0, 0), u1) == pytest.approx(offset, abs=1e-12)
    assert _left_distance(p, (5, 1), u2) == pytest.approx(offset, abs=1e-12)
    # fillet between the x axis and a vertical line at x = 5: centre one radius inside
    np.testing.assert_allclose(
        ms.IntersectionPoint(g.axis((0, 0), (1, 0)), g.axis((5, 0), (0, 1)), 1.0), [4, 1])


def test_intersection_point_offset_on_moving_bodies():
    m = models.slider_crank(crank=CRANK, rod=ROD, speed=W)
    cr, rod = m.body("crank"), m.body("rod")
    expr = ms.intersection_point(cr.axis(0, (1, 0)), rod.axis("b", (-1, 0)), 0.3)
    sol = m.solve(np.array([0.15, 0.4]))
    got = sol.eval(expr)
    for k, tk in enumerate(sol.t):
        th, A, xb, phi = slider_crank_closed_form(tk)
        u_rod = -np.array([np.cos(phi), np.sin(phi)])
        assert _left_distance(got[k], (0, 0), (np.cos(th), np.sin(th))) == pytest.approx(0.3)
        assert _left_distance(got[k], (xb, 0), u_rod) == pytest.approx(0.3)


def test_intersection_point_offset_is_planar_only():
    m = ms.Model3D()
    g = m.ground
    with pytest.raises(ms.GeometryError, match="planar"):
        ms.intersection_point(g.axis((0, 0, 0), (1, 0, 0)), g.axis((5, 0, 0), (1, 0, 0)), 1.0)


# -- 3. ParallelAxis with {angle, axis}, a rotation vector or Euler parameters ----------------

J_C = (0.5, 0.8, 1.1, 0.12, -0.07, 0.05)


def _matrix(j6):
    xx, yy, zz, xy, yz, zx = j6
    return np.array([[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]])


def test_parallel_axis_rotation_formats_against_scipy():
    angle, axis = 0.9, np.array([1.0, -2.0, 0.5])
    rv = angle * axis / np.linalg.norm(axis)
    R = Rotation.from_rotvec(rv).as_matrix()
    q = Rotation.from_rotvec(rv).as_quat()          # (x, y, z, w)
    euler = (q[3], q[0], q[1], q[2])
    d, mass = np.array([0.3, -0.2, 0.7]), 2.5
    expected = R @ _matrix(J_C) @ R.T + mass * (d @ d * np.eye(3) - np.outer(d, d))
    for rot in ((angle, tuple(axis)), tuple(rv), euler, R, sp.Matrix(R)):
        got = _matrix(ms.parallel_axis(d, mass, J_C, rot))
        np.testing.assert_allclose(got, expected, atol=1e-12)
    # a nested list is ambiguous (a matrix, or three rotation vectors?): refused, as by every
    # function taking a rotation (issue 34)
    with pytest.raises(ms.ModelError, match="ambiguous"):
        ms.parallel_axis(d, mass, J_C, R.tolist())


def test_parallel_axis_rotation_round_trip_with_negative_mass():
    angle, axis = 1.2, (0.0, 1.0, 1.0)
    R = Rotation.from_rotvec(angle * np.array(axis) / np.sqrt(2)).as_matrix()
    d, mass = np.array([0.4, 0.1, -0.3]), 1.7
    J_o = ms.ParallelAxis(d, mass, J_C, (angle, axis))
    # back: vector centroid -> other origin and the other frame's rotation, in centroidal axes
    J_back = ms.ParallelAxis(-R.T @ d, -mass, J_o, (-angle, axis))
    np.testing.assert_allclose(J_back, J_C, atol=1e-12)


# -- 4. Gravity with Magnitude -> Relative -----------------------------------------------------

def _held_arm(gravity, angle=0.6, mass=2.0, c=1.5):
    m = ms.Model2D()
    arm = m.add_body("arm", mass=mass, centroid=(c, 0), inertia=0.3, guess=((0, 0), angle))
    m.add(ms.Revolute2(m.ground.point((0, 0)), arm.point(0)), name="pivot")
    m.add(ms.RotationLock1(arm, angle), name="drive")
    m.add_load(gravity)
    return m


def test_gravity_relative_scales_by_vector_length():
    angle, mass, c = 0.6, 2.0, 1.5
    m = _held_arm(ms.Gravity((0, -2), 4.905, mode="relative"), angle, mass, c)
    sol = m.solve(0.0, solution="static")
    # the motor holds the weight m * (2 * 4.905) = m * 9.81 at lever c cos(angle)
    assert sol.reaction("drive", "arm")[1] == pytest.approx(mass * 9.81 * c * np.cos(angle))
    np.testing.assert_allclose(sol.loads("arm", coordinates="global")[0], [0, -mass * 9.81])
    # potential energy: m |g| height of the centroid
    assert sol.potential_energy() == pytest.approx(mass * 9.81 * c * np.sin(angle))
    # absolute (the default) ignores the vector's length
    m2 = _held_arm(ms.Gravity((0, -2), 9.81), angle, mass, c)
    sol2 = m2.solve(0.0, solution="static")
    assert sol2.reaction("drive", "arm")[1] == pytest.approx(mass * 9.81 * c * np.cos(angle))


def test_gravity_mode_is_checked():
    with pytest.raises(ms.ModelError, match="'absolute', 'relative'"):
        ms.Gravity((0, -1), 9.81, mode="Relative")


# -- 5. 2D guesses as degenerate Euler parameters (ei, ej) -------------------------------------

@pytest.mark.parametrize("angle", [0.0, 0.7, 2.5, -2.9, -0.4])
@pytest.mark.parametrize("scale", [1.0, 3.0])
def test_planar_guess_from_degenerate_euler_parameters(angle, scale):
    m = ms.Model2D()
    m.add_body("b", guess=((1, 2), (scale * np.cos(angle), scale * np.sin(angle))))
    np.testing.assert_allclose(m.guess(), [1, 2, angle], atol=1e-15)


def test_planar_guess_euler_pair_solves_like_the_angle():
    def build(rot_guess):
        m = models.slider_crank(crank=CRANK, rod=ROD, speed=W)
        m.set_guess(**{"rod.th": 0.0})
        rod = m.body("rod")
        rod.guess = rod._parse_guess(((CRANK, 0.5), rot_guess))
        return m.solve(0.1).q

    ang = -0.3
    np.testing.assert_allclose(build((np.cos(ang), np.sin(ang))), build(ang), atol=1e-12)


def test_planar_guess_bad_euler_pair():
    m = ms.Model2D()
    with pytest.raises(ms.ModelError, match="rotation guess of body 'b'.*do not define"):
        m.add_body("b", guess=((0, 0), (0.0, 0.0)))
    with pytest.raises(ms.ModelError, match="rotation guess of body 'c'"):
        m.add_body("c", guess=((0, 0), ("x", 1)))


# -- 6. GyroMoment without Inertia takes the spin inertia from the body ------------------------

W0, W1, WS = 3.0, 0.7, 40.0


def _rotor(gyro_inertia, axis=(1.0, 1.0, 0.0), with_gyro=True):
    m = ms.Model3D()
    b = m.add_body("rotor", mass=2.0, inertia=J_C, guess=((0, 0, 0), (1, 0, 0, 0)))
    x, y, z, e0, e1, e2, e3 = b.q
    th = W0 * T + W1 * T**2
    m.add(ms.Constraint([x, y, z]), name="fixed point")
    m.add(ms.Constraint([e1, e2]), name="z axis")
    m.add(ms.Constraint([e3 - sp.sin(th / 2)]), name="spin")
    if with_gyro:
        m.add_load(ms.GyroMoment(b, axis, WS, inertia=gyro_inertia))
    return m


def test_gyromoment_spin_inertia_from_the_body():
    a = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    I_s = a @ _matrix(J_C) @ a                     # 0.77, by hand: (0.5 + 0.8 + 2*0.12)/2
    assert I_s == pytest.approx(0.77)
    m = _rotor(None)
    assert float(m.load_list[0].spin_inertia(m)) == pytest.approx(I_s)
    # the same axis given as a body vector
    m_v = _rotor(None, axis=None, with_gyro=False)
    g = ms.GyroMoment(m_v.body("rotor"), m_v.body("rotor").vector((1, 1, 0)), WS)
    m_v.add_load(g)
    assert float(g.spin_inertia(m_v)) == pytest.approx(I_s)

    t = np.array([0.2, 0.9])
    sols = {k: _rotor(v, with_gyro=v != "none").solve(t, solution="dynamic")
            for k, v in (("body", None), ("given", I_s), ("none", "none"))}
    for c in ("fixed point", "z axis", "spin"):
        for u, v in zip(sols["body"].reaction(c, "rotor"), sols["given"].reaction(c, "rotor")):
            np.testing.assert_allclose(u, v, atol=1e-10)
    # by hand: the gyro applies M = -I_s ws (omega x a_global); the bearings take -M more
    dM = sum(np.asarray(sols["body"].reaction(c, "rotor", at=(0, 0, 0))[1])
             - np.asarray(sols["none"].reaction(c, "rotor", at=(0, 0, 0))[1])
             for c in ("fixed point", "z axis", "spin"))
    for k, tk in enumerate(t):
        th, w = W0 * tk + W1 * tk**2, W0 + 2 * W1 * tk
        ag = np.array([np.cos(th) - np.sin(th), np.sin(th) + np.cos(th), 0]) / np.sqrt(2)
        np.testing.assert_allclose(dM[k], I_s * WS * np.cross([0, 0, w], ag), atol=1e-9)


# -- 7. Location[bnum]: a body's coordinates ----------------------------------------------------

def test_location_of_bodies_gives_their_coordinates():
    m = models.slider_crank(crank=CRANK, rod=ROD, speed=W)
    crank, rod = m.body("crank"), m.body("rod")
    assert m.location([crank]) == sp.Matrix(crank.q)
    assert m.location(["crank", rod]) == sp.Matrix([*crank.q, *rod.q])
    assert m.location(ms.All) == sp.Matrix(m.compile().layout.q_symbols)
    assert m.location(crank) == crank.r              # a body handle stays its origin point
    t = np.array([0.1, 0.35])
    sol = m.solve(t)
    got = sol.location(["rod"])
    for k, tk in enumerate(t):
        th, A, xb, phi = slider_crank_closed_form(tk)
        np.testing.assert_allclose(got[k], [A[0], A[1], phi], atol=1e-10)
    np.testing.assert_allclose(sol.location(ms.All), sol.q)
    assert sol.location(ms.Rest).shape == (2, 0)
    np.testing.assert_allclose(sol.location([1.0, 2.0]), np.tile([1.0, 2.0], (2, 1)))


def test_location_of_a_spatial_body_has_seven_coordinates():
    m = _rotor(0.5)
    sol = m.solve(0.4)
    th = W0 * 0.4 + W1 * 0.16
    np.testing.assert_allclose(sol.location(["rotor"]),
                               [0, 0, 0, np.cos(th / 2), 0, 0, np.sin(th / 2)], atol=1e-10)


# -- 8. All / Rest / list forms: Jacobian^T . Generalized == Loads[All] -------------------------

def _dynamic_slider_crank():
    return models.slider_crank_dynamic(crank=CRANK, rod=ROD, speed=W,
                                       piston_force=-80.0 * sp.cos(W * T))


def test_static_balance_is_one_line():
    m = _dynamic_slider_crank()
    sol = m.solve(0.3, solution="static")
    assert np.allclose(sol.jacobian(ms.All, ms.All).T @ sol.generalized(ms.All),
                       sol.loads(ms.All), atol=1e-9)
    # and it is not trivially zero
    assert np.abs(sol.loads(ms.All)).max() > 10


def test_balance_on_a_free_equilibrium_uses_the_free_systems_rows():
    m = models.slider_crank_dynamic(piston_force=-50.0)
    eq = m.free(drop=["drive"], solution="static").solve(0.0)
    J, lam = eq.jacobian(ms.All, ms.All), eq.generalized(ms.All)
    assert J.shape == (8, 9) and lam.shape == (8,)      # the driver's row is dropped
    # the equilibrium's tolerance is relative to the loads (unit-free Newton): 1e-12 of them
    loads = eq.loads(ms.All)
    assert np.allclose(J.T @ lam, loads, rtol=0, atol=1e-10 * np.abs(loads).max())
    # symbolically on the model: the reaction is -Phi_q^T lambda, row for row
    assert sp.simplify(m.jacobian(ms.All, ms.All).T * m.generalized(ms.All)
                       + m.loads(ms.All, "reaction")) == sp.zeros(9, 1)


def test_dynamic_balance_is_one_line_over_a_sweep():
    m = _dynamic_slider_crank()
    sol = m.solve(np.linspace(0, 1, 9), solution="dynamic")
    J, lam = sol.jacobian(ms.All, ms.All), sol.generalized(ms.All)
    np.testing.assert_allclose(np.einsum("kij,ki->kj", J, lam),
                               sol.loads(ms.All) + sol.loads(ms.All, "dynamic"), atol=1e-8)
    np.testing.assert_allclose(sol.loads(ms.All, "reaction"), -np.einsum("kij,ki->kj", J, lam),
                               atol=1e-8)


def test_dynamic_balance_one_line_in_3d_with_euler_normalisation():
    m = _rotor(None)
    sol = m.solve(0.6, solution="dynamic")
    J, lam = sol.jacobian(ms.All, ms.All), sol.generalized(ms.All)
    assert J.shape == (7, 7) and lam.shape == (7,)     # 6 constraint rows + 1 normalisation
    np.testing.assert_allclose(J.T @ lam, sol.loads(ms.All) + sol.loads(ms.All, "dynamic"),
                               atol=1e-8)


def test_list_and_symbol_forms_match_the_single_forms():
    m = _dynamic_slider_crank()
    sol = m.solve(np.linspace(0, 0.5, 4), solution="dynamic")
    rod_th = m.body("rod").q[2]
    np.testing.assert_allclose(sol.loads(["crank", "piston"]),
                               np.hstack([sol.loads("crank"), sol.loads("piston")]))
    np.testing.assert_allclose(sol.loads(rod_th)[:, 0], sol.loads("rod")[:, 2])
    np.testing.assert_allclose(sol.loads(["rod", rod_th], "dynamic")[:, 3],
                               sol.loads("rod", "dynamic")[:, 2])
    np.testing.assert_allclose(sol.generalized(["drive", "slider"]),
                               np.hstack([sol.generalized("drive"), sol.generalized("slider")]))
    J_rows = sol.jacobian(["drive", "crank pin"], ["crank"])
    np.testing.assert_allclose(J_rows, np.concatenate([sol.jacobian("drive", "crank"),
                                                       sol.jacobian("crank pin", "crank")], 1))
    np.testing.assert_allclose(sol.mass_matrix(["rod"]), sol.mass_matrix("rod"))
    M = sol.mass_matrix(["piston", "crank"])
    assert M.shape == (4, 6, 6)
    np.testing.assert_allclose(M[:, :3, :3], sol.mass_matrix("piston"))
    np.testing.assert_allclose(sol.centrifugal(["rod"]), sol.centrifugal("rod"))
    assert sol.loads(ms.Rest).shape == (4, 0)
    assert m.generalized(ms.All) == sp.Matrix(m.compile().lam_symbols)
    with pytest.raises(ms.ModelError, match="single body"):
        sol.loads(ms.All, coordinates="global")
    with pytest.raises(ms.ModelError, match="empty"):
        sol.loads([])


def test_rest_selects_model_variables():
    m = ms.Model2D()
    b = m.add_body("b", guess=((0, 0.5), 0))
    s = m.variable("s", 0.5)
    x, y, th = b.q
    m.add(ms.Constraint([x, th, y - s]), name="user")
    m.add(ms.Constraint([s - 0.5 - 0.1 * T]), name="drive s")
    m.add_load(ms.Load(s, 7.0))
    m.add_load(ms.Force(b.point(0), (0, 1), -3.0))
    sol = m.solve(0.2, solution="static")
    np.testing.assert_allclose(sol.location(ms.Rest), [0.52])
    np.testing.assert_allclose(sol.loads(ms.Rest), [7.0])
    np.testing.assert_allclose(sol.loads(ms.All), [0, -3.0, 0, 7.0])
    assert sol.jacobian(ms.All, ms.Rest).shape == (4,)   # one column: a vector, as eval gives
    assert np.allclose(sol.jacobian(ms.All, ms.All).T @ sol.generalized(ms.All), sol.loads(ms.All))


def test_lambda_guess_forms():
    m = _dynamic_slider_crank()
    ref = m.solve(0.3, solution="static").generalized(ms.All)
    nm = len(ref)
    lam_sym = m.multipliers("drive")[0]
    for guess in (2.0, np.full(nm, -1.0), list(ref), {"drive": 5.0}, {lam_sym: 3.0},
                  {"crank pin": (1.0, 2.0)}):
        np.testing.assert_allclose(m.solve(0.3, solution="static", lambda_guess=guess)
                                   .generalized(ms.All), ref, atol=1e-9)
    with pytest.raises(ms.ModelError, match="lambda_guess"):
        m.solve(0.3, solution="static", lambda_guess=[1.0, 2.0])
    with pytest.raises(ms.ModelError, match=r"lambda_guess\['crank pin'\]"):
        m.solve(0.3, solution="static", lambda_guess={"crank pin": (1.0, 2.0, 3.0)})
    with pytest.raises(ms.ModelError, match="not a multiplier"):
        m.solve(0.3, solution="static", lambda_guess={sp.Symbol("lam99_1"): 1.0})
    with pytest.raises(ms.UnknownConstraintError):
        m.solve(0.3, solution="static", lambda_guess={"no such": 1.0})
