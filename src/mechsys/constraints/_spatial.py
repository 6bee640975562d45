r"""Constraints of spatial (3D) models.

Notation in the docstrings: an axis ``i`` has origin :math:`r_i`, direction :math:`u_i` (global;
``A u'`` when fixed in a body), reference direction :math:`g_i` (unit, perpendicular to
:math:`u_i`; see :func:`~mechsys.reference_direction`) and two *normals* :math:`h_i, f_i`
perpendicular to :math:`u_i` and to each other, fixed in the axis' body (so the equations
stay regular for every orientation). :math:`d = r_1 - r_2` joins the origins; :math:`\lvert u \rvert` is a
length (constant for body-fixed vectors). Equations are listed in Mech's order where its
reference gives one.

Constraints written once for 2D and 3D live elsewhere: ``Orthogonal1``, ``RelativeX1``,
``RelativeY1``, ``RelativeDistance1`` (``_planar``), ``RotationLock1``, ``RelativeAngle1``
(``_angles``), ``Constraint`` (``_general``).
"""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError
from ..geometry._points import as_axis, as_point
from ..geometry._rotations import _parse as _rotation_spec
from ..geometry._rotations import quaternion_inverse, quaternion_product
from . import _primitives as P
from ._angles import angle_equation, angle_frame, vector_norm
from ._base import ConstraintBase, as_expr
from ._planar import Coincident, OriginLock2, Parallel1, _RelativeCoordinate


def _nonzero(value, what: str, use: str) -> sp.Expr:
    v = as_expr(value, what)
    if v.is_number and v == 0:
        raise ModelError(f"{what} = 0 is singular; use {use} instead")
    return v


class _TwoAxes(ConstraintBase):
    """Base of constraints between ``axis1`` and ``axis2``."""

    spaces = ("spatial",)

    def __init__(self, axis1, axis2):
        super().__init__()
        self.a1, self.a2 = as_axis(axis1), as_axis(axis2)

    def geometry(self):
        return [self.a1, self.a2]

    def _d(self):
        return self.a1.location() - self.a2.location()


# -- points and bodies -----------------------------------------------------------------------


class Spherical3(Coincident):
    r"""Ball joint: two points coincide. Removes 3 DOF (3D).

    ``Spherical3(point1, point2)``:

    .. math::

        x_1 - x_2 &= 0 \\
        y_1 - y_2 &= 0 \\
        z_1 - z_2 &= 0
    """

    mech_name = "Spherical3"
    dof_removed = 3
    spaces = ("spatial",)


class OriginLock3(OriginLock2):
    r"""Lock the origin of ``body1`` to that of ``body2`` (ground if omitted) plus ``offset``.
    Removes 3 DOF (3D).

    ``OriginLock3(body1, body2=None, offset=None)``; ``offset`` is a :class:`Vector` (global
    if a plain tuple):

    .. math::

        x_1 - x_2 - d_x &= 0 \\
        y_1 - y_2 - d_y &= 0 \\
        z_1 - z_2 - d_z &= 0
    """

    mech_name = "OriginLock3"
    dof_removed = 3
    spaces = ("spatial",)

    def __init__(self, body1, body2=None, offset=None):
        super().__init__(body1, body2, offset)
        if body2 is None:
            self.p2 = as_point((0, 0, 0))


class RotationLock3(ConstraintBase):
    r"""Lock the orientation of ``body1`` to that of ``body2`` (ground if omitted), turned by
    a rotation. Removes 3 DOF (3D).

    ``RotationLock3(body1)``, ``RotationLock3(body1, body2)``,
    ``RotationLock3(body1, body2, rot1, rot2, ...)``, ``RotationLock3(body1, rot1, ...)``
    (``body2`` omitted or ``None``: ground). Each
    ``rot`` is ``(angle, (x, y, z))``, Euler parameters or a virtual rotation; angles may be
    expressions of ``T``. As in Mech, ``rot1``'s axis is in ``body2``'s coordinates,
    ``rot2``'s in those coordinates turned by ``rot1``, and so on: :math:`A_1 = A_2\, R_1\, R_2\, ...`.

    With :math:`p = e_2 * q_R` (quaternion product; :math:`q_R` the Euler parameters of
    :math:`R_1\, R_2\, ...`) and :math:`e_1` the Euler parameters of ``body1``, the equations are the
    vector part of the relative rotation :math:`p^{-1} * e_1`:

    .. math::

        p_0\, e_{1,x} - e_{1,0}\, p_x - (p_v \times e_{1,v})_x &= 0 \\
        p_0\, e_{1,y} - e_{1,0}\, p_y - (p_v \times e_{1,v})_y &= 0 \\
        p_0\, e_{1,z} - e_{1,0}\, p_z - (p_v \times e_{1,v})_z &= 0

    Regular at the solution, and satisfied only by the intended orientation (:math:`e_1 = \pm p`,
    one rotation).
    """

    mech_name = "RotationLock3"
    dof_removed = 3
    spaces = ("spatial",)

    def __init__(self, body1, body2=None, *rotations):
        super().__init__()
        from ..geometry._bodies import Body

        if not isinstance(body1, Body):
            raise ModelError(f"RotationLock3 body1: expected a body, got {body1!r}")
        if body2 is not None and not isinstance(body2, Body):  # body2 omitted: ground
            rotations = (body2, *rotations)
            body2 = None
        self.b1, self.b2 = body1, body2
        q = [sp.S.One, sp.S.Zero, sp.S.Zero, sp.S.Zero]
        for rot in rotations:
            q = quaternion_product(q, [sp.sympify(c) for c in _rotation_spec(rot)])
        self.q_rel = q

    def geometry(self):
        return [self.b1.point(0)] + ([self.b2.point(0)] if self.b2 is not None else [])

    @staticmethod
    def _params(body):
        if body is None or body.is_ground:
            return [sp.S.One, sp.S.Zero, sp.S.Zero, sp.S.Zero]
        return list(body.q[3:])

    def _build(self, space):
        p = quaternion_product(self._params(self.b2), self.q_rel)
        rel = quaternion_product(quaternion_inverse(p), self._params(self.b1))
        return rel[1:]


class RelativeZ1(_RelativeCoordinate):
    r"""Z coordinate of ``point1`` equals ``z`` or is ``dist`` more than that of ``point2``.
    Removes 1 DOF (3D).

    ``RelativeZ1(point, z)`` or ``RelativeZ1(point1, point2, dist)``:

    .. math::

        z_1 - z_2 - \mathit{dist} = 0
    """

    mech_name = "RelativeZ1"
    _axis_index = 2
    spaces = ("spatial",)


class Parallel2(Parallel1):
    r"""Two vectors are parallel (or anti-parallel). Removes 2 DOF (3D).

    ``Parallel2(vector1, vector2)``; :math:`h_2, f_2` normals of ``vector2``:

    .. math::

        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0
    """

    mech_name = "Parallel2"
    dof_removed = 2
    spaces = ("spatial",)


# -- points on lines, planes and circles -----------------------------------------------------


class PointOnLine2(ConstraintBase):
    r"""A point lies on a line (axis). Removes 2 DOF (3D).

    ``PointOnLine2(point, line)``; with :math:`d = r_p - r_o` and ``h, f`` the line's normals:

    .. math::

        h \cdot d &= 0 \\
        f \cdot d &= 0
    """

    mech_name = "PointOnLine2"
    dof_removed = 2
    spaces = ("spatial",)

    def __init__(self, point, line):
        super().__init__()
        self.p, self.axis = as_point(point), as_axis(line)

    def geometry(self):
        return [self.p, self.axis]

    def _build(self, space):
        return P.point_on_line(space, self.p, self.axis)


class PointOnPlane1(ConstraintBase):
    r"""A point lies in the plane normal to an axis through its origin, or ``dist`` from it
    on the side the axis points to. Removes 1 DOF (3D).

    ``PointOnPlane1(point, axis_or_plane, dist=0)``; with :math:`d = r_p - r_o`:

    .. math::

        u \cdot d - \mathit{dist}\, \lvert u \rvert = 0
    """

    mech_name = "PointOnPlane1"
    dof_removed = 1
    spaces = ("spatial",)

    def __init__(self, point, plane, dist=0):
        super().__init__()
        self.p, self.axis = as_point(point), as_axis(plane)
        self.dist = as_expr(dist, "PointOnPlane1 dist")

    def geometry(self):
        return [self.p, self.axis]

    def _build(self, space):
        u = self.axis.direction()
        d = self.p.location() - self.axis.location()
        return [u.dot(d) - self.dist * vector_norm(self.axis.dir)]


class PointOnCircle2(ConstraintBase):
    r"""A point lies on the circle of radius ``rad`` centred at the origin of an axis, in the
    plane normal to it. Removes 2 DOF (3D).

    ``PointOnCircle2(point, axis, rad)``; with :math:`d = r_p - r_o`:

    .. math::

        u \cdot d &= 0 \\
        d \cdot d - \mathit{rad}^2 &= 0
    """

    mech_name = "PointOnCircle2"
    dof_removed = 2
    spaces = ("spatial",)

    def __init__(self, point, axis, rad):
        super().__init__()
        self.p, self.axis = as_point(point), as_axis(axis)
        self.rad = _nonzero(rad, "PointOnCircle2 rad", "Spherical3 (a point at the centre)")

    def geometry(self):
        return [self.p, self.axis]

    def _build(self, space):
        d = self.p.location() - self.axis.location()
        return [self.axis.direction().dot(d), d.dot(d) - self.rad**2]


class PointAtIntersection3(ConstraintBase):
    r"""A point lies where ``axis1`` crosses the plane through the origin of ``axis2`` normal
    to it (``axis2`` is typically a :class:`Plane`). Removes 3 DOF (3D).

    ``PointAtIntersection3(point, axis1, axis2)``; with :math:`h_1, f_1` the normals of
    ``axis1``:

    .. math::

        h_1 \cdot (r_p - r_1) &= 0 \\
        f_1 \cdot (r_p - r_1) &= 0 \\
        u_2 \cdot (r_p - r_2) &= 0
    """

    mech_name = "PointAtIntersection3"
    dof_removed = 3
    spaces = ("spatial",)

    def __init__(self, point, axis1, axis2):
        super().__init__()
        self.p = as_point(point)
        self.a1, self.a2 = as_axis(axis1), as_axis(axis2)

    def geometry(self):
        return [self.p, self.a1, self.a2]

    def _build(self, space):
        d2 = self.p.location() - self.a2.location()
        return P.point_on_line(space, self.p, self.a1) + [self.a2.direction().dot(d2)]


# -- joints between two axes -----------------------------------------------------------------


class Revolute5(_TwoAxes):
    r"""Hinge: the origins coincide and the axes are parallel. Removes 5 DOF (3D).

    ``Revolute5(axis1, axis2)``; :math:`h_2, f_2` normals of ``axis2``:

    .. math::

        x_1 - x_2 &= 0 \\
        y_1 - y_2 &= 0 \\
        z_1 - z_2 &= 0 \\
        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0

    Parallel (not anti-parallel) axes are the branch a guess near them converges to.
    """

    mech_name = "Revolute5"
    dof_removed = 5

    def _build(self, space):
        return (P.coincident(self.a1.origin, self.a2.origin)
                + P.parallel(space, self.a1.dir, self.a2.dir))


class Cylindrical4(_TwoAxes):
    r"""The axes are colinear: they may slide along and turn about each other. Removes 4 DOF.

    ``Cylindrical4(axis1, axis2)``; :math:`h_1, f_1` normals of ``axis1`` (Mech's order: the
    origin of ``axis2`` on ``axis1``, then parallel):

    .. math::

        h_1 \cdot (r_2 - r_1) &= 0 \\
        f_1 \cdot (r_2 - r_1) &= 0 \\
        h_1 \cdot u_2 &= 0 \\
        f_1 \cdot u_2 &= 0
    """

    mech_name = "Cylindrical4"
    dof_removed = 4

    def _build(self, space):
        return (P.point_on_line(space, self.a2.origin, self.a1)
                + P.parallel(space, self.a2.dir, self.a1.dir))


class Translate5(Cylindrical4):
    r"""Prismatic joint: the axes are colinear and their reference directions parallel, so
    they only slide. Removes 5 DOF (3D).

    ``Translate5(axis1, axis2)``; the four ``Cylindrical4`` equations, then, with :math:`g_i` the
    reference directions and :math:`k_1 = \hat{u}_1 \times g_1`:

    .. math::

        h_1 \cdot (r_2 - r_1) &= 0 \\
        f_1 \cdot (r_2 - r_1) &= 0 \\
        h_1 \cdot u_2 &= 0 \\
        f_1 \cdot u_2 &= 0 \\
        k_1 \cdot g_2 &= 0
    """

    mech_name = "Translate5"
    dof_removed = 5

    def _build(self, space):
        g2 = angle_frame(space, self.a2)[0]
        return super()._build(space) + [angle_equation(angle_frame(space, self.a1), g2, 0)]


class Universal4(_TwoAxes):
    r"""Universal (Hooke, Cardan) joint: the origins coincide and the two axes -- the
    cross-pin directions fixed in each body -- stay perpendicular. Removes 4 DOF (3D).

    ``Universal4(axis1, axis2)``: ``axis1`` is the pin (yoke) axis of body 1, ``axis2`` that
    of body 2, through the joint centre:

    .. math::

        x_1 - x_2 &= 0 \\
        y_1 - y_2 &= 0 \\
        z_1 - z_2 &= 0 \\
        u_1 \cdot u_2 &= 0
    """

    mech_name = "Universal4"
    dof_removed = 4

    def _build(self, space):
        return P.coincident(self.a1.origin, self.a2.origin) + [P.dot(self.a1.dir, self.a2.dir)]


class ConstantVelocity4(_TwoAxes):
    r"""Constant-velocity joint: the origins coincide and the two shafts (the axes) spin
    equally. Removes 4 DOF (3D).

    ``ConstantVelocity4(axis1, axis2, C=0)``. The spin of shaft ``i`` is the angle about
    :math:`u_i` from :math:`n = u_1 \times u_2` to its reference direction :math:`g_i`; the
    joint keeps :math:`\mathit{spin}_2 = \mathit{spin}_1 + C`. That holds exactly when the
    relative rotation from frame 1 :math:`(g_1, k_1, \hat{u}_1)` (:math:`k_i = \hat{u}_i \times
    g_i`) to frame 2 turned back by ``C``, :math:`(g_2^{\prime}, k_2^{\prime}, \hat{u}_2)` with
    :math:`g_2^{\prime} = \cos C\, g_2 - \sin C\, k_2`, :math:`k_2^{\prime} = \sin C\, g_2 +
    \cos C\, k_2`, has its rotation axis perpendicular to :math:`u_1` -- a pure bend about
    ``n``:

    .. math::

        x_1 - x_2 &= 0 \\
        y_1 - y_2 &= 0 \\
        z_1 - z_2 &= 0 \\
        k_1 \cdot g_2^{\prime} - g_1 \cdot k_2^{\prime} &= 0

    The last equation (twice the sine-weighted axial component of the relative rotation) is
    regular at every bend, including zero bend where the spin reference ``n`` is undefined.
    The output shaft then turns at exactly the input speed.
    """

    mech_name = "ConstantVelocity4"
    dof_removed = 4

    def __init__(self, axis1, axis2, C=0):
        super().__init__(axis1, axis2)
        self.C = as_expr(C, "ConstantVelocity4 C")

    def _build(self, space):
        g1, k1 = angle_frame(space, self.a1)
        g2, k2 = angle_frame(space, self.a2)
        c, s = sp.cos(self.C), sp.sin(self.C)
        g2p, k2p = c * g2 - s * k2, s * g2 + c * k2
        return P.coincident(self.a1.origin, self.a2.origin) + [k1.dot(g2p) - g1.dot(k2p)]


class ParaRevolute4(_TwoAxes):
    r"""Two parallel hinges ``dist`` apart: ``axis1`` parallel to ``axis2``, their origins
    side by side, the axes ``dist`` apart. Removes 4 DOF (3D).

    ``ParaRevolute4(axis1, axis2, dist)`` (Mech's order: parallel, adjacent, distance):

    .. math::

        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0 \\
        u_2 \cdot d &= 0 \\
        d \cdot d - \mathit{dist}^2 &= 0

    Singular for :math:`\mathit{dist} = 0`: use ``Revolute5``.
    """

    mech_name = "ParaRevolute4"
    dof_removed = 4

    def __init__(self, axis1, axis2, dist):
        super().__init__(axis1, axis2)
        self.dist = _nonzero(dist, "ParaRevolute4 dist", "Revolute5")

    def _build(self, space):
        d = self._d()
        return (P.parallel(space, self.a1.dir, self.a2.dir)
                + [self.a2.direction().dot(d), d.dot(d) - self.dist**2])


class OrthoRevolute4(_TwoAxes):
    r"""Two perpendicular hinges ``dist`` apart (a universal joint with offset pins).
    Removes 4 DOF (3D).

    ``OrthoRevolute4(axis1, axis2, dist=0)``; ``dist`` is signed: the origin of ``axis1``
    lies ``dist`` from that of ``axis2`` along :math:`\hat{u}_1 \times \hat{u}_2` (Mech's order: origin 2 next
    to axis 1, origin 1 next to axis 2, separation, perpendicular):

    .. math::

        u_1 \cdot (r_2 - r_1) &= 0 \\
        u_2 \cdot d &= 0 \\
        (u_1 \times u_2) \cdot d - \mathit{dist}\, \lvert u_1 \rvert\, \lvert u_2 \rvert &= 0 \\
        u_1 \cdot u_2 &= 0

    Regular for every ``dist``, zero included.
    """

    mech_name = "OrthoRevolute4"
    dof_removed = 4

    def __init__(self, axis1, axis2, dist=0):
        super().__init__(axis1, axis2)
        self.dist = as_expr(dist, "OrthoRevolute4 dist")

    def _build(self, space):
        d = self._d()
        u1, u2 = self.a1.direction(), self.a2.direction()
        n = vector_norm(self.a1.dir) * vector_norm(self.a2.dir)
        return [-u1.dot(d), u2.dot(d), u1.cross(u2).dot(d) - self.dist * n, u1.dot(u2)]


class LineOnCylinder3(_TwoAxes):
    r"""``axis1`` is parallel to ``axis2`` and ``rad`` away from it (a line on a cylinder).
    Removes 3 DOF (3D).

    ``LineOnCylinder3(axis1, axis2, rad)``:

    .. math::

        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0 \\
        d \cdot d - (u_2 \cdot d)^2 / \lvert u_2 \rvert^2 - \mathit{rad}^2 &= 0

    Singular for :math:`\mathit{rad} = 0`: use ``Cylindrical4``.
    """

    mech_name = "LineOnCylinder3"
    dof_removed = 3

    def __init__(self, axis1, axis2, rad):
        super().__init__(axis1, axis2)
        self.rad = _nonzero(rad, "LineOnCylinder3 rad", "Cylindrical4")

    def _build(self, space):
        d = self._d()
        u2 = self.a2.direction()
        n2 = vector_norm(self.a2.dir) ** 2
        return (P.parallel(space, self.a1.dir, self.a2.dir)
                + [d.dot(d) - u2.dot(d) ** 2 / n2 - self.rad**2])


class LineToCircle1(_TwoAxes):
    r"""``axis1`` (a line) passes through the circle of radius ``rad`` centred at the origin
    of ``axis2`` in the plane normal to it (a shaft in a bearing with clearance). Removes
    1 DOF (3D).

    ``LineToCircle1(axis1, axis2, rad)``; the line meets the circle's plane at
    :math:`p = r_1 + u_1\, (u_2 \cdot (r_2 - r_1)) / c` with :math:`c = u_2 \cdot u_1`; multiplied through by
    ``c`` (no division), with :math:`w = c\, (r_1 - r_2) + (u_2 \cdot (r_2 - r_1))\, u_1 = c\, (p - r_2)`:

    .. math::

        w \cdot w - \mathit{rad}^2\, c^2 = 0

    (the line must not lie parallel to the circle's plane).
    """

    mech_name = "LineToCircle1"
    dof_removed = 1

    def __init__(self, axis1, axis2, rad):
        super().__init__(axis1, axis2)
        self.rad = _nonzero(rad, "LineToCircle1 rad", "PointAtIntersection3 or Cylindrical4")

    def _build(self, space):
        d = self._d()
        u1, u2 = self.a1.direction(), self.a2.direction()
        c = u2.dot(u1)
        w = c * d - u2.dot(d) * u1
        return [w.dot(w) - self.rad**2 * c**2]


class LineToLine1(_TwoAxes):
    r"""The shortest distance between two lines is ``dist``; without ``dist`` the lines
    intersect. Removes 1 DOF (3D).

    ``LineToLine1(axis1, axis2, dist=0)``; with :math:`w = u_1 \times u_2`:

    .. math::

        w \cdot d &= 0 \qquad \text{(intersecting form)} \\
        (w \cdot d)^2 - \mathit{dist}^2\, (w \cdot w) &= 0
        \qquad \text{(distance form, } \mathit{dist} \neq 0 \text{)}

    Both are regular at their solutions while the lines are not parallel. The distance form
    is a line tangent to a cylinder of radius ``dist`` about the other line.
    """

    mech_name = "LineToLine1"
    dof_removed = 1

    def __init__(self, axis1, axis2, dist=0):
        super().__init__(axis1, axis2)
        self.dist = as_expr(dist, "LineToLine1 dist")

    def _build(self, space):
        w = self.a1.direction().cross(self.a2.direction())
        wd = w.dot(self._d())
        if self.dist.is_number and self.dist == 0:
            return [wd]
        return [wd**2 - self.dist**2 * w.dot(w)]


class LineToPlane2(_TwoAxes):
    r"""``axis1`` lies in the plane normal to ``axis2`` through its origin (typically a
    :class:`Plane`), or in the parallel plane ``dist`` away along :math:`u_2`. Removes 2 DOF (3D).

    ``LineToPlane2(axis1, axis2, dist=0)``:

    .. math::

        u_1 \cdot u_2 &= 0 \\
        u_2 \cdot d - \mathit{dist}\, \lvert u_2 \rvert &= 0
    """

    mech_name = "LineToPlane2"
    dof_removed = 2

    def __init__(self, axis1, axis2, dist=0):
        super().__init__(axis1, axis2)
        self.dist = as_expr(dist, "LineToPlane2 dist")

    def _build(self, space):
        u2 = self.a2.direction()
        return [self.a1.direction().dot(u2),
                u2.dot(self._d()) - self.dist * vector_norm(self.a2.dir)]


class PlaneToPlane3(_TwoAxes):
    r"""The planes normal to two axes are parallel, ``dist`` apart (coincident without
    ``dist``). Removes 3 DOF (3D).

    ``PlaneToPlane3(axis1, axis2, dist=0)``: the origin of ``axis1`` lies ``dist`` from that of
    ``axis2`` along :math:`u_2`:

    .. math::

        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0 \\
        u_2 \cdot d - \mathit{dist}\, \lvert u_2 \rvert &= 0
    """

    mech_name = "PlaneToPlane3"
    dof_removed = 3

    def __init__(self, axis1, axis2, dist=0):
        super().__init__(axis1, axis2)
        self.dist = as_expr(dist, "PlaneToPlane3 dist")

    def _build(self, space):
        u2 = self.a2.direction()
        return (P.parallel(space, self.a1.dir, self.a2.dir)
                + [u2.dot(self._d()) - self.dist * vector_norm(self.a2.dir)])


class Planar3(PlaneToPlane3):
    r"""Planar joint: the planes normal to the two axes coincide (or lie ``dist`` apart), so
    the bodies slide on each other and turn about the normal. Removes 3 DOF (3D).

    ``Planar3(axis1, axis2, dist=0)``; the equations of ``PlaneToPlane3``:

    .. math::

        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0 \\
        u_2 \cdot d - \mathit{dist}\, \lvert u_2 \rvert &= 0
    """

    mech_name = "Planar3"


class PlaneToCircle1(_TwoAxes):
    r"""The plane normal to ``axis1`` through its origin touches a circle (a wheel on the
    ground), or a torus. Removes 1 DOF (3D).

    ``PlaneToCircle1(axis1, axis2, rad)``: circle of radius ``rad`` centred at the origin of
    ``axis2``, in the plane normal to :math:`u_2`. ``PlaneToCircle1(axis1, axis2, majrad,
    minrad)``: torus with that core circle and tube radius ``minrad``. The circle (torus) lies
    on the side of the plane that :math:`u_1` points to; its nearest point is at height
    :math:`\hat{u}_1 \cdot (r_2 - r_1) - \mathit{majrad}\, \lvert \hat{u}_1 \times \hat{u}_2
    \rvert`, which must equal ``minrad`` (0 for a circle):

    .. math::

        u_1 \cdot (r_2 - r_1) - \mathit{rad}\, \lvert u_1 \times u_2 \rvert / \lvert u_2 \rvert
        - \mathit{minrad}\, \lvert u_1 \rvert = 0

    Regular while the circle's plane is not parallel to the plane (then it would lie in it).
    """

    mech_name = "PlaneToCircle1"
    dof_removed = 1

    def __init__(self, axis1, axis2, rad, minrad=0):
        super().__init__(axis1, axis2)
        self.rad = as_expr(rad, "PlaneToCircle1 rad")
        self.minrad = as_expr(minrad, "PlaneToCircle1 minrad")

    def _build(self, space):
        u1, u2 = self.a1.direction(), self.a2.direction()
        w = u1.cross(u2)
        return [-u1.dot(self._d()) - self.rad * sp.sqrt(w.dot(w)) / vector_norm(self.a2.dir)
                - self.minrad * vector_norm(self.a1.dir)]


SPATIAL_TYPES = (
    Spherical3,
    OriginLock3,
    RotationLock3,
    RelativeZ1,
    Parallel2,
    PointOnLine2,
    PointOnPlane1,
    PointOnCircle2,
    PointAtIntersection3,
    Revolute5,
    Cylindrical4,
    Translate5,
    Universal4,
    ConstantVelocity4,
    ParaRevolute4,
    OrthoRevolute4,
    LineOnCylinder3,
    LineToCircle1,
    LineToLine1,
    LineToPlane2,
    PlaneToPlane3,
    Planar3,
    PlaneToCircle1,
)

__all__ = [t.__name__ for t in SPATIAL_TYPES] + ["SPATIAL_TYPES"]
