"""A four-slot Geneva drive as a StageSwitch (Mech chapter 5), checked against its closed form.

The crank turns about the origin at 1 rad/s (theta = T); its pin, at radius a, engages the
radial slots of the wheel, whose centre is at distance c on the +x axis. With four slots the
pin enters a slot tangentially when a / c = lambda = sin(pi/4). While engaged (|theta| <=
pi/4 modulo a turn) the wheel angle follows

    tan(phi) = sin(theta) / (1/lambda - cos(theta)),   wheel rotation = -phi,

and while the pin is outside the wheel is locked (the locking disc holds it). Each stage
removes one degree of freedom: the pin on the slot's line (PointOnLine1 with the slot of the
wheel) or the wheel's angle fixed (RotationLock1). Over two crank turns the wheel steps by 90
degrees per turn, in a quarter of the turn.

Run: ``python examples/geneva_drive.py``
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

c = 2.0                      # centre distance
lam = np.sin(np.pi / 4)      # four slots
a = lam * c                  # crank (pin) radius

m = ms.Model2D()
g = m.ground
crank = m.add_body("crank", points={"pin": (a, 0)}, guess=((0, 0), -np.pi))
wheel = m.add_body("wheel", guess=((c, 0), np.pi / 4))
m.add(ms.Revolute2(g.point((0, 0)), crank.point(0)), name="crank pivot")
m.add(ms.Revolute2(g.point((c, 0)), wheel.point(0)), name="wheel pivot")
m.add(ms.RotationLock1(crank, T - np.pi), name="drive")  # theta from -pi over two turns

th = crank.q[2]
pin = crank.point("pin")
q4 = np.pi / 4
# the slot facing the crank lies along the wheel's local x axis in the first engagement and
# along its local y axis in the second (the wheel has turned a quarter turn in between)
m.add(ms.StageSwitch(
    (th < -q4, ms.RotationLock1(wheel, q4)),
    (th <= q4, ms.PointOnLine1(pin, wheel.axis((0, 0), (1, 0)))),
    (th < 2 * sp.pi - q4, ms.RotationLock1(wheel, -q4)),
    (th <= 2 * sp.pi + q4, ms.PointOnLine1(pin, wheel.axis((0, 0), (0, 1)))),
    (True, ms.RotationLock1(wheel, -3 * q4)),
), name="geneva")

t = np.linspace(0, 4 * np.pi, 321)
sol = m.solve(t)
theta = sol.angle(crank)
wheel_angle = sol.angle(wheel)
stage = sol.stage("geneva")

# closed form while engaged: rotation -phi about the mid-engagement angle (0, then -pi/2)
engaged = (stage == 2) | (stage == 4)
rel = np.where(stage == 2, theta, theta - 2 * np.pi)
phi = np.arctan2(np.sin(rel), 1 / lam - np.cos(rel))
mid = np.where(stage == 2, 0.0, -np.pi / 2)
err = np.abs(wheel_angle - (mid - phi))[engaged].max()
print(f"engaged at {engaged.sum()} of {len(t)} points; max |wheel angle - closed form| = {err:.2e}")
assert err < 1e-10

locked = ~engaged
for s, value in ((1, q4), (3, -q4), (5, -3 * q4)):
    assert np.abs(wheel_angle[stage == s] - value).max() < 1e-12
print("wheel still while locked; steps per crank turn:",
      np.round(np.degrees(wheel_angle[stage == 3][0] - wheel_angle[stage == 1][0]), 9),
      np.round(np.degrees(wheel_angle[stage == 5][0] - wheel_angle[stage == 3][0]), 9))

# engagement lasts a quarter of the crank turn: the switch times, found as the times at which
# both neighbouring stages hold (the pin at the slot's mouth); the pin enters and leaves
# tangentially, so the stages touch without crossing: tangent=True
t_in = ms.FindSwitchTime(m, "geneva", 1, t_range=(0.1, 3.0), tangent=True)
t_out = ms.FindSwitchTime(m, "geneva", 2, t_range=(t_in + 0.1, 5.0), tangent=True)
print(f"engaged from t = {t_in:.12f} to {t_out:.12f}: {np.degrees(t_out - t_in):.9f} degrees of crank")
assert abs((t_out - t_in) - np.pi / 2) < 1e-9
