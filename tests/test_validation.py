"""Input validation (issue 10): names that collide with the model's own symbols, non-finite
parameters, non-physical mass properties, zero-length directions, constraints within one
body, and the generic exceptions bad input used to raise. Each test failed before its fix."""

import dataclasses

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T, models


def _slider_crank_with_mass():
    m = models.slider_crank(crank=2.0, rod=6.0, drive=2 * sp.pi * T)
    for name, mass, c, J in (("crank", 1.5, (1, 0), 0.4), ("rod", 2.0, (3, 0), 5.0),
                             ("piston", 3.0, (0, 0), 0.0)):
        m.set_mass_properties(name, mass=mass, centroid=c, inertia=J)
    m.add_load(ms.Gravity((0, -1), 9.81))
    return m


# -- 1. parameter names and values ----------------------------------------------------------


def test_parameter_named_T_is_rejected_as_the_time_symbol():
    m = ms.Model2D()
    with pytest.raises(ms.ModelError, match="parameter name 'T' is reserved: it is the time symbol"):
        m.parameter("T", 5.0)
    assert m.parameters == {}


@pytest.mark.parametrize("name, coord", [("x2", "x"), ("y7", "y"), ("th3", "th")])
def test_parameter_named_like_a_future_coordinate_is_rejected(name, coord):
    m = ms.Model2D()
    with pytest.raises(ms.ModelError, match=rf"'{name}' is reserved: .*coordinate {coord} of the "
                                            "body that will be added"):
        m.parameter(name, 1.0)


def test_parameter_named_like_a_present_coordinate_names_the_body():
    m = ms.Model3D()
    m.add_body("arm")
    with pytest.raises(ms.ModelError, match="'e02' is reserved: .*coordinate e0 of body 'arm'"):
        m.parameter("e02", 1.0)


@pytest.mark.parametrize("name, what", [("x2_d", "velocity symbol of 'x2'"),
                                        ("th4_dd", "acceleration symbol of 'th4'"),
                                        ("s_d", "velocity symbol of 's'")])
def test_parameter_named_like_a_velocity_or_acceleration_symbol_is_rejected(name, what):
    m = ms.Model2D()
    m.variable("s", 0.1)
    with pytest.raises(ms.ModelError, match=f"'{name}' is reserved: it is the {what}"):
        m.parameter(name, 1.0)


@pytest.mark.parametrize("name", ["lam1_1", "lam12_3", "lamN_rod"])
def test_parameter_named_like_a_multiplier_is_rejected(name):
    with pytest.raises(ms.ModelError, match="Lagrange multipliers"):
        ms.Model3D().parameter(name, 1.0)


def test_parameter_named_like_a_variable_is_rejected():
    m = ms.Model2D()
    m.variable("s")
    with pytest.raises(ms.ModelError, match="'s' is reserved: it is a variable of the model"):
        m.parameter("s", 1.0)


def test_ordinary_parameter_names_stay_allowed():
    m = ms.Model2D()
    for name in ("L", "x", "x1", "theta2", "c_d", "e02", "z2", "lam", "T0", "x02"):
        m.parameter(name, 1.0)      # e02 and z2 are not coordinates in 2D; body 1 is ground
    assert len(m.parameters) == 10
    b = m.add_body("b")             # x2, y2, th2: no collision with the names above
    assert [s.name for s in b.q] == ["x2", "y2", "th2"]


def test_variable_colliding_with_coordinates_or_parameters_is_rejected():
    m = ms.Model2D()
    m.parameter("c_d", 0.5)
    with pytest.raises(ms.ModelError, match="'x3' is reserved: .*coordinate x"):
        m.variable("x3")
    with pytest.raises(ms.ModelError, match="variable 'c' collides with parameter 'c_d'"):
        m.variable("c")
    with pytest.raises(ms.ModelError, match="'T' is reserved"):
        m.variable("T")
    # a constraint's new variable is checked when the constraint is added
    b = m.add_body("b")
    th5 = sp.Symbol("th5")
    with pytest.raises(ms.ModelError, match="'th5' is reserved: .*coordinate th"):
        m.add(ms.Constraint([b.q[0] - th5], {th5: 0.0}))
    c_d = sp.Symbol("c_d")
    with pytest.raises(ms.ModelError, match="'c_d' is reserved: it is a parameter of the model"):
        m.add(ms.Constraint([b.q[0] - c_d], {c_d: 0.0}))
    assert m.constraints == []


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -np.inf])
def test_non_finite_parameter_value_is_rejected_naming_the_parameter(bad):
    m = ms.Model2D()
    with pytest.raises(ms.ModelError, match="parameter 'L' must be finite"):
        m.parameter("L", bad)
    m.parameter("L", 2.0)
    m.parameter("h", 1.0)
    with pytest.raises(ms.ModelError, match="parameter 'L' must be finite"):
        m.set_parameters(h=3.0, L=bad)
    assert m.parameters == {"L": 2.0, "h": 1.0}   # all or nothing


def test_nan_parameter_as_point_coordinate_no_longer_gives_silent_nan():
    m = ms.Model2D()
    L = m.parameter("L", 2.0)
    crank = m.add_body("crank", points={"tip": (L, 0)})
    m.add(ms.Revolute2(crank.point(0), m.ground.point((0, 0))))
    m.add(ms.RotationLock1(crank, 0.0))
    assert np.allclose(m.solve(0.0).location(crank.point("tip")), [2.0, 0.0])
    with pytest.raises(ms.ModelError, match="parameter 'L' must be finite"):
        m.set_parameters(L=np.nan)
    with pytest.raises(ms.ModelError, match="parameter 'L' needs a number, got 'two'"):
        m.set_parameters(L="two")


# -- 2. mass properties -------------------------------------------------------------------------


@pytest.mark.parametrize("kw, match", [
    ({"mass": -1.0}, "mass of body 'bob' is negative"),
    ({"mass": float("nan")}, "mass of body 'bob' must be a finite real number"),
    ({"mass": np.inf}, "mass of body 'bob' must be a finite real number"),
    ({"mass": "2 kg"}, "mass of body 'bob' must be a number .* got the string"),
    ({"mass": [1, 2]}, r"mass of body 'bob' must be a number .* got \[1, 2\]"),
    ({"mass": 1.0, "inertia": -0.1}, "inertia of body 'bob' is negative"),
    ({"mass": 1.0, "inertia": (1, 2)}, "inertia of body 'bob' .*a planar inertia is one number"),
])
def test_non_physical_planar_mass_properties_are_rejected(kw, match):
    m = ms.Model2D()
    with pytest.raises(ms.ModelError, match=match):
        m.add_body("bob", **kw)
    assert len(m.bodies) == 1
    b = m.add_body("bob", mass=1.0, inertia=0.5)
    with pytest.raises(ms.ModelError, match=match):
        m.set_mass_properties(b, **kw)
    assert (b.mass, b.inertia) == (1.0, 0.5)       # unchanged


@pytest.mark.parametrize("inertia, match", [
    ((1, 1, 5), "violate the triangle inequality"),
    ((1, 1, 1, 2, 0, 0), "not positive semidefinite"),
    ([[1, 0.1, 0], [0, 1, 0], [0, 0, 1]], "not symmetric"),
    ((-1, 1, 1), "negative moment of inertia"),
    ((1, float("nan"), 1), "finite real number"),
    (5.0, r"give \(Ixx, Iyy, Izz, Ixy, Iyz, Izx\)"),
    ((1, 1, 1, 0), r"give \(Ixx, Iyy, Izz, Ixy, Iyz, Izx\)"),
])
def test_non_physical_spatial_inertia_is_rejected(inertia, match):
    m = ms.Model3D()
    with pytest.raises(ms.ModelError, match=f"inertia of body 'top'.*{match}"):
        m.add_body("top", mass=1.0, inertia=inertia)
    b = m.add_body("top", mass=1.0)
    with pytest.raises(ms.ModelError, match=f"inertia of body 'top'.*{match}"):
        m.set_mass_properties(b, inertia=inertia)
    assert b.inertia is None


def test_zero_and_symbolic_mass_properties_stay_allowed():
    m = ms.Model3D()
    M = m.parameter("M", 2.0)
    m.add_body("link", mass=0, inertia=(0, 0, 0))                  # massless link
    m.add_body("rod", mass=1.0, inertia=(0, 1.0, 1.0))      # thin rod: I_y = I_x + I_z, the limit
    b = m.add_body("p", mass=M, inertia=(M / 10, M / 10, M / 10))
    assert b.mass == M


def test_principal_moments_give_the_diagonal_inertia_matrix():
    def mass_matrix(inertia):
        m = ms.Model3D()
        b = m.add_body("top", mass=2.0, inertia=inertia)
        return m.mass_matrix(b)

    M = mass_matrix((1.0, 2.0, 2.5))
    assert M.shape == (7, 7) and M[0, 0] == 2.0
    assert (M - mass_matrix((1.0, 2.0, 2.5, 0, 0, 0))).expand() == sp.zeros(7, 7)


# -- 3. zero-length directions and one-body constraints ------------------------------------------


def test_float_zero_directions_are_rejected():
    m = ms.Model2D()
    rod = m.add_body("rod", points={"a": (0, 0), "b": (1.0, 0)})
    with pytest.raises(ms.GeometryError, match="axis on body 'rod'.*zero-length direction"):
        rod.axis(0, (0.0, 0.0))
    with pytest.raises(ms.GeometryError, match=r"zero-length direction on body 'rod' .*\(0, 0\)"):
        rod.vector((0, 0))
    with pytest.raises(ms.GeometryError, match=r"two points coincide on body 'rod' \('a' and 'a'\)"):
        rod.vector("a", to="a")
    with pytest.raises(ms.GeometryError, match="Parallel1 vector2: zero-length direction on ground"):
        ms.Parallel1(rod.vector((1, 0)), (0.0, 0.0))
    with pytest.raises(ms.GeometryError, match="Gravity direction: zero-length"):
        ms.Gravity((0, 0), 9.81)
    with pytest.raises(ms.GeometryError, match="Force direction: zero-length"):
        ms.Force(rod.point("b"), (0.0, 0.0), 5.0)
    with pytest.raises(ms.GeometryError, match="Moment direction: zero-length"):
        ms.Moment(rod, (0.0, 0.0, 0.0), 1.0)


def test_revolute_with_both_points_on_one_body_is_rejected():
    m = ms.Model2D()
    rod = m.add_body("rod", points={"a": (0, 0), "b": (1.0, 0)})
    with pytest.raises(ms.GeometryError, match="Revolute2.*point 'a' and point 'b' are both on "
                                               "body 'rod'"):
        m.add(ms.Revolute2(rod.point("a"), rod.point("b")))
    with pytest.raises(ms.GeometryError, match="both on ground"):
        m.add(ms.Revolute2((0, 0), m.ground.point((1, 0))))
    with pytest.raises(ms.GeometryError, match="RelativeDistance1.*both on body 'rod'"):
        m.add(ms.RelativeDistance1(rod.point("a"), rod.point("b"), 1.0))
    with pytest.raises(ms.GeometryError, match="OriginLock2.*both on body 'rod'"):
        m.add(ms.OriginLock2(rod, rod, (1, 0)))
    assert m.constraints == []
    # one-sided forms keep working: ground omitted
    m.add(ms.Revolute2(rod.point("a"), m.ground.point((0, 0))))
    m.add(ms.RotationLock1(rod, 0.3))
    assert np.isclose(m.solve(0.0)["rod.th"], 0.3)


def test_spatial_two_body_constraints_on_one_body_are_rejected():
    m = ms.Model3D()
    b = m.add_body("b", points={"p": (1, 0, 0)})
    with pytest.raises(ms.GeometryError, match="Spherical3.*both on body 'b'"):
        m.add(ms.Spherical3(b.point(0), b.point("p")))
    with pytest.raises(ms.GeometryError, match="Revolute5.*both on body 'b'"):
        m.add(ms.Revolute5(b.axis(0, (0, 0, 1)), b.axis("p", (0, 0, 1))))
    m.add(ms.RotationLock1(b.axis(0, (0, 0, 1)), 0.2))      # second axis omitted: ground


# -- 4. generic exceptions -------------------------------------------------------------------------


def test_set_guess_accepts_a_full_coordinate_array():
    m = _slider_crank_with_mass()
    g = m.guess() + 0.01
    m.set_guess(g)
    assert np.allclose(m.guess(), g)
    with pytest.raises(ms.ModelError, match=r"shape \(9,\).*'x2', 'y2', 'th2'.*got shape \(4,\)"):
        m.set_guess(np.zeros(4))
    with pytest.raises(ms.ModelError, match=r"got shape \(1, 9\)"):
        m.set_guess(np.zeros((1, 9)))
    with pytest.raises(ms.ModelError, match="set_guess takes"):
        m.set_guess("zeros")
    with pytest.raises(ms.ModelError,
                       match=r"the guess of 'x2' \(coordinate x of body 'crank'\) must be finite"):
        m.set_guess(x2=np.nan)
    assert np.allclose(m.guess(), g)


def test_state_index_out_of_range_names_the_valid_range():
    sol = _slider_crank_with_mass().solve(np.linspace(0, 1, 5))
    with pytest.raises(ms.ModelError, match=r"state index 100 is out of range.*5 time point\(s\), "
                                            r"valid indices 0\.\.4"):
        sol.state(100)
    assert sol.state(-5).t == 0.0


def test_three_dimensional_gravity_in_a_planar_model():
    m = _slider_crank_with_mass()
    with pytest.raises(ms.ModelError, match="Gravity: vector .* has 3 components; this model is 2D"):
        m.add_load(ms.Gravity((0, 0, -1), 9.81))
    with pytest.raises(ms.ModelError, match="a planar Moment takes"):
        m.add_load(ms.Moment("rod", (0, 0, 1), 2.0))
    assert len(m.load_list) == 1


def test_repr_of_an_empty_solution():
    sol = _slider_crank_with_mass().solve(0.0)
    empty = dataclasses.replace(sol, t=np.zeros(0), q=np.zeros((0, 9)), qd=None, qdd=None,
                                iterations=np.zeros(0, dtype=int))
    assert repr(empty) == "<Solution: 0 time point(s), 9 coordinates, location; Newton iterations 0>"


# -- 5. dynamic loads of a static solution ----------------------------------------------------------


def test_dynamic_loads_of_a_static_solution_are_zero():
    m = _slider_crank_with_mass()
    sol = m.solve(np.linspace(0, 1, 5), solution="static")
    dyn = sol.loads("rod", "dynamic")
    assert dyn.shape == (5, 3) and np.all(dyn == 0)
    applied, reaction = sol.loads("rod", "applied"), sol.loads("rod", "reaction")
    assert np.allclose(applied + reaction + dyn, 0, atol=1e-9)
    assert np.all(sol.coordinate("rod.th", order=2) == 0)


def test_missing_order_message_says_what_to_solve():
    m = _slider_crank_with_mass()
    sol = m.solve(0.2, solution="location")
    with pytest.raises(ms.MechError) as err:
        sol.loads("rod", "dynamic")
    assert str(err.value) == ("this location solution has no acceleration data; solve with "
                              "solution='acceleration'")
    with pytest.raises(ms.MechError, match="no velocity data; solve with solution='velocity' "
                                           "or 'acceleration'$"):
        sol.coordinate("rod.th", order=1)


# -- a stranger's inputs -----------------------------------------------------------------------------


def test_non_finite_geometry_guesses_and_load_magnitudes_are_rejected():
    m = ms.Model2D()
    with pytest.raises(ms.GeometryError, match=r"point 'tip' of body 'rod': coordinates \(nan, 0\)"):
        m.add_body("rod", points={"tip": (np.nan, 0)})
    with pytest.raises(ms.ModelError, match="guess of body 'rod' must be finite"):
        m.add_body("rod", guess=((np.inf, 0), 0))
    with pytest.raises(ms.GeometryError, match="centroid of body 'rod' has 3 coordinates"):
        m.add_body("rod", mass=1.0, centroid=(0, 0, 1))
    rod = m.add_body("rod", points={"tip": (1, 0)}, mass=1.0)
    with pytest.raises(ms.GeometryError, match="must be finite"):
        rod.point((0, np.inf))
    with pytest.raises(ms.ModelError, match="Gravity g must be a finite real number"):
        ms.Gravity((0, -1), np.nan)
    with pytest.raises(ms.ModelError, match="Force magnitude must be a finite real number"):
        ms.Force(rod.point("tip"), (0, 1), float("inf"))
    with pytest.raises(ms.ModelError, match="Spring stiffness must be a finite real number"):
        ms.Spring(rod.point("tip"), (0, 0), [1, 2])
    with pytest.raises(ms.ModelError, match="no coordinate or variable named 'x9'"):
        m.add_load(ms.Load("x9", 1.0))
    assert m.load_list == []


def test_gravity_on_one_body_given_by_name():
    m = ms.Model2D()
    a = m.add_body("a", mass=1.0)
    m.add_body("b", mass=2.0)
    m.add(ms.OriginLock2(a))
    g = ms.Gravity((0, -1), 10.0, bodies="a")     # a name, not a list of one-letter names
    m.add_load(g)
    assert g.only == ["a"]
    with pytest.raises(ms.UnknownBodyError, match="no body named 'rodd'"):
        m.add_load(ms.Gravity((0, -1), 10.0, bodies=["rodd"]))


def test_variable_guess_must_be_a_finite_number():
    m = ms.Model2D()
    with pytest.raises(ms.ModelError, match="guess of variable 's' must be finite"):
        m.variable("s", np.nan)
    with pytest.raises(ms.ModelError, match="guess of variable 's' must be a number"):
        ms.Constraint([], {sp.Symbol("s"): "half"})
    assert m.variable("s", 0.5) == sp.Symbol("s")
