"""The manual's chapter-10 examples (examples/*.py), checked independently."""

import numpy as np
import pytest
import sympy as sp
from scipy.optimize import minimize

import mechsys as ms
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


# -- parameters are read when the free system solves, not frozen by m.free() -----------------
def test_set_parameters_after_free_changes_the_free_acceleration():
    # the manual's 10.3 arm: the answer used to stay that of the load angle at m.free()
    ex = load("two_link_arm_mobility")
    m, free, angles, acc = ex.ellipse(7)
    tip = m.body("link2").point("tip")
    for k, ang in enumerate(angles):
        m.set_parameters(loadangle=ang)
        np.testing.assert_allclose(free.solve(0.0).acceleration(tip), acc[k], atol=1e-12)
    assert np.ptp(acc[:, 0]) > 0.5                       # the answers really differ
    # initial_condition overrides the model's value for that call only
    m.set_parameters(loadangle=angles[1])
    s = free.solve(0.0, initial_condition={"loadangle": angles[3]})
    np.testing.assert_allclose(s.acceleration(tip), acc[3], atol=1e-12)
    assert s.p[0] == angles[3]
    np.testing.assert_allclose(free.solve(0.0).acceleration(tip), acc[1], atol=1e-12)


def test_parameter_values_given_to_free_stay_with_the_free_system():
    ex = load("two_link_arm_mobility")
    m = ex.build()
    m.solve(0.0, solution="velocity")
    tip = m.body("link2").point("tip")
    pinned = m.free(drop=["set shoulder", "set elbow"], initial_condition={"loadangle": 1.0})
    m.set_parameters(loadangle=2.0)
    ref = m.free(drop=["set shoulder", "set elbow"], initial_condition={"loadangle": 1.0})
    np.testing.assert_allclose(pinned.solve(0.0).acceleration(tip),
                               ref.solve(0.0).acceleration(tip), atol=1e-14)


def _spring_bar():
    st = ms.Model2D()
    bar = st.add_body("bar", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0),
                      inertia=1 / 12)
    st.add(ms.Revolute2(st.ground.point((0, 0)), bar.point(0)), name="pivot")
    st.add(ms.RotationLock1(bar, 0.0), name="hold")
    k = st.parameter("k", 20.0)
    g = st.parameter("g", 9.81)
    st.add_load(ms.Gravity((0, -1), g))
    st.add_load(ms.Spring(bar.point("tip"), st.ground.point((1, 1)), stiffness=k,
                          free_length=0.0))
    st.solve(0.0)
    return st


def test_set_parameters_after_free_changes_the_static_equilibrium():
    st = _spring_bar()
    eq = st.free(drop=["hold"], solution="static")
    assert eq.solve()["bar.th"] == pytest.approx(np.arctan(1 - 9.81 / 40), abs=1e-12)
    st.set_parameters(k=50.0)
    assert eq.solve()["bar.th"] == pytest.approx(np.arctan(1 - 9.81 / 100), abs=1e-12)


def test_set_parameters_after_free_changes_the_equilibrium_velocity():
    m = ms.Model2D()
    b = m.add_body("bar", mass=1.0, centroid=(0.5, 0), inertia=0.1)
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, 0.0), name="hold")
    M0 = m.parameter("M0", 2.0)
    w = m.velocity_symbols()[b.q[2]]
    m.add_load(ms.Moment(b, M0 - 4 * w))                # viscous: w = M0 / 4
    m.solve(0.0)
    free = m.free(drop=["hold"], solution="kinematic")
    assert free.solve(0.0).coordinate("bar.th", 1) == pytest.approx(0.5, abs=1e-12)
    m.set_parameters(M0=6.0)
    assert free.solve(0.0).coordinate("bar.th", 1) == pytest.approx(1.5, abs=1e-12)


def test_set_parameters_after_free_changes_the_simulated_motion():
    m = ms.Model2D()
    b = m.add_body("bar", mass=1.0, centroid=(1.0, 0), inertia=0.0)
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, 0.0), name="hold")
    g = m.parameter("g", 9.81)
    m.add_load(ms.Gravity((0, -1), g))
    m.solve(0.0)
    free = m.free(drop=["hold"])
    t = np.linspace(0.0, 0.3, 4)
    slow = free.simulate(t, rtol=1e-11, atol=1e-12)
    m.set_parameters(g=4 * 9.81)                        # 4 g: the same motion twice as fast
    fast = free.simulate(t / 2, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(fast["bar.th"], slow["bar.th"], atol=1e-9)
    assert np.ptp(slow["bar.th"]) > 0.3
    assert list(fast.p) == [4 * 9.81]
    # a parameter declared after free() does not shift the values
    m.parameter("unused", 123.0)
    again = free.simulate(t / 2, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(again["bar.th"], slow["bar.th"], atol=1e-9)
