"""A rotating 3D cam with a spherical follower on a rocker (after the Mech manual, section
6.1.4 "Example 3D Cam Mechanism").

As in the manual, the cam turns about the global Y axis through (0, 0, 0) and the follower
is a rocker pivoted about the parallel axis through (-2, 0, 2); a ball of radius 0.25 at the
end of the rocker's arm rides on the cam. The cam surface is built as in the manual's
section 6.1.3: a 2D profile in the cam's local x-z plane, r(alpha) = 1 + 0.3 cos(alpha)
(our own formula), swept along the local y axis by a second parameter ``t``. The ball
touches it through ``CamToSphere1``; the parameters are given in the order (t, alpha) so
that the surface normal t_t x t_alpha points out of the cam, the side of a positive radius.

We drive the cam one revolution, print the rocker's swing and the pressure angle, and check
the contact independently: the ball's centre stays exactly one ball radius from the turned
profile (the distance found by dense sampling of the profile).

Run: ``python examples/cam_3d_spherical_follower.py``
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

Y = (0, 1, 0)
BALL, ARM = 0.25, 2.1
alpha, t = sp.symbols("alpha t")
r = 1 + 0.3 * sp.cos(alpha)
surface = (r * sp.cos(alpha), t, r * sp.sin(alpha))  # local coordinates on the cam

m = ms.Model3D()
cam = m.add_body("cam")
psi = 0.36  # the rocker's starting guess: a turn about Y bringing the ball over the cam
rocker = m.add_body("rocker", points={"ball": (ARM, 0, 0)},
                    guess=((-2, 1, 2), (np.cos(psi / 2), 0, np.sin(psi / 2), 0)))

m.add(ms.Revolute5(cam.axis(0, Y), m.ground.axis((0, 0, 0), Y)), name="cam bearing")
m.add(ms.RotationLock1(cam.axis(0, Y), m.ground.axis((0, 0, 0), Y), T), name="drive")
m.add(ms.Revolute5(rocker.axis(0, Y), m.ground.axis((-2, 1, 2), Y)), name="rocker pivot")
contact = m.add(ms.CamToSphere1(cam.point(surface), (t, 1.0), (alpha, 1.5), rocker.point("ball"), BALL),
                name="ball on cam")

print(m.dof())
th = np.linspace(0, 2 * np.pi, 49)
sol = m.solve(th, solution="velocity")

centre = sol.location(rocker.point("ball"))
phi = ms.pressure_angle(sol, contact)  # along the ball centre's velocity
print(f"\n{'cam [deg]':>9} {'ball x':>8} {'ball z':>8} {'ball vz':>8} {'pressure [deg]':>14}")
for k in range(0, len(th), 4):
    vz = sol.velocity(rocker.point("ball"))[k, 2]
    print(f"{np.degrees(th[k]):9.0f} {centre[k, 0]:8.4f} {centre[k, 2]:8.4f} {vz:8.4f} "
          f"{np.degrees(phi[k]):14.2f}")

# independent check: the distance from the ball's centre to the turned profile. The cam's
# local x and z axes, globally, from two of its points (the drive fixes them).
ex = sol.location(cam.point((1, 0, 0)))
ez = sol.location(cam.point((0, 0, 1)))
a = np.linspace(0, 2 * np.pi, 400001)
ra = 1 + 0.3 * np.cos(a)
px, pz = ra * np.cos(a), ra * np.sin(a)
dist = np.empty_like(th)
for k in range(len(th)):
    pts = np.outer(px, ex[k]) + np.outer(pz, ez[k])  # profile points in the plane y = 0
    d = centre[k] - pts
    d[:, 1] = 0.0  # the ball touches the cam in its own plane y = 1 (the surface is a prism)
    dist[k] = np.sqrt((d**2).sum(axis=1)).min()
err = np.abs(dist - BALL).max()
print(f"\nmax |distance from the ball's centre to the cam - ball radius| = {err:.1e}")
if err > 1e-8:
    raise SystemExit("the ball does not touch the cam")
if not np.allclose(centre[:, 1], 1.0):
    raise SystemExit("the ball left its plane")
