r"""The default picture of a model: drawn from its bodies' points and its joints.

A first model with no graphics given still shows something sensible:

* every moving body is drawn through its *attachment points* (its origin, its named points,
  its centroid and every point a constraint uses on it): two points give a bar, three or more a plate
  (their convex hull, outlined by bars), collinear points a chain of bars; a body with one
  point is a disc (2D) or a ball (3D), or a slider block when it slides;
* pin-type joints (``Revolute*``, ``Spherical*``, ``Universal*``, ``Cylindrical*``,
  ``OriginLock*``) are small circles (2D) or balls (3D); where one side is ground, a
  hatched ground pivot;
* sliding joints (``Translate*``, ``Prismatic*``) are a block on the sliding body and,
  when the guide is on ground, rails over the travel range;
* distance constraints (``RelativeDistance*``) are drawn as a grey link between their
  points, ``PointOnLine*`` as a dashed guide line.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..geometry._points import Axis, Line, Point, Vector
from . import _shapes as sh
from ._eval import Evaluator, Item
from ._primitives import (
    GROUND_COLOR,
    JOINT_COLOR,
    L_BODY,
    L_GROUND,
    L_GUIDE,
    L_JOINT,
    L_PLATE_EDGE,
    GroundPivot,
    PitchCircle,
    Primitive,
    body_color,
)

PIN = ("Revolute", "Spherical", "Universal", "Cylindrical", "OriginLock", "Coincident")
SLIDE = ("Translate", "Prismatic")
LINK = ("RelativeDistance",)
ON_LINE = ("PointOnLine",)


def _kind(c) -> str | None:
    name = type(c).__name__.removeprefix("Gen")  # a Gen joint is drawn as the joint it replaces
    for words, kind in ((PIN, "pin"), (SLIDE, "slide"), (LINK, "link"), (ON_LINE, "online")):
        if any(name.startswith(w) for w in words):
            return kind
    return None


def _points_of(geometry) -> list[Point]:
    out = []
    for g in geometry:
        if isinstance(g, Point):
            out.append(g)
        elif isinstance(g, Line):
            out.extend(g.points)
        elif isinstance(g, Axis):
            out.append(g.origin)
        elif isinstance(g, Vector) and g.points is not None:
            out.extend(g.points)
    return out


def _is_ground(p: Point) -> bool:
    return p.body is None or p.body.is_ground


def _unique(rows: list[np.ndarray], tol: float) -> np.ndarray:
    out: list[np.ndarray] = []
    for r in rows:
        if all(np.linalg.norm(r - o) > tol for o in out):
            out.append(r)
    return np.array(out)


class Skeleton(Primitive):
    """The default drawing of a model (see the module notes). ``width``: bar width
    (default 3.5 % of the picture size); ``joints``/``ground``: draw joint markers and
    ground symbols."""

    def __init__(self, width=None, joints=True, ground=True, **style):
        super().__init__(**style)
        self.width, self.joints, self.ground = width, joints, ground

    def _request(self, ev: Evaluator):
        model, dim = ev.model, ev.dim
        attach: dict[int, list] = {id(b): [b, [np.zeros(dim)]] for b in model.bodies[1:]}
        pins, slides, links, onlines = [], [], [], []
        for c in model.constraints:
            kind = _kind(c)
            geom = c.geometry()
            for p in _points_of(geom):
                if _is_ground(p):
                    continue
                loc = ev.numeric_local(p.local)
                if loc is not None and id(p.body) in attach:
                    attach[id(p.body)][1].append(loc)
            if kind == "pin":
                pts = _points_of(geom)
                if pts:
                    pins.append(pts)
            elif kind == "slide" and len(geom) >= 2 and all(isinstance(g, Axis) for g in geom[:2]):
                slides.append((geom[0], geom[1]))
            elif kind == "link":
                pts = [g for g in geom if isinstance(g, Point)]
                if len(pts) == 2:
                    links.append(pts)
            elif kind == "online":
                pts = [g for g in geom if isinstance(g, Point)]
                axes = [g for g in geom if isinstance(g, Axis)]
                if pts and axes:
                    onlines.append((pts[0], axes[0]))
        for b in model.bodies[1:]:
            extra = list(b.points.values())
            centroid = getattr(b, "centroid", None)
            if centroid is not None and len(centroid) == dim:
                extra.append(centroid)  # a pendulum's rod reaches its centre of mass
            for loc in extra:
                v = ev.numeric_local(loc)
                if v is not None:
                    attach[id(b)][1].append(v)

        finishers = []
        sliding = set()
        for a1, a2 in slides:
            for a in (a2, a1):
                if not _is_ground(a.origin):
                    sliding.add(id(a.origin.body))
                    break
        for b, locs in attach.values():
            finishers.append(self._body(ev, b, locs, id(b) in sliding))
        for a1, a2 in slides:
            finishers.append(self._slide(ev, a1, a2))
        for p1, p2 in links:
            finishers.append(self._link(ev, p1, p2))
            if self.joints:
                finishers += [self._pin(ev, [p1]), self._pin(ev, [p2])]
        for p, axis in onlines:
            finishers.append(self._online(ev, p, axis))
        for c in model.constraints:
            for centre, radius in getattr(c, "pitch_circles", lambda: [])():
                finishers += self._gear(ev, centre, radius)
        if self.joints:
            for pts in pins:
                finishers.append(self._pin(ev, pts))
        if self.ground:
            seen: list[np.ndarray] = []
            for pts in pins:
                for p in pts:
                    loc = ev.numeric_local(p.local)
                    if _is_ground(p) and loc is not None and all(
                            np.linalg.norm(loc - s) > 1e-9 for s in seen):
                        seen.append(loc)
                        finishers.append(GroundPivot(p)._prepare(ev))

        def finish():
            items: list[Item] = []
            for f in finishers:
                items.extend(f())
            return items

        return finish

    # -- parts ----------------------------------------------------------------------------
    def _gear(self, ev, centre, radius) -> list:
        """A gear wheel of a gear constraint: its pitch circle with a tooth mark (skipped when
        the radius or centre is not a number at the drawn parameters)."""
        try:
            r = abs(float(sp.sympify(radius).xreplace(ev._psubs)))
        except (TypeError, ValueError):
            return []
        if isinstance(centre, Axis):
            p, axis = centre.origin, getattr(centre.dir, "local", None)
            if axis is None or getattr(centre.dir, "body", None) is not p.body:
                return []
            axis = ev.numeric_local(axis)
        else:
            p, axis = centre, None
        loc = ev.numeric_local(p.local)
        if loc is None or not r > 0 or (axis is None and ev.dim == 3):
            return []
        body = p.body if p.body is not None else ev.model.ground
        kw = {} if axis is None else {"axis": tuple(axis)}
        return [PitchCircle(body, tuple(loc), r, **kw)._prepare(ev)]

    def _w(self, ev) -> float:
        return float(self.width) if self.width is not None else 0.035 * ev.size

    def _body(self, ev, b, locs, slides: bool):
        pose = ev.pose(b)
        color = body_color(b)
        dim = ev.dim

        def finish():
            w = self._w(ev)
            pts = _unique(locs, 1e-9 * max(ev.size, 1e-12))
            d = {"color": color}
            if len(pts) == 1:
                if slides:
                    return []  # the slider block draws it
                if dim == 2:
                    return [self._rigid("polygon", pose, sh.circle(pts[0], 0.9 * w, 24), d, L_BODY)]
                v, f = sh.sphere(pts[0], 0.9 * w, 12)
                return [self._rigid("mesh", pose, v, d, L_BODY, faces=f)]
            if dim == 2 and len(pts) >= 3:
                hull = sh.convex_hull_2d(pts)
                area = _area(pts[hull]) if len(hull) >= 3 else 0.0
                ext = np.ptp(pts, axis=0).max()
                if len(hull) >= 3 and area > 1e-3 * ext**2:
                    poly = pts[hull]
                    items = [self._rigid("polygon", pose, poly, {"color": color, "alpha": 0.45,
                                                                  "edgecolor": "none"}, L_BODY)]
                    for i in range(len(poly)):
                        a, c = poly[i], poly[(i + 1) % len(poly)]
                        items.append(self._rigid("polygon", pose, sh.stadium(a, c, w), d,
                                                 L_PLATE_EDGE))
                    return items
            items = []
            for i, j in sh.spanning_tree(pts):
                if dim == 2:
                    items.append(self._rigid("polygon", pose, sh.stadium(pts[i], pts[j], w), d,
                                             L_BODY))
                else:
                    v, f = sh.beam(pts[i], pts[j], 0.8 * w)
                    items.append(self._rigid("mesh", pose, v, d, L_BODY, faces=f))
            return items

        return finish

    def _pin(self, ev, pts: list[Point]):
        moving = [p for p in pts if not _is_ground(p)]
        if not moving:
            return lambda: []
        p = moving[0]
        loc = ev.numeric_local(p.local)
        if loc is None:
            geo = ev.points([p])
            pose = None
        else:
            pose = ev.pose(p.body)

        def finish():
            r = 0.022 * ev.size if self.width is None else 0.6 * float(self.width)
            if ev.dim == 2:
                d = {"color": "white", "edgecolor": JOINT_COLOR, "linewidth": 1.2}
                if pose is not None:
                    return [self._rigid("polygon", pose, sh.circle(loc, r, 20), d, L_JOINT)]
                c = geo.xyz[:, 0, :]
                ring = c[:, None, :] + sh.circle((0, 0), r, 20)[None]
                return [self._item("polygon", ring, d, L_JOINT)]
            d = {"color": JOINT_COLOR}
            v, f = sh.sphere(loc if pose is not None else np.zeros(3), 1.3 * r, 12)
            if pose is not None:
                return [self._rigid("mesh", pose, v, d, L_JOINT, faces=f)]
            return [self._item("mesh", geo.xyz[:, 0:1, :] + v[None], d, L_JOINT, faces=f)]

        return finish

    def _slide(self, ev, a1: Axis, a2: Axis):
        guide, mover = (a1, a2) if _is_ground(a1.origin) or not _is_ground(a2.origin) else (a2, a1)
        if _is_ground(mover.origin):
            return lambda: []
        b = mover.origin.body
        o = ev.numeric_local(mover.origin.local)
        u = ev.numeric_local(mover.dir.local) if mover.dir.points is None and (
            mover.dir.body is None or mover.dir.body is b) else None
        pose = ev.pose(b)
        track: list = []
        if _is_ground(guide.origin):
            go = ev.numeric_local(guide.origin.local)
            gd = ev.numeric_local(guide.dir.local) if guide.dir.points is None else None

            def compute():
                path = np.asarray(ev.full.eval(mover.origin.location()), dtype=float)
                track.append(path.reshape(-1, ev.dim))

            if go is not None and gd is not None:
                ev.later(compute)
        else:
            go = gd = None

        def finish():
            items: list[Item] = []
            a, h = 0.07 * ev.size, 0.04 * ev.size
            if o is not None and u is not None and np.linalg.norm(u) > 0:
                uu = u / np.linalg.norm(u)
                if ev.dim == 2:
                    nn = np.array([-uu[1], uu[0]])
                    block = np.array([o - a * uu - h * nn, o + a * uu - h * nn,
                                      o + a * uu + h * nn, o - a * uu + h * nn])
                    items.append(self._rigid("polygon", pose, block, {"color": body_color(b)},
                                             L_BODY))
                else:
                    e1, e2, e3 = sh.perpendicular_frame(uu)
                    v, f = sh.oriented_box(o, e1, e2, e3, h, h, a)
                    items.append(self._rigid("mesh", pose, v, {"color": body_color(b)}, L_BODY,
                                             faces=f))
            if track and np.linalg.norm(gd) > 0:
                g = gd / np.linalg.norm(gd)
                s = (track[0] - go) @ g
                s = s[np.isfinite(s)]
                if s.size:
                    s0, s1 = s.min() - 1.4 * a, s.max() + 1.4 * a
                    if ev.dim == 2:
                        n = np.array([-g[1], g[0]])
                        # the rails: the guide line's offset of the block centre
                        off = float(np.median((track[0] - go) @ n))
                        lines = []
                        for side in (-1, 1):
                            c = go + (off + side * 1.08 * h) * n
                            lines += [c + s0 * g, c + s1 * g, [np.nan] * 2]
                        c = go + (off - 1.08 * h) * n
                        for t in np.linspace(s0, s1, max(int((s1 - s0) / (0.7 * h)), 2)):
                            lines += [c + t * g, c + (t - 0.6 * h) * g - 0.6 * h * n, [np.nan] * 2]
                        items.append(self._item("line", np.array(lines)[None],
                                                {"color": GROUND_COLOR, "linewidth": 1.0},
                                                L_GROUND))
                    else:
                        rail = np.array([go + s0 * g, go + s1 * g])
                        items.append(self._item("line", rail[None],
                                                {"color": GROUND_COLOR, "linewidth": 2.0},
                                                L_GUIDE))
            return items

        return finish

    def _link(self, ev, p1: Point, p2: Point):
        geo = ev.points([p1, p2])

        def finish():
            P = geo.xyz
            d = {"color": "#8c8c8c"}
            if ev.dim == 2:
                return [self._item("polygon", sh.stadium(P[:, 0], P[:, 1], 0.8 * self._w(ev)), d,
                                   L_BODY)]
            return [self._item("line", P, {**d, "linewidth": 4.0}, L_BODY)]

        return finish

    def _online(self, ev, p: Point, axis: Axis):
        if not _is_ground(axis.origin) or axis.dir.points is not None:
            return lambda: []
        go = ev.numeric_local(axis.origin.local)
        gd = ev.numeric_local(axis.dir.local)
        track: list = []
        if go is None or gd is None:
            return lambda: []
        ev.later(lambda: track.append(np.asarray(ev.full.eval(p.location()),
                                                 dtype=float).reshape(-1, ev.dim)))

        def finish():
            g = gd / np.linalg.norm(gd)
            s = (track[0] - go) @ g
            s = s[np.isfinite(s)]
            if not s.size:
                return []
            pad = 0.05 * ev.size
            line = np.array([go + (s.min() - pad) * g, go + (s.max() + pad) * g])
            return [self._item("line", line[None], {"color": GROUND_COLOR, "linestyle": "--",
                                                    "linewidth": 1.0}, L_GUIDE)]

        return finish


def _area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


__all__ = ["Skeleton"]
