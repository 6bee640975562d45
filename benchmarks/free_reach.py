"""The free-motion jobs decision 0084 moved from the Python stepper to the loop: CPU time
and steps of each way, each in its own fresh process (warm Numba and kernel caches).

* the double pendulum with the SymPy backend's kernels (no C entry points; the loop calls
  them through ``ctypes`` callbacks), 10 s, DOP853 at rtol 1e-8: the Python stepper (as
  before the decision: no stepper planned), the loop interpreted (``MECHSYS_JIT=0``), the
  loop compiled;
* the Chaplygin sleigh whose blade touches down at t = 1 (a switched run, the stage after
  with one velocity row), 200 s (2001 outputs), DOP853 at 1e-12: that stage on the Python
  stepper (as before the decision: ``FreeStepper._plan_rows`` answers None), the loop
  interpreted and compiled.

The best of three runs each.

Usage: ``python benchmarks/free_reach.py`` (prints a Markdown table).
"""

from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]

_TASK = r"""
import json, os, sys, time
import numpy as np
case, way = sys.argv[1], sys.argv[2]
if case == "sympy":
    os.environ["MECHSYS_BACKEND"] = "sympy"
from mechsys import models
import mechsys as ms
from mechsys.solvers._jit_free import FreeStepper
if way == "python":
    FreeStepper.plan = classmethod(lambda cls, *a, **k: None)
if way == "python-rows":
    FreeStepper._plan_rows = classmethod(lambda cls, *a, **k: None)
def build():
    if case == "sympy":
        m = models.pendulum_chain(2, 9.81)
        m.solve(0.0)
        f = m.free(drop=["lock0", "lock1"])
        return f, dict(rtol=1e-8, atol=1e-10), np.linspace(0.0, 10.0, 201)
    m = ms.Model2D()
    b = m.add_body("sleigh", points={"P": (-0.5, 0.0)}, guess=((0.0, 0.0), 0.0), mass=1.0,
                   inertia=0.2)
    v = m.velocity(b.point("P"))
    m.add(ms.TimeSwitch(ms.Orthogonal1(v, b.vector((0, 1))), 1.0,
                        ms.Orthogonal1(v, b.vector((0, 1)))), name="edge")
    f = m.free(drop=[("edge", 1)])
    ic = {"sleigh.x_d": 0.5, "sleigh.y_d": 0.8, "sleigh.th_d": 1.0}
    return f, dict(initial_condition=ic, at_switch="project", rtol=1e-12, atol=1e-14), \
        np.linspace(0.0, 200.0, 2001)
f, kw, t = build()
f.simulate(t[:3], **kw)            # (kernels made, loops loaded: not timed)
c0 = time.process_time()
sol = f.simulate(t, **kw)
cpu = time.process_time() - c0
e = sol.extra
print(json.dumps({"cpu": cpu, "steps": int(e["steps"]), "compiled": int(e["compiled_steps"]),
                  "interpreted": int(e["interpreted_steps"]), "q_end": sol.q[-1].tolist()}))
"""


def run(case: str, way: str, jit: str) -> dict:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "MECHSYS_JIT": jit,
           "MECHSYS_COMPILE": "wait", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", _TASK, case, way], env=env, check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    rows = [("sympy", "python", "1", "Python stepper (before)"),
            ("sympy", "loop", "0", "loop, interpreted (MECHSYS_JIT=0)"),
            ("sympy", "loop", "1", "loop, compiled"),
            ("sleigh", "python-rows", "1", "blade stage on the Python stepper (before)"),
            ("sleigh", "loop", "0", "loop, interpreted (MECHSYS_JIT=0)"),
            ("sleigh", "loop", "1", "loop, compiled")]
    print("| case | way | CPU s | steps | compiled | interpreted |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    ends = {}
    for case, way, jit, label in rows:
        best = min((run(case, way, jit) for _ in range(3)), key=lambda r: r["cpu"])
        ends.setdefault(case, []).append(best["q_end"])
        print(f"| {case} | {label} | {best['cpu']:.3f} | {best['steps']} | "
              f"{best['compiled']} | {best['interpreted']} |")
    for case, q in ends.items():
        import numpy as np

        q = np.array(q)
        print(f"{case}: largest difference of the final coordinates from the first way: "
              f"{np.abs(q - q[0]).max():.2e}; interpreted vs compiled: "
              f"{np.abs(q[1] - q[2]).max():.2e}")


if __name__ == "__main__":
    main()
