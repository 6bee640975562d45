"""Long free-motion runs: progress display, Ctrl-C returning the solution so far, and a
short profile of benchmarks/long_run.py (bounded constraint drift and energy error)."""

import io
import pathlib
import sys

import numpy as np
import pytest

import mechsys as ms
import mechsys.analyses._free as free_module
from conftest import python_path

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import long_run  # noqa: E402


def _interrupt_after(monkeypatch, calls: int):
    """Make the free acceleration raise KeyboardInterrupt at its ``calls``-th evaluation
    (as Ctrl-C would at any moment of a long run)."""
    real = free_module.free_acceleration
    count = [0]

    def accel(*a, **k):
        count[0] += 1
        if count[0] == calls:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(free_module, "free_acceleration", accel)


@pytest.mark.parametrize("method,t", [("dop853", (0.0, 4.0)), ("adams", (0.0, 4.0)),
                                      ("dop853", "grid"), ("adams", "grid")])
def test_keyboard_interrupt_returns_the_solution_so_far(monkeypatch, method, t):
    python_path(monkeypatch)      # the Python stepper, whole (the loop's: the next test)
    _, free = long_run.pendulum()
    grid = np.linspace(0.0, 4.0, 81)
    tt = grid if isinstance(t, str) else t
    kw = {"step_size": 1e-2} if method == "adams" else {}
    full = free.simulate(tt, method=method, **kw)
    _interrupt_after(monkeypatch, 300)
    with pytest.warns(RuntimeWarning, match="interrupted at t = "):
        part = free.simulate(tt, method=method, **kw)
    assert part.extra["interrupted"] is True and "interrupted" not in full.extra
    k = len(part.t)
    assert 2 <= k < len(full.t)
    # the states so far are exactly those of the uninterrupted run (same steps)
    np.testing.assert_array_equal(part.t, full.t[:k])
    np.testing.assert_allclose(part.q, full.q[:k], rtol=0, atol=1e-12)
    np.testing.assert_allclose(part.qd, full.qd[:k], rtol=0, atol=1e-12)
    # and usable: accelerations and multipliers at every returned point
    assert np.all(np.isfinite(part.qdd)) and np.all(np.isfinite(part.lam))


@pytest.mark.parametrize("t", [(0.0, 4.0), "grid"])
def test_keyboard_interrupt_between_compiled_chunks(monkeypatch, t):
    """The compiled stepper returns every CHUNK_STEPS steps; a Ctrl-C that arrives during a
    chunk is raised when it returns: the solution so far comes back, as from Python."""
    pytest.importorskip("numba")
    import mechsys.solvers._jit_free as jf

    monkeypatch.setenv("MECHSYS_JIT", "1")
    monkeypatch.setattr(jf, "CHUNK_STEPS", 5)
    _, free = long_run.pendulum()
    tt = np.linspace(0.0, 4.0, 81) if isinstance(t, str) else t
    full = free.simulate(tt)
    assert full.extra["compiled_steps"] == full.extra["steps"] > 20
    real = jf.FreeStepper.advance
    calls = [0]

    def advance(self, *a, **k):
        calls[0] += 1
        if calls[0] == 3:
            raise KeyboardInterrupt
        return real(self, *a, **k)

    monkeypatch.setattr(jf.FreeStepper, "advance", advance)
    with pytest.warns(RuntimeWarning, match="interrupted at t = "):
        part = free.simulate(tt)
    k = len(part.t)
    assert part.extra["interrupted"] is True and 2 <= k < len(full.t)
    if isinstance(t, tuple):
        assert k == 11 and part.extra["compiled_steps"] == 10     # two chunks and the start
    np.testing.assert_array_equal(part.t, full.t[:k])
    np.testing.assert_array_equal(part.q, full.q[:k])
    np.testing.assert_array_equal(part.qdd, full.qdd[:k])
    assert np.all(np.isfinite(part.lam))


def test_progress_bar_on_request(monkeypatch):
    _, free = long_run.pendulum()
    buf = io.StringIO()
    monkeypatch.setattr(sys, "stderr", buf)
    free.simulate((0.0, 1.0), progress=True)
    text = buf.getvalue()
    assert text.startswith("\rsimulate:") and "100%" in text and text.endswith("\n")
    buf.truncate(0)
    buf.seek(0)
    free.simulate((0.0, 1.0), progress=False)
    free.simulate((0.0, 1.0))           # default: only on a terminal (a StringIO is not)
    assert buf.getvalue() == ""
    with pytest.raises(ms.ModelError, match="progress must be True, False, None or a callable"):
        free.simulate((0.0, 1.0), progress=1)


@pytest.mark.parametrize("build", ["pendulum", "four-bar"])
def test_short_long_run_has_bounded_drift_and_energy_error(build):
    fn = long_run.pendulum if build == "pendulum" else long_run.four_bar
    r = long_run.measure(build, fn, 2000, 1e-3)
    assert r["steps"] >= 2000 and not r["interrupted"]
    assert r["pos"] < 1e-10          # positions projected every step
    assert r["vel"] < 1e-10
    assert r["E_max"] < 1e-7         # the corrector keeps the energy (measured 2e-8, 1e-11)
    assert "| pendulum |" in long_run.table([r]).replace(build, "pendulum")
