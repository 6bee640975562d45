"""Kinematic sweeps through toggle (dead-centre) positions: the sweep continues on the branch
it followed, with continuous angles, satisfied constraints and a warning naming the time; it
never jumps by whole turns (issue 10: the crank ended at 8871.7 rad)."""

import dataclasses

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T, models
from mechsys.solvers import _kinematics

W = 2 * np.pi


def piston_driven(x_of_t, theta0):
    """Slider-crank (crank 2, rod 6) driven at the piston by ``x_of_t``; the guess is the
    upper-branch assembly at crank angle ``theta0``."""
    m = models.slider_crank()
    m.remove("drive")
    m.add(ms.RelativeX1(m.body("piston").point(0), x_of_t), name="piston drive")
    phi = np.arcsin(-2 * np.sin(theta0) / 6)
    m.set_guess({"crank.th": theta0, "rod.th": phi, "rod.x": 2 * np.cos(theta0),
                 "rod.y": 2 * np.sin(theta0), "piston.x": 2 * np.cos(theta0) + 6 * np.cos(phi)})
    return m


def crank_angle_of(x):
    """Crank angle in [0, pi] for piston position x (law of cosines)."""
    return np.arccos(np.clip((x**2 + 4 - 36) / (4 * x), -1, 1))


def assert_constraints_hold(m, sol, tol=1e-9):
    s = m.compile()
    worst = max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(sol.t, sol.q))
    assert worst < tol


def test_piston_drive_through_both_dead_centres_keeps_turning():
    """The piston follows exactly the motion of a crank turning at 2 pi rad/s, through the
    bottom (t = 0.5) and top (t = 1) dead centres, where Phi_q is singular. The sweep
    continues on the smooth branch: the crank angle is 2 pi t throughout."""
    x = 2 * sp.cos(W * T) + sp.sqrt(36 - 4 * sp.sin(W * T) ** 2)
    m = piston_driven(x, 0.05 * W)
    t = np.linspace(0.05, 1.05, 101)
    with pytest.warns(ms.NearSingularWarning, match=r"first at t = 0\.5 .*continued through"):
        sol = m.solve(t)
    th = sol.angle("crank")
    assert np.abs(np.diff(th)).max() < 0.1                   # step 0.063 rad, no jumps
    np.testing.assert_allclose(th, W * t, rtol=0, atol=1e-5)  # sqrt(ftol) at the toggles
    healthy = sol.extra["rcond"] > 1e-6
    assert healthy.sum() >= 97
    np.testing.assert_allclose(th[healthy], W * t[healthy], rtol=0, atol=1e-9)
    np.testing.assert_allclose(sol.omega("crank")[healthy], W, rtol=1e-6)
    assert_constraints_hold(m, sol)


def test_piston_pushed_to_top_dead_centre_and_back():
    """x = 8 - 2 (T - 1/2)^2 touches the dead centre x = 8 at T = 1/2 and returns. The crank
    passes through 0 on the branch the sweep followed (theta changes sign), continuously."""
    m = piston_driven(8 - 2 * (T - sp.Rational(1, 2)) ** 2, crank_angle_of(7.5))
    t = np.linspace(0.0, 1.0, 101)
    with pytest.warns(ms.NearSingularWarning, match=r"first at t = 0\.5 "):
        sol = m.solve(t)
    th = sol.angle("crank")
    assert np.abs(np.diff(th)).max() < 0.05
    expected = crank_angle_of(8 - 2 * (t - 0.5) ** 2) * np.sign(0.5 - t)
    np.testing.assert_allclose(th, expected, rtol=0, atol=1e-5)
    assert abs(th).max() < 1.0                               # 8871.7 rad before the fix
    assert_constraints_hold(m, sol)


def test_location_sweep_through_dead_centre():
    """Positions only (no qd for a Taylor predictor): the secant carries the sweep through."""
    x = 2 * sp.cos(W * T) + sp.sqrt(36 - 4 * sp.sin(W * T) ** 2)
    m = piston_driven(x, 0.05 * W)
    t = np.linspace(0.05, 1.05, 101)
    sol = m.solve(t, solution="location")
    np.testing.assert_allclose(sol.angle("crank"), W * t, rtol=0, atol=1e-5)


def test_whole_turn_jump_is_retried_then_reported(monkeypatch):
    """The continuity check: a position solve that lands a whole turn away from the
    prediction is solved again from the previous point; when that jumps too, the sweep
    stops with an error naming the time instead of returning the jump."""
    from mechsys.solvers import _jit_sweep

    m = models.slider_crank()
    t = np.linspace(0, 0.2, 5)
    real = _kinematics.solve_position
    calls = []
    # the check is the Python code's (the loop hands such a point over to it): every point
    # taken by the Python code, as the loop cannot be made to jump
    monkeypatch.setattr(_jit_sweep, "plan", lambda *a, **k: None)

    def turning(system, tk, g, options=None, p=None, scaling=None, chord=None, start=None, *,
                every=False):
        res = real(system, tk, g, options, p, scaling, chord=chord, start=start)
        calls.append(tk)
        i = system.layout.index("crank.th")
        if tk == t[2] and (every or len([c for c in calls if c == tk]) == 1):
            q = res.q.copy()
            q[i] += 2 * np.pi
            return dataclasses.replace(res, q=q)
        return res

    monkeypatch.setattr(_kinematics, "solve_position", turning)
    sol = m.solve(t)                                         # the retry recovers
    np.testing.assert_allclose(sol.angle("crank"), W * t, rtol=0, atol=1e-12)
    assert calls.count(t[2]) == 2
    monkeypatch.setattr(_kinematics, "solve_position",
                        lambda *a, **k: turning(*a, **k, every=True))
    with pytest.raises(ms.ConvergenceError, match=r"at t = 0\.1: a rotational coordinate "
                                                  r"\(crank\.th\) jumped by 6\.6 rad") as err:
        m.solve(t)
    assert err.value.time == t[2]


def test_an_ill_conditioned_iterate_is_not_called_a_redundancy():
    """A guess far from any assembled position (the crank turned 1e9 rad with the rod and
    piston guessed for 0) drives Newton to an iterate whose Jacobian is too ill-conditioned
    to factorise although every equation is independent: the error says so, instead of
    "singular ... (rank 9 of 9 equations)" and advice about redundant constraints."""
    m = models.slider_crank()
    m.set_guess({"crank.th": 1e9})
    with pytest.raises(ms.SingularJacobianError) as exc:
        m.solve([0.0, 0.1])
    msg = str(exc.value)
    assert "too ill-conditioned" in msg and "no equation depends on the others" in msg
    assert "(rank 9 of 9 equations" in msg and "redundant" not in msg
    assert "check the guess" in msg and exc.value.dependent == []


def test_solve_position_start_is_checked():
    """``solve_position(start=...)`` (the equations at the guess, already evaluated): the
    same answer as without it, and a clear error for a pair of the wrong shapes."""
    from mechsys.solvers import solve_position

    m = models.slider_crank()
    s = m.compile()
    g, p = m.guess(), m._p()
    F, J = s.residual_and_jacobian(0.1, g, p)
    plain = solve_position(s, 0.1, g, p=p)
    given = solve_position(s, 0.1, g, p=p, start=(F, J))
    np.testing.assert_array_equal(plain.q, given.q)
    assert plain.evaluations == given.evaluations
    for bad in ((F[:-1], J), (F, J[:, :-1]), (F,), "FJ", (F, None)):
        with pytest.raises(ms.ModelError, match="start"):
            solve_position(s, 0.1, g, p=p, start=bad)
