"""Long free-motion runs: 10^6 integration steps of a pendulum and of a closed loop (a
four-bar linkage swinging under gravity), with the constraint drift and the energy error
over the whole run.

Both are conservative, so the total energy (kinetic + gravity potential) must stay at its
initial value; the constraint residual must stay at the projection's tolerance. The runs use
Mech's Adams integrator with a fixed step (``method="corrector", step_size=h``) and constraint
correction (each step projected onto the position and velocity constraints), so that the
number of steps is ``(t1 - t0) / h`` (plus at most one final sliver step from rounding).
The method is ``"corrector"`` (Mech's ``Method -> Corrector``: every step predicted and
corrected, PECE), which keeps the energy error far below the predictor-only steps that
``"adams"`` takes when a step looks accurate enough. Reported:

* constraint drift: ``max_k max_i |Phi_i(q_k)| / r_i`` over every step, the scaled residual
  (in units of the model's characteristic length; mechsys's convergence measure);
* velocity drift: ``max_k max_i |(Phi_q qd + Phi_t)_i| / r_i``;
* energy error: ``max_k |E_k - E_0| / E_ref`` with ``E_ref`` the largest kinetic energy of the
  run (the swing's energy), and the final value ``|E_N - E_0| / E_ref`` (drift vs
  oscillation);
* CPU time per step.

Run: ``python benchmarks/long_run.py`` (10^6 steps each, about 10-20 min);
``--steps 20000`` for a quick look; ``--write docs/robustness_fuzz.md`` replaces the section
between ``<!-- long-run:begin -->`` and ``<!-- long-run:end -->``.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
# (the compiled loops it times compile in the process, not in the background: decision 0064)
os.environ.setdefault("MECHSYS_COMPILE", "wait")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import mechsys as ms  # noqa: E402
from mechsys.solvers._linalg import Scaling  # noqa: E402

BEGIN, END = "<!-- long-run:begin -->", "<!-- long-run:end -->"


def pendulum():
    """A 1 m bar pendulum (mass 1 kg at the tip) released 1 rad from the downward vertical."""
    m = ms.Model2D()
    th0 = -np.pi / 2 + 1.0
    b = m.add_body("bar", mass=1.0, centroid=(1, 0), inertia=0.01, guess=((0, 0), th0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, th0), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    return m, m.free(drop=["hold"])


def four_bar():
    """A four-bar (ground 2, crank 1, coupler 2, rocker 1.5) with massive links, released
    from rest with the crank at 60 degrees: a closed loop swinging under gravity."""
    m = ms.Model2D()
    crank = m.add_body("crank", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0),
                       inertia=1 / 12, guess=((0, 0), np.pi / 3))
    coupler = m.add_body("coupler", points={"tip": (2, 0)}, mass=2.0, centroid=(1, 0),
                         inertia=2 * 4 / 12, guess=((0.5, 0.87), -0.2))
    rocker = m.add_body("rocker", points={"tip": (1.5, 0)}, mass=1.5, centroid=(0.75, 0),
                        inertia=1.5 * 2.25 / 12, guess=((2, 0), 1.9))
    m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)), name="A")
    m.add(ms.Revolute2(crank.point("tip"), coupler.point(0)), name="B")
    m.add(ms.Revolute2(coupler.point("tip"), rocker.point("tip")), name="C")
    m.add(ms.Revolute2(rocker.point(0), m.ground.point((2, 0))), name="D")
    m.add(ms.RotationLock1(crank, np.pi / 3), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    return m, m.free(drop=["hold"])


def measure(name, build, steps: int, h: float) -> dict:
    m, free = build()
    t1 = steps * h
    c0 = time.process_time()
    sol = free.simulate((0.0, t1), method="corrector", step_size=h, constraint_correction=True,
                        progress=sys.stderr.isatty())
    cpu = time.process_time() - c0
    s = sol.system
    p = sol.p
    Q, QD = np.asarray(sol.q), np.asarray(sol.qd)
    sc = Scaling.of(s, Q[0], s.jacobian(0.0, Q[0], p))
    pos = vel = 0.0
    for k in range(0, len(Q)):
        J, rhs = s.velocity_rhs(sol.t[k], Q[k], p)
        r = sc.rows(J)
        pos = max(pos, float(np.abs(s.residual(sol.t[k], Q[k], p) / r).max()))
        vel = max(vel, float(np.abs((J @ QD[k] - rhs) / r).max() / sc.length))
    kin = np.asarray(sol.body_energy(), dtype=float)
    pot = np.asarray(sol.potential_energy(), dtype=float)
    E = kin + pot
    Eref = float(kin.max())
    dE = np.abs(E - E[0]) / Eref
    return {"name": name, "steps": len(sol.t) - 1, "h": h, "t1": float(sol.t[-1]),
            "interrupted": bool(sol.extra.get("interrupted", False)), "cpu": cpu,
            "us_per_step": 1e6 * cpu / max(len(sol.t) - 1, 1), "pos": pos, "vel": vel,
            "E_max": float(dE.max()), "E_end": float(dE[-1]), "E_ref": Eref}


def table(rows) -> str:
    out = ["| model | steps | h (s) | simulated (s) | constraint drift (scaled) | velocity "
           "drift (scaled, 1/s) | energy error max | energy error at end | CPU (s) | "
           "µs/step |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        flag = " (interrupted)" if r["interrupted"] else ""
        out.append(f"| {r['name']}{flag} | {r['steps']:,} | {r['h']:g} | {r['t1']:g} | "
                   f"{r['pos']:.1e} | {r['vel']:.1e} | {r['E_max']:.1e} | {r['E_end']:.1e} | "
                   f"{r['cpu']:.0f} | {r['us_per_step']:.0f} |")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=1_000_000)
    ap.add_argument("--h", type=float, default=1e-3)
    ap.add_argument("--write", type=Path, default=None)
    ap.add_argument("--only", choices=["pendulum", "four-bar"], default=None)
    a = ap.parse_args(argv)
    rows = []
    for name, build in (("pendulum", pendulum), ("four-bar", four_bar)):
        if a.only and a.only != name:
            continue
        r = measure(name, build, a.steps, a.h)
        print(r, flush=True)
        rows.append(r)
    text = table(rows)
    print(text)
    if a.write:
        page = a.write.read_text()
        i, j = page.index(BEGIN) + len(BEGIN), page.index(END)
        a.write.write_text(page[:i] + "\n" + text + "\n" + page[j:])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
