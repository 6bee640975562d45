r"""Angle constraints written once for 2D and 3D: ``RotationLock1`` and ``RelativeAngle1``,
and the shared equation builders for angles about an axis.

An axis carries a right-handed *angle frame* ``(g, k)``: unit vectors spanning the plane
in which angles about it are measured, ``k`` being ``g`` turned +90 degrees about the
axis. In 2D ``g`` is the unit axis direction and ``k`` its left normal; in 3D ``g`` is the
unit reference direction (perpendicular to the direction ``u``) and :math:`k = \hat{u} \times g`. Both
are fixed in the axis' body when the axis is. The counter-clockwise angle from ``g`` to
the projection of a vector ``f`` is ``a`` when:

.. math::

    \cos(a)\, (k \cdot f) - \sin(a)\, (g \cdot f) = 0

which is regular at the solution for every ``a``. It also holds at :math:`a + \pi`; for the
drivers (``RotationLock1``, ``RelativeAngle1`` in 2D) the solvers tell the two apart by
:class:`Branch` (decision 0033); elsewhere the guess picks the branch, as for ``Parallel1``.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .._errors import ModelError
from ..geometry._points import Axis, GlobalVector, Vector, as_axis
from . import _primitives as P
from ._base import ConstraintBase, TwoVectors, as_expr


def vector_norm(v: Vector) -> sp.Expr:
    """``|u|``: a constant for a vector fixed in a body (rigid bodies keep lengths), else the
    square root of the global expression."""
    if v.points is None and not isinstance(v, GlobalVector):
        return sp.sqrt(v.local.dot(v.local))
    d = v.direction()
    return sp.sqrt(d.dot(d))


def angle_frame(space, axis: Axis) -> tuple[sp.Matrix, sp.Matrix]:
    """Global unit vectors ``(g, k)`` of the axis' angle frame (see the module doc)."""
    d = axis.dir
    n = vector_norm(d)
    if space.dim == 2:
        return d.direction() / n, P.normals(space, d)[0] / n
    gv = axis.reference_vector()
    if d.points is None and not isinstance(d, GlobalVector) and gv.points is None \
            and not isinstance(gv, GlobalVector) and gv.body is d.body:
        k_local = (d.local / n).cross(gv.local)
        k = k_local if d.body is None else d.body.A * k_local
        return gv.direction(), k
    u = d.direction() / n
    g = gv.direction()
    return g, u.cross(g)


def angle_equation(frame, f: sp.Matrix, angle) -> sp.Expr:
    """``cos(a) (k . f) - sin(a) (g . f)``: the angle from ``g`` to ``f`` about the axis is
    ``a``."""
    g, k = frame
    a = sp.sympify(angle)
    return sp.cos(a) * k.dot(f) - sp.sin(a) * g.dot(f)


@dataclass(frozen=True)
class Branch:
    r"""The branch test of an angle equation :math:`\cos(a)\, (k \cdot f) - \sin(a)\, (g \cdot f) = 0`.

    The equation is :math:`\lvert f_p \rvert\, \sin(\phi - a) = 0` with ``phi`` the angle of
    ``f``'s projection :math:`f_p`: it holds at :math:`\phi = a` and at :math:`\phi = a + \pi`.
    :math:`\mathit{cos\_err} = \lvert f_p \rvert \cos(\phi - a)` (:math:`\cos(a)\, (g \cdot f) +
    \sin(a)\, (k \cdot f)`) tells them apart: positive on the asked branch, negative on the
    other; :math:`\mathit{sin\_err}` is the equation itself, so :math:`\phi - a =
    \operatorname{atan2}(\mathit{sin\_err}, \mathit{cos\_err})`. To move a configuration onto
    the asked angle, ``body`` (moving) is turned by :math:`\mathit{sign}\, (\phi - a)` about the
    global unit direction ``axis`` (None in 2D: about the plane's normal) through the global
    point ``origin``; ``body`` is None when no single body carries ``f`` (the branch is then
    only tested).
    """

    owner: object
    cos_err: sp.Expr
    sin_err: sp.Expr
    body: object
    sign: int
    axis: sp.Matrix | None
    origin: sp.Matrix | None


def _turnable(vec):
    """The moving body a vector is fixed in, or None (ground, global, or between points)."""
    if vec.points is not None or isinstance(vec, GlobalVector):
        return None
    b = vec.body
    return None if b is None or b.is_ground else b


def angle_branch(owner, frame, f: sp.Matrix, angle, turn1, turn2, axis, origin1, origin2):
    """The :class:`Branch` of ``angle_equation(frame, f, angle)``: ``turn1`` is the body of
    ``f`` (turned by ``-(phi - a)`` about ``axis`` through ``origin1``), ``turn2`` the body of
    the frame (turned by ``+(phi - a)`` through ``origin2``), used when ``turn1`` is None."""
    g, k = frame
    a = sp.sympify(angle)
    cos_err = sp.cos(a) * g.dot(f) + sp.sin(a) * k.dot(f)
    sin_err = sp.cos(a) * k.dot(f) - sp.sin(a) * g.dot(f)
    if turn1 is not None:
        return Branch(owner, cos_err, sin_err, turn1, -1, axis, origin1)
    return Branch(owner, cos_err, sin_err, turn2, 1, axis, origin2 if turn2 is not None else None)


def _body_of(obj):
    from ..geometry._bodies import Body

    return obj if isinstance(obj, Body) else None


def _ground_copy(axis: Axis) -> Axis:
    """The axis with the same local geometry, on ground (the axis' rest position)."""
    d = axis.dir
    if d.points is not None or isinstance(d, GlobalVector) or axis.origin.body is not d.body:
        raise ModelError("RotationLock1(axis, angle): the axis must be fixed in one body to "
                         "measure its rotation from rest; give the second axis explicitly")
    ref = axis.reference
    if ref is not None:
        if ref.points is not None or isinstance(ref, GlobalVector) or ref.body is not d.body:
            raise ModelError("RotationLock1(axis, angle): the reference direction must be fixed "
                             "in the axis' body; give the second axis explicitly")
        ref = Vector(None, ref.local)
    return Axis(axis.origin.local, Vector(None, d.local), ref if ref is not None
                else axis.reference_rule)


class RotationLock1(ConstraintBase):
    r"""Lock one rotation angle. Removes 1 DOF (2D/3D).

    Body form (2D, Mech's): ``RotationLock1(body, angle)`` or
    ``RotationLock1(body1, body2, angle)`` -- the angle of ``body1`` is ``angle`` more than
    that of ``body2`` (ground if omitted):

    .. math::

        \theta_1 - \theta_2 - \mathit{angle} = 0

    Axis form (2D and 3D): ``RotationLock1(axis1, axis2, angle)`` -- the counter-clockwise
    angle (right-hand sense about the direction :math:`u_2` of ``axis2``) from the reference
    direction :math:`g_2` of ``axis2`` to the reference direction :math:`g_1` of ``axis1``, projected
    on the plane normal to :math:`u_2`, is ``angle``; with :math:`k_2 = \hat{u}_2 \times g_2` (see
    :func:`~mechsys.reference_direction` for references not given explicitly):

    .. math::

        \cos(\mathit{angle})\, (k_2 \cdot g_1) - \sin(\mathit{angle})\, (g_2 \cdot g_1) = 0

    (in 2D :math:`g_i` are the unit axis directions and :math:`k_2` the left normal of
    :math:`u_2`). ``RotationLock1(axis, angle)`` measures from the same axis on ground at rest.
    ``angle`` may be an expression of ``T`` (a rotational driver). The equation is regular for
    every angle; it also holds at :math:`\mathit{angle} + \pi`, and the solvers tell the two
    apart by the sign of :math:`\cos(\mathit{angle})\, (g_2 \cdot g_1) + \sin(\mathit{angle})\,
    (k_2 \cdot g_1)` (positive at the asked angle): a guess or prediction more than a quarter
    turn off is first turned onto the asked angle, and a solution half a turn off is turned and
    solved again (decision 0033). The same holds for the 2D body form in Euler-parameter
    coordinates (``orientation="euler"``). In 3D a body's whole orientation is locked with
    ``RotationLock3``.
    """

    mech_name = "RotationLock1"
    dof_removed = 1

    def __init__(self, first, second=None, angle=None):
        super().__init__()
        self.b1 = self.b2 = self.axis1 = self.axis2 = None
        if second is None and angle is None:
            raise ModelError("RotationLock1 needs an angle: RotationLock1(body, angle), "
                             "RotationLock1(body1, body2, angle) or "
                             "RotationLock1(axis1, axis2, angle)")
        if _body_of(first) is not None:
            self.b1 = first
            if angle is None:
                self.angle = as_expr(second, "RotationLock1 angle")
            else:
                if _body_of(second) is None:
                    raise ModelError(f"RotationLock1 body2: expected a body, got {second!r}")
                self.b2 = second
                self.angle = as_expr(angle, "RotationLock1 angle")
            return
        try:
            self.axis1 = as_axis(first)
        except ModelError:
            raise ModelError(f"RotationLock1: the first argument must be a body or an axis, got "
                             f"{first!r}") from None
        if angle is None:
            self.axis2 = _ground_copy(self.axis1)
            self.angle = as_expr(second, "RotationLock1 angle")
        else:
            self.axis2 = as_axis(second)
            self.angle = as_expr(angle, "RotationLock1 angle")

    def geometry(self):
        if self.b1 is not None:
            # the bodies' origins, made once per pair of bodies (asked for several times as
            # the constraint is added: its bodies, dimension and side checks)
            g = self.__dict__.get("_origins")
            if g is None or g[0] is not self.b1 or g[1] is not self.b2:
                g = self._origins = (self.b1, self.b2, [self.b1.point(0)] + (
                    [self.b2.point(0)] if self.b2 is not None else []))
            return list(g[2])
        return [self.axis1, self.axis2]

    def _build(self, space):
        if self.b1 is not None:
            if space.dim != 2:
                raise ModelError(
                    "in 3D, RotationLock1 takes axes: RotationLock1(axis1, axis2, angle) locks the "
                    "rotation about axis2; RotationLock3(body, ...) locks a whole orientation")
            if hasattr(space, "relative_rotation"):  # orientation="euler": sin(th1 - th2 - a)
                rot = [None if b is None or b.is_ground else b.q[2:] for b in (self.b1, self.b2)]
                c, s = space.relative_rotation(*rot)
                return [s * sp.cos(self.angle) - c * sp.sin(self.angle)]
            th1 = space.angle(self.b1.q[space.dim:]) if not self.b1.is_ground else 0
            th2 = 0
            if self.b2 is not None and not self.b2.is_ground:
                th2 = space.angle(self.b2.q[space.dim:])
            if th2 == 0 and type(self.angle) is sp.Float and float(self.angle) == 0.0 \
                    and type(th1) is sp.Symbol:
                # a lock at a zero Float angle: SymPy's th - 0 - 0.0 is th itself, after
                # deducing the new zero coefficient's facts (~80 us a lock)
                return [th1]
            return [th1 - th2 - self.angle]
        g1 = angle_frame(space, self.axis1)[0]
        return [angle_equation(angle_frame(space, self.axis2), g1, self.angle)]

    def branch(self, space) -> Branch | None:
        """The :class:`Branch` that tells the asked angle from ``angle + pi`` (None for the
        2D body form in angle coordinates, linear in the angle: it has one root)."""
        if self.b1 is not None:
            if not hasattr(space, "relative_rotation"):
                return None
            rot = [None if b is None or b.is_ground else b.q[2:] for b in (self.b1, self.b2)]
            c, s = space.relative_rotation(*rot)
            a = self.angle
            cos_err, sin_err = c * sp.cos(a) + s * sp.sin(a), s * sp.cos(a) - c * sp.sin(a)
            if not self.b1.is_ground:
                return Branch(self, cos_err, sin_err, self.b1, -1, None, self.b1.r)
            b2 = self.b2 if self.b2 is not None and not self.b2.is_ground else None
            return Branch(self, cos_err, sin_err, b2, 1, None, None if b2 is None else b2.r)
        frame = angle_frame(space, self.axis2)
        axis = None
        if space.dim == 3:
            d = self.axis2.dir
            axis = d.direction() / vector_norm(d)
        return angle_branch(self, frame, angle_frame(space, self.axis1)[0], self.angle,
                            _turnable(self.axis1.dir), _turnable(self.axis2.dir), axis,
                            self.axis1.origin.location(), self.axis2.origin.location())


class RelativeAngle1(TwoVectors):
    r"""The angle between two vectors. Removes 1 DOF (2D/3D).

    ``RelativeAngle1(vector1, vector2, angle)`` (axes, lines and planes give their
    directions).

    2D (signed, Mech's): the counter-clockwise angle from ``vector2`` to ``vector1`` is
    ``angle``; with :math:`n_2` the left normal of :math:`u_2`:

    .. math::

        \cos(\mathit{angle})\, (n_2 \cdot u_1) - \sin(\mathit{angle})\, (u_2 \cdot u_1) = 0

    (regular for every angle; it also admits :math:`\mathit{angle} + \pi`, which the solvers
    refuse by the sign of :math:`\cos(\mathit{angle})\, (u_2 \cdot u_1) + \sin(\mathit{angle})\,
    (n_2 \cdot u_1)`, as for ``RotationLock1``).

    3D (unsigned, Mech's): the included angle between the vectors is :math:`\lvert \mathit{angle} \rvert`:

    .. math::

        u_1 \cdot u_2 - \lvert u_1 \rvert\, \lvert u_2 \rvert\, \cos(\mathit{angle}) = 0

    singular at 0 and pi (the vectors are then parallel): use ``Parallel2`` there.
    """

    mech_name = "RelativeAngle1"
    dof_removed = 1

    def __init__(self, vector1, vector2, angle):
        super().__init__(vector1, vector2)
        self.angle = as_expr(angle, "RelativeAngle1 angle")

    def branch(self, space) -> Branch | None:
        """2D: the :class:`Branch` that tells the asked angle from ``angle + pi`` (3D: None,
        the included angle has one root in ``[0, pi]``)."""
        if space.dim != 2:
            return None
        u1 = self.v1.direction()
        frame = (self.v2.direction(), P.normals(space, self.v2)[0])
        # a relative angle fixes orientations only: turn a body about its own origin
        b1, b2 = _turnable(self.v1), _turnable(self.v2)
        return angle_branch(self, frame, u1, self.angle, b1, b2, None,
                            None if b1 is None else b1.r, None if b2 is None else b2.r)

    def _build(self, space):
        u1, u2 = self.v1.direction(), self.v2.direction()
        if space.dim == 2:
            return [angle_equation((u2, P.normals(space, self.v2)[0]), u1, self.angle)]
        if self.angle.is_number:
            c = float(sp.cos(self.angle))
            if abs(abs(c) - 1) < 1e-12:
                raise ModelError(
                    f"{self.label()}: in 3D an included angle of 0 or pi is singular; use "
                    "Parallel2 to make the vectors parallel")
        return [u1.dot(u2) - vector_norm(self.v1) * vector_norm(self.v2) * sp.cos(self.angle)]


__all__ = ["RelativeAngle1", "RotationLock1", "angle_equation", "angle_frame", "vector_norm"]
