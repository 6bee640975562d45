"""Bodies: coordinates, local points, mass properties and the initial guess."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import sympy as sp

from .._errors import GeometryError, ModelError, UnknownPointError
from .._symbols import coord_symbol, number
from ._points import Axis, BodyRef, Line, Point, Vector, _as_matrix
from ._space import Space
from ._units import LENGTH, convert, has_quantity


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
        #: the generalized-coordinate joint whose slave this body is (None: own coordinates)
        self.gen_joint = None
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
        self.mass = mass
        if centroid is None:
            self.centroid = sp.zeros(space.dim, 1)
        else:
            self.centroid = _as_matrix(centroid, f"centroid of body {name!r}")
            if len(self.centroid) != space.dim:
                raise GeometryError(f"centroid of body {name!r} has {len(self.centroid)} "
                                    f"coordinates; this model is {space.dim}D")
        self.inertia = inertia

    # -- mass properties (checked whenever they are set) ----------------------------------
    @property
    def mass(self) -> sp.Expr:
        """Mass: a number >= 0 (0 is a massless link) or an expression of parameters."""
        return self._mass

    @mass.setter
    def mass(self, value) -> None:
        m = _scalar(value, f"mass of body {self.name!r}")
        if m.is_number and float(m) < 0:
            raise ModelError(f"mass of body {self.name!r} is negative ({m}); a mass must be >= 0 "
                             "(0 for a massless link)")
        self._mass = m

    @property
    def inertia(self):
        """Inertia about the centroid as given: a scalar ``J`` in 2D; in 3D
        ``(Ixx, Iyy, Izz, Ixy, Iyz, Izx)``, principal ``(Ixx, Iyy, Izz)`` or a 3x3 matrix."""
        return self._inertia

    @inertia.setter
    def inertia(self, value) -> None:
        if value is not None:
            _check_inertia(self.space, value, f"inertia of body {self.name!r}")
        self._inertia = value

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
            # (stored points were checked when added: a copy, as Point() would make)
            return Point._checked(self, self._points[spec].copy(), spec)
        if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
            if spec == 0:
                return Point._checked(self, sp.zeros(self.space.dim, 1), "origin")
            if not 1 <= spec <= len(self._order):
                raise UnknownPointError(
                    f"body {self.name!r} has no point number {spec}; it has "
                    f"{len(self._order)} point(s), numbered 1..{len(self._order)} (0 is the origin)"
                )
            key = self._order[spec - 1]
            return Point._checked(self, self._points[key].copy(), key)
        if has_quantity(spec):  # coordinates in the model's units (decision 0043)
            spec = convert(spec, self._units(), f"point of body {self.name!r}", LENGTH)
        p = Point(self, spec)
        p.check_dim(self.space.dim)
        return p

    def _units(self):
        model = getattr(self, "model", None)
        return getattr(model, "units", None)

    def vector(self, spec, to=None) -> Vector:
        """A vector fixed in this body: local components, or from the origin to a named point,
        or ``vector(p1, to=p2)`` from point ``p1`` to point ``p2`` of this body."""
        v = self._vector(spec, to)
        v.check_nonzero("vector")
        return v

    def _vector(self, spec, to=None) -> Vector:
        if to is not None:
            return Vector(self.point(spec), self.point(to))
        if isinstance(spec, (str, int)) and not isinstance(spec, bool):
            return Vector(self, self.point(spec).local)
        if has_quantity(spec):  # a direction keeps its own dimension (a length or none)
            spec = convert(spec, self._units(), f"vector of body {self.name!r}")
        v = Vector(self, spec)
        v.check_dim(self.space.dim)
        return v

    def axis(self, origin=0, direction=None, reference=None) -> Axis:
        """An axis through a point of this body along a local direction (default local x)."""
        if direction is None:
            direction = (1,) + (0,) * (self.space.dim - 1)
        try:
            d = direction if isinstance(direction, Vector) else self._vector(direction)
            ref = None
            if isinstance(reference, str) and reference in ("default", "minimal"):  # a rule (3D)
                ref = reference
            elif reference is not None:
                ref = reference if isinstance(reference, Vector) else self.vector(reference)
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
        g = np.array(pos + list(rot), dtype=float)
        if not np.isfinite(g).all():
            raise ModelError(f"guess of body {self.name!r} must be finite numbers; got {guess!r}")
        return g

    def __repr__(self) -> str:
        return f"<Body {self.number} {self.name!r}>"


def _scalar(value, what: str) -> sp.Expr:
    """A real scalar mass property: finite if numeric (parameter expressions pass)."""
    if isinstance(value, (str, bytes)):
        raise ModelError(f"{what} must be a number or an expression of parameters, got the "
                         f"string {value!r} (use the symbol m.parameter(...) returns)")
    try:
        # (a float: the same SymPy number for the same bits, decision 0086)
        v = number(value) if type(value) is float else sp.sympify(value, strict=True)
    except (sp.SympifyError, TypeError, ValueError, AttributeError, SyntaxError, NameError):
        v = None  # (a dict of strings is parsed as code: AttributeError, SyntaxError ...)
    if not isinstance(v, sp.Expr):
        raise ModelError(f"{what} must be a number or an expression of parameters, got {value!r}")
    if v.is_number and not (v.is_real and v.is_finite):
        raise ModelError(f"{what} must be a finite real number, got {value!r}")
    return v


def _check_inertia(space: Space, value, what: str) -> None:
    r"""Reject inertia no rigid body has: negative, not symmetric, not positive semidefinite
    or (3D) principal moments that break the triangle inequality ``I_k <= I_i + I_j``
    (``I_x + I_y - I_z = 2 integral z^2 dm >= 0``). Symbolic entries are not checked."""
    if space.dim == 2:
        J = _scalar(value, what + " (a planar inertia is one number J about the centroid)")
        if J.is_number and float(J) < 0:
            raise ModelError(f"{what} is negative ({J}); it must be >= 0")
        return
    if isinstance(value, (str, bytes)):
        raise ModelError(f"{what} must be numbers or expressions, got the string {value!r}")
    try:
        J = space.inertia_matrix(value)
    except (ValueError, TypeError, sp.SympifyError):
        raise ModelError(f"{what}: give (Ixx, Iyy, Izz, Ixy, Iyz, Izx), principal moments "
                         f"(Ixx, Iyy, Izz) or a 3x3 matrix; got {value!r}") from None
    for e in J:
        _scalar(e, what)
    if not all(e.is_number for e in J):
        return
    a = np.array(J.tolist(), dtype=float)
    scale = max(np.abs(a).max(), np.finfo(float).tiny)
    tol = 1e-9 * scale
    if np.abs(a - a.T).max() > tol:
        raise ModelError(f"{what} is not symmetric: {a.tolist()}; an inertia tensor has equal "
                         "products of inertia on both sides of the diagonal")
    if (np.diag(a) < -tol).any():
        raise ModelError(f"{what} has a negative moment of inertia on its diagonal "
                         f"{np.diag(a).tolist()}; moments must be >= 0")
    w = np.linalg.eigvalsh(a)  # ascending principal moments
    if w[0] < -tol:
        raise ModelError(f"{what} is not positive semidefinite (principal moments "
                         f"{w.tolist()}); check the signs of the products of inertia")
    if w[2] > w[0] + w[1] + tol:
        raise ModelError(f"{what}: the principal moments {w.tolist()} violate the triangle "
                         "inequality (each must be <= the sum of the other two), so no rigid "
                         "body has them")


def _normalize_points(points):
    if points is None:
        return []
    if isinstance(points, Mapping):
        return [(str(k), v) for k, v in points.items()]
    if isinstance(points, Sequence):
        return [(f"p{i + 1}", v) for i, v in enumerate(points)]
    raise ModelError(f"points must be a dict of name -> coordinates or a list; got {points!r}")
