"""m.lock (Mech's LockMech, manual 12.5): reactions for new load and inertia parameters at a
locked configuration equal those of a full solve; parameters that move the mechanism are
refused; stale locks and bad input are named."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T


def slider_crank_with_force():
    """The slider-crank of models.slider_crank with a force of magnitude F at angle k on the
    piston, a crank of parameter length r and a rod of parameter mass mr."""
    m = ms.Model2D()
    r = m.parameter("r", 2.0)
    k = m.parameter("k", 0.0)
    F = m.parameter("F", 10.0)
    mr = m.parameter("mr", 3.0)
    cr = m.add_body("crank", points={"pin": (r, 0)}, guess=((0, 0), 0.6))
    rd = m.add_body("rod", points={"b": (6, 0)}, mass=mr, centroid=(3, 0), inertia=mr * 3,
                    guess=((1.6, 1.1), -0.2))
    pi = m.add_body("piston", mass=1.0, guess=((7.5, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), cr.point(0)), name="crank pin")
    m.add(ms.Revolute2(cr.point("pin"), rd.point(0)), name="crank-rod")
    m.add(ms.Revolute2(rd.point("b"), pi.point(0)), name="wrist pin")
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), pi.axis((0, 0), (1, 0))), name="slider")
    m.add(ms.RotationLock1(cr, 2 * sp.pi * T), name="drive")
    m.add_load(ms.Force(pi.point(0), (sp.cos(k), sp.sin(k)), F))
    return m


@pytest.mark.parametrize("mode", ["static", "kinematic", "dynamic"])
def test_locked_reactions_equal_full_solves(mode):
    m = slider_crank_with_force()
    locked = m.lock(0.1, solution="acceleration" if mode == "dynamic" else "velocity")
    for k in np.linspace(0.0, np.pi, 5):
        for mass in (1.0, 5.0):
            got = locked.solve(mode, parameters={"k": k, "mr": mass})
            m.set_parameters(k=k, mr=mass)
            ref = m.solve(0.1, solution=mode)
            np.testing.assert_allclose(got.lam, ref.lam, rtol=1e-10, atol=1e-10)
            f_got, _ = got.reaction("slider", "piston")
            f_ref, _ = ref.reaction("slider", "piston")
            np.testing.assert_allclose(f_got, f_ref, rtol=1e-10, atol=1e-10)
    assert got.extra["locked"] and got.iterations.sum() == 0      # no position solve


def test_static_balance_of_the_piston():
    """Independent check: the slider reaction on the piston balances the applied force's
    vertical component plus the rod's pull (the piston is massless in statics here, so
    the wrist-pin force and the slider force and F sum to zero)."""
    m = slider_crank_with_force()
    locked = m.lock(0.1)
    sol = locked.solve("static", parameters={"k": 0.7, "F": 4.0})
    f_slider, _ = sol.reaction("slider", "piston")
    f_pin, _ = sol.reaction("wrist pin", "piston")
    weightless = f_slider + f_pin + 4.0 * np.array([np.cos(0.7), np.sin(0.7)])
    np.testing.assert_allclose(weightless, 0.0, atol=1e-10)


def test_location_lock_recomputes_velocities_for_new_parameters():
    m = slider_crank_with_force()
    pos = m.solve(0.1, solution="location")
    locked = m.lock(pos)
    got = locked.solve("dynamic", parameters={"mr": 2.0})
    m.set_parameters(mr=2.0)
    ref = m.solve(0.1, solution="dynamic")
    np.testing.assert_allclose(got.qdd, ref.qdd, atol=1e-12)
    np.testing.assert_allclose(got.lam, ref.lam, rtol=1e-10, atol=1e-10)


def test_parameter_that_moves_the_mechanism_is_refused():
    m = slider_crank_with_force()
    locked = m.lock(0.1)
    with pytest.raises(ms.ModelError, match=r"parameter\(s\) \['r'\].*no longer satisfies"):
        locked.solve("static", parameters={"r": 2.1})
    # the same value as at the lock is fine
    locked.solve("static", parameters={"r": 2.0})


def test_velocity_lock_refuses_a_changed_drive_speed():
    m = ms.Model2D()
    w = m.parameter("w", 1.0)
    arm = m.add_body("arm", points={"tip": (1, 0)}, mass=1.0, guess=((0, 0), 0.1))
    m.add(ms.Revolute2(m.ground.point((0, 0)), arm.point(0)))
    m.add(ms.RotationLock1(arm, w * T), name="drive")
    locked = m.lock(0.0, solution="velocity")
    with pytest.raises(ms.ModelError, match=r"\['w'\].*locked velocity"):
        locked.solve("kinematic", parameters={"w": 2.0})


def test_stale_lock_and_bad_input():
    m = slider_crank_with_force()
    locked = m.lock(0.1)
    with pytest.raises(ms.ModelError, match="unknown parameter 'q'"):
        locked.solve("static", parameters={"q": 1.0})
    with pytest.raises(ms.ModelError, match="solution must be one of"):
        locked.solve("statics")
    with pytest.raises(ms.ModelError, match="parameter 'k' must be finite"):
        locked.solve("static", parameters={"k": float("nan")})
    with pytest.raises(ms.ModelError, match="has 3 points"):
        m.lock(m.solve([0.0, 0.1, 0.2]))
    with pytest.raises(ms.ModelError, match="needs a state with velocities"):
        m.lock(m.solve(0.1, solution="location"), solution="velocity")
    with pytest.raises(ms.ModelError, match="highest order"):
        m.lock(0.1, solution="static")
    m.add_load(ms.Gravity((0, -1), 9.81))
    with pytest.raises(ms.ModelError, match="changed after m.lock"):
        locked.solve("static")
