"""Command line: ``mechsys demo`` (also ``python -m mechsys demo``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def demo(out: Path) -> int:
    """Planar slider-crank of Mech's section 1.2 through one crank revolution: a table of the
    piston's position, velocity and acceleration, and a PNG plot of them."""
    from . import models

    out.mkdir(parents=True, exist_ok=True)
    m = models.slider_crank(crank=2.0, rod=6.0, speed=2 * np.pi)
    t = np.linspace(0.0, 1.0, 361)
    sol = m.solve(t)
    piston = m.body("piston").point(0)
    x = sol.location(piston)[:, 0]
    v = sol.velocity(piston)[:, 0]
    a = sol.acceleration(piston)[:, 0]
    print("mechsys demo: planar slider-crank (crank 2, rod 6, 1 rev/s)")
    print(repr(m.dof()))
    print(f"{'t [s]':>8} {'crank [deg]':>12} {'x piston':>12} {'v piston':>12} {'a piston':>12}")
    for k in range(0, len(t), 20):
        print(f"{t[k]:8.3f} {np.degrees(2 * np.pi * t[k]):12.1f} {x[k]:12.5f} {v[k]:12.5f} {a[k]:12.4f}")
    print(f"solved {len(t)} points, {int(sol.iterations.sum())} Newton iterations in all")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    deg = np.degrees(2 * np.pi * t)
    for ax, y, lab in zip(axes, (x, v, a), ("position", "velocity", "acceleration")):
        ax.plot(deg, y)
        ax.set_ylabel(f"piston {lab}")
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("crank angle [deg]")
    fig.suptitle("Slider-crank: piston kinematics over one revolution")
    fig.tight_layout()
    path = out / "slider_crank_kinematics.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"wrote {path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="mechsys", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    d = sub.add_parser("demo", help="run the built-in slider-crank example")
    d.add_argument("--out", default="out", help="folder for the pictures (default: out)")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    if args.command == "demo":
        return demo(Path(args.out))
    return 2  # pragma: no cover
