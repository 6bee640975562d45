r"""Mass-property utilities (Mech's ``ParallelAxis``, ``PrincipalAxes``, composite bodies).

Inertia is the matrix :math:`J = \int (\lvert s \rvert^2 I - s s^T)\, dm` (scalar :math:`\int \lvert s
\rvert^2\, dm` in
2D), so products of inertia are the (signed) off-diagonal matrix elements.
"""

from __future__ import annotations

import numpy as np

from ._rotations import rotation_matrix


def _as_matrix3(inertia) -> np.ndarray:
    a = np.asarray(inertia, dtype=float)
    if a.shape == (3, 3):
        return a
    if a.shape == (6,):
        xx, yy, zz, xy, yz, zx = a
        return np.array([[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]])
    if a.shape == (3,):
        return np.diag(a)
    raise ValueError("3D inertia: (Ixx, Iyy, Izz, Ixy, Iyz, Izx), principal (3,) or 3x3")


def _as_list6(J: np.ndarray):
    return (J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[1, 2], J[2, 0])


def _rotation_matrix(rotation) -> np.ndarray:
    """3x3 matrix of a rotation in any of Mech's formats, read by the one rule of
    :mod:`mechsys.geometry._rotations` (a matrix is checked to be a rotation; a nested 3x3
    list is refused as ambiguous)."""
    return np.asarray(rotation_matrix(rotation), dtype=float)


def parallel_axis(vector, mass: float, inertia, rotation=None):
    r"""Inertia about another origin (parallel axis theorem).

    ``inertia`` is centroidal; ``vector`` runs from the new origin to the centroid:

    .. math::

        J_O &= J_c + m \lvert d \rvert^2 \qquad \text{(2D)} \\
        J_O &= R J_c R^T + m (\lvert d \rvert^2 I - d d^T) \qquad \text{(3D)}

    ``rotation`` (3D) is the rotation of the centroidal frame relative to the new frame,
    ``R`` its matrix (columns: the centroidal axes in new-frame components). As in Mech it
    may be given as ``(angle, (x, y, z))``, a virtual rotation vector ``(vx, vy, vz)``
    (axis times angle), Euler parameters ``(e0, e1, e2, e3)``, or a 3x3 rotation matrix as
    a NumPy array or SymPy ``Matrix`` (checked to be a rotation; a nested 3x3 Python list is
    refused as ambiguous, as everywhere: see docs/spatial.md).
    Negative ``mass`` goes the other way (non-centroidal to centroidal), as in Mech: then
    ``vector`` runs from the centroid to the other origin and ``rotation`` is that of the
    other frame, both in centroidal axes.
    Returns a scalar (2D) or ``(Ixx, Iyy, Izz, Ixy, Iyz, Izx)`` (3D).

    >>> parallel_axis((1.0, 0.0), 2.0, 0.5)
    2.5
    """
    d = np.asarray(vector, dtype=float)
    if d.shape == (2,):
        return float(inertia) + mass * float(d @ d)
    J = _as_matrix3(inertia)
    if rotation is not None:
        R = _rotation_matrix(rotation)
        J = R @ J @ R.T
    return _as_list6(J + mass * (float(d @ d) * np.eye(3) - np.outer(d, d)))


def principal_axes(inertia):
    """Principal moments (ascending) and axes (columns of a rotation matrix, right-handed)."""
    w, V = np.linalg.eigh(_as_matrix3(inertia))
    if np.linalg.det(V) < 0:
        V[:, 2] = -V[:, 2]
    return w, V


def composite_inertia(parts):
    r"""Combine parts ``[(mass, centroid, inertia), ...]`` (each inertia centroidal, all in
    one body frame) into ``(mass, centroid, inertia about the composite centroid)``.

    In 3D a part may carry a fourth element, the rotation of its own centroidal frame
    relative to the body frame (Mech's ``CompositeInertia`` element ``{mass, centroid,
    inertia, rotation}``), in any of :func:`parallel_axis`'s formats: its inertia, given in
    its own axes, enters as :math:`R J R^T`. Returns ``(M, centroid, J)``: ``J`` a scalar in 2D,
    ``(Ixx, Iyy, Izz, Ixy, Iyz, Izx)`` in 3D."""
    parts = [tuple(p) for p in parts]
    for p in parts:
        if len(p) not in (3, 4):
            raise ValueError(f"composite_inertia: a part is (mass, centroid, inertia) or, in 3D, "
                             f"(mass, centroid, inertia, rotation); got {p!r}")
    M = sum(float(p[0]) for p in parts)
    if M == 0:
        raise ValueError("composite_inertia: total mass is zero")
    c = sum(float(p[0]) * np.asarray(p[1], dtype=float) for p in parts) / M
    if c.shape == (2,):
        if any(len(p) == 4 for p in parts):
            raise ValueError("composite_inertia: a planar part has no rotation element (its "
                             "inertia is a scalar about the normal axis)")
        J = sum(parallel_axis(np.asarray(r) - c, m, I) for m, r, I in parts)
        return M, tuple(c), J
    J = np.zeros((3, 3))
    for p in parts:
        m, r, I = p[:3]
        rot = p[3] if len(p) == 4 else None
        J += _as_matrix3(parallel_axis(np.asarray(r, dtype=float) - c, m, I, rot))
    return M, tuple(c), _as_list6(J)


ParallelAxis = parallel_axis
PrincipalAxes = principal_axes
CompositeInertia = composite_inertia
