r"""Coulomb friction and viscous damping in joints, driven by the joint reaction.

The laws are written, typeset, in :class:`JointFriction`'s docstring. The equations become
nonlinear in the multipliers: statics and inverse dynamics then iterate (Newton,
``lambda_guess``).
"""

from __future__ import annotations

import math
import numbers

import sympy as sp

from .._errors import ModelError, choice
from ._loads import BodyMoment, LoadBase, PointForce

_ROTATIONAL = {"Revolute2", "Spherical3", "Revolute5"}
_TRANSLATIONAL = {"Translate2", "Translate5", "Cylindrical4"}


class JointFriction(LoadBase):
    r"""Coulomb (``mu``, and ``radius`` for rotational joints) plus viscous (``viscous``)
    friction in a joint: the constraint object, or its name or Mech number (resolved when the
    load is added to the model). ``kind`` is ``"rotational"`` or ``"translational"``
    (default from the constraint type).

    The reaction force the joint applies to its first body is, from its multipliers
    :math:`\lambda_c`, :math:`R = -(\partial \Phi_c / \partial r_1)^T \lambda_c`, of magnitude
    :math:`\lvert R \rvert = \sqrt{R \cdot R + \epsilon_R^2}` (:math:`\epsilon_R` =
    ``eps_reaction``, 1e-30 units of force: it only keeps the Newton on the multipliers
    differentiable at zero load, and must stay far below any reaction of the model: at 1e-9
    it dominated the reactions of a part of a few picograms in SI units). The sign of the
    sliding or turning velocity is regularised, :math:`s(v) = v / \sqrt{v \cdot v +
    v_\epsilon^2}` (:math:`v_\epsilon` = ``v_eps``, in the units of that rate: rad per unit
    time for rotational joints, whatever the unit of length; length per unit time for
    translational ones). The load on body 1 (the opposite on body 2) is:

    .. math::

        M_1 &= -\mu\, r \lvert R \rvert\, s(\omega_1 - \omega_2) - c\, (\omega_1 - \omega_2)
        \qquad \text{(rotational: Revolute2, Spherical3, Revolute5)} \\
        F_1 &= -\mu \lvert R \rvert\, s(v_\text{rel} \cdot u)\, u - c\, v_\text{rel}
        \qquad \text{(translational: Translate2, Translate5, ...)}

    with :math:`r` the pin ``radius``, :math:`c` the ``viscous`` coefficient, :math:`u` the
    unit slide direction and :math:`v_\text{rel}` the velocity of the axis origin relative
    to body 2; the force acts at that origin (on body 2: a force at its origin plus the
    transfer moment). The equations become nonlinear in the multipliers: statics and
    inverse dynamics then iterate (Newton, ``lambda_guess``).
    """

    def __init__(self, constraint, mu=0.0, radius=0.0, viscous=0.0, kind=None,
                 v_eps=1e-3, eps_reaction=1e-30):
        super().__init__()
        self.constraint = constraint
        self.mu = self._nonnegative(mu, "JointFriction mu",
                                    "a friction coefficient is never negative")
        self.radius = self._nonnegative(radius, "JointFriction radius")
        self.viscous = self._nonnegative(viscous, "JointFriction viscous",
                                         "a negative viscous coefficient feeds energy in")
        if kind is not None:
            choice(kind, ("rotational", "translational"), "JointFriction: kind")
        # a name or number is resolved by check(), when the load is added to a model
        self.kind = kind if kind is not None or _addressed(constraint) else _kind_of(constraint)
        # the regularisations must be positive: at 0 the sign function is 0/0 at rest
        self.v_eps, self.eps_reaction = (
            _positive_number(v_eps, "JointFriction v_eps"),
            _positive_number(eps_reaction, "JointFriction eps_reaction"))

    def bodies(self):
        # (addressed by name or number: the model resolves the constraint in check())
        return [] if _addressed(self.constraint) else self.constraint.bodies()

    def check(self, model) -> None:
        c = model.constraint(self.constraint)     # an unknown name or number raises here
        if self.kind is None:
            self.kind = _kind_of(c)
        super().check(model)

    def _pair(self, model):
        c = model.constraint(self.constraint)
        bs = c.bodies()
        if not bs:
            raise ModelError(f"JointFriction on {c.label()}: it joins no bodies")
        b1 = bs[0]
        b2 = bs[1] if len(bs) > 1 else model.ground
        return c, b1, b2

    def reaction_force(self, model, c, b1, b2):
        """Reaction force on the joint's first moving body (global), in multipliers."""
        body = b1 if not b1.is_ground else b2
        sign = 1 if body is b1 else -1
        dim = model.space.dim
        lam = sp.Matrix(model.multipliers(c))
        eqs = sp.Matrix(c.equations(model.space))
        R = -(eqs.jacobian(list(body.q[:dim])).T * lam)
        return sign * R

    def contributions(self, model):
        c, b1, b2 = self._pair(model)
        sp_ = model.space
        R = self.reaction_force(model, c, b1, b2)
        Rmag = sp.sqrt((R.T * R)[0, 0] + sp.sympify(self.eps_reaction) ** 2)
        if self.kind == "rotational":
            w = sp_.as_rotation_vector(model._omega(b1, False)) - sp_.as_rotation_vector(
                model._omega(b2, False))
            s = w / sp.sqrt((w.T * w)[0, 0] + self.v_eps**2)
            M = -self.mu * self.radius * Rmag * s - self.viscous * w
            Mv = M[0] if sp_.dim == 2 else M
            return [BodyMoment(b1, Mv), BodyMoment(b2, -Mv)]
        # translational: slide axis of the joint's first axis
        ax = getattr(c, "a1", None)
        if ax is None:
            raise ModelError(f"JointFriction: {c.label()} has no slide axis")
        u = ax.direction()
        u = u / sp.sqrt((u.T * u)[0, 0])
        P = ax.origin.location()
        v1 = model.time_derivative(P)
        # velocity of the material point of body 2 at P: r2' + A2' A2^T (P - r2)
        A2d = model.time_derivative(b2.A)
        v2 = model.time_derivative(b2.r) + A2d * b2.A.T * (P - b2.r)
        vrel = ((v1 - v2).T * u)[0, 0]
        f = -self.mu * Rmag * vrel / sp.sqrt(vrel**2 + self.v_eps**2) - self.viscous * vrel
        F = f * u
        out = [PointForce(ax.origin, F)]
        if not b2.is_ground:
            out.append(PointForce(b2.point(0), -F))
            out.append(BodyMoment(b2, sp_.moment_about(P - b2.r, -F)))
        return out


def _positive_number(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not (
            math.isfinite(value) and value > 0):
        raise ModelError(f"{what} must be a positive finite number, got {value!r}")
    return float(value)


def _addressed(constraint) -> bool:
    """A constraint given by name or Mech number rather than as the object."""
    return isinstance(constraint, str) or (isinstance(constraint, numbers.Integral)
                                           and not isinstance(constraint, bool))


def _kind_of(constraint) -> str:
    name = type(constraint).__name__
    kind = "rotational" if name in _ROTATIONAL else (
        "translational" if name in _TRANSLATIONAL else None)
    if kind is None:
        raise ModelError(f"JointFriction: cannot tell whether {name} is a rotational or "
                         "translational joint; pass kind='rotational' or 'translational'")
    return kind
