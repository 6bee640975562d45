"""The energy-drift tables of docs/free_motion.md (benchmarks/energy_drift.py) and the Adams
step rule they measure.

The tables were once written under an earlier doubling rule and went stale when decision
0022 changed it (the pendulum's linear fit: -0.0016 % in the page, -4.6 % from the code).
Now the page's section is rendered from the run the benchmark stores, the quick mode
re-runs two rows against that stored run, and the rule itself is checked step for step
against an independent implementation of Mech's ``MaxError`` specification (decision 0036).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mechsys.solvers._integrators import integrate_adams

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
_spec = importlib.util.spec_from_file_location("energy_drift", ROOT / "benchmarks" / "energy_drift.py")
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)


def test_page_section_is_the_stored_run_rendered():
    page = (ROOT / "docs" / "free_motion.md").read_text(encoding="utf-8")
    assert bench.section(page) == bench.tables(bench.load()), (
        "docs/free_motion.md's energy-drift section is not the stored run: run "
        "`python benchmarks/energy_drift.py --write docs/free_motion.md`")


def test_stored_run_has_every_row_and_its_figures():
    run = bench.load()
    assert [r["run"] for r in run["pendulum"]] == [r[0] for r in bench.PENDULUM_RUNS]
    assert [r["run"] for r in run["gyroscope"]] == [r[0] for r in bench.GYRO_RUNS]
    for r in run["pendulum"] + run["gyroscope"]:
        assert r["steps"] > 0 and r["evaluations"] > r["steps"] // 2
        assert r["cpu"] is not None and r["cpu"] > 0
        assert np.isfinite(r["drift"]) and r["max_dev"] >= abs(r["drift"]) * (1 - 1e-12)


def test_quick_mode_reproduces_the_stored_rows():
    # the deterministic figures (steps, evaluations, drift) of two pendulum rows, re-run now
    assert bench.compare(bench.load()) == []


def test_compare_notices_a_stale_row():
    run = bench.load()
    row = next(r for r in run["pendulum"] if r["run"] == "fit_degree linear")
    row["drift"] = -0.0016                         # the figure the page once showed
    row["steps"] = 2253
    bad = bench.compare(run, names=("fit_degree linear",))
    assert any("drift" in b for b in bad) and any("steps" in b for b in bad)


def test_write_block_replaces_only_the_section(tmp_path):
    page = tmp_path / "p.md"
    page.write_text(f"head\n{bench.BEGIN}\nold\n{bench.END}\ntail\n")
    bench.write_block(page, f"{bench.BEGIN}\nnew\n{bench.END}")
    assert page.read_text() == f"head\n{bench.BEGIN}\nnew\n{bench.END}\ntail\n"
    page.write_text("no markers\n")
    with pytest.raises(ValueError, match="energy-drift:begin"):
        bench.write_block(page, "x")


# -- Mech's Adams step rule, written again from its specification ---------------------------

def _quadrature(nodes, t, h):
    """Weights of int_t^{t+h} p(s) ds for the Lagrange polynomial p through ``nodes``
    (each basis polynomial built and integrated with numpy.polynomial)."""
    x = (np.asarray(nodes, dtype=float) - t) / h
    w = []
    for j in range(len(x)):
        others = np.delete(x, j)
        basis = np.polynomial.Polynomial.fromroots(others) if len(others) else \
            np.polynomial.Polynomial([1.0])
        basis = basis / basis(x[j])
        prim = basis.integ()
        w.append(prim(1.0) - prim(0.0))
    return h * np.array(w)


def _mech_adams(fun, t1, y0, degree, e, rule="mech"):
    """Mech's SolveFree integrator as its MaxError page specifies it, with MaxError -> e
    (= {e, e/10, e/100}): an Adams-Bashforth predictor through the last ``degree + 1``
    derivatives, an Adams-Moulton corrector through the last ``degree`` and the predicted
    one; the error is max |corrector - predictor|. Halve (and retry) above a, take the
    corrector between b and a, keep the predictor below b; "doubled if the maximum error in
    any of the last 2n steps drops below c" (each of them, counted since the last change).
    ``rule="sum4"``: the older reading (the sum of the last four errors below c)."""
    a, b, c = e, e / 10, e / 100
    t, y = 0.0, np.array(y0, dtype=float)
    hist = [(t, fun(t, y))]
    h = min(t1 / 100, 1e-3)
    errs, steps = [], []
    while t1 - t > 1e-14 * max(1.0, t1):
        hh = min(h, t1 - t)
        d = min(degree, len(hist) - 1)
        tp, fp = zip(*hist[-(d + 1):])
        y_p = y + _quadrature(tp, t, hh) @ np.array(fp)
        f_p = fun(t + hh, y_p)
        tc, fc = zip(*(hist[-d:] if d else hist[-1:]))
        y_c = y + _quadrature([*tc, t + hh], t, hh) @ np.array([*fc, f_p])
        err = np.abs(y_c - y_p).max()
        if err > a:
            h = hh / 2
            continue
        if err > b:
            y_p, f_p = y_c, fun(t + hh, y_c)
        t, y = t + hh, y_p
        hist = (hist + [(t, f_p)])[-6:]
        errs.append(err)
        steps.append(hh)
        window = 2 * degree if rule == "mech" else 4
        quiet = max(errs[-window:]) < c if rule == "mech" else sum(errs[-4:]) < c
        if len(errs) >= window and quiet:
            h, errs = 2 * h, []
    return np.array(steps), y


def _swing(t, y):
    # a pendulum (omega = 10 rad/s) swinging through 150 degrees: the step changes often
    return np.array([y[1], -100.0 * np.sin(y[0])])


@pytest.mark.parametrize("degree", ["linear", "quadratic", "cubic", "quartic"])
def test_adams_steps_are_mechs_rule_step_for_step(degree):
    n = {"linear": 1, "quadratic": 2, "cubic": 3, "quartic": 4}[degree]
    y0 = [np.radians(150.0), 0.0]
    res = integrate_adams(_swing, lambda t, y: y, 0.0, 3.0, y0, degree, 1e-4)
    steps, y_end = _mech_adams(_swing, 3.0, y0, n, 1e-4)
    # the same steps (up to the rounding of t + h - t, which the integrator takes as its step)
    assert len(res.diagnostics["step_size"]) == len(steps) > 50
    np.testing.assert_allclose(res.diagnostics["step_size"], steps, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(res.y[-1], y_end, rtol=1e-9, atol=1e-12)
    # the test tells the two readings apart: the older rule takes other steps
    older, _ = _mech_adams(_swing, 3.0, y0, n, 1e-4, rule="sum4")
    assert len(older) != len(steps) or not np.array_equal(older, steps)


@pytest.mark.parametrize("degree", ["linear", "quartic"])
def test_adams_converges_to_scipy_as_max_error_shrinks(degree):
    y0 = [np.radians(150.0), 0.0]
    ref = solve_ivp(_swing, (0.0, 3.0), y0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    errors = [np.abs(integrate_adams(_swing, lambda t, y: y, 0.0, 3.0, y0, degree, e).y[-1]
                     - ref).max() for e in (1e-4, 1e-6, 1e-8)]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < errors[0] / 100, errors     # order 2 (linear) or more
