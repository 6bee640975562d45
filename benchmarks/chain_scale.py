"""Scale of the model build: the N-link chain up to N = 1024 and a 100-link spatial chain.

For each N (64, 128, 256, 512, 1024) one fresh process with an empty kernel cache
(``MECHSYS_CACHE`` a new temporary directory: every LLVM kernel is compiled) measures, in
CPU time of that process:

* **build**: ``models.pendulum_chain(N)`` and its assembly ``m.solve(0.0)`` (the position,
  velocity and acceleration kernels of the locked chain);
* **free()**: ``m.free(drop=[lock0 ...])`` (the free system, its Jacobian kernel and the
  check that the remaining constraints are independent);
* **dynamics**: ``free.solve(0.0)`` (mass matrix, forces, the free-motion kernel);
* **first run** and **run**: ``free.simulate((0, 2), rtol=1e-6, atol=1e-8)`` four times: the
  first also loads the compiled stepper from Numba's cache (or compiles it when that is
  empty: once per installation, not per model, and not part of the model build), the run
  time is the median of the other three.

Numba's start-up (its import and first call of a cached function, ~0.5 s once per process)
is measured first, on its own, as in the peers benchmark: it is not a cost of the model.

Accuracy of the 2 s run: the largest difference of the final absolute link angles from a
reference. For N <= 256 that is the independent reference of the peers benchmark
(``peers/reference_cache.json``: the minimal-coordinate equations of the chain integrated
by SciPy's DOP853 at 1e-12); above, where that dense N x N reference costs hours, the same
mechsys chain run at ``rtol = 1e-10, atol = 1e-12`` (checked against the independent
reference at N = 256, printed beside).

Then a 100-link spatial chain (``models.spatial_chain(100, zigzag=0.3)``: ball joints, Euler
parameters, 700 coordinates) is built, freed and simulated for 0.5 s: it must run in the
compiled stepper (``sol.extra["compiled_steps"] > 0``); its energy drift and constraint gap
are reported.

Run: ``python benchmarks/chain_scale.py [--write docs/performance.md] [N ...]``. The block
between ``<!-- scale:begin -->`` and ``<!-- scale:end -->`` of the page is replaced.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")   # before NumPy loads: CPU time of one thread

import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
SIZES = (64, 128, 256, 512, 1024)
T_END = 2.0
BEGIN, END = "<!-- scale:begin -->", "<!-- scale:end -->"

# one process per size: what a user's first build of that model costs
CHILD = r"""
import json, sys, time
import numpy as np
from mechsys import models
clock = time.process_time
n, tight = int(sys.argv[1]), sys.argv[2] == "1"
out = {"N": n}
# Numba's start-up (its import, the first call of a cached function), once per process and
# met by the first solve above 150 unknowns: measured on its own, as in the peers benchmark
from mechsys.solvers._linalg import FixedPattern
t = clock()
FixedPattern(np.array([0, 1]), np.array([0]), 1, sparse=True).factor(np.ones(1))
out["numba"] = clock() - t
t = clock(); m = models.pendulum_chain(n); m.solve(0.0); out["build"] = clock() - t
t = clock(); free = m.free(drop=[f"lock{k}" for k in range(n)]); out["free"] = clock() - t
t = clock(); free.solve(0.0); out["dynamics"] = clock() - t
names = [f"l{k}.th" for k in range(n)]
runs = []
for _ in range(4):       # the first also loads the stepper; the run time: median of the rest
    t = clock(); sol = free.simulate((0.0, 2.0), rtol=1e-6, atol=1e-8); runs.append(clock() - t)
out["first_run"], out["run"] = runs[0], float(np.median(runs[1:]))
out["steps"] = sol.extra["steps"]
out["compiled_steps"] = sol.extra.get("compiled_steps", 0)
out["phi"] = [float(sol[k][-1]) for k in names]
if tight:
    t = clock(); ref = free.simulate((0.0, 2.0), rtol=1e-10, atol=1e-12)
    out["tight_cpu"] = clock() - t
    out["tight"] = [float(ref[k][-1]) for k in names]
print(json.dumps(out))
"""

SPATIAL = r"""
import json, time
import numpy as np
from mechsys import models
clock = time.process_time
n = 100
out = {"N": n}
t = clock(); m = models.spatial_chain(n, zigzag=0.3); m.solve(0.0); out["build"] = clock() - t
t = clock(); free = m.free(drop=[f"lock{k}" for k in range(n)]); out["free"] = clock() - t
t = clock(); free.solve(0.0); out["dynamics"] = clock() - t
s = free.system
out["n"], out["m"] = s.n, s.m
for key in ("first_run", "run"):
    t = clock(); sol = free.simulate(np.linspace(0.0, 0.5, 11), rtol=1e-8, atol=1e-10)
    out[key] = clock() - t
out["steps"] = sol.extra["steps"]
out["compiled_steps"] = sol.extra.get("compiled_steps", 0)
out["solver"] = sol.extra.get("compiled_solver")
e = sol.energy() if hasattr(sol, "energy") else None
if e is not None:
    e = np.asarray(e, float)
    out["energy_drift"] = float(np.abs(e - e[0]).max() / max(np.abs(e).max(), 1.0))
out["gap"] = float(max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(sol.t, sol.q)))
print(json.dumps(out))
"""


def _child(code: str, *args: str) -> dict:
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, MECHSYS_CACHE=cache)
        run = subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True,
                             text=True)
    if run.returncode:
        raise RuntimeError(f"the measuring process failed:\n{run.stderr[-3000:]}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def _references() -> dict:
    cache = HERE / "peers" / "reference_cache.json"
    return json.loads(cache.read_text()).get("B", {}) if cache.exists() else {}


def measure(sizes) -> tuple[list[dict], dict]:
    refs = _references()
    rows = []
    for n in sizes:
        independent = refs.get(str(n))
        # the tight mechsys run: the reference above 256, a check of it at 256
        tight = independent is None or n == 256
        r = _child(CHILD, str(n), "1" if tight else "0")
        phi = np.array(r.pop("phi"))
        if independent is not None:
            r["reference"] = "independent (SciPy DOP853 1e-12)"
            r["error"] = float(np.abs(phi - np.array(independent["phi"])).max())
        else:
            r["reference"] = "mechsys rtol 1e-10"
            r["error"] = float(np.abs(phi - np.array(r["tight"])).max())
        if "tight" in r and independent is not None:
            r["tight_vs_independent"] = float(
                np.abs(np.array(r["tight"]) - np.array(independent["phi"])).max())
        r.pop("tight", None)
        r["total"] = r["build"] + r["free"] + r["dynamics"]
        rows.append(r)
        print(f"  N = {n:5d}: build {r['build']:.2f}  free() {r['free']:.2f}  dynamics "
              f"{r['dynamics']:.2f}  total {r['total']:.2f} s;  run {r['run']:.3f} s "
              f"(first {r['first_run']:.2f}), {r['compiled_steps']}/{r['steps']} steps compiled, "
              f"error {r['error']:.1e}", flush=True)
    spatial = _child(SPATIAL)
    print(f"  spatial 100: {spatial}", flush=True)
    return rows, spatial


def _growth(rows, key) -> float:
    a, b = rows[0], rows[-1]
    return float(np.log(b[key] / a[key]) / np.log(b["N"] / a["N"]))


def page(rows, spatial, machine: str) -> str:
    lines = [BEGIN, "## Scale of the build: the chain to N = 1024, a spatial chain of 100",
             "", "Written by `python benchmarks/chain_scale.py --write docs/performance.md` "
             "(see its docstring for the method). Measured on: " + machine + ". CPU time of a "
             "fresh process with an empty kernel cache per row (every LLVM kernel compiled); "
             "the machine is shared with other jobs, so single times spread 10-40 %.", "",
             "| N | build + assembly [s] | free() [s] | dynamics [s] | total [s] | run 2 s [s] "
             "| steps (compiled) | error | reference | Numba start-up [s] |",
             "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: |"]
    for r in rows:
        lines.append(f"| {r['N']} | {r['build']:.2f} | {r['free']:.2f} | {r['dynamics']:.2f} | "
                     f"{r['total']:.2f} | {r['run']:.3f} | {r['steps']} ({r['compiled_steps']}) | "
                     f"{r['error']:.1e} | {r['reference']} | {r['numba']:.2f} |")
    if len(rows) >= 2:
        a, b = rows[0]["N"], rows[-1]["N"]
        lines += ["", f"Growth from N = {a} to {b}: build total N^{_growth(rows, 'total'):.2f}, "
                  f"run N^{_growth(rows, 'run'):.2f} (target ≤ N^1.1). Total at N = {b}: "
                  f"{rows[-1]['total']:.2f} s (target < 5 s)."]
    check = [r for r in rows if "tight_vs_independent" in r]
    if check:
        r = check[0]
        lines += ["", f"The tight mechsys run used as the reference above N = 256 differs from "
                  f"the independent reference by {r['tight_vs_independent']:.1e} at N = {r['N']}."]
    s = spatial
    drift = f", energy drift {s['energy_drift']:.1e}" if "energy_drift" in s else ""
    lines += ["", f"**Spatial chain of {s['N']} links** (ball joints, Euler parameters: {s['n']} "
              f"coordinates, {s['m']} equations): build + assembly {s['build']:.2f} s, free() "
              f"{s['free']:.2f} s, dynamics {s['dynamics']:.2f} s; 0.5 s of motion at rtol 1e-8 "
              f"in {s['run']:.2f} s, {s['compiled_steps']} of {s['steps']} steps in the compiled "
              f"stepper ({s['solver']} solver), constraint gap {s['gap']:.1e}{drift}.", END]
    return "\n".join(lines) + "\n"


def write_block(path: Path, block: str) -> None:
    text = path.read_text() if path.exists() else "# Performance\n"
    if BEGIN in text and END in text:
        pre, rest = text.split(BEGIN, 1)
        text = pre + block.rstrip("\n") + rest.split(END, 1)[1]
    else:
        text = text.rstrip("\n") + "\n\n" + block
    path.write_text(text)


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(HERE))
    from _machine import machine

    target = None
    if "--write" in argv:
        i = argv.index("--write")
        target = Path(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    sizes = tuple(int(a) for a in argv) or SIZES
    rows, spatial = measure(sizes)
    text = page(rows, spatial, machine())
    print(text)
    if target is not None:
        write_block(target, text)
        print(f"written into {target}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
