"""Caster (Mech manual 10.5): a nonholonomic wheel trailing a moving pivot.

Seen from above, the caster's pivot moves steadily along the global X axis (constraint 1);
the wheel sits ``TRAIL`` behind the pivot on the caster arm and can only roll along the arm:
its velocity is perpendicular to its axle. The dummy ``RotationLock1`` that assembles the
model is replaced by that velocity constraint. The pivot's travel is reversed with respect
to the caster's initial direction, so the caster swings out and settles behind the pivot.

Closed form (minimal coordinate, caster angle th, pivot speed V in -X)::

    th' = -(V / TRAIL) sin th   ->   tan(th/2) = tan(th0/2) exp(-V t / TRAIL)

Run: python examples/caster.py
"""

from __future__ import annotations

import numpy as np

import mechsys as ms
from mechsys import T

V, TRAIL, TH0 = 1.0, 0.3, np.pi - 0.05


def build():
    m = ms.Model2D()
    caster = m.add_body("caster", points={"wheel": (TRAIL, 0.0)}, guess=((0, 0), TH0))
    m.add(ms.Revolute2(caster.point(0), m.ground.point((-V * T, 0))), name="pivot")
    m.add(ms.RotationLock1(caster, TH0), name="dummy")
    m.solve(0.0)
    rolling = ms.Orthogonal1(m.velocity(caster.point("wheel")), caster.vector((0, 1)))
    return m, m.path(replace={"dummy": rolling})


def closed_form(t):
    return 2 * np.arctan(np.tan(TH0 / 2) * np.exp(-V * t / TRAIL))


def main() -> None:
    m, path = build()
    print(path)
    t = np.linspace(0, 3.0, 13)
    sol = path.simulate(t)
    for tk, th, ref in zip(t, sol["caster.th"], closed_form(t)):
        print(f"t = {tk:4.2f}  caster angle {np.degrees(th):9.4f} deg   closed form "
              f"{np.degrees(ref):9.4f} deg")
    print(f"holonomic drift {sol.extra['drift']:.1e}")


if __name__ == "__main__":
    main()
