r"""Nominal gear constraints (Mech 6.2): spur and internal gears, racks, belts, bevel and worm
sets, lead screws. Only the nominal rotary motion is modelled, not tooth-to-tooth contact.

Each constraint relates two rotation angles through a *phase constant* ``C`` fixed at
assembly (Mech's convention, quoted in each docstring) and introduces, where Mech does, a
new variable -- the angle that tracks the relative spin -- given as a ``(sym, guess)`` tuple
at Mech's position in the argument list (Mech's ``{sym, guess}``) or as ``variable=(sym,
guess)``. When it is omitted a variable named after the bodies is created
(``Theta_gear1_gear2``, ``Theta_gear_ground``), its guess computed from the bodies' guesses;
``Model.add`` refuses a second such default on the same bodies: give that one explicitly.

Angles about an axis use the axis' *angle frame* ``(g, k)`` (see ``_angles``): :math:`\angle(g
\to f) = a` is written :math:`\cos(a)\, (k \cdot f) - \sin(a)\, (g \cdot f) = 0`, regular for
every ``a`` and also satisfied at :math:`a + \pi` (the guess picks the branch).

Sign conventions (Mech's formulas): a negative gear radius is an internal (ring) gear --
:math:`r_1 + r_2` is then the signed centre distance and the pair turns the same way; a
negative tooth count in ``OrthogonalGears5`` reverses the sense; a negative ``pitch`` is a
left-hand screw. Zero radii, tooth counts and pitches are rejected.
"""

from __future__ import annotations

import inspect
import math

import sympy as sp

from .._errors import GeometryError, ModelError
from ..geometry._points import Axis, GlobalVector, as_axis, as_point
from . import _primitives as P
from ._angles import angle_equation, angle_frame, vector_norm
from ._base import ConstraintBase, Variable, as_expr


def _nonzero(value, what: str, hint: str = "") -> sp.Expr:
    v = as_expr(value, what)
    if v.is_number and (v.is_zero or not v.is_finite or not v.is_real):
        raise ModelError(f"{what} = {value!r}: must be a nonzero finite number{hint}")
    return v


def _split_variable(args: tuple, kind: str, where: int, variable=None) -> tuple[tuple, tuple | None]:
    """Remove Mech's optional ``{sym, guess}`` at position ``where`` of ``args`` (or take the
    ``variable=`` keyword)."""
    if len(args) > where and _is_variable_spec(args[where]):
        if variable is not None:
            raise ModelError(f"{kind}: the variable is given twice, positionally and as variable=")
        return args[:where] + args[where + 1:], args[where]
    if variable is not None and not _is_variable_spec(variable):
        raise ModelError(f"{kind} variable: expected (symbol, guess), got {variable!r}")
    return args, variable


def _signature(*names: str, optional: tuple = ()):
    """Give a class built on ``__init__(*args, variable=None)`` its documented signature:
    Mech's arguments, then ``variable=(sym, guess)`` (which may also stand at Mech's
    position)."""
    kind = inspect.Parameter.POSITIONAL_OR_KEYWORD
    params = [inspect.Parameter("self", kind)] + [inspect.Parameter(n, kind) for n in names]
    params += [inspect.Parameter(n, kind, default=d) for n, d in optional]
    params.append(inspect.Parameter("variable", inspect.Parameter.KEYWORD_ONLY, default=None))

    def deco(cls):
        base = cls.__init__

        def __init__(self, *args, variable=None):
            base(self, *args, variable=variable)

        __init__.__signature__ = inspect.Signature(params)
        cls.__init__ = __init__
        return cls

    return deco


def _is_variable_spec(obj) -> bool:
    if isinstance(obj, Variable):
        return True
    return (isinstance(obj, tuple) and len(obj) == 2 and isinstance(obj[0], (str, sp.Symbol))
            and not isinstance(obj[1], (tuple, list)))


def _arity(args, kind: str, names: list[str]) -> list:
    if len(args) != len(names):
        raise ModelError(f"{kind} takes ({', '.join(names)}); got {len(args)} arguments")
    return list(args)


def _body_angle(space, body) -> sp.Expr:
    """The planar angle coordinate of a body (0 for ground or no body)."""
    if body is None or getattr(body, "is_ground", False):
        return sp.Integer(0)
    if hasattr(space, "continuous_angle"):  # orientation="euler"
        space.continuous_angle("a gear constraint")
    return space.angle(body.q[space.dim:])


def _in_euler(bodies) -> bool:
    """Whether these bodies are in planar Euler coordinates (``orientation="euler"``)."""
    return any(hasattr(getattr(b, "space", None), "continuous_angle") for b in bodies)


def _angle_guess(body) -> sp.Expr:
    """A body's angle for a variable's default guess only: the principal value in Euler
    coordinates is enough to pick the branch."""
    if body is None or getattr(body, "is_ground", False):
        return sp.Integer(0)
    return body.space.angle(body.q[body.space.dim:])


def _body_frame(body) -> tuple[sp.Matrix, sp.Matrix]:
    """``(g, k)``: a planar body's x and y axes in global coordinates (ground's for None)."""
    if body is None or getattr(body, "is_ground", False):
        return sp.Matrix([1, 0]), sp.Matrix([0, 1])
    return body.A[:, 0], body.A[:, 1]


def _guess_value(expr, bodies) -> float | None:
    """``expr`` evaluated at the bodies' guesses (time 0); None if it has other symbols."""
    from .._symbols import T

    subs = {T: 0.0}
    for b in bodies:
        if not getattr(b, "is_ground", False):
            subs.update({q: float(v) for q, v in zip(b.q, b.guess)})
    try:
        val = complex(sp.sympify(expr).subs(subs).evalf())
    except (TypeError, ValueError):
        return None
    return val.real if math.isfinite(val.real) and abs(val.imag) < 1e-12 else None


class _Gear(ConstraintBase):
    """Shared handling of the tracking variable."""

    #: Mech adds the variable only with its Euler method: planar rack forms need none.
    _always_variable = True

    def _init_variable(self, spec) -> None:
        self._var_spec = spec
        self._var: Variable | None = None

    def _guess_expr(self) -> sp.Expr | None:
        """The variable's value as an expression of the coordinates (for its default guess)."""
        return None

    def variable(self) -> Variable | None:
        if self._var is None:
            spec = self._var_spec
            if isinstance(spec, Variable):
                self._var = spec
            elif spec is not None:
                self._var = Variable(*spec)
            elif self._always_variable:
                name = "_".join(["Theta"] + [b.name for b in self.bodies()])
                expr = self._guess_expr()
                guess = _guess_value(expr, self.bodies()) if expr is not None else None
                self._var = Variable(name, guess or 0.0)
                self._var.auto_named = True     # Model.add refuses to merge it with another
        return self._var

    def new_variables(self):
        v = self.variable()
        return [v] if v is not None else []

    @property
    def alpha(self) -> sp.Symbol | None:
        """The tracking variable's symbol (None if the form has none)."""
        v = self.variable()
        return v.symbol if v is not None else None

    def pitch_circles(self) -> list[tuple]:
        """``[(centre point or axis, pitch radius), ...]`` of the wheels this constraint
        meshes (used by pictures: ``mechsys.draw`` draws them as pitch circles)."""
        return []


class _WheelPair(_Gear):
    """Two wheels (centre points in 2D, axes in 3D) of pitch radii ``rad1``, ``rad2``;
    subclasses give ``_wheels() -> (wheel1, wheel2)``."""

    def _wheels(self):  # pragma: no cover - every subclass defines it
        raise NotImplementedError

    def geometry(self):
        return list(self._wheels())

    def pitch_circles(self):
        w1, w2 = self._wheels()
        return [(w1, self.rad1), (w2, self.rad2)]

    def _d(self):
        """``d = r_2 - r_1``, from the first wheel's centre to the second's."""
        w1, w2 = self._wheels()
        return w2.location() - w1.location()


# -- 2D ---------------------------------------------------------------------------------------


class _TwoWheels(_WheelPair):
    r"""Planar gears and pulleys: ``point1, rad1[, (sym, guess)], point2, rad2[, dist], C``.

    The variable is the direction angle :math:`\Theta` of ``d = r_2 - r_1`` (the line of
    centres), which keeps the equations free of ``atan2`` and its branch cut: a carrier
    may turn any number of times.
    """

    spaces = ("planar",)
    _sign = 1          # +1 gears (C = r1 e1 + r2 e2), -1 pulleys (C = r1 e1 - r2 e2)
    _with_distance = False
    _with_dist_arg = False

    def __init__(self, *args, variable=None):
        super().__init__()
        kind = type(self).__name__
        args, spec = _split_variable(args, kind, 2, variable)
        names = ["point1", "rad1", "point2", "rad2"] + (["dist"] if self._with_dist_arg else []) + ["C"]
        vals = _arity(args, kind, names)
        self.p1, self.p2 = as_point(vals[0]), as_point(vals[2])
        self.rad1 = _nonzero(vals[1], f"{kind} rad1")
        self.rad2 = _nonzero(vals[3], f"{kind} rad2")
        if self._with_dist_arg:
            self.dist = _nonzero(vals[4], f"{kind} dist", " (the centre distance)")
        self.C = as_expr(vals[-1], f"{kind} C")
        rho = self.rad1 + self._sign * self.rad2
        if rho.is_number and rho.is_zero:
            if self._sign < 0:
                raise ModelError(f"{kind}: rad1 = rad2 = {self.rad1}: the pulleys turn together; "
                                 "use RotationLock1(body1, body2, angle) (Mech's advice)")
            raise ModelError(f"{kind}: rad1 + rad2 = 0 puts both gear centres at one point; "
                             "the radii of an internal pair differ")
        self._init_variable(spec)

    def _wheels(self):
        return self.p1, self.p2

    def _guess_expr(self):
        d = self._d()
        if _in_euler(self.bodies()):
            # Mech's Euler form: the variable is e1, the angle from d to wheel 1's x axis
            return _angle_guess(self.p1.body) - sp.atan2(d[1], d[0])
        return sp.atan2(d[1], d[0])

    def _build(self, space):
        if hasattr(space, "continuous_angle"):
            return self._build_euler()
        th = self.alpha
        d = self._d()
        th1, th2 = _body_angle(space, self.p1.body), _body_angle(space, self.p2.body)
        mesh = self.rad1 * (th1 - th) + self._sign * self.rad2 * (th2 - th) - self.C
        if self._with_distance:
            rho = self.dist if self._with_dist_arg else self.rad1 + self.rad2
            rho = sp.sqrt(rho**2)
            return [d[0] - rho * sp.cos(th), d[1] - rho * sp.sin(th), mesh]
        return [mesh, d[0] * sp.sin(th) - d[1] * sp.cos(th)]

    def _build_euler(self):
        r"""Planar Euler coordinates carry no turn-counting angle, so (as Mech's Euler method
        and the spatial gears do) the variable is :math:`a = e_1`, the angle from ``d`` to wheel
        1's x axis, and :math:`e_2 = (C - \mathit{rad}_1\, a) / (\mathit{sign}\,
        \mathit{rad}_2)` follows from the mesh; each is imposed by a regular angle equation in
        its wheel's frame ``(g, k)``:

        .. math::

            \cos(-a)\, (k_1 \cdot d) - \sin(-a)\, (g_1 \cdot d) &= 0
            \qquad \text{(TwoGears1: with the next one)} \\
            d - \rho\, (\cos(a)\, g_1 - \sin(a)\, k_1) &= 0 \qquad \text{(TwoGears2: instead, 2 equations)} \\
            \cos(-e_2)\, (k_2 \cdot d) - \sin(-e_2)\, (g_2 \cdot d) &= 0
        """
        a = self.alpha
        d = self._d()
        e2 = (self.C - self.rad1 * a) / (self._sign * self.rad2)
        g1, k1 = _body_frame(self.p1.body)
        second = angle_equation(_body_frame(self.p2.body), d, -e2)
        if self._with_distance:
            rho = self.dist if self._with_dist_arg else self.rad1 + self.rad2
            u = sp.cos(a) * g1 - sp.sin(a) * k1       # at angle -a from g1
            return [d[0] - sp.sqrt(rho**2) * u[0], d[1] - sp.sqrt(rho**2) * u[1], second]
        return [angle_equation((g1, k1), d, -a), second]


@_signature("point1", "rad1", "point2", "rad2", "C")
class TwoGears1(_TwoWheels):
    r"""Two meshing gears (external, or internal with a negative radius) whose centres other
    constraints place. Removes 1 DOF (2D).

    ``TwoGears1(point1, rad1[, (sym, guess)], point2, rad2, C)``: ``point1``, ``point2`` the
    gear centres on the gear bodies, ``rad1``, ``rad2`` the pitch radii. :math:`C =
    \mathit{rad}_1\, e_1 + \mathit{rad}_2\, e_2` where :math:`e_i` is the angle from the vector
    ``point1 -> point2`` to gear i's local x axis, in any valid position (Mech's convention).
    With :math:`\Theta` the direction angle of :math:`d = r_2 - r_1` (the new variable) and
    :math:`\theta_i` the body angles:

    .. math::

        \mathit{rad}_1\, (\theta_1 - \Theta) + \mathit{rad}_2\, (\theta_2 - \Theta) - C &= 0 \\
        d_x\, \sin(\Theta) - d_y\, \cos(\Theta) &= 0

    Fixed centres give :math:`\theta_2^{\prime} = -(\mathit{rad}_1/\mathit{rad}_2)\,
    \theta_1^{\prime}`. The second equation also holds at :math:`\Theta + \pi`: the default
    guess is the direction at the bodies' guesses.
    """

    mech_name = "TwoGears1"
    dof_removed = 1


@_signature("point1", "rad1", "point2", "rad2", "C")
class TwoGears2(_TwoWheels):
    r"""Two meshing gears: centres :math:`\mathit{rad}_1 + \mathit{rad}_2` apart and the rotations
    related. Removes 2 DOF (2D).

    ``TwoGears2(point1, rad1[, (sym, guess)], point2, rad2, C)``; ``C`` as in
    :class:`TwoGears1`. A negative radius is an internal (ring) gear, :math:`\lvert
    \mathit{rad}_1 + \mathit{rad}_2 \rvert` the centre distance. With :math:`\Theta` the direction
    angle of :math:`d = r_2 - r_1`:

    .. math::

        d_x - \lvert \mathit{rad}_1 + \mathit{rad}_2 \rvert\, \cos(\Theta) &= 0 \\
        d_y - \lvert \mathit{rad}_1 + \mathit{rad}_2 \rvert\, \sin(\Theta) &= 0 \\
        \mathit{rad}_1\, (\theta_1 - \Theta) + \mathit{rad}_2\, (\theta_2 - \Theta) - C &= 0

    (Mech's first equation, the distance, is here the first two, which also give :math:`\Theta`
    without a branch ambiguity.) A turning carrier obeys Willis' formula.
    """

    mech_name = "TwoGears2"
    dof_removed = 2
    _with_distance = True


@_signature("point1", "rad1", "point2", "rad2", "dist", "C")
class TwoPulleys1(_TwoWheels):
    r"""Chain and sprockets, or belt and pulleys, with centres placed by other constraints.
    Removes 1 DOF (2D).

    ``TwoPulleys1(point1, rad1[, (sym, guess)], point2, rad2, dist, C)``; :math:`C = \mathit{rad}_1\, e_1 -
    \mathit{rad}_2\, e_2` with :math:`e_i` as in :class:`TwoGears1`. The radii must differ (use
    ``RotationLock1`` for equal ones, as Mech says); ``dist`` is only used by
    :class:`TwoPulleys2`. With :math:`\Theta` the direction angle of :math:`d = r_2 - r_1`:

    .. math::

        \mathit{rad}_1\, (\theta_1 - \Theta) - \mathit{rad}_2\, (\theta_2 - \Theta) - C &= 0 \\
        d_x\, \sin(\Theta) - d_y\, \cos(\Theta) &= 0

    Fixed centres: :math:`\theta_2^{\prime} = (\mathit{rad}_1/\mathit{rad}_2)\,
    \theta_1^{\prime}` (same sense).
    """

    mech_name = "TwoPulleys1"
    dof_removed = 1
    _sign = -1
    _with_dist_arg = True


@_signature("point1", "rad1", "point2", "rad2", "dist", "C")
class TwoPulleys2(_TwoWheels):
    r"""Chain and sprockets, or belt and pulleys, ``dist`` apart. Removes 2 DOF (2D).

    ``TwoPulleys2(point1, rad1[, (sym, guess)], point2, rad2, dist, C)``; ``C`` as in
    :class:`TwoPulleys1`:

    .. math::

        d_x - \lvert \mathit{dist} \rvert\, \cos(\Theta) &= 0 \\
        d_y - \lvert \mathit{dist} \rvert\, \sin(\Theta) &= 0 \\
        \mathit{rad}_1\, (\theta_1 - \Theta) - \mathit{rad}_2\, (\theta_2 - \Theta) - C &= 0
    """

    mech_name = "TwoPulleys2"
    dof_removed = 2
    _sign = -1
    _with_dist_arg = True
    _with_distance = True


class _PlanarRack(_Gear):
    """``point, rad[, (alpha, guess)], axis, C`` -- Mech adds ``alpha`` only when asked."""

    spaces = ("planar",)
    _with_distance = False

    @property
    def _always_variable(self) -> bool:
        # the form without alpha uses the body angles: in Euler coordinates alpha is needed
        return _in_euler(self.bodies())

    def _guess_expr(self):
        d = self.axis.dir
        if d.points is not None or isinstance(d, GlobalVector) or d.local is None:
            return None
        return (_angle_guess(self.p.body) - _angle_guess(d.body)
                - sp.atan2(d.local[1], d.local[0]))

    def __init__(self, *args, variable=None):
        super().__init__()
        kind = type(self).__name__
        args, spec = _split_variable(args, kind, 2, variable)
        vals = _arity(args, kind, ["point", "rad", "axis", "C"])
        self.p = as_point(vals[0])
        self.rad = _nonzero(vals[1], f"{kind} rad", " (the pinion's pitch radius)")
        (self.axis,) = _axes(kind, vals[2])
        self.C = as_expr(vals[3], f"{kind} C")
        self._init_variable(spec)

    def geometry(self):
        return [self.p, self.axis]

    def pitch_circles(self):
        return [(self.p, self.rad)]

    def _rack_angle(self, space):
        """Angle of the rack's direction: its body angle plus the local direction's."""
        d = self.axis.dir
        if d.points is not None or isinstance(d, GlobalVector) or d.local is None:
            raise ModelError(f"{type(self).__name__}: the rack axis must have a direction fixed in "
                             "its body (a local vector), or give (alpha, guess)")
        return _body_angle(space, d.body) + sp.atan2(d.local[1], d.local[0])

    def _build(self, space):
        u = self.axis.direction()
        s = u.dot(self.p.location() - self.axis.location()) / vector_norm(self.axis.dir)
        eqs = P.point_on_line(space, self.p, self.axis, self.rad) if self._with_distance else []
        alpha = self.alpha
        if alpha is None:
            rel = _body_angle(space, self.p.body) - self._rack_angle(space)
            return eqs + [s - self.C + self.rad * rel]
        x1 = self.p.body.A[:, 0] if self.p.body is not None else sp.Matrix([1, 0])
        frame = angle_frame(space, self.axis)
        return eqs + [s - self.C + self.rad * alpha, angle_equation(frame, x1, alpha)]


@_signature("point", "rad", "axis", "C")
class RackAndPinion1(_PlanarRack):
    r"""Rack and pinion whose distance other constraints fix. Removes 1 DOF (2D).

    ``RackAndPinion1(point, rad[, (alpha, guess)], axis, C)``: ``axis`` is the rack (on the rack
    body), ``point`` the pinion centre, ``rad`` its pitch radius. ``C`` is the distance along
    ``axis`` from its origin to ``point`` when the pinion's x axis is parallel to the rack. With
    :math:`s = \hat{u} \cdot (r_p - r_o)` and :math:`\alpha = \theta_p - \theta_{rack}` (the
    angle from the rack direction to the pinion's x axis):

    .. math::

        s - C + \mathit{rad}\, \alpha = 0

    With ``(alpha, guess)`` (Mech's Euler form) ``alpha`` is a new variable and, with
    ``(g, k)`` the rack's angle frame and :math:`x_p` the pinion's x axis:

    .. math::

        s - C + \mathit{rad}\, \alpha &= 0 \\
        \cos(\alpha)\, (k \cdot x_p) - \sin(\alpha)\, (g \cdot x_p) &= 0

    The pinion (centre on the left of the rack) rolls: :math:`ds = -\mathit{rad}\, d\alpha`.
    """

    mech_name = "RackAndPinion1"
    dof_removed = 1


@_signature("point", "rad", "axis", "C")
class RackAndPinion2(_PlanarRack):
    r"""Rack and pinion: the pinion centre ``rad`` to the left of the rack, rolling on it.
    Removes 2 DOF (2D).

    ``RackAndPinion2(point, rad[, (alpha, guess)], axis, C)``; ``C``, ``s`` and ``alpha`` as in
    :class:`RackAndPinion1`, :math:`d = r_p - r_o`:

    .. math::

        u \times d - \mathit{rad}\, \lvert u \rvert &= 0 \\
        s - C + \mathit{rad}\, \alpha &= 0

    (plus :math:`\cos(\alpha)\, (k \cdot x_p) - \sin(\alpha)\, (g \cdot x_p) = 0` with ``(alpha, guess)``).
    """

    mech_name = "RackAndPinion2"
    dof_removed = 2
    _with_distance = True


# -- 3D ---------------------------------------------------------------------------------------


def _axes(kind: str, *objs) -> list[Axis]:
    """The axes, a zero-length direction reported with the constraint's name."""
    out = []
    for k, obj in enumerate(objs, 1):
        what = f"{kind} axis{k}" if len(objs) > 1 else f"{kind} axis"
        try:
            a = as_axis(obj)
        except GeometryError as exc:
            raise GeometryError(f"{what}: {exc}") from None
        a.dir.check_nonzero(what)
        out.append(a)
    return out


class _ParallelGears(_WheelPair):
    """Gears (``_sign = +1``: ``C = rad1 e1 + rad2 e2``, centres ``rad1 + rad2`` apart) or
    belts and chains (``-1``: ``C = rad1 e1 - rad2 e2``, centres ``dist`` apart) on parallel
    axes; ``_adjacent``: the heads of the axes side by side."""

    spaces = ("spatial",)
    _adjacent = True
    _sign = 1

    def __init__(self, *args, variable=None):
        super().__init__()
        kind = type(self).__name__
        args, spec = _split_variable(args, kind, 2, variable)
        pulleys = self._sign < 0
        names = ["axis1", "rad1", "axis2", "rad2"] + (["dist"] if pulleys else []) + ["C"]
        vals = _arity(args, kind, names)
        self.a1, self.a2 = _axes(kind, vals[0], vals[2])
        self.rad1 = _nonzero(vals[1], f"{kind} rad1")
        self.rad2 = _nonzero(vals[3], f"{kind} rad2")
        if pulleys:
            self.dist = _nonzero(vals[4], f"{kind} dist", " (the centre distance)")
        elif (self.rad1 + self.rad2).is_zero:
            raise ModelError(f"{kind}: rad1 + rad2 = 0 puts both axes on one line; the radii "
                             "of an internal pair differ")
        self.C = as_expr(vals[-1], f"{kind} C")
        self._init_variable(spec)

    def _centre_distance(self):
        return self.dist if self._sign < 0 else self.rad1 + self.rad2

    def _wheels(self):
        return self.a1, self.a2

    def _guess_expr(self):
        g1, k1 = _plain_frame(self.a1)
        d = self._d()
        return -sp.atan2(k1.dot(d), g1.dot(d))

    def _build(self, space):
        d = self._d()
        a = self.alpha
        e2 = (self.C - self.rad1 * a) / (self._sign * self.rad2)
        u1h = self.a1.direction() / vector_norm(self.a1.dir)
        rho = self._centre_distance()
        if self._adjacent:
            dist = [d.dot(d) - rho**2]
            adj = [u1h.dot(d)]
        else:
            dp = d - u1h * u1h.dot(d)
            dist, adj = [dp.dot(dp) - rho**2], []
        return (P.parallel(space, self.a1.dir, self.a2.dir) + adj + dist
                + [angle_equation(angle_frame(space, self.a1), d, -a),
                   angle_equation(angle_frame(space, self.a2), d, -e2)])


def _plain_frame(axis: Axis):
    u = axis.direction()
    u = u / sp.sqrt(u.dot(u))
    g = axis.reference_vector().direction()
    return g, u.cross(g)


@_signature("axis1", "rad1", "axis2", "rad2", "C")
class ParallelGears5(_ParallelGears):
    r"""Spur (or helical, or internal) gears on parallel axes :math:`\mathit{rad}_1 +
    \mathit{rad}_2` apart, the heads of the axes side by side. Removes 5 DOF (3D).

    ``ParallelGears5(axis1, rad1[, (alpha, guess)], axis2, rad2, C)``; ``alpha`` (the new
    variable) is the spin of ``axis1`` relative to :math:`d = r_2 - r_1`. :math:`C =
    \mathit{rad}_1\, e_1 + \mathit{rad}_2 e_2`, :math:`e_i` the angle from ``d`` to the
    reference direction :math:`g_i` of axis i, about :math:`u_i` (Mech's convention); :math:`e_2
    = (C - \mathit{rad}_1\, \alpha) / \mathit{rad}_2`. With :math:`(g_i, k_i)` the angle frames,
    :math:`h_2, f_2` normals of axis 2 (Mech's order):

    .. math::

        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0 \\
        \hat{u}_1 \cdot d &= 0 \\
        d \cdot d - (\mathit{rad}_1 + \mathit{rad}_2)^2 &= 0 \\
        \cos(\alpha)\, (k_1 \cdot d) + \sin(\alpha)\, (g_1 \cdot d) &= 0 \\
        \cos(e_2)\, (k_2 \cdot d) + \sin(e_2)\, (g_2 \cdot d) &= 0

    A negative radius is an internal gear. The angle equations also hold half a turn away:
    the default guess of ``alpha`` is its value at the bodies' guesses.
    """

    mech_name = "ParallelGears5"
    dof_removed = 5


@_signature("axis1", "rad1", "axis2", "rad2", "C")
class ParallelGears4(_ParallelGears):
    r""":class:`ParallelGears5` without the adjacency equation: the gear of ``axis2`` may
    slide along its axis (a wide pinion). Removes 4 DOF (3D).

    ``ParallelGears4(axis1, rad1[, (alpha, guess)], axis2, rad2, C)``; with :math:`d_p = d -
    \hat{u}_1\, (\hat{u}_1 \cdot d)` the part of ``d`` across the axes:

    .. math::

        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0 \\
        d_p \cdot d_p - (\mathit{rad}_1 + \mathit{rad}_2)^2 &= 0 \\
        \cos(\alpha)\, (k_1 \cdot d) + \sin(\alpha)\, (g_1 \cdot d) &= 0 \\
        \cos(e_2)\, (k_2 \cdot d) + \sin(e_2)\, (g_2 \cdot d) &= 0

    (The angle equations only see the part of ``d`` across the axes.)
    """

    mech_name = "ParallelGears4"
    dof_removed = 4
    _adjacent = False


@_signature("axis1", "rad1", "axis2", "rad2", "dist", "C")
class TwoPulleys5(_ParallelGears):
    r"""Belt and pulleys, or chain and sprockets, on parallel axes ``dist`` apart, the heads
    of the axes side by side. Removes 5 DOF (3D).

    ``TwoPulleys5(axis1, rad1[, (alpha, guess)], axis2, rad2, dist, C)``; ``alpha`` as in
    :class:`ParallelGears5`; :math:`C = \mathit{rad}_1\, e_1 - \mathit{rad}_2\, e_2` (Mech's
    convention), so :math:`e_2 = (\mathit{rad}_1 \alpha - C) / \mathit{rad}_2` and both pulleys
    turn the same way:

    .. math::

        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0 \\
        \hat{u}_1 \cdot d &= 0 \\
        d \cdot d - \mathit{dist}^2 &= 0 \\
        \cos(\alpha)\, (k_1 \cdot d) + \sin(\alpha)\, (g_1 \cdot d) &= 0 \\
        \cos(e_2)\, (k_2 \cdot d) + \sin(e_2)\, (g_2 \cdot d) &= 0
    """

    mech_name = "TwoPulleys5"
    dof_removed = 5
    _sign = -1


@_signature("axis1", "rad1", "axis2", "rad2", "dist", "C")
class TwoPulleys4(_ParallelGears):
    r""":class:`TwoPulleys5` without the adjacency equation: the pulleys may slide along
    their axes relative to each other. Removes 4 DOF (3D).

    ``TwoPulleys4(axis1, rad1[, (alpha, guess)], axis2, rad2, dist, C)``; with :math:`d_p` the
    part of ``d`` across the axes:

    .. math::

        h_2 \cdot u_1 &= 0 \\
        f_2 \cdot u_1 &= 0 \\
        d_p \cdot d_p - \mathit{dist}^2 &= 0 \\
        \cos(\alpha)\, (k_1 \cdot d) + \sin(\alpha)\, (g_1 \cdot d) &= 0 \\
        \cos(e_2)\, (k_2 \cdot d) + \sin(e_2)\, (g_2 \cdot d) &= 0
    """

    mech_name = "TwoPulleys4"
    dof_removed = 4
    _sign = -1
    _adjacent = False


@_signature("axis1", "teeth1", "axis2", "teeth2", "dist_or_C", optional=(("C", None),))
class OrthogonalGears5(_Gear):
    r"""Gears on perpendicular axes: a bevel set (origins coincident) or, with ``dist``, a
    worm or spiral-bevel (hypoid) set with offset axes. Removes 5 DOF (3D).

    ``OrthogonalGears5(axis1, teeth1[, (alpha, guess)], axis2, teeth2[, dist], C)``. ``alpha``
    (the new variable) tracks the spin of ``axis1``: the angle, about :math:`u_1`, from
    :math:`u_2` to the reference direction :math:`g_1`. :math:`C = \mathit{teeth}_1\, e_1 +
    \mathit{teeth}_2\, e_2`, ``e1`` that angle, ``e2`` the angle about :math:`u_2` from
    :math:`u_1` to :math:`g_2` (Mech's convention), so :math:`e_2 = (C - \mathit{teeth}_1\,
    \alpha) / \mathit{teeth}_2` and the speed ratio is
    :math:`-\mathit{teeth}_1/\mathit{teeth}_2`; negating a tooth count reverses it. ``dist`` is
    signed along :math:`\hat{u}_1 \times \hat{u}_2`; :math:`d = r_1 - r_2`:

    .. math::

        u_1 \cdot u_2 &= 0 \\
        u_1 \cdot (r_2 - r_1) &= 0 \\
        u_2 \cdot d &= 0 \\
        (u_1 \times u_2) \cdot d - \mathit{dist}\, \lvert u_1 \rvert\, \lvert u_2 \rvert &= 0 \\
        \cos(\alpha)\, (k_1 \cdot u_2) + \sin(\alpha)\, (g_1 \cdot u_2) &= 0 \\
        \cos(e_2)\, (k_2 \cdot u_1) + \sin(e_2)\, (g_2 \cdot u_1) &= 0
    """

    mech_name = "OrthogonalGears5"
    dof_removed = 5
    spaces = ("spatial",)

    def __init__(self, *args, variable=None):
        super().__init__()
        kind = "OrthogonalGears5"
        args, spec = _split_variable(args, kind, 2, variable)
        if len(args) == 5:
            args = (*args[:4], 0, args[4])
        vals = _arity(args, kind, ["axis1", "teeth1", "axis2", "teeth2", "dist", "C"])
        self.a1, self.a2 = _axes(kind, vals[0], vals[2])
        self.teeth1 = _nonzero(vals[1], f"{kind} teeth1", " (negate it to reverse the sense)")
        self.teeth2 = _nonzero(vals[3], f"{kind} teeth2", " (negate it to reverse the sense)")
        self.dist = as_expr(vals[4], f"{kind} dist")
        self.C = as_expr(vals[5], f"{kind} C")
        self._init_variable(spec)

    def geometry(self):
        return [self.a1, self.a2]

    def _guess_expr(self):
        g1, k1 = _plain_frame(self.a1)
        u2 = self.a2.direction()
        return -sp.atan2(k1.dot(u2), g1.dot(u2))

    def _build(self, space):
        d = self.a1.location() - self.a2.location()
        u1, u2 = self.a1.direction(), self.a2.direction()
        n = vector_norm(self.a1.dir) * vector_norm(self.a2.dir)
        a = self.alpha
        e2 = (self.C - self.teeth1 * a) / self.teeth2
        return [u1.dot(u2), -u1.dot(d), u2.dot(d), u1.cross(u2).dot(d) - self.dist * n,
                angle_equation(angle_frame(space, self.a1), u2, -a),
                angle_equation(angle_frame(space, self.a2), u1, -e2)]


@_signature("axis1", "axis2", "pitch", "C")
class LeadScrew5(_Gear):
    r"""Lead screw: ``axis1`` (the screw) colinear with ``axis2`` (the nut), the axial
    travel tied to the relative spin by the pitch. Removes 5 DOF (3D).

    ``LeadScrew5(axis1[, (alpha, guess)], axis2, pitch, C)``; ``alpha`` (the new variable) is
    the spin of ``axis1`` relative to ``axis2``: the angle about :math:`u_2` from :math:`g_2` to :math:`g_1`.
    ``C`` is the distance from the origin of ``axis2`` to that of ``axis1`` at zero relative
    spin; a positive ``pitch`` (travel per turn) is a right-hand thread. With :math:`h_1, f_1`
    normals of axis 1 and :math:`s = \hat{u}_1 \cdot (r_1 - r_2)` (Mech's order):

    .. math::

        h_1 \cdot (r_2 - r_1) &= 0 \\
        f_1 \cdot (r_2 - r_1) &= 0 \\
        h_1 \cdot u_2 &= 0 \\
        f_1 \cdot u_2 &= 0 \\
        s - C - \mathit{pitch}\, \alpha / (2\, \pi) &= 0 \\
        \cos(\alpha)\, (k_2 \cdot g_1) - \sin(\alpha)\, (g_2 \cdot g_1) &= 0
    """

    mech_name = "LeadScrew5"
    dof_removed = 5
    spaces = ("spatial",)

    def __init__(self, *args, variable=None):
        super().__init__()
        kind = "LeadScrew5"
        args, spec = _split_variable(args, kind, 1, variable)
        vals = _arity(args, kind, ["axis1", "axis2", "pitch", "C"])
        self.a1, self.a2 = _axes(kind, vals[0], vals[1])
        self.pitch = _nonzero(vals[2], f"{kind} pitch",
                              " (zero pitch is a Cylindrical4 plus a rotation lock)")
        self.C = as_expr(vals[3], f"{kind} C")
        self._init_variable(spec)

    def geometry(self):
        return [self.a1, self.a2]

    def _guess_expr(self):
        g2, k2 = _plain_frame(self.a2)
        g1 = self.a1.reference_vector().direction()
        return sp.atan2(k2.dot(g1), g2.dot(g1))

    def _build(self, space):
        a = self.alpha
        u1h = self.a1.direction() / vector_norm(self.a1.dir)
        s = u1h.dot(self.a1.location() - self.a2.location())
        g1 = angle_frame(space, self.a1)[0]
        return (P.point_on_line(space, self.a2.origin, self.a1)
                + P.parallel(space, self.a2.dir, self.a1.dir)
                + [s - self.C - self.pitch * a / (2 * sp.pi),
                   angle_equation(angle_frame(space, self.a2), g1, a)])


class _SpatialRack(_Gear):
    spaces = ("spatial",)
    _adjacent = True

    def __init__(self, *args, variable=None):
        super().__init__()
        kind = type(self).__name__
        args, spec = _split_variable(args, kind, 2, variable)
        vals = _arity(args, kind, ["axis1", "rad", "axis2", "C"])
        self.a1, self.a2 = _axes(kind, vals[0], vals[2])
        self.rad = _nonzero(vals[1], f"{kind} rad", " (the pinion's pitch radius)")
        self.C = as_expr(vals[3], f"{kind} C")
        self._init_variable(spec)

    def geometry(self):
        return [self.a1, self.a2]

    def pitch_circles(self):
        return [(self.a1, self.rad)]

    def _guess_expr(self):
        g2, k2 = _plain_frame(self.a2)
        g1 = self.a1.reference_vector().direction()
        return sp.atan2(k2.dot(g1), g2.dot(g1))

    def _build(self, space):
        a = self.alpha
        d = self.a1.location() - self.a2.location()
        g2, k2 = angle_frame(space, self.a2)
        u2h = self.a2.direction() / vector_norm(self.a2.dir)
        g1 = angle_frame(space, self.a1)[0]
        adj = [u2h.dot(d)] if self._adjacent else []
        return (P.parallel(space, self.a2.dir, self.a1.dir) + [k2.dot(d) - self.rad] + adj
                + [g2.dot(d) - self.C + self.rad * a, angle_equation((g2, k2), g1, a)])


@_signature("axis1", "rad", "axis2", "C")
class RackAndPinion5(_SpatialRack):
    r"""Rack and pinion in 3D. Removes 5 DOF.

    ``RackAndPinion5(axis1, rad[, (alpha, guess)], axis2, C)``: ``axis1`` the pinion's rotation
    axis, ``axis2`` the rack: its direction along the cut of the teeth (parallel to the pinion
    axis), its reference direction :math:`g_2` along the rack's travel, both in the rack's pitch
    plane. The pinion axis lies ``rad`` from that plane on the side of :math:`k_2 = \hat{u}_2
    \times g_2`. ``alpha`` (the new variable) is the pinion's rotation: the angle about
    :math:`u_2` from :math:`g_2` to :math:`g_1`; ``C`` the travel :math:`g_2 \cdot d` at
    :math:`\alpha = 0`. With :math:`d = r_1 - r_2`, :math:`h_1, f_1` normals of axis 1 (Mech's
    order):

    .. math::

        h_1 \cdot u_2 &= 0 \\
        f_1 \cdot u_2 &= 0 \\
        k_2 \cdot d - \mathit{rad} &= 0 \\
        \hat{u}_2 \cdot d &= 0 \\
        g_2 \cdot d - C + \mathit{rad}\, \alpha &= 0 \\
        \cos(\alpha)\, (k_2 \cdot g_1) - \sin(\alpha)\, (g_2 \cdot g_1) &= 0
    """

    mech_name = "RackAndPinion5"
    dof_removed = 5


@_signature("axis1", "rad", "axis2", "C")
class RackAndPinion4(_SpatialRack):
    r""":class:`RackAndPinion5` without the adjacency equation: the pinion may slide along its
    axis. Removes 4 DOF (3D).

    ``RackAndPinion4(axis1, rad[, (alpha, guess)], axis2, C)``:

    .. math::

        h_1 \cdot u_2 &= 0 \\
        f_1 \cdot u_2 &= 0 \\
        k_2 \cdot d - \mathit{rad} &= 0 \\
        g_2 \cdot d - C + \mathit{rad}\, \alpha &= 0 \\
        \cos(\alpha)\, (k_2 \cdot g_1) - \sin(\alpha)\, (g_2 \cdot g_1) &= 0
    """

    mech_name = "RackAndPinion4"
    dof_removed = 4
    _adjacent = False


GEAR_TYPES = (
    TwoGears1,
    TwoGears2,
    RackAndPinion1,
    RackAndPinion2,
    TwoPulleys1,
    TwoPulleys2,
    ParallelGears4,
    ParallelGears5,
    TwoPulleys4,
    TwoPulleys5,
    OrthogonalGears5,
    LeadScrew5,
    RackAndPinion4,
    RackAndPinion5,
)

__all__ = [t.__name__ for t in GEAR_TYPES] + ["GEAR_TYPES"]
