"""Spatial mechanisms against independent results: the planar slider-crank and four-bar,
the closed form of a Cardan joint, and the loop equation of a spatial RSSR four-bar."""

import numpy as np
import pytest

import mechsys as ms
from mechsys import T, models


def wrap(x):
    return np.angle(np.exp(1j * np.asarray(x)))


# -- the 3D slider-crank reproduces the planar one -------------------------------------------


@pytest.mark.parametrize("offset", [0.0, 0.7])
def test_slider_crank_3d_reproduces_planar(offset):
    t = np.linspace(0, 1, 41)
    m3 = models.slider_crank_3d(offset=offset)
    m2 = models.slider_crank(offset=offset)
    assert int(m3.dof()) == 0
    s3, s2 = m3.solve(t), m2.solve(t)
    for body, point in (("piston", 0), ("rod", "b"), ("rod", (3.0, 0.0)), ("crank", "pin")):
        p2 = m2.body(body).point(point)
        p3 = m3.body(body).point(point if not isinstance(point, tuple) else (*point, 0.0))
        for f, tol in ((s2.location, 1e-10), (s2.velocity, 1e-9), (s2.acceleration, 1e-8)):
            a2 = f(p2)
            a3 = getattr(s3, f.__name__)(p3)
            np.testing.assert_allclose(a3[:, :2], a2, atol=tol * (1 + np.abs(a2).max()))
            np.testing.assert_allclose(a3[:, 2], 0.0, atol=tol)
    # angular velocity and acceleration: along +Z with the planar values
    for body in ("crank", "rod", "piston"):
        np.testing.assert_allclose(s3.omega(body)[:, 2], s2.omega(body), atol=1e-9)
        np.testing.assert_allclose(s3.omega(body)[:, :2], 0.0, atol=1e-9)
        np.testing.assert_allclose(s3.alpha(body)[:, 2], s2.alpha(body), atol=1e-7)


def test_slider_crank_3d_out_of_plane_matches_closed_form():
    # slider line raised by h: the rod's projection on the XY plane has length sqrt(L^2-h^2)
    r, L, e, h, w = 2.0, 6.0, 0.5, 1.5, 2 * np.pi
    m = models.slider_crank_3d(crank=r, rod=L, offset=e, height=h, speed=w)
    t = np.linspace(0, 1, 37)
    sol = m.solve(t)
    th = w * t
    s = e - r * np.sin(th)
    root = np.sqrt(L**2 - h**2 - s**2)
    x = r * np.cos(th) + root
    v = -r * np.sin(th) * w - s * (-r * np.cos(th) * w) / root
    p = m.body("piston").point(0)
    np.testing.assert_allclose(sol.location(p)[:, 0], x, atol=1e-9)
    np.testing.assert_allclose(sol.location(p)[:, 1:], np.tile([e, h], (len(t), 1)), atol=1e-9)
    np.testing.assert_allclose(sol.velocity(p)[:, 0], v, atol=1e-8)
    # the rod keeps its length and its ends stay on the crank pin and the piston
    d = sol.location(m.body("rod").point("b")) - sol.location(m.body("crank").point("pin"))
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), L, atol=1e-10)


# -- the planar subset of a 3D model agrees with the 2D model --------------------------------


def four_bar_3d(ground=4.0, crank=1.0, coupler=4.0, rocker=3.0, speed=1.0, branch=1):
    """The planar four-bar of ``models.four_bar`` built with 3D joints (hinges along Z)."""
    m2 = models.four_bar(ground, crank, coupler, rocker, speed, branch)
    phi = float(m2.guess()[5])
    m = ms.Model3D()
    g, z = m.ground, (0, 0, 1)
    cr = m.add_body("crank", points={"tip": (crank, 0, 0)})
    ro = m.add_body("rocker", points={"tip": (rocker, 0, 0)},
                    guess=((ground, 0, 0), (phi, (0, 0, 1))))
    m.add(ms.Revolute5(cr.axis(0, z), g.axis((0, 0, 0), z)))
    m.add(ms.Revolute5(ro.axis(0, z), g.axis((ground, 0, 0), z)))
    m.add(ms.RelativeDistance1(cr.point("tip"), ro.point("tip"), coupler))
    m.add(ms.RotationLock1(cr.axis(0, z), g.axis((0, 0, 0), z), speed * T))
    return m, m2


@pytest.mark.parametrize("branch", [1, -1])
def test_planar_four_bar_built_in_3d_agrees_with_2d(branch):
    m3, m2 = four_bar_3d(branch=branch)
    t = np.linspace(0, 2 * np.pi, 49)
    s3, s2 = m3.solve(t), m2.solve(t)
    tip3, tip2 = m3.body("rocker").point("tip"), m2.body("rocker").point("tip")
    np.testing.assert_allclose(s3.location(tip3)[:, :2], s2.location(tip2), atol=1e-10)
    np.testing.assert_allclose(s3.velocity(tip3)[:, :2], s2.velocity(tip2), atol=1e-9)
    np.testing.assert_allclose(s3.acceleration(tip3)[:, :2], s2.acceleration(tip2), atol=1e-8)
    np.testing.assert_allclose(s3.omega("rocker")[:, 2], s2.omega("rocker"), atol=1e-9)
    np.testing.assert_allclose(s3.alpha("rocker")[:, 2], s2.alpha("rocker"), atol=1e-8)
    # the rocker's rotation about Z, from the Euler parameters, is the planar angle
    e = np.column_stack([s3[f"rocker.e{k}"] for k in range(4)])
    signed = []
    for ek in e:
        ang, axis = ms.rotation(ek)
        np.testing.assert_allclose(abs(axis[2]), 1.0, atol=1e-9)
        signed.append(ang * np.sign(axis[2]))
    np.testing.assert_allclose(wrap(np.array(signed) - s2["rocker.th"]), 0, atol=1e-9)


# -- Cardan (Hooke) joint against its closed form; the constant-velocity joint ---------------


@pytest.mark.parametrize("bend", [0.3, 0.6])
def test_cardan_joint_speed_ratio_closed_form(bend):
    """w2/w1 = cos b / (1 - sin^2 b cos^2 th1), th1 the input yoke pin's angle from the
    plane of the two shafts (the convention of the classical derivation, where the ratio
    is largest, 1/cos b, with the input pin in that plane)."""
    w1 = 2 * np.pi
    m = models.cardan_joint(bend=bend, speed=w1)
    assert int(m.dof()) == 0
    t = np.linspace(0, 1, 61)
    sol = m.solve(t)
    a2 = np.array([np.cos(bend), np.sin(bend), 0.0])
    th1 = w1 * t
    den = 1 - np.sin(bend) ** 2 * np.cos(th1) ** 2
    ratio = np.cos(bend) / den
    np.testing.assert_allclose(sol.omega("output") @ a2 / w1, ratio, atol=1e-10)
    # no wobble: the output turns about its own axis only
    np.testing.assert_allclose(np.cross(sol.omega("output"), a2), 0, atol=1e-10)
    # angular acceleration: w1^2 d(ratio)/d(th1)
    dratio = -np.cos(bend) * 2 * np.sin(bend) ** 2 * np.cos(th1) * np.sin(th1) / den**2
    np.testing.assert_allclose(sol.alpha("output") @ a2, w1**2 * dratio, atol=1e-8)
    # the extremes: 1/cos b with the pin in the shafts' plane, cos b a quarter turn later
    r = sol.omega("output") @ a2 / w1
    assert np.isclose(r.max(), 1 / np.cos(bend)) and np.isclose(r.min(), np.cos(bend))
    # output angle: tan(th2) = tan(th1) / cos(b), th2 the output pin's angle from Z
    pin2 = sol.direction(m.body("output").vector((0, 0, 1)))
    th2 = ms.projected_angle(pin2, np.array([0, 0, 1.0]), a2)
    expect = np.arctan2(np.sin(th1), np.cos(th1) * np.cos(bend))
    np.testing.assert_allclose(wrap(th2 - expect), 0, atol=1e-10)


@pytest.mark.parametrize("bend", [0.0, 0.4, 0.9])
def test_constant_velocity_joint_ratio_is_one(bend):
    w1 = 2 * np.pi
    m = models.cardan_joint(bend=bend, speed=w1, joint="cv")
    t = np.linspace(0, 1, 41)
    sol = m.solve(t)
    a2 = np.array([np.cos(bend), np.sin(bend), 0.0])
    np.testing.assert_allclose(sol.omega("output") @ a2, w1, atol=1e-9)
    np.testing.assert_allclose(sol.alpha("output") @ a2, 0, atol=1e-7)


# -- spatial RSSR four-bar against its loop equation ------------------------------------------

C1, A_AX, G_A = np.zeros(3), np.array([0, 0, 1.0]), np.array([1.0, 0, 0])
C2 = np.array([4.0, 0.5, 1.0])
B_AX = np.array([0.3, 1.0, 0.4]) / np.linalg.norm([0.3, 1.0, 0.4])
G_B = np.cross(B_AX, [0, 0, 1.0]) / np.linalg.norm(np.cross(B_AX, [0, 0, 1.0]))
R1, R2, L = 1.0, 3.0, 4.6


def rssr_rocker_angle(th, branch=1):
    """Rocker angle phi (from G_B about B_AX) solving |P(th) - Q(phi)| = L in closed form:
    A cos(phi) + B sin(phi) = C."""
    P = C1 + R1 * (np.cos(th)[..., None] * G_A + np.sin(th)[..., None] * np.cross(A_AX, G_A))
    D = P - C2
    A = 2 * R2 * D @ G_B
    B = 2 * R2 * D @ np.cross(B_AX, G_B)
    C = (D * D).sum(-1) + R2**2 - L**2
    return np.arctan2(B, A) + branch * np.arccos(C / np.hypot(A, B))


def rssr_model(branch=1):
    m = ms.Model3D()
    g, z = m.ground, (0, 0, 1)
    phi0 = float(rssr_rocker_angle(np.array(0.0), branch))
    x0 = np.cos(phi0) * G_B + np.sin(phi0) * np.cross(B_AX, G_B)
    R = np.column_stack([x0, np.cross(B_AX, x0), B_AX])      # rocker: local z along B_AX
    cr = m.add_body("crank", points={"tip": (R1, 0, 0)})
    ro = m.add_body("rocker", points={"tip": (R2, 0, 0)}, guess=(tuple(C2), R))
    m.add(ms.Revolute5(cr.axis(0, z), g.axis(tuple(C1), tuple(A_AX))), name="crank hinge")
    m.add(ms.Revolute5(ro.axis(0, z), g.axis(tuple(C2), tuple(B_AX))), name="rocker hinge")
    m.add(ms.RelativeDistance1(cr.point("tip"), ro.point("tip"), L), name="coupler")
    m.add(ms.RotationLock1(cr.axis(0, z, (1, 0, 0)), g.axis(tuple(C1), tuple(A_AX), tuple(G_A)),
                           T), name="drive")
    return m


@pytest.mark.parametrize("branch", [1, -1])
def test_rssr_against_loop_equation(branch):
    m = rssr_model(branch)
    assert int(m.dof()) == 0
    t = np.linspace(0, 2 * np.pi, 73)
    sol = m.solve(t)
    tip = sol.location(m.body("rocker").point("tip"))
    phi = ms.projected_angle(tip - C2, G_B, B_AX)
    np.testing.assert_allclose(wrap(phi - rssr_rocker_angle(t, branch)), 0, atol=1e-10)
    # rates by 5-point central differences of the closed form (theta = t)
    h = 1e-3
    f = [rssr_rocker_angle(t + k * h, branch) for k in (-2, -1, 0, 1, 2)]
    f = np.unwrap(np.array(f), axis=0)
    d1 = (f[0] - 8 * f[1] + 8 * f[3] - f[4]) / (12 * h)
    d2 = (-f[0] + 16 * f[1] - 30 * f[2] + 16 * f[3] - f[4]) / (12 * h**2)
    np.testing.assert_allclose(sol.omega("rocker") @ B_AX, d1, atol=1e-8)
    np.testing.assert_allclose(sol.alpha("rocker") @ B_AX, d2, atol=1e-5)
    # the rocker turns about its hinge only
    np.testing.assert_allclose(np.cross(sol.omega("rocker"), B_AX), 0, atol=1e-10)
