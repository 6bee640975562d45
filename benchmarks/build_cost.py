"""What a user waits for before the first number: build, ``m.dof()``, the first kinematic,
static and inverse-dynamic solutions, and ``m.free(...)`` plus a first short ``simulate``, on
the N-link pendulum chain (3 N coordinates).

Run: ``.venv/bin/python benchmarks/build_cost.py [--cold] [N ...]`` (default 50 100 200).
Times are CPU time of this process, each step after the previous one on the same model, so
that a step shows only what it adds (what is shared is not paid twice). ``--cold`` compiles
everything (an empty kernel cache in a temporary directory, as on a first run); without it,
kernels cached on disk by earlier runs are loaded instead of compiled. To compare with
another checkout, run the same script with ``PYTHONPATH=<checkout>/src``.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import sys  # noqa: E402
import time  # noqa: E402

from _machine import machine  # noqa: E402  (sibling module: run as a script)

clock = time.process_time


def steps(n: int) -> dict:
    from mechsys import models

    out = {}
    t = clock()
    m = models.pendulum_chain(n)
    out["build"], t = clock() - t, clock()
    m.dof()
    out["dof()"], t = clock() - t, clock()
    m.solve(0.0)
    out["solve (kinematic)"], t = clock() - t, clock()
    m.solve(0.0, solution="static")
    out["solve static"], t = clock() - t, clock()
    m.solve(0.0, solution="dynamic")
    out["solve dynamic"], t = clock() - t, clock()
    free = m.free(drop=[f"lock{k}" for k in range(n)])
    free.simulate((0.0, 0.01))
    out["free + simulate 0.01 s"] = clock() - t
    return out


def main(argv: list[str]) -> None:
    if "--cold" in argv:
        import atexit
        import shutil
        import tempfile

        argv = [a for a in argv if a != "--cold"]
        # before mechsys is imported: its kernels are compiled, none loaded from disk
        os.environ["MECHSYS_CACHE"] = cache = tempfile.mkdtemp(prefix="mechsys-cold-")
        atexit.register(shutil.rmtree, cache, True)
    sizes = [int(a) for a in argv] or [50, 100, 200]
    rows = {n: steps(n) for n in sizes}
    names = list(next(iter(rows.values())))
    print(machine())
    print()
    print("| step [CPU s] | " + " | ".join(f"N = {n} ({3 * n} coords)" for n in sizes) + " |")
    print("| --- |" + " ---: |" * len(sizes))
    for name in names:
        print(f"| {name} | " + " | ".join(f"{rows[n][name]:.2f}" for n in sizes) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
