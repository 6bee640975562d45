"""The compiled sweep's condition estimates computed on demand (decision 0023): the same
numbers as computed in the loop, whichever way ``Solution.extra`` is read, and the
``Extra`` dict behaving as a dict."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from mechsys import models
from mechsys.results._extra import Extra
from mechsys.solvers import _jit_sweep
from mechsys.solvers._tolerances import RCOND_PENDING, RCOND_WARN

pytest.importorskip("numba")
pytestmark = pytest.mark.filterwarnings("ignore::mechsys.NearSingularWarning")


def _dead_centres():
    """Its points near the dead centres are below ``RCOND_WARN`` (estimated in the loop), the
    others are left pending."""
    from test_jit_sweep import dead_centre_crank

    return dead_centre_crank()


def _eager(monkeypatch):
    """Make the compiled loop compute every estimate itself (no row scales to defer with)."""
    real = _jit_sweep.run

    def run(*args, **kw):
        return real(*args[:15], None, *args[16:], **kw)

    monkeypatch.setattr(_jit_sweep, "run", run)


@pytest.mark.parametrize("build", [models.slider_crank, _dead_centres], ids=["regular", "dead-centres"])
def test_deferred_estimates_are_the_loops_own(monkeypatch, build):
    monkeypatch.setenv("MECHSYS_JIT", "1")
    t = np.linspace(0.05, 1.05, 201)
    lazy = build().solve(t)
    raw = dict.__getitem__(lazy.extra, "rcond")          # not computed yet
    assert not isinstance(raw, np.ndarray)
    with monkeypatch.context() as mp:
        _eager(mp)
        eager = build().solve(t)
    assert isinstance(dict.__getitem__(eager.extra, "rcond"), np.ndarray)
    got, want = lazy.extra["rcond"], eager.extra["rcond"]
    np.testing.assert_array_equal(got, want)               # bit for bit
    assert np.isfinite(got).all() and not (got == RCOND_PENDING).any()
    if build is _dead_centres:
        assert (got < RCOND_WARN).any() and (got >= RCOND_WARN).any()
    np.testing.assert_array_equal(lazy.q, eager.q)
    # and LAPACK's estimates (dgecon on the unit-free Jacobian at each solved point, through
    # the Python code's Scaling: not the loop) agree to rounding; at a dead centre (rcond ~
    # 1e-11) the two LU factorisations' last bits are amplified by the condition number
    from mechsys.solvers._kinematics import sweep

    m = build()
    s = m.compile()
    res = sweep(s, t, m.guess())
    np.testing.assert_array_equal(res.q, lazy.q)
    ref = [res.scaling.factor(s.jacobian(tk, qk, s.p_values)).rcond for tk, qk in zip(t, res.q)]
    rtol = 1e-6 if build is _dead_centres else 1e-12
    np.testing.assert_allclose(got, ref, rtol=rtol)


@pytest.mark.parametrize("read", [
    lambda e: e["rcond"], lambda e: e.get("rcond"), lambda e: dict(e)["rcond"],
    lambda e: {**e}["rcond"], lambda e: list(e.values())[0], lambda e: dict(e.items())["rcond"],
    lambda e: copy.copy(e)["rcond"], lambda e: copy.deepcopy(e)["rcond"], lambda e: e.copy()["rcond"],
    lambda e: pickle.loads(pickle.dumps(e))["rcond"], lambda e: e.pop("rcond"),
    lambda e: (e | {})["rcond"], lambda e: ({} | e)["rcond"], lambda e: e.setdefault("rcond"),
], ids=["getitem", "get", "dict", "unpack", "values", "items", "copy", "deepcopy", "dict.copy",
        "pickle", "pop", "or", "ror", "setdefault"])
def test_every_way_of_reading_gets_the_numbers(monkeypatch, read):
    monkeypatch.setenv("MECHSYS_JIT", "1")
    sol = models.slider_crank().solve(np.linspace(0, 1, 50))
    # (the sweep also records how many points the compiled loop solved: "compiled_points")
    assert list(sol.extra)[0] == "rcond" and set(sol.extra) <= {"rcond", "compiled_points"}
    got = read(sol.extra)
    assert isinstance(got, np.ndarray) and got.shape == (50,)
    assert np.isfinite(got).all() and (got > 0.1).all()


def test_printing_and_comparing_compute_first():
    calls = []
    e = Extra({"a": 1}, deferred={"b": lambda: calls.append(1) or 2.5})
    assert "b" in e and sorted(e) == ["a", "b"] and not calls
    assert repr(e) == "{'a': 1, 'b': 2.5}" and calls == [1]
    assert e == {"a": 1, "b": 2.5} and e["b"] == 2.5 and calls == [1]     # computed once
    e["b"] = 3
    assert e["b"] == 3
    f = Extra(deferred={"x": lambda: 7})
    assert f.popitem() == ("x", 7) and not f
    assert f.get("missing", 0) == 0
    with pytest.raises(KeyError):
        f["missing"]


def test_sweep_result_fills_once(monkeypatch):
    from mechsys.solvers._kinematics import sweep

    monkeypatch.setenv("MECHSYS_JIT", "1")
    m = models.slider_crank()
    s = m.compile()
    res = sweep(s, np.linspace(0, 1, 20), m.guess())
    assert res.rcond_pending and (res.rcond_raw == RCOND_PENDING).any()
    first = res.rcond
    assert not res.rcond_pending and res.rcond is first and np.isfinite(first).all()


def test_reading_releases_the_row_scales(monkeypatch):
    """The (N, n) row scales kept for the deferred estimates are freed once they are read."""
    import gc
    import weakref

    monkeypatch.setenv("MECHSYS_JIT", "1")
    refs = []
    real = _jit_sweep.rcond_filler

    def spy(system, pointers, times, Q, p, scaling, R):
        refs.append(weakref.ref(R))
        return real(system, pointers, times, Q, p, scaling, R)

    monkeypatch.setattr(_jit_sweep, "rcond_filler", spy)
    sol = models.slider_crank().solve(np.linspace(0, 1, 50))
    gc.collect()
    assert refs and refs[0]() is not None
    sol.extra["rcond"]
    gc.collect()
    assert refs[0]() is None
