"""A spatial slider-crank shown in the interactive HTML viewer and in matplotlib 3D.

The crank turns about the global z axis; the rod has ball joints at both ends (its spin
about its own axis is fixed by keeping its local y axis horizontal); the piston slides
along the line y = 0, z = h. The constraints are written as general equations
(``ms.Constraint``), so this runs with the foundation alone. Graphics are Mech's 3D
primitives: Cylinder, Bar, Sphere, Box, LocusPlot, LocalAxes.

Run: ``python examples/draw_spatial_crank.py`` and open ``draw_spatial_crank.html``.
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T, draw

r, L, h = 2.0, 6.0, 1.5
xr = np.sqrt(L**2 - h**2)

m = ms.Model3D()
crank = m.add_body("crank", points={"pin": (r, 0, 0)})
rod = m.add_body("rod", points={"a": (0, 0, 0), "b": (L, 0, 0)},
                 guess=((r, 0, 0), (-np.arctan2(h, xr), (0, 1, 0))))
piston = m.add_body("piston", guess=((r + xr, 0, h), (1, 0, 0, 0)))
e0, e1, e2, e3 = crank.q[3:]
th = 2 * sp.pi * T
m.add(ms.Constraint([*crank.r, e1, e2, e3 * sp.cos(th / 2) - e0 * sp.sin(th / 2)]), name="drive")
m.add(ms.Constraint(list(m.location(crank.point("pin")) - m.location(rod.point("a")))),
      name="crank ball")
m.add(ms.Constraint(list(m.location(rod.point("b")) - m.location(piston.point(0)))),
      name="wrist ball")
m.add(ms.Constraint([(rod.A * sp.Matrix([0, 1, 0]))[2]]), name="rod spin")
m.add(ms.Constraint([piston.r[1], piston.r[2] - h, *piston.q[4:]]), name="slider")
sol = m.solve(np.linspace(0, 1, 61))

# the closed form of the piston's travel checks the model
x = sol.location(piston.point(0))[:, 0]
phi = 2 * np.pi * sol.t
assert np.allclose(x, r * np.cos(phi) + np.sqrt(L**2 - (r * np.sin(phi))**2 - h**2))

graphics = [
    draw.Cylinder("ground", (0, 0, -1.6), (0, 0, -0.8), 0.35, color="#8c8c8c"),
    draw.Cylinder(crank, (0, 0, -0.8), (0, 0, 0.15), 0.2),
    draw.Bar(crank, (0, "pin"), width=0.35, thickness=0.2),
    draw.Sphere(crank, "pin", 0.24, color="#333333"),
    draw.Cylinder(rod, "a", "b", 0.13),
    draw.Sphere(rod, "b", 0.22, color="#333333"),
    draw.Box(piston, (-0.7, -0.45, -0.45), (0.7, 0.45, 0.45)),
    draw.Cylinder("ground", (3.2, 0, h), (9.5, 0, h), 0.08, color="#8c8c8c"),
    draw.LocusPlot(rod.point((3, 0, 0))),
    draw.LocalAxes(crank, size=1.0),
]
html = draw.viewer(sol, "draw_spatial_crank.html", graphics=graphics,
                   title="spatial slider-crank")
fig = draw.snapshot(sol, graphics=graphics, t=0.1, view=(20, -70))
fig.savefig("draw_spatial_crank.png", dpi=80)
print(f"wrote {html} and draw_spatial_crank.png")
