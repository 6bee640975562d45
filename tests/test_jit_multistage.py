"""Multistage sweeps in runs of one stage combination (decision 0029): the compiled loops and
the Python ones give the same positions, rates, stages and multipliers; each recorded stage is
the one its tests choose at its own solution; a sweep continuing earlier points (``prior``)
is the long sweep; ``partial`` keeps the points before a failure."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T, models
from mechsys.analyses import _multistage
from mechsys.solvers import _jit_multipliers, _jit_runtime, _jit_sweep, sweep
from mechsys.solvers._tolerances import RCOND_WARN
from test_multistage_free import lp, pushed_slider

pytestmark = pytest.mark.skipif(not _jit_runtime.available(), reason="Numba not installed")


def _spy(monkeypatch, module, name):
    """Record the value each call of ``module.name`` returns."""
    real = getattr(module, name)
    got = []

    def spy(*a, **k):
        got.append(real(*a, **k))
        return got[-1]

    monkeypatch.setattr(module, name, spy)
    return got


def _both(monkeypatch, build, t, **kw):
    runs = _spy(monkeypatch, _jit_sweep, "run")
    out = {}
    for jit in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        out[jit] = build().solve(t, **kw)
    return out["1"], out["0"], runs


def _close(a, b, tol=1e-12):
    a, b = np.asarray(a), np.asarray(b)
    scale = np.maximum(1.0, np.abs(b).max(axis=0))
    return (np.abs(a - b) / scale).max() <= tol


def _geneva_exact(sol, slots=4):
    r"""The Geneva wheel's angle and its first two time derivatives by the closed form, from
    the solved stages and crank angle (the crank turns at 1 rad/s): engaged,
    :math:`w = -2\pi k/n - \varphi`, :math:`\varphi = \operatorname{atan2}(\sin r, c -
    \cos r)` with :math:`r = \theta - 2\pi k`, :math:`c = 1/\sin(\pi/n)`, so
    :math:`\dot w = -(c\cos r - 1)/D` and :math:`\ddot w = c \sin r\,(c^2 - 1)/D^2`,
    :math:`D = c^2 + 1 - 2c\cos r`; locked in stage ``s``, :math:`\pi/n\,(2 - s)` at rest."""
    st, th = sol.stage("geneva"), sol.angle("crank")
    engaged = st % 2 == 0
    k = st // 2 - 1
    r = th - 2 * np.pi * k
    c = 1 / np.sin(np.pi / slots)
    D = c * c + 1 - 2 * c * np.cos(r)
    w = np.where(engaged, -2 * np.pi * k / slots - np.arctan2(np.sin(r), c - np.cos(r)),
                 np.pi / slots * (2 - st))
    wd = np.where(engaged, -(c * np.cos(r) - 1) / D, 0.0)
    wdd = np.where(engaged, c * np.sin(r) * (c * c - 1) / D**2, 0.0)
    return w, wd, wdd


@pytest.mark.parametrize("solution", ["location", "velocity", "acceleration"])
def test_compiled_and_interpreted_multistage_sweeps_agree(monkeypatch, solution):
    """The Geneva drive's multistage sweep: the loop compiled and interpreted (decision
    0081) bit for bit, and the wheel's angle, velocity and acceleration those of the closed
    form (``_geneva_exact``) at every point."""
    t = np.linspace(0, 4 * np.pi, 401)
    fast, slow, runs = _both(monkeypatch, models.geneva_drive, t, solution=solution)
    assert runs and sum(done for _, done, _, _ in runs) > 0.8 * len(t)  # the compiled loop ran
    np.testing.assert_array_equal(fast.stage("geneva"), slow.stage("geneva"))
    assert sorted(set(slow.stage("geneva"))) == [1, 2, 3, 4, 5]
    np.testing.assert_allclose(fast.angle("crank"), t - np.pi, rtol=0, atol=1e-12)
    w, wd, wdd = _geneva_exact(fast)
    np.testing.assert_allclose(fast.angle("wheel"), w, rtol=0, atol=1e-11)
    np.testing.assert_array_equal(fast.q, slow.q)
    if solution != "location":
        np.testing.assert_array_equal(fast.qd, slow.qd)
        np.testing.assert_allclose(fast.omega("wheel"), wd, rtol=0, atol=1e-10)
    if solution == "acceleration":
        np.testing.assert_array_equal(fast.qdd, slow.qdd)
        np.testing.assert_allclose(fast.alpha("wheel"), wdd, rtol=0, atol=1e-9)


@pytest.mark.parametrize("slots", [4, 6])
def test_geneva_drive_follows_its_closed_form_and_each_stage_its_test(monkeypatch, slots):
    monkeypatch.setenv("MECHSYS_JIT", "1")
    m = models.geneva_drive(slots)
    t = np.linspace(0, 4 * np.pi, 641)
    sol = m.solve(t)
    st, th, w = sol.stage("geneva"), sol.angle("crank"), sol.angle("wheel")
    engaged = st % 2 == 0
    k = st // 2 - 1                          # engagement number while engaged
    rel = th - 2 * np.pi * k
    phi = np.arctan2(np.sin(rel), 1 / np.sin(np.pi / slots) - np.cos(rel))
    assert np.abs(w - (-2 * np.pi * k / slots - phi))[engaged].max() < 1e-11
    for s in (1, 3, 5):                      # locked: pi/n - 2 pi j / n
        assert np.abs(w[st == s] - np.pi / slots * (2 - s)).max() < 1e-12
    # every recorded stage is the one the tests choose at the point's own solution
    tests = _multistage._Tests(m, m.compile())
    p = m._p()
    each = [tests.stages(ti, qi, p, {})[0] for ti, qi in zip(sol.t, sol.q)]
    np.testing.assert_array_equal(np.array(each) + 1, st)
    np.testing.assert_array_equal(tests.stages_over(sol.t, sol.q, p, {})[:, 0] + 1, st)


def test_geneva_drive_in_any_unit_and_its_bad_input():
    """The wheel's angles and the stages do not depend on the unit of length; bad arguments
    are named."""
    t = np.linspace(0, 4 * np.pi, 161)
    ref = models.geneva_drive(center_distance=2.0).solve(t)
    for c in (2e-3, 2e3):
        sol = models.geneva_drive(center_distance=c).solve(t)
        np.testing.assert_array_equal(sol.stage("geneva"), ref.stage("geneva"))
        np.testing.assert_allclose(sol.angle("wheel"), ref.angle("wheel"), atol=1e-12)
    for kw, what in (({"slots": 2}, "slots"), ({"slots": 4.5}, "slots"), ({"turns": 0}, "turns"),
                     ({"center_distance": 0.0}, "center_distance"),
                     ({"center_distance": float("nan")}, "center_distance"),
                     ({"center_distance": "two"}, "center_distance")):
        with pytest.raises(ms.ModelError, match=f"geneva_drive: {what}"):
            models.geneva_drive(**kw)


def _jog(mass):
    m = ms.Model2D()
    s = m.add_body("slider", points={"pin": (0, 0)}, guess=((0, 0), 0), mass=mass, inertia=1.0)
    pin = s.point("pin")
    m.add(ms.RelativeX1(pin, 0.5 * T + 0.1 * sp.sin(3 * T)), name="drive")
    m.add(ms.RotationLock1(s, 0), name="no rotation")
    ramp = ms.PointOnLine1(pin, m.ground.axis((2.0, 0), (np.cos(0.5), np.sin(0.5))))
    m.add(ms.StageSwitch((s.q[0] < 2.0, ms.RelativeY1(pin, 0)), (True, ramp)), name="jog")
    m.add_load(ms.Force(pin, (0, -1), 20.0))
    return m


@pytest.mark.parametrize("solution", ["static", "kinematic", "dynamic"])
def test_compiled_and_interpreted_multipliers_over_stages_agree(monkeypatch, solution):
    taken = _spy(monkeypatch, _jit_multipliers, "multipliers")
    t = np.linspace(0, 8, 161)
    fast, slow, _ = _both(monkeypatch, lambda: _jog(2.0), t, solution=solution)
    np.testing.assert_array_equal(fast.stage("jog"), slow.stage("jog"))
    assert set(slow.stage("jog")) == {1, 2}
    compiled = [k for k in taken if k]
    # each stage's run of points by the loop, compiled and then interpreted (decision 0081)
    assert sum(compiled) == 2 * len(t)
    assert np.abs(slow.lam).max() > 1.0
    np.testing.assert_array_equal(fast.lam, slow.lam)
    # the balance Phi_q^T lambda = Q + Qv - M qdd with each point's stage Jacobian
    if solution == "static":
        J, lam, Q = fast.jacobian(ms.All, ms.All), fast.generalized(ms.All), fast.loads(ms.All)
        np.testing.assert_allclose(np.einsum("kij,ki->kj", J, lam), Q, atol=1e-11)


def test_multistage_sweep_follows_the_auto_rule(monkeypatch):
    """``auto``: the whole multistage sweep's size decides the tier, as for a plain sweep
    (decision 0081): each run of a stage is given the whole job's size."""
    monkeypatch.delenv("MECHSYS_JIT", raising=False)
    asked = []
    real = _jit_runtime.tier

    def tier(points, n):
        asked.append(points)
        return real(points, n)

    monkeypatch.setattr(_jit_runtime, "tier", tier)
    m = models.geneva_drive()
    m.solve(np.linspace(0, 4 * np.pi, 201))
    assert asked and set(asked) == {201}
    asked.clear()
    m.solve(np.linspace(0, 4 * np.pi, _jit_runtime.AUTO_POINTS + 1))
    assert asked and set(asked) == {_jit_runtime.AUTO_POINTS + 1}


@pytest.mark.parametrize("jit", ["1", "0"])
def test_sweep_continuing_prior_points_is_the_long_sweep(monkeypatch, jit):
    """A sweep over the first points, then one continuing it (``prior`` with its ``rows``,
    the chord): the numbers of one long sweep, bit for bit; without the chord, to rounding."""
    monkeypatch.setenv("MECHSYS_JIT", jit)
    s = models.four_bar().compile()
    t = np.linspace(0, 6, 241)
    whole = sweep(s, t, s.guess, 2)
    k = 100
    head = sweep(s, t[:k], s.guess, 2)
    assert head.rows is not None and head.rows.shape == (s.n,)
    prior = (t[k - 3:k], head.q[-3:], head.qd[-3:], head.qdd[-3:], head.rcond[-3:])
    rest = sweep(s, t[k:], None, 2, None, None, head.scaling, prior=prior + (head.rows,))
    assert rest.stopped is None and len(rest.t) == len(t) - k
    for a, b in ((rest.q, whole.q[k:]), (rest.qd, whole.qd[k:]), (rest.qdd, whole.qdd[k:]),
                 (rest.rcond, whole.rcond[k:]), (rest.iterations, whole.iterations[k:])):
        np.testing.assert_array_equal(a, b)
    no_chord = sweep(s, t[k:], None, 2, None, None, head.scaling, prior=prior)
    for a, b in ((no_chord.q, whole.q[k:]), (no_chord.qd, whole.qd[k:])):
        assert _close(a, b, 1e-13)
    assert (rest.rcond >= RCOND_WARN).all()
    with pytest.raises(ms.ModelError, match="needs their scaling"):
        sweep(s, t[k:], None, 2, prior=prior)
    with pytest.raises(ms.ModelError, match=r"prior QDD must be an array of shape \(3, 6\)"):
        sweep(s, t[k:], None, 2, None, None, whole.scaling, prior=prior[:3] + (None, prior[4]))
    with pytest.raises(ms.ModelError, match="prior must be"):
        sweep(s, t[k:], None, 2, None, None, whole.scaling, prior=whole.q[:3])
    bad = (prior[0], prior[1] * np.nan) + prior[2:]
    with pytest.raises(ms.ModelError, match="prior Q must be"):
        sweep(s, t[k:], None, 2, None, None, whole.scaling, prior=bad)


@pytest.mark.parametrize("jit", ["1", "0"])
def test_partial_sweep_keeps_the_points_before_a_failure(monkeypatch, jit):
    """A pin on a circle of radius 1 driven along x = T has no position past T = 1: the sweep
    raises there, and with ``partial`` returns the points before it and the error."""
    monkeypatch.setenv("MECHSYS_JIT", jit)
    m = ms.Model2D()
    b = m.add_body("arm", points={"tip": (1, 0)}, guess=((0, 0), 1.5))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)))
    m.add(ms.RelativeX1(b.point("tip"), T), name="drive")
    s = m.compile()
    t = np.linspace(0, 1.2, 121)             # T = 1 at index 100
    with pytest.raises((ms.ConvergenceError, ms.SingularJacobianError)):
        sweep(s, t, s.guess, 2)
    with pytest.warns(ms.NearSingularWarning, match="t = 1 "):     # (the last point kept)
        got = sweep(s, t, s.guess, 2, partial=True)
    assert isinstance(got.stopped, (ms.ConvergenceError, ms.SingularJacobianError))
    assert 90 <= len(got.t) <= 101 and len(got.q) == len(got.t) == len(got.iterations)
    np.testing.assert_allclose(np.cos(got.q[:, 2]), got.t, atol=1e-9)   # tip x = T
    assert np.isfinite(got.q).all() and np.isfinite(got.qd).all()


# -- free motion through stage changes: compiled steps between events ---------------------
def _latching():
    m = lp.build()
    m.solve(0.0, solution="location")
    return m.free(drop=[("latch", 1)])


SWITCHED = {
    "latch": (_latching, np.linspace(0.0, 1.0, 21), {"at_switch": "project"}),
    "rebound": (_latching, np.linspace(0.0, 1.0, 21), {"at_switch": ("restitution", 0.5)}),
    "load": (pushed_slider, np.linspace(0, 3, 13), {}),
}


@pytest.mark.parametrize("name", list(SWITCHED))
def test_compiled_and_python_free_motion_with_switches_agree(monkeypatch, name):
    build, t, kw = SWITCHED[name]
    out = {}
    for jit in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        out[jit] = build().simulate(t, rtol=1e-10, atol=1e-12, **kw)
    fast, slow = out["1"], out["0"]
    assert slow.extra["compiled_steps"] == 0
    assert fast.extra["compiled_steps"] >= 0.7 * fast.extra["steps"] > 5
    ev_f, ev_s = fast.extra["events"], slow.extra["events"]
    assert [e["kind"] for e in ev_f] == [e["kind"] for e in ev_s] and ev_s
    np.testing.assert_allclose([e["t"] for e in ev_f], [e["t"] for e in ev_s], atol=1e-12)
    np.testing.assert_array_equal(fast.stage("latch") if name != "load" else 0,
                                  slow.stage("latch") if name != "load" else 0)
    assert fast.q.shape == slow.q.shape
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd)):
        assert _close(a, b, 1e-9)


def test_compiled_free_motion_with_switches_follows_the_closed_form(monkeypatch):
    monkeypatch.setenv("MECHSYS_JIT", "1")
    t = np.linspace(0, 3, 13)
    sol = pushed_slider().simulate(t, rtol=1e-10, atol=1e-12)
    assert sol.extra["compiled_steps"] > 0
    a = 3.0 / 2.0
    x = np.where(t < 1, 0, np.where(t < 2, a / 2 * (t - 1) ** 2, a / 2 + a * (t - 2)))
    np.testing.assert_allclose(sol["slider.x"], x, atol=1e-10)
    assert [round(e["t"], 12) for e in sol.extra["events"]] == [1.0, 2.0]


def test_rk45_with_switches_is_compiled_too(monkeypatch):
    """RK45 through stage changes: the compiled steps between events, the same events and
    states as the Python loop."""
    out = {}
    for jit in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        out[jit] = _latching().simulate(np.linspace(0.0, 1.0, 21), method="rk45", rtol=1e-10,
                                        atol=1e-12, at_switch="project")
    fast, slow = out["1"], out["0"]
    assert fast.extra["compiled_steps"] > 0 and slow.extra["compiled_steps"] == 0
    assert len(fast.extra["events"]) == len(slow.extra["events"]) > 0
    for a, b in zip(fast.extra["events"], slow.extra["events"]):
        assert abs(a["t"] - b["t"]) < 1e-9
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd)):
        assert _close(a, b, 1e-8)
