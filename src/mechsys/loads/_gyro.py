r"""Gyroscopic moments of an axially symmetric rotor without a spinning body (Mech's
``GyroMoment`` and ``GyroFilter``, manual 10.3.5 and 10.4.6).

A rotor of spin inertia :math:`I_s` spinning at :math:`\omega_s` about the body-fixed unit
axis :math:`a` of a carrier body (angular velocity :math:`\omega`) adds the angular momentum
:math:`h = I_s \omega_s a`. Its rate of change, applied to the carrier as a moment, is:

.. math::

    M = -I_s \omega_s\, (\omega \times a) - I_s \frac{d\omega_s}{dt}\, a

so the carrier can hold the rotor's transverse inertia while the fast spin never has to be
integrated. Valid only for a body rotating about a principal axis with equal transverse
moments (an axially symmetric rotor spinning about its axis).

``GyroFilter(inertia, axis)`` removes the spin-axis moment from an inertia tensor,
:math:`J - (a^T J a)\, a a^T`, so that a rotor's inertia can be lumped into its carrier (the
free spin carries no axial torque); pair it with a ``GyroMoment`` whose ``omega`` is the
rotor's absolute axial spin.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._errors import ModelError
from ..geometry._points import Vector, as_vector
from ._loads import BodyMoment, LoadBase, _magnitude


class GyroMoment(LoadBase):
    r"""``GyroMoment(body, axis, omega, inertia=None)``: the gyroscopic moment of a rotor
    spinning at ``omega`` (:math:`\omega_s`, an expression; may depend on ``T``) about ``axis``
    (:math:`a`, a vector fixed in ``body``, or local components) with spin inertia
    ``inertia`` (:math:`I_s`), applied to ``body`` (angular velocity :math:`\omega`):

    .. math::

        M = -I_s \omega_s\, (\omega \times a) - I_s \frac{d\omega_s}{dt}\, a

    Without ``inertia`` the spin inertia is taken from the body, as Mech does when its
    ``Inertia`` option is not given: the moment of the body's centroidal inertia tensor
    :math:`J` (body axes) about the unit spin axis :math:`a`, :math:`I_s = a^T J a` (:math:`a`
    in body axes; for an axis not fixed in the body, :math:`a^T A J A^T a` with global
    :math:`a`)."""

    def __init__(self, body, axis, omega, inertia=None):
        super().__init__()
        self.body = body
        self.axis = axis if isinstance(axis, Vector) else None
        self._axis_local = None if self.axis is not None else axis
        self.omega = _magnitude(omega, "GyroMoment omega")
        self.inertia = None if inertia is None else self._nonnegative(
            inertia, "GyroMoment inertia", "a spin inertia is never negative")

    def bodies(self):
        return [self.body]

    def contributions(self, model):
        if model.space.dim != 3:
            raise ModelError("GyroMoment is a spatial load (Model3D)")
        b = model.body(self.body)
        v = self.axis if self.axis is not None else b.vector(tuple(self._axis_local))
        d = as_vector(v).direction()
        a = d / sp.sqrt((d.T * d)[0, 0])
        Is = self.inertia if self.inertia is not None else self.spin_inertia(model)
        w = model._omega(b, False)
        M = -Is * self.omega * w.cross(a)
        wd = model.time_derivative(self.omega)
        if wd != 0:
            M = M - Is * wd * a
        return [BodyMoment(b, M)]

    def spin_inertia(self, model):
        r"""The spin inertia used: ``inertia`` when given, else :math:`a^T J a` from the body."""
        if self.inertia is not None:
            return self.inertia
        b = model.body(self.body)
        J = model.space.inertia_matrix(b.inertia)
        v = self.axis
        if v is None or (v.points is None and v.body is not None and model.body(v.body) is b):
            # a body-fixed axis: its local components give a constant spin inertia
            loc = sp.Matrix(list(self._axis_local if v is None else v.local))
            a = loc / sp.sqrt((loc.T * loc)[0, 0])
            return (a.T * J * a)[0, 0]
        d = as_vector(v).direction()
        a = d / sp.sqrt((d.T * d)[0, 0])
        return (a.T * b.A * J * b.A.T * a)[0, 0]


def gyro_filter(inertia, axis):
    r"""Inertia ``(Ixx, Iyy, Izz, Ixy, Iyz, Izx)`` with the moment about ``axis`` removed:
    :math:`J - (a^T J a)\, a a^T` with :math:`a` the unit axis."""
    from ..geometry._inertia import _as_list6, _as_matrix3

    J = _as_matrix3(inertia)
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    return _as_list6(J - float(a @ J @ a) * np.outer(a, a))


GyroFilter = gyro_filter
