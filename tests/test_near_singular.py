"""Sweeps that pass close to a toggle position warn, with the time and the conditioning."""

import warnings

import numpy as np
import pytest

import mechsys as ms
from mechsys import T, models


def piston_driven(delta):
    """Slider-crank (crank 2, rod 6) driven at the piston from ``delta`` short of the dead
    centre x = 8, moving away from it; the guess is the exact upper-branch assembly."""
    m = models.slider_crank()
    m.remove("drive")
    x0 = 8.0 - delta
    m.add(ms.RelativeX1(m.body("piston").point(0), x0 - T), name="piston drive")
    th = np.arccos((x0**2 + 4 - 36) / (4 * x0))          # law of cosines for the crank angle
    phi = np.arcsin(-2 * np.sin(th) / 6)
    m.set_guess({"crank.th": th, "rod.th": phi, "rod.x": 2 * np.cos(th),
                 "rod.y": 2 * np.sin(th), "piston.x": x0})
    return m


def test_close_to_dead_centre_warns():
    m = piston_driven(1e-12)
    with pytest.warns(ms.NearSingularWarning, match=r"first at t = 0 .*toggle"):
        sol = m.solve(np.linspace(0, 0.5, 6))
    assert sol.extra["rcond"][0] < 1e-6
    assert sol.extra["rcond"][-1] > 1e-3
    assert np.abs(sol.qd[0]).max() > 1e4                   # what the warning is about


def test_well_conditioned_sweep_is_silent():
    m = models.slider_crank()
    with warnings.catch_warnings():
        warnings.simplefilter("error", ms.NearSingularWarning)
        sol = m.solve(np.linspace(0, 1, 37))
    assert np.all(sol.extra["rcond"] > 1e-4)
