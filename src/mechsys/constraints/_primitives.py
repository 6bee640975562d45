r"""Equation builders shared by 2D and 3D constraints (written once, vector algebra only).

Notation: ``r_i`` a global point, ``u_i`` a global direction, ``A`` a body's rotation matrix,
``h, f`` directions orthogonal to ``u`` fixed in the body that carries ``u``.
"""

from __future__ import annotations

import sympy as sp

from ..geometry._points import Axis, Point, Vector


def coincident(p1: Point, p2: Point, offset=None) -> list[sp.Expr]:
    """:math:`r_1 - r_2 - d = 0` componentwise (``d`` a global offset, default zero)."""
    # entry by entry, each a single Add of the terms of both locations: a SymPy Matrix
    # difference goes through its domain matrices, and a difference of two sums builds three
    # (the same canonical sum, decision 0079)
    d = [sp.Add(*a, *(-t for t in b)) for a, b in zip(p1._location_terms(), p2._location_terms())]
    if offset is not None:
        d = [a - o for a, o in zip(d, offset)]
    return d


def dot(v1: Vector, v2: Vector) -> sp.Expr:
    """``u_1 . u_2``."""
    return (v1.direction().T * v2.direction())[0, 0]


def distance_squared(p1: Point, p2: Point, dist) -> sp.Expr:
    """``(r_1 - r_2).(r_1 - r_2) - dist^2``."""
    d = p1.location() - p2.location()
    return (d.T * d)[0, 0] - sp.sympify(dist) ** 2


def normals(space, v: Vector) -> list[sp.Matrix]:
    """Global directions orthogonal to ``v``: one in 2D, two in 3D.

    A body-fixed constant direction gets body-fixed normals (``A h'``), so the equations stay
    regular for every orientation; any other direction gets normals built from its global
    expression.
    """
    if v.is_local_constant() and v.body is not None:
        return [v.body.A * h for h in space.perpendiculars(v.local)]
    if v.is_local_constant():
        return space.perpendiculars(v.local)
    return space.perpendiculars(v.direction())


def point_on_line(space, p: Point, axis: Axis, dist=0) -> list[sp.Expr]:
    r""":math:`n_k \cdot (r_p - r_o) = 0` for each normal ``n_k`` of the axis (2D: minus ``dist |u|``)."""
    d = p.location() - axis.location()
    eqs = [(n.T * d)[0, 0] for n in normals(space, axis.dir)]
    if dist != 0:
        u = axis.dir.local if axis.dir.local is not None else axis.direction()
        eqs[0] = eqs[0] - sp.sympify(dist) * sp.sqrt((u.T * u)[0, 0])
    return eqs


def parallel(space, v1: Vector, v2: Vector) -> list[sp.Expr]:
    r"""``n_k . u_1 = 0`` for each normal ``n_k`` of ``v2`` (2D: :math:`u_2 \times u_1 = 0`)."""
    u1 = v1.direction()
    return [(n.T * u1)[0, 0] for n in normals(space, v2)]
