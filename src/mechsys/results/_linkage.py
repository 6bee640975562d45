r"""Linkage metrics: transmission angle and mechanical advantage (output functions: symbolic
on a model, arrays over a solution).

**Transmission angle** ``transmission_angle(coupler, output)``: the unsigned angle in
:math:`[0, \pi]` between two vectors (``Vector(point_from, point_to)``, a body vector, an axis):

.. math::

    \mu = \operatorname{atan2}(\lvert u \times v \rvert,\ u \cdot v)

* four-bar: ``coupler`` from the output joint ``C`` to the crank tip ``B``, ``output`` from
  ``C`` to the rocker's ground pivot ``D`` -- the classic ``mu`` of the triangle ``BCD``,
  :math:`\cos \mu = (b^2 + c^2 - a^2 - d^2 + 2 a d \cos \theta_2) / (2 b c)`;
* slider-crank: ``coupler`` along the connecting rod, ``output`` perpendicular to the
  slider's path (e.g. the piston's ``vector((0, 1))`` for a slide along x): :math:`\mu = 90^\circ`
  when the rod pushes along the path, :math:`\mu = 90^\circ \mp \phi` for a rod at ``phi`` to it (the
  sign depends on the sense of the normal; :math:`\lvert 90^\circ - \mu \rvert = \phi`).

Force transmission is best at :math:`\mu = 90^\circ`; a common design rule keeps
``|90 deg - mu| <= 50 deg``.

**Mechanical advantage** ``mechanical_advantage(input, output)``: the ratio of output to
input effort of an ideal (frictionless, quasi-static) mechanism, by virtual work equal to the
ratio of input to output rates:

.. math::

    \mathit{MA} = \frac{F_{\mathrm{out}}}{F_{\mathrm{in}}}
        = \frac{d\, \mathit{input} / dt}{d\, \mathit{output} / dt}

``input`` and ``output`` are a body (its angle: 2D only), a coordinate or model-variable
symbol, or any expression of the coordinates (e.g. ``m.location(piston.point(0))[0]``, a
slider's travel); the rates are their total time derivatives. Rotary input and output give a
torque ratio; a rotary input and a sliding output give force / torque (unit 1/length). The
value is infinite at the output's dead centres (toggle positions).
"""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError
from ..geometry._bodies import Body


class LinkageOutputs:
    """Mixin for :class:`Model` and :class:`Solution` (``_model()``, ``_finish(expr)``)."""

    def transmission_angle(self, coupler, output):
        """Unsigned angle ``[0, pi]`` between the coupler and output vectors (module doc)."""
        m = self._model()
        u = m._vector(coupler).direction()
        v = m._vector(output).direction()
        if m.space.dim == 2:
            cross = sp.Abs(m.space.cross(u, v))
        else:
            w = u.cross(v)
            cross = sp.sqrt(w.dot(w))
        return self._finish(sp.atan2(cross, u.dot(v)))

    def _rate_of(self, spec, what: str):
        m = self._model()
        if isinstance(spec, (Body, str)) or (isinstance(spec, int) and not isinstance(spec, bool)):
            b = m.body(spec)
            if m.space.dim != 2:
                raise ModelError(f"mechanical_advantage {what}: a body's angle is planar; in 3D "
                                 "give an expression (a joint variable, a projected angle)")
            if b.is_ground:
                raise ModelError(f"mechanical_advantage {what}: ground does not move")
            expr = m.space.angle(b.q[2:])
        elif isinstance(spec, (sp.MatrixBase, list, tuple)):
            raise ModelError(f"mechanical_advantage {what}: expected a scalar expression (one "
                             f"component, e.g. location(point)[0]), got {spec!r}")
        else:
            try:
                expr = sp.sympify(spec)
            except (sp.SympifyError, TypeError):
                raise ModelError(f"mechanical_advantage {what}: expected a body, a coordinate "
                                 f"or an expression of the coordinates, got {spec!r}") from None
            if not isinstance(expr, sp.Expr):
                raise ModelError(f"mechanical_advantage {what}: expected a scalar expression, "
                                 f"got {spec!r}")
        return m.time_derivative(expr)

    def mechanical_advantage(self, input, output):  # noqa: A002 - the engineering names
        r"""``(d input/dt) / (d output/dt)``: output effort per unit input effort (module doc).
        On a static solution of a driven model (zero velocities by definition) the rates are
        those of the drivers' motion, :math:`\Phi_q \dot q = -\Phi_t` at each point: the ratio does not
        depend on the drivers' speed."""
        expr = self._rate_of(input, "input") / self._rate_of(output, "output")
        if getattr(self, "_at_rest", False):
            return self._driven_rates()._finish(expr)
        return self._finish(expr)

    def _driven_rates(self):
        """This static solution with the velocities of its drivers' motion."""
        import dataclasses

        import numpy as np

        s = self.system
        if self.mode != "static" or s.m != s.n:
            raise ModelError(
                "mechanical_advantage needs the motion's velocities: this equilibrium of a "
                "free system has none (no drivers say how it moves); use a kinematic solution "
                "of the driven model (solution='velocity')")
        qd = []
        for t, q in zip(np.atleast_1d(self.t), np.atleast_2d(self.q)):
            J, rhs = s.velocity_rhs(t, q, self.p)
            qd.append(np.linalg.solve(J, rhs))
        return dataclasses.replace(self, qd=np.array(qd))


__all__ = ["LinkageOutputs"]
