"""Pendulum on a rope (Mech manual 10.1 and 10.4).

A slider runs without friction on an inextensible massless rope of length 5 hung between
ground points (0, 0) and (3, 0); a pendulum hangs from the slider. The rope's left part
has the unknown length ``s`` (a model variable), its right part ``5 - 1 - s`` (the slider is
1 long). Constraints 5, 6 and 7 only assemble the model and are dropped, one at a time, to
find the equilibrium under gravity and a spring (10.1); then, without the spring, the
pendulum is released from an offset position and its free response integrated (10.4).

Run: python examples/pendulum_on_rope.py
"""

from __future__ import annotations

import numpy as np
import sympy as sp

import mechsys as ms

G = 9.81


def build(spring: bool = True, dynamic: bool = False, offset: float = 0.0) -> ms.Model2D:
    """The seven-constraint model. ``offset``: initial pendulum angle (rad) for 10.4."""
    m = ms.Model2D()
    g = m.ground
    # ground points: P1 = left rope end (origin), P2 = right rope end, P3 = spring anchor
    anchors = {"left": (0.0, 0.0), "right": (3.0, 0.0), "spring": (4.0, -2.5)}
    inertia = (0.1, 0.4) if dynamic else (0.0, 0.0)
    slider = m.add_body("slider", points={"left": (-0.5, 0.0), "right": (0.5, 0.0)},
                        mass=1.0, inertia=inertia[0], guess=((1.5, -1.1), 0.0))
    pend = m.add_body("pendulum", points={"top": (0.0, 1.0)}, mass=2.0, inertia=inertia[1],
                      guess=((1.5, -2.1), 0.0))
    s = sp.Symbol("s", real=True)
    m.add(ms.RelativeDistance1(g.point(anchors["left"]), slider.point("left"), s), name="rope left")
    m.add(ms.RelativeDistance1(g.point(anchors["right"]), slider.point("right"), 5 - 1 - s),
          name="rope right")
    m.add(ms.Constraint([], {s: 1.5}), name="rope variable")
    m.add(ms.Revolute2(slider.point(0), pend.point("top")), name="hanger")
    m.add(ms.RelativeX1(slider.point(0), 1.5), name="slider x")
    m.add(ms.RotationLock1(slider, 0.0), name="slider rotation")
    m.add(ms.RotationLock1(pend, slider, offset), name="pendulum rotation")
    m.add_load(ms.Gravity((0, -1), G))
    if spring:
        m.add_load(ms.Spring(pend.point(0), g.point(anchors["spring"]), stiffness=20.0,
                             free_length=1.0))
    return m


def equilibrium_stages(m: ms.Model2D):
    """Drop constraint 7, then 5, then 6, each from the previous equilibrium."""
    m.solve()
    stages = []
    prev = None
    dropped: list[int] = []
    for cnum in (7, 5, 6):
        dropped.append(cnum)
        free = m.free(drop=list(dropped), solution="static", initial_guess=prev)
        prev = free.solve()
        stages.append((tuple(dropped), free, prev))
    return stages


def free_response(t_end: float = 4.5, **options):
    """Release from a 0.6 rad offset, spring removed, constraints 5-7 dropped."""
    m = build(spring=False, dynamic=True, offset=0.6)
    m.solve()
    free = m.free(drop=[5, 6, 7])
    sol = free.simulate((0.0, t_end), **options)
    return m, free, sol


def energy_drift(sol) -> float:
    """Total energy change over the run, relative to the largest kinetic energy (percent)."""
    E = sol.body_energy() + sol.potential_energy()
    return 100.0 * (E[-1] - E[0]) / np.max(sol.body_energy())


def main() -> None:
    m = build()
    for dropped, free, sol in equilibrium_stages(m):
        print(f"dropped {dropped}: {free}")
        print(f"   s = {sol['s']:.6f}   slider at {sol.location(m.body('slider').point(0))}"
              f"   pendulum angle {sol['pendulum.th']:+.6f}")
    _, _, sol = free_response()
    print(f"free response: {len(sol.t)} steps, energy drift {energy_drift(sol):+.2e} % "
          "of the peak kinetic energy")


if __name__ == "__main__":
    main()
