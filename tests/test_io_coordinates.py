"""Imported robots in absolute coordinates (``coordinates="absolute"``), robot-style dynamics
on models with constraint equations, URDF planar joints and floating joints below the root
(decision 0048).

References: the same file imported in generalized coordinates (itself checked against
Pinocchio and MuJoCo in test_io_urdf.py / test_io_mjcf.py), Pinocchio's RNEA on a URDF
where the planar joint is written out by hand as two prismatic joints and a revolute one,
Pinocchio's own planar joint for the frames, MuJoCo's ``mj_forward`` on a free-floating
MJCF, and the work-energy balance of a closed loop.
"""

from __future__ import annotations

import numpy as np
import pytest

import mechsys as ms
from test_io_mjcf import BALL_FREE, FOUR_BAR, ZOO, _qmul
from test_io_urdf import ROBOTS, UR5, frame_poses, needs_robots

RNG = np.random.default_rng(48)


def _named(names, X):
    return {n: X[..., i] for i, n in enumerate(names)}


@needs_robots
def test_ur5_absolute_same_dynamics_as_generalized():
    """The UR5 with every link an absolute body and Revolute5 joints: link frames (1e-12),
    inverse dynamics (1e-9 relative) and forward dynamics (1e-9) equal the generalized
    import's (which equals Pinocchio's and MuJoCo's); the joint coordinates keep their
    names and the bodies' coordinates are solved from them."""
    path = ROBOTS / UR5
    mg = ms.from_urdf(path, geometry=False)
    ma = ms.from_urdf(path, coordinates="absolute", geometry=False)
    names = mg.compile().layout.q_names
    s = ma.compile()
    assert (s.n, s.m) == (6 * 7 + 6, 6 * 7) and set(names) <= set(s.layout.q_names)
    assert type(ma.constraint("elbow_joint")).__name__ == "Revolute5"
    Q, QD, QDD = RNG.uniform(-2.5, 2.5, size=(3, 3, 6))
    tau_g = mg.inverse_dynamics(Q, QD, QDD)
    tau_a = ma.inverse_dynamics(_named(names, Q), _named(names, QD), _named(names, QDD))
    assert tau_a.names == names
    np.testing.assert_allclose(tau_a.values, tau_g.values, rtol=0,
                               atol=1e-9 * np.abs(tau_g.values).max())
    acc = ma.forward_dynamics(_named(names, Q), _named(names, QD), tau_g.values)
    cols = [acc.names.index(n) for n in names]
    np.testing.assert_allclose(acc.values[:, cols], QDD, rtol=0, atol=1e-9 * np.abs(QDD).max())
    # the full states: frames of every link equal the generalized model's
    full = ma.forward_kinematics(_named(names, Q), list(ma.import_report.frames), frame=True)
    for k in range(len(Q)):
        ref = frame_poses(mg, Q[k])
        for i, link in enumerate(ma.import_report.frames):
            np.testing.assert_allclose(full[k, i], ref[link], atol=1e-12, err_msg=link)


def test_mjcf_armature_and_absolute_against_mujoco(tmp_path):
    """The MJCF zoo (several joints in one body, a hinge and a slide with ``ref``, frames)
    with ``armature=True`` (the joints' armature added to the mass matrix's diagonal, as
    MuJoCo does), in generalized and in absolute coordinates: joint forces equal
    ``mj_inverse``'s with the armature on (1e-9 relative), accelerations ``mj_forward``'s
    (1e-9)."""
    mujoco = pytest.importorskip("mujoco")
    path = tmp_path / "zoo.xml"
    path.write_text(ZOO)
    mg = ms.from_mjcf(path, geometry=False, armature=True)
    ma = ms.from_mjcf(path, geometry=False, coordinates="absolute", armature=True)
    assert not any("armature" in n for n in mg.import_report.not_mapped)
    names = mg.compile().layout.q_names
    s = ma.compile()
    # bodies with joints: upper, fore (+ one intermediate), slider; each 7 coordinates
    assert s.n == 4 * 7 + 4 and s.m == 4 * 7
    # the guess is the file's pose: the joint coordinates start at qpos0 (ref)
    g = dict(zip(s.layout.q_names, s.guess))
    assert g["elbow"] == pytest.approx(np.radians(25)) and g["slide"] == pytest.approx(0.03)
    mm = mujoco.MjModel.from_xml_path(str(path))
    mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    mm.dof_damping[:] = 0
    mm.jnt_stiffness[:] = 0
    assert np.all(mm.dof_armature == 0.01)
    md = mujoco.MjData(mm)
    Q, QD, QDD = RNG.normal(size=(3, 2, 4)) * 0.7
    tau_g = mg.inverse_dynamics(Q, QD, QDD).values
    tau_a = ma.inverse_dynamics(_named(names, Q), _named(names, QD), _named(names, QDD)).values
    acc_g = mg.forward_dynamics(Q, QD, tau_g).values
    acc_a = ma.forward_dynamics(_named(names, Q), _named(names, QD), tau_g)
    acc_a = acc_a.values[:, [acc_a.names.index(n) for n in names]]
    for k in range(len(Q)):
        md.qpos[:], md.qvel[:], md.qacc[:] = Q[k], QD[k], QDD[k]
        mujoco.mj_inverse(mm, md)
        ref = md.qfrc_inverse.copy()
        for got in (tau_g[k], tau_a[k]):
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * np.abs(ref).max())
        md.qfrc_applied[:] = tau_g[k]
        mujoco.mj_forward(mm, md)
        for got in (acc_g[k], acc_a[k]):
            np.testing.assert_allclose(got, md.qacc, rtol=0, atol=1e-9 * (1 + np.abs(md.qacc).max()))


def test_floating_base_forward_dynamics_against_mujoco(tmp_path):
    """A free base carrying a ball-jointed arm and a hinged hand (MJCF): ``forward_dynamics``
    on the augmented system from MuJoCo's state gives MuJoCo's accelerations: the base's
    linear acceleration (world), its angular acceleration (local, ``2 G(e) e_ddot``) and the
    hinge's (1e-9), in generalized and in absolute coordinates. ``inverse_dynamics`` gives the
    hinge torque back; a base acceleration that no hinge torque can produce is refused."""
    mujoco = pytest.importorskip("mujoco")
    from mechsys.io._mjcf import quat_matrix

    path = tmp_path / "ball_free.xml"
    path.write_text(BALL_FREE)
    m = ms.from_mjcf(path, geometry=False)
    s = m.compile()
    lay = s.layout
    mm = mujoco.MjModel.from_xml_path(str(path))
    md = mujoco.MjData(mm)
    eb, ea = (v / np.linalg.norm(v) for v in RNG.normal(size=(2, 4)))
    rb, wb_loc, vb, wa_rel = RNG.normal(size=(4, 3))
    wrist, wrist_d, torque = RNG.normal(size=3)
    md.qpos[:] = np.concatenate((rb, eb, ea, [wrist]))
    md.qvel[:] = np.concatenate((vb, wb_loc, wa_rel, [wrist_d]))
    md.qfrc_applied[:] = 0
    md.qfrc_applied[-1] = torque
    mujoco.mj_forward(mm, md)
    # the same state in mechsys coordinates (both bodies absolute)
    Rb = quat_matrix(eb)
    e_arm = _qmul(eb, ea)
    Ra = quat_matrix(e_arm)
    jp, off = np.array([0.05, 0, 0]), np.array([0.2, 0, 0])
    w_b = Rb @ wb_loc
    w_a = w_b + Ra @ wa_rel
    r_arm = rb + Rb @ (off + jp) - Ra @ jp
    v_arm = vb + np.cross(w_b, Rb @ (off + jp)) - np.cross(w_a, Ra @ jp)
    q, qd = np.zeros(s.n), np.zeros(s.n)
    for body, r, e, v, w in (("base", rb, eb, vb, w_b), ("arm", r_arm, e_arm, v_arm, w_a)):
        sl = lay.body_slices[body]
        q[sl] = np.concatenate((r, e))
        qd[sl] = np.concatenate((v, 0.5 * _qmul(np.concatenate(([0.0], w)), e)))
    iw = lay.q_names.index("wrist")
    q[iw], qd[iw] = wrist, wrist_d
    acc = m.forward_dynamics(q, qd, [torque])
    assert acc.names == lay.q_names
    qdd = acc.values
    base = lay.body_slices["base"]
    e_dd = qdd[base][3:]
    G = np.array([[-eb[1], eb[0], eb[3], -eb[2]], [-eb[2], -eb[3], eb[0], eb[1]],
                  [-eb[3], eb[2], -eb[1], eb[0]]])
    got = np.concatenate((qdd[base][:3], 2 * G @ e_dd, [qdd[iw]]))
    ref = np.concatenate((md.qacc[:6], md.qacc[-1:]))
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * max(1.0, np.abs(md.qacc).max()))
    # the same in absolute coordinates (the hand an absolute body on a Revolute5), its
    # coordinates solved from the generalized model's
    ma = ms.from_mjcf(path, geometry=False, coordinates="absolute")
    acc_a = ma.forward_dynamics(dict(zip(lay.q_names, q)), dict(zip(lay.q_names, qd)), [torque])
    np.testing.assert_allclose([acc_a[n] for n in lay.q_names], qdd, rtol=0,
                               atol=1e-9 * np.abs(qdd).max())
    tau = m.inverse_dynamics(q, qd, qdd)
    assert tau.names == ("wrist",)
    assert tau["wrist"] == pytest.approx(torque, rel=1e-9, abs=1e-12)
    bad = qdd.copy()
    bad[base.start] += 1.0                       # the base pushed along x with nothing to push it
    bad[lay.body_slices["arm"].start] += 1.0     # (the arm with it: the ball joint holds)
    with pytest.raises(ms.ModelError, match="not free to choose"):
        m.inverse_dynamics(q, qd, bad)


def test_closed_loop_inverse_dynamics_work_energy():
    """The MJCF four-bar (a ``connect`` loop, consistently redundant): the crank torque that
    drives ``crank(t) = 0.4 sin(3 t)`` from ``inverse_dynamics`` (the coupler and rocker
    solved from the loop), integrated as power ``tau qd_crank`` over time, equals the gain in
    kinetic plus potential energy (Simpson, 1e-7 relative). The crank is actuated alone;
    actuating the rocker too is refused (the loop alone can hold both)."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "four_bar.xml"
        path.write_text(FOUR_BAR)
        m = ms.from_mjcf(path, geometry=False)
        s = m.compile()
    t = np.linspace(0.0, 1.0, 101)
    crank = {"crank_joint": 0.4 * np.sin(3 * t)}
    crank_d = {"crank_joint": 1.2 * np.cos(3 * t)}
    crank_dd = {"crank_joint": -3.6 * np.sin(3 * t)}
    tau = m.inverse_dynamics(crank, crank_d, crank_dd, actuated="crank_joint")
    assert tau.names == ("crank_joint",)
    power = tau["crank_joint"] * crank_d["crank_joint"]
    work = (t[1] - t[0]) / 3 * (power[0] + power[-1] + 4 * power[1:-1:2].sum() + 2 * power[2:-1:2].sum())
    # energy at the ends, from full states solved here independently of inverse_dynamics
    from mechsys.analyses._robot import _augmented, _complete

    names = s.layout.q_names
    ic = np.array([names.index("crank_joint")])
    Q, QD = _complete(s, "test", 0.0, crank["crank_joint"][[0, -1], None], ic,
                      crank_d["crank_joint"][[0, -1], None], None, ic, None)[:2]
    E = []
    for k in range(2):
        M = _augmented(s, 0.0, Q[k], QD[k])[0]
        z = m.forward_kinematics(Q[k], [b.point(tuple(float(c) for c in b.centroid)) for b in m.bodies[1:]])
        V = sum(9.81 * float(b.mass) * z_[2] for b, z_ in zip(m.bodies[1:], z))
        E.append(0.5 * QD[k] @ M @ QD[k] + V)
    assert work == pytest.approx(E[1] - E[0], rel=1e-7, abs=1e-9)
    with pytest.raises(ms.ModelError, match="not unique"):
        m.inverse_dynamics(crank, crank_d, crank_dd, actuated=["crank_joint", "rocker_joint"])


PLANAR = """<robot name="planar">
 <link name="base"/>
 <link name="cart"><inertial><origin xyz="0.1 0.05 0.02" rpy="0.2 0 0.1"/><mass value="2"/>
   <inertia ixx="0.1" ixy="0.01" ixz="0.002" iyy="0.2" iyz="-0.01" izz="0.25"/></inertial></link>
 <link name="arm"><inertial><origin xyz="0.3 0 0.1"/><mass value="1"/>
   <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>
 <joint name="glide" type="planar"><parent link="base"/><child link="cart"/>
   <origin xyz="0 0.1 0.5" rpy="0.3 0.2 0.1"/><axis xyz="0 0 1"/><limit effort="1" velocity="1"/></joint>
 <joint name="hinge" type="revolute"><parent link="cart"/><child link="arm"/>
   <origin xyz="0.2 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""

# the same robot with the planar joint written out by hand: two slides and a turn
EXPANDED = PLANAR.replace(
    """ <joint name="glide" type="planar"><parent link="base"/><child link="cart"/>
   <origin xyz="0 0.1 0.5" rpy="0.3 0.2 0.1"/><axis xyz="0 0 1"/><limit effort="1" velocity="1"/></joint>""",
    """ <link name="px"/><link name="py"/>
 <joint name="glide_x" type="prismatic"><parent link="base"/><child link="px"/>
   <origin xyz="0 0.1 0.5" rpy="0.3 0.2 0.1"/><axis xyz="1 0 0"/>
   <limit lower="-9" upper="9" effort="1" velocity="1"/></joint>
 <joint name="glide_y" type="prismatic"><parent link="px"/><child link="py"/>
   <axis xyz="0 1 0"/><limit lower="-9" upper="9" effort="1" velocity="1"/></joint>
 <joint name="glide_theta" type="revolute"><parent link="py"/><child link="cart"/><axis xyz="0 0 1"/>
   <limit lower="-9" upper="9" effort="1" velocity="1"/></joint>""")


def test_planar_joint_against_pinocchio(tmp_path):
    """A URDF ``planar`` joint: three coordinates ``glide_x, glide_y, glide_theta`` (slides in
    the joint frame's x-y plane, then the turn about z): frames equal those of Pinocchio's
    own planar joint at ``(x, y, cos, sin)`` (1e-12), and the joint forces Pinocchio's RNEA
    on the hand-expanded file (1e-9 relative), in generalized and absolute coordinates."""
    pin = pytest.importorskip("pinocchio")
    path = tmp_path / "planar.urdf"
    path.write_text(PLANAR)
    m = ms.from_urdf(path)
    rep = m.import_report
    assert rep.joints["glide"] == ("planar", ("glide_x", "glide_y", "glide_theta"), "cart")
    assert any("<limit> (not mapped on a planar joint" in n for n in rep.not_mapped)
    names = m.compile().layout.q_names
    assert names == ("glide_x", "glide_y", "glide_theta", "hinge")
    pm = pin.buildModelFromXML(PLANAR)
    pd = pm.createData()
    pe = pin.buildModelFromXML(EXPANDED)
    pde = pe.createData()
    assert tuple(pe.names[1:]) == names
    ma = ms.from_urdf(path, coordinates="absolute")
    for _ in range(2):
        q = RNG.uniform(-2, 2, size=4)
        qd, qdd = RNG.normal(size=(2, 4))
        pin.framesForwardKinematics(pm, pd, np.array([q[0], q[1], np.cos(q[2]), np.sin(q[2]), q[3]]))
        for link, M in frame_poses(m, q).items():
            if pm.existFrame(link):
                np.testing.assert_allclose(M, pd.oMf[pm.getFrameId(link)].homogeneous, atol=1e-12,
                                           err_msg=link)
        ref = pin.rnea(pe, pde, q, qd, qdd)
        np.testing.assert_allclose(m.inverse_dynamics(q, qd, qdd).values, ref, rtol=0,
                                   atol=1e-9 * np.abs(ref).max())
        got = ma.inverse_dynamics(_named(names, q), _named(names, qd), _named(names, qdd))
        np.testing.assert_allclose(got.values, ref, rtol=0, atol=1e-9 * np.abs(ref).max())


FLOAT_BELOW = """<robot name="fb">
 <link name="base"/>
 <link name="arm"><inertial><origin xyz="0.2 0 0"/><mass value="1"/>
   <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
 <link name="drone"><inertial><mass value="0.5"/>
   <inertia ixx="0.003" ixy="0" ixz="0" iyy="0.003" iyz="0" izz="0.005"/></inertial></link>
 <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/>
   <origin xyz="0 0 1"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
 <joint name="release" type="floating"><parent link="arm"/><child link="drone"/>
   <origin xyz="0.4 0 0" rpy="0 0.5 0"/><dynamics damping="1"/></joint>
</robot>"""


def test_floating_joint_below_the_root(tmp_path):
    """A ``floating`` joint on a moving link: its child a free body with global coordinates
    placed at the joint's origin at zero joint coordinates (noted in the report, with the
    joint's ``<dynamics>`` that has no counterpart); it transmits nothing: the drone falls at
    ``g`` and the arm's torque is the arm's alone (closed form ``m g c cos(q) + (I + m c^2)
    qdd`` about the shoulder)."""
    path = tmp_path / "fb.urdf"
    path.write_text(FLOAT_BELOW)
    m = ms.from_urdf(path)
    rep = m.import_report
    assert rep.joints["release"][0] == "floating" and rep.joints["release"][2] == "drone"
    assert any("below the root" in n and "'drone'" in n for n in rep.not_mapped)
    assert any("<dynamics> (not mapped on a floating joint" in n for n in rep.not_mapped)
    s = m.compile()
    g = dict(zip(s.layout.q_names, s.guess))
    np.testing.assert_allclose([g["drone.x"], g["drone.y"], g["drone.z"]], [0.4, 0, 1], atol=1e-15)
    np.testing.assert_allclose([g["drone.e0"], g["drone.e2"]], [np.cos(0.25), np.sin(0.25)], atol=1e-15)
    q = {"shoulder": 0.3, **{n: g[n] for n in s.layout.q_names if n.startswith("drone.")}}
    zero = {n: 0.0 for n in s.layout.q_names}
    acc = m.forward_dynamics(q, zero, [0.0])
    np.testing.assert_allclose(acc["drone.z"], -9.81, atol=1e-12)
    qdd = dict(zip(acc.names, np.array(acc.values)))
    qdd["shoulder"] = 2.0
    tau = m.inverse_dynamics(q, zero, qdd)
    # arm about y: gravity moment of the centroid at (0.2 cos q, 0, -0.2 sin q) from the pivot
    expected = (0.02 + 1 * 0.2**2) * 2.0 - 9.81 * 1 * 0.2 * np.cos(0.3)
    assert tau["shoulder"] == pytest.approx(expected, rel=1e-12)


def test_option_and_state_errors(tmp_path):
    path = tmp_path / "planar.urdf"
    path.write_text(PLANAR)
    with pytest.raises(ms.OptionError, match="coordinates='joint' is 'generalized' or 'absolute'"):
        ms.from_urdf(path, coordinates="joint")
    ma = ms.from_urdf(path, coordinates="absolute", geometry=False)
    n = ma.compile().n
    with pytest.raises(ms.ModelError, match="positions of point 0 violate the constraint"):
        ma.forward_dynamics(np.zeros(n), np.zeros(n), np.zeros(4))
    with pytest.raises(ms.ModelError, match=r"do not determine the others"):
        ma.forward_kinematics({"glide_x": 0.1}, "arm")
    with pytest.raises(ms.ModelError, match=r"actuated names \['cart.q'\]"):
        ma.inverse_dynamics({"glide_x": 0, "glide_y": 0, "glide_theta": 0, "hinge": 0},
                            {"glide_x": 0, "glide_y": 0, "glide_theta": 0, "hinge": 0},
                            {"glide_x": 0, "glide_y": 0, "glide_theta": 0, "hinge": 0},
                            actuated=["cart.q"])


def test_mujoco_test_model_imports_and_reports():
    """MuJoCo's own test model (shipped in the mujoco package's ``testdata``; nobody here wrote
    it): it imports; its unnamed hinge gets a coordinate named after its body, and what has no
    counterpart is reported with its line -- fluid forces (``<option density viscosity
    wind>``), gravity compensation, tendons, actuators, sensors, the joints' armature,
    damping and springs; the bodies' masses, the mesh geom's included, are MuJoCo's."""
    mujoco = pytest.importorskip("mujoco")
    from pathlib import Path

    path = Path(mujoco.__file__).parent / "testdata" / "model.xml"
    if not path.is_file():
        pytest.skip("the mujoco package ships no testdata/model.xml")
    m = ms.from_mjcf(path, geometry=False)
    rep = m.import_report
    text = str(rep)
    mm = mujoco.MjModel.from_xml_path(str(path))
    assert len(rep.joints) == mm.njnt
    unnamed = [n for n in rep.joints if n.endswith("_hinge1")]
    assert unnamed and f"its coordinate is named {unnamed[0]!r}" in text
    for what in ("<option density=...>", "<option viscosity=...>", "<option wind=...>",
                 "gravcomp=0.5", "<tendon>", "<actuator>", "<sensor>",
                 "armature=1.0", "damping 10.0", "stiffness 60.0"):
        assert what in text, what
    # the masses, the mesh geom's among them (computed as MuJoCo does, decision 0072)
    ours = {b.name: float(b.mass) for b in m.bodies}
    assert sum(ours.values()) == pytest.approx(float(mm.body_mass.sum()), rel=1e-12)
    for k in range(1, mm.nbody):
        if mm.body(k).name:
            assert ours[mm.body(k).name] == pytest.approx(float(mm.body_mass[k]), rel=1e-12)


def _zoo_reference(path):
    mujoco = pytest.importorskip("mujoco")
    mm = mujoco.MjModel.from_xml_path(str(path))
    mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    mm.dof_damping[:] = 0
    mm.jnt_stiffness[:] = 0
    return mujoco, mm, mujoco.MjData(mm)


def test_armature_in_the_fast_paths_against_mujoco(tmp_path, monkeypatch):
    """Armature on every path of the recursive Gen dynamics (decision 0057), against
    MuJoCo with its armature on: the O(N) articulated-body recursion (compiled and plain
    Python) gives ``mj_forward``'s accelerations; the compiled free-motion stepper takes
    every step and its accelerations along the motion are ``mj_forward``'s at the same
    states; the compiled multiplier solves of a driven sweep give joint torques equal to
    ``mj_inverse``'s (1e-9 relative)."""
    import sympy as sp

    path = tmp_path / "zoo.xml"
    path.write_text(ZOO)
    mujoco, mm, md = _zoo_reference(path)
    assert np.all(mm.dof_armature == 0.01)
    m = ms.from_mjcf(path, geometry=False, armature=True)
    s = m.compile()
    d = s.dynamics
    assert getattr(d, "recursive", False) and d.tree_only          # the O(N) recursion runs
    Q, QD = RNG.normal(size=(2, 3, 4))
    for engine in ("compiled", "python"):
        if engine == "python":
            d._numba = False
        for q, qd in zip(Q, QD):
            md.qpos[:], md.qvel[:], md.qfrc_applied[:] = q, qd, 0.0
            mujoco.mj_forward(mm, md)
            got = d.accelerations(0.0, q, qd, s.p_values)
            np.testing.assert_allclose(got, md.qacc, rtol=0, atol=1e-9 * np.abs(md.qacc).max(),
                                       err_msg=engine)
    # free motion, compiled stepper (armature used to send it to the Python stepper)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    m = ms.from_mjcf(path, geometry=False, armature=True)
    sol = m.free().simulate((0.0, 0.05), rtol=1e-10, atol=1e-10)
    assert sol.extra["compiled_steps"] == sol.extra["steps"] > 0
    for k in range(0, len(sol.t), max(1, len(sol.t) // 4)):
        md.qpos[:], md.qvel[:], md.qfrc_applied[:] = sol.q[k], sol.qd[k], 0.0
        mujoco.mj_forward(mm, md)
        np.testing.assert_allclose(sol.qdd[k], md.qacc, rtol=0,
                                   atol=1e-9 * np.abs(md.qacc).max())
    # every joint driven: the compiled multiplier solves give the drives' forces
    m = ms.from_mjcf(path, geometry=False, armature=True)
    names = m.compile().layout.q_names
    for k, n in enumerate(names):
        c = m.compile().layout.q_symbols[k]
        m.add(ms.Constraint([c - 0.2 * sp.sin((k + 1) * ms.T) - 0.1 * k]), name=f"drive_{n}")
    from test_jit_multipliers import spy_multipliers

    taken = spy_multipliers(monkeypatch)
    t = np.linspace(0.0, 1.0, 9)
    sol = m.solve(t, solution="dynamic")
    assert sol.extra["compiled_points"] == len(t) and taken == [len(t)]
    for k in range(len(t)):
        md.qpos[:], md.qvel[:], md.qacc[:] = sol.q[k], sol.qd[k], sol.qdd[k]
        mujoco.mj_inverse(mm, md)
        ref = md.qfrc_inverse
        # M qdd + Phi_q^T lambda = Q + Qv with Phi_q = I: the joint force is -lambda
        np.testing.assert_allclose(-sol.lam[k], ref, rtol=0, atol=1e-9 * np.abs(ref).max())
