"""Nonholonomic paths at scale: a tractor towing trailers (``models.trailer_train``), every
blade rolling without side slip, the stepper interpreted and compiled side by side.

Each row: 3 s at rtol 1e-10 (DOP853), 31 outputs; CPU time per evaluation of the
stepper's own code interpreted (``MECHSYS_JIT=0``, once, on the first 0.3 s) and compiled (``1``, the
median of interleaved repetitions after a warm-up run that compiles), the run's time
compiled, whether the interpreted job's numbers are the compiled tier's on that same job bit
for bit ("same numbers"), and the compiled run's distance of the tractor's blade from its closed-form
circle. Up to 150 coordinates the velocity system is dense (the written-out LU); above,
both tiers gather it into its fixed pattern and factorise it by the same compiled sparse
LU, and project through ``[[I, J^T], [J^, 0]]`` (decision 0027).

Run: ``.venv/bin/python benchmarks/paths.py`` prints the table (about a minute);
``--write docs/performance-free.md`` also puts it in that page (its ``paths`` block).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread

import sys  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from _machine import TIERS, per_evaluation, table_main  # noqa: E402  (sibling module)

from mechsys import models  # noqa: E402

TRAILERS = (10, 50, 100, 200)
SPEED, RATE = 2.0, 0.4


def tables(rounds: int = 3) -> str:
    warnings.simplefilter("ignore")
    t = np.linspace(0.0, 3.0, 31)
    R = SPEED / RATE
    circle = np.c_[R * np.sin(RATE * t), R * (1 - np.cos(RATE * t))]
    out = ["Tractor and trailers, 3 s, DOP853 rtol 1e-10:", "",
           "| trailers | coordinates | interpreted / evaluation | compiled / evaluation | ratio | "
           "compiled run | same numbers | blade off its circle |",
           "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for k in TRAILERS:
        path = models.trailer_train(k, speed=SPEED, rate=RATE)
        ep, ec, py, jit, tc, same = per_evaluation(
            lambda path=path: path.simulate(t, rtol=1e-10, atol=1e-12), rounds,
            short=lambda path=path: path.simulate(t[:4], rtol=1e-10, atol=1e-12))
        off = np.abs(jit.location(path.model.body("tractor").point("blade")) - circle).max()
        out.append(f"| {k} | {path.system.n} | {ep * 1e6:.0f} µs | {ec * 1e6:.0f} µs | "
                   f"{ep / ec:.1f} | {tc * 1e3:.1f} ms | "
                   f"{'yes' if same else 'no'} | {off:.1e} |")
    return "\n".join(out)


INTRO = (TIERS + " Above 150 coordinates both solve the velocity system "
         "$\\begin{bmatrix} \\Phi_q \\\\ \\psi_{\\dot q} \\end{bmatrix}$ through "
         "its fixed pattern by the same compiled sparse LU (decision 0027).")


def main(argv=None) -> int:
    return table_main(__doc__, "paths", "Nonholonomic paths (tractor and trailers)", INTRO,
                      tables, argv)


if __name__ == "__main__":
    sys.exit(main())
