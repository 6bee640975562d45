"""Four-bar linkage checked against Freudenstein's equation.

Ground pivots O2 = (0, 0) and O4 = (d, 0); crank O2A of length a at angle th2 (the input),
coupler AB of length b, rocker O4B of length c at angle th4 (the output). Closing the loop
gives Freudenstein's equation

    K1 cos(th4) - K2 cos(th2) + K3 = cos(th2 - th4),
    K1 = d / a,  K2 = d / c,  K3 = (a^2 - b^2 + c^2 + d^2) / (2 a c),

whose solution for th4 is closed-form. We model the linkage with three moving bodies, drive
the crank through one revolution, and compare the solved rocker angle and angular velocity
with Freudenstein's.

Run: ``python examples/four_bar.py``
"""

import numpy as np

import mechsys as ms
from mechsys import T

a, b, c, d = 1.0, 4.0, 3.0, 4.0  # crank, coupler, rocker, ground: a Grashof crank-rocker
K1, K2, K3 = d / a, d / c, (a**2 - b**2 + c**2 + d**2) / (2 * a * c)

m = ms.Model2D()
g = m.ground
crank = m.add_body("crank", points={"A": (a, 0)}, guess=((0, 0), 0))
coupler = m.add_body("coupler", points={"A": (0, 0), "B": (b, 0)}, guess=((a, 0), 0.9))
rocker = m.add_body("rocker", points={"B": (c, 0)}, guess=((d, 0), 1.8))  # open branch

m.add(ms.Revolute2(g.point((0, 0)), crank.point(0)), name="O2")
m.add(ms.Revolute2(crank.point("A"), coupler.point("A")), name="A")
m.add(ms.Revolute2(coupler.point("B"), rocker.point("B")), name="B")
m.add(ms.Revolute2(g.point((d, 0)), rocker.point(0)), name="O4")
m.add(ms.RotationLock1(crank, T), name="drive")  # th2 = T, 1 rad/s

t = np.linspace(0, 2 * np.pi, 73)
sol = m.solve(t)
th2 = sol.angle(crank)
th4 = sol.angle(rocker)
w4 = sol.omega(rocker)

# Freudenstein: P cos(th4) + Q sin(th4) + R = 0, solved for th4 on the branch of the model
P, Q, R = np.cos(th2) - K1, np.sin(th2), K2 * np.cos(th2) - K3
base, half = np.arctan2(Q, P), np.arccos(-R / np.hypot(P, Q))
branches = [base + half, base - half]
sign = np.argmin([abs(np.angle(np.exp(1j * (br[0] - th4[0])))) for br in branches])
th4_exact = branches[sign]
# angular velocity by implicit differentiation of F(th2, th4) = 0, with d th2/dt = 1
F2 = K2 * np.sin(th2) + np.sin(th2 - th4_exact)
F4 = -K1 * np.sin(th4_exact) - np.sin(th2 - th4_exact)
w4_exact = -F2 / F4

residual = K1 * np.cos(th4) - K2 * np.cos(th2) + K3 - np.cos(th2 - th4)
d_angle = np.abs(np.angle(np.exp(1j * (th4 - th4_exact))))

print(f"four-bar a={a} b={b} c={c} d={d}: K1={K1:.4f} K2={K2:.4f} K3={K3:.4f}")
print(f"{'th2 [deg]':>9} {'th4 [deg]':>10} {'Freudenstein':>12} {'residual':>10} "
      f"{'omega4':>9} {'Freudenstein':>12}")
for k in range(0, len(t), 6):
    print(f"{np.degrees(th2[k]):9.0f} {np.degrees(th4[k]) % 360:10.4f} "
          f"{np.degrees(th4_exact[k]) % 360:12.4f} {residual[k]:10.1e} "
          f"{w4[k]:9.5f} {w4_exact[k]:12.5f}")
print(f"max |Freudenstein residual| = {np.abs(residual).max():.1e}")
print(f"max |th4 - closed form| = {d_angle.max():.1e} rad, "
      f"max |omega4 - closed form| = {np.abs(w4 - w4_exact).max():.1e} rad/s")
if np.abs(residual).max() > 1e-9 or d_angle.max() > 1e-9 or np.abs(w4 - w4_exact).max() > 1e-8:
    raise SystemExit("the four-bar does not satisfy Freudenstein's equation")
