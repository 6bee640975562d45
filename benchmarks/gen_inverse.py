"""Kinematic sweeps and inverse dynamics of arms in generalized coordinates, interpreted and
compiled loops.

``models.driven_gen_arm(L)``: a planar arm of ``L`` links (1 m, 1 kg, 1/12), each a
``GenRevolute2`` slave of the previous one, every joint driven (``q_k = 0.3 sin((k + 1)
t)``), under gravity; 2 s at 400 points.
Short arms (``L <= 8``) get the symbolic dynamics, longer ones the recursive dynamics
(composite bodies, decision 0016). Their kernels are compiled with common-subexpression
elimination; the sweep and multiplier loops read them through the entry points compiled
once more without it (decision 0018, amended in the fourteenth session), and the recursive
dynamics' right-hand sides come from the compiled recursion (``_jit_free_loop.gen_points``).

Each row: CPU time per point of ``solve(t, solution="acceleration")`` (the sweep) and of
``solution="dynamic"`` (sweep and multipliers), the loops' own code interpreted
(``MECHSYS_JIT=0``, once, on the first 40 points; the recursion interpreted too) and
compiled (``1``, the median of interleaved repetitions after a warm-up run that compiles),
and whether the interpreted job's numbers (t, q, qd, qdd, multipliers) are the
compiled tier's on that same job bit for bit ("same numbers").

Run: ``.venv/bin/python benchmarks/gen_inverse.py`` prints the table (about a minute);
``--write docs/performance-free.md`` also puts it in that page (its ``gen_inverse`` block).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread

import sys  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from _machine import TIERS, both_loops, per_point, table_main  # noqa: E402  (sibling module)

from mechsys import models  # noqa: E402

LINKS = (4, 12, 24)
#: the interpreted tier's points (the first of the 400)
SHORT = 40


def tables(rounds: int = 3) -> str:
    warnings.simplefilter("ignore")
    t = np.linspace(0.0, 2.0, 400)
    out = ["Driven arms in generalized coordinates, 400 points:", "",
           "| links | dynamics | sweep, interpreted | sweep, compiled | "
           "inverse dynamics, interpreted | inverse dynamics, compiled | ratio | same numbers |",
           "| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    ts = t[:SHORT]
    for links in LINKS:
        m = models.driven_gen_arm(links)
        kind = "recursive" if getattr(m.compile().dynamics, "recursive", False) else "symbolic"
        sweep = both_loops(lambda m=m: m.solve(t, solution="acceleration"), rounds,
                           short=lambda m=m: m.solve(ts, solution="acceleration"))
        pp, pc, py, jit, same = per_point(m, t, rounds, short=SHORT)
        sp_, sc_ = sweep["0"][0] / len(ts), sweep["1"][0] / len(t)
        out.append(f"| {links} | {kind} | {sp_ * 1e6:.0f} µs | {sc_ * 1e6:.1f} µs | "
                   f"{pp * 1e6:.0f} µs | {pc * 1e6:.1f} µs | {pp / pc:.0f} | "
                   f"{'yes' if same and sweep['same'] else 'no'} |")
    return "\n".join(out)


INTRO = (TIERS + " The compiled sweep reads the CSE kernels through entry points compiled "
         "without CSE; the recursive dynamics' loads come from the compiled recursion "
         "(decision 0018).")


def main(argv=None) -> int:
    return table_main(__doc__, "gen_inverse", "Arms in generalized coordinates: sweeps and "
                      "inverse dynamics", INTRO, tables, argv)


if __name__ == "__main__":
    sys.exit(main())
