"""Non-physical loads, misspelt options and objects of another model, once accepted silently
and used (issue 34, section 1).

* Loads: a negative stiffness, free length, damping, friction coefficient, pin radius, spin
  inertia or cutoff raises a ``ModelError`` naming the load and the quantity; given as a
  parameter it is checked with the parameter values when a run starts. A force law of
  another sign stays possible through ``law=``, whose answer is checked against statics.
* Enumerated keywords (backend, solution kind, method, modes, coordinates ...) raise an
  ``OptionError`` listing the accepted values and suggesting the closest one; options
  classes name an unknown field instead of a bare ``TypeError``.
* A velocity constraint of another model given to ``m.path`` is refused.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T


def slider():
    """A block on a horizontal slide (x free), held at x = 2 by ``hold``."""
    m = ms.Model2D()
    b = m.add_body("block", points={"p": (0, 0)}, mass=1.0, inertia=0.1, guess=((2, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), b.axis((0, 0), (1, 0))), name="slide")
    m.add(ms.RelativeX1(b.point(0), m.ground.point((0, 0)), 2.0), name="hold")
    return m


def pend():
    m = ms.Model2D()
    b = m.add_body("bar", points={"tip": (1, 0)}, mass=1.0, centroid=(1, 0), inertia=0.1,
                   guess=((0, 0), -1.0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, -1.0), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    return m


# -- loads: values that have no physical meaning ---------------------------------------------
def _tip(m):
    return m.body("bar").point("tip"), m.ground.point((2, 0))


BAD_LOADS = [
    ("spring free length", lambda m: ms.Spring(*_tip(m), 10.0, free_length=-1.0),
     "Spring free_length"),
    ("spring stiffness", lambda m: ms.Spring(*_tip(m), -10.0), "Spring stiffness"),
    ("damper", lambda m: ms.Damper(*_tip(m), -0.5), "Damper damping"),
    ("torsion spring", lambda m: ms.TorsionSpring(m.ground, m.body("bar"), -3.0),
     "TorsionSpring stiffness"),
    ("torsion damper", lambda m: ms.TorsionDamper(m.ground, m.body("bar"), -3.0),
     "TorsionDamper damping"),
    ("friction mu", lambda m: ms.JointFriction("pivot", mu=-0.1, radius=0.05), "JointFriction mu"),
    ("friction radius", lambda m: ms.JointFriction("pivot", mu=0.1, radius=-0.05),
     "JointFriction radius"),
    ("friction viscous", lambda m: ms.JointFriction("pivot", viscous=-0.2),
     "JointFriction viscous"),
    ("friction v_eps", lambda m: ms.JointFriction("pivot", mu=0.1, radius=0.05, v_eps=-1e-3),
     "JointFriction v_eps"),
    ("friction eps_reaction", lambda m: ms.JointFriction("pivot", mu=0.1, eps_reaction="x"),
     "JointFriction eps_reaction"),
    ("friction mu not a number", lambda m: ms.JointFriction("pivot", mu="abc+"),
     "JointFriction mu"),
    ("force cutoff", lambda m: ms.Force(_tip(m)[0], (0, 1), 1.0, cutoff=-1.0), "Force cutoff"),
    ("moment cutoff", lambda m: ms.Moment(m.body("bar"), 1.0, cutoff=-1.0), "Moment cutoff"),
]


@pytest.mark.parametrize("make,culprit", [b[1:] for b in BAD_LOADS], ids=[b[0] for b in BAD_LOADS])
def test_non_physical_load_is_refused(make, culprit):
    m = pend()
    with pytest.raises(ms.ModelError, match=culprit):
        m.add_load(make(m))


def test_gyro_moment_negative_inertia_and_complex_spin_are_refused():
    m = ms.Model3D()
    b = m.add_body("rotor", mass=1.0, inertia=(1, 1, 2))
    with pytest.raises(ms.ModelError, match="GyroMoment inertia"):
        ms.GyroMoment(b, (0, 0, 1), 10.0, inertia=-2.0)
    with pytest.raises(ms.ModelError, match="GyroMoment omega"):
        ms.GyroMoment(b, (0, 0, 1), "I")


@pytest.mark.parametrize("kind", ["free_length", "stiffness", "mu", "damping"])
def test_negative_parameter_value_is_refused_when_the_run_starts(kind):
    """A symbolic value cannot be checked when the load is built; with its parameter's value
    it is, when a solve or a simulation starts (and again after ``set_parameters``)."""
    m = pend()
    tip, anchor = _tip(m)
    s = m.parameter("s", 1.0)
    load = {"free_length": lambda: ms.Spring(tip, anchor, 10.0, free_length=s / 2),
            "stiffness": lambda: ms.Spring(tip, anchor, 3 * s),
            "mu": lambda: ms.JointFriction("pivot", mu=s / 10, radius=0.05),
            "damping": lambda: ms.Damper(tip, anchor, s)}[kind]()
    m.add_load(load, name="element")
    m.solve(0.0, solution="static")                # s = 1: accepted
    m.set_parameters(s=-1.0)
    with pytest.raises(ms.ModelError, match=rf"load 'element'.*{kind}.*with the current "
                                            "parameter values"):
        m.solve(0.0, solution="static")
    free = m.free(drop=["hold"]) if kind != "mu" else None
    if free is not None:
        with pytest.raises(ms.ModelError, match="load 'element'"):
            free.simulate((0.0, 0.1))


def test_negative_parameter_value_is_refused_in_a_locked_load_case():
    """``m.lock(...).solve(parameters=...)`` runs load cases with other parameter values."""
    m = pend()
    tip, anchor = _tip(m)
    k = m.parameter("k", 10.0)
    m.add_load(ms.Spring(tip, anchor, k, free_length=0.5), name="spring")
    locked = m.lock(0.0)
    ok = locked.solve("static", parameters={"k": 20.0})
    assert np.all(np.isfinite(ok.lam))
    with pytest.raises(ms.ModelError, match=r"load 'spring'.*stiffness = k.*-20"):
        locked.solve("static", parameters={"k": -20.0})


def test_law_is_the_way_to_another_force_law():
    """A spring that pushes where a linear one would pull (``law=``) is accepted, and its
    static answer is the law's: block held at x = 2 by the driver, spring to the origin with
    tension ``-k (L - L0)``; the driver's reaction balances ``k (L - L0)`` along +x."""
    m = slider()
    b = m.body("block")
    k, L0 = 5.0, 0.5
    m.add_load(ms.Spring(b.point(0), m.ground.point((0, 0)), law=lambda L: -k * (L - L0)))
    sol = m.solve(0.0, solution="static")
    force, _ = sol.reaction("hold", "block")
    # spring force on the block: -tension * (r_block - 0)/L = +k (L - L0) along +x (pushes)
    np.testing.assert_allclose(np.ravel(force)[0] + k * (2.0 - L0), 0.0, atol=1e-12)
    with pytest.raises(ms.ModelError, match="law must be a function"):
        ms.Spring(b.point(0), m.ground.point((0, 0)), law=3.0)


def test_zero_values_stay_allowed():
    m = pend()
    tip, anchor = _tip(m)
    m.add_load(ms.Spring(tip, anchor, 0.0, free_length=0.0))
    m.add_load(ms.JointFriction("pivot", mu=0.0, radius=0.0, viscous=0.0))
    sol = m.solve(0.0, solution="static")
    # gravity alone: the driver holds m g times the lever arm cos(-1)
    _, moment = sol.reaction("hold", "bar")
    np.testing.assert_allclose(abs(float(moment)), 9.81 * np.cos(1.0), rtol=1e-10)


# -- enumerated keywords ---------------------------------------------------------------------
def crank():
    m = ms.Model2D()
    c = m.add_body("crank", points={"tip": (1, 0)}, guess=((0, 0), 0.1), mass=1.0, inertia=0.1)
    m.add(ms.Revolute2(m.ground.point((0, 0)), c.point(0)), name="pivot")
    m.add(ms.RotationLock1(c, T), name="drive")
    return m


MISSPELT = [
    ("backend", lambda: ms.Model2D(backend="symengin"), "'symengine'"),
    ("3D backend", lambda: ms.Model3D(backend="Sympy"), "'sympy'"),
    ("solution", lambda: crank().solve(0.0, solution="Velocity"), "'velocity'"),
    ("free solution", lambda: pend().free(drop=["hold"], solution="dynamc"), "'dynamic'"),
    ("lock solution", lambda: crank().lock(solution="velocty"), "'velocity'"),
    ("method", lambda: pend().free(drop=["hold"]).simulate((0, 1), method="dop835"), "'dop853'"),
    ("moment mode", lambda: ms.Moment("crank", 1.0, mode="absolut"), "'absolute'"),
    ("force mode", lambda: ms.Force(crank().body("crank").point(0), (0, 1), 1.0,
                                    mode="relativ"), "'relative'"),
    ("gravity mode", lambda: ms.Gravity((0, -1), 9.81, mode="Relative"), "'relative'"),
    ("friction kind", lambda: ms.JointFriction("pivot", mu=0.1, kind="rotationl"),
     "'rotational'"),
    ("orientation", lambda: ms.Model2D(orientation="eulr"), "'euler'"),
    ("velocity", lambda: ms.Model3D(velocity="angualr"), "'angular'"),
    ("coordinates", lambda: ms.Model3D(coordinates="lokal"), "'local'"),
    ("reaction coordinates", lambda: crank().solve([0.0, 0.5], "static").reaction(
        "pivot", "crank", coordinates="golbal"), "'global'"),
    ("loads type", lambda: crank().solve([0.0, 0.5], "static").loads("crank", type="aplied"),
     "'applied'"),
    ("instant centre", lambda: crank().instant_center("crank", coordinates="globl"), "'global'"),
    ("compile option", lambda: crank().set_compile_options(optlevel=1), "'opt_level'"),
    ("simulate keyword", lambda: pend().free(drop=["hold"]).simulate((0, 1), max_eror=1e-6),
     "'max_error'"),
    ("options mapping", lambda: crank().solve(0.0, options={"ftl": 1e-9}), "'ftol'"),
    ("cardan joint", lambda: __import__("mechsys.models").models.cardan_joint(joint="universl"),
     "'universal'"),
    ("equations part", lambda: crank().equations().pretty("jacobain"), "'jacobian'"),
    ("compile process", lambda: crank().set_compile_options(process="Chop"), "'chop'"),
    ("spline ends", lambda: ms.SplineFit([[0, 0], [1, 1], [2, 0]], end_conditions="natual"),
     "'natural'"),
]


@pytest.mark.parametrize("call,suggestion", [x[1:] for x in MISSPELT], ids=[x[0] for x in MISSPELT])
def test_misspelt_keyword_is_an_option_error_with_a_suggestion(call, suggestion):
    with pytest.raises(ms.OptionError, match=rf"did you mean {suggestion}") as err:
        call()
    assert isinstance(err.value, ms.ModelError)     # code catching ModelError keeps working


def test_misspelt_backend_in_the_environment(monkeypatch):
    from mechsys.compile import default_backend

    monkeypatch.setenv("MECHSYS_BACKEND", "symengin")
    with pytest.raises(ms.OptionError, match="MECHSYS_BACKEND.*did you mean 'symengine'"):
        default_backend()


@pytest.mark.parametrize("cls,kw,field", [
    (ms.PositionOptions, {"tol": 1e-9}, "ftol"),
    (ms.solvers.MultiplierOptions, {"tolerance": 1e-9}, "tol"),
])
def test_options_class_names_an_unknown_field(cls, kw, field):
    """Was a bare ``TypeError: __init__() got an unexpected keyword argument``."""
    with pytest.raises(ms.OptionError, match=rf"{cls.__name__}: unknown option.*'{field}'"):
        cls(**kw)
    with pytest.raises(ms.OptionError, match=cls.__name__):
        cls(1e-9, 5, 1.0, "extra")


@pytest.mark.parametrize("kw,culprit", [({"tol": -1.0}, "tol"), ({"max_iterations": 0}, "max_iterations"),
                                        ({"lambda_guess": "one"}, "lambda_guess")])
def test_multiplier_options_are_checked(kw, culprit):
    with pytest.raises(ms.OptionError, match=f"MultiplierOptions: {culprit}"):
        ms.solvers.MultiplierOptions(**kw)


# -- objects of another model ----------------------------------------------------------------
def caster():
    m = ms.Model2D()
    c = m.add_body("caster", points={"wheel": (0.3, 0.0)}, guess=((0, 0), 3.09))
    m.add(ms.Revolute2(c.point(0), m.ground.point((-T, 0))), name="pivot")
    m.add(ms.RotationLock1(c, 3.09), name="dummy")
    m.solve(0.0)
    return m


def test_path_refuses_a_velocity_constraint_of_another_model():
    """Another model's body 2 has the same coordinate symbols (x2, y2, th2) as this one's:
    its velocity constraint was accepted and acted on this model's body."""
    m, other = caster(), caster()
    c, oc = m.body("caster"), other.body("caster")
    foreign = ms.Orthogonal1(m.velocity(c.point("wheel")), oc.vector((0, 1)))
    with pytest.raises(ms.ModelError, match="'caster' of another model"):
        m.path({"dummy": foreign})
    with pytest.raises(ms.ModelError, match="already a constraint of another model"):
        m.path({"dummy": other.constraint("pivot")})
    with pytest.raises(ms.ModelError, match="already a constraint of this model"):
        m.path({"dummy": m.constraint("pivot")})
    assert other.constraint("pivot").name == "pivot"      # not renamed by the refused call
    # the model's own velocity constraint works: the wheel rolls without side slip
    own = ms.Orthogonal1(m.velocity(c.point("wheel")), c.vector((0, 1)))
    sol = m.path({"dummy": own}).simulate(np.linspace(0.0, 1.0, 5))
    v = sol.velocity(c.point("wheel"))
    th = sol.q[:, 2]
    side = -np.sin(th) * v[:, 0] + np.cos(th) * v[:, 1]
    np.testing.assert_allclose(side, 0.0, atol=1e-9)


@pytest.mark.parametrize("call", [
    lambda m, o: m.add(ms.RotationLock1(o.body("caster"), 0.0)),
    lambda m, o: m.add_load(ms.Force(o.body("caster").point("wheel"), (0, 1), 1.0)),
    lambda m, o: m.add_load(ms.JointFriction(o.constraint("pivot"), mu=0.1, radius=0.1)),
    lambda m, o: m.free(drop=[o.constraint("dummy")]),
    lambda m, o: m.remove(o.constraint("dummy")),
    lambda m, o: m.solve([0.0, 0.1]).location(o.body("caster").point("wheel")),
    lambda m, o: m.solve([0.0, 0.1], "static").reaction(o.constraint("pivot"), "caster"),
    lambda m, o: m.solve([0.0, 0.1], "static").reaction("pivot", o.body("caster")),
], ids=["add", "add_load", "friction", "free drop", "remove", "location", "reaction constraint",
        "reaction body"])
def test_other_entry_points_refuse_objects_of_another_model(call):
    """The places that take bodies, points, constraints or loads of a model (checked: they
    already refused; kept so)."""
    m, other = caster(), caster()
    with pytest.raises(ms.ModelError, match="another model|not in this model"):
        call(m, other)


def test_symbolic_values_are_sympy_expressions():
    """Non-numbers that are valid expressions stay accepted (a load of T)."""
    m = pend()
    tip, anchor = _tip(m)
    spring = ms.Spring(tip, anchor, 10.0 + sp.sin(T) ** 2, free_length=0.5)
    m.add_load(spring)
    assert spring.k == 10.0 + sp.sin(T) ** 2
