"""The compiled free-motion stepper (solvers/_jit_free.py): its loop compiled and the same
loop interpreted (``MECHSYS_JIT=0``, decision 0082) give equal numbers bit for bit
(``conftest.simulate_both``), and the motion is checked against independent references:
the double pendulum's and the pendulum's own minimal-coordinate ODEs (Lagrange, integrated
by SciPy's ``solve_ivp`` at a tight tolerance), closed forms, conservation of energy and the
closed loops; the accelerations and multipliers returned are those of the model at the
states (``free_acceleration``, the Python path's solve). Each case checks that the loop
really ran."""

import functools
import importlib.util
import pathlib
import sys

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechsys as ms
from conftest import simulate_both
from mechsys.solvers._free import free_acceleration

pytest.importorskip("numba")

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import free_motion  # noqa: E402
import long_run  # noqa: E402


def _example(name):
    """An example script as a module of its own (benchmarks/ has modules of the same names)."""
    spec = importlib.util.spec_from_file_location(f"_example_{name}", ROOT / "examples" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


_both = simulate_both


def _lagrange(_t, y, g=9.81):
    r"""The double pendulum (two uniform rods, 1 m, 1 kg, :math:`I = 1/12` about their
    centres) in its absolute link angles, Lagrange's equations written out by hand:
    :math:`T = \tfrac12 (\tfrac43 \omega_1^2 + \tfrac13 \omega_2^2 + \omega_1 \omega_2
    \cos(\theta_1 - \theta_2))`, :math:`V = g (\tfrac32 \sin\theta_1 + \tfrac12
    \sin\theta_2)`, so

    .. math:: \begin{bmatrix} 4/3 & c/2 \\ c/2 & 1/3 \end{bmatrix}
              \begin{bmatrix} \ddot\theta_1 \\ \ddot\theta_2 \end{bmatrix} =
              \begin{bmatrix} -\tfrac{s}{2} \omega_2^2 - \tfrac32 g \cos\theta_1 \\
              \tfrac{s}{2} \omega_1^2 - \tfrac12 g \cos\theta_2 \end{bmatrix},
              \quad c = \cos(\theta_1 - \theta_2), \; s = \sin(\theta_1 - \theta_2)

    (tests/test_free_motion.py derives the same equations with SymPy)."""
    th1, th2, w1, w2 = y
    c, s = np.cos(th1 - th2), np.sin(th1 - th2)
    M = np.array([[4.0 / 3.0, c / 2], [c / 2, 1.0 / 3.0]])
    rhs = np.array([-s / 2 * w2**2 - 1.5 * g * np.cos(th1), s / 2 * w1**2 - 0.5 * g * np.cos(th2)])
    return [w1, w2, *np.linalg.solve(M, rhs)]


@functools.lru_cache(maxsize=1)
def _minimal_ode():
    """:func:`_lagrange` from rest, both rods horizontal, integrated by SciPy's DOP853 at
    1e-13: a dense solution over [0, 2]."""
    return solve_ivp(_lagrange, (0.0, 2.0), [0.0, 0.0, 0.0, 0.0], method="DOP853",
                     rtol=1e-13, atol=1e-14, dense_output=True).sol


def _against_minimal(sol, atol_q, atol_qd):
    """The double pendulum's angles and rates against :func:`_minimal_ode`."""
    ref = _minimal_ode()(sol.t)
    for k, name in enumerate(("l0.th", "l1.th")):
        np.testing.assert_allclose(sol[name], ref[k], rtol=0, atol=atol_q)
        np.testing.assert_allclose(sol.coordinate(name, 1), ref[2 + k], rtol=0, atol=atol_qd)


def _energy_kept(sol, tol):
    energy = sol.body_energy() + sol.potential_energy()
    assert np.abs(energy - energy[0]).max() <= tol * max(1.0, np.abs(energy).max())


def _check_derivatives(free, sol, rows):
    """qdd and lambda returned with the compiled steps = a fresh solve at those states."""
    s = free.system
    for k in rows:
        qdd, lam, _ = free_acceleration(s, float(sol.t[k]), sol.q[k], sol.qd[k], s.p_values)
        np.testing.assert_allclose(sol.qdd[k], qdd, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(sol.lam[k], lam, rtol=1e-12, atol=1e-12)


def test_double_pendulum_against_its_minimal_ode(monkeypatch):
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    grid = np.linspace(0.0, 2.0, 41)
    _, jit = _both(monkeypatch, free, grid, rtol=1e-10, atol=1e-12)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 20
    np.testing.assert_array_equal(jit.t, grid)
    _against_minimal(jit, 1e-8, 1e-7)
    assert np.abs(free.system.residual(2.0, jit.q[-1])).max() < 1e-11    # projected
    _check_derivatives(free, jit, [5, 40])


def test_every_step_output_and_no_projection(monkeypatch):
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    _, jit = _both(monkeypatch, free, (0.0, 1.0), rtol=1e-8, atol=1e-10,
                   constraint_correction=False)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] and jit.t[-1] == 1.0
    _against_minimal(jit, 1e-6, 1e-5)
    _check_derivatives(free, jit, [1, len(jit.t) // 2, len(jit.t) - 1])


def test_four_bar_keeps_the_loop_closed(monkeypatch):
    _, free = long_run.four_bar()
    _, jit = _both(monkeypatch, free, np.linspace(0.0, 1.0, 21), rtol=1e-9, atol=1e-11)
    assert jit.extra["compiled_steps"] == jit.extra["steps"]
    _energy_kept(jit, 1e-8)
    gap = max(np.abs(free.system.residual(tk, qk)).max() for tk, qk in zip(jit.t, jit.q))
    assert gap < 1e-11
    _check_derivatives(free, jit, [10, 20])


def test_backwards_in_time(monkeypatch):
    r"""Backwards from t = 1 to 0, against the pendulum's own ODE (a point mass of 1 kg at
    1 m plus 0.01 kg m^2 about it: :math:`1.01\,\ddot\theta = -g \cos\theta`) integrated the
    same way by SciPy."""
    _, free = long_run.pendulum()
    _, jit = _both(monkeypatch, free, np.linspace(1.0, 0.0, 11), rtol=1e-10, atol=1e-12)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 0
    th0, w0 = jit["bar.th"][0], jit.coordinate("bar.th", 1)[0]
    ref = solve_ivp(lambda _t, y: [y[1], -9.81 * np.cos(y[0]) / 1.01], (1.0, 0.0), [th0, w0],
                    method="DOP853", rtol=1e-13, atol=1e-14, t_eval=jit.t)
    np.testing.assert_allclose(jit["bar.th"], ref.y[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(jit.coordinate("bar.th", 1), ref.y[1], rtol=0, atol=1e-8)


def test_spatial_gyroscope(monkeypatch):
    gyroscope = _example("gyroscope")
    m = gyroscope.build("rotor")
    m.solve(0.0)
    free = m.free(drop=["base lock"])
    ic = gyroscope.initial_condition("rotor")
    _, jit = _both(monkeypatch, free, np.linspace(0.0, 0.5, 11), initial_condition=ic,
                   rtol=1e-10, atol=1e-12)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 5
    # Euler-parameter mass blocks are singular (4 parameters, 3 rotations): the augmented
    # system is solved whole
    assert jit.extra["compiled_solver"] == "augmented"
    # the closed form: the symmetric rotor's inertia about the base's axis is its transverse
    # one whatever its spin angle, so the moment turns the base at psi = MZ t^2 / (2 I_T)
    psi = gyroscope.MZ * jit.t**2 / (2 * gyroscope.I_T)
    np.testing.assert_allclose(gyroscope.base_angle(jit), psi, rtol=0, atol=1e-8)
    _check_derivatives(free, jit, [10])


@pytest.mark.parametrize("links", [16, 52])
def test_chains_take_the_block_path(monkeypatch, links):
    """Larger systems (over 24 unknowns; 52 links: 260, above the sparse threshold, where
    the Python path uses SuperLU) solve the augmented system by the Schur complement on the
    block-diagonal mass matrix, banded: the energy kept, the chain closed, the model's
    accelerations; the interpreted loop's numbers bit for bit."""
    free, _ = free_motion.compiled(free_motion.chain, links)
    # (the interpreted loop's numbers, bit for bit, over its first steps)
    _both(monkeypatch, free, (0.0, 0.01 if links > 20 else 0.05), rtol=1e-8, atol=1e-10)
    jit = free.simulate(np.linspace(0.0, 0.5, 6), rtol=1e-8, atol=1e-10)
    assert jit.extra["compiled_solver"] == "block"
    assert jit.extra["compiled_steps"] == jit.extra["steps"]
    _energy_kept(jit, 1e-7)
    s = free.system
    assert max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(jit.t, jit.q)) < 1e-10
    _check_derivatives(free, jit, [5])


@pytest.mark.parametrize("method", ["DOP853", "predictor"])
def test_wide_trees_take_the_sparse_lu(monkeypatch, method):
    """A radial engine coasting under gravity (40 cylinders: 243 coordinates, every rod on
    the crank pin, so the augmented matrix's band spans the engine) solves its augmented
    system in the loop by the compiled sparse LU of the Python path's pattern, and projects
    through the Python path's pattern of ``[[I, J^T], [J^, 0]]`` with the same LU: the Python
    path's accelerations to rounding, every step compiled, within the tolerance of a run at a
    tight one, the loops closed and the energy kept; the interpreted loop's numbers bit for
    bit over the first steps."""
    from mechsys import models

    m = models.radial_engine(40, g=9.81)
    m.solve(0.0)
    free = m.free(drop=["drive"])
    s = free.system
    ic = {"crank.th_d": 3.0}
    opts = dict(initial_condition=ic, rtol=1e-9, atol=1e-11, method=method)
    if method != "DOP853":
        opts = dict(initial_condition=ic, method=method, max_error=1e-9)
    grid = np.linspace(0.0, 1.0, 11)
    if method == "DOP853":
        # (an interpreted step of this engine costs tens of milliseconds: its first steps;
        # Mech's Adams is compared bit for bit on the small systems)
        _both(monkeypatch, free, (0.0, 0.005), **opts)
    jit = free.simulate(grid, **opts)
    assert jit.extra["compiled_solver"] == "sparse"
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 5
    ref = free.simulate(grid, initial_condition=ic, rtol=1e-12, atol=1e-14)
    assert np.abs(jit.q - ref.q).max() < (1e-6 if method == "DOP853" else 1e-5)
    assert max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(jit.t, jit.q)) < 1e-10
    energy = jit.body_energy() + jit.potential_energy()
    assert np.abs(energy - energy[0]).max() < 1e-6 * np.abs(energy).max()
    # the loop's accelerations at its outputs are the Python path's, to rounding
    _check_derivatives(free, jit, [5, 10])


def test_without_constraints(monkeypatch):
    """A free body under gravity: no equations, the parabola exactly."""
    m = ms.Model2D()
    m.add_load(ms.loads.Gravity((0, -1), 9.81))
    m.add_body("ball", mass=2.0, inertia=0.1, guess=((0, 0), 0))
    m.add(ms.constraints.Revolute2(m.body("ball").point((0, 0)), m.ground.point((0, 0))),
          name="hold")
    m.add(ms.constraints.RotationLock1(m.body("ball"), 0.0), name="spin")
    m.solve(0.0)
    free = m.free(drop=["hold", "spin"])
    assert free.system.m == 0
    _, jit = _both(monkeypatch, free, np.linspace(0.0, 1.0, 5),
                   initial_condition={"ball.x_d": 1.0, "ball.y_d": 2.0})
    assert jit.extra["compiled_steps"] == jit.extra["steps"]
    t = jit.t
    np.testing.assert_allclose(jit["ball.y"], 2.0 * t - 9.81 / 2 * t**2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(jit["ball.x"], t, rtol=0, atol=1e-12)


def test_singular_instants_are_handed_to_python(monkeypatch):
    """The n-four-bar (parallelograms) passes instants where its Jacobian is singular: the
    compiled loop hands those steps to the Python stepper (zone guard, regularised
    projection) and takes over again, and so does the interpreted loop (the same numbers);
    the motion is the one-degree-of-freedom equation's (the example's own reference)."""
    n_four_bar = _example("n_four_bar")
    out = {}
    for mode in ("0", "1"):
        monkeypatch.setenv("MECHSYS_JIT", mode)
        out[mode] = n_four_bar.simulate(2, 3.0, 61)
    slow, jit = out["0"], out["1"]
    assert 0 < jit.extra["compiled_steps"] < jit.extra["steps"]
    assert jit.extra["compiled_solver"] == "block"
    assert slow.extra["interpreted_steps"] == jit.extra["compiled_steps"]
    from conftest import same_bits

    # (the start's projection is a kinematic Newton solve outside the loop, whose tier
    # follows MECHSYS_JIT too: a coordinate at zero differs by 1e-48 there)
    same_bits(slow, jit, ("t", "qd", "qdd", "lam"))
    np.testing.assert_array_equal(slow.q[1:], jit.q[1:])
    np.testing.assert_allclose(slow.q[0], jit.q[0], rtol=0, atol=1e-15)
    th = n_four_bar.one_dof(2, jit.t)
    np.testing.assert_allclose(jit.coordinate("coupler0.x"), np.cos(th), rtol=0, atol=1e-5)
    # the crank angle of a parallelogram four-bar moves through the instants smoothly
    assert np.all(np.isfinite(jit.qdd)) and np.all(np.isfinite(jit.lam))


@pytest.mark.parametrize("method,options,tol", [
    ("adams", {"fit_degree": "quartic", "max_error": 1e-10}, 1e-7),
    ("predictor", {"max_error": 1e-9}, 1e-6),
    ("corrector", {"fit_degree": "quadratic", "max_error": 1e-9, "constraint_correction": True},
     1e-6),
    ("adams", {"step_size": 1e-3}, 1e-4),
])
def test_adams_against_the_minimal_ode(monkeypatch, method, options, tol):
    """Mech's Adams integrator, compiled and interpreted (the same numbers), against the
    double pendulum's minimal ODE."""
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    _, jit = _both(monkeypatch, free, (0.0, 0.5), method=method, **options)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 50
    _against_minimal(jit, tol, 10 * tol)
    _check_derivatives(free, jit, [1, len(jit.t) // 2, len(jit.t) - 1])


def test_adams_output_times_use_the_compiled_derivatives(monkeypatch):
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    grid = np.linspace(0.0, 0.5, 11)
    _, jit = _both(monkeypatch, free, grid, method="adams", max_error=1e-10)
    np.testing.assert_array_equal(jit.t, grid)
    _against_minimal(jit, 1e-7, 1e-6)
    _check_derivatives(free, jit, [3, 10])


def test_rk45_compiled_equals_python(monkeypatch):
    """SciPy's RK45 (Dormand-Prince 5(4), its RMS error norm, exponent -1/5 and quartic dense
    output) in the loop, with and without projection and with fixed steps (every step
    accepted, ``max_step``): compiled and interpreted the same numbers and evaluations, the
    motion the minimal ODE's to the tolerance."""
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    grid = np.linspace(0.0, 1.0, 21)
    for t, kw, tol in ((grid, {}, 1e-6), ((0.0, 1.0), {"constraint_correction": False}, 1e-5),
                       (grid[:7], {"rtol": 1e6, "atol": 1e6, "max_step": 1e-3}, 1e-8)):
        opts = {"rtol": 1e-8, "atol": 1e-10} | kw
        slow, jit = _both(monkeypatch, free, t, method="rk45", **opts)
        assert jit.extra["compiled_steps"] == jit.extra["steps"] > 20
        assert jit.extra["evaluations"] == slow.extra["evaluations"]
        _against_minimal(jit, tol, 10 * tol)
        _check_derivatives(free, jit, [1, len(jit.t) - 1])


@pytest.mark.parametrize("kw", [{"method": "corrector", "step_size": 1e-3},
                                {"method": "automatic", "step_size": 1e-3, "max_error": 1e-9},
                                {"method": "predictor", "step_size": 5e-4},
                                {"method": "corrector", "step_size": 1e-3,
                                 "constraint_correction": False}],
                         ids=["corrector", "automatic", "predictor", "no-projection"])
def test_adams_fixed_steps_against_the_minimal_ode(monkeypatch, kw):
    """Mech's Adams integrator with a fixed step over 1 s of the chaotic double pendulum
    (a thousand steps and more): compiled and interpreted bit for bit, the motion the
    minimal ODE's to the fixed step's accuracy."""
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    _, jit = _both(monkeypatch, free, np.linspace(0.0, 1.0, 11), **kw)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] >= 1000
    _against_minimal(jit, 1e-4, 1e-3)


def test_mode_off_and_default(monkeypatch):
    _, free = long_run.pendulum()
    monkeypatch.setenv("MECHSYS_JIT", "1")
    assert free.simulate((0.0, 0.2), method="rk45").extra["compiled_steps"] > 0
    monkeypatch.setenv("MECHSYS_JIT", "off")
    assert free.simulate((0.0, 0.2)).extra["compiled_steps"] == 0
    monkeypatch.delenv("MECHSYS_JIT")
    assert free.simulate((0.0, 0.2)).extra["compiled_steps"] > 0         # default: on


def test_single_derivative_is_the_python_paths_and_says_when_it_cannot(monkeypatch):
    """``FreeStepper.derivative`` (SciPy's set-up and the output points' multipliers use it):
    the Python path's accelerations and multipliers to rounding; None where the Python path
    must decide (here: a state with a NaN), and a run makes no Python derivative at all."""
    from mechsys import models
    from mechsys.analyses import _free as AF
    from mechsys.solvers import _jit_free

    m = models.pendulum_chain(3, 9.81)
    m.solve(0.0)
    free = m.free(drop=["lock0", "lock1", "lock2"])
    steppers, calls = [], [0]
    init = _jit_free.FreeStepper.__init__

    def keep(self, *a, **k):
        init(self, *a, **k)
        steppers.append(self)

    def counted(*a, **k):
        calls[0] += 1
        return free_acceleration(*a, **k)

    monkeypatch.setattr(_jit_free.FreeStepper, "__init__", keep)
    monkeypatch.setattr(AF, "free_acceleration", counted)
    sol = free.simulate((0.0, 0.7), rtol=1e-9, atol=1e-11)
    assert calls[0] == 0 and sol.extra["compiled_steps"] > 0
    st = steppers[-1]
    n = free.system.n
    for k in (0, len(sol.t) // 2, len(sol.t) - 1):
        y = np.concatenate([sol.q[k], sol.qd[k]])
        f, lam = st.derivative(sol.t[k], y)
        qdd, lam_py, _ = free_acceleration(free.system, sol.t[k], sol.q[k], sol.qd[k], st.p)
        np.testing.assert_allclose(f[:n], sol.qd[k], rtol=0, atol=0)
        np.testing.assert_allclose(f[n:], qdd, rtol=1e-12, atol=1e-12 * np.abs(qdd).max())
        np.testing.assert_allclose(lam, lam_py, rtol=1e-12, atol=1e-12 * np.abs(lam_py).max())
        np.testing.assert_allclose(sol.qdd[k], qdd, rtol=1e-12, atol=1e-12 * np.abs(qdd).max())
    y = np.concatenate([sol.q[0], sol.qd[0]])
    y[2] = np.nan                     # an angle (l0.th): every equation of the link sees it
    assert st.derivative(0.0, y) is None
