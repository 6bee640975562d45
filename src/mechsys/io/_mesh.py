r"""Triangle meshes from files (STL, OBJ, MuJoCo's MSH) and their mass properties.

Reading is strict (files from strangers): a file larger than :data:`MAX_MESH_BYTES`, more
than :data:`MAX_MESH_TRIANGLES` triangles, a binary STL whose size disagrees with its
triangle count (truncated), an ASCII STL whose ``vertex`` lines are not three numbers, an
OBJ face naming a vertex that does not exist, an MSH whose header disagrees with its size,
and non-finite coordinates are refused with a :class:`~mechsys.ModelError` naming the file
and what is wrong. Coordinates are rounded to single precision, as MuJoCo stores them (its
mass properties are those of the rounded vertices).

Mass properties (:func:`mesh_mass_properties`) follow MuJoCo's ``<mesh inertia=...>`` modes
(decision 0072). For a closed surface of triangles :math:`(a_k, b_k, c_k)` wound
counter-clockwise seen from outside, the divergence theorem turns the volume integrals into
a sum over tetrahedra :math:`(p, a_k, b_k, c_k)` from any apex :math:`p` (Mirtich, "Fast and
accurate computation of polyhedral mass properties", J. Graphics Tools 1(2), 1996; Eberly,
"Polyhedral mass properties (revisited)", Geometric Tools, 2002); with the corners taken
relative to :math:`p`,

.. math::

    V_k = \tfrac16\, a_k \cdot (b_k \times c_k), \qquad
    \int_{T_k} x\, dV = V_k\, \tfrac{a_k + b_k + c_k}{4}, \qquad
    \int_{T_k} x x^T dV = \tfrac{V_k}{20}\bigl(a a^T + b b^T + c c^T + s s^T\bigr)_k,
    \quad s = a + b + c

(the last one the tetrahedron's second moment, Tonon, "Explicit exact formulas for the 3-D
tetrahedron inertia tensor in terms of its vertex coordinates", J. Math. Stat. 1(1), 2004),
and the inertia about the centroid is :math:`J = \operatorname{tr}(S)\, 1 - S` of the
second moment :math:`S` about it. ``exact`` sums the signed :math:`V_k`; ``convex`` does so
on the convex hull (SciPy's Qhull); ``legacy`` (MuJoCo's default up to at least 4.0) sums
:math:`|V_k|`, first from the area-weighted centre of the faces (volume and centroid), then
from the centroid (second moments and the volume that gives the mass), which counts the
solid twice where a tetrahedron leaves a non-convex mesh; ``shell`` puts the mass on the
surface, :math:`\int_{\triangle} x x^T dA = \tfrac{A}{12}(a a^T + b b^T + c c^T + s s^T)`.

Example::

    V, F = load_mesh(Path("link.stl"))
    volume, centroid, J = mesh_mass_properties(V, F, "legacy", "link.stl")
    mass, inertia = 1000 * volume, 1000 * J          # density 1000
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from .._errors import ModelError

#: a mesh file larger than this (bytes) is refused
MAX_MESH_BYTES = 100_000_000
#: a mesh with more triangles than this is refused
MAX_MESH_TRIANGLES = 2_000_000
#: MuJoCo's smallest volume (``mjMINVAL``): a mesh enclosing less is refused
MIN_VOLUME = 1e-15
#: the modes of MuJoCo's ``<mesh inertia=...>``
INERTIA_MODES = ("legacy", "convex", "exact", "shell")


def load_mesh(path: Path, label: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (k, 3) float, faces (f, 3) int)`` of an STL (binary or ASCII), OBJ
    (polygons fanned into triangles, negative indices counted from the end) or MuJoCo MSH
    file, the coordinates rounded to single precision. An MSH without faces gets its convex
    hull's, as in MuJoCo. ``label`` names the file in errors (default: its path).

    Raises :class:`~mechsys.ModelError` naming the file and what is wrong (see the module doc).
    """
    label = label or str(path)
    path = Path(path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise ModelError(f"mesh file {label!r} cannot be read: {exc.strerror or exc}") from None
    if not path.is_file():
        raise ModelError(f"mesh file {label!r} is not a regular file")
    if size > MAX_MESH_BYTES:
        raise ModelError(f"mesh file {label!r}: {size} bytes, more than the limit of {MAX_MESH_BYTES}")
    data = path.read_bytes()
    suffix = path.suffix.lower()
    if suffix == ".stl":
        V, F = _stl(data, label)
    elif suffix == ".obj":
        V, F = _obj(data, label)
    elif suffix == ".msh":
        V, F = _msh(data, label)
    else:
        raise ModelError(f"mesh file {label!r}: format {suffix or '(none)'!r} is not read (STL, OBJ or "
                         "MSH; convert it, or give the body an <inertial>)")
    if len(F) > MAX_MESH_TRIANGLES:
        raise ModelError(f"mesh file {label!r}: {len(F)} triangles, more than the limit of "
                         f"{MAX_MESH_TRIANGLES}")
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise ModelError(f"mesh file {label!r}: vertex {int(np.argmax(bad)) + 1} has a coordinate that "
                         "is not a finite number (NaN or infinite)")
    return V, F


def _stl(data: bytes, label: str) -> tuple[np.ndarray, np.ndarray]:
    n = struct.unpack("<I", data[80:84])[0] if len(data) >= 84 else -1
    if n >= 0 and len(data) == 84 + 50 * n:
        if n == 0:
            raise ModelError(f"mesh file {label!r}: a binary STL with no triangles")
        rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                            count=n, offset=84)
        tri = rec["v"].reshape(-1, 3).astype(np.float64)
    elif data.lstrip()[:5].lower() == b"solid":
        tri = _ascii_stl(data, label)
    else:
        raise ModelError(f"mesh file {label!r}: a binary STL whose header counts {n if n >= 0 else '?'} "
                         f"triangles ({84 + 50 * max(n, 0)} bytes) has {len(data)} bytes (truncated or "
                         "not an STL file)")
    # shared corners once (their bits compared, as MuJoCo does): faces index distinct vertices
    verts, inv = np.unique(tri, axis=0, return_inverse=True)
    return verts, inv.reshape(-1, 3).astype(np.int64)


def _ascii_stl(data: bytes, label: str) -> np.ndarray:
    rows = []
    for k, ln in enumerate(data.decode("ascii", "replace").splitlines(), 1):
        tok = ln.split()
        if tok and tok[0] == "vertex":
            if len(tok) != 4:
                raise ModelError(f"mesh file {label!r}, line {k}: a vertex line has three numbers")
            try:
                rows.append([float(t) for t in tok[1:]])
            except ValueError:
                raise ModelError(f"mesh file {label!r}, line {k}: vertex {' '.join(tok[1:])!r} is not "
                                 "three numbers") from None
    if not rows:
        raise ModelError(f"mesh file {label!r}: an ASCII STL with no vertex lines")
    if len(rows) % 3:
        raise ModelError(f"mesh file {label!r}: {len(rows)} vertex lines, not a multiple of three "
                         "(truncated?)")
    return np.array(rows, dtype=np.float32).astype(np.float64)


def _obj(data: bytes, label: str) -> tuple[np.ndarray, np.ndarray]:
    verts, tris = [], []
    for k, ln in enumerate(data.decode("ascii", "replace").splitlines(), 1):
        tok = ln.split()
        if not tok:
            continue
        if tok[0] == "v":
            try:
                verts.append([float(t) for t in tok[1:4]])
            except ValueError:
                raise ModelError(f"mesh file {label!r}, line {k}: vertex {' '.join(tok[1:4])!r} is not "
                                 "three numbers") from None
            if len(verts[-1]) != 3:
                raise ModelError(f"mesh file {label!r}, line {k}: a vertex has three coordinates")
        elif tok[0] == "f":
            try:
                idx = [int(t.split("/")[0]) for t in tok[1:]]
            except ValueError:
                raise ModelError(f"mesh file {label!r}, line {k}: face {' '.join(tok[1:])!r} is not "
                                 "vertex numbers") from None
            # negative indices count back from the vertices read so far (the OBJ rule)
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
            if len(idx) < 3 or min(idx) < 0 or max(idx) >= len(verts) or len(verts) in idx:
                raise ModelError(f"mesh file {label!r}, line {k}: face {' '.join(tok[1:])!r} names a vertex "
                                 f"that does not exist ({len(verts)} read so far) or has fewer than three")
            tris += [(idx[0], idx[i], idx[i + 1]) for i in range(1, len(idx) - 1)]
            if len(tris) > MAX_MESH_TRIANGLES:
                raise ModelError(f"mesh file {label!r}: more than the limit of {MAX_MESH_TRIANGLES} "
                                 "triangles")
    if not verts or not tris:
        raise ModelError(f"mesh file {label!r}: an OBJ file with no vertices or no faces")
    V = np.array(verts, dtype=np.float32).astype(np.float64)
    return V, np.array(tris, dtype=np.int64).reshape(-1, 3)


def _msh(data: bytes, label: str) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's binary MSH: four int32 counts (vertices, normals, texture coordinates,
    faces), then the vertices, normals (float32 x 3), texture coordinates (float32 x 2) and
    faces (int32 x 3)."""
    if len(data) < 16:
        raise ModelError(f"mesh file {label!r}: an MSH file shorter than its 16-byte header")
    nv, nn, nt, nf = struct.unpack("<4i", data[:16])
    if nv < 4 or nf < 0 or nn not in (0, nv) or nt not in (0, nv):
        raise ModelError(f"mesh file {label!r}: MSH header counts ({nv} vertices, {nn} normals, {nt} "
                         f"texture coordinates, {nf} faces) are not valid")
    want = 16 + 4 * (3 * nv + 3 * nn + 2 * nt + 3 * nf)
    if len(data) != want:
        raise ModelError(f"mesh file {label!r}: an MSH file whose header asks for {want} bytes has "
                         f"{len(data)} (truncated or corrupt)")
    V = np.frombuffer(data, "<f4", 3 * nv, 16).reshape(-1, 3).astype(np.float64)
    if nf == 0:
        return V, hull_faces(V, label)
    at = 16 + 4 * (3 * nv + 3 * nn + 2 * nt)
    F = np.frombuffer(data, "<i4", 3 * nf, at).reshape(-1, 3).astype(np.int64)
    if F.min() < 0 or F.max() >= nv:
        raise ModelError(f"mesh file {label!r}: an MSH face names a vertex that does not exist")
    return V, F


def hull_faces(V: np.ndarray, label: str) -> np.ndarray:
    """The triangles of the convex hull of ``V``, wound counter-clockwise seen from outside
    (SciPy's Qhull)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(V)
    except (QhullError, ValueError) as exc:
        raise ModelError(f"mesh {label!r}: its convex hull has no volume (the vertices are coplanar or "
                         f"fewer than four): {str(exc).splitlines()[0]}") from None
    F = hull.simplices.astype(np.int64)
    # Qhull's simplices are not consistently wound: turn each to face away from the hull's
    # interior (its facet normals point outwards)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), hull.equations[:, :3]) < 0
    F[flip] = F[flip][:, [0, 2, 1]]
    return F


def _second_moments(a, b, c, w) -> np.ndarray:
    """:math:`\\sum_k w_k (a a^T + b b^T + c c^T + s s^T)_k`, ``s = a + b + c``."""
    s = a + b + c
    return np.einsum("k,ki,kj->ij", w, a, a) + np.einsum("k,ki,kj->ij", w, b, b) + \
        np.einsum("k,ki,kj->ij", w, c, c) + np.einsum("k,ki,kj->ij", w, s, s)


def mesh_mass_properties(V: np.ndarray, F: np.ndarray, mode: str = "legacy",
                         label: str = "mesh") -> tuple[float, np.ndarray, np.ndarray]:
    r"""``(volume, centroid, J)`` of the solid (or, ``mode="shell"``, the surface: its area)
    bounded by the triangles ``F`` of the vertices ``V``, with ``J`` the inertia about the
    centroid at unit density (multiply both by the density), as MuJoCo's ``<mesh
    inertia=mode>`` computes them (module doc).

    Refused with :class:`~mechsys.ModelError` naming ``label``: a mesh of zero area or
    volume (coplanar triangles, an open sheet), in ``exact`` mode an inside-out one (faces
    wound clockwise seen from outside: negative volume), inertia with a non-positive
    principal moment or one violating :math:`A + B \ge C` (MuJoCo's checks).

    Example::

        >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
        >>> F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
        >>> vol, c, J = mesh_mass_properties(V, F, "exact")
        >>> round(vol * 6, 12), np.round(c * 4, 12).tolist()
        (1.0, [1.0, 1.0, 1.0])
    """
    if mode not in INERTIA_MODES:
        raise ModelError(f"mesh {label!r}: inertia={mode!r} is one of {', '.join(INERTIA_MODES)}")
    V = np.asarray(V, float)
    F = np.asarray(F, np.int64)
    if mode == "convex":
        F = hull_faces(V, label)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    n2 = np.cross(b - a, c - a)                     # twice the area times the unit normal
    area = 0.5 * np.linalg.norm(n2, axis=1)
    centre = (a + b + c) / 3
    total_area = area.sum()
    if not total_area > MIN_VOLUME:
        raise ModelError(f"mesh {label!r}: its triangles have no area (a degenerate mesh)")
    facecen = area @ centre / total_area
    if mode == "shell":
        # the surface's centroid, then its second moments about it
        com = facecen
        a0, b0, c0 = a - com, b - com, c - com
        S = _second_moments(a0, b0, c0, area / 12)
        size = total_area
    else:
        def tets(p):
            """Signed volumes of the tetrahedra from ``p``, and the corners relative to it."""
            a0, b0, c0 = a - p, b - p, c - p
            return np.einsum("ij,ij->i", a0, np.cross(b0, c0)) / 6, a0, b0, c0

        vol, *_ = tets(facecen)
        if mode == "legacy":
            vol = np.abs(vol)
        size = vol.sum()
        if size < 0:
            raise ModelError(f"mesh {label!r}: its volume is negative ({size:.3g}): the faces are wound "
                             "inside out (clockwise seen from outside); turn them, or use inertia='legacy' "
                             "or 'convex'")
        if size < MIN_VOLUME:
            raise ModelError(f"mesh {label!r}: it encloses no volume ({size:.3g}; an open or flat mesh); "
                             "give it inertia='shell' or give the body an <inertial>")
        # the tetrahedra's centroids are (apex + a + b + c) / 4
        com = facecen + vol @ ((a - facecen) + (b - facecen) + (c - facecen)) / 4 / size
        vol, a0, b0, c0 = tets(com)
        if mode == "legacy":
            vol = np.abs(vol)
        size = vol.sum()
        S = _second_moments(a0, b0, c0, vol / 20)
    J = np.trace(S) * np.eye(3) - S
    J = 0.5 * (J + J.T)
    ev = np.linalg.eigvalsh(J)
    if ev[-1] <= 0 or ev[0] <= -1e-12 * ev[-1]:
        raise ModelError(f"mesh {label!r}: its inertia has a principal moment <= 0 ({ev.tolist()})")
    if ev[0] + ev[1] < ev[2] * (1 - 1e-6) - 1e-9:
        raise ModelError(f"mesh {label!r}: its principal moments {ev.tolist()} violate A + B >= C")
    return float(size), com, J


def signed_volume(V: np.ndarray, F: np.ndarray) -> float:
    r"""The volume enclosed by the triangles, :math:`\tfrac16 \sum_k a_k \cdot (b_k \times c_k)`:
    negative when they are wound inside out, the enclosed volume when the surface is closed
    and wound counter-clockwise seen from outside (whatever its convexity)."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    p = V.mean(axis=0)                  # any apex; the centre of the points keeps it well scaled
    return float(np.einsum("ij,ij->i", a - p, np.cross(b - p, c - p)).sum() / 6)
