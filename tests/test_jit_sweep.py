"""The kinematic sweep's loop (solvers/_jit_sweep.py), compiled and interpreted: against
independent references (closed forms; loop-closure residuals, NumPy's dense solves of the
velocity and acceleration equations and central differences: ``_sweep_reference``), the two
tiers bit for bit on planar, spatial, parametric and toggle-passing sweeps, the hand-over to
the Python code at a point it cannot take, and the cases where the loop cannot run."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from _sweep_reference import check_sweep
from mechsys import T, models
from mechsys.solvers import _jit_runtime, _jit_sweep

pytest.importorskip("numba")
pytestmark = pytest.mark.filterwarnings("ignore::mechsys.NearSingularWarning")


def _both(monkeypatch, build, t, prefix=None, **solve):
    """Solve the same sweep with the loop compiled (``MECHSYS_JIT=1``) and interpreted
    (``0``, decision 0081; over ``t[:prefix]``: the loop is causal, so those are the whole
    sweep's first points)."""
    out = {}
    for mode in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", mode)
        m = build()
        out[mode] = m.solve(t if mode == "1" or prefix is None else t[:prefix], **solve)
    return out["1"], out["0"]


def _same(a, b, atol=None):
    """The same sweep: bit for bit (the loop compiled and interpreted), or to ``atol`` where
    one of them had points solved by the Python code (its LAPACK against the loop's LU)."""
    for x, y in ((a.q, b.q), (a.qd, b.qd), (a.qdd, b.qdd)):
        if x is None:
            assert y is None
            continue
        if atol is None:
            np.testing.assert_array_equal(x, y)
        else:
            np.testing.assert_allclose(x, y, rtol=0, atol=atol)
    np.testing.assert_array_equal(a.iterations, b.iterations)
    assert a.evaluations == b.evaluations


def _spatial_crank():
    return models.slider_crank_3d()


@pytest.mark.parametrize("build", [models.slider_crank, models.four_bar, lambda: models.four_bar_chain(3),
                                   _spatial_crank, lambda: models.cardan_joint()],
                         ids=["slider-crank", "four-bar", "chain3", "slider-crank-3d", "cardan"])
def test_compiled_and_interpreted_sweeps_are_right_and_agree(monkeypatch, build):
    t = np.linspace(0.0, 1.0, 61)
    fast, slow = _both(monkeypatch, build, t)
    assert fast.extra["compiled_points"] == len(t) and slow.extra["compiled_points"] == 0
    check_sweep(fast)
    _same(fast, slow)
    np.testing.assert_array_equal(fast.extra["rcond"], slow.extra["rcond"])


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
    """Piecewise kernels run in two stages; the loop calls both (compiled and interpreted: the
    same numbers), and the follower is at r(-theta) with the spline's own derivatives."""
    t = np.linspace(0.0, 1.0, 81)
    fast, slow = _both(monkeypatch, lambda: _spline_cam()[0], t)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    assert _jit_sweep.plan(fast.system, 10, 2)[0, 2] != 0          # a first stage is there
    _same(fast, slow)
    r = _spline_cam()[1]
    uu = 2 * np.pi - 2 * np.pi * t
    np.testing.assert_allclose(fast.coordinate("follower.x"), r.derivative(uu, 0), atol=1e-10)
    np.testing.assert_allclose(fast.coordinate("follower.x", 2), 4 * np.pi**2 * r.derivative(uu, 2),
                               rtol=1e-8, atol=1e-8)


def _gen_arm(links=4):
    """A planar arm in generalized coordinates (``GenRevolute2`` joints: CSE kernels) driven
    at its joints. Its Jacobian's entries are all 1: repeated outputs, which the CSE kernel
    computes once."""
    return models.driven_gen_arm(links, g=0.0)


def test_generalized_coordinates_sweep_compiled(monkeypatch):
    """Generalized coordinates compile their kernels with CSE, whose repeated outputs (here
    the Jacobian's ones) are computed once. The compiled sweep, which reads every output,
    gets the kernel compiled once more without CSE (``c_function``): the sweep runs compiled,
    with the interpreted loop's numbers and the drivers' closed form."""
    t = np.linspace(0.0, 2.0, 81)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    system = _gen_arm().compile()
    assert system.f_position.c_entry()[1] is not None          # repeated outputs
    assert _jit_sweep.plan(system, len(t), 2) is not None
    fast, slow = _both(monkeypatch, _gen_arm, t)
    _same(fast, slow)
    for k in range(4):
        w = k + 1
        np.testing.assert_allclose(fast[f"q{k}"], 0.3 * np.sin(w * t), rtol=0, atol=1e-12)
        np.testing.assert_allclose(fast.coordinate(f"q{k}", 2), -0.3 * w**2 * np.sin(w * t),
                                   rtol=0, atol=1e-10)
    _assert_compiled_sweep(monkeypatch, _gen_arm, t)


def _assert_compiled_sweep(monkeypatch, build, t):
    """The compiled loop is entered and finishes the sweep itself: every evaluation is the
    loop's (the scaling comes from its first one)."""
    calls = []
    real = _jit_sweep.run

    def spy(*a, **k):
        out = real(*a, **k)
        calls.append(out)
        return out

    monkeypatch.setattr(_jit_sweep, "run", spy)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    sol = build().solve(t)
    assert calls and calls[0][0] == len(t) and calls[0][1] == sol.evaluations


def test_compiled_path_ran(monkeypatch):
    """The agreement above is not two runs of one tier: the compiled loop is entered
    and finishes the sweep itself."""
    _assert_compiled_sweep(monkeypatch, models.slider_crank, np.linspace(0, 1, 50))


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


def test_through_dead_centres(monkeypatch):
    """The dead-centre crank: the loop takes the near-singular points with the predictor's
    rules; the crank turns at 2 pi rad/s (the closed form), the loop closes at every point,
    and the two tiers agree bit for bit (no LAPACK of the CPU's in either)."""
    t = np.linspace(0.05, 1.05, 101)
    fast, slow = _both(monkeypatch, dead_centre_crank, t)
    _same(fast, slow)
    np.testing.assert_allclose(fast.angle("crank"), 2 * np.pi * t, atol=1e-5)
    check_sweep(fast, differences=False)


def test_hand_over_to_the_python_loop(monkeypatch):
    """At a point the compiled loop cannot take (here: Newton limited to one iteration, so it
    fails at once) it stops and the Python loop continues with its own handling: the error
    the user sees is the Python loop's, naming the time."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    m = models.slider_crank()
    with pytest.raises(ms.ConvergenceError, match="t = 0"):
        m.solve(np.linspace(0, 1, 20), options={"max_iterations": 1, "ftol": 1e-15})


def test_handover_mid_sweep_gives_the_loops_result(monkeypatch):
    """Force the loop to stop at point 7 and at each point after it: those points are the
    Python code's (its predictor, Newton and LAPACK: an implementation of its own), and the
    whole equals the loop's sweep to rounding and is right by the references."""
    real = _jit_sweep.run
    t = np.linspace(0.0, 1.0, 30)

    def partial(system, pointers, times, *rest, **kw):
        return real(system, pointers, times[:7], *rest, **kw)

    monkeypatch.setenv("MECHSYS_JIT", "1")
    plain = models.four_bar().solve(t)
    monkeypatch.setattr(_jit_sweep, "run", partial)
    mixed = models.four_bar().solve(t)
    assert mixed.extra["compiled_points"] == 7
    _same(mixed, plain, atol=1e-12)
    check_sweep(mixed)


def _far_crank():
    """A millimetre slider-crank whose guess puts bodies a million times its size away (a
    large offset)."""
    m = models.slider_crank(crank=2e-3, rod=6e-3)
    m.set_guess({"piston.x": 7e3, "rod.x": -5e2, "rod.th": 0.3})
    return m


def _dead_centre_guess():
    """The guess at a dead centre: crank in line with the rod (the lever-arm round-off case
    of ``Scaling.of``)."""
    m = models.slider_crank()
    m.set_guess({"crank.th": 0.0, "rod.th": 0.0, "rod.x": 2.0, "piston.x": 8.0})
    return m


@pytest.mark.parametrize("build", [models.slider_crank, models.four_bar, _spatial_crank, _far_crank,
                                   _dead_centre_guess, dead_centre_crank,
                                   lambda: models.slider_crank(crank=2e-6, rod=6e-6)],
                         ids=["slider-crank", "four-bar", "spatial", "far", "dead-centre-guess",
                              "dead-centres", "micro"])
def test_the_loops_scaling_is_the_python_one(build):
    """Without a given scaling the compiled loop takes it from its first evaluation: the same
    length, offset and column scales as ``Scaling.of`` on ``system.jacobian`` at the guess."""
    from mechsys.solvers._linalg import Scaling, rotation_indices
    from mechsys.solvers._position import PositionOptions

    m = build()
    s = m.compile()
    q0, p = m.guess(), m._p()
    t = np.linspace(0.0, 0.1, 3)
    want = Scaling.of(s, q0, s.jacobian(t[0], q0, p))
    N, n = len(t), s.n
    out = [np.empty((N, n)) for _ in range(3)]
    _, _, got, _ = _jit_sweep.run(s, _jit_sweep.plan(s, 10_000, 2), t, q0, p, 2, PositionOptions(), None,
                         rotation_indices(s), *out, np.zeros(N, dtype=int), np.full(N, np.nan),
                         np.ones(n))
    assert got.length == want.length and got.offset == want.offset
    np.testing.assert_array_equal(got.columns, want.columns)


def _stub(bodies, variables, hint):
    """A planar system's layout only (what ``Scaling.of`` reads)."""
    from types import SimpleNamespace

    slices = {f"b{k}": slice(3 * k, 3 * k + 3) for k in range(bodies)}
    return SimpleNamespace(n=3 * bodies + variables, space=SimpleNamespace(dim=2),
                           layout=SimpleNamespace(body_slices=slices), length_hint=hint)


def test_the_loops_scaling_takes_every_branch_like_scaling_of():
    """``_jit_sweep_loop._scaling`` against ``Scaling.of`` on random Jacobians of every kind it
    decides on: ordinary, lever arms at round-off (the fallback to the hint or to the
    coordinates), entries and coordinates not finite, empty rows, model variables, no
    length at all."""
    from mechsys.solvers._jit_sweep_loop import _scaling
    from mechsys.solvers._linalg import Scaling, _column_kinds

    rng = np.random.default_rng(5)
    seen = set()                            # which length each trial came to
    for trial in range(300):
        bodies, variables = int(rng.integers(1, 5)), int(rng.integers(0, 3))
        hint = [0.0, 1.0, 6.0, 1e-3][(trial // 6) % 4]   # every hint with every kind
        sys_ = _stub(bodies, variables, hint)
        n = sys_.n
        trans, body = _column_kinds(sys_)
        J = rng.standard_normal((n, n)) * (rng.random((n, n)) < 0.4) * 10.0 ** rng.integers(-6, 7)
        q = rng.standard_normal(n) * 10.0 ** rng.integers(-3, 4)
        kind = trial % 6
        if kind == 1:                       # rotational entries at round-off of the lengths
            J[:, ~trans & (body >= 0)] *= 1e-17
        elif kind == 2:
            J[rng.integers(n), rng.integers(n)] = np.nan
            J[rng.integers(n), rng.integers(n)] = np.inf
        elif kind == 3:
            q[trans.nonzero()[0][0]] = [np.inf, np.nan][trial % 2]
        elif kind == 4:
            J[rng.integers(n)] = 0.0        # an empty row
        elif kind == 5:
            J[:] = 0.0                      # no lengths anywhere
            q[:] = 0.0
        want = Scaling.of(sys_, q, J)
        columns = np.empty(n)
        L, offset = _scaling(J, q, trans, body, max(int(body.max()) + 1, 0), hint, columns)
        assert L == want.length and offset == want.offset, trial
        np.testing.assert_array_equal(columns, want.columns)
        big = np.abs(q[trans]).max() if np.isfinite(q[trans]).all() else 0.0
        seen.add("hint" if L == hint else "coordinates" if L == big else "one" if L == 1.0
                 else "lever arm")
    assert seen == {"lever arm", "hint", "coordinates", "one"}


def test_when_it_does_not_run(monkeypatch):
    """The loop takes every sweep it can (decision 0081): ``MECHSYS_JIT`` chooses the tier
    only (``0`` interpreted; ``auto`` loads the compiled loop for jobs that repay it, else
    uses it only when loaded); the SymPy backend's kernels have no C entry points."""
    s = models.slider_crank().compile()
    monkeypatch.setitem(_jit_runtime._state, "interpreted", 0.0)   # (no small job before)
    monkeypatch.setenv("MECHSYS_JIT", "0")
    assert _jit_sweep.plan(s, 10_000, 2) is not None
    assert _jit_runtime.tier(10_000, s.n) == "interpreted"
    monkeypatch.setenv("MECHSYS_JIT", "1")
    assert _jit_sweep.plan(s, 5, 2) is not None and _jit_runtime.tier(5, s.n) == "load"
    monkeypatch.delenv("MECHSYS_JIT")
    assert _jit_runtime.tier(100, s.n) == "loaded"     # auto: too short to repay the load
    # ... but many of them do: their predicted interpreted time adds up to AUTO_SECONDS
    assert _jit_runtime.tier(600, s.n) == "load"
    assert _jit_runtime.tier(_jit_runtime.AUTO_POINTS, s.n) == "load"
    # (a large system's job repays the load sooner: its interpreted points cost more)
    assert _jit_runtime.tier(200, 63) == "load"
    # more equations than coordinates: the Python code
    over = ms.Model2D()
    b = over.add_body("b", guess=((0, 0), 0))
    over.add(ms.Revolute2(over.ground.point((0, 0)), b.point(0)))
    over.add(ms.RotationLock1(b, T))
    over.add(ms.Constraint([b.q[0]]), name="again")
    assert _jit_sweep.plan(over.compile(), 100, 2) is None


def test_sympy_backend_kernels_run_in_the_loop(monkeypatch):
    """The SymPy backend's kernels have no C entry points; the loop calls their Python
    functions through ``ctypes`` callbacks (``_jit_runtime.python_entry``, decision 0081):
    every point and every multiplier is the loop's, compiled and interpreted bit for bit,
    right by the references and equal to the SymEngine backend's to rounding."""
    from _sweep_reference import check_multipliers
    from test_jit_multipliers import spy_multipliers

    taken = spy_multipliers(monkeypatch)
    t = np.linspace(0.0, 1.0, 41)
    monkeypatch.setenv("MECHSYS_BACKEND", "sympy")
    out = {}
    for jit in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        m = models.slider_crank_dynamic()
        assert m.compile().f_position.backend == "sympy"
        out[jit] = m.solve(t, solution="dynamic")
    fast, slow = out["1"], out["0"]
    assert fast.extra["compiled_points"] == len(t) and taken == [len(t), len(t)]
    _same(fast, slow)
    np.testing.assert_array_equal(fast.lam, slow.lam)
    check_sweep(fast)
    check_multipliers(fast)
    monkeypatch.setenv("MECHSYS_BACKEND", "symengine")
    ref = models.slider_crank_dynamic().solve(t, solution="dynamic")
    np.testing.assert_allclose(fast.q, ref.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fast.lam, ref.lam, rtol=0, atol=1e-10 * np.abs(ref.lam).max())


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
        assert _jit_runtime.mode() in ("auto", "off", "on")


def _runs(monkeypatch):
    """Record ``(first point left to Python, evaluations)`` of each compiled sweep."""
    real, got = _jit_sweep.run, []

    def run(*a, **k):
        out = real(*a, **k)
        got.append(out[:2])
        return out

    monkeypatch.setattr(_jit_sweep, "run", run)
    return got


@pytest.mark.parametrize("loops", [30, 60])
def test_large_banded_sweep_is_compiled_with_the_same_numbers(monkeypatch, loops):
    """Above SPARSE_THRESHOLD coordinates (a chain of 183 and 363) the compiled loop takes
    the sweep through the Jacobian's FixedPattern (the compiled sparse LU both paths call):
    the interpreted loop's numbers bit for bit, with its iterations, evaluations and pivot
    ratios, and right by the references (loop closure, NumPy's dense solves, central
    differences)."""
    from mechsys.solvers._tolerances import SPARSE_THRESHOLD

    runs = _runs(monkeypatch)
    t = np.linspace(0.0, 2 * np.pi, 41)
    fast, slow = _both(monkeypatch, lambda: models.four_bar_chain(loops), t, prefix=3)
    assert fast.system.n > SPARSE_THRESHOLD
    assert runs and runs[0][0] == len(t)                   # every point compiled
    for x, y in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd),
                 (fast.extra["rcond"], slow.extra["rcond"])):
        np.testing.assert_array_equal(x[:3], y)
    np.testing.assert_array_equal(fast.iterations[:3], slow.iterations)
    # the chain's exact motion: every crank turns with the driver
    assert np.isfinite(fast.extra["rcond"]).all() and (fast.extra["rcond"] > 1e-6).all()
    check_sweep(fast)


def test_large_banded_sweep_hands_over_and_continues(monkeypatch):
    """The compiled loop stopped at point 7 and every point after it: the Python code takes
    those (its chord refactorised from the loop's row scales; its own predictor, Newton and
    sparse factorisation: an independent implementation), and the sweep is the loop's to
    rounding.
    A sweep continuing prior points (``prior`` with the chord's rows) is the long sweep, bit
    for bit, in the banded loop too."""
    from mechsys.solvers import sweep

    real = _jit_sweep.run
    t = np.linspace(0.0, 1.0, 30)

    def partial(system, pointers, times, *rest, **kw):
        return real(system, pointers, times[:7], *rest, **kw)

    monkeypatch.setenv("MECHSYS_JIT", "1")
    plain = models.four_bar_chain(30).solve(t)
    monkeypatch.setattr(_jit_sweep, "run", partial)
    mixed = models.four_bar_chain(30).solve(t)
    assert mixed.extra["compiled_points"] == 7
    _same(mixed, plain, atol=1e-12)
    monkeypatch.setattr(_jit_sweep, "run", real)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    s = models.four_bar_chain(30).compile()
    t = np.linspace(0.0, 2.0, 40)
    whole = sweep(s, t, s.guess, 2)
    k = 17
    head = sweep(s, t[:k], s.guess, 2)
    prior = (t[k - 3:k], head.q[-3:], head.qd[-3:], head.qdd[-3:], head.rcond[-3:], head.rows)
    rest = sweep(s, t[k:], None, 2, None, None, head.scaling, prior=prior)
    for a, b in ((rest.q, whole.q[k:]), (rest.qd, whole.qd[k:]), (rest.qdd, whole.qdd[k:]),
                 (rest.rcond, whole.rcond[k:]), (rest.iterations, whole.iterations[k:])):
        np.testing.assert_array_equal(a, b)


def _piston_travel(c, r, angle):
    """The slider-crank's closed form: the piston's distance from the crank's axis when the
    crank is at ``angle`` from the cylinder's axis."""
    return c * np.cos(angle) + np.sqrt(r**2 - (c * np.sin(angle)) ** 2)


@pytest.mark.parametrize("cylinders", [30, 60])
def test_wide_pattern_sweep_is_compiled_with_the_same_numbers(monkeypatch, cylinders):
    """A radial engine (every rod on the crank pin: a star, whose band is as wide as the
    engine; 183 and 363 coordinates) runs compiled through the sparse LU both loops call:
    the interpreted loop's numbers bit for bit. Against the closed form of each cylinder's
    slider-crank, and against SuperLU (no Numba: the same ordering and pivoting) to
    rounding."""
    from mechsys.solvers import _linalg

    runs = _runs(monkeypatch)
    t = np.linspace(0.0, 0.5, 26)
    fast, slow = _both(monkeypatch, lambda: models.radial_engine(cylinders), t, prefix=3)
    s = fast.system
    assert not s.jacobian_pattern().banded and runs and runs[0][0] == len(t)
    for x, y in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd),
                 (fast.extra["rcond"], slow.extra["rcond"])):
        np.testing.assert_array_equal(x[:3], y)
    np.testing.assert_array_equal(fast.iterations[:3], slow.iterations)
    theta = 2 * np.pi * t
    for k in (0, cylinders // 3, cylinders - 1):
        a = 2 * np.pi * k / cylinders
        want = _piston_travel(1.0, 4.0, theta - a)
        x = fast.coordinate(f"piston{k}.x")
        y = fast.coordinate(f"piston{k}.y")
        np.testing.assert_allclose(np.hypot(x, y), want, rtol=0, atol=1e-10)
    # without Numba: SuperLU, with the same ordering and pivoting (the same pivot ratios)
    monkeypatch.setattr(_linalg, "COMPILED_LU", False)
    runs.clear()
    ref = models.radial_engine(cylinders).solve(t)
    assert not runs
    assert type(ref.system.jacobian_pattern().factor(
        ref.system.jacobian(0.1, ref.q[3], ref.p, True).data)).__name__ == "_SuperFactor"
    for x, y in ((fast.q, ref.q), (fast.qd, ref.qd), (fast.qdd, ref.qdd)):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-12 * np.abs(y).max())
    np.testing.assert_allclose(fast.extra["rcond"], ref.extra["rcond"], rtol=1e-9)


def test_large_loop_needs_the_pattern(monkeypatch):
    """Above SPARSE_THRESHOLD the loops run only where they were asked to take a pattern."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    s = models.four_bar_chain(30).compile()
    assert _jit_sweep.plan(s, 10, 2) is not None
    assert not _jit_runtime.runnable(s)


def test_sparse_lu_storage_too_small_hands_over_and_grows(monkeypatch):
    """The compiled loop's factors live in storage sized from the pattern's estimate: when the
    fill exceeds it the loop hands the point to the Python path, whose factorisation grows
    the storage (and keeps it for the next run); the sweep is the same as with room enough."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    t = np.linspace(0.0, 0.2, 12)
    plain = models.radial_engine(30).solve(t)
    m = models.radial_engine(30)
    pat = m.compile().jacobian_pattern()
    monkeypatch.setattr(pat, "_cap", [8, 8])
    runs = _runs(monkeypatch)
    tight = m.solve(t)
    assert runs and runs[0][0] == 0                # the first point already handed over
    assert min(pat._cap) > 8                        # grown by the Python path
    for x, y in ((tight.q, plain.q), (tight.qd, plain.qd), (tight.qdd, plain.qdd)):
        np.testing.assert_array_equal(x, y)
    runs.clear()
    again = m.solve(t)
    assert runs and runs[0][0] == len(t)            # the next run has the room
    np.testing.assert_array_equal(again.q, plain.q)


def test_a_forced_hand_over_is_one_python_point(monkeypatch):
    """The loop made to stop at point 7 once: the Python code solves that point alone and the
    loop takes the rest; the numbers are those of the loop throughout, to rounding (the
    Python code's LAPACK against the loop's written-out LU at one point)."""
    real = _jit_sweep.run
    t = np.linspace(0.0, 1.0, 30)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    whole = models.four_bar().solve(t)
    seen = []

    def once(system, pointers, times, *rest, **kw):
        seen.append(rest[-2])
        return real(system, pointers, times[:7] if len(seen) == 1 else times, *rest, **kw)

    monkeypatch.setattr(_jit_sweep, "run", once)
    mixed = models.four_bar().solve(t)
    assert seen == [0, 8] and mixed.extra["compiled_points"] == 29
    _same(whole, mixed)
