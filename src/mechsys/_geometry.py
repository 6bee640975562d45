r"""Geometric objects attached to bodies: :class:`Point`, :class:`Vector`, :class:`Axis`,
:class:`Line` (and :class:`Plane` in 3D).

Each holds *local* coordinates on one body (SymPy expressions, so they may depend on time
``T`` or on parameters) and gives its *global* expression through the body's pose::

    r_P = r_b + A_b s'_P          (point)
    v   = A_b v'                  (vector)

A plain coordinate tuple wherever a point is expected means a point on ground; wherever a
vector is expected, a vector in ground (global) coordinates.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import sympy as sp

from ._errors import GeometryError, ModelError

if TYPE_CHECKING:  # pragma: no cover
    from ._bodies import Body


def _as_matrix(coords, what: str) -> sp.Matrix:
    if isinstance(coords, np.ndarray):
        coords = coords.tolist()
    if isinstance(coords, sp.MatrixBase):
        m = sp.Matrix(coords).reshape(len(coords), 1)
    elif isinstance(coords, Sequence) and not isinstance(coords, str):
        try:
            m = sp.Matrix([sp.sympify(c) for c in coords])
        except (sp.SympifyError, TypeError) as exc:
            raise GeometryError(f"{what}: coordinates {coords!r} are not numbers or expressions") from exc
    else:
        raise GeometryError(f"{what}: expected a coordinate tuple, got {coords!r}")
    return m


def _is_coords(obj) -> bool:
    if isinstance(obj, sp.MatrixBase):
        return True
    if isinstance(obj, np.ndarray):
        return obj.ndim == 1 and obj.size in (2, 3)
    return (
        isinstance(obj, Sequence)
        and not isinstance(obj, str)
        and len(obj) in (2, 3)
        and all(isinstance(c, (int, float, np.number, sp.Expr)) for c in obj)
    )


class Geometry:
    """Base of geometric objects; ``body`` is ``None`` for ground (global) objects."""

    body: Body | None

    def bodies(self) -> list:
        return [self.body] if self.body is not None else []

    def check_dim(self, dim: int) -> None:  # pragma: no cover - overridden
        pass

    def _owner(self) -> str:
        return f"body {self.body.name!r}" if self.body is not None else "ground"


class Point(Geometry):
    """A point fixed in a body, with local coordinates ``s'``: global ``r + A s'``."""

    def __init__(self, body: Body | None, local, label: str | None = None):
        self.body = body
        self.local = _as_matrix(local, "Point")
        self.label = label

    def check_dim(self, dim: int) -> None:
        if len(self.local) != dim:
            raise GeometryError(
                f"point {self.label or list(self.local)} on {self._owner()} has "
                f"{len(self.local)} coordinates; this model is {dim}D"
            )

    def location(self) -> sp.Matrix:
        """Global position, a column of SymPy expressions."""
        if self.body is None:
            return self.local
        return self.body.r + self.body.A * self.local

    def __sub__(self, other: Point) -> Vector:
        return Vector(self, as_point(other))

    def __repr__(self) -> str:
        name = f"{self.label!r}, " if self.label else ""
        return f"Point({self._owner()}, {name}{tuple(self.local)})"


class Vector(Geometry):
    """A direction: fixed in a body (``Vector(body, (vx, vy))``), or from one point to
    another (``Vector(p_from, p_to)``), or any global expression (``Vector(None, expr)``)."""

    def __init__(self, a, b=None):
        if isinstance(a, Point) and b is not None:
            self.body = None
            self.points = (a, as_point(b))
            self.local = None
        else:
            self.body = a
            self.points = None
            self.local = _as_matrix(b, "Vector")

    def bodies(self) -> list:
        if self.points is not None:
            return [b for p in self.points for b in p.bodies()]
        return super().bodies()

    def check_dim(self, dim: int) -> None:
        if self.points is not None:
            for p in self.points:
                p.check_dim(dim)
        elif len(self.local) != dim:
            raise GeometryError(
                f"vector {tuple(self.local)} on {self._owner()} has {len(self.local)} "
                f"components; this model is {dim}D"
            )

    def is_local_constant(self) -> bool:
        """True when the vector is fixed in one body with a constant local direction."""
        return self.points is None and all(c.is_number for c in self.local)

    def direction(self) -> sp.Matrix:
        """Global components."""
        if self.points is not None:
            return self.points[1].location() - self.points[0].location()
        if self.body is None:
            return self.local
        return self.body.A * self.local

    def check_nonzero(self, what: str) -> None:
        if self.points is not None:
            a, b = self.points
            if a.body is b.body and all(sp.simplify(x - y) == 0 for x, y in zip(a.local, b.local)):
                raise GeometryError(f"{what}: its two points coincide on {a._owner()}; "
                                    "give two distinct points")
            return
        if all(c.is_number for c in self.local) and all(c == 0 for c in self.local):
            raise GeometryError(f"{what}: zero-length direction on {self._owner()}; "
                                "give a non-zero direction vector")

    def __repr__(self) -> str:
        if self.points is not None:
            return f"Vector({self.points[0]!r} -> {self.points[1]!r})"
        return f"Vector({self._owner()}, {tuple(self.local)})"


class Axis(Geometry):
    """An origin point and a direction (and in 3D an optional rotational reference direction)."""

    def __init__(self, origin: Point, direction: Vector, reference: Vector | None = None):
        self.origin = as_point(origin)
        self.dir = as_vector(direction)
        self.reference = as_vector(reference) if reference is not None else None
        self.body = self.origin.body
        self.dir.check_nonzero("Axis")

    def bodies(self) -> list:
        out = self.origin.bodies() + self.dir.bodies()
        if self.reference is not None:
            out += self.reference.bodies()
        return out

    def check_dim(self, dim: int) -> None:
        self.origin.check_dim(dim)
        self.dir.check_dim(dim)
        if self.reference is not None:
            self.reference.check_dim(dim)

    def location(self) -> sp.Matrix:
        return self.origin.location()

    def direction(self) -> sp.Matrix:
        return self.dir.direction()

    def __repr__(self) -> str:
        return f"Axis({self.origin!r}, {self.dir!r})"


class Line(Axis):
    """An axis given by two points: origin ``point1``, direction ``point2 - point1``."""

    def __init__(self, point1, point2):
        p1, p2 = as_point(point1), as_point(point2)
        super().__init__(p1, Vector(p1, p2))
        self.points = (p1, p2)

    def __repr__(self) -> str:
        return f"Line({self.points[0]!r}, {self.points[1]!r})"


def as_point(obj) -> Point:
    """Coerce: a :class:`Point`; an axis (its origin); a body (its origin); coordinates (ground)."""
    from ._bodies import Body

    if isinstance(obj, Point):
        return obj
    if isinstance(obj, Axis):
        return obj.origin
    if isinstance(obj, Body):
        return obj.point(0)
    if _is_coords(obj):
        return Point(None, obj)
    raise ModelError(f"expected a point (body.point(...) or a coordinate tuple), got {obj!r}")


def as_vector(obj) -> Vector:
    """Coerce: a :class:`Vector`; an axis or line (its direction); coordinates (global)."""
    if isinstance(obj, Vector):
        return obj
    if isinstance(obj, Axis):
        return obj.dir
    if _is_coords(obj):
        return Vector(None, obj)
    raise ModelError(f"expected a vector (body.vector(...) or a tuple), got {obj!r}")


def as_axis(obj) -> Axis:
    """Coerce: an :class:`Axis` or :class:`Line`; a pair ``(origin, direction)`` on ground."""
    if isinstance(obj, Axis):
        return obj
    if isinstance(obj, tuple) and len(obj) == 2 and not _is_coords(obj):
        return Axis(as_point(obj[0]), as_vector(obj[1]))
    raise ModelError(f"expected an axis (body.axis(origin, direction)), got {obj!r}")
