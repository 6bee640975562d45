"""Coupled systems (Mech's SetCouple/SolveCouple, manual 9.1-9.4), each checked against an
independent computation: Freudenstein's equation solved here, a linear system of precision
positions, closed-form velocities, statics and dynamics of a bar."""

import numpy as np
import pytest
import sympy as sp
from scipy.optimize import brentq

import mechsys as ms
from mechsys import T

A, B, D = 1.0, 4.0, 4.0          # crank, coupler, ground of the four-bar; rocker c is a parameter


def four_bar(c=3.0, b=None, unit=1.0):
    """Grashof crank-rocker, crank angle th2 = T; the rocker length ``c`` (and the coupler
    length ``b`` when given) are parameters."""
    m = ms.Model2D()
    cp = m.parameter("c", c * unit)
    bp = m.parameter("b", b * unit) if b is not None else B * unit
    crank = m.add_body("crank", points={"A": (A * unit, 0)}, guess=((0, 0), 0))
    coupler = m.add_body("coupler", points={"A": (0, 0), "B": (bp, 0)},
                         guess=((A * unit, 0), 0.9))
    rocker = m.add_body("rocker", points={"B": (cp, 0)}, guess=((D * unit, 0), 1.8))
    m.add(ms.Revolute2((0, 0), crank.point(0)), name="O2")
    m.add(ms.Revolute2(crank.point("A"), coupler.point("A")), name="A")
    m.add(ms.Revolute2(coupler.point("B"), rocker.point("B")), name="B")
    m.add(ms.Revolute2((D * unit, 0), rocker.point(0)), name="O4")
    m.add(ms.RotationLock1(crank, T), name="drive")
    return m, crank, coupler, rocker


def freudenstein_th4(th2, b, c):
    """Rocker angle of the open branch, closed form."""
    K1, K2, K3 = D / A, D / c, (A**2 - b**2 + c**2 + D**2) / (2 * A * c)
    P, Q, R = np.cos(th2) - K1, np.sin(th2), K2 * np.cos(th2) - K3
    return np.arctan2(Q, P) - np.arccos(-R / np.hypot(P, Q))


def freudenstein_w4(th2, b, c):
    """Rocker angular velocity for crank speed 1 (implicit differentiation)."""
    K1, K2 = D / A, D / c
    th4 = freudenstein_th4(th2, b, c)
    F2 = K2 * np.sin(th2) + np.sin(th2 - th4)
    F4 = -K1 * np.sin(th4) - np.sin(th2 - th4)
    return -F2 / F4


def test_rocker_length_for_a_rocker_angle_matches_freudenstein():
    m, crank, coupler, rocker = four_bar()
    th2, th4 = 0.8, 1.7
    cm = m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(rocker), th4)], t=th2)
    res = cm.solve()

    def F(c):  # Freudenstein's equation with the target angles, as a function of c
        K1, K2, K3 = D / A, D / c, (A**2 - B**2 + c**2 + D**2) / (2 * A * c)
        return K1 * np.cos(th4) - K2 * np.cos(th2) + K3 - np.cos(th2 - th4)

    c_exact = brentq(F, 2.0, 4.5, xtol=1e-15)
    assert res["c"] == pytest.approx(c_exact, rel=1e-11)
    assert res.configurations[0].angle(rocker) == pytest.approx(th4, abs=1e-12)
    assert res.times.tolist() == [th2]
    # the solution carries the solved parameter: the loop closes with the new rocker
    B_coupler = res.configurations[0].location(coupler.point("B"))
    B_rocker = res.configurations[0].location(rocker.point("B"))
    assert np.allclose(B_coupler, B_rocker, atol=1e-12)
    assert np.linalg.norm(B_rocker - [D, 0]) == pytest.approx(c_exact, rel=1e-11)
    # the model itself is unchanged until the user keeps the values (Mech would keep them)
    assert m.parameters["c"] == 3.0
    m.set_parameters(res.parameters)
    assert m.solve(th2).angle(rocker) == pytest.approx(th4, abs=1e-11)


def test_two_configuration_couple_matches_precision_positions():
    """Coupler and rocker lengths for two precision positions (th2_i, th4_i): Freudenstein is
    linear in K2 = d/c and K3, so the answer is a 2x2 linear solve."""
    b_true, c_true = 3.6, 3.3
    th2s = np.array([0.5, 1.5])
    th4s = freudenstein_th4(th2s, b_true, c_true)
    K1 = D / A
    M = np.column_stack((-np.cos(th2s), np.ones(2)))
    K2, K3 = np.linalg.solve(M, np.cos(th2s - th4s) - K1 * np.cos(th4s))
    c_exact = D / K2
    b_exact = np.sqrt(A**2 + c_exact**2 + D**2 - 2 * A * c_exact * K3)

    m, crank, coupler, rocker = four_bar(c=3.0, b=4.0)
    cm = m.couple(unknowns=[("b", 4.0), ("c", 3.0)], configurations=[
        ms.Configuration(sp.Eq(m.angle(rocker), th4s[0]), t=th2s[0]),
        {"conditions": [sp.Eq(m.angle(rocker), th4s[1])], "t": th2s[1]},
    ])
    assert cm.size == 2 * 9 + 2
    res = cm.solve()
    assert res["b"] == pytest.approx(b_exact, rel=1e-10)
    assert res["c"] == pytest.approx(c_exact, rel=1e-10)
    assert b_exact == pytest.approx(b_true, rel=1e-12)
    assert np.allclose(res.solution.angle(rocker), th4s, atol=1e-12)   # (K,) over configurations
    assert res.solution.location(rocker.point("B")).shape == (2, 2)
    assert len(res) == 2


def test_velocity_couple_matches_closed_form():
    """Rocker length for which the rocker turns at 0.3 rad/s at th2 = 0.8 (crank 1 rad/s)."""
    m, crank, coupler, rocker = four_bar()
    th2, w_target = 0.8, 0.3
    cm = m.couple(unknowns=["c"], conditions=sp.Eq(m.omega(rocker), w_target), t=th2)
    assert cm.solution == "velocity"               # Mech's Solution -> Automatic upgrade
    res = cm.solve()
    c_exact = brentq(lambda c: freudenstein_w4(th2, B, c) - w_target, 1.5, 4.5, xtol=1e-15)
    assert res["c"] == pytest.approx(c_exact, rel=1e-10)
    assert res.configurations[0].omega(rocker) == pytest.approx(w_target, abs=1e-12)
    assert res.configurations[0].angle(rocker) == pytest.approx(
        freudenstein_th4(th2, B, c_exact), abs=1e-11)
    # the same condition through |omega| (Abs: derived by SymPy, not SymEngine) agrees
    cm_abs = m.couple(unknowns=["c"], conditions=sp.Eq(sp.Abs(m.omega(rocker)), w_target), t=th2)
    assert cm._native_derivation == (ms.compile.available_backends()[0] == "symengine")
    assert not cm_abs._native_derivation
    assert cm_abs.solve()["c"] == pytest.approx(c_exact, rel=1e-10)


def test_acceleration_couple_matches_differentiated_closed_form():
    m, crank, coupler, rocker = four_bar()
    th2, a_target = 0.8, 0.45
    cm = m.couple(unknowns=["c"], conditions=sp.Eq(m.alpha(rocker), a_target), t=th2)
    assert cm.solution == "acceleration"
    res = cm.solve()
    c = res["c"]
    h = 1e-4  # alpha4 = d w4 / d th2 for a unit crank speed, by a central difference
    alpha = (freudenstein_w4(th2 + h, B, c) - freudenstein_w4(th2 - h, B, c)) / (2 * h)
    assert alpha == pytest.approx(a_target, abs=1e-7)
    assert res.configurations[0].alpha(rocker) == pytest.approx(a_target, abs=1e-12)


def test_time_as_unknown_matches_freudenstein():
    """Mech's Time -> Free: when does the rocker reach 1.7 rad? Alone, and together with the
    rocker length and a second condition."""
    m, crank, coupler, rocker = four_bar()
    cm = m.couple(unknowns=[], conditions=sp.Eq(m.angle(rocker), 1.7), t=ms.Free(0.8))
    res = cm.solve()
    t_exact = brentq(lambda th2: freudenstein_th4(th2, B, 3.0) - 1.7, 0.3, 1.5, xtol=1e-15)
    assert res["T"] == pytest.approx(t_exact, abs=1e-11)
    # rocker length and time: rocker at 1.7 and coupler angle at 0.2 at the same instant
    cm2 = m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(rocker), 1.7),
                                               sp.Eq(m.angle(coupler), 0.2)], t=ms.Free(0.8))
    r2 = cm2.solve()
    th2, c = r2["T"], r2["c"]
    assert freudenstein_th4(th2, B, c) == pytest.approx(1.7, abs=1e-11)
    # the coupler angle closes the loop: A + b e(th3) = (D, 0) + c e(th4)
    Bx = A * np.cos(th2) + B * np.cos(0.2) - D - c * np.cos(1.7)
    By = A * np.sin(th2) + B * np.sin(0.2) - c * np.sin(1.7)
    assert abs(Bx) < 1e-11 and abs(By) < 1e-11


def test_resolve_at_new_time_and_from_previous_result():
    """Mech's InitialCondition -> {Time -> t}: the same CoupleSystem at another time equals a
    couple built there; a previous result is a valid start."""
    m, crank, coupler, rocker = four_bar()
    cm = m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(rocker), 1.7)], t=0.8)
    r1 = cm.solve(t=0.9)
    fresh = m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(rocker), 1.7)], t=0.9).solve()
    assert r1["c"] == pytest.approx(fresh["c"], rel=1e-12)
    assert r1.times.tolist() == [0.9]
    warm = cm.solve(guess=r1)            # starts at the answer: one Newton step
    assert warm["c"] == pytest.approx(r1["c"], rel=1e-13) and warm.iterations == 1
    with pytest.raises(ms.ModelError, match="one time per configuration"):
        cm.solve(t=[0.8, 0.9])


def test_conditions_may_take_up_the_model_freedom():
    """Without its driver the four-bar has one DOF; a condition on the crank angle takes it
    up (as the driver did), so two conditions fix the rocker length."""
    m, crank, coupler, rocker = four_bar()
    m.remove("drive")
    res = m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(crank), 0.8),
                                               sp.Eq(m.angle(rocker), 1.7)]).solve()
    driven, *_ = four_bar()
    ref = driven.couple(unknowns=["c"], conditions=sp.Eq(driven.angle("rocker"), 1.7), t=0.8)
    assert res["c"] == pytest.approx(ref.solve()["c"], rel=1e-12)
    with pytest.raises(ms.ConstraintCountError, match=r"plus the 1 freedom\(s\) the model leaves"):
        m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(rocker), 1.7)])


def test_couple_is_unit_free():
    """The same four-bar in metres and in millimetres: the same answer (scaled) in the same
    number of iterations."""
    res = []
    for unit in (1.0, 1000.0):
        m, crank, coupler, rocker = four_bar(unit=unit)
        cm = m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(rocker), 1.7)], t=0.8)
        res.append(cm.solve())
    assert res[1]["c"] == pytest.approx(1000 * res[0]["c"], rel=1e-12)
    assert res[0].iterations == res[1].iterations
    assert res[0].history == pytest.approx(res[1].history, rel=1e-6, abs=1e-14)


def bar_model(dynamic=False):
    """A uniform bar of length L (parameter), mass 2, pinned at the origin, in gravity; the
    drive holds it at 30 degrees (static) or turns it with th = pi/6 + T^2/2 (dynamic)."""
    m = ms.Model2D()
    L = m.parameter("L", 1.0)
    mass = 2.0
    bar = m.add_body("bar", points={"tip": (L, 0)}, mass=mass, centroid=(L / 2, 0),
                     inertia=mass * L**2 / 12, guess=((0, 0), 0.5))
    m.add(ms.Revolute2((0, 0), bar.point(0)), name="pin")
    drive = sp.pi / 6 + (T**2 / 2 if dynamic else 0)
    m.add(ms.RotationLock1(bar, drive), name="drive")
    m.add_load(ms.Gravity((0, -9.81)))
    return m, bar, mass


def test_load_dependent_couples_static_and_dynamic():
    """Bar length for which the drive must apply a moment of 5: statics
    M = m g (L/2) cos(th); inverse dynamics at th = pi/6, alpha = 1, omega = 0:
    M = m g (L/2) cos(th) + (m L^2 / 3) alpha, a quadratic in L."""
    g, M0, th = 9.81, 5.0, np.pi / 6
    m, bar, mass = bar_model()
    moment = m.reaction("drive", bar)[1]
    cm = m.couple(unknowns=["L"], conditions=sp.Eq(moment, M0))
    assert cm.solution == "static"
    res = cm.solve()
    assert res["L"] == pytest.approx(2 * M0 / (mass * g * np.cos(th)), rel=1e-11)
    assert res.configurations[0].reaction("drive", bar)[1] == pytest.approx(M0, rel=1e-11)

    m, bar, mass = bar_model(dynamic=True)
    moment = m.reaction("drive", bar)[1]
    with pytest.raises(ms.ModelError, match="multipliers"):
        m.couple(unknowns=["L"], conditions=sp.Eq(moment, M0), t=0.0, solution="acceleration")
    cm = m.couple(unknowns=["L"], conditions=sp.Eq(moment, M0), t=0.0, solution="dynamic")
    res = cm.solve()
    a2, a1 = mass / 3, mass * g * np.cos(th) / 2
    L_exact = (-a1 + np.sqrt(a1**2 + 4 * a2 * M0)) / (2 * a2)
    assert res["L"] == pytest.approx(L_exact, rel=1e-11)
    sol = res.configurations[0]
    assert sol.alpha(bar) == pytest.approx(1.0, abs=1e-12)
    # the static couple of the same condition gives a longer bar: inertia helps the drive
    static = m.couple(unknowns=["L"], conditions=sp.Eq(moment, M0), t=0.0).solve()
    assert static["L"] > res["L"]


def test_bad_input_is_a_clear_error():
    m, crank, coupler, rocker = four_bar(c=3.0, b=4.0)
    m.parameter("k", 1.0)                        # declared, used nowhere
    cond = sp.Eq(m.angle(rocker), 1.7)
    with pytest.raises(ms.ConstraintCountError,
                       match=r"2 unknown\(s\) \(2 parameter\(s\) \('b', 'c'\)\) but 1 condition"):
        m.couple(unknowns=["b", "c"], conditions=[cond], t=0.8)
    with pytest.raises(ms.ConstraintCountError, match=r"drop 1 condition"):
        m.couple(unknowns=["c"], conditions=[cond, sp.Eq(m.angle(coupler), 0.1)], t=0.8)
    with pytest.raises(ms.ModelError, match="parameter 'k' is not used"):
        m.couple(unknowns=["k"], conditions=[cond], t=0.8)
    with pytest.raises(ms.ModelError, match="'zz' is not a parameter"):
        m.couple(unknowns=["zz"], conditions=[cond], t=0.8)
    with pytest.raises(ms.ModelError, match="'rocker.th' is a coordinate"):
        m.couple(unknowns=["rocker.th"], conditions=[cond], t=0.8)
    with pytest.raises(ms.ModelError, match="depends on time"):
        m.couple(unknowns=["c"], configurations=[ms.Configuration(cond), ms.Configuration(cond)])
    with pytest.raises(ms.ModelError, match=r"uses \['w'\]"):
        m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(rocker), sp.Symbol("w"))], t=0.8)
    with pytest.raises(ms.ModelError, match="velocities"):
        m.couple(unknowns=["c"], conditions=sp.Eq(m.omega(rocker), 0.3), t=0.8,
                 solution="location")
    # singular: the crank angle is driven, no rocker length changes it
    cm = m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(crank), 0.8)], t=0.8)
    with pytest.raises(ms.SingularJacobianError,
                       match=r"(?s)do not determine parameter 'c'.*condition 1"):
        cm.solve()
    # a condition that cannot be met: B stays within a + b = 5 of the origin; Newton says so
    cm = m.couple(unknowns=["c"], conditions=[sp.Eq(m.distance((0, 0), rocker.point("B")), 100)],
                  t=0.8)
    with pytest.raises((ms.ConvergenceError, ms.SingularJacobianError)):
        cm.solve(options={"max_iterations": 15})


def test_spatial_couple_matches_closed_form():
    """Spatial slider-crank (Euler parameters): the rod length that puts the piston at x = 7
    at crank angle 2 pi 0.1 is sqrt((x - r cos th)^2 + (r sin th)^2)."""
    z, r = (0, 0, 1), 2.0
    m = ms.Model3D()
    L = m.parameter("L", 6.0)
    crank = m.add_body("crank", points={"pin": (r, 0, 0)})
    rod = m.add_body("rod", points={"a": (0, 0, 0), "b": (L, 0, 0)},
                     guess=((r, 0, 0), (1, 0, 0, 0)))
    piston = m.add_body("piston", guess=((r + 6, 0, 0), (1, 0, 0, 0)))
    m.add(ms.Revolute5(crank.axis(0, z), m.ground.axis((0, 0, 0), z)))
    m.add(ms.Spherical3(crank.point("pin"), rod.point("a")))
    m.add(ms.Universal4(rod.axis("b", (0, 1, 0)), piston.axis(0, z)))
    m.add(ms.Translate5(piston.axis(0, (1, 0, 0)), m.ground.axis((0, 0, 0), (1, 0, 0))))
    m.add(ms.RotationLock1(crank.axis(0, z), m.ground.axis((0, 0, 0), z), 2 * sp.pi * T))
    res = m.couple(unknowns=["L"], conditions=sp.Eq(m.location(piston.point(0))[0], 7.0),
                   t=0.1).solve()
    th = 2 * np.pi * 0.1
    assert res["L"] == pytest.approx(np.hypot(7.0 - r * np.cos(th), r * np.sin(th)), rel=1e-12)
