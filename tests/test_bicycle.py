"""The Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina & Schwab 2007, Proc. R. Soc. A
463:1955-1982) built from bodies, hinges and exact rolling contacts
(examples/whipple_bicycle.py) and linearised with ``free.linearize`` (decision 0054):
Table 2's eigenvalues at 0-10 m/s, the weave and capsize speeds, the lean/steer matrices of
eq. 5.4, the same model in millimetres, and the nonlinear motion after a small lean kick
against the linear prediction.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

_spec = importlib.util.spec_from_file_location(
    "whipple_bicycle", Path(__file__).resolve().parents[1] / "examples" / "whipple_bicycle.py")
wb = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(wb)


@pytest.fixture(scope="module")
def bicycle():
    m, coords = wb.build()
    return m.free(), coords


def test_table_2_eigenvalues_at_0_to_10_m_per_s(bicycle):
    free, coords = bicycle
    lin = wb.linearize(free, coords, 5.0)
    assert lin.states == ("lean", "steer", "lean_d", "steer_d", "rear_d")
    assert lin.speeds == ("lean", "steer", "rear") and free.dof == 3
    rows = wb.table(free, coords)
    for v, (s, zero, err) in rows.items():
        assert err < 1e-8, (v, s)
        assert abs(zero) < 1e-10                     # the forward speed: neutral
    # the stability verdicts: self-stable between the weave and capsize speeds only
    assert wb.linearize(free, coords, 5.0).stability.count("unstable") == 0
    assert "unstable" in wb.linearize(free, coords, 4.0).stability
    assert "unstable" in wb.linearize(free, coords, 7.0).stability


def test_weave_and_capsize_speeds(bicycle):
    vw, vc = wb.weave_and_capsize(*bicycle)
    assert abs(vw - 4.2923825) < 1e-7 and abs(vw - wb.WEAVE) < 1e-9
    assert abs(vc - 6.0242620) < 1e-7 and abs(vc - wb.CAPSIZE) < 1e-9


def test_lean_steer_block_against_the_papers_matrices(bicycle):
    Minv = np.linalg.inv(wb.M_PAPER)
    for v in (0.0, 2.5, 7.0):
        K, C = wb.lean_steer_matrices(wb.linearize(*bicycle, v))
        np.testing.assert_allclose(K, -Minv @ (wb.G * wb.K0_PAPER + v * v * wb.K2_PAPER),
                                   rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(C, -v * Minv @ wb.C1_PAPER, rtol=1e-10, atol=1e-10)


def test_millimetres_give_the_same_eigenvalues(bicycle):
    m, coords = wb.build(scale=1000.0)
    free = m.free()
    for v in (3.0, 6.0):
        s_mm, zero = wb.bicycle_eigenvalues(wb.linearize(free, coords, v, scale=1000.0))
        s_m, _ = wb.bicycle_eigenvalues(wb.linearize(*bicycle, v))
        assert np.abs(s_mm - s_m).max() < 1e-9 * np.abs(s_m).max()
        assert abs(zero) < 1e-10


@pytest.mark.parametrize("v, span, grows", [(5.0, 4.0, False), (8.0, 4.0, True),
                                            (2.0, 2.0, True)])
def test_nonlinear_kick_decays_in_the_stable_range_and_grows_outside(bicycle, v, span, grows):
    t = np.linspace(0.0, span, int(20 * span) + 1)
    lean, linear = wb.kick_response(*bicycle, v, t, kick=1e-3)
    # the linear prediction, to second order in the kick (1e-3 rad/s)
    assert np.abs(lean - linear).max() < 1e-4 * np.abs(linear).max()
    # (the second quarter: the kick's transient is over)
    q = len(t) // 4
    early, last = np.abs(lean[q:2 * q]).max(), np.abs(lean[-q:]).max()
    assert (last > early) == grows
    if v == 8.0:
        # the weave has died out (-2.69 1/s): the lean grows at the capsize eigenvalue
        rate = np.log(lean[-1] / lean[-21]) / (t[-1] - t[-21])
        s, _ = wb.bicycle_eigenvalues(wb.linearize(*bicycle, v))
        assert s[0].real == pytest.approx(0.14327879765713, rel=1e-10)
        assert rate == pytest.approx(s[0].real, rel=2e-3)
