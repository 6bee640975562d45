"""Conformance cases for the gear constraint types (Mech 6.2): configurations built by hand
from the definition of each gear set (centre distance, phase constant ``C``), not solved."""

from __future__ import annotations

import numpy as np

from .. import constraints as C
from .._symbols import T
from ..model import Model2D, Model3D
from ._cases_planar import _rot
from ._cases_spatial import _axis_local, _perp, _place_axis, _rand_R, _unit
from ._cases_spatial import _pose as _pose3
from ._cases_spatial import _two as _two3
from ._checks import Case, case, pose_vector

# -- 2D ---------------------------------------------------------------------------------------


def _wheels(rng, kind, r1, r2, Cc, *, dist=None, explicit=False, sign=1, distance=True):
    """Two gear (pulley) bodies with centres at local points; the line of centres at angle
    ``Th``, ``|r1 + sign r2|`` (or ``dist``) long, phases from ``C``."""
    s1, s2 = rng.uniform(-0.5, 0.5, 2), rng.uniform(-0.5, 0.5, 2)
    m = Model2D()
    b1 = m.add_body("g1", points={"c": s1})
    b2 = m.add_body("g2", points={"c": s2})
    extra = (dist,) if dist is not None else ()
    var = [("th_c", 0.3)] if explicit else []
    c = m.add(kind(b1.point("c"), r1, *var, b2.point("c"), r2, *extra, Cc))
    Th = rng.uniform(-np.pi, np.pi)
    rho = abs(dist) if dist is not None else abs(r1 + sign * r2)
    if not distance:
        rho = rng.uniform(0.5, 2.0)
    c1 = rng.uniform(-1, 1, 2)
    c2 = c1 + rho * np.array([np.cos(Th), np.sin(Th)])
    th1 = rng.uniform(-3, 3)
    th2 = Th + (Cc - r1 * (th1 - Th)) / (sign * r2)
    # the variable: the line of centres' angle, or in Euler coordinates (Mech's Euler form)
    # the angle e1 from the line of centres to wheel 1's x axis
    var_value = th1 - Th if m.orientation == "euler" else Th
    q = pose_vector(m, {b1: [*(c1 - _rot(th1) @ s1), th1], b2: [*(c2 - _rot(th2) @ s2), th2],
                        c.alpha: var_value})
    return Case(m, c, q)


@case("TwoGears1")
def _tg1(rng):
    return _wheels(rng, C.TwoGears1, 0.7, 1.3, 0.4, distance=False)


@case("TwoGears1")
def _tg1_named(rng):
    return _wheels(rng, C.TwoGears1, 0.5, -1.6, -0.2, explicit=True, distance=False)


@case("TwoGears2")
def _tg2(rng):
    return _wheels(rng, C.TwoGears2, 0.7, 1.3, 0.4)


@case("TwoGears2")
def _tg2_internal(rng):
    return _wheels(rng, C.TwoGears2, 0.5, -1.6, 0.9, explicit=True)


@case("TwoPulleys1")
def _tp1(rng):
    return _wheels(rng, C.TwoPulleys1, 0.6, 1.1, 0.3, dist=2.5, sign=-1, distance=False)


@case("TwoPulleys2")
def _tp2(rng):
    return _wheels(rng, C.TwoPulleys2, 0.6, 1.1, 0.3, dist=2.5, sign=-1)


@case("TwoPulleys2")
def _tp2_named(rng):
    return _wheels(rng, C.TwoPulleys2, 1.2, 0.4, -0.5, dist=3.0, sign=-1, explicit=True)


def _rack(rng, kind, rad, Cc, *, explicit=False, distance=True, moving=True):
    """A pinion (centre at a local point) on a rack axis of body 2 (or a driven ground axis)."""
    sp_ = rng.uniform(-0.5, 0.5, 2)
    m = Model2D()
    pin = m.add_body("pinion", points={"c": sp_})
    o_l, u_l = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2)
    if moving:
        rack = m.add_body("rack")
        axis = rack.axis(tuple(o_l), tuple(u_l))
        r2, th2 = rng.uniform(-1, 1, 2), rng.uniform(-np.pi, np.pi)
    else:
        rack = None
        axis = m.ground.axis(tuple(o_l), tuple(u_l))
        r2, th2 = np.zeros(2), 0.0
    var = [("a_c", 0.1)] if explicit else []
    c = m.add(kind(pin.point("c"), rad, *var, axis, Cc))
    o = r2 + _rot(th2) @ o_l
    g = _rot(th2) @ _unit(u_l)
    k = np.array([-g[1], g[0]])
    alpha = rng.uniform(-2, 2)
    s = Cc - rad * alpha
    h = rad if distance else rng.uniform(-1, 1)
    p = o + s * g + h * k
    th1 = th2 + np.arctan2(u_l[1], u_l[0]) + alpha
    poses = {pin: [*(p - _rot(th1) @ sp_), th1]}
    if rack is not None:
        poses[rack] = [*r2, th2]
    if c.alpha is not None:          # explicit, or always in Euler coordinates
        poses[c.alpha] = alpha
    return Case(m, c, pose_vector(m, poses))


@case("RackAndPinion1")
def _rp1(rng):
    return _rack(rng, C.RackAndPinion1, 0.8, 0.3, distance=False)


@case("RackAndPinion1")
def _rp1_named(rng):
    return _rack(rng, C.RackAndPinion1, 0.8, -0.3, distance=False, explicit=True)


@case("RackAndPinion2")
def _rp2(rng):
    return _rack(rng, C.RackAndPinion2, 0.8, 0.3)


@case("RackAndPinion2")
def _rp2_ground(rng):
    return _rack(rng, C.RackAndPinion2, 0.6, 1.1, moving=False)


@case("RackAndPinion2")
def _rp2_named(rng):
    return _rack(rng, C.RackAndPinion2, 0.8, 0.3, explicit=True)


# -- 3D ---------------------------------------------------------------------------------------


def _body_axes(rng, refs=False):
    m, b1, b2 = _two3()
    o1, u1 = rng.uniform(-0.5, 0.5, 3), rng.uniform(-1, 1, 3)
    o2, u2 = rng.uniform(-0.5, 0.5, 3), rng.uniform(-1, 1, 3)
    if refs:
        a1 = b1.axis(tuple(o1), tuple(u1), tuple(rng.uniform(-1, 1, 3)))
        a2 = b2.axis(tuple(o2), tuple(u2), tuple(rng.uniform(-1, 1, 3)))
    else:
        a1, a2 = b1.axis(tuple(o1), tuple(u1)), b2.axis(tuple(o2), tuple(u2))
    return m, b1, b2, a1, a2


def _turn(g, u, a):
    """``g`` turned by ``a`` about unit ``u``."""
    return np.cos(a) * g + np.sin(a) * np.cross(u, g)


def _parallel_gears(rng, kind, r1, r2, Cc, *, adjacent=True, refs=False, explicit=False,
                    dist=None):
    """Gears (``dist=None``: centres ``|r1 + r2|`` apart, ``C = r1 e1 + r2 e2``) or pulleys
    (centres ``dist`` apart, ``C = r1 e1 - r2 e2``)."""
    m, b1, b2, a1, a2 = _body_axes(rng, refs)
    var = [("al_c", 0.2)] if explicit else []
    extra = () if dist is None else (dist,)
    c = m.add(kind(a1, r1, *var, a2, r2, *extra, Cc))
    R1 = _rand_R(rng)
    O1 = rng.uniform(-1, 1, 3)
    o1l, u1l, g1l = _axis_local(a1)
    u = R1 @ _unit(u1l)
    g1 = R1 @ g1l
    o1 = O1 + R1 @ o1l
    w = _perp(u, rng)                                     # direction of d across the axes
    slide = 0.0 if adjacent else rng.uniform(-1, 1)
    o2 = o1 + (abs(r1 + r2) if dist is None else dist) * w + slide * u
    e1 = np.arctan2(np.cross(w, g1) @ u, w @ g1)          # angle from d to g1 about u
    e2 = (Cc - r1 * e1) / r2 if dist is None else (r1 * e1 - Cc) / r2
    q = pose_vector(m, {b1: _pose3(O1, R1), b2: _place_axis(a2, o2, u, _turn(w, u, e2), rng),
                        c.alpha: e1})
    return Case(m, c, q)


@case("ParallelGears5")
def _pg5(rng):
    return _parallel_gears(rng, C.ParallelGears5, 0.6, 1.4, 0.5)


@case("ParallelGears5")
def _pg5_internal(rng):
    return _parallel_gears(rng, C.ParallelGears5, 0.5, -1.7, -0.3, refs=True, explicit=True)


@case("ParallelGears4")
def _pg4(rng):
    return _parallel_gears(rng, C.ParallelGears4, 0.6, 1.4, 0.5, adjacent=False)


@case("TwoPulleys5")
def _tp5(rng):
    return _parallel_gears(rng, C.TwoPulleys5, 0.6, 1.4, 0.5, dist=2.7)


@case("TwoPulleys5")
def _tp5_equal(rng):
    return _parallel_gears(rng, C.TwoPulleys5, 0.8, 0.8, -0.2, dist=1.9, refs=True,
                           explicit=True)


@case("TwoPulleys4")
def _tp4(rng):
    return _parallel_gears(rng, C.TwoPulleys4, 0.6, 1.4, 0.5, adjacent=False, dist=2.7)


def _orthogonal(rng, t1, t2, Cc, dist=None, explicit=False):
    m, b1, b2, a1, a2 = _body_axes(rng, refs=True)
    var = [("al_c", 0.2)] if explicit else []
    extra = (dist,) if dist is not None else ()
    c = m.add(C.OrthogonalGears5(a1, t1, *var, a2, t2, *extra, Cc))
    R2, O2 = _rand_R(rng), rng.uniform(-1, 1, 3)
    o2l, u2l, g2l = _axis_local(a2)
    u2, g2, o2 = R2 @ _unit(u2l), R2 @ g2l, O2 + R2 @ o2l
    u1 = _perp(u2, rng)
    e2 = np.arctan2(np.cross(u1, g2) @ u2, u1 @ g2)       # angle from u1 to g2 about u2
    e1 = (Cc - t2 * e2) / t1
    o1 = o2 + (dist or 0.0) * np.cross(u1, u2)
    q = pose_vector(m, {b1: _place_axis(a1, o1, u1, _turn(u2, u1, e1), rng),
                        b2: _pose3(O2, R2), c.alpha: e1})
    return Case(m, c, q)


@case("OrthogonalGears5")
def _og5(rng):
    return _orthogonal(rng, 12, 30, 0.7)


@case("OrthogonalGears5")
def _og5_worm(rng):
    return _orthogonal(rng, 1, -40, 0.2, dist=0.45, explicit=True)


@case("LeadScrew5")
def _ls5(rng, pitch=0.25, Cc=0.3):
    m, b1, b2, a1, a2 = _body_axes(rng, refs=True)
    c = m.add(C.LeadScrew5(a1, ("al_c", 0.1), a2, pitch, Cc))
    R2, O2 = _rand_R(rng), rng.uniform(-1, 1, 3)
    o2l, u2l, g2l = _axis_local(a2)
    u, g2, o2 = R2 @ _unit(u2l), R2 @ g2l, O2 + R2 @ o2l
    alpha = rng.uniform(-4, 4)
    o1 = o2 + (Cc + pitch * alpha / (2 * np.pi)) * u
    q = pose_vector(m, {b1: _place_axis(a1, o1, u, _turn(g2, u, alpha), rng),
                        b2: _pose3(O2, R2), c.alpha: alpha})
    return Case(m, c, q)


def _rack3(rng, kind, rad, Cc, adjacent=True, driven=False):
    m, b1, b2, a1, a2 = _body_axes(rng, refs=True)
    if driven:
        # a rack on ground moving with time along its travel, the pinion alone
        m = Model3D()
        b1 = m.add_body("b1")
        a1 = b1.axis(tuple(rng.uniform(-0.5, 0.5, 3)), tuple(rng.uniform(-1, 1, 3)))
        a2 = m.ground.axis((0.3 * T, 0, 0.1), (0, 0, 1), (1, 0, 0))
    c = m.add(kind(a1, rad, a2, Cc))
    t = 0.3
    if driven:
        o2, u2, g2 = np.array([0.3 * t, 0, 0.1]), np.array([0, 0, 1.0]), np.array([1.0, 0, 0])
        poses = {}
    else:
        R2, O2 = _rand_R(rng), rng.uniform(-1, 1, 3)
        o2l, u2l, g2l = _axis_local(a2)
        u2, g2, o2 = R2 @ _unit(u2l), R2 @ g2l, O2 + R2 @ o2l
        poses = {b2: _pose3(O2, R2)}
    k2 = np.cross(u2, g2)
    alpha = rng.uniform(-3, 3)
    o1 = o2 + rad * k2 + (Cc - rad * alpha) * g2 + (0 if adjacent else rng.uniform(-1, 1)) * u2
    poses[b1] = _place_axis(a1, o1, u2, _turn(g2, u2, alpha), rng)
    poses[c.alpha] = alpha
    return Case(m, c, pose_vector(m, poses), t=t)


@case("RackAndPinion5")
def _rp5(rng):
    return _rack3(rng, C.RackAndPinion5, 0.7, 0.4)


@case("RackAndPinion5")
def _rp5_driven(rng):
    return _rack3(rng, C.RackAndPinion5, 0.5, -0.2, driven=True)


@case("RackAndPinion4")
def _rp4(rng):
    return _rack3(rng, C.RackAndPinion4, 0.7, 0.4, adjacent=False)


__all__: list[str] = []
