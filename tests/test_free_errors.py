"""Free systems: crashes and internal exceptions replaced by MechErrors naming the culprit."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T


def pendulum(mass=1.0, inertia=0.0, angle0=0.0, loads=True):
    m = ms.Model2D()
    b = m.add_body("bar", mass=mass, centroid=(1.0, 0), inertia=inertia, guess=((0, 0), angle0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, angle0), name="hold")
    if loads:
        m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    return m


def test_initial_guess_mapping():
    # used to raise AttributeError ('_q0')
    m = pendulum()
    free = m.free(drop=["hold"], initial_guess={"bar.th": -0.3})
    s = free.solve(0.0)
    assert s["bar.th"] == pytest.approx(-0.3)
    assert s.coordinate("bar.th", 2) == pytest.approx(-9.81 * np.cos(-0.3), rel=1e-12)
    # the static equilibrium from a mapping guess: hanging straight down
    eq = m.free(drop=["hold"], solution="static", initial_guess={"bar.th": -1.2}).solve()
    assert eq["bar.th"] == pytest.approx(-np.pi / 2, abs=1e-10)
    with pytest.raises(ms.ModelError, match="not a coordinate, velocity"):
        m.free(drop=["hold"], initial_guess={"nope": 1.0})


def test_initial_guess_from_another_model_is_rejected():
    two = ms.Model2D()
    for k in range(2):
        bk = two.add_body(f"b{k}")
        two.add(ms.RelativeX1(bk.point(0), float(k)))
        two.add(ms.RelativeY1(bk.point(0), 0.0))
        two.add(ms.RotationLock1(bk, 0.0))
    m = pendulum()
    with pytest.raises(ms.ModelError, match="has 6 coordinates, this free system 3"):
        m.free(drop=["hold"], initial_guess=two.solve(0.0))
    with pytest.raises(ms.ModelError, match="initial_condition: the solution has 6"):
        m.free(drop=["hold"]).solve(0.0, initial_condition=two.solve(0.0))


def test_non_finite_initial_condition_is_rejected():
    free = pendulum().free(drop=["hold"])
    with pytest.raises(ms.ModelError, match="'bar.th_d' is nan"):
        free.solve(0.0, initial_condition={"bar.th_d": np.nan})
    with pytest.raises(ms.ModelError, match="must be a number"):
        free.solve(0.0, initial_condition={"bar.th": "fast"})
    with pytest.raises(ms.ModelError, match="t must be a finite number"):
        free.solve(np.nan)


def drag_model(fn):
    """A bar on a pivot driven by a unit moment against a velocity-dependent drag."""
    m = ms.Model2D()
    b = m.add_body("bar", mass=1.0, centroid=(0.5, 0), inertia=0.1)
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, 0.0), name="hold")
    w = m.velocity_symbols()[b.q[2]]
    m.add_load(ms.Moment(b, 1 - fn(w)))
    m.solve(0.0)
    return m


@pytest.mark.parametrize("fn,w_eq", [
    (lambda w: 4 * sp.Abs(w) * w, 0.5),                         # 4 |w| w = 1
    (lambda w: 2 * sp.tanh(w), np.arctanh(0.5)),                 # 2 tanh(w) = 1
    (lambda w: sp.sqrt(1 + w**2) - 1 + w, 0.75),                # sqrt(1 + w^2) + w = 2
])
def test_equilibrium_velocity_with_non_polynomial_loads(fn, w_eq):
    # free.linear and repr(free) raised AttributeError; with Abs the compile failed
    # (velocity symbols were not real, so d|w|/dw stayed an unprintable Derivative)
    free = drag_model(fn).free(drop=["hold"], solution="kinematic")
    assert free.linear is False
    assert "nonlinear" in repr(free)
    s = free.solve(0.0, initial_condition={"bar.th_d": 1.0})
    assert s.coordinate("bar.th", 1) == pytest.approx(w_eq, abs=1e-10)


def test_a_velocity_load_linear_in_velocity_is_linear():
    free = drag_model(lambda w: 3 * w + sp.sin(T) * w).free(drop=["hold"], solution="kinematic")
    assert free.linear is True


def test_abs_of_time_in_a_driver():
    # |T - 0.5| failed 25 frames deep in SymPy: the time symbol was not real
    m = ms.Model2D()
    b = m.add_body("b")
    m.add(ms.RelativeX1(b.point(0), sp.Abs(T - 0.5)), name="x")
    m.add(ms.RelativeY1(b.point(0), 0.0), name="y")
    m.add(ms.RotationLock1(b, 0.0), name="th")
    sol = m.solve([0.2, 0.8])
    np.testing.assert_allclose(sol["b.x"], [0.3, 0.3], atol=1e-12)
    np.testing.assert_allclose(sol.coordinate("b.x", 1), [-1.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(sol.coordinate("b.x", 2), [0.0, 0.0], atol=1e-12)


def test_symbols_are_real():
    m = ms.Model2D()
    b = m.add_body("b")
    assert T.is_real and all(s.is_real for s in b.q)
    assert all(v.is_real for v in m.velocity_symbols().values())
    assert sp.sqrt(b.q[0] ** 2) == sp.Abs(b.q[0])


def test_body_freed_of_all_constraints_falls_freely(capfd):
    # crashed with the internal `Singular` and LAPACK printed to stderr
    m = ms.Model2D()
    b = m.add_body("b", mass=2.0, inertia=0.5)
    m.add(ms.RelativeX1(b.point(0), 0.0), name="x")
    m.add(ms.RelativeY1(b.point(0), 0.0), name="y")
    m.add(ms.RotationLock1(b, 0.0), name="th")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    free = m.free(drop=["x", "y", "th"])
    assert free.dof == 3
    t = np.linspace(0, 1, 5)
    sol = free.simulate(t, initial_condition={"b.x_d": 1.5, "b.th_d": 2.0})
    np.testing.assert_allclose(sol["b.x"], 1.5 * t, atol=1e-12)
    np.testing.assert_allclose(sol["b.y"], -9.81 * t**2 / 2, atol=1e-12)
    np.testing.assert_allclose(sol["b.th"], 2.0 * t, atol=1e-12)
    assert capfd.readouterr().err == ""


def test_empty_model_cannot_be_freed(capfd):
    with pytest.raises(ms.ModelError, match="no moving bodies"):
        ms.Model2D().free()
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize("mass,inertia,lacks", [(0.0, 0.0, "inertia"), (1.0, 0.0, None)])
def test_massless_free_motion_names_the_body(mass, inertia, lacks):
    # used to say "the constraint Jacobian is singular (rank 2 of 2)": full rank, no body
    m = ms.Model2D()
    a = m.add_body("arm", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0), inertia=0.1)
    b = m.add_body("flag", mass=mass, inertia=inertia, guess=((1, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)), name="shoulder")
    m.add(ms.Revolute2(a.point("tip"), b.point(0)), name="elbow")
    m.add(ms.RotationLock1(a, 0.0), name="lock arm")
    m.add(ms.RotationLock1(b, 0.0), name="lock flag")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    free = m.free(drop=["lock arm", "lock flag"])
    for run in (lambda: free.solve(0.0), lambda: free.simulate((0.0, 0.1))):
        with pytest.raises(ms.SingularMassError) as exc:
            run()
        msg = str(exc.value)
        assert f"body 'flag' (mass {mass:g}, inertia 0; its free coordinates flag.th" in msg
        assert "carry no inertia" in msg and "'arm'" not in msg and "t = 0" in msg
        assert exc.value.bodies == ["flag"] and exc.value.time == 0.0
        assert isinstance(exc.value, ms.SingularJacobianError)


def test_redundant_kept_constraints_are_named_and_solved():
    # the projection's J J^T was factored unchecked: the internal `Singular` escaped; then
    # (issue 12) redundant but consistent kept constraints are solved as Adams does: the
    # dependent equation is left out with a warning naming it, and the motion is the same
    m = pendulum()
    m.add(ms.RelativeX1(m.body("bar").point(0), 0.0), name="extra x")   # repeats the pivot's x
    with pytest.warns(ms.RedundantConstraintWarning, match="free motion: redundant") as rec:
        free = m.free(drop=["hold"])
    msg = str(rec[0].message)
    assert "'extra x'" in msg and "'pivot'" in msg
    t = np.linspace(0.0, 0.5, 11)
    sol = free.simulate(t)
    ref = pendulum().free(drop=["hold"]).simulate(t)
    np.testing.assert_allclose(sol["bar.th"], ref["bar.th"], rtol=0, atol=1e-9)
    assert sol.extra["indeterminate"] == ["pivot", "extra x"]


def test_static_equilibrium_without_loads_raises():
    # documented to raise, used to return a result: without loads every configuration is one
    m = pendulum(loads=False)
    with pytest.raises(ms.ModelError, match="no loads, so every configuration"):
        m.free(drop=["hold"], solution="static")


def test_equilibrium_velocity_without_velocity_loads_raises():
    free = pendulum().free(drop=["hold"], solution="kinematic")
    with pytest.raises(ms.ModelError, match="no load depends on the velocities"):
        free.solve(0.0)


def test_free_acceleration_is_taken_at_a_consistent_state_keeping_the_given_velocity():
    """Before: free.solve(initial_condition={"a.th_d": 2}) on a double pendulum left b's
    velocities at zero, a state the elbow forbids, and took the free acceleration there (a
    silent wrong answer). Now the start is projected onto the constraints keeping the given
    value: a.th_d stays 2 and b's coordinates follow (simulate does the same)."""
    from mechsys import models

    m = models.pendulum_chain(2)          # uniform rods of length 1, pinned end to end
    m.solve(0.0)
    free = m.free(drop=["lock0", "lock1"])
    sol = free.solve(0.0, initial_condition={"l0.th_d": 2.0})
    J, rhs = free.system.velocity_rhs(0.0, sol.q[0], sol.p)
    np.testing.assert_allclose(J @ sol.qd[0] - rhs, 0, atol=1e-12)
    assert float(sol.omega(m.body("l0"))) == 2.0                  # held exactly
    # the elbow moves with link 0's tip, (0, 2) for the horizontal link
    np.testing.assert_allclose(sol.velocity(m.body("l1").point(0)), [0, 2.0], atol=1e-12)
    # the minimum change gives link 1 no rotation of its own (its rate was not given)
    assert abs(float(sol.omega(m.body("l1")))) < 1e-12
    # and simulate starts from the same state
    run = free.simulate([0.0, 0.01], initial_condition={"l0.th_d": 2.0})
    np.testing.assert_allclose(run.qd[0], sol.qd[0], atol=1e-12)


def test_given_velocities_the_constraints_forbid_are_named():
    from mechsys import models

    m = models.pendulum_chain(1)          # a rod pinned at its origin: x, y cannot move
    m.solve(0.0)
    free = m.free(drop=["lock0"])
    with pytest.raises(ms.ModelError, match=r"velocities \['l0.x_d', 'l0.th_d'\] are not allowed"):
        free.solve(0.0, initial_condition={"l0.th_d": 2.0, "l0.x_d": 0.5})
    with pytest.raises(ms.ModelError, match=r"positions \['l0.x'\] are not allowed"):
        free.simulate((0, 0.1), initial_condition={"l0.x": 0.3})
