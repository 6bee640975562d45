"""Event location of free motion through stage changes (``analyses._free_switch``): the
root finder on the dense output (``_bracket``), the compiled steps' dense output
(``StepDense``) and the step with an event taken compiled (``FreeStepper.step_again``)."""

import importlib.util
import os
import pathlib

import numpy as np
import pytest
from scipy.integrate import DOP853, RK45

from conftest import python_path, same_bits
from mechsys.analyses._free_switch import SwitchedFreeSystem, _Events
from mechsys.compile._stages import stage_system
from mechsys.solvers._jit_free import StepDense
from mechsys.solvers._jit_free_loop import DOP853 as DOP853_CODE
from mechsys.solvers._jit_free_loop import RK45 as RK45_CODE

_spec = importlib.util.spec_from_file_location(
    "latching_pendulum", pathlib.Path(__file__).parents[1] / "examples" / "latching_pendulum.py")
lp = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(lp)
EPS = np.finfo(float).eps


@pytest.mark.parametrize("cls,code", [(DOP853, DOP853_CODE), (RK45, RK45_CODE)])
def test_step_dense_is_scipys_dense_output(cls, code):
    # the same coefficients as SciPy's dense output of a step: the same polynomial
    def f(t, y):
        return np.array([y[1], -np.sin(y[0]) + 0.3 * np.cos(2 * t)])

    s = cls(f, 0.0, np.array([1.0, 0.2]), 10.0, rtol=1e-6, atol=1e-9)
    s.step()
    s.step()
    do = s.dense_output()
    F = do.Q.T if cls is RK45 else do.F
    FD = np.zeros((8, 2))
    FD[:len(F)] = F
    FD[7] = do.y_old
    dense = StepDense(do.t_old, do.t, FD, code)
    for t in np.linspace(do.t_old, do.t, 9):
        np.testing.assert_allclose(dense(t), do(t), rtol=0, atol=4 * EPS)
    np.testing.assert_array_equal(dense(do.t_old), do.y_old)


class _Counting:
    """The latching pendulum's event relations (``rod.th > -beta``), counting evaluations."""

    def __init__(self):
        m = lp.build()
        self.events = _Events(m, stage_system(m, None))
        self.calls = 0

    def phi(self, *args):
        self.calls += 1
        return self.events.phi(*args)


def _state(th):
    # the rod's state (x, y, th, xd, yd, thd); only the angle matters to the relation
    return np.array([0.0, 0.0, th, 0.0, 0.0, 0.0])


def test_bracket_finds_a_crossing_to_a_few_ulps_in_few_evaluations():
    ev = _Counting()
    p = np.zeros(0)
    # th(t) = -beta + 0.3 cos(5 t): on the near side (above -beta) until t = pi/10
    def dense(t):
        return _state(-lp.BETA + 0.3 * np.cos(5 * t))

    i, b, a, s0 = SwitchedFreeSystem._bracket(ev, dense, p, 0, 0.2, 0.45, 1.0)
    assert b - a <= 4 * EPS * b and abs(b - np.pi / 10) < 1e-14
    assert ev.events(b, dense(b), p)[0] == -1.0       # b strictly on the far side
    assert ev.events(a, dense(a), p)[0] != -1.0       # a not
    assert ev.calls <= 16                            # bisection took about 50


def test_bracket_after_a_rebound_finds_the_return_not_the_start():
    # a restart on the stop after a rebound: the start is (by rounding) on the far side, the
    # motion dips to the near side and comes back at t = 0.01; the event is the return
    ev = _Counting()
    p = np.zeros(0)

    def dense(t):
        return _state(-lp.BETA - 1e-14 + t * (0.01 - t))

    assert ev.phi(0.0, dense(0.0), p, 0, 1.0) > 0
    i, b, a, s0 = SwitchedFreeSystem._bracket(ev, dense, p, 0, 0.0, 0.05, 1.0)
    assert b - a <= 4 * EPS * b and abs(b - 0.01) < 1e-11
    assert ev.events(b, dense(b), p)[0] == -1.0 and ev.events(a, dense(a), p)[0] != -1.0


@pytest.mark.parametrize("method", ["dop853", "rk45"])
def test_compiled_runs_take_the_event_steps_compiled_with_the_same_events(method):
    m = lp.build()
    m.solve(0.0, solution="location")
    fs = m.free(drop=[("latch", 1)])
    out = {}
    for mode in ("0", "1"):
        os.environ["MECHSYS_JIT"] = mode
        try:
            out[mode] = fs.simulate((0.0, 2.0), at_switch=("restitution", 0.5), rtol=1e-10,
                                    atol=1e-12, method=method)
        finally:
            os.environ.pop("MECHSYS_JIT", None)
    slow, jit = out["0"], out["1"]
    # every step compiled, the steps with an event too (taken again with their dense output);
    # interpreted (MECHSYS_JIT=0, decision 0082) the same steps, events and numbers
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 20
    assert slow.extra["compiled_steps"] == 0
    assert slow.extra["interpreted_steps"] == jit.extra["compiled_steps"]
    assert len(jit.extra["events"]) == len(slow.extra["events"]) > 10
    assert [e["t"] for e in slow.extra["events"]] == [e["t"] for e in jit.extra["events"]]
    same_bits(slow, jit)


def test_compiled_outputs_keep_the_loops_accelerations_and_multipliers(monkeypatch):
    """The solution's accelerations and multipliers at the rows the compiled loop produced
    are the loop's own (computed at the same states): the assembly evaluates only the other
    rows (events, steps taken in Python), and the numbers equal the Python path's."""
    from mechsys.analyses import _free_switch

    calls = []
    real = _free_switch.free_acceleration

    def counting(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(_free_switch, "free_acceleration", counting)
    m = lp.build()
    m.solve(0.0, solution="location")
    fs = m.free(drop=[("latch", 1)])
    t = np.linspace(0.0, 1.2, 241)
    out = {}
    for mode in ("1", "python"):
        if mode == "python":
            python_path(monkeypatch)       # (the Python stepper whole: it evaluates every row)
        else:
            monkeypatch.setenv("MECHSYS_JIT", mode)
        calls.clear()
        out[mode] = (fs.simulate(t, at_switch=("restitution", 0.5), rtol=1e-10, atol=1e-12),
                     len(calls))
    (py, n_py), (jit, n_jit) = out["python"], out["1"]
    assert n_jit < 0.2 * len(t) < n_py
    np.testing.assert_allclose(jit.qdd, py.qdd, rtol=0, atol=1e-8 * np.abs(py.qdd).max())
    np.testing.assert_allclose(jit.lam, py.lam, rtol=0, atol=1e-8 * np.abs(py.lam).max())
