"""Four-bar linkage against the Freudenstein equation, both assembly branches."""

import numpy as np
import pytest

from mechsys import models


def freudenstein_output(a, b, c, d, th2, branch):
    """Rocker angle th4 from K1 cos th4 - K2 cos th2 + K3 = cos(th2 - th4) (Freudenstein),
    for crank a, coupler b, rocker c, ground d. Solved as A cos th4 + B sin th4 = C."""
    K1, K2 = d / a, d / c
    K3 = (a**2 - b**2 + c**2 + d**2) / (2 * a * c)
    # cos(th2 - th4) = cos th2 cos th4 + sin th2 sin th4
    A = K1 - np.cos(th2)
    B = -np.sin(th2)
    C = K2 * np.cos(th2) - K3
    R = np.hypot(A, B)
    base = np.arctan2(B, A)
    return base + branch * np.arccos(np.clip(C / R, -1, 1))


def wrap(x):
    return np.angle(np.exp(1j * x))


@pytest.mark.parametrize("branch", [1, -1])
def test_rocker_angle_follows_freudenstein(branch):
    a, b, c, d = 1.0, 4.0, 3.0, 4.0
    m = models.four_bar(ground=d, crank=a, coupler=b, rocker=c, speed=1.0, branch=branch)
    t = np.linspace(0, 2 * np.pi, 91)
    sol = m.solve(t)
    th4 = sol.angle("rocker")
    expected = np.array([freudenstein_output(a, b, c, d, x, +1) for x in t])
    other = np.array([freudenstein_output(a, b, c, d, x, -1) for x in t])
    # the solved branch is one of the two closed-form roots throughout, and never switches
    e1 = np.abs(wrap(th4 - expected)).max()
    e2 = np.abs(wrap(th4 - other)).max()
    assert min(e1, e2) < 1e-9
    # branch +1 puts the rocker tip above the ground line at t = 0
    tip_y = sol.location(m.body("rocker").point("tip"))[:, 1]
    assert np.sign(tip_y[0]) == branch


def test_both_branches_are_distinct_assemblies():
    up = models.four_bar(branch=1).solve(0.3)
    down = models.four_bar(branch=-1).solve(0.3)
    assert abs(up["rocker.th"] - down["rocker.th"]) > 0.5


def test_poor_guess_reaches_nearest_branch():
    a, b, c, d = 1.0, 4.0, 3.0, 4.0
    m = models.four_bar(ground=d, crank=a, coupler=b, rocker=c, branch=1)
    th2 = 0.0
    roots = [freudenstein_output(a, b, c, d, th2, s) for s in (1, -1)]
    for target in roots:
        guess = m.guess()
        guess[m.compile().layout.index("rocker.th")] = target + 0.35   # 20 degrees off
        sol = m.solve(0.0, guess=guess)
        assert abs(wrap(sol["rocker.th"] - target)) < 1e-9


def test_rocker_velocity_matches_differentiated_closed_form():
    a, b, c, d = 1.0, 4.0, 3.0, 4.0
    m = models.four_bar(ground=d, crank=a, coupler=b, rocker=c, speed=1.0, branch=1)
    t = np.linspace(0.1, 6.0, 25)
    sol = m.solve(t)
    h = 1e-6
    th4 = sol.angle("rocker")
    br = [1 if abs(wrap(x - freudenstein_output(a, b, c, d, tt, 1))) < 1e-6 else -1
          for x, tt in zip(th4, t)]
    num = np.array([(freudenstein_output(a, b, c, d, tt + h, s)
                     - freudenstein_output(a, b, c, d, tt - h, s)) / (2 * h) for tt, s in zip(t, br)])
    np.testing.assert_allclose(sol.omega("rocker"), num, atol=1e-6)
