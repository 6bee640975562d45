"""Conformance cases for the planar constraint types: configurations built by hand."""

from __future__ import annotations

import numpy as np
import sympy as sp

from .. import constraints as C
from .._symbols import T
from ..geometry._points import Vector
from ..model import Model2D
from ._checks import Case, case, pose_vector


def _rot(th):
    c, s = np.cos(th), np.sin(th)
    return np.array([[c, -s], [s, c]])


def _two_bodies(rng, pts1=None, pts2=None):
    m = Model2D()
    b1 = m.add_body("b1", points=pts1)
    b2 = m.add_body("b2", points=pts2)
    return m, b1, b2


def _rand_pose(rng):
    return rng.uniform(-2, 2, 2), rng.uniform(-np.pi, np.pi)


@case("Revolute2")
def _revolute(rng):
    s1, s2 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    m, b1, b2 = _two_bodies(rng, {"p": s1}, {"p": s2})
    c = m.add(C.Revolute2(b1.point("p"), b2.point("p")))
    r1, th1 = _rand_pose(rng)
    th2 = rng.uniform(-np.pi, np.pi)
    r2 = r1 + _rot(th1) @ s1 - _rot(th2) @ s2
    return Case(m, c, pose_vector(m, {b1: [*r1, th1], b2: [*r2, th2]}))


@case("Revolute2")
def _revolute_ground_driven(rng):
    # a point on ground moving with time: a translational driver
    m = Model2D()
    b = m.add_body("b", points={"p": (0.5, 0.2)})
    c = m.add(C.Revolute2(b.point("p"), (sp.cos(T), 0.3 * T)))
    th = 0.7
    t = 0.3
    r = np.array([np.cos(t), 0.3 * t]) - _rot(th) @ np.array([0.5, 0.2])
    return Case(m, c, pose_vector(m, {b: [*r, th]}), t=t)


@case("Translate2")
def _translate(rng):
    o1, u1 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    o2, u2 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    m, b1, b2 = _two_bodies(rng)
    c = m.add(C.Translate2(b1.axis(tuple(o1), tuple(u1)), b2.axis(tuple(o2), tuple(u2))))
    r2, th2 = _rand_pose(rng)
    # direction of axis 2 globally, then turn body1 so that A1 u1 is parallel to it
    g2 = _rot(th2) @ u2
    th1 = np.arctan2(g2[1], g2[0]) - np.arctan2(u1[1], u1[0]) + np.pi * rng.integers(0, 2)
    s = rng.uniform(-2, 2)
    origin1 = r2 + _rot(th2) @ o2 + s * g2
    r1 = origin1 - _rot(th1) @ o1
    return Case(m, c, pose_vector(m, {b1: [*r1, th1], b2: [*r2, th2]}))


@case("OriginLock2")
def _originlock(rng):
    m, b1, b2 = _two_bodies(rng)
    d = rng.uniform(-1, 1, 2)
    c = m.add(C.OriginLock2(b1, b2, tuple(d)))
    r2, th2 = _rand_pose(rng)
    th1 = rng.uniform(-3, 3)
    return Case(m, c, pose_vector(m, {b1: [*(r2 + d), th1], b2: [*r2, th2]}))


@case("OriginLock2")
def _originlock_ground_body_vector(rng):
    m, b1, b2 = _two_bodies(rng)
    d = rng.uniform(-1, 1, 2)
    c = m.add(C.OriginLock2(b1, None, b2.vector(tuple(d))))
    r2, th2 = _rand_pose(rng)
    r1 = _rot(th2) @ d
    return Case(m, c, pose_vector(m, {b1: [*r1, 0.2], b2: [*r2, th2]}))


@case("RotationLock1")
def _rotlock(rng):
    m, b1, b2 = _two_bodies(rng)
    c = m.add(C.RotationLock1(b1, b2, 0.5 + sp.sin(2 * T)))
    t = 0.3
    th2 = rng.uniform(-3, 3)
    th1 = th2 + 0.5 + np.sin(2 * t)
    return Case(m, c, pose_vector(m, {b1: [0.1, 0.2, th1], b2: [0.3, -0.1, th2]}), t=t)


@case("RotationLock1")
def _rotlock_abs(rng):
    m = Model2D()
    b = m.add_body("b")
    c = m.add(C.RotationLock1(b, 3 * T**2))
    return Case(m, c, pose_vector(m, {b: [1, 2, 3 * 0.3**2]}))


def _relative_coordinate(kind, k):
    def build(rng):
        s1, s2 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
        m, b1, b2 = _two_bodies(rng, {"p": s1}, {"p": s2})
        dist = rng.uniform(-1, 1)
        c = m.add(kind(b1.point("p"), b2.point("p"), dist))
        r2, th2 = _rand_pose(rng)
        th1 = rng.uniform(-3, 3)
        p2 = r2 + _rot(th2) @ s2
        p1 = p2.copy()
        p1[k] += dist
        p1[1 - k] += rng.uniform(-1, 1)
        r1 = p1 - _rot(th1) @ s1
        return Case(m, c, pose_vector(m, {b1: [*r1, th1], b2: [*r2, th2]}))

    def build_abs(rng):
        m = Model2D()
        b = m.add_body("b", points={"p": (0.3, -0.4)})
        c = m.add(kind(b.point("p"), 2 * T))
        th = 0.4
        p = np.array([0.7, 0.7])
        p[k] = 2 * 0.3
        r = p - _rot(th) @ np.array([0.3, -0.4])
        return Case(m, c, pose_vector(m, {b: [*r, th]}))

    return build, build_abs


for _kind, _k in ((C.RelativeX1, 0), (C.RelativeY1, 1)):
    _b, _ba = _relative_coordinate(_kind, _k)
    case(_kind.mech_name)(_b)
    case(_kind.mech_name)(_ba)


@case("RelativeDistance1")
def _reldist(rng):
    s1, s2 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    m, b1, b2 = _two_bodies(rng, {"p": s1}, {"p": s2})
    L = rng.uniform(0.5, 2)
    c = m.add(C.RelativeDistance1(b1.point("p"), b2.point("p"), L))
    r2, th2 = _rand_pose(rng)
    th1 = rng.uniform(-3, 3)
    phi = rng.uniform(-3, 3)
    p1 = r2 + _rot(th2) @ s2 + L * np.array([np.cos(phi), np.sin(phi)])
    r1 = p1 - _rot(th1) @ s1
    return Case(m, c, pose_vector(m, {b1: [*r1, th1], b2: [*r2, th2]}))


@case("RelativeAngle1")
def _relangle(rng):
    u1, u2 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    m, b1, b2 = _two_bodies(rng)
    ang = 0.4 + T
    c = m.add(C.RelativeAngle1(b1.vector(tuple(u1)), b2.vector(tuple(u2)), ang))
    t = 0.3
    th2 = rng.uniform(-3, 3)
    # global angle of u1 = global angle of u2 + ang
    g2 = np.arctan2(*(_rot(th2) @ u2)[::-1])
    th1 = g2 + 0.4 + t - np.arctan2(u1[1], u1[0])
    return Case(m, c, pose_vector(m, {b1: [0, 0, th1], b2: [1, 1, th2]}), t=t)


@case("Orthogonal1")
def _orth(rng):
    u1, u2 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    m, b1, b2 = _two_bodies(rng)
    c = m.add(C.Orthogonal1(b1.vector(tuple(u1)), b2.vector(tuple(u2))))
    th2 = rng.uniform(-3, 3)
    g2 = np.arctan2(*(_rot(th2) @ u2)[::-1])
    th1 = g2 + np.pi / 2 - np.arctan2(u1[1], u1[0])
    return Case(m, c, pose_vector(m, {b1: [0, 0, th1], b2: [1, 1, th2]}))


@case("Orthogonal1")
def _orth_points(rng):
    # a vector between points of two bodies, orthogonal to a ground direction
    m, b1, b2 = _two_bodies(rng, {"p": (0.5, 0)}, {"p": (0, 0.5)})
    c = m.add(C.Orthogonal1(Vector(b1.point("p"), b2.point("p")), (1, 0)))
    th1, th2 = 0.3, -0.2
    p1 = np.array([0.2, 0.1]) + _rot(th1) @ np.array([0.5, 0])
    r2 = np.array([p1[0], 2.0]) - _rot(th2) @ np.array([0, 0.5])
    return Case(m, c, pose_vector(m, {b1: [0.2, 0.1, th1], b2: [*r2, th2]}))


@case("Parallel1")
def _par(rng):
    u1, u2 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    m, b1, b2 = _two_bodies(rng)
    c = m.add(C.Parallel1(b1.vector(tuple(u1)), b2.vector(tuple(u2))))
    th2 = rng.uniform(-3, 3)
    g2 = np.arctan2(*(_rot(th2) @ u2)[::-1])
    th1 = g2 - np.arctan2(u1[1], u1[0]) + np.pi
    return Case(m, c, pose_vector(m, {b1: [0, 0, th1], b2: [1, 1, th2]}))


def _point_on_line(dist):
    def build(rng):
        s1 = rng.uniform(-1, 1, 2)
        o2, u2 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
        m, b1, b2 = _two_bodies(rng, {"p": s1})
        c = m.add(C.PointOnLine1(b1.point("p"), b2.axis(tuple(o2), tuple(u2)), dist))
        r2, th2 = _rand_pose(rng)
        g = _rot(th2) @ u2
        g = g / np.linalg.norm(g)
        left = np.array([-g[1], g[0]])
        p = r2 + _rot(th2) @ o2 + rng.uniform(-2, 2) * g + dist * left
        th1 = rng.uniform(-3, 3)
        r1 = p - _rot(th1) @ s1
        return Case(m, c, pose_vector(m, {b1: [*r1, th1], b2: [*r2, th2]}))

    return build


case("PointOnLine1")(_point_on_line(0.0))
case("PointOnLine1")(_point_on_line(0.4))


@case("PointOnLine1")
def _point_on_line_of_points(rng):
    m, b1, b2 = _two_bodies(rng, {"p": (0.3, 0.1)}, {"a": (0, 0), "b": (2, 1)})
    c = m.add(C.PointOnLine1(b1.point("p"), b2.line("a", "b")))
    th2 = 0.5
    r2 = np.array([0.1, -0.3])
    p = r2 + _rot(th2) @ np.array([2, 1]) * 0.6
    r1 = p - _rot(0.9) @ np.array([0.3, 0.1])
    return Case(m, c, pose_vector(m, {b1: [*r1, 0.9], b2: [*r2, th2]}))


@case("Constraint")
def _general(rng):
    m = Model2D()
    b = m.add_body("b", points={"p": (1, 0)})
    s = sp.Symbol("s", real=True)
    loc = b.point("p").location()
    c = m.add(C.Constraint([loc[0] - s, loc[1] - s**2 - T], {s: 0.5}))
    # body at angle th with origin chosen so the point is at (s, s^2 + t)
    sv, th, t = 0.7, 0.4, 0.3
    r = np.array([sv, sv**2 + t]) - _rot(th) @ np.array([1, 0])
    return Case(m, c, pose_vector(m, {b: [*r, th], s: sv}), t=t)
