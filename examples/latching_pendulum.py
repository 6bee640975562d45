"""A pendulum that swings onto a stop and latches (issue 14: free motion through a stage change).

A uniform rod of length ``2 c`` hangs from a pivot at the origin and is released at rest from
the horizontal. Its angle is constrained by a ``StageSwitch`` named ``"latch"``: stage 1 (angle
above ``-beta``) is a driver used only to assemble and animate the model kinematically and is
*dropped* in free motion (``drop=[("latch", 1)]``: the rod swings freely); stage 2 locks the
angle at ``-beta`` (the latch). The switch from stage 1 to stage 2 is located during the
integration as an event, to the integrator's accuracy; the rod arrives with angular velocity
``w = -sqrt(2 m g c sin(beta) / I_O)`` which the latch does not allow, so the user chooses what
happens to it:

* ``at_switch="project"``: the velocity compatible with the latch is kept (zero here); the
  kinetic energy ``m g c sin(beta)`` is lost and reported in ``sol.extra["events"]``;
* ``at_switch=("restitution", e)``: the rod rebounds off the stop with ``-e w`` and swings back
  (stage 1 continues), losing ``(1 - e^2)`` of its kinetic energy at each impact.

The time to reach the stop is the elliptic-integral time of a pendulum released from 90 degrees:
``t = (K(1/2) - F(u, 1/2)) / w0`` with ``sin(u) = sin(psi / 2) / sin(pi / 4)``, ``psi = pi/2 - beta``
(the angle from the bottom at the stop) and ``w0^2 = m g c / I_O``.

Run: python examples/latching_pendulum.py
"""

from __future__ import annotations

import numpy as np
from scipy.special import ellipkinc

import mechsys as ms
from mechsys import T

G, MASS, C, BETA = 9.81, 2.0, 0.5, np.radians(60)
I_CM = MASS * (2 * C) ** 2 / 12            # uniform rod about its centre
I_O = I_CM + MASS * C**2                   # about the pivot


def build() -> ms.Model2D:
    """The rod (body frame at its centre, pivot at local (-c, 0)) with the latch switch."""
    m = ms.Model2D()
    rod = m.add_body("rod", points={"pivot": (-C, 0.0)}, mass=MASS, inertia=I_CM,
                     guess=((C, 0.0), 0.0))
    m.add(ms.Revolute2(rod.point("pivot"), m.ground.point((0.0, 0.0))), name="pivot")
    m.add(ms.StageSwitch((rod.q[2] > -BETA, ms.RotationLock1(rod, -T)),
                         (True, ms.RotationLock1(rod, -BETA))), name="latch")
    m.add_load(ms.Gravity((0, -1), G))
    return m


def stop_time() -> float:
    """The elliptic-integral time to swing from the horizontal down to the stop."""
    w0 = np.sqrt(MASS * G * C / I_O)
    psi = np.pi / 2 - BETA
    u = np.arcsin(np.sin(psi / 2) / np.sin(np.pi / 4))
    return float((ellipkinc(np.pi / 2, 0.5) - ellipkinc(u, 0.5)) / w0)


def main() -> None:
    m = build()
    m.solve(0.0, solution="location")           # assemble at rest at the horizontal
    fs = m.free(drop=[("latch", 1)])
    sol = fs.simulate((0.0, 1.0), at_switch="project", rtol=1e-10, atol=1e-12)
    ev = sol.extra["events"][0]
    print(f"latched at t = {ev['t']:.10f} s (elliptic integral: {stop_time():.10f} s)")
    print(f"kinetic energy lost {ev['energy_lost']:.6f} J (m g c sin(beta) = "
          f"{MASS * G * C * np.sin(BETA):.6f} J); angle after: "
          f"{np.degrees(sol['rod.th'][-1]):.4f} deg, speed {sol.coordinate('rod.th', 1)[-1]:.1e}")
    bounce = fs.simulate((0.0, 0.6), at_switch=("restitution", 0.5), rtol=1e-10, atol=1e-12)
    first = bounce.extra["events"][0]
    print(f"with e = 0.5: rebound at t = {first['t']:.6f} s keeps "
          f"{first['kinetic_energy_after'] / first['kinetic_energy_before']:.4f} of the kinetic "
          f"energy (e^2 = 0.25); stage after the impact {first['stage_after']}")


if __name__ == "__main__":
    main()
