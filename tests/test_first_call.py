"""The first result of a fresh process (decision 0065): kernels evaluated by SymEngine's
interpreter until the work pays for LLVM (``compile_exprs(first_use=True)``), the memoized
search of SymEngine expressions for what real double-precision code cannot hold, and the
body template derived in SymEngine. Each gives the numbers of the path it replaces."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import ModelError
from mechsys.compile import _backends, _dynamics

se = pytest.importorskip("symengine")
pytestmark = pytest.mark.skipif(_backends.default_backend() != "symengine",
                                reason="SymEngine kernels only")


@pytest.fixture
def no_cache(monkeypatch):
    monkeypatch.setenv("MECHSYS_CACHE", "0")


def _exprs():
    """SymEngine 0.15's CSE bug case (decision 0002): a repeated output and an argument
    ``x2`` that does not occur, beside a piecewise output (two-stage kernels)."""
    x2, x4, y4, th4 = se.symbols("x2 x4 y4 th4")
    args = [x2, x4, y4, th4]
    exprs = [se.sin(th4), -se.cos(th4), x4 * se.cos(th4) + y4 * se.sin(th4), -se.cos(th4),
             se.Piecewise((x4 * x4, x4 > 0), (y4, True)) + th4]
    x = np.array([0.3, 1.5, -0.7, 0.4])
    exact = [math.sin(0.4), -math.cos(0.4), 1.5 * math.cos(0.4) - 0.7 * math.sin(0.4),
             -math.cos(0.4), 1.5**2 + 0.4]
    return args, exprs, x, np.array(exact)


def test_first_use_kernel_interprets_then_compiles_with_the_same_numbers(no_cache):
    args, exprs, x, exact = _exprs()
    f = _backends.compile_exprs(args, exprs, first_use=True)
    assert isinstance(f, _backends._FirstUse) and f._full is None
    assert f._cheap.backend == "symengine-lambda"
    first = f(x)
    np.testing.assert_allclose(first, exact, rtol=1e-15, atol=1e-15)
    X = np.array([x, x + 0.1, x - 0.2])
    small = f.batch(X)
    assert f._full is None                            # a few points: still interpreted
    # the C entry points of a compiled loop: the LLVM kernel from here on
    assert f.c_entry() is not None and f._full.backend == "symengine-llvm"
    llvm = _backends.compile_exprs(args, exprs)
    np.testing.assert_allclose(f(x), first, rtol=1e-15, atol=0)
    np.testing.assert_allclose(f(x), llvm(x), rtol=0, atol=0)
    np.testing.assert_allclose(small, llvm.batch(X), rtol=1e-15, atol=1e-16)


def test_first_use_kernel_compiles_after_many_calls_or_a_large_batch(no_cache, monkeypatch):
    args, exprs, x, exact = _exprs()
    monkeypatch.setattr(_backends, "FIRST_USE_CALLS", 3)
    f = _backends.compile_exprs(args, exprs, first_use=True)
    for _ in range(3):
        f(x)
    assert f._full is None
    np.testing.assert_allclose(f(x), exact, rtol=1e-15, atol=1e-15)
    assert f._full is not None and f._full.backend == "symengine-llvm"
    g = _backends.compile_exprs(args, exprs, first_use=True)
    X = np.tile(x, (_backends.FIRST_USE_ROWS, 1))
    np.testing.assert_allclose(g.batch(X), np.tile(exact, (len(X), 1)), rtol=1e-15, atol=1e-15)
    assert g._full is not None


def test_first_use_kernel_pickles(no_cache):
    args, exprs, x, exact = _exprs()
    f = _backends.compile_exprs(args, exprs, first_use=True)
    g = pickle.loads(pickle.dumps(f))                 # (the interpreted kernel does not pickle)
    np.testing.assert_allclose(g(x), exact, rtol=1e-15, atol=1e-15)
    assert g.c_entry() is not None


def test_first_use_kernel_loads_llvm_from_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHSYS_CACHE", str(tmp_path / "kernels"))
    args, exprs, x, exact = _exprs()
    f = _backends.compile_exprs(args, exprs, first_use=True)
    assert f._full is None and not list((tmp_path / "kernels").glob("*.kernel"))
    f.c_entry()                                       # compiled and stored
    assert list((tmp_path / "kernels").glob("*.kernel"))

    def refuse(*a, **k):
        raise AssertionError("compiled or interpreted although cached")

    monkeypatch.setattr(_backends._se, "Lambdify", refuse)
    g = _backends.compile_exprs(args, exprs, first_use=True)
    assert g._full is not None and g._full.backend == "symengine-llvm"
    np.testing.assert_array_equal(g(x), f(x))


def test_search_for_complex_constants_visits_shared_subexpressions_once():
    """A chain of 60 products each using the previous one twice: as a tree 2**60 nodes
    (SymEngine's own ``atoms`` walks the tree and would not finish), as a DAG 120."""
    x = se.Symbol("x")
    e = x
    for _ in range(60):
        e = se.sin(e) * se.cos(e)
    assert _backends.real_expressions([e, x + 1]) == [e, x + 1]
    assert _backends._flagged(_backends._search([e, e * se.I]))
    assert _backends._flagged(_backends._search([e * x ** (2**64 + 1)]))
    assert not _backends._flagged(_backends._search([e * x ** 3]))
    # (what is flagged then goes expression by expression, as before: small ones here)
    with pytest.raises(ModelError, match="complex constant"):
        _backends.real_expressions([x + 1, se.sqrt(x) * se.I])
    big = _backends.real_expressions([x + 1, x ** (2**64 + 1)])
    assert not _backends._flagged(_backends._search(big))
    assert float(big[1].xreplace({x: se.RealDouble(-1.0)})) == -1.0


@pytest.mark.parametrize("space", [ms.Model3D().space, ms.Model2D().space,
                                   ms.Model2D(orientation="euler").space],
                         ids=["spatial", "planar", "planar-euler"])
def test_body_template_in_symengine_is_the_sympy_derivation(space, monkeypatch):
    native = _dynamics._body_template.__wrapped__(space)
    monkeypatch.setattr(_dynamics, "se", None)        # the SymPy derivation (hessian_terms)
    ref = _dynamics._body_template.__wrapped__(space)
    q, qd, m, c, J = native[0]
    syms = [*q, *qd, m, *c, *J]
    rng = np.random.default_rng(3)
    for _ in range(3):
        vals = dict(zip(syms, rng.uniform(-1.0, 1.0, len(syms))))
        sev = {se.sympify(k): v for k, v in vals.items()}

        def flat(tpl, sub):
            T, M, Qv = tpl[1:]
            return np.array([float(e.xreplace(sub)) for e in [T, *(x for r in M for x in r),
                                                                *Qv]])

        a = flat(native, sev)
        b = flat(ref, {k: sp.Float(v) for k, v in vals.items()})
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-14)
