"""The first tier of decision 0064: while a compiled loop is being compiled in the background,
``_jit_modes.entry`` returns None and every analysis must take its first tier and give that
tier's answer: the loop's own code interpreted where it runs (the sweep, the multiplier
solves: decisions 0075 and 0081, which also run it under ``MECHSYS_JIT=0``; the free-motion
Runge-Kutta stepper of a small system: decision 0077; the compiled loop's numbers, which
agree with the Python path's to rounding here), else the Python path. The suite runs with
``MECHSYS_COMPILE=wait`` (conftest), so that tier is never met there otherwise; here
``entry`` is made to answer "still compiling" for every loop, as a
first session with empty caches does, and each analysis is compared with
``MECHSYS_JIT=0``.

A switched free motion whose first stage holds velocity rows crashed on it: the compiled
stepper handed back no steps and the event signs of zero states could not be shaped.
"""

from __future__ import annotations

import numpy as np
import pytest

import mechsys as ms
from _sweep_reference import check_multipliers, check_sweep
from conftest import load_example
from mechsys.solvers import _jit_modes

sleigh = load_example("chaplygin_sleigh")


@pytest.fixture
def compiling(monkeypatch):
    """``entry`` always answers "being compiled in the background"; returns a function that
    runs ``job()`` first with ``MECHSYS_JIT=0`` and then in that state."""
    asked = []

    def still_compiling(dispatcher, args, literal=(), say=None):
        asked.append(getattr(dispatcher, "__name__", dispatcher))
        return None

    def both(job):
        monkeypatch.setenv("MECHSYS_JIT", "0")
        plain = job()
        monkeypatch.setenv("MECHSYS_JIT", "1")
        monkeypatch.setattr(_jit_modes, "entry", still_compiling)
        asked.clear()
        tier = job()
        monkeypatch.undo()
        return plain, tier, list(asked)

    return both


def _same(a, b, tol=1e-12):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape
    assert np.array_equal(np.isnan(a), np.isnan(b))
    ok = ~np.isnan(a)
    assert np.abs(a[ok] - b[ok]).max(initial=0.0) <= tol * max(1.0, np.abs(a[ok]).max(initial=0.0))


def _sleigh():
    m = ms.Model2D()
    b = m.add_body("sleigh", points={"P": (-sleigh.OFFSET, 0.0)}, guess=sleigh.START,
                   mass=sleigh.MASS, inertia=sleigh.INERTIA)
    return m, b, m.velocity(b.point("P"))


def test_blade_touching_down_at_a_time_switch(compiling):
    def job():
        m, b, v = _sleigh()
        blade = ms.Orthogonal1(v, b.vector((0, 1)))
        m.add(ms.TimeSwitch(blade, 1.0, ms.Orthogonal1(v, b.vector((0, 1)))), name="edge")
        fs = m.free(drop=[("edge", 1)])
        return fs.simulate(np.linspace(0, 2.0, 11), at_switch="project",
                           initial_condition={"sleigh.x_d": 0.5, "sleigh.y_d": 0.8, "sleigh.th_d": 1.0})

    plain, tier, asked = compiling(job)
    assert asked, "the compiled stepper was never asked for"
    _same(plain.q, tier.q)
    _same(plain.qd, tier.qd)
    _same(plain.extra["mu"], tier.extra["mu"])
    assert [e["t"] for e in plain.extra["events"]] == [e["t"] for e in tier.extra["events"]]


def test_blade_released_at_an_event(compiling):
    def job():
        m, b, v = _sleigh()
        stop = sleigh.START[1] + 0.5
        m.add(ms.StageSwitch((b.q[2] < stop, ms.Orthogonal1(v, b.vector((0, 1)))),
                             (True, ms.Orthogonal1(v, b.vector((0, 1))))), name="lift")
        return m.free(drop=[("lift", 2)]).simulate(np.linspace(0, 1.2, 7),
                                                   initial_condition={"th2_d": sleigh.W0})

    plain, tier, asked = compiling(job)
    assert asked
    _same(plain.q, tier.q)
    _same(plain.extra["mu"], tier.extra["mu"])


@pytest.mark.parametrize("method", ["dop853", "adams"])
def test_double_pendulum(compiling, method):
    from test_free_motion import double_pendulum_model

    def job():
        return double_pendulum_model()[1].simulate(np.linspace(0, 2.0, 21), method=method)

    plain, tier, asked = compiling(job)
    assert asked
    # (DOP853: the interpreted loop took every step; Adams: the Python path, decision 0077)
    assert tier.extra["interpreted_steps"] == (tier.extra["steps"] if method == "dop853" else 0)
    _same(plain.q, tier.q)
    _same(plain.qdd, tier.qdd, 1e-10)


def test_rolling_coin(compiling):
    coin = load_example("rolling_coin")

    def job():
        m, _, _ = coin.build(0.2)
        free, ic = coin.start(m, 0.2, 3.0, 0.0, 10.0)
        return free.simulate(np.linspace(0, 0.5, 6), initial_condition=ic)

    plain, tier, asked = compiling(job)
    assert asked
    _same(plain.q, tier.q)
    _same(plain.extra["mu"], tier.extra["mu"])


def test_sweep_and_reactions(compiling):
    """A driven slider-crank (the kinematic sweep) with masses: positions to accelerations
    and the reactions (the compiled multiplier solves) over 400 points."""
    import sympy as sp

    def job():
        m = ms.Model2D()
        crank = m.add_body("crank", points={"pin": (2.0, 0)}, guess=((0, 0), 0), mass=1.0,
                           centroid=(1.0, 0), inertia=0.4)
        rod = m.add_body("rod", points={"b": (6.0, 0)}, guess=((2.0, 0.1), 0.05), mass=2.0,
                         centroid=(3.0, 0), inertia=6.0)
        piston = m.add_body("piston", guess=((8.0, 0), 0), mass=0.5)
        m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)), name="bearing")
        m.add(ms.Revolute2(crank.point("pin"), rod.point(0)), name="crank pin")
        m.add(ms.Revolute2(rod.point("b"), piston.point(0)), name="wrist pin")
        m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), piston.axis((0, 0), (1, 0))),
              name="cylinder")
        m.add(ms.RotationLock1(crank, 2 * sp.pi * ms.T), name="drive")
        m.add_load(ms.Gravity((0, -1), 9.81))
        sol = m.solve(np.linspace(0, 1, 400), solution="dynamic")
        return sol, sol.reaction("crank pin", "rod")

    (plain, rp), (tier, rt), asked = compiling(job)
    assert asked
    # the loop interpreted in both runs (decision 0081): bit for bit; and right by the
    # independent references (loop closure, NumPy's dense solves of the velocity,
    # acceleration and load-balance equations, central differences)
    for x, y in ((plain.q, tier.q), (plain.qd, tier.qd), (plain.qdd, tier.qdd),
                 (plain.lam, tier.lam), *zip(rp, rt)):
        np.testing.assert_array_equal(x, y)
    check_sweep(tier)
    check_multipliers(tier)
