"""mechsys beside MuJoCo and Exudyn on the peer problems, in one process run.

Every entrant (``peer_sides.py``) is built first (not timed); then the runs are interleaved: each
round runs every case once, in an order rotated from round to round, so that a slow spell of
the shared machine hits all packages alike. The time of a case is the median CPU time
(``time.process_time``, one thread) of its rounds: 5 rounds for runs under 0.5 s, 3 under
5 s, 1 above. For each accuracy target the table lists, per package, the cheapest setting
that meets it (error against the independent references of ``peer_problems.py``), and the ratio
of mechsys's time to the best peer's.

Besides the free-motion problems: the slider-crank kinematic sweep against a vectorised
NumPy closed form (D), model build + compile time against the number of links, and Mech's
Adams integrator against the default one on the double pendulum.

Every mechsys case runs once untimed before the rounds (its first run may compile a loop
with Numba, tens of seconds); the peers' cases do not need it (their first runs compile
nothing, and their single-round cases take up to a minute and a half).

Run: ``make bench`` (``python benchmarks/peers/run.py --write docs/performance.md``), which
needs the ``bench`` extra (``pip install -e .[bench]``: mujoco, exudyn). Peers that are not
installed are skipped and said so. ``--quick``: problems A, B4, B16, C and D only, 3 rounds.
``--write PATH`` replaces the block between ``<!-- peers:begin -->`` and
``<!-- peers:end -->`` of that page (``benchmarks/kinematic_sweep.py`` keeps the block when it
rewrites the page). The columns "before" come from the block the page holds when it is
written, or from ``--before PATH`` (e.g. an older commit's page, ``git show
<commit>:docs/performance.md > old.md``), so that a change is read against a chosen run.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread

import argparse  # noqa: E402
import json  # noqa: E402
import re  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import peer_problems as P  # noqa: E402  (sibling modules: run as a script)
import peer_sides as sides  # noqa: E402

clock = time.process_time
BEGIN, END = "<!-- peers:begin -->", "<!-- peers:end -->"
TARGETS = {"A": (1e-4, 1e-6, 1e-8), "B": (1e-6,), "C": (1e-6,)}
C_GAP = 1e-10      # the four-bar's loop-closure target for mechsys (exact constraints)
WARM = {"mechsys"}  # packages whose cases run once untimed before the rounds (Numba)


def build_cases(problems: set[str], sizes, full: bool) -> tuple[list, list[str]]:
    cases, notes = sides.mechsys_cases(problems, sizes), []
    if sides.available("mujoco"):
        cases += sides.mujoco_cases(problems, sizes)
    else:
        notes.append("MuJoCo is not installed (`pip install -e .[bench]`): its columns are empty.")
    if sides.available("exudyn"):
        cases += sides.exudyn_cases(problems, sizes, full)
    else:
        notes.append("Exudyn is not installed (`pip install -e .[bench]`): its columns are empty.")
    return cases, notes


def measure(cases, refs, max_rounds: int) -> list[dict]:
    """Interleaved rounds; a case leaves the rotation once it has its number of rounds."""
    times = {id(c): [] for c in cases}
    want = {}
    for c in cases:
        if c.package in WARM:
            # (untimed: a setting's first run may compile its loop, tens of seconds, which
            # would count as its only round; the peers' first runs compile nothing)
            c.reset()
            c.run()
    for c in cases:                          # first round: also the accuracy
        c.reset()
        t0 = clock()
        c.run()
        dt = clock() - t0
        times[id(c)].append(dt)
        want[id(c)] = 1 if dt > 5 else (min(3, max_rounds) if dt > 0.5 else max_rounds)
        angles, gap = c.result()
        ref = _reference(c.problem, refs)
        c.extra["error"] = P.angle_error(angles, ref)
        c.extra["gap"] = gap
        print(f"  {c.problem:<5} {c.package:<8} {c.setting:<46} {dt:8.4f} s  "
              f"error {c.extra['error']:.1e}" + ("" if gap is None else f"  gap {gap:.1e}"), flush=True)
    for k in range(1, max_rounds):
        todo = [c for c in cases if len(times[id(c)]) < want[id(c)]]
        if not todo:
            break
        shift = k % len(todo)
        for c in todo[shift:] + todo[:shift]:
            c.reset()
            t0 = clock()
            c.run()
            times[id(c)].append(clock() - t0)
    rows = []
    for c in cases:
        rows.append({"problem": c.problem, "package": c.package, "setting": c.setting,
                     "cpu": statistics.median(times[id(c)]), "rounds": len(times[id(c)]),
                     "error": c.extra["error"], "gap": c.extra["gap"], "compile": c.extra.get("compile"),
                     "evaluations": c.extra.get("evaluations")})
    return rows


def _reference(problem, refs):
    if problem.startswith("B"):
        return refs["B"][problem[1:]]["phi"]
    return refs[problem]["phi"]


def cheapest(rows, problem, package, tol, gap=None):
    ok = [r for r in rows if r["problem"] == problem and r["package"] == package and r["error"] <= tol
          and (gap is None or (r["gap"] is not None and r["gap"] <= gap))]
    return min(ok, key=lambda r: r["cpu"]) if ok else None


# ---------------------------------------------------------------------------------------
# problems that only mechsys runs
# ---------------------------------------------------------------------------------------
def sweep_row(rounds: int) -> dict:
    """D: 1000-point slider-crank sweep (positions, velocities, accelerations) vs NumPy.

    Both sides are timed alike, interleaved: each round the mean of a batch of consecutive
    calls (10 sweeps of about 2 ms, 100 closed forms of about 0.2 ms: the same span of
    time), the median over rounds. (Timing one cold sweep against the mean of 100 warm
    closed forms made the ratio depend on what ran just before.)"""
    from mechsys import models

    t = np.linspace(0.0, 1.0, 1000)
    m = models.slider_crank()
    m.compile()
    m.solve(t[:3])                    # compiles the kernels
    ours, theirs = [], []
    for _ in range(rounds):
        t0 = clock()
        for _ in range(10):
            sol = m.solve(t)
        ours.append((clock() - t0) / 10)
        t0 = clock()
        for _ in range(100):
            exact = P.slider_crank_closed_form(t)
        theirs.append((clock() - t0) / 100)
    got = np.stack([sol.coordinate(k, order) for order in (0, 1, 2)
                    for k in ("crank.th", "rod.th", "piston.x")])
    return {"ours": statistics.median(ours), "numpy": statistics.median(theirs),
            "error": float(np.abs(got - exact).max())}


def build_rows(sizes) -> list[dict]:
    """Model build + free() + dynamics compile of the N-link chain, each in a fresh process:
    first with an empty kernel cache (cold), then again with the kernels it left (warm: a
    second run of the same script)."""
    import subprocess
    import tempfile

    # Numba's start-up (its import and the first call of a cached function: ~0.5-0.8 s of
    # CPU, once per process) is measured first and reported on its own: a model above 150
    # unknowns meets it in its first solve (the Jacobian's compiled sparse LU, decision
    # 0031), a smaller one in its first compiled simulation; either way once per process,
    # not a cost of building or compiling the model
    code = ("import sys, json, time; sys.path.insert(0, {bench!r}); import free_motion as F; "
            "import numpy as np; from mechsys.solvers._linalg import FixedPattern; "
            "t = time.process_time(); "
            "FixedPattern(np.array([0, 1]), np.array([0]), 1, sparse=True).factor(np.ones(1)); "
            "up = time.process_time() - t; "
            "_, c = F.compiled(F.chain, {n}); c['numba'] = up; print(json.dumps(c))")
    rows = []
    for n in sizes:
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, MECHSYS_CACHE=cache)
            runs = []
            for _ in range(2):
                out = subprocess.run([sys.executable, "-c", code.format(bench=str(P.HERE.parent), n=n)],
                                     env=env, capture_output=True, text=True, check=True)
                runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
        rows.append({"N": n, **runs[0], "warm": runs[1]["compile"]})
        print(f"  build chain N = {n}: {runs[0]['compile']:.2f} s cold, {runs[1]['compile']:.2f} s warm "
              f"(Numba start-up {runs[0]['numba']:.2f} s)", flush=True)
    return rows


# ---------------------------------------------------------------------------------------
# the page
# ---------------------------------------------------------------------------------------
def _fmt_time(s):
    if s < 0.0095:
        return f"{s * 1e3:.1f} ms"
    return f"{s * 1e3:.0f} ms" if s < 10 else f"{s:.1f} s"


def _cell(r, with_gap=False):
    if r is None:
        return "not reached"
    text = f"{_fmt_time(r['cpu'])} ({r['setting']}; {r['error']:.1e}"
    if with_gap and r["gap"] is not None:
        text += f", gap {r['gap']:.0e}"
    return text + ")"


def _ratio(ours, best):
    if ours is None or best is None:
        return "–"
    return f"{ours['cpu'] / best['cpu']:.2f}"


def _best_peer(rows, problem, tol, packages, gap=None):
    found = [cheapest(rows, problem, p, tol, gap) for p in packages]
    found = [r for r in found if r is not None]
    return min(found, key=lambda r: r["cpu"]) if found else None


def previous(path: Path) -> tuple[str, dict]:
    """The mechsys column of the block the page holds now and its ratio to the best peer:
    ``(its date, {(problem, target): (CPU seconds, ratio)})``, to be shown beside the new
    figures ("before" is whatever was last written, so a change's effect reads off one
    table). The ratio is the load-robust comparison: the rounds interleave the packages, so
    a busier machine slows them alike, while the CPU times themselves move with the load."""
    if not path.exists():
        return "", {}
    text = path.read_text()
    if BEGIN not in text or END not in text:
        return "", {}
    block = text.split(BEGIN, 1)[1].split(END, 1)[0]
    date = re.search(r"Measured on: (\d{4}-\d{2}-\d{2})", block)
    old: dict = {}
    at = None                           # the column of the ratio to the best peer
    for line in block.splitlines():
        if line.startswith("| problem | target |"):
            at = [c.strip() for c in line.strip().strip("|").split("|")].index("mechsys / best peer")
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 4 or cells[0] in ("problem", "---"):
            continue
        got = re.match(r"([\d.]+) (ms|s) ", cells[2] + " ")
        ratio = re.fullmatch(r"[\d.]+", cells[at]) if at is not None and at < len(cells) else None
        if got:
            old[(cells[0], cells[1])] = (float(got.group(1)) * (1e-3 if got.group(2) == "ms" else 1.0),
                                         float(ratio.group(0)) if ratio else None)
    return (date.group(1) if date else ""), old


def page(rows, sweep, builds, sizes, notes, command, machine, before=("", {})) -> str:
    peers = sorted({r["package"] for r in rows} - {"mechsys"})
    when, old = before
    extra = (f" | mechsys before ({when}) | after / before | mechsys / best peer before"
             if old else "")
    head = "| problem | target | mechsys | " + " | ".join(peers) + " | mechsys / best peer" + extra + " |"
    lines = [BEGIN, "## Side by side with the peers", "",
             f"Written by `{command}` (see the script's docstring for the method); rerun it rather "
             "than editing. Measured on: " + machine + ".", "",
             "CPU time of the simulate call only (model build excluded), median of interleaved "
             "rounds; in brackets the cheapest setting of each package that meets the target and "
             "its error (rad, final absolute link angles against the independent reference). "
             "Repetitions on this shared machine spread 5–20 %: treat ratios within 1.3 as equal.",
             ""]
    lines += [f"* {n}" for n in notes]
    lines += ["", head, "|" + " --- |" * (4 + len(peers) + (3 if old else 0))]
    problems = [("A", "double pendulum 10 s")] + [(f"B{n}", f"{n}-link chain 2 s") for n in sizes] + [
        ("C", "four-bar 5 s")]
    present = {r["problem"] for r in rows}
    for key, name in problems:
        if key not in present:
            continue
        for tol in TARGETS[key[0]]:
            gap = C_GAP if key == "C" else None
            ours = cheapest(rows, key, "mechsys", tol, gap)
            theirs = [cheapest(rows, key, p, tol) for p in peers]
            target = f"error ≤ {tol:.0e}" + (f", gap ≤ {C_GAP:.0e} (mechsys)" if gap else "")
            row = (f"| {name} | {target} | {_cell(ours, key == 'C')} | "
                   + " | ".join(_cell(t, key == "C") for t in theirs)
                   + f" | {_ratio(ours, _best_peer(rows, key, tol, peers))} |")
            if old:
                was, was_ratio = old.get((name, target), (None, None))
                row += (" – | – |" if was is None else f" {_fmt_time(was)} | "
                        + ("–" if ours is None else f"{ours['cpu'] / was:.2f}") + " |")
                row += " – |" if was_ratio is None else f" {was_ratio:.2f} |"
            lines.append(row)
    chain = [(n, cheapest(rows, f"B{n}", "mechsys", 1e-6)) for n in sizes]
    chain = [(n, r) for n, r in chain if r is not None]
    if len(chain) >= 2:
        (n0, r0), (n1, r1) = chain[0], chain[-1]
        growth = np.log(r1["cpu"] / r0["cpu"]) / np.log(n1 / n0)
        lines += ["", f"Cost growth of mechsys on the chain from N = {n0} to {n1}: N^{growth:.2f} "
                  "(target ≤ N^1.1)."]
    if sweep:
        lines += ["", "**D. Slider-crank kinematic sweep** (1000 points, positions, velocities and "
                  f"accelerations): mechsys {sweep['ours'] * 1e3:.1f} ms, the vectorised NumPy closed "
                  f"form {sweep['numpy'] * 1e3:.3f} ms: ratio {sweep['ours'] / sweep['numpy']:.1f} "
                  f"(target ≤ 10; each the median over rounds of a batch's mean, interleaved); "
                  f"largest difference {sweep['error']:.1e}."]
    if builds:
        lines += ["", "**Build and compile** (model, `free()`, dynamics kernels) of the N-link chain, "
                  "each in a fresh process: cold (empty kernel cache), then warm (a second run of the "
                  "same script: the kernels come from the on-disk cache; target < 5 s at N = 1024, "
                  "issue 35, and < 1 s at N = 64; `benchmarks/chain_scale.py` has the sizes between "
                  "and the runs). Numba's start-up (its import and first call of a cached "
                  "function) is measured first, on its own: once per process, met by the first "
                  "solve of a model above 150 unknowns (the Jacobian's compiled sparse LU, decision "
                  "0031) or else by the first compiled simulation; add it for the time to the first "
                  "result of a fresh process:",
                  "", "| N | build [s] | free() [s] | dynamics [s] | total cold [s] | total warm [s] "
                  "| Numba start-up [s] |",
                  "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
        lines += [f"| {b['N']} | {b['build']:.2f} | {b['free']:.2f} | {b['dynamics']:.2f} "
                  f"| {b['compile']:.2f} | {b['warm']:.2f} | {b.get('numba', float('nan')):.2f} |"
                  for b in builds]
    adams = cheapest(rows, "A", "mechsys", 1e-8)
    adams_only = [r for r in rows if r["problem"] == "A" and r["package"] == "mechsys"
                  and r["setting"].startswith("Adams") and r["error"] <= 1e-8]
    if adams and adams_only:
        best_adams = min(adams_only, key=lambda r: r["cpu"])
        ea, ed = best_adams["evaluations"], adams["evaluations"]
        evals = "" if not (ea and ed) else (
            f" Evaluations of the equations of motion: {ea:,} against {ed:,} ({ea / ed:.2f} x), "
            f"{best_adams['cpu'] / ea * 1e6:.2f} against {adams['cpu'] / ed * 1e6:.2f} µs each "
            "(the same compiled evaluation; Adams adds its fits, history and output per step, "
            "spread over 1.4 evaluations a step against DOP853's 12): Mech's method (fixed "
            "degree, the step only halved or doubled) needs about three times the default "
            "integrator's evaluations here, so even at equal cost per evaluation the ratio "
            "could not go below that ([decision 0022](decisions/0022-adams-doubling-rule.md)).")
        lines += ["", f"**Mech's Adams integrator**, double pendulum to 1e-8: {_cell(best_adams)}; "
                  f"the cheapest mechsys setting: {_cell(adams)}: ratio "
                  f"{best_adams['cpu'] / adams['cpu']:.1f} (target ≤ 3).{evals}"]
    elif adams:
        tried = [r for r in rows if r["problem"] == "A" and r["setting"].startswith("Adams")]
        if tried:
            closest = min(tried, key=lambda r: r["error"])
            lines += ["", "**Mech's Adams integrator**, double pendulum to 1e-8: not reached by the "
                      f"settings tried; the closest, {_cell(closest)}, against the cheapest mechsys "
                      f"setting {_cell(adams)} (target ≤ 3 times)."]
    lines += ["", "All runs:", "", "| problem | package | setting | CPU | rounds | error | gap |",
              "| --- | --- | --- | ---: | ---: | ---: | ---: |"]
    for r in rows:
        gap = "" if r["gap"] is None else f"{r['gap']:.1e}"
        lines.append(f"| {r['problem']} | {r['package']} | {r['setting']} | {_fmt_time(r['cpu'])} | "
                     f"{r['rounds']} | {r['error']:.1e} | {gap} |")
    lines.append(END)
    return "\n".join(lines) + "\n"


def write_block(path: Path, block: str) -> None:
    text = path.read_text() if path.exists() else "# Performance\n"
    if BEGIN in text and END in text:
        pre, rest = text.split(BEGIN, 1)
        post = rest.split(END, 1)[1]
        text = pre + block.rstrip("\n") + post
    else:
        text = text.rstrip("\n") + "\n\n" + block
    path.write_text(text)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", metavar="PATH", help="write the tables into this page")
    ap.add_argument("--quick", action="store_true", help="A, B4, B16, C, D; 3 rounds")
    ap.add_argument("--fresh-reference", action="store_true", help="recompute the references")
    ap.add_argument("--before", metavar="PATH",
                    help="read the 'before' columns from this page's block (default: --write's)")
    ap.add_argument("--problems", help="comma-separated subset of A,B4,B16,B64,B256,C,D,build")
    args = ap.parse_args(sys.argv[1:] if argv is None else argv)

    from _machine import machine

    sizes = (4, 16) if args.quick else P.CHAIN_SIZES
    wanted = set(args.problems.split(",")) if args.problems else (
        {"A", "C", "D", "build"} | {f"B{n}" for n in sizes})
    sizes = tuple(n for n in sizes if f"B{n}" in wanted) or tuple(
        int(p[1:]) for p in wanted if p.startswith("B"))
    refs = P.references(args.fresh_reference, sizes)
    print("building the models ...", flush=True)
    cases, notes = build_cases(wanted, sizes, full=not args.quick)
    print(f"measuring {len(cases)} cases ...", flush=True)
    rows = measure(cases, refs, max_rounds=3 if args.quick else 5)
    sweep = sweep_row(3 if args.quick else 15) if "D" in wanted else None   # (rounds: cheap, noisy)
    builds = build_rows((4, 16) if args.quick else (4, 16, 64, 256, 1024)) if "build" in wanted else []
    command = "python benchmarks/peers/run.py " + " ".join(sys.argv[1:] if argv is None else argv)
    # ("before": the block of --before, else the one the page holds now)
    source = args.before or args.write
    before = previous(Path(source)) if source else ("", {})
    text = page(rows, sweep, builds, sizes, notes, command.strip(), machine(), before)
    print()
    print(text)
    if args.write:
        write_block(Path(args.write), text)
        print(f"written into {args.write}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
