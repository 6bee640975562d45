r"""Output functions, written once: symbolic on a :class:`Model`, numeric on a
:class:`Solution` (which evaluates the same expressions over its time points).

Velocities and accelerations are total time derivatives:

.. math::

    v_P &= \frac{d r_P}{dt} = (r_P)_q \dot q + (r_P)_t \\
    a_P &= \frac{d v_P}{dt}

Planar instant centre of a body with origin velocity :math:`v_O` and angular velocity
:math:`w`:

.. math::

    r_{IC} = r_O + \operatorname{perp}(v_O) / w, \qquad \operatorname{perp}(v) = (-v_y, v_x)

(infinite when ``w = 0``: the body translates).

Selections (Mech's ``All`` / ``Rest`` / lists, for ``location``, ``jacobian`` and the load
outputs): ``All`` every coordinate (and model variable) in layout order, ``Rest`` the model
variables only (Mech: the extra variables of cam and user constraints), a coordinate symbol
one coordinate, a list the concatenation of its items (bodies, symbols).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._errors import ModelError, choice
from ..geometry._points import Axis, Point, Vector, as_point, as_vector


class Selector:
    """Mech's ``All`` and ``Rest`` as arguments of output functions (``ms.All``, ``ms.Rest``)."""

    __slots__ = ("name",)

    def __init__(self, name: str) -> None:
        self.name = name

    def __repr__(self) -> str:
        return f"mechsys.{self.name}"


All = Selector("All")
Rest = Selector("Rest")


def is_selection(spec) -> bool:
    """True for the multi-coordinate forms: ``All``, ``Rest``, a coordinate symbol or a list."""
    return isinstance(spec, (Selector, sp.Symbol, list))


def _is_number(x) -> bool:
    return isinstance(x, (int, float, np.number, sp.Number)) and not isinstance(x, bool)


def selected_coordinates(m, spec) -> list:
    """Coordinate symbols (layout order within each item) of a selection on model ``m``."""
    if spec is All:
        return m._coordinate_symbols()
    if spec is Rest:
        return [v.symbol for v in m._variables]
    if isinstance(spec, sp.Symbol):
        if spec not in m._coordinate_symbols():
            raise ModelError(f"{spec} is not a coordinate or variable of this model")
        return [spec]
    if isinstance(spec, list):
        out = []
        for item in spec:
            if isinstance(item, (Selector, list)):
                raise ModelError(f"a selection list holds bodies and coordinate symbols, got {item!r}")
            out.extend(selected_coordinates(m, item))
        return out
    return list(m.body(spec).q)


class OutputFunctions:
    """Mixin: subclasses provide ``_model()`` and ``_finish(expr)``."""

    def _model(self):  # pragma: no cover - interface
        raise NotImplementedError

    def _finish(self, expr):  # pragma: no cover - interface
        raise NotImplementedError

    # -- points ---------------------------------------------------------------------------
    def location(self, point):
        """Global location ``(dim,)`` of a point (an axis gives its origin; a body handle
        its origin, as a point).

        Mech's ``Location[bnum]`` form: a *list* of bodies (``[body]`` for one), ``All`` or
        ``Rest`` gives the coordinates themselves (``(x, y, th)`` per planar body, ``(x, y, ei, ej)``
        with ``Model2D(orientation="euler")``,
        ``(x, y, z, e0, e1, e2, e3)`` per spatial body, then variables), concatenated. Name
        the bodies (handles or names) in that list: a list of numbers is a global point.
        """
        m = self._model()
        # a list of numbers stays a global point (as before); a list naming bodies selects
        numeric_list = isinstance(point, list) and any(_is_number(x) for x in point)
        if is_selection(point) and not numeric_list:
            syms = selected_coordinates(m, point)
            return self._finish(sp.Matrix(len(syms), 1, syms))
        return self._finish(m._point(point).location())

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
        return self._finish(sp.S.Zero if b.is_ground else m.space.angle(b.q[2:]))

    def omega(self, body, coordinates: str | None = None):
        """Angular velocity: scalar in 2D, ``(3,)`` in 3D (global or ``"local"`` axes)."""
        m = self._model()
        b = m.body(body)
        coordinates = coordinates or getattr(m, "coordinates", "global")
        return self._finish(m._omega(b, coordinates == "local"))

    def alpha(self, body, coordinates: str | None = None):
        """Angular acceleration: scalar in 2D, ``(3,)`` in 3D. In 3D the local value is the
        local-axis components of the global angular acceleration."""
        m = self._model()
        b = m.body(body)
        w = m._omega(b, False)
        a = m.time_derivative(w)
        coordinates = coordinates or getattr(m, "coordinates", "global")
        if coordinates == "local" and m.space.dim == 3:
            a = b.A.T * a
        return self._finish(a)

    def instant_center(self, body, coordinates: str = "global"):
        r"""Planar instant centre ``(2,)`` of ``body`` (infinite when it does not rotate).

        In 3D a body has an instant screw axis instead: returns ``(point, direction)``, the
        point of the axis nearest the body origin ``r_O`` and the axis direction ``omega``::

            r_S = r_O + (omega x v_O) / (omega . omega)

        Every point on the axis has the same velocity, ``omega`` times the slip along it
        (infinite / undefined while the body only translates).

        ``coordinates="local"`` (Mech's ``Coordinates -> Local``) gives the point in the
        body's own frame, ``A^T (r_IC - r_O)`` (and in 3D the direction in body axes,
        :math:`A^T \omega`); the default ``"global"`` as in Mech.
        """
        m = self._model()
        b = m.body(body)
        choice(coordinates, ("global", "local"), "instant_center: coordinates")
        v = m.time_derivative(b.r)
        w = m._omega(b, False)
        if m.space.dim == 3:
            arm = w.cross(v) / w.dot(w)
            if coordinates == "local":
                return self._finish(b.A.T * arm), self._finish(b.A.T * w)
            return self._finish(b.r + arm), self._finish(w)
        arm = sp.Matrix([-v[1], v[0]]) / w
        return self._finish(b.A.T * arm if coordinates == "local" else b.r + arm)

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

    def point_to_local(self, body, point):
        """Coordinates of ``point`` in the frame of ``body`` (Mech's ``PointToLocal``):
        ``A_b^T (r_P - r_b)``, the inverse of :meth:`location` for a point of ``body``.
        ``point`` is a point of any body (or global coordinates, a ground point)."""
        m = self._model()
        b = m.body(body)
        return self._finish(b.A.T * (m._point(point).location() - b.r))

    def vector_to_local(self, body, vector):
        """Components of ``vector`` in the axes of ``body`` (Mech's ``VectorToLocal``):
        :math:`A_b^T d`, the inverse of :meth:`direction`."""
        m = self._model()
        return self._finish(m.body(body).A.T * m._vector(vector).direction())

    # -- constraints ----------------------------------------------------------------------
    def constraint_equations(self, constraint=None):
        """The equations of one constraint (all when omitted) as a column."""
        m = self._model()
        if constraint is None:
            return self._finish(sp.Matrix(m._all_equations()[0]))
        c = m.constraint(constraint)
        return self._finish(sp.Matrix(c.equations(m.space)))

    def jacobian(self, constraint=None, body=None):
        r""":math:`d \Phi_c / d q_b`: of one constraint's equations with respect to one body's
        coordinates (all equations or all coordinates when omitted).

        Mech's forms: ``constraint`` may be ``All`` (every equation of the system, Euler
        normalisations included, in the order of ``generalized(All)``) or a list of
        constraints (rows stacked); ``body`` any selection (``All``, ``Rest``, a list of
        bodies or coordinate symbols). So the static balance is ``J.T @ lam == Q``::

            sol.jacobian(ms.All, ms.All).T @ sol.generalized(ms.All) == sol.loads(ms.All)
        """
        from ._stagewise import is_staged, stagewise

        if is_staged(self):  # a multistage solution: each point with its stage's rows
            return stagewise(self, lambda s: s.jacobian(constraint, body))
        m = self._model()
        eqs = sp.Matrix(self._equation_rows(constraint))
        syms = (m._coordinate_symbols() if body is None
                else selected_coordinates(m, body) if is_selection(body) else list(m.body(body).q))
        return self._finish(eqs.jacobian(syms) if syms else sp.zeros(len(eqs), 0))

    def velocity_terms(self, constraint=None):
        """Mech's ``VelocityTerms``: the explicit time derivative ``Phi_t`` of a constraint's
        equations (all when omitted or ``All``; a list stacks), so that the velocity
        equations read ``jacobian(c) @ qd + velocity_terms(c) == 0``. Only equations that
        depend on ``T`` (drivers) have nonzero terms."""
        from .._symbols import T

        eqs = sp.Matrix(self._equation_rows(constraint))
        return self._finish(eqs.diff(T) if len(eqs) else eqs)

    def acceleration_terms(self, constraint=None):
        r"""Mech's ``AccelerationTerms``: the part of the second time derivative of a
        constraint's equations that is not linear in the accelerations,
        :math:`(\Phi_q \dot q)_q \dot q + 2 \Phi_{qt} \dot q + \Phi_{tt} = -\gamma`, so that the acceleration
        equations read ``jacobian(c) @ qdd + acceleration_terms(c) == 0``."""
        m = self._model()
        eqs = sp.Matrix(self._equation_rows(constraint))
        if not len(eqs):
            return self._finish(eqs)
        acc = m.time_derivative(m.time_derivative(eqs))
        # the accelerations are the rates of the velocity symbols; their terms are J qdd
        zero = {m.time_derivative(v): 0 for v in m.velocity_symbols().values()}
        return self._finish(acc.xreplace(zero))

    def _equation_rows(self, constraint) -> list:
        """Equations of a constraint selection; on a solution, those of its own system (a
        free system has fewer), so rows match the multipliers ``generalized`` returns."""
        m = self._model()
        sys_ = getattr(self, "system", None)
        eqs, owners = (list(sys_.phi), list(sys_.layout.eq_owner)) if sys_ is not None else \
            m._all_equations()[:2]
        if constraint is None or constraint is All:
            return eqs
        if isinstance(constraint, list):
            return [e for c in constraint for e in self._equation_rows(c)]
        c = m.constraint(constraint)
        rows = [e for e, o in zip(eqs, owners) if o is c]
        # a constraint dropped by free() still has equations (evaluated at the free motion)
        return rows if rows else list(c.equations(m.space))


def point_of(obj) -> Point:
    if isinstance(obj, Axis):
        return obj.origin
    return as_point(obj)


def vector_of(obj) -> Vector:
    if isinstance(obj, Point):
        raise ModelError(f"expected a vector, got a point {obj!r}; use body.vector(...)")
    return as_vector(obj)


class VelocityViews:
    """Velocities and accelerations of bodies in a chosen representation (Mech's
    ``SetSymbols[Method -> Euler | Angular, Coordinates -> Global | Local]``).

    mechsys integrates and solves with Euler-parameter rates (one formulation, compiled
    once; see ``docs/decisions/0006-velocity-representation.md``); these views give the
    same solution in the other representations:

    * ``"euler"``: the coordinate rates ``(x', y', z', e0', e1', e2', e3')`` (2D: ``x', y', th'``);
    * ``"angular"``: ``(x', y', z', w_x, w_y, w_z)`` with ``w`` the angular velocity in global
      or body-local axes (2D: identical to ``"euler"``).
    """

    def velocities(self, body=None, representation: str | None = None,
                   coordinates: str | None = None):
        """Velocity coordinates of one body (or all moving bodies, concatenated)."""
        return self._views(body, representation, coordinates, 1)

    def accelerations(self, body=None, representation: str | None = None,
                      coordinates: str | None = None):
        """Acceleration coordinates of one body (or all moving bodies, concatenated)."""
        return self._views(body, representation, coordinates, 2)

    def _views(self, body, representation, coordinates, order):
        m = self._model()
        rep = representation or getattr(m, "velocity_representation", "euler")
        coords = coordinates or getattr(m, "coordinates", "global")
        choice(rep, ("euler", "angular"), "representation")
        bodies = [m.body(body)] if body is not None else m.bodies[1:]
        parts = []
        for b in bodies:
            if rep == "euler" or m.space.dim == 2:
                syms = list(b.q)
                for _ in range(order):
                    syms = [m.time_derivative(s) for s in syms]
                parts.append(sp.Matrix(syms))
            else:
                lin = m.time_derivative(b.r)
                ang = m._omega(b, False)
                if order == 2:
                    lin = m.time_derivative(lin)
                    ang = m.time_derivative(ang)
                if coords == "local":
                    ang = b.A.T * ang
                parts.append(sp.Matrix.vstack(lin, ang))
        return self._finish(sp.Matrix.vstack(*parts))
