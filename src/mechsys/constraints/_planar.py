r"""Constraints of planar models (and those written once for 2D and 3D).

Each docstring states the equations in Mech's order. ``r`` global points, ``u`` global
directions, ``x`` the scalar cross product :math:`a \times b = a_x\, b_y - a_y\, b_x` in 2D.
"""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError
from ..geometry._points import as_axis, as_point, as_vector
from . import _primitives as P
from ._angles import RelativeAngle1, RotationLock1
from ._base import ConstraintBase, TwoVectors, as_expr


def _body_of(obj, what: str):
    from ..geometry._bodies import Body

    if isinstance(obj, Body):
        return obj
    raise ModelError(f"{what}: expected a body (from model.add_body or model.ground), got {obj!r}")


class Coincident(ConstraintBase):
    """Two points coincide (:math:`r_1 - r_2 = 0`): the shared body of ``Revolute2`` (2D) and
    ``Spherical3`` (3D)."""

    def __init__(self, point1, point2):
        super().__init__()
        self.p1, self.p2 = as_point(point1), as_point(point2)

    def geometry(self):
        return [self.p1, self.p2]

    def _build(self, space):
        return P.coincident(self.p1, self.p2)


class Revolute2(Coincident):
    r"""Pin joint: two points coincide. Removes 2 DOF (2D).

    ``Revolute2(point1, point2)``:

    .. math::

        x_1 - x_2 &= 0 \\
        y_1 - y_2 &= 0
    """

    mech_name = "Revolute2"
    dof_removed = 2
    spaces = ("planar",)


class Translate2(ConstraintBase):
    r"""Prismatic joint: ``axis1`` slides along ``axis2`` without rotating. Removes 2 DOF (2D).

    ``Translate2(axis1, axis2)``; with :math:`d = r_{o1} - r_{o2}`:

    .. math::

        u_2 \times d &= 0 \qquad \text{(origin of axis1 on axis2)} \\
        u_2 \times u_1 &= 0 \qquad \text{(axes parallel)}
    """

    mech_name = "Translate2"
    dof_removed = 2
    spaces = ("planar",)

    def __init__(self, axis1, axis2):
        super().__init__()
        self.a1, self.a2 = as_axis(axis1), as_axis(axis2)

    def geometry(self):
        return [self.a1, self.a2]

    def _build(self, space):
        return P.point_on_line(space, self.a1.origin, self.a2) + P.parallel(space, self.a1.dir, self.a2.dir)


class OriginLock2(ConstraintBase):
    r"""Lock the origin of ``body1`` to that of ``body2`` (ground if omitted) plus ``offset``.
    Removes 2 DOF (2D).

    ``OriginLock2(body1, body2=None, offset=None)``; ``offset`` is a :class:`Vector` (global
    if a plain tuple):

    .. math::

        x_1 - x_2 - d_x &= 0 \\
        y_1 - y_2 - d_y &= 0
    """

    mech_name = "OriginLock2"
    dof_removed = 2
    spaces = ("planar",)

    def __init__(self, body1, body2=None, offset=None):
        super().__init__()
        self.b1 = _body_of(body1, "OriginLock2 body1")
        self.p1 = self.b1.point(0)
        self.p2 = _body_of(body2, "OriginLock2 body2").point(0) if body2 is not None else as_point((0, 0))
        self.offset = as_vector(offset) if offset is not None else None

    def geometry(self):
        return [self.p1, self.p2] + ([self.offset] if self.offset is not None else [])

    def sides(self):
        return [self.p1], [self.p2]

    def _build(self, space):
        off = self.offset.direction() if self.offset is not None else None
        return P.coincident(self.p1, self.p2, off)


# RotationLock1 and RelativeAngle1 are written once for 2D and 3D in ``_angles``.


class _RelativeCoordinate(ConstraintBase):
    _axis_index = 0
    dof_removed = 1

    def __init__(self, point1, point2_or_value=None, value=None):
        super().__init__()
        self.p1 = as_point(point1)
        if value is None and not _looks_like_point(point2_or_value):
            self.p2 = None
            self.value = as_expr(point2_or_value if point2_or_value is not None else 0, self.mech_name)
        else:
            self.p2 = as_point(point2_or_value)
            self.value = as_expr(value if value is not None else 0, self.mech_name)

    def geometry(self):
        return [self.p1] + ([self.p2] if self.p2 is not None else [])

    def _build(self, space):
        k = self._axis_index
        c2 = self.p2.location()[k] if self.p2 is not None else 0
        return [self.p1.location()[k] - c2 - self.value]


def _looks_like_point(obj) -> bool:
    from ..geometry._bodies import Body
    from ..geometry._points import Axis, Point

    return isinstance(obj, (Point, Axis, Body, tuple, list, sp.MatrixBase))


class RelativeX1(_RelativeCoordinate):
    r"""X coordinate of ``point1`` equals ``x`` or is ``dist`` more than that of ``point2``.
    Removes 1 DOF (2D/3D).

    ``RelativeX1(point, x)`` or ``RelativeX1(point1, point2, dist)``:

    .. math::

        x_1 - x_2 - \mathit{dist} = 0
    """

    mech_name = "RelativeX1"
    _axis_index = 0


class RelativeY1(_RelativeCoordinate):
    r"""Y coordinate of ``point1`` equals ``y`` or is ``dist`` more than that of ``point2``.
    Removes 1 DOF (2D/3D).

    ``RelativeY1(point, y)`` or ``RelativeY1(point1, point2, dist)``:

    .. math::

        y_1 - y_2 - \mathit{dist} = 0
    """

    mech_name = "RelativeY1"
    _axis_index = 1


class RelativeDistance1(ConstraintBase):
    r"""Distance between two points. Removes 1 DOF (2D/3D).

    ``RelativeDistance1(point1, point2, dist)``; with :math:`d = r_1 - r_2`:

    .. math::

        d \cdot d - \mathit{dist}^2 = 0

    Singular when ``dist`` is zero: use a coincident constraint (``Revolute2``) instead.
    """

    mech_name = "RelativeDistance1"
    dof_removed = 1

    def __init__(self, point1, point2, dist):
        super().__init__()
        self.p1, self.p2 = as_point(point1), as_point(point2)
        self.dist = as_expr(dist, "RelativeDistance1 dist")
        if self.dist.is_number and self.dist == 0:
            raise ModelError("RelativeDistance1 with dist = 0 is singular; use Revolute2 "
                             "(2D) or Spherical3 (3D) to make the points coincide")

    def geometry(self):
        return [self.p1, self.p2]

    def _build(self, space):
        return [P.distance_squared(self.p1, self.p2, self.dist)]


class Orthogonal1(TwoVectors):
    r"""Two vectors are orthogonal. Removes 1 DOF (2D/3D).

    ``Orthogonal1(vector1, vector2)``:

    .. math::

        u_1 \cdot u_2 = 0
    """

    mech_name = "Orthogonal1"
    dof_removed = 1

    def _build(self, space):
        return [P.dot(self.v1, self.v2)]


class Parallel1(TwoVectors):
    r"""Two vectors are parallel (or anti-parallel). Removes 1 DOF (2D).

    ``Parallel1(vector1, vector2)``:

    .. math::

        u_2 \times u_1 = 0
    """

    mech_name = "Parallel1"
    dof_removed = 1
    spaces = ("planar",)

    def _build(self, space):
        return P.parallel(space, self.v1, self.v2)


class PointOnLine1(ConstraintBase):
    r"""A point lies on a line (axis) of another body, or ``dist`` to its left. Removes 1 DOF (2D).

    ``PointOnLine1(point, line, dist=0)``; with :math:`d = r_p - r_o` and ``u`` the line's
    direction:

    .. math::

        u \times d - \mathit{dist}\, \lvert u \rvert = 0
    """

    mech_name = "PointOnLine1"
    dof_removed = 1
    spaces = ("planar",)

    def __init__(self, point, line, dist=0):
        super().__init__()
        self.p = as_point(point)
        self.axis = as_axis(line)
        self.dist = as_expr(dist, "PointOnLine1 dist")

    def geometry(self):
        return [self.p, self.axis]

    def _build(self, space):
        if self.dist == 0:
            return P.point_on_line(space, self.p, self.axis)
        return P.point_on_line(space, self.p, self.axis, self.dist)


__all__ = [
    "Revolute2",
    "Translate2",
    "OriginLock2",
    "RotationLock1",
    "RelativeX1",
    "RelativeY1",
    "RelativeDistance1",
    "RelativeAngle1",
    "Orthogonal1",
    "Parallel1",
    "PointOnLine1",
]
