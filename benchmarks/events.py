"""Free motion through stage changes: the cost of an event, Python and compiled loops.

The latching pendulum of ``examples/latching_pendulum.py`` (a rod released from the
horizontal onto a stop at 60 degrees), rtol 1e-10, atol 1e-12:

* ``project``: it latches at the first impact (one event, 1 s);
* ``restitution 0.5``: it rebounds, each rebound keeping a quarter of the kinetic energy,
  until the approach speed is 1e-6 of the first (21 events in 3 s, most of them in the
  last 0.05 s before it latches).

Each run reports its CPU time (median of interleaved repetitions), its events, steps and
compiled steps, the time per event (the run's time over its events: an upper bound), and
for scale the time of the same model's motion without the stop (both stages of the latch
dropped: the rod swings freely over the same span, in the same loop; its angle still crosses
the switch's test, events of kind "relation" that change no stage). Both loops locate the same events
(times within 1e-9; the tests check it).

Run: ``.venv/bin/python benchmarks/events.py`` prints the table; ``--write
docs/performance-free.md`` also puts it in that page (its ``events`` block).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread

import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))

import latching_pendulum as lp  # noqa: E402
from _machine import table_main  # noqa: E402  (sibling module: run as a script)

clock = time.process_time
TOL = {"rtol": 1e-10, "atol": 1e-12}
CASES = (("project", (0.0, 1.0), "project"), ("restitution 0.5", (0.0, 3.0), ("restitution", 0.5)))


def _systems():
    m = lp.build()
    m.solve(0.0, solution="location")
    # the same motion without events: both stages of the latch dropped (the rod swings freely)
    return m.free(drop=[("latch", 1)]), m.free(drop=[("latch", 1), ("latch", 2)])


def _run(fs, span, policy, mode):
    os.environ["MECHSYS_JIT"] = mode
    try:
        t0 = clock()
        sol = fs.simulate(span, at_switch=policy, **TOL)
        return clock() - t0, sol
    finally:
        os.environ.pop("MECHSYS_JIT", None)


def table(rounds: int = 9) -> str:
    with_events, without = _systems()
    rows = []
    for name, span, policy in CASES:
        for mode, loop in (("0", "Python"), ("1", "compiled")):
            _run(with_events, span, policy, mode)          # compile, warm the caches
            _run(without, span, policy, mode)
            times, base = [], []
            for _ in range(rounds):                        # interleaved
                dt, sol = _run(with_events, span, policy, mode)
                times.append(dt)
                db, free = _run(without, span, policy, mode)
                base.append(db)
            ev, steps = len(sol.extra["events"]), sol.extra["steps"]
            t = statistics.median(times)
            rows.append((name, loop, t, ev, steps, sol.extra["compiled_steps"],
                         statistics.median(base), free.extra["steps"],
                         len(free.extra["events"])))
    lines = ["| run | loop | CPU | events | steps | compiled steps | CPU / event | "
             "without the stop (steps, events) |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for name, loop, t, ev, steps, comp, tb, sb, eb in rows:
        lines.append(f"| {name} | {loop} | {t * 1e3:.1f} ms | {ev} | {steps} | {comp} | "
                     f"{t / ev * 1e3:.2f} ms | {tb * 1e3:.1f} ms ({sb}, {eb}) |")
    return "\n".join(lines)


INTRO = ("The latching pendulum of `examples/latching_pendulum.py` (rtol 1e-10): latching at "
         "the first impact (1 s), and rebounding with restitution 0.5 until it latches (3 s). "
         "CPU time is the median of interleaved repetitions; \"CPU / event\" is the run's time "
         "over its events (an upper bound). For scale, the same rod without the stop (its "
         "angle still crosses the switch's test: events that change no stage).")


def main(argv=None) -> int:
    return table_main(__doc__, "events", "Events of free motion through stage changes", INTRO,
                      table, argv)


if __name__ == "__main__":
    sys.exit(main())
