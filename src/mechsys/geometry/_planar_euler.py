r"""Planar bodies in Mech's degenerate Euler parameters (``SetSymbols[Method -> Euler]`` in
Modeler2D; manual 12.4.1): ``q_b = (x, y, ei, ej)`` with :math:`e_i = \cos \theta`, :math:`e_j = \sin \theta`.

The rotation matrix is *linear* in the coordinates, so no constraint contains a sine or a
cosine of a coordinate:

.. math::

    A(e) = \begin{bmatrix} e_i & -e_j \\ e_j & e_i \end{bmatrix}, \qquad
    e_i^2 + e_j^2 - 1 = 0 \quad \text{(one normalisation per body)}

Angular velocity and acceleration follow from the rates (exact on :math:`\lvert e \rvert = 1`):

.. math::

    \omega &= e_i e_j' - e_j e_i' \\
    \alpha &= e_i e_j'' - e_j e_i''

and the angle reported to the user is :math:`\theta = \operatorname{atan2}(e_j, e_i)` in
:math:`(-\pi, \pi]`. Select it
with ``Model2D(orientation="euler")``; decision 0015 records why it is an option and not
the default.

Example::

    m = Model2D(orientation="euler")
    crank = m.add_body("crank", guess=((0, 0), 0.3))   # an angle guess becomes (cos, sin)
    crank.q            # (x2, y2, ei2, ej2)
"""

from __future__ import annotations

import math

import sympy as sp

from .._errors import ModelError
from ._space import Planar


class PlanarEuler(Planar):
    """Planar bodies with coordinates ``x, y, ei, ej`` (see the module doc)."""

    ncoord = 4
    name = "planar"
    orientation = "euler"
    coordinate_names = ("x", "y", "ei", "ej")

    def rotation_matrix(self, rot) -> sp.Matrix:
        ei, ej = rot
        return sp.Matrix([[ei, -ej], [ej, ei]])

    def zero_rotation(self):
        return (1, 0)

    def rotation_guess(self, rot, who: str) -> tuple:
        r"""``(cos th, sin th)`` from an angle guess or from ``(ei, ej)`` (any positive
        scale; normalised here so the first Newton step starts on :math:`\lvert e \rvert = 1`)."""
        (th,) = super().rotation_guess(rot, who)
        return (math.cos(th), math.sin(th))

    def angle(self, rot):
        """``atan2(ej, ei)``: the principal angle (for outputs; constraints avoid it)."""
        ei, ej = rot
        return sp.atan2(ej, ei)

    def omega(self, rot, rot_d, local: bool = False):
        """``ei ej' - ej ei'`` (the same in global and local axes)."""
        ei, ej = rot
        ei_d, ej_d = rot_d
        return ei * ej_d - ej * ei_d

    def body_normalization(self, rot) -> list:
        ei, ej = rot
        return [ei**2 + ej**2 - 1]

    def wrench_from_generalized(self, G, rot):
        r"""Force (2,) at the body origin and moment from a body's generalized force
        ``(Q_x, Q_y, Q_ei, Q_ej)``: a virtual turn :math:`de = (-e_j, e_i)\, d\theta` does the work
        ``M dth``, so :math:`M = e_i Q_{e_j} - e_j Q_{e_i}` (the part along ``e``, the normalisation's
        reaction, does no work)."""
        ei, ej = rot
        return sp.Matrix(G[:2]), ei * G[3] - ej * G[2]

    def relative_rotation(self, rot1, rot2):
        """``(cos, sin)`` of ``th1 - th2`` as polynomials of the parameters (ground: ``None``)."""
        c1, s1 = rot1 if rot1 is not None else (1, 0)
        c2, s2 = rot2 if rot2 is not None else (1, 0)
        return c1 * c2 + s1 * s2, s1 * c2 - c1 * s2

    def rates_from_omega(self, rot, w: float) -> tuple[float, float]:
        """Rates :math:`(e_i', e_j') = w (-e_j, e_i)` of a body turning at ``w`` (initial conditions)."""
        ei, ej = (float(v) for v in rot)
        return (-ej * w, ei * w)

    def continuous_angle(self, what: str):
        """Raise: ``what`` needs the angle as a coordinate (several turns), which these
        coordinates do not carry."""
        raise ModelError(
            f"{what} needs a body's angle as a coordinate (it may pass several turns), but this "
            "model uses degenerate Euler parameters (orientation='euler'), which carry the angle "
            "only modulo 2 pi; build the model with Model2D(orientation='angle') (the default)")


PLANAR_EULER = PlanarEuler()

__all__ = ["PLANAR_EULER", "PlanarEuler"]
