"""A Cardan (Hooke) joint between two shafts, and a constant-velocity joint.

The input shaft turns at a constant speed about X; the output shaft's axis is bent by
``bend`` in the XY plane. Through a universal joint the output speed fluctuates twice per
revolution:

    w2 / w1 = cos(bend) / (1 - sin(bend)^2 cos(th1)^2)

with ``th1`` the input yoke pin's angle from the plane of the two shafts. A
constant-velocity joint (``ConstantVelocity4``) passes the speed on unchanged.

Run: ``python examples/cardan_joint.py``
"""

import numpy as np

import mechsys as ms
from mechsys import models

bend, w1 = 0.5, 2 * np.pi
a2 = np.array([np.cos(bend), np.sin(bend), 0.0])      # output shaft axis
t = np.linspace(0, 0.5, 13)                            # half a revolution
th1 = w1 * t

hooke = models.cardan_joint(bend=bend, speed=w1).solve(t)
cv = models.cardan_joint(bend=bend, speed=w1, joint="cv").solve(t)

ratio = hooke.omega("output") @ a2 / w1
closed = np.cos(bend) / (1 - np.sin(bend) ** 2 * np.cos(th1) ** 2)
ratio_cv = cv.omega("output") @ a2 / w1

print(f"bend = {np.degrees(bend):.1f} deg")
print(f"{'th1 [deg]':>10} {'Hooke w2/w1':>12} {'closed form':>12} {'CV w2/w1':>10}")
for k in range(len(t)):
    print(f"{np.degrees(th1[k]):10.1f} {ratio[k]:12.6f} {closed[k]:12.6f} {ratio_cv[k]:10.6f}")
assert np.allclose(ratio, closed) and np.allclose(ratio_cv, 1.0)

# output shaft angle from its Euler parameters (angle-axis): the Hooke joint lags and leads
e = np.column_stack([hooke[f"output.e{k}"] for k in range(4)])
angle, axis = ms.rotation(e[3])
print(f"output shaft at t = {t[3]:.3f}: turned {angle:.4f} rad about {np.round(axis, 4)}")
