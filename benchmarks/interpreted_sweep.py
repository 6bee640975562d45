"""The kinematic sweep's three ways to run (decision 0075): the compiled loop, the same loop's
code run by the Python interpreter (``solvers/_jit_interp``: the tier wherever the compiled
one is not loaded, and ``MECHSYS_JIT=0``: decision 0081), and the Python code's per-point
path (since decision 0081 only for sweeps with hooks: a ``pre_solve`` hook that does
nothing makes it take every point), on mechanisms of
9, 21 and 63 unknowns; and the cold start of the 1000-point slider-crank sweep with the
interpreted first tier.

Per size, each way in its own fresh process (``MECHSYS_COMPILE=wait``: the compiled loop is
compiled, or loaded from Numba's cache, before it is timed): the CPU time per point of a
sweep with velocities and accelerations (``time.process_time`` around ``Model.solve``, the
kernels compiled by a short sweep first), and the largest difference of the interpreted
loop's positions, velocities, accelerations and condition estimates from the compiled
loop's (0: the same numbers, bit for bit).

``--opt``: candidate (b) of the decision, the compiled loop built at Numba's lowest
optimisation level (``NUMBA_OPT=0``) in a fresh process with an empty cache: the CPU time
to its first result (its compile) and its cost per point.

``--sparse``: the same three ways on chains of 183 and 273 unknowns (the sparse kind,
above ``SPARSE_THRESHOLD``; interpreted since decision 0081).

``--cold``: ``benchmarks/cold_start.py``'s sweep row (a fresh process with empty caches, the
background compile, a second session).

Run from the repository root::

    PYTHONPATH=src python benchmarks/interpreted_sweep.py [--opt] [--cold] [--sparse]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent

_CHILD = r"""
import json, os, sys, time
import numpy as np
from mechsys import models

way, size, N, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
# interpreted: never compiled (decision 0081); python: a hook keeps the Python code at every
# point (it does nothing)
os.environ["MECHSYS_JIT"] = "0" if way == "interpreted" else "1"
kw = {"pre_solve": lambda t: None} if way == "python" else {}
build = models.slider_crank if size == 0 else (lambda: models.four_bar_chain(size))
m = build()
t = np.linspace(0.0, 1.0, N)
m.solve(t[:5], **kw)                 # the kernels (and the compiled loop) made before timing
c0 = time.process_time()
sol = m.solve(t, **kw)
c1 = time.process_time()
rc = np.asarray(sol.extra["rcond"])  # (the pending estimates: not in the time)
np.savez(out, q=sol.q, qd=sol.qd, qdd=sol.qdd, rc=rc)
print(json.dumps({"n": sol.q.shape[1], "us": (c1 - c0) / N * 1e6,
                  "compiled": int(sol.extra["compiled_points"])}))
"""

#: (label, four_bar_chain loops or 0 for the slider-crank, points)
CASES = [("slider-crank", 0, 1000), ("four-bar chain, 3 loops", 3, 200),
         ("four-bar chain, 10 loops", 10, 200)]
#: ``--sparse``: chains above ``SPARSE_THRESHOLD`` unknowns (the sparse LU's kind)
SPARSE_CASES = [("four-bar chain, 30 loops", 30, 40), ("four-bar chain, 45 loops", 45, 20)]


def _child(way: str, size: int, N: int, out: str, env=None) -> dict:
    env = dict(os.environ if env is None else env, MECHSYS_COMPILE="wait")
    got = subprocess.run([sys.executable, "-c", _CHILD, way, str(size), str(N), out], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(got.stdout.strip().splitlines()[-1])


def ways(cases=CASES) -> str:
    import numpy as np

    lines = ["| mechanism | unknowns | points | compiled loop: µs/point | interpreted loop: "
             "µs/point | Python loop: µs/point | interpreted / Python | largest difference "
             "interpreted - compiled |", "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    with tempfile.TemporaryDirectory() as tmp:
        for label, size, N in cases:
            got, arrays = {}, {}
            for way in ("compiled", "interpreted", "python"):
                path = os.path.join(tmp, f"{way}.npz")
                got[way] = _child(way, size, N, path)
                arrays[way] = dict(np.load(path))
            diff = max(float(np.abs(arrays["interpreted"][k] - arrays["compiled"][k]).max())
                       for k in arrays["compiled"])
            lines.append(f"| {label} | {got['compiled']['n']} | {N} | {got['compiled']['us']:.1f} | "
                         f"{got['interpreted']['us']:.0f} | {got['python']['us']:.0f} | "
                         f"{got['interpreted']['us'] / got['python']['us']:.1f} | {diff:.1e} |")
            print(lines[-1], file=sys.stderr)
    return "\n".join(lines)


_OPT = r"""
import json, time
import numpy as np
from mechsys import models
m = models.slider_crank()
t = np.linspace(0.0, 1.0, 1000)
c0 = time.process_time()
sol = m.solve(t)
c1 = time.process_time()
sol = m.solve(t)
c2 = time.process_time()
print(json.dumps({"first": c1 - c0, "us": (c2 - c1) / 1000 * 1e6,
                  "compiled": int(sol.extra["compiled_points"])}))
"""


def optimisation_levels() -> str:
    lines = ["| `NUMBA_OPT` | first 1000-point sweep, empty cache: CPU s (its compile) | "
             "then: µs/point |", "| --- | ---: | ---: |"]
    for level in ("0", "3"):
        with tempfile.TemporaryDirectory() as nb, tempfile.TemporaryDirectory() as mc:
            env = dict(os.environ, NUMBA_OPT=level, NUMBA_CACHE_DIR=nb, MECHSYS_CACHE=mc,
                       MECHSYS_COMPILE="wait", MECHSYS_JIT="1")
            got = subprocess.run([sys.executable, "-c", _OPT], env=env, capture_output=True,
                                 text=True, check=True)
            r = json.loads(got.stdout.strip().splitlines()[-1])
        lines.append(f"| {level} | {r['first']:.1f} | {r['us']:.1f} |")
        print(lines[-1], file=sys.stderr)
    return "\n".join(lines)


def cold() -> str:
    sys.path.insert(0, str(HERE))
    import cold_start

    return cold_start.table(cold_start.measure(["sweep"]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--opt", action="store_true", help="also NUMBA_OPT=0 against 3")
    ap.add_argument("--cold", action="store_true", help="also the sweep's cold start")
    ap.add_argument("--sparse", action="store_true",
                    help="also the sparse kind (183 and 273 unknowns)")
    args = ap.parse_args(argv)
    print(ways())
    if args.sparse:
        print()
        print(ways(SPARSE_CASES))
    if args.opt:
        print()
        print(optimisation_levels())
    if args.cold:
        print()
        print(cold())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
