"""simulate()'s times and options (free and path systems): checked up front, max_error
honoured by every integrator, options that do not apply raise; Newton options of free solves."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from conftest import load_example as load
from conftest import simulate_both

caster = load("caster")


def pendulum(L=1.0, g=9.81, angle0=0.0):
    m = ms.Model2D()
    b = m.add_body("bar", mass=1.0, centroid=(L, 0), inertia=0.0, guess=((0, 0), angle0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, angle0), name="hold")
    m.add_load(ms.Gravity((0, -1), g))
    m.solve(0.0)
    return m, m.free(drop=["hold"])


@pytest.fixture(scope="module")
def free():
    return pendulum()[1]


@pytest.fixture(scope="module")
def path():
    return caster.build()[1]


# -- times -------------------------------------------------------------------------------------
@pytest.mark.parametrize("which", ["free", "path"])
def test_unsorted_output_times_are_rejected(which, free, path):
    # used to integrate to each time in turn from wherever the stepper was: 2e-3 rad wrong
    system = free if which == "free" else path
    with pytest.raises(ms.ModelError, match=r"strictly monotonic .* t\[1\] = 0.5, t\[2\] = 0.2"):
        system.simulate([0.0, 0.5, 0.2, 1.0])
    with pytest.raises(ms.ModelError, match="strictly monotonic"):
        system.simulate([0.0, 0.5, 0.5, 1.0])          # a repeated time too


def test_sorted_and_backward_output_times_still_work(free):
    fwd = free.simulate([0.0, 0.2, 0.5], rtol=1e-11, atol=1e-12)
    np.testing.assert_array_equal(fwd.t, [0.0, 0.2, 0.5])
    bwd = free.simulate([0.0, -0.2, -0.5], rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(bwd["bar.th"], fwd["bar.th"], atol=1e-9)   # time-symmetric


@pytest.mark.parametrize("which", ["free", "path"])
@pytest.mark.parametrize("t", [(0.0, np.inf), (0.0, np.nan), [0.0, np.nan, 1.0], (-np.inf, 0.0)])
def test_non_finite_times_are_rejected(which, t, free, path):
    # (0, inf) used to hang; a NaN end time reported "singular at t = nan"
    system = free if which == "free" else path
    with pytest.raises(ms.ModelError, match="times must be finite"):
        system.simulate(t)


@pytest.mark.parametrize("which", ["free", "path"])
def test_scalar_time_is_rejected(which, free, path):
    # simulate(1.0) used to "integrate" from 1 to 1 and return two copies of the start
    system = free if which == "free" else path
    with pytest.raises(ms.ModelError, match=r"\(t0, t1\) or an array .* use solve\(t\)"):
        system.simulate(1.0)


@pytest.mark.parametrize("t,msg", [(np.zeros((2, 2)), "1-D array"), ([], "1-D array"),
                                   ([1.0], "1-D array"), ((1.0, 1.0), "t0 and t1 are equal"),
                                   (("a", "b"), "must be numbers")])
def test_malformed_times_are_rejected(t, msg, free):
    with pytest.raises(ms.ModelError, match=msg):
        free.simulate(t)


# -- max_error with every method ----------------------------------------------------------------
@pytest.mark.parametrize("method", ["dop853", "rk45"])
def test_max_error_sets_the_runge_kutta_tolerances(method, free):
    # max_error used to be ignored silently unless method="adams"
    coarse = free.simulate((0.0, 1.0), method=method, max_error=1e-3)
    assert coarse.extra["rtol"] == coarse.extra["atol"] == 1e-3
    same = free.simulate((0.0, 1.0), method=method, rtol=1e-3, atol=1e-3)
    np.testing.assert_array_equal(coarse.q, same.q)
    fine = free.simulate((0.0, 1.0), method=method, max_error=1e-9)
    assert fine.extra["steps"] > 2 * coarse.extra["steps"]
    default = free.simulate((0.0, 1.0), method=method)
    assert (default.extra["rtol"], default.extra["atol"]) == (1e-8, 1e-10)


def test_max_error_controls_the_accuracy_of_dop853():
    # pendulum released horizontally: the time to reach the bottom is a quarter of the
    # elliptic-integral period, T0 K(sin 45 deg) 2 / pi = T0 * 1.1803405990160962 / 4
    _, free = pendulum()
    T0 = 2 * np.pi / np.sqrt(9.81)
    t = np.linspace(0.0, 0.25 * 1.1803405990160962 * T0, 3)
    errors = {e: abs(free.simulate(t, max_error=e)["bar.th"][-1] + np.pi / 2)
              for e in (1e-3, 1e-6, 1e-10)}
    assert errors[1e-10] < 1e-8 < errors[1e-3]
    assert errors[1e-10] < errors[1e-6] < errors[1e-3]


def test_max_error_with_path_systems(path):
    t = np.linspace(0, 3.0, 7)
    tight = path.simulate(t, max_error=1e-11)
    np.testing.assert_allclose(tight["caster.th"], caster.closed_form(t), atol=1e-8)
    loose = path.simulate(t, max_error=1e-2)
    assert np.abs(loose["caster.th"] - caster.closed_form(t)).max() > 1e-7
    assert loose.extra["steps"] < tight.extra["steps"]


# -- options that do not apply, unknown options, bad values -------------------------------------
@pytest.mark.parametrize("which", ["free", "path"])
@pytest.mark.parametrize("kw,msg", [
    ({"fit_degree": "quartic"}, "fit_degree apply only to the Adams"),
    ({"fit_degree": "cubic"}, "fit_degree apply only to the Adams"),    # even the default value
    ({"step_size": 0.01}, "step_size apply only to the Adams"),
    ({"max_error": 1e-6, "rtol": 1e-6}, "either max_error or rtol"),
    ({"max_error": 1e-6, "atol": 1e-9}, "either max_error or atol"),
    ({"max_error": (1e-4, 1e-5, 1e-6)}, r"max_error=\(a, b, c\) sets the Adams"),
    ({"method": "adams", "rtol": 1e-6}, "rtol apply only to the Runge-Kutta"),
    ({"method": "adams", "atol": 1e-6, "max_step": 0.1}, "atol and max_step apply only"),
    ({"method": "euler"}, "method must be one of .*got 'euler'"),
    ({"options": {"ftol": 1e-8}}, r"unknown option\(s\) \['options'\]"),
    ({"tol": 1e-8}, r"unknown option\(s\) \['tol'\]"),
])
def test_options_that_do_not_apply_raise(which, kw, msg, free, path):
    system = free if which == "free" else path
    with pytest.raises(ms.ModelError, match=msg):
        system.simulate((0.0, 0.1), **kw)


@pytest.mark.parametrize("kw,msg", [
    ({"method": "adams", "fit_degree": "sextic"}, "fit_degree must be one of"),
    ({"method": "adams", "fit_degree": 5}, "fit_degree must be one of"),
    ({"max_step": 0}, "max_step must be a positive number"),
    ({"max_step": -1.0}, "max_step must be a positive number"),
    ({"rtol": 0}, "rtol must be a positive"),
    ({"rtol": 1e-20}, "below what double precision can meet"),
    ({"atol": -1e-9}, "atol must be a positive"),
    ({"rtol": np.nan}, "rtol must be a positive"),
    ({"max_error": 0.0}, "max_error must be a positive"),
    ({"method": "adams", "max_error": (1e-4, 1e-3, 1e-6)}, "c <= b <= a"),
    ({"method": "adams", "max_error": (1e-4, 1e-5)}, r"a number or \(a, b, c\)"),
    ({"method": "adams", "step_size": -0.01}, "step_size must be positive"),
    ({"method": "adams", "step_size": 0}, "step_size must be positive"),
    ({"constraint_correction": "yes"}, "constraint_correction must be True or False"),
    ({"starting_step_size": 0}, "starting_step_size must be a positive"),
    ({"starting_step_size": -0.01}, "starting_step_size must be a positive"),
    ({"starting_step_size": np.nan}, "starting_step_size must be a positive"),
    ({"starting_step_size": np.inf}, "starting_step_size must be a positive"),
    ({"starting_step_size": "0.01"}, "starting_step_size must be a positive"),
    ({"starting_step_size": True}, "starting_step_size must be a positive"),
    ({"starting_step_size": 0.2}, "longer than the interval"),
    ({"method": "adams", "starting_step_size": 0.2}, "longer than the interval"),
    ({"starting_step_size": 0.05, "max_step": 0.01}, "exceeds max_step=0.01"),
    ({"method": "adams", "step_size": 0.01, "starting_step_size": 0.01},
     "step_size=0.01 fixes every step"),
])
def test_bad_option_values_raise_model_errors(kw, msg, free):
    # fit_degree="sextic" was a KeyError, max_step=0 a SciPy ValueError, a negative Adams
    # step_size was replaced silently, rtol=0 reported "singular at t = nan"
    with pytest.raises(ms.ModelError, match=msg):
        free.simulate((0.0, 0.1), **kw)


def test_adams_constant_step_size_is_used(free):
    sol = free.simulate((0.0, 0.5), method="adams", step_size=0.01, diagnostics=True)
    np.testing.assert_allclose(sol.extra["diagnostics"]["step_size"], 0.01)
    assert sol.extra["steps"] == 50
    back = free.simulate((0.0, -0.5), method="adams", step_size=0.01, diagnostics=True)
    np.testing.assert_allclose(back.extra["diagnostics"]["step_size"], -0.01)


# -- starting_step_size (Mech's StartingStepSize) ------------------------------------------------
@pytest.mark.parametrize("method,kw", [("dop853", {}), ("rk45", {}),
                                       ("adams", {"max_error": 1e-8})])
def test_starting_step_size_is_the_first_step_in_both_loops(monkeypatch, method, kw, free):
    # small enough that every method accepts it as it is: the first accepted step equals it
    for h0 in (1e-5, 3e-5):
        for sol in simulate_both(monkeypatch, free, (0.0, 0.5), method=method,
                                 starting_step_size=h0, diagnostics=True, **kw):
            assert sol.extra["diagnostics"]["step_size"][0] == pytest.approx(h0, rel=1e-15)
        back = free.simulate((0.0, -0.5), method=method, starting_step_size=h0,
                             diagnostics=True, **kw)
        # (SciPy reports the size of a step, Adams its signed length)
        assert abs(back.extra["diagnostics"]["step_size"][0]) == pytest.approx(h0, rel=1e-15)
    # (compiled and interpreted: the same numbers, simulate_both)
    _, compiled = simulate_both(monkeypatch, free, (0.0, 0.5), method=method,
                                starting_step_size=1e-5, **kw)
    assert compiled.extra["compiled_steps"] > 0
    default = free.simulate((0.0, 0.5), method=method, diagnostics=True, **kw)
    assert default.extra["diagnostics"]["step_size"][0] != pytest.approx(1e-5)
    # the same motion, each run within its tolerance of the pendulum's own ODE
    # (a point mass at 1 m: theta'' = -g cos(theta), released at rest horizontal)
    from scipy.integrate import solve_ivp

    ref = solve_ivp(lambda _t, y: [y[1], -9.81 * np.cos(y[0])], (0.0, 0.5), [0.0, 0.0],
                    method="DOP853", rtol=1e-13, atol=1e-14).y[0, -1]
    tol = 2e-6 if method == "rk45" else 1e-6
    for run in (compiled, default):
        assert abs(run["bar.th"][-1] - ref) < tol


def test_adams_steps_follow_the_starting_step_by_halving_and_doubling(free):
    # Mech's rule: the step only halves or doubles, so every step is h0 * 2^k
    h0 = 0.0123
    sol = free.simulate((0.0, 2.0), method="adams", max_error=1e-7, starting_step_size=h0,
                        diagnostics=True)
    h = sol.extra["diagnostics"]["step_size"][:-1]        # (the last step ends at t1)
    k = np.log2(h / h0)
    np.testing.assert_allclose(k, np.round(k), atol=1e-9)
    assert len(np.unique(np.round(k))) > 1                # it did adapt
    assert sol.extra["diagnostics"]["step_size"][0] < h0  # the first try was rejected


def test_too_large_starting_step_is_shrunk_by_the_runge_kutta_control(free):
    sol = free.simulate((0.0, 1.0), rtol=1e-10, atol=1e-12, starting_step_size=0.5,
                        diagnostics=True)
    assert sol.extra["diagnostics"]["step_size"][0] < 0.5
    assert sol.extra["rejected"] >= 1
    ref = free.simulate((0.0, 1.0), rtol=1e-10, atol=1e-12)
    assert abs(sol["bar.th"][-1] - ref["bar.th"][-1]) < 1e-8


@pytest.mark.parametrize("t0", [1e6, 1e9, 1e10])
def test_adams_far_from_time_zero_integrates_the_steps_it_takes(monkeypatch, t0, free):
    # far from t = 0 the sum t + h rounds; the fits must integrate over the step the stored
    # time takes (it integrated over h: 3e-5 off at t0 = 1e9, 1e-2 at 1e12, silently)
    ref = free.simulate((0.0, 1.0), method="adams", max_error=1e-7)["bar.th"][-1]
    for sol in simulate_both(monkeypatch, free, (t0, t0 + 1.0), method="adams",
                             max_error=1e-7):
        assert abs(sol["bar.th"][-1] - ref) < 1e-8
        assert sol.t[-1] == t0 + 1.0


def test_adams_error_that_no_step_can_meet_raises(monkeypatch, free):
    # at t = 1e11 a step below 1.5e-4 does not advance the time: the start (degree 0) cannot
    # meet 1e-9, and accepting the step anyway would break max_error silently
    for jit in ("0", "1"):
        monkeypatch.setenv("MECHSYS_JIT", jit)
        with pytest.raises(ms.MechError, match=r"at t = 1e\+11 the error .* exceeds max_error "
                                               r"1e-09.*time's resolution"):
            free.simulate((1e11, 1e11 + 1.0), method="adams", max_error=1e-9)


@pytest.mark.parametrize("kw", [{"starting_step_size": 1e-17}, {"step_size": 1e-13},
                                {"method": "adams", "starting_step_size": 1e-300}])
def test_steps_that_do_not_advance_the_time_are_refused(kw, free):
    kw = {"method": "adams", **kw} if "step_size" in kw else kw
    with pytest.raises(ms.ModelError, match="does not advance the time"):
        free.simulate((100.0, 101.0), **kw)


def test_starting_step_size_with_path_systems(path):
    for method in ("dop853", "adams"):
        sol = path.simulate((0.0, 1.0), method=method, starting_step_size=2e-4,
                            diagnostics=True)
        assert sol.extra["diagnostics"]["step_size"][0] == pytest.approx(2e-4, rel=1e-15)
        t = np.linspace(0.0, 1.0, 5)
        np.testing.assert_allclose(path.simulate(t, method=method, starting_step_size=2e-4,
                                                 max_error=1e-10)["caster.th"],
                                   caster.closed_form(t), atol=1e-7)
    with pytest.raises(ms.ModelError, match="longer than the interval"):
        path.simulate((0.0, 0.1), starting_step_size=1.0)


# -- Newton options of free solves --------------------------------------------------------------
def spring_bar():
    st = ms.Model2D()
    bar = st.add_body("bar", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0),
                      inertia=1 / 12)
    st.add(ms.Revolute2(st.ground.point((0, 0)), bar.point(0)), name="pivot")
    st.add(ms.RotationLock1(bar, 0.0), name="hold")
    st.add_load(ms.Gravity((0, -1), 9.81))
    st.add_load(ms.Spring(bar.point("tip"), st.ground.point((1, 1)), stiffness=20.0,
                          free_length=0.0))
    st.solve(0.0)
    return st


def test_newton_options_of_the_equilibrium_are_used():
    st = spring_bar()
    eq = st.free(drop=["hold"], solution="static")
    exact = np.arctan(1 - 9.81 / 40)
    ref = eq.solve()
    assert ref["bar.th"] == pytest.approx(exact, abs=1e-12)
    loose = eq.solve(tolerance=1e-2)
    assert loose.iterations[0] < ref.iterations[0]
    assert abs(ref["bar.th"] - exact) < abs(loose["bar.th"] - exact) < 0.05
    with pytest.raises(ms.ConvergenceError, match="did not converge in 1 iterations"):
        eq.solve(max_iterations=1)
    assert eq.solve(max_iterations=ref.iterations[0]).iterations[0] == ref.iterations[0]


def test_newton_options_of_the_equilibrium_velocity_are_used():
    # a quadratic drag moment 4 |w| w against a unit moment: w = 1/2
    m = ms.Model2D()
    b = m.add_body("bar", mass=1.0, centroid=(0.5, 0), inertia=0.1)
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, 0.0), name="hold")
    w = m.velocity_symbols()[b.q[2]]
    m.add_load(ms.Moment(b, 1 - 4 * sp.Abs(w) * w))
    m.solve(0.0)
    free = m.free(drop=["hold"], solution="kinematic")
    start = {"bar.th_d": 2.0}
    ref = free.solve(0.0, initial_condition=start)
    assert ref.coordinate("bar.th", 1) == pytest.approx(0.5, abs=1e-12)
    with pytest.raises(ms.ConvergenceError, match="did not converge in 1 iterations"):
        free.solve(0.0, initial_condition=start, max_iterations=1)
    loose = free.solve(0.0, initial_condition=start, tolerance=1e-3)
    assert loose.iterations[0] < ref.iterations[0]
    assert 1e-12 < abs(loose.coordinate("bar.th", 1) - 0.5) < 0.01


def test_newton_options_of_a_nonlinear_free_acceleration_are_used():
    # an acceleration-dependent load (added mass) makes the free acceleration a Newton solve
    m = ms.Model2D()
    b = m.add_body("bar", mass=2.0, centroid=(1.2, 0), inertia=0.0, guess=((0, 0), -0.3))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, -0.3), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.add_load(ms.Force(b.point((1.2, 0)), -0.5 * m.acceleration(b.point((1.2, 0))),
                        mode="relative"))
    m.solve(0.0)
    free = m.free(drop=["hold"])
    assert free.solve(0.0, max_iterations=2).iterations[0] == 1
    with pytest.raises(ms.ConvergenceError, match="in 1 iterations"):
        free.solve(0.0, max_iterations=1)
    with pytest.raises(ms.ConvergenceError, match="in 1 iterations"):
        free.simulate((0.0, 0.1), max_iterations=1)


@pytest.mark.parametrize("kw,msg", [({"tolerance": 0.0}, "tolerance must be a number in"),
                                    ({"tolerance": 2.0}, "tolerance must be a number in"),
                                    ({"max_iterations": 0}, "max_iterations must be a positive"),
                                    ({"max_iterations": 2.5}, "max_iterations must be a positive")])
def test_bad_newton_options_raise(kw, msg):
    eq = spring_bar().free(drop=["hold"], solution="static")
    with pytest.raises(ms.ModelError, match=msg):
        eq.solve(**kw)


def test_newton_options_on_a_linear_free_acceleration_raise(free):
    # one linear solve: the options would be ignored, so they are refused
    with pytest.raises(ms.ModelError, match="does not use"):
        free.solve(0.0, tolerance=1e-6)
    with pytest.raises(ms.ModelError, match="does not use"):
        free.simulate((0.0, 0.1), max_iterations=5)
