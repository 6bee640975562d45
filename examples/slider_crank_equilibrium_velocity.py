"""Equilibrium velocity of a slider-crank (Mech manual 10.2).

A driving moment that fades with speed, ``M = M0 (1 - w / w0)``, turns the crank against
viscous friction on the piston, ``F = -c xd``. With the driver constraint dropped the model
has one degree of freedom; at each crank position (``initial_condition`` from a kinematic
solution there) the velocity at which the loads balance is found. Centrifugal (inertial)
terms do not enter a velocity equilibrium.

Closed form for the check: the loads' power balances, ``M(w) w = c xd^2`` with
``xd = (dx/dth) w``, so ``w = M0 / (c (dx/dth)^2 + M0 / w0)``.

Run: python examples/slider_crank_equilibrium_velocity.py
"""

from __future__ import annotations

import numpy as np

import mechsys as ms
from mechsys import models

M0, W0, C = 50.0, 20.0, 3.0


def build():
    m = models.slider_crank(crank=2.0, rod=6.0, speed=1.0)   # driver: th = T
    crank, piston = m.body("crank"), m.body("piston")
    w = m.velocity_symbols()[crank.q[2]]
    m.add_load(ms.Moment(crank, M0 * (1 - w / W0)))
    m.add_load(ms.Damper(piston.point(0), (100.0, 0.0), C))   # horizontal viscous slider
    return m


def cycle(n: int = 37):
    m = build()
    angles = np.linspace(0.05, 2 * np.pi - 0.05, n)
    kin = m.solve(angles)                      # positions (and velocities) along the cycle
    free = m.free(drop=["drive"], solution="kinematic")
    omegas = []
    for k in range(len(angles)):
        s = free.solve(float(angles[k]), initial_condition=kin.state(k))
        omegas.append(s.coordinate("crank.th", 1))
    return m, angles, np.array(omegas)


def closed_form(angles, r=2.0, L=6.0):
    dxdth = -r * np.sin(angles) - r**2 * np.sin(angles) * np.cos(angles) / np.sqrt(
        L**2 - (r * np.sin(angles)) ** 2)
    return M0 / (C * dxdth**2 + M0 / W0)


def main() -> None:
    m, angles, w = cycle()
    ref = closed_form(angles)
    print(f"{'crank [deg]':>12} {'w [rad/s]':>12} {'closed form':>12}")
    for a, x, y in zip(angles[::4], w[::4], ref[::4]):
        print(f"{np.degrees(a):12.1f} {x:12.6f} {y:12.6f}")
    print(f"largest difference from the closed form: {np.abs(w - ref).max():.2e}")


if __name__ == "__main__":
    main()
