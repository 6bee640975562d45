"""A rotating plate cam with a pivoted flat-faced follower (after the Mech manual, section
6.1.2 "Example 2D Cam Mechanism").

As in the manual, the cam (body 2) turns about the ground point (0, 0) and the follower
(body 3) is a lever pivoted on ground at (-3.5, 4.0) whose flat face -- a line through the
pivot, along the lever -- rests on the cam. The cam profile is our own smooth convex curve
in polar form, r(alpha) = 2 + 0.4 sin(alpha) + 0.2 cos(2 alpha) (the manual's formula is not
reproduced here). The face touches the profile through ``CamToLine1``, whose parameter
alpha becomes a model variable.

We drive the cam one revolution, print the follower's swing, and check it against an
independent computation: the face is the tangent from the pivot to the cam, so its angle is
the largest angle under which the pivot sees a point of the turned profile (sampled densely).
The radius of curvature of the profile at the contact stays positive: the profile is convex
everywhere a flat face touches it (a concave stretch would be skipped by a real flat face).

Run: ``python examples/cam_2d_flat_follower.py [picture.png]`` (the picture: the cam profile,
drawn with ``CamPlot``, and the lever at a quarter turn).
"""

import sys

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

PIVOT = np.array([-3.5, 4.0])
alpha = sp.Symbol("alpha")
r = 2 + 0.4 * sp.sin(alpha) + 0.2 * sp.cos(2 * alpha)
profile = (r * sp.cos(alpha), r * sp.sin(alpha))  # local coordinates on the cam

m = ms.Model2D()
cam = m.add_body("cam", guess=((0, 0), 0))
follower = m.add_body("follower", guess=(tuple(PIVOT), -0.45))

m.add(ms.Revolute2(m.ground.point((0, 0)), cam.point(0)), name="cam bearing")
m.add(ms.RotationLock1(cam, T), name="drive")  # one radian per second
m.add(ms.Revolute2(m.ground.point(tuple(PIVOT)), follower.point(0)), name="pivot")
contact = m.add(ms.CamToLine1(cam.point(profile), (alpha, 1.3), follower.axis((0, 0), (1, 0))),
                name="cam contact")

# every picture of the model shows the cam profile, carried by the cam (Mech's CamPlot), the
# lever with its flat face along its x axis, and the two ground pivots
ms.draw.attach(m, ms.draw.CamPlot(cam.point(profile), (alpha, 0, 2 * sp.pi)),
               ms.draw.Bar(follower, ((0, 0), (6.5, 0)), width=0.12),
               ms.draw.GroundPivot(m.ground.point((0, 0))),
               ms.draw.GroundPivot(m.ground.point(tuple(PIVOT))))

print(m.dof())
th = np.linspace(0, 2 * np.pi, 73)
sol = m.solve(th, solution="acceleration")

phi = sol.angle(follower)
rho = ms.profile_radius(sol, contact)
touch = sol.location(cam.point(profile))  # the contact point, in global coordinates

print(f"\n{'cam [deg]':>9} {'lever [deg]':>11} {'omega':>8} {'ang acc':>9} {'contact x':>9} "
      f"{'contact y':>9} {'rho':>6}")
for k in range(0, len(th), 6):
    print(f"{np.degrees(th[k]):9.0f} {np.degrees(phi[k]):11.3f} {sol.omega(follower)[k]:8.4f} "
          f"{sol.alpha(follower)[k]:9.4f} {touch[k, 0]:9.4f} {touch[k, 1]:9.4f} {rho[k]:6.3f}")

# independent check: the tangent from the pivot to the turned profile
a = np.linspace(0, 2 * np.pi, 400001)
ra = 2 + 0.4 * np.sin(a) + 0.2 * np.cos(2 * a)
expected = np.empty_like(th)
for k, t in enumerate(th):
    x = ra * np.cos(a + t) - PIVOT[0]
    y = ra * np.sin(a + t) - PIVOT[1]
    expected[k] = np.max(np.arctan2(y, x))
err = np.abs(np.angle(np.exp(1j * (phi - expected)))).max()
print(f"\nmax |lever angle - tangent from the pivot| = {err:.1e} rad")
if err > 1e-8:
    raise SystemExit("the follower does not rest on the cam")
if not np.all(rho > 0):
    raise SystemExit("the flat face touches a concave stretch of the profile")

if len(sys.argv) > 1:
    import matplotlib.pyplot as plt

    fig = ms.draw.snapshot(sol, index=18)      # cam turned by 90 degrees
    fig.savefig(sys.argv[1], dpi=90)
    plt.close(fig)
    print(f"picture written to {sys.argv[1]}")
