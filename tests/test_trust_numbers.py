"""Numbers the compiled kernels used to change, and runs whose accuracy degraded silently
(issue 34, section 1).

* Integer exponents of 2**63 or more wrapped modulo 2**64 in SymEngine's LLVM code: a driver
  ``T**(2**64 + 1)`` ran as ``T``. They are now rewritten with float exponents where
  expressions become code (``compile._backends.real_expression``); the reference is the
  power computed in Python's floats.
* Complex constants (``sqrt(-1)``, ``log(-1) = I pi``, ``"I"``, ``asin(2)``) were cut to their
  real part with only a NumPy warning; they are refused, naming the constraint or load.
* A free motion without constraint correction drifted off its constraints, and a mechanism
  far from the origin lost accuracy, without a word: the run now reports its own measure
  (``sol.extra["accuracy"]``) and warns ``DegradedAccuracyWarning`` when degraded; the
  reference for the drift is the joint gap computed from the solution's point locations.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from conftest import python_path
from mechsys import T
from mechsys.compile import available_backends, compile_exprs

BACKENDS = available_backends()


def crank(drive, backend=None):
    m = ms.Model2D(backend=backend)
    c = m.add_body("crank", points={"tip": (1, 0)}, guess=((0, 0), 0.1))
    m.add(ms.Revolute2(m.ground.point((0, 0)), c.point(0)), name="pivot")
    m.add(ms.RotationLock1(c, drive), name="drive")
    return m


# -- huge integer exponents ------------------------------------------------------------------
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("n", [2**63, 2**64, 2**64 + 1, 3 * 2**62 + 1])
def test_driver_with_a_huge_integer_exponent_is_the_power(backend, n):
    """``th = T**n`` at T = 0.5 is 0 (not 0.5, as the wrapped exponent 1 gave, nor 1 as the
    exponent 0 of 2**64 gave), at T = -1 it is (-1)**n (the parity kept), at T = 1 it is 1."""
    times = np.array([0.5, -1.0, 1.0])
    sol = crank(T**n, backend).solve(times, solution="location")
    expected = [0.0, -1.0 if n % 2 else 1.0, 1.0]
    np.testing.assert_allclose(sol.q[:, 2], expected, atol=1e-15)


@pytest.mark.parametrize("backend", BACKENDS)
def test_compile_exprs_keeps_huge_exponents_and_their_derivative(backend):
    x = sp.Symbol("x")
    n = 2**64 + 1
    f = compile_exprs([x], [x**n, sp.diff(x**n, x), 3 * x ** (-n)], backend)
    np.testing.assert_allclose(f(np.array([-1.0])), [-1.0, float(n), -3.0])
    with np.errstate(divide="ignore", over="ignore"):
        np.testing.assert_allclose(f(np.array([0.5])), [0.0, 0.0, np.inf])
        np.testing.assert_allclose(f(np.array([-0.5])), [0.0, 0.0, -np.inf])


@pytest.mark.parametrize("backend", BACKENDS)
def test_load_with_a_huge_exponent_is_the_power(backend):
    """A moment ``2 T**(2**64 + 1)`` on a held crank: the static reaction of the driver
    balances it (0 at T = 0.5, where the wrapped exponent gave 1; -2 at T = -1)."""
    m = crank(0.0, backend)
    c = m.body("crank")
    m.set_mass_properties("crank", mass=1.0, inertia=0.1)
    m.add_load(ms.Moment(c, 2 * T ** (2**64 + 1)))
    sol = m.solve([0.5, -1.0], solution="static")
    _, moment = sol.reaction("drive", "crank")
    applied = np.array([0.0, -2.0])
    np.testing.assert_allclose(moment + applied, 0.0, atol=1e-12)


# -- complex constants -----------------------------------------------------------------------
@pytest.mark.parametrize("drive", [sp.sqrt(-1) * T, sp.log(-1) + T, "I*T", T + sp.I,
                                   sp.asin(2) * T, T * sp.Integer(-2) ** sp.Rational(1, 3)],
                         ids=["sqrt(-1)", "log(-1)", "string I", "T + I", "asin(2)", "cbrt(-2)"])
def test_complex_constant_in_a_constraint_is_refused(drive):
    with pytest.raises(ms.ModelError, match=r"'drive'.*complex constant"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")      # no NumPy "discards the imaginary part" either
            crank(drive).solve([0.0, 0.5])


def test_complex_constant_in_a_load_is_refused():
    m = crank(0.0)
    c = m.body("crank")
    m.add_load(ms.Force(c.point("tip"), (0, 1), T + sp.I), name="push")
    with pytest.raises(ms.ModelError, match=r"load 'push'.*complex constant I"):
        m.solve([0.0, 0.5], solution="static")


def test_compile_exprs_refuses_complex_constants():
    x = sp.Symbol("x")
    with pytest.raises(ms.ModelError, match="complex constant"):
        compile_exprs([x], [x + sp.log(-2)])


def test_real_expressions_are_unchanged():
    """The check changes nothing else: exponents below 2**53 and real constants stay."""
    from mechsys.compile._backends import real_expression

    x = sp.Symbol("x")
    for e in (x**3 + sp.sqrt(2) * x, x ** (2**52), sp.asin(sp.Rational(1, 2)) * x, x**-7):
        assert real_expression(e) == e


# -- the run's own measure of its accuracy ---------------------------------------------------
def four_bar():
    """A four-bar of uniform links (crank 1, coupler 4, rocker 3, ground 4) under gravity,
    assembled at a crank angle of 1.2 rad held by ``drive``."""
    m = ms.Model2D()
    g = m.ground

    def link(length):
        return dict(mass=length, centroid=(length / 2, 0), inertia=length**3 / 12)

    cr = m.add_body("crank", points={"tip": (1, 0)}, guess=((0, 0), 1.2), **link(1.0))
    co = m.add_body("coupler", points={"end": (4, 0)}, guess=((0.36, 0.93), -0.1), **link(4.0))
    ro = m.add_body("rocker", points={"tip": (3, 0)}, guess=((4, 0), 1.7), **link(3.0))
    m.add(ms.Revolute2(g.point((0, 0)), cr.point(0)), name="A")
    m.add(ms.Revolute2(cr.point("tip"), co.point(0)), name="B")
    m.add(ms.Revolute2(co.point("end"), ro.point("tip")), name="C")
    m.add(ms.Revolute2(g.point((4, 0)), ro.point(0)), name="D")
    m.add(ms.RotationLock1(cr, 1.2), name="drive")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    return m


def joint_gap(m, sol) -> float:
    """The largest component of a joint's gap at the last time, from point locations."""
    b = {k: m.body(k) for k in ("crank", "coupler", "rocker")}
    pairs = [(b["crank"].point(0), m.ground.point((0, 0))),
             (b["crank"].point("tip"), b["coupler"].point(0)),
             (b["coupler"].point("end"), b["rocker"].point("tip")),
             (b["rocker"].point(0), m.ground.point((4, 0)))]
    return max(float(np.abs(sol.location(p)[-1] - sol.location(q)[-1]).max()) for p, q in pairs)


@pytest.mark.parametrize("jit", ["python", "1"], ids=["python-stepper", "compiled-stepper"])
def test_drift_without_correction_is_reported_and_warned(jit, monkeypatch):
    # (the Python stepper whole: conftest.python_path; MECHSYS_JIT=0 runs the loop
    # interpreted, the compiled loop's numbers: decision 0082)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    if jit == "python":
        python_path(monkeypatch)
    m = four_bar()
    free = m.free(drop=["drive"])
    with pytest.warns(ms.DegradedAccuracyWarning, match="drifted") as rec:
        sol = free.simulate((0.0, 20.0), initial_condition={"crank.th_d": 3.0},
                            method="adams", constraint_correction=False)
    acc = sol.extra["accuracy"]
    gap = joint_gap(m, sol)
    # each revolute row's scale is L (the x coefficient 1 times L, above every lever arm)
    L = sol.extra["length_scale"]
    np.testing.assert_allclose(acc["position"] * L, gap, rtol=1e-9)
    assert gap > 1e-3                       # the drift is real: joints open by > 1e-3
    assert rec[0].message.measure == pytest.approx(acc["position"])
    # the same run with correction: on the constraints, and nothing to report
    with warnings.catch_warnings():
        warnings.simplefilter("error", ms.DegradedAccuracyWarning)
        good = free.simulate((0.0, 20.0), initial_condition={"crank.th_d": 3.0}, method="adams")
    assert joint_gap(m, good) < 1e-12
    assert good.extra["accuracy"]["position"] < 1e-12


def pendulum(x0):
    m = ms.Model2D()
    b = m.add_body("bar", points={"tip": (1, 0)}, mass=1.0, centroid=(1, 0), inertia=0.1,
                   guess=((x0, 0), -1.0))
    m.add(ms.Revolute2(m.ground.point((x0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, -1.0), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    return m.free(drop=["hold"])


def test_mechanism_far_from_the_origin_is_warned():
    """Placed 1e11 from the origin, a pendulum of length 1 is resolved only to
    eps * 1e11 = 2.2e-5 of its length, above the run's rtol (1e-8): warned; at 1e3 not."""
    with pytest.warns(ms.DegradedAccuracyWarning, match="from the origin") as rec:
        far = pendulum(1e11).simulate((0.0, 0.5))
    w = [r.message for r in rec if "origin" in str(r.message)][0]
    assert w.measure == pytest.approx(np.finfo(float).eps * 1e11, rel=1e-6)
    assert far.extra["accuracy"]["offset"] == pytest.approx(1e11, rel=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ms.DegradedAccuracyWarning)
        near = pendulum(1e3).simulate((0.0, 0.5))
    assert near.extra["accuracy"]["offset"] == pytest.approx(1e3, rel=1e-6)
