"""The compiled loops specialised on their mode (``solvers._jit_modes``, decision 0044): a
literal mode compiles only the solvers of that mode, the specialisation gives the general
loop's numbers, and a missing specialisation is announced before it compiles."""

from __future__ import annotations

import logging

import numba as nb
import numpy as np

from mechsys.solvers import _jit_cache
from mechsys.solvers._jit_modes import entry, in_cache, signature, within


@nb.njit
def _double(x, out):
    out[0] = 2.0 * x
    return True


@nb.njit
def _negate(x, out):
    out[0] = -x
    return True


@nb.njit
def _pick(mode, x, out):
    if mode == 0:
        return within(mode, 0, 0, _double, x, out)
    return within(mode, 1, 2, _negate, x, out)


def test_within_is_the_call_in_range_and_false_outside():
    out = np.zeros(1)
    assert within(1, 1, 2, lambda v: v > 0, 3.0)
    assert within(3, 1, 2, lambda v: v > 0, 3.0) is False
    assert _pick(0, 1.5, out) and out[0] == 3.0       # the general loop: both solvers
    assert _pick(2, 1.5, out) and out[0] == -1.5


def test_a_literal_mode_compiles_only_its_solvers():
    @nb.njit
    def double(x, out):
        out[0] = 2.0 * x
        return True

    @nb.njit
    def negate(x, out):
        out[0] = -x
        return True

    @nb.njit
    def pick(mode, x, out):
        if mode == 0:
            return within(mode, 0, 0, double, x, out)
        return within(mode, 1, 2, negate, x, out)

    out = np.zeros(1)
    args = (2, 1.5, out)
    fn = entry(pick, args, literal=(0,))
    assert fn(*args) and out[0] == -1.5
    assert pick.signatures == [(nb.types.literal(2), nb.float64, nb.typeof(out))]
    assert double.signatures == []          # never typed: the mode cannot reach it
    assert negate.signatures == [(nb.float64, nb.typeof(out))]
    assert entry(pick, args, literal=(0,)) is fn          # found again, not compiled again
    assert in_cache(pick, signature(args, (0,)))
    assert not in_cache(pick, signature((0, 1.5, out), (0,)))


def test_a_missing_specialisation_is_announced_once(monkeypatch, caplog):
    """``entry`` calls its ``say`` before a compile and ``notice`` without functions says
    it (once per process and message)."""
    @nb.njit
    def twice(mode, x):
        return 2.0 * x + mode

    monkeypatch.setattr(_jit_cache, "_said", set())
    said = []
    with caplog.at_level(logging.INFO, logger="mechsys"):
        fn = entry(twice, (1, 2.0), literal=(0,),
                   say=lambda _: said.append(_jit_cache.notice("a test loop (kind 1)", 3)))
        assert fn(1, 2.0) == 5.0
        entry(twice, (1, 2.0), literal=(0,), say=lambda _: said.append("again"))
        assert not _jit_cache.notice("a test loop (kind 1)", 3)
    assert said == [True]
    assert [r.getMessage() for r in caplog.records] == [
        "mechsys: compiling a test loop (kind 1) (first run, about 3 s of CPU; cached for "
        "later runs)"]
