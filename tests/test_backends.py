"""Numeric backends agree, and functions SymEngine cannot compile fall back to SymPy."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T, models
from mechsys.compile import available_backends, compile_exprs


def test_backends_agree_on_a_model():
    m = models.four_bar()
    s = m.compile()
    lay = s.layout
    exprs = s.phi + s.jac_exprs + s.gamma
    rng = np.random.default_rng(2)
    x = s.pack(0.3, rng.standard_normal(s.n), rng.standard_normal(s.n))
    vals = {b: compile_exprs(lay.args(), exprs, b)(x) for b in available_backends()}
    ref = vals["sympy"]
    for v in vals.values():
        np.testing.assert_allclose(v, ref, rtol=1e-13, atol=1e-13)


def test_unsupported_function_falls_back_to_sympy():
    x = sp.Symbol("x")
    f = compile_exprs([T, x], [sp.Mod(T, 1) * x, sp.Piecewise((1, x > 0), (0, True))])
    np.testing.assert_allclose(f(np.array([2.5, 3.0])), [1.5, 1.0])
    np.testing.assert_allclose(f.batch(np.array([[2.5, 3.0], [0.2, -1.0]])), [[1.5, 1.0], [-0.2, 0.0]])


def test_periodic_driver_with_mod_solves():
    # a saw-tooth crank driver: theta = 2 pi (T mod 1)
    m = models.slider_crank(drive=2 * sp.pi * sp.Mod(T, 1))
    sol = m.solve([0.25, 1.25])
    np.testing.assert_allclose(sol["piston.x"][0], sol["piston.x"][1], atol=1e-12)
    assert isinstance(m, ms.Model2D)


@pytest.mark.skipif("symengine" not in available_backends(), reason="symengine not installed")
def test_default_backend_is_symengine_llvm():
    x = sp.Symbol("x")
    f = compile_exprs([x], [sp.sin(x)])
    assert f.backend.startswith("symengine")


def test_fast_entry_point_agrees_with_the_checked_call_and_returns_fresh_arrays():
    """The compiled kernels use SymEngine's unchecked ``unsafe_real`` (0.8 us instead of 4 us
    a call); the checks it skips are made by mechsys: a wrong length raises, each call
    returns a new array (a caller keeping the last result must not see it overwritten), and
    the values equal the checked call's, also for two-stage Piecewise kernels."""
    import numpy as np
    import pytest
    import sympy as sp

    from mechsys.compile import compile_exprs

    x, y = sp.symbols("x y")
    pw = sp.Piecewise((x**2, x < 0.5), (1 - x, True))
    for exprs in ([sp.sin(x) * y, x + y, y**2], [pw * y, pw + y, sp.cos(pw)]):
        f = compile_exprs([x, y], exprs, "symengine")
        a, b = np.array([0.3, 2.0]), np.array([0.7, -1.0])
        fa = f(a)
        fb = f(b)
        np.testing.assert_allclose(fa, f._slow(a), rtol=1e-15)
        np.testing.assert_allclose(fb, f._slow(b), rtol=1e-15)
        assert not np.shares_memory(fa, fb)
        ref = [float(e.subs({x: 0.3, y: 2.0})) for e in exprs]
        np.testing.assert_allclose(fa, ref, rtol=1e-14)
        with pytest.raises(ValueError, match="called with shape"):
            f(np.zeros(3))


def test_cse_kernels_repeated_outputs_are_right():
    """SymEngine 0.15's CSE returns the first argument for a repeated output (decision 0002,
    benchmarks/symengine_cse_bug.py); kernels compiled with ``cse=True`` (models with Gen
    joints) compile each distinct output once and copy it, so the values are right."""
    pytest.importorskip("symengine")
    import math

    x2, x4, y4, th4 = sp.symbols("x2 x4 y4 th4")
    exprs = [sp.sin(th4), -sp.cos(th4), x4 * sp.cos(th4) + y4 * sp.sin(th4), -sp.cos(th4)]
    f = compile_exprs([x2, x4, y4, th4], exprs, "symengine", cse=True)
    x = np.array([0.3, 1.5, -0.7, 0.4])
    exact = [math.sin(0.4), -math.cos(0.4), 1.5 * math.cos(0.4) - 0.7 * math.sin(0.4), -math.cos(0.4)]
    np.testing.assert_allclose(f(x), exact, rtol=1e-14)
    np.testing.assert_allclose(f.batch(np.vstack([x, x])), [exact, exact], rtol=1e-14)
    # the compiled loops without an expansion map (sweep, multipliers) get the kernel
    # compiled again without CSE: its C function writes every output, the right ones
    import ctypes

    row = f.c_function()
    assert row is not None and row[2] == 0 and f.c_entry()[1] is not None
    cfun = ctypes.CFUNCTYPE(None, ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double),
                            ctypes.c_void_p)(row[0])
    out = np.full(4, np.nan)
    cfun(out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
         x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), row[1])
    np.testing.assert_allclose(out, exact, rtol=1e-14)
