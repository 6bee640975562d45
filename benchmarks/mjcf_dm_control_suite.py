"""dm_control's suite MJCF files that use ``<include>``: ``ms.from_mjcf`` against MuJoCo's
``mj_inverse`` at a random state (constraints, damping, armature and springs off), relative
to the largest torque (decision 0070). Models with free or ball joints are imported only.
Run from a scratch folder: MuJoCo writes its warnings to ``MUJOCO_LOG.TXT`` there.
"""

import importlib.util
from pathlib import Path

import mujoco
import numpy as np

import mechsys as ms

suite = Path(next(iter(importlib.util.find_spec("dm_control").submodule_search_locations))) / "suite"
rng = np.random.default_rng(1)
for f in sorted(suite.glob("*.xml")):
    if "<include" not in f.read_text():
        continue
    m = ms.from_mjcf(f)
    mm = mujoco.MjModel.from_xml_path(str(f))
    mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    mm.dof_damping[:] = 0
    mm.dof_armature[:] = 0
    mm.jnt_stiffness[:] = 0
    if mm.nv == 0 or mm.nq != mm.nv or np.isin(mm.jnt_type, (0, 1)).any():
        print(f"{f.name:18s} imported ({mm.nv} dof; free/ball joints or none: not compared)")
        continue
    names = m.compile().layout.q_names
    assert names == tuple(mm.joint(i).name for i in range(mm.njnt))
    Q, QD, QDD = rng.normal(size=(3, mm.nv))
    tau = np.ravel(m.inverse_dynamics(Q, QD, QDD).values)
    d = mujoco.MjData(mm)
    d.qpos[:], d.qvel[:], d.qacc[:] = Q, QD, QDD
    mujoco.mj_inverse(mm, d)
    err = np.abs(tau - d.qfrc_inverse).max() / np.abs(d.qfrc_inverse).max()
    print(f"{f.name:18s} {mm.nv:3d} dof  {err:.1e}")
