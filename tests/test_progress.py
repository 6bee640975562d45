"""Progress reporting keeps the compiled loops (decision 0039): a sweep with a progress bar or
callback runs the compiled loop in chunks, with the same numbers as one uninterrupted call;
``mechsys run`` reaches the compiled loop; a KeyboardInterrupt raised by the callback (as
Ctrl-C) stops the run with the points solved so far, or a clear error when there are none."""

from __future__ import annotations

import io
import pathlib
import sys

import numpy as np
import pytest

import mechsys as ms
from mechsys import models
from mechsys.solvers import _jit_sweep
from mechsys.solvers import _kinematics as kin

pytest.importorskip("numba")
pytestmark = pytest.mark.filterwarnings("ignore::mechsys.NearSingularWarning")

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _spy_runs(monkeypatch):
    """Record every call of the compiled sweep loop: (first point, points given, returned k)."""
    calls = []
    real = _jit_sweep.run

    def spy(system, pointers, times, *rest, **kw):
        out = real(system, pointers, times, *rest, **kw)
        calls.append((rest[-2], len(times), out[0]))
        return out

    monkeypatch.setattr(_jit_sweep, "run", spy)
    return calls


def _identical(a, b):
    assert ("rcond" in a.extra) == ("rcond" in b.extra)
    pairs = [(a.q, b.q), (a.qd, b.qd), (a.qdd, b.qdd)]
    if "rcond" in a.extra:
        pairs.append((a.extra["rcond"], b.extra["rcond"]))
    for x, y in pairs:
        assert (x is None) == (y is None)
        if x is not None:
            np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(a.iterations, b.iterations)
    assert a.evaluations == b.evaluations


@pytest.mark.parametrize("build,solution", [(models.slider_crank, "acceleration"),
                                            (models.four_bar, "velocity"),
                                            (models.slider_crank_3d, "location")])
def test_progress_keeps_the_compiled_loop_and_its_numbers(monkeypatch, build, solution):
    monkeypatch.setenv("MECHSYS_JIT", "1")
    t = np.linspace(0.0, 2.0, 1500)
    plain = build().solve(t, solution=solution)
    assert plain.extra["compiled_points"] == len(t)
    # tiny chunks: every chunk boundary (chord rebuilt, predictor history) is exercised
    monkeypatch.setattr(kin, "CHUNK_SECONDS", 1e-7)
    calls = _spy_runs(monkeypatch)
    seen = []
    sol = build().solve(t, solution=solution, progress=lambda done, total: seen.append((done, total)))
    assert sol.extra["compiled_points"] == len(t)        # no point left to the Python loop
    assert len(calls) > 10 and all(k == n for _, n, k in calls)
    assert [first for first, _, _ in calls[1:]] == [n for _, n, _ in calls[:-1]]   # contiguous
    assert seen[-1] == (len(t), len(t)) and all(a[0] < b[0] for a, b in zip(seen, seen[1:]))
    _identical(sol, plain)


def test_progress_bar_run_equals_plain_run(monkeypatch):
    """``progress=True`` (the tqdm bar) also stays compiled and writes its bar."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    t = np.linspace(0.0, 1.0, 1200)
    plain = models.slider_crank().solve(t)
    buf = io.StringIO()
    monkeypatch.setattr(sys, "stderr", buf)
    sol = models.slider_crank().solve(t, progress=True)
    assert "1200/1200" in buf.getvalue()
    assert sol.extra["compiled_points"] == len(t)
    _identical(sol, plain)


def test_progress_in_the_python_code_equals_plain(monkeypatch):
    """Hooks keep the Python code at every point (decision 0081): ``progress`` is called
    there too, about every ``CHUNK_SECONDS``, and the sweep is the loop's to rounding (the
    Python code's LAPACK against the loop's LU)."""
    monkeypatch.setattr(kin, "CHUNK_SECONDS", 0.0)        # a call after every point
    t = np.linspace(0.0, 1.0, 40)
    plain = models.four_bar().solve(t)
    seen, at = [], []
    sol = models.four_bar().solve(t, progress=lambda done, total: seen.append(done),
                                  pre_solve=at.append)
    assert at == list(t)                  # (the hook saw every point: the Python code's)
    assert sol.extra["compiled_points"] == 0 and seen == list(range(1, 41))
    for x, y in ((sol.q, plain.q), (sol.qd, plain.qd), (sol.qdd, plain.qdd)):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-12)


@pytest.mark.parametrize("jit", ["1", "0"])
def test_keyboard_interrupt_from_the_callback_returns_the_points_solved(monkeypatch, jit):
    monkeypatch.setenv("MECHSYS_JIT", jit)
    monkeypatch.setattr(kin, "CHUNK_SECONDS", 0.0 if jit == "0" else 1e-7)
    t = np.linspace(0.0, 1.0, 1100)
    full = models.slider_crank().solve(t)
    at = []

    def stop(done, total):
        if done >= 100:
            at.append(done)
            raise KeyboardInterrupt

    with pytest.warns(RuntimeWarning, match="solve: interrupted after"):
        part = models.slider_crank().solve(t, progress=stop)
    k = len(part.t)
    assert part.extra["interrupted"] is True and "KeyboardInterrupt" in part.extra["stopped"]
    assert k == at[0] and 100 <= k < len(t)
    np.testing.assert_array_equal(part.t, full.t[:k])
    np.testing.assert_array_equal(part.q, full.q[:k])
    np.testing.assert_array_equal(part.qdd, full.qdd[:k])
    np.testing.assert_array_equal(part.extra["rcond"], full.extra["rcond"][:k])


def test_interrupt_before_any_point_is_a_clear_error(monkeypatch):
    monkeypatch.setenv("MECHSYS_JIT", "1")

    def ctrl_c(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(_jit_sweep, "run", ctrl_c)
    with pytest.raises(ms.MechError, match="before any point was solved: interrupted"):
        models.slider_crank().solve(np.linspace(0, 1, 1000), progress=lambda d, n: None)


def test_a_bad_progress_argument_is_refused():
    with pytest.raises(ms.ModelError, match="solve: progress must be True, False, None or a callable"):
        models.slider_crank().solve([0.0, 0.1], progress="yes")


@pytest.mark.parametrize("flag", ["--progress", "--no-progress"])
def test_cli_run_reaches_the_compiled_loop(monkeypatch, tmp_path, flag):
    """``mechsys run`` used to pass a pre_solve hook always, which sent every point to the
    Python loop: now the whole table comes from the compiled loop (MECHSYS_JIT unset: auto)."""
    from mechsys.cli import main

    monkeypatch.delenv("MECHSYS_JIT", raising=False)
    m = models.slider_crank(crank=2.0, rod=6.0, speed=2 * np.pi)
    path = m.save(tmp_path / "crank.json")
    calls = _spy_runs(monkeypatch)
    out = tmp_path / "r.csv"
    assert main(["run", str(path), "--t", "0:1:2000", "--out", str(out), flag]) == 0
    assert calls and calls[-1][2] == 2000
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    with open(out) as f:
        header = f.readline().strip().split(",")
    sol = models.slider_crank(crank=2.0, rod=6.0, speed=2 * np.pi).solve(np.linspace(0, 1, 2000))
    for j, name in enumerate(sol.names):
        np.testing.assert_array_equal(table[:, header.index(name + "_dd")], sol.qdd[:, j])


def test_simulate_progress_callback_keeps_the_compiled_stepper(monkeypatch):
    """The free-motion stepper returns every CHUNK_STEPS steps; the callback runs between
    chunks, so the run is the compiled one with the same numbers; a KeyboardInterrupt from
    it returns the motion so far."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import long_run

    import mechsys.solvers._jit_free as jf

    monkeypatch.setenv("MECHSYS_JIT", "1")
    monkeypatch.setattr(jf, "CHUNK_STEPS", 20)
    _, free = long_run.pendulum()
    full = free.simulate((0.0, 4.0))
    seen = []
    sol = free.simulate((0.0, 4.0), progress=lambda done, total: seen.append((done, total)))
    assert sol.extra["compiled_steps"] == full.extra["compiled_steps"] == full.extra["steps"]
    assert len(seen) >= 2 and seen[-1] == (4.0, 4.0)
    np.testing.assert_array_equal(sol.q, full.q)
    np.testing.assert_array_equal(sol.qdd, full.qdd)

    def stop(done, total):
        if done > 1.0:
            raise KeyboardInterrupt

    with pytest.warns(RuntimeWarning, match="interrupted at t = "):
        part = free.simulate((0.0, 4.0), progress=stop)
    k = len(part.t)
    assert part.extra["interrupted"] is True and 1.0 < part.t[-1] < 4.0
    np.testing.assert_array_equal(part.q, full.q[:k])


def test_a_long_compile_is_announced_once(monkeypatch, caplog):
    """A loop missing from Numba's cache is announced (the first free-motion run compiles for
    about a minute and used to look hung); once per process, and not when it is cached."""
    import logging

    from mechsys.solvers import _jit_cache

    monkeypatch.setattr(_jit_cache, "_said", set())
    with caplog.at_level(logging.INFO, logger="mechsys"):
        assert _jit_cache.notice("a test loop", 12, ("_jit_sweep_loop", "no_such_loop"))
        assert not _jit_cache.notice("a test loop", 12, ("_jit_sweep_loop", "no_such_loop"))
    assert [r.getMessage() for r in caplog.records] == [
        "mechsys: compiling a test loop (first run, about 12 s of CPU; cached for later runs)"]
    # a loop in the cache (the compiled sweep, after one ran) is not announced
    monkeypatch.setenv("MECHSYS_JIT", "1")
    models.slider_crank().solve(np.linspace(0, 1, 20))
    assert _jit_cache.cached("_jit_sweep_loop", "sweep_dense")
    assert not _jit_cache.notice("the kinematic sweep", 25, ("_jit_sweep_loop", "sweep_dense"))
