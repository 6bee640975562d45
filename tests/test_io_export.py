"""Export of tree models (``m.to_urdf``, ``m.to_mjcf``), decision 0040: import -> export ->
import gives the same dynamics, MuJoCo reading the exported MJCF agrees with mechsys, the
exported rpy reproduce their rotation, and what the formats cannot hold is refused by name."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys.io._export import matrix_rpy
from mechsys.io._urdf import rpy_matrix
from test_io_mjcf import ZOO
from test_io_urdf import ARM, PANDA, ROBOTS, UR5, needs_robots

RNG = np.random.default_rng(3700)


def _same_dynamics(m1, m2, n, tol=1e-12):
    q, qd, qdd = RNG.normal(size=(3, 3, n))
    t1 = m1.inverse_dynamics(q, qd, qdd).values
    t2 = m2.inverse_dynamics(q, qd, qdd).values
    np.testing.assert_allclose(t2, t1, rtol=0, atol=tol * (1 + np.abs(t1).max()))
    return q, qd, qdd, t1


def _mujoco_inverse_agrees(mujoco, path, q, qd, qdd, tau):
    """MuJoCo reading ``path``: its ``mj_inverse`` equals ``tau`` at each state (1e-9)."""
    mm = mujoco.MjModel.from_xml_path(str(path))
    md = mujoco.MjData(mm)
    for k in range(len(q)):
        md.qpos[:], md.qvel[:], md.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(mm, md)
        np.testing.assert_allclose(md.qfrc_inverse, tau[k], rtol=0, atol=1e-9 * np.abs(tau[k]).max())


def test_matrix_rpy_inverts_rpy_matrix():
    for rpy in [*RNG.uniform(-3, 3, size=(20, 3)), (0.3, np.pi / 2, 0.2), (0.1, -np.pi / 2, -1.0)]:
        R = rpy_matrix(rpy)
        np.testing.assert_allclose(rpy_matrix(matrix_rpy(R)), R, atol=1e-14)


@pytest.mark.parametrize("fmt", ["urdf", "mjcf"])
def test_round_trip_hand_made_files(tmp_path, fmt):
    """The URDF arm (rpy origins, an oblique axis, a prismatic joint, a merged fixed link) and
    the MJCF zoo (frames, several joints per body, geoms' masses): import, export, import."""
    src = tmp_path / "arm.urdf"
    src.write_text(ARM)
    zoo = tmp_path / "zoo.xml"
    zoo.write_text(ZOO)
    for m in (ms.from_urdf(src), ms.from_mjcf(zoo, gravity=9.81)):
        out = tmp_path / f"out.{fmt}"
        if fmt == "urdf" and m.import_report.format == "MJCF":
            with pytest.raises(ms.ModelError, match="gravity"):   # the zoo's gravity is oblique
                m.to_urdf(out)
            continue
        getattr(m, f"to_{fmt}")(out)
        back = (ms.from_urdf if fmt == "urdf" else ms.from_mjcf)(out)
        assert back.compile().layout.q_names == m.compile().layout.q_names
        _same_dynamics(m, back, m.compile().n)


@needs_robots
@pytest.mark.parametrize("rel", [UR5, PANDA])
def test_round_trip_robots_and_mujoco_reads_the_export(tmp_path, rel):
    mujoco = pytest.importorskip("mujoco")
    m = ms.from_urdf(ROBOTS / rel)
    n = m.compile().n
    u = m.to_urdf(tmp_path / "robot.urdf")
    _same_dynamics(m, ms.from_urdf(u), n, tol=0)                   # exact: repr'd doubles
    x = m.to_mjcf(tmp_path / "robot.xml")
    q, qd, qdd, tau = _same_dynamics(m, ms.from_mjcf(x), n)
    _mujoco_inverse_agrees(mujoco, x, q, qd, qdd, tau)


def test_refusals_name_what_cannot_be_written(tmp_path):
    m = ms.Model3D()
    a = m.add_body("a", mass=1, inertia=(0.1, 0.1, 0.1))
    with pytest.raises(ms.ModelError, match="body 'a' has its own"):
        m.to_urdf(tmp_path / "x.urdf")
    m.add(ms.GenCylindrical4(a.axis(0), m.ground.axis((0, 0, 0)), ("s", 0), ("phi", 0)), name="cyl")
    with pytest.raises(ms.ModelError, match="GenCylindrical4"):
        m.to_mjcf(tmp_path / "x.xml")
    m.remove("cyl")
    m.add(ms.GenRevolute5(a.axis(0), m.ground.axis((0, 0, 0)), ("theta", 0)), name="hinge")
    motor = m.add_load(ms.Load(sp.Symbol("theta"), 1.0), name="motor")
    with pytest.raises(ms.ModelError, match="load motor"):
        m.to_mjcf(tmp_path / "x.xml")
    m.remove_load(motor)
    m.add(ms.Constraint(sp.Symbol("theta") - 0.2), name="hold")
    with pytest.raises(ms.ModelError, match="hold"):
        m.to_urdf(tmp_path / "x.urdf")
    with pytest.raises(ms.ModelError, match="spatial"):
        ms.Model2D().to_urdf(tmp_path / "x.urdf")


def test_passive_joint_loads_round_trip_and_mujoco_agrees(tmp_path):
    """The zoo's damping, springs (``springref``) and armature, imported as loads, are written
    back as MJCF joint attributes: reading the export gives the same loads, and MuJoCo's
    ``mj_inverse`` on the export, passive forces and armature included, agrees with mechsys on
    the original (1e-9); URDF holds the damping only and refuses the rest by the load's
    name."""
    mujoco = pytest.importorskip("mujoco")
    zoo = tmp_path / "zoo.xml"
    # (the fore body's two joints: written as one body again, decision 0057)
    zoo.write_text(ZOO)
    kw = dict(joint_damping=True, joint_springs=True, armature=True, geometry=False)
    m = ms.from_mjcf(zoo, **kw)
    out = m.to_mjcf(tmp_path / "out.xml")
    back = ms.from_mjcf(out, **kw)
    assert back.import_report.damping == m.import_report.damping
    assert sorted(ld.name for ld in back.load_list) == sorted(ld.name for ld in m.load_list)
    q, qd, qdd = RNG.normal(size=(3, 3, 4))
    tau = m.inverse_dynamics(q, qd, qdd).values
    mm = mujoco.MjModel.from_xml_path(str(out))
    mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    assert np.all(mm.dof_armature == 0.01) and np.all(mm.dof_damping == 0.2)
    md = mujoco.MjData(mm)
    for k in range(len(q)):
        md.qpos[:], md.qvel[:], md.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(mm, md)
        np.testing.assert_allclose(md.qfrc_inverse, tau[k], rtol=0, atol=1e-9 * np.abs(tau[k]).max())
    with pytest.raises(ms.ModelError, match="load elbow_spring on joint 'elbow'"):
        ms.from_mjcf(zoo, joint_springs=True, gravity=9.81).to_urdf(tmp_path / "x.urdf")
    arm = tmp_path / "arm.urdf"
    arm.write_text(ARM)
    u = ms.from_urdf(arm, joint_damping=True, geometry=False).to_urdf(tmp_path / "back.urdf")
    assert '<dynamics damping="0.4"/>' in u.read_text()
    assert ms.from_urdf(u, joint_damping=True).import_report.damping == {"j1": 0.4}


@pytest.mark.parametrize("case", ["planar", "expanded"])
def test_massless_holders_are_written_as_one_body_mujoco_reads(tmp_path, case):
    """MuJoCo refuses moving bodies without mass: the massless bodies the importers make (a
    body with several MJCF joints, a URDF planar joint's two slides) or a file has (massless
    URDF links between joints) are written as one body holding the chain's joints in order
    (decision 0057). MuJoCo reads the export and its ``mj_inverse`` equals mechsys's joint
    forces on the original (1e-9 relative); reading the export back gives the same joint
    names and dynamics (1e-12). (The zoo's body with two joints: the passive-loads test.)"""
    from test_io_coordinates import EXPANDED, PLANAR

    mujoco = pytest.importorskip("mujoco")
    src = tmp_path / "src.urdf"
    src.write_text({"planar": PLANAR, "expanded": EXPANDED}[case])
    m = ms.from_urdf(src)
    massless = [b.name for b in m.bodies[1:] if float(b.mass) == 0]
    assert massless                                   # the case has holders to merge
    out = m.to_mjcf(tmp_path / "out.xml")
    for name in massless:
        assert f'name="{name}"' not in out.read_text()
    back = ms.from_mjcf(out)
    names = m.compile().layout.q_names
    assert back.compile().layout.q_names == names
    q, qd, qdd, tau = _same_dynamics(m, back, len(names))
    _mujoco_inverse_agrees(mujoco, out, q, qd, qdd, tau)


def test_bodies_mujoco_refuses_are_named(tmp_path):
    """A moving body MuJoCo would refuse (no mass at the end of a chain; a point mass) is
    refused by name before a file is written."""
    for kw, match in [({"mass": 0}, "body 'a' is moved by a joint and has no mass"),
                      ({"mass": 1.0, "centroid": (0.5, 0, 0)},
                       "body 'a' has mass 1.0 and principal moments")]:
        m = ms.Model3D()
        a = m.add_body("a", **kw)
        m.add(ms.GenRevolute5(a.axis((0, 0, 0), (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)),
                              ("q", 0.0)), name="j")
        with pytest.raises(ms.ModelError, match=match):
            m.to_mjcf(tmp_path / "x.xml")
    assert not (tmp_path / "x.xml").exists()
