"""Every error the foundation issue lists: the right exception class, and a message that
names the culprit (body, point, constraint, time, residual) and says what to do."""

import re

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T, models


@pytest.fixture
def crank_model():
    m = ms.Model2D()
    crank = m.add_body("crank", points={"pin": (2, 0)})
    return m, crank


# -- unknown names --------------------------------------------------------------------------
def test_unknown_body_by_name(crank_model):
    m, _ = crank_model
    with pytest.raises(ms.UnknownBodyError, match=r"no body named 'crnk'.*'ground', 'crank'"):
        m.body("crnk")


def test_unknown_body_by_number(crank_model):
    m, _ = crank_model
    with pytest.raises(ms.UnknownBodyError, match=r"no body number 7; bodies are numbered 1\.\.2"):
        m.body(7)


def test_body_of_another_model_is_rejected(crank_model):
    m, crank = crank_model
    other = ms.Model2D()
    with pytest.raises(ms.ModelError, match="body 'crank' of another model"):
        other.add(ms.Revolute2(other.ground.point((0, 0)), crank.point(0)))


def test_unknown_point_by_name(crank_model):
    _, crank = crank_model
    with pytest.raises(ms.UnknownPointError, match=r"body 'crank' has no point 'tip'.*\['pin'\]"):
        crank.point("tip")


def test_unknown_point_by_number(crank_model):
    _, crank = crank_model
    with pytest.raises(ms.UnknownPointError, match="body 'crank' has no point number 3"):
        crank.point(3)


def test_unknown_errors_are_key_and_value_errors(crank_model):
    m, _ = crank_model
    with pytest.raises(KeyError):
        m.body("nope")
    with pytest.raises(ValueError):
        m.body("nope")


def test_unknown_constraint(crank_model):
    m, crank = crank_model
    m.add(ms.Revolute2((0, 0), crank.point(0)), name="pivot")
    with pytest.raises(ms.UnknownConstraintError, match=r"no constraint named 'drive'.*'pivot'"):
        m.constraint("drive")


# -- dimensions and degenerate geometry -----------------------------------------------------
def test_wrong_dimension_of_local_point(crank_model):
    m, _ = crank_model
    with pytest.raises(ms.GeometryError,
                       match="point 'a' of body 'rod' has 3 coordinates; this model is 2D"):
        m.add_body("rod", points={"a": (0, 0, 0)})


def test_wrong_dimension_in_constraint(crank_model):
    m, crank = crank_model
    with pytest.raises(ms.GeometryError, match="on ground has 3 coordinates; this model is 2D"):
        m.add(ms.Revolute2((0, 0, 0), crank.point(0)))
    with pytest.raises(ms.GeometryError, match="on body 'crank' has 3 coordinates"):
        m.add(ms.Revolute2((0, 0), crank.point((1, 0, 0))))


def test_wrong_dimension_of_guess(crank_model):
    m, _ = crank_model
    with pytest.raises(ms.GeometryError, match="guess of body 'rod' has a 3-component position"):
        m.add_body("rod", guess=((0, 0, 0), 0.0))


def test_zero_length_axis(crank_model):
    m, crank = crank_model
    with pytest.raises(ms.GeometryError, match="axis on body 'crank'.*zero-length direction"):
        crank.axis(0, (0, 0))
    with pytest.raises(ms.GeometryError, match="zero-length direction on body 'ground'"):
        m.ground.axis((1, 1), (0, 0))
    with pytest.raises(ms.GeometryError, match="zero-length direction on ground"):
        ms.Translate2(((0, 0), (0, 0)), crank.axis(0, (1, 0)))  # a plain pair is a ground axis


def test_axis_through_two_coincident_points(crank_model):
    _, crank = crank_model
    with pytest.raises(ms.GeometryError, match="two points coincide on body 'crank'"):
        crank.line("pin", "pin")


# -- duplicate names ------------------------------------------------------------------------
def test_duplicate_body_name(crank_model):
    m, _ = crank_model
    with pytest.raises(ms.ModelError, match="a body named 'crank' already exists"):
        m.add_body("crank")


def test_duplicate_constraint_name(crank_model):
    m, crank = crank_model
    m.add(ms.Revolute2((0, 0), crank.point(0)), name="pivot")
    with pytest.raises(ms.ModelError, match="a constraint named 'pivot' already exists"):
        m.add(ms.RotationLock1(crank, T), name="pivot")


# -- wrong number of degrees of freedom -----------------------------------------------------
def test_underconstrained_kinematic_solve_says_how_many_dof(crank_model):
    m, crank = crank_model
    m.add(ms.Revolute2((0, 0), crank.point(0)))
    with pytest.raises(ms.ConstraintCountError,
                       match=r"1 degree\(s\) of freedom \(3 coordinates, 2 equations\)"):
        m.solve(0.0)


def test_overconstrained_names_the_redundant_constraints():
    # consistent (issue 12): solved as Adams does, with a warning naming the pair that fixes
    # the piston's y twice; inconsistent: an error naming them
    m = models.slider_crank()
    m.add(ms.RelativeY1(m.body("piston").point(0), 0), name="extra")
    with pytest.warns(ms.RedundantConstraintWarning, match="redundant but consistent") as rec:
        m.solve(0.0)
    assert "'slider'" in str(rec[0].message)
    assert "'extra'" in str(rec[0].message)
    m.replace("extra", ms.RelativeY1(m.body("piston").point(0), 0.5))
    with pytest.warns(ms.RedundantConstraintWarning), \
            pytest.raises(ms.ConstraintCountError, match="inconsistent") as err:
        m.solve(0.0)
    assert "'slider'" in str(err.value)
    assert "'extra'" in str(err.value)


def test_dof_report_names_redundant_constraints():
    m = models.slider_crank()
    m.add(ms.RelativeY1(m.body("piston").point(0), 0), name="extra")
    dof = m.dof()
    assert dof == 0 and dof.gruebler == -1
    assert "redundant" in repr(dof)


# -- solver failures ------------------------------------------------------------------------
def test_nonconvergence_reports_residual_per_equation():
    m = models.slider_crank()
    with pytest.raises(ms.ConvergenceError, match=r"at t = 0\.25 did not converge in 3") as err:
        m.solve(0.25, guess=np.full(9, 100.0), options=ms.PositionOptions(max_iterations=3))
    msg = str(err.value)
    # one line per equation: constraint name, equation number, signed residual
    assert re.search(r"constraint 'wrist pin' \(Revolute2, number 3\), equation 1: [+-]\d", msg)
    assert "initial guess" in msg
    e = err.value
    assert e.time == 0.25
    assert e.residuals.shape == (9,) and np.abs(e.residuals).max() > 1e-2
    assert len(e.history) == 4


def test_no_assembly_beyond_dead_centre_is_not_reported_as_converged():
    """Piston driven past the top dead centre (x = crank + rod = 8): no assembly exists at
    t = 1.1, which must be an error, not a 'solution' with a large residual."""
    m = models.slider_crank(drive=None)
    m.replace("drive", ms.RelativeX1(m.body("piston").point(0), 7 + T))
    m.set_guess(**{"crank.th": 0.9, "rod.x": 1.2, "rod.y": 1.6, "rod.th": -0.27, "piston.x": 7})
    with pytest.raises(ms.ConvergenceError, match=r"t = 1\.1 did not converge"):
        m.solve(np.linspace(0, 1.2, 13))


def _piston_driven_slider_crank(x_of_t):
    """Slider-crank whose piston is driven; crank and rod start exactly at top dead centre."""
    m = ms.Model2D()
    g = m.ground
    crank = m.add_body("crank", points={"pin": (2, 0)}, guess=((0, 0), 0))
    rod = m.add_body("rod", points={"a": (0, 0), "b": (6, 0)}, guess=((2, 0), 0))
    piston = m.add_body("piston", guess=((8, 0), 0))
    m.add(ms.Revolute2(g.point((0, 0)), crank.point(0)), name="crank pin")
    m.add(ms.Revolute2(crank.point("pin"), rod.point("a")), name="crank-rod")
    m.add(ms.Revolute2(rod.point("b"), piston.point(0)), name="wrist pin")
    m.add(ms.Translate2(g.axis((0, 0), (1, 0)), piston.axis((0, 0), (1, 0))), name="slider")
    m.add(ms.RelativeX1(piston.point(0), x_of_t), name="piston drive")
    return m


def test_singular_jacobian_at_dead_centre_names_time_and_constraints():
    m = _piston_driven_slider_crank(8 - T)
    with pytest.raises(ms.SingularJacobianError, match=r"singular at t = 0 ") as err:
        m.solve(np.linspace(0, 1, 11))
    msg = str(err.value)
    assert "'piston drive'" in msg
    for name in ("'crank pin'", "'crank-rod'", "'wrist pin'"):  # the locked loop
        assert name in msg
    assert "lock-up/toggle" in msg
    assert err.value.time == 0.0
    assert [c.name for c in err.value.dependent] == ["piston drive"]
    assert err.value.rank == 8


def test_singular_jacobian_at_four_bar_limit_position():
    """Rocker-driven four-bar (ground 4, crank 1, coupler 4, rocker 3): at rocker angle 90
    degrees crank and coupler are stretched in line, a limit position (reached at t = 0.5)."""
    m = ms.Model2D()
    g = m.ground
    crank = m.add_body("crank", points={"tip": (1, 0)}, guess=((0, 0), np.arctan2(0.6, 0.8)))
    rocker = m.add_body("rocker", points={"tip": (3, 0)}, guess=((4, 0), np.pi / 2))
    m.add(ms.Revolute2(g.point((0, 0)), crank.point(0)), name="crank pivot")
    m.add(ms.Revolute2(g.point((4, 0)), rocker.point(0)), name="rocker pivot")
    m.add(ms.RelativeDistance1(crank.point("tip"), rocker.point("tip"), 4), name="coupler")
    m.add(ms.RotationLock1(rocker, sp.pi / 2 + (T - sp.Rational(1, 2))), name="rocker drive")
    with pytest.raises(ms.SingularJacobianError, match=r"at t = 0\.5 ") as err:
        m.solve(np.linspace(0.5, 1.0, 6))
    msg = str(err.value)
    assert "'rocker drive'" in msg and "'coupler'" in msg
    assert err.value.time == 0.5


# -- general constraints --------------------------------------------------------------------
def test_unknown_symbol_in_general_constraint():
    m = models.slider_crank()
    s = sp.Symbol("s")
    y_b = m.location(m.body("rod").point("b"))[1]
    m.add(ms.Constraint([y_b - s]), name="user")
    with pytest.raises(ms.ModelError, match=r"constraint 'user' .* unknown symbol\(s\) \['s'\]"):
        m.solve(0.0)
    with pytest.raises(ms.ModelError, match=r"m\.parameter\(name, value\) or m\.variable"):
        m.dof()


def test_general_constraint_needs_an_equation():
    with pytest.raises(ms.ModelError, match="at least one equation"):
        ms.Constraint([])


# -- misuse of the solution -----------------------------------------------------------------
def test_missing_order_in_solution():
    m = models.slider_crank()
    sol = m.solve([0.0, 0.1], solution="location")
    with pytest.raises(ms.MechError, match="no velocity data; solve with solution='velocity'"):
        sol.velocity(m.body("piston").point(0))


def test_bad_solution_order():
    m = models.slider_crank()
    with pytest.raises(ms.ModelError, match="solution must be one of"):
        m.solve(0.0, solution="position")


def test_bad_guess_shape_lists_coordinates():
    m = models.slider_crank()
    with pytest.raises(ms.ModelError, match=r"guess must have shape \(9,\).*'crank\.x'"):
        m.solve(0.0, guess=np.zeros(3))
