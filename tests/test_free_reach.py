r"""Free-motion jobs the loop now takes whole (decision 0084): kernels without C entry points
(``MECHSYS_BACKEND=sympy``: the loop calls their Python functions through ``ctypes``
callbacks, ``_jit_runtime.python_entry``), switched runs whose stages hold velocity rows
(the bordered kind ``ROLLING``), and the recursive Gen dynamics' multiplier solves after a
first ``MECHSYS_JIT=0`` solve in a fresh process.

Each run is checked against an independent reference: the double pendulum against its
Lagrange equations written out by hand (integrated by SciPy's DOP853 at 1e-13), the
Chaplygin sleigh after its blade touches down against its minimal equations
:math:`\dot u = a \omega^2`, :math:`(I + m a^2) \dot\omega = -m a u \omega` (by SciPy), and
the Gen arm's multipliers against :math:`\Phi_q^T \lambda = Q + Q_v - M \ddot q` solved by
NumPy; ``MECHSYS_JIT=0`` (the loop interpreted) and ``1`` (compiled) bit for bit.
"""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechsys as ms
from conftest import python_path, simulate_both
from mechsys import models
from mechsys.solvers import _jit_runtime
from mechsys.solvers._jit_free import FreeStepper
from test_jit_free import _minimal_ode

pytest.importorskip("numba")

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _sympy_pendulum(monkeypatch):
    """The double pendulum, released with both rods horizontal, with the SymPy backend's
    kernels (no C entry points)."""
    monkeypatch.setenv("MECHSYS_BACKEND", "sympy")
    m = models.pendulum_chain(2, 9.81)
    m.solve(0.0)
    free = m.free(drop=["lock0", "lock1"])
    assert free.system.f_position.backend == "sympy"
    assert _jit_runtime.pointer(free.system.f_position) is None     # no C entry point
    return free


GRID = np.linspace(0.0, 1.0, 21)


def test_sympy_backend_free_motion_runs_in_the_loop(monkeypatch):
    """Every step the loop's (compiled, and interpreted bit for bit), right by the double
    pendulum's own Lagrange equations, and the SymEngine backend's run to rounding."""
    free = _sympy_pendulum(monkeypatch)
    slow, fast = simulate_both(monkeypatch, free, GRID, rtol=1e-10, atol=1e-12)
    assert fast.extra["compiled_steps"] == fast.extra["steps"] > 20
    assert slow.extra["interpreted_steps"] == slow.extra["steps"]
    ref = _minimal_ode()(fast.t)   # (the hand-written Lagrange equations, test_jit_free)
    for k, name in enumerate(("l0.th", "l1.th")):
        np.testing.assert_allclose(fast[name], ref[k], rtol=0, atol=1e-8)
        np.testing.assert_allclose(fast.coordinate(name, 1), ref[2 + k], rtol=0, atol=1e-7)
    monkeypatch.setenv("MECHSYS_BACKEND", "symengine")
    m = models.pendulum_chain(2, 9.81)
    m.solve(0.0)
    other = m.free(drop=["lock0", "lock1"]).simulate(GRID, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(fast.q, other.q, rtol=0, atol=1e-12)


class _Boom(ValueError):
    """The error a user's kernel raises (in the tests below)."""


def _failing(kernel, exc, once=False):
    """Make ``kernel`` (a SymPy kernel: its argument vector starts with ``t``) raise ``exc``
    from ``t > 0.5`` on (``once``: at its first such call only)."""
    real, fired = kernel._f, []

    def f(x):
        if x[0] > 0.5 and not (once and fired):
            fired.append(x[0])
            raise exc(f"the kernel failed at t = {x[0]:.6g}")
        return real(x)

    kernel._f = f
    return fired


@pytest.mark.parametrize("jit", ["0", "1", "python"])
def test_an_error_inside_a_sympy_kernel_surfaces_as_itself(monkeypatch, jit):
    """The callback writes NaN, the loop hands the step over, the Python stepper evaluates
    the kernel and raises its error: the same exception as the Python path's."""
    free = _sympy_pendulum(monkeypatch)
    free.solve(0.0)
    fired = _failing(free.system.dynamics.free_kernel(False).f, _Boom)
    if jit == "python":
        python_path(monkeypatch)
    else:
        monkeypatch.setenv("MECHSYS_JIT", jit)
    with pytest.raises(_Boom, match="the kernel failed at t = 0.5"):
        free.simulate(GRID, rtol=1e-10, atol=1e-12)
    assert fired and min(fired) > 0.5


@pytest.mark.parametrize("jit", ["0", "1"])
def test_ctrl_c_inside_a_sympy_kernel_stops_the_run(monkeypatch, jit):
    """A ``KeyboardInterrupt`` raised once inside the kernel (Ctrl-C while the loop calls
    it) is kept by the callback and raised when the loop returns: the run ends as
    interrupted (decision 0039's solution so far) instead of going on past it."""
    free = _sympy_pendulum(monkeypatch)
    free.solve(0.0)
    _failing(free.system.dynamics.free_kernel(False).f, KeyboardInterrupt, once=True)
    monkeypatch.setenv("MECHSYS_JIT", jit)
    with pytest.warns(RuntimeWarning, match="interrupted at t = "):
        part = free.simulate(GRID, rtol=1e-10, atol=1e-12)
    assert part.extra["interrupted"] is True and part.t[-1] < 0.5
    assert _jit_runtime._state["callback_error"] is None


def test_sympy_backend_path_runs_in_the_loop(monkeypatch):
    """A nonholonomic path (``examples/caster.py``) with the SymPy backend: every step the
    loop's (``FreeStepper.plan_path``), the caster's angle by its closed form."""
    from conftest import load_example

    caster = load_example("caster")
    monkeypatch.setenv("MECHSYS_BACKEND", "sympy")
    path = caster.build()[1]
    assert _jit_runtime.pointer(path.system.f_position) is None
    t = np.linspace(0.0, 3.0, 31)
    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    assert sol.extra["compiled_steps"] == sol.extra["steps"] > 10
    np.testing.assert_allclose(sol["caster.th"], caster.closed_form(t), atol=1e-8)


# --- switched runs whose stages hold velocity rows ------------------------------------------
_sleigh = None


def _sleigh_module():
    from conftest import load_example

    global _sleigh
    if _sleigh is None:
        _sleigh = load_example("chaplygin_sleigh")
    return _sleigh


def _spy_rows_steps(monkeypatch) -> list:
    """``(velocity rows, steps)`` of every call of the loop's stepping."""
    got, real = [], FreeStepper.advance

    def advance(self, *a, **k):
        out = real(self, *a, **k)
        got.append((self.kv, len(out[1])))
        return out

    monkeypatch.setattr(FreeStepper, "advance", advance)
    return got


def test_switched_stage_with_velocity_rows_runs_in_the_loop(monkeypatch):
    """The Chaplygin sleigh slides freely, its blade touches down at t = 1 (a TimeSwitch,
    the plastic impulse of ``at_switch="project"``): the stage with the blade's velocity
    row runs in the loop (compiled, and interpreted bit for bit), and after the impact the
    motion is the sleigh's minimal equations' (SciPy)."""
    ex = _sleigh_module()
    mass, inertia, a = ex.MASS, ex.INERTIA, ex.OFFSET
    J = inertia + mass * a**2
    m = ms.Model2D()
    b = m.add_body("sleigh", points={"P": (-a, 0.0)}, guess=ex.START, mass=mass,
                   inertia=inertia)
    v = m.velocity(b.point("P"))
    m.add(ms.TimeSwitch(ms.Orthogonal1(v, b.vector((0, 1))), 1.0,
                        ms.Orthogonal1(v, b.vector((0, 1)))), name="edge")
    fs = m.free(drop=[("edge", 1)])
    t = np.linspace(0.0, 3.0, 31)
    ic = {"sleigh.x_d": 0.5, "sleigh.y_d": 0.8, "sleigh.th_d": 1.0}
    taken = _spy_rows_steps(monkeypatch)
    slow, sol = simulate_both(monkeypatch, fs, t, initial_condition=ic, at_switch="project",
                              rtol=1e-11, atol=1e-13)
    # every step the loop's, those after the touch-down with the blade's row (half of the
    # loop's calls are the interpreted run's)
    assert sol.extra["compiled_steps"] == sol.extra["steps"] > 0
    rolled = sum(s for k, s in taken if k == 1)
    assert rolled >= 8 and rolled % 2 == 0
    (ev,) = sol.extra["events"]
    after = t >= 1.0
    e1 = np.c_[np.cos(sol["sleigh.th"]), np.sin(sol["sleigh.th"])]
    u = np.sum(sol.qd[:, :2] * e1, axis=1)
    k = int(np.argmax(after))

    def minimal(_t, s):
        x, y, th, uu, w = s
        c, sn = np.cos(th), np.sin(th)
        return [uu * c - a * w * sn, uu * sn + a * w * c, w, a * w * w, -mass * a * uu * w / J]

    start = [*sol.q[k], u[k], sol.qd[k, 2]]
    ref = solve_ivp(minimal, (1.0, 3.0), start, t_eval=t[after], rtol=1e-12, atol=1e-14,
                    method="DOP853").y.T
    assert np.abs(sol.q[after] - ref[:, :3]).max() < 1e-9
    assert np.abs(u[after] - ref[:, 3]).max() < 1e-9
    assert np.abs(sol.qd[after, 2] - ref[:, 4]).max() < 1e-9
    # the row holds: no slip of P across the blade
    e2 = np.c_[-np.sin(sol["sleigh.th"]), np.cos(sol["sleigh.th"])]
    slip = np.sum(sol.qd[after, :2] * e2[after], axis=1) - a * sol.qd[after, 2]
    assert np.abs(slip).max() < 1e-12
    assert ev["energy_lost"] > 0


# --- the recursive Gen dynamics after a first MECHSYS_JIT=0 solve ---------------------------
_FIRST_SOLVE = r"""
import json, os
import numpy as np
from mechsys import models
from mechsys.solvers import _jit_multipliers, _statics
taken = []
real = _jit_multipliers.multipliers
def spy(*a, **k):
    taken.append(int(real(*a, **k)))
    return taken[-1]
_statics._jit_multipliers.multipliers = spy
out = []
for jit in ("0", "1", "0"):
    os.environ["MECHSYS_JIT"] = jit
    sol = models.driven_gen_arm(8).solve(np.linspace(0.0, 1.0, 5), solution="dynamic")
    assert getattr(sol.system.dynamics, "recursive", False)
    out.append(sol.lam.tolist())
print(json.dumps({"taken": taken, "lam": out}))
"""


def test_recursive_gen_multipliers_in_the_loop_after_a_first_interpreted_solve():
    """In a fresh process whose first solve runs under ``MECHSYS_JIT=0``, the recursive Gen
    arm's multiplier solves are the loop's at every point (interpreted, then compiled, then
    interpreted again), bit for bit across the tiers."""
    import json

    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "MECHSYS_COMPILE": "wait"}
    got = subprocess.run([sys.executable, "-c", _FIRST_SOLVE], env=env, capture_output=True,
                         text=True, timeout=600)
    assert got.returncode == 0, got.stderr
    res = json.loads(got.stdout.strip().splitlines()[-1])
    assert res["taken"] == [5, 5, 5]
    lam = [np.array(x) for x in res["lam"]]
    np.testing.assert_array_equal(lam[0], lam[1])
    np.testing.assert_array_equal(lam[0], lam[2])
    # the balance Phi_q^T lambda = Q + Qv - M qdd at each point (NumPy)
    from _sweep_reference import check_multipliers

    monkey = models.driven_gen_arm(8).solve(np.linspace(0.0, 1.0, 5), solution="dynamic")
    np.testing.assert_array_equal(monkey.lam, lam[1])
    check_multipliers(monkey, "dynamic")


def test_recursive_gen_dynamics_with_the_sympy_backend(monkeypatch):
    """The recursive Gen dynamics built with the SymPy backend: its joint kernels' body terms
    come in plain symbols while the model's coordinates are real ones (SymPy tells them
    apart: the kernel once failed with ``NameError: th2``). The multipliers balance the loads
    and equal the SymEngine build's; the multiplier loop takes every point through the
    kernels' Python entries."""
    from _sweep_reference import check_multipliers
    from test_jit_multipliers import spy_multipliers

    t = np.linspace(0.0, 1.0, 9)
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")
    monkeypatch.setenv("MECHSYS_BACKEND", "symengine")
    ref = models.driven_gen_arm(3).solve(t, solution="dynamic")
    monkeypatch.setenv("MECHSYS_BACKEND", "sympy")
    taken = spy_multipliers(monkeypatch)
    m = models.driven_gen_arm(3)
    assert getattr(m.compile().dynamics, "recursive", False)
    sol = m.solve(t, solution="dynamic")
    assert taken == [len(t)]
    check_multipliers(sol)
    scale = np.maximum(1.0, np.abs(ref.lam).max())
    assert np.abs(sol.lam - ref.lam).max() / scale <= 1e-12


def test_friction_whose_load_derivatives_have_a_first_stage_runs_in_the_loop(monkeypatch, tmp_path):
    """Joint friction (loads that depend on the multipliers) whose ``dQ/dlambda`` kernel is
    large enough to compile in two stages (above ``STAGE_TRIG`` outputs: a 128-link chain's;
    here the threshold is lowered so that a 4-link chain's are): the Newton kind runs in the
    loop (it once refused any first stage of those kernels and sent the run to the Python
    stepper whole), interpreted and compiled give the same bits, and the motion is the
    one-stage build's to the integration tolerance."""
    from mechsys.compile import _backends
    from mechsys.solvers import _jit_free

    def chain():
        m = models.pendulum_chain(4)
        for k in range(4):
            m.add_load(ms.JointFriction(f"j{k}", mu=0.1, radius=0.01, v_eps=1e-3))
        m.solve(0.0)
        return m.free(drop=[f"lock{k}" for k in range(4)])

    span = dict(rtol=1e-9, atol=1e-11)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    ref = chain().simulate((0.0, 0.3), **span)
    monkeypatch.setenv("MECHSYS_CACHE", str(tmp_path))
    monkeypatch.setattr(_backends, "LARGE_KERNEL", 10)
    monkeypatch.setattr(_backends, "STAGE_TRIG", 10)
    free = chain()
    entry = _jit_free.kernel_entry(free.system.dynamics.f_dQ_dlam)
    assert entry is not None and entry[0][2] != 0        # a first stage
    slow, fast = simulate_both(monkeypatch, free, (0.0, 0.3), **span)
    assert fast.extra["compiled_solver"] == "newton"
    assert fast.extra["compiled_steps"] == fast.extra["steps"]
    assert slow.extra["interpreted_steps"] == slow.extra["steps"]
    np.testing.assert_allclose(fast.q[-1], ref.q[-1], rtol=0, atol=1e-7)
    np.testing.assert_allclose(fast.qd[-1], ref.qd[-1], rtol=0, atol=1e-6)


def test_a_first_use_kernel_llvm_refuses_is_called_through_its_python_entry(monkeypatch,
                                                                             tmp_path):
    """A first-use kernel (the Gen joints' kernels) whose LLVM compile is refused keeps its
    interpreted SymEngine function; the compiled loops then call it through a C entry point
    made of that function (``python_entry``), as a SymPy-backend kernel, instead of leaving
    the whole run to the Python code."""
    import sympy as sp

    from mechsys.compile import _backends
    from mechsys.solvers._jit_interp import _kcall

    monkeypatch.setenv("MECHSYS_CACHE", str(tmp_path))
    a, b = sp.symbols("a b")
    k = _backends.compile_exprs([a, b], [sp.sin(a) * b, a + b**2], first_use=True)
    real = _backends._SymengineCompiled

    def refusing(*args, mode=None, **kw):
        if mode is None:
            raise RuntimeError("LLVM refused this kernel (test)")
        return real(*args, mode=mode, **kw)

    monkeypatch.setattr(_backends, "_SymengineCompiled", refusing)
    assert k.c_entry() is None                     # LLVM refused: no machine code
    row, expand = _jit_runtime.kernel_entry(k)
    assert len(expand) == 0
    out, x = np.full(2, np.nan), np.array([0.3, 2.0])
    _kcall(int(row[0]), out, 0, x, 0)
    np.testing.assert_allclose(out, [np.sin(0.3) * 2.0, 0.3 + 4.0], rtol=1e-15)


def test_compiled_calls_are_sized_by_their_time():
    """A compiled call of a stepping loop takes about ``CALL_SECONDS`` of work: the first
    call of a large system a few steps (not 2000 steps of 16 ms: half a minute without
    progress or Ctrl-C), a small system's the full chunk; the later calls the steps that fit
    at the measured rate, within the chunk."""
    import types

    from mechsys.solvers import _jit_free

    budget, rate = _jit_free.FreeStepper.budget, _jit_free.FreeStepper._rate
    big = types.SimpleNamespace(_call_steps={}, n=3072, nl=2048)      # the 1024-link chain
    small = types.SimpleNamespace(_call_steps={}, n=6, nl=4)          # the double pendulum
    assert budget(big, "loop", 2000) == _jit_free.CALL_MIN_STEPS
    assert budget(small, "loop", 2000) == 2000
    rate(big, "loop", 16, 0.08)                     # 5 ms a step
    assert budget(big, "loop", 2000) == int(_jit_free.CALL_SECONDS * 16 / 0.08)
    rate(big, "loop", 0, 0.01)                      # (a hand-over before any step: no rate)
    assert budget(big, "loop", 2000) == int(_jit_free.CALL_SECONDS * 16 / 0.08)
    rate(small, "adams", 20000, 0.02)
    assert budget(small, "adams", 20000) == 20000   # (at most the chunk)
    rate(big, "loop", 1, 10.0)                      # a very slow step: still a few steps
    assert budget(big, "loop", 2000) == _jit_free.CALL_MIN_STEPS


@pytest.mark.parametrize("options", [{"rtol": 1e-8, "atol": 1e-8},
                                     {"method": "adams", "max_error": 1e-6}])
def test_a_run_cut_into_many_compiled_calls_is_the_run_in_one(monkeypatch, options):
    """Each compiled call resumes the run from the state the last one left (the solver's
    time, step, state and derivative; Adams' history), so the chunks change no number: a run
    cut into calls of 7 steps is the run of whole chunks, bit for bit."""
    from mechsys.solvers import _jit_free

    m = models.pendulum_chain(2)
    m.solve(0.0)
    free = m.free(drop=["lock0", "lock1"])
    whole = free.simulate((0.0, 3.0), **options)
    calls = []

    def seven(self, name, cap):
        calls.append(name)
        return 7

    monkeypatch.setattr(_jit_free.FreeStepper, "budget", seven)
    cut = free.simulate((0.0, 3.0), **options)
    assert whole.extra["compiled_steps"] == whole.extra["steps"] == cut.extra["compiled_steps"]
    assert len(calls) >= whole.extra["steps"] // 7
    for name in ("t", "q", "qd", "qdd", "lam"):
        np.testing.assert_array_equal(getattr(cut, name), getattr(whole, name), err_msg=name)
