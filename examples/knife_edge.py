"""A planar knife edge (sled) steered along a prescribed heading: nonholonomic path.

The sled's contact point may only move along the blade (no side slip) and moves forward at
``SPEED``; its heading is driven, ``theta = RATE T``. Both velocity constraints replace two
dummy constraints that assemble the model. With constant steering the contact point runs
on a circle of radius ``SPEED / RATE``::

    x = (SPEED/RATE) sin(RATE t),   y = (SPEED/RATE) (1 - cos(RATE t))

Run: python examples/knife_edge.py
"""

from __future__ import annotations

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

SPEED, RATE = 2.0, 0.8


def build():
    m = ms.Model2D()
    sled = m.add_body("sled", points={"blade": (0.0, 0.0)})
    m.add(ms.RelativeX1(sled.point("blade"), 0.0), name="dummy x")
    m.add(ms.RelativeY1(sled.point("blade"), 0.0), name="dummy y")
    m.add(ms.RotationLock1(sled, RATE * T), name="steering")
    m.solve(0.0)
    v = m.velocity(sled.point("blade"))
    ahead = sled.A * sp.Matrix([1, 0])
    no_side_slip = ms.Orthogonal1(v, sled.vector((0, 1)))
    forward = ms.Constraint([(v.T * ahead)[0, 0] - SPEED])
    return m, m.path(replace={"dummy x": no_side_slip, "dummy y": forward})


def main() -> None:
    m, path = build()
    t = np.linspace(0, 2 * np.pi / RATE, 9)
    sol = path.simulate(t, rtol=1e-10, atol=1e-12)
    p = sol.location(m.body("sled").point("blade"))
    R = SPEED / RATE
    ref = np.c_[R * np.sin(RATE * t), R * (1 - np.cos(RATE * t))]
    print(path)
    print(f"largest distance from the closed-form circle: {np.abs(p - ref).max():.2e}")


if __name__ == "__main__":
    main()
