"""Bodies: coordinates, local points, mass properties and the initial guess."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import sympy as sp

from .._errors import GeometryError, ModelError, UnknownPointError
from .._symbols import coord_symbol
from ._points import Axis, BodyRef, Line, Point, Vector, _as_matrix
from ._space import Space


class Body(BodyRef):
    """A rigid body of a model. Create with ``model.add_body``; ground is ``model.ground``.

    Attributes
    ----------
    name, number : the body's name and Mech number (ground is 1, then 2, 3, ... in order).
    q : tuple of SymPy symbols, its coordinates (``x2, y2, th2`` in 2D; empty for ground).
    r, A : its position (dim,) and rotation matrix (dim, dim) as SymPy expressions.
    points : ``{name: local coordinates}``; Mech point numbers are 1.. in this order.
    mass, centroid, inertia : mass properties (centroid local; inertia about the centroid).
    """

    def __init__(
        self,
        space: Space,
        name: str,
        number: int,
        points=None,
        guess=None,
        mass=0,
        centroid=None,
        inertia=None,
        is_ground: bool = False,
    ):
        self.space = space
        self.name = name
        self.number = number
        self.is_ground = is_ground
        self._points: dict[str, sp.Matrix] = {}
        self._order: list[str] = []
        for key, coords in _normalize_points(points):
            self._add_point(key, coords)
        if is_ground:
            self.q: tuple[sp.Symbol, ...] = ()
            self.r = sp.zeros(space.dim, 1)
            self.A = sp.eye(space.dim)
        else:
            self.q = tuple(coord_symbol(f"{c}{number}") for c in space.coordinate_names)
            r, rot = space.split(list(self.q))
            self.r = r
            self.rot = rot
            self.A = space.rotation_matrix(rot)
        self.guess = self._parse_guess(guess)
        self.mass = sp.sympify(mass)
        self.centroid = _as_matrix(centroid, "centroid") if centroid is not None else sp.zeros(space.dim, 1)
        self.inertia = inertia

    # -- points ---------------------------------------------------------------------------
    def _add_point(self, key: str, coords) -> None:
        m = _as_matrix(coords, f"point {key!r} of body {self.name!r}")
        if len(m) != self.space.dim:
            raise GeometryError(
                f"point {key!r} of body {self.name!r} has {len(m)} coordinates; "
                f"this model is {self.space.dim}D"
            )
        if key in self._points:
            raise ModelError(f"body {self.name!r} already has a point named {key!r}")
        self._points[key] = m
        self._order.append(key)

    @property
    def points(self) -> dict[str, sp.Matrix]:
        return dict(self._points)

    def point(self, spec=0) -> Point:
        """A point of this body: by name, Mech number (0 = origin, 1.. in definition order)
        or local coordinates."""
        if isinstance(spec, Point):
            return spec
        if isinstance(spec, str):
            if spec not in self._points:
                raise UnknownPointError(
                    f"body {self.name!r} has no point {spec!r}; its points are {self._order}"
                )
            return Point(self, self._points[spec], label=spec)
        if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
            if spec == 0:
                return Point(self, sp.zeros(self.space.dim, 1), label="origin")
            if not 1 <= spec <= len(self._order):
                raise UnknownPointError(
                    f"body {self.name!r} has no point number {spec}; it has "
                    f"{len(self._order)} point(s), numbered 1..{len(self._order)} (0 is the origin)"
                )
            key = self._order[spec - 1]
            return Point(self, self._points[key], label=key)
        p = Point(self, spec)
        p.check_dim(self.space.dim)
        return p

    def vector(self, spec, to=None) -> Vector:
        """A vector fixed in this body: local components, or from the origin to a named point,
        or ``vector(p1, to=p2)`` from point ``p1`` to point ``p2`` of this body."""
        if to is not None:
            return Vector(self.point(spec), self.point(to))
        if isinstance(spec, (str, int)) and not isinstance(spec, bool):
            return Vector(self, self.point(spec).local)
        v = Vector(self, spec)
        v.check_dim(self.space.dim)
        return v

    def axis(self, origin=0, direction=None, reference=None) -> Axis:
        """An axis through a point of this body along a local direction (default local x)."""
        if direction is None:
            direction = (1,) + (0,) * (self.space.dim - 1)
        d = direction if isinstance(direction, Vector) else self.vector(direction)
        ref = None
        if isinstance(reference, str) and reference in ("default", "minimal"):  # a rule (3D)
            ref = reference
        elif reference is not None:
            ref = reference if isinstance(reference, Vector) else self.vector(reference)
        try:
            return Axis(self.point(origin), d, ref)
        except GeometryError as exc:
            raise GeometryError(f"axis on body {self.name!r}: {exc}") from None

    def line(self, point1, point2) -> Line:
        """A line from ``point1`` to ``point2`` of this body."""
        return Line(self.point(point1), self.point(point2))

    # -- guesses --------------------------------------------------------------------------
    def _parse_guess(self, guess) -> np.ndarray:
        dim = self.space.dim
        if self.is_ground:
            return np.zeros(0)
        if guess is None:
            return np.array([0.0] * dim + list(self.space.zero_rotation()), dtype=float)
        try:
            pos, rot = guess
            pos = [float(v) for v in pos]
        except (TypeError, ValueError) as exc:
            raise ModelError(
                f"guess of body {self.name!r} must be ((x, y{', z' if dim == 3 else ''}), rotation); "
                f"got {guess!r}"
            ) from exc
        if len(pos) != dim:
            raise GeometryError(
                f"guess of body {self.name!r} has a {len(pos)}-component position; "
                f"this model is {dim}D"
            )
        rot = self.space.rotation_guess(rot, self.name)
        return np.array(pos + list(rot), dtype=float)

    def __repr__(self) -> str:
        return f"<Body {self.number} {self.name!r}>"


def _normalize_points(points):
    if points is None:
        return []
    if isinstance(points, Mapping):
        return [(str(k), v) for k, v in points.items()]
    if isinstance(points, Sequence):
        return [(f"p{i + 1}", v) for i, v in enumerate(points)]
    raise ModelError(f"points must be a dict of name -> coordinates or a list; got {points!r}")
