r"""Output functions, written once: symbolic on a :class:`Model`, numeric on a
:class:`Solution` (which evaluates the same expressions over its time points).

Velocities and accelerations are total time derivatives::

    v_P = d r_P / dt = (r_P)_q qd + (r_P)_t,      a_P = d v_P / dt

Planar instant centre of a body with origin velocity ``v_O`` and angular velocity ``w``::

    r_IC = r_O + perp(v_O) / w,    perp(v) = (-v_y, v_x)

(infinite when ``w = 0``: the body translates).
"""

from __future__ import annotations

import sympy as sp

from ._errors import ModelError
from ._geometry import Axis, Point, Vector, as_point, as_vector


class OutputFunctions:
    """Mixin: subclasses provide ``_model()`` and ``_finish(expr)``."""

    def _model(self):  # pragma: no cover - interface
        raise NotImplementedError

    def _finish(self, expr):  # pragma: no cover - interface
        raise NotImplementedError

    # -- points ---------------------------------------------------------------------------
    def location(self, point):
        """Global location ``(dim,)`` of a point (an axis gives its origin)."""
        return self._finish(self._model()._point(point).location())

    def velocity(self, point):
        """Global velocity ``(dim,)`` of a point fixed in its body."""
        m = self._model()
        return self._finish(m.time_derivative(m._point(point).location()))

    def acceleration(self, point):
        """Global acceleration ``(dim,)`` of a point fixed in its body."""
        m = self._model()
        return self._finish(m.time_derivative(m.time_derivative(m._point(point).location())))

    def relative_velocity(self, point1, point2):
        """``v_1 - v_2``."""
        m = self._model()
        d = m._point(point1).location() - m._point(point2).location()
        return self._finish(m.time_derivative(d))

    # -- bodies ---------------------------------------------------------------------------
    def angle(self, body):
        """Planar body angle ``theta`` (radians)."""
        m = self._model()
        b = m.body(body)
        if m.space.dim != 2:
            raise ModelError("angle(body) is planar; in 3D use euler_parameters or rotation")
        return self._finish(sp.S.Zero if b.is_ground else b.q[2])

    def omega(self, body, coordinates: str = "global"):
        """Angular velocity: scalar in 2D, ``(3,)`` in 3D (global or ``"local"`` axes)."""
        m = self._model()
        b = m.body(body)
        return self._finish(m._omega(b, coordinates == "local"))

    def alpha(self, body, coordinates: str = "global"):
        """Angular acceleration: scalar in 2D, ``(3,)`` in 3D. In 3D the local value is the
        local-axis components of the global angular acceleration."""
        m = self._model()
        b = m.body(body)
        w = m._omega(b, False)
        a = m.time_derivative(w)
        if coordinates == "local" and m.space.dim == 3:
            a = b.A.T * a
        return self._finish(a)

    def instant_center(self, body):
        """Planar instant centre ``(2,)`` of ``body`` (infinite when it does not rotate)."""
        m = self._model()
        b = m.body(body)
        if m.space.dim != 2:
            raise ModelError("instant_center is planar here; the spatial screw axis comes with Model3D")
        v = m.time_derivative(b.r)
        w = m._omega(b, False)
        return self._finish(b.r + sp.Matrix([-v[1], v[0]]) / w)

    # -- vectors --------------------------------------------------------------------------
    def direction(self, vector):
        """Global components of a vector (or the direction of an axis/line)."""
        return self._finish(self._model()._vector(vector).direction())

    def magnitude(self, vector):
        """Length of a vector."""
        d = self._model()._vector(vector).direction()
        return self._finish(sp.sqrt((d.T * d)[0, 0]))

    def unit(self, vector):
        """The vector divided by its length."""
        d = self._model()._vector(vector).direction()
        return self._finish(d / sp.sqrt((d.T * d)[0, 0]))

    def distance(self, point1, point2):
        """Distance between two points."""
        m = self._model()
        d = m._point(point1).location() - m._point(point2).location()
        return self._finish(sp.sqrt((d.T * d)[0, 0]))

    # -- constraints ----------------------------------------------------------------------
    def constraint_equations(self, constraint=None):
        """The equations of one constraint (all when omitted) as a column."""
        m = self._model()
        if constraint is None:
            return self._finish(sp.Matrix(m._all_equations()[0]))
        c = m.constraint(constraint)
        return self._finish(sp.Matrix(c.equations(m.space)))

    def jacobian(self, constraint=None, body=None):
        """``d Phi_c / d q_b``: of one constraint's equations with respect to one body's
        coordinates (all equations or all coordinates when omitted)."""
        m = self._model()
        eqs = sp.Matrix(m._all_equations()[0] if constraint is None
                        else m.constraint(constraint).equations(m.space))
        syms = m._coordinate_symbols() if body is None else list(m.body(body).q)
        return self._finish(eqs.jacobian(syms) if syms else sp.zeros(len(eqs), 0))


def point_of(obj) -> Point:
    if isinstance(obj, Axis):
        return obj.origin
    return as_point(obj)


def vector_of(obj) -> Vector:
    if isinstance(obj, Point):
        raise ModelError(f"expected a vector, got a point {obj!r}; use body.vector(...)")
    return as_vector(obj)
