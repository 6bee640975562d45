"""Planar slider-crank, built step by step (Mech manual, section 1.2 "Basic 2D Model").

A crank (body 2) turns about a ground pivot at the origin at one revolution per second; a
connecting rod (body 3) joins the crank pin to the piston (body 4), which slides along the
global x axis. We build the model with the public API, check its degrees of freedom, solve
position, velocity and acceleration over one revolution, print a table, and compare the
piston's motion with the closed-form slider-crank equations.

Run: ``python examples/slider_crank_2d.py``
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

CRANK, ROD = 2.0, 6.0  # crank radius and connecting-rod length

# 1. The model and its bodies (Mech: SetBodies / Body). Ground is body 1 and exists already.
#    Local points are named; guesses are ((x, y), angle) near the assembled position at T = 0.
m = ms.Model2D()
ground = m.ground
crank = m.add_body("crank", points={"pin": (CRANK, 0)}, guess=((0, 0), 0))
rod = m.add_body("rod", points={"a": (0, 0), "b": (ROD, 0)}, guess=((CRANK, 0.1), 0.05))
piston = m.add_body("piston", guess=((CRANK + ROD, 0), 0))

# 2. The constraints (Mech: SetConstraints). A plain tuple is a point on ground; point 0 is a
#    body's origin.
m.add(ms.Revolute2(ground.point((0, 0)), crank.point(0)), name="main bearing")
m.add(ms.Revolute2(crank.point("pin"), rod.point("a")), name="crank pin")
m.add(ms.Revolute2(rod.point("b"), piston.point(0)), name="wrist pin")
m.add(ms.Translate2(ground.axis((0, 0), (1, 0)), piston.axis((0, 0), (1, 0))), name="cylinder")
# the driver: the crank angle as a function of time T, one revolution per second
m.add(ms.RotationLock1(crank, 2 * sp.pi * T), name="drive")

# 3. Check the degrees of freedom: 9 coordinates, 9 equations, full rank -> 0 DOF.
dof = m.dof()
print(dof)
assert dof == 0

# 4. Solve one revolution (Mech: SolveMech over a time range). Each point starts from the
#    previous one, so the sweep follows one assembly branch.
t = np.linspace(0.0, 1.0, 73)
sol = m.solve(t)

# 5. Outputs: arrays over the 73 times (points give (73, 2), planar angular rates (73,)).
x = sol.location(piston.point(0))[:, 0]
v = sol.velocity(piston.point(0))[:, 0]
a = sol.acceleration(piston.point(0))[:, 0]
w_rod = sol.omega(rod)

print(f"\n{'crank [deg]':>11} {'piston x':>10} {'piston v':>10} {'piston a':>10} {'rod omega':>10}")
for k in range(0, len(t), 6):
    print(f"{360 * t[k]:11.0f} {x[k]:10.4f} {v[k]:10.4f} {a[k]:10.3f} {w_rod[k]:10.4f}")
print(f"\n{len(t)} points, {int(sol.iterations.sum())} Newton iterations in all")

# 6. Check against the closed form x = r cos(th) + sqrt(L^2 - r^2 sin^2(th)).
th = 2 * np.pi * t
x_exact = CRANK * np.cos(th) + np.sqrt(ROD**2 - (CRANK * np.sin(th)) ** 2)
err = np.abs(x - x_exact).max()
print(f"max |x - closed form| = {err:.1e}")
if err > 1e-9:
    raise SystemExit("piston position does not match the closed form")

# The same output functions on the model are symbolic, in the bodies' coordinates and their
# velocities (names ending in _d):
print("velocity of the rod's end b:", list(m.velocity(rod.point("b"))))
