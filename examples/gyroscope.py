"""Gyroscope (Mech manual 10.3.3-10.3.5, 10.4.4-10.4.6).

Base turns about the vertical ground axis Z, the gimbal about the base's horizontal X
axis, the rotor about the gimbal's Y axis; all origins coincide and every body starts
aligned with the global axes. Base and gimbal are massless; the rotor is a thin disk.
A constant moment ``MZ`` about Z acts on the base. Constraints 2 and 4 only lock base and
gimbal for assembly; constraint 6 drives the rotor's spin relative to the gimbal at
``freq``. Three equivalent models:

* ``"rotor"``: the spinning rotor itself;
* ``"gyromoment"``: the rotor kept but not spinning, its spin replaced by ``GyroMoment``;
* ``"gyrofilter"``: the rotor removed: its inertia, filtered by ``GyroFilter``, and a
  ``GyroMoment`` go on the gimbal.

Run: python examples/gyroscope.py
"""

from __future__ import annotations

import numpy as np

import mechsys as ms
from mechsys import T

MASS, RADIUS, MZ, FREQ = 1.0, 0.5, 1.0, 30.0
I_S = MASS * RADIUS**2 / 2          # spin axis (rotor Y)
I_T = MASS * RADIUS**2 / 4          # transverse
ROTOR_J = (I_T, I_S, I_T, 0, 0, 0)


def build(kind: str = "rotor", freq: float = FREQ) -> ms.Model3D:
    m = ms.Model3D()
    g = m.ground
    base = m.add_body("base")
    gimbal_j = ms.gyro_filter(ROTOR_J, (0, 1, 0)) if kind == "gyrofilter" else None
    gimbal = m.add_body("gimbal", mass=MASS if kind == "gyrofilter" else 0.0, inertia=gimbal_j)
    m.add(ms.Revolute5(base.axis(0, (0, 0, 1)), g.axis((0, 0, 0), (0, 0, 1))), name="base axis")
    m.add(ms.Orthogonal1(base.vector((1, 0, 0)), (0, 1, 0)), name="base lock")
    m.add(ms.Revolute5(gimbal.axis(0, (1, 0, 0)), base.axis(0, (1, 0, 0))), name="gimbal axis")
    m.add(ms.Orthogonal1(gimbal.vector((0, 1, 0)), base.vector((0, 0, 1))), name="gimbal lock")
    if kind != "gyrofilter":
        rotor = m.add_body("rotor", mass=MASS, inertia=ROTOR_J)
        m.add(ms.Revolute5(rotor.axis(0, (0, 1, 0)), gimbal.axis(0, (0, 1, 0))), name="rotor axis")
        spin = freq * T if kind == "rotor" else 0
        m.add(ms.RotationLock1(rotor.axis(0, (0, 1, 0), (1, 0, 0)),
                               gimbal.axis(0, (0, 1, 0), (1, 0, 0)), spin), name="spin")
        if kind == "gyromoment":
            m.add_load(ms.GyroMoment(rotor, (0, 1, 0), freq, inertia=I_S))
    else:
        m.add_load(ms.GyroMoment(gimbal, (0, 1, 0), freq, inertia=I_S))
    m.add_load(ms.Moment(base, (0, 0, 1), MZ))
    return m


def initial_condition(kind: str, base_rate=0.0, gimbal_rate=0.0, freq: float = FREQ) -> dict:
    """Angular velocities: every body shares the base's Z rate; gimbal and rotor add the
    gimbal's X rate; the spinning rotor adds its spin about Y."""
    cond: dict[tuple[str, str], tuple[float, float, float]] = {
        ("omega", "base"): (0, 0, base_rate), ("omega", "gimbal"): (gimbal_rate, 0, base_rate)}
    if kind != "gyrofilter":
        spin = freq if kind == "rotor" else 0.0
        cond[("omega", "rotor")] = (gimbal_rate, spin, base_rate)
    return cond


def free_acceleration(kind="rotor", drop=("base lock",), base_rate=0.0, gimbal_rate=0.0):
    m = build(kind)
    m.solve(0.0, solution="velocity")
    free = m.free(drop=list(drop))
    return m, free.solve(0.0, initial_condition=initial_condition(kind, base_rate, gimbal_rate))


def base_angle(sol):
    """Base rotation about Z from its Euler parameters (robust projected angle)."""
    e0, e3 = sol["base.e0"], sol["base.e3"]
    return np.unwrap(2 * np.arctan2(e3, e0))


def free_response(kind="gyromoment", t_end=2.0, **options):
    """Free motion with constraints 2, 4 and 6 dropped (6 only where the rotor exists)."""
    m = build(kind)
    m.solve(0.0, solution="velocity")
    drop = ["base lock", "gimbal lock"] + (["spin"] if kind != "gyrofilter" else [])
    free = m.free(drop=drop)
    sol = free.simulate((0.0, t_end), initial_condition=initial_condition(kind), **options)
    return m, free, sol


def energy_drift(sol) -> float:
    """Total energy change (kinetic, plus the applied moment's potential -MZ psi) in percent
    of the largest kinetic energy."""
    E = sol.body_energy() - MZ * base_angle(sol)
    return 100.0 * (E[-1] - E[0]) / np.max(np.abs(sol.body_energy()))


def main() -> None:
    for drop, rate in ((("base lock",), 0.0), (("base lock",), 2.0),
                       (("base lock", "gimbal lock"), 2.0)):
        m, s = free_acceleration("rotor", drop, base_rate=rate)
        print(f"drop {drop}, base rate {rate}: base alpha {s.alpha('base')}, "
              f"gimbal alpha {s.alpha('gimbal')}")
    for kind in ("rotor", "gyromoment", "gyrofilter"):
        m, free, sol = free_response(kind, 1.0)
        print(f"{kind:>10}: base angle at 1 s {base_angle(sol)[-1]:+.6f}, "
              f"gimbal e1 {sol['gimbal.e1'][-1]:+.6f}, steps {sol.extra['steps']}")


if __name__ == "__main__":
    main()
