r"""Cam synthesis: from a follower motion law to a spline cam profile, and back.

The law (cam angle ``theta``, one revolution): a cycloidal rise of height ``H`` over
``BETA1``, a dwell, a cycloidal return over ``BETA3`` and a dwell. Cycloidal, with
``x = theta / beta`` on a rise:

    s   = H (x - sin(2 pi x) / (2 pi))
    s'  = ds/dtheta   = H / beta (1 - cos(2 pi x))
    s'' = d2s/dtheta2 = 2 pi H / beta^2 sin(2 pi x)

(the return is ``H - s`` of the same form). The follower is a translating roller (radius
``RR``) on the line ``x = E`` (offset ``E``), its centre at ``(E, d0 + s)`` with
``d0 = sqrt((RB + RR)^2 - E^2)`` (``RB`` the base-circle radius). The cam turns
counterclockwise by ``theta``, so in cam coordinates the roller centre (the *pitch curve*)
is ``p(theta) = R(-theta) (E, d0 + s)``; its tangent is ``R(-theta) (d0 + s, s' - E)`` and
the cam profile is the pitch curve moved by ``RR`` along the inward normal
``R(-theta) (s' - E, -(d0 + s)) / |.|``.

The profile is sampled at ``n`` cam angles (knots at every transition of the law) and
fitted with ``ms.SplineFit(points, "closed", knots=angles)``: a periodic cubic of the cam
parameter ``a``. The roller rests on it through ``CamToCircle1`` (the profile runs
clockwise in cam coordinates, so its left is the outside: radius ``+RR``). Driving the cam
at one radian per second (time = cam angle), the follower's lift, velocity and
acceleration reproduce the law up to the spline's error, printed against the number of
knots.

The profile's parametrisation by ``theta`` has a second derivative that jumps at the four
transitions (it contains the jerk ``s'''``, which jumps for a cycloidal law): so the spline
error does not fall as ``O(h^4)``, the order of a smooth curve, but as about ``h^3`` for the
lift, ``h^2`` for the velocity and ``h`` for the acceleration (measured; see
docs/cams.md, "Cam synthesis"). The spline misses the profile by ``O(h^2)``, mostly along its
tangent; through the pitch curve (only its third derivative jumps) it would converge as
``h^4``.

Run: ``python examples/cam_synthesis.py [plot.png]``
"""

from __future__ import annotations

import sys
from functools import lru_cache

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

H = 1.0                                  # rise
BETA1, DWELL1, BETA3 = np.radians(120), np.radians(60), np.radians(120)   # then dwell 60 deg
RB, RR, E = 3.0, 0.5, 0.0                # base circle, roller radius, follower offset
D0 = float(np.sqrt((RB + RR) ** 2 - E**2))
A = sp.Symbol("a")                       # the cam parameter


def law(theta) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lift ``s``, ``ds/dtheta`` and ``d2s/dtheta2`` of the cycloidal rise-dwell-return-dwell
    law at cam angles ``theta`` (any, taken modulo 2 pi)."""
    th = np.mod(np.asarray(theta, dtype=float), 2 * np.pi)
    s, v, acc = np.zeros_like(th), np.zeros_like(th), np.zeros_like(th)
    rise = th < BETA1
    x = th[rise] / BETA1
    s[rise] = H * (x - np.sin(2 * np.pi * x) / (2 * np.pi))
    v[rise] = H / BETA1 * (1 - np.cos(2 * np.pi * x))
    acc[rise] = 2 * np.pi * H / BETA1**2 * np.sin(2 * np.pi * x)
    s[(th >= BETA1) & (th < BETA1 + DWELL1)] = H
    ret = (th >= BETA1 + DWELL1) & (th < BETA1 + DWELL1 + BETA3)
    x = (th[ret] - BETA1 - DWELL1) / BETA3
    s[ret] = H * (1 - x + np.sin(2 * np.pi * x) / (2 * np.pi))
    v[ret] = -H / BETA3 * (1 - np.cos(2 * np.pi * x))
    acc[ret] = -2 * np.pi * H / BETA3**2 * np.sin(2 * np.pi * x)
    return s, v, acc


def pressure_angle_exact(theta) -> np.ndarray:
    """``tan(phi) = |s' - E| / (d0 + s)``: the common normal passes through the roller
    centre and is normal to the pitch curve, ``R(-theta) (s' - E, -(d0 + s))`` in cam
    coordinates, i.e. ``(s' - E, -(d0 + s))`` in the fixed frame; the follower moves
    along ``(0, 1)``."""
    s, v, _ = law(theta)
    return np.arctan(np.abs(v - E) / (D0 + s))


def profile_points(theta) -> np.ndarray:
    """Cam profile points (cam coordinates) that the roller touches at cam angles ``theta``."""
    th = np.asarray(theta, dtype=float)
    s, v, _ = law(th)
    c, sn = np.cos(th), np.sin(th)

    def turn_back(x, y):  # R(-theta) (x, y)
        return np.stack([c * x + sn * y, -sn * x + c * y], axis=-1)

    pitch = turn_back(E + 0 * th, D0 + s)
    length = np.hypot(D0 + s, v - E)
    return pitch + RR * turn_back((v - E) / length, -(D0 + s) / length)


def build(knots: int):
    """The cam mechanism with a profile fitted through ``knots`` points (the last repeats the
    first). Returns ``(model, cam, follower, contact constraint, profile point)``."""
    if (knots - 1) % 24:
        raise ValueError("knots - 1 must be a multiple of 24, so every transition is a knot")
    angles = np.linspace(0, 2 * np.pi, knots)
    pts = profile_points(angles)
    pts[-1] = pts[0]                     # exactly closed: a periodic spline
    spline = ms.SplineFit(pts, "closed", knots=angles)
    m = ms.Model2D()
    cam = m.add_body("cam", guess=((0, 0), 0))
    fol = m.add_body("follower", guess=((E, D0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), cam.point(0)), name="bearing")
    m.add(ms.RotationLock1(cam, T), name="drive")        # theta = t
    m.add(ms.Translate2(m.ground.axis((E, 0), (0, 1)), fol.axis((0, 0), (0, 1))), name="guide")
    profile = cam.point(tuple(spline(A)))
    contact = m.add(ms.CamToCircle1(profile, (A, 0.0), fol.point(0), RR), name="cam")
    return m, cam, fol, contact, profile


@lru_cache(maxsize=4)
def sweep(knots: int, points: int = 721):
    """Run one revolution; returns ``(theta, lift, velocity, acceleration, pressure angle,
    solution, parts)`` with ``parts`` what :func:`build` returned. Cached: the compile of a
    spline cam of many knots takes seconds."""
    parts = build(knots)
    m, _, fol, contact, _ = parts
    th = np.linspace(0, 2 * np.pi, points)
    sol = m.solve(th, solution="acceleration")
    lift = sol.location(fol.point(0))[:, 1] - D0
    vel = sol.velocity(fol.point(0))[:, 1]
    acc = sol.acceleration(fol.point(0))[:, 1]
    phi = ms.pressure_angle(sol, contact, direction=(0, 1))
    return th, lift, vel, acc, phi, sol, parts


def errors(knots: int, points: int = 721) -> dict[str, float]:
    """Largest errors over a revolution against the closed form (lift relative to ``H``)."""
    th, lift, vel, acc, phi, _, _ = sweep(knots, points)
    s, v, a = law(th)
    return {"lift": float(np.abs(lift - s).max() / H), "velocity": float(np.abs(vel - v).max()),
            "acceleration": float(np.abs(acc - a).max()),
            "pressure angle": float(np.abs(phi - pressure_angle_exact(th)).max())}


def plot(path: str, knots: int = 49) -> None:
    """Lift, velocity, acceleration and pressure angle vs cam angle to ``path``, and a
    snapshot of the cam (``ms.draw.CamPlot``) and roller at 40 degrees beside it
    (``<path stem>_snapshot.png``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    th, lift, vel, acc, phi, sol, (m, cam, fol, _, profile) = sweep(knots, 361)
    s, v, a = law(th)
    fig, axes = plt.subplots(2, 2, figsize=(10, 7))
    deg = np.degrees(th)
    for ax, got, want, name in zip(axes.flat, (lift, vel, acc, np.degrees(phi)),
                                   (s, v, a, np.degrees(pressure_angle_exact(th))),
                                   ("lift", "ds/dtheta", "d2s/dtheta2", "pressure angle [deg]")):
        ax.plot(deg, want, "k-", lw=3, alpha=0.3, label="law")
        ax.plot(deg, got, "C0-", lw=1, label=f"spline cam, {knots} knots")
        ax.set(xlabel="cam angle [deg]", title=name)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    k = int(np.argmin(np.abs(th - np.radians(40))))
    snap = ms.draw.snapshot(sol, [ms.draw.CamPlot(profile, (A, 0, 2 * sp.pi), samples=361),
                                  ms.draw.Wheel(fol, (0, 0), RR, spokes=0)], index=k)
    stem = path[:-4] if path.lower().endswith(".png") else path
    snap.savefig(stem + "_snapshot.png", dpi=90)
    plt.close(snap)


def main(path: str | None = None, knot_counts=(25, 49)) -> dict[int, dict[str, float]]:
    table = {n: errors(n, 361) for n in knot_counts}
    print(f"cycloidal rise {H} over {np.degrees(BETA1):.0f} deg, dwell {np.degrees(DWELL1):.0f}, "
          f"return over {np.degrees(BETA3):.0f}; Rb = {RB}, roller {RR}, offset {E}")
    print(f"{'knots':>5} {'lift/H':>9} {'ds/dth':>9} {'d2s/dth2':>9} {'pressure':>9}")
    for n, e in table.items():
        print(f"{n:5d} {e['lift']:9.2e} {e['velocity']:9.2e} {e['acceleration']:9.2e} "
              f"{e['pressure angle']:9.2e}")
    if path:
        plot(path, knot_counts[-1])
        print(f"plot written to {path}")
    return table


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
