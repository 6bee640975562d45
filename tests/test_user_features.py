"""Features users looked for at once (issue 17): torsion springs and dampers, momentum
outputs, linkage metrics, tabulated drivers, Model.copy / remove_body, units."""

from __future__ import annotations

import numpy as np
import pytest

import mechsys as ms

# -- torsion springs and dampers ----------------------------------------------------------


def torsion_pendulum(k=30.0, phi0=0.4, mass=2.0, L=0.7, J=0.05, g=9.81):
    m = ms.Model2D()
    arm = m.add_body("arm", mass=mass, centroid=(L, 0), inertia=J, guess=((0, 0), 0.0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), arm.point(0)))
    m.add_load(ms.TorsionSpring(m.ground, arm, k, free_angle=phi0))
    if g:
        m.add_load(ms.Gravity((0, -1), g))
    return m


def test_torsion_spring_closes_the_energy_balance_of_a_free_pendulum():
    m = torsion_pendulum()
    sol = m.free().simulate(np.linspace(0, 2.0, 41), initial_condition={"arm.th_d": 3.0},
                            rtol=1e-11, atol=1e-12)
    E = sol.body_energy() + sol.potential_energy()
    # the torsion spring's energy is part of potential_energy: without it E is not constant
    spring = m.load_list[0]
    Vs = sol.eval(spring.potential(m))
    th = sol.coordinate("arm.th")
    assert Vs == pytest.approx(30.0 * (th - 0.4) ** 2 / 2, rel=1e-12)
    assert np.ptp(E) < 1e-8 * np.abs(E).max()
    assert np.ptp(E - Vs) > 1.0


def test_torsion_spring_static_equilibrium_closed_form():
    # 2D: a constant moment M against the spring: theta = phi0 + M / k
    m = torsion_pendulum(g=0)
    m.add_load(ms.Moment("arm", 6.0))
    eq = m.free(solution="static").solve()
    assert float(eq.coordinate("arm.th")) == pytest.approx(0.4 + 6.0 / 30.0, rel=1e-12)
    # with gravity: k (theta - phi0) = -m g L cos(theta), solved independently
    from scipy.optimize import brentq

    m = torsion_pendulum()
    eq = m.free(solution="static").solve()
    th = brentq(lambda x: 30.0 * (x - 0.4) + 2.0 * 9.81 * 0.7 * np.cos(x), -np.pi / 2, 0.4)
    assert float(eq.coordinate("arm.th")) == pytest.approx(th, rel=1e-11)
    with pytest.raises(ms.ModelError, match="needs the motion's velocities"):
        eq.mechanical_advantage("arm", "arm")


def test_torsion_spring_3d_about_a_revolute_axis():
    k, phi0, M = 12.0, 0.2, 3.0
    m = ms.Model3D()
    w = m.add_body("wheel", mass=1.0, inertia=(0.1, 0.1, 0.2, 0, 0, 0))
    ga = m.ground.axis((0, 0, 0), (0, 0, 1), (1, 0, 0))
    wa = w.axis((0, 0, 0), (0, 0, 1), (1, 0, 0))
    m.add(ms.Revolute5(wa, ga))
    m.add_load(ms.TorsionSpring(ga, wa, k, free_angle=phi0))
    m.add_load(ms.Moment(w, (0, 0, 1), M))
    eq = m.free(solution="static").solve()
    e = eq.q[0, 3:7]
    angle = 2 * np.arctan2(e[3], e[0])
    assert angle == pytest.approx(phi0 + M / k, rel=1e-10)
    # the same spring as a torsional oscillator: w = sqrt(k / Jz)
    m.remove_load(m.load_list[1])
    modes = m.vibration(at={"wheel.e0": np.cos(phi0 / 2), "wheel.e3": np.sin(phi0 / 2)})
    assert modes.omega == pytest.approx([np.sqrt(k / 0.2)], rel=1e-9)


def test_torsion_damper_damping_ratio():
    k, c, J = 40.0, 0.6, 0.08
    m = ms.Model2D()
    disk = m.add_body("disk", inertia=J, mass=1.0)
    m.add(ms.Revolute2(m.ground.point((0, 0)), disk.point(0)))
    m.add_load(ms.TorsionSpring(m.ground, disk, k))
    m.add_load(ms.TorsionDamper(m.ground, disk, c))
    modes = m.vibration(at=m.guess())
    assert modes.omega[0] == pytest.approx(np.sqrt(k / J), rel=1e-9)
    assert modes.damping_ratio[0] == pytest.approx(c / (2 * np.sqrt(k * J)), rel=1e-9)
    # the damper's torque on the disk: -c theta_dot
    damper = m.load_list[1]
    Q = damper.contributions(m)
    assert len(Q) == 1 and Q[0].magnitude.equals(-c * m.velocity_symbols()[disk.q[2]])


def test_torsion_errors():
    m = ms.Model2D()
    a = m.add_body("a")
    with pytest.raises(ms.ModelError, match="two bodies"):
        ms.TorsionSpring(a, a.axis((0, 0), (1, 0)), 1.0)
    with pytest.raises(ms.ModelError, match="both ends"):
        m.add_load(ms.TorsionSpring(a, "a", 1.0))
    with pytest.raises(ms.ModelError, match="stiffness"):
        ms.TorsionSpring(a, m.ground, "x + ")
    m3 = ms.Model3D()
    b = m3.add_body("b")
    with pytest.raises(ms.ModelError, match="in 3D give two axes"):
        m3.add_load(ms.TorsionSpring(m3.ground, b, 1.0))


# -- momentum ----------------------------------------------------------------------------


def test_momentum_conserved_in_torque_free_3d_body():
    """A free asymmetric body (no constraints, no loads), centroid off the body origin,
    tumbling about a non-principal axis: p, H about the centre of mass and H about a fixed
    point stay constant to the integration tolerance."""
    m = ms.Model3D()
    b = m.add_body("b", mass=2.5, centroid=(0.3, -0.2, 0.1), inertia=(0.4, 0.7, 0.9, 0.05, 0, 0.02))
    free = m.free()
    cond = {("omega", "b"): (1.5, -2.0, 3.0), "b.x_d": 0.4, "b.y_d": -0.3, "b.z_d": 0.2}
    sol = free.simulate(np.linspace(0, 3.0, 31), initial_condition=cond, rtol=1e-11, atol=1e-12)
    p = sol.linear_momentum()
    H = sol.angular_momentum()
    HO = sol.angular_momentum(about=(1.0, 2.0, -0.5))
    assert p.shape == (31, 3) and H.shape == (31, 3)
    for X in (p, H, HO):
        assert np.abs(X - X[0]).max() < 1e-8 * np.abs(X[0]).max()
    # the body really tumbles: its angular velocity changes a lot
    w = sol.omega(b)
    assert np.abs(w - w[0]).max() > 0.5
    # linear momentum is m times the centroid velocity; H_O = H_G + (r_G - r_O) x p
    vc = sol.velocity(b.point((0.3, -0.2, 0.1)))
    assert p == pytest.approx(2.5 * vc, rel=1e-12, abs=1e-12)
    rG = sol.centre_of_mass()
    assert HO == pytest.approx(H + np.cross(rG - np.array([1.0, 2.0, -0.5]), p), rel=1e-10)


def test_momentum_2d_pendulum_and_symbolic_forms():
    mass, L, J = 2.0, 0.7, 0.05
    m = torsion_pendulum(mass=mass, L=L, J=J)
    arm = m.body("arm")
    sol = m.free().simulate(np.linspace(0, 1.0, 11), initial_condition={"arm.th_d": 2.0})
    th, thd = sol.coordinate("arm.th"), sol.coordinate("arm.th", 1)
    # about the fixed pivot: (m L^2 + J) theta_dot; about the centroid: J theta_dot
    pivot = m.ground.point((0, 0))
    assert sol.angular_momentum(arm, about=pivot) == pytest.approx((mass * L**2 + J) * thd, rel=1e-12)
    assert sol.angular_momentum(arm) == pytest.approx(J * thd, rel=1e-12)
    p = sol.linear_momentum([arm])
    assert p == pytest.approx(mass * L * thd[:, None] * np.c_[-np.sin(th), np.cos(th)], rel=1e-12)
    # symbolic on the model
    import sympy as sp

    vs = m.velocity_symbols()
    x, y = arm.q[0], arm.q[1]
    H = m.angular_momentum(arm, about=pivot).subs({x: 0, y: 0, vs[x]: 0, vs[y]: 0})
    assert float(sp.simplify(H / vs[arm.q[2]])) == pytest.approx(mass * L**2 + J, rel=1e-14)
    mm = ms.Model2D()
    mm.add_body("ghost")
    with pytest.raises(ms.ModelError, match="no mass"):
        mm.centre_of_mass()


# -- linkage metrics ----------------------------------------------------------------------


def test_four_bar_transmission_angle_and_mechanical_advantage():
    from mechsys import models

    a, b, c, d = 1.0, 4.0, 3.0, 4.0
    m = models.four_bar(ground=d, crank=a, coupler=b, rocker=c)
    cr, ro = m.body("crank"), m.body("rocker")
    sol = m.solve(np.linspace(0, 2 * np.pi, 25))
    th2 = sol.coordinate("crank.th")
    th4 = sol.coordinate("rocker.th")
    B, C = sol.location(cr.point("tip")), sol.location(ro.point("tip"))
    th3 = np.arctan2(C[:, 1] - B[:, 1], C[:, 0] - B[:, 0])
    mu = sol.transmission_angle(ms.Vector(ro.point("tip"), cr.point("tip")),
                                ms.Vector(ro.point("tip"), m.ground.point((d, 0))))
    cos_mu = (b**2 + c**2 - a**2 - d**2 + 2 * a * d * np.cos(th2)) / (2 * b * c)
    assert mu == pytest.approx(np.arccos(cos_mu), rel=1e-10)
    # torque ratio T_rocker / T_crank = w2 / w4 = c sin(th4 - th3) / (a sin(th2 - th3))
    ma = sol.mechanical_advantage(cr, ro)
    assert ma == pytest.approx(c * np.sin(th4 - th3) / (a * np.sin(th2 - th3)), rel=1e-9)


def test_slider_crank_transmission_angle_and_mechanical_advantage():
    from mechsys import models

    r, L = 2.0, 6.0
    m = models.slider_crank(crank=r, rod=L)
    cr, rod, piston = m.body("crank"), m.body("rod"), m.body("piston")
    t = np.linspace(0.01, 0.49, 13)          # away from the dead centres
    sol = m.solve(t)
    th = sol.coordinate("crank.th")
    mu = sol.transmission_angle(rod.vector((1, 0)), piston.vector((0, 1)))
    phi = np.arcsin(r * np.sin(th) / L)       # rod angle to the path
    # the normal's sense is arbitrary: mu = 90 deg +- phi, the deviation from 90 deg is |phi|
    assert np.abs(np.pi / 2 - mu) == pytest.approx(np.abs(phi), rel=1e-10)
    # force on the piston per crank torque: w / v_piston (closed form of the velocity)
    x = m.location(piston.point(0))[0]
    ma = sol.mechanical_advantage(cr, x)
    v_over_w = -r * np.sin(th) * (1 + r * np.cos(th) / np.sqrt(L**2 - r**2 * np.sin(th) ** 2))
    assert ma == pytest.approx(1 / v_over_w, rel=1e-9)
    # virtual work, an independent check: with a force F on the piston (massless links), the
    # statics driver torque is F / MA (the driver's reaction on the crank is its negative)
    F = 50.0
    ms_ = models.slider_crank_dynamic(crank=r, rod=L, masses=(0, 0, 0), inertias=(0, 0, 0), g=0,
                                      piston_force=F)
    st = ms_.solve(t, solution="static")
    ma_static = st.mechanical_advantage("crank", ms_.location(ms_.body("piston").point(0))[0])
    assert ma_static == pytest.approx(ma, rel=1e-9)
    torque = st.reaction("drive", "crank")[1]
    assert torque == pytest.approx(-F / ma_static, rel=1e-9)
    with pytest.raises(ms.ModelError, match="ground does not move"):
        sol.mechanical_advantage(m.ground, cr)
    with pytest.raises(ms.ModelError, match="no body named"):
        sol.mechanical_advantage("no such", cr)
    with pytest.raises(ms.ModelError, match="scalar expression"):
        sol.mechanical_advantage(cr, m.location(piston.point(0)))


# -- tabulated drivers --------------------------------------------------------------------


def test_tabulated_driver_reproduces_the_table_with_consistent_derivatives():
    t_tab = np.array([0.0, 0.3, 0.7, 1.0, 1.6, 2.0])
    x_tab = np.array([1.0, 1.4, 2.5, 2.6, 2.0, 2.2])
    m = ms.Model2D()
    s = m.add_body("slider", guess=((1.0, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), s.axis((0, 0), (1, 0))))
    m.add(ms.RelativeX1(s.point(0), ms.tabulated(t_tab, x_tab)), name="measured")
    # at the knots the slider is where the table says
    sol = m.solve(t_tab)
    assert sol.coordinate("slider.x") == pytest.approx(x_tab, rel=1e-12, abs=1e-12)
    # between them its velocity and acceleration are the spline's analytic derivatives
    spline = ms.SplineFit(x_tab, knots=t_tab)
    t = np.linspace(0.05, 1.95, 23)
    sol = m.solve(t)
    assert sol.coordinate("slider.x") == pytest.approx(spline(t), rel=1e-12)
    assert sol.coordinate("slider.x", 1) == pytest.approx(spline.derivative(t, 1), rel=1e-10,
                                                          abs=1e-12)
    assert sol.coordinate("slider.x", 2) == pytest.approx(spline.derivative(t, 2), rel=1e-10,
                                                          abs=1e-12)
    # and consistent with each other: finite differences of the solved positions
    h = 1e-5
    tc = np.array([0.5, 1.3])
    qp, qm = m.solve(tc + h).coordinate("slider.x"), m.solve(tc - h).coordinate("slider.x")
    assert (qp - qm) / (2 * h) == pytest.approx(m.solve(tc).coordinate("slider.x", 1), rel=1e-7)


def test_tabulated_clamped_ends_and_errors():
    t_tab, y_tab = [0, 1, 2, 3], [0.0, 0.5, 0.4, 1.0]
    expr = ms.tabulated(t_tab, y_tab, end_conditions=(0.2, -0.1))
    import sympy as sp

    d = sp.diff(expr, ms.T)
    assert float(d.subs(ms.T, 0)) == pytest.approx(0.2, rel=1e-12)
    assert float(d.subs(ms.T, 3)) == pytest.approx(-0.1, rel=1e-12)
    with pytest.raises(ms.ModelError, match="equal length"):
        ms.tabulated([0, 1, 2], [1, 2])
    with pytest.raises(ms.ModelError, match="strictly increasing"):
        ms.tabulated([0, 2, 1], [1, 2, 3])
    with pytest.raises(ms.ModelError, match="end_conditions"):
        ms.tabulated([0, 1, 2], [1, 2, 3], end_conditions="sticky")


# -- Model.copy and remove_body --------------------------------------------------------------


def test_model_copy_is_independent_and_solves_identically():
    from mechsys import models

    m = models.slider_crank_dynamic(piston_force=50.0)
    m.set_guess({"rod.th": -0.05})
    ref = m.solve(np.linspace(0, 0.5, 6), solution="dynamic")
    c = m.copy()
    assert c is not m and c.bodies[1] is not m.bodies[1]
    assert all(b.model is c for b in c.bodies)
    assert all(k.model is c for k in c.constraints) and all(ld.model is c for ld in c.load_list)
    sol = c.solve(np.linspace(0, 0.5, 6), solution="dynamic")
    assert sol.q == pytest.approx(ref.q, rel=1e-13, abs=1e-13)
    assert sol.lam == pytest.approx(ref.lam, rel=1e-12, abs=1e-12)
    # edits of the copy leave the original alone
    c.set_mass_properties("rod", mass=10.0)
    c.remove("drive")
    c.add_body("extra")
    assert m.body("rod").mass == 2.0 and len(m.constraints) == 5 and len(m.bodies) == 4
    again = m.solve(np.linspace(0, 0.5, 6), solution="dynamic")
    assert again.lam == pytest.approx(ref.lam, rel=1e-12, abs=1e-12)
    # a body handle of the original does not address the copy
    with pytest.raises(ms.ModelError, match="another model"):
        c.body(m.body("rod"))


def test_model_copy_carries_attached_graphics():
    from mechsys import draw, models
    from mechsys.draw._scene import attached

    m = models.slider_crank()
    m.add_graphics(draw.Bar(m.body("rod"), ("a", "b")))
    c = m.copy()
    (bar,) = attached(c)
    assert bar.body is c.body("rod") and bar.body is not m.body("rod")


def test_remove_body_refuses_while_used_then_cascades():
    from mechsys import models

    m = models.slider_crank()
    with pytest.raises(ms.ModelError, match=r"used by .*wrist pin.*slider.*cascade=True"):
        m.remove_body("piston")
    with pytest.raises(ms.ModelError, match="ground"):
        m.remove_body(1)
    removed = m.remove_body("piston", cascade=True)
    assert removed.model is None
    assert [c.name for c in m.constraints] == ["crank pin", "crank-rod", "drive"]
    assert [b.name for b in m.bodies] == ["ground", "crank", "rod"]
    # numbers and symbols of the others stay; a new body takes a fresh number
    assert m.body(3).name == "rod" and str(m.body("rod").q[0]) == "x3"
    with pytest.raises(ms.UnknownBodyError, match="no body number 4"):
        m.body(4)
    new = m.add_body("slider2", guess=((8, 0), 0))
    assert new.number == 5 and str(new.q[0]) == "x5"
    m.add(ms.Revolute2(m.body("rod").point("b"), new.point(0)))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), new.axis((0, 0), (1, 0))))
    ref = models.slider_crank().solve(np.linspace(0, 1, 5))
    sol = m.solve(np.linspace(0, 1, 5))
    assert sol.location(new.point(0)) == pytest.approx(
        ref.location(ref.model.body("piston").point(0)), rel=1e-12, abs=1e-12)
    # a load on a removed body goes with it
    m2 = models.slider_crank_dynamic(piston_force=5.0)
    m2.remove_body("piston", cascade=True)
    assert [ld.name for ld in m2.load_list] == ["load1"]


# -- units --------------------------------------------------------------------------------


def test_pint_quantities_converted_to_the_declared_units():
    pint = pytest.importorskip("pint")
    ureg = pint.get_application_registry()
    m = ms.Model2D()
    m.set_units(length="mm", mass="kg", time="s")
    L = m.parameter("L", 0.15 * ureg.m)
    g = m.parameter("g", 9.81 * ureg.m / ureg.s**2)
    assert m.parameters == {"L": pytest.approx(150.0), "g": pytest.approx(9810.0)}
    assert m.to_units(20 * ureg.N) == pytest.approx(20000.0)          # kg mm / s^2
    assert m.to_units(2 * ureg.N * ureg.m) == pytest.approx(2e6)        # moment: kg mm^2 / s^2
    assert m.to_units(30 * ureg.deg) == pytest.approx(np.pi / 6)
    assert m.to_units(3.0) == 3.0                                       # plain numbers pass
    m.set_parameters(L=20 * ureg.cm)
    assert m.parameters["L"] == pytest.approx(200.0)
    # the physics does not depend on the system: a pendulum in mm and in m
    freqs = []
    for length, gval in ((L, g), (0.2, 9.81)):
        mm = m if length is L else ms.Model2D()
        b = mm.add_body("bob", mass=1.0, centroid=(length, 0), inertia=0, guess=((0, 0), -np.pi / 2))
        mm.add(ms.Revolute2(mm.ground.point((0, 0)), b.point(0)))
        mm.add_load(ms.Gravity((0, -1), gval))
        freqs.append(mm.vibration(at=mm.guess()).omega[0])
    assert freqs[0] == pytest.approx(freqs[1], rel=1e-12)
    assert freqs[1] == pytest.approx(np.sqrt(9.81 / 0.2), rel=1e-12)


def test_units_errors():
    pint = pytest.importorskip("pint")
    ureg = pint.get_application_registry()
    m = ms.Model2D()
    with pytest.raises(ms.ModelError, match="set_units"):
        m.parameter("L", 1 * ureg.m)
    with pytest.raises(ms.ModelError, match="not a length unit"):
        m.set_units(length="kg")
    with pytest.raises(ms.ModelError, match="not a unit pint knows"):
        m.set_units(length="furlongzz")
    with pytest.raises(ms.ModelError, match="at least one"):
        m.set_units()
    m.set_units(length="m")
    with pytest.raises(ms.ModelError, match="needs a mass unit"):
        m.to_units(1 * ureg.kg)
    with pytest.raises(ms.ModelError, match="dimension"):
        m.to_units(1 * ureg.ampere)
