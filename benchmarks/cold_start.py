"""Cold start: the CPU time from a fresh process with empty caches to the first result of four
first-use tasks (issue 35, item 2; decision 0039), and the same again with the caches the
first run filled (a second session).

Each task runs in its own fresh Python process whose Numba cache (``NUMBA_CACHE_DIR``) and
kernel cache (``MECHSYS_CACHE``) point at new empty directories; the time is the process's
CPU time (user + system, ``resource.getrusage``) at the first result, imports included.
Then a second fresh process runs the task with the caches the first one left.

* ``sweep``: slider-crank, 1000 points with velocities and accelerations (compiled sweep);
* ``simulate``: double pendulum (two rods, absolute coordinates), 10 s, DOP853 at 1e-8;
* ``inverse dynamics``: slider-crank with masses, 1000 points, ``solution="dynamic"``;
* ``adams``: the double pendulum, 10 s, Mech's Adams integrator (``max_error=1e-6``).

Run from the repository root::

    PYTHONPATH=src python benchmarks/cold_start.py
    PYTHONPATH=src python benchmarks/cold_start.py --write docs/performance.md
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import table_main  # noqa: E402

_PRELUDE = """
import resource, json, time
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
import numpy as np
import mechsys as ms
from mechsys import models
"""

_DOUBLE = """
m = models.pendulum_chain(2)
m.solve(0.0)
free = m.free(drop=["lock0", "lock1"])
"""

TASKS = {
    "sweep": ("slider-crank sweep, 1000 points (acceleration)", """
sol = models.slider_crank().solve(np.linspace(0.0, 1.0, 1000))
compiled = sol.extra["compiled_points"] == 1000
"""),
    "simulate": ("double pendulum `simulate`, 10 s (DOP853, 1e-8)", _DOUBLE + """
sol = free.simulate((0.0, 10.0), rtol=1e-8, atol=1e-8)
compiled = sol.extra["compiled_steps"] == sol.extra["steps"]
"""),
    "inverse": ("slider-crank inverse dynamics, 1000 points", """
sol = models.slider_crank_dynamic().solve(np.linspace(0.0, 1.0, 1000), solution="dynamic")
compiled = sol.extra["compiled_points"] == 1000
"""),
    "adams": ("double pendulum, 10 s, Adams (`max_error=1e-6`)", _DOUBLE + """
sol = free.simulate((0.0, 10.0), method="adams", max_error=1e-6)
compiled = sol.extra["compiled_steps"] == sol.extra["steps"]
"""),
}


def run_task(key: str, numba_cache: str, mechsys_cache: str) -> dict:
    """One fresh process running ``TASKS[key]``: ``{"cpu": s, "compiled": bool}``."""
    code = _PRELUDE + TASKS[key][1] + "\nprint(json.dumps({'cpu': cpu(), 'compiled': bool(compiled)}))\n"
    env = dict(os.environ, NUMBA_CACHE_DIR=numba_cache, MECHSYS_CACHE=mechsys_cache)
    env.pop("MECHSYS_JIT", None)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(keys=None) -> list:
    rows = []
    for key in keys or TASKS:
        with tempfile.TemporaryDirectory() as nb, tempfile.TemporaryDirectory() as mc:
            cold = run_task(key, nb, mc)
            warm = run_task(key, nb, mc)
        rows.append((TASKS[key][0], cold, warm))
        print(f"{key}: cold {cold['cpu']:.1f} s, cached {warm['cpu']:.1f} s", file=sys.stderr)
    return rows


def table(rows) -> str:
    lines = ["| first use | cold: empty caches, CPU s | second session: caches filled, CPU s | "
             "compiled loop ran |", "| --- | ---: | ---: | --- |"]
    for name, cold, warm in rows:
        lines.append(f"| {name} | {cold['cpu']:.1f} | {warm['cpu']:.1f} | "
                     f"{'yes' if cold['compiled'] and warm['compiled'] else 'no'} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    return table_main(__doc__, "cold_start", "Cold start: the first result of a new session", (
        "CPU time of a fresh process (imports included) to the first result, with empty Numba "
        "and kernel caches (`NUMBA_CACHE_DIR`, `MECHSYS_CACHE` in new directories), then of a "
        "second fresh process with the caches the first filled. Most of the cold time is "
        "Numba compiling the compiled loops once, each for the solver kind the run uses; decisions "
        "0039 (measured) and 0044 (compiled per kind; before and after there)."), lambda: table(measure()),
        argv)


if __name__ == "__main__":
    raise SystemExit(main())
