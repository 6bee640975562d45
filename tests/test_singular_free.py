"""Free motion and kinematic sweeps through singular configurations: the IFToMM benchmark's
N-four-bar mechanism (problem A02), whose links are all collinear twice per turn (the
constraint Jacobian then loses N ranks for an instant).

Reference, derived here independently of mechsys: every loop stays a parallelogram, so all
cranks turn by the same angle theta (from +x) and every coupler translates with the crank
tips. With N + 1 cranks (mass 1, length 1, inertia 1/3 about the pivot) and N couplers (mass
1, translating with speed |theta'|)::

    T = a theta'^2 / 2,   a = (N + 1) / 3 + N
    V = b g sin(theta),   b = (N + 1) / 2 + N          (centroids at heights sin / 2, sin)
    a theta'' = -b g cos(theta)

from theta(0) = pi / 2 (cranks vertical) with x'_B0 = -sin(theta) theta' = 1, i.e.
theta'(0) = -1. The links are horizontal at theta = 0 (t ~ 0.71) and theta = -pi (t ~ 1.2).
"""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import mechsys as ms
from mechsys import T, models

G = 9.81


def exact_theta(n_loops, t):
    a = (n_loops + 1) / 3 + n_loops
    b = (n_loops + 1) / 2 + n_loops
    sol = solve_ivp(lambda _, y: [y[1], -b * G / a * np.cos(y[0])], (0.0, float(t[-1])),
                    [np.pi / 2, -1.0], t_eval=t, method="DOP853", rtol=1e-13, atol=1e-13)
    return sol.y[0], sol.y[1], a, b


def energy(n_loops, sol):
    """Kinetic energy from the body velocities, potential energy of the centroids."""
    E = np.zeros(len(sol.t))
    for name in [f"crank{k}" for k in range(n_loops + 1)] + [f"coupler{k}" for k in
                                                            range(n_loops)]:
        x_d = sol.coordinate(f"{name}.x", 1)
        y_d = sol.coordinate(f"{name}.y", 1)
        th, w = sol.coordinate(f"{name}.th"), sol.coordinate(f"{name}.th", 1)
        # centroid (0.5, 0) in body axes: velocity of the origin + w x r
        vx = x_d - 0.5 * np.sin(th) * w
        vy = y_d + 0.5 * np.cos(th) * w
        E += 0.5 * (vx**2 + vy**2) + 0.5 * w**2 / 12
        E += G * (sol.coordinate(f"{name}.y") + 0.5 * np.sin(th))
    return E


@pytest.mark.parametrize("n_loops", [1, 2, 10])
def test_n_four_bar_free_motion_passes_its_singular_instants(n_loops):
    """Through theta = 0 and theta = -pi (two singular instants): B0's x matches the exact
    one-DOF motion to 1e-5, energy is conserved to 1e-6 relative, the loops stay
    parallelograms. Before: SingularJacobianError at the first instant."""
    m = models.n_four_bar(n_loops)
    m.solve(0.0)
    free = m.free(drop=["hold"])
    t = np.linspace(0.0, 1.6, 65)
    sol = free.simulate(t, initial_condition={"crank0.th_d": -1.0})
    th, _, a, b = exact_theta(n_loops, t)
    assert th.min() < -np.pi - 0.2                     # both singular instants passed
    np.testing.assert_allclose(sol.coordinate("coupler0.x"), np.cos(th), rtol=0, atol=1e-5)
    E = energy(n_loops, sol)
    assert E[0] == pytest.approx(0.5 * a + b * G, rel=1e-12)
    assert np.abs(E - E[0]).max() / E[0] < 1e-6
    for k in range(1, n_loops + 1):
        np.testing.assert_allclose(np.unwrap(sol.angle(f"crank{k}")),
                                   np.unwrap(sol.angle("crank0")), rtol=0, atol=1e-6)
    s = free.system
    worst = max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(sol.t, sol.q))
    assert worst < 1e-10


@pytest.mark.parametrize("unit", [1e-3, 1e3])
def test_n_four_bar_in_other_units(unit):
    """The same motion with lengths in millimetres or kilometres (the zone test, the
    regularisation and the projections are unit-free)."""
    m = models.n_four_bar(2, length=unit)
    m.solve(0.0)
    t = np.linspace(0.0, 1.6, 33)
    sol = m.free(drop=["hold"]).simulate(t, initial_condition={"crank0.th_d": -1.0})
    th = exact_theta(2, t)[0]
    np.testing.assert_allclose(sol.coordinate("coupler0.x") / unit, np.cos(th), rtol=0,
                               atol=1e-5)


def horizontal_state(n_loops, w):
    """All links horizontal (the singular configuration), crank rate ``w``."""
    cond = {}
    for k in range(n_loops + 1):
        cond.update({f"crank{k}.x": float(k), f"crank{k}.y": 0.0, f"crank{k}.th": 0.0,
                     f"crank{k}.x_d": 0.0, f"crank{k}.y_d": 0.0, f"crank{k}.th_d": w})
    for k in range(n_loops):
        cond.update({f"coupler{k}.x": k + 1.0, f"coupler{k}.y": 0.0, f"coupler{k}.th": 0.0,
                     f"coupler{k}.x_d": 0.0, f"coupler{k}.y_d": w, f"coupler{k}.th_d": 0.0})
    return cond


@pytest.mark.parametrize("n_loops", [1, 3])
def test_free_acceleration_at_the_singular_instant(n_loops):
    """At the instant itself the augmented matrix is singular: the acceleration is solved
    with the independent constraint combinations and the minimum-norm multipliers (the
    reactions along the dependent directions are indeterminate there). It satisfies the
    acceleration constraints; with one loop, by symmetry, it is the motion's own: every
    crank theta'' = -b g / a, the coupler translates (x'' = -w^2)."""
    m = models.n_four_bar(n_loops)
    m.solve(0.0)
    free = m.free(drop=["hold"])
    w = -4.0
    s = free.solve(0.0, initial_condition=horizontal_state(n_loops, w))
    system = free.system
    q, qd, qdd = s.q[0], s.qd[0], s.qdd[0]
    np.testing.assert_allclose(system.jacobian(0.0, q) @ qdd, system.gamma_values(0.0, q, qd),
                               rtol=0, atol=1e-9)
    assert np.all(np.isfinite(s.lam))
    if n_loops == 1:
        _, _, a, b = exact_theta(n_loops, np.array([0.0, 1e-3]))
        for k in range(2):
            assert s.coordinate(f"crank{k}.th", 2) == pytest.approx(-b * G / a, rel=1e-9)
        assert s.coordinate("coupler0.x", 2) == pytest.approx(-w**2, rel=1e-9)
        assert s.coordinate("coupler0.th", 2) == pytest.approx(0.0, abs=1e-9)


def test_kinematic_sweep_through_the_singular_instant_keeps_the_parallelogram():
    """Driven at crank0 through theta = 0, a sample exactly there (where the other cranks
    could take any angle): the sweep continues the parallelogram branch, with the rates of
    the continuous motion (theta = pi/2 - pi/2 t)."""
    m = models.n_four_bar(2)
    m.replace("hold", ms.RotationLock1(m.body("crank0"), sp.pi / 2 - sp.pi / 2 * T))
    t = np.linspace(0.0, 2.0, 21)
    with pytest.warns(ms.NearSingularWarning, match=r"first at t = 1 \(reciprocal condition 0"):
        sol = m.solve(t)
    th = np.pi / 2 - np.pi / 2 * t
    for k in range(3):
        np.testing.assert_allclose(sol.angle(f"crank{k}"), th, rtol=0, atol=1e-9)
        np.testing.assert_allclose(sol.omega(f"crank{k}"), -np.pi / 2, rtol=0, atol=1e-5)
    # coupler0 translates on the circle of B0: x = cos(theta), x'' = -(pi/2)^2 cos(theta)
    np.testing.assert_allclose(sol.coordinate("coupler0.x"), np.cos(th), rtol=0, atol=1e-9)
    np.testing.assert_allclose(sol.coordinate("coupler0.x", 2), -(np.pi / 2) ** 2 * np.cos(th),
                               rtol=0, atol=1e-4)
    assert sol.extra["rcond"][10] == 0.0
