"""URDF import (``ms.from_urdf``) and the robot-style dynamics (``m.inverse_dynamics``,
``m.forward_dynamics``), decision 0040.

References nobody here wrote: robot files of ``example-robot-data`` (BSD-3, read offline from
the installed package), Pinocchio's forward kinematics, RNEA and ABA, and MuJoCo's
``mj_inverse``/``mj_forward`` on the same files (contacts and limits off, no damping). The
small hand-made file is also checked against a forward-kinematics composition written here
from the URDF specification, and the file reader's refusals name the element and the line.
"""

from __future__ import annotations

import importlib.metadata
import re
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys.io import _xml
from mechsys.io._urdf import normal_to, rpy_matrix

RNG = np.random.default_rng(37)


def _robots() -> Path | None:
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    p = Path(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))
    return p if p.is_dir() else None


ROBOTS = _robots()
needs_robots = pytest.mark.skipif(ROBOTS is None, reason="example-robot-data is not installed")
UR5 = "ur_description/urdf/ur5_robot.urdf"
PANDA = "panda_description/urdf/panda.urdf"


# -- a small file written from the specification -------------------------------------------------
ARM = """<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="l1">
    <inertial><origin xyz="0.1 0.02 0.3" rpy="0.3 -0.2 0.5"/><mass value="2.0"/>
      <inertia ixx="0.05" ixy="0.001" ixz="-0.002" iyy="0.04" iyz="0.003" izz="0.03"/></inertial>
    <visual><origin xyz="0 0 0.2" rpy="0 0.4 0"/><geometry><box size="0.1 0.1 0.4"/></geometry></visual>
  </link>
  <link name="l2">
    <inertial><origin xyz="0.2 0 0" rpy="0 0 0"/><mass value="1.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <visual><geometry><cylinder radius="0.03" length="0.4"/></geometry></visual>
  </link>
  <link name="tool">
    <inertial><origin xyz="0 0 0.05"/><mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.0005"/></inertial>
    <visual><geometry><sphere radius="0.04"/></geometry></visual>
  </link>
  <link name="slide"><inertial><mass value="0.7"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.001"/></inertial></link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1" rpy="0.1 0.2 0.3"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-2" upper="2" effort="10" velocity="3"/><dynamics damping="0.4" friction="0.1"/>
  </joint>
  <joint name="j2" type="continuous">
    <parent link="l1"/><child link="l2"/>
    <origin xyz="0.05 0 0.4" rpy="-0.7 0.1 1.2"/><axis xyz="1 1 0"/>
  </joint>
  <joint name="flange" type="fixed">
    <parent link="l2"/><child link="tool"/><origin xyz="0.4 0 0" rpy="0 1.5707963267948966 0"/>
  </joint>
  <joint name="j3" type="prismatic">
    <parent link="tool"/><child link="slide"/>
    <origin xyz="0 0.02 0.1" rpy="0.2 0 -0.3"/><axis xyz="0 0 -1"/>
    <limit lower="0" upper="0.1" effort="50" velocity="0.2"/>
  </joint>
  <transmission name="t1"/>
</robot>
"""


@pytest.fixture(scope="module")
def arm_file(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("urdf") / "arm.urdf"
    p.write_text(ARM)
    return p


def _rot(axis, angle) -> np.ndarray:
    """Rodrigues' formula."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _arm_fk(q) -> dict:
    """Link frames of ARM at joint coordinates q, by composing the URDF transforms."""
    def T(xyz, rpy):
        M = np.eye(4)
        M[:3, :3] = (_rot((0, 0, 1), rpy[2]) @ _rot((0, 1, 0), rpy[1]) @ _rot((1, 0, 0), rpy[0]))
        M[:3, 3] = xyz
        return M

    def R(axis, a):
        M = np.eye(4)
        M[:3, :3] = _rot(axis, a)
        return M

    def P(axis, s):
        M = np.eye(4)
        M[:3, 3] = s * np.asarray(axis, float) / np.linalg.norm(axis)
        return M

    l1 = T((0, 0, 0.1), (0.1, 0.2, 0.3)) @ R((0, 0.6, 0.8), q[0])
    l2 = l1 @ T((0.05, 0, 0.4), (-0.7, 0.1, 1.2)) @ R((1, 1, 0), q[1])
    tool = l2 @ T((0.4, 0, 0), (0, np.pi / 2, 0))
    slide = tool @ T((0, 0.02, 0.1), (0.2, 0, -0.3)) @ P((0, 0, -1), q[2])
    return {"base": np.eye(4), "l1": l1, "l2": l2, "tool": tool, "slide": slide}


def frame_poses(m, q) -> dict:
    """World 4x4 pose of every link frame of an imported model at coordinates q."""
    links = list(m.import_report.frames)
    return dict(zip(links, m.forward_kinematics(q, links, frame=True)))


# -- rotations -------------------------------------------------------------------------------------
def test_rpy_is_fixed_axis_xyz():
    """URDF rpy: R = Rz(y) Ry(p) Rx(r) (SciPy's extrinsic 'xyz' as the second reference)."""
    from scipy.spatial.transform import Rotation

    for rpy in RNG.uniform(-3, 3, size=(5, 3)):
        ref = _rot((0, 0, 1), rpy[2]) @ _rot((0, 1, 0), rpy[1]) @ _rot((1, 0, 0), rpy[0])
        np.testing.assert_allclose(rpy_matrix(rpy), ref, atol=1e-15)
        np.testing.assert_allclose(rpy_matrix(rpy), Rotation.from_euler("xyz", rpy).as_matrix(), atol=1e-15)
    for a in (np.array([1.0, 0, 0]), np.array([0, 0.6, 0.8]), np.array([0.99, 0.1, 0]) / np.hypot(0.99, 0.1)):
        g = normal_to(a)
        assert abs(g @ a) < 1e-15 and abs(np.linalg.norm(g) - 1) < 1e-15


# -- the small file ---------------------------------------------------------------------------------
def test_arm_file_structure_and_report(arm_file):
    m = ms.from_urdf(arm_file)
    s = m.compile()
    assert s.layout.q_names == ("j1", "j2", "j3") and s.m == 0 and int(m.dof()) == 3
    rep = m.import_report
    assert rep.robot == "arm" and rep.joints["j3"] == ("prismatic", ("j3",), "slide")
    assert rep.frames["tool"][0] == "l2"                    # merged over the fixed joint
    assert [b.name for b in m.bodies[1:]] == ["l1", "l2", "slide"]
    assert rep.limits["j1"] == (-2.0, 2.0, 10.0, 3.0) and rep.damping == {"j1": 0.4}
    assert rep.friction == {"j1": 0.1}
    text = str(rep)
    assert "line 38: <transmission name='t1'>" in text and "friction" in text
    # the merged body: mass and centroid of l2 and tool together
    l2 = m.body("l2")
    assert float(l2.mass) == pytest.approx(2.0)
    c_tool = np.array([0.4, 0, 0]) + rpy_matrix((0, np.pi / 2, 0)) @ np.array([0, 0, 0.05])
    np.testing.assert_allclose(np.asarray(l2.centroid, float).ravel(),
                               (1.5 * np.array([0.2, 0, 0]) + 0.5 * c_tool) / 2, atol=1e-15)
    # the inertia of l1 rotated into link axes
    Ii = np.array([[0.05, 0.001, -0.002], [0.001, 0.04, 0.003], [-0.002, 0.003, 0.03]])
    R = rpy_matrix((0.3, -0.2, 0.5))
    np.testing.assert_allclose(np.asarray(m.space.inertia_matrix(m.body("l1").inertia), float),
                               R @ Ii @ R.T, atol=1e-15)


def test_arm_file_frames_against_composition(arm_file):
    m = ms.from_urdf(arm_file)
    for q in RNG.uniform(-2, 2, size=(3, 3)):
        got, ref = frame_poses(m, q), _arm_fk(q)
        for link in ref:
            np.testing.assert_allclose(got[link], ref[link], atol=1e-13, err_msg=link)


def test_arm_file_dynamics_consistent_and_damping(arm_file):
    """forward_dynamics inverts inverse_dynamics; vectorised over points; named columns;
    joint_damping adds -d qd on j1."""
    m = ms.from_urdf(arm_file)
    q, qd, qdd = RNG.normal(size=(3, 4, 3))
    tau = m.inverse_dynamics(q, qd, qdd)
    assert tau.values.shape == (4, 3) and tau.names == ("j1", "j2", "j3")
    np.testing.assert_allclose(m.forward_dynamics(q, qd, tau.values).values, qdd, atol=1e-10)
    one = m.inverse_dynamics(q[1], qd[1], qdd[1])
    np.testing.assert_allclose(one.values, tau.values[1], atol=1e-12)
    named = m.inverse_dynamics({"j1": q[:, 0], "j2": q[:, 1], "j3": q[:, 2]}, qd, qdd)
    np.testing.assert_allclose(named["j2"], tau["j2"], atol=1e-12)
    md = ms.from_urdf(arm_file, joint_damping=True)
    td = md.inverse_dynamics(q, qd, qdd)
    np.testing.assert_allclose(td["j1"] - tau["j1"], 0.4 * qd[:, 0], atol=1e-10)
    np.testing.assert_allclose(td["j2"], tau["j2"], atol=1e-10)


# -- safe reading -------------------------------------------------------------------------------------
@pytest.mark.parametrize("text, match", [
    ('<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY a "aaaa">]>\n<robot name="x"/>', r"line 2: a DOCTYPE"),
    ('<robot name="x">\n<!ENTITY a "b">\n</robot>', r"line 2: a ENTITY"),
    ('<robot name="x">\n  <link name="a">\n</robot>', r"line 3: not well-formed"),
    ('<robot name="x">\n  <link name="a"/>\n  <link name="a"/>\n</robot>',
     r"line 3, <link name='a'>.*second link"),
    ('<robot name="x">\n <link name="a"/>\n <link name="b"/>\n <joint name="j" type="revolute">\n'
     '  <parent link="a"/><child link="b"/>\n  <origin xyz="0 zero 0"/>\n </joint>\n</robot>',
     r"line 6, <origin>: attribute xyz="),
    ('<robot name="x">\n <link name="a"/>\n <joint name="j" type="hinge">\n'
     '  <parent link="a"/><child link="a"/>\n </joint>\n</robot>', r"line 3, <joint name='j'>.*'hinge'"),
    ('<robot name="x">\n <link name="a"/>\n <joint name="j" type="fixed">\n'
     '  <parent link="a"/><child link="c"/>\n </joint>\n</robot>', r"line 4, <child>: link 'c'"),
    ('<robot name="x">\n <link name="a"/>\n <link name="b"/>\n</robot>', r"one root link.*\['a', 'b'\]"),
    ('<sdf version="1.6"/>', r"line 1, <sdf>: a URDF's root element is <robot>"),
    ('<robot name="x">\n <link name="a"><inertial><mass value="-1"/></inertial></link>\n</robot>',
     r"line 2, <mass>: the mass"),
])
def test_bad_files_name_element_and_line(tmp_path, text, match):
    p = tmp_path / "bad.urdf"
    p.write_text(text)
    with pytest.raises(ms.ModelError, match=match):
        ms.from_urdf(p)


def test_billion_laughs_refused_before_parsing(tmp_path):
    lol = ('<?xml version="1.0"?>\n<!DOCTYPE lolz [\n <!ENTITY lol "lol">\n'
           + "".join(f' <!ENTITY lol{k} "{("&lol" + (str(k - 1) if k > 1 else "") + ";") * 10}">\n'
                     for k in range(1, 10))
           + ']>\n<robot name="&lol9;"/>\n')
    p = tmp_path / "lol.urdf"
    p.write_text(lol)
    with pytest.raises(ms.ModelError, match="DOCTYPE"):
        ms.from_urdf(p)



def test_parser_refuses_declarations_without_the_byte_scan(monkeypatch):
    """Expat's own handlers refuse a DOCTYPE/ENTITY too (the second line of defence)."""
    monkeypatch.setattr(_xml, "REFUSED", ())
    with pytest.raises(ms.ModelError, match="line 2: a document type or entity declaration"):
        _xml.parse_xml(b'<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY a "aaaa">]>\n<robot name="&a;"/>')


def test_size_limit_and_regular_files(tmp_path, monkeypatch):
    with pytest.raises(ms.ModelError, match="not a regular file"):
        ms.from_urdf(tmp_path)
    with pytest.raises(ms.ModelError, match="cannot read"):
        ms.from_urdf(tmp_path / "missing.urdf")
    p = tmp_path / "big.urdf"
    p.write_text('<robot name="x"><link name="a"/></robot>' + " " * 100)
    monkeypatch.setattr(_xml, "MAX_XML_BYTES", 100)
    with pytest.raises(ms.ModelError, match="limit of 100"):
        ms.from_urdf(p)


def test_robot_dynamics_refuses_constrained_models_and_bad_shapes(arm_file):
    m = ms.from_urdf(arm_file)
    with pytest.raises(ms.ModelError, match=r"shape \(n,\) or \(N, n\) with n = 3"):
        m.inverse_dynamics(np.zeros(2), np.zeros(3), np.zeros(3))
    with pytest.raises(ms.ModelError, match=r"missing \['j3'\]"):
        m.inverse_dynamics({"j1": 0, "j2": 0}, np.zeros(3), np.zeros(3))
    with pytest.raises(ms.ModelError, match="no joint coordinate named 'j9'"):
        m.inverse_dynamics(np.zeros(3), np.zeros(3), np.zeros(3))["j9"]
    # a constraint equation: the state must satisfy it (decision 0048; constrained models'
    # dynamics: test_io_coordinates.py)
    f = ms.from_urdf(arm_file, floating_base=False)
    f.add(ms.Constraint(f.compile().layout.q_symbols[0] - 0.1), name="hold")
    with pytest.raises(ms.ModelError, match="positions of point 0 violate"):
        f.inverse_dynamics(np.zeros(3), np.zeros(3), np.zeros(3))


# -- real robots against Pinocchio and MuJoCo ---------------------------------------------------------
def _pin_model(path):
    pin = pytest.importorskip("pinocchio")
    return pin, pin.buildModelFromUrdf(str(path))


@needs_robots
@pytest.mark.parametrize("rel", [UR5, PANDA])
def test_real_robot_against_pinocchio(rel):
    """Frame poses (1e-12), RNEA (1e-9 relative) and ABA (1e-9) of Pinocchio on the same file."""
    path = ROBOTS / rel
    pin, pm = _pin_model(path)
    pd = pm.createData()
    m = ms.from_urdf(path)
    names = m.compile().layout.q_names
    assert names == tuple(pm.names[i] for i in range(1, pm.njoints))
    assert pm.nq == pm.nv == len(names)
    n = len(names)
    lo, hi = pm.lowerPositionLimit, pm.upperPositionLimit
    Q = RNG.uniform(np.maximum(lo, -3), np.minimum(hi, 3), size=(3, n))
    QD, QDD = RNG.normal(size=(2, 3, n))
    for q in Q:
        got = frame_poses(m, q)
        pin.framesForwardKinematics(pm, pd, q)
        for link, M in got.items():
            if not pm.existFrame(link):
                continue
            ref = pd.oMf[pm.getFrameId(link)].homogeneous
            np.testing.assert_allclose(M, ref, atol=1e-12, rtol=0, err_msg=link)
    last = pm.frames[len(pm.frames) - 1].name                  # the tool frame
    ref = []
    for q in Q:
        pin.framesForwardKinematics(pm, pd, q)
        ref.append(pd.oMf[pm.getFrameId(last)].translation.copy())
    np.testing.assert_allclose(m.forward_kinematics(Q, last), ref, atol=1e-12, rtol=0)
    tau = m.inverse_dynamics(Q, QD, QDD).values
    qdd = m.forward_dynamics(Q, QD, tau).values
    for k in range(len(Q)):
        ref = pin.rnea(pm, pd, Q[k], QD[k], QDD[k])
        np.testing.assert_allclose(tau[k], ref, rtol=0, atol=1e-9 * np.abs(ref).max())
        acc = pin.aba(pm, pd, Q[k], QD[k], ref)
        np.testing.assert_allclose(acc, QDD[k], atol=1e-9 * (1 + np.abs(QDD[k]).max()))
        np.testing.assert_allclose(qdd[k], acc, rtol=0, atol=1e-9 * (1 + np.abs(acc).max()))


def _mujoco_from_urdf(path: Path):
    """The URDF loaded by MuJoCo itself, without its meshes (visual and collision elements
    removed: dynamics only), joint limits, contacts and damping off."""
    mujoco = pytest.importorskip("mujoco")
    text = path.read_text()
    text = re.sub(r"<(visual|collision)>.*?</\1>", "", text, flags=re.S)
    text = re.sub(r"<dynamics[^>]*/>", "", text)
    mm = mujoco.MjModel.from_xml_string(text)
    mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    mm.dof_damping[:] = 0
    mm.dof_armature[:] = 0
    mm.dof_frictionloss[:] = 0
    mm.opt.gravity[:] = (0, 0, -9.81)
    return mujoco, mm


@needs_robots
@pytest.mark.parametrize("rel", [UR5, PANDA])
def test_real_robot_against_mujoco(rel):
    """mj_inverse (1e-9 relative) and mj_forward (1e-9) on MuJoCo's own import of the file."""
    path = ROBOTS / rel
    mujoco, mm = _mujoco_from_urdf(path)
    md = mujoco.MjData(mm)
    m = ms.from_urdf(path)
    names = m.compile().layout.q_names
    jn = [mujoco.mj_id2name(mm, mujoco.mjtObj.mjOBJ_JOINT, i) for i in range(mm.njnt)]
    assert tuple(jn) == names and mm.nv == len(names)
    n = len(names)
    Q = RNG.uniform(-2, 2, size=(2, n)) * (mm.jnt_type == int(mujoco.mjtJoint.mjJNT_HINGE)) \
        + RNG.uniform(0, 0.04, size=(2, n)) * (mm.jnt_type == int(mujoco.mjtJoint.mjJNT_SLIDE))
    QD, QDD = RNG.normal(size=(2, 2, n))
    tau = m.inverse_dynamics(Q, QD, QDD).values
    qdd = m.forward_dynamics(Q, QD, tau).values
    for k in range(len(Q)):
        md.qpos[:], md.qvel[:], md.qacc[:] = Q[k], QD[k], QDD[k]
        mujoco.mj_inverse(mm, md)
        ref = md.qfrc_inverse.copy()
        np.testing.assert_allclose(tau[k], ref, rtol=0, atol=1e-9 * np.abs(ref).max())
        md.qfrc_applied[:] = ref
        mujoco.mj_forward(mm, md)
        np.testing.assert_allclose(qdd[k], md.qacc, rtol=0, atol=1e-9 * (1 + np.abs(md.qacc).max()))


def _qmul(a, b):
    w1, v1, w2, v2 = a[0], np.asarray(a[1:]), b[0], np.asarray(b[1:])
    return np.concatenate(([w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + np.cross(v1, v2)))


@needs_robots
@pytest.mark.parametrize("rel", ["solo_description/robots/solo12.urdf",
                                 "simple_humanoid_description/urdf/simple_humanoid.urdf"])
def test_floating_base_against_pinocchio(rel):
    """A quadruped (Solo-12) and a humanoid (29 joints) with a free base
    (``floating_base=True``: the base an absolute body, x y z and Euler parameters): frame
    poses against Pinocchio's free-flyer model (1e-12), and the joint accelerations of the
    unactuated free fall (the augmented free-motion system, the normalisation constraint
    included) against ABA with zero torques (1e-9 relative). Joints are matched by name
    (Pinocchio's URDF parser orders siblings by name, mechsys as the file does)."""
    path = ROBOTS / rel
    pin = pytest.importorskip("pinocchio")
    pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    pd = pm.createData()
    m = ms.from_urdf(path, floating_base=True)
    s = m.compile()
    names = s.layout.q_names[7:]
    assert sorted(names) == sorted(pm.names[i] for i in range(2, pm.njoints)) and s.m == 1
    assert all(pm.joints[pm.getJointId(n)].nq == 1 for n in names)
    iq = np.array([pm.joints[pm.getJointId(n)].idx_q for n in names])   # ours -> Pinocchio's
    iv = np.array([pm.joints[pm.getJointId(n)].idx_v for n in names])
    nj = len(names)
    for _ in range(2):
        e = RNG.normal(size=4)
        e /= np.linalg.norm(e)
        r, qj = RNG.normal(size=3), RNG.uniform(-1.5, 1.5, size=nj)
        q = np.concatenate((r, e, qj))
        q_pin = np.zeros(pm.nq)
        q_pin[:7] = np.concatenate((r, e[1:], e[:1]))
        q_pin[iq] = qj
        pin.framesForwardKinematics(pm, pd, q_pin)
        for link, M in frame_poses(m, q).items():
            if pm.existFrame(link):
                np.testing.assert_allclose(M, pd.oMf[pm.getFrameId(link)].homogeneous, atol=1e-12,
                                           err_msg=link)
        feet = [f for f in m.import_report.frames if pm.existFrame(f)][-3:]
        np.testing.assert_allclose(m.forward_kinematics(q, feet),
                                   [pd.oMf[pm.getFrameId(f)].translation for f in feet], atol=1e-12)
        v_loc, w_loc, qdj = RNG.normal(size=3), RNG.normal(size=3), RNG.normal(size=nj)
        R = pd.oMf[pm.getFrameId(m.bodies[1].name)].rotation
        qd = np.concatenate((R @ v_loc, 0.5 * _qmul(e, np.concatenate(([0.0], w_loc))), qdj))
        v_pin = np.zeros(pm.nv)
        v_pin[:6] = np.concatenate((v_loc, w_loc))
        v_pin[iv] = qdj
        a = pin.aba(pm, pd, q_pin, v_pin, np.zeros(pm.nv))[iv]
        K, rhs = s.dynamics.free_kernel()(0.0, q, qd, np.zeros(s.m), s.p_values)
        qdd = np.linalg.solve(np.asarray(K.todense() if hasattr(K, "todense") else K), rhs)[:s.n]
        np.testing.assert_allclose(qdd[7:], a, rtol=0, atol=1e-9 * np.abs(a).max())


def test_geometry_kept_for_drawing(arm_file, tmp_path):
    """The arm's visuals: a rotated box (six facets), a cylinder, a sphere; a picture draws;
    a mesh that cannot be read is noted, one that can (STL, OBJ; binary or ASCII) is drawn
    as its triangles."""
    import matplotlib

    matplotlib.use("Agg")
    from mechsys import draw

    m = ms.from_urdf(arm_file)
    kinds = [type(p).__name__ for p in draw.attached(m)]
    assert kinds.count("Facet") == 6 and kinds.count("Cylinder") == 1 and kinds.count("Sphere") == 1
    sol = m.free().simulate([0.0, 0.01], initial_condition={"j1": 0.3})
    draw.snapshot(sol, index=0)
    # meshes: an ASCII STL beside the file is drawn as its triangles, a missing one noted
    (tmp_path / "part.stl").write_text("solid p\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                                       "vertex 0.2 0 0\nvertex 0 0.1 0.05\nendloop\nendfacet\n"
                                       "endsolid p\n")
    text = ARM.replace('<cylinder radius="0.03" length="0.4"/>', '<mesh filename="part.stl"/>').replace(
        '<sphere radius="0.04"/>', '<mesh filename="package://nowhere/x.dae"/>')
    p = tmp_path / "mesh.urdf"
    p.write_text(text)
    mm = ms.from_urdf(p)
    (mesh,) = [q for q in draw.attached(mm) if type(q).__name__ == "Mesh"]
    assert mesh.faces == [(0, 2, 1)]             # the distinct corners, sorted, indexed
    np.testing.assert_allclose(mesh.vertices, [[0, 0, 0], [0, 0.1, 0.05], [0.2, 0, 0]], atol=1e-7)
    assert any("x.dae" in n and "not drawn" in n for n in mm.import_report.not_mapped)
    draw.snapshot(mm)                            # the Mesh drawn (at the guess)
    # a binary STL (a unit square: two triangles, four corners) and an OBJ quad with
    # negative indices (fanned into two triangles), read by our own reader
    import struct

    from mechsys.io._urdf import read_mesh

    tris = [((0, 0, 0), (1, 0, 0), (1, 1, 0)), ((0, 0, 0), (1, 1, 0), (0, 1, 0))]
    blob = b"x" * 80 + struct.pack("<I", 2) + b"".join(
        struct.pack("<12fH", 0, 0, 1, *[c for v in t for c in v], 0) for t in tris)
    (tmp_path / "sq.stl").write_bytes(blob)
    V, F = read_mesh(tmp_path / "sq.stl")
    assert len(V) == 4 and F.shape == (2, 3)
    np.testing.assert_allclose(V[F].reshape(2, 3, 3), np.array(tris, float))
    (tmp_path / "sq.obj").write_text("# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3/1 -2//1 -1\n")
    V, F = read_mesh(tmp_path / "sq.obj")
    np.testing.assert_array_equal(F, [[0, 1, 2], [0, 2, 3]])
    (tmp_path / "bad.obj").write_text("v 0 0 0\nf 1 2 3\n")
    assert read_mesh(tmp_path / "bad.obj") is None
    with pytest.raises(ms.GeometryError, match="needs at least three indices"):
        draw.Mesh(mm.ground, V, [(0, 1, 7)])


def test_floating_joint_on_world(tmp_path):
    """A ``floating`` joint from the root makes an absolute body placed at the joint's origin
    (planar joints and floating joints below the root: test_io_coordinates.py)."""
    text = ('<robot name="f">\n <link name="world"/>\n <link name="base"><inertial><mass value="2"/>'
            '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>\n'
            ' <joint name="float" type="floating"><parent link="world"/><child link="base"/>'
            '<origin xyz="0 0 1" rpy="0 0 0.5"/></joint>\n</robot>')
    p = tmp_path / "f.urdf"
    p.write_text(text)
    m = ms.from_urdf(p)
    s = m.compile()
    assert s.n == 7 and s.m == 1 and m.import_report.joints["float"][0] == "floating"
    np.testing.assert_allclose(s.guess, [0, 0, 1, np.cos(0.25), 0, 0, np.sin(0.25)], atol=1e-15)


@needs_robots
def test_mimic_reported_or_a_constraint():
    """The Panda's second finger mimics the first: reported by default (the model stays a
    tree, as Pinocchio reads it), a constraint finger2 - finger1 = 0 with ``mimic=True``."""
    path = ROBOTS / PANDA
    m = ms.from_urdf(path)
    assert any("<mimic>" in n and "panda_finger_joint2" in n for n in m.import_report.not_mapped)
    mm = ms.from_urdf(path, mimic=True, geometry=False)
    (eq,) = mm.constraint("panda_finger_joint2_mimic").equations(mm.space)
    f1, f2 = sp.Symbol("panda_finger_joint1"), sp.Symbol("panda_finger_joint2")
    assert sp.simplify(eq - (f2 - f1)) == 0
    assert mm.compile().m == 1


# -- forward dynamics over many points, compiled (decision 0073) --------------------------------------
def _spy_points(monkeypatch):
    """Record ``(mode, points done)`` of each call of the compiled loop over points."""
    from mechsys.solvers import _jit_gen_points as jp

    calls, real = [], jp.points

    def spy(system, times, Q, QD, X, mode, p=None):
        got = real(system, times, Q, QD, X, mode, p)
        calls.append((mode, None if got is None else got[1]))
        return got

    monkeypatch.setattr(jp, "points", spy)
    return calls


@needs_robots
def test_forward_dynamics_compiled_over_points(monkeypatch):
    """The UR5 over ``AUTO_POINTS`` states with ``MECHSYS_JIT`` unset: the compiled loop over
    points takes every point (the composite-body mass matrix and its Cholesky factor); its
    accelerations equal the Python path's (``MECHSYS_JIT=0``, 1e-13 relative) and MuJoCo's
    ``mj_forward`` on MuJoCo's own import of the file (contacts off, 1e-9 relative), and the
    compiled inverse dynamics gives the joint forces back (1e-12). The same robot on a free
    base (an absolute body: one constraint equation) through the augmented system: equal to
    the Python path, and a round trip with the inverse dynamics on the joints."""
    from mechsys.analyses._robot import AUTO_POINTS
    from mechsys.solvers import _jit_gen_points as jp

    path = ROBOTS / UR5
    m = ms.from_urdf(path, geometry=False)
    n = m.compile().n
    N = AUTO_POINTS
    Q = RNG.uniform(-2.5, 2.5, size=(N, n))
    QD, TAU = RNG.normal(size=(2, N, n))
    TAU *= 20.0
    monkeypatch.delenv("MECHSYS_JIT", raising=False)
    calls = _spy_points(monkeypatch)
    qdd = m.forward_dynamics(Q, QD, TAU).values
    assert calls == [(jp.FORWARD_FREE, N)]
    tau = m.inverse_dynamics(Q, QD, qdd).values               # compiled too (N points)
    assert calls[-1] == (jp.DYNAMIC_LOADS, N)
    np.testing.assert_allclose(tau, TAU, rtol=0, atol=1e-12 * np.abs(TAU).max())
    monkeypatch.setenv("MECHSYS_JIT", "0")
    ref = m.forward_dynamics(Q[:6], QD[:6], TAU[:6]).values
    assert len(calls) == 2                                    # the Python path
    np.testing.assert_allclose(qdd[:6], ref, rtol=0, atol=1e-13 * np.abs(ref).max())
    mujoco, mm = _mujoco_from_urdf(path)
    md = mujoco.MjData(mm)
    for k in range(0, N, 20):
        md.qpos[:], md.qvel[:], md.qfrc_applied[:] = Q[k], QD[k], TAU[k]
        mujoco.mj_forward(mm, md)
        np.testing.assert_allclose(qdd[k], md.qacc, rtol=0, atol=1e-9 * np.abs(md.qacc).max())
    # a free base: x, y, z and Euler parameters, the joints actuated
    f = ms.from_urdf(path, geometry=False, floating_base=True)
    s = f.compile()
    assert s.m == 1 and s.n == n + 7
    k = 5
    e = RNG.normal(size=(k, 4))
    e /= np.linalg.norm(e, axis=1)[:, None]
    w = RNG.normal(size=(k, 4))
    w -= np.sum(w * e, axis=1)[:, None] * e                   # e . e_dot = 0
    Qf = np.hstack((RNG.normal(size=(k, 3)), e, Q[:k]))
    QDf = np.hstack((RNG.normal(size=(k, 3)), w, QD[:k]))
    monkeypatch.setenv("MECHSYS_JIT", "1")
    acc = f.forward_dynamics(Qf, QDf, TAU[:k]).values
    assert calls[-1] == (jp.FORWARD_AUGMENTED, k)
    back = f.inverse_dynamics(Qf, QDf, acc).values            # the joints' forces
    np.testing.assert_allclose(back, TAU[:k], rtol=0, atol=1e-9 * np.abs(TAU).max())
    monkeypatch.setenv("MECHSYS_JIT", "0")
    ref = f.forward_dynamics(Qf, QDf, TAU[:k]).values
    np.testing.assert_allclose(acc, ref, rtol=0, atol=1e-13 * np.abs(ref).max())


def test_forward_dynamics_compiled_hands_a_massless_joint_to_python(arm_file, tmp_path,
                                                                     monkeypatch):
    """A joint that moves no mass (the slide's link massless): the compiled loop stops at
    that point (its Cholesky factor fails) and the Python path raises its error naming the
    joint, as without the compiled loop."""
    from mechsys.solvers import _jit_gen_points as jp

    text = ARM.replace('<link name="slide"><inertial><mass value="0.7"/>\n      <inertia '
                       'ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.001"/>'
                       '</inertial></link>', '<link name="slide"/>')
    assert text != ARM
    p = tmp_path / "massless.urdf"
    p.write_text(text)
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")   # (3 joints: else symbolic)
    m = ms.from_urdf(p, geometry=False)
    assert getattr(m.compile().dynamics, "recursive", False)
    calls = _spy_points(monkeypatch)
    q, qd, tau = RNG.normal(size=(3, 2, 3))
    for jit in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        with pytest.raises(ms.SingularMassError, match=r"joints \['j3'\] move no mass"):
            m.forward_dynamics(q, qd, tau)
    assert calls == [(jp.FORWARD_FREE, 0)]
