"""Conformance cases for the cam constraints: configurations built by hand.

Each builder puts the cam body at a random pose, picks the profile parameters, evaluates the
contact point, tangents and normal of the profile numerically (NumPy from the profile's own
formula, independent of the constraint's equations) and places the follower body so that
the contact holds by construction: the follower point at the contact point (or at the roller
centre, a radius along the unit normal), a line or plane through the contact point along the
tangent, a second profile turned so that its normal is parallel to the first's.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .. import constraints as C
from ..model import Model2D, Model3D
from ._cases_spatial import _map, _perp, _pose, _rand_R, _unit
from ._checks import Case, case, pose_vector

A_, B_, G_, D_ = sp.symbols("a_cam b_cam g_cam d_cam")


def _rot2(th):
    c, s = np.cos(th), np.sin(th)
    return np.array([[c, -s], [s, c]])


def _numeric(local, syms):
    """``f(*values) -> (s', [ds'/dsym_k])`` as NumPy arrays, from the profile's formula."""
    pos = sp.lambdify(syms, sp.Matrix(local), "numpy")
    tan = [sp.lambdify(syms, sp.Matrix(local).diff(s), "numpy") for s in syms]

    def f(*vals):
        return (np.asarray(pos(*vals), dtype=float).ravel(),
                [np.asarray(t(*vals), dtype=float).ravel() for t in tan])

    return f


# -- 2D profiles -------------------------------------------------------------------------------

#: a disk cam ``r(a) = 1.2 + 0.3 cos 3a`` (a point of parameter ``a_cam``)
DISK = ((1.2 + 0.3 * sp.cos(3 * A_)) * sp.cos(A_), (1.2 + 0.3 * sp.cos(3 * A_)) * sp.sin(A_))
#: an ellipse of parameter ``b_cam``
ELLIPSE = (1.5 * sp.cos(B_), 0.8 * sp.sin(B_))


def _cam2(rng, follower_points=None):
    m = Model2D()
    cam = m.add_body("cam")
    fol = m.add_body("follower", points=follower_points)
    r1, th1 = rng.uniform(-2, 2, 2), rng.uniform(-np.pi, np.pi)
    a0 = rng.uniform(-np.pi, np.pi)
    s, (t,) = _numeric(DISK, [A_])(a0)
    c = r1 + _rot2(th1) @ s
    tg = _rot2(th1) @ t
    return m, cam, fol, (r1, th1), a0, c, tg


@case("CamToPoint1")
def _cam_point_2d(rng):
    p2 = rng.uniform(-1, 1, 2)
    m, cam, fol, (r1, th1), a0, c, _ = _cam2(rng, {"p": p2})
    con = m.add(C.CamToPoint1(cam.point(DISK), (A_, a0), fol.point("p")))
    th2 = rng.uniform(-np.pi, np.pi)
    r2 = c - _rot2(th2) @ p2
    return Case(m, con, pose_vector(m, {cam: [*r1, th1], fol: [*r2, th2], A_: a0}))


def _cam_circle_2d(sign):
    def build(rng):
        p2 = rng.uniform(-1, 1, 2)
        m, cam, fol, (r1, th1), a0, c, tg = _cam2(rng, {"p": p2})
        rad = sign * rng.uniform(0.2, 0.6)
        con = m.add(C.CamToCircle1(cam.point(DISK), (A_, a0), fol.point("p"), rad))
        left = np.array([-tg[1], tg[0]]) / np.linalg.norm(tg)  # the tangent turned +90 deg
        centre = c + rad * left
        th2 = rng.uniform(-np.pi, np.pi)
        r2 = centre - _rot2(th2) @ p2
        return Case(m, con, pose_vector(m, {cam: [*r1, th1], fol: [*r2, th2], A_: a0}),
                    label=f"CamToCircle1[radius {'+' if sign > 0 else '-'}]")

    return build


case("CamToCircle1")(_cam_circle_2d(+1))
case("CamToCircle1")(_cam_circle_2d(-1))


@case("CamToLine1")
def _cam_line_2d(rng):
    o2, u2 = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    m, cam, fol, (r1, th1), a0, c, tg = _cam2(rng)
    con = m.add(C.CamToLine1(cam.point(DISK), (A_, a0), fol.axis(tuple(o2), tuple(u2))))
    # turn the follower so that its line runs along the tangent (either way), then slide it
    th2 = np.arctan2(tg[1], tg[0]) - np.arctan2(u2[1], u2[0]) + np.pi * rng.integers(0, 2)
    origin = c + rng.uniform(-1, 1) * tg
    r2 = origin - _rot2(th2) @ o2
    return Case(m, con, pose_vector(m, {cam: [*r1, th1], fol: [*r2, th2], A_: a0}))


@case("CamToCam1")
def _cam_cam_2d(rng):
    m, cam, fol, (r1, th1), a0, c, tg = _cam2(rng)
    b0 = rng.uniform(-np.pi, np.pi)
    con = m.add(C.CamToCam1(cam.point(DISK), (A_, a0), fol.point(ELLIPSE), (B_, b0)))
    s2, (t2,) = _numeric(ELLIPSE, [B_])(b0)
    th2 = np.arctan2(tg[1], tg[0]) - np.arctan2(t2[1], t2[0]) + np.pi * rng.integers(0, 2)
    r2 = c - _rot2(th2) @ s2
    return Case(m, con, pose_vector(m, {cam: [*r1, th1], fol: [*r2, th2], A_: a0, B_: b0}))


# -- 3D profiles -------------------------------------------------------------------------------

#: a wavy cylinder: radius ``1 + 0.2 sin(2 b)`` about z, height ``b``
DRUM = ((1 + 0.2 * sp.sin(2 * B_)) * sp.cos(A_), (1 + 0.2 * sp.sin(2 * B_)) * sp.sin(A_), B_)
#: a bumpy surface of parameters ``g_cam, d_cam``
BUMP = (G_, D_, 0.3 * sp.sin(G_) * sp.cos(D_) + 0.1 * G_ * D_)
#: a helix of parameter ``a_cam``
HELIX = (sp.cos(A_), sp.sin(A_), 0.3 * A_)


def _cam3(rng, surface=True, follower_points=None):
    m = Model3D()
    cam = m.add_body("cam")
    fol = m.add_body("follower", points=follower_points)
    r1, R1 = rng.uniform(-2, 2, 3), _rand_R(rng)
    if surface:
        vals = [rng.uniform(-np.pi, np.pi), rng.uniform(-1, 1)]
        s, ts = _numeric(DRUM, [A_, B_])(*vals)
    else:
        vals = [rng.uniform(-np.pi, np.pi)]
        s, ts = _numeric(HELIX, [A_])(*vals)
    c = r1 + R1 @ s
    return m, cam, fol, (r1, R1), vals, c, [R1 @ t for t in ts]


@case("CamToPoint1")
def _cam_point_3d(rng):
    p2 = rng.uniform(-1, 1, 3)
    m, cam, fol, (r1, R1), (a0, b0), c, _ = _cam3(rng, follower_points={"p": p2})
    con = m.add(C.CamToPoint1(cam.point(DRUM), (A_, a0), (B_, b0), fol.point("p")))
    R2 = _rand_R(rng)
    r2 = c - R2 @ p2
    return Case(m, con, pose_vector(m, {cam: _pose(r1, R1), fol: _pose(r2, R2), A_: a0, B_: b0}),
                label="CamToPoint1[3D]")


@case("CurveToPoint2")
def _curve_point(rng):
    p2 = rng.uniform(-1, 1, 3)
    m, cam, fol, (r1, R1), (a0,), c, _ = _cam3(rng, surface=False, follower_points={"p": p2})
    con = m.add(C.CurveToPoint2(cam.point(HELIX), (A_, a0), fol.point("p")))
    R2 = _rand_R(rng)
    r2 = c - R2 @ p2
    return Case(m, con, pose_vector(m, {cam: _pose(r1, R1), fol: _pose(r2, R2), A_: a0}))


def _cam_sphere(sign):
    def build(rng):
        p2 = rng.uniform(-1, 1, 3)
        m, cam, fol, (r1, R1), (a0, b0), c, (ta, tb) = _cam3(rng, follower_points={"p": p2})
        rad = sign * rng.uniform(0.2, 0.6)
        con = m.add(C.CamToSphere1(cam.point(DRUM), (A_, a0), (B_, b0), fol.point("p"), rad))
        centre = c + rad * _unit(np.cross(ta, tb))
        R2 = _rand_R(rng)
        r2 = centre - R2 @ p2
        return Case(m, con, pose_vector(m, {cam: _pose(r1, R1), fol: _pose(r2, R2), A_: a0, B_: b0}),
                    label=f"CamToSphere1[radius {'+' if sign > 0 else '-'}]")

    return build


case("CamToSphere1")(_cam_sphere(+1))
case("CamToSphere1")(_cam_sphere(-1))


@case("CamToPlane1")
def _cam_plane(rng):
    o2, u2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    m, cam, fol, (r1, R1), (a0, b0), c, (ta, tb) = _cam3(rng)
    con = m.add(C.CamToPlane1(cam.point(DRUM), (A_, a0), (B_, b0), fol.axis(tuple(o2), tuple(u2))))
    n = _unit(np.cross(ta, tb)) * (1 if rng.integers(0, 2) else -1)
    R2 = _map(u2, _perp(u2, rng), n, _perp(n, rng))
    origin = c + rng.uniform(-1, 1) * _unit(ta) + rng.uniform(-1, 1) * _unit(tb)
    r2 = origin - R2 @ o2
    return Case(m, con, pose_vector(m, {cam: _pose(r1, R1), fol: _pose(r2, R2), A_: a0, B_: b0}))


@case("CamToCam1")
def _cam_cam_3d(rng):
    m, cam, fol, (r1, R1), (a0, b0), c, (ta, tb) = _cam3(rng)
    g0, d0 = rng.uniform(-1, 1, 2)
    con = m.add(C.CamToCam1(cam.point(DRUM), (A_, a0), (B_, b0), fol.point(BUMP), (G_, g0), (D_, d0)))
    s2, (tg, td) = _numeric(BUMP, [G_, D_])(g0, d0)
    n1, n2 = np.cross(ta, tb), np.cross(tg, td)
    sign = 1 if rng.integers(0, 2) else -1
    R2 = _map(n2, _perp(n2, rng), sign * n1, _perp(n1, rng))
    r2 = c - R2 @ s2
    vals = {A_: a0, B_: b0, G_: g0, D_: d0}
    return Case(m, con, pose_vector(m, {cam: _pose(r1, R1), fol: _pose(r2, R2), **vals}),
                label="CamToCam1[3D]")


@case("CurveToCam1")
def _curve_cam(rng):
    m, cam, fol, (r1, R1), (a0,), c, (t1,) = _cam3(rng, surface=False)
    g0, d0 = rng.uniform(-1, 1, 2)
    con = m.add(C.CurveToCam1(cam.point(HELIX), (A_, a0), fol.point(BUMP), (G_, g0), (D_, d0)))
    s2, (tg, td) = _numeric(BUMP, [G_, D_])(g0, d0)
    n2 = np.cross(tg, td)
    # the surface's normal goes to a direction orthogonal to the curve's tangent
    R2 = _map(n2, _perp(n2, rng), _perp(t1, rng), rng.standard_normal(3))
    r2 = c - R2 @ s2
    return Case(m, con, pose_vector(m, {cam: _pose(r1, R1), fol: _pose(r2, R2), A_: a0, G_: g0, D_: d0}))


@case("CurveToPlane1")
def _curve_plane(rng):
    o2, u2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    m, cam, fol, (r1, R1), (a0,), c, (t1,) = _cam3(rng, surface=False)
    con = m.add(C.CurveToPlane1(cam.point(HELIX), (A_, a0), fol.axis(tuple(o2), tuple(u2))))
    n = _perp(t1, rng)  # the plane's normal: any direction orthogonal to the tangent
    R2 = _map(u2, _perp(u2, rng), n, _perp(n, rng))
    origin = c + rng.uniform(-1, 1) * _unit(t1) + rng.uniform(-1, 1) * np.cross(n, _unit(t1))
    r2 = origin - R2 @ o2
    return Case(m, con, pose_vector(m, {cam: _pose(r1, R1), fol: _pose(r2, R2), A_: a0}))


@case("CurveToCylinder1")
def _curve_cylinder(rng):
    o2, u2 = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    m, cam, fol, (r1, R1), (a0,), c, (t1,) = _cam3(rng, surface=False)
    rad = rng.uniform(0.3, 1.0)
    con = m.add(C.CurveToCylinder1(cam.point(HELIX), (A_, a0), fol.axis(tuple(o2), tuple(u2)), rad))
    radial = _perp(t1, rng)  # the cylinder's normal at the contact, orthogonal to the tangent
    w = _perp(radial, rng)  # its axis, orthogonal to that normal
    R2 = _map(u2, _perp(u2, rng), w, _perp(w, rng))
    origin = c - rad * radial + rng.uniform(-1, 1) * w
    r2 = origin - R2 @ o2
    return Case(m, con, pose_vector(m, {cam: _pose(r1, R1), fol: _pose(r2, R2), A_: a0}))
