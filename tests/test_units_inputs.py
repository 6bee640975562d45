"""pint quantities for every input (issue 38, item 3; decision 0043): converted once where they
enter the model, checked for their dimension, and giving the same mechanism in any unit
system: the slider-crank built from the same quantities in m and in mm has the same positions
(x1000) and joint torques (x1e6, kg mm^2/s^2 against N m)."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms

pint = pytest.importorskip("pint")
Q = pint.get_application_registry().Quantity


def crank_slider(length: str):
    m = ms.Model2D()
    m.set_units(length=length, mass="kg", time="s")
    cr = m.add_body("crank", points={"pin": (Q(2, "m"), Q(0, "m"))}, guess=((0, 0), 0),
                    mass=Q(1.5, "kg"), centroid=(Q(1, "m"), Q(0, "m")), inertia=Q(0.4, "kg*m**2"))
    rd = m.add_body("rod", points={"a": (0, 0), "b": (Q(6000, "mm"), 0)},
                    guess=((Q(2, "m"), 0), Q(10, "deg")), mass=Q(2000, "g"),
                    centroid=(Q(3, "m"), Q(0, "m")), inertia=Q(5, "kg*m**2"))
    pi = m.add_body("piston", guess=((Q(8, "m"), 0), 0), mass=Q(3, "kg"))
    m.add(ms.Revolute2(m.ground.point((0, 0)), cr.point(0)), name="pin")
    m.add(ms.Revolute2(cr.point("pin"), rd.point("a")))
    m.add(ms.Revolute2(rd.point("b"), pi.point(0)))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), pi.axis((0, 0), (1, 0))))
    m.add(ms.RotationLock1(cr, 2 * sp.pi * ms.T + 0.3), name="drive")
    m.add_load(ms.Gravity((0, -1), Q(9.81, "m/s**2")))
    m.add_load(ms.Force(pi.point(0), (1, 0), Q(-40, "N")))
    m.add_load(ms.Spring(m.ground.point((Q(10, "m"), 0)), pi.point(0), Q(100, "N/m"), Q(1, "m")))
    return m


def test_same_mechanism_in_metres_and_millimetres():
    m1, m2 = crank_slider("m"), crank_slider("mm")
    assert float(m2.body("rod").points["b"][0]) == 6000
    assert float(m2.body("crank").inertia) == pytest.approx(4e5)
    s1 = m1.solve(Q(np.linspace(0, 1, 7), "s"), solution="dynamic")
    s2 = m2.solve(Q(np.linspace(0, 1000, 7), "ms"), solution="dynamic")
    j = s1.names.index("piston.x")
    assert np.allclose(s2.q[:, j], 1000 * s1.q[:, j], rtol=1e-12, atol=1e-9)
    tau1, tau2 = s1.generalized("drive")[:, 0], s2.generalized("drive")[:, 0]
    assert np.allclose(tau2, 1e6 * tau1, rtol=1e-10, atol=1e-6 * np.abs(tau2).max())
    # the closed form of the piston's position (crank 2 m, rod 6 m)
    th = 2 * np.pi * s1.t + 0.3
    assert np.allclose(s1.q[:, j], 2 * np.cos(th) + np.sqrt(36 - 4 * np.sin(th) ** 2), rtol=1e-12)


def test_driver_angle_in_degrees_and_a_point_in_metres():
    m = ms.Model2D()
    m.set_units(length="mm", mass="kg", time="s")
    arm = m.add_body("arm", points={"tip": (Q(0.3, "m"), 0)}, guess=((0, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), arm.point(0)))
    m.add(ms.RotationLock1(arm, Q(30, "deg")), name="drive")
    tip = m.solve(0.0).location(arm.point("tip"))
    assert np.allclose(tip, [300 * np.cos(np.pi / 6), 300 * np.sin(np.pi / 6)], rtol=1e-12)


@pytest.mark.parametrize("make, culprit", [
    (lambda m, b: m.add_load(ms.Force(b.point(0), (1, 0), Q(5, "kg"))), "Force magnitude"),
    (lambda m, b: m.add_load(ms.Spring(b.point(0), m.ground.point((0, 0)), Q(5, "N"))),
     "Spring stiffness"),
    (lambda m, b: m.add_load(ms.Gravity((0, -1), Q(9.81, "m/s"))), "Gravity g"),
    (lambda m, b: b.point((Q(1, "kg"), 0)), "point of body 'b'"),
    (lambda m, b: m.add_body("c", mass=Q(1, "m")), "body 'c' mass"),
    (lambda m, b: m.add_body("c", inertia=Q(1, "kg*m")), "body 'c' inertia"),
    (lambda m, b: m.add(ms.RotationLock1(b, Q(1, "m"))), "RotationLock1 angle"),
    (lambda m, b: m.solve(Q(1, "m")), "solve: t"),
    (lambda m, b: m.add_body("c", points={"p": (Q(1, "A"), 0)}), "current"),
    (lambda m, b: m.add_load(ms.Spring(b.point(0), m.ground.point((0, 0)), Q(5, "N/m"),
                                       Q(-1, "m"))), "free_length"),
])
def test_a_quantity_of_the_wrong_dimension_is_refused(make, culprit):
    m = ms.Model2D()
    m.set_units(length="m", mass="kg", time="s")
    b = m.add_body("b", guess=((0, 0), 0))
    with pytest.raises(ms.ModelError, match=culprit):
        make(m, b)


def test_a_quantity_without_declared_units_is_refused():
    m = ms.Model2D()
    b = m.add_body("b", guess=((0, 0), 0))
    with pytest.raises(ms.ModelError, match="no units"):
        m.add_load(ms.Force(b.point(0), (1, 0), Q(5, "N")))
    with pytest.raises(ms.ModelError, match="no units"):
        m.add_body("c", mass=Q(1, "kg"))
    assert len(m.load_list) == 0 and [x.name for x in m.bodies] == ["ground", "b"]


def test_the_equations_hold_no_unit():
    m = crank_slider("mm")
    names = {s.name for e in m.compile().dynamics.Q for s in sp.sympify(e).free_symbols}
    assert not any("pint" in n for n in names), names


# -- vectors and initial conditions as quantities; every output in units ---------------------

def _pendulum(force, gravity, length="mm"):
    """A pendulum arm (0.3 m, 1 kg at 0.15 m) with a tip force and gravity as given."""
    m = ms.Model2D()
    m.set_units(length=length, mass="kg", time="s")
    arm = m.add_body("arm", points={"tip": (Q(0.3, "m"), 0)}, guess=((0, 0), 0), mass=Q(1, "kg"),
                     centroid=(Q(0.15, "m"), 0), inertia=Q(0.0075, "kg*m**2"))
    m.add(ms.Revolute2(m.ground.point((0, 0)), arm.point(0)), name="pin")
    m.add_load(gravity)
    m.add_load(ms.Force(arm.point("tip"), *force))
    return m, arm


def test_force_gravity_and_moment_vectors_as_quantities():
    """``Force(p, Q([fx, fy], "N"))`` is the force vector; ``Gravity(Q([0, -g], ...))`` the
    field: the same generalized forces as direction plus magnitude."""
    m1, a1 = _pendulum((Q(np.array([0.0, -40.0]), "N"),), ms.Gravity(Q(np.array([0, -9.81]), "m/s**2")))
    m2, a2 = _pendulum(((0, -1), Q(40, "N")), ms.Gravity((0, -1), Q(9.81, "m/s**2")))
    for m, a in ((m1, a1), (m2, a2)):
        m.add(ms.RotationLock1(a, 0), name="hold")
    s1, s2 = (m.solve(0.0, solution="static") for m in (m1, m2))
    # statics by hand: the holding torque balances 40 N at 0.3 m and 9.81 N at 0.15 m, in
    # kg mm^2/s^2 (N m x 1e6)
    torque = (40 * 0.3 + 9.81 * 0.15) * 1e6
    assert abs(float(np.ravel(s1.generalized("hold"))[0])) == pytest.approx(torque, rel=1e-12)
    assert np.allclose(s1.generalized("hold"), s2.generalized("hold"), rtol=1e-14)
    with pytest.raises(ms.ModelError, match="Force: give the vector as a quantity or a magnitude"):
        ms.Force((0, 0), Q(np.array([1.0, 0]), "N"), 5)
    with pytest.raises(ms.ModelError, match="Force magnitude"):     # a vector of the wrong dimension
        _pendulum((Q(np.array([0.0, -1.0]), "kg"),), ms.Gravity())
    m3 = ms.Model3D()
    m3.set_units(length="m", mass="kg", time="s")
    b = m3.add_body("b", mass=1.0)
    moment = ms.Moment(b, Q(np.array([0.0, 0, 2.0]), "N*m"))
    m3.add_load(moment)
    assert [float(x) for x in moment.moment_value(m3)] == [0, 0, 2.0]


def test_initial_conditions_take_quantities_of_their_coordinates_dimension():
    m, arm = _pendulum(((0, -1), Q(0, "N")), ms.Gravity((0, -1), Q(9.81, "m/s**2")))
    free = m.free()
    sol = free.simulate(np.array([0.0, 0.01]),
                        initial_condition={"arm.th": Q(10, "deg"), "arm.th_d": Q(60, "rpm")})
    assert sol.q[0, 2] == pytest.approx(np.pi / 18, rel=1e-12)
    assert sol.qd[0, 2] == pytest.approx(2 * np.pi, rel=1e-12)
    with pytest.raises(ms.ModelError, match=r"'arm.th_d'.*\[length\]"):
        free.simulate(np.array([0.0, 0.01]), initial_condition={"arm.th_d": Q(1, "mm/s")})


def test_every_output_in_units_agrees_between_metres_and_millimetres():
    """``sol.in_units``: the same mechanism built in m and in mm gives, converted, the same
    locations, velocities, reactions, loads, energies and momenta; an expression takes the
    dimension its caller names; what has no known dimension is refused by name."""
    ureg = pint.get_application_registry()
    t = np.linspace(0, 1, 5)
    s1 = crank_slider("m").solve(t, solution="dynamic")
    s2 = crank_slider("mm").solve(t, solution="dynamic")
    u1, u2 = s1.in_units, s2.in_units
    pin = s1.model.body("piston").point(0)
    pin2 = s2.model.body("piston").point(0)
    loc = u2.location(pin2)
    assert loc.units == ureg.mm
    # the closed form of the piston's position (crank 2 m, rod 6 m), in metres
    th = 2 * np.pi * t + 0.3
    assert np.allclose(loc.to("m").magnitude[:, 0], 2 * np.cos(th) + np.sqrt(36 - 4 * np.sin(th) ** 2),
                       rtol=1e-12)
    for name, args1, args2, unit in [
            ("velocity", (pin,), (pin2,), "m/s"), ("acceleration", (pin,), (pin2,), "m/s**2"),
            ("omega", ("rod",), ("rod",), "rad/s"), ("alpha", ("rod",), ("rod",), "rad/s**2"),
            ("angle", ("rod",), ("rod",), "deg"),
            ("body_energy", ("rod",), ("rod",), "J"), ("potential_energy", (), (), "J"),
            ("linear_momentum", (), (), "kg*m/s"), ("angular_momentum", ("rod",), ("rod",), "J*s")]:
        a = getattr(u1, name)(*args1).to(unit).magnitude
        b = getattr(u2, name)(*args2).to(unit).magnitude
        assert np.allclose(a, b, rtol=1e-9, atol=1e-9 * np.abs(a).max()), name
    (F1, M1), (F2, M2) = u1.reaction("pin", "crank"), u2.reaction("pin", "crank")
    assert F2.units == ureg.kg * ureg.mm / ureg.s ** 2
    assert np.allclose(F1.to("N").magnitude, F2.to("N").magnitude, rtol=1e-9, atol=1e-9)
    assert np.allclose(M1.to("N*m").magnitude, M2.to("N*m").magnitude, rtol=1e-9, atol=1e-9)
    L1, _ = u1.loads("piston", coordinates="global")
    L2, _ = u2.loads("piston", coordinates="global")
    assert np.allclose(L1.to("N").magnitude, L2.to("N").magnitude, rtol=1e-12, atol=1e-9)
    x = s2.model.body("piston").q[0]
    assert np.allclose(u2.eval(x, "[length]").to("m").magnitude, loc.to("m").magnitude[:, 0])
    assert u2.eval(x, "km").units == ureg.mm           # a unit names the dimension only
    assert u2.t.units == ureg.s
    with pytest.raises(ms.ModelError, match="name the expression's dimension"):
        u2.eval(x)
    with pytest.raises(ms.ModelError, match="current"):
        u2.eval(x, "[current]")
    with pytest.raises(ms.ModelError, match="instant_center"):
        u2.instant_center("rod")
    with pytest.raises(ms.ModelError, match="coordinates='global'"):
        u2.loads("piston")
    plain = ms.Model2D()
    b = plain.add_body("b", guess=((0, 0), 0))
    plain.add(ms.Revolute2(plain.ground.point((0, 0)), b.point(0)))
    plain.add(ms.RotationLock1(b, ms.T))
    with pytest.raises(ms.ModelError, match="m.set_units"):
        _ = plain.solve(0.0).in_units


def test_times_guesses_and_sweep_values_keep_their_units():
    """Quantities that NumPy would silently strip of their unit (an array of times in ms given
    to ``simulate``, an array of lengths swept) are converted instead: 100 ms is 0.1 s, 1 m is
    1000 mm; a guess takes its coordinate's dimension."""
    m, arm = _pendulum(((0, -1), Q(0, "N")), ms.Gravity((0, -1), Q(9.81, "m/s**2")))
    free = m.free()
    sol = free.simulate(Q(np.linspace(0, 100, 3), "ms"), max_step=Q(5, "ms"))
    assert np.allclose(sol.t, [0, 0.05, 0.1], rtol=0, atol=1e-15)
    assert free.simulate((Q(0, "s"), Q(20, "ms"))).t[-1] == pytest.approx(0.02, rel=1e-12)
    m.set_guess({"arm.th": Q(90, "deg")})
    assert m.guess()[2] == pytest.approx(np.pi / 2, rel=1e-12)
    with pytest.raises(ms.ModelError, match=r"set_guess 'x2'.*\[length\]"):
        m.set_guess({"arm.x": Q(1, "s")})

    s = ms.Model2D()
    s.set_units(length="mm", mass="kg", time="s")
    length = s.parameter("L", Q(0.3, "m"))
    bar = s.add_body("bar", points={"tip": (length, 0)}, guess=((0, 0), 0))
    s.add(ms.Revolute2(s.ground.point((0, 0)), bar.point(0)))
    s.add(ms.RotationLock1(bar, 0))
    tip = bar.point("tip")
    df = ms.sweep(s, {"L": Q(np.array([1.0, 2.0]), "m")}, "location",
                  outputs={"x": lambda r: r.location(tip)[0]})
    assert df["x"].tolist() == [1000.0, 2000.0]


def test_vibration_frequencies_in_units():
    """A pendulum (1 kg at 0.15 m, 0.0075 kg m^2 about its centroid) hanging down:
    omega^2 = m g c / J_O = 9.81 * 0.15 / 0.03, whether the model counts time in s or ms."""
    omegas = []
    for time in ("s", "ms"):
        m = ms.Model2D()
        m.set_units(length="mm", mass="kg", time=time)
        arm = m.add_body("arm", guess=((0, 0), -np.pi / 2), mass=Q(1, "kg"),
                         centroid=(Q(0.15, "m"), 0), inertia=Q(0.0075, "kg*m**2"))
        m.add(ms.Revolute2(m.ground.point((0, 0)), arm.point(0)))
        m.add_load(ms.Gravity((0, -1), Q(9.81, "m/s**2")))
        modes = m.vibration(at={"arm.th": -np.pi / 2})
        omega = modes.quantity("omega")
        assert modes.quantity("hz").to("1/s").magnitude == pytest.approx(
            omega.to("rad/s").magnitude / (2 * np.pi), rel=1e-12)
        omegas.append(omega.to("rad/s").magnitude[0])
    assert omegas == pytest.approx([np.sqrt(9.81 * 0.15 / 0.03)] * 2, rel=1e-9)
    with pytest.raises(ms.OptionError, match="omega"):
        modes.quantity("omegas")
