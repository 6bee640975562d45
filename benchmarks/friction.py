"""Friction at scale: loads that depend on the multipliers, interpreted and compiled loops.

* Free motion: a chain of N uniform rods (``models.pendulum_chain``) with Coulomb friction
  in every joint (``JointFriction``, mu 0.1, radius 0.01, 1e-3 rad/s regularisation),
  released horizontal, 0.1 s at rtol 1e-6. Each evaluation is a Newton on ``(qdd,
  lambda)``; above 150 unknowns the compiled loop goes through the Newton matrix's banded
  pattern (decision 0028).
* Free motion of a tree: a radial engine (``models.radial_engine(C, g=9.81)``, every rod
  on the crank pin) coasting from 3 rad/s with Coulomb friction in every rod's crank-pin
  bearing (mu 0.1, radius 0.05), 1 s at rtol 1e-8. Its Newton matrix is not banded: both
  tiers factorise it by the loop's sparse LU of its fixed pattern.
* Inverse dynamics of trees: the radial engine driven at one revolution a second with the
  same bearings' friction (mu 0.2), 40 points; the multipliers' Newton matrix by the
  compiled sparse LU in both loops.
* Inverse dynamics: the four-bar chain of ``models.four_bar_chain(L)`` (``3 (2 L + 1)``
  coordinates) with unit masses, gravity and friction in its ``L + 1`` ground pivots, 40
  points; the multipliers' Newton at every point (decision 0030).

Each row: CPU time per evaluation (free motion) or per point (sweep and multipliers) of
the loops' own code interpreted (``MECHSYS_JIT=0``, once, on a fifth or a tenth of the span
or the first 8 points) and compiled (``1``, the median of interleaved repetitions after a
warm-up run that compiles), and whether the interpreted job's numbers (t, q, qd, qdd, multipliers) are the
compiled tier's on that same job bit for bit ("same numbers").

Run: ``.venv/bin/python benchmarks/friction.py`` prints the tables (about a minute);
``--write docs/performance-free.md`` also puts them in that page (its ``friction`` block).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread

import sys  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from _machine import TIERS, per_evaluation, per_point, table_main  # noqa: E402  (sibling module)

import mechsys as ms  # noqa: E402
from mechsys import models  # noqa: E402

LINKS = (8, 32, 64, 128)
LOOPS = (10, 30, 60)
CYLINDERS = (14, 30, 60)


def _chain(links):
    m = models.pendulum_chain(links)
    for k in range(links):
        m.add_load(ms.JointFriction(f"j{k}", mu=0.1, radius=0.01, v_eps=1e-3))
    m.solve(0.0)
    return m.free(drop=[f"lock{k}" for k in range(links)])


def _loops(loops):
    m = models.four_bar_chain(loops)
    for b in m.bodies:
        if not b.is_ground:
            m.set_mass_properties(b.name, mass=1.0, centroid=(0.5, 0), inertia=0.1)
    m.add_load(ms.Gravity((0, -1), 9.81))
    for k in range(loops + 1):
        m.add_load(ms.JointFriction(f"pivot{k}", mu=0.2, radius=0.05, v_eps=1e-3))
    return m


def _engine(cylinders):
    m = models.radial_engine(cylinders, g=9.81)
    for k in range(cylinders):
        m.add_load(ms.JointFriction(f"pin{k}", mu=0.1, radius=0.05, v_eps=1e-3))
    m.solve(0.0)
    return m.free(drop=["drive"])


def tables(rounds: int = 3) -> str:
    warnings.simplefilter("ignore")
    out = ["Free motion of a chain with friction in every joint, 0.1 s, rtol 1e-6:", "",
           "| links | unknowns | interpreted / evaluation | compiled / evaluation | ratio | "
           "same numbers |",
           "| ---: | ---: | ---: | ---: | ---: | ---: |"]
    for links in LINKS:
        free = _chain(links)
        ep, ec, py, jit, _, same = per_evaluation(
            lambda free=free: free.simulate((0.0, 0.1), rtol=1e-6, atol=1e-8), rounds,
            short=lambda free=free: free.simulate((0.0, 0.02), rtol=1e-6, atol=1e-8))
        out.append(f"| {links} | {free.system.n + free.system.m} | {ep * 1e6:.0f} µs | "
                   f"{ec * 1e6:.0f} µs | {ep / ec:.1f} | {'yes' if same else 'no'} |")
    out += ["", "Free motion of a radial engine with friction in every crank-pin bearing, 1 s, "
            "rtol 1e-8:", "",
            "| cylinders | unknowns | interpreted / evaluation | compiled / evaluation | ratio | "
            "same numbers |",
            "| ---: | ---: | ---: | ---: | ---: | ---: |"]
    for c in CYLINDERS:
        free = _engine(c)
        ep, ec, py, jit, _, same = per_evaluation(lambda free=free: free.simulate(
            (0.0, 1.0), initial_condition={"crank.th_d": 3.0}, rtol=1e-8), rounds,
            short=lambda free=free: free.simulate(
                (0.0, 0.1), initial_condition={"crank.th_d": 3.0}, rtol=1e-8))
        out.append(f"| {c} | {free.system.n + free.system.m} | {ep * 1e6:.0f} µs | "
                   f"{ec * 1e6:.0f} µs | {ep / ec:.1f} | {'yes' if same else 'no'} |")
    out += ["", "Inverse dynamics of the four-bar chain with friction in its ground pivots, "
            "40 points (sweep included):", "",
            "| loops | coordinates | interpreted / point | compiled / point | ratio | "
            "same numbers |",
            "| ---: | ---: | ---: | ---: | ---: | ---: |"]
    t = np.linspace(0.1, 1.0, 40)
    for loops in LOOPS:
        m = _loops(loops)
        pp, pc, py, jit, same = per_point(m, t, rounds, short=8)
        out.append(f"| {loops} | {py.system.n} | {pp * 1e3:.2f} ms | "
                   f"{pc * 1e3:.2f} ms | {pp / pc:.0f} | {'yes' if same else 'no'} |")
    out += ["", "Inverse dynamics of the radial engine driven at one revolution a second, "
            "friction in every crank-pin bearing (a star: the sparse LU), 40 points (sweep "
            "included):", "",
            "| cylinders | coordinates | interpreted / point | compiled / point | ratio | "
            "same numbers |",
            "| ---: | ---: | ---: | ---: | ---: | ---: |"]
    for c in CYLINDERS[1:]:
        m = models.radial_engine(c, speed=2 * np.pi, g=9.81)
        for k in range(c):
            m.add_load(ms.JointFriction(f"pin{k}", mu=0.2, radius=0.05, v_eps=1e-3))
        pp, pc, py, jit, same = per_point(m, t, rounds, short=8)
        out.append(f"| {c} | {py.system.n} | {pp * 1e3:.2f} ms | "
                   f"{pc * 1e3:.2f} ms | {pp / pc:.0f} | {'yes' if same else 'no'} |")
    return "\n".join(out)


INTRO = (TIERS + " Above 150 unknowns both go through the Newton matrix's fixed pattern: banded "
         "for chains, the compiled sparse LU for trees (decisions 0028 and 0030).")


def main(argv=None) -> int:
    return table_main(__doc__, "friction", "Friction at scale (loads that depend on the "
                      "multipliers)", INTRO, tables, argv)


if __name__ == "__main__":
    sys.exit(main())
