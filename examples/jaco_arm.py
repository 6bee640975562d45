"""The Kinova Jaco arm from a real MJCF file: its joint torques along a trajectory checked
against MuJoCo, and an animation drawn from its meshes.

The MuJoCo Menagerie's files do not install offline (the ``mujoco-menagerie`` package
downloads them at run time), so the arm here is the Kinova Jaco that ``dm_control`` ships
(``dm_control/third_party/kinova/jaco_arm.xml``, Apache-2.0, with its STL meshes): a
six-joint arm with joint ``armature``, ``damping`` and ``frictionloss``, bodies turned by
quaternions, and links whose masses are given on mesh geoms. Only the package's files are
read (its Python code is not imported). The script

1. imports the arm with ``ms.from_mjcf(..., armature=True, joint_damping=True)`` straight
   from the package's file: six ``GenRevolute5`` joints whose coordinates are named after
   the file's joints, each link's mass, centroid and inertia computed by the importer from
   its STL mesh and the geom's ``mass`` as MuJoCo does (its default ``legacy`` mesh inertia,
   decision 0072), ``common.xml`` read through the file's ``<include>`` (decision 0070); it
   prints what the import report could not map and each link's mass properties beside
   those of MuJoCo's compiled model;
2. drives the six joints along quintics and computes the joint torques with
   ``m.inverse_dynamics`` at every instant at once, and checks them against MuJoCo's
   ``mj_inverse`` on the original file (constraints off: no contacts, joint limits or dry
   friction; armature, damping and gravity on), to 1e-9 relative (1.3e-12 measured);
3. plots the torques and animates the arm, each link drawn by the importer from its STL
   mesh (a ``draw.Mesh`` of its triangles).
"""

import importlib.util
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechsys as ms
from mechsys import draw


def package_dir(name: str) -> Path:
    """The folder of an installed package, found without importing it (importing
    dm_control loads OpenGL machinery)."""
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.submodule_search_locations:
        sys.exit(f"jaco_arm.py needs the {name!r} package: pip install {name}")
    return Path(list(spec.submodule_search_locations)[0])


kinova = package_dir("dm_control") / "third_party" / "kinova"
try:
    import mujoco  # type: ignore[import-untyped]  # no type information shipped
except ImportError:
    sys.exit("jaco_arm.py needs the 'mujoco' package (for the reference torques): pip install mujoco")

# -- 1. the file as it is, and MuJoCo's compiled model of it -------------------------------------
path = kinova / "jaco_arm.xml"
m = ms.from_mjcf(path, armature=True, joint_damping=True)
mj = mujoco.MjModel.from_xml_path(str(path))
names = list(m.compile().layout.q_names)
assert names == [mj.joint(k).name for k in range(mj.njnt)]
print("joints:", ", ".join(names))
print(m.import_report)
print("link masses [kg], centroids [m], principal moments [kg m^2]: mechsys | MuJoCo's largest difference")
for k in range(1, 7):
    link, ref = m.body(f"b_{k}"), mj.body(f"b_{k}")
    mass, centroid = float(link.mass), np.array(link.centroid, float).ravel()
    moments = np.linalg.eigvalsh(np.array(link.inertia, float))
    diff = max(abs(mass - ref.mass[0]), np.abs(centroid - ref.ipos).max(),
               np.abs(moments - np.sort(ref.inertia)).max())
    print(f"  b_{k}  {mass:.6f}  {np.round(centroid, 4)}  {np.round(moments, 6)} | {diff:.1e}")
    assert diff < 1e-12

# -- 2. quintics from q0 to q1 in 2 s, the torques, and MuJoCo's -------------------------------
q0 = np.array([0.0, 2.6, 1.2, -0.6, 0.9, 0.0])
q1 = np.array([1.4, 3.7, 2.3, 0.8, -0.7, 1.2])   # joints 2 and 3 stay inside their ranges
t = np.linspace(0.0, 2.0, 41)
s = t / 2.0
blend = (10 * s**3 - 15 * s**4 + 6 * s**5)[:, None]
dblend = ((30 * s**2 - 60 * s**3 + 30 * s**4) / 2.0)[:, None]
ddblend = ((60 * s - 180 * s**2 + 120 * s**3) / 4.0)[:, None]
q, qd, qdd = q0 + (q1 - q0) * blend, (q1 - q0) * dblend, (q1 - q0) * ddblend
tau = m.inverse_dynamics(q, qd, qdd).values      # (41, 6), all instants at once

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
# the rotors' armature (4 and 2 kg m^2) carries most of the torque: the links' own share
# (gravity, inertia, Coriolis, damping) is checked on its own scale too
links = ref - mj.dof_armature * qdd
err_links = np.abs(tau - ref).max() / np.abs(links).max()
print(f"  relative to the links' share alone (max {np.abs(links).max():.3f} N m): {err_links:.1e}")
assert err_links < 1e-9
print("peak |torque| per joint [N m]:")
for k, name in enumerate(names):
    print(f"  {name:8s} {np.abs(tau[:, k]).max():8.3f}")

# -- 3. the torques, and the motion drawn from the links' STL meshes ---------------------------
fig, ax = plt.subplots(figsize=(6, 3.2))
for k, name in enumerate(names):
    ax.plot(t, tau[:, k], label=name)
ax.set_xlabel("t [s]")
ax.set_ylabel("joint torque [N m]")
ax.legend(ncol=3, fontsize=8)
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig("jaco_arm_torques.png", dpi=80)


# the animation: a copy of the import whose joints are driven along the same quintics
# (a Constraint q - f(T) = 0 per joint), solved kinematically at 11 instants; the importer
# draws the mesh geoms from their STL files
driven = ms.from_mjcf(path)
T = ms.T
sT = T / 2
for k, qk in enumerate(driven.compile().layout.q_symbols):
    driven.add(ms.Constraint([qk - (q0[k] + (q1[k] - q0[k]) * (10 * sT**3 - 15 * sT**4 + 6 * sT**5))]),
               name=f"drive_{names[k]}")
sol = driven.solve(np.linspace(0.0, 2.0, 11))
assert np.abs(sol.q - q[::4]).max() < 1e-9
draw.animate(sol, "jaco_arm.gif", fps=5, dpi=50)
print("wrote jaco_arm_torques.png and jaco_arm.gif")
