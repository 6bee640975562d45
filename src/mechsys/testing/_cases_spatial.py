"""Conformance cases for the spatial constraint types: configurations built by hand.

Each builder places body 2 at a random pose, chooses the global geometry that body 1 must
have for the constraint to hold (directly, from the definition of the joint, not by solving
its equations), and turns that into body 1's pose: the rotation that takes body 1's local
(direction, reference) pair onto the chosen global pair, then the translation that puts the
chosen local point where it must be.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .. import constraints as C
from .._symbols import T
from ..geometry._points import Plane, Vector
from ..geometry._rotations import euler_parameters, rotation_matrix
from ..model import Model3D
from ._checks import Case, case, pose_vector

# -- small numeric helpers -------------------------------------------------------------------


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def _rand_unit(rng):
    return _unit(rng.standard_normal(3))


def _perp(u, rng):
    """A random unit vector perpendicular to ``u``."""
    u = _unit(u)
    v = rng.standard_normal(3)
    return _unit(v - (v @ u) * u)


def _frame(u, g):
    u = _unit(u)
    g = _unit(g - (g @ u) * u)
    return np.column_stack([u, g, np.cross(u, g)])


def _map(u_loc, g_loc, u_glob, g_glob):
    """The rotation taking local (u, g) onto global (u, g) (g's perpendicular parts)."""
    return _frame(u_glob, g_glob) @ _frame(u_loc, g_loc).T


def _rand_R(rng):
    return rotation_matrix(rng.standard_normal(4))


def _pose(r, R):
    return [*np.asarray(r, dtype=float), *euler_parameters(R)]


def _two(pts1=None, pts2=None):
    m = Model3D()
    return m, m.add_body("b1", points=pts1), m.add_body("b2", points=pts2)


def _axis_local(axis):
    """Local origin, direction and (library) reference direction of a body-fixed axis."""
    o = np.array([float(c) for c in axis.origin.local])
    u = np.array([float(c) for c in axis.dir.local])
    g = np.array([float(c) for c in axis.reference_vector().local])
    return o, u, g


def _place_axis(axis, o, u, g, rng):
    """Pose of the axis' body putting the axis origin at ``o``, direction along ``u`` and
    reference along ``g`` (a random spin when ``g`` is None)."""
    o_l, u_l, g_l = _axis_local(axis)
    if g is None:
        g = _perp(u, rng)
    R = _map(u_l, g_l, u, g)
    return _pose(np.asarray(o) - R @ o_l, R)


def _global_axis(axis, r, R):
    o_l, u_l, g_l = _axis_local(axis)
    return r + R @ o_l, R @ _unit(u_l), R @ g_l


_AXES = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, -1), (-1, 0, 0)]


def _axes(rng, kind, args=(), refs=False, on_ground=False):
    """A model with ``kind(axis1 on b1, axis2, *args)``, axis2 placed at random.
    Returns (model, constraint, axis1, b1, b2 or None, pose2 or None, (o2, u2 unit, g2)).

    ``on_ground``: axis2 is a ground axis and both axes have generic local geometry.
    Otherwise axis2 is on a second body and both local directions are coordinate axes
    (random origins): symbolic compilation of two generic bodies is slow, and the two
    variants together cover generic geometry and body-body coupling.
    """
    m = Model3D()
    b1 = m.add_body("b1")
    o1, o2 = tuple(rng.uniform(-1, 1, 3)), tuple(rng.uniform(-1, 1, 3))
    if on_ground:
        u1, u2 = tuple(rng.uniform(-1, 1, 3)), tuple(rng.uniform(-1, 1, 3))
        ref1 = tuple(rng.uniform(-1, 1, 3)) if refs else None
        ref2 = tuple(rng.uniform(-1, 1, 3)) if refs else None
    else:
        i, j = rng.choice(len(_AXES), 2, replace=False)
        u1, u2 = _AXES[i], _AXES[j]
        ref1 = tuple(np.roll(np.abs(u1), 1) + 0.5 * np.array(u1)) if refs else None
        ref2 = tuple(np.roll(np.abs(u2), 2) - 0.3 * np.array(u2)) if refs else None
    a1 = b1.axis(o1, u1, ref1)
    if on_ground:
        a2 = m.ground.axis(o2, u2, ref2)
        c = m.add(kind(a1, a2, *args))
        return m, c, a1, b1, None, None, _global_axis(a2, np.zeros(3), np.eye(3))
    b2 = m.add_body("b2")
    a2 = b2.axis(o2, u2, ref2)
    c = m.add(kind(a1, a2, *args))
    r2, R2 = rng.uniform(-2, 2, 3), _rand_R(rng)
    return m, c, a1, b1, b2, _pose(r2, R2), _global_axis(a2, r2, R2)


def _poses(b1, pose1, b2, pose2):
    return {b1: pose1} if b2 is None else {b1: pose1, b2: pose2}


def _axes_case(kind, place1, args=(), refs=False, variants=(True, False)):
    """Register cases (``variants``: True = axis2 on ground with generic geometry, False =
    axis2 on a body): ``place1(rng, o2, u2, g2) -> (o1, u1, g1 or None)`` gives axis1's
    global placement."""

    def build(rng, on_ground):
        m, c, a1, b1, b2, pose2, (o2, u2, g2) = _axes(rng, kind, args, refs, on_ground)
        o1, u1, g1 = place1(rng, o2, u2, g2)
        pose1 = _place_axis(a1, o1, u1, g1, rng)
        return Case(m, c, pose_vector(m, _poses(b1, pose1, b2, pose2)))

    for on_ground in variants:
        case(kind.mech_name)(lambda rng, g=on_ground: build(rng, g))


# -- points and bodies -----------------------------------------------------------------------


@case("Spherical3")
def _spherical(rng):
    s1, s2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    m, b1, b2 = _two({"p": s1}, {"p": s2})
    c = m.add(C.Spherical3(b1.point("p"), b2.point("p")))
    r2, R2, R1 = rng.uniform(-2, 2, 3), _rand_R(rng), _rand_R(rng)
    r1 = r2 + R2 @ s2 - R1 @ s1
    return Case(m, c, pose_vector(m, {b1: _pose(r1, R1), b2: _pose(r2, R2)}))


@case("Spherical3")
def _spherical_ground_driven(rng):
    m = Model3D()
    b = m.add_body("b", points={"p": (0.5, 0.2, -0.3)})
    c = m.add(C.Spherical3(b.point("p"), (sp.cos(T), 0.3 * T, sp.sin(2 * T))))
    t, R = 0.3, _rand_R(rng)
    r = np.array([np.cos(t), 0.3 * t, np.sin(2 * t)]) - R @ np.array([0.5, 0.2, -0.3])
    return Case(m, c, pose_vector(m, {b: _pose(r, R)}), t=t)


@case("OriginLock3")
def _originlock(rng):
    m, b1, b2 = _two()
    d = rng.uniform(-1, 1, 3)
    c = m.add(C.OriginLock3(b1, b2, tuple(d)))
    r2 = rng.uniform(-2, 2, 3)
    return Case(m, c, pose_vector(m, {b1: _pose(r2 + d, _rand_R(rng)),
                                      b2: _pose(r2, _rand_R(rng))}))


@case("OriginLock3")
def _originlock_ground_body_vector(rng):
    m, b1, b2 = _two()
    d = rng.uniform(-1, 1, 3)
    c = m.add(C.OriginLock3(b1, None, b2.vector(tuple(d))))
    r2, R2 = rng.uniform(-2, 2, 3), _rand_R(rng)
    return Case(m, c, pose_vector(m, {b1: _pose(R2 @ d, _rand_R(rng)), b2: _pose(r2, R2)}))


@case("RotationLock3")
def _rotlock3_sequence(rng):
    m, b1, b2 = _two()
    ax1, ax2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    e = _unit(rng.standard_normal(4))
    c = m.add(C.RotationLock3(b1, b2, (0.3 + T, tuple(ax1)), (0.5, tuple(ax2)), tuple(e)))
    t = 0.3
    R2 = _rand_R(rng)
    R1 = R2 @ rotation_matrix([(0.3 + t, ax1), (0.5, ax2), e])
    return Case(m, c, pose_vector(m, {b1: _pose(rng.uniform(-1, 1, 3), R1),
                                      b2: _pose(rng.uniform(-1, 1, 3), R2)}), t=t)


@case("RotationLock3")
def _rotlock3_ground_virtual(rng):
    m = Model3D()
    b = m.add_body("b")
    v = rng.uniform(-2, 2, 3)
    c = m.add(C.RotationLock3(b, None, tuple(v)))
    R = rotation_matrix(v)
    return Case(m, c, pose_vector(m, {b: _pose(rng.uniform(-1, 1, 3), R)}))


def _rotlock1(refs, on_ground):
    def build(rng):
        ang = 0.4 + T
        m, c, a1, b1, b2, pose2, (o2, u2, g2) = _axes(rng, C.RotationLock1, (ang,), refs,
                                                       on_ground)
        t = 0.3
        k2 = np.cross(u2, g2)
        u1 = _rand_unit(rng)
        p, q = _perp(u1, rng), None
        q = np.cross(u1, p)
        # g1 = cos(b) p + sin(b) q with cos(a)(k2.g1) - sin(a)(g2.g1) = 0
        a = 0.4 + t
        A = np.cos(a) * (k2 @ p) - np.sin(a) * (g2 @ p)
        B = np.cos(a) * (k2 @ q) - np.sin(a) * (g2 @ q)
        beta = np.arctan2(-A, B)
        g1 = np.cos(beta) * p + np.sin(beta) * q
        pose1 = _place_axis(a1, rng.uniform(-1, 1, 3), u1, g1, rng)
        return Case(m, c, pose_vector(m, _poses(b1, pose1, b2, pose2)), t=t)

    return build


case("RotationLock1")(_rotlock1(False, True))
case("RotationLock1")(_rotlock1(True, False))


@case("RotationLock1")
def _rotlock1_from_rest(rng):
    # RotationLock1(axis, angle): the body turned by angle about its own axis from rest
    m = Model3D()
    b = m.add_body("b")
    u, o = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    c = m.add(C.RotationLock1(b.axis(tuple(o), tuple(u)), 2 * T))
    t = 0.3
    R = rotation_matrix((2 * t, u))  # turned 2t about the axis direction from rest
    return Case(m, c, pose_vector(m, {b: _pose(rng.uniform(-1, 1, 3), R)}), t=t)


@case("RelativeAngle1")
def _relangle3(rng):
    m, b1, b2 = _two()
    v1, v2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    c = m.add(C.RelativeAngle1(b1.vector(tuple(v1)), b2.vector(tuple(v2)), 0.7 + T))
    t, R2 = 0.3, _rand_R(rng)
    w2 = _unit(R2 @ v2)
    w1 = np.cos(0.7 + t) * w2 + np.sin(0.7 + t) * _perp(w2, rng)
    R1 = _map(v1, _perp(v1, rng), w1, _perp(w1, rng))
    return Case(m, c, pose_vector(m, {b1: _pose(rng.uniform(-1, 1, 3), R1),
                                      b2: _pose(rng.uniform(-1, 1, 3), R2)}), t=t)


def _relcoord3(kind, k):
    def build(rng):
        s1, s2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
        m, b1, b2 = _two({"p": s1}, {"p": s2})
        dist = rng.uniform(-1, 1)
        c = m.add(kind(b1.point("p"), b2.point("p"), dist))
        r2, R2, R1 = rng.uniform(-2, 2, 3), _rand_R(rng), _rand_R(rng)
        p1 = r2 + R2 @ s2 + rng.uniform(-1, 1, 3)
        p1[k] = (r2 + R2 @ s2)[k] + dist
        return Case(m, c, pose_vector(m, {b1: _pose(p1 - R1 @ s1, R1), b2: _pose(r2, R2)}))

    def build_abs(rng):
        m = Model3D()
        b = m.add_body("b", points={"p": (0.3, -0.4, 0.2)})
        c = m.add(kind(b.point("p"), 2 * T))
        R = _rand_R(rng)
        p = rng.uniform(-1, 1, 3)
        p[k] = 0.6
        return Case(m, c, pose_vector(m, {b: _pose(p - R @ np.array([0.3, -0.4, 0.2]), R)}))

    return build, build_abs


for _kind, _k in ((C.RelativeX1, 0), (C.RelativeY1, 1), (C.RelativeZ1, 2)):
    _two_bodies, _absolute = _relcoord3(_kind, _k)
    case(_kind.mech_name)(_absolute)
    if _kind is C.RelativeZ1:  # X and Y share the code; their 2D cases cover two bodies
        case(_kind.mech_name)(_two_bodies)


@case("RelativeDistance1")
def _reldist3(rng):
    s1, q = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    m = Model3D()
    b1 = m.add_body("b1", points={"p": s1})
    c = m.add(C.RelativeDistance1(b1.point("p"), tuple(q), 1.5 + 0.5 * T))
    R1 = _rand_R(rng)
    p1 = q + (1.5 + 0.5 * 0.3) * _rand_unit(rng)
    return Case(m, c, pose_vector(m, {b1: _pose(p1 - R1 @ s1, R1)}))


@case("Orthogonal1")
def _orth3(rng):
    m, b1, b2 = _two()
    v1, v2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    c = m.add(C.Orthogonal1(b1.vector(tuple(v1)), b2.vector(tuple(v2))))
    R2 = _rand_R(rng)
    w1 = _perp(R2 @ v2, rng)
    R1 = _map(v1, _perp(v1, rng), w1, _perp(w1, rng))
    return Case(m, c, pose_vector(m, {b1: _pose(rng.uniform(-1, 1, 3), R1),
                                      b2: _pose(rng.uniform(-1, 1, 3), R2)}))


@case("Parallel2")
def _par2(rng):
    m, b1, b2 = _two()
    v1, v2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    c = m.add(C.Parallel2(b1.vector(tuple(v1)), b2.vector(tuple(v2))))
    R2 = _rand_R(rng)
    w1 = -_unit(R2 @ v2)  # anti-parallel also satisfies Parallel2
    R1 = _map(v1, _perp(v1, rng), w1, _perp(w1, rng))
    return Case(m, c, pose_vector(m, {b1: _pose(rng.uniform(-1, 1, 3), R1),
                                      b2: _pose(rng.uniform(-1, 1, 3), R2)}))


@case("Parallel2")
def _par2_points_of_two_bodies(rng):
    # a vector between points of two bodies parallel to a ground direction
    m, b1, b2 = _two({"p": (0.5, 0, 0.1)}, {"p": (0, 0.5, -0.2)})
    c = m.add(C.Parallel2(Vector(b1.point("p"), b2.point("p")), (0.3, 0.4, 1.0)))
    r1, R1, R2 = rng.uniform(-1, 1, 3), _rand_R(rng), _rand_R(rng)
    p1 = r1 + R1 @ np.array([0.5, 0, 0.1])
    p2 = p1 + 1.7 * np.array([0.3, 0.4, 1.0])
    r2 = p2 - R2 @ np.array([0, 0.5, -0.2])
    return Case(m, c, pose_vector(m, {b1: _pose(r1, R1), b2: _pose(r2, R2)}))


# -- points on lines, planes and circles -----------------------------------------------------


def _point_and_axis(rng, kind, args=()):
    """A point of body 1 and a generic ground axis (cases with the axis on a second body
    follow each type)."""
    s1 = rng.uniform(-1, 1, 3)
    m = Model3D()
    b1 = m.add_body("b1", points={"p": s1})
    o, u = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    c = m.add(kind(b1.point("p"), m.ground.axis(tuple(o), tuple(u)), *args))
    return m, c, b1, s1, o, _unit(u)


def _put_point(b1, s1, p, rng):
    R1 = _rand_R(rng)
    return _pose(p - R1 @ s1, R1)


@case("PointOnLine2")
def _pol2(rng):
    m, c, b1, s1, o, u = _point_and_axis(rng, C.PointOnLine2)
    p = o + rng.uniform(-2, 2) * u
    return Case(m, c, pose_vector(m, {b1: _put_point(b1, s1, p, rng)}))


@case("PointOnLine2")
def _pol2_line_of_points(rng):
    # a Line through two points of body 2 along its local x axis (the awkward direction for
    # normals built from the global expression)
    m, b1, b2 = _two({"p": (0.3, 0.1, -0.2)}, {"a": (0, 0, 0), "b": (2, 0, 0)})
    c = m.add(C.PointOnLine2(b1.point("p"), b2.line("a", "b")))
    r2, R2 = rng.uniform(-1, 1, 3), _rand_R(rng)
    p = r2 + R2 @ np.array([2.0, 0, 0]) * 0.6
    return Case(m, c, pose_vector(m, {b1: _put_point(b1, np.array([0.3, 0.1, -0.2]), p, rng),
                                      b2: _pose(r2, R2)}))


@case("PointOnPlane1")
def _pop1(rng):
    dist = 0.3 + T
    m, c, b1, s1, o, u = _point_and_axis(rng, C.PointOnPlane1, (dist,))
    p = o + (0.3 + 0.3) * u + 1.3 * _perp(u, rng)
    return Case(m, c, pose_vector(m, {b1: _put_point(b1, s1, p, rng)}))


@case("PointOnPlane1")
def _pop1_plane_object(rng):
    pts = {"a": (0.1, 0.2, 0.3), "b": (1.0, 0.2, 0.5), "c": (0.2, 1.1, -0.1)}
    m, b1, b2 = _two({"p": (0.2, -0.1, 0.4)}, pts)
    c = m.add(C.PointOnPlane1(b1.point("p"), Plane(b2, "a", "b", "c")))
    r2, R2 = rng.uniform(-1, 1, 3), _rand_R(rng)
    A, B, Cc = (r2 + R2 @ np.array(pts[k]) for k in "abc")
    p = A + 0.7 * (B - A) - 0.4 * (Cc - A)
    return Case(m, c, pose_vector(m, {b1: _put_point(b1, np.array([0.2, -0.1, 0.4]), p, rng),
                                      b2: _pose(r2, R2)}))


@case("PointOnCircle2")
def _poc2(rng):
    m, c, b1, s1, o, u = _point_and_axis(rng, C.PointOnCircle2, (0.8,))
    p = o + 0.8 * _perp(u, rng)
    return Case(m, c, pose_vector(m, {b1: _put_point(b1, s1, p, rng)}))


@case("PointOnCircle2")
def _poc2_body_axis(rng):
    m, b1, b2 = _two({"p": (0.3, 0.1, -0.2)})
    axis = b2.axis((0.2, -0.3, 0.1), (0, 1, 0))
    c = m.add(C.PointOnCircle2(b1.point("p"), axis, 0.8))
    r2, R2 = rng.uniform(-1, 1, 3), _rand_R(rng)
    o, u, g = _global_axis(axis, r2, R2)
    p = o + 0.8 * (np.cos(0.4) * g + np.sin(0.4) * np.cross(u, g))
    return Case(m, c, pose_vector(m, {b1: _put_point(b1, np.array([0.3, 0.1, -0.2]), p, rng),
                                      b2: _pose(r2, R2)}))


@case("PointAtIntersection3")
def _pai3(rng):
    # a ground line through the point where it crosses a Plane on body 3
    s1 = rng.uniform(-1, 1, 3)
    pts = {"a": (0.1, 0.2, 0.3), "b": (1.0, 0.2, 0.5), "c": (0.2, 1.1, -0.1)}
    r3, R3 = rng.uniform(-1, 1, 3), _rand_R(rng)
    A, B, Cc = (r3 + R3 @ np.array(pts[k]) for k in "abc")
    n = np.cross(B - A, Cc - A)
    p = A + 0.3 * (B - A) + 0.5 * (Cc - A)            # the intersection point, in the plane
    u = n + 0.8 * np.linalg.norm(n) * _perp(n, rng)  # line direction, not in the plane
    m = Model3D()
    b1, b3 = m.add_body("b1", points={"p": s1}), m.add_body("b3", points=pts)
    line = m.ground.axis(tuple(p - 0.9 * u), tuple(u))
    c = m.add(C.PointAtIntersection3(b1.point("p"), line, Plane(b3, "a", "b", "c")))
    return Case(m, c, pose_vector(m, {b1: _put_point(b1, s1, p, rng), b3: _pose(r3, R3)}))


# -- joints between axes ---------------------------------------------------------------------

_axes_case(C.Revolute5, lambda rng, o2, u2, g2: (o2, u2, None))
_axes_case(C.Cylindrical4, lambda rng, o2, u2, g2: (o2 + rng.uniform(-2, 2) * u2, u2, None))
_axes_case(C.Translate5, lambda rng, o2, u2, g2: (o2 + rng.uniform(-2, 2) * u2, u2, g2),
           variants=(True,))
_axes_case(C.Translate5, lambda rng, o2, u2, g2: (o2 - 0.7 * u2, u2, g2), refs=True,
           variants=(False,))
_axes_case(C.Universal4, lambda rng, o2, u2, g2: (o2, _perp(u2, rng), None))
_axes_case(C.ParaRevolute4, lambda rng, o2, u2, g2: (o2 + 0.6 * _perp(u2, rng), u2, None), (0.6,),
           variants=(True,))
_axes_case(C.LineOnCylinder3,
           lambda rng, o2, u2, g2: (o2 + 0.4 * u2 + 0.7 * _perp(u2, rng), -u2, None), (0.7,),
           variants=(True,))


def _ortho_place(dist):
    def place(rng, o2, u2, g2):
        u1 = _perp(u2, rng)
        return o2 + dist * np.cross(u1, u2), u1, None

    return place


_axes_case(C.OrthoRevolute4, _ortho_place(0.0), variants=(False,))
_axes_case(C.OrthoRevolute4, _ortho_place(0.45), (0.45,), variants=(True,))


def _cv_place(Cc):
    def place(rng, o2, u2, g2):
        u1 = _rand_unit(rng)
        n = _unit(np.cross(u1, u2))
        spin2 = np.arctan2(g2 @ np.cross(u2, n), g2 @ n)
        s1 = spin2 - Cc
        return o2, u1, np.cos(s1) * n + np.sin(s1) * np.cross(u1, n)

    return place


_axes_case(C.ConstantVelocity4, _cv_place(0.0))
_axes_case(C.ConstantVelocity4, _cv_place(0.35), (0.35,), refs=True, variants=(False,))


def _line_to_circle(rng, o2, u2, g2):
    rim = o2 + 0.9 * (np.cos(1.1) * g2 + np.sin(1.1) * np.cross(u2, g2))
    u1 = _unit(u2 + 0.7 * _perp(u2, rng))
    return rim - 0.8 * u1, u1, None


_axes_case(C.LineToCircle1, _line_to_circle, (0.9,), variants=(True,))


def _line_to_line(dist):
    def place(rng, o2, u2, g2):
        u1 = _rand_unit(rng)
        x = o2 + 0.5 * u2 + dist * _unit(np.cross(u1, u2))
        return x - 1.2 * u1, u1, None

    return place


_axes_case(C.LineToLine1, _line_to_line(0.0), variants=(False,))
_axes_case(C.LineToLine1, _line_to_line(0.55), (0.55,), variants=(True,))


def _in_plane(dist):
    def place(rng, o2, u2, g2):
        return o2 + dist * u2 + 1.1 * _perp(u2, rng), _perp(u2, rng), None

    return place


_axes_case(C.LineToPlane2, _in_plane(0.0), variants=(True,))
_axes_case(C.LineToPlane2, _in_plane(0.35), (0.35,), variants=(False,))


def _plane_parallel(dist):
    def place(rng, o2, u2, g2):
        return o2 + dist * u2 + 0.9 * _perp(u2, rng), u2, None

    return place


_axes_case(C.PlaneToPlane3, _plane_parallel(0.0), variants=(True,))
_axes_case(C.PlaneToPlane3, _plane_parallel(-0.4), (-0.4,), variants=(False,))
_axes_case(C.Planar3, _plane_parallel(0.0), variants=(False,))


@case("PlaneToPlane3")
def _plane_to_plane_planes(rng):
    pts1 = {"a": (0, 0, 0), "b": (1, 0, 0), "c": (0, 1, 0)}
    pts2 = {"a": (0.2, 0.1, 0.0), "b": (0.9, 0.3, 0.2), "c": (0.1, 0.8, -0.3)}
    m, b1, b2 = _two(pts1, pts2)
    c = m.add(C.PlaneToPlane3(Plane(b1, "a", "b", "c"), Plane(b2, "a", "b", "c")))
    r2, R2 = rng.uniform(-1, 1, 3), _rand_R(rng)
    A, B, Cc = (r2 + R2 @ np.array(pts2[k]) for k in "abc")
    n = _unit(np.cross(B - A, Cc - A))
    R1 = _map(np.array([0, 0, 1.0]), np.array([1.0, 0, 0]), n, _perp(n, rng))
    r1 = A + 0.4 * (B - A) + 0.2 * (Cc - A)
    return Case(m, c, pose_vector(m, {b1: _pose(r1, R1), b2: _pose(r2, R2)}))


def _plane_to_circle(rad, minrad, args, on_ground):
    def build(rng):
        # axis1: the plane (normal u1); axis2: the circle's axis
        m, c, a1, b1, b2, pose2, (o2, u2, g2) = _axes(rng, C.PlaneToCircle1, args,
                                                       on_ground=on_ground)
        u1 = _unit(u2 + 1.3 * _perp(u2, rng))
        h = rad * np.linalg.norm(np.cross(u1, u2)) + minrad
        o1 = o2 - h * u1 + 0.8 * _perp(u1, rng)
        pose1 = _place_axis(a1, o1, u1, None, rng)
        return Case(m, c, pose_vector(m, _poses(b1, pose1, b2, pose2)))

    case("PlaneToCircle1")(build)


_plane_to_circle(0.9, 0.0, (0.9,), True)
_plane_to_circle(0.9, 0.25, (0.9, 0.25), False)


@case("Constraint")
def _general3(rng):
    m = Model3D()
    b = m.add_body("b", points={"p": (1, 0, 0)})
    s = sp.Symbol("s", real=True)
    loc = b.point("p").location()
    c = m.add(C.Constraint([loc[0] - s, loc[1] - s**2 - T, loc[2] - sp.sin(s)], {s: 0.5}))
    sv, t, R = 0.7, 0.3, _rand_R(rng)
    r = np.array([sv, sv**2 + t, np.sin(sv)]) - R @ np.array([1.0, 0, 0])
    return Case(m, c, pose_vector(m, {b: _pose(r, R), s: sv}), t=t)
