"""Command line: ``mechsys demo`` (also ``python -m mechsys demo``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def demo(out: Path) -> int:
    """Planar slider-crank of Mech's section 1.2 through one crank revolution: a table of the
    piston's position, velocity and acceleration, a PNG plot of them, a GIF animation of the
    mechanism, and a spatial slider-crank as an interactive HTML viewer."""
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
    written = [path]
    print(f"wrote {path}")

    from . import draw

    rod = m.body("rod")
    scene = draw.Scene(m, [
        draw.LocusPlot(rod.point((3.0, 0.0)), trail=True, color="#6a3d9a"),
        draw.Arrow(piston, m.velocity(piston), scale="auto", anchor="tail"),
    ], default=True)
    gif = scene.animate(sol, out / "slider_crank.gif", rate=0.5, fps=25, dpi=80, title=(
        "Slider-crank at half speed: rod-midpoint path, piston velocity"))
    written.append(gif)
    print(f"wrote {gif} (animation, {_gif_frames(gif)} frames)")

    m3, note = _spatial_model()
    sol3 = m3.solve(np.linspace(0.0, 1.0, 121))
    html = draw.viewer(sol3, out / "slider_crank_3d.html", graphics=_spatial_graphics(m3),
                       default="auto" if note is None else False,
                       title="mechsys: spatial slider-crank")
    written.append(html)
    print(f"wrote {html} (interactive 3D viewer; open it in any browser)")
    if note:
        print(note)
    print("demo outputs: " + ", ".join(str(p) for p in written))
    return 0


def _gif_frames(path: Path) -> int:
    from PIL import Image

    with Image.open(path) as im:
        return int(getattr(im, "n_frames", 1))


def _spatial_model():
    """``models.slider_crank_3d()`` when it exists; else a spatial slider-crank written with
    general ``Constraint`` equations (and a note saying so)."""
    from . import models

    factory = getattr(models, "slider_crank_3d", None)
    if factory is not None:
        return factory(), None
    return _slider_crank_3d_equations(), (
        "note: models.slider_crank_3d() is not available yet; the 3D demo uses a spatial "
        "slider-crank written with general Constraint equations")


def _slider_crank_3d_equations(r: float = 2.0, L: float = 6.0, h: float = 1.5,
                               speed: float = 2 * np.pi):
    """Crank turning about the global z axis; a rod with ball joints at both ends (its
    spin about its own axis fixed by keeping its local y axis horizontal); a piston sliding
    along the line ``y = 0, z = h`` without turning."""
    import sympy as sp

    from . import Constraint, Model3D, T

    m = Model3D()
    xr = float(np.sqrt(L**2 - h**2))
    cr = m.add_body("crank", points={"pin": (r, 0, 0)})
    rd = m.add_body("rod", points={"a": (0, 0, 0), "b": (L, 0, 0)},
                    guess=((r, 0, 0), (-float(np.arctan2(h, xr)), (0, 1, 0))))
    pi = m.add_body("piston", guess=((r + xr, 0, h), (1, 0, 0, 0)))
    th = speed * T
    e0, e1, e2, e3 = cr.q[3:]
    m.add(Constraint([*cr.r, e1, e2, e3 * sp.cos(th / 2) - e0 * sp.sin(th / 2)]), name="drive")
    m.add(Constraint(list(m.location(cr.point("pin")) - m.location(rd.point("a")))),
          name="crank ball")
    m.add(Constraint(list(m.location(rd.point("b")) - m.location(pi.point(0)))),
          name="wrist ball")
    m.add(Constraint([(rd.A * sp.Matrix([0, 1, 0]))[2]]), name="rod spin")
    m.add(Constraint([pi.r[1], pi.r[2] - h, *pi.q[4:]]), name="slider")
    return m


def _spatial_graphics(m):
    """Solid graphics for the equation-built spatial slider-crank (none for a factory
    model: its joints draw it)."""
    from . import draw

    if getattr(__import__("mechsys.models").models, "slider_crank_3d", None) is not None:
        return [draw.LocusPlot(m.body("rod").point((3, 0, 0)))]
    joint = "#333333"
    return [
        draw.Cylinder("ground", (0, 0, -1.6), (0, 0, -0.8), 0.35, color="#8c8c8c"),
        draw.Cylinder("crank", (0, 0, -0.8), (0, 0, 0.15), 0.2),
        draw.Bar("crank", (0, "pin"), width=0.35, thickness=0.2),
        draw.Sphere("crank", "pin", 0.24, color=joint),
        draw.Cylinder("rod", "a", "b", 0.13),
        draw.Sphere("rod", "b", 0.22, color=joint),
        draw.Box("piston", (-0.7, -0.45, -0.45), (0.7, 0.45, 0.45)),
        draw.Cylinder("ground", (3.2, 0, 1.5), (9.5, 0, 1.5), 0.08, color="#8c8c8c"),
        draw.LocusPlot(m.body("rod").point((3, 0, 0))),
        draw.LocalAxes("crank", size=1.0),
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="mechsys", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    d = sub.add_parser("demo", help="run the built-in slider-crank example")
    d.add_argument("--out", default="out", help="folder for the pictures (default: out)")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    if args.command == "demo":
        return demo(Path(args.out))
    return 2  # pragma: no cover
