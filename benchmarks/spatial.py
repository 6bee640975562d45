"""Spatial chains at scale (Euler parameters), interpreted and compiled loops.

``models.spatial_chain(L, zigzag=0.3)``: ``L`` rods joined by ball joints, turned
alternately by +-0.3 rad about the vertical so that the chain falls out of any plane; 1 s
from rest, DOP853 rtol 1e-8. Each rod has 7 coordinates and 4 equations (its ball joint
and its Euler parameters' norm), so ``11 L`` unknowns.

The mass matrix of a rod in Euler parameters is singular (rank 6 of 7). The compiled
loop's block path makes each block regular with the rows on that rod alone and reorders
the rows to keep ``J M^-1 J^T`` banded (``compiled_solver == "block"``, decision 0032), in
time linear in the rods.

Each row: CPU time per evaluation of the loop's own code interpreted (``MECHSYS_JIT=0``,
once, on a tenth of the span) and compiled (``1``, the median of interleaved repetitions
after a warm-up run that compiles), and whether the
interpreted job's numbers (t, q, qd, qdd, multipliers) are the compiled tier's on that same
job bit for bit ("same numbers").

Run: ``.venv/bin/python benchmarks/spatial.py`` prints the table (about a minute);
``--write docs/performance-free.md`` also puts it in that page (its ``spatial`` block).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread

import sys  # noqa: E402
import warnings  # noqa: E402

from _machine import TIERS, per_evaluation, table_main  # noqa: E402  (sibling module)

from mechsys import models  # noqa: E402

LINKS = (6, 12, 24, 48, 96)


def _falling(links):
    m = models.spatial_chain(links, zigzag=0.3)
    m.solve(0.0)
    return m.free(drop=[f"lock{k}" for k in range(links)])


def tables(rounds: int = 3) -> str:
    warnings.simplefilter("ignore")
    out = ["Free fall of a zigzag spatial chain, 1 s, DOP853 rtol 1e-8:", "",
           "| links | unknowns | interpreted / evaluation | compiled / evaluation | ratio | "
           "compiled run | same numbers |",
           "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for links in LINKS:
        free = _falling(links)
        ep, ec, py, jit, tc, same = per_evaluation(
            lambda free=free: free.simulate((0.0, 1.0), rtol=1e-8), rounds,
            short=lambda free=free: free.simulate((0.0, 0.1), rtol=1e-8))
        out.append(f"| {links} | {free.system.n + free.system.m} | {ep * 1e6:.0f} µs | "
                   f"{ec * 1e6:.0f} µs | {ep / ec:.1f} | {tc * 1e3:.0f} ms "
                   f"({jit.extra['compiled_solver']}) | {'yes' if same else 'no'} |")
    return "\n".join(out)


INTRO = (TIERS + " Euler-parameter bodies have singular mass blocks: the compiled block path "
         "makes them regular with each rod's own rows and reorders the rows to a narrow "
         "band (decision 0032).")


def main(argv=None) -> int:
    return table_main(__doc__, "spatial", "Spatial chains (Euler parameters)", INTRO,
                      tables, argv)


if __name__ == "__main__":
    sys.exit(main())
