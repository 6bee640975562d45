r"""Rolling without slip: a thin disk or a sphere on a plane (3D), a circle on a line (2D).

A rolling contact has two parts:

* a **holonomic** part, the contact itself (the body touches the surface): an ordinary
  position constraint, returned by :meth:`RollingContact.holonomic` (``PlaneToCircle1``,
  ``PointOnPlane1``, ``PointOnLine1``) and added to the model like any other;
* a **nonholonomic** part, no slip: the material point of the rolling body at the contact
  moves with the surface. These are the equations of the rolling classes themselves, linear
  in the velocities, :math:`A(q) \dot q = 0` (``b = 0``: the bodies' own velocities carry all the
  motion), written with the rate symbols of the coordinates (``x2_d``, ``e02_d``, ...).
  Only the components *in* the surface are equations: the normal one is the time
  derivative of the holonomic part (the contact is the rim's extreme point) and would
  repeat it.

Notation: the surface (plane or line) is an axis of body 1 with origin ``r_1`` and direction
``u_1`` (the plane's normal; the line's direction); ``h_1``, ``f_1`` directions in the plane
fixed in body 1; the rolling body 2 has its centre ``r_2``. The material velocity of body
``i`` at a global point ``c`` is :math:`v_i(c) = v_{O_i} + \omega_i \times (c - r_{O_i})` (``O_i`` the body
origin, ``omega_i`` its angular velocity from the rates of its rotation coordinates), and the
slip velocity is ``v_c = v_2(c) - v_1(c)``.

The contact point is an output: :meth:`RollingContact.contact_point` is a point (on ground,
with coordinates that are expressions of the coordinates) for ``m.location`` /
``sol.location``; :meth:`RollingContact.slip_velocity` is ``v_c`` for ``sol.eval``.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
import sympy as sp

from .._errors import GeometryError, ModelError
from .._symbols import T, velocity_symbol
from ..geometry._points import Point, as_axis, as_point
from ..geometry._units import is_quantity
from . import _primitives as P
from ._base import ConstraintBase, _local_symbols, as_expr
from ._velocity import linear_velocity_form


def positive_radius(value, what: str) -> sp.Expr:
    """A radius: a positive finite number, or an expression of parameters (checked when
    numeric); time-dependent radii are refused (the rolling equations treat it as fixed)."""
    if is_quantity(value):      # a length with its unit: converted when the model is known
        try:
            x = float(value.magnitude)
        except (TypeError, ValueError):
            x = math.nan
        if not (math.isfinite(x) and x > 0):
            raise GeometryError(f"{what} must be a positive finite length, got {value!r}; "
                                "give the radius of the rolling body (> 0)")
    r = as_expr(value, what)
    if r.is_number:
        try:
            x = float(r)
        except TypeError:
            x = math.nan
        if not (math.isfinite(x) and x > 0):
            raise GeometryError(f"{what} must be a positive finite length, got {value!r}; "
                                "give the radius of the rolling body (> 0)")
    elif T in r.free_symbols:
        raise GeometryError(f"{what} = {r} depends on time T; a rolling body's radius must be "
                            "constant (a number or a parameter)")
    return r


def norm2(vector) -> sp.Expr:
    r""":math:`\lvert u \rvert^2` of a direction: of its local components when it is fixed in a body (or
    ground) with constant components, a constant; else of its global expression. (Rotation
    matrices are orthogonal on the Euler-parameter normalisation, so both are equal there;
    the constant keeps the contact's expressions of low degree: a disk's contact is then of
    degree 2 in the Euler parameters under a square root of degree 4, instead of 6 and 12,
    and its derivatives stay small.)"""
    if vector.is_local_constant():
        return vector.local.dot(vector.local)
    u = vector.direction()
    return u.dot(u)


def material_velocity(space, body, x: sp.Matrix) -> sp.Matrix:
    """Velocity of the material point of ``body`` that is at the global point ``x`` now:
    ``v_O + omega x (x - r_O)`` (2D: ``omega`` times ``x - r_O`` turned by +90 deg); zero
    on ground. Linear in the body's rates."""
    dim = space.dim
    if body is None or getattr(body, "is_ground", False):
        return sp.zeros(dim, 1)
    rates = [velocity_symbol(s.name) for s in body.q]
    v = sp.Matrix(rates[:dim])
    w = space.omega(body.q[dim:], rates[dim:], False)
    d = x - body.r
    if dim == 3:
        return v + w.cross(d)
    return v + w * sp.Matrix([-d[1], d[0]])


class RollingContact(ConstraintBase):
    """Base of the rolling constraints: velocity (nonholonomic) constraints.

    Subclasses set ``rolling_body``, ``surface`` (an axis) and implement
    :meth:`contact_location` and :meth:`holonomic`."""

    #: 1: the equations are velocity equations (0 for position constraints)
    order: ClassVar[int] = 1

    surface = None
    rolling_body = None

    def _refuse_time(self) -> None:
        """Moving geometry inside a body would slip by its own motion, which the material
        velocities below do not see: refuse it (drive a body instead)."""
        for g in self.geometry():
            if T in _local_symbols(g):
                raise GeometryError(
                    f"{type(self).__name__}: {g!r} depends on time T; the rolling surface and "
                    "body must be fixed in their bodies (drive the body with a constraint)")

    def contact_location(self) -> sp.Matrix:  # pragma: no cover - interface
        raise NotImplementedError

    def holonomic(self) -> ConstraintBase:  # pragma: no cover - interface
        raise NotImplementedError

    def contact_point(self) -> Point:
        """The contact point as a point (on ground, its coordinates expressions of the
        coordinates): ``m.location(roll.contact_point())`` symbolic,
        ``sol.location(roll.contact_point())`` over a solution. Its ``velocity`` is the speed
        at which the contact runs along the surface (the track), not the slip."""
        return Point(None, self.contact_location(), label=f"contact of {self.label()}")

    def slip_velocity(self, space=None) -> sp.Matrix:
        """``v_c = v_2(c) - v_1(c)``: the velocity of the rolling body's material point at the
        contact relative to the surface's, all components (zero when it rolls)."""
        if space is None:
            space = self._space()
        c = self.contact_location()
        return (material_velocity(space, self.rolling_body, c)
                - material_velocity(space, self.surface.body, c))

    def _space(self):
        # the rolling body's space: the model's (Model2D(orientation="euler") has its own)
        return self.rolling_body.space

    def _build(self, space):
        vc = self.slip_velocity(space)
        return [(n.T * vc)[0, 0] for n in self._tangents(space)]

    def _tangents(self, space) -> list[sp.Matrix]:  # pragma: no cover - interface
        raise NotImplementedError

    def velocity_form(self, model) -> tuple[sp.Matrix, sp.Matrix]:
        r"""``(A, b)``: the equations as :math:`A(q, t) \dot q + b(q, t) = 0`, columns in the order of
        the model's coordinates (see :func:`~mechsys.linear_velocity_form`)."""
        return linear_velocity_form(self, model)

    def tangential_force(self, sol) -> np.ndarray:
        r"""The in-surface contact force (friction that prevents slip) the surface applies
        to the rolling body at the contact over a free-motion solution (``m.free()`` with this
        constraint added to the model; decision 0053), array ``(N, dim)``. With the no-slip
        rows :math:`\psi_i = t_i \cdot v_c` (:math:`t_i` the in-surface directions) and their
        multipliers :math:`\mu_i` (``sol.extra["mu"]``, the equations of the motion
        :math:`M \ddot q + \Phi_q^T \lambda + A^T \mu = Q`):

        .. math::  F_t = -\sum_i \mu_i\, t_i

        (the surface's body takes :math:`-F_t`). The normal force is the reaction of the
        holonomic part: ``sol.reaction(touch, body)``. Example::

            F_t = roll.tangential_force(sol)
        """
        names = list(sol.extra.get("velocity_multipliers", ()))
        rows = [i for i, x in enumerate(names) if x.rsplit("[", 1)[0] == self.name]
        if not rows:
            raise ModelError(
                f"{self.label()}.tangential_force: the solution has no multipliers of this "
                "constraint; add it to the model (m.add(roll)) and run free motion (m.free()"
                ".simulate or .solve)")
        mu = np.asarray(sol.extra["mu"], dtype=float).reshape(len(np.atleast_1d(sol.t)), -1)
        N = mu.shape[0]
        F = 0.0
        for k, t in zip(rows, self._tangents(self._space())):
            F = F - mu[:, k:k + 1] * np.asarray(sol.eval(t), dtype=float).reshape(N, -1)
        return F


class RollingDisk2(RollingContact):
    r"""A thin disk (a wheel) rolls without slipping on a plane: velocity constraint, 2
    equations (3D). With its holonomic part (:meth:`holonomic`, the rim touches the plane)
    it removes 1 coordinate and 2 velocities.

    ``RollingDisk2(plane, axis, rad)``: ``plane`` an axis (or ``Plane``) of body 1 whose
    direction ``u_1`` is the plane's normal, the disk on the side ``u_1`` points to; ``axis``
    the disk's axis on body 2, its origin the disk centre ``r_2``, direction ``u_2``; ``rad``
    the disk radius. The contact is the rim's point nearest the plane, at any lean, with
    :math:`w = u_2 \times (u_1 \times u_2)` (in the disk's plane, towards the plane's
    normal):

    .. math::

        c = r_2 - \mathit{rad}\, \frac{w}{|w|}

    Holonomic part, ``PlaneToCircle1(plane, axis, rad)``:

    .. math::

        u_1 \cdot (r_2 - r_1) - \mathit{rad}\, \frac{|u_1 \times u_2|}{|u_2|} = 0

    Velocity equations, :math:`v_c = v_2(c) - v_1(c)` the slip velocity at the contact,
    :math:`h_1`, :math:`f_1` the plane's in-plane directions fixed in body 1:

    .. math::

        h_1 \cdot v_c = 0, \qquad f_1 \cdot v_c = 0

    Linear in the velocities, :math:`A(q)\, \dot q = 0` (:meth:`velocity_form`). Regular
    while the disk is not flat on the plane (:math:`u_1 \times u_2 = 0`). Give the velocity
    constraint to a path system in place of two dummy constraints:
    ``m.path(replace={("dummy x", "dummy y"): roll})``. Example::

        roll = ms.RollingDisk2(m.ground.axis((0, 0, 0), (0, 0, 1)), disk.axis(0, (0, 1, 0)), 0.3)
        m.add(roll.holonomic(), name="touch")
    """

    mech_name = "RollingDisk2"
    dof_removed = 2
    spaces = ("spatial",)

    def __init__(self, plane, axis, rad):
        super().__init__()
        self.plane, self.axis = as_axis(plane), as_axis(axis)
        self.plane.dir.check_nonzero("RollingDisk2 plane normal")
        self.axis.dir.check_nonzero("RollingDisk2 disk axis")
        if self.axis.body is None or getattr(self.axis.body, "is_ground", False):
            raise GeometryError("RollingDisk2 axis: the disk's axis must be an axis of the "
                                "rolling body (disk.axis(...)), not of ground")
        self.rad = positive_radius(rad, "RollingDisk2 rad")
        self.surface, self.rolling_body = self.plane, self.axis.body
        self._refuse_time()

    def geometry(self):
        return [self.plane, self.axis]

    def contact_location(self):
        u1, u2 = self.plane.direction(), self.axis.direction()
        n1, n2, c12 = norm2(self.plane.dir), norm2(self.axis.dir), u1.dot(u2)
        w = u1 * n2 - u2 * c12              # u_2 x (u_1 x u_2)
        return self.axis.location() - self.rad * w / sp.sqrt(n2 * (n1 * n2 - c12**2))

    def _tangents(self, space):
        return P.normals(space, self.plane.dir)

    def holonomic(self) -> ConstraintBase:
        """The contact, ``PlaneToCircle1(plane, axis, rad)`` (a new constraint object)."""
        from ._spatial import PlaneToCircle1

        return PlaneToCircle1(self.plane, self.axis, self.rad)


class RollingSphere2(RollingContact):
    r"""A sphere rolls without slipping on a plane: velocity constraint, 2 equations (3D).
    With its holonomic part (:meth:`holonomic`) it removes 1 coordinate and 2 velocities
    (the sphere keeps all three rotations).

    ``RollingSphere2(plane, point, rad)``: ``plane`` an axis (or ``Plane``) of body 1 whose
    direction ``u_1`` is the normal, the sphere on the side ``u_1`` points to; ``point`` the
    sphere's centre :math:`r_2`, fixed in the sphere's body; ``rad`` its radius. Contact:

    .. math::

        c = r_2 - \mathit{rad}\, \frac{u_1}{|u_1|}

    Holonomic part, ``PointOnPlane1(point, plane, rad)``:

    .. math::

        u_1 \cdot (r_2 - r_1) - \mathit{rad}\, |u_1| = 0

    Velocity equations (:math:`v_c`, :math:`h_1`, :math:`f_1` as in :class:`RollingDisk2`):

    .. math::

        h_1 \cdot v_c = 0, \qquad f_1 \cdot v_c = 0

    Example::

        roll = ms.RollingSphere2(m.ground.axis((0, 0, 0), (0, 0, 1)), ball.point(0), 0.1)
        m.add(roll.holonomic(), name="touch")
    """

    mech_name = "RollingSphere2"
    dof_removed = 2
    spaces = ("spatial",)

    def __init__(self, plane, point, rad):
        super().__init__()
        self.plane, self.point = as_axis(plane), as_point(point)
        self.plane.dir.check_nonzero("RollingSphere2 plane normal")
        if self.point.body is None or getattr(self.point.body, "is_ground", False):
            raise GeometryError("RollingSphere2 point: the sphere's centre must be a point of "
                                "the rolling body (ball.point(...)), not of ground")
        self.rad = positive_radius(rad, "RollingSphere2 rad")
        self.surface, self.rolling_body = self.plane, self.point.body
        self._refuse_time()

    def geometry(self):
        return [self.plane, self.point]

    def contact_location(self):
        return self.point.location() - self.rad * self.plane.direction() / sp.sqrt(
            norm2(self.plane.dir))

    def _tangents(self, space):
        return P.normals(space, self.plane.dir)

    def holonomic(self) -> ConstraintBase:
        """The contact, ``PointOnPlane1(point, plane, rad)`` (a new constraint object)."""
        from ._spatial import PointOnPlane1

        return PointOnPlane1(self.point, self.plane, self.rad)


class RollingCircle1(RollingContact):
    r"""A circle (a wheel, a disk in the plane) rolls without slipping on a line: velocity
    constraint, 1 equation (2D). With its holonomic part (:meth:`holonomic`) it removes 1
    coordinate and 1 velocity.

    ``RollingCircle1(point, rad, line)`` (the argument order of ``RackAndPinion2``): the
    circle of radius ``rad`` centred at ``point`` (``r_2``, fixed in the rolling body) lies
    on the left of ``line`` (origin ``r_1``, direction ``u_1``, on body 1). With ``n`` the
    left normal (:math:`u_1` turned by +90 deg):

    .. math::

        c = r_2 - \mathit{rad}\, \frac{n}{|n|}

    Holonomic part, ``PointOnLine1(point, line, rad)``:

    .. math::

        u_1 \times (r_2 - r_1) - \mathit{rad}\, |u_1| = 0

    Velocity equation (:math:`v_c` the slip velocity at :math:`c`):

    .. math::

        u_1 \cdot v_c = 0

    In the plane this constraint integrates: with :math:`s = \hat u_1 \cdot (r_2 - r_1)` and
    :math:`\alpha` the rolling body's angle from the line,
    :math:`\mathrm{d}s = -\mathit{rad}\, \mathrm{d}\alpha`, the position constraint
    :math:`s - C + \mathit{rad}\, \alpha = 0` of ``RackAndPinion2(point, rad, line, C)``. Use that one in a
    kinematic model (``m.solve``, free motion); this velocity form is for path systems and
    for the velocity constraints of dynamics, where ``C`` need not be known. Example::

        roll = ms.RollingCircle1(wheel.point(0), 0.5, m.ground.axis((0, 0), (1, 0)))
        m.add(roll.holonomic(), name="touch")
    """

    mech_name = "RollingCircle1"
    dof_removed = 1
    spaces = ("planar",)

    def __init__(self, point, rad, line):
        super().__init__()
        self.point, self.line = as_point(point), as_axis(line)
        self.line.dir.check_nonzero("RollingCircle1 line direction")
        if self.point.body is None or getattr(self.point.body, "is_ground", False):
            raise GeometryError("RollingCircle1 point: the circle's centre must be a point of "
                                "the rolling body (wheel.point(...)), not of ground")
        self.rad = positive_radius(rad, "RollingCircle1 rad")
        self.surface, self.rolling_body = self.line, self.point.body
        self._refuse_time()

    def geometry(self):
        return [self.point, self.line]

    def contact_location(self):
        u = self.line.direction()
        return self.point.location() - self.rad * sp.Matrix([-u[1], u[0]]) / sp.sqrt(
            norm2(self.line.dir))

    def _tangents(self, space):
        return [self.line.direction()]

    def holonomic(self) -> ConstraintBase:
        """The contact, ``PointOnLine1(point, line, rad)`` (a new constraint object)."""
        from ._planar import PointOnLine1

        return PointOnLine1(self.point, self.line, self.rad)


ROLLING_TYPES = (RollingDisk2, RollingSphere2, RollingCircle1)
