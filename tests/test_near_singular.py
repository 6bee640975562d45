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


# -- who is to blame: the guesses or the constraints ------------------------------------------
def _four_bar(guesses: bool):
    m = ms.Model2D()
    g = m.ground
    kw = {"crank": {"guess": ((0, 0), 0.6)}, "rocker": {"guess": ((4, 0), 1.9)}} if guesses else {
        "crank": {}, "rocker": {}}
    cr = m.add_body("crank", points={"tip": (1, 0)}, **kw["crank"])
    ro = m.add_body("rocker", points={"tip": (3, 0)}, **kw["rocker"])
    m.add(ms.Revolute2(g.point((0, 0)), cr.point(0)), name="crank pivot")
    m.add(ms.Revolute2(g.point((4, 0)), ro.point(0)), name="rocker pivot")
    m.add(ms.RelativeDistance1(cr.point("tip"), ro.point("tip"), 4), name="coupler")
    m.add(ms.RotationLock1(cr, 0.6 + T), name="drive")
    return m


def test_four_bar_without_guesses_blames_the_guesses():
    """All bodies at the origin without rotation: the Jacobian is singular there, but the
    constraints are independent. Before: 'Dependent equations come from: rocker pivot'."""
    m = _four_bar(guesses=False)
    with pytest.raises(ms.SingularJacobianError,
                       match=r"initial guesses put the mechanism in a singular configuration.*"
                             r"give guesses for bodies 'crank', 'rocker'") as err:
        m.solve(0.0)
    assert err.value.dependent == [] and err.value.time == 0.0
    dof = m.dof()
    assert int(dof) == 0 and dof.rank == 6 and dof.redundant == []
    assert "give guesses for bodies 'crank', 'rocker'" in repr(dof)
    # with guesses it solves, and the same model reports no redundancy
    sol = _four_bar(guesses=True).solve(0.0)
    assert abs(sol["crank.th"] - 0.6) < 1e-12


def test_redundant_spatial_four_bar_names_the_dependent_equations():
    """Four parallel Revolute5 joints: 3 equations are dependent. The report gives that number
    and the equations, and does not advise removing whole joints (10 equations)."""
    m = ms.Model3D()
    g = m.ground
    z = (0, 0, 1)
    a = m.add_body("crank", points={"tip": (1, 0, 0)}, guess=((0, 0, 0), (1, 0, 0, 0)))
    c = m.add_body("coupler", points={"end": (4, 0, 0)}, guess=((1, 0, 0), (-0.3, z)))
    r = m.add_body("rocker", points={"tip": (3, 0, 0)}, guess=((4, 0, 0), (1.9, z)))
    m.add(ms.Revolute5(a.axis(0, z), g.axis((0, 0, 0), z)), name="A")
    m.add(ms.Revolute5(a.axis("tip", z), c.axis(0, z)), name="B")
    m.add(ms.Revolute5(c.axis("end", z), r.axis("tip", z)), name="C")
    m.add(ms.Revolute5(r.axis(0, z), g.axis((4, 0, 0), z)), name="D")
    m.add(ms.RotationLock1(a.axis(0, z), g.axis((0, 0, 0), z), T), name="drive")
    # consistent, so (issue 12) solved as Adams does, with the report as a warning
    with pytest.warns(ms.RedundantConstraintWarning) as rec:
        m.solve(0.0)
    msg = str(rec[0].message)
    assert "(rank 21 of 24 equations, 21 coordinates). 3 dependent equation(s): equation" in msg
    for name in "ABCD":
        assert f"constraint '{name}'" in msg
    assert "Remove them" not in msg


def test_genuine_toggle_at_the_guess_is_not_blamed_on_the_guess():
    """The crank's guess is the default (origin, no rotation) but the guess is assembled: the
    singularity is the mechanism's (a dead centre), so the constraints are named."""
    m = piston_driven(0.0)
    m.set_guess({"crank.th": 0.0, "rod.th": 0.0, "rod.x": 2.0, "rod.y": 0.0, "piston.x": 8.0})
    with pytest.raises(ms.SingularJacobianError, match=r"singular at t = 0 .*'piston drive'") as e:
        m.solve(0.0)
    assert "initial guesses" not in str(e.value)
