r"""Dimension strategy objects: the only place that knows whether a model is planar or spatial.

A body's pose is a position ``r`` and a rotation matrix ``A``; a global point is
``r + A s'`` in both dimensions, so constraints written with :class:`Space` helpers are
written once.

Planar body coordinates :math:`q_b = (x, y, \theta)`:

.. math::

    A(\theta) = \begin{bmatrix} \cos\theta & -\sin\theta \\ \sin\theta & \cos\theta \end{bmatrix}

Spatial body coordinates ``q_b = (x, y, z, e0, e1, e2, e3)`` with Euler parameters
:math:`e_0 = \cos(\phi/2)`, :math:`(e_1, e_2, e_3) = \sin(\phi/2) u` and the normalisation constraint
:math:`e_0^2 + e_1^2 + e_2^2 + e_3^2 - 1 = 0`:

.. math::

    A(e) = (2 e_0^2 - 1)\, I + 2\, (e e^T + e_0 \tilde e)
"""

from __future__ import annotations

import math

import sympy as sp

from .._errors import GeometryError, MechError, ModelError
from ._points import _matrix
from ._rotations import euler_parameters, matrix_elements


class Space:
    """Common interface of :class:`Planar` and :class:`Spatial`."""

    dim: int
    ncoord: int
    name: str
    coordinate_names: tuple[str, ...]

    def rotation_matrix(self, rot) -> sp.Matrix:  # pragma: no cover - interface
        raise NotImplementedError

    def cross(self, a: sp.Matrix, b: sp.Matrix):  # pragma: no cover - interface
        raise NotImplementedError

    def split(self, q: list) -> tuple[sp.Matrix, list]:
        """Split body coordinates into position and rotation coordinates."""
        return _matrix(self.dim, 1, list(q[: self.dim])), list(q[self.dim :])

    def body_normalization(self, rot) -> list:
        """Extra equations a body's own coordinates must satisfy (none in 2D)."""
        return []


class Planar(Space):
    """Planar (2D) bodies: ``x, y, theta``."""

    dim = 2
    ncoord = 3
    name = "planar"
    coordinate_names = ("x", "y", "th")

    def rotation_matrix(self, rot) -> sp.Matrix:
        (th,) = rot
        # of a coordinate symbol SymPy's evaluation finds nothing to simplify but costs ~1 ms
        # a function (a third of a large planar chain's build): built unevaluated, the same
        # expressions
        plain = isinstance(th, sp.Symbol)
        c, s = sp.cos(th, evaluate=not plain), sp.sin(th, evaluate=not plain)
        return _matrix(2, 2, [c, -s, s, c])

    def cross(self, a, b):
        """Scalar cross product ``a_x b_y - a_y b_x`` (the z component)."""
        return a[0] * b[1] - a[1] * b[0]

    def perpendiculars(self, u):
        """Vectors spanning the complement of ``u`` (one in 2D): ``u`` turned by +90 deg."""
        return [sp.Matrix([-u[1], u[0]])]

    def zero_rotation(self):
        return (0,)

    def rotation_guess(self, rot, who: str) -> tuple:
        r"""A planar rotation guess is the angle (radians), or Mech's degenerate Euler
        parameters :math:`(e_i, e_j) = (\cos \theta, \sin \theta)` (any positive scale), converted at once
        to ``th = atan2(ej, ei)``."""
        if isinstance(rot, (tuple, list)) and len(rot) == 2:
            try:
                ei, ej = (float(v) for v in rot)
            except (TypeError, ValueError):
                raise ModelError(f"rotation guess of body {who!r}: degenerate Euler parameters "
                                 f"(ei, ej) must be numbers; got {rot!r}") from None
            if ei == 0.0 and ej == 0.0 or not (math.isfinite(ei) and math.isfinite(ej)):
                raise ModelError(f"rotation guess of body {who!r}: degenerate Euler parameters "
                                 f"(ei, ej) = {rot!r} do not define an angle; give "
                                 "(cos th, sin th) or the angle th")
            return (math.atan2(ej, ei),)
        try:
            return (float(rot),)
        except (TypeError, ValueError):

            raise ModelError(f"rotation guess of body {who!r} must be an angle or degenerate "
                             f"Euler parameters (ei, ej); got {rot!r}") from None

    def angle(self, rot):
        return rot[0]

    def omega(self, rot, rot_d, local: bool = False):
        """Angular velocity (scalar) from ``theta_dot``: the same in global and local axes."""
        return rot_d[0]

    def inertia_matrix(self, inertia) -> sp.Matrix:
        """Centroidal inertia as a 1x1 matrix from a scalar ``J``."""
        return sp.Matrix([[sp.sympify(0 if inertia is None else inertia)]])

    def as_rotation_vector(self, w) -> sp.Matrix:
        """Angular quantities as a column (1 component in 2D)."""
        return sp.Matrix([w])

    def moment_about(self, arm, force):
        """Moment of ``force`` with lever ``arm`` (scalar ``arm x force`` in 2D)."""
        return self.cross(arm, force)

    def wrench_from_generalized(self, G, rot):
        """Force (2,) at the body origin and moment from a body's generalized force (3,)."""
        return sp.Matrix(G[:2]), G[2]


class Spatial(Space):
    """Spatial (3D) bodies: ``x, y, z, e0, e1, e2, e3`` (Euler parameters)."""

    dim = 3
    ncoord = 7
    name = "spatial"
    coordinate_names = ("x", "y", "z", "e0", "e1", "e2", "e3")

    def rotation_matrix(self, rot) -> sp.Matrix:

        return sp.Matrix(matrix_elements(rot))

    def cross(self, a, b):
        return sp.Matrix(a).cross(sp.Matrix(b))

    def perpendiculars(self, u):
        """Two vectors orthogonal to ``u`` and to each other (non-singular for every u).

        Picks the coordinate axis least aligned with ``u`` numerically when ``u`` is constant,
        else crosses with the x axis and the result, which callers use only on local (constant)
        directions.
        """
        u = sp.Matrix(u)
        try:
            absu = [abs(float(c)) for c in u]
            k = absu.index(min(absu))
        except TypeError:
            k = 0
        ek = sp.zeros(3, 1)
        ek[k] = 1
        h = u.cross(ek)
        f = u.cross(h)
        return [sp.simplify(h), sp.simplify(f)]

    def zero_rotation(self):
        return (1, 0, 0, 0)

    def rotation_guess(self, rot, who: str) -> tuple:
        """Euler parameters (normalised) from any Mech rotation format: ``(e0, e1, e2, e3)``,
        a virtual rotation ``(vx, vy, vz)``, ``(angle, (ux, uy, uz))``, a 3 x 3 NumPy rotation
        matrix, or a list of these applied in succession (see :mod:`mechsys.geometry._rotations`)."""
        import numpy as np

        try:
            e = np.asarray(euler_parameters(rot), dtype=float).ravel()
            if e.shape != (4,):
                raise ValueError
        except GeometryError as exc:   # not a rotation (a reflection, a shear, NaN): say so
            raise GeometryError(f"rotation guess of body {who!r}: {exc}") from None
        except ModelError as exc:
            if "ambiguous" not in str(exc):
                raise self._format_error(who, rot) from None
            raise ModelError(f"rotation guess of body {who!r}: {exc}") from None
        except (MechError, TypeError, ValueError, ZeroDivisionError):
            raise self._format_error(who, rot) from None
        n = np.linalg.norm(e)
        if n == 0:
            raise ModelError(f"rotation guess of body {who!r}: Euler parameters are all zero")
        return tuple(e / n)

    @staticmethod
    def _format_error(who: str, rot) -> ModelError:
        return ModelError(
            f"rotation guess of body {who!r}: give Euler parameters (e0, e1, e2, e3), a "
            "virtual rotation (vx, vy, vz), (angle, (ux, uy, uz)), a 3 x 3 numpy rotation "
            f"matrix or a list of these (successive rotations); got {rot!r}")

    def omega(self, rot, rot_d, local: bool = False) -> sp.Matrix:
        """Angular velocity (3,) from Euler-parameter rates::

            omega  = 2 E(e) e_dot,  E = [-e, e~ + e0 I]   (global)
            omega' = 2 G(e) e_dot,  G = [-e, -e~ + e0 I]  (body-local)
        """
        e0, e1, e2, e3 = rot
        sign = -1 if local else 1
        E = sp.Matrix(
            [
                [-e1, e0, -sign * e3, sign * e2],
                [-e2, sign * e3, e0, -sign * e1],
                [-e3, -sign * e2, sign * e1, e0],
            ]
        )
        return 2 * E * sp.Matrix(rot_d)

    def body_normalization(self, rot) -> list:
        e0, e1, e2, e3 = rot
        return [e0**2 + e1**2 + e2**2 + e3**2 - 1]

    def inertia_matrix(self, inertia) -> sp.Matrix:
        """Centroidal inertia matrix (3x3, body axes) from ``(Ixx, Iyy, Izz, Ixy, Iyz, Izx)``
        (the matrix entries, products included with their sign as matrix elements), principal
        moments ``(Ixx, Iyy, Izz)`` or a 3x3 matrix; ``None`` is zero."""
        if inertia is None:
            return sp.zeros(3, 3)
        if isinstance(inertia, sp.MatrixBase) or (
            hasattr(inertia, "__len__") and len(inertia) == 3
            and all(hasattr(row, "__len__") for row in inertia)
        ):
            J = sp.Matrix(inertia)
            if J.shape != (3, 3):
                raise ValueError("a 3D inertia matrix must be 3x3")
            return J
        vals = [sp.sympify(v) for v in inertia]
        if len(vals) == 3:
            vals = vals + [0, 0, 0]
        if len(vals) != 6:
            raise ValueError("3D inertia: give (Ixx, Iyy, Izz, Ixy, Iyz, Izx) or a 3x3 matrix")
        xx, yy, zz, xy, yz, zx = vals
        return sp.Matrix([[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]])

    def as_rotation_vector(self, w) -> sp.Matrix:
        return sp.Matrix(w)

    def moment_about(self, arm, force):
        return sp.Matrix(arm).cross(sp.Matrix(force))

    def wrench_from_generalized(self, G, rot):
        """Force (3,) at the origin and global moment (3,) from a body's generalized force
        ``(Q_r, Q_e)`` (7,): :math:`Q_e = 2 E^T M` so :math:`M = E Q_e / 2` (:math:`E E^T = I`)."""
        e0, e1, e2, e3 = rot
        E = sp.Matrix([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])
        return sp.Matrix(G[:3]), E * sp.Matrix(G[3:]) / 2


PLANAR = Planar()
SPATIAL = Spatial()
