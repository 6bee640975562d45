"""Generalized-coordinate joints (Mech ch. 11): planar checks against independent
computations (absolute-coordinate models, a minimal-coordinate ODE written here, closed
forms, Freudenstein's equation)."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import mechsys as ms

G = 9.81
M1, J1, C1 = 1.0, 0.1, (0.5, 0.0)
M2, J2, C2 = 2.0, 0.2, (0.4, 0.1)
L1 = 1.0


def _links(m, guess_b=None):
    a = m.add_body("a", points={"o": (0, 0), "e": (L1, 0)}, mass=M1, inertia=J1, centroid=C1)
    b = m.add_body("b", points={"o": (0, 0), "e": (1, 0)}, mass=M2, inertia=J2, centroid=C2,
                   guess=guess_b)
    return a, b


def gen_pendulum():
    m = ms.Model2D()
    a, b = _links(m)
    m.add(ms.GenRevolute2(a.axis("o"), m.ground.axis((0, 0)), ("t1", 0.3)), name="j1")
    m.add(ms.GenRevolute2(b.axis("o"), a.axis("e"), ("t2", 0.2)), name="j2")
    m.add_load(ms.Gravity((0, -1), G))
    return m


def abs_pendulum(t1, t2):
    m = ms.Model2D()
    a, b = _links(m, guess_b=((L1 * np.cos(t1), L1 * np.sin(t1)), t1 + t2))
    m.add(ms.Revolute2(a.point("o"), m.ground.point((0, 0))), name="j1")
    m.add(ms.Revolute2(b.point("o"), a.point("e")), name="j2")
    m.add(ms.RotationLock1(a, t1), name="l1")
    m.add(ms.RotationLock1(b, t1 + t2), name="l2")
    m.add_load(ms.Gravity((0, -1), G))
    m.solve(0.0)
    return m


def minimal_rhs(t, y):
    """The double pendulum's Lagrange equations in joint angles, written out: link b's
    centroid at distance d2 from the pin, at angle delta off the link."""
    q1, q2, w1, w2 = y
    d1 = C1[0]
    d2, de = np.hypot(*C2), np.arctan2(C2[1], C2[0])
    c = np.cos(q2 + de)
    h = M2 * L1 * d2 * np.sin(q2 + de)
    M = np.array([[M1 * d1**2 + J1 + M2 * (L1**2 + d2**2 + 2 * L1 * d2 * c) + J2,
                   M2 * (d2**2 + L1 * d2 * c) + J2],
                  [M2 * (d2**2 + L1 * d2 * c) + J2, M2 * d2**2 + J2]])
    cor = np.array([-h * (2 * w1 * w2 + w2**2), h * w1**2])
    grav = np.array([M1 * G * d1 * np.cos(q1) + M2 * G * (L1 * np.cos(q1) + d2 * np.cos(q1 + q2 + de)),
                     M2 * G * d2 * np.cos(q1 + q2 + de)])
    qdd = np.linalg.solve(M, -cor - grav)
    return [w1, w2, *qdd]


T_OUT = np.linspace(0, 1.5, 7)
Y0 = (0.3, 0.2, 1.0, -0.5)


@pytest.fixture(scope="module")
def pendulums():
    g = gen_pendulum()
    sg = g.free().simulate(T_OUT, initial_condition={"t1": Y0[0], "t2": Y0[1], "t1_d": Y0[2],
                                                      "t2_d": Y0[3]}, rtol=1e-12, atol=1e-12)
    am = abs_pendulum(Y0[0], Y0[1])
    sa = am.free(drop=["l1", "l2"]).simulate(
        T_OUT, initial_condition={"a.th_d": Y0[2], "b.th_d": Y0[2] + Y0[3]}, rtol=1e-12, atol=1e-12)
    return g, sg, am, sa


def test_double_pendulum_coordinates_are_the_dof(pendulums):
    g = pendulums[0]
    assert g.compile().layout.q_names == ("t1", "t2")
    assert g.compile().m == 0
    assert int(g.dof()) == 2


def test_double_pendulum_matches_absolute_model_and_minimal_ode(pendulums):
    g, sg, am, sa = pendulums
    pg = sg.location(g.body("b").point("e"))
    pa = sa.location(am.body("b").point("e"))
    assert np.abs(pg - pa).max() < 1e-8
    np.testing.assert_allclose(sg["t1"], sa["a.th"], atol=1e-8)
    np.testing.assert_allclose(sg["t1"] + sg["t2"], sa["b.th"], atol=1e-8)
    ode = solve_ivp(minimal_rhs, (0, T_OUT[-1]), Y0, t_eval=T_OUT, rtol=1e-12, atol=1e-12,
                    method="DOP853")
    np.testing.assert_allclose(sg["t1"], ode.y[0], atol=1e-8)
    np.testing.assert_allclose(sg["t2"], ode.y[1], atol=1e-8)
    # outputs on the slave bodies: velocity, acceleration, omega, alpha
    np.testing.assert_allclose(sg.velocity(g.body("b").point("e")),
                               sa.velocity(am.body("b").point("e")), atol=1e-8)
    np.testing.assert_allclose(sg.acceleration(g.body("b").point("e")),
                               sa.acceleration(am.body("b").point("e")), atol=1e-7)
    np.testing.assert_allclose(np.ravel(sg.omega("b")), np.ravel(sa.omega("b")), atol=1e-8)
    np.testing.assert_allclose(np.ravel(sg.alpha("b")), np.ravel(sa.alpha("b")), atol=1e-7)
    np.testing.assert_allclose(sg.instant_center("b"), sa.instant_center("b"), atol=1e-7)


def test_double_pendulum_joint_reactions(pendulums):
    g, sg, am, sa = pendulums
    for j, body in (("j1", "a"), ("j2", "b")):
        Fg, Mg = sg.joint_reaction(j)
        Fa, Ma = sa.reaction(j, body)
        np.testing.assert_allclose(Fg, Fa, atol=1e-7)
        np.testing.assert_allclose(np.ravel(Mg), np.ravel(Ma), atol=1e-7)
        assert np.abs(Fg).max() > 1.0    # the pins carry the weight: a real check


def test_energy_is_conserved(pendulums):
    g, sg = pendulums[:2]
    dyn = g.free().system.dynamics
    E = sg.eval(sp.Add(*dyn.kinetic.values()) + dyn.potential)
    assert np.ptp(E) < 1e-8


def test_slider_on_gen_translate_with_spring_closed_form():
    """A mass on an inclined GenTranslate2 slide, held by a spring along the slide:
    s(t) = s_eq + (s0 - s_eq) cos(w t) + v0/w sin(w t), w^2 = k/m, s_eq = -m g sin(a)/k."""
    ang, k, mass, s0, v0 = np.radians(30), 40.0, 2.0, 0.25, -0.3
    u = (np.cos(ang), np.sin(ang))
    m = ms.Model2D()
    cart = m.add_body("cart", points={"o": (0, 0)}, mass=mass, inertia=0.05, centroid=(0.1, 0.05))
    m.add(ms.GenTranslate2(cart.axis("o"), m.ground.axis((0, 0), u), ("s", s0)), name="slide")
    m.add_load(ms.Spring(cart.point("o"), m.ground.point((-u[0], -u[1])), stiffness=k,
                         free_length=1.0))
    m.add_load(ms.Gravity((0, -1), G))
    assert m.compile().layout.q_names == ("s",)
    t = np.linspace(0, 2, 9)
    sol = m.free().simulate(t, initial_condition={"s": s0, "s_d": v0}, rtol=1e-12, atol=1e-12)
    w = np.sqrt(k / mass)
    s_eq = -mass * G * np.sin(ang) / k
    exact = s_eq + (s0 - s_eq) * np.cos(w * t) + v0 / w * np.sin(w * t)
    np.testing.assert_allclose(sol["s"], exact, atol=1e-9)
    # the slave turns with the slide's direction (its axis, local x, is parallel to it)
    np.testing.assert_allclose(np.ravel(sol.eval(cart.q[2])), ang, atol=1e-14)
    np.testing.assert_allclose(sol.location(cart.point("o")), np.outer(sol["s"], u), atol=1e-12)
    # static equilibrium in the generalized coordinate
    eq = m.free(solution="static").solve()
    assert abs(float(np.ravel(eq["s"])[0]) - s_eq) < 1e-10


def _four_bar(gen_rocker: bool):
    """Crank a and coupler b on a Gen chain from ground; rocker c (Gen or absolute) closed
    on the coupler's tip by a Revolute2; the crank angle driven."""
    a_, b_, c_, d_ = 1.0, 3.0, 2.5, 3.2
    m = ms.Model2D()
    crank = m.add_body("crank", points={"o": (0, 0), "e": (a_, 0)})
    coupler = m.add_body("coupler", points={"o": (0, 0), "e": (b_, 0)})
    rocker = m.add_body("rocker", points={"o": (0, 0), "e": (c_, 0)}, guess=((d_, 0), 1.8))
    m.add(ms.GenRevolute2(crank.axis("o"), m.ground.axis((0, 0)), ("th", 0.5)), name="j1")
    m.add(ms.GenRevolute2(coupler.axis("o"), crank.axis("e"), ("phi", 0.5)), name="j2")
    if gen_rocker:
        m.add(ms.GenRevolute2(rocker.axis("o"), m.ground.axis((d_, 0)), ("psi", 1.8)), name="j4")
    else:
        m.add(ms.Revolute2(rocker.point("o"), m.ground.point((d_, 0))), name="j4")
    m.add(ms.Revolute2(coupler.point("e"), rocker.point("e")), name="close")
    m.add(ms.Constraint(sp.Symbol("th") - 0.5 - 2 * ms.T), name="drive")
    return m, (a_, b_, c_, d_)


@pytest.mark.parametrize("gen_rocker", [True, False])
def test_four_bar_closed_on_gen_chain_freudenstein(gen_rocker):
    m, (a_, b_, c_, d_) = _four_bar(gen_rocker)
    assert int(m.dof()) == 0
    t = np.linspace(0, 1, 6)
    sol = m.solve(t)
    th = np.ravel(sol["th"])
    psi = np.ravel(sol.eval(m.body("rocker").q[2]))
    K1, K2, K3 = d_ / a_, d_ / c_, (a_**2 - b_**2 + c_**2 + d_**2) / (2 * a_ * c_)
    res = K1 * np.cos(psi) - K2 * np.cos(th) + K3 - np.cos(th - psi)
    assert np.abs(res).max() < 1e-10
    np.testing.assert_allclose(th, 0.5 + 2 * t, atol=1e-12)
    # the rocker's angular velocity by finite differences of the position solution
    h = 1e-4
    p = np.ravel(m.solve([0.3 - h, 0.3 + h], solution="location").eval(m.body("rocker").q[2]))
    w = np.ravel(m.solve(0.3, solution="velocity").omega("rocker"))[0]
    assert abs(w - (p[1] - p[0]) / (2 * h)) < 1e-6 * max(1.0, abs(w))


def test_torque_on_joint_angle_inverse_dynamics_and_statics():
    """Loads on a generalized coordinate (a torque on a joint angle) and Mech 11.2's
    Reaction[cnum, sym]: the driver's reaction on the coordinate is the joint torque."""
    m = gen_pendulum()
    th1, th2 = sp.symbols("t1 t2")
    m.add(ms.Constraint(th1 - 0.3 - ms.T), name="d1")
    m.add(ms.Constraint(th2 - 0.2 + 0.5 * ms.T**2), name="d2")
    sol = m.solve([0.0, 0.4], solution="dynamic")
    y = np.array([np.ravel(sol["t1"]), np.ravel(sol["t2"]),
                  np.ravel(sol.coordinate("t1", 1)), np.ravel(sol.coordinate("t2", 1))])
    qdd = np.array([np.ravel(sol.coordinate("t1", 2)), np.ravel(sol.coordinate("t2", 2))])
    for k in range(2):
        # torques the minimal ODE needs for these accelerations: tau = M qdd + c + g
        free_qdd = np.array(minimal_rhs(0, y[:, k])[2:])
        M = _minimal_mass(y[1, k])
        tau = M @ (qdd[:, k] - free_qdd)
        np.testing.assert_allclose([np.ravel(sol.reaction("d1", th1))[k],
                                    np.ravel(sol.reaction("d2", th2))[k]], tau, atol=1e-9)
    # statics: a torque on t2 holds link b horizontal-ish; the load on the coordinate balances
    s = m.solve(0.0, solution="static")
    assert abs(float(np.ravel(s.loads(th2, "applied"))[0]
                     + np.ravel(s.loads(th2, "reaction"))[0])) < 1e-10
    with pytest.raises(ms.ModelError, match="slave of"):
        s.loads("b")
    with pytest.raises(ms.ModelError, match="not a constraint"):
        s.reaction("j1", "a")


def _minimal_mass(q2):
    d1 = C1[0]
    d2, de = np.hypot(*C2), np.arctan2(C2[1], C2[0])
    c = np.cos(q2 + de)
    return np.array([[M1 * d1**2 + J1 + M2 * (L1**2 + d2**2 + 2 * L1 * d2 * c) + J2,
                      M2 * (d2**2 + L1 * d2 * c) + J2],
                     [M2 * (d2**2 + L1 * d2 * c) + J2, M2 * d2**2 + J2]])


def test_moment_load_on_slave_and_gen_constraint():
    """A Moment on a slave body (reacted on its master) equals a Load on its joint angle;
    GenConstraint reproduces GenRevolute2 (user-defined relation)."""
    m1 = gen_pendulum()
    m1.add_load(ms.Moment("b", 3.0, reaction="a"))
    m2 = gen_pendulum()
    m2.add_load(ms.Load(sp.Symbol("t2"), 3.0))
    ic = {"t1": 0.3, "t2": 0.2, "t1_d": 0.4}
    a1 = m1.free().solve(0.0, initial_condition=ic).qdd
    a2 = m2.free().solve(0.0, initial_condition=ic).qdd
    np.testing.assert_allclose(a1, a2, atol=1e-12)
    m3 = ms.Model2D()
    a, b = _links(m3)
    m3.add(ms.GenConstraint(a.point("o"), m3.ground.point((0, 0)), "t1", ("t1", 0.3)))
    m3.add(ms.GenConstraint(b.point("o"), a.point("e"), "t2", ("t2", 0.2)))
    m3.add_load(ms.Gravity((0, -1), G))
    m3.add_load(ms.Moment("b", 3.0, reaction="a"))
    a3 = m3.free().solve(0.0, initial_condition=ic).qdd
    np.testing.assert_allclose(a1, a3, atol=1e-12)


def test_bad_input_names_the_joint():
    m = ms.Model2D()
    a = m.add_body("a", points={"e": (1, 0)})
    b = m.add_body("b")
    m.add(ms.GenRevolute2(a.axis(0), m.ground.axis((0, 0)), ("t1", 0)), name="j1")
    with pytest.raises(ms.ModelError, match="'j2'.*already the slave of constraint 'j1'"):
        m.add(ms.GenRevolute2(a.axis(0), b.axis(0), ("t9", 0)), name="j2")
    with pytest.raises(ms.ModelError, match="slave of itself"):
        ms.GenRevolute2(a.axis(0), a.axis("e"), ("t9", 0))
    m.add(ms.GenRevolute2(b.axis(0), a.axis("e"), ("t2", 0)), name="j3")
    c = m.add_body("c")
    with pytest.raises(ms.ModelError, match="'j4'.*loop"):  # a's master would be b: a loop
        m2 = ms.Model2D()
        x = m2.add_body("x")
        y = m2.add_body("y")
        m2.add(ms.GenRevolute2(x.axis(0), y.axis(0), ("u", 0)), name="j1")
        m2.add(ms.GenRevolute2(y.axis(0), x.axis(0), ("v", 0)), name="j4")
    with pytest.raises(ms.ModelError, match="'j5'.*'t2' is already a variable"):
        m.add(ms.GenRevolute2(c.axis(0), b.axis(0), ("t2", 0)), name="j5")
    other = ms.Model2D()
    stranger = other.add_body("stranger")
    with pytest.raises(ms.ModelError, match="'j6'.*'stranger' is not a body of this model"):
        m.add(ms.GenRevolute2(c.axis(0), stranger.axis(0), ("t3", 0)), name="j6")
    with pytest.raises(ms.ModelError, match="ground"):
        ms.GenRevolute2(m.ground.axis((0, 0)), a.axis(0), ("t4", 0))
    with pytest.raises(ms.ModelError, match="name"):
        m.add(ms.GenRevolute2(c.axis(0), b.axis(0), ("x4", 0)), name="j7")
    with pytest.raises(ms.GeometryError, match="entirely on one body"):
        ms.GenRevolute2(ms.Axis(c.point(0), ms.Vector(c.point(0), a.point("e"))), b.axis(0), ("t5", 0))
    m3 = ms.Model3D()
    z = m3.add_body("z")
    with pytest.raises(ms.ModelError, match="GenRevolute2.*planar"):
        m3.add(ms.GenRevolute2(z.axis(0), ((0, 0, 0), (0, 0, 1)), ("t", 0)))


def test_symbolic_outputs_on_the_model_and_rest_selection():
    """Symbolic outputs of a model with slaves are in the generalized coordinates; Mech's
    Loads[Rest] selects the model variables, the Gen coordinates among them."""
    m = gen_pendulum()
    t1, t2 = sp.symbols("t1 t2")
    tip = m.location(m.body("b").point("e"))
    assert sp.simplify(tip[0] - (sp.cos(t1) + sp.cos(t1 + t2))) == 0
    w = m.omega("b")
    assert sp.simplify(w - (m.velocity_symbols()[t1] + m.velocity_symbols()[t2])) == 0
    m.add(ms.Constraint(t1 - 0.3 - ms.T), name="d1")
    m.add(ms.Constraint(t2 - 0.2), name="d2")
    s = m.solve([0.0, 0.1], solution="dynamic")
    rest = np.asarray(s.loads(ms.Rest))
    assert rest.shape == (2, 2)
    np.testing.assert_allclose(rest[:, 1], np.ravel(s.loads(t2)), atol=1e-14)
    # the gravity moment about each joint, by hand (applied load on the joint angles)
    q1, q2 = np.ravel(s["t1"]), np.ravel(s["t2"])
    d2, de = np.hypot(*C2), np.arctan2(C2[1], C2[0])
    g2 = -M2 * G * d2 * np.cos(q1 + q2 + de)
    np.testing.assert_allclose(rest[:, 1], g2, atol=1e-12)


def test_slave_angular_velocity_initial_condition_refused():
    g = gen_pendulum()
    with pytest.raises(ms.ModelError, match="slave of constraint 'j2'.*t2_d"):
        g.free().solve(0.0, initial_condition={("omega", "b"): 1.0})
