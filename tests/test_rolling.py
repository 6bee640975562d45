"""Rolling constraints (RollingDisk2, RollingSphere2, RollingCircle1) in path systems, against
closed forms; their velocity form ``A qd + b``; bad input. (Residual, Jacobians and the
acceleration rows against finite differences: the conformance suite.)"""

from __future__ import annotations

import importlib.util
import pathlib

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture
def python_stepper(monkeypatch):
    # the compiled path stepper gives the same numbers (decision 0027); the Python one spares
    # these short runs the first Numba compile
    monkeypatch.setenv("MECHSYS_JIT", "0")


def _example(name):
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_disk_at_constant_lean_traces_its_circle(python_stepper):
    """The contact of a disk at constant lean, spin and turning rate runs on a circle of
    radius R SPIN / TURN; the slip velocity stays zero; the contact stays on the plane."""
    ex = _example("rolling_disk")
    m, roll, path = ex.build()
    t = np.linspace(0, 2 * np.pi / ex.TURN, 9)
    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    c = sol.location(roll.contact_point())
    assert np.abs(c - ex.closed_form(t, c[0])).max() < 1e-8
    assert np.abs(sol.eval(roll.slip_velocity())).max() < 1e-10
    # the centre is R above the contact along the disk's plane: height R cos(lean)
    centre = sol.location(m.body("disk").point(0))
    np.testing.assert_allclose(centre[:, 2], ex.R * np.cos(ex.LEAN), atol=1e-10)
    np.testing.assert_allclose(np.linalg.norm(centre - c, axis=1), ex.R, atol=1e-10)
    # A qd + b = 0 at every output (b = 0 for rolling on a fixed plane)
    A, b = roll.velocity_form(m)
    assert A.shape == (2, 7) and b == sp.zeros(2, 1)
    rates = m.velocity_symbols()
    f = sp.lambdify([*rates, *rates.values()], A)
    for q, qd in zip(sol.q, sol.qd):
        assert np.abs(np.array(f(*q, *qd), dtype=float) @ qd).max() < 1e-10


def test_sphere_rolls_along_a_straight_line(python_stepper):
    """A ball spun at a constant rate W about a fixed horizontal axis k rolls with its centre
    moving at W rad (k x n): along a straight line at constant height."""
    rad, W, k = 0.2, 3.0, np.array([np.cos(0.4), np.sin(0.4), 0.0])
    m = ms.Model3D()
    ball = m.add_body("ball", guess=((0, 0, rad), (1, 0, 0, 0)))
    roll = ms.RollingSphere2(m.ground.axis((0, 0, 0), (0, 0, 1)), ball.point(0), rad)
    m.add(roll.holonomic(), name="touch")
    m.add(ms.RotationLock3(ball, (W * T, tuple(k))), name="spin")
    m.add(ms.RelativeX1(ball.point(0), 0.0), name="dx")
    m.add(ms.RelativeY1(ball.point(0), 0.0), name="dy")
    m.solve(0.0)
    path = m.path(replace={("dx", "dy"): roll})
    t = np.linspace(0, 2.0, 5)
    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    v = W * rad * np.cross(k, [0, 0, 1])
    np.testing.assert_allclose(sol.location(ball.point(0)), np.c_[t] * v + [0, 0, rad],
                               atol=1e-9)
    np.testing.assert_allclose(sol.location(roll.contact_point())[:, 2], 0.0, atol=1e-12)
    assert np.abs(sol.eval(roll.slip_velocity())).max() < 1e-10


def test_circle_on_line_matches_rack_and_pinion(python_stepper):
    """Planar rolling integrates: the path of RollingCircle1 (a velocity constraint) and the
    kinematics of RackAndPinion2 (its integrated position form) give the same motion, and
    both the closed form x = x0 - rad (theta - theta0)."""
    rad = 0.5
    m = ms.Model2D()
    wheel = m.add_body("wheel", guess=((0.2, rad), 0.0))
    line = m.ground.axis((0, 0), (1, 0))
    roll = ms.RollingCircle1(wheel.point(0), rad, line)
    m.add(roll.holonomic(), name="touch")
    m.add(ms.RotationLock1(wheel, 0.3 - 2 * T + 0.5 * T**2), name="turn")
    m.add(ms.RelativeX1(wheel.point(0), 0.2), name="dummy")
    m.solve(0.0)
    t = np.linspace(0, 3, 7)
    sol = m.path(replace={"dummy": roll}).simulate(t, rtol=1e-11, atol=1e-12)
    x = sol.location(wheel.point(0))[:, 0]
    np.testing.assert_allclose(x, 0.2 - rad * (-2 * t + 0.5 * t**2), atol=1e-9)
    m2 = ms.Model2D()
    w2 = m2.add_body("wheel", guess=((0.2, rad), 0.3))
    m2.add(ms.RackAndPinion2(w2.point(0), rad, m2.ground.axis((0, 0), (1, 0)), 0.2 + rad * 0.3))
    m2.add(ms.RotationLock1(w2, 0.3 - 2 * T + 0.5 * T**2))
    np.testing.assert_allclose(m2.solve(t).location(w2.point(0))[:, 0], x, atol=1e-9)


def test_velocity_form_and_its_refusals():
    m = ms.Model2D()
    wheel = m.add_body("wheel")
    roll = ms.RollingCircle1(wheel.point((0.1, 0)), 0.5, m.ground.axis((0, 0), (1, 0)))
    A, b = ms.linear_velocity_form(roll, m)
    x_d, y_d, th_d = m.velocity_symbols().values()
    assert sp.simplify((A * sp.Matrix([x_d, y_d, th_d]))[0] - roll.equations(m.space)[0]) == 0
    assert b == sp.zeros(1, 1)
    bent = ms.Constraint([x_d**2 - 1])
    with pytest.raises(ms.ModelError, match="not linear in the velocities"):
        ms.linear_velocity_form(bent, m)
    m.add(roll)                    # a velocity constraint in the position equations: refused
    with pytest.raises(ms.ModelError, match="velocity constraint"):
        m.solve(0.0)


@pytest.mark.parametrize("rad", [0, -0.3, float("nan"), float("inf")])
def test_bad_radius_is_refused(rad):
    m = ms.Model3D()
    b = m.add_body("b")
    plane = m.ground.axis((0, 0, 0), (0, 0, 1))
    with pytest.raises(ms.GeometryError, match="RollingDisk2 rad"):
        ms.RollingDisk2(plane, b.axis(0, (0, 1, 0)), rad)
    with pytest.raises(ms.GeometryError, match="RollingSphere2 rad"):
        ms.RollingSphere2(plane, b.point(0), rad)
    m2 = ms.Model2D()
    w = m2.add_body("w")
    with pytest.raises(ms.GeometryError, match="RollingCircle1 rad"):
        ms.RollingCircle1(w.point(0), rad, m2.ground.axis((0, 0), (1, 0)))


def test_bad_geometry_is_refused():
    m = ms.Model3D()
    b = m.add_body("b")
    plane = m.ground.axis((0, 0, 0), (0, 0, 1))
    zero = ms.Axis(ms.Point(None, (0, 0, 0)), ms.Vector(None, (1, 0, 0)))
    zero.dir = ms.Vector(None, (0, 0, 0))            # (an Axis refuses a zero direction itself)
    with pytest.raises(ms.GeometryError, match="plane normal"):
        ms.RollingDisk2(zero, b.axis(0, (0, 1, 0)), 0.3)
    zero_b = b.axis(0, (0, 1, 0))
    zero_b.dir = ms.Vector(b, (0, 0, 0))
    with pytest.raises(ms.GeometryError, match="disk axis"):
        ms.RollingDisk2(plane, zero_b, 0.3)
    with pytest.raises(ms.GeometryError, match="zero-length"):
        ms.RollingSphere2(m.ground.axis((0, 0, 0), (0, 0, 0)), b.point(0), 0.3)
    with pytest.raises(ms.GeometryError, match="depends on time"):
        ms.RollingDisk2(plane, b.axis(0, (0, 1, 0)), 0.3 + T)
    with pytest.raises(ms.GeometryError, match="rolling body"):
        ms.RollingDisk2(plane, m.ground.axis((0, 0, 1), (0, 1, 0)), 0.3)
    with pytest.raises(ms.GeometryError, match="rolling body"):
        ms.RollingSphere2(plane, (0, 0, 1), 0.3)


def test_path_refuses_a_velocity_constraint_given_twice():
    m = ms.Model2D()
    w = m.add_body("w", guess=((0, 0.5), 0.0))
    roll = ms.RollingCircle1(w.point(0), 0.5, m.ground.axis((0, 0), (1, 0)))
    m.add(roll.holonomic(), name="touch")
    m.add(ms.RotationLock1(w, T), name="turn")
    m.add(ms.RelativeX1(w.point(0), 0.0), name="d1")
    with pytest.raises(ms.ModelError, match="replaces two entries"):
        m.path(replace={"d1": roll, "turn": roll})


def test_radius_with_units_in_a_model_in_millimetres(python_stepper):
    """A radius of 500 mm in a model in millimetres: the same motion as 500 in numbers."""
    pint = pytest.importorskip("pint")
    Q = pint.get_application_registry().Quantity
    xs = []
    for rad in (Q(0.5, "m"), 500.0):
        m = ms.Model2D()
        m.set_units(length="mm", mass="kg", time="s")
        wheel = m.add_body("wheel", guess=((0.0, 500.0), 0.0))
        roll = ms.RollingCircle1(wheel.point(0), rad, m.ground.axis((0, 0), (1, 0)))
        m.add(roll.holonomic(), name="touch")
        m.add(ms.RotationLock1(wheel, -T), name="turn")
        m.add(ms.RelativeX1(wheel.point(0), 0.0), name="dummy")
        m.solve(0.0)
        sol = m.path(replace={"dummy": roll}).simulate(np.array([0.0, 1.0]), rtol=1e-10,
                                                       atol=1e-12)
        xs.append(sol.location(wheel.point(0))[-1, 0])
    np.testing.assert_allclose(xs, [500.0, 500.0], rtol=1e-9)
    with pytest.raises(ms.GeometryError, match="RollingCircle1 rad"):
        ms.RollingCircle1(wheel.point(0), Q(-1.0, "mm"), m.ground.axis((0, 0), (1, 0)))
