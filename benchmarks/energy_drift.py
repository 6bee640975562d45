"""Energy drift of the free-motion integrators on the Mech manual's two conservative
examples (section 10.4), next to the manual's numbers.

* Pendulum on a rope (``examples/pendulum_on_rope.free_response``): released 0.6 rad off,
  4.5 s. Mech (SolveFree defaults: FitDegree Cubic, MaxError 1e-4, no constraint
  correction): +0.04 %; MaxError 1e-6: +0.0007 %; ConstraintCorrection: +0.002 %;
  Quadratic: +0.08 %; Quartic: -0.04 %.
* Gyroscope with ``GyroMoment`` (``examples/gyroscope.free_response("gyromoment", t_end)``),
  constant moment on the base, its work counted as potential energy. Mech: -2 % of the
  largest kinetic energy; MaxError 1e-5: 0.12 %; Quartic: 0.71 %; constraint correction
  "virtually no effect".

Drift is ``energy_drift(sol)`` of each example: the change of total energy from start to end
in percent of the largest kinetic energy over the run. For the pendulum it is also given
relative to the total energy |E(0)| (gravity potential with the datum at the rope's
anchors, y = 0), since the manual does not say which it used; the largest deviation
max |E - E(0)| is listed too. CPU time: ``time.process_time`` of one ``free.simulate`` call
(best of five), compilation excluded.

Run: ``.venv/bin/python benchmarks/energy_drift.py`` prints the tables;
``--write docs/free_motion.md`` replaces the section between the markers
``<!-- energy-drift:begin -->`` and ``<!-- energy-drift:end -->`` in that page.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread, repeatable

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))

import gyroscope  # noqa: E402
import pendulum_on_rope  # noqa: E402

BEGIN, END = "<!-- energy-drift:begin -->", "<!-- energy-drift:end -->"
GYRO_T_END = 2.0

MECH = {"method": "adams", "fit_degree": "cubic", "max_error": 1e-4,
        "constraint_correction": False}


def _adams(**kw):
    return {**MECH, **kw}


# (label, simulate options, the manual's number in percent or None)
PENDULUM_RUNS = [
    ("Mech defaults (cubic, 1e-4, no correction)", MECH, 0.04),
    ("max_error 1e-6", _adams(max_error=1e-6), 0.0007),
    ("constraint_correction", _adams(constraint_correction=True), 0.002),
    ("fit_degree linear", _adams(fit_degree="linear"), None),
    ("fit_degree quadratic", _adams(fit_degree="quadratic"), 0.08),
    ("fit_degree cubic (= Mech defaults)", _adams(fit_degree="cubic"), 0.04),
    ("fit_degree quartic", _adams(fit_degree="quartic"), -0.04),
    ('simulate(method="adams") defaults (projection on)', {"method": "adams"}, None),
    ("simulate() defaults: dop853 rtol 1e-8, projection", {}, None),
    ("dop853 rtol 1e-8, no projection", {"constraint_correction": False}, None),
    ("dop853 rtol 1e-6", {"rtol": 1e-6, "atol": 1e-8}, None),
    ("dop853 rtol 1e-10", {"rtol": 1e-10, "atol": 1e-12}, None),
]

GYRO_RUNS = [
    ("Mech defaults (cubic, 1e-4, no correction)", MECH, "2 (loss)"),
    ("max_error 1e-5", _adams(max_error=1e-5), "0.12"),
    ("constraint_correction", _adams(constraint_correction=True), "~2 (no effect)"),
    ("fit_degree linear", _adams(fit_degree="linear"), None),
    ("fit_degree quadratic", _adams(fit_degree="quadratic"), None),
    ("fit_degree quartic", _adams(fit_degree="quartic"), "0.71"),
    ('simulate(method="adams") defaults (projection on)', {"method": "adams"}, None),
    ("simulate() defaults: dop853 rtol 1e-8, projection", {}, None),
    ("dop853 rtol 1e-8, no projection", {"constraint_correction": False}, None),
    ("dop853 rtol 1e-6", {"rtol": 1e-6, "atol": 1e-8}, None),
]


def _timed(run, repeat):
    best, sol = np.inf, None
    for _ in range(repeat):
        c0 = time.process_time()
        sol = run()
        best = min(best, time.process_time() - c0)
    return best, sol


def pendulum(repeat):
    _, free, _ = pendulum_on_rope.free_response(0.1)        # compiles; warm-up
    rows = []
    for name, opts, mech in PENDULUM_RUNS:
        cpu, sol = _timed(lambda o=opts: free.simulate((0.0, 4.5), **o), repeat)
        kin = sol.body_energy()
        E = kin + sol.potential_energy()
        rows.append({"run": name, "cpu": cpu, "steps": sol.extra["steps"],
                     "evaluations": sol.extra["evaluations"],
                     "drift": pendulum_on_rope.energy_drift(sol),
                     "drift_total": 100 * (E[-1] - E[0]) / abs(E[0]),
                     "max_dev": 100 * np.abs(E - E[0]).max() / kin.max(), "mech": mech,
                     "E0": E[0], "kin_max": kin.max()})
        _echo(rows[-1])
    return rows


def gyro(repeat, t_end=GYRO_T_END):
    _, free, _ = gyroscope.free_response("gyromoment", 0.1)
    cond = gyroscope.initial_condition("gyromoment")
    rows = []
    for name, opts, mech in GYRO_RUNS:
        cpu, sol = _timed(lambda o=opts: free.simulate((0.0, t_end), initial_condition=cond,
                                                       **o), repeat)
        kin = sol.body_energy()
        E = kin - gyroscope.MZ * gyroscope.base_angle(sol)
        rows.append({"run": name, "cpu": cpu, "steps": sol.extra["steps"],
                     "evaluations": sol.extra["evaluations"],
                     "drift": gyroscope.energy_drift(sol),
                     "max_dev": 100 * np.abs(E - E[0]).max() / np.abs(kin).max(), "mech": mech,
                     "kin_max": kin.max()})
        _echo(rows[-1])
    return rows


def precession_loops(t_end=GYRO_T_END):
    """Cusps of the base angle (minima of its rate) over the run: the nutation loops of
    the precessing gyroscope, and their mean period."""
    _, _, sol = gyroscope.free_response("gyromoment", t_end, rtol=1e-10, atol=1e-12)
    rate = np.gradient(gyroscope.base_angle(sol), sol.t)
    k = np.nonzero((rate[1:-1] < rate[:-2]) & (rate[1:-1] <= rate[2:]))[0] + 1
    gim = 2 * np.arctan2(sol["gimbal.e1"], sol["gimbal.e0"])
    return len(k), float(np.diff(sol.t[k]).mean()), float(gim[-1])


def _echo(r):
    print(f"  {r['run']:<52} cpu {r['cpu']:6.3f} s  steps {r['steps']:5d}  "
          f"drift {r['drift']:+.2e} %", flush=True)


def _pct(x):
    return f"{x:+.1e}"


def tables(pend, gy, loops) -> str:
    base = pend[0]["cpu"]
    L = [BEGIN, "",
         "<!-- Written by `python benchmarks/energy_drift.py --write docs/free_motion.md`; "
         "rerun it rather than editing the tables. -->", "",
         "### Pendulum on a rope, 4.5 s", "",
         f"E(0) = {pend[0]['E0']:.3f} J (gravity, datum y = 0 at the rope anchors); largest "
         f"kinetic energy {pend[0]['kin_max']:.3f} J. Drift in percent; Mech's numbers from "
         "the manual (10.4.3).", "",
         "| run | CPU [s] | CPU / Mech defaults | steps | evaluations | drift, % of peak KE |"
         " drift, % of abs(E(0)) | max abs(E - E(0)), % of peak KE | Mech [%] |",
         "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in pend:
        mech = "" if r["mech"] is None else f"{r['mech']:+g}"
        L.append(f"| {r['run']} | {r['cpu']:.3f} | {r['cpu'] / base:.2f} | {r['steps']} | "
                 f"{r['evaluations']} | {_pct(r['drift'])} | {_pct(r['drift_total'])} | "
                 f"{r['max_dev']:.1e} | {mech} |")
    n, period, gimbal = loops
    base = gy[0]["cpu"]
    L += ["", f"### Gyroscope (GyroMoment), {GYRO_T_END:g} s", "",
          f"t_end = {GYRO_T_END:g} s covers {n} precession (nutation) loops of period "
          f"{period:.3f} s while the gimbal tips by {gimbal:.2f} rad; the manual does not "
          "give its run length. Total energy starts at 0 (at rest, base angle 0), so drift is "
          "only given relative to the largest kinetic energy "
          f"({gy[0]['kin_max']:.2e} J).", "",
          "| run | CPU [s] | CPU / Mech defaults | steps | evaluations | drift, % of peak KE |"
          " max abs(E - E(0)), % of peak KE | Mech [%] |",
          "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in gy:
        L.append(f"| {r['run']} | {r['cpu']:.3f} | {r['cpu'] / base:.2f} | {r['steps']} | "
                 f"{r['evaluations']} | {_pct(r['drift'])} | {r['max_dev']:.1e} | "
                 f"{r['mech'] or ''} |")
    L += ["", END]
    return "\n".join(L)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", metavar="PATH", help="update the marked section of this page")
    ap.add_argument("--repeat", type=int, default=5, help="repeats per run (best of)")
    args = ap.parse_args(argv)
    print("pendulum on a rope, 4.5 s", flush=True)
    pend = pendulum(args.repeat)
    print(f"gyroscope, {GYRO_T_END:g} s", flush=True)
    gy = gyro(args.repeat)
    text = tables(pend, gy, precession_loops())
    print()
    print(text)
    if args.write:
        path = Path(args.write)
        page = path.read_text()
        if BEGIN not in page or END not in page:
            print(f"{path} has no {BEGIN} ... {END} section", file=sys.stderr)
            return 1
        head, rest = page.split(BEGIN, 1)
        tail = rest.split(END, 1)[1]
        path.write_text(head + text + tail)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
