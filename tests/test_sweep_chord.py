"""The sweep's position solve starts with chord steps on the previous point's velocity
factorisation, from an O(dt^4) predictor (decision 0020): the chord's fall-back to Newton,
its extra step from within the tolerance (accuracy as Newton's, checked against the closed
form), the predictor's order, and the compiled and Python loops agreeing where the chord is
handed from one to the other."""

from __future__ import annotations

import numpy as np
import pytest

import mechsys as ms
from mechsys import models
from mechsys.solvers import _jit_sweep, _kinematics
from mechsys.solvers._linalg import Scaling, rotation_columns
from mechsys.solvers._position import solve_position
from mechsys.solvers._tolerances import CHORD_RATE

W = 2 * np.pi


def closed_form(t, r=2.0, rod=6.0):
    """Slider-crank (crank angle 2 pi t): crank angle, rod angle and piston x with their first
    two derivatives (the rod angle from ``rod sin(phi) = -r sin(theta)``)."""
    th = W * t
    k = r / rod
    phi = np.arcsin(-k * np.sin(th))
    c = np.cos(phi)
    phid = -k * W * np.cos(th) / c
    phidd = (k * W * W * np.sin(th) + phid * phid * np.sin(phi)) / c
    x = r * np.cos(th) + rod * c
    xd = -r * W * np.sin(th) - rod * np.sin(phi) * phid
    xdd = -r * W * W * np.cos(th) - rod * (c * phid * phid + np.sin(phi) * phidd)
    return np.stack([th, phi, x, np.full_like(t, W), phid, xd, 0 * t, phidd, xdd])


def _system():
    m = models.slider_crank()
    s = m.compile()
    return m, s, m._p()


def _point(s, p, t):
    """The exact position at time t, and the scaling and factorisation there."""
    q = closed_form(np.array([t]))[:3, 0]
    m_q = np.zeros(s.n)
    lay = s.layout
    m_q[lay.index("crank.th")], m_q[lay.index("rod.th")], m_q[lay.index("piston.x")] = q
    m_q[lay.index("rod.x")] = 2 * np.cos(q[0])
    m_q[lay.index("rod.y")] = 2 * np.sin(q[0])
    sc = Scaling.of(s, m_q, s.jacobian(t, m_q, p))
    return m_q, sc


def test_chord_from_a_nearby_point_is_as_accurate_as_newton():
    """From a guess 1e-9 off, with the factorisation of a point 1e-3 earlier: chord steps
    only (no factorisation of the new Jacobian), one more once within tol, and the result
    agrees with plain Newton's to rounding."""
    m, s, p = _system()
    q0, sc = _point(s, p, 0.3)
    chord = sc.factor(s.jacobian(0.3, q0, p))
    t = 0.301
    exact, _ = _point(s, p, t)
    guess = exact + 1e-9 * np.linspace(1, -1, s.n)
    calls = []
    real = sc.factor
    sc.factor = lambda *a: calls.append(1) or real(*a)        # count Newton's factorisations
    got = solve_position(s, t, guess, None, p, sc, chord=chord)
    assert not calls                                           # chord steps only
    assert got.iterations >= 2                                 # the extra step from within tol
    assert got.history[-2] <= 1e-12 * (1 + sc.offset)          # ... started within tol
    sc.factor = real
    newton = solve_position(s, t, guess, None, p, sc)
    np.testing.assert_allclose(got.q, newton.q, rtol=1e-14, atol=1e-15)   # a few ulps
    np.testing.assert_allclose(got.q, exact, rtol=0, atol=1e-13)
    assert got.residual <= 1e-14 and newton.residual <= 1e-14    # both at rounding (tol 5e-12)


def test_slow_chord_falls_back_to_newton():
    """A chord from far away (a quarter turn earlier) contracts too slowly: its first step is
    discarded (an evaluation spent, no iteration counted) and Newton continues from the
    guess with the Jacobian there: Newton's own iterates, then (the last Newton step having
    started outside tol) one more step with Newton's last factorisation."""
    m, s, p = _system()
    q0, sc = _point(s, p, 0.05)
    far = sc.factor(s.jacobian(0.05, q0, p))
    t = 0.3
    exact, _ = _point(s, p, t)
    guess = exact + 1e-3 * np.linspace(1, -1, s.n)
    plain = solve_position(s, t, guess, None, p, sc)
    chord = solve_position(s, t, guess, None, p, sc, chord=far)
    tol = 1e-12 * (1 + sc.offset)
    assert plain.history[-2] > tol >= plain.history[-1]
    # the discarded step and the extra step: two evaluations more, Newton's iterates between
    assert chord.evaluations == plain.evaluations + 2
    assert chord.iterations == plain.iterations + 1
    assert chord.history[:-1] == plain.history
    assert chord.history[-1] <= tol
    np.testing.assert_allclose(chord.q, plain.q, rtol=0, atol=1e-12)
    # and it was discarded for its rate, not by chance
    step = guess - far.solve(s.residual(t, guess, p))
    rows = sc.rows(s.jacobian(t, guess, p))
    assert np.abs(s.residual(t, step, p) / rows).max() > CHORD_RATE * plain.history[0]


def test_max_iterations_one_still_converges_with_the_chord():
    """The extra step is for accuracy, not a condition of convergence: with max_iterations=1
    a chord step that lands within tol converges."""
    m, s, p = _system()
    q0, sc = _point(s, p, 0.3)
    chord = sc.factor(s.jacobian(0.3, q0, p))
    exact, _ = _point(s, p, 0.3001)
    got = solve_position(s, 0.3001, exact + 1e-11, ms.PositionOptions(max_iterations=1), p, sc,
                         chord=chord)
    assert got.success and got.iterations == 1


def test_predictor_is_fifth_order():
    """The Taylor predictor with the third and fourth derivatives from the last three
    accelerations (divided differences): its error falls about 32 x when the step halves
    (the second-order Taylor step alone: 8 x)."""
    m, s, p = _system()
    rot = np.flatnonzero(rotation_columns(s))
    errs, taylor = [], []
    for N in (101, 201):
        t = np.linspace(0.0, 0.25, N)
        sol = m.solve(t)
        k = N - 1
        g = _kinematics._predict(sol.q, sol.qd, sol.qdd, sol.extra["rcond"], t, k, rot)
        errs.append(np.abs(g - sol.q[k]).max())
        dt = t[k] - t[k - 1]
        taylor.append(np.abs(sol.q[k - 1] + sol.qd[k - 1] * dt + 0.5 * sol.qdd[k - 1] * dt * dt
                             - sol.q[k]).max())
    assert 26 < errs[0] / errs[1] < 40
    assert errs[1] < 1e-3 * taylor[1]


@pytest.mark.parametrize("jit", ["0", "1"])
def test_sweep_as_accurate_as_before(monkeypatch, jit):
    """1000 points against the closed form: positions, velocities and accelerations to
    rounding (2.8e-14 here; a chord stopped at the first iterate within tol, from a
    third-order predictor, left 1.5e-12 in the accelerations), with one chord step a point
    (the predictor is within tol: no factorisation but the velocity's)."""
    pytest.importorskip("numba")
    monkeypatch.setenv("MECHSYS_JIT", jit)
    t = np.linspace(0.0, 1.0, 1000)
    sol = models.slider_crank().solve(t)
    got = np.stack([sol.coordinate(k, o) for o in (0, 1, 2) for k in ("crank.th", "rod.th", "piston.x")])
    assert np.abs(got - closed_form(t)).max() < 2e-13
    assert np.bincount(sol.iterations)[1] > 990


def test_handover_passes_the_chord(monkeypatch):
    """The compiled loop stops at point 500 and each point after it: the Python code (its own
    predictor, Newton and LAPACK) refactorises the chord the loop had (from the returned row
    scales), so the iterations and evaluations at every later point are those of the loop
    (compiled, and interpreted: bit for bit), and the numbers agree to rounding."""
    pytest.importorskip("numba")
    real = _jit_sweep.run
    t = np.linspace(0.0, 1.0, 1000)

    def partial(system, pointers, times, *rest, **kw):
        return real(system, pointers, times[:500], *rest, **kw)

    monkeypatch.setenv("MECHSYS_JIT", "1")
    fast = models.slider_crank().solve(t)
    monkeypatch.setattr(_jit_sweep, "run", partial)
    chords = []
    real_solve = _kinematics.solve_position

    def spy(*a, **k):
        chords.append(k.get("chord") is not None)
        return real_solve(*a, **k)

    monkeypatch.setattr(_kinematics, "solve_position", spy)
    mixed = models.slider_crank().solve(t)
    assert len(chords) == 500 and all(chords)       # the Python loop had the chord at once
    monkeypatch.setenv("MECHSYS_JIT", "0")
    plain = models.slider_crank().solve(t)
    for a in (fast, mixed):
        np.testing.assert_array_equal(a.iterations, plain.iterations)
        assert a.evaluations == plain.evaluations
        for x, y in ((a.q, plain.q), (a.qd, plain.qd), (a.qdd, plain.qdd)):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-12)
        np.testing.assert_allclose(a.extra["rcond"], plain.extra["rcond"], rtol=1e-12)


def test_singular_instant_found_by_the_chord_is_solved_again_with_newton(monkeypatch):
    """Chord steps do not factorise the Jacobian, so at a singular instant (a parallelogram
    chain driven through its flat position, tests/test_singular_free.py) they converge
    without noticing; the singular velocity factorisation then sends the point back to
    Newton, which diagnoses and approaches it: the rates there are the continuous motion's."""
    import sympy as sp

    m = models.n_four_bar(2)
    m.replace("hold", ms.RotationLock1(m.body("crank0"), sp.pi / 2 - sp.pi / 2 * ms.T))
    t = np.linspace(0.0, 2.0, 21)
    calls = []
    real = _kinematics.solve_position

    def spy(system, tk, *a, **k):
        calls.append((float(tk), k.get("chord") is not None))
        return real(system, tk, *a, **k)

    monkeypatch.setattr(_kinematics, "solve_position", spy)
    monkeypatch.setenv("MECHSYS_JIT", "0")
    with pytest.warns(ms.NearSingularWarning):
        sol = m.solve(t)
    at = [c for tk, c in calls if tk == 1.0]
    assert at[:2] == [True, False]          # chord first, then Newton alone
    assert sol.extra["rcond"][10] == 0.0
    np.testing.assert_allclose(sol.omega("crank1")[10], -np.pi / 2, rtol=0, atol=1e-5)
