"""The free-motion stepper's interpreted tier at growing size (decision 0082).

Pendulum chains released horizontal, 2 s, DOP853 at 1e-8: CPU ms per step of the Python
path (no stepper planned: what the first session took above 12 unknowns before decision
0082), of the loop interpreted (``MECHSYS_JIT=0``, and the first session while its loop is
compiled in the background) and of the compiled loop, and the CPU time of one interpreted
call at the size (``INTERP_SECONDS`` bounds it). Run::

    PYTHONPATH=src python benchmarks/free_interp_sizes.py [links ...]
"""

from __future__ import annotations

import os
import sys
import time


def run(links: int, how: str, span: float = 2.0) -> dict:
    from mechsys import models
    from mechsys.solvers._jit_free import FreeStepper

    m = models.pendulum_chain(links, 9.81)
    m.solve(0.0)
    free = m.free(drop=[f"lock{k}" for k in range(links)])
    real = FreeStepper.plan, FreeStepper.plan_path
    if how == "python":
        FreeStepper.plan = classmethod(lambda cls, *a, **k: None)
    os.environ["MECHSYS_JIT"] = "0" if how == "interpreted" else "1"
    try:
        free.simulate((0.0, 0.01), rtol=1e-8, atol=1e-8)          # (warm-up: kernels, imports)
        c0 = time.process_time()
        sol = free.simulate((0.0, span), rtol=1e-8, atol=1e-8)
        cpu = time.process_time() - c0
    finally:
        FreeStepper.plan, FreeStepper.plan_path = real
    s = free.system
    steps = sol.extra["steps"]
    return {"links": links, "unknowns": s.n + s.m, "how": how, "steps": steps,
            "solver": sol.extra["compiled_solver"], "cpu": cpu, "ms_step": 1e3 * cpu / steps,
            "interpreted": sol.extra["interpreted_steps"], "compiled": sol.extra["compiled_steps"]}


def main(argv) -> None:
    links = [int(a) for a in argv] or [1, 2, 3, 4, 5, 8]
    print("| links | unknowns | solver | Python path: ms/step | interpreted: ms/step | "
          "compiled: ms/step | interpreted / Python |")
    print("| ---: | ---: | --- | ---: | ---: | ---: | ---: |")
    for k in links:
        r = {how: run(k, how) for how in ("python", "interpreted", "compiled")}
        assert r["interpreted"]["interpreted"] == r["interpreted"]["steps"]
        print(f"| {k} | {r['python']['unknowns']} | {r['interpreted']['solver']} | "
              f"{r['python']['ms_step']:.2f} | {r['interpreted']['ms_step']:.2f} | "
              f"{r['compiled']['ms_step']:.3f} | "
              f"{r['interpreted']['ms_step'] / r['python']['ms_step']:.1f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
