"""The multiplier solves of static, kinematic and dynamic sweeps (the loop of
solvers/_jit_multipliers_loop.py, driven by _jit_multipliers.py), compiled and interpreted:
against the load balance solved by NumPy (``_sweep_reference.check_multipliers``) and closed
forms, the two tiers bit for bit on planar, spatial and two-stage (spline) models and
friction's Newton, the hand-over to the Python code at a point it must diagnose, and when
the loop runs."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from _sweep_reference import check_multipliers
from mechsys import T, models
from mechsys.solvers import _jit_multipliers, _statics
from mechsys.solvers._linalg import Scaling

pytest.importorskip("numba")

MODES = ("static", "kinematic", "dynamic")


def _gas_crank():
    """The slider-crank with masses, gravity and a piston force varying in time."""
    return models.slider_crank_dynamic(piston_force=300 * sp.sin(2 * sp.pi * T) + 50)


def _rotor():
    """A spatial rotor on a fixed axis (Euler parameters), spin accelerating, under gravity
    with its centroid off the axis (tests/test_inverse_dynamics_3d.py)."""
    m = ms.Model3D()
    b = m.add_body("rotor", mass=2.0, centroid=(0.1, 0.05, 0.2),
                   inertia=(0.5, 0.8, 1.1, 0.12, -0.07, 0.05), guess=((0, 0, 0), (1, 0, 0, 0)))
    x, y, z, e0, e1, e2, e3 = b.q
    th = 3.0 * T + 0.7 * T**2
    m.add(ms.Constraint([x, y, z]), name="fixed point")
    m.add(ms.Constraint([e1, e2]), name="z axis")
    m.add(ms.Constraint([e3 - sp.sin(th / 2)]), name="spin")
    m.add_load(ms.Gravity((0, 1, -1), 9.81))
    return m


def _loaded_spline_cam():
    """The spline cam of tests/test_jit_sweep.py (two-stage Piecewise kernels) with masses,
    its follower pushed back by a spring-like force along x."""
    from test_jit_sweep import _spline_cam

    m, _ = _spline_cam()
    m.set_mass_properties("cam", mass=1.0, inertia=0.2)
    m.set_mass_properties("follower", mass=0.5, inertia=0.01)
    fol = m.body("follower")
    m.add_load(ms.Force(fol.point(0), (1, 0), -40 * (fol.q[0] - 1.5)))
    return m


def loaded_chain(loops: int = 30):
    """A chain of ``loops`` four-bar loops with masses and gravity (30 loops: 183
    coordinates, above SPARSE_THRESHOLD, a banded Jacobian)."""
    m = models.four_bar_chain(loops)
    for b in m.bodies:
        if not b.is_ground:
            m.set_mass_properties(b.name, mass=1.0, centroid=(0.5, 0), inertia=0.1)
    m.add_load(ms.Gravity((0, -1), 9.81))
    return m


def _gen_arm(links=4):
    """``models.driven_gen_arm``: a driven arm in generalized coordinates under gravity.
    Short (4 links), its dynamics is symbolic (a CSE kernel whose repeated outputs the
    compiled loop reads through the kernel compiled again without CSE); long (12 links), it
    is the recursion (composite bodies), whose right-hand sides the compiled loop gets from
    ``_jit_free_loop.gen_points``."""
    return models.driven_gen_arm(links)


def test_long_gen_arm_has_the_recursive_dynamics():
    """(So that the build "gen-arm-12" below covers the recursion.)"""
    assert getattr(_gen_arm(12).compile().dynamics, "recursive", False)
    assert not getattr(_gen_arm(4).compile().dynamics, "recursive", False)


BUILDS = {"gen-arm": _gen_arm, "gen-arm-12": lambda: _gen_arm(12), "slider-crank": _gas_crank,
          "n-four-bar": lambda: models.n_four_bar(3),
          "rotor-3d": _rotor, "spline-cam": _loaded_spline_cam, "chain-183": loaded_chain,
          # a star: the sparse LU of a wide pattern
          "radial-183": lambda: models.radial_engine(30, g=9.81)}


def spy_multipliers(monkeypatch) -> list:
    """A list that receives, for each multiplier solve, how many points the compiled
    multiplier loop took."""
    taken = []
    real = _jit_multipliers.multipliers

    def spy(*a, **k):
        taken.append(real(*a, **k))
        return taken[-1]

    monkeypatch.setattr(_statics._jit_multipliers, "multipliers", spy)
    return taken


#: the interpreted run of a large model (183 unknowns: 10-25 ms a point) takes the first
#: points only: the loop is causal, so they are the whole run's first points
LARGE_PREFIX = 5


def _solve_both(monkeypatch, build, t, mode, prefix=None):
    """The same solve with the loops compiled (``MECHSYS_JIT=1``) and interpreted (``0``,
    decision 0081; over ``t[:prefix]``); also how many points the multiplier loop took in
    each: ``(compiled, interpreted, taken)``."""
    taken = spy_multipliers(monkeypatch)
    out = {}
    for jit in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        out[jit] = build().solve(t if jit == "1" or prefix is None else t[:prefix],
                                 solution=mode)
    return out["1"], out["0"], taken


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("name", list(BUILDS))
def test_compiled_and_interpreted_multipliers_agree_and_balance(monkeypatch, name, mode):
    t = np.linspace(0.0, 1.0, 41)
    prefix = LARGE_PREFIX if name.endswith("183") else None
    fast, slow, taken = _solve_both(monkeypatch, BUILDS[name], t, mode, prefix)
    assert taken[0] == len(t)                # the compiled loop took every point
    assert np.abs(slow.lam).max() > 0.1      # loads are there: not a comparison of zeros
    check_multipliers(fast, mode)
    assert taken[1] == len(slow.t)           # the interpreted loop took every point
    np.testing.assert_array_equal(fast.lam[:len(slow.t)], slow.lam)


@pytest.mark.parametrize("name", list(BUILDS))
def test_compiled_multipliers_balance_the_loads(monkeypatch, name):
    """An independent check of the compiled numbers: ``Phi_q^T lambda = Q + Qv - M qdd`` with
    the Jacobian and dynamic terms evaluated separately in Python (the residual; the solve
    by NumPy is ``check_multipliers``, above)."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    t = np.linspace(0.0, 1.0, 13)
    sol = BUILDS[name]().solve(t, solution="dynamic")
    s, dyn = sol.system, sol.system.dynamics
    for k in range(len(t)):
        J = s.jacobian(t[k], sol.q[k], sol.p)
        M, Q, Qv = dyn.terms(t[k], sol.q[k], sol.qd[k], sol.lam[k], sol.p, sol.qdd[k])
        rhs = Q + Qv - M @ sol.qdd[k]
        res = J.T @ sol.lam[k] - rhs
        assert np.abs(res).max() <= 1e-11 * (1 + np.abs(rhs).max() + np.abs(J).max()
                                              * np.abs(sol.lam[k]).max())


def test_closed_form_static_crank_torque(monkeypatch):
    """A crank of mass m (centroid at r/2) held at angle th by its driver: the driver's
    multiplier is the gravity moment m g r/2 cos(th) (up to the sign convention of
    RotationLock1), compiled and interpreted alike (bit for bit)."""
    def crank():
        m = ms.Model2D()
        c = m.add_body("crank", mass=3.0, centroid=(0.5, 0), inertia=0.25, guess=((0, 0), 0.0))
        m.add(ms.Revolute2(m.ground.point((0, 0)), c.point(0)), name="pivot")
        m.add(ms.RotationLock1(c, 2 * sp.pi * T), name="drive")
        m.add_load(ms.Gravity((0, -1), 9.81))
        return m

    t = np.linspace(0.0, 1.0, 25)
    fast, slow, taken = _solve_both(monkeypatch, crank, t, "static")
    assert taken[0] == len(t)
    k = fast.system.m - 1                    # the driver's row comes last
    moment = 3.0 * 9.81 * 0.5 * np.cos(2 * np.pi * t)
    np.testing.assert_allclose(np.abs(fast.lam[:, k]), np.abs(moment), atol=1e-12)
    np.testing.assert_array_equal(fast.lam, slow.lam)


def test_non_finite_loads_are_refused_in_both_paths(monkeypatch):
    """A load that divides by zero at t = 0.5: the compiled loop hands that point to the
    Python path, whose error names the time and the coordinate (not a NaN answer)."""
    for jit in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        m = models.slider_crank_dynamic(piston_force=1 / (T - sp.Rational(1, 2)))
        with pytest.raises(ms.ModelError, match=r"t = 0\.5: the applied loads are not finite "
                                                r"on coordinate\(s\) piston\.x"):
            m.solve(np.linspace(0, 1, 11), solution="static")


def _friction_incline():
    from test_friction import incline

    return incline(0.3, 0.25)


@pytest.mark.parametrize("build", [_gas_crank, _friction_incline, loaded_chain],
                         ids=["linear", "friction", "chain-183"])
def test_hand_over_mid_sweep_gives_the_python_result(monkeypatch, build):
    """The compiled loop stopped after 7 points: the Python code continues (with friction,
    its Newton from the 7th point's multipliers: an implementation of its own, LAPACK's
    solves), and the whole equals the loop's solve to its tolerance and balances the loads."""
    real = _jit_multipliers.multipliers

    def partial(system, times, Q, QD, QDD, p, mode, LAM, *rest):
        cut = lambda a: None if a is None else a[:7]   # noqa: E731
        return real(system, times[:7], Q[:7], cut(QD), cut(QDD), p, mode, LAM[:7], *rest)

    t = np.linspace(0.1, 1.0, 30)
    monkeypatch.setattr(_statics._jit_multipliers, "multipliers", partial)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    mixed = build().solve(t, solution="dynamic")
    monkeypatch.setattr(_statics._jit_multipliers, "multipliers", real)
    plain = build().solve(t, solution="dynamic")
    np.testing.assert_allclose(mixed.lam, plain.lam, rtol=1e-9, atol=1e-9)
    check_multipliers(mixed, "dynamic", tol=1e-8)


@pytest.mark.parametrize("mode", MODES)
def test_friction_newton_in_the_loop(monkeypatch, mode):
    """Loads that depend on the multipliers (Coulomb friction driven by the joint reactions):
    Newton at every point in the loop, each point from the previous one's multipliers:
    compiled and interpreted bit for bit, and the load balance (evaluated at the solution's
    own multipliers) solved by NumPy holds to Newton's tolerance."""
    t = np.linspace(0.1, 1.0, 12)
    fast, slow, taken = _solve_both(monkeypatch, _friction_incline, t, mode)
    assert taken == [len(t), len(t)]
    assert np.abs(slow.lam).max() > 1.0
    np.testing.assert_array_equal(fast.lam, slow.lam)
    check_multipliers(fast, mode, tol=1e-8)


def _gen_arm_with_friction():
    """The 8-link driven Gen arm (the recursive dynamics' size) with a slider on a rail that
    has Coulomb and viscous friction, pushed along the rail and loaded across it."""
    m = _gen_arm(8)
    sl = m.add_body("slider", points={"p": (0, 0)}, mass=2.0, inertia=0.1, guess=((0, -3), 0))
    m.add(ms.Translate2(m.ground.axis((0, -3)), sl.axis("p")), name="rail")
    m.add(ms.RelativeX1(sl.point("p"), 0.5 * sp.sin(T)), name="push")
    m.add_load(ms.JointFriction("rail", mu=0.3, viscous=0.1))
    m.add_load(ms.Force(sl.point("p"), (1, -1), 10.0))
    return m


@pytest.mark.parametrize("mode", MODES)
def test_long_gen_arm_with_friction_runs_compiled(monkeypatch, mode):
    """Loads that depend on the multipliers make a long Gen chain take the symbolic dynamics
    (the recursion refuses them), whose multipliers the compiled loop solves by Newton: no
    Gen model is left to the Python path for its multipliers."""
    dyn = _gen_arm_with_friction().compile().dynamics
    assert dyn.depends_on_lambda and not getattr(dyn, "recursive", False)
    t = np.linspace(0.1, 1.0, 12)
    fast, slow, taken = _solve_both(monkeypatch, _gen_arm_with_friction, t, mode)
    assert taken == [len(t), len(t)]
    assert np.abs(slow.lam).max() > 1.0
    np.testing.assert_array_equal(fast.lam, slow.lam)
    check_multipliers(fast, mode, tol=1e-8)


def test_friction_too_large_hands_over_with_the_python_error(monkeypatch):
    """Friction that locks the joint: the compiled Newton does not converge at the first
    point, and the Python path raises its ConvergenceError there (as without the loop)."""
    from test_friction import incline

    for jit in ("1", "0"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        with pytest.raises(ms.ConvergenceError, match="t = 0.1"):
            incline(0.3, 5.0).solve(np.linspace(0.1, 1.0, 4), solution="dynamic")


def test_when_the_loop_runs(monkeypatch):
    """The loop takes every job it can (decision 0081), ``MECHSYS_JIT`` choosing its tier
    (0: interpreted; auto, a short job: interpreted unless loaded; 1: compiled): the same
    multipliers bit for bit. Not without the column scales, nor in a mode whose rates were
    not computed."""
    m = _gas_crank()
    t = np.linspace(0.0, 1.0, 5)
    sol = m.solve(t, solution="dynamic")
    s = sol.system
    lam = np.empty((len(t), s.m))
    columns = Scaling.of(s, sol.q[0], s.jacobian(t[0], sol.q[0], sol.p)).columns
    args = (s, t, sol.q, sol.qd, sol.qdd, sol.p, "dynamic", lam)
    kw = {"columns": columns}
    got = []
    for jit in ("0", "auto", "1"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        lam[:] = np.nan
        assert _jit_multipliers.multipliers(*args, **kw) == len(t)
        got.append(lam.copy())
    for x in got:
        np.testing.assert_array_equal(x, sol.lam)
    check_multipliers(sol)
    # without the column scales, or in a mode whose rates were not computed: not compiled
    assert _jit_multipliers.multipliers(*args) == 0
    assert _jit_multipliers.multipliers(s, t, sol.q, None, None, sol.p, "kinematic", lam, **kw) == 0


def _friction_chain():
    """The 183-coordinate chain of ``loaded_chain`` with Coulomb friction in every ground
    pivot, driven by the joint reactions."""
    m = loaded_chain()
    for k in range(31):
        m.add_load(ms.JointFriction(f"pivot{k}", mu=0.2, radius=0.05, v_eps=1e-3))
    return m


def _friction_radial():
    """``models.radial_engine(30)`` (183 coordinates, every rod on the crank pin) with
    friction in every rod's crank-pin bearing: a Newton matrix whose pattern is a star."""
    m = models.radial_engine(30, g=9.81)
    for k in range(30):
        m.add_load(ms.JointFriction(f"pin{k}", mu=0.2, radius=0.05, v_eps=1e-3))
    return m


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
@pytest.mark.parametrize("build,plain", [(_friction_chain, loaded_chain),
                                         (_friction_radial, lambda: models.radial_engine(
                                             30, g=9.81))], ids=["chain", "radial"])
def test_large_model_with_friction_runs_compiled_through_the_band(monkeypatch, mode, build,
                                                                   plain):
    """Above SPARSE_THRESHOLD coordinates, loads that depend on the multipliers: the loop's
    Newton factorises ``Phi_q^T - dQ/dlambda`` through the Python path's pattern
    (``_patterns.multiplier_newton_pattern``: banded for the chain, the compiled sparse LU for the
    radial engine's star) and forms the residual from the Jacobian's CSC values. Compiled
    and interpreted agree bit for bit; the friction is active (the multipliers differ from
    those without it), and the compiled multipliers balance the loads evaluated separately
    in Python."""
    from mechsys.solvers._patterns import multiplier_newton_pattern

    t = np.linspace(0.1, 1.0, 12)
    fast, slow, taken = _solve_both(monkeypatch, build, t, mode, LARGE_PREFIX)
    assert fast.system.n == 183 and taken[0] == len(t)
    assert multiplier_newton_pattern(fast.system)[2].banded == (build is _friction_chain)
    assert taken[1] == LARGE_PREFIX
    np.testing.assert_array_equal(fast.lam[:LARGE_PREFIX], slow.lam)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    plain = plain().solve(t, solution=mode)
    assert np.abs(plain.lam - fast.lam).max() > 1e-3 * np.abs(plain.lam).max()
    s, dyn = fast.system, fast.system.dynamics
    for k in range(len(t)):
        J = s.jacobian(t[k], fast.q[k], fast.p)
        qdd = fast.qdd[k] if mode == "dynamic" else None
        M, Q, Qv = dyn.terms(t[k], fast.q[k], fast.qd[k], fast.lam[k], fast.p, qdd)
        rhs = Q + Qv - M @ qdd if mode == "dynamic" else Q
        res = J.T @ fast.lam[k] - rhs
        assert np.abs(res).max() <= 1e-9 * (1 + np.abs(rhs).max() + np.abs(J).max()
                                             * np.abs(fast.lam[k]).max())
