"""Free-motion benchmark: CPU time against final accuracy for every integrator setting of
``FreeSystem.simulate`` on three fixed problems.

* Double pendulum: two uniform rods (1 m, 1 kg, centroidal inertia 1/12 kg m^2), revolute
  joints, g = 9.81, released from rest with both links horizontal, 10 s. Error: the larger
  error of the two final absolute link angles against an independent reference (the
  minimal-coordinate ODE derived here with SymPy by Lagrange, integrated in mpmath at 30
  digits by Gragg-Bulirsch-Stoer extrapolation; its accuracy is checked by a second run at
  other precision, tolerance and step). The motion is chaotic: errors grow ~1e4-fold.
* Four-bar: ground 4, crank 1, coupler 4, rocker 3 (m), uniform rods of 1 kg/m (mass = L,
  centroidal inertia m L^2/12), crank at 90 degrees, released from rest under gravity (-Y),
  5 s. Error: final crank angle against an independent one-coordinate Lagrange equation
  (closed-form loop closure and kinematic coefficients, mpmath, same extrapolation); the
  loop-closure gap is max |Phi| over the accepted steps.
* Chain of N rods like the double pendulum's (N = 4, 16, 64, 256), released horizontal,
  2 s. Error: largest final link-angle error against a tighter run (DOP853, rtol 1e-11).

CPU time is ``time.process_time`` of one ``free.simulate(...)`` call (everything the user
waits for: projection of the initial state, integration, multipliers at the output points),
best of 3 to 7 repeats for short runs (one run when it takes over 2 s). Model compilation
(building and assembling the model, ``Model.free`` and the first free-acceleration call,
which compiles the dynamics) is excluded and reported separately.

Run: ``.venv/bin/python benchmarks/free_motion.py`` prints the tables (a full run takes
several minutes: references ~1 min, the N = 256 chain's compilation ~40 s);
``--write docs/performance-free.md`` also writes them to that page; ``--quick`` runs a
reduced grid with a cheaper reference (a smoke run, about a minute).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread, repeatable

import argparse  # noqa: E402
import re  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _machine import machine  # noqa: E402  (sibling module: run as a script)

G = 9.81

# Measured elsewhere on this machine class, for the record only (not tuned to).
TARGETS = {
    "dp_1e-8_c": (1e-8, 0.35, "a well-known C engine: double pendulum to 1e-8"),
    "dp_1e-4_cpp": (1e-4, 8.0, "an absolute-coordinate C++ code: double pendulum to 1e-4"),
    "fb_6e-7_c": (6e-7, 0.075, "the C engine: four-bar to 6e-7"),
    "chain256_cpp": (None, 4.2, "the absolute-coordinate C++ code: N = 256 chain"),
}


# ---------------------------------------------------------------------------------------
# mechsys models
# ---------------------------------------------------------------------------------------
def double_pendulum():
    """Two rods hanging from the origin, both horizontal; locks ``lock1``, ``lock2``."""
    return chain(2)


def chain(n_links: int):
    """``n_links`` uniform rods (1 m, 1 kg, 1/12), pinned end to end, the first to the
    ground at the origin, all horizontal along +X. Bodies ``l0 ... l{N-1}``; constraints
    ``lock{k}`` fix the link angles for assembly and are dropped."""
    from mechsys import models

    m = models.pendulum_chain(n_links, G)
    m.solve(0.0)
    return m, [f"lock{k}" for k in range(n_links)]


def four_bar_config(th):
    """Coupler and rocker angles of the four-bar at crank angle ``th`` (upper branch: the
    coupler-rocker pin above the line from the crank tip to the rocker pivot). Works on
    floats and on mpmath numbers."""
    import mpmath as mp

    ax, ay = mp.cos(th), mp.sin(th)
    ex, ey = 4 - ax, -ay
    d = mp.sqrt(ex * ex + ey * ey)
    phi = mp.atan2(ey, ex) + mp.acos((d * d + 16 - 9) / (8 * d))
    bx, by = ax + 4 * mp.cos(phi), ay + 4 * mp.sin(phi)
    return phi, mp.atan2(by, bx - 4)


def four_bar():
    """Ground 4, crank 1, coupler 4, rocker 3, rods of 1 kg/m, crank held at 90 degrees."""
    import mechsys as ms

    m = ms.Model2D()
    th0 = np.pi / 2
    phi, psi = (float(v) for v in four_bar_config(th0))
    links = {"crank": 1.0, "coupler": 4.0, "rocker": 3.0}
    guesses = {"crank": ((0.0, 0.0), th0), "coupler": ((0.0, 1.0), phi),
               "rocker": ((4.0, 0.0), psi)}
    b = {name: m.add_body(name, points={"tip": (L, 0)}, mass=L, centroid=(L / 2, 0),
                          inertia=L**3 / 12, guess=guesses[name]) for name, L in links.items()}
    m.add(ms.Revolute2(m.ground.point((0, 0)), b["crank"].point(0)), name="crank pivot")
    m.add(ms.Revolute2(b["crank"].point("tip"), b["coupler"].point(0)), name="crank pin")
    m.add(ms.Revolute2(b["coupler"].point("tip"), b["rocker"].point("tip")), name="rocker pin")
    m.add(ms.Revolute2(m.ground.point((4, 0)), b["rocker"].point(0)), name="rocker pivot")
    m.add(ms.RotationLock1(b["crank"], th0), name="hold")
    m.add_load(ms.Gravity((0, -1), G))
    m.solve(0.0)
    return m, ["hold"]


def compiled(build, *args):
    """Build, assemble and free a model and compile its dynamics; CPU time of each part."""
    from mechsys.solvers._tolerances import SPARSE_THRESHOLD

    c0 = time.process_time()
    m, drop = build(*args)
    c1 = time.process_time()
    free = m.free(drop=drop)
    c2 = time.process_time()
    free.solve(0.0)              # derives and compiles mass matrix, forces and the kernel
    c3 = time.process_time()
    s = free.system
    return free, {"build": c1 - c0, "free": c2 - c1, "dynamics": c3 - c2,
                  "compile": c3 - c0, "n": s.n, "m": s.m,
                  "sparse": s.n + s.m > SPARSE_THRESHOLD}


# ---------------------------------------------------------------------------------------
# independent references (no mechsys)
# ---------------------------------------------------------------------------------------
def double_pendulum_ode():
    """Lagrange's equations of the double pendulum in the absolute link angles, derived
    with SymPy: returns ``f(x1, x2, w1, w2) -> (a1, a2)`` for mpmath and for NumPy."""
    import sympy as sp

    t = sp.Symbol("t")
    th = [sp.Function(f"th{i}")(t) for i in (1, 2)]
    g = sp.Rational(981, 100)
    c1 = sp.Matrix([sp.cos(th[0]), sp.sin(th[0])]) / 2
    c2 = 2 * c1 + sp.Matrix([sp.cos(th[1]), sp.sin(th[1])]) / 2
    v1, v2 = c1.diff(t), c2.diff(t)
    kinetic = (v1.dot(v1) + v2.dot(v2)) / 2 + (th[0].diff(t) ** 2 + th[1].diff(t) ** 2) / 24
    lag = kinetic - g * (c1[1] + c2[1])
    x1, x2, w1, w2, a1, a2 = sp.symbols("x1 x2 w1 w2 a1 a2")
    eqs = [sp.diff(lag.diff(q.diff(t)), t) - lag.diff(q) for q in th]
    rep = [({th[0].diff(t, 2): a1, th[1].diff(t, 2): a2}),
           ({th[0].diff(t): w1, th[1].diff(t): w2}), ({th[0]: x1, th[1]: x2})]
    for r in rep:
        eqs = [e.subs(r) for e in eqs]
    sol = sp.solve(eqs, [a1, a2], dict=True)[0]
    acc = [sp.simplify(sol[a1]), sp.simplify(sol[a2])]
    args = (x1, x2, w1, w2)
    return sp.lambdify(args, acc, "mpmath"), sp.lambdify(args, acc, "numpy")


def four_bar_ode():
    """The four-bar as one coordinate (crank angle th): ``M(th) th'' + M'(th) th'^2 / 2 +
    V'(th) = 0`` with ``M = sum m |dc/dth|^2 + I (dangle/dth)^2``. Coupler and rocker
    angles from the closed-form loop closure, their first and second derivatives from the
    differentiated loop equation (kinematic coefficients). mpmath numbers throughout."""
    import mpmath as mp

    masses = (1, 4, 3)
    inertia = (mp.mpf(1) / 12, mp.mpf(64) / 12, mp.mpf(27) / 12)
    g = mp.mpf(981) / 100

    def rhs(y):
        th, w = y
        phi, psi = four_bar_config(th)
        ut, up, us = (mp.cos(th), mp.sin(th)), (mp.cos(phi), mp.sin(phi)), (mp.cos(psi),
                                                                            mp.sin(psi))
        nt, n_p, ns = (-ut[1], ut[0]), (-up[1], up[0]), (-us[1], us[0])
        # loop A(th) + 4 u(phi) = D + 3 u(psi); d/dth: [4 n(phi), -3 n(psi)] [phi', psi'] = -n(th)
        K = mp.matrix([[4 * n_p[0], -3 * ns[0]], [4 * n_p[1], -3 * ns[1]]])
        p1, s1 = mp.lu_solve(K, mp.matrix([-nt[0], -nt[1]]))
        b2 = [ut[i] + 4 * p1**2 * up[i] - 3 * s1**2 * us[i] for i in (0, 1)]
        p2, s2 = mp.lu_solve(K, mp.matrix(b2))
        dc = ([nt[i] / 2 for i in (0, 1)], [nt[i] + 2 * p1 * n_p[i] for i in (0, 1)],
              [mp.mpf(3) / 2 * s1 * ns[i] for i in (0, 1)])
        ddc = ([-ut[i] / 2 for i in (0, 1)],
               [-ut[i] + 2 * p2 * n_p[i] - 2 * p1**2 * up[i] for i in (0, 1)],
               [mp.mpf(3) / 2 * (s2 * ns[i] - s1**2 * us[i]) for i in (0, 1)])
        da, dda = (1, p1, s1), (0, p2, s2)
        M = sum(mk * (c[0] ** 2 + c[1] ** 2) for mk, c in zip(masses, dc))
        M += sum(ik * a**2 for ik, a in zip(inertia, da))
        dM = 2 * sum(mk * (c[0] * cc[0] + c[1] * cc[1]) for mk, c, cc in zip(masses, dc, ddc))
        dM += 2 * sum(ik * a * aa for ik, a, aa in zip(inertia, da, dda))
        dV = g * sum(mk * c[1] for mk, c in zip(masses, dc))
        return [w, -(dM * w * w / 2 + dV) / M]

    return rhs


def _midpoint(f, y, H, n):
    h = H / n
    z0 = list(y)
    z1 = [a + h * b for a, b in zip(z0, f(z0))]
    for _ in range(n - 1):
        z0, z1 = z1, [a + 2 * h * b for a, b in zip(z0, f(z1))]
    return [(a + b + h * c) / 2 for a, b, c in zip(z1, z0, f(z1))]


def gbs(f, y0, t_end, H, tol, dps, kmax=16):
    """Gragg-Bulirsch-Stoer extrapolation (modified midpoint, n = 2, 4, 6, ..., Neville
    in h^2) in mpmath at ``dps`` digits: a step of length ``H`` is accepted once two
    successive diagonal entries agree to ``tol``; otherwise ``H`` is halved."""
    import mpmath as mp

    with mp.workdps(dps):
        y = [mp.mpf(v) for v in y0]
        t, t_end, H, tol = mp.mpf(0), mp.mpf(t_end), mp.mpf(H), mp.mpf(tol)
        steps = 0
        while t < t_end - mp.mpf(10) ** (-dps // 2):
            h = min(H, t_end - t)
            table, ns, done = [], [], False
            for j in range(kmax):
                ns.append(2 * (j + 1))
                row = [_midpoint(f, y, h, ns[j])]
                for k in range(1, j + 1):
                    r = mp.mpf(ns[j]) ** 2 / ns[j - k] ** 2 - 1
                    row.append([a + (a - b) / r for a, b in zip(row[k - 1], table[j - 1][k - 1])])
                table.append(row)
                if j >= 2 and max(abs(a - b) for a, b in zip(row[j], row[j - 1])) < tol:
                    done = True
                    break
            if not done:
                H = h / 2
                continue
            y, t, steps = row[j], t + h, steps + 1
        return [+v for v in y], steps


def reference(problem: str, quick: bool) -> dict:
    """Final state of the independent reference, with a second run for its accuracy."""
    from scipy.integrate import solve_ivp

    if problem == "double pendulum":
        f_mp, f_np = double_pendulum_ode()
        f = lambda y: [y[2], y[3], *f_mp(*y)]    # noqa: E731
        y0, t_end, nq = [0, 0, 0, 0], 10.0, 2
        runs = [(20, 1e-16, 0.05)] if quick else [(30, 1e-24, 0.02), (24, 1e-18, 0.05)]
    else:
        f = four_bar_ode()
        f_np = None
        y0, t_end, nq = [np.pi / 2, 0.0], 5.0, 1       # the model's float start
        runs = [(20, 1e-16, 0.1)] if quick else [(30, 1e-24, 0.05), (24, 1e-18, 0.1)]
    out = {"runs": []}
    for dps, tol, H in runs:
        c0 = time.process_time()
        y, steps = gbs(f, y0, t_end, H, tol, dps)
        out["runs"].append({"dps": dps, "tol": tol, "H": H, "steps": steps,
                            "cpu": time.process_time() - c0, "y": y})
    best = out["runs"][0]["y"]
    out["q"] = np.array([float(v) for v in best[:nq]])
    if len(out["runs"]) > 1:
        other = out["runs"][1]["y"]
        out["accuracy"] = float(max(abs(a - b) for a, b in zip(best[:nq], other[:nq])))
    if f_np is not None:        # what float64 DOP853 achieves, for comparison
        fn = lambda _t, y: [y[2], y[3], *f_np(*y)]    # noqa: E731
        out["scipy"] = {}
        ends = []
        for rtol in (1e-13, 1e-14):
            with warnings.catch_warnings():      # SciPy raises rtol 1e-14 to 2.2e-14
                warnings.simplefilter("ignore", UserWarning)
                r = solve_ivp(fn, (0, t_end), [0.0] * 4, method="DOP853", rtol=rtol,
                              atol=rtol / 100)
            ends.append(r.y[:2, -1])
            out["scipy"][rtol] = float(np.abs(r.y[:2, -1] - out["q"]).max())
        out["scipy"]["mutual"] = float(np.abs(ends[0] - ends[1]).max())
    return out


# ---------------------------------------------------------------------------------------
# runs
# ---------------------------------------------------------------------------------------
def settings(problem: str, quick: bool) -> list[tuple[str, dict]]:
    if quick:
        rt = [1e-6, 1e-8, 1e-10]
        grid = [("dop853", {"rtol": r, "atol": r / 100, "constraint_correction": c})
                for r in rt for c in (True, False)]
        grid += [("rk45", {"rtol": 1e-8, "atol": 1e-10, "constraint_correction": True})]
        grid += [("adams", {"fit_degree": d, "max_error": e, "constraint_correction": c})
                 for d in ("cubic", "quartic") for e in (1e-4, 1e-6) for c in (False, True)]
        return grid
    rt = [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13]
    grid = [("dop853", {"rtol": r, "atol": r / 100, "constraint_correction": c})
            for r in rt for c in (True, False)]
    grid += [("rk45", {"rtol": r, "atol": r / 100, "constraint_correction": True})
             for r in (1e-6, 1e-8, 1e-10)]
    grid += [("rk45", {"rtol": 1e-8, "atol": 1e-10, "constraint_correction": False})]
    errors = {"linear": (1e-4, 1e-6), "quadratic": (1e-4, 1e-6, 1e-8),
              "cubic": (1e-4, 1e-6, 1e-8, 1e-10), "quartic": (1e-4, 1e-6, 1e-8, 1e-10)}
    if problem == "four-bar":
        errors["quartic"] += (1e-11,)
    grid += [("adams", {"fit_degree": d, "max_error": e, "constraint_correction": c})
             for d, es in errors.items() for e in es for c in (False, True)]
    return grid


def timed(free, t_end, method, opts, repeat, max_repeat=7):
    """Best CPU time and the solution: one run when it takes over 2 s, else at least
    ``repeat`` runs, continued (up to ``max_repeat``) until 1 s has been spent, so that the
    short runs, most exposed to other jobs on the machine, get the most repeats."""
    best, sol, spent = np.inf, None, 0.0
    for k in range(max(repeat, max_repeat)):
        c0 = time.process_time()
        sol = free.simulate((0.0, t_end), method=method, **opts)
        dt = time.process_time() - c0
        best, spent = min(best, dt), spent + dt
        if (dt > 2.0 and k == 0) or (k + 1 >= repeat and spent > 1.0):
            break
    return best, sol


def label(method, opts):
    if method == "adams":
        return f"adams {opts['fit_degree']} max_error {opts['max_error']:.0e}"
    return f"{method} rtol {opts['rtol']:.0e}"


def chain_label(method, opts):
    text = label(method, opts)
    return text + (", no projection" if opts.get("constraint_correction") is False else "")


def run_grid(problem, free, t_end, ref_q, names, quick, repeat):
    rows = []
    s = free.system
    for method, opts in settings(problem, quick):
        cpu, sol = timed(free, t_end, method, opts, repeat)
        q_end = np.array([sol[k][-1] for k in names])
        gap = max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(sol.t, sol.q))
        row = {"setting": label(method, opts), "method": method,
               "correction": opts["constraint_correction"], "cpu": cpu,
               "steps": sol.extra["steps"], "evaluations": sol.extra["evaluations"],
               "rejected": sol.extra["rejected"], "error": float(np.abs(q_end - ref_q).max()),
               "gap": gap, "opts": opts}
        rows.append(row)
        print(f"  {row['setting']:<34} corr={str(row['correction']):<5} cpu {cpu:8.3f} s  "
              f"steps {row['steps']:6d}  evals {row['evaluations']:7d}  "
              f"error {row['error']:.2e}  gap {gap:.1e}", flush=True)
    return rows


def cheapest(rows, tol, **where):
    ok = [r for r in rows if r["error"] <= tol and all(r[k] == v for k, v in where.items())]
    return min(ok, key=lambda r: r["cpu"]) if ok else None


def chain_case(n_links, t_end, quick, repeat):
    free, comp = compiled(chain, n_links)
    names = [f"l{k}.th" for k in range(n_links)]
    c0 = time.process_time()
    ref = free.simulate((0.0, t_end), rtol=1e-11, atol=1e-13)
    ref_cpu = time.process_time() - c0
    ref_q = np.array([ref[k][-1] for k in names])
    rows = []
    grid = [("dop853", {"rtol": 1e-6, "atol": 1e-8}), ("dop853", {"rtol": 1e-8, "atol": 1e-10}),
            ("dop853", {"rtol": 1e-8, "atol": 1e-10, "constraint_correction": False})]
    if not quick and n_links <= 64:
        grid += [("adams", {"fit_degree": "cubic", "max_error": 1e-6,
                            "constraint_correction": False})]
    for method, opts in grid:
        cpu, sol = timed(free, t_end, method, opts, repeat)
        q_end = np.array([sol[k][-1] for k in names])
        ev, st = sol.extra["evaluations"], sol.extra["steps"]
        rows.append({"N": n_links, "setting": chain_label(method, opts), "cpu": cpu, "steps": st,
                     "evaluations": ev, "per_step_ms": cpu / st * 1e3,
                     "per_eval_us": cpu / ev * 1e6,
                     "error": float(np.abs(q_end - ref_q).max())})
        print(f"  N={n_links:<4} {rows[-1]['setting']:<30} cpu {cpu:8.3f} s  steps {st:5d}  "
              f"evals {ev:6d}  {rows[-1]['per_eval_us']:7.0f} us/eval  "
              f"error {rows[-1]['error']:.1e}", flush=True)
    comp["reference_cpu"] = ref_cpu
    comp["reference_steps"] = ref.extra["steps"]
    return comp, rows


# ---------------------------------------------------------------------------------------
# report
# ---------------------------------------------------------------------------------------
def _grid_table(rows, with_gap=False):
    head = "| setting | projection | CPU [s] | steps | evaluations | rejected | error |"
    sep = "| --- | --- | ---: | ---: | ---: | ---: | ---: |"
    if with_gap:
        head += " max abs(Phi) |"
        sep += " ---: |"
    out = [head, sep]
    for r in rows:
        line = (f"| {r['setting']} | {'yes' if r['correction'] else 'no'} | {r['cpu']:.3f} | "
                f"{r['steps']} | {r['evaluations']} | {r['rejected']} | {r['error']:.1e} |")
        if with_gap:
            line += f" {r['gap']:.1e} |"
        out.append(line)
    return out


def _families(rows):
    fam = {}
    for r in rows:
        key = r["method"] + (f" {r['opts']['fit_degree']}" if r["method"] == "adams" else "")
        key += ", projection" if r["correction"] else ", no projection"
        fam.setdefault(key, []).append(r)
    return fam


def _tolerance(r):
    return r["opts"]["max_error"] if r["method"] == "adams" else r["opts"]["rtol"]


def reliable(rows, tol):
    """The loosest setting of one integrator from which every tighter setting of the grid
    also meets ``tol`` (chaotic errors are not monotone in the tolerance)."""
    rs = sorted(rows, key=_tolerance, reverse=True)
    for i in range(len(rs)):
        if all(r["error"] <= tol for r in rs[i:]):
            return rs[i]
    return None


def _cell(r):
    return f"{r['cpu']:.3f} ({r['setting'].split(' ', 1)[1]})" if r else "not reached"


def _reach_table(rows, tols):
    out = ["| integrator | " + " | ".join(f"to {t:.0e}: cheapest | to {t:.0e}: reliably"
                                         for t in tols) + " |",
           "| --- |" + " ---: | ---: |" * len(tols)]
    for key, rs in _families(rows).items():
        cells = []
        for tol in tols:
            cells += [_cell(cheapest(rs, tol)), _cell(reliable(rs, tol))]
        out.append(f"| {key} | " + " | ".join(cells) + " |")
    return out


def _best_reliable(rows, tol):
    """The cheapest of the integrators' reliable settings for ``tol``."""
    found = [reliable(rs, tol) for rs in _families(rows).values()]
    found = [r for r in found if r is not None]
    return min(found, key=lambda r: r["cpu"]) if found else None


def _ratio(ours, theirs):
    return f"{ours:.3f} s vs {theirs:g} s: x{ours / theirs:.2f}" if ours else "not reached"


def report(res, quick) -> str:
    L = ["# Free-motion performance", "",
         "<!-- Written by `python benchmarks/free_motion.py --write docs/performance-free.md`;",
         "rerun it rather than editing the tables. -->", "",
         f"Measured on: {machine()}.", "",
         f"Command: `python benchmarks/free_motion.py{' --quick' if quick else ''} --write "
         "docs/performance-free.md`.", "",
         "CPU time is `time.process_time` of one `free.simulate((0, t_end), ...)` call, the best "
         "of 3 to 7 repeats (until 1 s is spent; one run when it takes over 2 s) on a machine "
         "shared with other jobs, where repeated measurements still differ by up to ~20 %. It "
         "includes projecting the "
         "initial state and computing qdd and the multipliers at every output step. "
         "Compilation is excluded and listed separately. \"evaluations\" counts evaluations "
         "of the free acceleration by the integrator, \"steps\" accepted steps, \"rejected\" "
         "rejected steps. \"projection\" is `constraint_correction` (projection of positions "
         "and velocities onto the constraints after every step). DOP853 and RK45 use "
         "`atol = rtol / 100`.", ""]
    dp = res["dp"]
    ref = dp["ref"]
    L += ["## Double pendulum (10 s, chaotic)", "",
          f"Compile: build and assemble {dp['comp']['build']:.2f} s, `free()` "
          f"{dp['comp']['free']:.2f} s, dynamics {dp['comp']['dynamics']:.2f} s "
          f"(n = {dp['comp']['n']}, m = {dp['comp']['m']}).", ""]
    r0 = ref["runs"][0]
    L += [f"Reference: the minimal-coordinate ODE (absolute link angles, Lagrange's equations "
          f"derived with SymPy in the script) integrated in mpmath by Gragg-Bulirsch-Stoer "
          f"extrapolation at {r0['dps']} digits, local tolerance {r0['tol']:.0e}, step "
          f"{r0['H']} s ({r0['steps']} steps, {r0['cpu']:.1f} s CPU). Final angles "
          f"th1 = {ref['q'][0]:.15f}, th2 = {ref['q'][1]:.15f}."]
    if "accuracy" in ref:
        r1 = ref["runs"][1]
        L += [f"A second run at {r1['dps']} digits, tolerance {r1['tol']:.0e}, step {r1['H']} s "
              f"agrees to {ref['accuracy']:.1e} rad: the reference is good to far better than "
              "1e-12."]
    if "scipy" in ref:
        s = ref["scipy"]
        L += [f"For comparison, SciPy's DOP853 in double precision on the same ODE at rtol "
              f"1e-13 and 1e-14 (raised by SciPy to 2.2e-14) differ from each other by "
              f"{s['mutual']:.1e} but miss the reference by {s[1e-13]:.1e} and {s[1e-14]:.1e}: "
              "the convergence check would overstate a float64 reference, which cannot be "
              "good to 1e-12 for this chaotic motion (round-off alone grows ~1e4-fold)."]
    L += ["", *(_grid_table(dp["rows"], with_gap=True)), "",
          "max abs(Phi): the largest constraint residual over the accepted steps.", "",
          "CPU time [s] (setting) to reach an error: \"cheapest\" is the cheapest setting of "
          "the grid that did, \"reliably\" the loosest setting from which every tighter one "
          "also did (the chaotic error is not monotone in the tolerance); \"not reached\": no "
          "setting of the grid did.", "", *_reach_table(dp["rows"], (1e-4, 1e-8)), ""]
    b4 = _best_reliable(dp["rows"], 1e-4)
    b8 = _best_reliable(dp["rows"], 1e-8)
    t4, t8 = TARGETS["dp_1e-4_cpp"], TARGETS["dp_1e-8_c"]
    L += [f"Fastest reliably to 1e-4: {b4['setting'] if b4 else '-'}"
          f"{', projection' if b4 and b4['correction'] else ''}; to 1e-8: "
          f"{b8['setting'] if b8 else '-'}{', projection' if b8 and b8['correction'] else ''}.",
          "", "Against numbers measured elsewhere on this machine class (for the record only):",
          "", f"* {t4[2]}: 8 s; ours {_ratio(b4['cpu'] if b4 else None, t4[1])}.",
          f"* {t8[2]}: 0.35 s; ours {_ratio(b8['cpu'] if b8 else None, t8[1])}.", ""]
    fb = res["fb"]
    ref = fb["ref"]
    r0 = ref["runs"][0]
    L += ["## Four-bar (5 s)", "",
          f"Compile: build and assemble {fb['comp']['build']:.2f} s, `free()` "
          f"{fb['comp']['free']:.2f} s, dynamics {fb['comp']['dynamics']:.2f} s "
          f"(n = {fb['comp']['n']}, m = {fb['comp']['m']}).", "",
          "Reference: an independent one-coordinate formulation (crank angle; coupler and "
          "rocker angles from the closed-form loop closure, their derivatives from the "
          "differentiated loop equation; `M(th) th'' + M'(th) th'^2/2 + V'(th) = 0`), "
          f"integrated in mpmath as above at {r0['dps']} digits, tolerance {r0['tol']:.0e}, "
          f"step {r0['H']} s ({r0['cpu']:.1f} s CPU); final crank angle {ref['q'][0]:.15f} rad."]
    if "accuracy" in ref:
        r1 = ref["runs"][1]
        L += [f"A second run ({r1['dps']} digits, {r1['tol']:.0e}, step {r1['H']}) agrees to "
              f"{ref['accuracy']:.1e} rad."]
    L += ["", *(_grid_table(fb["rows"], with_gap=True)), "",
          "max abs(Phi) is the loop-closure gap: the largest constraint residual over the "
          "accepted steps. CPU time [s] (setting) to reach an error, as above:", "",
          *_reach_table(fb["rows"], (6e-7, 1e-8)), ""]
    b = _best_reliable(fb["rows"], 6e-7)
    t = TARGETS["fb_6e-7_c"]
    L += [f"Against the record: {t[2]}: 75 ms; ours, reliably "
          f"({b['setting'] if b else '-'}) {_ratio(b['cpu'] if b else None, t[1])}.", ""]
    ch = res["chain"]
    L += ["## N-link chain (2 s)", "",
          "Error: largest final link-angle error against a DOP853 run at rtol 1e-11 "
          "(atol 1e-13) of the same model. Above `SPARSE_THRESHOLD` (n + m > 150) the "
          "augmented system is solved by sparse LU.", "",
          "| N | n | m | LU | build+assemble [s] | free() [s] | dynamics [s] | reference CPU [s]"
          " (steps) |", "| ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: |"]
    for comp, _ in ch:
        L.append(f"| {comp['N']} | {comp['n']} | {comp['m']} | "
                 f"{'sparse' if comp['sparse'] else 'dense'} | {comp['build']:.2f} | "
                 f"{comp['free']:.2f} | {comp['dynamics']:.2f} | {comp['reference_cpu']:.2f} "
                 f"({comp['reference_steps']}) |")
    L += ["", "| N | setting | CPU [s] | steps | evaluations | per step [ms] | per evaluation "
          "[µs] | error |", "| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for _, rows in ch:
        for r in rows:
            L.append(f"| {r['N']} | {r['setting']} | {r['cpu']:.3f} | {r['steps']} | "
                     f"{r['evaluations']} | {r['per_step_ms']:.2f} | {r['per_eval_us']:.0f} | "
                     f"{r['error']:.1e} |")
    growth = []
    for a, b in zip(ch[:-1], ch[1:]):
        ra = next(r for r in a[1] if r["setting"] == "dop853 rtol 1e-08")
        rb = next(r for r in b[1] if r["setting"] == "dop853 rtol 1e-08")
        k = np.log(rb["per_eval_us"] / ra["per_eval_us"]) / np.log(b[0]["N"] / a[0]["N"])
        growth.append(f"N {a[0]['N']} -> {b[0]['N']}: x{rb['per_eval_us'] / ra['per_eval_us']:.1f} "
                      f"(~ N^{k:.2f})")
    L += ["", "Growth of the cost per evaluation (default setting): " + "; ".join(growth) + ".",
          ""]
    last = ch[-1]
    if last[0]["N"] == 256:
        r = next(r for r in last[1] if r["setting"] == "dop853 rtol 1e-08")
        t = TARGETS["chain256_cpp"]
        L += [f"Against the record: {t[2]}: 4.2 s (its accuracy was not given); ours at the "
              f"default setting {_ratio(r['cpu'], t[1])} (error {r['error']:.0e}), plus "
              f"{last[0]['compile']:.0f} s of compilation.", ""]
    return "\n".join(L) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", metavar="PATH", help="write the tables to this Markdown file")
    ap.add_argument("--quick", action="store_true", help="reduced grid and reference")
    ap.add_argument("--repeat", type=int, default=3, help="repeats of short runs (best of)")
    args = ap.parse_args(argv)
    res = {}
    print("double pendulum: reference ...", flush=True)
    ref = reference("double pendulum", args.quick)
    free, comp = compiled(double_pendulum)
    free.simulate((0.0, 0.1))                          # warm-up
    rows = run_grid("double pendulum", free, 10.0, ref["q"], ["l0.th", "l1.th"], args.quick,
                    args.repeat)
    res["dp"] = {"ref": ref, "comp": comp, "rows": rows}
    print("four-bar: reference ...", flush=True)
    ref = reference("four-bar", args.quick)
    free, comp = compiled(four_bar)
    free.simulate((0.0, 0.1))
    rows = run_grid("four-bar", free, 5.0, ref["q"], ["crank.th"], args.quick, args.repeat)
    res["fb"] = {"ref": ref, "comp": comp, "rows": rows}
    print("chain ...", flush=True)
    res["chain"] = []
    for n_links in ((4, 16) if args.quick else (4, 16, 64, 256)):
        comp, rows = chain_case(n_links, 2.0, args.quick, args.repeat)
        comp["N"] = n_links
        print(f"  N={n_links}: compile {comp['compile']:.2f} s", flush=True)
        res["chain"].append((comp, rows))
    text = report(res, args.quick)
    print()
    print(text)
    if args.write:
        page = Path(args.write)
        # sections other scripts write (between <!-- name: begin ... --> and
        # <!-- name: end -->) are kept, after this script's tables
        old = page.read_text() if page.exists() else ""
        blocks = [b.group(0) for b in re.finditer(r"<!-- (\w+): begin.*?<!-- \1: end -->", old,
                                                  re.S)]
        page.write_text(text.rstrip("\n") + "".join("\n\n" + b for b in blocks) + "\n")
        print(f"wrote {args.write}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
