r"""Cam constraints (Mech manual 6.1): a profile in tangent contact with a point, circle,
line, plane, sphere or another profile, written once for 2D and 3D.

A *profile* is a body point whose local coordinates ``s'(a)`` are expressions of one cam
parameter (a 2D curve or a 3D space curve) or two (a 3D surface): ``cam.point((r(a) cos a,
r(a) sin a))``. Each parameter is given as Mech's ``{sym, guess}`` pair, here a ``(sym,
guess)`` tuple, and becomes a model variable, so a cam constraint writes more equations
than the degrees of freedom it removes (``len(equations) - len(parameters)``).

Notation in the docstrings: :math:`r_c = r + A\, s^{\prime}(a)` the global contact point of a
profile, :math:`t_k = A\, \partial s'/\partial a_k` its tangents, ``n`` its normal: in 2D ``t``
turned by +90 degrees (the left of the profile travelled with increasing ``a``), in 3D
:math:`t_1 \times t_2` (the side from which :math:`a_1` turns to :math:`a_2` counterclockwise).
Normals are built in local coordinates and turned by ``A`` (rotations keep lengths and cross
products), so :math:`\lvert n \rvert` depends on the parameters only. :math:`r_p` a global
point, ``u`` the direction of a line or the normal of a plane, :math:`r_o` its origin.

Outputs: the follower's lift, velocity and acceleration are those of its points; the
contact point is ``solution.location(locuspoint)`` (at the solved parameter, which is
``solution.coordinate(sym)``); :func:`pressure_angle` and :func:`profile_radius` give the
pressure angle and the profile's radius of curvature at the contact. Guide: docs/cams.md.
"""

from __future__ import annotations

import sympy as sp

from .._errors import GeometryError, MechError, ModelError
from ..geometry._points import Point, as_axis, as_point, as_vector
from . import _primitives as P
from ._angles import vector_norm
from ._base import ConstraintBase, Variable, as_expr


def _d(e, sym):
    """``de/dsym``, with the derivatives of step functions set to zero: a periodic spline
    profile reduces its parameter by ``floor``, which SymPy would leave as an uncompilable
    ``Subs(Derivative(floor(x), x), ...)``."""
    from ..compile._derive import _drop_step_derivatives

    return e.applyfunc(lambda c: _drop_step_derivatives(sp.diff(c, sym)))


class Profile:
    """A profile: a locus point and its parameters (one for a curve, two for a surface)."""

    def __init__(self, locus, params: list[Variable], who: str, what: str = "profile"):
        self.point: Point = as_point(locus)
        self.params = params
        self.what = what
        for v in params:
            if not any(c.diff(v.symbol) != 0 for c in self.point.local):
                raise GeometryError(
                    f"{who}: the {what} {_describe(self.point)} does not depend on its parameter "
                    f"{v.symbol.name!r}; give the locus point local coordinates that are "
                    f"expressions of {v.symbol.name} (e.g. cam.point((r({v.symbol.name})*cos"
                    f"({v.symbol.name}), r({v.symbol.name})*sin({v.symbol.name}))))")

    def _rotate(self, v: sp.Matrix) -> sp.Matrix:
        body = self.point.body
        return v if body is None else body.A * v

    def location(self) -> sp.Matrix:
        return self.point.location()

    def local_tangents(self) -> list[sp.Matrix]:
        return [_d(self.point.local, v.symbol) for v in self.params]

    def tangents(self) -> list[sp.Matrix]:
        r"""Global tangents :math:`t_k = A\, \partial s' / \partial a_k`."""
        return [self._rotate(t) for t in self.local_tangents()]

    def local_normal(self, space) -> sp.Matrix:
        """``n'``: ``t'`` turned by +90 deg in 2D, ``t'_1 x t'_2`` in 3D (not unit)."""
        t = self.local_tangents()
        if space.dim == 2:
            return space.perpendiculars(t[0])[0]
        return t[0].cross(t[1])

    def normal(self, space) -> sp.Matrix:
        return self._rotate(self.local_normal(space))

    def unit_normal(self, space) -> sp.Matrix:
        n = self.local_normal(space)
        return self._rotate(n / sp.sqrt(n.dot(n)))


def _describe(p: Point) -> str:
    owner = f"body {p.body.name!r}" if p.body is not None else "ground"
    name = f"{p.label!r} " if p.label else ""
    return f"point {name}{tuple(p.local)} on {owner}"


def _variable(pair, who: str) -> Variable:
    if isinstance(pair, Variable):
        return pair
    if isinstance(pair, sp.Symbol):
        return Variable(pair, 0.0)
    if isinstance(pair, (tuple, list)) and len(pair) == 2:
        sym, guess = pair
        if isinstance(sym, str):
            sym = sp.Symbol(sym)
        if not isinstance(sym, sp.Symbol):
            raise ModelError(f"{who}: a cam parameter is a (symbol, guess) pair; {sym!r} is not a symbol")
        return Variable(sym, guess)
    raise ModelError(f"{who}: expected a cam parameter as a (symbol, guess) pair, got {pair!r}")


def _radius(value, who: str, signed: bool = True) -> sp.Expr:
    """A follower's radius: nonzero, its sign picking the side (``signed``), or positive."""
    r = as_expr(value, f"{who} radius")
    if not isinstance(r, sp.Expr):
        raise GeometryError(f"{who}: radius must be a number or expression, got {value!r}")
    if not r.is_number:
        return r
    if signed and (not r.is_real or r == 0):
        raise GeometryError(f"{who}: radius must be a nonzero real number (its sign picks the side "
                            f"of the profile), got {value!r}; for a point follower use CamToPoint1")
    if not signed and not (r.is_real and r > 0):
        raise GeometryError(f"{who}: the cylinder's radius must be positive, got {value!r}")
    return r


class _Cam(ConstraintBase):
    """Base: ``profiles`` and the follower geometry; the parameters are the new variables."""

    #: parameters of each profile argument: None = one per dimension below the model's
    #: (a curve in 2D, a surface in 3D), 1 = a curve.
    _shape: tuple = (None,)

    def __init__(self, *args):
        super().__init__()
        self.profiles: list[Profile] = []
        rest = list(args)
        who = self.mech_name
        for k, shape in enumerate(self._shape):
            if not rest:
                raise ModelError(f"{who}: missing the locus point of profile {k + 1}")
            locus = rest.pop(0)
            pairs = []
            # a surface takes two (sym, guess) pairs in 3D; a plain tuple of two symbols-or-
            # numbers after them is the follower, so count what the signature leaves over
            want = shape if shape is not None else self._count_pairs(rest, k)
            if want < 1:
                raise ModelError(f"{who}: expected {who}{self._call}, got {len(args)} argument(s)")
            for _ in range(want):
                if not rest:
                    raise ModelError(f"{who}: missing a (symbol, guess) pair for profile {k + 1}")
                pairs.append(_variable(rest.pop(0), who))
            what = "profile" if len(self._shape) == 1 else f"profile {k + 1}"
            self.profiles.append(Profile(locus, pairs, who, what))
        self._follower(rest)
        syms = [v.symbol for p in self.profiles for v in p.params]
        if len(set(syms)) != len(syms):
            raise ModelError(f"{who}: each profile parameter needs its own symbol, got {syms}")

    def _count_pairs(self, rest: list, k: int) -> int:
        """Pairs of profile ``k`` when it has one per dimension, from what the call leaves:
        ``n (1 + later such profiles) + later loci + later fixed pairs + follower args``."""
        later = self._shape[k + 1:]
        fixed = len(later) + sum(s for s in later if s is not None) + self._n_follower_args
        return max(len(rest) - fixed, 0) // (1 + sum(1 for s in later if s is None))

    _n_follower_args = 0
    #: the call, for messages
    _call = "(locuspoint1, (sym, guess)..., locuspoint2, (sym, guess)...)"

    def _follower(self, rest: list) -> None:
        if rest:
            raise ModelError(f"{self.mech_name}: expected {self.mech_name}{self._call}; "
                             f"unexpected arguments {rest!r}")

    def _follower_count(self, rest: list) -> None:
        if len(rest) != self._n_follower_args:
            raise ModelError(f"{self.mech_name}: expected {self.mech_name}{self._call}, got "
                             f"{len(rest)} argument(s) after the parameters")

    def new_variables(self):
        return [v for p in self.profiles for v in p.params]

    def contact_normal(self, space) -> sp.Matrix:
        """The common normal at the contact (global, not unit): the first profile's normal
        by default."""
        prof = self.profiles[0]
        if len(prof.params) != space.dim - 1:
            raise MechError(f"{self.label()}: the contact normal of a space curve is not unique "
                            "(any direction in its normal plane)")
        return prof.normal(space)

    def geometry(self):
        return [p.point for p in self.profiles]

    def _check_shape(self, space) -> None:
        for prof, shape in zip(self.profiles, self._shape, strict=True):
            want = shape if shape is not None else space.dim - 1
            if len(prof.params) != want:
                kind = "curve" if want == 1 else "surface"
                raise ModelError(
                    f"{self.label()}: in a {space.dim}D model the {prof.what} is a {kind} of "
                    f"{want} parameter(s), given {len(prof.params)} (symbol, guess) pair(s)")


def contact(space, first: Profile, second: Profile, normal_of: Profile) -> list[sp.Expr]:
    """Two profiles touch: :math:`r_{c1} - r_{c2} = 0`, then the normal of ``normal_of`` is
    orthogonal to each tangent of the other one (``n . t_k = 0``)."""
    other = second if normal_of is first else first
    n = normal_of.normal(space)
    return list(first.location() - second.location()) + [n.dot(t) for t in other.tangents()]


class CamToPoint1(_Cam):
    r"""A point follower on a cam profile. Removes 1 DOF (2D/3D).

    ``CamToPoint1(locuspoint, (a, guess), point)`` in 2D; in 3D the profile is a surface,
    ``CamToPoint1(locuspoint, (a, guess), (b, guess), point)``. New variables: the
    parameters. Equations (2D: two, 3D: three):

    .. math::

        r_c(a) - r_p = 0
    """

    mech_name = "CamToPoint1"
    dof_removed = 1
    _n_follower_args = 1

    _call = "(locuspoint, (sym, guess)..., point)"

    def _follower(self, rest):
        self._follower_count(rest)
        self.p = as_point(rest[0])

    def geometry(self):
        return super().geometry() + [self.p]

    def _build(self, space):
        self._check_shape(space)
        return P.coincident(self.profiles[0].point, self.p)


class CurveToPoint2(CamToPoint1):
    r"""A point follower on a space curve (a point in a slot). Removes 2 DOF (3D).

    ``CurveToPoint2(locuspoint, (a, guess), point)``; new variable ``a``:

    .. math::

        r_c(a) - r_p = 0 \qquad \text{(three equations)}
    """

    mech_name = "CurveToPoint2"
    dof_removed = 2
    spaces = ("spatial",)
    _shape = (1,)


class CamToCircle1(_Cam):
    r"""A roller (circular) follower of radius ``radius`` centred at ``point`` on a cam
    profile. Removes 1 DOF (2D).

    ``CamToCircle1(locuspoint, (a, guess), point, radius)``; the roller lies on the left of
    the profile travelled with increasing ``a`` when ``radius > 0``, on the right when
    ``radius < 0``. With ``n`` the profile's left normal:

    .. math::

        r_c + \mathit{radius}\, n/\lvert n \rvert - r_p = 0 \qquad \text{(two equations)}
    """

    mech_name = "CamToCircle1"
    dof_removed = 1
    spaces = ("planar",)
    _n_follower_args = 2

    _call = "(locuspoint, (sym, guess)..., point, radius)"

    def _follower(self, rest):
        self._follower_count(rest)
        self.p = as_point(rest[0])
        self.radius = _radius(rest[1], self.mech_name)

    def geometry(self):
        return super().geometry() + [self.p]

    def _build(self, space):
        self._check_shape(space)
        prof = self.profiles[0]
        return list(prof.location() + self.radius * prof.unit_normal(space) - self.p.location())


class CamToSphere1(CamToCircle1):
    r"""A spherical follower of radius ``radius`` centred at ``point`` on a cam surface.
    Removes 1 DOF (3D).

    ``CamToSphere1(locuspoint, (a, guess), (b, guess), point, radius)``; the sphere lies on
    the side of :math:`n = t_a \times t_b` when ``radius > 0``:

    .. math::

        r_c + \mathit{radius}\, n/\lvert n \rvert - r_p = 0 \qquad \text{(three equations)}
    """

    mech_name = "CamToSphere1"
    spaces = ("spatial",)


class _CamToFlat(_Cam):
    """A profile tangent to a line (2D) or plane (3D) with normal ``m``:
    ``m . (r_c - r_o) = 0`` and ``m . t_k = 0``."""

    _n_follower_args = 1

    _call = "(locuspoint, (sym, guess)..., line or plane)"

    def _follower(self, rest):
        self._follower_count(rest)
        self.axis = as_axis(rest[0])

    def geometry(self):
        return super().geometry() + [self.axis]

    def contact_normal(self, space):
        if space.dim == 2:  # the line's normal, fixed in its body
            return P.normals(space, self.axis.dir)[0]
        return self.axis.direction()  # the plane's normal is the axis direction

    def _build(self, space):
        self._check_shape(space)
        prof = self.profiles[0]
        m = self.contact_normal(space)
        d = prof.location() - self.axis.location()
        return [m.dot(d)] + [m.dot(t) for t in prof.tangents()]


class CamToLine1(_CamToFlat):
    r"""A flat-faced follower: a cam profile tangent to a line. Removes 1 DOF (2D).

    ``CamToLine1(locuspoint, (a, guess), line)``; ``line`` an axis or line with origin
    :math:`r_o` and direction ``u``:

    .. math::

        u \times (r_c - r_o) &= 0 \qquad \text{(contact point on the line)} \\
        u \times t &= 0 \qquad \text{(profile tangent to the line)}
    """

    mech_name = "CamToLine1"
    dof_removed = 1
    spaces = ("planar",)


class CamToPlane1(_CamToFlat):
    r"""A cam surface tangent to a plane (a flat-faced follower in 3D). Removes 1 DOF (3D).

    ``CamToPlane1(locuspoint, (a, guess), (b, guess), plane)``; ``plane`` an axis or plane
    with origin :math:`r_o` and normal ``u``:

    .. math::

        u \cdot (r_c - r_o) &= 0 \qquad \text{(contact point in the plane)} \\
        u \cdot t_a &= 0 \qquad \text{(surface tangent to the plane)} \\
        u \cdot t_b &= 0
    """

    mech_name = "CamToPlane1"
    dof_removed = 1
    spaces = ("spatial",)


class CurveToPlane1(_CamToFlat):
    r"""A space curve tangent to a plane. Removes 1 DOF (3D).

    ``CurveToPlane1(locuspoint, (a, guess), axis)``; the plane is normal to ``axis`` (origin
    :math:`r_o`, direction ``u``) through its origin:

    .. math::

        u \cdot (r_c - r_o) &= 0 \qquad \text{(contact point in the plane)} \\
        u \cdot t &= 0 \qquad \text{(curve tangent to the plane)}
    """

    mech_name = "CurveToPlane1"
    dof_removed = 1
    spaces = ("spatial",)
    _shape = (1,)


class CurveToCylinder1(_Cam):
    r"""A space curve tangent to a cylinder of radius ``radius`` about ``axis``. Removes 1
    DOF (3D).

    ``CurveToCylinder1(locuspoint, (a, guess), axis, radius)``; with :math:`d = r_c - r_o` and
    :math:`w = d - (d \cdot u)\, u / (u \cdot u)` its part normal to the axis (the cylinder's normal at
    the contact):

    .. math::

        w \cdot w - \mathit{radius}^2 &= 0 \qquad \text{(contact point on the cylinder)} \\
        w \cdot t &= 0 \qquad \text{(curve tangent to it)}
    """

    mech_name = "CurveToCylinder1"
    dof_removed = 1
    spaces = ("spatial",)
    _shape = (1,)
    _n_follower_args = 2

    _call = "(locuspoint, (sym, guess), axis, radius)"

    def _follower(self, rest):
        self._follower_count(rest)
        self.axis = as_axis(rest[0])
        self.radius = _radius(rest[1], self.mech_name, signed=False)

    def geometry(self):
        return super().geometry() + [self.axis]

    def contact_normal(self, space):
        r"""``w``: the part of :math:`r_c - r_o` normal to the cylinder's axis."""
        u = self.axis.direction()
        d = self.profiles[0].location() - self.axis.location()
        return d - u * (u.dot(d) / vector_norm(self.axis.dir) ** 2)

    def _build(self, space):
        self._check_shape(space)
        w = self.contact_normal(space)
        (t,) = self.profiles[0].tangents()
        return [w.dot(w) - self.radius**2, w.dot(t)]


class CamToCam1(_Cam):
    r"""Two cam profiles work against each other (tangent contact). Removes 1 DOF (2D/3D).

    ``CamToCam1(locuspoint1, (a, guess), locuspoint2, (b, guess))`` in 2D; in 3D both are
    surfaces: ``CamToCam1(locuspoint1, (a1, g), (a2, g), locuspoint2, (b1, g), (b2, g))``.
    New variables: the four (3D) or two (2D) parameters. With :math:`n_1` the first profile's
    normal and :math:`t_{2,k}` the second's tangents:

    .. math::

        r_{c1} - r_{c2} &= 0 \qquad \text{(two or three equations: the contact points coincide)} \\
        n_1 \cdot t_{2,k} &= 0 \qquad \text{(2D: } t_1 \times t_2 = 0 \text{; 3D: two}
        \ \text{equations, normals parallel)}
    """

    mech_name = "CamToCam1"
    dof_removed = 1
    _shape = (None, None)

    def _build(self, space):
        self._check_shape(space)
        return contact(space, *self.profiles, normal_of=self.profiles[0])


class CurveToCam1(_Cam):
    r"""A space curve tangent to a cam surface. Removes 1 DOF (3D).

    ``CurveToCam1(locuspoint1, (a, guess), locuspoint2, (g, guess), (d, guess))``: the curve
    :math:`r_1(a)` touches the surface :math:`r_2(g, d)`. New variables ``a, g, d``; with
    :math:`n_2 = t_g \times t_d` and :math:`t_1` the curve's tangent:

    .. math::

        r_{c1} - r_{c2} &= 0 \qquad \text{(three equations)} \\
        n_2 \cdot t_1 &= 0
    """

    mech_name = "CurveToCam1"
    dof_removed = 1
    spaces = ("spatial",)
    _shape = (1, 2)
    _call = "(locuspoint1, (sym, guess), locuspoint2, (sym, guess), (sym, guess))"

    def contact_normal(self, space):
        return self.profiles[1].normal(space)  # the surface's

    def _build(self, space):
        self._check_shape(space)
        return contact(space, *self.profiles, normal_of=self.profiles[1])


# -- outputs a cam designer reads ---------------------------------------------------------------


def _cam_of(result, constraint) -> _Cam:
    model = result._model()
    c = model.constraint(constraint)
    if not isinstance(c, _Cam):
        raise MechError(f"{c.label()} is not a cam constraint")
    return c


def pressure_angle(result, constraint, direction=None):
    r"""Pressure angle at the contact of a cam constraint: the angle between the common
    normal :math:`n` (the direction of the contact force without friction) and the direction
    :math:`v` in which the follower moves:

    .. math::

        \phi = \operatorname{atan2}(\lvert n \times v \rvert, \lvert n \cdot v \rvert)
        \in [0, \pi/2]

    ``result`` is a :class:`~mechsys.Solution` (an array over its times) or the model (a
    SymPy expression in its coordinates, velocities and the cam parameters).
    ``constraint``: a cam constraint (handle, name or number).
    ``direction``: the follower's direction of motion as a vector (a tuple is global, a
    body vector turns with its body), e.g. the slide of a translating follower; by default
    the velocity of the follower's point (the roller's or ball's centre), which needs a
    solution with velocities and is undefined (``nan``) where that point is at rest. The
    common normal is the profile's normal (``CamToPoint1``, ``CamToCircle1``,
    ``CamToSphere1``, the first profile of ``CamToCam1``, the surface of ``CurveToCam1``),
    the line's or plane's normal (``CamToLine1``, ``CamToPlane1``, ``CurveToPlane1``) or the
    cylinder's (``CurveToCylinder1``); ``CurveToPoint2`` has none.
    """
    c = _cam_of(result, constraint)
    model = result._model()
    space = model.space
    n = c.contact_normal(space)
    if direction is not None:
        v = as_vector(direction)
        v.check_dim(space.dim)
        v = v.direction()
    elif hasattr(c, "p"):
        v = model.time_derivative(c.p.location())
    else:
        raise MechError(f"{c.label()}: give the follower's direction of motion (direction=...); "
                        "this constraint has no follower point whose velocity would give it")
    cross = space.cross(n, v)
    sin = sp.sqrt(cross.dot(cross)) if isinstance(cross, sp.MatrixBase) else sp.Abs(cross)
    return result._finish(sp.atan2(sin, sp.Abs(n.dot(v))))


def profile_radius(result, constraint, profile: int = 1):
    r"""Radius of curvature of a cam profile at the contact (a 2D profile or a 3D space
    curve; ``profile`` 1 or 2 picks the profile of ``CamToCam1``/``CurveToCam1``). With
    :math:`s'(a)` the profile's local coordinates (rotation keeps curvature) and subscripts
    derivatives in :math:`a`:

    .. math::

        \rho &= \frac{\lvert s'_a \rvert^3}{s'_a \times s'_{aa}} \qquad \text{(2D, signed)} \\
        \rho &= \frac{\lvert s'_a \rvert^3}{\lvert s'_a \times s'_{aa} \rvert}
        \qquad \text{(3D: a space curve)}

    In 2D :math:`\rho > 0` where the profile turns left (its centre of curvature on the
    left, the side of a positive ``CamToCircle1`` radius).

    Infinite where the profile is straight. A surface has two principal curvatures, not one
    radius: a :class:`~mechsys.MechError`. Returns what ``result`` gives (see
    :func:`pressure_angle`).
    """
    c = _cam_of(result, constraint)
    if profile not in range(1, len(c.profiles) + 1):
        raise MechError(f"{c.label()} has {len(c.profiles)} profile(s); profile={profile!r}")
    prof = c.profiles[profile - 1]
    if len(prof.params) != 1:
        raise MechError(f"{c.label()}: profile {profile} is a surface, which has two principal "
                        "radii of curvature, not one")
    sym = prof.params[0].symbol
    t = _d(prof.point.local, sym)
    tt = _d(t, sym)
    speed3 = sp.sqrt(t.dot(t)) ** 3
    if len(t) == 2:
        return result._finish(speed3 / (t[0] * tt[1] - t[1] * tt[0]))
    k = t.cross(tt)
    return result._finish(speed3 / sp.sqrt(k.dot(k)))


CAM_TYPES = (CamToPoint1, CamToCircle1, CamToLine1, CamToCam1, CamToSphere1, CamToPlane1,
             CurveToPoint2, CurveToPlane1, CurveToCylinder1, CurveToCam1)

__all__ = [c.__name__ for c in CAM_TYPES] + ["CAM_TYPES", "Profile", "contact", "pressure_angle",
                                             "profile_radius"]
