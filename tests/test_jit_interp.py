"""The compiled loops' own code run by the interpreter (solvers/_jit_interp.py, decision 0075):
the kinematic sweep's tier wherever its compiled loop is not loaded (decision 0081). Checked
against closed forms (the slider-crank's positions, velocities and accelerations, the
dead-centre crank's angle), against the compiled loop bit for bit (the same code: the same
numbers), and the C calls it makes through ctypes against SciPy."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import models
from mechsys.solvers import _jit_interp, _jit_modes, _jit_sweep

pytest.importorskip("numba")
pytestmark = pytest.mark.filterwarnings("ignore::mechsys.NearSingularWarning")


def _first_tier(monkeypatch, compiled_after: int | None = None, chunk: int = 7):
    """The sweep as in a first session: ``entry`` finds no machine code (being compiled in the
    background) for its first ``compiled_after`` requests (None: never), so the loop runs
    interpreted in chunks of ``chunk`` points; returns the list of requests made."""
    real = _jit_modes.entry
    asked = []

    def entry(dispatcher, args, literal=(), say=None):
        asked.append(dispatcher)
        if compiled_after is None or len(asked) <= compiled_after:
            return None
        return real(dispatcher, args, literal, say)

    monkeypatch.setattr(_jit_modes, "entry", entry)
    monkeypatch.setattr(_jit_sweep, "INTERP_CHUNK", chunk)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    return asked


def _slider_crank_exact(t, r=2.0, rod=6.0, w=2 * np.pi):
    """The piston's x, its velocity and acceleration, and the rod's angle, by SymPy from
    ``x = r cos(wt) + sqrt(l^2 - r^2 sin^2(wt))``."""
    s = sp.Symbol("t")
    x = r * sp.cos(w * s) + sp.sqrt(rod**2 - (r * sp.sin(w * s)) ** 2)
    phi = sp.asin(-r * sp.sin(w * s) / rod)
    f = sp.lambdify(s, [x, x.diff(s), x.diff(s, 2), phi, phi.diff(s), phi.diff(s, 2)], "numpy")
    return [np.asarray(v, dtype=float) * np.ones_like(t) for v in f(t)]


def test_interpreted_sweep_against_the_closed_form(monkeypatch):
    _first_tier(monkeypatch)
    t = np.linspace(0.0, 1.0, 40)
    m = models.slider_crank()
    sol = m.solve(t)
    assert sol.extra["compiled_points"] == 0           # (the interpreted loop took them all)
    x, v, a, phi, om, al = _slider_crank_exact(t)
    piston = m.body("piston").point(0)
    np.testing.assert_allclose(sol.location(piston)[:, 0], x, atol=1e-12)
    np.testing.assert_allclose(sol.velocity(piston)[:, 0], v, atol=1e-10)
    np.testing.assert_allclose(sol.acceleration(piston)[:, 0], a, atol=1e-8)
    np.testing.assert_allclose(sol.angle("rod"), phi, atol=1e-12)
    np.testing.assert_allclose(sol.omega("rod"), om, atol=1e-10)
    np.testing.assert_allclose(sol.alpha("rod"), al, atol=1e-8)
    # the condition estimates the loop left pending, computed by the interpreted fill
    assert np.all(np.isfinite(sol.extra["rcond"])) and np.all(sol.extra["rcond"] > 0)


@pytest.mark.parametrize("build", [models.slider_crank, models.four_bar])
def test_interpreted_then_compiled_equals_compiled_bit_for_bit(monkeypatch, build):
    """Three chunks interpreted, the rest compiled (the switch of a first session when the
    background compile ends): every number equals an all-compiled sweep's, bit for bit."""
    t = np.linspace(0.0, 1.0, 30)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    fast = build().solve(t)
    assert fast.extra["compiled_points"] == 30
    _first_tier(monkeypatch, compiled_after=3)
    mixed = build().solve(t)
    assert mixed.extra["compiled_points"] == 30 - 3 * 7
    for x, y in ((fast.q, mixed.q), (fast.qd, mixed.qd), (fast.qdd, mixed.qdd),
                 (fast.extra["rcond"], mixed.extra["rcond"])):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(fast.iterations, mixed.iterations)


def test_interpreted_through_dead_centres(monkeypatch):
    """Driven at the piston through both dead centres (near-singular points, the predictor's
    secant rules): the crank turns at 2 pi rad/s, and the numbers are the compiled loop's."""
    from test_jit_sweep import dead_centre_crank

    t = np.linspace(0.05, 1.05, 101)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    fast = dead_centre_crank().solve(t)
    _first_tier(monkeypatch)
    slow = dead_centre_crank().solve(t)
    np.testing.assert_allclose(slow.angle("crank"), 2 * np.pi * t, atol=1e-5)
    np.testing.assert_array_equal(slow.q, fast.q)
    np.testing.assert_array_equal(slow.qdd, fast.qdd)


def test_interpreted_loop_hands_over_like_the_compiled_one(monkeypatch):
    """A point the loop cannot take (Newton limited to one iteration) goes to the Python
    loop's handling, whose error names the time."""
    _first_tier(monkeypatch)
    with pytest.raises(ms.ConvergenceError, match="t = 0"):
        models.slider_crank().solve(np.linspace(0, 1, 20),
                                    options={"max_iterations": 1, "ftol": 1e-15})


def test_never_compiled_is_the_loop_interpreted(monkeypatch):
    """``MECHSYS_JIT=0`` (decision 0081): the loop interpreted, no Python point, the closed
    form's numbers; an ``auto`` job too small to load the compiled loop likewise unless it
    is loaded (then compiled): the same numbers bit for bit either way."""
    from mechsys.solvers import _jit_runtime

    t = np.linspace(0.0, 1.0, 40)       # (fine steps: no coarse-step check, decision 0035)
    monkeypatch.setenv("MECHSYS_JIT", "0")
    taken = _count_python_points(monkeypatch)
    m = models.slider_crank()
    sol = m.solve(t)
    assert sol.extra["compiled_points"] == 0 and taken == []
    x, v, a = _slider_crank_exact(t)[:3]
    piston = m.body("piston").point(0)
    np.testing.assert_allclose(sol.location(piston)[:, 0], x, atol=1e-12)
    np.testing.assert_allclose(sol.velocity(piston)[:, 0], v, atol=1e-10)
    np.testing.assert_allclose(sol.acceleration(piston)[:, 0], a, atol=1e-8)
    assert _jit_runtime.tier(12, 9) == "interpreted"
    monkeypatch.setenv("MECHSYS_JIT", "auto")
    monkeypatch.setitem(_jit_runtime._state, "interpreted", 0.0)   # (no small job before)
    assert _jit_runtime.tier(12, 9) == "loaded"
    assert _jit_runtime.tier(_jit_runtime.AUTO_POINTS, 9) == "load"
    assert _jit_runtime.tier(200, 63) == "load"        # (about 1 s interpreted)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    assert _jit_runtime.tier(12, 9) == "load"
    fast = m.solve(t)
    assert fast.extra["compiled_points"] == 40
    monkeypatch.setenv("MECHSYS_JIT", "auto")          # (loaded now: compiled)
    again = m.solve(t)
    assert again.extra["compiled_points"] == 40
    for X, Y, Z in ((sol.q, fast.q, again.q), (sol.qd, fast.qd, again.qd),
                    (sol.qdd, fast.qdd, again.qdd)):
        np.testing.assert_array_equal(X, Y)
        np.testing.assert_array_equal(X, Z)


def test_the_interpreted_function_is_the_loops_code():
    from mechsys.solvers._jit_lapack import getrf
    from mechsys.solvers._jit_sweep_loop import sweep_dense

    f = _jit_interp.interpreted(sweep_dense)
    assert f.__code__ is sweep_dense.py_func.__code__
    assert f.__globals__["_predict"].__code__ is sweep_dense.py_func.__globals__["_predict"].py_func.__code__
    assert _jit_interp.interpreted(f) is f and _jit_interp.interpreted(len) is len
    # a leaf of another module, with that module's globals
    g = f.__globals__["_factor"].__globals__["getrf"]
    assert g.__code__ is getrf.py_func.__code__
    A = np.array([[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 4.0]])
    AT, piv = A.T.copy(), np.zeros(3, dtype=np.int32)
    assert g(AT, 3, piv) == 0
    import scipy.linalg

    lu, ipiv, info = scipy.linalg.lapack.dgetrf(A)
    np.testing.assert_allclose(AT.T, lu, rtol=1e-15)
    np.testing.assert_array_equal(piv, ipiv)


def test_ctypes_calls_match_scipy():
    """The shims of the intrinsics: LAPACK's dgetrf by its C address (``_ccall``) and a
    kernel by its C entry point (``_kcall``) against SciPy and the kernel's Python call."""
    import scipy.linalg

    from mechsys.solvers._jit_runtime import lapack, pointer

    A = np.array([[4.0, 1.0, 2.0], [1.0, 3.0, 0.0], [2.0, 0.0, 5.0]])
    B = A.T.copy()                        # (column-major storage of A)
    ib = np.array([3, 3, 3, 0], dtype=np.int32)
    piv = np.zeros(3, dtype=np.int32)
    _jit_interp._ccall(lapack()[0], (ib[0:1], ib[1:2], B, ib[2:3], piv, ib[3:4]))
    lu, ipiv, info = scipy.linalg.lapack.dgetrf(A)
    assert ib[3] == info == 0
    np.testing.assert_array_equal(B.T, lu)
    np.testing.assert_array_equal(piv, ipiv + 1)     # (Fortran's 1-based pivots)
    s = models.slider_crank().compile()
    row = pointer(s.f_position)
    q = np.linspace(0.1, 0.9, s.n)
    packed = s.pack(0.3, q, None, None)
    x = np.concatenate([packed, np.zeros(max(int(row[4]), 0))])
    want = s.f_position(packed)
    out = np.zeros(1 + want.size)
    if row[2]:
        _jit_interp._kcall(row[2], x, packed.size, x, row[3])
    _jit_interp._kcall(row[0], out, 1, x, row[1])
    np.testing.assert_array_equal(out[1:], want)
    assert out[0] == 0.0                  # (the offset: nothing written before it)


def test_python_kernels_entry_point():
    """``_jit_runtime.python_entry``: a Python kernel called through its C entry point
    writes its outputs; an exception writes NaN (the loop then hands the point to the Python
    code, which raises it), an interrupt is kept for ``raise_callback_error``."""
    from mechsys.solvers import _jit_runtime

    class Kernel:
        nargs, nout = 3, 2

        def __init__(self, fail=None):
            self.fail = fail

        def __call__(self, x):
            if self.fail is not None:
                raise self.fail
            return np.array([x[0] * x[1], x[2] - x[0]])

    x = np.array([2.0, 3.0, 7.0])
    out = np.zeros(3)
    good = Kernel()
    row = _jit_runtime.python_entry(good)
    assert row[1:] == (0, 0, 0, 0) and _jit_runtime.python_entry(good) == row
    _jit_interp._kcall(row[0], out, 1, x, 0)
    np.testing.assert_array_equal(out, [0.0, 6.0, 5.0])
    for exc in (ValueError("domain"), KeyboardInterrupt()):
        bad = Kernel(exc)
        out[:] = 1.0
        _jit_interp._kcall(_jit_runtime.python_entry(bad)[0], out, 0, x, 0)
        assert np.isnan(out[:2]).all() and out[2] == 1.0
        if isinstance(exc, KeyboardInterrupt):
            with pytest.raises(KeyboardInterrupt):
                _jit_runtime.raise_callback_error()
        _jit_runtime.raise_callback_error()          # (nothing kept: no raise)
    assert _jit_runtime.python_entry(object()) is None


def _assert_power_balance(sol, t):
    """The drive's power equals the rate of the kinetic plus potential energy (central
    differences; an independent check of a dynamic solution's multipliers)."""
    energy = np.asarray(sol.body_energy(), dtype=float) + np.asarray(sol.potential_energy(),
                                                                     dtype=float)
    rate = np.gradient(energy, t)
    power = np.asarray(sol.power("drive"), dtype=float)
    scale = np.abs(power).max()
    np.testing.assert_allclose(power[1:-1], rate[1:-1], rtol=0, atol=5e-4 * scale)


def test_interpreted_multipliers_against_the_power_balance(monkeypatch):
    """The multiplier solves' first tier (the same loop interpreted): the drive's power equals
    the rate of the kinetic plus potential energy (central differences), and the
    multipliers are the compiled loop's bit for bit."""
    t = np.linspace(0.0, 1.0, 401)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    fast = models.slider_crank_dynamic().solve(t[:40], solution="dynamic")
    _first_tier(monkeypatch, chunk=256)
    slow = models.slider_crank_dynamic().solve(t, solution="dynamic")
    np.testing.assert_array_equal(slow.lam[:40], fast.lam)
    _assert_power_balance(slow, t)


def _count_python_points(monkeypatch):
    """The points the Python loop's per-point path takes (``_kinematics._solve_point``)."""
    from mechsys.solvers import _kinematics

    taken = []
    real = _kinematics._solve_point

    def solve_point(*args, **kwargs):
        taken.append(args[1])
        return real(*args, **kwargs)

    monkeypatch.setattr(_kinematics, "_solve_point", solve_point)
    return taken


def test_interpreted_above_the_old_limit(monkeypatch):
    """A four-bar chain of 10 loops (63 unknowns, above decision 0075's limit of 24 and
    within decision 0078's): the interpreted first tier takes every point, none is left to
    the Python loop, the loop equations hold at every point, and the numbers are the
    compiled loop's bit for bit."""
    t = np.linspace(0.0, 1.0, 8)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    fast = models.four_bar_chain(10).solve(t)
    assert fast.extra["compiled_points"] == 8
    _first_tier(monkeypatch)
    taken = _count_python_points(monkeypatch)
    m = models.four_bar_chain(10)
    slow = m.solve(t)
    assert slow.q.shape[1] == 63
    assert slow.extra["compiled_points"] == 0 and taken == []
    system = m.compile()
    for k in range(len(t)):
        assert np.abs(system.residual_and_jacobian(t[k], slow.q[k], system.p_values,
                                                   False)[0]).max() < 1e-10
    for x, y in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd),
                 (fast.extra["rcond"], slow.extra["rcond"])):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(fast.iterations, slow.iterations)


def test_interpreted_multipliers_above_the_old_limit(monkeypatch):
    """The inverse dynamics of the 63-unknown chain with masses under gravity, its multiplier
    solves interpreted (the Python multiplier solve never called): the drive's power equals
    the rate of the kinetic plus potential energy (central differences), and the
    multipliers are the compiled loop's bit for bit."""
    from mechsys.solvers import _jit_multipliers, _statics
    from test_jit_multipliers import loaded_chain

    t = np.linspace(0.0, 1.0, 201)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    fast = loaded_chain(10).solve(t[:12], solution="dynamic")
    real = _jit_modes.entry

    def entry(dispatcher, args, literal=(), say=None):
        if dispatcher is _jit_multipliers._state["multipliers"]:
            return None                  # (being compiled in the background)
        return real(dispatcher, args, literal, say)

    monkeypatch.setattr(_jit_modes, "entry", entry)

    def python_path(*args, **kwargs):
        raise AssertionError("the Python multiplier solve ran")

    monkeypatch.setattr(_statics, "solve_multipliers", python_path)
    slow = loaded_chain(10).solve(t, solution="dynamic")
    assert slow.q.shape[1] == 63
    np.testing.assert_array_equal(slow.lam[:12], fast.lam)
    _assert_power_balance(slow, t)


def test_a_large_first_sweep_takes_the_python_code_while_compiling(monkeypatch):
    """Above ``INTERP_WAIT_MAX`` (64) unknowns a first session's sweep takes the Python code
    while its loop compiles in the background (decision 0083: 10-30 x cheaper a point there
    than the interpreted loop), asking for the compiled loop again after each point; the loop
    equations hold at every point. ``MECHSYS_JIT=0`` interprets it instead (the loop's own
    code: no Python point)."""
    from mechsys.solvers import _jit_runtime

    t = np.linspace(0.0, 1.0, 6)
    asked = _first_tier(monkeypatch)
    taken = _count_python_points(monkeypatch)
    m = models.four_bar_chain(11)
    sol = m.solve(t)
    assert sol.q.shape[1] == 69 > _jit_runtime.INTERP_WAIT_MAX
    assert sol.extra["compiled_points"] == 0 and len(taken) == len(t)
    assert len(asked) >= len(t)              # (asked again after each Python point)
    system = m.compile()
    for k in range(len(t)):
        assert np.abs(system.residual_and_jacobian(t[k], sol.q[k], system.p_values,
                                                   False)[0]).max() < 1e-10
    taken.clear()
    monkeypatch.setenv("MECHSYS_JIT", "0")
    slow = models.four_bar_chain(11).solve(t)
    assert taken == [] and slow.extra["compiled_points"] == 0
    np.testing.assert_allclose(slow.q, sol.q, rtol=0, atol=1e-12)
