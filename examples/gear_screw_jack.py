"""A screw jack: a motor shaft drives a bevel gear set that turns a lead screw, which lifts a
nut that cannot turn (Mech manual, ch. 6.2.2 3D gear constraints).

The motor shaft lies along global x with a 12-tooth bevel pinion; the 36-tooth bevel gear
is fixed to the vertical screw (z). ``OrthogonalGears5`` relates the two rotations (and
places the pinion's axis through the apex); ``LeadScrew5`` ties the nut's rise to the
screw's turn with a 5 mm pitch. We check the nut's travel against ``pitch * theta / 2 pi``
and, with a load on the nut, the motor torque of a static solution against the power
balance.

Run: ``python examples/gear_screw_jack.py``
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

TEETH_PINION, TEETH_GEAR, PITCH = 12, 36, 0.005
W_MOTOR = 2 * sp.pi * 3          # three motor revolutions per second
LOAD = 2000.0                     # newtons on the nut, downwards

m = ms.Model3D()
g = m.ground
z, x = (0, 0, 1), (1, 0, 0)
screw = m.add_body("screw", guess=((0, 0, 0), (1, 0, 0, 0)))
motor = m.add_body("motor", guess=((0, 0, 0), (1, 0, 0, 0)))
nut = m.add_body("nut", guess=((0, 0, 0.2), (1, 0, 0, 0)))

m.add(ms.Revolute5(screw.axis(0, z), g.axis((0, 0, 0), z)), name="screw bearing")
# the bevel set: gear (on the screw, axis z) and pinion (motor, axis x), common apex;
# C = 36 e1 + 12 e2 = 0 with both reference directions set at assembly
m.add(ms.OrthogonalGears5(screw.axis(0, z), TEETH_GEAR, ("a_bevel", 0.0),
                          motor.axis(0, x), TEETH_PINION, 0.0), name="bevel")
m.add(ms.Orthogonal1(motor.vector(x), (0, 1, 0)), name="motor bearing")   # shaft stays on x
m.add(ms.LeadScrew5(screw.axis(0, z), ("a_screw", 0.0), nut.axis(0, z), PITCH, -0.2), name="screw")
m.add(ms.RotationLock1(nut.axis(0, z, x), g.axis((0, 0, 0), z, x), 0.0), name="nut guide")
m.add(ms.RotationLock1(motor.axis(0, x), g.axis((0, 0, 0), x), W_MOTOR * T), name="motor")
assert m.dof() == 0

t = np.linspace(0.0, 1.0, 11)
sol = m.solve(t)
w_screw = sol.omega(screw)[:, 2]
rise = sol.location(nut.point(0))[:, 2]
w_motor = float(W_MOTOR)
theta_screw = -w_motor * TEETH_PINION / TEETH_GEAR * t       # bevel ratio -t1/t2
print(f"screw speed {w_screw[0]:.6f} rad/s (bevel ratio: {-w_motor * TEETH_PINION / TEETH_GEAR:.6f})")
assert np.allclose(w_screw, -w_motor * TEETH_PINION / TEETH_GEAR, atol=1e-10)
# s = z_screw - z_nut = C + pitch alpha / 2 pi, alpha = screw spin relative to the nut
expected = 0.2 - PITCH * theta_screw / (2 * np.pi)
print(f"nut height after {t[-1]} s: {rise[-1]:.6f} m (pitch * theta / 2 pi: {expected[-1]:.6f})")
assert np.allclose(rise, expected, atol=1e-12)

# Statics: the load pushes the nut down; the motor driver holds it.
m.add_load(ms.Force(nut.point(0), (0, 0, -1), LOAD))
st = m.solve(0.0, solution="static")
_, torque = st.reaction("motor", "motor")
tau_x = float(np.ravel(torque)[0])
v_nut = PITCH / (2 * np.pi) * w_motor * TEETH_PINION / TEETH_GEAR   # nut speed per unit
tau_hand = LOAD * v_nut / w_motor                                  # power balance
print(f"motor torque {tau_x:.6f} N m (power balance: {tau_hand:.6f})")
assert np.isclose(abs(tau_x), tau_hand, rtol=1e-9)
