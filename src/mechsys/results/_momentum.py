r"""Momentum outputs: linear and angular momentum of a body or a set of bodies, and the centre
of mass (symbolic on a model, numeric over a solution, like every output function).

For bodies ``b`` with mass ``m_b``, centroid :math:`c_b = r_b + A_b c'_b`, centroid velocity
:math:`v_b` and angular velocity :math:`\omega_b`:

.. math::

    p &= \textstyle\sum_b m_b v_b \qquad \text{(linear momentum)} \\
    r_G &= \textstyle\sum_b m_b c_b \big/ \sum_b m_b \qquad \text{(centre of mass)} \\
    H_O &= \textstyle\sum_b (c_b - r_O) \times m_b v_b + A_b J'_b \omega'_b
        \qquad \text{(angular momentum about } O \text{)}

:math:`J'_b` the centroidal inertia in body axes and :math:`\omega'_b` the body-local angular
velocity (3D; in 2D :math:`J_b \omega_b` and the cross product is the scalar :math:`z`
component).
``about=None`` takes the centroid of the body, or the centre of mass of a set of bodies;
``about`` may also be a body point (moving: ``r_O`` follows it, velocities stay absolute)
or a global point. Without applied moments about ``O`` (a fixed point or the centre of
mass) ``H_O`` is conserved; without applied forces ``p`` is.
"""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError
from ._outputs import All


class MomentumOutputs:
    """Mixin for :class:`Model` and :class:`Solution` (``_model()``, ``_finish(expr)``)."""

    def _momentum_bodies(self, body) -> list:
        m = self._model()
        if body is None or body is All:
            bodies = m.bodies[1:]
        elif isinstance(body, (list, tuple)):
            bodies = [m.body(b) for b in body]
        else:
            bodies = [m.body(body)]
        return [b for b in bodies if not b.is_ground]

    @staticmethod
    def _centroid(b) -> sp.Matrix:
        return b.r + b.A * b.centroid

    def _mass_centre(self, bodies) -> sp.Matrix:
        total = sp.Add(*[sp.sympify(b.mass) for b in bodies])
        if total == 0:
            names = ", ".join(repr(b.name) for b in bodies) or "none"
            raise ModelError(f"the bodies ({names}) have no mass, so they have no centre of mass; "
                             "give the angular momentum about a point (about=...)")
        return sp.Matrix.hstack(*[b.mass * self._centroid(b) for b in bodies]) * sp.ones(
            len(bodies), 1) / total

    def centre_of_mass(self, body=None):
        """Centre of mass ``(dim,)`` of the moving bodies (all, one, or a list)."""
        return self._finish(self._mass_centre(self._momentum_bodies(body)))

    def linear_momentum(self, body=None):
        """Linear momentum ``sum m_b v_b`` ``(dim,)`` of the moving bodies (all, one, or a
        list)."""
        m = self._model()
        out = sp.zeros(m.space.dim, 1)
        for b in self._momentum_bodies(body):
            if b.mass != 0:
                out += b.mass * m.time_derivative(self._centroid(b))
        return self._finish(out)

    def angular_momentum(self, body=None, about=None):
        """Angular momentum about a point: scalar (2D) or ``(3,)`` global (3D) -- see the
        module docstring. ``about=None``: the body's centroid (one body) or the centre of mass
        (several or all bodies); else a body point (``body.point(...)``) or a global point."""
        m = self._model()
        bodies = self._momentum_bodies(body)
        if about is None:
            rO = self._centroid(bodies[0]) if len(bodies) == 1 else self._mass_centre(bodies)
        else:
            rO = m._point(about).location()
        space = m.space
        total = sp.S.Zero if space.dim == 2 else sp.zeros(3, 1)
        for b in bodies:
            rc = self._centroid(b)
            if b.mass != 0:
                total += space.cross(rc - rO, b.mass * m.time_derivative(rc))
            J = space.inertia_matrix(b.inertia)
            if space.dim == 2:
                total += J[0, 0] * m._omega(b, local=False)
            else:
                total += b.A * (J * m._omega(b, local=True))
        return self._finish(total)


__all__ = ["MomentumOutputs"]
