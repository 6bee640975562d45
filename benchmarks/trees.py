"""Trees of many branches at scale: radial engines (every rod on the crank pin), whose
Jacobian and augmented matrix have bands as wide as the engine, interpreted and compiled loops.

* Free motion: ``models.radial_engine(C, g=9.81)`` with its driver dropped, coasting from
  3 rad/s, 3 s at rtol 1e-8 (DOP853). Above 150 unknowns the loop factorises the
  augmented matrix by the sparse LU of its fixed pattern (``compiled_solver == "sparse"``, decision 0031).
* Inverse dynamics over a sweep: the same engines driven at one revolution a second, 200
  points, position, velocity, acceleration and multipliers at every point.

Each row: CPU time per evaluation (free motion) or per point (sweep) of the loops' own code
interpreted (``MECHSYS_JIT=0``, once, on a tenth of the span or of the points) and compiled
(``1``, the median of interleaved repetitions after a warm-up run that compiles), and whether the
interpreted job's numbers (t, q, qd, qdd, multipliers) are the compiled tier's on that same
job bit for bit ("same numbers").

Run: ``.venv/bin/python benchmarks/trees.py`` prints the tables (about a minute);
``--write docs/performance-free.md`` also puts them in that page (its ``trees`` block).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread

import sys  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from _machine import TIERS, per_evaluation, per_point, table_main  # noqa: E402  (sibling module)

from mechsys import models  # noqa: E402

CYLINDERS = (14, 30, 60, 120)


def _coasting(cylinders):
    m = models.radial_engine(cylinders, g=9.81)
    m.solve(0.0)
    return m.free(drop=["drive"])


def tables(rounds: int = 3) -> str:
    warnings.simplefilter("ignore")
    out = ["Free motion of a coasting radial engine, 3 s, DOP853 rtol 1e-8:", "",
           "| cylinders | unknowns | interpreted / evaluation | compiled / evaluation | ratio | "
           "compiled run | same numbers |",
           "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for c in CYLINDERS:
        free = _coasting(c)
        ep, ec, py, jit, tc, same = per_evaluation(lambda free=free: free.simulate(
            (0.0, 3.0), initial_condition={"crank.th_d": 3.0}, rtol=1e-8), rounds,
            short=lambda free=free: free.simulate(
                (0.0, 0.3), initial_condition={"crank.th_d": 3.0}, rtol=1e-8))
        out.append(f"| {c} | {free.system.n + free.system.m} | {ep * 1e6:.0f} µs | "
                   f"{ec * 1e6:.0f} µs | {ep / ec:.1f} | {tc * 1e3:.0f} ms "
                   f"({jit.extra['compiled_solver']}) | {'yes' if same else 'no'} |")
    out += ["", "Inverse dynamics of the driven engine, one revolution at 200 points (sweep "
            "included):", "",
            "| cylinders | coordinates | interpreted / point | compiled / point | ratio | "
            "same numbers |",
            "| ---: | ---: | ---: | ---: | ---: | ---: |"]
    t = np.linspace(0.0, 1.0, 200)
    for c in CYLINDERS:
        m = models.radial_engine(c, speed=2 * np.pi, g=9.81)
        pp, pc, py, jit, same = per_point(m, t, rounds, short=20)
        out.append(f"| {c} | {py.system.n} | {pp * 1e6:.0f} µs | "
                   f"{pc * 1e6:.0f} µs | {pp / pc:.1f} | {'yes' if same else 'no'} |")
    return "\n".join(out)


INTRO = (TIERS + " Above 150 unknowns both factorise through the fixed pattern's sparse LU in a "
         "minimum-degree ordering, the same compiled function (decision 0031): linear in the "
         "cylinders, where the band LU of a star costs the square of its width.")


def main(argv=None) -> int:
    return table_main(__doc__, "trees", "Trees of many branches (radial engines)", INTRO,
                      tables, argv)


if __name__ == "__main__":
    sys.exit(main())
