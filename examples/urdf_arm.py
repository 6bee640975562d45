"""A robot arm read from its URDF file: joint torques along a trajectory and its workspace.

The UR5 description of the ``example-robot-data`` package (BSD-3; read offline from the
installed package, or a small two-link arm written here when it is not installed) is imported
with ``ms.from_urdf``: each revolute joint becomes a ``GenRevolute5`` joint whose coordinate
is named after it (``shoulder_pan_joint``, ...), links joined by fixed joints are merged into
one body, and what the model could not map (transmissions, Gazebo tags, meshes not drawn) is
listed in ``m.import_report``. The script

1. computes the joint torques of a smooth point-to-point motion (a quintic in joint space)
   with ``m.inverse_dynamics`` and checks that ``m.forward_dynamics`` gives the motion back;
2. checks the holding torques at rest against the gravity moments computed by hand from the
   links' masses and centroids (the static balance of each joint);
3. samples the workspace: the tool frame's locations over random joint angles
   (``m.forward_kinematics``), plotted from the side and from above.
"""

import importlib.metadata
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechsys as ms

TWO_LINK = """<robot name="two_link">
  <link name="base"/>
  <link name="upper"><inertial><origin xyz="0 0 0.2"/><mass value="2"/>
    <inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.002"/></inertial></link>
  <link name="lower"><inertial><origin xyz="0 0 0.15"/><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.001"/></inertial></link>
  <link name="tool0"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <axis xyz="0 1 0"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="lower"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 1 0"/></joint>
  <joint name="flange" type="fixed"><parent link="lower"/><child link="tool0"/>
    <origin xyz="0 0 0.3"/></joint>
</robot>
"""


def robot_file() -> Path:
    try:
        share = importlib.metadata.distribution("example-robot-data").locate_file(
            "cmeel.prefix/share/example-robot-data/robots")
        path = Path(str(share)) / "ur_description" / "urdf" / "ur5_robot.urdf"
        if path.is_file():
            return path
    except importlib.metadata.PackageNotFoundError:
        pass
    print("example-robot-data is not installed: using a two-link arm written here")
    path = Path("two_link.urdf")
    path.write_text(TWO_LINK)
    return path


m = ms.from_urdf(robot_file())
names = m.compile().layout.q_names
n = len(names)
print("joints:", ", ".join(names))
print("not mapped:", len(m.import_report.not_mapped), "items, e.g.", m.import_report.not_mapped[0]
      if m.import_report.not_mapped else "none")

# 1. a quintic from q0 to q1 in 2 s: torques along it, and the motion back from them
q0, q1 = np.zeros(n), np.linspace(0.8, -0.6, n)
t = np.linspace(0, 2, 41)
s = t / 2
blend = 10 * s**3 - 15 * s**4 + 6 * s**5
blend_d = (30 * s**2 - 60 * s**3 + 30 * s**4) / 2
blend_dd = (60 * s - 180 * s**2 + 120 * s**3) / 4
q = q0 + np.outer(blend, q1 - q0)
qd = np.outer(blend_d, q1 - q0)
qdd = np.outer(blend_dd, q1 - q0)
tau = m.inverse_dynamics(q, qd, qdd)
back = m.forward_dynamics(q, qd, tau.values)
assert np.abs(back.values - qdd).max() < 1e-9
print("peak |torque| per joint [N m]:")
for name in names:
    print(f"  {name:22s} {np.abs(tau[name]).max():9.3f}")

# 2. at rest the torques hold the weight: joint k carries the gravity moment, about its axis,
#    of every body beyond it (centroids and axes from the imported model)
rest = np.full(n, 0.3)
hold = m.inverse_dynamics(rest, np.zeros(n), np.zeros(n)).values
g = np.array([0, 0, -9.81])


def masters(b):
    """``b`` and the bodies up its chain of Gen joints (to ground)."""
    while b is not None and not b.is_ground:
        yield b
        b = b.gen_joint.master if b.gen_joint is not None else None


# every point the balance needs, located in one compiled call: per joint its point and a
# point one unit along its axis (on its child body), per body with mass its centroid
joints = [m.constraint(jname) for jname in names]
points = []
for joint in joints:
    axis = joint.geometry()[0]
    o_loc = np.ravel(np.asarray(axis.origin.local, dtype=float))
    u_loc = np.ravel(np.asarray(axis.dir.local, dtype=float))
    points += [joint.slave.point(tuple(o_loc)), joint.slave.point(tuple(o_loc + u_loc))]
massive = [b for b in m.bodies[1:] if float(b.mass) > 0]
points += [b.point(tuple(np.ravel(np.asarray(b.centroid, dtype=float)))) for b in massive]
at = m.forward_kinematics(rest, points)
by_hand = np.zeros(n)
for k, joint in enumerate(joints):
    o, u = at[2 * k], at[2 * k + 1] - at[2 * k]
    for i, b in enumerate(massive):
        if joint.slave in list(masters(b)):
            by_hand[k] -= np.cross(at[2 * n + i] - o, float(b.mass) * g) @ u
print("holding torques   :", np.round(hold, 4))
print("gravity by hand   :", np.round(by_hand, 4))
assert np.abs(hold - by_hand).max() < 1e-9 * max(1.0, np.abs(by_hand).max())

# 3. workspace of the tool frame
rng = np.random.default_rng(1)
samples = rng.uniform(-np.pi, np.pi, size=(1500, n))
tool = m.forward_kinematics(samples, "tool0")
reach = np.linalg.norm(tool, axis=1).max()
print(f"workspace: {len(tool)} samples, farthest reach {reach:.3f} m")

fig, ax = plt.subplots(1, 3, figsize=(13, 4))
for name in names:
    ax[0].plot(t, tau[name], label=name)
ax[0].set(xlabel="t [s]", ylabel="joint torque [N m]", title="torques along the motion")
ax[0].legend(fontsize=7)
ax[1].scatter(tool[:, 0], tool[:, 2], s=2)
ax[1].set(xlabel="x [m]", ylabel="z [m]", title="workspace, side", aspect="equal")
ax[2].scatter(tool[:, 0], tool[:, 1], s=2)
ax[2].set(xlabel="x [m]", ylabel="y [m]", title="workspace, top", aspect="equal")
fig.tight_layout()
fig.savefig("urdf_arm.png", dpi=90)
