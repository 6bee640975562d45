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
