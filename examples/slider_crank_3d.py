"""The spatial slider-crank of Mech's section 1.3, written joint by joint.

The crank turns about the global Z axis (a hinge, ``Revolute5``), the connecting rod hangs
on the crank pin by a ball joint (``Spherical3``) and on the piston by a universal joint
(``Universal4``, which stops the rod spinning about its own axis), and the piston slides
along X without turning (``Translate5``). The crank is driven at one revolution per second
(``RotationLock1`` about the hinge axis). The same model is ``models.slider_crank_3d()``.

The piston's travel is checked against the planar model and against its closed form.

Run: ``python examples/slider_crank_3d.py``
"""

import numpy as np

import mechsys as ms
from mechsys import T, models

r, L = 2.0, 6.0
z = (0, 0, 1)

m = ms.Model3D()
g = m.ground
crank = m.add_body("crank", points={"pin": (r, 0, 0)})
rod = m.add_body("rod", points={"a": (0, 0, 0), "b": (L, 0, 0)}, guess=((r, 0, 0), (1, 0, 0, 0)))
piston = m.add_body("piston", guess=((r + L, 0, 0), (1, 0, 0, 0)))

m.add(ms.Revolute5(crank.axis(0, z), g.axis((0, 0, 0), z)), name="crank pin")
m.add(ms.Spherical3(crank.point("pin"), rod.point("a")), name="crank-rod")
m.add(ms.Universal4(rod.axis("b", (0, 1, 0)), piston.axis(0, z)), name="wrist pin")
m.add(ms.Translate5(piston.axis(0, (1, 0, 0)), g.axis((0, 0, 0), (1, 0, 0))), name="slider")
m.add(ms.RotationLock1(crank.axis(0, z), g.axis((0, 0, 0), z), 2 * np.pi * T), name="drive")

print(m.dof())
sol = m.solve(np.linspace(0, 1, 13))

x = sol.location(piston.point(0))[:, 0]
v = sol.velocity(piston.point(0))[:, 0]
a = sol.acceleration(piston.point(0))[:, 0]
w_rod = sol.omega(rod)                       # (N, 3), global
th = 2 * np.pi * sol.t
x_closed = r * np.cos(th) + np.sqrt(L**2 - (r * np.sin(th)) ** 2)

planar = models.slider_crank(crank=r, rod=L).solve(sol.t)
x_planar = planar["piston.x"]

print(f"{'t':>6} {'piston x':>10} {'closed form':>12} {'planar':>10} {'v':>10} {'a':>10} "
      f"{'rod omega_z':>12}")
for k in range(len(sol.t)):
    print(f"{sol.t[k]:6.3f} {x[k]:10.5f} {x_closed[k]:12.5f} {x_planar[k]:10.5f} {v[k]:10.4f} "
          f"{a[k]:10.3f} {w_rod[k, 2]:12.5f}")
assert np.allclose(x, x_closed) and np.allclose(x, x_planar)

# the rod's instant screw axis: a point on it and its direction (= omega)
point, direction = sol.instant_center(rod)
print(f"rod screw axis at t = {sol.t[1]:.3f}: through {np.round(point[1], 4)}, "
      f"direction {np.round(direction[1], 4)}")
