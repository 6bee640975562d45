"""Nonholonomic paths of many coordinates (above SPARSE_THRESHOLD): the velocity system
``[Phi_q; psi_qd]`` is assembled and factorised sparse (``psi_qd`` by its structural
nonzeros), with the numbers of the dense solve, on a train of trailers whose motion has
closed-form checks."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from conftest import python_path
from mechsys import models
from mechsys.analyses import _path

SPEED, RATE = 2.0, 0.4


def _train(trailers: int, repeat_pin: bool = False, cubic: bool = False):
    """``models.trailer_train(trailers)`` (its tractor at ``SPEED``, steered at ``RATE``):
    ``(model, path)``. ``repeat_pin``: the first trailer's blade replaced by a velocity
    constraint that repeats its pin; ``cubic``: the tractor's speed ``u`` given by ``u + u^3 /
    10``, a velocity constraint nonlinear in the velocities (the same motion)."""
    path = models.trailer_train(trailers, speed=SPEED, rate=RATE)
    m = path.model
    if not (repeat_pin or cubic):
        return m, path
    replace = {d.name: vc for d, vc in path.replaced.items()}
    tractor = m.body("tractor")
    if cubic:
        v = m.velocity(tractor.point("blade"))
        u = (v.T * (tractor.A * sp.Matrix([1, 0])))[0, 0]
        replace["dummy y"] = ms.Constraint([u + u**3 / 10 - (SPEED + SPEED**3 / 10)])
    if repeat_pin:
        first = m.body("trailer0")
        front = m.velocity(first.point("front")) - m.velocity(tractor.point("hitch"))
        replace["dummy0"] = ms.Constraint([front[0]])
    return m, m.path(replace=replace)


def test_large_path_is_solved_sparse_with_the_dense_numbers(monkeypatch):
    m, path = _train(50)
    n = path.system.n
    assert n == 153 and n > _path.SPARSE_THRESHOLD and path._sparse
    # psi_qd by its nonzeros: a handful per velocity equation, not n
    assert path._b_rows.size <= 4 * len(path.psi)
    t = np.linspace(0.0, 3.0, 7)
    sol = path.simulate(t, rtol=1e-10, atol=1e-12)
    # the tractor's blade on the closed-form circle of radius SPEED / RATE
    R = SPEED / RATE
    p = sol.location(m.body("tractor").point("blade"))
    np.testing.assert_allclose(p, np.c_[R * np.sin(RATE * t), R * (1 - np.cos(RATE * t))],
                               rtol=0, atol=1e-8)
    # no trailer slips sideways, at the solution's own velocities
    for k in (0, 24, 49):
        b = m.body(f"trailer{k}")
        v = sol.velocity(b.point("blade"))
        th = sol.coordinate(f"trailer{k}.th")
        side = -v[:, 0] * np.sin(th) + v[:, 1] * np.cos(th)
        assert np.abs(side).max() < 1e-9
    # the dense solve of the same system (the pre-sparse code path), state by state
    monkeypatch.setattr(_path, "SPARSE_THRESHOLD", 10**6)
    _, dense = _train(50)
    assert not dense._sparse
    for k in (2, 6):
        qd_s = path.velocities(sol.t[k], sol.q[k], p=sol.p)
        qd_d = dense.velocities(sol.t[k], sol.q[k], p=sol.p)
        np.testing.assert_allclose(qd_s, qd_d, rtol=0, atol=1e-12 * np.abs(qd_d).max())
        np.testing.assert_allclose(path.accelerations(sol.t[k], sol.q[k], qd_s, p=sol.p),
                                   dense.accelerations(sol.t[k], sol.q[k], qd_d, p=sol.p),
                                   rtol=0, atol=1e-10)


def test_large_singular_path_is_diagnosed():
    """The first trailer's blade replaced by a velocity constraint that repeats its pin (the
    pin's x equation, differentiated): the sparse velocity system loses rank, and the error
    names the constraints involved."""
    m, path = _train(50, repeat_pin=True)
    assert path._sparse
    with pytest.raises(ms.SingularJacobianError, match="pin0"):
        path.simulate(np.linspace(0.0, 1.0, 3))


def _both(monkeypatch, build, t, **kw):
    """``(compiled loop, Python stepper)``: the loop's sparse velocity solve against the
    Python path's (the whole run by it, ``conftest.python_path``, as for kernels without C
    entry points; ``MECHSYS_JIT=0`` runs the loop interpreted, the compiled numbers bit for
    bit: decision 0082)."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    m, path = build()
    fast = (m, path, path.simulate(t, **kw))
    with monkeypatch.context() as mp:
        python_path(mp)
        m, path = build()
        slow = (m, path, path.simulate(t, **kw))
    return fast, slow


@pytest.mark.parametrize("method,kw", [("dop853", {"rtol": 1e-10, "atol": 1e-12}),
                                       ("adams", {"max_error": 1e-9})])
def test_large_path_runs_compiled_with_the_python_numbers(monkeypatch, method, kw):
    """Above SMALL_LU coordinates the compiled stepper solves the velocity system by the
    Python path's pattern and the same sparse LU, and projects through ``[[I, J^T], [J^,
    0]]``: every step compiled, the Python stepper's motion to rounding, the circle."""
    pytest.importorskip("numba")
    t = np.linspace(0.0, 3.0, 7)
    (m, path, fast), (_, _, slow) = _both(monkeypatch, lambda: _train(50), t, method=method,
                                          **kw)
    assert path.system.n > _path.SPARSE_THRESHOLD
    assert fast.extra["compiled_solver"] == "path"
    assert fast.extra["compiled_steps"] == fast.extra["steps"] > 10
    assert slow.extra["compiled_steps"] == 0
    assert fast.extra["steps"] == slow.extra["steps"]
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd)):
        scale = np.maximum(1.0, np.abs(b).max(axis=0))
        assert (np.abs(a - b) / scale).max() <= 1e-12
    R = SPEED / RATE
    p = fast.location(m.body("tractor").point("blade"))
    np.testing.assert_allclose(p, np.c_[R * np.sin(RATE * t), R * (1 - np.cos(RATE * t))],
                               rtol=0, atol=1e-7)
    assert fast.extra["drift"] < 1e-10
    # the accelerations at the outputs are the Python path's own, bit for bit (the same
    # kernels, pattern, scaling and LU)
    for k in (0, 3, 6):
        np.testing.assert_array_equal(
            fast.qdd[k], path.accelerations(fast.t[k], fast.q[k], fast.qd[k], p=fast.p))


def test_large_nonlinear_path_runs_compiled(monkeypatch):
    """Velocity constraints nonlinear in the velocities: Newton in every evaluation, in the
    loop as in the Python stepper."""
    pytest.importorskip("numba")
    t = np.linspace(0.0, 2.0, 5)
    (m, path, fast), (_, _, slow) = _both(monkeypatch, lambda: _train(50, cubic=True), t,
                                          rtol=1e-10, atol=1e-12)
    assert not path.linear
    assert fast.extra["compiled_steps"] == fast.extra["steps"] > 10
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd)):
        scale = np.maximum(1.0, np.abs(b).max(axis=0))
        assert (np.abs(a - b) / scale).max() <= 1e-12
    R = SPEED / RATE
    np.testing.assert_allclose(fast.location(m.body("tractor").point("blade")),
                               np.c_[R * np.sin(RATE * t), R * (1 - np.cos(RATE * t))],
                               rtol=0, atol=1e-7)

