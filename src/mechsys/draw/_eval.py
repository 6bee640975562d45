r"""Numeric evaluation of graphics over the frames of a solution.

Primitives never evaluate anything themselves. They *request* what they need from an
:class:`Evaluator` (body poses, point locations, any SymPy expression), and the evaluator
evaluates every request of every primitive in **one** compiled call of
:meth:`Solution.eval` over all frames. Body-fixed geometry with constant local coordinates
is then placed numerically, for every frame :math:`k` at once (one numpy ``einsum``):

.. math::

    r_P(k) = r_b(k) + A_b(k)\, s'_P

so no symbolic work happens per frame, and a mesh of hundreds of vertices costs only the
pose of its body (``dim + dim^2`` expressions).

The result of a primitive is a list of :class:`Item` - renderer-independent display lists
(polylines, polygons, meshes, markers, text) holding global coordinates per frame.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from .._errors import GeometryError, ModelError
from ..geometry._points import Point


# ----------------------------------------------------------------------------------------
# Display items
# ----------------------------------------------------------------------------------------
@dataclass(eq=False)
class Item:
    """One drawable thing, in global coordinates.

    * ``kind``: ``"line"`` (polyline), ``"polygon"`` (one face), ``"mesh"`` (faces over shared
      vertices, 3D), ``"points"`` (markers) or ``"text"`` (one label per vertex).
    * ``xyz``: ``(N, V, dim)`` vertices per frame, or ``(1, V, dim)`` when static.
    * ``style``: colour and line options (see :data:`STYLE_KEYS`).
    * ``faces``: for meshes, a list of vertex-index tuples (triangles or quads).
    * ``texts``: for text, one string per vertex.
    * ``closed``: for lines, join the last vertex to the first.
    * ``upto``: optional ``(N,)`` number of vertices shown per frame (growing trails).
    * ``rigid``: ``(pose, local (V, dim))`` when every vertex is fixed in one body; lets the
      HTML viewer ship local meshes plus body poses instead of vertices per frame.
    * ``layer``: drawing order (higher on top; 2D depth order, 3D tie-break).
    * ``fit``: whether the picture's bounds must hold all its vertices (instant centres only
      count when they lie within one picture size of the rest).
    """

    kind: str
    xyz: np.ndarray
    style: dict = field(default_factory=dict)
    faces: list | None = None
    texts: list | None = None
    closed: bool = False
    upto: np.ndarray | None = None
    rigid: tuple | None = None
    layer: int = 2
    fit: bool = True  # False: far points do not enlarge the picture (instant centres)

    def at(self, k: int) -> np.ndarray:
        """Vertices ``(V, dim)`` at frame ``k`` (trails cut to their length)."""
        a = self.xyz[k if self.xyz.shape[0] > 1 else 0]
        if self.upto is not None:
            a = a[: int(self.upto[k])]
        return a

    @property
    def static(self) -> bool:
        return self.xyz.shape[0] == 1


#: Style options every primitive accepts.
STYLE_KEYS = {
    "color": "main colour (any matplotlib colour: name, '#rrggbb', (r, g, b))",
    "edgecolor": "outline colour of filled shapes",
    "alpha": "opacity 0..1",
    "linewidth": "line width in points",
    "linestyle": "'-', '--', ':', '-.'",
    "marker": "marker symbol for points ('o', 's', '^', ...)",
    "markersize": "marker size in points",
    "fontsize": "text size in points",
    "faces": "True: filled faces; False: wire frame (Mech's Faces option)",
    "layer": "drawing order, higher on top",
    "label": "legend label",
}


def check_style(style: dict, who: str) -> dict:
    bad = sorted(set(style) - set(STYLE_KEYS))
    if bad:
        allowed = ", ".join(sorted(STYLE_KEYS))
        raise ModelError(f"{who}: unknown style option(s) {bad}; allowed: {allowed}")
    return dict(style)


# ----------------------------------------------------------------------------------------
# Requests and their values
# ----------------------------------------------------------------------------------------
class Ref:
    """A requested expression; ``value`` is ``(N,) + shape`` after :meth:`Evaluator.run`."""

    def __init__(self, start: int, shape: tuple):
        self.start = start
        self.shape = shape
        self.value: np.ndarray | None = None


class Pose:
    """A body's position ``r (N, dim)`` and rotation ``A (N, dim, dim)`` over the frames."""

    def __init__(self, body, index: int):
        self.body = body
        self.index = index  # position in Evaluator.poses
        self.ref: Ref | None = None
        self.r: np.ndarray | None = None
        self.A: np.ndarray | None = None

    def place(self, local: np.ndarray) -> np.ndarray:
        """Global ``(N, V, dim)`` of local points ``(V, dim)``."""
        local = np.asarray(local, dtype=float).reshape(-1, self.r.shape[1])
        return self.r[:, None, :] + np.einsum("nij,vj->nvi", self.A, local)

    def place_vector(self, local: np.ndarray) -> np.ndarray:
        """Global ``(N, V, dim)`` of local directions ``(V, dim)``."""
        local = np.asarray(local, dtype=float).reshape(-1, self.r.shape[1])
        return np.einsum("nij,vj->nvi", self.A, local)


class Geo:
    """Vertices requested from the evaluator; ``xyz`` ``(N, V, dim)`` after the run."""

    def __init__(self, parts: list):
        # parts: ("rigid", pose, local (V, dim)) | ("expr", ref, V)
        self.parts = parts

    @property
    def xyz(self) -> np.ndarray:
        arrays = []
        for part in self.parts:
            if part[0] == "rigid":
                arrays.append(part[1].place(part[2]))
            else:
                ref, nv = part[1], part[2]
                v = ref.value  # (N, dim * V) column-major by point
                N = v.shape[0]
                arrays.append(v.reshape(N, nv, -1))
        if len(arrays) == 1:
            return arrays[0]
        N = max(a.shape[0] for a in arrays)
        return np.concatenate([np.broadcast_to(a, (N,) + a.shape[1:]) for a in arrays], axis=1)

    @property
    def rigid(self) -> tuple | None:
        """``(pose, local)`` when all vertices are fixed in one body."""
        if len(self.parts) == 1 and self.parts[0][0] == "rigid":
            return self.parts[0][1], np.asarray(self.parts[0][2], dtype=float)
        poses = {id(p[1]) for p in self.parts if p[0] == "rigid"}
        if len(poses) == 1 and all(p[0] == "rigid" for p in self.parts):
            return self.parts[0][1], np.concatenate([p[2] for p in self.parts], axis=0)
        return None


class Evaluator:
    """Collects the symbolic requests of all primitives, evaluates them in one call.

    ``sol`` is the solution restricted to the frames drawn; ``full`` the whole solution
    (for loci). ``size`` is a characteristic length of the scene (set by the scene after
    the run; primitives use it for automatic sizes).
    """

    def __init__(self, model, sol, full=None):
        self.model = model
        self.sol = sol
        self.full = full if full is not None else sol
        self.dim = model.space.dim
        self.N = len(sol.t)
        self._exprs: list = []
        self._refs: list[Ref] = []
        self._poses: dict[int, Pose] = {}
        self._later: list[Callable[[], None]] = []
        self.size = 1.0
        self._ran = False
        lay = sol.system.layout
        self._psubs = dict(zip(lay.p_symbols, [float(v) for v in sol.p]))

    # -- requests -------------------------------------------------------------------------
    def expr(self, e) -> Ref:
        """Request any SymPy expression or matrix; ``value`` ``(N,) + shape``."""
        if self._ran:
            raise RuntimeError("Evaluator already ran")  # pragma: no cover
        if isinstance(e, sp.MatrixBase):
            flat = list(e.T)  # column-major: point after point for (dim, V) matrices
            shape = (e.shape[0],) if e.shape[1] == 1 else (e.shape[1], e.shape[0])
        else:
            flat = [sp.sympify(e)]
            shape = ()
        ref = Ref(len(self._exprs), shape)
        ref.count = len(flat)
        self._exprs.extend(flat)
        self._refs.append(ref)
        return ref

    def pose(self, body) -> Pose:
        """Request a body's pose (ground's is constant)."""
        key = id(body)
        if key not in self._poses:
            p = Pose(body, len(self._poses))
            if not body.is_ground:
                p.ref = self.expr(sp.Matrix([*body.r, *body.A]))
            self._poses[key] = p
        return self._poses[key]

    @property
    def poses(self) -> list[Pose]:
        return list(self._poses.values())

    def numeric_local(self, m) -> np.ndarray | None:
        """Local coordinates as floats (parameters substituted), or ``None`` when they depend
        on time or coordinates."""
        m = sp.Matrix(m)
        if self._psubs:
            m = m.subs(self._psubs)
        try:
            return np.array([float(c) for c in m], dtype=float)
        except (TypeError, ValueError):
            return None

    def points(self, pts: list[Point]) -> Geo:
        """Request the global locations of points (any bodies)."""
        parts: list = []
        for p in pts:
            p.check_dim(self.dim)
            loc = self.numeric_local(p.local)
            if loc is not None:
                body = p.body if p.body is not None else self.model.ground
                pose = self.pose(body)
                if parts and parts[-1][0] == "rigid" and parts[-1][1] is pose:
                    parts[-1] = ("rigid", pose, np.vstack([parts[-1][2], loc[None, :]]))
                else:
                    parts.append(("rigid", pose, loc[None, :]))
            else:
                parts.append(("expr", self.expr(p.location()), 1))
        return Geo(parts)

    def body_points(self, body, local: np.ndarray) -> Geo:
        """Request points given by constant local coordinates ``(V, dim)`` on ``body``."""
        return Geo([("rigid", self.pose(body), np.asarray(local, dtype=float).reshape(-1, self.dim))])

    def later(self, fn: Callable[[], None]) -> None:
        """Run ``fn`` after the evaluation (used for values computed on the full solution)."""
        self._later.append(fn)

    # -- evaluation -----------------------------------------------------------------------
    def run(self) -> None:
        N, dim = self.N, self.dim
        if self._exprs:
            vals = np.asarray(self.sol.eval(sp.Matrix(self._exprs)), dtype=float)
            vals = vals.reshape(N, len(self._exprs))
        else:
            vals = np.zeros((N, 0))
        for ref in self._refs:
            v = vals[:, ref.start : ref.start + ref.count]
            ref.value = v.reshape((N,) + ref.shape) if ref.shape else v[:, 0]
        for pose in self._poses.values():
            if pose.ref is None:
                pose.r = np.zeros((1, dim))
                pose.A = np.eye(dim)[None]
            else:
                v = pose.ref.value
                pose.r = v[:, :dim]
                pose.A = v[:, dim:].reshape(N, dim, dim)
        self._ran = True
        for fn in self._later:
            fn()


# ----------------------------------------------------------------------------------------
# Helpers: resolving user arguments
# ----------------------------------------------------------------------------------------
def resolve_body(model, spec):
    return model.body(spec)


def resolve_points(model, body, specs, who: str) -> list[Point]:
    """Points from specs: on ``body`` (names, numbers, local coords) or, with no body, Point
    objects / global coordinate tuples (ground)."""
    from ..geometry._points import as_point

    if isinstance(specs, (str, int, Point)) or _is_coord(specs):
        specs = [specs]
    out = []
    for s in specs:
        try:
            if isinstance(s, Point):
                p = s
            elif body is not None:
                p = body.point(s)
            else:
                p = as_point(s)
        except ModelError as exc:
            raise type(exc)(f"{who}: {exc}") from None
        p.check_dim(model.space.dim)
        for b in p.bodies():
            model.body(b)
        out.append(p)
    if not out:
        raise GeometryError(f"{who}: no points given")
    return out


def _is_coord(obj) -> bool:
    if isinstance(obj, sp.MatrixBase):
        return True
    if isinstance(obj, np.ndarray):
        return obj.ndim == 1
    return (isinstance(obj, (tuple, list)) and 2 <= len(obj) <= 3
            and all(isinstance(c, (int, float, np.number, sp.Expr)) for c in obj))


def subsolution(sol, idx):
    """The solution restricted to frame indices ``idx`` (a new immutable Solution)."""
    idx = np.asarray(idx, dtype=int)
    N = len(sol.t)
    changes = {}
    for f in dataclasses.fields(sol):
        if f.name == "p":
            continue
        v = getattr(sol, f.name)
        if isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == N:
            changes[f.name] = v[idx]
    changes["scalar"] = False
    return dataclasses.replace(sol, **changes)


def as_solution(obj):
    """A Solution from a Solution, or from a Model (drawn at its initial guess)."""
    if hasattr(obj, "eval") and hasattr(obj, "q") and hasattr(obj, "t"):
        if np.ndim(obj.t) == 0:  # pragma: no cover - defensive
            raise ModelError("expected a Solution over time points")
        if obj.scalar:
            return dataclasses.replace(obj, scalar=False)
        return obj
    if hasattr(obj, "compile") and hasattr(obj, "guess"):
        from ..results._solution import Solution

        system = obj.compile()
        g = np.asarray(obj.guess(), dtype=float)[None, :]
        return Solution(t=np.zeros(1), q=g, qd=None, qdd=None, p=obj._p(), system=system,
                        model=obj, iterations=np.zeros(1, dtype=int), message="initial guess")
    raise ModelError(f"expected a Solution (or a Model, drawn at its guess), got {obj!r}")
