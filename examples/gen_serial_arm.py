"""A planar three-link arm in generalized coordinates (Mech chapter 11).

Each link is the slave of the previous one through a ``GenRevolute2`` joint, so the model's
coordinates are the three joint angles and nothing else (no constraint equations). Joint
torques are loads on the joint angles: a PD controller holds the arm at a target pose
against gravity. The script

1. integrates the controlled motion and checks that the arm settles where the static
   balance of the torques says (the torque at each joint equals the gravity moment of the
   links it carries, computed here by hand);
2. prints the force the shoulder transmits (``joint_reaction``) and checks it against the
   total weight the arm hangs on the shoulder at rest.
"""

import numpy as np
import sympy as sp

import mechsys as ms

G = 9.81
LENGTHS = [1.0, 0.8, 0.5]
MASSES = [2.0, 1.5, 0.5]
TARGET = [0.6, -0.4, -0.3]         # joint angles [rad]
KP, KD = 400.0, 60.0

m = ms.Model2D()
master = m.ground.axis((0, 0))
for k, (L, mass) in enumerate(zip(LENGTHS, MASSES)):
    link = m.add_body(f"link{k}", points={"o": (0, 0), "e": (L, 0)}, mass=mass,
                      centroid=(L / 2, 0), inertia=mass * L**2 / 12)
    m.add(ms.GenRevolute2(link.axis("o"), master, (f"q{k}", 0.0)), name=f"joint{k}")
    master = link.axis("e")
m.add_load(ms.Gravity((0, -1), G))
q = sp.symbols("q0:3")
qd = [m.velocity_symbols()[s] for s in q]
for k in range(3):
    m.add_load(ms.Load(q[k], -KP * (q[k] - TARGET[k]) - KD * qd[k]))

print("coordinates:", m.compile().layout.q_names, " DOF:", int(m.dof()))

sol = m.free().simulate(np.linspace(0, 4, 41))
final = np.array([sol[f"q{k}"][-1] for k in range(3)])
print("final joint angles:", np.round(final, 5))

# static balance by hand: the PD torque at joint k carries the gravity moment about that
# joint of all links beyond it, so q_k - target_k = -moment_k / KP
angles = np.cumsum(final)
origins = np.vstack([[0, 0], np.cumsum([[L * np.cos(a), L * np.sin(a)]
                                         for L, a in zip(LENGTHS, angles)], axis=0)])
centroids = [origins[k] + LENGTHS[k] / 2 * np.array([np.cos(angles[k]), np.sin(angles[k])])
             for k in range(3)]
moments = [sum(-MASSES[j] * G * (centroids[j][0] - origins[k][0]) for j in range(k, 3))
           for k in range(3)]
expected = np.array(TARGET) + np.array(moments) / KP
print("static balance    :", np.round(expected, 5))
assert np.abs(final - expected).max() < 1e-3, (final, expected)

F, M = sol.joint_reaction("joint0")
print("shoulder force at rest:", np.round(F[-1], 4), "(weight", sum(MASSES) * G, ")")
assert abs(F[-1][1] - sum(MASSES) * G) < 1e-2 and abs(F[-1][0]) < 1e-2
