"""Kinematic sweep benchmark: compile time, time per solved point, Newton iterations per point,
and the cost of one evaluation of the compiled equations, for both numeric backends.

Models: the planar slider-crank (``mechsys.models.slider_crank``) over one revolution, and the
chain of four-bar loops ``mechsys.models.four_bar_chain(N)`` (``3 (2N + 1)`` coordinates) for
N = 1, 10, 100; radial engines ``models.radial_engine(N)`` (every rod on the crank pin: a
star, ``3 (2N + 1)`` coordinates) for N = 30, 60, 120 over one revolution; the Geneva drive
(``models.geneva_drive``: a ``StageSwitch`` of five stages) over two crank turns. Each sweep
solves position, velocity and acceleration at every point.
Loads over a sweep: the slider-crank with masses, gravity and a gas force
(``models.slider_crank_dynamic``) solved for its multipliers (statics, kinematic loads,
inverse dynamics) at 1000 points, Python and compiled loops.

Run: ``.venv/bin/python benchmarks/kinematic_sweep.py`` (what ``make bench`` runs) prints the
tables; ``--write docs/performance.md`` also writes them into that page; ``--quick`` uses
fewer points and N = 1, 10 only (a smoke run).

Times are CPU time of this process (``time.process_time``), with BLAS limited to one thread:
on a machine shared with other jobs that is far more repeatable than wall-clock time, and on
an idle machine the two agree for this single-threaded work.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: single-threaded, like the solver
# compile times are measured cold: no kernels from the on-disk cache of an earlier run
os.environ.setdefault("MECHSYS_CACHE", "0")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import timeit  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _machine import machine  # noqa: E402  (sibling module: run as a script)

clock = time.process_time

BACKENDS = ("symengine", "sympy")


def _model(case: str, n_loops: int | None):
    from mechsys import models

    if case == "slider-crank":
        return models.slider_crank()
    if case == "geneva drive":
        return models.geneva_drive()
    if case == "radial engine":
        return models.radial_engine(n_loops)
    return models.four_bar_chain(n_loops)


def _times(case: str, points: int) -> np.ndarray:
    if case == "slider-crank":
        return np.linspace(0.0, 1.0, points)  # one crank revolution
    if case == "geneva drive":
        return np.linspace(0.0, 4 * np.pi, points)  # two engagements, five stages
    if case == "radial engine":
        return np.linspace(0.0, 1.0, points)  # one crank revolution
    return np.linspace(0.0, 2 * np.pi, points)  # one period of the chain's driver


def sweep_case(case: str, n_loops: int | None, points: int, backend: str,
               repeat: int = 3, loop: str = "python") -> dict:
    """Build, compile (symbolic derivation + numeric compile) and sweep one model; the sweep
    time is the best of ``repeat`` runs (the compiled system is reused). ``loop``: the
    Python sweep loop or the compiled one (``MECHSYS_JIT``, solvers/_jit_sweep.py)."""
    os.environ["MECHSYS_BACKEND"] = backend
    os.environ["MECHSYS_JIT"] = "1" if loop == "compiled" else "0"
    try:
        m = _model(case, n_loops)
        t0 = clock()
        system = m.compile()
        # the kernels compile on first use: touch them so that "compile" includes them
        _ = (system.f_position, system.f_velocity, system.f_gamma)
        t1 = clock()
        best = np.inf
        m.solve(_times(case, 3))     # loads the compiled loop once per process (not timed)
        for _ in range(repeat):
            s0 = clock()
            sol = m.solve(_times(case, points))
            best = min(best, clock() - s0)
    finally:
        os.environ.pop("MECHSYS_BACKEND", None)
        os.environ.pop("MECHSYS_JIT", None)
    t2 = t1 + best
    return {
        "case": _name(case, n_loops),
        "backend": system.f_position.backend,
        "loop": loop,
        "n": system.n,
        "m": system.m,
        "nnz": system.nnz,
        "points": points,
        "compile_s": t1 - t0,
        "sweep_s": t2 - t1,
        "per_point_us": (t2 - t1) / points * 1e6,
        "iterations": float(sol.iterations.mean()),
        "evaluations": sol.evaluations / points,
    }


def _name(case: str, n: int | None) -> str:
    if n is None:
        return case
    return f"radial_engine({n})" if case == "radial engine" else f"four_bar_chain({n})"


def loads_case(solution: str, loop: str, points: int, repeat: int = 3) -> dict:
    """The loaded slider-crank solved with ``solution`` at ``points`` points of one revolution
    (best of ``repeat``): the whole ``m.solve`` and, against the kinematic sweep alone, the
    part spent on the multipliers."""
    from mechsys import T, models

    os.environ["MECHSYS_JIT"] = "1" if loop == "compiled" else "0"
    try:
        import sympy as sp

        m = models.slider_crank_dynamic(piston_force=300 * sp.sin(2 * sp.pi * T) + 50)
        t = np.linspace(0.0, 1.0, points)
        best = {}
        for sol in ("acceleration", solution):
            m.solve(t[:3], solution=sol)          # compiles kernels and loads the loops
            b = np.inf
            for _ in range(repeat):
                s0 = clock()
                m.solve(t, solution=sol)
                b = min(b, clock() - s0)
            best[sol] = b
    finally:
        os.environ.pop("MECHSYS_JIT", None)
    return {"solution": solution, "loop": loop, "points": points, "solve_s": best[solution],
            "multipliers_s": best[solution] - best["acceleration"]}


def loads_table(rows: list[dict]) -> str:
    return _markdown(["solution", "loop", "points", "whole solve [ms]", "multipliers [µs / point]"],
                     "llrrr", [(r["solution"], r["loop"], r["points"], f"{r['solve_s'] * 1e3:.1f}",
                                     f"{r['multipliers_s'] / r['points'] * 1e6:.1f}") for r in rows])


def _markdown(head: list[str], align: str, body) -> str:
    """A markdown table: ``align`` one letter a column (``l`` left, ``r`` right)."""
    lines = ["| " + " | ".join(head) + " |",
             "| " + " | ".join("---:" if a == "r" else "---" for a in align) + " |"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in body]
    return "\n".join(lines)


def eval_case(case: str, n_loops: int | None, backend: str) -> dict:
    """One compiled function of Phi, the Jacobian's nonzero values and gamma: its compile
    time and its time per call at a solved state."""
    from mechsys.compile import compile_exprs

    m = _model(case, n_loops)
    system = m.compile()  # default backend: only for the expressions and a solved state
    sol = m.solve(0.3)
    st = sol.state()
    exprs = list(system.phi) + list(system.jac_exprs) + list(system.gamma)
    t0 = clock()
    f = compile_exprs(system.layout.args(), exprs, backend)
    compile_s = clock() - t0
    x = system.pack(st.t, st.q, st.qd)
    f(x)
    timer = timeit.Timer(lambda: f(x), timer=clock)
    number, _ = timer.autorange()
    per_call = min(timer.repeat(repeat=5, number=number)) / number
    return {
        "case": _name(case, n_loops),
        "backend": f.backend,
        "n": system.n,
        "outputs": len(exprs),
        "compile_s": compile_s,
        "call_us": per_call * 1e6,
    }


def _jit_available() -> bool:
    from mechsys.solvers import _jit_runtime

    return _jit_runtime.available()


def _growth(rows: list[dict], key: str, loop: str = "python",
            model: str = "four_bar_chain") -> str:
    """Exponent k of cost ~ n^k between consecutive sizes of one model and loop."""
    chain = [r for r in rows if r["case"].startswith(model) and r.get("loop") == loop]
    out = []
    for a, b in zip(chain, chain[1:], strict=False):
        if a["backend"] != b["backend"]:
            continue
        k = np.log(b[key] / a[key]) / np.log(b["n"] / a["n"])
        out.append(f"n {a['n']} -> {b['n']}: x{b[key] / a[key]:.1f} (~ n^{k:.2f})")
    return "; ".join(out)


def sweep_table(rows: list[dict]) -> str:
    return _markdown(["model", "backend", "loop", "coordinates", "points", "compile [s]",
                      "per point [µs]", "Newton iterations / point", "function calls / point"],
                     "lllrrrrrr", [(r["case"], r["backend"], r["loop"], r["n"], r["points"],
                                    f"{r['compile_s']:.2f}", f"{r['per_point_us']:.0f}",
                                    f"{r['iterations']:.2f}", f"{r['evaluations']:.2f}")
                                   for r in rows])


def eval_table(rows: list[dict]) -> str:
    return _markdown(["model", "coordinates", "outputs", "backend", "compile [s]", "per call [µs]"],
                     "lrrlrr", [(r["case"], r["n"], r["outputs"], r["backend"],
                                 f"{r['compile_s']:.2f}", f"{r['call_us']:.1f}") for r in rows])


PAGE = """\
# Performance

<!-- Written by `python benchmarks/kinematic_sweep.py --write docs/performance.md`; rerun it
rather than editing the tables. -->

Measured on: {machine}. Times are CPU time of the benchmark process (the machine is shared;
see the script's docstring).

Command: `{command}`.

## Kinematic sweeps

Position (damped Newton, continued from a Taylor predictor of the previous point), velocity
and acceleration at every point. "compile" is `m.compile()`: the symbolic derivation of the
Jacobian, `Phi_t` and `gamma` plus compiling the three numeric functions. "per point" is the
whole sweep (best of three runs) divided by the number of points. "function calls" counts
evaluations of the compiled functions. The Geneva drive changes its stage (a `StageSwitch`
of five stages) four times; its points go in runs of one stage between the changes
([decision 0029](decisions/0029-multistage-runs.md)).

{sweeps}

Growth of the time per point with the number of coordinates `n` (chain; the Python loop of
each backend, then the compiled loop):
{growth}.

## Loads over a sweep

The slider-crank with masses, gravity and a gas force on the piston
(`models.slider_crank_dynamic`), one revolution at 1000 points, solved for its multipliers:
`"static"` (`Phi_q^T lambda = Q`), `"dynamic"` (inverse dynamics, `Phi_q^T lambda = Q + Qv -
M qdd`). "multipliers" is the whole solve minus the kinematic sweep alone (`"acceleration"`),
per point. The compiled loop ([decision 0026](decisions/0026-compiled-multiplier-solves.md))
makes the same operations as the Python one (the same numbers to 1e-13).

{loads}

## One evaluation of the equations

One compiled function returning `Phi`, the Jacobian's nonzero values and `gamma`, called at a
solved state: the inner-loop cost that decides the backend
([decision 0002](decisions/0002-numeric-backend.md)). "compile" is only the numeric compile
of that function (no symbolic derivation).

{evals}

## Reading the numbers

* "loop": the sweep's loop in Python, or compiled (Numba calling the compiled equations and
  LAPACK's algorithms directly, [decisions 0013](decisions/0013-compiled-sweep.md) and
  [0019](decisions/0019-sweep-lu-structure-and-guard.md); the same numbers as the Python loop
  to 1e-12 and the same decisions).
  The compiled loop runs by default for sweeps of 1000 points or more (`MECHSYS_JIT`, see the
  [guide](guide.md#compiled-sweeps-and-the-kernel-cache)); above 150 coordinates it
  factorises the Jacobian with the sparse LU the Python loop calls
  ([decisions 0030](decisions/0030-banded-kinematic-sweeps.md) and
  [0031](decisions/0031-sparse-lu-for-trees.md)); the growth exponents below the table are
  given for each loop.
* A sweep needs about one iteration per point: the predictor (the Taylor step
  `q + qd dt + qdd dt^2/2` from the previous point with third- and fourth-derivative terms
  from the last accelerations) lands within the tolerance at fine sampling, and the position
  solve starts with chord steps on the previous point's velocity factorisation
  ([decision 0020](decisions/0020-sweep-chord-steps.md)), so a regular point factorises its
  Jacobian once. Each point then costs four calls of compiled functions (residual and
  Jacobian twice, velocity, gamma).
* For small models the time per point is Python overhead in the solver (assembling,
  factorising and solving with NumPy/SciPy), not equation evaluation, which is a few µs of it;
  the two backends are then equally fast.
* Above 150 coordinates both loops factorise the Jacobian through its sparsity pattern,
  analysed once per model: rows matched to columns, a minimum-degree ordering, then a
  compiled sparse LU (decisions 0030, 0031); the cost per point grows about linearly with
  `n` (exponents above), for chains and for the radial engines' star alike. There the
  evaluation cost shows: SymPy's per-call time grows linearly with the number of outputs,
  SymEngine's LLVM code hardly at all.
* Compiling happens once per model change (`m.compile()` is cached), and changing parameter
  values does not recompile. For large models most of it is the numeric compile of the
  solver's three functions rather than the symbolic derivation.
"""


def with_rest_of_page(page: str, old: str) -> str:
    """This script's part of the page followed by everything the old page holds from the
    peers' block on: that block (``benchmarks/peers/run.py``) and the blocks and notes the
    other benchmarks write below it (bicycle, robots, cold start, scale), which an earlier
    version dropped (it kept the peers' block only). A page without the peers' block keeps
    nothing of the old text: this script's part is then the whole page."""
    begin = "<!-- peers:begin -->"
    if begin not in old:
        return page
    return page + "\n" + begin + old.split(begin, 1)[1]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", metavar="PATH", help="also write the results page (markdown)")
    ap.add_argument("--quick", action="store_true", help="fewer points, N = 1 and 10 only")
    ap.add_argument("--backends", default=",".join(BACKENDS),
                    help="comma-separated backends to measure (default: symengine,sympy)")
    args = ap.parse_args(sys.argv[1:] if argv is None else argv)

    from mechsys.compile import available_backends

    backends = [b for b in args.backends.split(",") if b in available_backends()]
    chain_sizes = (1, 10) if args.quick else (1, 10, 100)
    radial_sizes = () if args.quick else (30, 60, 120)
    sc_points, chain_points = (100, 50) if args.quick else (1000, 200)

    sweeps, evals = [], []
    for backend in backends:
        runs = [("slider-crank", None, sc_points), ("geneva drive", None, sc_points)] + [
            ("chain", k, chain_points) for k in chain_sizes]
        if backend == "symengine":
            runs += [("radial engine", k, chain_points) for k in radial_sizes]
        loops = ["python"]
        if backend == "symengine" and _jit_available():
            loops.append("compiled")
        for (case, n_loops, points), loop in ((c, lp) for c in runs for lp in loops):
            r = sweep_case(case, n_loops, points, backend, loop=loop)
            sweeps.append(r)
            print(f"sweep {r['case']:<20} {r['backend']:<16} {loop:<8} n={r['n']:<4} compile "
                  f"{r['compile_s']:6.2f} s  {r['per_point_us']:7.0f} µs/point  "
                  f"{r['iterations']:.2f} it/point", flush=True)
    for case, n_loops in [("slider-crank", None)] + [("chain", k) for k in chain_sizes]:
        for backend in backends:
            r = eval_case(case, n_loops, backend)
            evals.append(r)
            print(f"eval  {r['case']:<20} {r['backend']:<16} n={r['n']:<4} compile "
                  f"{r['compile_s']:6.2f} s  {r['call_us']:8.1f} µs/call", flush=True)

    loads = []
    for solution in ("static", "dynamic"):
        for loop in ["python"] + (["compiled"] if _jit_available() else []):
            r = loads_case(solution, loop, sc_points)
            loads.append(r)
            print(f"loads {solution:<10} {loop:<8} {r['solve_s'] * 1e3:8.1f} ms  multipliers "
                  f"{r['multipliers_s'] / r['points'] * 1e6:6.1f} µs/point", flush=True)

    growth = "; ".join(
        f"{b}: {_growth([r for r in sweeps if r['backend'].startswith(b)], 'per_point_us')}"
        for b in backends)
    compiled = _growth(sweeps, "per_point_us", "compiled")
    if compiled:
        growth += f"; compiled loop: {compiled}"
    for loop in ("python", "compiled"):
        star = _growth(sweeps, "per_point_us", loop, "radial_engine")
        if star:
            growth += f"; radial engines, {loop} loop: {star}"
    print()
    print(sweep_table(sweeps))
    print()
    print(eval_table(evals))
    print()
    print(loads_table(loads))
    print()
    print("growth of time per point:", growth)
    if args.write:
        cmd = "python benchmarks/kinematic_sweep.py " + " ".join(
            sys.argv[1:] if argv is None else argv)
        page = PAGE.format(machine=machine(), command=cmd.strip(), sweeps=sweep_table(sweeps),
                           evals=eval_table(evals), growth=growth, loads=loads_table(loads))
        out = Path(args.write)
        old = out.read_text(encoding="utf-8") if out.exists() else ""
        out.write_text(with_rest_of_page(page, old), encoding="utf-8")
        print(f"wrote {args.write}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
