"""The design loop: a four-bar's coupler curve following its link lengths, with sliders.

In Jupyter, ``ms.draw.explore`` shows a slider per parameter; each change re-solves the
linkage over one crank revolution and redraws it with the coupler point's curve. Here the
sliders are moved from code (as a drag would move them) and each new curve is checked
against the closed form: the crank tip ``A = a (cos th, sin th)``, the rocker tip ``B`` at
the intersection of the circles of radius ``b`` about ``A`` and ``c`` about the rocker pivot
(on the branch the linkage was assembled in), and the coupler point ``P`` fixed in the
coupler at ``(b/2, h)``. Lengths that cannot close the loop leave the last picture and say
why.

Run: ``python examples/four_bar_sliders.py`` (needs ipywidgets: ``pip install ipywidgets``)
"""

import importlib.util

import numpy as np

import mechsys as ms
from mechsys import T

D, C, H = 4.0, 3.0, 1.0          # ground, rocker, coupler-point offset


def build():
    m = ms.Model2D()
    a = m.parameter("crank", 1.0)
    b = m.parameter("coupler", 4.0)
    crank = m.add_body("crank", points={"A": (a, 0)}, guess=((0, 0), 0))
    cp = m.add_body("coupler", points={"B": (b, 0), "P": (b / 2, H)}, guess=((1, 0), 0.9))
    rocker = m.add_body("rocker", points={"B": (C, 0)}, guess=((D, 0), 1.8))
    m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)), name="O2")
    m.add(ms.Revolute2(crank.point("A"), cp.point(0)), name="A")
    m.add(ms.Revolute2(cp.point("B"), rocker.point("B")), name="B")
    m.add(ms.Revolute2(m.ground.point((D, 0)), rocker.point(0)), name="O4")
    m.add(ms.RotationLock1(crank, T), name="drive")
    return m


def coupler_curve(a, b, th):
    """Closed form of the coupler point P over crank angles ``th`` (open branch)."""
    A = a * np.stack([np.cos(th), np.sin(th)], axis=1)
    O4 = np.array([D, 0.0])
    d = np.linalg.norm(O4 - A, axis=1)
    along = (b**2 - C**2 + d**2) / (2 * d)               # from A towards O4
    half = np.sqrt(b**2 - along**2)
    u = (O4 - A) / d[:, None]
    n = np.stack([-u[:, 1], u[:, 0]], axis=1)
    B = A + along[:, None] * u + half[:, None] * n        # the branch above the line A-O4
    e = (B - A) / b
    f = np.stack([-e[:, 1], e[:, 0]], axis=1)
    return A + (b / 2) * e + H * f


def main():
    m = build()
    t = np.linspace(0, 2 * np.pi, 73)
    P = m.body("coupler").point("P")
    if importlib.util.find_spec("ipywidgets") is None:
        print("ipywidgets is not installed: solving without sliders")
        sol = m.solve(t)
        assert np.allclose(sol.location(P), coupler_curve(1.0, 4.0, t), atol=1e-9)
        return
    ex = ms.draw.explore(m, t, parameters={"crank": (0.5, 2.5), "coupler": (3.0, 5.0)},
                         graphics=[ms.draw.LocusPlot(P)])
    for a, b in ((1.0, 4.0), (1.3, 4.0), (1.3, 3.4), (0.7, 4.6)):
        ex.set(crank=a, coupler=b)
        err = np.abs(ex.solution.location(P) - coupler_curve(a, b, t)).max()
        print(f"crank {a}, coupler {b}: coupler curve within {err:.1e} of the closed form "
              f"({ex.message})")
        assert err < 1e-9
    drawn = ex.redraws
    ex.set(crank=2.5, coupler=5.0)    # at th = 0: |A O4| = 1.5 < coupler - rocker = 2
    print("crank 2.5, coupler 5.0:", ex.message[:90], "...")
    assert ex.message.startswith("cannot solve") and ex.redraws == drawn
    assert m.parameters == {"crank": 0.7, "coupler": 4.6}     # the last good values kept
    ex.figure.savefig("four_bar_sliders.png", dpi=80)


if __name__ == "__main__":
    main()
