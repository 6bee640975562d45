"""Regressions found while benchmarking free motion (benchmarks/free_motion.py,
benchmarks/energy_drift.py): evaluation counts, backward integration with output times,
cached Adams weights, and the documented default of ``simulate``."""

import inspect
import re
from pathlib import Path

import numpy as np
import pytest

import mechsys as ms
from mechsys.analyses._free import FreeSystem
from mechsys.solvers._integrators import integrate_adams, integrate_rk


def _oscillator():
    calls = []

    def fun(t, y):
        calls.append(t)
        return np.array([y[1], -y[0]])

    return fun, calls


@pytest.mark.parametrize("correction", [True, False])
@pytest.mark.parametrize("method", ["dop853", "rk45"])
def test_rk_evaluations_count_each_derivative_call_once(method, correction):
    # the refresh after a projection goes through solver.fun, which SciPy already counts
    fun, calls = _oscillator()
    res = integrate_rk(fun, lambda t, y: y, 0.0, 3.0, [1.0, 0.0], method, 1e-8, 1e-10,
                       correction=correction)
    assert res.evaluations == len(calls)
    assert res.diagnostics["projections"] == (res.steps if correction else 0)
    assert abs(res.y[-1, 0] - np.cos(3.0)) < 1e-6


@pytest.mark.parametrize("method,stages", [("dop853", 12), ("rk45", 6)])
def test_rk_reports_rejected_steps(method, stages):
    # a far too large first step must be rejected (it was always reported as 0); each attempt
    # costs `stages` evaluations, plus the initial one and one refresh per projection
    fun, calls = _oscillator()
    res = integrate_rk(fun, lambda t, y: y, 0.0, 3.0, [1.0, 0.0], method, 1e-10, 1e-12,
                       first_step=2.5)
    assert res.rejected >= 1
    assert res.evaluations == 1 + stages * (res.steps + res.rejected) + res.steps


def test_adams_evaluations_count_each_derivative_call_once():
    fun, calls = _oscillator()
    res = integrate_adams(fun, lambda t, y: y, 0.0, 3.0, [1.0, 0.0], "cubic", 1e-8,
                          correction=True)
    assert res.evaluations == len(calls)


def test_adams_refuses_a_step_whose_error_is_not_finite():
    """A derivative that turns NaN mid-run: the Python driver of Adams' step stops with an
    error naming the time (the step's error is NaN, and ``NaN > max_error`` is false: the
    step was once accepted, and the run went on with NaN states)."""
    def fun(t, y):
        return np.array([y[1], -y[0] if t < 0.5 else np.nan])

    with pytest.raises(ms.MechError, match=r"adams: at t = 0\.4.* not finite"):
        integrate_adams(fun, lambda t, y: y, 0.0, 1.0, [1.0, 0.0], "cubic", 1e-8)


def _pendulum():
    m = ms.Model2D()
    b = m.add_body("bar", mass=1.0, centroid=(1.0, 0), inertia=0.0, guess=((0, 0), 0.0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, 0.0), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    return m.free(drop=["hold"])


@pytest.mark.parametrize("method,opts", [("dop853", {"rtol": 1e-10, "atol": 1e-12}),
                                         ("rk45", {"rtol": 1e-9, "atol": 1e-11}),
                                         ("adams", {"max_error": 1e-9, "fit_degree": "quartic"})])
def test_backward_integration_with_output_times(method, opts):
    # released from rest, the motion is time-symmetric: theta(-t) = theta(t). Backward output
    # times used to return the initial state at every time (RK) or fail (Adams).
    free = _pendulum()
    t = np.linspace(0.0, 0.6, 7)
    fwd = free.simulate(t, method=method, **opts)
    bwd = free.simulate(-t, method=method, **opts)
    np.testing.assert_allclose(bwd.t, -t)
    assert np.ptp(bwd["bar.th"]) > 0.5
    np.testing.assert_allclose(bwd["bar.th"], fwd["bar.th"], atol=1e-6)


def test_simulate_default_is_projected_dop853():
    # decision 0005: the default is DOP853, rtol 1e-8, atol 1e-10, projection on
    sig = inspect.signature(FreeSystem.simulate)
    d = {k: v.default for k, v in sig.parameters.items()}
    assert d["method"] == "dop853" and d["constraint_correction"] is True
    assert d["rtol"] == 1e-8 and d["atol"] == 1e-10


def test_free_motion_page_code_runs():
    # the ```python blocks of docs/free_motion.md, in order, in one namespace
    text = (Path(__file__).resolve().parents[1] / "docs" / "free_motion.md").read_text()
    blocks = re.findall(r"^```python[ \t]*\n(.*?)^```[ \t]*$", text, re.M | re.S)
    assert len(blocks) >= 3
    ns: dict = {}
    for code in blocks:
        exec(compile(code, "docs/free_motion.md", "exec"), ns)  # noqa: S102
    assert abs(np.tan(ns["eq"]["bar.th"]) - (1 - 9.81 / 40)) < 1e-9
    assert np.ptp(ns["E"]) < 1e-6
    assert ns["mech"].extra["method"] == "adams"
