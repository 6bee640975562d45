r"""Graphics primitives with Mech's names.

Each primitive holds geometry on a body (local points, sizes) or global SymPy expressions,
and yields global coordinates at every frame of a solution through the scene's
:class:`~mechsys.draw._eval.Evaluator` (one compiled :meth:`Solution.eval` call for the
whole picture). Body-fixed shapes are built once in local coordinates and placed by the
body pose ``r + A s'``.

Forms, following Mech (``bnum`` there is a body handle, name or number here):

==================  ======================================================================
``Bar``             ``Bar(body, (p1, p2), width=None)``: round-ended bar (2D) or
                    rectangular beam (3D) between two points of a body
``Box``             ``Box(body, corner1, corner2)``: rectangle (2D) / box (3D), diagonal
                    corners in body coordinates
``Facet``           ``Facet(body, [p1, p2, ...])`` or ``Facet([point1, point2, ...])``:
                    filled polygon (vertices may lie on different bodies)
``Edge``            ``Edge(body, [p1, ...], closed=False)`` / ``Edge([point1, ...])``: lines
``Vertex``          ``Vertex(body, [p1, ...])`` / ``Vertex([point1, ...])``: point markers
``Wheel``           ``Wheel(body, center, radius, spokes=6)``: wheel with spokes
``Arrow``           ``Arrow(point, vector, scale=1, head_size=None)``: any vector
                    (a ``Vector``, a SymPy expression, or a callable of the solution)
``LocalAxes``       ``LocalAxes(bodies="all", size=None)``: body axes x, y (z) in red,
                    green (blue)
``PointLabel``      ``PointLabel(body, "all")`` / ``PointLabel([point1, ...])``
``LocusPlot``       ``LocusPlot(point, solution=None, trail=False)``: path of a point
``InstantCenter``   ``InstantCenter(body, to=None)``: planar instant centre (needs velocities)
``Extrude``         ``Extrude(body, [p1, ...], vector, dist)`` (3D)
``Revolve``         ``Revolve(body, [(r, h), ...], axis=(origin, direction))`` (3D)
``Sphere``          ``Sphere(body, center, radius)`` (3D)
``Torus``           ``Torus(body, center, major, minor, axis=(0, 0, 1))`` (3D)
``Cylinder``        ``Cylinder(body, p1, p2, radius)`` (3D)
``GroundPivot``     ``GroundPivot(point)``: hatched ground symbol at a fixed point
==================  ======================================================================

Every primitive takes style keywords (``color``, ``edgecolor``, ``alpha``, ``linewidth``,
``linestyle``, ``marker``, ``markersize``, ``fontsize``, ``layer``, ``label``) and
``faces=True|False`` (Mech's ``Faces`` option: filled, or wire frame).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import sympy as sp

from .._errors import GeometryError, ModelError
from .._signature import InitSignature
from ..geometry._points import Axis, Point, Vector, as_point
from . import _shapes as sh
from ._eval import Evaluator, Item, check_style, resolve_points

#: the most segments, spokes or teeth of one primitive: a picture needs no more, and a model
#: file from a stranger must not make one of a billion (issue 39)
MAX_SEGMENTS = 1000
#: the most samples of a plotted curve or surface parameter
MAX_SAMPLES = 10_000


def _count(value, what: str, low: int, high: int = MAX_SEGMENTS) -> int:
    """``value`` as an integer count in ``[low, high]``, else :class:`~mechsys.ModelError`
    naming ``what`` and the limit."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not np.isfinite(value) or value != int(value) or not low <= value <= high:
        raise ModelError(f"{what} must be a whole number from {low} to {high}, got {value!r}")
    return int(value)

PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#17becf", "#bcbd22", "#7f7f7f")
GROUND_COLOR = "#4d4d4d"
JOINT_COLOR = "#222222"
AXIS_COLORS = ("#d62728", "#2ca02c", "#1f77b4")

# drawing layers (higher on top)
L_GUIDE, L_GROUND, L_BODY, L_PLATE_EDGE, L_LOCUS, L_JOINT, L_ARROW, L_AXES, L_LABEL = range(9)


def body_color(body) -> str:
    """The default colour of a body (by its Mech number; ground is dark grey)."""
    if body is None or body.is_ground:
        return GROUND_COLOR
    return PALETTE[(body.number - 2) % len(PALETTE)]


def _dark(hex_color: str, f: float = 0.55) -> str:
    """A darker shade of a '#rrggbb' colour (loci show over their own body)."""
    r, g, b = (int(hex_color[i : i + 2], 16) for i in (1, 3, 5))
    return "#{:02x}{:02x}{:02x}".format(*(int(c * f) for c in (r, g, b)))


class Primitive:
    """Base of graphics primitives. Subclasses implement ``_request(ev)`` which registers
    what must be evaluated and returns a function building the :class:`Item` list."""

    #: the model dimensions a primitive works in
    dims: tuple[int, ...] = (2, 3)

    # the signature shown by help() and the API reference is __init__'s, not __new__'s
    __signature__ = InitSignature()

    def __new__(cls, *args, **kwargs):
        # the constructor's arguments, kept for model files (mechsys.io)
        self = super().__new__(cls)
        self._init_args = (args, kwargs)
        return self

    def __init__(self, **style):
        self.style = check_style(style, type(self).__name__)

    # -- used by scenes -------------------------------------------------------------------
    def _prepare(self, ev: Evaluator) -> Callable[[], list[Item]]:
        if ev.dim not in self.dims:
            other = "planar" if ev.dim == 3 else "spatial"
            raise ModelError(f"{type(self).__name__} is a {other}-only primitive; "
                             f"this model is {ev.dim}D")
        return self._request(ev)

    def _request(self, ev: Evaluator) -> Callable[[], list[Item]]:  # pragma: no cover
        raise NotImplementedError

    # -- helpers --------------------------------------------------------------------------
    def _item(self, kind, xyz, defaults: dict, layer: int, **kw) -> Item:
        style = dict(defaults)
        style.update(self.style)
        layer = int(style.pop("layer", layer))
        return Item(kind=kind, xyz=np.asarray(xyz, dtype=float), style=style, layer=layer, **kw)

    def _rigid(self, kind, pose, local, defaults, layer, **kw) -> Item:
        local = np.asarray(local, dtype=float)
        return self._item(kind, pose.place(local), defaults, layer, rigid=(pose, local), **kw)

    def __repr__(self) -> str:
        return f"<{type(self).__name__}>"


def _body(ev: Evaluator, spec):
    return ev.model.body(spec)


def _locals_on(ev: Evaluator, body, specs, who: str) -> np.ndarray:
    """Constant local coordinates ``(k, dim)`` of point specs on ``body``."""
    pts = resolve_points(ev.model, body, specs, who)
    out = []
    for p in pts:
        if p.body is not None and p.body is not body and not (body.is_ground and p.body.is_ground):
            raise GeometryError(f"{who}: point {p!r} is not on body {body.name!r}")
        loc = ev.numeric_local(p.local)
        if loc is None:
            raise GeometryError(
                f"{who} on body {body.name!r}: local point {tuple(p.local)} depends on time or "
                "coordinates; body shapes need constant local geometry (use Edge/Facet/Vertex "
                "for moving points)")
        out.append(loc)
    return np.array(out, dtype=float)


def _local_vector(ev: Evaluator, body, v, who: str) -> np.ndarray:
    if isinstance(v, Vector):
        if v.points is not None or (v.body is not None and v.body is not body):
            raise GeometryError(f"{who}: give the direction in the coordinates of body {body.name!r}")
        v = v.local
    loc = ev.numeric_local(sp.Matrix(list(v)))
    if loc is None or len(loc) != ev.dim:
        raise GeometryError(f"{who}: direction {v!r} must be {ev.dim} constant components")
    return loc


def _split_body_points(body_or_points, points):
    """``(body, points)`` from Mech's two forms ``F(body, pts)`` and ``F([point1, ...])``."""
    from ..geometry._bodies import Body

    if points is None:
        if isinstance(body_or_points, (Body, str, int)) and not isinstance(body_or_points, bool):
            return body_or_points, "all"
        return None, body_or_points
    return body_or_points, points


def _point_specs(ev: Evaluator, body_spec, points, who: str) -> list[Point]:
    body = _body(ev, body_spec) if body_spec is not None else None
    if isinstance(points, str) and points == "all":
        if body is None:
            raise ModelError(f"{who}: 'all' needs a body")
        names = list(body.points)
        if not names:
            return [body.point(0)]
        return [body.point(n) for n in names]
    return resolve_points(ev.model, body, points, who)


def _fmt(v) -> str:
    return "(" + ", ".join(f"{float(c):g}" for c in v) + ")"


# ----------------------------------------------------------------------------------------
# Planar and spatial primitives
# ----------------------------------------------------------------------------------------
class Bar(Primitive):
    """A bar between two points of a body: round-ended (2D) or a rectangular beam (3D).

    ``width`` defaults to 3.5 % of the picture size; ``thickness`` (3D) to the width.
    """

    def __init__(self, body, points=(0, 1), width=None, thickness=None, **style):
        super().__init__(**style)
        self.body, self.points = body, points
        self.width, self.thickness = width, thickness

    def _request(self, ev):
        b = _body(ev, self.body)
        loc = _locals_on(ev, b, list(self.points), "Bar")
        if len(loc) != 2:
            raise GeometryError(f"Bar on body {b.name!r} needs exactly two points, got {len(loc)}")
        pose = ev.pose(b)

        def finish():
            w = float(self.width) if self.width is not None else 0.035 * ev.size
            if ev.dim == 2:
                outline = sh.stadium(loc[0], loc[1], w)
                return [self._rigid("polygon", pose, outline, {"color": body_color(b)}, L_BODY)]
            if np.allclose(loc[0], loc[1]):
                verts, faces = sh.box(loc[0] - w / 2, loc[0] + w / 2)
            else:
                verts, faces = sh.beam(loc[0], loc[1], w, self.thickness)
            return [self._rigid("mesh", pose, verts, {"color": body_color(b)}, L_BODY,
                                faces=faces)]

        return finish


class Box(Primitive):
    """A rectangle (2D) or box (3D) with diagonal corners given in body coordinates."""

    def __init__(self, body, corner1, corner2, **style):
        super().__init__(**style)
        self.body, self.corners = body, (corner1, corner2)

    def _request(self, ev):
        b = _body(ev, self.body)
        c = _locals_on(ev, b, list(self.corners), "Box")
        pose = ev.pose(b)

        def finish():
            if ev.dim == 2:
                return [self._rigid("polygon", pose, sh.rectangle(c[0], c[1]),
                                    {"color": body_color(b)}, L_BODY)]
            verts, faces = sh.box(c[0], c[1])
            return [self._rigid("mesh", pose, verts, {"color": body_color(b)}, L_BODY, faces=faces)]

        return finish


class _VertexList(Primitive):
    kind = "line"
    layer = L_BODY

    def __init__(self, body_or_points, points=None, **style):
        super().__init__(**style)
        self.body, self.points = _split_body_points(body_or_points, points)

    def _color(self, ev, pts):
        bodies = {id(p.body): p.body for p in pts}
        if len(bodies) == 1:
            return body_color(next(iter(bodies.values())))
        return GROUND_COLOR

    def _request(self, ev):
        pts = _point_specs(ev, self.body, self.points, type(self).__name__)
        geo = ev.points(pts)

        def finish():
            return [self._item(self.kind, geo.xyz, self._defaults(ev, pts), self.layer,
                               rigid=geo.rigid, **self._extra(pts))]

        return finish

    def _defaults(self, ev, pts):
        return {"color": self._color(ev, pts)}

    def _extra(self, pts):
        return {}


class Facet(_VertexList):
    """A filled polygon through points of one body, or through points of several bodies
    (``Facet([point1, point2, ...])``); in 3D one planar face."""

    kind = "polygon"

    def _defaults(self, ev, pts):
        return {"color": self._color(ev, pts), "alpha": 0.8}


class Edge(_VertexList):
    """Lines through points (``closed=True`` joins the last to the first)."""

    def __init__(self, body_or_points, points=None, closed=False, **style):
        super().__init__(body_or_points, points, **style)
        self.closed = closed

    def _extra(self, pts):
        return {"closed": self.closed}


class Vertex(_VertexList):
    """Point markers."""

    kind = "points"
    layer = L_JOINT

    def _defaults(self, ev, pts):
        return {"color": self._color(ev, pts), "marker": "o", "markersize": 6}


class PointLabel(_VertexList):
    """Text labels at points: ``body.point`` names by default (``PointLabel(body, "all")``
    labels every named point of the body). ``text``: a list of strings or a function of the
    :class:`Point`. ``offset``: in picture-size fractions (default a little up-right)."""

    kind = "text"
    layer = L_LABEL

    def __init__(self, body_or_points, points=None, text=None, offset=(0.012, 0.012), **style):
        super().__init__(body_or_points, points, **style)
        self.text, self.offset = text, offset

    def _labels(self, pts):
        if self.text is None:
            out = []
            for p in pts:
                owner = p.body.name if p.body is not None else "ground"
                out.append(f"{owner}.{p.label}" if p.label else f"{owner}{_fmt(p.local)}")
            return out
        if callable(self.text):
            return [str(self.text(p)) for p in pts]
        texts = [self.text] if isinstance(self.text, str) else list(self.text)
        if len(texts) != len(pts):
            raise ModelError(f"PointLabel: {len(texts)} text(s) for {len(pts)} point(s)")
        return [str(t) for t in texts]

    def _request(self, ev):
        pts = _point_specs(ev, self.body, self.points, "PointLabel")
        geo = ev.points(pts)
        labels = self._labels(pts)

        def finish():
            off = np.zeros(ev.dim)
            off[: len(self.offset)] = np.asarray(self.offset, dtype=float)[: ev.dim] * ev.size
            xyz = geo.xyz + off
            return [self._item("text", xyz, {"color": "black", "fontsize": 9}, L_LABEL,
                               texts=labels)]

        return finish


class Wheel(Primitive):
    """A wheel on a body: a disc of ``radius`` about ``center`` with ``spokes`` spokes.
    In 3D the disc is normal to the local ``axis`` and ``width`` thick (default radius/6)."""

    def __init__(self, body, center=0, radius=1.0, spokes=6, axis=(0, 0, 1), width=None, **style):
        super().__init__(**style)
        self.body, self.center, self.radius = body, center, float(radius)
        self.spokes = _count(spokes, "Wheel: spokes", 0)
        self.axis, self.width = axis, width

    def _request(self, ev):
        b = _body(ev, self.body)
        c = _locals_on(ev, b, [self.center], "Wheel")[0]
        pose = ev.pose(b)
        r = self.radius
        if r <= 0:
            raise GeometryError(f"Wheel on body {b.name!r}: radius must be positive")

        def finish():
            color = body_color(b)
            a = np.linspace(0, 2 * np.pi, self.spokes, endpoint=False)
            if ev.dim == 2:
                rim = sh.circle(c, r, 48)
                spokes = []
                for ang in a:
                    spokes += [c, c + 0.92 * r * np.array([np.cos(ang), np.sin(ang)]), [np.nan] * 2]
                items = [self._rigid("polygon", pose, rim, {"color": color, "alpha": 0.35}, L_BODY)]
                if self.spokes:
                    items.append(self._rigid("line", pose, np.array(spokes, dtype=float),
                                             {"color": color, "linewidth": 1.5}, L_PLATE_EDGE))
                return items
            ax = _local_vector(ev, b, self.axis, "Wheel axis")
            u, v, w = sh.perpendicular_frame(ax)
            width = float(self.width) if self.width is not None else r / 6
            verts, faces = sh.cylinder(c - w * width / 2, c + w * width / 2, r, 32)
            items = [self._rigid("mesh", pose, verts, {"color": color}, L_BODY, faces=faces)]
            if self.spokes:
                spokes = []
                face = c + w * width * 0.52
                for ang in a:
                    spokes += [face, face + 0.92 * r * (np.cos(ang) * u + np.sin(ang) * v),
                               [np.nan] * 3]
                items.append(self._rigid("line", pose, np.array(spokes, dtype=float),
                                         {"color": "white", "linewidth": 1.5}, L_PLATE_EDGE))
            return items

        return finish


class PitchCircle(Primitive):
    """A gear drawn as its pitch circle on a body, with a tooth mark (a radial tick at the
    local direction ``mark``) so that its rotation shows; ``teeth`` adds a tick per tooth.
    In 3D the circle lies in the plane normal to the local ``axis``."""

    def __init__(self, body, center=0, radius=1.0, axis=(0, 0, 1), mark=None, teeth=None,
                 **style):
        super().__init__(**style)
        self.body, self.center, self.axis, self.mark = body, center, axis, mark
        try:
            self.radius = float(radius)
        except (TypeError, ValueError):
            raise ModelError(f"PitchCircle: radius must be a number, got {radius!r}") from None
        if not (self.radius > 0 and np.isfinite(self.radius)):
            raise GeometryError(f"PitchCircle: radius must be positive, got {radius!r}")
        if teeth is not None and (isinstance(teeth, bool) or not isinstance(teeth, int)
                                  or teeth < 3):
            raise ModelError(f"PitchCircle: teeth must be an integer >= 3, got {teeth!r}")
        self.teeth = None if teeth is None else _count(teeth, "PitchCircle: teeth", 3)

    def _request(self, ev):
        b = _body(ev, self.body)
        c = _locals_on(ev, b, [self.center], "PitchCircle")[0]
        pose = ev.pose(b)
        r = self.radius
        if ev.dim == 2:
            u, v = np.array([1.0, 0.0]), np.array([0.0, 1.0])
        else:
            w = _local_vector(ev, b, self.axis, "PitchCircle axis")
            u, v, w = sh.perpendicular_frame(w)
        if self.mark is not None:
            m = _local_vector(ev, b, self.mark, "PitchCircle mark")
            m = m - (m @ w) * w if ev.dim == 3 else m
            if np.linalg.norm(m) < 1e-12:
                raise GeometryError("PitchCircle: the tooth mark must not be along the axis")
            u = m / np.linalg.norm(m)
            v = np.cross(w, u) if ev.dim == 3 else np.array([-u[1], u[0]])

        def finish():
            color = _dark(body_color(b))
            a = np.linspace(0, 2 * np.pi, 97)
            rim = c + r * (np.cos(a)[:, None] * u + np.sin(a)[:, None] * v)
            ticks = [c, c + 1.12 * r * u, [np.nan] * ev.dim]
            for ang in (np.linspace(0, 2 * np.pi, self.teeth, endpoint=False)
                        if self.teeth else []):
                d = np.cos(ang) * u + np.sin(ang) * v
                ticks += [c + 0.94 * r * d, c + 1.06 * r * d, [np.nan] * ev.dim]
            return [self._rigid("line", pose, rim, {"color": color, "linewidth": 1.2,
                                                    "linestyle": "--"}, L_PLATE_EDGE),
                    self._rigid("line", pose, np.array(ticks, dtype=float),
                                {"color": color, "linewidth": 2.0}, L_PLATE_EDGE)]

        return finish


class Arrow(Primitive):
    """An arrow at ``point`` along ``vector``.

    ``vector``: a :class:`Vector` (or axis), a SymPy column or tuple of global components
    (any expressions of ``T``, coordinates, velocities, accelerations and parameters), or a
    callable ``f(solution) -> (N, dim)`` array (for data such as reactions). ``scale``:
    drawing length per unit of the vector, or ``"auto"`` (the longest arrow over all frames
    is a quarter of the picture size). ``head_size``: width of the head (Mech's HeadSize;
    by default the head is 1/5 of the arrow's length). ``anchor="tail"`` starts the arrow at the point,
    ``"head"`` ends it there (forces pushing on a point).
    """

    def __init__(self, point, vector, scale=1.0, head_size=None, anchor="tail", **style):
        super().__init__(**style)
        if anchor not in ("tail", "head"):
            raise ModelError("Arrow: anchor must be 'tail' or 'head'")
        if not (scale == "auto" or isinstance(scale, (int, float))):
            raise ModelError(f"Arrow: scale must be a number or 'auto', got {scale!r}")
        self.point, self.vector = point, vector
        self.scale, self.head_size, self.anchor = scale, head_size, anchor

    def _request(self, ev):
        pt = as_point(self.point)
        pgeo = ev.points([pt])
        vec = self.vector
        if callable(vec) and not isinstance(vec, (sp.Basic, sp.MatrixBase)):
            vref = None
        else:
            if isinstance(vec, (Vector, Axis)):
                v = ev.model._vector(vec).direction()
            else:
                v = sp.Matrix([sp.sympify(c) for c in vec])
            if len(v) != ev.dim:
                raise GeometryError(f"Arrow: vector has {len(v)} components; model is {ev.dim}D")
            vref = ev.expr(sp.Matrix(v))

        def finish():
            P = pgeo.xyz[:, 0, :]
            if vref is None:
                V = np.asarray(vec(ev.sol), dtype=float).reshape(-1, ev.dim)
                if V.shape[0] not in (1, ev.N):
                    raise ModelError(f"Arrow: the vector function returned {V.shape[0]} rows for "
                                     f"{ev.N} frames")
            else:
                V = np.asarray(vref.value, dtype=float).reshape(-1, ev.dim)
            N = max(P.shape[0], V.shape[0])
            P = np.broadcast_to(P, (N, ev.dim))
            V = np.broadcast_to(V, (N, ev.dim))
            s = self.scale
            if s == "auto":
                mag = np.linalg.norm(V, axis=1)
                mag = mag[np.isfinite(mag)]
                top = mag.max() if mag.size else 0.0
                s = 0.25 * ev.size / top if top > 0 else 1.0
            D = float(s) * V
            tail, tip = (P, P + D) if self.anchor == "tail" else (P - D, P)
            return arrow_items(self, ev.dim, tail, tip, self.head_size,
                               {"color": "#c00000", "linewidth": 2.0}, L_ARROW)

        return finish


def arrow_items(prim: Primitive, dim, tail, tip, head_size, defaults, layer,
                pose=None) -> list[Item]:
    """Shaft line and head (triangle in 2D, cone in 3D) from ``tail`` to ``tip`` ``(N, dim)``
    (local coordinates placed by ``pose`` when given)."""
    d = tip - tail
    L = np.linalg.norm(d, axis=1)
    safe = np.where(L > 0, L, 1.0)
    u = d / safe[:, None]
    if head_size is not None:  # Mech's HeadSize: the width of the head
        hw = np.full(L.shape, float(head_size))
        hl = np.minimum(1.6 * hw, L)
    else:  # Automatic: the head is 1/5 of the arrow's length
        hl = L / 5
        hw = hl / 1.6
    base = tip - hl[:, None] * u
    shaft = np.stack([tail, base], axis=1)
    color = prim.style.get("color", defaults.get("color"))
    hdef = {"color": color, "linewidth": 0.5}
    if dim == 2:
        nrm = np.stack([-u[:, 1], u[:, 0]], axis=1)
        head = np.stack([tip, base + hw[:, None] / 2 * nrm, base - hw[:, None] / 2 * nrm], axis=1)
        hitem = ("polygon", head, None)
    else:
        verts, faces = sh.cone(base, tip, hw / 2, 10)
        hitem = ("mesh", verts, faces)
    if pose is None:
        return [prim._item("line", shaft, defaults, layer),
                prim._item(hitem[0], hitem[1], hdef, layer, faces=hitem[2])]
    return [prim._rigid("line", pose, shaft[0], defaults, layer),
            prim._rigid(hitem[0], pose, hitem[1][0], hdef, layer, faces=hitem[2])]


class LocalAxes(Primitive):
    """Local x, y (and z) axes of bodies at their origins: red, green (blue) arrows of
    length ``size`` (default 12 % of the picture). ``bodies``: a body, a list, or "all"
    (every moving body)."""

    def __init__(self, bodies="all", size=None, **style):
        super().__init__(**style)
        self.bodies, self.size = bodies, size

    def _request(self, ev):
        if isinstance(self.bodies, str) and self.bodies == "all":
            bodies = ev.model.bodies[1:]
        elif isinstance(self.bodies, (list, tuple)):
            bodies = [_body(ev, b) for b in self.bodies]
        else:
            bodies = [_body(ev, self.bodies)]
        poses = [ev.pose(b) for b in bodies]

        def finish():
            size = float(self.size) if self.size is not None else 0.12 * ev.size
            items = []
            for pose in poses:
                for i in range(ev.dim):
                    tip = np.zeros((1, ev.dim))
                    tip[0, i] = size
                    col = {"color": AXIS_COLORS[i], "linewidth": 1.5}
                    sub = _Styled(self.style, color=AXIS_COLORS[i])
                    items += arrow_items(sub, ev.dim, np.zeros((1, ev.dim)), tip, size / 6, col,
                                         L_AXES, pose=pose)
            return items

        return finish


class CamPlot(Edge):
    """A cam profile drawn in global coordinates (Mech's ``CamPlot``): the locus of a body
    point whose local coordinates are expressions of a profile parameter, sampled over
    ``(alpha, lo, hi)`` and carried by the body as it moves::

        r = 1 + 0.3 * sp.cos(a)
        profile = cam.point((r * sp.cos(a), r * sp.sin(a)))
        CamPlot(profile, (a, 0, 2 * sp.pi))

    In 3D a profile is a surface of two parameters: give one range per parameter
    (``CamPlot(p, (u, 0, 1), (v, 0, 1))``), drawn as its parameter lines. Parameters of the
    model take the solution's values. ``closed`` defaults to whether the two ends meet.
    """

    def __init__(self, locus_point, *ranges, samples: int = 181, closed: bool | None = None,
                 **style):
        Primitive.__init__(self, **style)
        if not isinstance(locus_point, Point) or locus_point.body is None:
            raise ModelError("CamPlot: give the cam's locus point, a point of the cam body "
                             "whose coordinates depend on the profile parameter, e.g. "
                             "cam.point((r(a) cos(a), r(a) sin(a)))")
        if not ranges or any(not (isinstance(r, (tuple, list)) and len(r) == 3)
                             for r in ranges):
            raise ModelError("CamPlot: give each profile parameter's range as (symbol, low, "
                             "high)")
        if len(ranges) > 2:
            raise ModelError("CamPlot: a profile has one (curve) or two (surface) parameters")
        for sym, lo, hi in ranges:
            if not isinstance(sym, sp.Symbol) or sym not in locus_point.local.free_symbols:
                raise ModelError(f"CamPlot: the locus point {locus_point!r} does not depend "
                                 f"on {sym!r}; a profile must be a function of its parameter")
            if not (sp.sympify(hi) - sp.sympify(lo)).is_positive:
                raise ModelError(f"CamPlot: the range of {sym} must have low < high, got "
                                 f"({lo}, {hi})")
        if isinstance(samples, bool) or not isinstance(samples, int) or samples < 3:
            raise ModelError(f"CamPlot: samples must be an integer >= 3, got {samples!r}")
        # a surface (two parameters) samples its grid: samples**2 points
        samples = _count(samples, "CamPlot: samples", 3,
                         MAX_SAMPLES if len(ranges) == 1 else MAX_SEGMENTS)
        self.locus, self.ranges, self.samples = locus_point, list(ranges), samples
        self._closed = closed
        self.body, self.points, self.closed = locus_point.body, [], False

    def _request(self, ev):
        expr = self.locus.local.xreplace(ev._psubs)
        syms = [r[0] for r in self.ranges]
        extra = expr.free_symbols - set(syms)
        if extra:
            raise ModelError(f"CamPlot: the profile uses {sorted(map(str, extra))}, which are "
                             "neither its parameters nor model parameters")
        f = sp.lambdify(syms, list(expr), "numpy")
        grids = [np.linspace(float(lo), float(hi), self.samples) for _, lo, hi in self.ranges]
        if len(grids) == 1:
            pts = np.array(np.broadcast_arrays(*f(grids[0])), dtype=float).T
            lines = [pts]
        else:
            # a surface: parameter lines of each family
            lines = []
            for k in range(0, self.samples, max(self.samples // 12, 1)):
                lines.append(np.array(np.broadcast_arrays(*f(grids[0], grids[1][k])),
                                      dtype=float).T)
                lines.append(np.array(np.broadcast_arrays(*f(grids[0][k], grids[1])),
                                      dtype=float).T)
        finishers = []
        for line in lines:
            if not np.all(np.isfinite(line)):
                raise ModelError("CamPlot: the profile is not finite over the given range")
            ends_meet = np.linalg.norm(line[0] - line[-1]) <= 1e-9 * max(
                np.abs(line).max(initial=0.0), 1e-300)
            part = Edge(self.body, [tuple(p) for p in line],
                        closed=ends_meet if self._closed is None else self._closed,
                        **self.style)
            finishers.append(part._request(ev))
        return lambda: [item for fin in finishers for item in fin()]


class _Styled(Primitive):
    """A primitive-like holder of a modified style (for sub-items)."""

    def __init__(self, style, **over):
        self.style = dict(style)
        self.style.update(over)


class LocusPlot(Primitive):
    """The path of a point over a solution (Mech's LocusPlot).

    ``solution``: the solution to trace (default: the one being drawn, over all of its
    time points, whatever frames are shown). ``trail=True`` in an animation shows the path
    only up to the current time.
    """

    def __init__(self, point, solution=None, trail=False, **style):
        super().__init__(**style)
        self.point, self.solution, self.trail = point, solution, trail

    def _request(self, ev):
        pt = as_point(self.point)
        pt.check_dim(ev.dim)
        for b in pt.bodies():
            ev.model.body(b)
        out: list = []

        def compute():
            src = self.solution if self.solution is not None else ev.full
            xyz = np.asarray(src.eval(pt.location()), dtype=float).reshape(-1, ev.dim)
            upto = None
            if self.trail:
                upto = np.clip(np.searchsorted(src.t, ev.sol.t + 1e-12, side="right"), 1, len(xyz))
            out.append((xyz, upto))

        ev.later(compute)

        def finish():
            xyz, upto = out[0]
            color = _dark(body_color(pt.body)) if pt.body is not None else GROUND_COLOR
            return [self._item("line", xyz[None], {"color": color, "linewidth": 1.5},
                               L_LOCUS, upto=upto)]

        return finish


class InstantCenter(Primitive):
    """The planar instant centre of a body (a hollow marker; none while the body only
    translates), optionally with dashed rays ``to`` points of the body. Needs a solution
    with velocities."""

    dims = (2,)

    def __init__(self, body, to=None, **style):
        super().__init__(**style)
        self.body, self.to = body, to

    def _request(self, ev):
        b = _body(ev, self.body)
        if b.is_ground:
            raise ModelError("InstantCenter: ground has no instant centre")
        ic = ev.expr(ev.model.instant_center(b))
        rays = ev.points(resolve_points(ev.model, b, self.to, "InstantCenter")) if self.to else None

        def finish():
            c = np.asarray(ic.value, dtype=float).reshape(-1, 1, 2)
            color = body_color(b)
            items = [self._item("points", c, {"color": color, "marker": "o", "markersize": 9,
                                              "faces": False}, L_LABEL, fit=False)]
            if rays is not None:
                P = rays.xyz
                segs = []
                for j in range(P.shape[1]):
                    segs += [c[:, 0], P[:, j], np.full_like(c[:, 0], np.nan)]
                items.append(self._item("line", np.stack(segs, axis=1),
                                        {"color": color, "linestyle": ":", "linewidth": 1.0},
                                        L_GUIDE, fit=False))
            return items

        return finish


class GroundPivot(Primitive):
    """A ground symbol at a fixed point: a hatched triangle (2D) or a block (3D)."""

    def __init__(self, point, size=None, **style):
        super().__init__(**style)
        self.point, self.size = point, size

    def _request(self, ev):
        pt = as_point(self.point)
        if pt.body is not None and not pt.body.is_ground:
            raise GeometryError(f"GroundPivot: {pt!r} is not a ground point")
        geo = ev.points([pt])

        def finish():
            s = float(self.size) if self.size is not None else 0.03 * ev.size
            c = geo.xyz[0, 0]  # ground points are static
            d = {"color": GROUND_COLOR}
            if ev.dim == 2:
                tri = np.array([c, c + [-s, -1.6 * s], c + [s, -1.6 * s]])
                y0 = c[1] - 1.6 * s
                base = [[c[0] - 1.6 * s, y0], [c[0] + 1.6 * s, y0], [np.nan, np.nan]]
                for x in np.linspace(-1.4 * s, 1.4 * s, 5):
                    base += [[c[0] + x, y0], [c[0] + x - 0.5 * s, y0 - 0.6 * s], [np.nan, np.nan]]
                return [self._item("polygon", tri[None], {"color": "#bdbdbd",
                                                          "edgecolor": GROUND_COLOR}, L_GROUND),
                        self._item("line", np.array(base)[None], {**d, "linewidth": 1.0},
                                   L_GROUND)]
            verts, faces = sh.box(c - [1.4 * s, 1.4 * s, 1.4 * s], c + [1.4 * s, 1.4 * s, 1.4 * s])
            return [self._item("mesh", verts[None], {"color": "#9e9e9e"}, L_GROUND, faces=faces)]

        return finish


# ----------------------------------------------------------------------------------------
# Spatial primitives
# ----------------------------------------------------------------------------------------
class _Mesh3D(Primitive):
    dims = (3,)

    def _mesh(self, ev, b) -> tuple[np.ndarray, list]:  # pragma: no cover - interface
        raise NotImplementedError

    def _request(self, ev):
        b = _body(ev, self.body)
        pose = ev.pose(b)
        built = self._mesh(ev, b)  # validates eagerly (errors name the body)

        def finish():
            verts, faces = built
            return [self._rigid("mesh", pose, verts, {"color": body_color(b)}, L_BODY,
                                faces=faces)]

        return finish


class Mesh(_Mesh3D):
    """A polygon mesh fixed in a body: ``vertices`` ``(k, 3)`` in the body's coordinates and
    ``faces``, each a sequence of at least three vertex indices (an imported robot's STL or
    OBJ visual, ``ms.from_urdf``).

    Example: one triangle on body ``b``::

        draw.Mesh(b, [(0, 0, 0), (0.1, 0, 0), (0, 0.1, 0)], [(0, 1, 2)])
    """

    def __init__(self, body, vertices, faces, **style):
        super().__init__(**style)
        self.body = body
        try:
            v = np.asarray(vertices, dtype=float)
        except (TypeError, ValueError):
            raise GeometryError("Mesh: vertices must be numbers of shape (k, 3)") from None
        if v.ndim != 2 or v.shape[1] != 3 or not len(v) or not np.all(np.isfinite(v)):
            raise GeometryError(f"Mesh: vertices must be finite numbers of shape (k, 3), got shape "
                                f"{v.shape}")
        fs = []
        for f in faces:
            try:
                idx = tuple(int(i) for i in f)
            except (TypeError, ValueError):
                raise GeometryError(f"Mesh: face {f!r} is not a sequence of vertex indices") from None
            if len(idx) < 3 or min(idx) < 0 or max(idx) >= len(v):
                raise GeometryError(f"Mesh: face {f!r} needs at least three indices of the {len(v)} "
                                    "vertices")
            fs.append(idx)
        if not fs:
            raise GeometryError("Mesh: no faces")
        self.vertices, self.faces = v, fs

    def _mesh(self, ev, b):
        return self.vertices, self.faces


class Sphere(_Mesh3D):
    """A sphere of ``radius`` about a point of a body."""

    def __init__(self, body, center=0, radius=1.0, n=16, **style):
        super().__init__(**style)
        self.body, self.center, self.radius = body, center, float(radius)
        self.n = _count(n, "Sphere: n", 3)

    def _mesh(self, ev, b):
        c = _locals_on(ev, b, [self.center], "Sphere")[0]
        return sh.sphere(c, self.radius, self.n)


class Cylinder(_Mesh3D):
    """A cylinder of ``radius`` between two points of a body (closed by ``caps``)."""

    def __init__(self, body, point1, point2, radius=1.0, n=20, caps=True, **style):
        super().__init__(**style)
        self.body, self.ends, self.radius = body, (point1, point2), float(radius)
        self.n, self.caps = _count(n, "Cylinder: n", 3), caps

    def _mesh(self, ev, b):
        e = _locals_on(ev, b, list(self.ends), "Cylinder")
        if np.allclose(e[0], e[1]):
            raise GeometryError(f"Cylinder on body {b.name!r}: its two end points coincide")
        return sh.cylinder(e[0], e[1], self.radius, self.n, self.caps)


class Torus(_Mesh3D):
    """A torus about a point of a body, its main circle normal to the local ``axis``."""

    def __init__(self, body, center=0, major=1.0, minor=0.25, axis=(0, 0, 1), n=24, m=12,
                 **style):
        super().__init__(**style)
        self.body, self.center, self.major, self.minor = body, center, float(major), float(minor)
        self.axis, self.n, self.m = axis, _count(n, "Torus: n", 3), _count(m, "Torus: m", 3)

    def _mesh(self, ev, b):
        c = _locals_on(ev, b, [self.center], "Torus")[0]
        ax = _local_vector(ev, b, self.axis, "Torus axis")
        return sh.torus(c, self.major, self.minor, ax, self.n, self.m)


class Revolve(_Mesh3D):
    """Surface of revolution of a profile ``[(radius, height), ...]`` about a body axis
    ``(origin, direction)`` in body coordinates (default the local z axis), through
    ``angle`` (default a full turn)."""

    def __init__(self, body, profile, axis=None, n=24, angle=2 * np.pi, **style):
        super().__init__(**style)
        self.body, self.profile, self.axis = body, profile, axis
        self.n, self.angle = _count(n, "Revolve: n", 2), float(angle)

    def _mesh(self, ev, b):
        if self.axis is None:
            origin, direction = np.zeros(3), np.array([0.0, 0.0, 1.0])
        elif isinstance(self.axis, Axis):
            origin = _locals_on(ev, b, [self.axis.origin], "Revolve axis")[0]
            direction = _local_vector(ev, b, self.axis.dir, "Revolve axis")
        else:
            o, d = self.axis
            origin = _locals_on(ev, b, [o], "Revolve axis")[0]
            direction = _local_vector(ev, b, d, "Revolve axis")
        prof = np.asarray(self.profile, dtype=float)
        if prof.ndim != 2 or prof.shape[1] != 2 or len(prof) < 2:
            raise GeometryError("Revolve: profile must be two or more (radius, height) pairs")
        return sh.revolve(prof, origin, direction, self.n, self.angle)


class Extrude(Primitive):
    """Extrude the lines between points by ``dist`` along ``vector`` (Mech's Extrude):
    ``Extrude(body, [p1, p2, ...], vector, dist)`` in body coordinates, or
    ``Extrude([point1, ...], vector, dist)`` with a global vector. ``magnitude="relative"``
    multiplies ``dist`` by the vector's length. ``closed=True`` closes the outline and caps
    both ends (a prism)."""

    dims = (3,)

    def __init__(self, body_or_points, points, vector=None, dist=1.0, magnitude="absolute",
                 closed=False, **style):
        super().__init__(**style)
        from ..geometry._bodies import Body

        if vector is None or not isinstance(body_or_points, (Body, str, int)):
            # global form: Extrude(points, vector, dist)
            if vector is not None:
                dist = vector
            self.body, self.points, self.vector = None, body_or_points, points
        else:
            self.body, self.points, self.vector = body_or_points, points, vector
        self.dist, self.closed = float(dist), closed
        if magnitude not in ("absolute", "relative"):
            raise ModelError("Extrude: magnitude must be 'absolute' or 'relative'")
        self.magnitude = magnitude

    def _offset(self, v) -> np.ndarray:
        v = np.asarray(v, dtype=float)
        if self.magnitude == "relative":
            return self.dist * v
        return self.dist * sh.unit(v, "Extrude vector")

    def _request(self, ev):
        if self.body is not None:
            b = _body(ev, self.body)
            loc = _locals_on(ev, b, list(self.points), "Extrude")
            off = self._offset(_local_vector(ev, b, self.vector, "Extrude vector"))
            pose = ev.pose(b)
            verts, faces = sh.extrude(loc, off, self.closed)

            def finish():
                return [self._rigid("mesh", pose, verts, {"color": body_color(b)}, L_BODY,
                                    faces=faces)]

            return finish
        pts = resolve_points(ev.model, None, self.points, "Extrude")
        geo = ev.points(pts)
        vec = ev.numeric_local(sp.Matrix(list(self.vector)))
        if vec is None or len(vec) != 3:
            raise GeometryError("Extrude: the global vector must be 3 constant components")
        off = self._offset(vec)
        _, faces = sh.extrude(np.zeros((len(pts), 3)), off, self.closed)

        def finish():
            P = geo.xyz
            return [self._item("mesh", np.concatenate([P, P + off], axis=1),
                               {"color": GROUND_COLOR}, L_BODY, faces=faces)]

        return finish


__all__ = [
    "Arrow",
    "Bar",
    "Box",
    "Cylinder",
    "Edge",
    "Extrude",
    "Facet",
    "GroundPivot",
    "InstantCenter",
    "LocalAxes",
    "LocusPlot",
    "PointLabel",
    "Primitive",
    "Revolve",
    "Sphere",
    "Torus",
    "Vertex",
    "Wheel",
    "body_color",
]
