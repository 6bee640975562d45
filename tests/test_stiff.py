"""Stiff models with the implicit method (``method="radau"``, decision 0051): a stiff
spring-damper against its closed form, a constrained pendulum with a stiff torsion spring
against an ODE of its own in its one coordinate, and the method's place in the registry."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechsys as ms
from mechsys.solvers import _methods


def slider(k, c, mass=1.0):
    m = ms.Model2D()
    b = m.add_body("b", mass=mass, inertia=0.1, guess=((1.0, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), b.axis((0, 0), (1, 0))))
    m.add_load(ms.Spring(m.ground.point((0, 0)), b.point(0), k, 1.0))
    m.add_load(ms.Damper(m.ground.point((0, 0)), b.point(0), c))
    return m


def test_stiff_spring_damper_against_its_closed_form():
    # eigenvalues -100 and about -1e6: an explicit method's step is bounded by the fast one
    k, c = 1e8, 1e6
    free = slider(k, c).free(initial_guess={"b.x": 1.001}, initial_condition={"b.x_d": 0.0})
    sol = free.simulate((0, 0.05), method="radau", rtol=1e-8, atol=1e-12)
    s1, s2 = np.roots([1.0, c, k])
    a = np.linalg.solve([[1.0, 1.0], [s1, s2]], [1e-3, 0.0])
    exact = 1.0 + a[0] * np.exp(s1 * sol.t) + a[1] * np.exp(s2 * sol.t)
    assert np.abs(sol["b.x"] - exact).max() < 1e-10
    # a stable step far beyond the explicit bound 3.3 / 1e6 s: the whole run in a few
    # hundred steps (DOP853 needs about 7,800 here: benchmarks/stiff.py)
    assert sol.extra["steps"] < 1000
    assert sol.extra["method"] == "radau"
    # the evaluations include those of the finite-difference Jacobians; SciPy reports no
    # count of rejected attempts, which is said rather than given as zero
    assert sol.extra["evaluations"] > 2 * sol.extra["steps"]
    assert sol.extra["rejected"] is None
    assert sol.extra["compiled_steps"] == 0


def test_constrained_pendulum_with_a_stiff_torsion_spring_against_its_own_ode():
    # a rod in absolute coordinates (x, y, th and a revolute joint's two equations), a stiff
    # torsion spring and damper to ground: theta'' I_O = -m g l sin th - k th - c th'
    mass, length, g, k, c = 2.0, 0.5, 9.81, 4e5, 40.0
    inertia_c = mass * length ** 2 / 12
    m = ms.Model2D()
    m.add_load(ms.Gravity((0, -g)))
    rod = m.add_body("rod", mass=mass, inertia=inertia_c, guess=((length / 2, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), rod.point((-length / 2, 0))))
    m.add_load(ms.TorsionSpring(m.ground, rod, k))
    m.add_load(ms.TorsionDamper(m.ground, rod, c))
    th0 = 0.02
    free = m.free(initial_guess={"rod.x": length / 2 * np.cos(th0),
                                 "rod.y": length / 2 * np.sin(th0), "rod.th": th0},
                  initial_condition={"rod.th_d": 0.0})
    t = np.linspace(0, 0.2, 41)
    sol = free.simulate(t, method="radau", rtol=1e-9, atol=1e-12)
    io = inertia_c + mass * (length / 2) ** 2

    def rhs(_, y):
        return [y[1], (-mass * g * length / 2 * np.cos(y[0]) - k * y[0] - c * y[1]) / io]

    ref = solve_ivp(rhs, (0, 0.2), [th0, 0.0], method="Radau", t_eval=t, rtol=1e-12,
                    atol=1e-14)
    assert np.abs(sol["rod.th"] - ref.y[0]).max() < 1e-8
    # the joint held at position and velocity level by the projection after each step
    x, y, th = sol["rod.x"], sol["rod.y"], sol["rod.th"]
    assert np.abs(x - length / 2 * np.cos(th)).max() < 1e-10
    assert np.abs(y - length / 2 * np.sin(th)).max() < 1e-10


def test_radau_is_a_registered_method_without_a_compiled_loop():
    spec = _methods.get("Radau")
    assert spec.name == "radau" and spec.implicit and spec.dense_output
    assert spec.compiled is None and spec.scipy == "Radau"
    # the Runge-Kutta options, not Adams's
    free = slider(1e4, 10.0).free(initial_guess={"b.x": 1.01})
    with pytest.raises(ms.ModelError, match="fit_degree"):
        free.simulate((0, 0.01), method="radau", fit_degree="quartic")
    with pytest.raises(ms.OptionError, match="radau"):
        free.simulate((0, 0.01), method="raduu")
