"""State-space linearisation of free systems (``free.linearize``) against closed forms: simple
and double pendulum, the inverted pendulum on a cart (force, named-load and driver inputs),
a constrained model against its minimal (generalized-coordinate) twin, millimetres against
metres, a sleeping top about its steady spin, and the named errors of a state that is not
steady."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal as ss
import sympy as sp

import mechsys as ms
from mechsys import T

G = 9.81


def ordered(s):
    """Eigenvalues in a fixed order (by imaginary, then real part, each rounded: the real
    parts of undamped pairs are rounding, which np.sort_complex would sort by)."""
    s = np.asarray(s, dtype=complex)
    return s[np.lexsort((np.round(s.real, 6), np.round(s.imag, 6)))]


def pendulum(c=0.8, mass=1.4, inertia=0.05):
    m = ms.Model2D()
    b = m.add_body("b", mass=mass, centroid=(c, 0), inertia=inertia,
                   guess=((0, 0), -np.pi / 2))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)))
    m.add_load(ms.Gravity((0, -1), G))
    return m


def test_simple_pendulum_closed_form():
    c, mass, inertia = 0.8, 1.4, 0.05
    lin = pendulum(c, mass, inertia).free().linearize(outputs=["b.th", "b.th_d"])
    w2 = mass * G * c / (inertia + mass * c * c)  # about the pivot
    assert lin.states == ("b.th", "b.th_d") and lin.coordinates == ("b.th",)
    assert lin.A == pytest.approx(np.array([[0, 1], [-w2, 0]]), rel=1e-12, abs=1e-12)
    assert lin.C == pytest.approx(np.eye(2), abs=1e-15) and lin.B.shape == (2, 0)
    assert np.sort(lin.eigenvalues.imag) == pytest.approx([-np.sqrt(w2), np.sqrt(w2)],
                                                          rel=1e-12)
    assert lin.stability == ("neutral", "neutral") and lin.stable


def double_pendulum(m1=1.3, m2=0.7, l1=1.1, l2=0.8, scale=1.0):
    l1, l2 = l1 * scale, l2 * scale
    m = ms.Model2D()
    a = m.add_body("a", points={"tip": (l1, 0)}, mass=m1, centroid=(l1, 0), inertia=0,
                   guess=((0, 0), -np.pi / 2 + 0.05))
    b = m.add_body("b", mass=m2, centroid=(l2, 0), inertia=0,
                   guess=((0.05, -l1), -np.pi / 2 + 0.1))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)))
    m.add(ms.Revolute2(a.point("tip"), b.point(0)))
    m.add_load(ms.Gravity((0, -1), G * scale))
    return m


def double_pendulum_A(m1=1.3, m2=0.7, l1=1.1, l2=0.8):
    # Lagrange, small angles from the vertical: M th'' + K th = 0
    M = np.array([[(m1 + m2) * l1**2, m2 * l1 * l2], [m2 * l1 * l2, m2 * l2**2]])
    K = np.diag([(m1 + m2) * G * l1, m2 * G * l2])
    return np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, K), np.zeros((2, 2))]])


@pytest.mark.parametrize("scale", [1.0, 1000.0])
def test_double_pendulum_closed_form_and_units(scale):
    m = double_pendulum(scale=scale)
    eq = m.free(solution="static").solve()
    free = m.free()
    lin = free.linearize(eq, coordinates=["a.th", "b.th"])
    A = double_pendulum_A()
    # angles: the same A in metres and in millimetres (g scaled with the lengths)
    assert lin.A == pytest.approx(A, rel=1e-10, abs=1e-10)
    ref = ordered(np.linalg.eigvals(A))
    assert ordered(lin.eigenvalues) == pytest.approx(ref, rel=1e-10)
    # the computed minimal set: QR picks the same coordinates in any unit, same eigenvalues
    auto = free.linearize(eq)
    assert len(auto.coordinates) == 2
    assert ordered(auto.eigenvalues) == pytest.approx(ref, rel=1e-9)
    assert auto.stable and set(auto.stability) == {"neutral"}


def test_constrained_model_matches_its_minimal_twin():
    """Absolute coordinates with revolute joints (6 coordinates, 4 constraints) against the
    generalized-coordinate chain (2 coordinates, no constraints)."""
    m1, m2, l1, l2 = 1.3, 0.7, 1.1, 0.8
    g = ms.Model2D()
    up = g.add_body("up", points={"e": (l1, 0)}, mass=m1, centroid=(l1, 0), inertia=0)
    lo = g.add_body("lo", mass=m2, centroid=(l2, 0), inertia=0)
    g.add(ms.GenRevolute2(up.axis(0), g.ground.axis((0, 0)), ("q1", -np.pi / 2)))
    g.add(ms.GenRevolute2(lo.axis(0), up.axis("e"), ("q2", 0.0)))
    g.add_load(ms.Gravity((0, -1), G))
    minimal = g.free().linearize()
    assert minimal.coordinates == ("q1", "q2")
    # vibration accepts this equilibrium too (its steadiness test once compared the
    # rounding of the accelerations with the zero forces acting in minimal coordinates)
    modes = g.vibration(at=g.guess())
    assert modes.omega == pytest.approx(np.sort(np.abs(minimal.eigenvalues.imag))[::2],
                                        rel=1e-10)
    full = double_pendulum().free()
    absolute = full.linearize(full.model.free(solution="static").solve())
    assert ordered(minimal.eigenvalues) == pytest.approx(
        ordered(absolute.eigenvalues), rel=1e-10)
    # relative angle q2 = b.th - a.th as an expression coordinate gives the minimal A exactly
    a, b = full.model.body("a"), full.model.body("b")
    rel = full.linearize(absolute_state(full), coordinates=[a.q[2], ("q2", b.q[2] - a.q[2])])
    assert rel.A == pytest.approx(minimal.A, rel=1e-10, abs=1e-10)
    assert rel.states == ("a.th", "q2", "a.th_d", "q2_d")


def absolute_state(free):
    return free.model.free(solution="static").solve()


def cart_pole(Mc=2.0, mp=0.5, l=0.6, inertia=0.03, driven=False):
    m = ms.Model2D()
    F = m.parameter("F", 0.0)
    cart = m.add_body("cart", mass=Mc, inertia=0.1, guess=((0, 0), 0))
    pole = m.add_body("pole", mass=mp, centroid=(l, 0), inertia=inertia,
                      guess=((0, 0), np.pi / 2))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), cart.axis((0, 0), (1, 0))))
    m.add(ms.Revolute2(cart.point(0), pole.point(0)))
    if driven:
        m.add(ms.RelativeX1(cart.point(0), 1.5 * T), name="drive")
    m.add_load(ms.Gravity((0, -1), G))
    m.add_load(ms.Force(cart.point(0), (1, 0), F))
    m.add_load(ms.Force(cart.point(0), (1, 0), 0.0), name="push")
    return m


def test_inverted_pendulum_on_a_cart_textbook():
    Mc, mp, l, inertia = 2.0, 0.5, 0.6, 0.03
    free = cart_pole(Mc, mp, l, inertia).free()
    lin = free.linearize(coordinates=["cart.x", "pole.th"], inputs=["F", "push"],
                         outputs=["cart.x", "pole.th_dd"])
    # (M + m) x'' - m l th'' = F, (I + m l^2) th'' - m l x'' - m g l th = 0 (th from upright)
    J = inertia + mp * l * l
    p = (Mc + mp) * J - (mp * l) ** 2
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1
    A[2, 1], A[3, 1] = (mp * l) ** 2 * G / p, (Mc + mp) * mp * G * l / p
    B = np.array([0, 0, J / p, mp * l / p])
    assert lin.A == pytest.approx(A, rel=1e-12, abs=1e-12)
    # a parameter in a force's magnitude and a named load's magnitude: the same input
    assert lin.B == pytest.approx(np.column_stack([B, B]), rel=1e-12, abs=1e-12)
    # outputs: a coordinate (C) and an acceleration (C and D)
    assert lin.C == pytest.approx(np.array([[1, 0, 0, 0], [0, A[3, 1], 0, 0]]), abs=1e-12)
    assert lin.D == pytest.approx(np.array([[0, 0], [B[3], B[3]]]), abs=1e-12)
    # upright: one unstable, one stable, the cart's free motion neutral (a double zero)
    assert lin.stability.count("unstable") == 1 and lin.stability.count("neutral") == 2
    assert not lin.stable
    assert max(lin.eigenvalues.real) == pytest.approx(np.sqrt(A[3, 1]), rel=1e-12)
    # controllable from the force; scipy's state space holds the same matrices
    Cm = lin.controllability()
    assert np.linalg.matrix_rank(Cm) == 4 and lin.controllable
    plant = lin.to_scipy()
    assert isinstance(plant, ss.StateSpace) and np.array_equal(plant.A, lin.A)
    # the step response of the linear plant from scipy: x'' = (J/p) F at the first instant
    _, y, _ = ss.lsim(plant, U=np.column_stack([np.ones(3), np.zeros(3)]), T=[0, 1e-4, 2e-4])
    assert y[-1, 0] == pytest.approx(0.5 * B[2] * (2e-4) ** 2, rel=1e-3)
    try:
        import control  # noqa: F401
    except ImportError:  # python-control is optional: a named error says how to get it
        with pytest.raises(ms.MechError, match="pip install control"):
            lin.to_control()
    else:  # pragma: no cover - not installed here
        assert np.array_equal(lin.to_control().A, lin.A)
    # the pole's angle alone does not see the cart's position
    pole_only = free.linearize(coordinates=["cart.x", "pole.th"])
    assert pole_only.B.shape == (4, 0) and not pole_only.controllable


def test_driver_acceleration_input_at_constant_speed():
    """The cart driven at 1.5 m/s: a steady motion; the driver's acceleration is the input,
    its equation's deviation a state, th'' = (m g l th + m l a) / (I + m l^2)."""
    mp, l, inertia = 0.5, 0.6, 0.03
    free = cart_pole(mp=mp, l=l, inertia=inertia, driven=True).free()
    lin = free.linearize({"cart.x_d": 1.5}, inputs=["drive"], coordinates=["pole.th"],
                         outputs=["cart.x"])
    J = inertia + mp * l * l
    assert lin.states == ("pole.th", "drive", "pole.th_d", "drive_d")
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1
    A[2, 0] = mp * G * l / J
    assert lin.A == pytest.approx(A, rel=1e-12, abs=1e-12)
    assert lin.B[:, 0] == pytest.approx([0, 0, mp * l / J, 1], rel=1e-12)
    assert lin.C == pytest.approx(np.array([[0, 1, 0, 0]]), abs=1e-14)


def test_steady_motion_cyclic_coordinate_and_galilean_invariance():
    """The cart-pole moving at constant speed: cart.x moves, the motion does not depend on
    it; the linearisation equals the one at rest, and cyclic= drops its position."""
    free = cart_pole().free()
    rest = free.linearize(coordinates=["cart.x", "pole.th"])
    moving = free.linearize({"cart.x_d": 3.0, "pole.x_d": 3.0},
                            coordinates=["cart.x", "pole.th"])
    assert moving.A == pytest.approx(rest.A, rel=1e-12, abs=1e-12)
    assert moving.qd[0] == pytest.approx(3.0)
    cyc = free.linearize({"cart.x_d": 3.0}, coordinates=["cart.x", "pole.th"],
                         cyclic=["cart.x"])
    assert cyc.states == ("pole.th", "cart.x_d", "pole.th_d")
    assert cyc.A == pytest.approx(rest.A[1:, 1:], abs=1e-12)
    with pytest.raises(ms.NotSteadyError, match="'pole.th' is not cyclic"):
        free.linearize(coordinates=["cart.x", "pole.th"], cyclic=["pole.th"])


def sleeping_top(mass=1.2, h=0.1, Jp=0.004, Jc=0.006):
    m = ms.Model3D()
    top = m.add_body("top", mass=mass, centroid=(0, 0, h), inertia=(Jc, Jc, Jp, 0, 0, 0))
    m.add(ms.Spherical3(m.ground.point((0, 0, 0)), top.point(0)))
    m.add_load(ms.Gravity((0, 0, -1), G))
    return m, top


def test_sleeping_top_about_its_steady_spin():
    """Tilt of a top spinning upright at W: Jt s^2 - i Jp W s - m g h = 0 for the complex tilt
    (Jt about the pivot); stable (neutral) above W = 2 sqrt(Jt m g h) / Jp, unstable below.
    Coordinates: the axis' global x and y components and the spin 2 atan2(e3, e0) (cyclic)."""
    mass, h, Jp, Jc = 1.2, 0.1, 0.004, 0.006
    m, top = sleeping_top(mass, h, Jp, Jc)
    e0, _, _, e3 = top.q[3:]
    axis = top.point((0, 0, 1)).location()
    coords = [("tilt_x", axis[0]), ("tilt_y", axis[1]), ("spin", 2 * sp.atan2(e3, e0))]
    Jt = Jc + mass * h * h
    critical = 2 * np.sqrt(Jt * mass * G * h) / Jp
    free = m.free()
    for W in (0.3 * critical, 1.6 * critical):
        lin = free.linearize({"top.e3_d": W / 2}, coordinates=coords, cyclic=["spin"])
        root = np.sqrt(complex(4 * Jt * mass * G * h - (Jp * W) ** 2))
        s = np.array([1j * Jp * W + root, 1j * Jp * W - root]) / (2 * Jt)
        ref = ordered(np.concatenate([s, s.conj(), [0]]))
        assert ordered(lin.eigenvalues) == pytest.approx(ref, rel=1e-9, abs=1e-9)
        assert lin.stable == (W > critical)
        assert lin.stability.count("unstable") == (0 if W > critical else 2)


def test_not_a_steady_motion_and_bad_input():
    free = pendulum().free()
    with pytest.raises(ms.NotSteadyError, match="acceleration of b.th is"):
        free.linearize({"b.th": -1.0})
    # through the bottom with a speed: accelerations zero now, but the motion changes them
    with pytest.raises(ms.NotSteadyError, match="changes the accelerations"):
        free.linearize({"b.th_d": 1.0})
    # a base shaken by a driver x = 0.1 sin(2 T), at T = 0: at rest relative to the base and
    # no base acceleration now, but a jerk: the driver changes the accelerations
    m = pendulum()
    base = m.add_body("base", mass=1.0, inertia=0.1, guess=((0, 0), 0))
    m.remove(m.constraints[0])
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), base.axis((0, 0), (1, 0))))
    m.add(ms.RelativeX1(base.point(0), 0.1 * sp.sin(2 * T)), name="shake")
    m.add(ms.Revolute2(base.point(0), m.body("b").point(0)))
    with pytest.raises(ms.NotSteadyError, match="the time .* changes the accelerations"):
        m.free().linearize({"base.x_d": 0.2})
    with pytest.raises(ms.ModelError, match="takes 1 coordinate"):
        free.linearize(coordinates=["b.th", "b.x"])
    with pytest.raises(ms.ModelError, match="not independent"):
        free.linearize(coordinates=["b.x"])
    with pytest.raises(ms.ModelError, match="'nope' is not a parameter"):
        free.linearize(inputs=["nope"])
    with pytest.raises(ms.ModelError, match="give a list"):
        free.linearize(inputs="F")
    with pytest.raises(ms.ModelError, match="tolerance"):
        free.linearize(tolerance=2)
    with pytest.raises(ms.ModelError, match="not coordinates"):
        free.linearize(outputs=[sp.Symbol("zz")])
    # inputs that cannot be one: gravity has no magnitude, a joint of two equations, a
    # dropped driver; an output that needs a dropped (cyclic) position
    cp = cart_pole(driven=True)
    cp.add_load(ms.Gravity((0, -1), 1.0), name="g2")
    with pytest.raises(ms.ModelError, match="load 'g2' .* has no magnitude"):
        cp.free().linearize({"cart.x_d": 1.5}, inputs=["g2"], coordinates=["pole.th"])
    cp.constraints[1].name = "pin"
    with pytest.raises(ms.ModelError, match="'pin' has 2 equations"):
        cp.free().linearize({"cart.x_d": 1.5}, inputs=["pin"], coordinates=["pole.th"])
    with pytest.raises(ms.ModelError, match="'drive' is dropped"):
        cp.free(drop=["drive"]).linearize(inputs=["drive"])
    with pytest.raises(ms.ModelError, match="output 'cart.x' depends on the position"):
        cart_pole().free().linearize(coordinates=["cart.x", "pole.th"], cyclic=["cart.x"],
                                     outputs=["cart.x"])


@pytest.mark.parametrize("kb", [1e4, 1e12])
def test_each_eigenvalue_judged_on_its_own_scale(kb):
    """An upright pendulum on a torsion spring slightly too weak (s = +-0.012 1/s) beside a
    slider on a stiff spring (s = +-i sqrt(kb)), the model of tests/test_trust_vibration.py:
    the slow capsize is unstable whatever the stiff mode; with the spring just strong enough
    the double zero is neutral; a damper makes the stiff pair stable."""
    from test_trust_vibration import pendulum_beside_stiff_spring

    m = pendulum_beside_stiff_spring(kb=kb)
    lin = m.free().linearize(coordinates=["pend.th", "slider.x"])
    s = lin.eigenvalues
    by = {c: [x for x, k in zip(s, lin.stability) if k == c] for c in set(lin.stability)}
    assert sorted(lin.stability) == ["neutral", "neutral", "stable", "unstable"]
    assert by["unstable"][0].real == pytest.approx(0.012, rel=1e-6)
    assert by["stable"][0].real == pytest.approx(-0.012, rel=1e-6)
    assert sorted(abs(x.imag) for x in by["neutral"]) == pytest.approx([np.sqrt(kb)] * 2,
                                                                       rel=1e-12)
    assert not lin.stable
    neutral = pendulum_beside_stiff_spring(s_up=0.0, kb=kb).free().linearize(
        coordinates=["pend.th", "slider.x"])
    assert neutral.stable and set(neutral.stability) == {"neutral"}
    damped = pendulum_beside_stiff_spring(kb=kb, c=10.0).free().linearize(
        coordinates=["pend.th", "slider.x"])
    assert sorted(damped.stability) == ["stable", "stable", "stable", "unstable"]


@pytest.mark.parametrize("scale", [1.0, 1000.0])
def test_closed_loop_parallelogram_closed_form(scale):
    """A hanging parallelogram four-bar (crank and rocker of length L, a coupler body that
    translates): one degree of freedom of a closed loop, the pendulum
    w^2 = g (m1 c1 + m3 c3 + m2 L) / (I1o + I3o + m2 L^2) (I1o, I3o about the pivots).
    QR picks the coordinate; the same in millimetres; vibration agrees."""
    L, d = 1.0 * scale, 3.0 * scale
    (m1, c1, i1), (m2, i2), (m3, c3, i3) = (1.0, 0.4, 0.05), (0.5, 0.3), (0.8, 0.6, 0.07)
    c1, c3 = c1 * scale, c3 * scale
    i1, i2, i3 = (i * scale**2 for i in (i1, i2, i3))
    m = ms.Model2D()
    cr = m.add_body("crank", points={"tip": (L, 0)}, mass=m1, centroid=(c1, 0), inertia=i1,
                    guess=((0, 0), -np.pi / 2 + 0.1))
    cp = m.add_body("coupler", points={"b": (d, 0)}, mass=m2, centroid=(d / 2, 0), inertia=i2,
                    guess=((0.1 * L, -L), 0.0))
    ro = m.add_body("rocker", points={"tip": (L, 0)}, mass=m3, centroid=(c3, 0), inertia=i3,
                    guess=((d, 0), -np.pi / 2 + 0.1))
    m.add(ms.Revolute2(m.ground.point((0, 0)), cr.point(0)))
    m.add(ms.Revolute2(m.ground.point((d, 0)), ro.point(0)))
    m.add(ms.Revolute2(cr.point("tip"), cp.point(0)))
    m.add(ms.Revolute2(cp.point("b"), ro.point("tip")))
    m.add_load(ms.Gravity((0, -1), G * scale))
    eq = m.free(solution="static").solve()
    lin = m.free().linearize(eq, outputs=["coupler.x"])
    w2 = G * (m1 * c1 + m3 * c3 + m2 * L) / ((i1 + m1 * c1**2) + (i3 + m3 * c3**2) + m2 * L**2)
    w2 *= scale  # g and lengths scaled together: the frequency is that of metres
    assert lin.A.shape == (2, 2)
    assert ordered(lin.eigenvalues) == pytest.approx([-1j * np.sqrt(w2), 1j * np.sqrt(w2)],
                                                    rel=1e-9)
    # the coupler's x moves with the crank angle: dx = L dth (at the hanging position)
    k = lin.coordinates[0]
    per_unit = {"crank.th": L, "rocker.th": L}.get(k, 1.0)
    assert abs(lin.C[0, 0]) == pytest.approx(per_unit, rel=1e-9)
    assert m.vibration(at=eq).omega == pytest.approx([np.sqrt(w2)], rel=1e-9)
