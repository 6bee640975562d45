"""MJCF import (``ms.from_mjcf``), decision 0040: dynamics against MuJoCo reading the same file.

MuJoCo itself is the reference for what a file means: a model written here to exercise the
format (default classes and ``childclass``, degrees, an ``eulerseq``, every orientation form,
``<frame>``, several joints in one body, mass from geoms of every primitive type) and the
example-robot-data arms as MuJoCo writes them (``mj_saveLastXML``) are compared with
``mj_inverse``/``mj_forward`` (constraints and damping off) to 1e-9; a closed-loop four-bar
(``<connect>``) keeps its loop closed and conserves energy in free motion.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import mechsys as ms
from test_io_urdf import PANDA, ROBOTS, UR5, needs_robots

mujoco = pytest.importorskip("mujoco")
RNG = np.random.default_rng(370)

ZOO = """<mujoco model="zoo">
  <compiler angle="degree" eulerseq="zyX"/>
  <option gravity="0.5 -1 -9.7"/>
  <default>
    <joint damping="0.2"/>
    <geom density="800"/>
    <default class="arm">
      <joint axis="0 1 0" armature="0.01"/>
      <geom type="capsule" size="0.03"/>
      <default class="heavy"><geom density="3000"/></default>
    </default>
  </default>
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body name="base" pos="0 0 0.3" euler="10 20 30">
      <geom type="box" size="0.1 0.08 0.05"/>
      <body name="upper" pos="0.1 0 0.05" axisangle="1 1 0 40" childclass="arm">
        <joint name="shoulder" pos="0 0 0.02" axis="0.3 0.4 1"/>
        <geom fromto="0 0 0 0 0 0.4"/>
        <geom class="heavy" type="sphere" size="0.05" pos="0 0 0.4"/>
        <body name="fore" pos="0 0 0.4" xyaxes="0 1 0 -1 0.2 0">
          <joint name="elbow" ref="25" stiffness="3" springref="10"/>
          <joint name="twist" type="hinge" axis="0 0 1" pos="0.01 0 0"/>
          <inertial pos="0.02 0.01 0.15" mass="1.2" fullinertia="0.02 0.025 0.015 0.001 -0.002 0.0005"/>
          <frame pos="0 0 0.3" euler="0 0 90">
            <body name="slider" zaxis="1 1 1">
              <joint name="slide" type="slide" axis="1 0 0" pos="0.1 0 0" ref="0.03"/>
              <geom type="cylinder" size="0.02 0.05" class="heavy"/>
              <geom type="ellipsoid" size="0.03 0.02 0.04" pos="0.05 0 0" euler="30 0 0"/>
              <body name="tip" pos="0.05 0.05 0">
                <inertial pos="0 0 0.01" quat="0.9 0.1 0.3 0.2" mass="0.3" diaginertia="0.001 0.002 0.0015"/>
              </body>
            </body>
          </frame>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="elbow"/></actuator>
</mujoco>
"""

FOUR_BAR = """<mujoco model="four_bar">
  <compiler angle="radian"/>
  <worldbody>
    <body name="crank">
      <joint name="crank_joint" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/>
      <body name="coupler" pos="0.1 0 0">
        <joint name="coupler_joint" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0.1" size="0.01"/>
        <body name="rocker" pos="0.3 0 0.1">
          <joint name="rocker_joint" axis="0 1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 -0.25" size="0.01"/>
        </body>
      </body>
    </body>
  </worldbody>
  <equality><connect name="close" body1="rocker" body2="world" anchor="0 0 -0.25"/></equality>
</mujoco>
"""


def _write(tmp_path, text, name="model.xml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _reference(path):
    mm = mujoco.MjModel.from_xml_path(str(path))
    mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    mm.dof_damping[:] = 0
    mm.dof_armature[:] = 0
    mm.jnt_stiffness[:] = 0
    return mm, mujoco.MjData(mm)


def _compare(m, mm, md, points=2, scale=0.8):
    names = m.compile().layout.q_names
    jn = tuple(mujoco.mj_id2name(mm, mujoco.mjtObj.mjOBJ_JOINT, i) for i in range(mm.njnt))
    assert names == jn and mm.nq == mm.nv == len(names)
    Q, QD, QDD = RNG.normal(size=(3, points, mm.nv)) * scale
    tau = m.inverse_dynamics(Q, QD, QDD).values
    qdd = m.forward_dynamics(Q, QD, tau).values
    for k in range(points):
        md.qpos[:], md.qvel[:], md.qacc[:] = Q[k], QD[k], QDD[k]
        mujoco.mj_inverse(mm, md)
        ref = md.qfrc_inverse.copy()
        np.testing.assert_allclose(tau[k], ref, rtol=0, atol=1e-9 * np.abs(ref).max())
        md.qfrc_applied[:] = ref
        mujoco.mj_forward(mm, md)
        np.testing.assert_allclose(qdd[k], md.qacc, rtol=0, atol=1e-9 * (1 + np.abs(md.qacc).max()))


def test_format_features_against_mujoco(tmp_path):
    path = _write(tmp_path, ZOO)
    m = ms.from_mjcf(path)
    rep = m.import_report
    assert rep.joints["twist"] == ("hinge", ("twist",), "fore")
    assert rep.frames["tip"][0] == "slider" and rep.frames["base"][0] == "ground"
    assert rep.damping == {"shoulder": 0.2, "elbow": 0.2, "twist": 0.2, "slide": 0.2}
    assert "line 39: <actuator>" in str(rep) and "armature=0.01" in str(rep)
    mm, md = _reference(path)
    # masses from the geoms as MuJoCo computes them (capsule, sphere, cylinder, ellipsoid)
    mj_mass = {mujoco.mj_id2name(mm, mujoco.mjtObj.mjOBJ_BODY, i): mm.body_mass[i] for i in range(mm.nbody)}
    assert float(m.body("upper").mass) == pytest.approx(mj_mass["upper"], rel=1e-14)
    assert float(m.body("slider").mass) == pytest.approx(mj_mass["slider"] + mj_mass["tip"], rel=1e-14)
    _compare(m, mm, md)
    # joint_damping adds MuJoCo's damping (mj_inverse subtracts the passive force -d qd)
    md2 = ms.from_mjcf(path, joint_damping=True)
    q, qd, qdd = RNG.normal(size=(3, 4))
    diff = md2.inverse_dynamics(q, qd, qdd).values - m.inverse_dynamics(q, qd, qdd).values
    np.testing.assert_allclose(diff, 0.2 * qd, atol=1e-12)
    # with the springs too: MuJoCo's passive forces (damping, the elbow's spring) in mj_inverse
    mp = ms.from_mjcf(path, joint_damping=True, joint_springs=True)
    mm2 = mujoco.MjModel.from_xml_path(str(path))
    mm2.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    mm2.dof_armature[:] = 0
    d2 = mujoco.MjData(mm2)
    d2.qpos[:], d2.qvel[:], d2.qacc[:] = q, qd, qdd
    mujoco.mj_inverse(mm2, d2)
    np.testing.assert_allclose(mp.inverse_dynamics(q, qd, qdd).values, d2.qfrc_inverse, rtol=0,
                               atol=1e-9 * np.abs(d2.qfrc_inverse).max())


@needs_robots
@pytest.mark.parametrize("rel", [UR5, PANDA])
def test_robot_files_written_by_mujoco(tmp_path, rel):
    """The URDF arms as MuJoCo converts and writes them (its own MJCF, with <frame>s and, for
    the Panda, the fingers' mimic as an equality)."""
    text = re.sub(r"<(visual|collision)>.*?</\1>", "", (ROBOTS / rel).read_text(), flags=re.S)
    path = tmp_path / "robot.xml"
    mujoco.mj_saveLastXML(str(path), mujoco.MjModel.from_xml_string(text))
    m = ms.from_mjcf(path)
    if "panda" in rel:
        c = m.constraint("joint_panda_finger_joint2")      # the mimic: finger2 = finger1
        assert c is not None
        with pytest.raises(ms.ModelError, match=r"panda_finger_joint2'\] are not unique"):
            m.inverse_dynamics(np.zeros(9), np.zeros(9), np.zeros(9))
        m.remove(c)                                        # MuJoCo's reference runs without it
    mm, md = _reference(path)
    _compare(m, mm, md)


def test_closed_loop_four_bar(tmp_path):
    """``<connect>`` closes the loop (a Spherical3, consistently redundant in the plane): one
    DOF; free motion under gravity keeps the loop closed and conserves energy."""
    path = _write(tmp_path, FOUR_BAR)
    with pytest.warns(ms.RedundantConstraintWarning):
        m = ms.from_mjcf(path)
        fr = m.free(initial_condition={"crank_joint": 0.0})
        assert fr.dof == 1
        t = np.linspace(0, 0.5, 11)
        sol = fr.simulate(t, rtol=1e-11, atol=1e-11)
    tip = sol.location(m.body("rocker").point((0, 0, -0.25)))
    np.testing.assert_allclose(tip, np.tile([0.4, 0, -0.15], (len(t), 1)), atol=1e-8)
    E = np.ravel(sol.body_energy()) + np.ravel(sol.potential_energy())
    assert np.ptp(E) < 1e-8 * max(1.0, np.abs(E).max())
    assert np.ptp(np.ravel(sol["crank_joint"])) > 0.1           # it moved


@pytest.mark.parametrize("text, match", [
    ('<mujoco>\n <worldbody>\n  <body name="a">\n   <joint name="j" type="hinge" axis="0 0 0"/>\n'
     '   <geom size="0.1"/>\n  </body>\n </worldbody>\n</mujoco>',
     r"line 4, <joint name='j'>: the joint axis is zero"),
    ('<mujoco>\n <compiler angle="grad"/>\n <worldbody/>\n</mujoco>', r"line 2, <compiler>: angle='grad'"),
    ('<mujoco>\n <worldbody>\n  <body name="a" quat="1 0 0 0" euler="0 0 1"><joint name="j"/></body>\n'
     ' </worldbody>\n</mujoco>', r"line 3, <body name='a'>: give one orientation"),
    ('<mujoco>\n <worldbody>\n  <body name="a" childclass="nope"><joint name="j"/></body>\n </worldbody>\n'
     '</mujoco>', r"line 3, <joint name='j'>: default class 'nope'"),
    ('<mujoco>\n <include file="other.xml"/>\n <worldbody/>\n</mujoco>', r"line 2, <include>"),
    ('<mujoco>\n <worldbody>\n  <body name="a"><joint name="j"/><geom size="0.1"/></body>\n </worldbody>\n'
     ' <equality><connect body1="b" anchor="0 0 0"/></equality>\n</mujoco>', r"line 5, <connect>: body1='b'"),
    ('<robot name="r"/>', r"line 1, <robot name='r'>: an MJCF's root element is <mujoco>"),
    ('<mujoco>\n <worldbody>\n  <body name="a"><joint name="j"/>\n'
     '   <inertial mass="1" diaginertia="1 1 3"/></body>\n </worldbody>\n</mujoco>',
     r"line 3, <body name='a'>: inertia of body 'a'.*triangle"),
])
def test_bad_files_name_element_and_line(tmp_path, text, match):
    with pytest.raises(ms.ModelError, match=match):
        ms.from_mjcf(_write(tmp_path, text))


BALL_FREE = """<mujoco model="ball_free">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base" pos="0.1 0.2 1.0">
      <freejoint name="root"/>
      <geom type="box" size="0.2 0.1 0.05"/>
      <body name="arm" pos="0.2 0 0">
        <joint name="shoulder" type="ball" pos="0.05 0 0"/>
        <geom type="capsule" fromto="0.05 0 0 0.35 0 0.1" size="0.03"/>
        <body name="hand" pos="0.35 0 0.1">
          <joint name="wrist" axis="0 1 0.3"/>
          <geom type="ellipsoid" size="0.05 0.03 0.08" pos="0.05 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def _qmul(a, b):
    w1, v1, w2, v2 = a[0], np.asarray(a[1:]), b[0], np.asarray(b[1:])
    return np.concatenate(([w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + np.cross(v1, v2)))


def _qrot(e):
    from mechsys.io._mjcf import quat_matrix

    return quat_matrix(e)


def test_free_and_ball_joints_against_mujoco(tmp_path):
    """A free base carrying a ball-jointed arm and a hinged hand: both absolute bodies (the
    ball a Spherical3), the hand a Gen joint. From MuJoCo's state (qpos: position and
    quaternions, qvel: world linear and local angular velocities) the hinge's free-fall
    acceleration of the augmented system equals MuJoCo's (1e-9)."""
    path = _write(tmp_path, BALL_FREE)
    m = ms.from_mjcf(path)
    rep = m.import_report
    assert rep.joints["root"][0] == "free" and rep.joints["shoulder"][0] == "ball"
    s = m.compile()
    mm = mujoco.MjModel.from_xml_path(str(path))
    md = mujoco.MjData(mm)
    lay = s.layout
    for _ in range(2):
        eb, ea = RNG.normal(size=4), RNG.normal(size=4)
        eb, ea = eb / np.linalg.norm(eb), ea / np.linalg.norm(ea)
        rb, wb_loc, vb = RNG.normal(size=3), RNG.normal(size=3), RNG.normal(size=3)
        wa_rel, wrist, wrist_d = RNG.normal(size=3), RNG.normal(), RNG.normal()
        md.qpos[:] = np.concatenate((rb, eb, ea, [wrist]))
        md.qvel[:] = np.concatenate((vb, wb_loc, wa_rel, [wrist_d]))
        mujoco.mj_forward(mm, md)
        # the same state in mechsys coordinates: base absolute, arm absolute (global pose)
        Rb = _qrot(eb)
        e_arm = _qmul(eb, ea)                                  # arm frame = base * (0.2, 0, 0) * ball
        Ra = _qrot(e_arm)
        jp = np.array([0.05, 0, 0])
        r_arm = rb + Rb @ (np.array([0.2, 0, 0]) + jp) - Ra @ jp
        w_b = Rb @ wb_loc                                      # world angular velocities
        w_a = w_b + Ra @ wa_rel
        v_arm = vb + np.cross(w_b, Rb @ (np.array([0.2, 0, 0]) + jp)) - np.cross(w_a, Ra @ jp)
        q = np.zeros(s.n)
        qd = np.zeros(s.n)
        for body, r, e, v, w in (("base", rb, eb, vb, w_b), ("arm", r_arm, e_arm, v_arm, w_a)):
            sl = lay.body_slices[body]
            q[sl] = np.concatenate((r, e))
            qd[sl] = np.concatenate((v, 0.5 * _qmul(np.concatenate(([0.0], w)), e)))
        iw = lay.q_names.index("wrist")
        q[iw], qd[iw] = wrist, wrist_d
        K, rhs = s.dynamics.free_kernel()(0.0, q, qd, np.zeros(s.m), s.p_values)
        qdd = np.linalg.solve(np.asarray(K.todense() if hasattr(K, "todense") else K), rhs)[:s.n]
        ref = md.qacc[-1]
        assert abs(qdd[iw] - ref) <= 1e-9 * max(1.0, np.abs(md.qacc).max()), (qdd[iw], ref)


MESHED = """<mujoco>
  <compiler angle="radian" meshdir="parts"/>
  <asset><mesh file="tet.stl" scale="2 1 0.5"/><mesh name="gone" file="missing.stl"/></asset>
  <worldbody>
    <body name="link" pos="0.1 0.2 0.3" quat="0.9 0.1 0.3 0.2">
      <joint name="j" axis="0 1 0"/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
      <geom type="mesh" mesh="tet" pos="0.05 -0.02 0.1" euler="0.3 -0.4 0.7" mass="0"/>
      <geom type="mesh" mesh="gone" mass="0"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_mesh_geoms_are_drawn_where_mujoco_places_them(tmp_path):
    """A mesh geom (binary STL under the compiler's meshdir, scaled, the geom turned and
    offset in a turned body) is drawn as its triangles in the body's coordinates; its
    vertices in the world at a joint angle equal MuJoCo's (which moves the mesh to its
    inertial frame and the geom by the opposite offset). A missing file is noted."""
    import struct

    from mechsys import draw

    corners = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.08, 0], [0.02, 0.03, 0.06]], float)
    tris = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (2, 0, 3)]
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "tet.stl").write_bytes(
        b"\0" * 80 + struct.pack("<I", 4) + b"".join(
            struct.pack("<12fH", 0, 0, 0, *corners[list(t)].ravel(), 0) for t in tris))
    path = _write(tmp_path, MESHED)
    m = ms.from_mjcf(path)
    (mesh,) = [p for p in draw.attached(m) if type(p).__name__ == "Mesh"]
    assert len(mesh.faces) == 4
    assert any("missing.stl" in n and "not drawn" in n for n in m.import_report.not_mapped)
    # MuJoCo refuses the missing file: it reads the file without that mesh
    path = _write(tmp_path, re.sub(r'<mesh name="gone".*?/>|<geom type="mesh" mesh="gone".*?/>', "",
                                   MESHED), "mujoco.xml")
    mm = mujoco.MjModel.from_xml_path(str(path))
    md = mujoco.MjData(mm)
    md.qpos[0] = 0.7
    mujoco.mj_kinematics(mm, md)
    g = 0                                                  # the tetrahedron's geom
    k0, nv = mm.mesh_vertadr[mm.geom_dataid[g]], mm.mesh_vertnum[mm.geom_dataid[g]]
    ref = md.geom_xpos[g] + mm.mesh_vert[k0:k0 + nv] @ md.geom_xmat[g].reshape(3, 3).T
    b = md.xpos[1], md.xmat[1].reshape(3, 3)               # the body's frame at q = 0.7
    ours = b[0] + np.asarray(mesh.vertices, float) @ b[1].T
    order = np.lexsort(ref.T)
    np.testing.assert_allclose(ours[np.lexsort(ours.T)], ref[order], atol=1e-6)


# <include> (decision 0070): a main file whose defaults, assets and bodies come from included
# files, one of them nested and in a subfolder, read as the same model written in one file
INC_MAIN = """<mujoco model="inc">
  <compiler angle="radian"/>
  <include file="parts/defaults.xml"/>
  <default>
    <geom density="800"/>
  </default>
  <worldbody>
    <body name="base" pos="0 0 0.5">
      <joint name="yaw" axis="0 0 1"/>
      <geom type="box" size="0.1 0.1 0.05"/>
      <include file="parts/arm.xml"/>
    </body>
  </worldbody>
</mujoco>
"""
INC_DEFAULTS = """<mujoco>
  <asset><material name="red" rgba="1 0 0 1"/></asset>
  <default>
    <joint axis="0 1 0"/>
    <geom density="300" material="red"/>
    <default class="thin"><geom type="capsule" size="0.02"/></default>
  </default>
</mujoco>
"""
INC_ARM = """<mujoco>
  <body name="upper" pos="0.1 0 0.05" quat="0.9 0.1 0.3 0.2">
    <joint name="shoulder"/>
    <geom class="thin" fromto="0 0 0 0.4 0 0"/>
    <include file="parts/hand.xml"/>
  </body>
</mujoco>
"""
INC_HAND = """<mujoco>
  <body name="hand" pos="0.4 0 0">
    <joint name="wrist" axis="1 0 0.5" frictionloss="0.1"/>
    <geom type="sphere" size="0.05" pos="0.05 0 0"/>
  </body>
</mujoco>
"""


def _inner(text):
    return text[len("<mujoco>\n"):-len("</mujoco>\n")]


# the same model in one file, each include replaced by the included file's children
INC_ONE = (INC_MAIN.replace('  <include file="parts/defaults.xml"/>\n', _inner(INC_DEFAULTS))
           .replace('      <include file="parts/arm.xml"/>\n', _inner(INC_ARM).replace(
               '    <include file="parts/hand.xml"/>\n', _inner(INC_HAND))))


def _included(tmp_path, **parts):
    (tmp_path / "parts").mkdir(exist_ok=True)
    files = {"parts/defaults.xml": INC_DEFAULTS, "parts/arm.xml": INC_ARM, "parts/hand.xml": INC_HAND}
    files.update({k.replace("__", "/") + ".xml": v for k, v in parts.items()})
    for name, text in files.items():
        _write(tmp_path, text, name)
    return _write(tmp_path, INC_MAIN)


def test_include_reads_as_one_file_and_as_mujoco(tmp_path):
    assert "include" not in INC_ONE
    m = ms.from_mjcf(_included(tmp_path))
    one = ms.from_mjcf(_write(tmp_path, INC_ONE, "one.xml"))
    assert m.compile().layout.q_names == one.compile().layout.q_names == ("yaw", "shoulder", "wrist")
    # the report names the included file an element came from
    assert f"{tmp_path / 'parts' / 'hand.xml'}, line 3: joint 'wrist' frictionloss" in str(m.import_report)
    Q, QD, QDD = RNG.normal(size=(3, 3))
    tau, tau1 = (x.inverse_dynamics(Q, QD, QDD).values for x in (m, one))
    np.testing.assert_allclose(tau, tau1, rtol=0, atol=1e-12 * np.abs(tau1).max())
    # MuJoCo reading the main file: the merged defaults (density 800 after 300), the nested
    # include found beside the main file, masses and frames
    mm, md = _reference(tmp_path / "model.xml")
    assert mm.nbody == 4
    _compare(m, mm, md)


@pytest.mark.parametrize("parts, match", [
    ({"parts__hand": "<mujoco>\n<body name='h'><include file='parts/gone.xml'/></body></mujoco>"},
     r"hand\.xml, line 2, <include>: included file 'parts/gone\.xml' not found"),
    ({"parts__hand": "<mujoco>\n <include file='parts/arm.xml'/>\n</mujoco>"},
     r"hand\.xml, line 2, <include>: 'parts/arm\.xml' closes an include cycle \(model\.xml -> "
     r"arm\.xml -> hand\.xml -> arm\.xml\)"),
    ({"parts__hand": "<mujoco>\n <include file='parts/defaults.xml'/>\n</mujoco>"},
     r"hand\.xml, line 2, <include>: 'parts/defaults\.xml' is already included"),
    ({"parts__hand": "<robot name='r'/>"},
     r"hand\.xml, line 1, <robot name='r'>: an included file's root element is <mujoco>.*"
     r"arm\.xml, line 5, <include>"),
    ({"parts__hand": "<mujoco>\n <body name='h'>\n  <joint name='w' axis='0 0 0'/>\n"
                     "  <geom size='0.1'/></body>\n</mujoco>"},
     r"hand\.xml, line 3, <joint name='w'>: the joint axis is zero"),
])
def test_include_refusals_name_file_and_line(tmp_path, parts, match):
    with pytest.raises(ms.ModelError, match=match):
        ms.from_mjcf(_included(tmp_path, **parts))


def test_include_size_limit_over_all_files(tmp_path, monkeypatch):
    import mechsys.io._mjcf as mjcf_mod

    path = _included(tmp_path)
    size = sum(p.stat().st_size for p in tmp_path.rglob("*.xml") if p.name != "one.xml")
    monkeypatch.setattr(mjcf_mod, "MAX_XML_BYTES", size - 1)     # each file fits, all do not
    with pytest.raises(ms.ModelError, match=r"arm\.xml, line 5, <include>: the included files "
                                            r"together pass the limit"):
        ms.from_mjcf(path)
    monkeypatch.setattr(mjcf_mod, "MAX_XML_BYTES", size)
    ms.from_mjcf(path)


@pytest.mark.parametrize("name", ["cheetah", "finger"])
def test_dm_control_suite_files_with_includes_against_mujoco(name, tmp_path, monkeypatch):
    """Real files: dm_control's suite models include ``./common/*.xml`` (visual, skybox,
    materials); the cheetah sets ``<compiler settotalmass>``, the finger disables gravity
    with ``<flag gravity="disable"/>``: both read as MuJoCo reads them."""
    import importlib.util

    spec = importlib.util.find_spec("dm_control")
    if spec is None:
        pytest.skip("dm_control is not installed")
    path = next(iter(spec.submodule_search_locations)) + f"/suite/{name}.xml"
    monkeypatch.chdir(tmp_path)     # MuJoCo logs settotalmass's deprecation to MUJOCO_LOG.TXT
    m = ms.from_mjcf(path)
    assert "common/visual.xml, line 2: <visual>" in str(m.import_report)
    mm, md = _reference(path)
    _compare(m, mm, md, points=1)


SPRINGDAMPER = """<mujoco>
  <default><joint axis="0 1 0" stiffness="0.5" damping="0.2" springref="10"/></default>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" springdamper="0.1 0.7"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.03"/>
      <body name="fore" pos="0.4 0 0">
        <joint name="elbow"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_springdamper_is_reported_not_replaced_by_class_values(tmp_path):
    """A joint's ``springdamper`` makes MuJoCo derive its stiffness and damping from the
    joint's inertia at qpos0, overriding the class's: the importer reports it and adds
    neither (before, the class's stiffness and damping were added, silently wrong, as the
    dm_control dog showed); the other joint keeps its spring and damper. Against
    ``mj_inverse`` with the springdamper joint's derived values zeroed (1e-9)."""
    path = _write(tmp_path, SPRINGDAMPER)
    m = ms.from_mjcf(path, joint_springs=True, joint_damping=True)
    assert any("'shoulder' springdamper=[0.1, 0.7]" in n for n in m.import_report.not_mapped)
    assert "shoulder" not in m.import_report.damping and m.import_report.damping["elbow"] == 0.2
    mm = mujoco.MjModel.from_xml_path(str(path))
    assert mm.jnt_stiffness[0] != 0.5 and mm.dof_damping[0] != 0.2      # MuJoCo's own values
    mm.jnt_stiffness[0] = mm.dof_damping[0] = 0.0
    md = mujoco.MjData(mm)
    q, qd, qdd = RNG.normal(size=(3, 2))
    md.qpos[:], md.qvel[:], md.qacc[:] = q, qd, qdd
    mujoco.mj_inverse(mm, md)
    np.testing.assert_allclose(m.inverse_dynamics(q, qd, qdd).values, md.qfrc_inverse, rtol=0,
                               atol=1e-9 * np.abs(md.qfrc_inverse).max())
    with pytest.raises(ms.ModelError, match="line 5.*springdamper=.*two positive numbers"):
        ms.from_mjcf(_write(tmp_path, SPRINGDAMPER.replace("0.1 0.7", "0 0.7"), "bad.xml"))
