"""Numeric shape builders: outlines (2D) and meshes (3D) in local coordinates.

Meshes are ``(vertices (V, 3), faces)`` with faces a list of vertex-index tuples (quads and
triangles), outward-facing when closed. Nothing here knows about bodies or SymPy.
"""

from __future__ import annotations

import numpy as np


def unit(v, what: str = "direction") -> np.ndarray:
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    if not np.isfinite(n) or n == 0:
        from .._errors import GeometryError

        raise GeometryError(f"{what} has zero length")
    return v / n


def perpendicular_frame(w) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orthonormal ``(u, v, w)`` with ``w`` along the given direction (right-handed)."""
    w = unit(w)
    k = int(np.argmin(np.abs(w)))
    e = np.zeros(3)
    e[k] = 1.0
    u = np.cross(e, w)
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    return u, v, w


def circle(center, radius: float, n: int = 32) -> np.ndarray:
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.asarray(center, dtype=float) + radius * np.c_[np.cos(a), np.sin(a)]


def stadium(p1, p2, width: float, n: int = 10) -> np.ndarray:
    """Outline of a bar with round ends around the segment ``p1 p2`` (batched over leading
    axes: ``p1, p2`` of shape ``(..., 2)`` give ``(..., V, 2)``)."""
    p1 = np.asarray(p1, dtype=float)
    p2 = np.asarray(p2, dtype=float)
    d = p2 - p1
    L = np.linalg.norm(d, axis=-1, keepdims=True)
    safe = np.where(L > 0, L, 1.0)
    u = np.where(L > 0, d / safe, np.array([1.0, 0.0]))
    nrm = np.stack([-u[..., 1], u[..., 0]], axis=-1)
    r = width / 2
    # half circle at p2 from +n to -n through +u, then at p1 from -n to +n through -u
    a = np.linspace(np.pi / 2, -np.pi / 2, n)
    c, s = np.cos(a)[:, None], np.sin(a)[:, None]
    end2 = p2[..., None, :] + r * (c * u[..., None, :] + s * nrm[..., None, :])
    end1 = p1[..., None, :] + r * (-c * u[..., None, :] - s * nrm[..., None, :])
    return np.concatenate([end2, end1], axis=-2)


def rectangle(c1, c2) -> np.ndarray:
    (x1, y1), (x2, y2) = c1, c2
    return np.array([[x1, y1], [x2, y1], [x2, y2], [x1, y2]], dtype=float)


def convex_hull_2d(pts: np.ndarray) -> np.ndarray:
    """Indices of the convex hull, counter-clockwise (monotone chain)."""
    pts = np.asarray(pts, dtype=float)
    order = sorted(range(len(pts)), key=lambda i: (pts[i, 0], pts[i, 1]))

    def cross(o, a, b):
        return (pts[a, 0] - pts[o, 0]) * (pts[b, 1] - pts[o, 1]) - (
            pts[a, 1] - pts[o, 1]) * (pts[b, 0] - pts[o, 0])

    lower: list[int] = []
    for i in order:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], i) <= 1e-12:
            lower.pop()
        lower.append(i)
    upper: list[int] = []
    for i in reversed(order):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], i) <= 1e-12:
            upper.pop()
        upper.append(i)
    return np.array(lower[:-1] + upper[:-1], dtype=int)


def spanning_tree(pts: np.ndarray) -> list[tuple[int, int]]:
    """Edges of the Euclidean minimum spanning tree (Prim), for drawing a body's points."""
    n = len(pts)
    if n < 2:
        return []
    inside = [0]
    edges = []
    rest = set(range(1, n))
    while rest:
        best = None
        for i in inside:
            for j in rest:
                d = float(np.linalg.norm(pts[i] - pts[j]))
                if best is None or d < best[0]:
                    best = (d, i, j)
        _, i, j = best
        edges.append((i, j))
        inside.append(j)
        rest.remove(j)
    return edges


# -- 3D meshes ----------------------------------------------------------------------------
def box(c1, c2):
    """Axis-aligned box with diagonal corners ``c1``, ``c2``."""
    (x1, y1, z1), (x2, y2, z2) = np.minimum(c1, c2), np.maximum(c1, c2)
    v = np.array([[x1, y1, z1], [x2, y1, z1], [x2, y2, z1], [x1, y2, z1],
                  [x1, y1, z2], [x2, y1, z2], [x2, y2, z2], [x1, y2, z2]], dtype=float)
    f = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    return v, f


def oriented_box(center, u, v, w, a: float, b: float, c: float):
    """Box of half-sizes ``a, b, c`` along orthonormal ``u, v, w`` around ``center``."""
    verts, faces = box((-a, -b, -c), (a, b, c))
    R = np.c_[u, v, w]
    return np.asarray(center, dtype=float) + verts @ R.T, faces


def beam(p1, p2, width: float, thickness: float | None = None, extend: float | None = None):
    """Rectangular bar from ``p1`` to ``p2`` (3D), extended past the ends by ``extend``
    (default half the width) so the joints at the ends are covered."""
    p1, p2 = np.asarray(p1, dtype=float), np.asarray(p2, dtype=float)
    thickness = width if thickness is None else thickness
    extend = width / 2 if extend is None else extend
    u, v, w = perpendicular_frame(p2 - p1)  # w along the bar
    L = float(np.linalg.norm(p2 - p1))
    center = (p1 + p2) / 2
    return oriented_box(center, u, v, w, width / 2, thickness / 2, L / 2 + extend)


def revolve(profile, origin=(0, 0, 0), direction=(0, 0, 1), n: int = 24,
            angle: float = 2 * np.pi):
    """Surface of revolution of a profile of ``(radius, height)`` points about an axis."""
    prof = np.asarray(profile, dtype=float).reshape(-1, 2)
    u, v, w = perpendicular_frame(direction)
    full = np.isclose(angle, 2 * np.pi)
    m = n if full else n + 1
    a = np.linspace(0, angle, m, endpoint=not full)
    verts = []
    for r, h in prof:
        for t in a:
            verts.append(np.asarray(origin) + r * (np.cos(t) * u + np.sin(t) * v) + h * w)
    faces = []
    for i in range(len(prof) - 1):
        for j in range(n):
            j2 = (j + 1) % m if full else j + 1
            a0, a1 = i * m + j, i * m + j2
            b0, b1 = (i + 1) * m + j, (i + 1) * m + j2
            faces.append((a0, a1, b1, b0))
    return np.array(verts, dtype=float), faces


def cylinder(p1, p2, radius: float, n: int = 20, caps: bool = True):
    p1, p2 = np.asarray(p1, dtype=float), np.asarray(p2, dtype=float)
    L = float(np.linalg.norm(p2 - p1))
    prof = [(radius, 0.0), (radius, L)]
    if caps:
        prof = [(0.0, 0.0)] + prof + [(0.0, L)]
    return revolve(prof, p1, p2 - p1, n)


def sphere(center, radius: float, n: int = 16):
    a = np.linspace(-np.pi / 2, np.pi / 2, max(n // 2, 3) + 1)
    prof = np.c_[radius * np.cos(a), radius * np.sin(a)]
    prof[0, 0] = prof[-1, 0] = 0.0
    return revolve(prof, center, (0, 0, 1), n)


def torus(center, major: float, minor: float, direction=(0, 0, 1), n: int = 24, m: int = 12):
    a = np.linspace(0, 2 * np.pi, m + 1)
    prof = np.c_[major + minor * np.cos(a), minor * np.sin(a)]
    return revolve(prof, center, direction, n)


def extrude(points, vector, closed: bool = False, caps: bool = True):
    """Side faces between the polyline ``points (k, 3)`` and its copy moved by ``vector``;
    a closed outline also gets its two cap polygons when ``caps``."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    k = len(p)
    verts = np.vstack([p, p + np.asarray(vector, dtype=float)])
    faces = []
    for i in range(k if closed else k - 1):
        j = (i + 1) % k
        faces.append((i, j, k + j, k + i))
    if closed and caps and k >= 3:
        faces.append(tuple(range(k - 1, -1, -1)))
        faces.append(tuple(range(k, 2 * k)))
    return verts, faces


def cone(base, tip, radius, n: int = 10):
    """A closed cone (batched: ``base, tip`` of shape ``(N, 3)`` and ``radius`` scalar or
    ``(N,)`` give ``(N, n + 2, 3)``)."""
    base = np.atleast_2d(np.asarray(base, dtype=float))
    tip = np.atleast_2d(np.asarray(tip, dtype=float))
    d = tip - base
    L = np.linalg.norm(d, axis=1, keepdims=True)
    w = np.where(L > 0, d / np.where(L > 0, L, 1), np.array([0, 0, 1.0]))
    e = np.zeros_like(w)
    e[np.arange(len(w)), np.argmin(np.abs(w), axis=1)] = 1.0
    u = np.cross(e, w)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(w, u)
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    radius = np.asarray(radius, dtype=float).reshape(-1, 1, 1)
    ring = base[:, None, :] + radius * (np.cos(a)[None, :, None] * u[:, None, :]
                                        + np.sin(a)[None, :, None] * v[:, None, :])
    verts = np.concatenate([ring, tip[:, None, :], base[:, None, :]], axis=1)
    faces = [(i, (i + 1) % n, n) for i in range(n)] + [((i + 1) % n, i, n + 1) for i in range(n)]
    return verts, faces
