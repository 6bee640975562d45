"""Nonholonomic paths of many coordinates (above SPARSE_THRESHOLD): the velocity system
``[Phi_q; psi_qd]`` is assembled and factorised sparse (``psi_qd`` by its structural
nonzeros), with the numbers of the dense solve, on a train of trailers whose motion has
closed-form checks."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T
from mechsys.analyses import _path

SPEED, RATE = 2.0, 0.4


def _train(trailers: int, repeat_pin: bool = False):
    """A tractor steered at ``RATE`` rad/s, its blade moving forward at ``SPEED`` without side
    slip, towing ``trailers`` trailers, each pinned to the hitch ahead and rolling on a blade
    that cannot slip sideways: ``3 (trailers + 1)`` coordinates, one velocity constraint per
    trailer. Each hitch is half a trailer's reach behind its blade, so a swing halves from
    trailer to trailer (with the hitch further back than the front it would double: 2^50
    down a train of 50, an ill-posed motion)."""
    m = ms.Model2D()
    tractor = m.add_body("tractor", points={"blade": (0.0, 0.0), "hitch": (-0.5, 0.0)})
    m.add(ms.RelativeX1(tractor.point("blade"), 0.0), name="dummy x")
    m.add(ms.RelativeY1(tractor.point("blade"), 0.0), name="dummy y")
    m.add(ms.RotationLock1(tractor, RATE * T), name="steering")
    prev, bodies = tractor, []
    for k in range(trailers):
        b = m.add_body(f"trailer{k}", points={"front": (1.0, 0.0), "blade": (0.0, 0.0),
                                              "hitch": (-0.5, 0.0)},
                       guess=((-1.5 * (k + 1), 0.0), 0.0))
        m.add(ms.Revolute2(prev.point("hitch"), b.point("front")), name=f"pin{k}")
        m.add(ms.RotationLock1(b, 0.0), name=f"dummy{k}")
        bodies.append(b)
        prev = b
    m.solve(0.0)
    v = m.velocity(tractor.point("blade"))
    ahead = tractor.A * sp.Matrix([1, 0])
    replace = {"dummy x": ms.Orthogonal1(v, tractor.vector((0, 1))),
               "dummy y": ms.Constraint([(v.T * ahead)[0, 0] - SPEED])}
    for k, b in enumerate(bodies):
        replace[f"dummy{k}"] = ms.Orthogonal1(m.velocity(b.point("blade")), b.vector((0, 1)))
    if repeat_pin:
        front = m.velocity(bodies[0].point("front")) - m.velocity(tractor.point("hitch"))
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
