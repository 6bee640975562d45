"""One chain row of the peers table, two mechsys trees and the peers, on the same machine.

``run.py``'s "mechsys before" column is copied from an earlier run, possibly on another
machine; this script measures the row again for an older commit and for this tree side by
side, with the peers of the row in the same run, so that a change of the ratio to the best
peer can be told apart from a change of machine.

The case is the N-link chain of ``peer_problems.py`` (uniform rods, released horizontal,
2 s), run as ``peer_sides.py`` runs it: mechsys ``simulate`` with DOP853 at ``rtol``
(``atol = rtol / 100``, projection on), MuJoCo RK4 at ``dt``, Exudyn's KinematicTree RK67 at
``h``. Each entrant runs in its own fresh process (``--worker``): it builds its model (not
timed), runs once untimed (the compiled loops loaded), then ``--reps`` timed runs (CPU time,
``time.process_time``, one BLAS thread); the process reports the median. A round starts one
process per entrant in an order rotated from round to round; the table gives the median over
the rounds of those medians and their spread (lowest and highest round), and, since the shared
machine's speed drifts between rounds, the ratios taken within each round (new / old, mechsys
/ best peer), of the processes' medians and of their fastest runs, with their median. The error of every
entrant is the largest final link-angle error against the reference of ``peer_problems.py``;
the two mechsys trees' final angles are also compared with each other.

Each tree keeps its own Numba cache (beside its sources): compile both first, e.g. by one
``--rounds 0`` run, which only warms (``MECHSYS_COMPILE=wait``: compiled in the process,
never in the background while the Python path is timed).

Run (the old tree checked out with ``git worktree add /tmp/old <commit>``)::

    python benchmarks/peers/ab_chain.py --old /tmp/old/src --new src --n 16 --rounds 7
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread
os.environ.setdefault("MECHSYS_COMPILE", "wait")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
T_CHAIN, G = 2.0, 9.81


def _mechsys(n: int, rtol: float):
    from mechsys import models

    m = models.pendulum_chain(n, G)
    m.solve(0.0)
    free = m.free(drop=[f"lock{k}" for k in range(n)])
    free.solve(0.0)
    box = {}

    def run():
        box["sol"] = free.simulate((0.0, T_CHAIN), method="dop853", rtol=rtol, atol=rtol / 100,
                                   constraint_correction=True)

    def result():
        sol = box["sol"]
        return np.array([sol[f"l{k}.th"][-1] for k in range(n)]), sol.extra.get("evaluations")

    return lambda: None, run, result


def _peer(package: str, n: int, step: float):
    sys.path.insert(0, str(HERE))
    import peer_sides as sides

    if package == "MuJoCo":
        cases, want = sides.mujoco_cases({f"B{n}"}, [n]), f"RK4 dt {step:g}"
    else:
        cases, want = sides.exudyn_cases({f"B{n}"}, [n], full=True), f"KinematicTree RK67 h {step:g}"
    case = next(c for c in cases if c.setting == want)
    return case.reset, case.run, lambda: (case.result()[0], None)


def worker(args) -> None:
    """Build, one untimed run, ``reps`` timed runs; one JSON line on stdout."""
    if args.worker == "mechsys":
        reset, run, result = _mechsys(args.n, args.rtol)
    else:
        reset, run, result = _peer(args.worker, args.n, args.dt if args.worker == "MuJoCo" else args.h)
    reset()
    run()
    times = []
    for _ in range(args.reps):
        reset()
        t0 = time.process_time()
        run()
        times.append(time.process_time() - t0)
    angles, evaluations = result()
    print(json.dumps({"times": times, "angles": angles.tolist(), "evaluations": evaluations}))


def _spawn(entrant: tuple[str, str, str | None], args) -> dict:
    label, kind, src = entrant
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(Path(src).resolve())
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", kind, "--n", str(args.n),
           "--reps", str(args.reps), "--rtol", str(args.rtol), "--dt", str(args.dt), "--h", str(args.h)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise SystemExit(f"{label} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--worker", choices=("mechsys", "MuJoCo", "Exudyn"))
    ap.add_argument("--old", help="the older tree's src directory")
    ap.add_argument("--new", default=str(HERE.parents[1] / "src"), help="this tree's src (default)")
    ap.add_argument("--n", type=int, default=16)
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--dt", type=float, default=2e-3, help="MuJoCo's RK4 step")
    ap.add_argument("--h", type=float, default=5e-3, help="Exudyn's RK67 step")
    ap.add_argument("--reps", type=int, default=7, help="timed runs in each process")
    ap.add_argument("--rounds", type=int, default=7, help="fresh processes per entrant")
    ap.add_argument("--peers", default="MuJoCo,Exudyn", help="comma list; empty for none")
    args = ap.parse_args()
    if args.worker:
        worker(args)
        return
    entrants = [("mechsys new", "mechsys", args.new)]
    if args.old:
        entrants.insert(0, ("mechsys old", "mechsys", args.old))
    entrants += [(p, p, None) for p in args.peers.split(",") if p]

    sys.path.insert(0, str(HERE))
    import peer_problems as P
    from _machine import machine  # (benchmarks/: put on the path by peer_problems)

    ref = P.references(sizes=(args.n,))["B"][str(args.n)]["phi"]
    warm = {}
    for e in entrants:                         # warm-up: compiles what is missing
        if e[1] == "mechsys":
            c0 = time.time()
            warm[e[0]] = _spawn(e, args)
            print(f"warm {e[0]}: {time.time() - c0:.1f} s wall", flush=True)
    meds = {e[0]: [] for e in entrants}
    mins = {e[0]: [] for e in entrants}
    last = dict(warm)
    for k in range(args.rounds):
        order = entrants[k % len(entrants):] + entrants[:k % len(entrants)]
        for e in order:
            got = _spawn(e, args)
            meds[e[0]].append(statistics.median(got["times"]))
            mins[e[0]].append(min(got["times"]))
            last[e[0]] = got
        print(f"round {k + 1}: " + ", ".join(f"{e[0]} {1e3 * meds[e[0]][-1]:.2f} ms" for e in entrants),
              flush=True)
    if not args.rounds:
        return
    print(f"\nN = {args.n}, {args.rounds} rounds x {args.reps} runs; {machine()}")
    best_peer = min((statistics.median(meds[e[0]]) for e in entrants if e[1] != "mechsys"),
                    default=None)
    print("| entrant | setting | CPU median [ms] | rounds' range [ms] | error | evaluations | / best peer |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: |")
    for label, kind, _src in entrants:
        med = statistics.median(meds[label])
        setting = {"mechsys": f"DOP853 rtol {args.rtol:g}", "MuJoCo": f"RK4 dt {args.dt:g}",
                   "Exudyn": f"KinematicTree RK67 h {args.h:g}"}[kind]
        err = P.angle_error(last[label]["angles"], ref)
        ratio = f"{med / best_peer:.2f}" if best_peer and kind == "mechsys" else ""
        ev = last[label]["evaluations"]
        print(f"| {label} | {setting} | {1e3 * med:.2f} | {1e3 * min(meds[label]):.2f}-"
              f"{1e3 * max(meds[label]):.2f} | {err:.1e} | {'' if ev is None else ev} | {ratio} |")
    # the machine's speed drifts from round to round (other jobs): ratios within a round, of
    # the processes' medians and of their fastest runs (the least disturbed by other jobs)
    peers = [e[0] for e in entrants if e[1] != "mechsys"]
    pairs = [(f"{label} / best peer", label, peers) for label, kind, _s in entrants
             if kind == "mechsys" and peers]
    if args.old:
        pairs.append(("new / old", "mechsys new", ["mechsys old"]))
    for name, label, against in pairs:
        for what, data in (("medians", meds), ("fastest runs", mins)):
            r = [data[label][k] / min(data[p][k] for p in against) for k in range(args.rounds)]
            print(f"\n{name}, round by round, of the {what}: median {statistics.median(r):.2f} "
                  f"(range {min(r):.2f}-{max(r):.2f})", end="")
    if args.old:
        a, b = (np.array(last[x]["angles"]) for x in ("mechsys old", "mechsys new"))
        print(f"\nlargest difference of the two trees' final angles: {np.abs(a - b).max():.1e}", end="")
    print()


if __name__ == "__main__":
    main()
