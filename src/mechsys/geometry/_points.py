r"""Geometric objects attached to bodies: :class:`Point`, :class:`Vector`, :class:`Axis`,
:class:`Line` (and :class:`Plane` in 3D).

Each holds *local* coordinates on one body (SymPy expressions, so they may depend on time
``T`` or on parameters) and gives its *global* expression through the body's pose:

.. math::

    r_P &= r_b + A_b s'_P \qquad \text{(point)} \\
    v &= A_b v' \qquad \text{(vector)}

A plain coordinate tuple wherever a point is expected means a point on ground; wherever a
vector is expected, a vector in ground (global) coordinates.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence

import numpy as np
import sympy as sp

from .._errors import GeometryError, ModelError, close_match
from .._symbols import number


class BodyRef:
    """What points, vectors and rotations need to know of a body.

    :class:`~mechsys.Body` derives from it; the geometry below bodies tests
    ``isinstance(x, BodyRef)`` so that it never imports the body module (imports run down).
    """

    __slots__ = ()

    def point(self, spec) -> Point:  # pragma: no cover - Body implements it
        raise NotImplementedError


def _matrix(rows: int, cols: int, flat: list) -> sp.Matrix:
    r"""``sp.Matrix(rows, cols, flat)`` for entries that are SymPy expressions already: the
    same matrix (SymPy's own conversion of the entries to its domain matrix, an integer or
    rational domain when every entry is a rational number), without the generic input
    parsing and the per-entry ``sympify`` of ``sp.Matrix``, about 50 µs of the 60 to 110 µs
    a small matrix costs (decision 0079: the 1024-link chain builds some 10,000 of them).

    Example::

        x, y = sp.symbols("x y")
        _matrix(2, 1, [x, y]) == sp.Matrix([x, y])      # True
    """
    # (SymPy's ``_flat_list_to_DomainMatrix`` keeps the entries ``!= 0``; for an entry whose
    # type compares as ``Basic`` does, ``e != 0`` is True unless ``e`` is 0 itself, and SymPy
    # finds that only after looking for a converter of ``int``: ~2 µs an entry, a tenth of
    # the chain's model build (decision 0086). Numbers compare as SymPy compares them.)
    cls = sp.MutableDenseMatrix
    if _EXTERNAL.get(int) is not None or _EXTERNAL.get(object) is not None:
        # (someone taught sympify about ints: SymPy's own test, which asks that converter)
        return cls._fromrep(cls._flat_list_to_DomainMatrix(rows, cols, flat))
    basic_eq = sp.Basic.__eq__
    dod: dict = {}
    for n, e in enumerate(flat):
        if (type(e).__eq__ is basic_eq and e is not _ZERO) or (
                type(e).__eq__ is not basic_eq and e != 0):
            i, j = divmod(n, cols)
            dod.setdefault(i, {})[j] = e
    return cls._fromrep(cls._dod_to_DomainMatrix(rows, cols, dod, set(map(type, flat))))


_ZERO = sp.S.Zero
#: converters of other types registered with SymPy by third parties (SymPy's own dictionary)
_EXTERNAL = importlib.import_module("sympy.core.sympify")._external_converter


#: checked columns of plain Python numbers (:func:`_as_matrix`), by their exact values; bounded
_COLUMNS: dict = {}
_COLUMNS_MAX = 4096


def _as_matrix(coords, what: str) -> sp.Matrix:
    if isinstance(coords, np.ndarray):
        coords = coords.tolist()
    plain = type(coords) is tuple and all(type(c) is int or type(c) is float for c in coords)
    if plain:
        # a tuple of Python ints and floats (a point's or a centroid's coordinates): checked
        # once, then copied (a large model repeats them in every body: decision 0086); the
        # key keeps each number's type and exact value (0.0 and -0.0, 1 and 1.0 apart)
        key = tuple((c.hex() if type(c) is float else c, type(c) is float) for c in coords)
        got = _COLUMNS.get(key)
        if got is not None:
            return got.copy()
    if isinstance(coords, sp.MatrixBase):
        # a column already (a body's stored point): a copy of its entries, not a new Matrix
        # built element by element (~0.5 ms: a fifth of a large chain's build)
        m = (coords.copy() if type(coords) is sp.MutableDenseMatrix and coords.cols == 1
             else sp.Matrix(coords).reshape(len(coords), 1))
    elif isinstance(coords, Sequence) and not isinstance(coords, str):
        try:
            # (a float: the same SymPy number for the same bits, decision 0086)
            entries = [number(c) if type(c) is float else sp.sympify(c) for c in coords]
            m = _matrix(len(entries), 1, entries)
        except (sp.SympifyError, TypeError) as exc:
            raise GeometryError(f"{what}: coordinates {coords!r} are not numbers or expressions") from exc
    else:
        raise GeometryError(f"{what}: expected a coordinate tuple, got {coords!r}")
    for c in m:
        if not isinstance(c, sp.Expr) or (c.is_number and not (c.is_real and c.is_finite)):
            raise GeometryError(f"{what}: coordinates {coords!r} must be finite real numbers "
                                "or expressions")
    if plain:
        if len(_COLUMNS) >= _COLUMNS_MAX:
            _COLUMNS.clear()
        _COLUMNS[key] = m.copy()
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

    body: BodyRef | None

    def bodies(self) -> list:
        return [self.body] if self.body is not None else []

    def check_dim(self, dim: int) -> None:  # pragma: no cover - overridden
        pass

    def _owner(self) -> str:
        return f"body {self.body.name!r}" if self.body is not None else "ground"


class Point(Geometry):
    """A point fixed in a body, with local coordinates ``s'``: global ``r + A s'``."""

    def __init__(self, body: BodyRef | None, local, label: str | None = None):
        self.body = body
        self.local = _as_matrix(local, "Point")
        self.label = label

    @classmethod
    def _checked(cls, body: BodyRef, local: sp.Matrix, label: str | None) -> Point:
        """A point of ``body`` at ``local``, a new column the caller owns whose entries were
        checked already (a copy of a body's stored point): what ``Point(body, local, label)``
        gives, without copying and checking the entries again (~35 µs, 3 points a link of a
        chain: decision 0086)."""
        p = cls.__new__(cls)
        p.body, p.local, p.label = body, local, label
        return p

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
        # entry by entry, zero coordinates left out: SymPy's Matrix product and sum go through
        # its domain matrices (~2 ms a point: 4 s of a 1024-link chain's build); the same
        # expressions
        return _matrix(len(self.local), 1, [sp.Add(*terms) for terms in self._location_terms()])

    def _location_terms(self) -> list:
        """The terms of each entry of :meth:`location`: ``[r_i, A_i0 c'_0, ...]`` with the
        zero local coordinates left out (``[s'_i]`` on ground), for sums built in one
        ``Add`` (:func:`~mechsys.constraints._primitives.coincident`)."""
        c = self.local
        if self.body is None:
            return [[e] for e in c]
        r, A = self.body.r, self.body.A
        dim = len(c)
        cs = [c[j] for j in range(dim)]
        nz = [j for j in range(dim) if cs[j] != 0]
        return [[r[i], *(A[i, j] * cs[j] for j in nz)] for i in range(dim)]

    def __sub__(self, other: Point) -> Vector:
        return Vector(self, as_point(other))

    def __repr__(self) -> str:
        name = f"{self.label!r}, " if self.label else ""
        return f"Point({self._owner()}, {name}{tuple(self.local)})"


class Vector(Geometry):
    """A direction: fixed in a body (``Vector(body, (vx, vy))``), or from one point to
    another (``Vector(p_from, p_to)``), or any global expression (``Vector(None, expr)``)."""

    def __init__(self, a, b=None):
        self.endpoints = None
        if isinstance(a, Point) and b is not None:
            b = as_point(b)
            self.endpoints = (a, b)
            if a.body is b.body and len(a.local) == len(b.local):
                # both points on one body: a body-fixed direction, so that its normals are
                # body-fixed too (regular equations for every orientation)
                self.body = a.body
                self.points = None
                self.local = b.local - a.local
                return
            self.body = None
            self.points = (a, b)
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
        """Raise when the direction is zero whatever the coordinates: a zero local vector or
        two coincident points of one body. (``is_zero``, not ``== 0``: a SymPy ``Float``
        zero is not ``== 0``.)"""
        ends = self.endpoints if self.endpoints is not None else self.points
        if ends is not None:
            a, b = ends
            if a.body is b.body and len(a.local) == len(b.local) and all(
                    sp.simplify(x - y).is_zero for x, y in zip(a.local, b.local)):
                names = f"{a.label or tuple(a.local)!r} and {b.label or tuple(b.local)!r}"
                raise GeometryError(f"{what}: its two points coincide on {a._owner()} ({names}); "
                                    "give two distinct points")
            return
        if all(c.is_zero for c in self.local):
            raise GeometryError(f"{what}: zero-length direction on {self._owner()} (components "
                                f"{tuple(self.local)}); give a non-zero direction vector")

    def __repr__(self) -> str:
        ends = self.points if self.points is not None else self.endpoints
        if ends is not None:
            return f"Vector({ends[0]!r} -> {ends[1]!r})"
        return f"Vector({self._owner()}, {tuple(self.local)})"


class GlobalVector(Vector):
    """A direction given by a global expression of the coordinates of ``bodies`` (e.g. the
    normal of a plane through points of several bodies)."""

    def __init__(self, expr, bodies):
        super().__init__(None, expr)
        self._bodies = [b for b in bodies if b is not None]

    def bodies(self) -> list:
        return list(self._bodies)

    def is_local_constant(self) -> bool:
        return False

    def __repr__(self) -> str:
        return f"GlobalVector({tuple(self.local)})"


REFERENCE_RULES = ("default", "minimal")


def reference_direction(direction, rule: str = "default"):
    r"""The rotational reference direction of an axis that was given none: a unit vector
    perpendicular to ``direction`` (Mech's ``ReferenceDirection``).

    With ``u`` the unit direction, the reference is the image of +X under the smallest
    rotation that takes the Z axis of a frame onto ``u``:

    * ``"default"`` (non-singular for every direction): the frame is the global one when
      :math:`u_z \ge 0` and the one turned half a revolution about X (Z -> -Z) when
      :math:`u_z < 0`:

      .. math::

          \mathit{ref} = \left(1 - \frac{u_x^2}{1 + \lvert u_z \rvert},\;
          -\frac{u_x u_y}{1 + \lvert u_z \rvert},\; -s\, u_x\right), \qquad
          s = \operatorname{sign}(u_z) \ (s = +1 \text{ at } u_z = 0)

      so +Z gets +X, -Z gets +X, and the rule is continuous within each hemisphere (it jumps
      only across ``u_z = 0``, like Mech's ``Step``-function rule).
    * ``"minimal"`` (Mech's ``$MechUseMinimalRotation``): always from +Z,
      :math:`\mathit{ref} = (1 - u_x^2/(1 + u_z), -u_x u_y/(1 + u_z), -u_x)`; simpler, but singular at
      ``u = -Z``.

    Numeric input gives a NumPy array; SymPy input a SymPy column (a ``Piecewise`` for the
    default rule).
    """
    if rule not in REFERENCE_RULES:
        raise GeometryError(f"reference rule must be one of {REFERENCE_RULES}, got {rule!r}"
                            f"{close_match(rule, REFERENCE_RULES)}")
    vals = list(direction)
    symbolic = any(isinstance(c, sp.Basic) and not c.is_number for c in vals)
    if not symbolic:
        u = np.array([float(c) for c in vals])
        n = np.linalg.norm(u)
        if n == 0:
            raise GeometryError("reference direction of a zero-length axis direction")
        ux, uy, uz = u / n
        if rule == "minimal":
            if 1 + uz < 1e-12:
                raise GeometryError(
                    "the minimal-rotation reference rule is singular for an axis along -Z; "
                    "use the default rule or give a reference direction")
            return np.array([1 - ux * ux / (1 + uz), -ux * uy / (1 + uz), -ux])
        s = 1.0 if uz >= 0 else -1.0
        a = 1 + abs(uz)
        return np.array([1 - ux * ux / a, -ux * uy / a, -s * ux])
    u = sp.Matrix(vals)
    ux, uy, uz = u / sp.sqrt(u.dot(u))
    up = [1 - ux**2 / (1 + uz), -ux * uy / (1 + uz), -ux]
    if rule == "minimal":
        return sp.Matrix(up)
    down = [1 - ux**2 / (1 - uz), -ux * uy / (1 - uz), ux]
    return sp.Matrix([sp.Piecewise((a, uz >= 0), (b, True)) for a, b in zip(up, down, strict=True)])


def _local_numeric(m):
    try:
        return np.array([float(c) for c in m])
    except TypeError:
        return None


class Axis(Geometry):
    """An origin point and a direction, and in 3D a rotational reference direction.

    ``Axis(origin, direction, reference=None)``: ``reference`` is a vector (only its part
    perpendicular to ``direction`` matters) or the name of a rule, ``"default"`` or
    ``"minimal"`` (see :func:`reference_direction`), used when none is given. The rule is
    applied to the direction in the coordinates of the body that carries it, so the
    reference is fixed in that body.
    """

    def __init__(self, origin: Point, direction: Vector, reference=None):
        self.origin = as_point(origin)
        self.dir = as_vector(direction)
        self.reference_rule = "default"
        if isinstance(reference, str):
            if reference not in REFERENCE_RULES:
                raise GeometryError(f"Axis reference must be a vector or one of "
                                    f"{REFERENCE_RULES}; got {reference!r}"
                                    f"{close_match(reference, REFERENCE_RULES)}")
            self.reference_rule = reference
            reference = None
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

    def reference_vector(self) -> Vector:
        """The unit reference direction, perpendicular to the axis direction (3D).

        Body-fixed (``A g'``) whenever the direction is fixed in a body: an explicit reference
        fixed in the same body is orthonormalised in local coordinates, else the rule is
        applied to the local direction. Otherwise a global expression.
        """
        d, r = self.dir, self.reference
        # the dimension from the local components: ``d.direction()`` would multiply a body's
        # symbolic rotation matrix in SymPy (5-10 ms, half of reading a 7-joint arm's URDF)
        if len(d.local if d.points is None else d.points[0].local) != 3:
            raise GeometryError("reference directions exist for 3D axes only")
        if d.points is None and not isinstance(d, GlobalVector):
            if r is None:
                g = reference_direction(d.local, self.reference_rule)
                return Vector(d.body, tuple(g))
            if r.points is None and not isinstance(r, GlobalVector) and r.body is d.body:
                u, g = _local_numeric(d.local), _local_numeric(r.local)
                if u is not None and g is not None:
                    g = g - (g @ u) / (u @ u) * u
                    n = np.linalg.norm(g)
                    if n < 1e-12 * max(1.0, np.linalg.norm(_local_numeric(r.local))):
                        raise GeometryError(
                            f"axis on {self._owner()}: the reference direction {tuple(r.local)} "
                            f"is parallel to the axis direction {tuple(d.local)}; give a "
                            "reference perpendicular to the axis")
                    return Vector(d.body, tuple(g / n))
                u, g = d.local, r.local
                g = g - (g.dot(u) / u.dot(u)) * u
                return Vector(d.body, tuple(g / sp.sqrt(g.dot(g))))
        u = d.direction()
        if r is None:
            g = reference_direction(u, self.reference_rule)
            return GlobalVector(g, self.bodies())
        g = r.direction()
        g = g - (g.dot(u) / u.dot(u)) * u
        return GlobalVector(g / sp.sqrt(g.dot(g)), self.bodies())

    def __repr__(self) -> str:
        return f"Axis({self.origin!r}, {self.dir!r})"


class Line(Axis):
    """An axis given by two points: origin ``point1``, direction ``point2 - point1``. Its
    reference direction follows the default rule (it cannot be given)."""

    def __init__(self, point1, point2):
        p1, p2 = as_point(point1), as_point(point2)
        super().__init__(p1, Vector(p1, p2))
        self.points = (p1, p2)

    def __repr__(self) -> str:
        return f"Line({self.points[0]!r}, {self.points[1]!r})"


class Plane(Axis):
    r"""A plane through three points (3D): origin ``point1``, normal
    :math:`(r_2 - r_1) \times (r_3 - r_1)` and reference direction from ``point1`` to ``point2``.

    ``Plane(point1, point2, point3)`` or ``Plane(body, p1, p2, p3)`` (point names, numbers
    or local coordinates of ``body``). Used where a vector is expected it gives its normal;
    where an axis is expected, origin, normal and reference.
    """

    def __init__(self, *args):

        if len(args) == 4 and isinstance(args[0], BodyRef):
            body = args[0]
            pts = [body.point(p) for p in args[1:]]
        elif len(args) == 3:
            pts = [as_point(p) for p in args]
        else:
            raise ModelError("Plane takes three points, or a body and three of its points")
        for p in pts:
            p.check_dim(3)
        p1, p2, p3 = pts
        owners = {id(p.body) for p in pts}
        if len(owners) == 1:
            a, b = p2.local - p1.local, p3.local - p1.local
            n = a.cross(b)
            if all(c.is_number for c in n) and all(abs(float(c)) < 1e-14 for c in n):
                raise GeometryError(
                    f"Plane on {p1._owner()}: its three points are collinear; give three points "
                    "that span a plane")
            normal = Vector(p1.body, n)
            ref = Vector(p1.body, a)
        else:
            r1 = p1.location()
            n = (p2.location() - r1).cross(p3.location() - r1)
            normal = GlobalVector(n, [p.body for p in pts])
            ref = Vector(p1, p2)
        super().__init__(p1, normal, ref)
        self.points = (p1, p2, p3)

    def __repr__(self) -> str:
        return f"Plane({self.points[0]!r}, {self.points[1]!r}, {self.points[2]!r})"


def as_point(obj) -> Point:
    """Coerce: a :class:`Point`; an axis (its origin); a body (its origin); coordinates (ground)."""

    if isinstance(obj, Point):
        return obj
    if isinstance(obj, Axis):
        return obj.origin
    if isinstance(obj, BodyRef):
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
