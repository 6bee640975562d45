"""Nonholonomic paths: the caster and the knife edge against closed forms; errors."""

import numpy as np
import pytest

import mechsys as ms
from conftest import load_example as load
from mechsys import T

caster = load("caster")
knife = load("knife_edge")


@pytest.mark.parametrize("method,kw,tol", [("dop853", {"rtol": 1e-11, "atol": 1e-12}, 1e-8),
                                           ("adams", {"max_error": 1e-8}, 1e-5)])
def test_caster_follows_its_minimal_ode(method, kw, tol):
    m, path = caster.build()
    t = np.linspace(0, 3.0, 31)
    sol = path.simulate(t, method=method, **kw)
    np.testing.assert_allclose(sol["caster.th"], caster.closed_form(t), atol=tol)
    assert sol.extra["drift"] < 1e-10


def test_caster_wheel_rolls_without_side_slip():
    m, path = caster.build()
    t = np.linspace(0, 3.0, 3001)
    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    wheel = sol.location(m.body("caster").point("wheel"))
    v = np.gradient(wheel, t, axis=0, edge_order=2)          # velocity of the trajectory itself
    axle = sol.eval(m.body("caster").A[:, 1])
    side = np.einsum("ij,ij->i", v, axle)
    assert np.abs(side[2:-2]).max() < 1e-5 * np.abs(v).max()
    # the pivot moves as driven, the caster settles behind it
    pivot = sol.location(m.body("caster").point(0))
    np.testing.assert_allclose(pivot[:, 0], -caster.V * t, atol=1e-10)
    assert abs(sol["caster.th"][-1]) < 0.01


def test_knife_edge_runs_on_the_circle():
    m, path = knife.build()
    t = np.linspace(0, 2 * np.pi / knife.RATE, 41)
    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    p = sol.location(m.body("sled").point("blade"))
    R = knife.SPEED / knife.RATE
    ref = np.c_[R * np.sin(knife.RATE * t), R * (1 - np.cos(knife.RATE * t))]
    np.testing.assert_allclose(p, ref, atol=1e-8)
    speed = np.linalg.norm(sol.velocity(m.body("sled").point("blade")), axis=1)
    np.testing.assert_allclose(speed, knife.SPEED, rtol=1e-10)
    # centripetal acceleration of uniform circular motion
    acc = np.linalg.norm(sol.acceleration(m.body("sled").point("blade")), axis=1)
    np.testing.assert_allclose(acc, knife.SPEED**2 / R, rtol=1e-8)


def test_replacing_an_unknown_constraint_is_an_error():
    m, _ = caster.build()
    rolling = ms.Orthogonal1(m.velocity(m.body("caster").point("wheel")),
                             m.body("caster").vector((0, 1)))
    with pytest.raises(ms.UnknownConstraintError, match="no constraint named 'nope'"):
        m.path(replace={"nope": rolling})


def test_velocity_constraint_making_the_system_singular():
    m, _ = caster.build()
    c = m.body("caster")
    # a velocity constraint on the pivot repeats what the holonomic pivot constraint fixes
    bad = ms.Orthogonal1(m.velocity(c.point(0)), (0, 1))
    path = m.path(replace={"dummy": bad})
    with pytest.raises(ms.SingularJacobianError) as exc:
        path.simulate((0.0, 1.0))
    msg = str(exc.value)
    assert "singular" in msg and "velocity constraint replacing 'dummy'" in msg and "pivot" in msg


def test_wrong_number_of_velocity_equations():
    m = ms.Model2D()
    b = m.add_body("b")
    m.add(ms.RelativeX1(b.point(0), T), name="x")
    m.add(ms.RelativeY1(b.point(0), 0.0), name="y")
    m.add(ms.RotationLock1(b, 0.0), name="dummy")
    m.solve(0.0)
    v = m.velocity(b.point(0))
    with pytest.raises(ms.ModelError, match="velocity equations"):
        m.path(replace={"dummy": ms.Constraint([v[0] - 1, v[1]])})


def test_set_parameters_after_path_changes_the_motion():
    # path systems used to freeze the parameters at m.path()
    m = ms.Model2D()
    c = m.add_body("caster", points={"wheel": (caster.TRAIL, 0.0)}, guess=((0, 0), caster.TH0))
    v = m.parameter("v", 1.0)
    m.add(ms.Revolute2(c.point(0), m.ground.point((-v * T, 0))), name="pivot")
    m.add(ms.RotationLock1(c, caster.TH0), name="dummy")
    m.solve(0.0)
    path = m.path(replace={"dummy": ms.Orthogonal1(m.velocity(c.point("wheel")),
                                                   c.vector((0, 1)))})
    t = np.linspace(0, 1.5, 7)

    def closed(speed):
        return 2 * np.arctan(np.tan(caster.TH0 / 2) * np.exp(-speed * t / caster.TRAIL))

    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(sol["caster.th"], closed(1.0), atol=1e-8)
    m.set_parameters(v=2.0)
    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(sol["caster.th"], closed(2.0), atol=1e-8)
    np.testing.assert_allclose(sol.location(c.point(0))[:, 0], -2.0 * t, atol=1e-10)
    sol = path.simulate(t, initial_condition={"v": 0.5}, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(sol["caster.th"], closed(0.5), atol=1e-8)
    from mechsys.solvers import _jit_runtime

    if _jit_runtime.available() and _jit_runtime.mode() != "off":  # the parameters reached the compiled loop
        assert sol.extra["compiled_steps"] == sol.extra["steps"] > 0
    np.testing.assert_allclose(path.velocities(0.0, sol.q[0]), sol.qd[0] * 4, atol=1e-12)
