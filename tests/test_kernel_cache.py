"""The on-disk cache of compiled kernels (compile/_backends.py): a second build of the same
equations compiles nothing and gives the same numbers; a change anywhere in the equations,
down to the last bit of a length, gets its own kernel; a broken or unwritable cache costs
compile time, never a wrong answer."""

from __future__ import annotations

import numpy as np
import pytest

from mechsys import models
from mechsys.compile import _backends

pytest.importorskip("symengine")
pytestmark = pytest.mark.skipif(_backends.default_backend() != "symengine", reason="LLVM kernels only")

T = np.linspace(0.0, 1.0, 21)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    d = tmp_path / "kernels"
    monkeypatch.setenv("MECHSYS_CACHE", str(d))
    return d


def _no_compiler(monkeypatch):
    def refuse(*a, **k):
        raise AssertionError("compiled although cached")

    monkeypatch.setattr(_backends._se, "Lambdify", refuse)


def test_second_build_compiles_nothing_and_agrees(cache, monkeypatch):
    first = models.slider_crank().solve(T)
    files = sorted(cache.glob("*.pkl"))
    assert len(files) == 3                      # position, velocity, gamma kernels
    _no_compiler(monkeypatch)
    second = models.slider_crank().solve(T)
    np.testing.assert_array_equal(second.q, first.q)
    np.testing.assert_array_equal(second.qdd, first.qdd)


def test_last_bit_of_a_length_makes_a_new_kernel(cache):
    """Printed SymEngine expressions round doubles to 15 digits: the key must not."""
    rod = 6.0
    rod2 = rod + 2e-15
    assert str(_backends._se.sympify(rod)) == str(_backends._se.sympify(rod2))   # same print
    a = models.slider_crank(rod=rod).compile()
    x = a.pack(0.3, a.guess)
    fa = a.f_position(x)
    n_files = len(list(cache.glob("*.pkl")))
    b = models.slider_crank(rod=rod2).compile()
    fb = b.f_position(x)
    assert len(list(cache.glob("*.pkl"))) > n_files
    # the kernel of the second model holds its own rod length, to the last bit
    assert np.abs(fb - fa).max() > 0


def test_corrupt_entry_is_replaced(cache):
    good = models.slider_crank().solve(T)
    for f in cache.glob("*.pkl"):
        f.write_bytes(b"not a pickle")
    again = models.slider_crank().solve(T)
    np.testing.assert_array_equal(again.q, good.q)
    for f in cache.glob("*.pkl"):
        assert f.read_bytes() != b"not a pickle"


def test_cache_off_and_unwritable(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHSYS_CACHE", "0")
    assert _backends.cache_dir() is None
    ref = models.slider_crank().solve(T)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    monkeypatch.setenv("MECHSYS_CACHE", str(blocker / "sub"))    # cannot be created
    sol = models.slider_crank().solve(T)
    np.testing.assert_array_equal(sol.q, ref.q)
    assert not list(tmp_path.glob("**/*.tmp"))
