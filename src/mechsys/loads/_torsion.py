r"""Rotational (torsion) springs and dampers between two bodies.

The relative angle :math:`\phi` of body 2 with respect to body 1:

* 2D, ``TorsionSpring(body1, body2, ...)``: :math:`\phi = \theta_2 - \theta_1`
  (counter-clockwise, not wrapped: a spring wound several turns keeps its energy);
* 2D or 3D, ``TorsionSpring(axis1, axis2, ...)``: the angle, right-handed about the
  direction of ``axis1``, from the reference direction ``g_1`` of ``axis1`` to the reference
  direction ``g_2`` of ``axis2`` projected on the plane normal to ``axis1``
  (:math:`\phi = \operatorname{atan2}(k_1 \cdot g_2, g_1 \cdot g_2)` with
  :math:`k_1 = u_1 \times g_1`, the angle frame of ``RotationLock1``; in 2D :math:`g` is the
  axis direction).
  Meant for two bodies joined about a common axis (a revolute joint, ``axis1`` and
  ``axis2`` its two halves); any other relative motion is allowed and the spring acts on the
  projected angle only. In 3D :math:`\phi` lies in :math:`(-\pi, \pi]`: keep
  :math:`\phi - \phi_0` (``free_angle``) inside that range (the potential jumps at the
  branch cut).

Spring: torque :math:`\tau = k (\phi - \phi_0)` (or ``law(phi)``), potential
:math:`k (\phi - \phi_0)^2 / 2`. Damper: torque :math:`\tau = c\, \dot\phi` (or
``law(phi, dphi/dt)``). The torque acts to reduce :math:`\phi`: :math:`-\tau` on body 2 and
:math:`+\tau` on body 1 about the axis. Its generalized force is exact virtual work for any
motion of the bodies:

.. math::

    Q = -\tau \frac{\partial \phi}{\partial q}

(for the spring :math:`-\partial V / \partial q`; for the damper
:math:`-\partial (c \dot\phi^2 / 2) / \partial \dot q`), so the spring's potential closes the
energy balance whatever the joint.
"""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError
from ..geometry._points import Axis, as_axis
from ._loads import DirectLoad, LoadBase, _magnitude


class TorsionSpring(LoadBase):
    r"""Rotational spring between two bodies: ``TorsionSpring(body1, body2, stiffness,
    free_angle=0, law=None)`` (2D) or ``TorsionSpring(axis1, axis2, stiffness, ...)`` (2D and
    3D). Torque :math:`k (\phi - \phi_0)`, :math:`\phi_0` = ``free_angle`` (or
    ``law(phi)``) resisting the relative angle :math:`\phi` of body 2 from body 1 (see the
    module doc); potential :math:`k (\phi - \phi_0)^2 / 2`.

    Example::

        m.add_load(ms.TorsionSpring(m.ground, arm, 50.0, free_angle=0.3))
        m.add_load(ms.TorsionSpring(shaft.axis(0, (0, 0, 1), (1, 0, 0)),
                                    wheel.axis(0, (0, 0, 1), (1, 0, 0)), 120.0))
    """

    kind = "TorsionSpring"

    def __init__(self, first, second, stiffness=0, free_angle=0, law=None):
        super().__init__()
        if isinstance(first, Axis) != isinstance(second, Axis):
            raise ModelError(f"{self.kind}: give two bodies (2D) or two axes, got {first!r} and "
                             f"{second!r}")
        if not isinstance(first, Axis):  # bodies: handles, names or numbers
            self.b1, self.b2, self.axis1, self.axis2 = first, second, None, None
        else:
            try:
                self.axis1, self.axis2 = as_axis(first), as_axis(second)
            except (ModelError, TypeError, AttributeError):
                raise ModelError(f"{self.kind}: give two bodies (2D) or two axes "
                                 f"(body.axis(origin, direction, reference)), got {first!r} and "
                                 f"{second!r}") from None
            self.b1 = self.b2 = None
        self.k = self._nonnegative(stiffness, f"{self.kind} stiffness",
                                   "for another torque law give law=f(phi)")
        self.phi0 = _magnitude(free_angle, f"{self.kind} free_angle")
        self.law = law
        if law is not None and not callable(law):
            raise ModelError(f"{self.kind} law must be a function of the angle, got {law!r}")

    def bodies(self):
        if self.b1 is not None:
            return [self.b1, self.b2]
        return self.axis1.bodies() + self.axis2.bodies()

    def geometry(self):
        return [self.axis1, self.axis2] if self.axis1 is not None else []

    def check(self, model) -> None:
        super().check(model)
        if self.b1 is not None:
            if model.space.dim != 2:
                raise ModelError(f"{self.label()}: in 3D give two axes (with reference directions) "
                                 "about which the angle is measured, not bodies")
            if model.body(self.b1) is model.body(self.b2):
                raise ModelError(f"{self.label()}: both ends are body "
                                 f"{model.body(self.b1).name!r}; give two different bodies")
        self.angle(model)

    def angle(self, model) -> sp.Expr:
        """The relative angle ``phi`` (symbolic)."""
        sp_ = model.space
        if self.b1 is not None:
            bs = [model.body(b) for b in (self.b1, self.b2)]
            if hasattr(sp_, "relative_rotation"):  # orientation="euler": no angle coordinate
                c, s = sp_.relative_rotation(*(None if b.is_ground else b.q[2:] for b in bs[::-1]))
                return sp.atan2(s, c)   # like the two-axis form: in (-pi, pi]
            th = [0 if b.is_ground else sp_.angle(b.q[sp_.dim:]) for b in bs]
            return sp.sympify(th[1] - th[0])
        g1, k1 = _angle_frame(sp_, self.axis1)
        g2 = _angle_frame(sp_, self.axis2)[0]
        return sp.atan2(k1.dot(g2), g1.dot(g2))

    def torque(self, model) -> sp.Expr:
        """Torque ``tau`` resisting ``phi`` (acts as ``-tau`` on body 2)."""
        phi = self.angle(model)
        if self.law is not None:
            return sp.sympify(self.law(phi))
        return self.k * (phi - self.phi0)

    def contributions(self, model):
        phi = self.angle(model)
        tau = self.torque(model)
        out = []
        for s in sorted(phi.free_symbols, key=lambda x: x.name):
            if _is_coordinate(model, s):
                out.append(DirectLoad(s, -tau * phi.diff(s)))
        return out

    def potential(self, model):
        if self.law is not None:
            return None
        return self.k * (self.angle(model) - self.phi0) ** 2 / 2


class TorsionDamper(TorsionSpring):
    r"""Rotational damper between two bodies: ``TorsionDamper(body1, body2, damping,
    law=None)`` or with two axes (as :class:`TorsionSpring`); torque :math:`c\, \dot\phi` (or
    ``law(phi, dphi/dt)``) resisting the relative angular velocity."""

    kind = "TorsionDamper"

    def __init__(self, first, second, damping=0, law=None):
        super().__init__(first, second, 0, 0)
        self.c = self._nonnegative(damping, "TorsionDamper damping",
                                   "a negative damping coefficient feeds energy in; for another "
                                   "torque law give law=f(phi, dphi/dt)")
        if law is not None and not callable(law):
            raise ModelError(f"TorsionDamper law must be a function (phi, phidot), got {law!r}")
        self.dlaw = law

    def torque(self, model) -> sp.Expr:
        phi = self.angle(model)
        rate = model.time_derivative(phi)
        if self.dlaw is not None:
            return sp.sympify(self.dlaw(phi, rate))
        return self.c * rate

    def potential(self, model):
        return None


def _angle_frame(space, axis: Axis):
    """``(g, k)``: the axis' reference direction ``g`` (2D: the unit axis direction) and
    ``k = g`` turned +90 degrees about the axis (as RotationLock1's frame; the ratio of the two
    components is all ``atan2`` needs, so ``g``'s length does not matter)."""
    u = axis.direction()
    if space.dim == 2:
        return u, sp.Matrix([-u[1], u[0]])
    g = axis.reference_vector().direction()
    d = axis.dir.local if axis.dir.points is None else u  # a body-fixed length is constant
    return g, (u / sp.sqrt(d.dot(d))).cross(g)


def _is_coordinate(model, s) -> bool:
    return s in model.velocity_symbols()


__all__ = ["TorsionDamper", "TorsionSpring"]
