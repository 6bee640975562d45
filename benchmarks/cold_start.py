"""Cold start: the CPU time from a fresh process with empty caches to the first result of four
first-use tasks (issue 35, item 2; decisions 0039, 0044, 0064), the CPU time of the background
compile it starts, and the same again with the caches that compile filled (a second session).

Each task runs in its own fresh Python process whose Numba cache (``NUMBA_CACHE_DIR``) and
kernel cache (``MECHSYS_CACHE``) point at new empty directories; the time is the process's
CPU time (user + system, ``resource.getrusage``) at the first result, imports included.
With ``MECHSYS_COMPILE`` unset (``background``) the run takes its first tier while one
background process compiles the loops into the cache (the loop's own code interpreted: the
sweep and multipliers, decision 0075, the Runge-Kutta stepper of a small system, decision
0077; else the Python path: Mech's Adams integrator); the script waits for it (its lock
files) and reads the CPU time it recorded (``mechsys-bg-*.json``). Then a second fresh
process runs the task with the caches the first one left. Last, for comparison, a fresh
process with new empty caches and ``MECHSYS_COMPILE=wait`` (compile in the process first:
the behaviour before decision 0064).

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
import time
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


def run_task(key: str, numba_cache: str, mechsys_cache: str, policy: str | None = None) -> dict:
    """One fresh process running ``TASKS[key]`` with ``MECHSYS_COMPILE=policy`` (None: unset,
    the background default): ``{"cpu": s, "compiled": bool}``."""
    code = _PRELUDE + TASKS[key][1] + "\nprint(json.dumps({'cpu': cpu(), 'compiled': bool(compiled)}))\n"
    env = dict(os.environ, NUMBA_CACHE_DIR=numba_cache, MECHSYS_CACHE=mechsys_cache)
    env.pop("MECHSYS_JIT", None)
    env.pop("MECHSYS_COMPILE", None)
    if policy is not None:
        env["MECHSYS_COMPILE"] = policy
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def background_cpu(numba_cache: str, timeout: float = 3600.0) -> float:
    """Wait until the background compiles a session left are over (no ``mechsys-bg-*.lock``
    under ``numba_cache``; they outlive the session), then the CPU seconds of their processes
    (each child's own ``getrusage`` at its last job, imports included, from the
    ``mechsys-bg-*.json`` results it wrote); removes the results (counted once)."""
    root = Path(numba_cache)
    deadline = time.monotonic() + timeout
    while any(root.rglob("mechsys-bg-*.lock")):
        if time.monotonic() > deadline:
            raise RuntimeError(f"background compiles under {root} still running after {timeout} s")
        time.sleep(1.0)
    per_child: dict = {}
    for path in root.rglob("mechsys-bg-*.json"):
        got = json.loads(path.read_text())
        if not got.get("ok"):
            raise RuntimeError(f"background compile failed: {got}")
        per_child[got["pid"]] = max(per_child.get(got["pid"], 0.0), got["process_cpu"])
        path.unlink()
    return sum(per_child.values())


def measure(keys=None) -> list:
    rows = []
    for key in keys or TASKS:
        with tempfile.TemporaryDirectory() as nb, tempfile.TemporaryDirectory() as mc:
            first = run_task(key, nb, mc)
            first["background"] = background_cpu(nb)
            second = run_task(key, nb, mc)
            second["background"] = background_cpu(nb)   # (what it left: the derivative)
        with tempfile.TemporaryDirectory() as nb, tempfile.TemporaryDirectory() as mc:
            wait = run_task(key, nb, mc, "wait")
        rows.append((TASKS[key][0], first, second, wait))
        print(f"{key}: first {first['cpu']:.1f} s (background {first['background']:.1f} s), "
              f"second {second['cpu']:.1f} s (background {second['background']:.1f} s), "
              f"wait {wait['cpu']:.1f} s", file=sys.stderr)
    return rows


def table(rows) -> str:
    lines = ["| first use | first session: CPU s to the first result | its background compile: "
             "CPU s (another process) | second session: CPU s | its background compile: CPU s "
             "| compiled loop ran (first, second) | `MECHSYS_COMPILE=wait`, empty caches: CPU s |",
             "| --- | ---: | ---: | ---: | ---: | --- | ---: |"]
    yes = {True: "yes", False: "no"}
    for name, first, second, wait in rows:
        lines.append(f"| {name} | {first['cpu']:.1f} | {first['background']:.1f} | "
                     f"{second['cpu']:.1f} | {second['background']:.1f} | "
                     f"{yes[first['compiled']]}, {yes[second['compiled']]} | {wait['cpu']:.1f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    return table_main(__doc__, "cold_start", "Cold start: the first result of a new session", (
        "CPU time of a fresh process (imports included) to the first result, with empty Numba "
        "and kernel caches (`NUMBA_CACHE_DIR`, `MECHSYS_CACHE` in new directories) and "
        "`MECHSYS_COMPILE` unset: the compiled loops the run needs are compiled by one "
        "low-priority background process (its CPU time, imports included, in the next column; "
        "it outlives the session and fills the cache) while the run takes its first tier "
        "(decision 0064): the loop's own code interpreted, the same numbers bit for bit (the "
        "sweep and the multipliers: decision 0075; the DOP853 stepper: decision 0077), or, for "
        "Adams, its step's one code interpreted with the Python derivative (decision 0088). "
        "Then a second fresh process with the caches it filled (it compiles "
        "in the background what only it asks for: the free-motion derivative). The last column "
        "is a fresh process with empty caches that compiles in its own process and waits "
        "(`MECHSYS_COMPILE=wait`, the behaviour before decision 0064; decisions 0039 and 0044)."),
        lambda: table(measure()), argv)


if __name__ == "__main__":
    raise SystemExit(main())
