"""Velocity representations (Euler-parameter rates, angular velocities global/local)."""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T


def tumbling(**kw):
    """A body whose orientation is prescribed: rotation a(t) about X, then b(t) about its Z."""
    m = ms.Model3D(**kw)
    b = m.add_body("b", guess=((0, 0, 0), (1, 0, 0, 0)))
    x, y, z, e0, e1, e2, e3 = b.q
    a, c = 0.8 * T, 1.3 * T + 0.2
    # Euler parameters of Rx(a) Rz(c): (cos a/2, sin a/2, 0, 0) * (cos c/2, 0, 0, sin c/2)
    E = [sp.cos(a / 2) * sp.cos(c / 2), sp.sin(a / 2) * sp.cos(c / 2),
         -sp.sin(a / 2) * sp.sin(c / 2), sp.cos(a / 2) * sp.sin(c / 2)]
    m.add(ms.Constraint([x - sp.sin(T), y, z - T**2]), name="path")
    m.add(ms.Constraint([e1 - E[1], e2 - E[2], e3 - E[3]]), name="orientation")
    return m


def test_angular_views_match_the_closed_form():
    m = tumbling()
    t = np.linspace(0, 1.5, 7)
    sol = m.solve(t)
    w_global = sol.velocities("b", "angular", "global")
    w_local = sol.velocities("b", "angular", "local")
    a_d, c_d = 0.8, 1.3
    for k, tk in enumerate(t):
        a = 0.8 * tk
        Rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
        # omega = a' X + c' (Rx Z), both global
        expected = a_d * np.array([1, 0, 0]) + c_d * Rx @ np.array([0, 0, 1])
        np.testing.assert_allclose(w_global[k, 3:], expected, atol=1e-10)
        A = sol.eval(m.body("b").A)[k]
        np.testing.assert_allclose(w_local[k, 3:], A.T @ expected, atol=1e-10)
    np.testing.assert_allclose(w_global[:, :3], np.c_[np.cos(t), 0 * t, 2 * t], atol=1e-12)
    # Euler view: the coordinate rates themselves
    np.testing.assert_allclose(sol.velocities("b", "euler"), sol.qd, atol=0)
    # angular accelerations: constant rates, so alpha = a' X x c' (Rx Z)
    acc = sol.accelerations("b", "angular")
    for k, tk in enumerate(t):
        a = 0.8 * tk
        Rz_axis = np.array([0, -np.sin(a), np.cos(a)])
        np.testing.assert_allclose(acc[k, 3:], np.cross(a_d * np.array([1, 0, 0]), c_d * Rz_axis),
                                   atol=1e-9)


def test_model_defaults_choose_the_representation():
    m = tumbling(velocity="angular", coordinates="local")
    sol = m.solve([0.3, 0.6])
    np.testing.assert_allclose(sol.omega("b"), sol.omega("b", coordinates="local"))
    np.testing.assert_allclose(sol.velocities("b")[:, 3:], sol.omega("b", coordinates="local"))
    assert sol.velocities("b").shape == (2, 6)


def test_bad_representation_names():
    import pytest

    with pytest.raises(ms.ModelError, match="velocity must be"):
        ms.Model3D(velocity="quaternion")
    with pytest.raises(ms.ModelError, match="coordinates must be"):
        ms.Model3D(coordinates="body")


def test_model_velocity_method_not_shadowed_by_the_representation_option():
    """Model3D used to store its ``velocity=`` option as ``self.velocity``, hiding the output
    method: ``m.velocity(point)`` raised "'str' object is not callable" on every 3D model, and
    ``velocities()`` on a 2D model picked up the method as its representation."""
    m = tumbling(velocity="angular")
    b = m.body("b")
    v = m.velocity(b.point((1, 0, 0)))            # symbolic velocity of a body point
    assert v.shape == (3, 1)
    sol = m.solve(0.4)
    np.testing.assert_allclose(sol.velocity(b.point(0)), [np.cos(0.4), 0, 0.8], atol=1e-12)
    # the option still sets the default representation of the views: angular here (6 rows)
    assert np.ravel(sol.velocities("b")).size == 6
    m2 = ms.Model2D()
    arm = m2.add_body("arm", points={"tip": (1, 0)}, guess=((0, 0), 0.1))
    m2.add(ms.Revolute2(m2.ground.point((0, 0)), arm.point(0)))
    m2.add(ms.RotationLock1(arm, 2 * T))
    s2 = m2.solve(0.5)
    np.testing.assert_allclose(np.ravel(s2.velocities("arm")), [0, 0, 2], atol=1e-12)
