"""Coulomb friction driven by joint reactions, against hand calculations."""

import numpy as np
import pytest

import mechsys as ms
from mechsys import T


def incline(alpha, mu, mass=2.0, g=9.81, v=1.0):
    m = ms.Model2D()
    blk = m.add_body("block", mass=mass, inertia=0.1, guess=((0.0, 0.0), alpha))
    ca, sa = np.cos(alpha), np.sin(alpha)
    slide = m.add(ms.Translate2(blk.axis((0, 0), (1, 0)), m.ground.axis((0, 0), (ca, sa))),
                  name="slide")
    m.add(ms.RelativeX1(blk.point(0), v * ca * T), name="push")
    m.add_load(ms.Gravity((0, -1), g))
    m.add_load(ms.JointFriction(slide, mu=mu, v_eps=1e-4))
    return m


@pytest.mark.parametrize("alpha,mu", [(0.3, 0.25), (0.6, 0.1), (0.2, 0.0)])
def test_block_pushed_up_incline(alpha, mu):
    mass, g = 2.0, 9.81
    m = incline(alpha, mu, mass, g)
    sol = m.solve(np.linspace(0.1, 1.0, 4), solution="dynamic")
    F, _ = sol.reaction("push", "block")
    # horizontal push Fx: along the incline Fx cos a = m g sin a + mu N,
    # normal N = m g cos a + Fx sin a
    ca, sa = np.cos(alpha), np.sin(alpha)
    Fx = mass * g * (sa + mu * ca) / (ca - mu * sa)
    np.testing.assert_allclose(F[:, 0], Fx, rtol=1e-6)
    np.testing.assert_allclose(F[:, 1], 0, atol=1e-9)
    # the slide's reaction (normal force) on the block
    N = mass * g * ca + Fx * sa
    Fs, _ = sol.reaction("slide", "block")
    np.testing.assert_allclose(np.hypot(Fs[:, 0], Fs[:, 1]), N, rtol=1e-6)


def test_pin_friction_torque():
    mu, r, W, H = 0.2, 0.05, 300.0, 400.0
    m = ms.Model2D()
    wheel = m.add_body("wheel", mass=0.0)
    pin = m.add(ms.Revolute2(m.ground.point((0, 0)), wheel.point(0)), name="pin")
    m.add(ms.RotationLock1(wheel, 3.0 * T), name="motor")
    m.add_load(ms.Force(wheel.point(0), (0, -1), W))
    m.add_load(ms.Force(wheel.point(0), (1, 0), H))
    m.add_load(ms.JointFriction(pin, mu=mu, radius=r, v_eps=1e-6))
    sol = m.solve(np.linspace(0, 1, 5), solution="static")
    _, torque = sol.reaction("motor", "wheel")
    # static: velocities are zero, so the regularised sign is zero: no friction torque
    np.testing.assert_allclose(torque, 0, atol=1e-9)
    sol = m.solve(np.linspace(0, 1, 5), solution="kinematic")
    _, torque = sol.reaction("motor", "wheel")
    np.testing.assert_allclose(torque, mu * r * np.hypot(W, H), rtol=1e-9)
    # reversing the motor reverses the friction torque
    m.replace("motor", ms.RotationLock1(wheel, -3.0 * T))
    sol = m.solve(np.linspace(0, 1, 5), solution="kinematic")
    _, torque = sol.reaction("motor", "wheel")
    np.testing.assert_allclose(torque, -mu * r * np.hypot(W, H), rtol=1e-9)


def test_friction_too_large_reports_clearly():
    # mu so large that the push can never move the block: cos a - mu sin a < 0
    m = incline(0.6, 2.0)
    with pytest.raises(ms.MechError) as exc:
        m.solve(0.2, solution="dynamic")
    assert "lambda" in str(exc.value).lower() or "friction" in str(exc.value).lower()


def test_spherical_joint_friction_3d():
    """A ball joint carrying a vertical load W while the body spins about Z at w: the spin
    driver must supply mu r W against friction (no other moment about Z)."""
    import sympy as sp

    mu, r, W = 0.3, 0.02, 500.0
    m = ms.Model3D()
    b = m.add_body("ball", guess=((0, 0, 0), (1, 0, 0, 0)))
    x, y, z, e0, e1, e2, e3 = b.q
    ball = m.add(ms.Spherical3(b.point(0), m.ground.point((0, 0, 0))), name="ball")
    m.add(ms.Constraint([e1, e2]), name="upright")
    m.add(ms.Constraint([e3 - sp.sin(2.0 * T / 2)]), name="spin")
    m.add_load(ms.Force(b.point(0), (0, 0, -1), W))
    m.add_load(ms.JointFriction(ball, mu=mu, radius=r, v_eps=1e-6))
    sol = m.solve(np.linspace(0.1, 1.0, 4), solution="kinematic")
    _, Mspin = sol.reaction("spin", "ball", at=(0, 0, 0))
    np.testing.assert_allclose(Mspin[:, 2], mu * r * W, rtol=1e-8)
    F, _ = sol.reaction("ball", "ball")
    np.testing.assert_allclose(F, np.tile([0, 0, W], (4, 1)), atol=1e-8)


def test_joint_addressed_by_name_or_number():
    """``JointFriction("pin")`` (or the constraint's Mech number) is the friction of that
    joint, its kind inferred when the load is added; an unknown name and a bad ``kind`` are
    refused with a clear error. (Before, a name raised "cannot tell whether str is a
    rotational or translational joint".)"""
    def wheel(spec, **kw):
        m = ms.Model2D()
        w = m.add_body("wheel", mass=0.0)
        pin = m.add(ms.Revolute2(m.ground.point((0, 0)), w.point(0)), name="pin")
        m.add(ms.RotationLock1(w, 3.0 * T), name="motor")
        m.add_load(ms.Force(w.point(0), (0, -1), 300.0))
        load = ms.JointFriction(pin.number if spec == "number" else spec, mu=0.2, radius=0.05,
                                v_eps=1e-6, **kw)
        m.add_load(load)
        _, torque = m.solve(np.linspace(0, 1, 3), solution="kinematic").reaction("motor", "wheel")
        return load, torque

    for spec in ("pin", "number"):
        load, torque = wheel(spec)
        assert load.kind == "rotational"
        np.testing.assert_allclose(torque, 0.2 * 0.05 * 300.0, rtol=1e-9)
    with pytest.raises(ms.UnknownConstraintError, match="no constraint named 'hinge'"):
        wheel("hinge")
    with pytest.raises(ms.ModelError, match="kind must be one of 'rotational', 'translational'"):
        ms.JointFriction("pin", mu=0.2, kind="rotary")
    with pytest.raises(ms.ModelError, match="cannot tell whether Constraint is a rotational"):
        m = ms.Model2D()
        b = m.add_body("b")
        ms.JointFriction(ms.Constraint([b.q[0]]), mu=0.1)
