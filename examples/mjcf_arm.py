"""An arm read from an MJCF (MuJoCo) file, driven along a trajectory: animated, with its
joint torques.

The MuJoCo Menagerie's arms are not shipped in any package that installs offline (the
``mujoco-menagerie`` package downloads its models at run time), so the file here is written
by the script: a three-joint arm in the Menagerie's style (capsule links, a base turning
about ``z``, a shoulder and an elbow about ``y``, joint ``armature`` as MuJoCo's rotors). It
is imported with ``ms.from_mjcf(..., armature=True)``: each hinge becomes a ``GenRevolute5``
joint whose coordinate is named after it, the capsules are kept for drawing, and the
armature enters the mass matrix's diagonal as MuJoCo's does. The script

1. drives every joint along a quintic (a ``Constraint`` ``q - f(T) = 0`` per joint) and
   solves the inverse dynamics of the driven model (``solution="dynamic"``): the drives'
   reactions are the joint torques, ``tau = -lambda``;
2. checks them against ``m.inverse_dynamics`` of the undriven import at the same states
   (the recursion of decision 0016, a second route to the same numbers), and the gravity
   torque of the shoulder at rest against the moments of the links' weights computed by
   hand;
3. plots the torques and writes an animation of the motion.
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechsys as ms
from mechsys import draw

ARM = """<mujoco model="three_joint_arm">
  <compiler angle="radian"/>
  <option gravity="0 0 -9.81"/>
  <default><joint armature="0.05" damping="0.5"/><geom type="capsule" size="0.04" density="2700"/></default>
  <worldbody>
    <geom type="cylinder" size="0.12 0.05" pos="0 0 0.05"/>
    <body name="turret" pos="0 0 0.1">
      <joint name="base_yaw" axis="0 0 1"/>
      <geom fromto="0 0 0 0 0 0.25" size="0.06"/>
      <body name="upper_arm" pos="0 0 0.25">
        <joint name="shoulder" axis="0 1 0"/>
        <geom fromto="0 0 0 0.45 0 0"/>
        <body name="forearm" pos="0.45 0 0">
          <joint name="elbow" axis="0 1 0"/>
          <geom fromto="0 0 0 0.4 0 0" size="0.03"/>
          <geom type="sphere" size="0.05" pos="0.4 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

path = Path("three_joint_arm.xml")
path.write_text(ARM)
m = ms.from_mjcf(path, armature=True)
names = m.compile().layout.q_names
print("joints:", ", ".join(names))
print(m.import_report)

# 1. every joint driven along a quintic from q0 to q1 in 2 s
q0, q1 = np.array([0.0, -0.3, 0.6]), np.array([1.5, -1.1, 1.4])
T = ms.T
s = T / 2
blend = 10 * s**3 - 15 * s**4 + 6 * s**5
driven = ms.from_mjcf(path, armature=True)
for k, name in enumerate(names):
    q = driven.compile().layout.q_symbols[k]
    driven.add(ms.Constraint([q - (q0[k] + (q1[k] - q0[k]) * blend)]), name=f"drive_{name}")
t = np.linspace(0.0, 2.0, 41)
sol = driven.solve(t, solution="dynamic")
tau = -sol.lam                                   # M qdd + Phi_q^T lambda = Q + Qv, Phi_q = I

# 2. the same torques from the robot entry point of the undriven import
check = m.inverse_dynamics(sol.q, sol.qd, sol.qdd).values
assert np.abs(check - tau).max() < 1e-9 * np.abs(tau).max()
# the shoulder's holding torque at rest, straight out along x: the links' weights at their
# centroids turn the arm about +y by m g x (r x F = (x, 0, 0) x (0, 0, -m g)), which the
# joint holds with the opposite torque
rest = m.inverse_dynamics([0.0, 0.0, 0.0], np.zeros(3), np.zeros(3))
upper, fore = m.body("upper_arm"), m.body("forearm")
moment = 9.81 * (float(upper.mass) * float(upper.centroid[0])
                 + float(fore.mass) * (0.45 + float(fore.centroid[0])))
assert abs(rest["shoulder"] + moment) < 1e-9 * moment
print(f"shoulder holding torque, arm straight out: {rest['shoulder']:.3f} N m "
      f"(weights' moment by hand: {moment:.3f} N m, held by its opposite)")
print("peak |torque| per joint [N m]:")
for k, name in enumerate(names):
    print(f"  {name:10s} {np.abs(tau[:, k]).max():8.3f}")

# 3. torques along the motion, and the motion itself
fig, ax = plt.subplots(figsize=(6, 3.2))
for k, name in enumerate(names):
    ax.plot(t, tau[:, k], label=name)
ax.set_xlabel("t [s]")
ax.set_ylabel("joint torque [N m]")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig("mjcf_arm_torques.png", dpi=80)
draw.animate(sol, "mjcf_arm.gif", fps=10, dpi=50)
print("wrote mjcf_arm_torques.png and mjcf_arm.gif")
