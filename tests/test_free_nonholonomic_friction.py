"""Loads that depend on the multipliers (joint friction) or on the accelerations beside
velocity constraints in free motion (decision 0068): the Newton iteration of
``free_acceleration`` on the bordered system.

The case with a closed form: a cart slides without friction along a slope rising at ``AL``
(``Translate2``); a wheel (radius ``RAD``, mass ``MW``, inertia ``IW``) is pinned to it at its
centre (``Revolute2`` "pin") and rolls without slip on the slope (``RollingCircle1``, a
velocity row: the slope carries only a tangential force ``F_c``, the pin the wheel's weight
across the slope). The pin has Coulomb friction (``JointFriction``: moment ``mu_b r_b |R|``
against the wheel's spin, ``R`` the pin's reaction). With ``a`` the acceleration along the
slope and an optional added mass ``ca`` on the cart (a force ``-ca`` times its acceleration:
a load depending on the accelerations), Newton's law along the slope for both bodies and
about the wheel's centre (rolling: ``w = -v / RAD``) give

    (mc + mw + ca + Iw / RAD^2) a + (mc + mw) g sin(AL) = (mu_b r_b / RAD) |R|,
    |R| = sqrt(((mc + ca) a + mc g sin(AL))^2 + (mw g cos(AL))^2)

(for a wheel rolling down, ``w > 0``): a quadratic in ``a``, the root where the left side is
positive. The motion is then uniformly accelerated.
"""

from __future__ import annotations

import numpy as np
import pytest

import mechsys as ms

AL, RAD, MC, MW, IW, G, MUB, RB = 0.3, 0.5, 2.0, 3.0, 0.4, 9.81, 0.2, 0.05
S0, W0 = 2.0, 2.0                     # start: 2 along the slope, spinning down at 2 rad/s
TU, NU = np.array([np.cos(AL), np.sin(AL)]), np.array([-np.sin(AL), np.cos(AL)])


def cart_and_wheel(added_mass=0.0, damping=None, friction=True, ecc=0.0, th0=0.0):
    m = ms.Model2D()
    c0 = S0 * TU + RAD * NU
    cart = m.add_body("cart", guess=(tuple(c0), AL), mass=MC, inertia=0.1)
    wheel = m.add_body("wheel", guess=(tuple(c0), th0), mass=MW, inertia=IW,
                       centroid=(ecc, 0.0))
    m.add(ms.Translate2(cart.axis((0, 0), (1, 0)), m.ground.axis(tuple(RAD * NU), tuple(TU))),
          name="slide")
    m.add(ms.Revolute2(wheel.point(0), cart.point(0)), name="pin")
    roll = ms.RollingCircle1(wheel.point(0), RAD, m.ground.axis((0, 0), tuple(TU)))
    m.add(roll, name="roll")
    m.add_load(ms.Gravity((0, -1), G))
    if friction:
        # (v_eps far below the spin: the regularised sign is 1 to 1e-19)
        m.add_load(ms.JointFriction("pin", mu=MUB, radius=RB, v_eps=1e-9))
    if added_mass:
        m.add_load(ms.Force(cart.point(0), -added_mass * m.acceleration(cart.point(0)),
                            mode="relative"))
    if damping is not None:
        m.add_load(ms.TorsionDamper(m.ground, wheel, damping))
    return m, cart, wheel, roll


def scaled_cart_and_wheel(k):
    """:func:`cart_and_wheel` written in a unit of length ``1/k`` m (``k = 1000``: mm): lengths
    times ``k``, inertias times ``k^2``, gravity times ``k``."""
    m = ms.Model2D()
    c0 = (S0 * TU + RAD * NU) * k
    cart = m.add_body("cart", guess=(tuple(c0), AL), mass=MC, inertia=0.1 * k * k)
    wheel = m.add_body("wheel", guess=(tuple(c0), 0.0), mass=MW, inertia=IW * k * k)
    m.add(ms.Translate2(cart.axis((0, 0), (1, 0)), m.ground.axis(tuple(RAD * k * NU), tuple(TU))),
          name="slide")
    m.add(ms.Revolute2(wheel.point(0), cart.point(0)), name="pin")
    m.add(ms.RollingCircle1(wheel.point(0), RAD * k, m.ground.axis((0, 0), tuple(TU))), name="roll")
    m.add_load(ms.Gravity((0, -1), G * k))
    m.add_load(ms.JointFriction("pin", mu=MUB, radius=RB * k, v_eps=1e-9))
    return m


def closed_form(added_mass=0.0):
    """``(a, |R|, F_c)``: the acceleration along the slope, the pin's reaction and the
    slope's tangential force on the wheel (along ``TU``)."""
    sa, ca = np.sin(AL), np.cos(AL)
    me = MC + MW + added_mass + IW / RAD**2
    k, G1, mc = MUB * RB / RAD, (MC + MW) * G * sa, MC + added_mass
    # (me a + G1)^2 = k^2 ((mc a + MC g sa)^2 + (MW g ca)^2)
    roots = np.roots([me**2 - k**2 * mc**2, 2 * me * G1 - 2 * k**2 * mc * MC * G * sa,
                      G1**2 - k**2 * ((MC * G * sa)**2 + (MW * G * ca)**2)])
    a = max(r.real for r in roots if me * r.real + G1 >= 0)
    R = np.hypot(mc * a + MC * G * sa, MW * G * ca)
    Fc = (-IW * a / RAD + MUB * RB * R) / RAD        # about the centre: IW w' = RAD Fc - MUB RB R
    return a, R, Fc


def test_wheel_with_bearing_friction_rolls_down_against_the_closed_form():
    m, cart, wheel, roll = cart_and_wheel()
    a, R, Fc = closed_form()
    assert a == pytest.approx(-2.110920008597880, rel=1e-12)  # (frictionless: -2.19625)
    free = m.free()
    assert free.dof == 1
    start = {"wheel.th_d": W0, "cart.x": (S0 * TU + RAD * NU)[0]}
    t = np.linspace(0.0, 1.5, 16)
    sol = free.simulate(t, initial_condition=start, rtol=1e-12, atol=1e-12)
    # the Python stepper takes these runs (the compiled Newton kind holds no velocity rows)
    assert sol.extra["compiled_steps"] == 0 and sol.extra["compiled_solver"] is None
    s = S0 - RAD * W0 * t + a * t**2 / 2                # along the slope: uniformly accelerated
    centre = np.column_stack((sol["cart.x"], sol["cart.y"]))
    assert np.abs(centre - (s[:, None] * TU + RAD * NU)).max() < 1e-9
    assert np.abs(sol["wheel.th"] - (W0 * t - a * t**2 / (2 * RAD))).max() < 1e-9
    assert np.abs(sol.omega(wheel) - (W0 - a * t / RAD)).max() < 1e-9
    assert np.abs(sol.qdd[:, :2] - a * TU).max() < 1e-9
    F, _ = sol.reaction("pin", wheel)
    assert np.abs(np.linalg.norm(F, axis=1) - R).max() < 1e-9
    assert np.abs(roll.tangential_force(sol) - Fc * TU).max() < 1e-9
    assert sol.extra["velocity_multipliers"] == ["roll[0]"]
    # energy: the kinetic and potential energy lost is the friction's work, the integral of
    # its power MUB RB |R| |w| (linear in time here: the trapezoidal rule is exact)
    P = MUB * RB * np.linalg.norm(F, axis=1) * np.abs(sol.omega(wheel))
    W = np.concatenate(([0.0], np.cumsum(0.5 * (P[1:] + P[:-1]) * np.diff(t))))
    E = sol.body_energy() + sol.potential_energy()
    assert W[-1] == pytest.approx(MUB * RB * R * (W0 * 1.5 - a * 1.5**2 / (2 * RAD)), rel=1e-12)
    assert np.abs((E[0] - E) - W).max() < 1e-8
    acc = sol.extra["accuracy"]
    assert max(acc["position"], acc["velocity"], acc["nonholonomic"]) < 1e-12
    # one state (free.solve): the same Newton, the same numbers
    one = free.solve(0.0, initial_condition=start, tolerance=1e-12)
    assert np.ravel(one.qdd)[:2] == pytest.approx(a * TU, abs=1e-12)
    assert np.ravel(roll.tangential_force(one)) == pytest.approx(Fc * TU, abs=1e-12)


def test_acceleration_dependent_load_with_friction_and_rolling():
    """An added mass on the cart (a force ``-ca`` times its acceleration) with the friction:
    Newton on the bordered system takes both."""
    ca = 1.5
    m, cart, wheel, roll = cart_and_wheel(added_mass=ca)
    a, R, Fc = closed_form(ca)
    free = m.free()
    dyn = free.system.dynamics
    assert dyn.depends_on_qdd and dyn.depends_on_lambda
    start = {"wheel.th_d": W0, "cart.x": (S0 * TU + RAD * NU)[0]}
    one = free.solve(0.0, initial_condition=start)
    assert np.ravel(one.qdd)[:2] == pytest.approx(a * TU, abs=1e-10)
    assert np.linalg.norm(one.reaction("pin", wheel)[0]) == pytest.approx(R, rel=1e-10)
    sol = free.simulate(np.linspace(0.0, 0.5, 3), initial_condition=start, rtol=1e-12,
                        atol=1e-12)
    s = S0 - RAD * W0 * sol.t + a * sol.t**2 / 2
    assert np.abs(np.column_stack((sol["cart.x"], sol["cart.y"]))
                  - (s[:, None] * TU + RAD * NU)).max() < 1e-9


def test_equilibria_with_friction_and_rolling():
    """Kinematic: against a rotational damper ``c`` the wheel rolls down at the spin where
    the damper and the pin friction take the weight's power, ``c w = RAD (mc + mw) g sin(AL)
    - mu_b r_b |R|`` with ``|R|`` the reaction at no acceleration. Static (friction vanishes
    at rest, the regularised sign being 0): a wheel whose centroid is ``ecc`` off its centre
    rests where the weight's moment about the centre balances the slope's force ``(mc + mw) g
    sin(AL)``, ``mw g ecc cos(th) = RAD (mc + mw) g sin(AL)``."""
    c = 0.7
    m, cart, wheel, roll = cart_and_wheel(damping=c)
    R = np.hypot(MC * G * np.sin(AL), MW * G * np.cos(AL))
    w = (RAD * (MC + MW) * G * np.sin(AL) - MUB * RB * R) / c
    sk = m.free(solution="kinematic").solve(initial_condition={"wheel.th_d": 1.0})
    assert np.ravel(sk.qd)[5] == pytest.approx(w, rel=1e-12)
    assert np.ravel(sk.qd)[:2] == pytest.approx(-RAD * w * TU, abs=1e-12)
    assert np.linalg.norm(sk.reaction("pin", wheel)[0]) == pytest.approx(R, rel=1e-12)
    ecc = 0.4
    m, cart, wheel, roll = cart_and_wheel(ecc=ecc, th0=-1.0)
    eq = m.free(solution="static").solve()
    Ft = (MC + MW) * G * np.sin(AL)
    assert np.ravel(eq.q)[5] == pytest.approx(-np.arccos(RAD * Ft / (MW * G * ecc)), abs=1e-10)
    assert np.ravel(roll.tangential_force(eq)) == pytest.approx(Ft * TU, abs=1e-12)
    assert np.ravel(eq.reaction("pin", wheel)[0]) == pytest.approx(
        MW * G * np.array([0.0, 1.0]) - Ft * TU, abs=1e-12)


def test_what_stays_refused_is_named():
    m, cart, wheel, roll = cart_and_wheel()
    # a velocity constraint has no multiplier symbols for a load
    with pytest.raises(ms.ModelError, match="'roll'.*no multiplier symbols"):
        m.multipliers("roll")
    assert [str(s) for s in m.multipliers("pin")] == ["lam2_1", "lam2_2"]
    # sensitivities (the bordered tangent lacks the loads' derivatives) and linearisation
    # (Coulomb friction is not smooth)
    push = m.parameter("push", 0.5)
    m.add_load(ms.Force(cart.point(0), (1, 0), push))
    with pytest.raises(ms.ModelError, match="roll.*not supported"):
        m.sensitivity(["push"], free=m.free()).simulate(np.linspace(0, 0.1, 2))
    with pytest.raises(ms.ModelError, match="friction"):
        m.free().linearize({"wheel.th_d": W0})
    # through switches and events: not yet
    m.add_load(ms.TimeSwitch(1.0, ms.Force(cart.point(0), (1, 0), 1.0), 2.0))
    with pytest.raises(ms.ModelError, match="roll.*switches"):
        m.free()


def test_the_same_motion_in_millimetres():
    """The wheel with bearing friction, written in metres and in millimetres: the same motion
    (lengths times 1000), the same rolling multiplier (a force: times 1000) and the holonomic
    multipliers in their own units (forces times 1000, the slide's moment times 10^6), to
    rounding; a result that depended on the unit of length would be a silent error."""
    t = np.linspace(0, 0.5, 6)
    m_, mm = (scaled_cart_and_wheel(k).free().simulate(t, initial_condition={"wheel.th_d": W0})
              for k in (1.0, 1000.0))
    unit = np.array([1000.0, 1000.0, 1.0] * 2)
    for a, b in ((m_.q, mm.q), (m_.qd, mm.qd), (m_.qdd, mm.qdd)):
        assert np.abs(b / unit - a).max() <= 1e-12 * np.abs(a).max()
    assert np.abs(mm.extra["mu"] / 1000 - m_.extra["mu"]).max() <= 1e-12 * np.abs(m_.extra["mu"]).max()
    lam_unit = np.array([1e3, 1e6, 1e3, 1e3, 1e3])        # slide: a force and a moment; pin: forces
    assert np.abs(mm.lam / lam_unit - m_.lam).max() <= 1e-12 * np.abs(m_.lam).max()
