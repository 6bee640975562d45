"""The manual's chapter-10 examples (examples/*.py), checked independently."""

import numpy as np
import pytest
import sympy as sp
from scipy.optimize import minimize

from conftest import load_example as load

rope = load("pendulum_on_rope")


@pytest.fixture(scope="module")
def stages():
    m = rope.build()
    return m, rope.equilibrium_stages(m)


def test_rope_equilibria_satisfy_virtual_work(stages):
    """At equilibrium dV . dq = 0 for every admissible virtual displacement dq."""
    m, st = stages
    for _, free, sol in st:
        s = free.system
        q = sol.q[0]
        J = s.jacobian(0.0, q)
        V = sp.Matrix([m.potential_energy()])
        grad = np.array(sol.eval(V.jacobian(list(s.layout.q_symbols)))).reshape(-1)
        _, sv, vt = np.linalg.svd(J)
        null = vt[len(sv[sv > 1e-10]):]
        assert null.shape[0] == free.dof
        np.testing.assert_allclose(null @ grad, 0, atol=1e-8)
        assert np.abs(s.residual(0.0, q)).max() < 1e-10


def test_rope_final_equilibrium_minimises_potential(stages):
    """An independent constrained minimisation (SLSQP) of the potential lands on it."""
    m, st = stages
    _, free, sol = st[-1]
    s = free.system
    V = sp.lambdify([list(s.layout.q_symbols)], m.potential_energy(), "numpy")
    q0 = sol.q[0] + 0.03 * np.random.default_rng(1).standard_normal(s.n)
    res = minimize(V, q0, method="SLSQP",
                   constraints={"type": "eq", "fun": lambda q: s.residual(0.0, q),
                                "jac": lambda q: s.jacobian(0.0, q)},
                   options={"ftol": 1e-14, "maxiter": 500})
    assert res.success
    np.testing.assert_allclose(res.x, sol.q[0], atol=1e-5)


def test_rope_free_response_conserves_energy():
    m, free, sol = rope.free_response()
    assert sol.t[-1] == pytest.approx(4.5)
    assert abs(rope.energy_drift(sol)) < 1e-4          # percent of peak kinetic energy
    assert np.ptp(sol["pendulum.th"]) > 0.5            # it really swings
    m2, free2, sol2 = rope.free_response(method="adams")
    assert abs(rope.energy_drift(sol2)) < 0.5


def test_equilibrium_velocity_closed_form():
    ex = load("slider_crank_equilibrium_velocity")
    m, angles, w = ex.cycle(19)
    np.testing.assert_allclose(w, ex.closed_form(angles), rtol=1e-10)


def test_ellipse_of_mobility():
    ex = load("two_link_arm_mobility")
    m, free, angles, acc = ex.ellipse(25)
    # tip acceleration a = (J M^-1 J^T) F at rest: a linear map of the unit force
    F = np.c_[np.cos(angles), np.sin(angles)]
    A, *_ = np.linalg.lstsq(F, acc, rcond=None)
    np.testing.assert_allclose(F @ A, acc, atol=1e-12)
    assert np.allclose(A, A.T, atol=1e-12)                     # mobility tensor is symmetric
    assert np.all(np.linalg.eigvalsh(A) > 0)                   # and positive definite
