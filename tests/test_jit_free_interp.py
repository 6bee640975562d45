"""The free-motion stepper's first tier (decision 0077): while its compiled loop is compiled
in the background, the loop's own code runs interpreted (solvers/_jit_interp.py), in chunks
of ``INTERP_STEPS`` steps, and the compiled loop takes the next chunk once its machine code
is at hand. Checked against an independent ODE (the double pendulum's two-angle Lagrange
equations, by SymPy), and against the compiled loop bit for bit (the same code: the same
numbers), all-interpreted and interpreted-then-compiled; the Python path takes no regular
step (``sol.extra["interpreted_steps"]``)."""

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
    """All-interpreted, and three interpreted chunks of four steps then compiled (the switch
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
    mixed = double_pendulum.simulate((0.0, 1.0), **kw)
    assert slow.extra["interpreted_steps"] == slow.extra["steps"]
    assert mixed.extra["interpreted_steps"] == 3 * 4
    assert mixed.extra["compiled_steps"] == mixed.extra["steps"] - 3 * 4
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


def test_a_large_system_keeps_the_python_path(monkeypatch):
    """Above ``INTERP_MAX`` unknowns the Python path takes the steps meanwhile (the
    interpreted loop's cost grows as the cube of the size)."""
    from test_free_motion import double_pendulum_model

    monkeypatch.setenv("MECHSYS_JIT", "1")
    free = double_pendulum_model()[1]
    monkeypatch.setattr(_jit_free, "INTERP_MAX", 9)        # (the pendulum has 6 + 4)
    _first_tier(monkeypatch)
    sol = free.simulate((0.0, 0.2), rtol=1e-8, atol=1e-8)
    assert sol.extra["interpreted_steps"] == sol.extra["compiled_steps"] == 0
    assert sol.extra["steps"] > 0
