"""The compiled kinematic sweep (solvers/_jit.py) against the Python loop: the same numbers on
planar, spatial, parametric and toggle-passing sweeps, the hand-over to the Python loop at a
point it cannot take, and the cases where it must not run."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T, models
from mechsys.solvers import _jit

pytest.importorskip("numba")
pytestmark = pytest.mark.filterwarnings("ignore::mechsys.NearSingularWarning")


def _both(monkeypatch, build, t, **solve):
    """Solve the same sweep with the compiled loop and with the Python loop."""
    out = {}
    for mode in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", mode)
        m = build()
        out[mode] = m.solve(t, **solve)
    return out["1"], out["0"]


def _same(a, b):
    for x, y in ((a.q, b.q), (a.qd, b.qd), (a.qdd, b.qdd)):
        if x is None:
            assert y is None
            continue
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(a.iterations, b.iterations)
    assert a.evaluations == b.evaluations


def _spatial_crank():
    return models.slider_crank_3d()


@pytest.mark.parametrize("build", [models.slider_crank, models.four_bar, lambda: models.four_bar_chain(3),
                                   _spatial_crank, lambda: models.cardan_joint()],
                         ids=["slider-crank", "four-bar", "chain3", "slider-crank-3d", "cardan"])
def test_compiled_and_python_sweeps_agree(monkeypatch, build):
    t = np.linspace(0.0, 1.0, 61)
    fast, slow = _both(monkeypatch, build, t)
    _same(fast, slow)
    np.testing.assert_allclose(fast.extra["rcond"], slow.extra["rcond"], rtol=1e-12)


def _spline_cam():
    """A disk cam whose radius is a closed cubic spline (two-stage Piecewise kernels) pushing
    a follower along x (benchmarks/curves.py)."""
    a = np.linspace(0, 2 * np.pi, 25)
    r = ms.SplineFunction(2 + 0.3 * np.sin(3 * a), "closed", knots=a)
    m = ms.Model2D()
    cam = m.add_body("cam", guess=((0, 0), 0))
    fol = m.add_body("follower", guess=((2.0, 0), 0))
    u = sp.Symbol("u")
    prof = cam.point((r(u) * sp.cos(u), r(u) * sp.sin(u)))
    m.add(ms.Revolute2(m.ground.point((0, 0)), cam.point(0)))
    m.add(ms.RotationLock1(cam, 2 * sp.pi * T))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), fol.axis((0, 0), (1, 0))))
    loc = m.location(prof)
    x, y, _ = fol.q
    m.add(ms.Constraint([x - loc[0], y - loc[1]], {u: 0.0}), name="contact")
    return m, r


def test_spline_cam_two_stage_kernels(monkeypatch):
    """Piecewise kernels run in two stages; the compiled loop calls both: same numbers, and the
    follower is at r(-theta) with the spline's own derivatives."""
    t = np.linspace(0.0, 1.0, 81)
    fast, slow = _both(monkeypatch, lambda: _spline_cam()[0], t)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    assert _jit.plan(fast.system, 10, 2)[0, 2] != 0          # a first stage is there
    _same(fast, slow)
    r = _spline_cam()[1]
    uu = 2 * np.pi - 2 * np.pi * t
    np.testing.assert_allclose(fast.coordinate("follower.x"), r.derivative(uu, 0), atol=1e-10)
    np.testing.assert_allclose(fast.coordinate("follower.x", 2), 4 * np.pi**2 * r.derivative(uu, 2),
                               rtol=1e-8, atol=1e-8)


def test_compiled_path_ran(monkeypatch):
    """The agreement above is not two runs of the Python loop: the compiled loop is entered
    and finishes the sweep itself."""
    calls = []
    real = _jit.run

    def spy(*a, **k):
        out = real(*a, **k)
        calls.append(out)
        return out

    monkeypatch.setattr(_jit, "run", spy)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    sol = models.slider_crank().solve(np.linspace(0, 1, 50))
    assert calls and calls[0][0] == 50 and calls[0][1] == sol.evaluations - 1   # minus the scaling's


@pytest.mark.parametrize("order", ["location", "velocity", "acceleration"])
def test_orders_and_parameters(monkeypatch, order):
    def build():
        m = ms.Model2D()
        r = m.parameter("r", 2.0)
        cr = m.add_body("crank", points={"pin": (r, 0)}, guess=((0, 0), 0))
        rd = m.add_body("rod", points={"b": (6, 0)}, guess=((2, 0), 0))
        pi = m.add_body("piston", guess=((8, 0), 0))
        m.add(ms.Revolute2(m.ground.point((0, 0)), cr.point(0)))
        m.add(ms.Revolute2(cr.point("pin"), rd.point(0)))
        m.add(ms.Revolute2(rd.point("b"), pi.point(0)))
        m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), pi.axis((0, 0), (1, 0))))
        m.add(ms.RotationLock1(cr, 2 * sp.pi * T + 0.3 * sp.sin(4 * sp.pi * T)))
        m.set_parameters({"r": 1.5})
        return m

    t = np.linspace(0.0, 1.0, 41)
    fast, slow = _both(monkeypatch, build, t, solution=order)
    _same(fast, slow)
    # and the numbers are right: piston position from the closed form with r = 1.5
    th = 2 * np.pi * t + 0.3 * np.sin(4 * np.pi * t)
    x = 1.5 * np.cos(th) + np.sqrt(36 - (1.5 * np.sin(th)) ** 2)
    np.testing.assert_allclose(fast.coordinate("piston.x"), x, atol=1e-10)


def dead_centre_crank():
    """A slider-crank driven at the piston through both dead centres (tests/test_toggle.py),
    its crank turning at 2 pi rad/s from 0.05 revolutions."""
    W = 2 * np.pi
    m = models.slider_crank()
    m.remove("drive")
    m.add(ms.RelativeX1(m.body("piston").point(0),
                        2 * sp.cos(W * T) + sp.sqrt(36 - 4 * sp.sin(W * T) ** 2)), name="piston drive")
    th0 = 0.05 * W
    phi = np.arcsin(-2 * np.sin(th0) / 6)
    m.set_guess({"crank.th": th0, "rod.th": phi, "rod.x": 2 * np.cos(th0), "rod.y": 2 * np.sin(th0),
                 "piston.x": 2 * np.cos(th0) + 6 * np.cos(phi)})
    return m


def test_through_dead_centres_like_the_python_loop(monkeypatch):
    """The dead-centre crank: the compiled loop takes the near-singular points with the same
    predictor rules."""
    t = np.linspace(0.05, 1.05, 101)
    fast, slow = _both(monkeypatch, dead_centre_crank, t)
    _same(fast, slow)
    np.testing.assert_allclose(fast.angle("crank"), 2 * np.pi * t, atol=1e-5)


def test_hand_over_to_the_python_loop(monkeypatch):
    """At a point the compiled loop cannot take (here: Newton limited to one iteration, so it
    fails at once) it stops and the Python loop continues with its own handling: the error
    the user sees is the Python loop's, naming the time."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    m = models.slider_crank()
    with pytest.raises(ms.ConvergenceError, match="t = 0"):
        m.solve(np.linspace(0, 1, 20), options={"max_iterations": 1, "ftol": 1e-15})


def test_handover_mid_sweep_gives_the_python_result(monkeypatch):
    """Force the compiled loop to stop after 7 points: the rest is the Python loop's, and the
    whole equals an all-Python sweep."""
    real = _jit.run
    t = np.linspace(0.0, 1.0, 30)

    def partial(system, pointers, times, *rest):
        k, e = real(system, pointers, times[:7], *rest)
        return k, e

    monkeypatch.setattr(_jit, "run", partial)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    mixed = models.four_bar().solve(t)
    monkeypatch.setenv("MECHSYS_JIT", "0")
    plain = models.four_bar().solve(t)
    _same(mixed, plain)


def test_when_it_does_not_run(monkeypatch):
    s = models.slider_crank().compile()
    monkeypatch.setenv("MECHSYS_JIT", "0")
    assert _jit.plan(s, 10_000, 2) is None
    monkeypatch.setenv("MECHSYS_JIT", "1")
    assert _jit.plan(s, 5, 2) is not None
    monkeypatch.delenv("MECHSYS_JIT")
    assert _jit.plan(s, _jit.AUTO_POINTS - 1, 2) is None      # auto: too short to pay the load
    assert _jit.plan(s, _jit.AUTO_POINTS, 2) is not None
    models.slider_crank().solve(np.linspace(0, 1, _jit.AUTO_POINTS))   # loaded now ...
    assert _jit.plan(s, _jit.AUTO_POINTS - 1, 2) is None      # ... and still the same choice
    # the SymPy backend has no C entry points
    monkeypatch.setenv("MECHSYS_JIT", "1")
    monkeypatch.setenv("MECHSYS_BACKEND", "sympy")
    assert _jit.plan(models.slider_crank().compile(), 100, 2) is None


@pytest.mark.parametrize("value", ["of", "2", "enable", "ture"])
def test_a_misspelled_mode_is_an_error_not_a_default(monkeypatch, value):
    """MECHSYS_JIT=of must not quietly run the compiled loops (it would mean the opposite of
    what was typed): sweeps and free motion both refuse it, naming the variable."""
    m = models.slider_crank()
    chain = models.pendulum_chain(2)
    chain.solve(0.0)
    monkeypatch.setenv("MECHSYS_JIT", value)
    with pytest.raises(ms.ModelError, match="MECHSYS_JIT=.*use 0 .*1 .*auto"):
        m.solve(np.linspace(0.0, 1.0, 5))
    with pytest.raises(ms.ModelError, match="MECHSYS_JIT"):
        chain.free(drop=["lock0", "lock1"]).simulate((0.0, 0.1))
    for ok in ("AUTO", " 0 ", "On"):
        monkeypatch.setenv("MECHSYS_JIT", ok)
        assert _jit.mode() in ("auto", "off", "on")
