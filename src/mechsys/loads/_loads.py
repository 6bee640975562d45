r"""Applied loads and their generalized forces (by virtual work, derived once, symbolically).

Every load reduces to *contributions*: a global force :math:`F` at a body point :math:`P`,
a moment :math:`M` on a body, or a magnitude applied directly to a coordinate. The
generalized force on the coordinates is:

.. math::

    Q = \sum_P \left(\frac{\partial v_P}{\partial \dot q}\right)^T F
      + \sum_b \left(\frac{\partial \omega_b}{\partial \dot q}\right)^T M
      + Q_\text{direct}

which is the virtual work :math:`\delta W = F \cdot \delta r_P + M \cdot \delta\pi_b` in any
velocity representation.
Magnitudes may be expressions of ``T``, parameters, coordinates, velocities and Lagrange
multipliers (friction).

Sign conventions (written once, followed everywhere; see ``docs/loads.md``):

* equations of motion :math:`M \ddot q + \Phi_q^T \lambda = Q + Q_v` (:math:`Q_v` the
  centrifugal and gyroscopic terms), so the *reaction* on the coordinates is
  :math:`-\Phi_q^T \lambda`;
* :math:`\text{applied} + \text{reaction} + \text{dynamic} = 0` on every body,
  :math:`\text{dynamic} = Q_v - M \ddot q`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from .._errors import ModelError, choice
from .._signature import InitSignature
from ..geometry._points import Axis, BodyRef, Point, Vector, as_point, as_vector
from ..geometry._units import is_quantity, placeholder


@dataclass
class PointForce:
    point: Point
    force: sp.Matrix  # global


@dataclass
class BodyMoment:
    body: object
    moment: object  # scalar (2D) or global (3,) column (3D)


@dataclass
class DirectLoad:
    symbol: sp.Symbol
    magnitude: sp.Expr


class LoadBase:
    """A load: ``contributions(model)`` and, when conservative, ``potential(model)``."""

    # the signature shown by help() and the API reference is __init__'s, not __new__'s
    __signature__ = InitSignature()

    def __new__(cls, *args, **kwargs):
        # the constructor's arguments, kept for model files (mechsys.io)
        self = super().__new__(cls)
        self._init_args = (args, kwargs)
        return self

    def __init__(self) -> None:
        self.name: str | None = None
        self.model = None
        #: ``(what, expression, hint)`` of the quantities that must not be negative (a
        #: stiffness, a free length, a damping or friction coefficient); a number is checked
        #: when given, an expression of parameters by :meth:`check_values` when a run starts
        self._bounds: list = []

    def _nonnegative(self, value, what: str, hint: str = "") -> sp.Expr:
        """``value`` as a load magnitude that must be zero or positive (physical: a negative
        stiffness, free length, damping or friction coefficient feeds energy in or has no
        meaning); a negative number is a :class:`ModelError` naming ``what``."""
        v = _magnitude(value, what)
        _check_nonnegative(v, what, hint, "")
        self._bounds.append((what, v, hint))
        return v

    def check_values(self, params: dict) -> None:
        """Check the quantities that must not be negative with the parameter values
        ``params`` ({symbol: value}) of a run. An expression of ``T``, coordinates or
        velocities cannot be checked before the run and is not."""
        for what, v, hint in getattr(self, "_bounds", ()):
            if not v.free_symbols <= set(params):  # (a number: a quantity converted on add)
                continue
            _check_nonnegative(sp.sympify(v.xreplace(params)), f"{self.label()}: {what} = {v}", hint,
                               " with the current parameter values")

    def contributions(self, model) -> list:  # pragma: no cover - interface
        raise NotImplementedError

    def potential(self, model):
        """Potential energy (conservative loads) or ``None``."""
        return None

    def bodies(self) -> list:
        return []

    def geometry(self) -> list:
        """Points and vectors of the load (checked against the model's dimension)."""
        return []

    def check(self, model) -> None:
        """Checks when the load is added to ``model``: the dimension of its geometry."""
        for g in self.geometry():
            try:
                g.check_dim(model.space.dim)
            except ModelError as exc:
                raise type(exc)(f"{self.label()}: {exc}") from None

    def label(self) -> str:
        return f"load {self.name!r} ({type(self).__name__})" if self.name else type(self).__name__


def _magnitude(value, what: str) -> sp.Expr:
    """A load magnitude: an expression, finite and real when it is a number."""
    if is_quantity(value):  # converted to the model's units when the load is added
        return placeholder(value, what)
    try:
        v = sp.sympify(value)
    except (sp.SympifyError, TypeError, ValueError, AttributeError, SyntaxError, NameError):
        v = None  # (a dict of strings is parsed as code: AttributeError, SyntaxError ...)
    if not isinstance(v, sp.Expr) or (v.is_number and not (v.is_real and v.is_finite)):
        raise ModelError(f"{what} must be a finite real number or an expression, got {value!r}")
    return v


def _split_vector(vector, magnitude, default, mode: str, cutoff, what: str):
    """``(direction, magnitude)`` of a load given as one pint quantity vector
    (``Force(p, Q([0, -20], "N"))``): the numbers become the direction and the unit, with the
    vector's length in the absolute mode, the magnitude (converted when the load is added,
    its dimension checked there). Other arguments pass through unchanged."""
    if not is_quantity(vector):
        return vector, magnitude
    if magnitude is not default and not (isinstance(magnitude, (int, float))
                                         and magnitude == default):
        raise ModelError(f"{what}: give the vector as a quantity or a magnitude, not both "
                         f"(got {vector} and {magnitude!r})")
    if cutoff:
        raise ModelError(f"{what}: a cutoff is in the direction's own numbers; give the "
                         "direction as numbers and the magnitude as the quantity")
    numbers = np.asarray(vector.magnitude, dtype=float).ravel()
    if not np.all(np.isfinite(numbers)):
        raise ModelError(f"{what}: the vector {vector} must be finite")
    size = float(np.linalg.norm(numbers)) if mode == "absolute" else 1.0
    return tuple(numbers), size * (1 * vector.units)


def _check_nonnegative(v: sp.Expr, what: str, hint: str, when: str) -> None:
    if v.is_number and v.is_real and bool(v < 0):
        raise ModelError(f"{what} must be zero or positive, got {float(v):g}{when}"
                         + (f"; {hint}" if hint else ""))


def check_load_values(loads, params: dict) -> None:
    """:meth:`LoadBase.check_values` of every load (and every load inside a switch) with the
    parameter values ``params`` ({symbol: value}) of a run."""
    for ld in loads:
        for inner in [ld, *(x for s in getattr(ld, "sets", ()) for x in s)]:
            inner.check_values(params)


def _unit(d: sp.Matrix, cutoff=0):
    n2 = (d.T * d)[0, 0]
    if cutoff:
        return d / sp.sqrt(n2 + sp.sympify(cutoff) ** 2)
    return d / sp.sqrt(n2)


class Force(LoadBase):
    r"""A force at a point of a body.

    ``Force(point, direction, magnitude)`` or ``Force(axis, magnitude=...)`` (Mech's
    ``Force[bnum, axis, mag]``: the axis origin is the point of application, its direction
    the line of action). ``direction`` is a :class:`Vector` (fixed in its body: a follower
    force) or a global tuple:

    .. math::

        F &= \mathit{magnitude}\; u / \lvert u \rvert
        \qquad \text{(mode="absolute", the default)} \\
        F &= \mathit{magnitude}\; u \qquad \text{(mode="relative")}

    ``cutoff`` > 0 uses :math:`u / \sqrt{\lvert u \rvert^2 + \mathit{cutoff}^2}` so the
    direction may shrink to zero without a singularity. ``reaction=point2`` applies
    :math:`-F` at ``point2`` of another body (action and reaction).
    """

    def __init__(self, point, direction=None, magnitude=1, *, mode: str = "absolute",
                 cutoff=0, reaction=None):
        super().__init__()
        if isinstance(point, Axis) and direction is None:
            self.point, self.direction = point.origin, point.dir
        else:
            if direction is None:
                raise ModelError("Force needs a direction (a vector, axis or tuple)")
            direction, magnitude = _split_vector(direction, magnitude, 1, mode, cutoff, "Force")
            self.point, self.direction = as_point(point), as_vector(direction)
        choice(mode, ("absolute", "relative"), "Force: mode")
        self.magnitude = _magnitude(magnitude, "Force magnitude")
        self.mode, self.cutoff = mode, self._nonnegative(cutoff, "Force cutoff")
        self.reaction = as_point(reaction) if reaction is not None else None
        if mode == "absolute" and not cutoff:  # u/|u| of a zero vector is 0/0
            self.direction.check_nonzero("Force direction")

    def bodies(self):
        return self.point.bodies() + (self.reaction.bodies() if self.reaction else [])

    def geometry(self):
        return [self.point, self.direction] + ([self.reaction] if self.reaction else [])

    def force_vector(self) -> sp.Matrix:
        d = self.direction.direction()
        u = d if self.mode == "relative" else _unit(d, self.cutoff)
        return self.magnitude * u

    def contributions(self, model):
        F = self.force_vector()
        out = [PointForce(self.point, F)]
        if self.reaction is not None:
            out.append(PointForce(self.reaction, -F))
        return out


class Moment(LoadBase):
    r"""A moment on a body: ``Moment(body, magnitude)`` in 2D (counter-clockwise positive),
    ``Moment(body, vector, magnitude)`` in 3D (:math:`M = \mathit{magnitude}\; u/\lvert u
    \rvert`).
    ``reaction=body2`` applies the opposite moment to ``body2``."""

    def __init__(self, body, a, b=None, *, reaction=None, mode: str = "absolute", cutoff=0):
        super().__init__()
        self.body = body
        if b is None and not (is_quantity(a) and np.ndim(a.magnitude) == 1):
            self.vector, self.magnitude = None, _magnitude(a, "Moment magnitude")
        elif is_quantity(a) and np.ndim(a.magnitude) == 1:   # a 3D moment as one vector
            a, b = _split_vector(a, 1 if b is None else b, 1, mode, cutoff, "Moment")
            self.vector, self.magnitude = as_vector(a), _magnitude(b, "Moment magnitude")
        else:
            self.vector, self.magnitude = as_vector(a), _magnitude(b, "Moment magnitude")
        self.reaction = reaction
        choice(mode, ("absolute", "relative"), "Moment: mode")
        self.mode, self.cutoff = mode, self._nonnegative(cutoff, "Moment cutoff")
        if self.vector is not None and mode == "absolute" and not cutoff:
            self.vector.check_nonzero("Moment direction")

    def bodies(self):
        return [self.body] + ([self.reaction] if self.reaction is not None else [])

    def geometry(self):
        return [self.vector] if self.vector is not None else []

    def check(self, model) -> None:
        self.moment_value(model)  # a vector in 2D, none in 3D: say so now
        super().check(model)

    def moment_value(self, model):
        if model.space.dim == 2:
            if self.vector is not None:
                raise ModelError("a planar Moment takes (body, magnitude), not a vector")
            return self.magnitude
        if self.vector is None:
            raise ModelError("a 3D Moment needs a direction: Moment(body, vector, magnitude)")
        d = self.vector.direction()
        return self.magnitude * (d if self.mode == "relative" else _unit(d, self.cutoff))

    def contributions(self, model):
        M = self.moment_value(model)
        out = [BodyMoment(model.body(self.body), M)]
        if self.reaction is not None:
            out.append(BodyMoment(model.body(self.reaction), -M))
        return out


class Gravity(LoadBase):
    r"""Weight at the centroid of each body (all, or ``bodies``).

    ``Gravity(vector, g, bodies=None, mode="absolute")``: on each body of mass :math:`m`

    .. math::

        F = m g \, \frac{u}{\lVert u \rVert} \quad (\text{mode="absolute", the default}),
        \qquad F = m g \, u \quad (\text{mode="relative"}),

    the relative mode being Mech's ``Magnitude -> Relative``: the force is
    :math:`m g \lVert u \rVert`, so ``u`` carries the field strength too. Potential energy
    :math:`V = -\sum F \cdot r_c` over the bodies (:math:`r_c` the centroids).
    """

    def __init__(self, vector=(0, -1), g=9.81, bodies=None, *, mode: str = "absolute"):
        super().__init__()
        vector, g = _split_vector(vector, g, 9.81, mode, 0, "Gravity")
        self.vector = as_vector(vector)
        self.vector.check_nonzero("Gravity direction")
        self.g = _magnitude(g, "Gravity g")
        # one body (a handle or name) or a list of them
        self.only = [bodies] if isinstance(bodies, (str, int, BodyRef)) else bodies
        choice(mode, ("absolute", "relative"), "Gravity: mode")
        self.mode = mode

    def geometry(self):
        return [self.vector]

    def check(self, model) -> None:
        super().check(model)
        for b in self.only or []:
            model.body(b)

    def _bodies(self, model):
        bs = model.bodies[1:] if self.only is None else [model.body(b) for b in self.only]
        return [b for b in bs if b.mass != 0]

    def _field(self) -> sp.Matrix:
        """Acceleration of gravity ``g u/|u|`` (absolute) or ``g u`` (relative)."""
        d = self.vector.direction()
        return self.g * (d if self.mode == "relative" else _unit(d))

    def contributions(self, model):
        gv = self._field()
        return [PointForce(Point(b, b.centroid, label="centroid"), b.mass * gv)
                for b in self._bodies(model)]

    def potential(self, model):
        gv = self._field()
        terms = []
        for b in self._bodies(model):
            rc = b.r + b.A * b.centroid
            terms.append(-b.mass * (gv.T * rc)[0, 0])
        return sp.Add(*terms)  # one Add: summing one by one re-flattens (N^2 for N bodies)


class Load(LoadBase):
    """A magnitude added directly to the generalized force of one coordinate or variable
    (Mech's ``Load[sym, mag]``)."""

    def __init__(self, symbol, magnitude):
        super().__init__()
        self.symbol = symbol
        self.magnitude = _magnitude(magnitude, "Load magnitude")

    def check(self, model) -> None:
        if not isinstance(self.symbol, sp.Symbol):
            model._coordinate_by_name(str(self.symbol))  # unknown names fail now, not at compile

    def contributions(self, model):
        s = self.symbol if isinstance(self.symbol, sp.Symbol) else model._coordinate_by_name(str(self.symbol))
        return [DirectLoad(s, self.magnitude)]


class Spring(LoadBase):
    r"""Spring between two points: tension :math:`k (L - L_0)` (or ``law(L)``) pulls them
    together.

    ``Spring(point1, point2, stiffness, free_length=0, law=None)``; with
    :math:`L = \lVert r_1 - r_2 \rVert` the force on point 1 is
    :math:`-\,\mathit{tension}\, (r_1 - r_2)/L`, opposite on point 2; the potential of the
    linear spring is :math:`V = \tfrac12 k (L - L_0)^2`.
    """

    def __init__(self, point1, point2, stiffness=0, free_length=0, law=None):
        super().__init__()
        self.p1, self.p2 = as_point(point1), as_point(point2)
        law_hint = "for another force law give law=f(L), the tension as a function of the length"
        self.k = self._nonnegative(stiffness, "Spring stiffness", law_hint)
        self.L0 = self._nonnegative(free_length, "Spring free_length",
                                    "a length is never negative (the spring pushes at lengths "
                                    "below free_length, pulls above it)")
        if law is not None and not callable(law):
            raise ModelError(f"Spring law must be a function of the length, got {law!r}")
        self.law = law

    def bodies(self):
        return self.p1.bodies() + self.p2.bodies()

    def geometry(self):
        return [self.p1, self.p2]

    def length(self):
        d = self.p1.location() - self.p2.location()
        return sp.sqrt((d.T * d)[0, 0])

    def tension(self, model):
        L = self.length()
        return sp.sympify(self.law(L)) if self.law is not None else self.k * (L - self.L0)

    def contributions(self, model):
        d = self.p1.location() - self.p2.location()
        F = -self.tension(model) * d / self.length()
        return [PointForce(self.p1, F), PointForce(self.p2, -F)]

    def potential(self, model):
        if self.law is not None:
            return None
        return self.k * (self.length() - self.L0) ** 2 / 2


class Damper(Spring):
    r"""Linear damper between two points: tension :math:`c\, \dot L` (or ``law(L, dL/dt)``),
    with :math:`L` the distance between them."""

    def __init__(self, point1, point2, damping=0, law=None):
        super().__init__(point1, point2)
        self.c = self._nonnegative(damping, "Damper damping",
                                   "a negative damping coefficient feeds energy in; for another "
                                   "force law give law=f(L, dL/dt)")
        if law is not None and not callable(law):
            raise ModelError(f"Damper law must be a function (L, dL/dt), got {law!r}")
        self.dlaw = law

    def tension(self, model):
        L = self.length()
        Ld = model.time_derivative(L)
        return sp.sympify(self.dlaw(L, Ld)) if self.dlaw is not None else self.c * Ld

    def potential(self, model):
        return None


__all__ = ["Damper", "Force", "Gravity", "Load", "LoadBase", "Moment", "Spring", "Vector"]
