"""Issue 34, section 2: messages name the culprit and give advice that can be followed."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T
from mechsys.models import slider_crank


def crank_driven_by(angle):
    m = ms.Model2D()
    c = m.add_body("crank", points={"tip": (1, 0)})
    m.add(ms.Revolute2((0, 0), c.point(0)))
    m.add(ms.RotationLock1(c, angle), name="drive")
    return m


def test_nan_guess_names_the_body_and_coordinate():
    m = slider_crank()
    with pytest.raises(ms.ModelError, match=r"'x3' \(coordinate x of body 'rod'\) must be finite"):
        m.set_guess({"rod.x": float("nan")})
    g = m.guess()
    g[4] = np.inf                                        # (rod.y)
    with pytest.raises(ms.ModelError, match=r"value inf given for 'rod\.y' is not finite"):
        m.solve(0.0, guess=g)


def test_a_body_no_constraint_uses_is_named():
    m = slider_crank()
    m.add_body("loose", guess=((1, 1), 0))
    with pytest.raises(ms.ConstraintCountError, match="coordinates of body 'loose'"):
        m.solve(0.0)
    m2 = slider_crank()                                  # no such body: no such sentence
    m2.remove("drive")
    with pytest.raises(ms.ConstraintCountError) as err:
        m2.solve(0.0)
    assert "No constraint uses" not in str(err.value)


@pytest.mark.parametrize("angle", ["2*pi*T", 2 * sp.pi * sp.Symbol("T")], ids=["string", "Symbol"])
def test_a_time_symbol_of_its_own_gets_possible_advice(angle):
    """Not "declare it with m.parameter", which is impossible for T: say which T to use."""
    with pytest.raises(ms.ModelError) as err:
        crank_driven_by(angle).solve(0.1)
    msg = str(err.value)
    assert "other assumptions" in msg and "mechsys.T" in msg and "m.parameter(name" not in msg
    # and the advice works
    sol = crank_driven_by(2 * sp.pi * T).solve(0.1, "location")
    assert np.isclose(sol.q[0, 2], 0.2 * np.pi)


def test_a_parameter_symbol_with_other_assumptions_is_named():
    m = ms.Model2D()
    c = m.add_body("crank")
    m.parameter("w", 2.0)
    m.add(ms.Revolute2((0, 0), c.point(0)))
    m.add(ms.RotationLock1(c, sp.Symbol("w", positive=True) * T))
    with pytest.raises(ms.ModelError, match=r"'w' exists in the model with other assumptions.*"
                                            r"m\.parameter\('w'"):
        m.solve(0.1)


def test_a_velocity_constraint_in_the_model_points_to_path():
    m = ms.Model2D()
    caster = m.add_body("caster", points={"wheel": (0.3, 0.0)}, guess=((0, 0), 3.09), mass=1,
                        inertia=0.1)
    m.add(ms.Revolute2(caster.point(0), m.ground.point((-T, 0))), name="pivot")
    m.add(ms.Orthogonal1(m.velocity(caster.point("wheel")), caster.vector((0, 1))), name="rolling")
    with pytest.raises(ms.ModelError, match=r"'rolling'.*velocity constraint.*m\.path\(replace="
                                            r".*free motion \(m\.free\) holds"):
        m.solve(0.0)
    # free motion holds it (decision 0053): the wheel point never moves sideways
    sol = m.free(drop=["pivot"], initial_condition={"caster.x_d": 0.5}).simulate(
        np.linspace(0, 1, 3))
    assert sol.extra["accuracy"]["nonholonomic"] < 1e-12


@pytest.mark.parametrize("name", ["pi", "E", "I", "oo"])
def test_constant_names_are_refused_as_parameters(name):
    m = ms.Model2D()
    with pytest.raises(ms.ModelError, match=rf"parameter name '{name}' is reserved: it is SymPy's"):
        m.parameter(name, 3.0)
    with pytest.raises(ms.ModelError, match=rf"'{name}' is reserved"):
        m.variable(name, 0.0)


def test_saving_names_a_symbol_called_pi(tmp_path):
    """A symbol named pi that got into a model another way (a general Constraint's variable)
    is named when saving, instead of "does not read back"."""
    m = crank_driven_by(2 * sp.pi * T)
    m.parameter("k", 1.0)
    m._params[sp.Symbol("pi")] = 3.0          # (as models from before the refusal could hold)
    m.remove("drive")
    m.add(ms.RotationLock1(m.body("crank"), sp.Symbol("pi") * T + sp.pi), name="drive")
    with pytest.raises(ms.ModelError, match=r"symbol 'pi' \(a parameter or variable of the model\)"
                                            r" has the name of the constant pi"):
        m.save(tmp_path / "m.json")
