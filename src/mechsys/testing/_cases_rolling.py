r"""Conformance cases for the rolling constraints: configurations and rates built by hand.

Each builder places the rolling body at random, moves it along the surface normal until it
touches (the geometry of the contact, not the constraint's equations), and chooses random
angular velocities and a random motion of the surface body; the rolling body's centre then
gets the velocity that makes the material point at the contact move with the surface:
:math:`v_{\mathrm{centre}} = v_1(c) - \omega_2 \times (c - r_{\mathrm{centre}})`. The model holds the
holonomic part only
(``constraint.holonomic()``); the velocity constraint is checked on ``(q, qd)``.
"""

from __future__ import annotations

import numpy as np

from .. import constraints as C
from ..model import Model2D, Model3D
from ._cases_spatial import _pose, _rand_R, _unit
from ._checks import Case, case, pose_vector


def _euler_rates(e, omega):
    """``e_dot = E(e)^T omega / 2``: the Euler-parameter rates of the global angular
    velocity ``omega`` (``omega = 2 E e_dot``, ``E = [-e, e~ + e0 I]``; ``E E^T = I``)."""
    e0, e1, e2, e3 = e
    E = np.array([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])
    return 0.5 * E.T @ omega


def _rates(m, q, motions) -> np.ndarray:
    """``qd`` (n,) from ``{body: (velocity of its origin, angular velocity)}`` at ``q``."""
    lay = m.compile().layout
    qd = np.zeros(len(q))
    for body, (v, w) in motions.items():
        sl = lay.body_slices[body.name]
        if m.space.dim == 3:
            qd[sl] = [*v, *_euler_rates(q[sl][3:], w)]
        elif sl.stop - sl.start == 4:      # Model2D(orientation="euler"): (cos th, sin th)
            c, s = q[sl][2:]
            qd[sl] = [*v, -s * w, c * w]
        else:
            qd[sl] = [*v, w]
    return qd


def _material(v, w, r, x):
    """Velocity of the point at ``x`` of a body with origin ``r`` moving with ``(v, w)``."""
    d = np.asarray(x) - np.asarray(r)
    if len(d) == 3:
        return np.asarray(v) + np.cross(w, d)
    return np.asarray(v) + w * np.array([-d[1], d[0]])


def _surface_motion(rng, moving, dim):
    if not moving:
        return np.zeros(dim), (np.zeros(3) if dim == 3 else 0.0)
    return rng.standard_normal(dim), (rng.standard_normal(3) if dim == 3 else rng.standard_normal())


def _disk(rng, moving):
    m = Model3D()
    rad = rng.uniform(0.3, 1.0)
    if moving:          # coordinate directions on two bodies: smaller symbolic expressions
        b1 = m.add_body("floor")
        o1l, u1l = rng.uniform(-1, 1, 3), np.array([0.0, 0.0, 1.0])
        plane = b1.axis(tuple(o1l), tuple(u1l))
        r1, R1 = rng.uniform(-1, 1, 3), _rand_R(rng)
        o1, n = r1 + R1 @ o1l, R1 @ u1l
        u2l = np.array([0.0, 1.0, 0.0])
    else:
        b1, r1 = None, np.zeros(3)
        o1, u1 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3) + np.array([0, 0, 1.5])
        plane = m.ground.axis(tuple(o1), tuple(u1))
        n = _unit(u1)
        u2l = rng.uniform(-1, 1, 3) + np.array([0, 1.5, 0])
    disk = m.add_body("disk")
    o2l = rng.uniform(-0.5, 0.5, 3)
    roll = C.RollingDisk2(plane, disk.axis(tuple(o2l), tuple(u2l)), float(rad))
    m.add(roll.holonomic(), name="touch")
    R2 = _rand_R(rng)
    a = R2 @ _unit(u2l)
    w = _unit(np.cross(a, np.cross(n, a)))      # towards the plane's normal, in the disk
    centre = rng.uniform(-1, 1, 3)
    centre = centre + (n @ (o1 - (centre - rad * w))) * n    # slide along n until it touches
    c = centre - rad * w
    r2 = centre - R2 @ o2l
    return _rolling_case(rng, moving, m, roll, disk, (r2, R2, centre, c),
                         b1, (r1, R1) if b1 is not None else (r1, None))


def _rolling_case(rng, moving, m, roll, body, rolling_pose, b1, surface_pose):
    """The case of a 3D rolling contact: the rolling ``body`` at ``(r2, R2)`` with its centre
    and contact point ``c``, the surface body ``b1`` (or ground) at ``(r1, R1)``; rates with
    the contact point's material velocities equal on both (no slip), the rest random."""
    r2, R2, centre, c = rolling_pose
    r1, R1 = surface_pose
    poses = {body: _pose(r2, R2)}
    if b1 is not None:
        poses[b1] = _pose(r1, R1)
    q = pose_vector(m, poses)
    v1, w1 = _surface_motion(rng, moving, 3)
    w2 = rng.standard_normal(3)
    v_centre = _material(v1, w1, r1, c) - np.cross(w2, c - centre)
    motions = {body: (_material(v_centre, w2, centre, r2), w2)}
    if b1 is not None:
        motions[b1] = (v1, w1)
    return Case(m, roll, q, qd=_rates(m, q, motions))


def _sphere(rng, moving):
    m = Model3D()
    rad = rng.uniform(0.2, 1.0)
    if moving:
        b1 = m.add_body("floor")
        o1l, u1l = rng.uniform(-1, 1, 3), np.array([1.0, 0.0, 0.0])
        plane = b1.axis(tuple(o1l), tuple(u1l))
        r1, R1 = rng.uniform(-1, 1, 3), _rand_R(rng)
        o1, n = r1 + R1 @ o1l, R1 @ u1l
    else:
        b1, r1 = None, np.zeros(3)
        o1, u1 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3) + np.array([0, 0, 1.5])
        plane = m.ground.axis(tuple(o1), tuple(u1))
        n = _unit(u1)
    ball = m.add_body("ball")
    pl = rng.uniform(-0.5, 0.5, 3)
    roll = C.RollingSphere2(plane, ball.point(tuple(pl)), float(rad))
    m.add(roll.holonomic(), name="touch")
    R2 = _rand_R(rng)
    centre = rng.uniform(-1, 1, 3)
    centre = centre + (n @ (o1 - centre) + rad) * n
    c = centre - rad * n
    r2 = centre - R2 @ pl
    return _rolling_case(rng, moving, m, roll, ball, (r2, R2, centre, c),
                         b1, (r1, R1) if b1 is not None else (r1, None))


def _circle(rng, moving):
    m = Model2D()
    rad = rng.uniform(0.2, 1.0)
    b1 = m.add_body("rail") if moving else None
    o1l, u1l = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2) + np.array([1.5, 0])
    line = (b1.axis(tuple(o1l), tuple(u1l)) if moving
            else m.ground.axis(tuple(o1l), tuple(u1l)))
    wheel = m.add_body("wheel")
    pl = rng.uniform(-0.5, 0.5, 2)
    roll = C.RollingCircle1(wheel.point(tuple(pl)), float(rad), line)
    m.add(roll.holonomic(), name="touch")
    r1, th1 = (rng.uniform(-1, 1, 2), rng.uniform(-np.pi, np.pi)) if moving else (np.zeros(2), 0.0)
    R1 = np.array([[np.cos(th1), -np.sin(th1)], [np.sin(th1), np.cos(th1)]])
    o1, u = r1 + R1 @ o1l, _unit(R1 @ u1l)
    left = np.array([-u[1], u[0]])
    centre = o1 + rng.uniform(-1, 1) * u + rad * left
    c = centre - rad * left
    th2 = rng.uniform(-np.pi, np.pi)
    R2 = np.array([[np.cos(th2), -np.sin(th2)], [np.sin(th2), np.cos(th2)]])
    r2 = centre - R2 @ pl
    poses = {wheel: (*r2, th2)}
    if b1 is not None:
        poses[b1] = (*r1, th1)
    q = pose_vector(m, poses)
    v1, w1 = _surface_motion(rng, moving, 2)
    w2 = rng.standard_normal()
    v_centre = _material(v1, w1, r1, c) - _material(np.zeros(2), w2, centre, c)
    motions = {wheel: (_material(v_centre, w2, centre, r2), w2)}
    if b1 is not None:
        motions[b1] = (v1, w1)
    return Case(m, roll, q, qd=_rates(m, q, motions))


# a disk on a moving plane is left out: its derivatives take half a minute to compile on a
# loaded machine, and the sphere on a moving plane runs the same code for the plane's body
# (its material velocity at the contact, its body-fixed in-plane directions)
for _name, _build, _variants in (("RollingDisk2", _disk, (False,)),
                                 ("RollingSphere2", _sphere, (False, True)),
                                 ("RollingCircle1", _circle, (False, True))):
    for _moving in _variants:
        case(_name)(lambda rng, b=_build, mv=_moving: b(rng, mv))
