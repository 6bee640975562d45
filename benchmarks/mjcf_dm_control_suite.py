"""dm_control's MJCF files against MuJoCo (decisions 0070 and 0072); not run by the tests.

1. The suite's fixed-base files that use ``<include>``: ``ms.from_mjcf`` against
   ``mj_inverse`` at a random state (constraints, damping, armature, springs and fluid
   forces off in MuJoCo, not mapped in mechsys), relative to the largest torque.
2. The suite's free-base files (humanoid, humanoid_CMU, quadruped, dog, fish) and the
   locomotion walkers ``dog_v2`` and ``fruitfly_v2`` (mesh bones): inverse
   dynamics against ``mj_inverse`` and forward dynamics against ``mj_forward`` at random
   states, with what mechsys maps switched on on both sides (joint ``armature``,
   ``damping``, ``stiffness``/``springref``: ``from_mjcf(armature=True, joint_damping=True,
   joint_springs=True)``) and what it does not zeroed in MuJoCo: every constraint
   (``mjDSBL_CONSTRAINT``: contacts, joint and tendon limits, friction loss, equalities),
   actuators (``mjDSBL_ACTUATION``), fluid forces (``opt.density``, ``opt.viscosity``,
   ``opt.wind``), tendon springs and dampers, gravity compensation, and the damping,
   armature and stiffness of free joints (no counterpart on an absolute body) and the
   stiffness and damping of joints with ``springdamper`` (which MuJoCo derives from the
   joint's inertia at ``qpos0``; the importer reports them and adds neither).
   MuJoCo's free joint: ``qpos = (r, e)`` (the body frame's origin in the world, its
   quaternion), ``qvel = (v, w_b)`` (the origin's velocity in the world frame, the angular
   velocity in the body frame), ``qacc = (a, dw_b/dt)``; mechsys's absolute body has
   ``(r, e)`` and their rates, so ``de/dt = e (x) (0, w_b) / 2`` and
   ``d2e/dt2 = (de/dt (x) (0, w_b) + e (x) (0, dw_b/dt)) / 2`` (Hamilton products), and back
   ``w_b = 2 vec(conj(e) (x) de/dt)``, ``dw_b/dt = 2 vec(conj(e) (x) d2e/dt2)``.
   Forward: random ``qpos``, ``qvel`` and joint forces on the hinges (``qfrc_applied``),
   ``mj_forward``'s ``qacc`` against mechsys's ``forward_dynamics`` mapped to MuJoCo's
   coordinates; inverse: mechsys's ``inverse_dynamics`` at that state and acceleration
   against ``mj_inverse``'s ``qfrc_inverse`` on the hinges (the applied forces) and its
   free-joint rows (zero: the base is unactuated).
3. Files with mesh geoms (the Jaco arm and hand, the dog, the rodent, the fruit fly, ...):
   every body's mass, centroid and principal moments against MuJoCo's compiled
   ``body_mass``, ``body_ipos``, ``body_inertia`` (MuJoCo bodies without joints merged as
   mechsys merges them) and the tensor against ``R diag(I) R^T`` (``body_iquat``), relative
   (the centroid to the larger of its distance from the body frame and 1 mm).

Run from a scratch folder: MuJoCo writes its warnings to ``MUJOCO_LOG.TXT`` there.
``python mjcf_dm_control_suite.py [part ...]`` (parts 1 2 3; default all).
"""

import importlib.util
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

import mechsys as ms

dm = Path(next(iter(importlib.util.find_spec("dm_control").submodule_search_locations)))
suite = dm / "suite"
parts = sys.argv[1:] or ["1", "2", "3"]


def qmul(a, b):
    """Hamilton product of quaternions ``(w, x, y, z)``."""
    w1, v1, w2, v2 = a[0], np.asarray(a[1:]), b[0], np.asarray(b[1:])
    return np.concatenate(([w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + np.cross(v1, v2)))


def conj(e):
    return np.array([e[0], -e[1], -e[2], -e[3]])


def fixed_base():
    rng = np.random.default_rng(1)
    print("part 1: fixed-base suite files with <include>, inverse dynamics against mj_inverse")
    for f in sorted(suite.glob("*.xml")):
        if "<include" not in f.read_text():
            continue
        mm = mujoco.MjModel.from_xml_path(str(f))
        if mm.nv == 0 or mm.nq != mm.nv or np.isin(mm.jnt_type, (0, 1)).any():
            continue
        m = ms.from_mjcf(f)
        mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
        mm.opt.density = mm.opt.viscosity = 0.0          # fluid forces: no counterpart
        mm.dof_damping[:] = 0
        mm.dof_armature[:] = 0
        mm.jnt_stiffness[:] = 0
        names = m.compile().layout.q_names
        assert names == tuple(mm.joint(i).name for i in range(mm.njnt))
        Q, QD, QDD = rng.normal(size=(3, mm.nv))
        tau = np.ravel(m.inverse_dynamics(Q, QD, QDD).values)
        d = mujoco.MjData(mm)
        d.qpos[:], d.qvel[:], d.qacc[:] = Q, QD, QDD
        mujoco.mj_inverse(mm, d)
        err = np.abs(tau - d.qfrc_inverse).max() / np.abs(d.qfrc_inverse).max()
        print(f"  {f.name:18s} {mm.nv:3d} dof  {err:.1e}")


def zero_unmapped(mm, f):
    """Switch off in MuJoCo what mechsys does not model (module doc, part 2)."""
    # springdamper: MuJoCo's stiffness and damping from the joint's inertia at qpos0 (not
    # mapped by the importer, which adds neither)
    for js in mujoco.MjSpec.from_file(str(f)).joints:
        if js.springdamper[0] > 0 and js.springdamper[1] > 0:
            j = mm.joint(js.name).id
            mm.jnt_stiffness[j] = 0.0
            mm.dof_damping[mm.jnt_dofadr[j]] = 0.0
    B = mujoco.mjtDisableBit
    mm.opt.disableflags |= int(B.mjDSBL_CONSTRAINT) | int(B.mjDSBL_ACTUATION)
    mm.opt.density = 0.0
    mm.opt.viscosity = 0.0
    mm.opt.wind[:] = 0.0
    mm.body_gravcomp[:] = 0.0
    if mm.ntendon:
        mm.tendon_stiffness[:] = 0.0
        mm.tendon_damping[:] = 0.0
    for j in np.nonzero(mm.jnt_type == int(mujoco.mjtJoint.mjJNT_FREE))[0]:
        a = mm.jnt_dofadr[j]
        mm.dof_damping[a:a + 6] = 0.0
        mm.dof_armature[a:a + 6] = 0.0
        mm.jnt_stiffness[j] = 0.0


def exact_principal_axes(m, mm):
    """Give MuJoCo's bodies the principal axes and moments of mechsys's inertia tensors
    (NumPy's ``eigh``): MuJoCo's compiler stops its Jacobi rotations at a cosine of
    1 - 1e-12, so its axes of a mesh's inertia (and of a body's) carry up to ~1e-6 rad of
    that tolerance (decision 0072). Where mechsys merged several MuJoCo bodies into one, the
    owner (the MuJoCo body whose frame is the mechsys body's) takes the rest of the merged
    tensor once the others' are taken off (only the rigid group's total matters)."""
    fr = m.import_report.frames
    owners: dict = {}
    for i in range(1, mm.nbody):
        owners.setdefault(fr[mm.body(i).name][0], []).append(i)
    for mb, ids in owners.items():
        own = [i for i in ids if not fr[mm.body(i).name][1].any()
               and np.allclose(fr[mm.body(i).name][2], np.eye(3))]
        if mb == "ground" or len(own) != 1 or mm.body_mass[own[0]] == 0:
            continue
        i = own[0]
        b = m.body(mb)
        C = np.array(b.centroid, float).ravel()
        J = np.array(b.inertia, float)
        for k in ids:                       # the others' share about the group's centroid
            if k == i:
                continue
            _, p, R = fr[mm.body(k).name]
            Rk = np.zeros(9)
            mujoco.mju_quat2Mat(Rk, mm.body_iquat[k])
            Rk = R @ Rk.reshape(3, 3)
            dk = p + R @ mm.body_ipos[k] - C
            J = J - Rk @ np.diag(mm.body_inertia[k]) @ Rk.T
            J = J - mm.body_mass[k] * (dk @ dk * np.eye(3) - np.outer(dk, dk))
        d0 = mm.body_ipos[i] - C
        I = J - mm.body_mass[i] * (d0 @ d0 * np.eye(3) - np.outer(d0, d0))
        ev, V = np.linalg.eigh(I)
        # in MuJoCo's order and sense of its axes (a body whose axes are the body frame's
        # stays so: MuJoCo's "simple body" shortcuts rely on it)
        R0 = np.zeros(9)
        mujoco.mju_quat2Mat(R0, mm.body_iquat[i])
        order = np.argmax(np.abs(R0.reshape(3, 3).T @ V), axis=1)
        if sorted(order) != [0, 1, 2]:
            continue
        ev, V = ev[order], V[:, order]
        V = V * np.sign(np.einsum("ij,ij->j", R0.reshape(3, 3), V))
        q = np.zeros(4)
        mujoco.mju_mat2Quat(q, V.ravel())
        mm.body_inertia[i], mm.body_iquat[i] = ev, q


def free_base(points=3, exact_axes=False):
    rng = np.random.default_rng(72)
    print("part 2: free-base suite files; relative to the largest |qacc| (forward) and |qfrc| (inverse)")
    print(f"  {'file':22s} {'nq':>3s} {'nv':>3s} {'free':>4s} {'hinge':>5s}  {'forward':>8s} {'inverse':>8s} "
          f"{'base rows':>9s}  import+compile, {points} points")
    files = [suite / f"{name}.xml" for name in ("humanoid", "humanoid_CMU", "quadruped", "dog", "fish")]
    files += [dm / "locomotion/walkers/assets" / n for n in ("dog_v2/dog.xml", "fruitfly_v2/fruitfly.xml")]
    for f in files:
        t0 = time.process_time()
        m = ms.from_mjcf(f, armature=True, joint_damping=True, joint_springs=True, geometry=False)
        s = m.compile()
        lay = s.layout
        mm = mujoco.MjModel.from_xml_path(str(f))
        zero_unmapped(mm, f)
        if exact_axes:
            exact_principal_axes(m, mm)
        d = mujoco.MjData(mm)
        free = [int(j) for j in np.nonzero(mm.jnt_type == int(mujoco.mjtJoint.mjJNT_FREE))[0]]
        other = [j for j in range(mm.njnt) if j not in free]
        hs = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        assert all(mm.jnt_type[j] in hs for j in other)
        jn = [mm.joint(j).name for j in other]
        idx = [lay.q_names.index(n) for n in jn]              # mechsys's index of each hinge
        act = [i for i in range(s.n) if not any(i in range(*sl.indices(s.n))
                                                for sl in lay.body_slices.values())]
        assert sorted(idx) == act, "every non-free joint is a Gen coordinate"
        fwd = inv = base = 0.0
        worst = ""
        for _ in range(points):
            mujoco.mj_resetData(mm, d)
            for j in range(mm.njnt):
                a, v = mm.jnt_qposadr[j], mm.jnt_dofadr[j]
                if j in free:
                    e = rng.normal(size=4)
                    d.qpos[a:a + 7] = np.concatenate((rng.normal(size=3), e / np.linalg.norm(e)))
                    d.qvel[v:v + 6] = rng.normal(size=6)
                else:
                    d.qpos[a] = mm.qpos0[a] + 0.5 * rng.normal()
                    d.qvel[v] = rng.normal()
                    d.qfrc_applied[v] = rng.normal() * mm.body_mass.sum() * 0.05
            mujoco.mj_forward(mm, d)
            # the state in mechsys's coordinates
            q, qd, qdd = np.zeros(s.n), np.zeros(s.n), np.zeros(s.n)
            for j in free:
                a, v = mm.jnt_qposadr[j], mm.jnt_dofadr[j]
                sl = lay.body_slices[mm.body(mm.jnt_bodyid[j]).name]
                e = d.qpos[a + 3:a + 7]
                w, dw = d.qvel[v + 3:v + 6], d.qacc[v + 3:v + 6]
                de = 0.5 * qmul(e, np.concatenate(([0.0], w)))
                dde = 0.5 * (qmul(de, np.concatenate(([0.0], w))) + qmul(e, np.concatenate(([0.0], dw))))
                q[sl] = d.qpos[a:a + 7]
                qd[sl] = np.concatenate((d.qvel[v:v + 3], de))
                qdd[sl] = np.concatenate((d.qacc[v:v + 3], dde))
            for j, i in zip(other, idx):
                a, v = mm.jnt_qposadr[j], mm.jnt_dofadr[j]
                q[i], qd[i], qdd[i] = d.qpos[a], d.qvel[v], d.qacc[v]
            tau_m = np.zeros(len(act))
            for j, i in zip(other, idx):
                tau_m[act.index(i)] = d.qfrc_applied[mm.jnt_dofadr[j]]
            # forward: mechsys's accelerations in MuJoCo's coordinates
            got = np.ravel(m.forward_dynamics(q, qd, tau_m).values)
            acc = np.zeros(mm.nv)
            for j in free:
                a, v = mm.jnt_qposadr[j], mm.jnt_dofadr[j]
                sl = lay.body_slices[mm.body(mm.jnt_bodyid[j]).name]
                acc[v:v + 3] = got[sl][:3]
                acc[v + 3:v + 6] = 2 * qmul(conj(q[sl][3:]), got[sl][3:])[1:]
            for j, i in zip(other, idx):
                acc[mm.jnt_dofadr[j]] = got[i]
            fwd = max(fwd, np.abs(acc - d.qacc).max() / np.abs(d.qacc).max())
            # inverse: at MuJoCo's acceleration, the hinges' forces against mj_inverse's
            tau = np.ravel(m.inverse_dynamics(q, qd, qdd).values)
            mujoco.mj_inverse(mm, d)
            ref = d.qfrc_inverse
            ours = np.zeros(mm.nv)
            for j, i in zip(other, idx):
                ours[mm.jnt_dofadr[j]] = tau[act.index(i)]
            e_inv = np.abs(ours - ref) / np.abs(ref).max()
            if e_inv.max() > inv:
                inv, worst = e_inv.max(), mm.joint(mm.dof_jntid[int(np.argmax(e_inv))]).name
            base = max(base, max(np.abs(ref[mm.jnt_dofadr[j]:mm.jnt_dofadr[j] + 6]).max() for j in free)
                       / np.abs(ref).max())
        cpu = time.process_time() - t0
        label = f.name if f.parent == suite else f"{f.parent.name}/{f.name}"
        print(f"  {label:22s} {mm.nq:3d} {mm.nv:3d} {len(free):4d} {len(other):5d}  {fwd:8.1e} {inv:8.1e} "
              f"{base:9.1e}  {cpu:.0f} s CPU (inverse worst at {worst})")


def merged_bodies(m, mm):
    """MuJoCo's bodies' mass properties summed into mechsys's bodies (a body without joints
    is merged into its parent), in each mechsys body's frame."""
    fr = m.import_report.frames
    out: dict = {}
    for i in range(1, mm.nbody):
        b = mm.body(i)
        mb, p, R = fr[b.name]
        Ri = np.zeros(9)
        mujoco.mju_quat2Mat(Ri, b.iquat)
        Ri = Ri.reshape(3, 3)
        RR = R @ Ri
        out.setdefault(mb, []).append((b.mass[0], p + R @ b.ipos, RR @ np.diag(b.inertia) @ RR.T, i))
    return out


def meshes():
    print("part 3: files with mesh geoms, mass properties against MuJoCo's compiled bodies")
    print(f"  {'file':52s} {'bodies':>6s} {'meshes':>6s}  {'mass':>7s} {'centroid':>7s} {'moments':>7s} "
          f"{'tensor':>7s}")
    files = [dm / "third_party/kinova/jaco_arm.xml", dm / "third_party/kinova/jaco_hand.xml",
             suite / "dog.xml", dm / "locomotion/walkers/assets/dog_v2/dog.xml",
             dm / "locomotion/walkers/assets/rodent.xml",
             dm / "locomotion/walkers/assets/fruitfly_v2/fruitfly.xml",
             dm / "locomotion/walkers/assets/jumping_ball/jumping_ball_with_head.xml",
             dm / "locomotion/soccer/assets/boxhead/boxhead.xml", dm / "mujoco/testing/assets/arm.xml"]
    for f in files:
        mm = mujoco.MjModel.from_xml_path(str(f))
        m = ms.from_mjcf(f, geometry=False)
        nmesh = int(np.sum(mm.geom_type == int(mujoco.mjtGeom.mjGEOM_MESH)))
        worst = np.zeros(4)
        n = 0
        for mb, ps in merged_bodies(m, mm).items():
            M = sum(x[0] for x in ps)
            if mb == "ground" or M == 0:
                continue
            n += 1
            C = sum(x[0] * x[1] for x in ps) / M
            J = sum(x[2] + x[0] * ((x[1] - C) @ (x[1] - C) * np.eye(3) - np.outer(x[1] - C, x[1] - C))
                    for x in ps)
            b = m.body(mb)
            I = np.array(b.inertia, float)
            err = [abs(float(b.mass) - M) / M,
                   np.abs(np.array(b.centroid, float).ravel() - C).max() / max(np.linalg.norm(C), 1e-3),
                   np.abs(np.linalg.eigvalsh(I) - np.linalg.eigvalsh(J)).max() / np.abs(J).max(),
                   np.abs(I - J).max() / np.abs(J).max()]
            worst = np.maximum(worst, err)
        cols = " ".join(f"{x:7.1e}" for x in worst)
        print(f"  {str(f.relative_to(dm)):52s} {n:6d} {nmesh:6d}  {cols}")


if "1" in parts:
    fixed_base()
if "2" in parts:
    free_base()
    print("  again, MuJoCo's bodies given mechsys's inertia tensors' exact principal axes:")
    free_base(exact_axes=True)
if "3" in parts:
    meshes()
