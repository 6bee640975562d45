"""Spatial inverse dynamics against the Newton-Euler equations of a rotor on a fixed axis."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T

W0, W1 = 3.0, 0.7        # spin angle th(t) = W0 t + W1 t^2
J_LOCAL = (0.5, 0.8, 1.1, 0.12, -0.07, 0.05)   # Ixx, Iyy, Izz, Ixy, Iyz, Izx (matrix entries)


def rotor_model(mass=2.0, centroid=(0.0, 0.0, 0.0)):
    m = ms.Model3D()
    b = m.add_body("rotor", mass=mass, centroid=centroid, inertia=J_LOCAL,
                   guess=((0, 0, 0), (1, 0, 0, 0)))
    x, y, z, e0, e1, e2, e3 = b.q
    th = W0 * T + W1 * T**2
    m.add(ms.Constraint([x, y, z]), name="fixed point")
    m.add(ms.Constraint([e1, e2]), name="z axis")
    m.add(ms.Constraint([e3 - sp.sin(th / 2)]), name="spin")
    m.add_load(ms.Gravity((0, 0, -1), 9.81))
    return m


def newton_euler_moment(t, centroid, mass):
    th = W0 * t + W1 * t**2
    w, a = W0 + 2 * W1 * t, 2 * W1
    c, s = np.cos(th), np.sin(th)
    A = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    xx, yy, zz, xy, yz, zx = J_LOCAL
    Jc = np.array([[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]])
    d = np.asarray(centroid, dtype=float)
    J0 = Jc + mass * (d @ d * np.eye(3) - np.outer(d, d))   # about the fixed point, body axes
    Jg = A @ J0 @ A.T
    omega, alpha = np.array([0, 0, w]), np.array([0, 0, a])
    rc = A @ d
    weight = np.array([0, 0, -9.81 * mass])
    # moment about the fixed point needed: J alpha + w x J w = M_reaction + rc x weight
    return Jg @ alpha + np.cross(omega, Jg @ omega) - np.cross(rc, weight)


@pytest.mark.parametrize("centroid", [(0.0, 0.0, 0.0), (0.2, -0.1, 0.3)])
def test_rotor_bearing_moments(centroid):
    mass = 2.0
    m = rotor_model(mass, centroid)
    t = np.linspace(0, 2, 21)
    sol = m.solve(t, solution="dynamic")
    origin = (0, 0, 0)
    total = sum(np.asarray(sol.reaction(c, "rotor", at=origin)[1]) for c in
                ("fixed point", "z axis", "spin"))
    expected = np.array([newton_euler_moment(tt, centroid, mass) for tt in t])
    np.testing.assert_allclose(total, expected, atol=1e-9)
    # the bearing force keeps the centroid on its circle: F = m a_c - weight
    F = sol.reaction("fixed point", "rotor")[0]
    ac = sol.acceleration(m.body("rotor").point(tuple(centroid)))
    np.testing.assert_allclose(F, mass * ac - np.array([0, 0, -9.81 * mass]), atol=1e-9)
    # balance on the body in generalized coordinates
    bal = (sol.loads("rotor", "applied") + sol.loads("rotor", "reaction")
           + sol.loads("rotor", "dynamic"))
    np.testing.assert_allclose(bal, 0, atol=1e-9)


def test_rotor_kinetic_energy_and_power():
    m = rotor_model()
    t = np.linspace(0.2, 1.8, 401)
    sol = m.solve(t, solution="dynamic")
    w = W0 + 2 * W1 * t
    assert np.allclose(sol.body_energy("rotor"), 0.5 * J_LOCAL[2] * w**2)
    np.testing.assert_allclose(sol.omega("rotor")[:, 2], w, atol=1e-12)
    E = sol.body_energy() + sol.potential_energy()
    P = sum(sol.power(c) for c in ("fixed point", "z axis", "spin"))
    np.testing.assert_allclose(P[3:-3], np.gradient(E, t)[3:-3], rtol=1e-4)
