"""Ellipse of mobility of a two-link planar arm (Mech manual 10.3.1-10.3.2).

A unit force of varying direction (parameter ``loadangle``) acts at the tip of link 2; the
two joints are free (the two RelativeAngle1 constraints that assemble the arm are dropped).
The free acceleration of the tip, over all load angles, traces the ellipse of mobility.
One FreeSystem serves every load angle through ``initial_condition={"loadangle": ...}``.

Run: python examples/two_link_arm_mobility.py [out.png]
"""

from __future__ import annotations

import sys

import numpy as np
import sympy as sp

import mechsys as ms


def build(th1: float = 0.3, th2: float = 0.9):
    m = ms.Model2D()
    a = m.add_body("link1", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0), inertia=1 / 12,
                   guess=((0, 0), th1))
    b = m.add_body("link2", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0), inertia=1 / 12,
                   guess=((np.cos(th1), np.sin(th1)), th1 + th2))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)), name="shoulder")
    m.add(ms.Revolute2(a.point("tip"), b.point(0)), name="elbow")
    m.add(ms.RelativeAngle1(a.vector((1, 0)), (1, 0), th1), name="set shoulder")
    m.add(ms.RelativeAngle1(b.vector((1, 0)), a.vector((1, 0)), th2), name="set elbow")
    phi = m.parameter("loadangle", 0.0)
    m.add_load(ms.Force(b.point("tip"), (sp.cos(phi), sp.sin(phi)), 1.0))
    return m


def ellipse(n: int = 73):
    m = build()
    m.solve(0.0, solution="velocity")
    free = m.free(drop=["set shoulder", "set elbow"])
    tip = m.body("link2").point("tip")
    angles = np.linspace(0, 2 * np.pi, n)
    acc = np.array([free.solve(0.0, initial_condition={"loadangle": a}).acceleration(tip)
                    for a in angles])
    return m, free, angles, acc


def main(path: str | None = None) -> None:
    m, free, angles, acc = ellipse()
    r = np.hypot(acc[:, 0], acc[:, 1])
    print(f"{free}")
    print(f"tip acceleration per unit force: min {r.min():.4f}, max {r.max():.4f}")
    if path:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.4, 3.2))
        ax.plot(acc[:, 0], acc[:, 1], "-", label="tip acceleration")
        ax.plot([0], [0], "k+")
        ax.set_aspect("equal")
        # links of 1 m and 1 kg: an acceleration per newton, m s^-2 N^-1 = 1/kg
        ax.set_xlabel("tip a_x / F [m/(s² N)]")
        ax.set_ylabel("tip a_y / F [m/(s² N)]")
        ax.set_title("Ellipse of mobility, two-link arm")
        fig.savefig(path, dpi=90, bbox_inches="tight")   # cropped to the drawing
        print(f"wrote {path}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
