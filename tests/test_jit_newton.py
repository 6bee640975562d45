"""Free motion whose loads depend on the multipliers (friction) or on the accelerations (added
mass) in the compiled loops (``_jit_free_loop`` kind ``NEWTON``, decision 0028): the Newton
of ``solvers._free.free_acceleration`` in the loop, against the Python stepper, the equations
of motion and a conserved energy; the Newton options reach the loop."""

from __future__ import annotations

import numpy as np
import pytest

import mechsys as ms
from conftest import python_path, simulate_both

pytest.importorskip("numba")


def sliding_block(mu=0.3, alpha=0.5):
    """A block released on an incline, Coulomb friction driven by the normal reaction."""
    m = ms.Model2D()
    blk = m.add_body("block", mass=2.0, inertia=0.1, guess=((0.0, 0.0), alpha))
    slide = m.add(ms.Translate2(blk.axis((0, 0), (1, 0)),
                                m.ground.axis((0, 0), (np.cos(alpha), np.sin(alpha)))),
                  name="slide")
    m.add(ms.RelativeX1(blk.point(0), 0.0), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.add_load(ms.JointFriction(slide, mu=mu, v_eps=1e-3))
    m.solve(0.0)
    return m.free(drop=["hold"])


def added_mass_pendulum(L=1.2, m0=2.0, ma=0.5):
    """A pendulum whose bob carries the load ``-m_a a`` (tests/test_free_motion.py)."""
    m = ms.Model2D()
    b = m.add_body("bar", mass=m0, centroid=(L, 0), inertia=0.0, guess=((0, 0), -0.3))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, -0.3), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.add_load(ms.Force(b.point((L, 0)), -ma * m.acceleration(b.point((L, 0))), mode="relative"))
    m.solve(0.0)
    return m.free(drop=["hold"])


def _both(monkeypatch, build, t, **kw):
    """``(compiled loop, Python stepper)``: the loop's Newton against the Python path's
    (``free_acceleration``; the whole run by it, ``conftest.python_path``, as for kernels
    without C entry points). ``MECHSYS_JIT=0`` runs the loop's own code interpreted, the
    compiled numbers bit for bit (decision 0082; :func:`test_interpreted_newton_is_the_loops`)."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    fast = build().simulate(t, **kw)
    with monkeypatch.context() as mp:
        python_path(mp)
        slow = build().simulate(t, **kw)
    return fast, slow


@pytest.mark.parametrize("name", ["friction", "added-mass", "friction-adams"])
def test_interpreted_newton_is_the_loops(monkeypatch, name):
    """``MECHSYS_JIT=0``: the loop's Newton interpreted, the compiled numbers bit for bit."""
    build, kw = CASES[name]
    simulate_both(monkeypatch, build(), np.linspace(0.0, 0.3, 4), **kw)


CASES = {"friction": (sliding_block, {"rtol": 1e-10, "atol": 1e-12}),
         "added-mass": (added_mass_pendulum, {"rtol": 1e-10, "atol": 1e-12}),
         "friction-adams": (sliding_block, {"method": "adams", "max_error": 1e-10}),
         "friction-rk45": (sliding_block, {"method": "rk45", "rtol": 1e-10, "atol": 1e-12})}


@pytest.mark.parametrize("name", list(CASES))
def test_compiled_and_python_newton_agree(monkeypatch, name):
    build, kw = CASES[name]
    t = np.linspace(0.0, 1.0, 11)
    fast, slow = _both(monkeypatch, build, t, **kw)
    assert fast.extra["compiled_solver"] == "newton"
    assert fast.extra["compiled_steps"] == fast.extra["steps"] > 10
    assert slow.extra["compiled_steps"] == 0
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd),
                 (fast.lam, slow.lam)):
        scale = np.maximum(1.0, np.abs(b).max(axis=0))
        assert (np.abs(a - b) / scale).max() <= 1e-9


@pytest.mark.parametrize("name", ["friction", "added-mass"])
def test_compiled_newton_satisfies_the_equations_of_motion(monkeypatch, name):
    """An independent check of the loop's numbers at every output: ``M qdd + J^T lambda = Q +
    Qv`` with the loads evaluated at the loop's own multipliers and accelerations, and
    ``J qdd = gamma``, by the Python kernels."""
    build, kw = CASES[name]
    monkeypatch.setenv("MECHSYS_JIT", "1")
    sol = build().simulate(np.linspace(0.0, 1.0, 6), **kw)
    _assert_equations_of_motion(sol, 1e-9)


def _assert_equations_of_motion(sol, tol):
    """``M qdd + J^T lambda = Q + Qv`` (the loads at the solution's multipliers and
    accelerations) and ``J qdd = gamma`` at every output, by the Python kernels."""
    s = sol.system
    for k in range(len(sol.t)):
        t, q, qd, qdd, lam = sol.t[k], sol.q[k], sol.qd[k], sol.qdd[k], sol.lam[k]
        M, Q, Qv = s.dynamics.terms(t, q, qd, lam, sol.p, qdd)
        J = s.jacobian(t, q, sol.p)
        r1 = M @ qdd + J.T @ lam - Q - Qv
        r2 = J @ qdd - s.gamma_values(t, q, qd, sol.p)
        assert np.abs(r1).max() <= tol * (1 + np.abs(Q).max() + np.abs(J.T @ lam).max())
        assert np.abs(r2).max() <= tol * (1 + np.abs(qdd).max())


def test_added_mass_energy_of_the_equivalent_system(monkeypatch):
    """The pendulum with added mass moves like one of mass m + m_a under the weight of m
    alone: that system's energy is conserved along the compiled run."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    L, m0, ma, g = 1.2, 2.0, 0.5, 9.81
    sol = added_mass_pendulum(L, m0, ma).simulate((0.0, 2.0), rtol=1e-10, atol=1e-12)
    assert sol.extra["compiled_steps"] > 0
    th, w = sol["bar.th"], sol.coordinate("bar.th", 1)
    E = 0.5 * (m0 + ma) * (L * w) ** 2 + m0 * g * L * np.sin(th)
    assert np.ptp(E) < 1e-8


@pytest.mark.parametrize("jit", ["1", "0"])
def test_newton_options_reach_the_loop(monkeypatch, jit):
    """``max_iterations=1`` cannot converge (at least one step, then a check): the loop hands
    the step over and the Python stepper raises the same error as without the loop; with 2
    the loop converges and takes every step."""
    monkeypatch.setenv("MECHSYS_JIT", jit)
    with pytest.raises(ms.ConvergenceError, match="in 1 iterations"):
        added_mass_pendulum().simulate((0.0, 0.1), max_iterations=1)
    sol = added_mass_pendulum().simulate((0.0, 0.1), max_iterations=2)
    assert sol.extra["compiled_steps"] == (sol.extra["steps"] if jit == "1" else 0)


def test_newton_tolerance_is_the_loops(monkeypatch):
    """The tolerance given to simulate is the one the loop tests against (its work array),
    and the iteration limit is in its structure."""
    from mechsys.solvers._jit_free import FreeStepper

    monkeypatch.setenv("MECHSYS_JIT", "1")
    free = sliding_block()
    s = free.system
    from mechsys.solvers._free import scaling_at

    q0 = free.simulate((0.0, 0.01)).q[0]
    fast = FreeStepper.plan(s, "dop853", s.p_values, scaling_at(s, 0.0, q0, s.p_values), None,
                            False, True, None, (0.0, q0), newton={"tol": 1e-3, "max_iterations": 7})
    assert fast.solver == "newton"
    assert fast.ws[16][0][7][0] == 1e-3
    assert fast.blk_i[0][0][2] == 7


def friction_chain(n_links=32):
    """A chain of ``n_links`` pendulums with Coulomb friction in every joint: ``5 n_links``
    unknowns (coordinates and multipliers), above the dense loop's ``SMALL_LU`` = 150 from
    31 links."""
    from mechsys import models

    m = models.pendulum_chain(n_links)
    for k in range(n_links):
        m.add_load(ms.JointFriction(f"j{k}", mu=0.1, radius=0.01, v_eps=1e-3))
    m.solve(0.0)
    return m.free(drop=[f"lock{k}" for k in range(n_links)])


@pytest.mark.parametrize("rtol", [1e-6, 1e-3])
def test_large_friction_chain_runs_compiled_through_the_band(monkeypatch, rtol):
    """Above 150 unknowns the loop's Newton and projections go through the Newton matrix's
    banded pattern (``_newton_accel_band``, ``_min_norm_band``). With the same steps in both
    loops and a Newton converged to rounding, the two agree to rounding; ``rtol = 1e-3``
    leaves a drift that the projections correct (their minimum-norm corrections, by an
    augmented system here, by ``J^ J^T`` in Python)."""
    free = friction_chain(32)
    assert free.system.n + free.system.m == 160
    t = np.linspace(0.0, 0.1, 6)
    kw = dict(rtol=1e6, atol=1e6, max_step=0.1 / 60, tolerance=1e-14)
    fast, slow = _both(monkeypatch, lambda: free, t, **kw)
    assert fast.extra["compiled_solver"] == "newton"
    assert fast.extra["compiled_steps"] == fast.extra["steps"] >= 60
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd), (fast.lam, slow.lam)):
        scale = np.maximum(1.0, np.abs(b).max(axis=0))
        assert (np.abs(a - b) / scale).max() <= 1e-12
    # adaptive, with drift to project away
    fast, slow = _both(monkeypatch, lambda: free, t, rtol=rtol, atol=rtol / 100)
    assert fast.extra["compiled_steps"] == fast.extra["steps"]
    s = fast.system
    for k in range(len(t)):
        assert np.abs(s.residual(t[k], fast.q[k])).max() <= 1e-10
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd)):
        assert np.abs(a - b).max() <= 1e-7 * max(1.0, np.abs(b).max())


@pytest.mark.parametrize("jit", ["1", "python"])
def test_large_friction_chain_satisfies_the_equations_of_motion(monkeypatch, jit):
    """The banded loop's (and the Python path's pattern Newton's) accelerations and
    multipliers against the dense equations: ``M qdd + J^T lambda = Q + Qv`` with the
    friction evaluated at their multipliers, ``J qdd = gamma``."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    if jit == "python":
        python_path(monkeypatch)
    free = friction_chain(32)
    sol = free.simulate(np.linspace(0.0, 0.1, 4), rtol=1e-8, atol=1e-10)
    assert sol.extra["compiled_steps"] == (sol.extra["steps"] if jit == "1" else 0)
    _assert_equations_of_motion(sol, 1e-8)


def added_mass_chain(n_links=32):
    """``n_links`` pendulums, each tip carrying the load ``-0.3 a`` of an added mass (its own
    acceleration): loads that depend on the accelerations, 160 unknowns."""
    from mechsys import models

    m = models.pendulum_chain(n_links)
    for k in range(n_links):
        tip = m.body(f"l{k}").point((1.0, 0))
        m.add_load(ms.Force(tip, -0.3 * m.acceleration(tip), mode="relative"))
    m.solve(0.0)
    return m.free(drop=[f"lock{k}" for k in range(n_links)])


def test_large_added_mass_chain_runs_compiled_through_the_band(monkeypatch):
    """``dQ/dqdd`` in the banded Newton matrix (its first block ``M - dQ/dqdd``), both loops:
    the same steps give the same motion to rounding, and both satisfy the equations of
    motion with the loads at their own accelerations."""
    free = added_mass_chain(32)
    assert free.system.dynamics.depends_on_qdd and free.system.n + free.system.m == 160
    t = np.linspace(0.0, 0.2, 5)
    kw = dict(rtol=1e6, atol=1e6, max_step=0.2 / 100, tolerance=1e-14)
    fast, slow = _both(monkeypatch, lambda: free, t, **kw)
    assert fast.extra["compiled_steps"] == fast.extra["steps"] >= 100
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd), (fast.lam, slow.lam)):
        assert np.abs(a - b).max() <= 1e-13 * max(1.0, np.abs(b).max())
    _assert_equations_of_motion(fast, 1e-10)
    _assert_equations_of_motion(slow, 1e-10)


def friction_engine(cylinders=14):
    """A radial engine (``models.radial_engine``: every rod on the crank pin, so the Newton
    matrix's band spans the engine) coasting under gravity from 3 rad/s, Coulomb friction
    in every rod's crank-pin bearing: 173 unknowns at 14 cylinders, a pattern that is not
    banded."""
    from mechsys import models

    m = models.radial_engine(cylinders, g=9.81)
    for k in range(cylinders):
        m.add_load(ms.JointFriction(f"pin{k}", mu=0.1, radius=0.05, v_eps=1e-3))
    m.solve(0.0)
    return m.free(drop=["drive"])


def test_wide_friction_tree_runs_compiled_through_the_sparse_lu(monkeypatch):
    """A Newton matrix whose pattern is not banded (a star) goes through the compiled sparse
    LU of the Python path's pattern, in the Newton and in the projections: with the same
    steps and a Newton converged to rounding the two loops agree to rounding; adaptive, both
    are within the tolerance of a tight reference, with the loops closed."""
    from mechsys.solvers._patterns import free_newton_pattern

    free = friction_engine()
    s = free.system
    assert s.n + s.m == 173 and not free_newton_pattern(s)[2].banded
    ic = {"crank.th_d": 3.0}
    t = np.linspace(0.0, 0.3, 4)
    kw = dict(initial_condition=ic, rtol=1e6, atol=1e6, max_step=0.3 / 60, tolerance=1e-14)
    fast, slow = _both(monkeypatch, lambda: free, t, **kw)
    assert fast.extra["compiled_solver"] == "newton"
    assert fast.extra["compiled_steps"] == fast.extra["steps"] >= 60
    assert slow.extra["compiled_steps"] == 0
    for a, b in ((fast.q, slow.q), (fast.qd, slow.qd), (fast.qdd, slow.qdd), (fast.lam, slow.lam)):
        scale = np.maximum(1.0, np.abs(b).max(axis=0))
        assert (np.abs(a - b) / scale).max() <= 1e-12
    _assert_equations_of_motion(fast, 1e-10)
    t = np.linspace(0.0, 1.0, 5)
    fast, slow = _both(monkeypatch, lambda: free, t, initial_condition=ic, rtol=1e-8,
                       atol=1e-10)
    assert fast.extra["compiled_steps"] == fast.extra["steps"] > 10
    with monkeypatch.context() as mp:
        python_path(mp)
        ref = free.simulate(t, initial_condition=ic, rtol=1e-11, atol=1e-13)
    for run in (fast, slow):
        assert np.abs(run.q - ref.q).max() < 3e-6       # (measured: 1e-7 and 9e-7)
        assert max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(run.t, run.q)) < 1e-10
    # friction takes energy out; gravity and the bearings' work are the only loads
    energy = fast.body_energy() + fast.potential_energy()
    assert np.all(np.diff(energy) < 1e-9 * np.abs(energy).max())
