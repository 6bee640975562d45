"""A rolling disk (a coin, a wheel) steered around a circle: nonholonomic path with exact rolling.

The disk of radius ``R`` touches the ground plane (``roll.holonomic()``, a
``PlaneToCircle1``) and rolls on it without slipping (``RollingDisk2``: the velocity of the
disk's material point at the contact is zero). Its attitude is driven: heading
``psi = TURN T`` about the vertical, a constant lean ``LEAN`` about the heading, and a spin
``theta = SPIN T`` about the disk's axis. Two dummy constraints hold the centre's x and y
while the model is assembled; the path replaces them by the two no-slip equations, so the
position of the disk follows by integrating its velocities.

Closed form: at constant lean the contact point runs forward along the heading at the
speed ``R SPIN`` (the rim unrolls on the plane), so it traces a circle of radius
``R SPIN / TURN`` whatever the lean::

    c(t) = c(0) + (R SPIN / TURN) (sin(TURN t), 1 - cos(TURN t), 0)

The example prints the largest distance of the contact from that circle and the largest
slip velocity (both near the integration tolerance and rounding: about 1e-10 and 1e-15).

Run: python examples/rolling_disk.py
"""

from __future__ import annotations

import numpy as np

import mechsys as ms
from mechsys import T

R, LEAN, TURN, SPIN = 0.3, 0.25, 0.8, 5.0


def build():
    m = ms.Model3D()
    disk = m.add_body("disk", guess=((0, 0, R * np.cos(LEAN)), (1, 0, 0, 0)))
    ground = m.ground.axis((0, 0, 0), (0, 0, 1))             # the plane z = 0, normal +z
    roll = ms.RollingDisk2(ground, disk.axis(0, (0, 1, 0)), R)   # the disk's axis: local y
    m.add(roll.holonomic(), name="touch")
    m.add(ms.RotationLock3(disk, (TURN * T, (0, 0, 1)), (LEAN, (1, 0, 0)), (SPIN * T, (0, 1, 0))),
          name="attitude")
    m.add(ms.RelativeX1(disk.point(0), 0.0), name="dummy x")
    m.add(ms.RelativeY1(disk.point(0), R * np.sin(LEAN)), name="dummy y")
    # a thin disk for the pictures: a short cylinder about the axis
    ms.draw.attach(m, ms.draw.Cylinder(disk, (0, -0.01, 0), (0, 0.01, 0), radius=R))
    m.solve(0.0)
    return m, roll, m.path(replace={("dummy x", "dummy y"): roll})


def closed_form(t, c0):
    rho = R * SPIN / TURN
    return c0 + np.c_[rho * np.sin(TURN * t), rho * (1 - np.cos(TURN * t)), 0 * t]


def main() -> None:
    m, roll, path = build()
    t = np.linspace(0, 2 * np.pi / TURN, 41)
    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    c = sol.location(roll.contact_point())
    off = np.abs(c - closed_form(t, c[0])).max()
    slip = np.abs(sol.eval(roll.slip_velocity())).max()
    print(path)
    print(f"contact circle radius {R * SPIN / TURN:.4f}; largest distance from the closed form: "
          f"{off:.2e}")
    print(f"largest slip velocity at the contact: {slip:.2e}")


if __name__ == "__main__":
    main()
