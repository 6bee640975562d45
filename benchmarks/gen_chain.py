"""N-link pendulum chain in generalized coordinates (GenRevolute2 joints: n = N coordinates,
no equations) against the same chain in absolute coordinates (3N coordinates, 2N pin
equations): compile time, free-motion CPU per step and per evaluation, and agreement. The
Gen chain runs with the recursive dynamics (decision 0016) and, up to ``--symbolic-max``
links, with the symbolic projection (decision 0010) too; a run at the peers' accuracy
target is set beside their numbers (cited from ``docs/performance.md``, not rerun).

Run from the repository root::

    PYTHONPATH=src python benchmarks/gen_chain.py            # N = 4, 16, 64, 256
    PYTHONPATH=src python benchmarks/gen_chain.py --sizes 4 16 --write docs/performance-free.md

``--write`` replaces (or appends) the section between the ``gen_chain`` markers of that
page and leaves the rest of it alone.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import machine, write_block  # noqa: E402

G = 9.81
T_END = 2.0
SETTING = {"method": "dop853", "rtol": 1e-8, "atol": 1e-10}
BEGIN = "<!-- gen_chain: begin (written by benchmarks/gen_chain.py --write; rerun it) -->"
END = "<!-- gen_chain: end -->"


def gen_chain(n_links: int):
    """The chain of ``mechsys.models.pendulum_chain`` (uniform rods of 1 m, 1 kg, 1/12, all
    horizontal along +X at the start), each link a GenRevolute2 slave of the previous one:
    coordinates ``q0 ... q{N-1}`` are the relative joint angles."""
    import mechsys as ms

    m = ms.Model2D()
    master = m.ground.axis((0, 0))
    for k in range(n_links):
        b = m.add_body(f"l{k}", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0), inertia=1 / 12)
        m.add(ms.GenRevolute2(b.axis(0), master, (f"q{k}", 0.0)), name=f"j{k}")
        master = b.axis("tip")
    m.add_load(ms.Gravity((0, -1), G))
    return m, []


def abs_chain(n_links: int):
    from mechsys import models

    m = models.pendulum_chain(n_links, G)
    m.solve(0.0)
    return m, [f"lock{k}" for k in range(n_links)]


#: the peers' block of docs/performance.md (2026-11-23), N-link chain 2 s, error <= 1e-6:
#: CPU [ms] of the cheapest setting that meets it (mechsys = absolute coordinates)
PEERS = {4: {"mechsys": 3, "Exudyn": 3, "MuJoCo": 8},
         16: {"mechsys": 16, "Exudyn": 39, "MuJoCo": 18},
         64: {"mechsys": 65, "Exudyn": 831, "MuJoCo": 116},
         256: {"mechsys": 342, "Exudyn": 44800, "MuJoCo": 3819}}
#: the mechsys setting of the peers' comparison (benchmarks/peers/peer_sides.py)
PEER_SETTING = {"method": "dop853", "rtol": 1e-6, "atol": 1e-8}


def _mode(key):
    os.environ["MECHSYS_GEN_DYNAMICS"] = {"gen": "recursive", "sym": "symbolic"}.get(key, "auto")


def build(builder, n_links):
    c0 = time.process_time()
    m, drop = builder(n_links)
    free = m.free(drop=drop)
    c1 = time.process_time()
    free.solve(0.0)  # derives and compiles the mass matrix, forces and the free kernel
    c2 = time.process_time()
    s = free.system
    return m, free, {"build": c1 - c0, "dynamics": c2 - c1, "n": s.n, "m": s.m}


def timed(free, repeat=3):
    best, sol = np.inf, None
    for _ in range(repeat):
        c0 = time.process_time()
        sol = free.simulate((0.0, T_END), **SETTING)
        dt = time.process_time() - c0
        best = min(best, dt)
        if dt > 2.0:
            break
    return best, sol


def _stepper(sol):
    """How the steps ran: the compiled loop's solve (``sol.extra["compiled_solver"]``) when
    it took every step, else "Python" (with the compiled share)."""
    x = sol.extra
    if x.get("compiled_steps", 0) == x["steps"] and x.get("compiled_solver"):
        return f"compiled, {x['compiled_solver']}"
    if x.get("compiled_steps", 0):
        return f"compiled {x['compiled_steps']}/{x['steps']}"
    return "Python"


def tip(m, sol, n_links):
    return np.asarray(sol.location(m.body(f"l{n_links - 1}").point("tip")))[-1]


def measure(n_links: int, symbolic_max: int) -> dict:
    row = {"N": n_links}
    keys = (("gen", gen_chain), ("sym", gen_chain), ("abs", abs_chain))
    for key, builder in keys:
        if key == "sym" and n_links > symbolic_max:
            continue
        _mode(key)
        m, free, comp = build(builder, n_links)
        cpu, sol = timed(free)
        ev, st = sol.extra["evaluations"], sol.extra["steps"]
        row[key] = {**comp, "cpu": cpu, "steps": st, "evals": ev,
                    "stepper": _stepper(sol),
                    "per_step_ms": cpu / st * 1e3, "per_eval_us": cpu / ev * 1e6,
                    "tip": tip(m, sol, n_links)}
        print(f"  N={n_links:<4} {key}: n {comp['n']:4d} m {comp['m']:4d}  build {comp['build']:6.2f} s "
              f"dynamics {comp['dynamics']:6.2f} s  cpu {cpu:7.3f} s  steps {st:4d}  "
              f"{row[key]['per_step_ms']:7.2f} ms/step  {row[key]['per_eval_us']:7.0f} us/eval",
              flush=True)
        if key == "gen":
            row["peer"] = peer_run(free, n_links)
    for key in ("gen", "sym"):
        if key in row:
            row[key]["tip_diff"] = float(np.abs(row[key]["tip"] - row["abs"]["tip"]).max())
    row["abs"]["tip_diff"] = 0.0
    _mode("auto")
    return row


def peer_run(free, n_links):
    """The Gen chain at the mechsys setting of the peers' comparison: CPU (best of 3) and the
    error of the final absolute link angles (cumulative joint angles) against the peers'
    independent reference (``benchmarks/peers/reference_cache.json``, by N)."""
    import json

    best, sol = np.inf, None
    for _ in range(3):
        c0 = time.process_time()
        sol = free.simulate((0.0, T_END), **PEER_SETTING)
        best = min(best, time.process_time() - c0)
    ref = json.loads((Path(__file__).parent / "peers" / "reference_cache.json").read_text())
    phi = ref.get("B", {}).get(str(n_links))
    q = np.array([float(np.ravel(sol[f"q{k}"])[-1]) for k in range(n_links)])
    err = float(np.abs(np.cumsum(q) - np.asarray(phi["phi"])).max()) if phi else float("nan")
    print(f"  N={n_links:<4} gen at the peers' setting: {best * 1e3:.0f} ms, error {err:.1e}", flush=True)
    return {"cpu": best, "error": err}


def _compile(x):
    return x["build"] + x["dynamics"]


def _exponent(rows, key, what):
    pts = [(r["N"], what(r[key])) for r in rows if key in r]
    if len(pts) < 2:
        return ""
    (n0, a), (n1, b) = pts[0], pts[-1]
    return f"~ N^{np.log(b / a) / np.log(n1 / n0):.2f}"


def report(rows) -> str:
    L = [BEGIN, "", "## N-link chain in generalized coordinates (2 s)", "",
         f"Measured on: {machine()}.", "",
         "Command: `PYTHONPATH=src python benchmarks/gen_chain.py --write docs/performance-free.md`.",
         "",
         "The chain of the section above (uniform rods pinned end to end, released horizontal) "
         "built with `GenRevolute2` joints (`docs/generalized.md`): n = N relative joint angles "
         "and no constraint equation, against the absolute-coordinate model (3N coordinates, "
         "2N pin equations). The Gen chain with the recursive dynamics (\"recursive\": per-joint "
         "kernels and the articulated-body recursion, decision 0016; the default from 8 Gen "
         "joints on) and, for short chains, with the symbolic minimal-coordinate mass matrix "
         "(\"symbolic\", decision 0010). All at DOP853 rtol 1e-8, atol 1e-10, best of up to 3 runs "
         "(`time.process_time`); \"stepper\": how the steps ran (the compiled free-motion "
         "stepper and how it solved for the accelerations, decisions 0014 and 0018, or "
         "Python); compilation (build + `free()` + the dynamics kernels, on-disk "
         "kernel cache off) listed apart. \"tip diff\": the largest difference of the last "
         "tip's final position from the absolute model's.", "",
         "| N | model | stepper | n | m | compile [s] | CPU [s] | steps | evaluations "
         "| per step [ms] | per evaluation [µs] | tip diff |",
         "| ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        for key, name in (("gen", "Gen, recursive"), ("sym", "Gen, symbolic"), ("abs", "absolute")):
            if key not in r:
                continue
            x = r[key]
            L.append(f"| {r['N']} | {name} | {x['stepper']} | {x['n']} | {x['m']} | {_compile(x):.2f} | "
                     f"{x['cpu']:.3f} | {x['steps']} | {x['evals']} | {x['per_step_ms']:.2f} | "
                     f"{x['per_eval_us']:.0f} | {x['tip_diff']:.1e} |")
    L.append("")
    for r in rows:
        g, a = r["gen"], r["abs"]
        L.append(f"* N = {r['N']}: per step Gen (recursive) / absolute = "
                 f"{g['per_step_ms'] / a['per_step_ms']:.2f}, per evaluation "
                 f"{g['per_eval_us'] / a['per_eval_us']:.2f}, compile Gen / absolute = "
                 f"{_compile(g) / _compile(a):.2f}.")
    n0, n1 = rows[0]["N"], rows[-1]["N"]
    L.append(f"* Growth from N = {n0} to {n1}: Gen (recursive) compile "
             f"{_exponent(rows, 'gen', _compile)}, per evaluation "
             f"{_exponent(rows, 'gen', lambda x: x['per_eval_us'])}; absolute compile "
             f"{_exponent(rows, 'abs', _compile)}, per evaluation "
             f"{_exponent(rows, 'abs', lambda x: x['per_eval_us'])}.")
    sym = [r for r in rows if "sym" in r]
    if len(sym) >= 2:
        L.append(f"* Gen (symbolic), N = {sym[0]['N']} to {sym[-1]['N']}: compile "
                 f"{_exponent(sym, 'sym', _compile)}, per evaluation "
                 f"{_exponent(sym, 'sym', lambda x: x['per_eval_us'])}.")
    L += ["", "Beside the peers (their numbers and mechsys' absolute-coordinate ones from the "
          "peers' block of [performance.md](performance.md), 2026-11-23, not rerun here): CPU of "
          "the 2 s simulation at the accuracy target error ≤ 1e-6 (final absolute link angles "
          "against the peers' independent reference). The Gen chain at the mechsys setting of "
          "that comparison, DOP853 rtol 1e-6, atol 1e-8:", "",
          "| N | Gen, recursive [ms] (error) | absolute [ms] | Exudyn [ms] | MuJoCo [ms] "
          "| Gen / best peer |", "| ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        p, c = r["peer"], PEERS.get(r["N"])
        if c is None:
            continue
        best = min(c["Exudyn"], c["MuJoCo"])
        L.append(f"| {r['N']} | {p['cpu'] * 1e3:.0f} ({p['error']:.1e}) | {c['mechsys']} | "
                 f"{c['Exudyn']} | {c['MuJoCo']} | {p['cpu'] * 1e3 / best:.2f} |")
    L += ["", "The symbolic minimal-coordinate mass matrix is dense (`J^T M_b J` summed over the "
          "links): N^2 entries, each a sum over the links beyond both joints, so its symbolic "
          "size and compile time grow like N^4 (the symbolic rows above; minutes at N = 64, "
          "hours at 256), "
          "which is why the recursive formulation is the default for chains of 8 Gen joints and "
          "more (3D: 4): one small kernel per distinct joint (here two: the first joint on ground and "
          "the others), compile time about linear in N (the rest is building the model and its "
          "slave kinematics), and the free accelerations of a tree of Gen joints on ground by "
          "the O(N) articulated-body recursion (Numba). Mixed models and models with "
          "closing constraints use the composite-body mass matrix (O(N) kernel calls, O(N "
          "depth) small products) in the augmented system.", "", END]
    return "\n".join(L)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[4, 16, 64, 256])
    ap.add_argument("--symbolic-max", type=int, default=16,
                    help="largest N also run with the symbolic mass matrix (N^4 compile)")
    ap.add_argument("--write", metavar="PATH", help="write the section to this Markdown page")
    args = ap.parse_args(argv)
    os.environ.setdefault("MECHSYS_CACHE", "0")   # compile times without the on-disk cache
    for key, builder in (("gen", gen_chain), ("sym", gen_chain), ("abs", abs_chain)):
        _mode(key)     # one-off imports, LLVM start-up and Numba's compile, untimed
        build(builder, 2)[1].simulate((0.0, 0.1))
    rows = [measure(n, args.symbolic_max) for n in args.sizes]
    text = report(rows)
    print(text)
    if args.write:
        write_block(Path(args.write), BEGIN, END, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
