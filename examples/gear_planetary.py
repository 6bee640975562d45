"""A planetary (epicyclic) gear train with nominal gear constraints (Mech manual, ch. 6.2.1).

The sun (radius 1) is driven about the origin, the ring (an internal gear of radius 3, so a
negative radius) is held, and one planet (radius 1) turns on a pin of the carrier arm. Two
``TwoGears1`` constraints relate the rotations: sun-planet and planet-ring (the carrier
places the centres, so the distance equations of ``TwoGears2`` would be redundant). We
check the carrier speed against Willis' formula, then hold the sun and load the carrier to
get the tooth force of a static solution against a hand torque balance.

Run: ``python examples/gear_planetary.py``
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

R_SUN, R_PLANET, R_RING = 1.0, 1.0, -3.0   # pitch radii; negative = internal gear
ARM = R_SUN + R_PLANET                       # carrier arm length
W_SUN = 2 * sp.pi                            # one sun revolution per second

m = ms.Model2D()
g = m.ground
sun = m.add_body("sun", guess=((0, 0), 0))
ring = m.add_body("ring", guess=((0, 0), 0))
carrier = m.add_body("carrier", points={"pin": (ARM, 0)}, guess=((0, 0), 0))
planet = m.add_body("planet", guess=((ARM, 0), 0))

m.add(ms.Revolute2(g.point((0, 0)), sun.point(0)), name="sun bearing")
m.add(ms.Revolute2(g.point((0, 0)), ring.point(0)), name="ring bearing")
m.add(ms.Revolute2(g.point((0, 0)), carrier.point(0)), name="carrier bearing")
m.add(ms.Revolute2(carrier.point("pin"), planet.point(0)), name="planet pin")
# C = r1 e1 + r2 e2 with e_i the angle from the centre line (point1 -> point2) to gear i's x
# axis: all x axes along +x at assembly gives C = 0 for the sun mesh (centre line +x) and
# C = (R_PLANET + R_RING) * (-pi) for the ring mesh (centre line planet -> origin is -x).
m.add(ms.TwoGears1(sun.point(0), R_SUN, planet.point(0), R_PLANET, 0.0), name="sun mesh")
m.add(ms.TwoGears1(planet.point(0), R_PLANET, ("phi", np.pi), ring.point(0), R_RING,
                   -(R_PLANET + R_RING) * np.pi), name="ring mesh")
m.add(ms.RotationLock1(ring, 0.0), name="ring held")
m.add(ms.RotationLock1(sun, W_SUN * T), name="drive")
assert m.dof() == 0

t = np.linspace(0.0, 2.0, 25)
sol = m.solve(t)
w_c = sol.omega(carrier)
w_p = sol.omega(planet)

# Willis: (w_sun - w_c) / (w_ring - w_c) = -N_ring / N_sun = -3 with w_ring = 0
w_sun = float(W_SUN)
w_c_willis = w_sun / (1 + abs(R_RING) / R_SUN)
w_p_willis = w_c_willis - (w_sun - w_c_willis) * R_SUN / R_PLANET
print(f"carrier speed {w_c[0]:.6f} rad/s (Willis {w_c_willis:.6f}); "
      f"planet {w_p[0]:.6f} rad/s (Willis {w_p_willis:.6f})")
assert np.allclose(w_c, w_c_willis, atol=1e-10)
assert np.allclose(w_p, w_p_willis, atol=1e-10)
# the sun turns twice; the carrier half a turn, the planet centre stays on its circle
pc = sol.location(planet.point(0))
assert np.allclose(np.hypot(pc[:, 0], pc[:, 1]), ARM, atol=1e-10)

# Statics: the drive holds the sun, a resisting moment loads the carrier.
M_OUT = 8.0
m.add_load(ms.Moment(carrier, -M_OUT))
st = m.solve(0.0, solution="static")
_, tau = st.reaction("drive", "sun")
tau = float(np.ravel(tau)[0])
f_sun, _ = st.reaction("sun mesh", "sun", at=g.point((R_SUN, 0)))
tooth = float(np.hypot(*np.ravel(f_sun)))
# power balance tau w_sun = M_OUT w_c, and the tooth force on the sun is tau / r_sun
print(f"drive torque {tau:.6f} (hand: {M_OUT * w_c_willis / w_sun:.6f}); "
      f"sun tooth force {tooth:.6f} (hand: {tau / R_SUN:.6f})")
assert np.isclose(tau, M_OUT * w_c_willis / w_sun, atol=1e-9)
assert np.isclose(tooth, tau / R_SUN, atol=1e-9)
