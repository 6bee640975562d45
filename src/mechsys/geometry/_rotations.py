r"""Rotation and coordinate utilities (Mech's ``EulerParameters``, ``Rotation``,
``RotationMatrix``, ``VirtualRotation``, ``ProjectedAngle``, ``IntersectionPoint``, the
cylindrical/spherical conversions, ``Magnitude``, ``Unit``, ``Direction``, ``Distance``).

Conventions
-----------
Euler parameters ``e = (e0, e1, e2, e3)`` of a rotation by :math:`\phi` about the unit axis
:math:`u`:

.. math::

    e_0 = \cos(\phi / 2), \qquad (e_1, e_2, e_3) = \sin(\phi / 2)\, u

and its matrix (the one bodies use, see :mod:`mechsys.geometry._space`), with
:math:`e = (e_1, e_2, e_3)` and :math:`\tilde e` its cross-product matrix:

.. math::

    A(e) = (e_0^2 - e \cdot e)\, I + 2\, e e^T + 2 e_0 \tilde e

A *rotation specification* is any of Mech's formats:

* Euler parameters ``(e0, e1, e2, e3)``;
* a virtual rotation ``(vx, vy, vz)`` -- the axis times the angle (radians);
* an angle and axis ``(angle, (x, y, z))`` (the axis need not be unit; it may be a mechsys
  :class:`~mechsys.Vector`, ``Axis``, ``Line`` or ``Plane``);
* a rotation matrix, given as a 2-D ``numpy`` array or a SymPy ``Matrix``; it must be a
  proper rotation (:math:`\max \lvert R^T R - I \rvert \le 10^{-6}`, ``det R > 0``), else
  :class:`GeometryError`;
* a nested Python list or tuple of three rows of three numbers is refused as ambiguous (a
  matrix, or three virtual rotations?) by every function that takes a rotation;
* a sequence of the above, ``[rot1, rot2, ...]``: rotate by ``rot1``, then by ``rot2`` about
  axes expressed in the frame already rotated by ``rot1``, and so on (Mech's
  ``RotationLock3`` convention; intrinsic, so :math:`A = A_1 A_2 \cdots A_n`). Equivalently, rotate by
  ``rotn`` first, then ``rot(n-1)``, ..., all about fixed axes;
* a :class:`~mechsys.Body` (its Euler-parameter coordinates, symbolic).

Numeric input gives NumPy arrays; input holding SymPy symbols (an angle ``2*pi*T``, a body)
gives SymPy expressions, so the result can be evaluated over a solution with ``sol.eval``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import sympy as sp

from .._errors import GeometryError, ModelError, choice
from ._points import Axis, BodyRef, Point, Vector, as_axis, as_point, as_vector

# ---------------------------------------------------------------------------------------
# numeric / symbolic helpers
# ---------------------------------------------------------------------------------------


class _NumpyMath:
    sqrt = staticmethod(np.sqrt)
    atan2 = staticmethod(np.arctan2)
    cos = staticmethod(np.cos)
    sin = staticmethod(np.sin)


class _SympyMath:
    sqrt = staticmethod(sp.sqrt)
    atan2 = staticmethod(sp.atan2)
    cos = staticmethod(sp.cos)
    sin = staticmethod(sp.sin)


def _is_symbolic(*values) -> bool:
    """True when any (nested) value is a SymPy expression that is not a plain number."""
    for v in values:
        if isinstance(v, sp.MatrixBase):
            if any(not e.is_number for e in v):
                return True
        elif isinstance(v, sp.Basic):
            if not v.is_number:
                return True
        elif isinstance(v, np.ndarray):
            if v.dtype == object and any(_is_symbolic(x) for x in v.ravel()):
                return True
        elif isinstance(v, Sequence) and not isinstance(v, str):
            if any(_is_symbolic(x) for x in v):
                return True
    return False


def _is_scalar(x) -> bool:
    if isinstance(x, (int, float, np.number)) and not isinstance(x, bool):
        return True
    return isinstance(x, sp.Expr) and not isinstance(x, sp.MatrixBase)


def _geometry_direction(obj):
    """Global direction of a mechsys vector-like object, else ``None``."""

    if isinstance(obj, (Vector, Axis)):
        return list(obj.direction())
    return None


def _vec3(v, what: str) -> list:
    d = _geometry_direction(v)
    if d is not None:
        return d
    if isinstance(v, (sp.MatrixBase, np.ndarray)):
        v = list(np.asarray(v, dtype=object).ravel()) if isinstance(v, np.ndarray) else list(v)
    if not (isinstance(v, Sequence) and len(v) == 3 and all(_is_scalar(c) for c in v)):
        raise ModelError(f"{what}: expected a 3-vector (x, y, z), got {v!r}")
    return list(v)


def _finish(vals, symbolic: bool, shape=None):
    if symbolic:
        m = sp.Matrix(vals)
        return m.reshape(*shape) if shape else m
    out = np.array([float(v) for v in (np.asarray(vals, dtype=object).ravel())])
    return out.reshape(shape) if shape else out


# ---------------------------------------------------------------------------------------
# quaternion algebra (generic arithmetic: works on floats and SymPy expressions alike)
# ---------------------------------------------------------------------------------------


def quaternion_product(a, b) -> list:
    """Euler parameters of the rotation ``a`` followed by ``b`` in ``a``'s rotated frame
    (``A(a) A(b)``; Mech's ``EulerMultiply``)::

        (a0 b0 - a.b,  a0 b + b0 a + a x b)
    """
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return [
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + b0 * a1 + a2 * b3 - a3 * b2,
        a0 * b2 + b0 * a2 + a3 * b1 - a1 * b3,
        a0 * b3 + b0 * a3 + a1 * b2 - a2 * b1,
    ]


def quaternion_inverse(e) -> list:
    """The inverse rotation (Mech's ``EulerInverse``): ``(e0, -e1, -e2, -e3)``."""
    return [e[0], -e[1], -e[2], -e[3]]


def matrix_elements(e) -> list:
    """Rows of ``A(e)`` (3 x 3 nested list) for Euler parameters ``e`` (any arithmetic type)."""
    e0, e1, e2, e3 = e
    return [
        [e0**2 + e1**2 - e2**2 - e3**2, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)],
        [2 * (e1 * e2 + e0 * e3), e0**2 - e1**2 + e2**2 - e3**2, 2 * (e2 * e3 - e0 * e1)],
        [2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0**2 - e1**2 - e2**2 + e3**2],
    ]


# ---------------------------------------------------------------------------------------
# parsing rotation specifications
# ---------------------------------------------------------------------------------------


def _from_angle_axis(angle, axis, assume_unit: bool = False) -> list:
    u = _vec3(axis, "rotation axis")
    symbolic = _is_symbolic(angle, u)
    M = _SympyMath if symbolic else _NumpyMath
    if not symbolic:
        angle = float(angle)
        u = [float(c) for c in u]
        n = float(np.linalg.norm(u))
        if n == 0.0:
            if angle == 0.0:
                return [1.0, 0.0, 0.0, 0.0]
            raise GeometryError("rotation axis is the zero vector; give a non-zero axis")
        if not assume_unit:
            u = [c / n for c in u]
    elif not assume_unit:
        n = sp.sqrt(sum(c**2 for c in u))
        if n.is_number and n == 0:
            raise GeometryError("rotation axis is the zero vector; give a non-zero axis")
        u = [c / n for c in u]
    s = M.sin(angle / 2)
    return [M.cos(angle / 2), s * u[0], s * u[1], s * u[2]]


def _from_virtual(v) -> list:
    v = _vec3(v, "virtual rotation")
    if _is_symbolic(v):
        phi = sp.sqrt(sum(c**2 for c in v))
        k = sp.sin(phi / 2) / phi
        return [sp.cos(phi / 2), k * v[0], k * v[1], k * v[2]]
    v = np.array([float(c) for c in v])
    phi = float(np.linalg.norm(v))
    k = 0.5 * np.sinc(phi / (2 * np.pi))  # sin(phi/2)/phi, finite at phi = 0
    return [float(np.cos(phi / 2)), *(k * v)]


#: a matrix is a rotation when :math:`\max \lvert R^T R - I \rvert \le \mathtt{ORTHO\_TOL}`
#: and :math:`\det R > 0`. Rotation
#: matrices are dimensionless, so the bound is absolute: it takes matrices computed in double
#: precision or printed to seven digits or more (float32 round trips), and refuses a shear,
#: a scaling or a matrix rounded to a few digits, whose rotation would be a guess.
ORTHO_TOL = 1e-6


def check_rotation_matrix(R, what: str = "rotation matrix") -> np.ndarray:
    r"""``R`` as a (3, 3) float array when it is a proper rotation, else :class:`GeometryError`
    saying what it is instead (not finite, not orthonormal, a reflection). The test is
    :math:`\max \lvert R^T R - I \rvert \le \mathtt{ORTHO\_TOL}` and ``det R > 0``."""
    try:
        R = np.array(R.tolist() if isinstance(R, sp.MatrixBase) else R, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{what}: a rotation matrix must be numeric, got {R!r}; give symbolic "
                         "rotations as (angle, (x, y, z)) or Euler parameters") from None
    if R.shape != (3, 3):
        raise ModelError(f"{what}: a rotation matrix must be 3 x 3, got shape {R.shape}")
    if not np.all(np.isfinite(R)):
        raise GeometryError(f"{what} has entries that are not finite (NaN or inf): {R.tolist()}")
    dev = float(np.abs(R.T @ R - np.eye(3)).max())
    if dev > ORTHO_TOL:
        raise GeometryError(
            f"{what} is not a rotation: its columns are not orthonormal (max |R^T R - I| = "
            f"{dev:.3g} > {ORTHO_TOL:g}; a shear, a scaling or a matrix rounded to few digits). "
            "Give a rotation matrix to about seven digits or better; to take the nearest "
            "rotation of a rounded one, U, _, Vt = np.linalg.svd(R); R = U @ Vt")
    if np.linalg.det(R) < 0:
        raise GeometryError(f"{what} is a reflection (det R = {np.linalg.det(R):.3g}), not a "
                            "rotation: a right-handed frame turns into a left-handed one; "
                            "change the sign of one column")
    return R


def _from_matrix(R, what: str = "rotation matrix") -> list:
    """Shepperd's method: pick the largest of (e0^2, e1^2, e2^2, e3^2) to divide by, so the
    result is accurate for every rotation, including those near 180 degrees. ``R`` must be a
    proper rotation (:func:`check_rotation_matrix`)."""
    R = check_rotation_matrix(R, what)
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    k = int(np.argmax([tr, R[0, 0], R[1, 1], R[2, 2]]))
    if k == 0:
        e0 = 0.5 * np.sqrt(max(1.0 + tr, 0.0))
        f = 0.25 / e0
        e = [e0, (R[2, 1] - R[1, 2]) * f, (R[0, 2] - R[2, 0]) * f, (R[1, 0] - R[0, 1]) * f]
    elif k == 1:
        e1 = 0.5 * np.sqrt(max(1.0 + 2 * R[0, 0] - tr, 0.0))
        f = 0.25 / e1
        e = [(R[2, 1] - R[1, 2]) * f, e1, (R[0, 1] + R[1, 0]) * f, (R[0, 2] + R[2, 0]) * f]
    elif k == 2:
        e2 = 0.5 * np.sqrt(max(1.0 + 2 * R[1, 1] - tr, 0.0))
        f = 0.25 / e2
        e = [(R[0, 2] - R[2, 0]) * f, (R[0, 1] + R[1, 0]) * f, e2, (R[1, 2] + R[2, 1]) * f]
    else:
        e3 = 0.5 * np.sqrt(max(1.0 + 2 * R[2, 2] - tr, 0.0))
        f = 0.25 / e3
        e = [(R[1, 0] - R[0, 1]) * f, (R[0, 2] + R[2, 0]) * f, (R[1, 2] + R[2, 1]) * f, e3]
    e = np.array(e)
    e /= np.linalg.norm(e)
    if e[0] < 0:
        e = -e
    return list(e)


def _parse(rot, assume_unit: bool = False) -> list:
    """Euler parameters (a list of 4 floats or SymPy expressions) of any rotation format."""

    if isinstance(rot, BodyRef):
        return [sp.S.One, sp.S.Zero, sp.S.Zero, sp.S.Zero] if rot.is_ground else list(
            rot.q[rot.space.dim:])
    if isinstance(rot, np.ndarray) and rot.ndim == 2:
        return _from_matrix(rot)
    if isinstance(rot, sp.MatrixBase) and rot.shape == (3, 3):
        return _from_matrix(rot)
    d = _geometry_direction(rot)
    if d is not None:
        return _from_virtual(d)
    if isinstance(rot, (np.ndarray, sp.MatrixBase)):
        rot = (list(np.asarray(rot, dtype=object).ravel()) if isinstance(rot, np.ndarray)
               else list(rot))
    if not isinstance(rot, Sequence) or isinstance(rot, str) or len(rot) == 0:
        raise ModelError(_FORMATS.format(rot=rot))
    if all(_is_scalar(c) for c in rot):
        _check_finite(rot)
        if len(rot) == 4:
            if not _is_symbolic(rot) and not any(float(c) for c in rot):
                raise GeometryError("Euler parameters (0, 0, 0, 0) do not define a rotation")
            return list(rot)
        if len(rot) == 3:
            return _from_virtual(rot)
        raise ModelError(_FORMATS.format(rot=rot))
    if len(rot) == 3 and all(_is_row3(r) for r in rot):
        raise ModelError(_AMBIGUOUS.format(rot=rot))
    if len(rot) == 2 and _is_scalar(rot[0]):
        _check_finite([rot[0]])
        return _from_angle_axis(rot[0], rot[1], assume_unit)
    # a sequence of rotations, each in the frame rotated by the ones before it
    e = None
    for r in rot:
        q = _parse(r, assume_unit)
        e = q if e is None else quaternion_product(e, q)
    return e


def _is_row3(r) -> bool:
    """A plain row of three numbers or expressions (a list, tuple or 1-D array)."""
    if isinstance(r, np.ndarray):
        return r.ndim == 1 and r.shape == (3,)
    return (isinstance(r, Sequence) and not isinstance(r, str) and len(r) == 3
            and all(_is_scalar(c) for c in r))


def _check_finite(values) -> None:
    """:class:`GeometryError` when a numeric value of a rotation is NaN or infinite."""
    for c in values:
        if not _is_symbolic(c) and not np.isfinite(complex(c)):
            raise GeometryError(f"a rotation has a value that is not finite ({c}): {values!r}")


#: the one rule for nested lists (docs/spatial.md): three rows of three numbers could be a
#: matrix or three virtual rotations, and the two readings give different rotations
_AMBIGUOUS = (
    "{rot!r} is ambiguous: three rows of three numbers could be a rotation matrix or a "
    "sequence of three virtual rotations (axis times angle). Write a matrix as "
    "np.array([[...], [...], [...]]) (or sp.Matrix), and a sequence of rotations with "
    "each one as (angle, (x, y, z)) or Euler parameters (e0, e1, e2, e3)"
)

_FORMATS = (
    "cannot read {rot!r} as a rotation: give Euler parameters (e0, e1, e2, e3), a virtual "
    "rotation (vx, vy, vz), (angle, (x, y, z)), a 3 x 3 numpy rotation matrix, or a list of "
    "these (successive rotations)"
)


# ---------------------------------------------------------------------------------------
# public utilities
# ---------------------------------------------------------------------------------------


def euler_parameters(rot, normalized: bool = False):
    """Euler parameters ``(e0, e1, e2, e3)`` of any rotation format (see the module doc).

    ``normalized=True`` assumes a given rotation axis is already a unit vector (Mech's
    ``Assumptions -> Normalized``). From a matrix the result has ``e0 >= 0`` and is accurate
    near 180 degrees (Shepperd's method). Numeric input gives a NumPy array ``(4,)``; symbolic
    input a SymPy column ``(4, 1)``.
    """
    e = _parse(rot, normalized)
    return _finish(e, _is_symbolic(e))


def rotation_matrix(rot):
    """The 3 x 3 rotation matrix of any rotation format (NumPy, or SymPy when symbolic).

    From Euler parameters the matrix is ``A(e)`` above; numeric parameters are normalised
    first so that a slightly drifted set still gives an orthogonal matrix.
    """

    if isinstance(rot, BodyRef):
        return rot.A
    e = _parse(rot)
    symbolic = _is_symbolic(e)
    if not symbolic:
        e = np.array(e, dtype=float)
        n = np.linalg.norm(e)
        if n == 0:
            raise GeometryError("Euler parameters are all zero; they do not define a rotation")
        e = e / n
    return _finish(matrix_elements(e), symbolic, (3, 3))


def rotation(rot, normalized: bool = True):
    r"""Angle and axis ``(angle, (x, y, z))`` of any rotation format (Mech's ``Rotation``).

    Numeric: the angle is in ``[0, pi]`` (the sign of the parameters is chosen with
    ``e0 >= 0``), computed as ``2 atan2(|e_v|, e0)`` so it stays accurate near 0 and 180
    degrees and for parameters that drifted off the unit sphere. At zero angle the axis is
    undefined; ``(1, 0, 0)`` is returned. ``normalized=False`` returns the vector part
    ``(e1, e2, e3)`` (length ``sin(angle/2)``) as the axis, unnormalised. Symbolic input
    (a body) gives the angle in ``[0, 2 pi)`` without the sign choice.

    Planar forms (Mech's ``Rotation`` in Modeler2D) return the scalar angle ``theta``
    (radians, counterclockwise): a planar body (its angle coordinate, symbolic), the
    degenerate Euler parameters :math:`(e_i, e_j) = (\cos \theta, \sin \theta)` (any positive scale;
    ``atan2(ej, ei)``, as ``Model2D(orientation="euler")``), or a 2 x 2 rotation matrix
    (``atan2(A[1, 0], A[0, 0])``; a matrix that is not a rotation raises ``GeometryError``).
    """
    planar = _planar_angle(rot)
    if planar is not None:
        return planar
    e = _parse(rot)
    if _is_symbolic(e):
        s = sp.sqrt(e[1] ** 2 + e[2] ** 2 + e[3] ** 2)
        ang = 2 * sp.atan2(s, e[0])
        axis = sp.Matrix(e[1:]) / s if normalized else sp.Matrix(e[1:])
        return ang, axis
    e = np.array(e, dtype=float)
    if e[0] < 0:
        e = -e
    s = float(np.linalg.norm(e[1:]))
    ang = 2.0 * float(np.arctan2(s, e[0]))
    if not normalized:
        return ang, e[1:].copy()
    axis = e[1:] / s if s > 0 else np.array([1.0, 0.0, 0.0])
    return ang, axis


def _planar_angle(rot):
    """The angle of a planar rotation format, or None when ``rot`` is not one."""
    if isinstance(rot, BodyRef):
        if rot.space.dim != 2:
            return None
        return sp.S.Zero if rot.is_ground else rot.space.angle(rot.q[2:])
    if isinstance(rot, (np.ndarray, sp.MatrixBase)) and getattr(rot, "shape", None) == (2, 2):
        if isinstance(rot, sp.MatrixBase) and rot.free_symbols:
            return sp.atan2(rot[1, 0], rot[0, 0])
        A = np.array(rot.tolist() if isinstance(rot, sp.MatrixBase) else rot, dtype=float)
        if not np.allclose(A.T @ A, np.eye(2), atol=1e-9) or np.linalg.det(A) < 0:
            raise GeometryError(f"rotation: {A.tolist()} is not a 2 x 2 rotation matrix "
                                "(orthonormal columns, determinant +1)")
        return float(np.arctan2(A[1, 0], A[0, 0]))
    if isinstance(rot, Sequence) and not isinstance(rot, str) and len(rot) == 2 and \
            all(_is_scalar(c) for c in rot):
        ei, ej = rot
        if any(isinstance(c, sp.Basic) and c.free_symbols for c in rot):
            return sp.atan2(ej, ei)
        ei, ej = float(ei), float(ej)
        if ei == 0.0 and ej == 0.0:
            raise GeometryError("rotation: planar Euler parameters (0, 0) do not define an angle")
        return float(np.arctan2(ej, ei))
    return None


def virtual_rotation(rot):
    """The virtual rotation vector (axis times angle, radians) of any rotation format
    (Mech's ``VirtualRotation``). Numeric: angle in ``[0, pi]``, smooth through zero."""
    e = _parse(rot)
    if _is_symbolic(e):
        ang, axis = rotation(rot)
        return ang * axis
    e = np.array(e, dtype=float)
    if e[0] < 0:
        e = -e
    s = float(np.linalg.norm(e[1:]))
    if s < 1e-300:
        return np.zeros(3)
    return 2.0 * np.arctan2(s, e[0]) / s * e[1:]


def projected_angle(vector1, vector2, vector3=None):
    """Counter-clockwise angle (right-hand sense about ``vector3``) from the direction of
    ``vector2`` to that of ``vector1``, both projected on the plane normal to ``vector3``;
    in ``(-pi, pi]`` (Mech's ``ProjectedAngle``).

    ``projected_angle(vector, axis)`` uses the axis direction as ``vector3`` and its
    reference direction as ``vector2``. Computed as ``atan2(n.(v2 x v1), v2_p.v1_p)``
    (``n`` the unit normal, ``_p`` the projections): no ``arccos``, so it stays finite and
    accurate when body vectors come from Euler parameters that drifted past unit length
    (a uniform scale does not change the angle). Numeric arrays broadcast over leading
    axes (shape ``(..., 3)``); mechsys vectors give a SymPy expression.
    """

    if vector3 is None:
        if not isinstance(vector2, Axis):
            raise ModelError("projected_angle(vector, axis) needs an axis (with a reference "
                             "direction) as second argument, or give three vectors")
        vector3 = vector2.dir
        vector2 = vector2.reference_vector()
    objs = (vector1, vector2, vector3)
    if any(isinstance(v, (Vector, Axis)) for v in objs):

        v1, v2, v3 = (as_vector(v).direction() for v in objs)
        n = v3 / sp.sqrt(v3.dot(v3))
        y = n.dot(v2.cross(v1))
        x = v2.dot(v1) - v2.dot(n) * v1.dot(n)
        return sp.atan2(y, x)
    v1, v2, v3 = (np.asarray(v, dtype=float) for v in objs)
    n = v3 / np.linalg.norm(v3, axis=-1, keepdims=True)
    y = np.einsum("...i,...i->...", n, np.cross(v2, v1))
    x = (np.einsum("...i,...i->...", v2, v1)
         - np.einsum("...i,...i->...", v2, n) * np.einsum("...i,...i->...", v1, n))
    return np.arctan2(y, x)


def intersection_point(axis1, axis2, offset=None):
    r"""Point where ``axis1`` meets the plane through the origin of ``axis2`` normal to its
    direction (3D; ``axis2`` is typically a :class:`~mechsys.Plane`), or where two lines
    meet (2D: the "plane" of ``axis2`` is the line itself):

    .. math::

        r = r_1 + u_1 \, \frac{n_2 \cdot (r_2 - r_1)}{n_2 \cdot u_1}

    with :math:`n_2` the plane normal (3D) or the normal of line 2 (2D). Symbolic in the body
    coordinates (evaluate with ``sol.eval``); numeric when both axes are on ground.
    Raises :class:`GeometryError` when the axis is parallel to the plane (numerically).

    2D only, ``offset`` (Mech's ``IntersectionPoint[axis1, axis2, offset]``): the point
    ``offset`` units to the left of both axes, e.g. the centre of a fillet of radius
    ``offset`` between them -- the intersection of the two lines each moved by ``offset``
    along its left normal ``perp(u)/|u|``, :math:`\mathit{perp}(u) = (-u_y, u_x)` (negative: to the right).
    """

    a1, a2 = as_axis(axis1), as_axis(axis2)
    r1, u1 = a1.location(), a1.direction()
    r2, u2 = a2.location(), a2.direction()
    if offset is not None:
        if len(u2) != 2:
            raise GeometryError("intersection_point: the offset form is planar (2D axes); "
                                "in 3D give two arguments")
        off = sp.sympify(offset)
        r1 = r1 + off * sp.Matrix([-u1[1], u1[0]]) / sp.sqrt(u1.dot(u1))
        r2 = r2 + off * sp.Matrix([-u2[1], u2[0]]) / sp.sqrt(u2.dot(u2))
    if len(u2) == 2:
        n2 = sp.Matrix([-u2[1], u2[0]])
    elif len(u2) == 3:
        n2 = u2
    else:  # pragma: no cover - geometry checks dimensions
        raise GeometryError("intersection_point needs 2D or 3D axes")
    den = n2.dot(u1)
    if den.is_number and abs(float(den)) < 1e-14:
        raise GeometryError("intersection_point: the axis is parallel to the plane (or line); "
                            "they do not intersect")
    r = r1 + u1 * (n2.dot(r2 - r1) / den)
    if all(c.is_number for c in r):
        return np.array([float(c) for c in r])
    return r


# -- coordinate conversions --------------------------------------------------------------

_ORDERS = {"XYZ": (0, 1, 2), "YZX": (1, 2, 0), "ZXY": (2, 0, 1)}


def _order(coordinates: str):
    try:
        return _ORDERS[str(coordinates).upper()]
    except KeyError:
        choice(coordinates, list(_ORDERS), "coordinates")
        raise  # pragma: no cover - choice raised


def _components(p):
    symbolic = _is_symbolic(p)
    if symbolic:
        p = list(p)
        if len(p) != 3:
            raise ModelError(f"expected a 3D point, got {p!r}")
        return p, _SympyMath, True
    a = np.asarray(p, dtype=float)
    if a.shape[-1] != 3:
        raise ModelError(f"expected 3D point(s) with shape (..., 3), got shape {a.shape}")
    return [a[..., 0], a[..., 1], a[..., 2]], _NumpyMath, False


def _pack(vals, symbolic):
    if symbolic:
        return sp.Matrix(vals)
    return np.stack(np.broadcast_arrays(*vals), axis=-1)


def xyz_to_cylindrical(point, coordinates: str = "XYZ"):
    """Cartesian ``(x, y, z)`` to cylindrical ``(radius, angle, altitude)``.

    ``coordinates="XYZ"`` (default): altitude along Z, angle ``atan2(y, x)`` (zero when Y is
    zero and X positive). ``"YZX"``: altitude along X, angle ``atan2(z, y)``; ``"ZXY"``:
    altitude along Y, angle ``atan2(x, z)`` (the axes cycled, each right-handed)."""
    c, M, sym = _components(point)
    i, j, k = _order(coordinates)
    a, b, h = c[i], c[j], c[k]
    return _pack([M.sqrt(a**2 + b**2), M.atan2(b, a), h], sym)


def cylindrical_to_xyz(point, coordinates: str = "XYZ"):
    """Cylindrical ``(radius, angle, altitude)`` to Cartesian; inverse of
    :func:`xyz_to_cylindrical` with the same ``coordinates`` convention."""
    c, M, sym = _components(point)
    rad, ang, h = c
    out = [None, None, None]
    i, j, k = _order(coordinates)
    out[i], out[j], out[k] = rad * M.cos(ang), rad * M.sin(ang), h
    return _pack(out, sym)


def polar_to_xy(point):
    r"""Planar polar ``(radius, angle)`` to Cartesian ``(x, y)`` (Mech's ``PolarToXY``):
    :math:`x = r \cos(\mathit{angle})`, :math:`y = r \sin(\mathit{angle})`, the angle counterclockwise from
    +X in
    radians. Numeric input of shape ``(..., 2)`` gives an array ``(..., 2)``; symbolic input
    a SymPy column. Inverse of ``(hypot(x, y), atan2(y, x))``."""
    if _is_symbolic(point):
        p = list(point)
        if len(p) != 2:
            raise ModelError(f"polar_to_xy: expected (radius, angle), got {point!r}")
        return sp.Matrix([p[0] * sp.cos(p[1]), p[0] * sp.sin(p[1])])
    a = np.asarray(point, dtype=float)
    if a.shape[-1:] != (2,):
        raise ModelError(f"polar_to_xy: expected (radius, angle) pairs with shape (..., 2), "
                         f"got shape {a.shape}")
    return np.stack((a[..., 0] * np.cos(a[..., 1]), a[..., 0] * np.sin(a[..., 1])), axis=-1)


def xyz_to_spherical(point, coordinates: str = "XYZ"):
    """Cartesian to spherical ``(radius, base angle, altitude angle)``.

    ``"XYZ"``: base angle ``atan2(y, x)`` in the XY plane, altitude angle the elevation above
    that plane towards +Z, in ``[-pi/2, pi/2]``; ``"YZX"``/``"ZXY"`` cycle the axes as in
    :func:`xyz_to_cylindrical`."""
    c, M, sym = _components(point)
    i, j, k = _order(coordinates)
    a, b, h = c[i], c[j], c[k]
    rho = M.sqrt(a**2 + b**2)
    return _pack([M.sqrt(a**2 + b**2 + h**2), M.atan2(b, a), M.atan2(h, rho)], sym)


def spherical_to_xyz(point, coordinates: str = "XYZ"):
    """Spherical ``(radius, base angle, altitude angle)`` to Cartesian; inverse of
    :func:`xyz_to_spherical`."""
    c, M, sym = _components(point)
    rad, base, alt = c
    rho = rad * M.cos(alt)
    out = [None, None, None]
    i, j, k = _order(coordinates)
    out[i], out[j], out[k] = rho * M.cos(base), rho * M.sin(base), rad * M.sin(alt)
    return _pack(out, sym)


# -- vectors and points ------------------------------------------------------------------


def _as_direction(v):

    if isinstance(v, (Vector, Axis)):
        return as_vector(v).direction(), True
    return np.asarray(v, dtype=float), False


def direction(vector):
    """Global components of a vector (a mechsys vector, axis, line or plane: symbolic), or
    the array itself."""
    d, sym = _as_direction(vector)
    return d


def magnitude(vector):
    """Length of a vector (Mech's ``Magnitude``); arrays ``(..., n)`` give ``(...)``."""
    d, sym = _as_direction(vector)
    if sym:
        return sp.sqrt(d.dot(d))
    return np.linalg.norm(d, axis=-1)


def unit(vector):
    """The vector divided by its length (Mech's ``Unit``)."""
    d, sym = _as_direction(vector)
    if sym:
        return d / sp.sqrt(d.dot(d))
    n = np.linalg.norm(d, axis=-1, keepdims=True)
    if np.any(n == 0):
        raise GeometryError("unit: the vector has zero length")
    return d / n


def distance(point1, point2):
    """Distance between two points (mechsys points: symbolic; coordinate arrays: numeric)."""

    if isinstance(point1, Point) or isinstance(point2, Point):

        d = as_point(point1).location() - as_point(point2).location()
        return sp.sqrt(d.dot(d))
    d = np.asarray(point1, dtype=float) - np.asarray(point2, dtype=float)
    return np.linalg.norm(d, axis=-1)


# Mech's names
EulerParameters = euler_parameters
RotationMatrix = rotation_matrix
Rotation = rotation
VirtualRotation = virtual_rotation
ProjectedAngle = projected_angle
IntersectionPoint = intersection_point
XYZToCylindrical = xyz_to_cylindrical
CylindricalToXYZ = cylindrical_to_xyz
PolarToXY = polar_to_xy
XYZToSpherical = xyz_to_spherical
SphericalToXYZ = spherical_to_xyz
Magnitude = magnitude
Unit = unit
Direction = direction
Distance = distance
EulerMultiply = quaternion_product
EulerInverse = quaternion_inverse

__all__ = [
    "CylindricalToXYZ",
    "Direction",
    "Distance",
    "EulerInverse",
    "EulerMultiply",
    "EulerParameters",
    "IntersectionPoint",
    "Magnitude",
    "ProjectedAngle",
    "Rotation",
    "RotationMatrix",
    "SphericalToXYZ",
    "Unit",
    "VirtualRotation",
    "XYZToCylindrical",
    "XYZToSpherical",
    "cylindrical_to_xyz",
    "direction",
    "distance",
    "euler_parameters",
    "intersection_point",
    "magnitude",
    "matrix_elements",
    "projected_angle",
    "quaternion_inverse",
    "quaternion_product",
    "rotation",
    "rotation_matrix",
    "spherical_to_xyz",
    "unit",
    "virtual_rotation",
    "xyz_to_cylindrical",
    "xyz_to_spherical",
]
