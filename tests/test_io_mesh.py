"""Mesh geoms' mass properties in ``ms.from_mjcf`` (decision 0072): closed forms, MuJoCo's
compiled model and ``mj_inverse`` on small hand-written files, and refusals of bad files.

The mesh is an L-shaped prism (not convex, so MuJoCo's ``legacy`` mode, its default, differs
from the solid's ``exact`` volume): its closed forms are those of two boxes.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest

import mechsys as ms
from mechsys.io._mesh import load_mesh, mesh_mass_properties

S, H = 0.05, 0.04                                   # the L's unit and its thickness
POLY = np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 3), (0, 3)], float) * S


def ell():
    """Vertices and outward-wound triangles of the L prism (z from 0 to H)."""
    n = len(POLY)
    V = np.vstack([np.c_[POLY, np.zeros(n)], np.c_[POLY, np.full(n, H)]])
    F = []
    for k in range(1, n - 1):                       # a fan from corner 0 (it sees every corner)
        F += [(0, k + 1, k), (n, n + k, n + k + 1)]  # bottom facing -z, top +z
    for i in range(n):
        j = (i + 1) % n
        F += [(i, j, n + j), (i, n + j, n + i)]     # sides: edge x z points outwards
    return V, np.array(F)


def boxes_closed_form():
    """Volume, centroid and inertia (unit density) of the L as two boxes."""
    parts = [((0, 0, 0), (2 * S, S, H)), ((0, S, 0), (S, 2 * S, H))]
    vol = sum(np.prod(d) for _, d in parts)
    c = sum(np.prod(d) * (np.array(o) + np.array(d) / 2) for o, d in parts) / vol
    J = np.zeros((3, 3))
    for o, d in parts:
        m, r = np.prod(d), np.array(o) + np.array(d) / 2 - c
        a, b, h = d
        J += m / 12 * np.diag([b * b + h * h, a * a + h * h, a * a + b * b])
        J += m * (r @ r * np.eye(3) - np.outer(r, r))
    return vol, c, J


def write_stl(path, V, F):
    path.write_bytes(b"\0" * 80 + struct.pack("<I", len(F)) + b"".join(
        struct.pack("<12fH", 0, 0, 0, *V[f].ravel(), 0) for f in F))


def write_obj(path, V, F):
    path.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F))


def write_msh(path, V, F):
    path.write_bytes(struct.pack("<4i", len(V), 0, 0, len(F)) + np.asarray(V, "<f4").tobytes()
                     + np.asarray(F, "<i4").tobytes())


def test_mass_properties_closed_forms():
    """``exact`` and ``convex`` against two boxes and the hull, ``shell`` against a hollow
    cube (5/18 m s^2), ``legacy`` counting more than the solid on the L (not convex) and
    the same on the cube; an inside-out mesh: the same in ``legacy``, refused in ``exact``."""
    V, F = ell()
    V32 = V.astype(np.float32).astype(float)
    vol, c, J = mesh_mass_properties(V32, F, "exact")
    vol0, c0, J0 = boxes_closed_form()
    assert vol == pytest.approx(vol0, rel=1e-6)            # single-precision corners
    np.testing.assert_allclose(c, c0, rtol=0, atol=1e-8)
    np.testing.assert_allclose(J, J0, rtol=0, atol=1e-6 * np.abs(J0).max())
    # the convex hull of the L: the hexagon (0,0) (2,0) (2,1) (1,3) (0,3) extruded
    hv, _, _ = mesh_mass_properties(V32, F, "convex")
    assert hv == pytest.approx((vol0 / H + 0.5 * S * 2 * S) * H, rel=1e-6)
    lv, _, _ = mesh_mass_properties(V32, F, "legacy")
    assert lv > vol * (1 + 1e-3)
    # a cube of side 2 (centred): legacy = exact = 8, inertia 8 * 4 * 2 / 12; its surface
    cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    Fc = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                   [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    for mode in ("legacy", "exact", "convex"):
        v, cc, Jc = mesh_mass_properties(cube, Fc, mode)
        assert v == pytest.approx(8, rel=1e-14)
        np.testing.assert_allclose(Jc, np.eye(3) * 8 * 8 / 12, atol=1e-13)
    area, cc, Js = mesh_mass_properties(cube, Fc, "shell")
    assert area == pytest.approx(24, rel=1e-14)
    np.testing.assert_allclose(Js, np.eye(3) * 24 * 5 / 18 * 4, atol=1e-12)
    inside_out = Fc[:, [0, 2, 1]]
    assert mesh_mass_properties(cube, inside_out, "legacy")[0] == pytest.approx(8, rel=1e-14)
    with pytest.raises(ms.ModelError, match="'box.stl'.*inside out"):
        mesh_mass_properties(cube, inside_out, "exact", "box.stl")


ARM = """<mujoco>
  <compiler angle="radian" meshdir="m"/>
  <asset>
    <mesh name="ell" file="ell.stl" scale="1.2 -0.8 1.1" refpos="0.01 -0.02 0.005"
          refquat="0.9 0.1 -0.2 0.3" inertia="MODE"/>
    <mesh name="ellobj" file="ell.obj" inertia="MODE"/>
    <mesh name="ellmsh" file="ell.msh" scale="0.7 0.7 0.7" inertia="MODE"/>
  </asset>
  <worldbody>
    <body name="upper" pos="0 0 0.3" quat="0.9 0.1 0.3 0.2">
      <joint name="shoulder" axis="0 1 0"/>
      <geom type="mesh" mesh="ell" pos="0.05 0 0.02" euler="0.3 -0.4 0.7" density="700"/>
      <body name="fore" pos="0.2 0 0">
        <joint name="elbow" axis="1 0 0.3"/>
        <geom type="mesh" mesh="ellobj" mass="0.4" quat="0 1 0 0"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/>
        <geom type="mesh" mesh="ellmsh" pos="0 0.05 0" density="300"/>
        <body name="hand" pos="0.1 0 0">
          <joint name="wrist" axis="0 0 1"/>
          <geom type="mesh" mesh="ell" density="500" pos="0.02 0 0"/>
          <body name="finger" pos="0.05 0.02 0" euler="0.2 0.1 0">
            <joint name="knuckle" axis="0 1 0"/>
            <geom type="mesh" mesh="ellmsh" density="900" euler="0 0.5 0"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def _arm(tmp_path, mode):
    V, F = ell()
    (tmp_path / "m").mkdir(exist_ok=True)
    write_stl(tmp_path / "m" / "ell.stl", V, F)
    write_obj(tmp_path / "m" / "ell.obj", V, F)
    write_msh(tmp_path / "m" / "ell.msh", V, F)
    path = tmp_path / f"arm_{mode}.xml"
    path.write_text(ARM.replace("MODE", mode))
    return path


def test_mesh_inertia_against_mujoco(tmp_path):
    """Mass, centroid and inertia of bodies carrying STL, OBJ and MSH meshes (scaled, one
    mirrored, ``refpos``/``refquat``, geoms offset and turned, ``mass`` or ``density``) in
    every ``inertia`` mode against MuJoCo's compiled bodies (mass and centroid 1e-12, the
    principal moments 1e-12, the tensor to MuJoCo's Jacobi tolerance; MuJoCo's ``mju_eig3``
    of ours gives its principal axes), and the legacy file's inverse dynamics against
    ``mj_inverse`` (1e-9)."""
    mujoco = pytest.importorskip("mujoco")
    for mode in ("legacy", "exact", "convex", "shell"):
        if mode == "shell":
            path = _arm(tmp_path, "legacy")
            path.write_text(ARM.replace('inertia="MODE"', 'inertia="shell"'))
        else:
            path = _arm(tmp_path, mode)
        m = ms.from_mjcf(path, geometry=False)
        mm = mujoco.MjModel.from_xml_path(str(path))
        for k in range(1, mm.nbody):
            b = mm.body(k)
            mb = m.body(b.name)
            I = np.array(mb.inertia, float)
            assert float(mb.mass) == pytest.approx(b.mass[0], rel=1e-12), (mode, b.name)
            np.testing.assert_allclose(np.array(mb.centroid, float).ravel(), b.ipos, rtol=0, atol=1e-13)
            np.testing.assert_allclose(np.linalg.eigvalsh(I), np.sort(b.inertia), rtol=0,
                                       atol=1e-12 * b.inertia.max())
            R = np.zeros(9)
            mujoco.mju_quat2Mat(R, b.iquat)
            R = R.reshape(3, 3)
            np.testing.assert_allclose(I, R @ np.diag(b.inertia) @ R.T, rtol=0, atol=1e-7 * b.inertia.max())
            if b.name == "upper":               # one geom: MuJoCo's eigen-solver on our tensor
                ev, vec, quat = np.zeros(3), np.zeros(9), np.zeros(4)
                mujoco.mju_eig3(ev, vec, quat, I.ravel())
                assert abs(abs(quat @ b.iquat) - 1) < 1e-12
        if mode == "legacy":
            assert any("'ell.stl' is not convex" in n for n in m.import_report.not_mapped)
            mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
            md = mujoco.MjData(mm)
            rng = np.random.default_rng(72)
            Q, QD, QDD = rng.normal(size=(3, 4))
            md.qpos[:], md.qvel[:], md.qacc[:] = Q, QD, QDD
            mujoco.mj_inverse(mm, md)
            tau = np.ravel(m.inverse_dynamics(Q, QD, QDD).values)
            ref = md.qfrc_inverse
            np.testing.assert_allclose(tau, ref, rtol=0, atol=1e-9 * np.abs(ref).max())


def test_ascii_stl_and_obj_read_as_binary_stl(tmp_path):
    V, F = ell()
    write_stl(tmp_path / "a.stl", V, F)
    write_obj(tmp_path / "a.obj", V, F)
    (tmp_path / "b.stl").write_text("solid ell\n" + "".join(
        "facet normal 0 0 0\nouter loop\n"
        + "".join(f"vertex {x!r} {y!r} {z!r}\n" for x, y, z in V[f].tolist())
        + "endloop\nendfacet\n" for f in F) + "endsolid ell\n")
    ref = mesh_mass_properties(*load_mesh(tmp_path / "a.stl"))
    for name in ("a.obj", "b.stl"):
        got = mesh_mass_properties(*load_mesh(tmp_path / name))
        assert got[0] == pytest.approx(ref[0], rel=1e-14)
        np.testing.assert_allclose(got[2], ref[2], rtol=0, atol=1e-14 * np.abs(ref[2]).max())


def _bad_files(tmp_path):
    V, F = ell()
    good = b"\0" * 80 + struct.pack("<I", len(F)) + b"".join(
        struct.pack("<12fH", 0, 0, 0, *V[f].ravel(), 0) for f in F)
    (tmp_path / "cut.stl").write_bytes(good[:-30])
    Vn = V.copy()
    Vn[3, 1] = np.nan
    write_stl(tmp_path / "nan.stl", Vn, F)
    flat = V.copy()
    flat[:, 2] = 0
    write_stl(tmp_path / "flat.stl", flat, F)
    write_stl(tmp_path / "turned.stl", V, F[:, [0, 2, 1]])
    (tmp_path / "index.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
    write_msh(tmp_path / "short.msh", V, F)
    (tmp_path / "short.msh").write_bytes((tmp_path / "short.msh").read_bytes()[:-4])
    (tmp_path / "part.dae").write_text("<COLLADA/>")


@pytest.mark.parametrize("file, mode, match", [
    ("cut.stl", "legacy", r"'cut.stl'.*header counts 20 triangles.*truncated"),
    ("nan.stl", "legacy", r"'nan.stl'.*not a finite number"),
    ("flat.stl", "legacy", r"'flat.stl'.*encloses no volume.*shell"),
    ("turned.stl", "exact", r"'turned.stl'.*inside out"),
    ("index.obj", "legacy", r"'index.obj', line 4: face .* does not exist"),
    ("short.msh", "legacy", r"'short.msh'.*truncated or corrupt"),
    ("part.dae", "legacy", r"'part.dae'.*'.dae' is not read"),
])
def test_bad_mesh_files_name_file_and_fault(tmp_path, file, mode, match):
    _bad_files(tmp_path)
    (tmp_path / "model.xml").write_text(
        f'<mujoco><asset><mesh name="m" file="{file}" inertia="{mode}"/></asset><worldbody>'
        '<body name="b"><joint name="j"/><geom type="mesh" mesh="m"/></body></worldbody></mujoco>')
    with pytest.raises(ms.ModelError, match=match) as exc:
        ms.from_mjcf(tmp_path / "model.xml")
    assert "model.xml, line 1" in str(exc.value)       # the geom whose mass needed the file


def test_size_limit_and_inside_out_legacy(tmp_path, monkeypatch):
    """A file over the size limit is refused before it is read; an inside-out mesh in MuJoCo's
    legacy mode weighs what the solid does (MuJoCo takes absolute volumes), noted."""
    from mechsys.io import _mesh

    _bad_files(tmp_path)
    monkeypatch.setattr(_mesh, "MAX_MESH_BYTES", 100)
    with pytest.raises(ms.ModelError, match=r"'turned.stl': \d+ bytes, more than the limit of 100"):
        load_mesh(tmp_path / "turned.stl", "turned.stl")
    monkeypatch.undo()
    V, F = ell()
    write_stl(tmp_path / "right.stl", V, F)
    masses, notes = [], []
    for f in ("turned.stl", "right.stl"):
        (tmp_path / "model.xml").write_text(
            f'<mujoco><asset><mesh name="m" file="{f}"/></asset><worldbody><body name="b">'
            '<joint name="j"/><geom type="mesh" mesh="m"/></body></worldbody></mujoco>')
        m = ms.from_mjcf(tmp_path / "model.xml", geometry=False)
        masses.append(float(m.body("b").mass))
        notes.append(" ".join(m.import_report.not_mapped))
    assert masses[0] == pytest.approx(masses[1], rel=1e-14)
    assert "'turned.stl' is wound inside out" in notes[0] and "inside out" not in notes[1]


def test_inline_vertices_and_msh_without_faces_take_the_hull(tmp_path):
    """A ``<mesh vertex=...>`` without faces and an MSH file without faces are their convex
    hull, as in MuJoCo: mass and centroid against MuJoCo's compiled bodies (1e-12)."""
    mujoco = pytest.importorskip("mujoco")
    V, _ = ell()
    write_msh(tmp_path / "pts.msh", V, np.zeros((0, 3), int))
    verts = " ".join(f"{x!r}" for x in V.ravel().tolist())
    path = tmp_path / "hull.xml"
    path.write_text(f"""<mujoco><asset><mesh name="pts" vertex="{verts}"/><mesh file="pts.msh"
      scale="1 2 1"/></asset><worldbody>
      <body name="a"><joint name="ja"/><geom type="mesh" mesh="pts" density="500" euler="10 20 30"/></body>
      <body name="b" pos="1 0 0"><joint name="jb"/><geom type="mesh" mesh="pts.msh" pos="0 0.1 0"/></body>
      </worldbody></mujoco>""".replace('mesh="pts.msh"', 'mesh="pts_1"').replace(
        'file="pts.msh"', 'name="pts_1" file="pts.msh"'))
    m = ms.from_mjcf(path, geometry=False)
    mm = mujoco.MjModel.from_xml_path(str(path))
    for name in ("a", "b"):
        b = mm.body(name)
        assert float(m.body(name).mass) == pytest.approx(b.mass[0], rel=1e-12)
        np.testing.assert_allclose(np.array(m.body(name).centroid, float).ravel(), b.ipos, atol=1e-13)
