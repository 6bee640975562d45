"""The compiled free-motion stepper on generalized coordinates (decision 0018): the recursive
Gen dynamics (joint kernels, articulated-body and composite-body recursions) and the
symbolic projection's CSE kernels evaluated inside the compiled DOP853 and Adams loops,
against independent references (the minimal ODE of the double pendulum, the
absolute-coordinate models) and interpreted (``MECHSYS_JIT=0``: the same numbers bit for bit,
decision 0082); the accelerations and multipliers the loop returns are those of a fresh
Python evaluation of the recursion at the same states (1e-12)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechsys as ms
from test_generalized import T_OUT, Y0, _four_bar, abs_pendulum, gen_pendulum, minimal_rhs
from test_generalized_3d import abs_arm, abs_arm_omegas, gen_arm
from test_generalized_recursive import _mixed, slide_chain
from test_jit_free import _both, _check_derivatives

pytest.importorskip("numba")

IC = {"t1": Y0[0], "t2": Y0[1], "t1_d": Y0[2], "t2_d": Y0[3]}


def test_recursive_chain_dop853_compiled_equals_python(monkeypatch):
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")
    free = slide_chain().free()
    grid = np.linspace(0.0, 1.0, 21)
    # (interpreted, MECHSYS_JIT=0: the same numbers bit for bit; decision 0082)
    _, jit = _both(monkeypatch, free, grid, rtol=1e-10, atol=1e-12)
    assert jit.extra["compiled_solver"] == "recursive"
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 20
    np.testing.assert_array_equal(jit.t, grid)
    # the loop's recursion against the Python recursion at its states
    _check_derivatives(free, jit, [3, 20])


@pytest.mark.parametrize("method", ["automatic", "predictor", "corrector"])
def test_recursive_chain_adams_compiled_equals_python(monkeypatch, method):
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")
    free = slide_chain().free()
    # (interpreted, MECHSYS_JIT=0: the same numbers bit for bit; decision 0082)
    _, jit = _both(monkeypatch, free, (0.0, 0.5), method=method, max_error=1e-7)
    assert jit.extra["compiled_solver"] == "recursive"
    assert jit.extra["compiled_steps"] > 0.9 * jit.extra["steps"]
    _check_derivatives(free, jit, [len(jit.t) // 2, len(jit.t) - 1])


@pytest.mark.parametrize("mode", ["recursive", "symbolic"])
def test_double_pendulum_compiled_vs_minimal_ode_and_absolute(monkeypatch, mode):
    """The issue's check on the compiled path: GenRevolute2 double pendulum against the
    minimal ODE written in the test and the absolute-coordinate model, 1e-8."""
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", mode)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    g = gen_pendulum()
    sol = g.free().simulate(T_OUT, initial_condition=IC, rtol=1e-12, atol=1e-12)
    assert sol.extra["compiled_steps"] == sol.extra["steps"]
    # symbolic: the CSE kernel's repeated outputs expanded in the loop
    assert sol.extra["compiled_solver"] == ("recursive" if mode == "recursive" else "augmented")
    ref = solve_ivp(minimal_rhs, (0, T_OUT[-1]), Y0, t_eval=T_OUT, rtol=1e-12, atol=1e-12,
                    method="DOP853")
    np.testing.assert_allclose(np.ravel(sol["t1"]), ref.y[0], atol=1e-8)
    np.testing.assert_allclose(np.ravel(sol["t2"]), ref.y[1], atol=1e-8)
    am = abs_pendulum(Y0[0], Y0[1])
    sa = am.free(drop=["l1", "l2"]).simulate(
        T_OUT, initial_condition={"a.th_d": Y0[2], "b.th_d": Y0[2] + Y0[3]}, rtol=1e-12, atol=1e-12)
    assert sa.extra["compiled_steps"] == sa.extra["steps"]
    np.testing.assert_allclose(sol.location(g.body("b").point("e")),
                               sa.location(am.body("b").point("e")), atol=1e-8)
    _check_derivatives(g.free(), sol, [2, 6])


def _closed_four_bar():
    m = _four_bar(True)[0]
    for b, (mass, j) in zip(("crank", "coupler", "rocker"), ((1.0, 0.1), (2.0, 0.3), (1.5, 0.2))):
        m.set_mass_properties(b, mass=mass, inertia=j, centroid=(0.5, 0.1))
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    return m


@pytest.mark.parametrize("mode", ["recursive", "symbolic"])
def test_four_bar_on_gen_chain_compiled_with_projection(monkeypatch, mode):
    """A four-bar closed on a Gen chain by a Revolute2 (two closing equations): the mass
    matrix from the composite-body recursion (or the symbolic one) in the augmented system,
    the projection onto the closing constraint after every step, all compiled."""
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", mode)
    m = _closed_four_bar()
    free = m.free(drop=["drive"])
    grid = np.linspace(0.0, 1.0, 11)
    py, jit = _both(monkeypatch, free, grid, rtol=1e-10, atol=1e-12)
    assert jit.extra["compiled_solver"] == ("recursive+augmented" if mode == "recursive"
                                            else "augmented")
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 10
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-8)
    s = free.system
    for k in (5, 10):
        assert np.abs(s.residual(float(jit.t[k]), jit.q[k])).max() < 1e-11   # projected
    _check_derivatives(free, jit, [4, 10])
    # Adams too
    py, jit = _both(monkeypatch, free, (0.0, 0.3), method="automatic", max_error=1e-7)
    assert jit.extra["compiled_steps"] > 0 and jit.extra["steps"] == py.extra["steps"]
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-9)


def test_four_bar_on_gen_chain_matches_the_absolute_four_bar(monkeypatch):
    """The same free motion as the all-absolute four-bar (3 bodies, 4 pins), compiled both."""
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")
    monkeypatch.setenv("MECHSYS_JIT", "1")
    m = _closed_four_bar()
    sg = m.free(drop=["drive"]).simulate(np.linspace(0, 1, 6), initial_condition={"th_d": 2.0},
                                         rtol=1e-11, atol=1e-12)
    assert sg.extra["compiled_solver"] == "recursive+augmented"
    a_, b_, c_, d_ = _four_bar(True)[1]
    sol0 = m.solve(0.0, solution="location")
    a = ms.Model2D()
    bodies = {}
    for name, length, mass, j in (("crank", a_, 1.0, 0.1), ("coupler", b_, 2.0, 0.3),
                                  ("rocker", c_, 1.5, 0.2)):
        x, y, th = (float(np.ravel(sol0.eval(s))[0]) for s in m.body(name).q)
        bodies[name] = a.add_body(name, points={"o": (0, 0), "e": (length, 0)}, mass=mass,
                                  inertia=j, centroid=(0.5, 0.1), guess=((x, y), th))
    a.add(ms.Revolute2(bodies["crank"].point("o"), a.ground.point((0, 0))), name="j1")
    a.add(ms.Revolute2(bodies["coupler"].point("o"), bodies["crank"].point("e")), name="j2")
    a.add(ms.Revolute2(bodies["rocker"].point("o"), a.ground.point((d_, 0))), name="j4")
    a.add(ms.Revolute2(bodies["coupler"].point("e"), bodies["rocker"].point("e")), name="close")
    a.add(ms.RotationLock1(bodies["crank"], 0.5), name="lock")
    a.add_load(ms.Gravity((0, -1), 9.81))
    a.solve(0.0)
    sa = a.free(drop=["lock"]).simulate(np.linspace(0, 1, 6), initial_condition={"crank.th_d": 2.0},
                                        rtol=1e-11, atol=1e-12)
    assert sa.extra["compiled_steps"] == sa.extra["steps"]
    for name in ("crank", "coupler", "rocker"):
        np.testing.assert_allclose(sg.location(m.body(name).point("e")),
                                   sa.location(a.body(name).point("e")), atol=1e-7)


def test_absolute_master_loads_and_slide(monkeypatch):
    """A Gen pendulum and telescope on an absolute cart on a slide, with a spring, a damper,
    a moment and a joint torque: absolute mass entries, the recursion's contributions to the
    cart's coordinates and the slide's multipliers, compiled = Python."""
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")
    free = _mixed().free()
    grid = np.linspace(0.0, 0.6, 7)
    py, jit = _both(monkeypatch, free, grid, rtol=1e-10, atol=1e-12)
    assert jit.extra["compiled_solver"] == "recursive+augmented"
    assert jit.extra["compiled_steps"] == jit.extra["steps"]
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-8)
    _check_derivatives(free, jit, [3, 6])


@pytest.mark.parametrize("mode", ["recursive", "symbolic"])
def test_arm_3d_compiled_vs_absolute_model(monkeypatch, mode):
    """The issue's 3D arm of three GenRevolute5 joints (Euler-parameter poses): compiled, the
    same tip motion as the absolute-coordinate arm."""
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", mode)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    q0, qd0 = [0.3, -0.4, 0.7], [0.8, 0.0, -0.6]
    t = np.linspace(0, 0.6, 4)
    g = gen_arm()
    ic = {f"q{k}": q0[k] for k in range(3)} | {f"q{k}_d": qd0[k] for k in range(3)}
    sg = g.free().simulate(t, initial_condition=ic, rtol=1e-11, atol=1e-11)
    assert sg.extra["compiled_steps"] == sg.extra["steps"]
    assert sg.extra["compiled_solver"] == ("recursive" if mode == "recursive" else "augmented")
    a = abs_arm(q0)
    sa = a.free().simulate(t, initial_condition=abs_arm_omegas(q0, qd0), rtol=1e-11, atol=1e-11)
    for k in range(3):
        np.testing.assert_allclose(sg.location(g.body(f"l{k}").point("e")),
                                   sa.location(a.body(f"l{k}").point("e")), atol=1e-7)
    _check_derivatives(g.free(), sg, [1, 3])


def test_mode_off_runs_the_loop_interpreted(monkeypatch):
    """``MECHSYS_JIT=0``: nothing compiled, the loop's recursion interpreted (decision 0082)."""
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")
    monkeypatch.setenv("MECHSYS_JIT", "0")
    sol = slide_chain(4).free().simulate((0.0, 0.2))
    assert sol.extra["compiled_steps"] == 0 and sol.extra["compiled_solver"] == "recursive"
    assert sol.extra["interpreted_steps"] == sol.extra["steps"] > 0


def test_massless_joint_is_handed_to_python(monkeypatch):
    """A joint whose motion carries no mass: the articulated recursion fails in the loop, the
    Python stepper takes the step and gives the model's diagnosis."""
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")
    monkeypatch.setenv("MECHSYS_JIT", "1")
    m = gen_pendulum()
    m.set_mass_properties("b", mass=0, inertia=0)
    with pytest.raises(ms.SingularMassError, match="'t2'"):
        m.free().simulate((0.0, 0.1))


def test_pickles_after_a_compiled_run(monkeypatch):
    """The kernels' C entry points (ctypes) are not pickled: a free system that ran compiled
    is still a sweep's payload, and runs compiled again after unpickling."""
    import pickle

    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")
    monkeypatch.setenv("MECHSYS_JIT", "1")
    free = slide_chain(4).free()
    a = free.simulate((0.0, 0.2))
    assert a.extra["compiled_solver"] == "recursive"
    b = pickle.loads(pickle.dumps(free)).simulate((0.0, 0.2))
    assert b.extra["compiled_solver"] == "recursive"
    np.testing.assert_allclose(b.q, a.q, rtol=0, atol=1e-13)
