"""The rocker driven by an eccentric (Mech section 5.1.2): a StageSwitch toggled by a parameter.

Geometry from the manual: ground points P1 = (0, 0) (the eccentric's axis) and P2 = (-2, -1)
(the rocker's pivot); the eccentric's axis at its local (0, 0) and its disk centre at local
(0.5, 0); the rocker's pivot at its local (0, 0) and the right end of its face at (4, 0).
Constraints as the manual lists them: a Revolute2 at the rocker's pivot, a RelativeX1 fixing
the X of the eccentric's axis, and (our reconstruction of the parts of the page we could not
read) the eccentric driven at 1 rad/s, the disk (radius R = 1.25, our choice) touching the
rocker's face, and the StageSwitch of the two modes, each removing one degree of freedom:

* mode 1: the eccentric's axis is fixed (RelativeY1 = 0); the rocker rocks on the disk;
* mode 2: the rocker is held (RotationLock1 at angle phi0); the eccentric's axis is free
  vertically, so the eccentric rises and falls as it turns.

The mode is the parameter ``mode`` (tests ``Eq(mode, 1)``, ``Eq(mode, 2)``), changed with
``set_parameters`` without recompiling. Both modes are checked against closed forms: the
face's line through the pivot ``P`` at angle ``phi`` is at distance ``R`` from the disk
centre ``C``: ``cos(phi) (Cy - Py) - sin(phi) (Cx - Px) = R``.

Run: ``python examples/rocker_eccentric.py``
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

R, e, phi0 = 1.25, 0.5, 0.05
P = np.array([-2.0, -1.0])

m = ms.Model2D()
mode = m.parameter("mode", 1)
ecc = m.add_body("eccentric", points={"axis": (0, 0), "centre": (e, 0)}, guess=((0, 0), 0))
rocker = m.add_body("rocker", points={"pivot": (0, 0), "end": (4, 0)}, guess=((-2, -1), 0.1))
m.add(ms.Revolute2(rocker.point("pivot"), m.ground.point(tuple(P))), name="rocker pivot")
m.add(ms.RelativeX1(ecc.point("axis"), 0), name="axis x")
m.add(ms.RotationLock1(ecc, T), name="drive")
# the disk centre lies R to the left of the face (the disk sits on the face)
m.add(ms.PointOnLine1(ecc.point("centre"), rocker.axis((0, 0), (1, 0)), R), name="contact")
m.add(ms.StageSwitch(
    (sp.Eq(mode, 1), ms.RelativeY1(ecc.point("axis"), 0)),
    (sp.Eq(mode, 2), ms.RotationLock1(rocker, phi0)),
), name="mode switch")

t = np.linspace(0, 2 * np.pi, 73)

# mode 1: A cos(phi) - B sin(phi) = R with A = Cy - Py, B = Cx - Px
sol = m.solve(t)
assert set(sol.stage("mode switch")) == {1}
A, B = e * np.sin(t) - P[1], e * np.cos(t) - P[0]
rho, delta = np.hypot(A, B), np.arctan2(B, A)
phi = np.arccos(R / rho) - delta
phi = np.where(np.abs(phi) < np.pi, phi, phi - 2 * np.pi * np.sign(phi))
phi_alt = -np.arccos(R / rho) - delta  # the other tangent; pick the branch near the guess
phi = np.where(np.abs(phi - 0.1) < np.abs(phi_alt - 0.1), phi, phi_alt)
err1 = np.abs(sol.angle(rocker) - phi).max()
print(f"mode 1: rocker swings {np.degrees(np.ptp(sol.angle(rocker))):.3f} degrees; "
      f"max error vs closed form {err1:.1e}")
assert err1 < 1e-12

# mode 2: the rocker is held, the eccentric's axis height y solves
# cos(phi0) (y + e sin(t) - Py) - sin(phi0) (e cos(t) - Px) = R
m.set_parameters(mode=2)
sol2 = m.solve(t)
assert set(sol2.stage("mode switch")) == {2}
y = (R + np.sin(phi0) * (e * np.cos(t) - P[0])) / np.cos(phi0) - e * np.sin(t) + P[1]
err2 = np.abs(sol2["eccentric.y"] - y).max()
print(f"mode 2: the eccentric rises and falls by {np.ptp(sol2['eccentric.y']):.4f}; "
      f"max error vs closed form {err2:.1e}")
assert err2 < 1e-12
