"""Command line: ``mechsys demo`` (also ``python -m mechsys demo``),
``mechsys run model.json --t 0:1:101 --out results.csv`` (solve a model file over time, write
a table; ``.parquet`` with pyarrow), and ``mechsys cache info`` / ``mechsys cache clear``
(the compiled-kernel cache)."""

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
    print("mechsys demo: planar slider-crank (crank 2 m, rod 6 m, 1 rev/s)")
    print(repr(m.dof()))
    print(f"{'t [s]':>8} {'crank [deg]':>12} {'x [m]':>12} {'v [m/s]':>12} {'a [m/s^2]':>12}")
    for k in range(0, len(t), 20):
        print(f"{t[k]:8.3f} {np.degrees(2 * np.pi * t[k]):12.1f} {x[k]:12.5f} {v[k]:12.5f} {a[k]:12.4f}")
    print(f"solved {len(t)} points, {int(sol.iterations.sum())} Newton iterations in all")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    deg = np.degrees(2 * np.pi * t)
    # the model is in metres and seconds (its loads, below, in kg and N)
    for ax, y, lab in zip(axes, (x, v, a), ("position [m]", "velocity [m/s]",
                                             "acceleration [m/s²]")):
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

    written.append(_loads_demo(out))

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

    # the spatial slider-crank of Mech's section 1.3, its slider line lifted out of the
    # crank's plane; drawn from its joints, with the path of the rod's midpoint
    m3 = models.slider_crank_3d(crank=2.0, rod=6.0, height=1.5)
    sol3 = m3.solve(np.linspace(0.0, 1.0, 121))
    html = draw.viewer(sol3, out / "slider_crank_3d.html", default=True,
                       graphics=[draw.LocusPlot(m3.body("rod").point((3.0, 0.0, 0.0)))],
                       title="mechsys: spatial slider-crank")
    written.append(html)
    print(f"wrote {html} (interactive 3D viewer; open it in any browser)")
    print("demo outputs: " + ", ".join(str(p) for p in written))
    return 0


def _loads_demo(out: Path) -> Path:
    """Inverse dynamics of the slider-crank with masses, gravity and a gas force on the
    piston: the driving torque and the wrist-pin reaction over one revolution."""
    import matplotlib.pyplot as plt
    import sympy as sp

    from . import models
    from ._symbols import T

    # a periodic pressure pulse just after top dead centre
    gas = -400 * sp.exp((sp.cos(2 * sp.pi * T - 0.4) - 1) / 0.05)
    m = models.slider_crank_dynamic(piston_force=gas)
    t = np.linspace(0.0, 1.0, 181)
    sol = m.solve(t, solution="dynamic")
    torque = sol.reaction("drive", "crank")[1]
    pin, _ = sol.reaction("wrist pin", "piston")
    print("inverse dynamics (masses 1.5 / 2 / 3 kg, gravity, gas force on the piston):")
    print(f"{'crank [deg]':>12} {'torque [N m]':>14} {'|wrist pin| [N]':>16}")
    for k in range(0, len(t), 30):
        print(f"{np.degrees(2 * np.pi * t[k]):12.1f} {torque[k]:14.3f} {np.hypot(*pin[k]):16.3f}")
    fig, axes = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    deg = np.degrees(2 * np.pi * t)
    axes[0].plot(deg, torque)
    axes[0].set_ylabel("driving torque [N m]")
    axes[1].plot(deg, pin[:, 0], label="x")
    axes[1].plot(deg, pin[:, 1], label="y")
    axes[1].set_ylabel("wrist pin on piston [N]")
    axes[1].legend()
    axes[1].set_xlabel("crank angle [deg]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.suptitle("Slider-crank: driving torque and a joint reaction")
    fig.tight_layout()
    path = out / "slider_crank_loads.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"wrote {path}")
    return path


def _gif_frames(path: Path) -> int:
    from PIL import Image

    with Image.open(path) as im:
        return int(getattr(im, "n_frames", 1))


def parse_times(spec: str) -> np.ndarray:
    """``"t0:t1:n"`` -> ``n`` equally spaced times from ``t0`` to ``t1``; ``"t"`` -> one time.

    >>> parse_times("0:1:3")
    array([0. , 0.5, 1. ])
    """
    from ._errors import ModelError

    parts = spec.split(":")
    try:
        if len(parts) == 1:
            return np.array([float(parts[0])])
        if len(parts) == 3:
            t0, t1, n = float(parts[0]), float(parts[1]), int(parts[2])
            if n >= 1 and n <= 10_000_000 and np.isfinite(t0) and np.isfinite(t1):
                return np.linspace(t0, t1, n)
    except ValueError:
        pass
    raise ModelError(f"--t {spec!r}: give start:stop:count (e.g. 0:1:101, count >= 1) or one time")


def run(model_file: Path, times: str, out: Path, solution: str = "acceleration",
        progress: bool | None = None) -> int:
    """Load a model file (``mechsys.load``, safe for files from strangers), solve it at the
    times ``t0:t1:n`` and write ``t``, every coordinate and its ``_d``/``_dd`` rates to ``out``
    by :meth:`~mechsys.Solution.save`: CSV (``.csv``, header ``name [unit]`` where the model
    declares its units) or Parquet (``.parquet``, needs pyarrow; units in the field
    metadata). A progress bar (tqdm) on stderr
    counts the solved points (``progress=None``: on a terminal, once the solve has taken 2 s);
    it does not slow the solve (the compiled loop runs in chunks, the bar advanced between
    them). Ctrl-C writes the points solved so far and returns 130."""
    import warnings

    from ._errors import MechError
    from .io import load

    t = parse_times(times)
    suffix = out.suffix.lower()
    if suffix not in (".csv", ".parquet"):
        raise MechError(f"--out {out}: the table is written as .csv or .parquet")
    if suffix == ".parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise MechError("writing .parquet needs pyarrow: pip install pyarrow (or write .csv)") from None
    m = load(model_file)
    with warnings.catch_warnings():
        # (an interruption is reported below, once)
        warnings.filterwarnings("ignore", message="solve: interrupted", category=RuntimeWarning)
        sol = m.solve(t, solution=solution, progress=progress)
    # the library's own table writer (Solution.save): the same columns as to_dataframe,
    # the header "name [unit]" where the model declares units, Parquet with field metadata
    out.parent.mkdir(parents=True, exist_ok=True)
    sol.save(out)
    ncols = 1 + sum(len(sol.names) for a in (sol.q, sol.qd, sol.qdd) if a is not None)
    if sol.extra.get("interrupted"):
        _say(f"interrupted: solved {len(sol.t)} of {len(t)} points of {model_file}; wrote them "
             f"to {out} ({ncols} columns)", sys.stderr)
        return 130
    _say(f"solved {len(t)} points of {model_file}; wrote {out} ({ncols} columns)", sys.stdout)
    return 0


def cache(action: str) -> int:
    """``mechsys cache info``: the kernel cache's directory, entries, size and bounds;
    ``mechsys cache clear``: delete its entries (and its key)."""
    from .compile import _cache

    if action == "clear":
        d, n = _cache.clear()
        if d is None:
            print("the kernel cache is off (MECHSYS_CACHE=off); nothing to clear")
        else:
            print(f"deleted {n} files from the kernel cache {d} (and its key)")
        return 0
    info = _cache.info()
    if not info["enabled"]:
        print("kernel cache: off (MECHSYS_CACHE=off)")
    else:
        print(f"kernel cache: {info['directory']}")
        print(f"entries: {info['entries']}, {info['bytes'] / 1e6:.1f} MB (bound "
              f"{info['max_bytes'] / 1e6:.0f} MB, MECHSYS_CACHE_MAX_MB; entries unused for "
              f"{info['max_age_days']} days are deleted)")
    print(f"Numba's compiled loops: {info['numba_cache_dir']}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="mechsys", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    d = sub.add_parser("demo", help="run the built-in slider-crank example")
    d.add_argument("--out", default="out", help="folder for the pictures (default: out)")
    r = sub.add_parser("run", help="solve a model file over time and write a table")
    r.add_argument("model", help="a model file written by Model.save (JSON)")
    r.add_argument("--t", default="0:1:101", help="times start:stop:count (default 0:1:101)")
    r.add_argument("--out", default="results.csv", help="table to write: .csv or .parquet")
    r.add_argument("--solution", default="acceleration", choices=["location", "velocity", "acceleration"],
                   help="highest order solved (default acceleration)")
    r.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="show a progress bar (default: on a terminal, once the solve takes 2 s)")
    c = sub.add_parser("cache", help="the kernel cache (MECHSYS_CACHE): info or clear")
    c.add_argument("action", choices=["info", "clear"],
                   help="info: where it is and its size; clear: delete every entry")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    if args.command == "demo":
        return demo(Path(args.out))
    try:
        if args.command == "cache":
            return cache(args.action)
        return run(Path(args.model), args.t, Path(args.out), args.solution, args.progress)
    except KeyboardInterrupt:
        _say(f"mechsys {args.command}: interrupted")
        return 1
    except Exception as exc:  # noqa: BLE001 - the command line's contract: one line, exit 1
        from ._errors import MechError

        if isinstance(exc, MechError):
            _say(f"mechsys {args.command}: {exc}")
        elif isinstance(exc, OSError):
            _say(f"mechsys {args.command}: {exc.filename or ''}: {exc.strerror or exc}")
        else:
            # not a MechError: a bug of mechsys, still one line (MECHSYS_DEBUG=1: traceback)
            import os

            if os.environ.get("MECHSYS_DEBUG"):
                raise
            _say(f"mechsys {args.command}: internal error {type(exc).__name__}: {exc} (please "
                 "report it; MECHSYS_DEBUG=1 shows the traceback)")
        return 1


def _say(message: str, stream=None) -> None:
    """One line on stderr, whatever it holds: newlines shown as ``\\n``, characters the
    terminal cannot encode (a lone surrogate of a name) escaped, never an exception."""
    line = message.replace("\r", "\\r").replace("\n", "\\n")
    stream = sys.stderr if stream is None else stream
    enc = getattr(stream, "encoding", None) or "utf-8"
    line = line.encode(enc, "backslashreplace").decode(enc, "replace")
    print(line, file=stream)
