"""A pin on a slider in a track with a jog (Mech section 5.2): a TimeSwitch and FindSwitchTime.

The slider's pin is driven along X at speed v (x = v T). The track is horizontal (y = 0) up to
x = x_j and then rises at angle beta: y = (x - x_j) tan(beta). As a TimeSwitch the track
changes at a switch time the user guesses; FindSwitchTime finds the time at which both tracks
hold (the pin at the corner), t = x_j / v, and with it the positions are continuous. The same
mechanism as a StageSwitch tests the pin's x coordinate instead of the time.

Run: ``python examples/slider_jog.py``
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

v, x_j, beta = 0.5, 2.0, np.radians(30)


def build(switch_time):
    m = ms.Model2D()
    m.parameter("t_switch", switch_time)
    s = m.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0))
    pin = s.point("pin")
    m.add(ms.RelativeX1(pin, v * T), name="drive")
    m.add(ms.RotationLock1(s, 0), name="no rotation")
    flat = ms.RelativeY1(pin, 0)
    ramp = ms.PointOnLine1(pin, m.ground.axis((x_j, 0), (np.cos(beta), np.sin(beta))))
    m.add(ms.TimeSwitch(flat, sp.Symbol("t_switch"), ramp), name="track")
    return m, s


t = np.linspace(0, 8, 33)
m, slider = build(3.0)                      # a poor guess of the switch time
sol = m.solve(t)
y = sol.location(slider.point("pin"))[:, 1]
jump = np.abs(np.diff(y)).max()
print(f"switch time guessed 3.0: largest step of the pin's y between samples {jump:.3f}")

ts = ms.FindSwitchTime(m, "track", 1)       # range: the span of the last solution
print(f"FindSwitchTime: {ts:.15f}   closed form x_j / v = {x_j / v:.15f}")
assert abs(ts - x_j / v) < 1e-12

m.set_parameters(t_switch=ts)
sol = m.solve(t)
y = sol.location(slider.point("pin"))[:, 1]
x = sol.location(slider.point("pin"))[:, 0]
exact = np.where(x < x_j, 0.0, (x - x_j) * np.tan(beta))
print(f"with the found time: max |y - track| = {np.abs(y - exact).max():.2e}, stages "
      f"{sol.stage('track')[[0, 16, -1]]}")
assert np.abs(y - exact).max() < 1e-12

# the same track as a StageSwitch on the pin's x coordinate
m2 = ms.Model2D()
s2 = m2.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0))
pin2 = s2.point("pin")
m2.add(ms.RelativeX1(pin2, v * T), name="drive")
m2.add(ms.RotationLock1(s2, 0), name="no rotation")
m2.add(ms.StageSwitch(
    (s2.q[0] < x_j, ms.RelativeY1(pin2, 0)),
    (True, ms.PointOnLine1(pin2, m2.ground.axis((x_j, 0), (np.cos(beta), np.sin(beta))))),
), name="track")
sol2 = m2.solve(t)
assert np.abs(sol2.q - sol.q).max() < 1e-12
print("StageSwitch on x gives the same motion; pin reaches y = 1 at t =",
      ms.FindTime(m2, sp.Eq(s2.q[1], 1.0), (0, 8)), "(closed form",
      (x_j + 1 / np.tan(beta)) / v, ")")
