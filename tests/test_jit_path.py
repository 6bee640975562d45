"""The compiled stepper of nonholonomic paths (``_jit_free_loop`` kind ``PATH``, decision
0027) against the Python stepper and closed forms: DOP853 and Mech's Adams, a path without
holonomic constraints, and velocity constraints nonlinear in the velocities. (Parameters reach the
compiled loop: tests/test_path.py's parameter test runs compiled by default.)"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from conftest import load_example as load
from mechsys import T

pytest.importorskip("numba")
caster = load("caster")
knife = load("knife_edge")


def _both(monkeypatch, build, t, **kw):
    out = {}
    for jit in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        out[jit] = build()[1].simulate(t, **kw)
    return out["1"], out["0"]


@pytest.mark.parametrize("method,kw", [("dop853", {"rtol": 1e-11, "atol": 1e-12}),
                                       ("rk45", {"rtol": 1e-10, "atol": 1e-12}),
                                       ("adams", {"max_error": 1e-9})])
@pytest.mark.parametrize("example", [caster, knife], ids=["caster", "knife-edge"])
def test_compiled_and_python_paths_agree(monkeypatch, example, method, kw):
    t = np.linspace(0.0, 3.0, 16)
    fast, slow = _both(monkeypatch, example.build, t, method=method, **kw)
    assert fast.extra["compiled_steps"] == fast.extra["steps"] > 10
    assert fast.extra["compiled_solver"] == "path"
    assert slow.extra["compiled_steps"] == 0
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd)):
        scale = np.maximum(1.0, np.abs(b).max(axis=0))
        assert (np.abs(a - b) / scale).max() <= 1e-9


@pytest.mark.parametrize("method,kw,tol", [("dop853", {"rtol": 1e-11, "atol": 1e-12}, 1e-8),
                                           ("rk45", {"rtol": 1e-10, "atol": 1e-12}, 1e-8),
                                           ("adams", {"max_error": 1e-8}, 1e-5)])
def test_compiled_caster_follows_its_closed_form(monkeypatch, method, kw, tol):
    monkeypatch.setenv("MECHSYS_JIT", "1")
    t = np.linspace(0, 3.0, 31)
    sol = caster.build()[1].simulate(t, method=method, **kw)
    assert sol.extra["compiled_steps"] > 0
    np.testing.assert_allclose(sol["caster.th"], caster.closed_form(t), atol=tol)
    assert sol.extra["drift"] < 1e-10


def _free_sled():
    """The knife edge with its heading a velocity constraint too: no holonomic equation is
    left, the path's derivative is the velocity constraints' alone."""
    m = ms.Model2D()
    sled = m.add_body("sled", points={"blade": (0.0, 0.0)})
    m.add(ms.RelativeX1(sled.point("blade"), 0.0), name="dummy x")
    m.add(ms.RelativeY1(sled.point("blade"), 0.0), name="dummy y")
    m.add(ms.RotationLock1(sled, 0.0), name="dummy th")
    m.solve(0.0)
    v = m.velocity(sled.point("blade"))
    ahead = sled.A * sp.Matrix([1, 0])
    th = sled.q[2]
    from mechsys._symbols import velocity_symbol

    turn = ms.Constraint([velocity_symbol(th.name) - knife.RATE])
    return m, m.path(replace={"dummy x": ms.Orthogonal1(v, sled.vector((0, 1))),
                              "dummy y": ms.Constraint([(v.T * ahead)[0, 0] - knife.SPEED]),
                              "dummy th": turn})


def test_path_without_holonomic_constraints(monkeypatch):
    monkeypatch.setenv("MECHSYS_JIT", "1")
    m, path = _free_sled()
    assert path.system.m == 0
    t = np.linspace(0, 2 * np.pi / knife.RATE, 21)
    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    assert sol.extra["compiled_steps"] > 0
    R = knife.SPEED / knife.RATE
    ref = np.c_[R * np.sin(knife.RATE * t), R * (1 - np.cos(knife.RATE * t))]
    np.testing.assert_allclose(sol.location(m.body("sled").point("blade")), ref, atol=1e-8)


def _cubic_sled():
    """The knife edge with its speed prescribed by an equation cubic in the velocities."""
    m = ms.Model2D()
    sled = m.add_body("sled", points={"blade": (0.0, 0.0)})
    m.add(ms.RelativeX1(sled.point("blade"), 0.0), name="dummy x")
    m.add(ms.RelativeY1(sled.point("blade"), 0.0), name="dummy y")
    m.add(ms.RotationLock1(sled, knife.RATE * T), name="steering")
    m.solve(0.0)
    v = m.velocity(sled.point("blade"))
    ahead = sled.A * sp.Matrix([1, 0])
    speed = (v.T * ahead)[0, 0]
    # speed + speed^3 / 10 increases monotonically: its one root is the speed SPEED
    cubic = speed + speed**3 / 10 - (knife.SPEED + knife.SPEED**3 / 10)
    return m, m.path(replace={"dummy x": ms.Orthogonal1(v, sled.vector((0, 1))),
                              "dummy y": ms.Constraint([cubic])})


def test_nonlinear_velocity_constraints(monkeypatch):
    """A velocity constraint nonlinear in the velocities: Newton in every evaluation, in the
    loop as in the Python stepper; both on the closed-form circle."""
    t = np.linspace(0, 2.0, 5)
    fast, slow = _both(monkeypatch, _cubic_sled, t, rtol=1e-11, atol=1e-12)
    assert not _cubic_sled()[1].linear
    assert fast.extra["compiled_steps"] == fast.extra["steps"] > 0
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * max(1.0, np.abs(b).max()))
    R = knife.SPEED / knife.RATE
    ref = np.c_[R * np.sin(knife.RATE * t), R * (1 - np.cos(knife.RATE * t))]
    np.testing.assert_allclose(fast.location(fast.model.body("sled").point("blade")), ref,
                               atol=1e-8)
