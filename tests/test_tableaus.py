"""Our own Runge-Kutta tableaus (solvers/_tableaus.py, decision 0038) against the theory they
come from, not against SciPy: the order conditions of every rooted tree (Butcher) up to the
method's order, the embedded estimators' orders, the dense outputs' end values, and the
convergence order on ``y' = y`` (``exp(t)``); and the registry of methods (solvers/_methods.py)
that every part reads."""

from __future__ import annotations

from fractions import Fraction
from functools import cache

import numpy as np
import pytest

import mechsys as ms
from mechsys.solvers import _methods
from mechsys.solvers._tableaus import DOP853_TABLEAU, RK45_TABLEAU


@cache
def _trees(order: int) -> tuple:
    """Every rooted tree with ``order`` nodes, as a sorted tuple of its subtrees."""
    if order == 1:
        return ((),)
    out = set()

    def forests(total, smallest):
        # multisets of trees whose orders add up to ``total`` (non-decreasing, no repeats)
        if total == 0:
            yield ()
            return
        for k in range(1, total + 1):
            for t in _trees(k):
                if (k, t) < smallest:
                    continue
                for rest in forests(total - k, (k, t)):
                    yield ((k, t),) + rest

    for f in forests(order - 1, (0, ())):
        out.add(tuple(sorted(t for _, t in f)))
    return tuple(sorted(out))


def _size(t) -> int:
    return 1 + sum(_size(c) for c in t)


def _density(t) -> Fraction:
    g = Fraction(_size(t))
    for c in t:
        g *= _density(c)
    return g


def _weights(A, t) -> np.ndarray:
    """The stage vector of tree ``t``: ``prod_k (A g(t_k))_i`` (ones for the leaf)."""
    g = np.ones(A.shape[0])
    for c in t:
        g = g * (A @ _weights(A, c))
    return g


def _worst(A, b, order) -> float:
    """The largest violation of the order conditions ``b . g(t) = 1 / gamma(t)`` over every
    tree up to ``order`` nodes."""
    return max(abs(b @ _weights(A, t) - 1.0 / float(_density(t)))
               for p in range(1, order + 1) for t in _trees(p))


def test_tree_count_is_butchers():
    # 1, 1, 2, 4, 9, 20, 48, 115 rooted trees of orders 1..8 (OEIS A000081)
    assert [len(_trees(p)) for p in range(1, 9)] == [1, 1, 2, 4, 9, 20, 48, 115]


def test_dop853_order_conditions():
    A, B, C, E3, E5, D = DOP853_TABLEAU
    A12 = A[:12, :12]
    np.testing.assert_allclose(A.sum(axis=1), C, rtol=0, atol=1e-14)  # the nodes are row sums
    # the simplest conditions by hand: sum b = 1, sum b c = 1/2, sum b c^2 = 1/3 ...
    for k in range(1, 9):
        assert abs(B @ C[:12] ** (k - 1) - 1 / k) < 1e-13
    assert _worst(A12, B, 8) < 1e-12                  # all 200 trees up to order 8
    assert _worst(A12, B, 9) > 1e-6                   # and not order 9 (the tableau is not padded)
    # the 5th-order estimator: b - er satisfies every condition up to order 5 (stage 13 unused)
    assert E5[12] == 0 and _worst(A12, B - E5[:12], 5) < 1e-12
    # the 3rd-order one: bhh = b - E3 (three stages) up to order 3
    assert _worst(A12, B - E3[:12], 3) < 1e-12
    # the stage at the new point is the propagated solution's derivative
    np.testing.assert_array_equal(A[12, :12], B)
    assert D.shape == (4, 16)


def test_rk45_order_conditions_and_dense_output():
    A, B, C, E, P = RK45_TABLEAU
    A6 = np.hstack([A, np.zeros((6, 1))])
    np.testing.assert_allclose(A6.sum(axis=1), C, rtol=0, atol=1e-15)
    assert _worst(A6, B, 5) < 1e-14 and _worst(A6, B, 6) > 1e-6
    # the embedded 4th-order weights over the 7 stages (the 7th: the new point, row b)
    A7 = np.zeros((7, 7))
    A7[:6, :6], A7[6, :6] = A6, B
    assert _worst(A7, np.append(B, 0.0) - E, 4) < 1e-14
    # Shampine's dense output at theta = 1 is the step's end: the rows of P add up to b
    np.testing.assert_allclose(P.sum(axis=1), np.append(B, 0.0), rtol=0, atol=1e-15)


def _exp_error(tableau, h: float, rk45: bool) -> float:
    """Global error at t = 1 of ``y' = y, y(0) = 1`` in constant steps ``h``."""
    A, B = tableau[0], tableau[1]
    s = len(B)
    A = A[:s, :s] if not rk45 else np.hstack([A, np.zeros((6, 1))])
    y = 1.0
    for _ in range(round(1 / h)):
        K = np.zeros(s)
        for i in range(s):
            K[i] = y + h * (A[i, :i] @ K[:i])     # f(y) = y
        y = y + h * (B @ K)
    return abs(y - np.e)


@pytest.mark.parametrize("tableau,order,rk45,h", [(DOP853_TABLEAU, 8, False, 0.5),
                                                  (RK45_TABLEAU, 5, True, 0.125)])
def test_exp_converges_at_the_methods_order(tableau, order, rk45, h):
    """Halving the step divides the error by about 2^order (steps short enough to be in the
    asymptotic range, long enough to stay above rounding)."""
    e1, e2 = _exp_error(tableau, h, rk45), _exp_error(tableau, h / 2, rk45)
    rate = np.log2(e1 / e2)
    assert order - 0.3 < rate < order + 0.5, rate


# -- the registry -------------------------------------------------------------------------------
def test_registry_names_every_method_once():
    assert _methods.NAMES == ("dop853", "rk45", "radau", "automatic", "adams", "predictor",
                              "corrector")
    assert _methods.get("ADAMS").name == "automatic" and _methods.get("Dop853").name == "dop853"
    with pytest.raises(ms.OptionError, match=r"method must be one of 'dop853', .*did you mean 'rk45'"):
        _methods.get("rk4")
    from mechsys.solvers import _jit_free

    # the compiled stepper's list is the registry's, not a copy that can drift
    assert _jit_free.METHODS == tuple(n for n, m in _methods.METHODS.items() if m.compiled)
    for m in _methods.METHODS.values():
        assert m.runge_kutta == (m.family == "runge_kutta")
        assert m.dense_output == m.runge_kutta
        if m.runge_kutta:
            import scipy.integrate

            assert hasattr(scipy.integrate, m.scipy)           # the public stepper class


@pytest.mark.parametrize("method", list(_methods.METHODS))
def test_every_registered_method_runs_compiled(monkeypatch, method):
    """A method of the registry with a compiled loop reaches it (no silent fall-back to Python
    because one list forgot it), and its run matches the pendulum's energy."""
    pytest.importorskip("numba")
    monkeypatch.setenv("MECHSYS_JIT", "1")
    m = ms.Model2D()
    bar = m.add_body("bar", mass=1.0, centroid=(1, 0), inertia=0.0, guess=((0, 0), 0.3))
    m.add(ms.Revolute2(m.ground.point((0, 0)), bar.point(0)), name="pivot")
    m.add(ms.RotationLock1(bar, 0.3), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    sol = m.free(drop=["hold"]).simulate((0.0, 1.0), method=method, max_error=1e-8)
    assert sol.extra["method"] == method
    assert sol.extra["compiled_steps"] > 0 if _methods.METHODS[method].compiled else \
        sol.extra["compiled_steps"] == 0
    th = sol.q[:, sol.names.index("bar.th")]
    w = sol.qd[:, sol.names.index("bar.th")]
    energy = 0.5 * w**2 + 9.81 * np.sin(th)          # point mass at 1 from the pivot
    assert np.ptp(energy) < 1e-5
