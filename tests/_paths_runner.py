"""Run one example script and check that the compiled loops and their other tier give the
same numbers on every free motion and kinematic sweep it computes (used by
``tests/test_examples.py``; run as ``python tests/_paths_runner.py examples/x.py
[--first-steps]``).

The script runs once as written, with ``FreeSystem.simulate`` and the kinematic sweep
(``solvers._kinematics.sweep``) recorded. Then each recorded computation is repeated with
``MECHSYS_JIT=0`` and ``MECHSYS_JIT=1`` (the compiled loops wherever they apply).
``MECHSYS_JIT=0`` runs every loop's own code interpreted (decisions 0081, 0082: the same
code as the compiled one, so the two runs compare the tiers, not two implementations; each
example's motion is checked against its own reference by its tests). Compared:

* a sweep over its first ``SWEEP_POINTS`` points (the loop is causal: they are the whole
  sweep's first points; compiled against interpreted, bit for bit);
* a multistage sweep (a model with stage switches) over all of its points: the same
  positions, rates and stages;
* the multipliers of a static, kinematic or dynamic solve over its first ``SWEEP_POINTS``
  points;
* a free motion (through stage changes too) or a nonholonomic path, twice:

  - as the script asked, over its first steps (about 20). Over a whole run the step-size
    controller amplifies rounding-sized differences of the error estimate into different
    steps, and a chaotic motion amplifies those, so two correct implementations of one
    method agree to the integration tolerance there, not to rounding;
  - with the same steps in both loops (kind ``"free steps"`` etc.): every step half the
    adaptive run's mean step, all accepted (``_same_steps``), over its first steps (the
    interpreted loop's step costs several times the Python path's: decision 0082).

Printed on the last line, after ``paths-agree:``: a JSON list with, per computation, its kind, the largest
difference (relative to ``max(1, |value|)``) and whether the compiled loop ran.
"""

from __future__ import annotations

import json
import os
import runpy
import sys

import numpy as np

os.environ.setdefault("MPLBACKEND", "Agg")

from mechsys import model as model_module  # noqa: E402
from mechsys.analyses import _free, _free_switch, _multistage, _path  # noqa: E402
from mechsys.solvers import _kinematics, _statics  # noqa: E402

FIRST_STEPS = 20
#: sweeps and multiplier solves are compared over this many points at most (interpreted,
#: a point of a large model costs milliseconds)
SWEEP_POINTS = 200
FIRST_STEPS_ONLY = False
LOOSE = 1e6
inf = float("inf")
records: list = []


def _record_simulate(original, kind="free"):
    def simulate(self, t, *args, **kwargs):
        sol = original(self, t, *args, **kwargs)
        if len(records) < 40:
            records.append((kind, self, t, args, kwargs, sol))
        return sol
    return simulate


def _record_sweep(original):
    def sweep(system, times, guess, *args, **kwargs):
        out = original(system, times, guess, *args, **kwargs)
        if len(records) < 40 and kwargs.get("hooks") is None and len(np.atleast_1d(times)) > 2:
            records.append(("sweep", system, np.array(times, dtype=float), (np.array(guess),) + args,
                            kwargs, out))
        return out
    return sweep


def _record_stages(original):
    def sweep_stages(model, times, guess, order, options, forced):
        out = original(model, times, guess, order, options, forced)
        if len(records) < 40 and len(np.atleast_1d(times)) > 2:
            records.append(("stages", model, np.array(times, dtype=float),
                            (np.array(guess, dtype=float), order, options, dict(forced)), {},
                            out))
        return out
    return sweep_stages


def _record_multipliers(original):
    def multipliers_over(system, times, Q, QD, QDD, p, *args, **kwargs):
        lam = original(system, times, Q, QD, QDD, p, *args, **kwargs)
        if len(records) < 40 and len(times) > 2:
            copy = [None if a is None else np.array(a) for a in (times, Q, QD, QDD, p)]
            records.append(("multipliers", system, None, (*copy, *args), kwargs, lam))
        return lam
    return multipliers_over


def _diff(a, b) -> float:
    """Largest difference, each column measured in its own scale ``max(1, max |column|)``
    (an acceleration of 30 m/s² is compared in units of 30, an angle in radians); inf when
    the shapes or the places of non-finite entries differ."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or not np.array_equal(np.isfinite(a), np.isfinite(b)):
        return float("inf")
    if not a.size:
        return 0.0
    a2, b2 = a.reshape(len(a), -1), b.reshape(len(b), -1)
    fin = np.isfinite(a2)
    a2, b2 = np.where(fin, a2, 0.0), np.where(fin, b2, 0.0)
    scale = np.maximum(1.0, np.abs(a2).max(axis=0))
    return float((np.abs(a2 - b2) / scale).max())


def _short_span(t, sol):
    """Output times over the first ``FIRST_STEPS`` steps of a run. Always output times, so
    the two runs are compared at the same instants: where the error estimate is a
    difference of nearly equal numbers the two loops choose step sizes that differ by a
    rounding-sized relative amount, and states at different instants differ by the motion
    in between."""
    steps = max(int(sol.extra.get("steps", len(sol.t))), 1)
    frac = min(1.0, FIRST_STEPS / steps)
    if isinstance(t, tuple | list) and len(t) == 2:
        t0, t1 = float(t[0]), float(t[1])
    else:
        t = np.asarray(t, dtype=float)
        t0, t1 = float(t[0]), float(t[-1])
    return np.linspace(t0, t0 + frac * (t1 - t0), 11)


def _same_steps_span(t, sol, first_steps: bool = False) -> tuple[np.ndarray, float]:
    """Output times and step size of the comparison with the same steps: 11 times over the
    whole run (over its first ``FIRST_STEPS`` steps with ``--first-steps`` or
    ``first_steps``), and half the adaptive run's mean step."""
    steps = max(int(sol.extra.get("steps", len(sol.t))), 1)
    if FIRST_STEPS_ONLY or first_steps:
        span = _short_span(t, sol)
        return span, float(span[-1] - span[0]) / (2 * min(steps, FIRST_STEPS))
    t0, t1 = (float(t[0]), float(t[-1])) if len(t) else (0.0, 0.0)
    return np.linspace(t0, t1, 11), (t1 - t0) / (2 * steps)


def _same_steps(h: float, kwargs) -> dict:
    """The options of a run whose steps both loops take alike, of size ``h``. A Runge-Kutta
    method gets ``max_step = h`` and tolerances so loose (``LOOSE``) that every step is
    accepted: SciPy's first step is then 1e-4 (its floor of 1e-6, times 100), and each
    accepted step grows ten-fold until ``max_step`` caps it, the same in both loops. Mech's
    Adams integrator gets ``step_size = h``."""
    out = {k: v for k, v in kwargs.items() if k not in ("rtol", "atol", "max_error", "max_step")}
    if str(kwargs.get("method", "dop853")).lower() in ("dop853", "rk45"):
        out.update(rtol=LOOSE, atol=LOOSE, max_step=h)
    else:
        out.update(step_size=h)
    return out


def _both(fn, *args, **kwargs):
    """``fn(*args, **kwargs)`` with the Python loops, then with the compiled ones."""
    out = {}
    for mode in ("0", "1"):
        os.environ["MECHSYS_JIT"] = mode
        out[mode] = fn(*args, **kwargs)
    os.environ.pop("MECHSYS_JIT", None)
    return out["0"], out["1"]


def _counting(ran: list):
    """``_jit_sweep.run`` that appends how many points the compiled loop solved to ``ran``."""
    def run(*a, **k):
        out = original_run(*a, **k)
        ran.append(out[0])
        return out
    return run


def _counting_multipliers(ran: list):
    """``_jit_multipliers.multipliers`` that appends how many points the compiled loop solved to ``ran``."""
    def multipliers(*a, **k):
        out = original_jit_multipliers(*a, **k)
        ran.append(out)
        return out
    return multipliers


def check() -> list[dict]:
    results = []
    for kind, obj, t, args, kwargs, sol in records:
        if kind in ("free", "path", "switched"):
            span = _short_span(t, sol)
            run = {"free": original_simulate, "path": original_path,
                   "switched": original_switched}[kind]
            py, jit = _both(run, obj, span, *args, **kwargs)
            each = {k: _diff(getattr(py, k), getattr(jit, k))
                    for k in ("t", "q", "qd", "qdd", "lam") if getattr(py, k) is not None}
            results.append({"kind": kind, "difference": max(each.values()), "each": each,
                            "rows": len(py.t),
                            "compiled": int(jit.extra.get("compiled_steps", 0)),
                            "python_compiled": int(py.extra.get("compiled_steps", 0))})
            span, h = _same_steps_span(t, sol, first_steps=True)
            py, jit = _both(run, obj, span, *args, **_same_steps(h, kwargs))
            each = {k: _diff(getattr(py, k), getattr(jit, k))
                    for k in ("t", "q", "qd", "qdd", "lam") if getattr(py, k) is not None}
            steps = [int(py.extra["steps"]), int(jit.extra["steps"])]
            results.append({"kind": kind + " steps",
                            "difference": max(each.values()) if steps[0] == steps[1] else inf,
                            "each": each, "rows": len(py.t), "steps": steps,
                            "compiled": int(jit.extra.get("compiled_steps", 0)),
                            "python_compiled": int(py.extra.get("compiled_steps", 0))})
        elif kind == "multipliers":
            ran = []
            _statics._jit_multipliers.multipliers = _counting_multipliers(ran)
            cut = SWEEP_POINTS
            args = (*(None if a is None else a[:cut] for a in args[:4]), *args[4:])
            try:
                py, jit = _both(original_multipliers, obj, *args, **kwargs)
            finally:
                _statics._jit_multipliers.multipliers = original_jit_multipliers
            results.append({"kind": "multipliers", "difference": _diff(py, jit),
                            "rows": len(py), "compiled": int(sum(ran))})
        else:
            ran: list = []
            _kinematics._jit_sweep.run = _counting(ran)
            try:
                fn = original_sweep if kind == "sweep" else original_stages
                if kind == "sweep":
                    t = t[:SWEEP_POINTS]
                py, jit = _both(fn, obj, t, *args, **kwargs)
            finally:
                _kinematics._jit_sweep.run = original_run
            d = 0.0
            if kind == "stages":      # (result, stages, scalings): the stages must be equal
                if not np.array_equal(py[1], jit[1]):
                    d = float("inf")
                py, jit = py[0], jit[0]
            parts = [(py.q, jit.q), (py.qd, jit.qd), (py.qdd, jit.qdd)]
            d = max([d] + [_diff(a, b) for a, b in parts if a is not None or b is not None])
            results.append({"kind": kind, "difference": d, "rows": len(t),
                            "compiled": int(sum(ran))})
    return results


original_simulate = _free.FreeSystem.simulate
original_path = _path.PathSystem.simulate
original_switched = _free_switch.SwitchedFreeSystem.simulate
original_sweep = _kinematics.sweep
original_run = _kinematics._jit_sweep.run
original_multipliers = _statics.multipliers_over
original_stages = _multistage._sweep_stages
original_jit_multipliers = _statics._jit_multipliers.multipliers

if __name__ == "__main__":
    FIRST_STEPS_ONLY = "--first-steps" in sys.argv[2:]
    script = sys.argv[1]
    _free.FreeSystem.simulate = _record_simulate(original_simulate)
    _path.PathSystem.simulate = _record_simulate(original_path, "path")
    _free_switch.SwitchedFreeSystem.simulate = _record_simulate(original_switched, "switched")
    _kinematics.sweep = model_module.sweep = _record_sweep(original_sweep)
    _statics.multipliers_over = _record_multipliers(original_multipliers)
    _multistage._sweep_stages = _record_stages(original_stages)
    sys.argv = [script]
    sys.path[0] = os.path.dirname(os.path.abspath(script))   # as `python script` has it
    runpy.run_path(script, run_name="__main__")
    _free.FreeSystem.simulate = original_simulate
    _path.PathSystem.simulate = original_path
    _free_switch.SwitchedFreeSystem.simulate = original_switched
    _kinematics.sweep = model_module.sweep = original_sweep
    _statics.multipliers_over = original_multipliers
    _multistage._sweep_stages = original_stages
    print("paths-agree: " + json.dumps(check()))
