"""The compiled free-motion stepper (solvers/_jit_free.py) against the Python stepper.

Both run SciPy's DOP853 step-size control on the same equations; the compiled one sums the
stages in its own order, so the two agree to the integration tolerance (not bit for bit:
at tight tolerances the error estimate itself is a difference of rounding-sized numbers).
Each case checks that the compiled path really ran, that the states agree at common output
times, and that its accelerations and multipliers are those of the model at those states."""

import importlib.util
import pathlib
import sys

import numpy as np
import pytest

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


def _check_derivatives(free, sol, rows):
    """qdd and lambda returned with the compiled steps = a fresh solve at those states."""
    s = free.system
    for k in rows:
        qdd, lam, _ = free_acceleration(s, float(sol.t[k]), sol.q[k], sol.qd[k], s.p_values)
        np.testing.assert_allclose(sol.qdd[k], qdd, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(sol.lam[k], lam, rtol=1e-12, atol=1e-12)


def test_double_pendulum_compiled_equals_python(monkeypatch):
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    grid = np.linspace(0.0, 2.0, 41)
    py, jit = _both(monkeypatch, free, grid, rtol=1e-10, atol=1e-12)
    assert py.extra["compiled_steps"] == 0
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 20
    np.testing.assert_array_equal(jit.t, grid)
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(jit.qd, py.qd, rtol=0, atol=1e-8)
    np.testing.assert_allclose(jit.qdd, py.qdd, rtol=0, atol=1e-7)
    # the same step-size control: the same work, within a few steps
    assert abs(jit.extra["steps"] - py.extra["steps"]) <= 2
    assert np.abs(free.system.residual(2.0, jit.q[-1])).max() < 1e-11    # projected
    _check_derivatives(free, jit, [5, 40])


def test_every_step_output_and_no_projection(monkeypatch):
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    py, jit = _both(monkeypatch, free, (0.0, 1.0), rtol=1e-8, atol=1e-10,
                    constraint_correction=False)
    assert jit.extra["compiled_steps"] == jit.extra["steps"]
    # the local errors of these small steps are rounding-sized, so the step sizes differ at
    # the 1e-7 level; the motions agree to the tolerance
    assert abs(len(jit.t) - len(py.t)) <= 2 and jit.t[-1] == py.t[-1] == 1.0
    np.testing.assert_allclose(jit.q[-1], py.q[-1], rtol=0, atol=1e-7)
    _check_derivatives(free, jit, [1, len(jit.t) // 2, len(jit.t) - 1])


def test_four_bar_keeps_the_loop_closed(monkeypatch):
    _, free = long_run.four_bar()
    py, jit = _both(monkeypatch, free, np.linspace(0.0, 1.0, 21), rtol=1e-9, atol=1e-11)
    assert jit.extra["compiled_steps"] == jit.extra["steps"]
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-8)
    gap = max(np.abs(free.system.residual(tk, qk)).max() for tk, qk in zip(jit.t, jit.q))
    assert gap < 1e-11
    _check_derivatives(free, jit, [10, 20])


def test_backwards_in_time(monkeypatch):
    _, free = long_run.pendulum()
    py, jit = _both(monkeypatch, free, np.linspace(1.0, 0.0, 11), rtol=1e-10, atol=1e-12)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 0
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-9)


def test_spatial_gyroscope(monkeypatch):
    gyroscope = _example("gyroscope")
    m = gyroscope.build("rotor")
    m.solve(0.0)
    free = m.free(drop=["base lock"])
    ic = gyroscope.initial_condition("rotor")
    py, jit = _both(monkeypatch, free, np.linspace(0.0, 0.5, 11), initial_condition=ic,
                    rtol=1e-10, atol=1e-12)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 5
    # Euler-parameter mass blocks are singular (4 parameters, 3 rotations): the augmented
    # system is solved whole
    assert jit.extra["compiled_solver"] == "augmented"
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-8)
    _check_derivatives(free, jit, [10])


@pytest.mark.parametrize("links", [16, 52])
def test_chains_take_the_block_path(monkeypatch, links):
    """Larger systems (over 24 unknowns; 52 links: 260, above the sparse threshold, where
    the Python path uses SuperLU) solve the augmented system by the Schur complement on the
    block-diagonal mass matrix, banded: the same motion as the Python path."""
    free, _ = free_motion.compiled(free_motion.chain, links)
    py, jit = _both(monkeypatch, free, np.linspace(0.0, 0.5, 6), rtol=1e-8, atol=1e-10)
    assert jit.extra["compiled_solver"] == "block" and py.extra["compiled_solver"] is None
    assert jit.extra["compiled_steps"] == jit.extra["steps"]
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(jit.qd, py.qd, rtol=0, atol=1e-8)
    s = free.system
    assert max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(jit.t, jit.q)) < 1e-10
    _check_derivatives(free, jit, [5])


@pytest.mark.parametrize("method", ["DOP853", "predictor"])
def test_wide_trees_take_the_sparse_lu(monkeypatch, method):
    """A radial engine coasting under gravity (40 cylinders: 243 coordinates, every rod on
    the crank pin, so the augmented matrix's band spans the engine) solves its augmented
    system in the loop by the compiled sparse LU of the Python path's pattern, and projects
    through the Python path's pattern of ``[[I, J^T], [J^, 0]]`` with the same LU: the Python
    path's accelerations bit for bit, every step
    compiled, the same motion to the tolerance (both within it of a tight reference), the
    loops closed and the energy kept."""
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
    py, jit = _both(monkeypatch, free, grid, **opts)
    assert jit.extra["compiled_solver"] == "sparse" and py.extra["compiled_steps"] == 0
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 5
    monkeypatch.setenv("MECHSYS_JIT", "0")
    ref = free.simulate(grid, initial_condition=ic, rtol=1e-12, atol=1e-14)
    for run in (py, jit):
        err = np.abs(run.q - ref.q).max()
        assert err < (1e-6 if method == "DOP853" else 1e-5)
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=2 * np.abs(py.q - ref.q).max() + 1e-9)
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
    py, jit = _both(monkeypatch, free, np.linspace(0.0, 1.0, 5),
                    initial_condition={"ball.x_d": 1.0, "ball.y_d": 2.0})
    assert jit.extra["compiled_steps"] == jit.extra["steps"]
    t = jit.t
    np.testing.assert_allclose(jit["ball.y"], 2.0 * t - 9.81 / 2 * t**2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-12)


def test_singular_instants_are_handed_to_python(monkeypatch):
    """The n-four-bar (parallelograms) passes instants where its Jacobian is singular: the
    compiled loop hands those steps to the Python stepper (zone guard, regularised
    projection) and takes over again; the motion is that of the Python path."""
    n_four_bar = _example("n_four_bar")
    out = {}
    for mode in ("0", "1"):
        monkeypatch.setenv("MECHSYS_JIT", mode)
        out[mode] = n_four_bar.simulate(2, 3.0, 61)
    py, jit = out["0"], out["1"]
    assert 0 < jit.extra["compiled_steps"] < jit.extra["steps"]
    assert jit.extra["compiled_solver"] == "block"
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-6)
    # the crank angle of a parallelogram four-bar moves through the instants smoothly
    assert np.all(np.isfinite(jit.qdd)) and np.all(np.isfinite(jit.lam))


@pytest.mark.parametrize("method,options", [
    ("adams", {"fit_degree": "quartic", "max_error": 1e-10}),
    ("predictor", {"max_error": 1e-9}),
    ("corrector", {"fit_degree": "quadratic", "max_error": 1e-9, "constraint_correction": True}),
    ("adams", {"step_size": 1e-3}),
])
def test_adams_compiled_equals_python(monkeypatch, method, options):
    """Mech's Adams integrator, compiled: the same steps (the fits' weights are the same
    small solves; only rounding differs) and the same motion."""
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    py, jit = _both(monkeypatch, free, (0.0, 0.5), method=method, **options)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] == py.extra["steps"] > 50
    np.testing.assert_allclose(jit.t, py.t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(jit.qd, py.qd, rtol=0, atol=1e-9)
    _check_derivatives(free, jit, [1, len(jit.t) // 2, len(jit.t) - 1])


def test_adams_output_times_use_the_compiled_derivatives(monkeypatch):
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    grid = np.linspace(0.0, 0.5, 11)
    py, jit = _both(monkeypatch, free, grid, method="adams", max_error=1e-10)
    np.testing.assert_array_equal(jit.t, grid)
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-10)
    _check_derivatives(free, jit, [3, 10])


def test_rk45_compiled_equals_python(monkeypatch):
    """SciPy's RK45 (Dormand-Prince 5(4), its RMS error norm, exponent -1/5 and quartic dense
    output) in the compiled loop: the same steps and evaluations as the Python stepper, with
    and without projection. Adaptive steps agree to the tolerance (the error estimates differ
    by rounding, as DOP853's); with fixed steps (every step accepted, ``max_step``) the
    arithmetic agrees to rounding."""
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    grid = np.linspace(0.0, 1.0, 21)
    for t, kw, tol in ((grid, {}, 1e-9), ((0.0, 1.0), {"constraint_correction": False}, 1e-7),
                       (grid, {"rtol": 1e6, "atol": 1e6, "max_step": 1e-3}, 1e-12)):
        opts = {"rtol": 1e-8, "atol": 1e-10} | kw
        py, jit = _both(monkeypatch, free, t, method="rk45", **opts)
        assert py.extra["compiled_steps"] == 0
        assert jit.extra["compiled_steps"] == jit.extra["steps"] > 20
        assert jit.extra["steps"] == py.extra["steps"]
        assert jit.extra["evaluations"] == py.extra["evaluations"]
        np.testing.assert_allclose(jit.t, py.t, rtol=0, atol=tol)
        for a, b in ((jit.q, py.q), (jit.qd, py.qd), (jit.qdd, py.qdd), (jit.lam, py.lam)):
            scale = np.maximum(1.0, np.abs(b).max(axis=0))
            assert (np.abs(a - b) / scale).max() <= tol
        _check_derivatives(free, jit, [1, len(jit.t) - 1])
    # RK45's own accuracy: DOP853 at a tight tolerance
    ref = free.simulate(grid, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(jit.q, ref.q, atol=1e-5)


@pytest.mark.parametrize("kw", [{"method": "corrector", "step_size": 1e-3},
                                {"method": "automatic", "step_size": 1e-3, "max_error": 1e-9},
                                {"method": "predictor", "step_size": 5e-4},
                                {"method": "corrector", "step_size": 1e-3,
                                 "constraint_correction": False}],
                         ids=["corrector", "automatic", "predictor", "no-projection"])
def test_adams_fixed_steps_agree_to_rounding(monkeypatch, kw):
    """Mech's Adams integrator with a fixed step: the two loops take the same steps, so the
    arithmetic is compared alone (2 s of the chaotic double pendulum, thousands of steps):
    within 1e-12 of each other (measured 7e-15 to 3e-14)."""
    free, _ = free_motion.compiled(free_motion.double_pendulum)
    py, jit = _both(monkeypatch, free, np.linspace(0.0, 2.0, 21), **kw)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] == py.extra["steps"] >= 2000
    for a, b in ((jit.q, py.q), (jit.qd, py.qd), (jit.qdd, py.qdd), (jit.lam, py.lam)):
        scale = np.maximum(1.0, np.abs(b).max(axis=0))
        assert (np.abs(a - b) / scale).max() <= 1e-12


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
