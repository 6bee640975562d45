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


# -- absolute bodies and equalities (decision 0067) -------------------------------------------
FLOATING = """<mujoco model="floating">
  <compiler angle="radian"/>
  <option gravity="0.3 -0.2 -9.6"/>
  <worldbody>
    <body name="base" pos="0.1 0.2 1.0" quat="0.9 0.1 -0.3 0.2">
      <freejoint name="root"/>
      <geom type="box" size="0.2 0.1 0.05"/>
      <body name="arm" pos="0.2 0.05 0" euler="0.3 -0.2 0.5">
        <joint name="shoulder" type="ball" pos="0.05 0.01 -0.02"/>
        <geom type="capsule" fromto="0.05 0 0 0.35 0 0.1" size="0.03"/>
        <body name="hand" pos="0.35 0 0.1" quat="0.8 0.2 0.1 -0.4">
          <joint name="wrist" axis="0 1 0.3" pos="0.01 0 0"/>
          <geom type="ellipsoid" size="0.05 0.03 0.08" pos="0.05 0 0"/>
        </body>
      </body>
    </body>
    <body name="bob" pos="0.5 -0.3 0.8" quat="0.6 0.3 0.2 0.1">
      <joint name="pivot" type="ball" pos="0 0 0.2"/>
      <geom type="box" size="0.05 0.06 0.2"/>
    </body>
  </worldbody>
</mujoco>
"""

LOOPS = """<mujoco model="loops">
  <compiler angle="radian"/>
  <worldbody>
    <body name="crank" pos="0 0 0.5" euler="0.1 0.2 0.3">
      <joint name="crank_joint" axis="0 1 0.2"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>
      <body name="link" pos="0.3 0 0">
        <joint name="link_joint" axis="0.1 0 1"/>
        <geom type="capsule" fromto="0 0 0 0 0.25 0.05" size="0.02"/>
      </body>
    </body>
    <body name="float" pos="0.3 0.25 0.55" quat="0.9 0.2 0.1 0.3">
      <joint name="hang" type="ball" pos="0 0 0.1"/>
      <geom type="box" size="0.05 0.04 0.03"/>
    </body>
    <body name="plate" pos="-0.2 0.1 0.4" euler="0.4 0 -0.3">
      <freejoint/>
      <geom type="box" size="0.1 0.08 0.01"/>
    </body>
  </worldbody>
  <equality>
    <connect name="tie" body1="float" body2="link" anchor="0.02 0.01 0"/>
    <weld name="glue" body1="plate" body2="crank" anchor="0.05 0 0"/>
    <joint name="mesh" joint1="link_joint" joint2="crank_joint" polycoef="0.1 -2 0.3 0 0.05"/>
  </equality>
</mujoco>
"""


def _dense(K):
    return np.asarray(K.todense() if hasattr(K, "todense") else K)


def _same_system(m1, m2, points=3, dynamics=True):
    """``m2`` is ``m1`` again: the same coordinates, bodies (mass, centroid, inertia),
    constraints (by name and type) and guesses; at random states the same constraint
    residuals, Jacobian and gamma and (``dynamics``) the same augmented free-motion system
    ``K = [[M, Phi_q^T], [Phi_q, 0]]``, ``rhs = [Q + Qv; gamma]`` (mass matrix, bias forces),
    to 1e-12 relative. Returns ``m1``'s system."""
    s1, s2 = m1.compile(), m2.compile()
    assert s2.layout.q_names == s1.layout.q_names
    assert [(c.name, type(c).__name__) for c in m2.constraints] == \
        [(c.name, type(c).__name__) for c in m1.constraints]
    np.testing.assert_allclose(m2.guess(), m1.guess(), rtol=0, atol=1e-15)
    for b1, b2 in zip(m1.bodies[1:], m2.bodies[1:], strict=True):
        assert b2.name == b1.name and float(b2.mass) == pytest.approx(float(b1.mass), rel=1e-15)
        for a1, a2 in ((b1.centroid, b2.centroid), (m1.space.inertia_matrix(b1.inertia),
                                                    m2.space.inertia_matrix(b2.inertia))):
            np.testing.assert_allclose(np.asarray(a2, float), np.asarray(a1, float), rtol=0, atol=1e-15)

    def close(a2, a1):
        a1, a2 = _dense(a1), _dense(a2)
        np.testing.assert_allclose(a2, a1, rtol=0, atol=1e-12 * max(1.0, np.abs(a1).max()))

    kerns = (s1.dynamics.free_kernel(), s2.dynamics.free_kernel()) if dynamics else None
    for _ in range(points):
        q, qd = RNG.normal(size=(2, s1.n))
        close(s2.residual(0.0, q), s1.residual(0.0, q))
        close(s2.jacobian(0.0, q), s1.jacobian(0.0, q))
        close(s2.gamma_values(0.0, q, qd), s1.gamma_values(0.0, q, qd))
        if dynamics:
            (K1, b1), (K2, b2) = (k(0.0, q, qd, np.zeros(s.m), s.p_values)
                                  for k, s in zip(kerns, (s1, s2)))
            close(K2, K1)
            close(b2, b1)
    return s1


def _G(e):
    """:math:`\\omega = 2 G(e) \\dot e` (global angular velocity of Euler parameters ``e``)."""
    e0, e1, e2, e3 = e
    return np.array([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])


def _mujoco_masses_agree(mujoco, mm, m):
    """MuJoCo's bodies of the export carry the mechsys bodies' masses, centroids (body frame)
    and principal moments."""
    for b in m.bodies[1:]:
        i = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_BODY, b.name)
        I = np.asarray(m.space.inertia_matrix(b.inertia), float)
        assert mm.body_mass[i] == pytest.approx(float(b.mass), rel=1e-14)
        np.testing.assert_allclose(np.sort(mm.body_inertia[i]), np.linalg.eigvalsh(I), rtol=1e-12)
        np.testing.assert_allclose(mm.body_ipos[i], np.ravel(b.centroid).astype(float), atol=1e-15)


def test_free_and_ball_bodies_round_trip_and_mujoco_agrees(tmp_path):
    """A free base carrying a ball-jointed arm and a hinged hand, and a body on a ball joint
    to ground (all frames oblique): exported as ``<freejoint>``, ``ball`` joints and a hinge
    (decision 0067), read back as the same system (1e-12), and MuJoCo reading the export has
    the same masses and joint layout and, with contacts off, the same accelerations as
    mechsys's augmented system at random states: the free base's and the ball bodies' world
    linear and angular accelerations (``mj_objectAcceleration``) and the hinge's, 1e-9."""
    mujoco = pytest.importorskip("mujoco")
    src = tmp_path / "floating.xml"
    src.write_text(FLOATING)
    m = ms.from_mjcf(src, geometry=False)
    out = m.to_mjcf(tmp_path / "out.xml")
    text = out.read_text()
    assert "<freejoint/>" in text and 'name="shoulder" type="ball"' in text
    s = _same_system(m, ms.from_mjcf(out))
    mm = mujoco.MjModel.from_xml_path(str(out))
    mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    J = mujoco.mjtJoint
    assert list(mm.jnt_type) == [J.mjJNT_FREE, J.mjJNT_BALL, J.mjJNT_HINGE, J.mjJNT_BALL]
    assert [mujoco.mj_id2name(mm, mujoco.mjtObj.mjOBJ_JOINT, i) for i in range(1, 4)] == \
        ["shoulder", "wrist", "pivot"]
    _mujoco_masses_agree(mujoco, mm, m)
    md = mujoco.MjData(mm)
    lay, kern = s.layout, s.dynamics.free_kernel()
    iw = lay.q_names.index("wrist")
    wrist = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_JOINT, "wrist")
    g = np.array([0.3, -0.2, -9.6])
    for _ in range(2):
        md.qpos[:], md.qvel[:] = RNG.normal(size=mm.nq), RNG.normal(size=mm.nv)
        mujoco.mj_normalizeQuat(mm, md.qpos)
        mujoco.mj_forward(mm, md)
        mujoco.mj_rnePostConstraint(mm, md)
        # mechsys's state from MuJoCo's body frames (the export's body frames are mechsys's)
        q, qd, acc = np.zeros(s.n), np.zeros(s.n), {}
        for name in ("base", "arm", "bob"):
            i = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_XBODY, name)
            v, a = np.zeros(6), np.zeros(6)
            mujoco.mj_objectVelocity(mm, md, mujoco.mjtObj.mjOBJ_XBODY, i, v, 0)
            mujoco.mj_objectAcceleration(mm, md, mujoco.mjtObj.mjOBJ_XBODY, i, a, 0)
            sl = lay.body_slices[name]
            q[sl] = np.concatenate((md.xpos[i], md.xquat[i]))
            qd[sl] = np.concatenate((v[3:], 0.5 * _G(md.xquat[i]).T @ v[:3]))
            acc[name] = a
        q[iw], qd[iw] = md.qpos[mm.jnt_qposadr[wrist]], md.qvel[mm.jnt_dofadr[wrist]]
        K, rhs = kern(0.0, q, qd, np.zeros(s.m), s.p_values)
        qdd = np.linalg.solve(_dense(K), rhs)[:s.n]
        scale = 1 + np.abs(md.qacc).max()
        for name, a in acc.items():
            sl = lay.body_slices[name]
            # MuJoCo's accelerations include the world's -g (its recursion's trick)
            np.testing.assert_allclose(qdd[sl][:3], a[3:] + g, rtol=0, atol=1e-9 * scale)
            np.testing.assert_allclose(2 * _G(q[sl][3:]) @ qdd[sl][3:], a[:3], rtol=0, atol=1e-9 * scale)
        assert abs(qdd[iw] - md.qacc[mm.jnt_dofadr[wrist]]) <= 1e-9 * scale


def test_closed_loops_round_trip_and_mujoco_reads_the_equalities(tmp_path):
    """A crank and link on hinges, a body on a ball joint to ground tied to the link
    (``connect``), a free plate welded to the crank (``weld``) and the link's angle a
    polynomial of the crank's (``joint``): the equalities are written between sites (MuJoCo
    makes the sites, and for a weld their frames, coincide), so the export does not depend
    on the file's pose; here the plate's guess is moved off the weld to show it. Read back:
    the same system (residuals, mass matrix, bias forces, constraint rows; 1e-12). MuJoCo
    reading the export: its connect and weld residuals vanish at the original file's
    ``qpos0`` (where the importer closed them; 1e-12), and at a random pose all its equality rows
    (connect, weld position and rotation, joint) equal mechsys's equations (1e-12): the
    importer reads a site weld as MuJoCo does, the sites' frames welded."""
    mujoco = pytest.importorskip("mujoco")
    src = tmp_path / "loops.xml"
    src.write_text(LOOPS)
    m = ms.from_mjcf(src, geometry=False)
    e = np.array([0.9, 0.3, 0.1, -0.2]) / np.linalg.norm([0.9, 0.3, 0.1, -0.2])
    m.set_guess({f"plate.e{k}": v for k, v in enumerate(e)})   # off the weld: sites carry it
    out = m.to_mjcf(tmp_path / "out.xml")
    text = out.read_text()
    for line in ('<connect name="tie" site1="tie_site1" site2="tie_site2"/>',
                 '<weld name="glue" site1="glue_site1" site2="glue_site2"/>',
                 '<joint name="mesh" joint1="link_joint" joint2="crank_joint" '
                 'polycoef="0.1 -2.0 0.3 -0.0 0.05"/>'):
        assert line in text
    s = _same_system(m, ms.from_mjcf(out), dynamics=False)     # (the dynamics: above)
    mm = mujoco.MjModel.from_xml_path(str(out))
    md = mujoco.MjData(mm)
    E = mujoco.mjtEq
    assert list(mm.eq_type) == [E.mjEQ_CONNECT, E.mjEQ_WELD, E.mjEQ_JOINT]
    _mujoco_masses_agree(mujoco, mm, m)
    md.qpos[:] = mm.qpos0                             # the export's pose: off the weld
    mujoco.mj_forward(mm, md)
    assert np.abs(md.efc_pos[3:9]).max() > 0.05
    orig = mujoco.MjModel.from_xml_path(str(src))
    md.qpos[:] = orig.qpos0                           # same joints in the same order
    mujoco.mj_forward(mm, md)
    assert md.nefc == 3 + 6 + 1
    np.testing.assert_allclose(md.efc_pos[:9], 0, atol=1e-12)     # connect, weld
    assert md.efc_pos[9] == pytest.approx(-0.1, abs=1e-15)          # 0 - poly(0): not closed there
    md.qpos[:] = RNG.normal(size=mm.nq)
    mujoco.mj_normalizeQuat(mm, md.qpos)
    mujoco.mj_forward(mm, md)
    q = np.zeros(s.n)
    for name in ("float", "plate"):
        i = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_BODY, name)
        q[s.layout.body_slices[name]] = np.concatenate((md.xpos[i], md.xquat[i]))
    for j in ("crank_joint", "link_joint"):
        jid = mujoco.mj_name2id(mm, mujoco.mjtObj.mjOBJ_JOINT, j)
        q[s.layout.q_names.index(j)] = md.qpos[mm.jnt_qposadr[jid]]
    r = s.residual(0.0, q)
    rows = [k for c in ("tie", "glue", "glue_rotation", "mesh")
            for k, o in enumerate(s.layout.eq_owner) if getattr(o, "name", None) == c]
    # MuJoCo's rows: connect, weld (position, then the relative quaternion's vector part),
    # joint: mechsys's equations, row for row
    np.testing.assert_allclose(r[rows], md.efc_pos[:10], rtol=0, atol=1e-12)


def test_urdf_floating_base_round_trip(tmp_path):
    """A floating base (``from_urdf(floating_base=True)``) is written as a ``floating`` joint
    from the world link at the base's guessed pose; the URDF importer reads it back as the
    same free body, guessed at the same pose, carrying the same joints (frames, masses; 1e-15)
    and constraint rows (1e-12)."""
    src = tmp_path / "arm.urdf"
    src.write_text(ARM.replace('<link name="base"/>', '<link name="base"><inertial><mass value="3.0"/>'
                               '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.25"/>'
                               '</inertial></link>'))
    m = ms.from_urdf(src, floating_base=True, geometry=False)
    e = np.array([0.8, 0.1, -0.4, 0.3]) / np.linalg.norm([0.8, 0.1, -0.4, 0.3])
    m.set_guess({"base.x": 0.3, "base.y": -0.2, "base.z": 1.1, **{f"base.e{k}": v for k, v in enumerate(e)}})
    u = m.to_urdf(tmp_path / "out.urdf")
    assert '<joint name="base_floating" type="floating">' in u.read_text()
    back = ms.from_urdf(u)
    _same_system(m, back, dynamics=False)
    for j1, j2 in zip(m.constraints, back.constraints, strict=True):
        for f1, f2 in zip(j1._frames(m.space), j2._frames(back.space), strict=True):
            np.testing.assert_allclose(np.asarray(f2, float), np.asarray(f1, float), rtol=0, atol=1e-15)


def _two_bodies():
    """Two bodies on hinges ``qa``, ``qb`` to ground and an absolute body ``c``."""
    m = ms.Model3D()
    kw = dict(mass=1.0, inertia=(0.1, 0.2, 0.25))
    a, b, c = (m.add_body(n, **kw) for n in "abc")
    for body, q in ((a, "qa"), (b, "qb")):
        m.add(ms.GenRevolute5(body.axis((0, 0, 0), (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)),
                              (q, 0.0)), name=f"hinge_{body.name}")
    return m, a, b, c


@pytest.mark.parametrize("case, match", [
    ("other type", "constraint 'lock' .*OriginLock3.* has no MJCF counterpart"),
    ("rotation only", "constraint 'turn' .*RotationLock3.* locks a relative rotation only"),
    ("absolute coordinate", r"constraint 'eq' .* depends on \['x4'\]"),
    ("not a polynomial", "constraint 'eq' .* is not a polynomial"),
    ("nonlinear", "constraint 'eq' .* is not linear in one coordinate"),
    ("variables", r"constraint 'eq' .* adds variables \['s'\]"),
    ("two equations", "constraint 'eq' .* has 2 equations"),
    ("massless free body", "body 'c' has a free joint and has no mass"),
    ("no rotation guessed", r"the guess of body 'c' has Euler parameters \[0.0, 0.0, 0.0, 0.0\]"),
    ("point on a merged body", "constraint 'tie' .* has a point on body 'h'"),
    ("joint names", "the joint of body 'c' and the joint of body 'a' would both be MJCF joints named 'qa'"),
    ("urdf ball", "to_urdf: constraint 'ball' .* use to_mjcf"),
    ("urdf floating name", "floating joint of body 'c' would be named 'c_floating'"),
])
def test_refusals_of_absolute_bodies_and_equalities_name_the_culprit(tmp_path, case, match):
    """What MJCF (or URDF) cannot hold of absolute bodies and equations is refused with a
    ``ModelError`` naming the constraint or body (decision 0067), before a file is written."""
    m, a, b, c = _two_bodies()
    qa, qb = sp.symbols("qa qb")
    fmt = "mjcf"
    if case == "other type":
        m.add(ms.OriginLock3(c), name="lock")
    elif case == "rotation only":
        m.add(ms.RotationLock3(c, a), name="turn")
    elif case == "absolute coordinate":
        m.add(ms.Constraint(c.q[0] - qa), name="eq")
    elif case == "not a polynomial":
        m.add(ms.Constraint(sp.sin(qa) - qb), name="eq")
    elif case == "nonlinear":
        m.add(ms.Constraint(qa**2 + qb**2 - 1), name="eq")
    elif case == "variables":
        m.add(ms.Constraint([qa - sp.Symbol("s")], {sp.Symbol("s"): 0.0}), name="eq")
    elif case == "two equations":
        m.add(ms.Constraint([qa - qb, qa + qb]), name="eq")
    elif case == "massless free body":
        m.set_mass_properties(c, mass=0, inertia=(0, 0, 0))
    elif case == "no rotation guessed":
        m.set_guess({"c.e0": 0.0})
    elif case == "point on a merged body":
        h = m.add_body("h")                            # massless, carrying one hinge: merged
        m.add(ms.GenRevolute5(h.axis((0, 0, 0), (1, 0, 0)), a.axis((0, 0, 0.1), (1, 0, 0)),
                              ("qh", 0.0)), name="hinge_h")
        d = m.add_body("d", mass=1.0, inertia=(0.1, 0.2, 0.25))
        m.add(ms.GenRevolute5(d.axis((0, 0, 0), (0, 1, 0)), h.axis((0, 0, 0), (0, 1, 0)),
                              ("qd", 0.0)), name="hinge_d")
        m.add(ms.Spherical3(h.point((0.1, 0, 0)), b.point((0, 0.1, 0))), name="tie")
    elif case == "joint names":
        m.add(ms.Spherical3(c.point((0, 0, 0)), a.point((0, 0, 0.2))), name="qa")
    elif case == "urdf ball":
        m.add(ms.Spherical3(c.point((0, 0, 0)), a.point((0, 0, 0.2))), name="ball")
        fmt = "urdf"
    elif case == "urdf floating name":
        m.add(ms.GenRevolute5(m.add_body("e", mass=1.0, inertia=(0.1, 0.2, 0.25)).axis((0, 0, 0)),
                              a.axis((0, 0, 0)), ("c_floating", 0.0)), name="hinge_e")
        fmt = "urdf"
    path = tmp_path / f"x.{fmt}"
    with pytest.raises(ms.ModelError, match=match):
        getattr(m, f"to_{fmt}")(path)
    assert not path.exists()
