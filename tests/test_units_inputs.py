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
