"""The free-motion stepper's first tier (decisions 0077, 0082): while its compiled loop is
compiled in the background, the loop's own code runs interpreted (solvers/_jit_interp.py) at
any size, in calls bounded by about ``INTERP_SECONDS`` of work (``INTERP_STEPS`` steps
scaled to the size on the first), and the compiled loop takes the next call once its machine
code is at hand; with ``MECHSYS_JIT=0`` the loops run interpreted every step. Checked
against an independent ODE (the double pendulum's two-angle Lagrange equations, by SymPy),
and against the compiled loop bit for bit (the same code: the same numbers),
all-interpreted and interpreted-then-compiled; the Python path takes no regular step
(``sol.extra["interpreted_steps"]``)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mechsys.solvers import _jit_free, _jit_modes

pytest.importorskip("numba")


def _first_tier(monkeypatch, compiled_after: int | None = None, steps: int = 4):
    """A first session: ``entry`` finds no machine code (being compiled in the background)
    until the stepping loop has been asked for ``compiled_after`` times (None: never), so
    the loops run interpreted, ``steps`` steps a call; returns the list of requests made."""
    real = _jit_modes.entry
    asked = []

    def entry(dispatcher, args, literal=(), say=None):
        name = dispatcher.py_func.__name__
        asked.append(name)
        loops = sum(a in ("runge_kutta", "adams") for a in asked)
        if compiled_after is None or loops < compiled_after + (name in ("runge_kutta", "adams")):
            return None
        return real(dispatcher, args, literal, say)

    monkeypatch.setattr(_jit_modes, "entry", entry)
    monkeypatch.setattr(_jit_free, "INTERP_STEPS", {"loop": steps, "adams": steps})
    return asked


@pytest.fixture
def double_pendulum(monkeypatch):
    from test_free_motion import double_pendulum_model

    monkeypatch.setenv("MECHSYS_JIT", "1")
    return double_pendulum_model()[1]


def test_interpreted_free_motion_against_the_minimal_ode(monkeypatch, double_pendulum):
    from test_free_motion import minimal_double_pendulum

    asked = _first_tier(monkeypatch)
    t = np.linspace(0.0, 1.5, 31)
    sol = double_pendulum.simulate(t, rtol=1e-11, atol=1e-12)
    # every step the interpreted loop's, none the Python path's
    assert sol.extra["interpreted_steps"] == sol.extra["steps"] > 10
    assert sol.extra["compiled_steps"] == 0 and "runge_kutta" in asked
    ref = solve_ivp(minimal_double_pendulum(), (0, 1.5), [0, 0, 0, 0], method="DOP853",
                    rtol=1e-12, atol=1e-13, t_eval=t)
    np.testing.assert_allclose(sol["a.th"], ref.y[0], atol=1e-8)
    np.testing.assert_allclose(sol["b.th"], ref.y[1], atol=1e-8)
    np.testing.assert_allclose(sol.coordinate("a.th", 1), ref.y[2], atol=1e-7)
    np.testing.assert_allclose(sol.coordinate("b.th", 1), ref.y[3], atol=1e-7)


@pytest.mark.parametrize("method", ["dop853", "rk45"])
def test_interpreted_then_compiled_equals_compiled_bit_for_bit(monkeypatch, double_pendulum,
                                                               method):
    """All-interpreted, and three interpreted calls (four steps, then one each) then compiled (the switch
    of a first session when the background compile ends): positions, velocities,
    accelerations and multipliers equal an all-compiled run's, bit for bit."""
    kw = dict(rtol=1e-9, atol=1e-9, method=method)
    fast = double_pendulum.simulate((0.0, 1.0), **kw)
    assert fast.extra["compiled_steps"] == fast.extra["steps"]
    # (the accelerations of the first row: the derivative, asked once per stepper)
    _first_tier(monkeypatch)
    slow = double_pendulum.simulate((0.0, 1.0), **kw)
    monkeypatch.undo()
    monkeypatch.setenv("MECHSYS_JIT", "1")
    _first_tier(monkeypatch, compiled_after=3)
    monkeypatch.setattr(_jit_free, "INTERP_SECONDS", 0.0)     # (one step a call after the first)
    mixed = double_pendulum.simulate((0.0, 1.0), **kw)
    assert slow.extra["interpreted_steps"] == slow.extra["steps"]
    # (three interpreted calls: four steps, then as many as fit in INTERP_SECONDS: one)
    assert mixed.extra["interpreted_steps"] == 4 + 1 + 1
    assert mixed.extra["compiled_steps"] == mixed.extra["steps"] - mixed.extra["interpreted_steps"]
    for other in (slow, mixed):
        for key in ("t", "q", "qd", "qdd", "lam"):
            assert np.array_equal(getattr(fast, key), getattr(other, key)), key


def test_adams_keeps_the_python_path_and_its_loop_interprets_bit_for_bit(monkeypatch,
                                                                         double_pendulum):
    """Mech's Adams integrator is not in ``INTERP_LOOPS`` (its interpreted steps cost 2.7 x
    the Python path's): its Python path takes the steps meanwhile. Its loop, interpreted,
    gives the compiled loop's numbers bit for bit all the same (the tier, when enabled)."""
    kw = dict(method="adams", max_error=1e-6)
    fast = double_pendulum.simulate((0.0, 0.5), **kw)
    assert fast.extra["compiled_steps"] == fast.extra["steps"]
    _first_tier(monkeypatch)
    python = double_pendulum.simulate((0.0, 0.5), **kw)
    assert python.extra["interpreted_steps"] == python.extra["compiled_steps"] == 0
    np.testing.assert_allclose(python.q, fast.q, atol=1e-12)
    monkeypatch.setattr(_jit_free, "INTERP_LOOPS", _jit_free.INTERP_LOOPS | {"adams"})
    slow = double_pendulum.simulate((0.0, 0.5), **kw)
    assert slow.extra["interpreted_steps"] == slow.extra["steps"]
    for key in ("t", "q", "qd", "qdd", "lam"):
        assert np.array_equal(getattr(fast, key), getattr(slow, key)), key


def test_a_large_system_runs_interpreted_in_calls_bounded_by_work(monkeypatch):
    """Above ``INTERP_WAIT_MAX`` (12) unknowns a first session's run takes the Python path
    while the loop compiles (decision 0083: cheaper there); with the limit raised the loop
    runs interpreted (as ``MECHSYS_JIT=0`` does at any size): the first call takes
    ``INTERP_STEPS`` scaled to the size (3 links: 15 unknowns, 4 * 12 // 15 = 3 steps), the
    later ones the steps that fit in ``INTERP_SECONDS`` (here 0: one each), so the compiled
    loop is asked for again after every bounded piece of work. The numbers are the compiled
    loop's bit for bit, and the energy is kept (an independent check)."""
    from mechsys import models

    monkeypatch.setenv("MECHSYS_JIT", "1")
    m = models.pendulum_chain(3, 9.81)
    m.solve(0.0)
    free = m.free(drop=["lock0", "lock1", "lock2"])
    assert free.system.n + free.system.m == 15
    kw = dict(rtol=1e-9, atol=1e-9)
    fast = free.simulate((0.0, 0.5), **kw)
    assert fast.extra["compiled_steps"] == fast.extra["steps"]
    asked = _first_tier(monkeypatch)
    python = free.simulate((0.0, 0.5), **kw)
    assert python.extra["interpreted_steps"] == python.extra["compiled_steps"] == 0
    assert np.abs(python.q[-1] - fast.q[-1]).max() < 1e-6
    asked.clear()
    monkeypatch.setattr(_jit_free, "INTERP_WAIT_MAX", 64)
    monkeypatch.setattr(_jit_free, "INTERP_SECONDS", 0.0)
    slow = free.simulate((0.0, 0.5), **kw)
    assert slow.extra["interpreted_steps"] == slow.extra["steps"] > 10
    assert asked.count("runge_kutta") == slow.extra["steps"] - 3 + 1
    for key in ("t", "q", "qd", "qdd", "lam"):
        assert np.array_equal(getattr(fast, key), getattr(slow, key)), key
    energy = slow.body_energy() + slow.potential_energy()
    assert np.abs(energy - energy[0]).max() < 1e-6 * max(1.0, np.abs(energy).max())


@pytest.mark.parametrize("kw", [dict(rtol=1e-9, atol=1e-9),
                                dict(method="adams", max_error=1e-6)], ids=["dop853", "adams"])
def test_jit_off_runs_the_loop_interpreted(monkeypatch, double_pendulum, kw):
    """``MECHSYS_JIT=0`` (decision 0082): nothing compiled, every step the loop's own code
    interpreted (Adams too), the compiled loop's numbers bit for bit."""
    from mechsys.solvers import _jit_modes as modes

    fast = double_pendulum.simulate((0.0, 0.5), **kw)
    assert fast.extra["compiled_steps"] == fast.extra["steps"]
    monkeypatch.setenv("MECHSYS_JIT", "0")
    monkeypatch.setattr(modes, "entry", None)          # (never asked for machine code)
    slow = double_pendulum.simulate((0.0, 0.5), **kw)
    assert slow.extra["interpreted_steps"] == slow.extra["steps"] > 10
    assert slow.extra["compiled_steps"] == 0
    for key in ("t", "q", "qd", "qdd", "lam"):
        assert np.array_equal(getattr(fast, key), getattr(slow, key)), key


def test_jit_off_with_a_refused_cache_takes_the_python_path(monkeypatch, double_pendulum):
    """``MECHSYS_JIT=0`` is the way around a Numba cache refused as unsafe (the
    ``CacheError`` raised when the loops' module is imported says so): the stepper is then
    not planned and the Python path takes the run, instead of the error."""
    import importlib.abc
    import sys

    import mechsys.solvers as solvers
    from mechsys import CacheError

    name = "mechsys.solvers._jit_free_loop"

    class Refuse(importlib.abc.MetaPathFinder):
        def find_spec(self, fullname, path=None, target=None):
            if fullname == name:
                raise CacheError("the cache directory is writable by others (test)")
            return None

    monkeypatch.delitem(sys.modules, name)
    monkeypatch.delattr(solvers, "_jit_free_loop")
    monkeypatch.setattr(sys, "meta_path", [Refuse(), *sys.meta_path])
    monkeypatch.setenv("MECHSYS_JIT", "0")
    sol = double_pendulum.simulate((0.0, 0.3))
    assert sol.extra["compiled_solver"] is None
    assert sol.extra["interpreted_steps"] == sol.extra["compiled_steps"] == 0
    assert sol.extra["steps"] > 0
