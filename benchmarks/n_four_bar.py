"""The IFToMM multibody benchmark's N-four-bar mechanism (problem A02) through its singular
instants: N = 1, 2, 10, 40 loops, 10 s from the benchmark's start (cranks vertical, point B0
moving at 1 m/s along +x), default integrator settings (DOP853, rtol 1e-8, atol 1e-10,
projection), 401 output times.

Errors against the exact one-degree-of-freedom motion ``a theta'' = -b g cos(theta)``
(``a = (N + 1) / 3 + N``, ``b = (N + 1) / 2 + N``; integrated by SciPy's DOP853 at 1e-13):
the largest |x_B0 - cos(theta)| over the output times; the largest relative change of the
total energy (kinetic energy from every body's velocities, potential energy of every
centroid); the largest angle difference between the cranks (0 for a parallelogram); the
constraint residual. CPU: ``time.process_time`` of the ``simulate`` call (compilation
excluded).

Run: ``.venv/bin/python benchmarks/n_four_bar.py`` prints the table (several minutes, most
for N = 40); ``--write docs/robustness.md`` replaces the section between the markers
``<!-- n-four-bar:begin -->`` and ``<!-- n-four-bar:end -->`` in that page;
``--n 1 2`` limits the sizes.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread, repeatable

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _machine import machine  # noqa: E402  (sibling module: run as a script)
from scipy.integrate import solve_ivp  # noqa: E402

from mechsys import models  # noqa: E402

G = 9.81
T_END = 10.0


def exact(n_loops, t):
    a, b = (n_loops + 1) / 3 + n_loops, (n_loops + 1) / 2 + n_loops
    sol = solve_ivp(lambda _, y: [y[1], -b * G / a * np.cos(y[0])], (0.0, float(t[-1])),
                    [np.pi / 2, -1.0], t_eval=t, method="DOP853", rtol=1e-13, atol=1e-13)
    return sol.y[0]


def energy(n_loops, sol):
    E = np.zeros(len(sol.t))
    names = [f"crank{k}" for k in range(n_loops + 1)] + [f"coupler{k}" for k in range(n_loops)]
    for name in names:
        th, w = sol.coordinate(f"{name}.th"), sol.coordinate(f"{name}.th", 1)
        vx = sol.coordinate(f"{name}.x", 1) - 0.5 * np.sin(th) * w
        vy = sol.coordinate(f"{name}.y", 1) + 0.5 * np.cos(th) * w
        E += 0.5 * (vx**2 + vy**2) + 0.5 * w**2 / 12 + G * (sol.coordinate(f"{name}.y")
                                                              + 0.5 * np.sin(th))
    return E


def run(n_loops):
    m = models.n_four_bar(n_loops)
    m.solve(0.0)
    free = m.free(drop=["hold"])
    t = np.linspace(0.0, T_END, 401)
    free.simulate((0.0, 1e-3), initial_condition={"crank0.th_d": -1.0})   # compile
    c0 = time.process_time()
    sol = free.simulate(t, initial_condition={"crank0.th_d": -1.0})
    cpu = time.process_time() - c0
    th = exact(n_loops, t)
    E = energy(n_loops, sol)
    base = np.unwrap(sol.angle("crank0"))
    spread = max((np.abs(np.unwrap(sol.angle(f"crank{k}")) - base).max()
                  for k in range(1, n_loops + 1)), default=0.0)
    s = free.system
    resid = max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(sol.t, sol.q))
    return {"N": n_loops, "n": s.n, "crossings": int(np.sum(np.diff(np.floor(-th / np.pi)) != 0)),
            "cpu": cpu, "steps": sol.extra["steps"], "rejected": sol.extra["rejected"],
            "x_err": float(np.abs(sol.coordinate("coupler0.x") - np.cos(th)).max()),
            "e_err": float(np.abs(E - E[0]).max() / E[0]), "spread": spread, "resid": resid}


def table(rows) -> str:
    out = ["| N | coordinates | singular instants | CPU (s) | steps | rejected | "
           "max abs x_B0 error (m) | max rel. energy error | crank spread (rad) | max abs Phi |",
           "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        out.append(f"| {r['N']} | {r['n']} | {r['crossings']} | {r['cpu']:.2f} | {r['steps']} | "
                   f"{r['rejected']} | {r['x_err']:.1e} | {r['e_err']:.1e} | "
                   f"{r['spread']:.1e} | {r['resid']:.1e} |")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, nargs="*", default=[1, 2, 10, 40])
    ap.add_argument("--write", type=Path)
    args = ap.parse_args()
    rows = []
    for n_loops in args.n:
        rows.append(run(n_loops))
        print(table(rows[-1:]).splitlines()[-1], flush=True)
    text = f"{table(rows)}\n\n{machine()}"
    print(text)
    if args.write:
        page = args.write.read_text()
        a, b = "<!-- n-four-bar:begin -->", "<!-- n-four-bar:end -->"
        i, j = page.index(a) + len(a), page.index(b)
        args.write.write_text(page[:i] + "\n" + text + "\n" + page[j:])


if __name__ == "__main__":
    main()
