"""Machine and library versions printed with every benchmark table (shared by the
benchmark scripts)."""

from __future__ import annotations

import datetime as _dt
import os
import platform
from pathlib import Path

# The benchmarks time the compiled loops: a loop missing from Numba's cache is compiled in the
# process before it runs (not in the background while the warm-up run takes the Python path,
# which would then be timed as "compiled"; decision 0064). cold_start.py sets its own.
os.environ.setdefault("MECHSYS_COMPILE", "wait")


def machine() -> str:
    import numpy
    import scipy
    import sympy

    try:
        import symengine

        se = symengine.__version__
    except ImportError:  # pragma: no cover
        se = "not installed"
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        load = f"load average {os.getloadavg()[0]:.1f} at the start"
    except OSError:  # pragma: no cover
        load = "load average unknown"
    return (f"{_dt.date.today().isoformat()}; {cpu}, {os.cpu_count()} cores "
            f"(shared with other jobs; {load}); {platform.system()} {platform.release()}; "
            f"Python {platform.python_version()}, NumPy {numpy.__version__}, "
            f"SciPy {scipy.__version__}, SymPy {sympy.__version__}, SymEngine {se}")


#: the first sentence of the tables that compare the two tiers (:func:`both_loops`)
TIERS = ("`MECHSYS_JIT=0` (the loops' own code run by the interpreter, decisions 0081-0082: "
         "once, on a shorter job of the same kind) and `1` (compiled: the median of "
         "interleaved repetitions after a warm-up run that compiles) side by side, CPU time "
         "with one BLAS thread; \"same numbers\": the interpreted job's numbers are the "
         "compiled tier's on that job bit for bit.")


def both_loops(run, rounds: int, clock=None, short=None) -> dict:
    """``{mode: (median CPU time, result)}`` of ``run()`` with ``MECHSYS_JIT=0`` (the loops'
    own code run by the Python interpreter: decisions 0081 and 0082) and ``1`` (the compiled
    loops), interleaved, after a warm-up run of the compiled one (it compiles and fills the
    caches). The interpreted tier compiles nothing and costs tens of times more: it is timed
    once, on ``short()`` when given (a shorter job of the same kind, so that large systems
    take seconds, not hours), and ``"same"`` tells whether the compiled tier gives that job's
    numbers bit for bit (:func:`same_numbers`)."""
    import statistics
    import time

    clock = clock or time.process_time
    times = {"0": [], "1": []}
    out = {}
    os.environ["MECHSYS_JIT"] = "1"
    run()
    for k in range(rounds):
        for mode in ("0", "1") if k == 0 else ("1",):
            os.environ["MECHSYS_JIT"] = mode
            job = short if mode == "0" and short is not None else run
            t0 = clock()
            out[mode] = job()
            times[mode].append(clock() - t0)
    os.environ["MECHSYS_JIT"] = "1"
    twin = out["1"] if short is None else short()
    os.environ.pop("MECHSYS_JIT", None)
    got = {mode: (statistics.median(times[mode]), out[mode]) for mode in times}
    got["same"] = same_numbers(out["0"], twin)
    return got


def same_numbers(a, b) -> bool:
    """Whether two solutions hold the same numbers bit for bit (every array attribute of
    the two: ``t``, ``q``, ``qd``, ``qdd``, ``lam`` where present)."""
    import numpy as np

    for name in ("t", "q", "qd", "qdd", "lam"):
        x, y = getattr(a, name, None), getattr(b, name, None)
        if x is None and y is None:
            continue
        if x is None or y is None or not np.array_equal(np.asarray(x), np.asarray(y),
                                                         equal_nan=True):
            return False
    return True


def per_evaluation(run, rounds: int, short=None):
    """``(interpreted CPU s per evaluation, compiled CPU s per evaluation, interpreted result,
    compiled result, compiled run's CPU s, same)`` of a simulation ``run()`` in both tiers
    (:func:`both_loops`; ``short``: the interpreted tier's shorter run); every step of the
    compiled run must have run compiled."""
    got = both_loops(run, rounds, short=short)
    (tp, py), (tc, jit) = got["0"], got["1"]
    assert jit.extra["compiled_steps"] == jit.extra["steps"], "a step ran in Python"
    return tp / py.extra["evaluations"], tc / jit.extra["evaluations"], py, jit, tc, got["same"]


def per_point(model, t, rounds: int, short: int | None = None):
    """``(interpreted CPU s per point, compiled CPU s per point, interpreted result, compiled
    result, same)`` of the inverse dynamics ``model.solve(t, solution="dynamic")`` in both
    tiers (the interpreted one on the first ``short`` points when given)."""
    ts = t if short is None else t[:short]
    got = both_loops(lambda: model.solve(t, solution="dynamic"), rounds,
                     short=None if short is None else (lambda: model.solve(ts, solution="dynamic")))
    (tp, py), (tc, jit) = got["0"], got["1"]
    return tp / len(ts), tc / len(t), py, jit, got["same"]


def relative_difference(a, b) -> float:
    """``max |a - b| / max(1, max |b|)``: two loops' results against each other."""
    import numpy as np

    return float(np.abs(a - b).max() / max(1.0, np.abs(b).max()))


def write_block(path: Path, begin: str, end: str, text: str) -> None:
    """Put ``text`` (which starts with ``begin`` and ends with ``end``) into the page at
    ``path`` in place of the block between those markers, or at its end when the page has
    none (the pages' other blocks and the rest are kept)."""
    old = path.read_text() if path.exists() else ""
    if begin in old and end in old:
        head, rest = old.split(begin, 1)
        new = head + text + rest.split(end, 1)[1]
    else:
        new = old.rstrip("\n") + "\n\n" + text + "\n"
    path.write_text(new)


def table_main(doc: str, name: str, title: str, intro: str, make, argv=None) -> int:
    """The ``main`` of a benchmark script that prints Markdown tables (``make()``) and, with
    ``--write PATH``, puts them into that page as its block ``name`` (a ``## title``
    heading, the machine, ``intro``, the tables; :func:`write_block`)."""
    import argparse

    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--write", metavar="PATH", help="also put the tables into this page")
    args = ap.parse_args(argv)
    text = make()
    print(text)
    if args.write:
        begin = f"<!-- {name}: begin (written by benchmarks/{name}.py --write; rerun it) -->"
        end = f"<!-- {name}: end -->"
        block = "\n".join([begin, "", f"## {title}", "", f"Measured on: {machine()}.", "",
                           intro + f" Command: `python benchmarks/{name}.py --write "
                           f"{args.write}`.", "", text, "", end])
        write_block(Path(args.write), begin, end, block)
        print(f"wrote {args.write}")
    return 0
