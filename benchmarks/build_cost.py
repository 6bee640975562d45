"""What a user waits for before the first number: build, ``m.dof()``, the first kinematic,
static and inverse-dynamic solutions, and ``m.free(...)`` plus a first short ``simulate``, on
the N-link pendulum chain (3 N coordinates).

Run: ``.venv/bin/python benchmarks/build_cost.py [N ...]`` (default 50 100 200). Times are CPU
time of this process, each step after the previous one on the same model, so that a step
shows only what it adds (what is shared is not paid twice). To compare with another checkout,
run the same script with ``PYTHONPATH=<checkout>/src``.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import sys  # noqa: E402
import time  # noqa: E402

from _machine import machine  # noqa: E402  (sibling module: run as a script)

clock = time.process_time


def chain(n):
    import mechsys as ms

    m = ms.Model2D()
    prev = None
    for k in range(n):
        b = m.add_body(f"l{k}", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0),
                       inertia=1 / 12, guess=((float(k), 0.0), 0.0))
        joint = m.ground.point((0, 0)) if prev is None else prev.point("tip")
        m.add(ms.Revolute2(joint, b.point(0)), name=f"j{k}")
        m.add(ms.RotationLock1(b, 0.0), name=f"lock{k}")
        prev = b
    m.add_load(ms.Gravity((0, -1), 9.81))
    return m


def steps(n: int) -> dict:
    out = {}
    t = clock()
    m = chain(n)
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
