"""Slider-crank against its closed form (position, velocity, acceleration of the piston)."""

import numpy as np
import pytest

from mechsys import models


def closed_form(r, L, e, w, t):
    """Piston x for crank r, rod L, offset e (slider line y = e), crank angle w t."""
    th = w * t
    s = e - r * np.sin(th)
    root = np.sqrt(L**2 - s**2)
    x = r * np.cos(th) + root
    # derivatives by the chain rule on th (w constant)
    ds = -r * np.cos(th) * w
    dds = r * np.sin(th) * w**2
    droot = -s * ds / root
    ddroot = -(ds**2 + s * dds) / root - s**2 * ds**2 / root**3
    v = -r * np.sin(th) * w + droot
    a = -r * np.cos(th) * w**2 + ddroot
    return x, v, a


@pytest.mark.parametrize("offset", [0.0, 0.8, -1.1])
def test_piston_matches_closed_form(offset):
    r, L, w = 2.0, 6.0, 2 * np.pi
    m = models.slider_crank(crank=r, rod=L, offset=offset, speed=w)
    t = np.linspace(0, 1, 73)
    sol = m.solve(t)
    p = m.body("piston").point(0)
    x, v, a = closed_form(r, L, offset, w, t)
    np.testing.assert_allclose(sol.location(p)[:, 0], x, atol=1e-9)
    np.testing.assert_allclose(sol.location(p)[:, 1], offset, atol=1e-9)
    np.testing.assert_allclose(sol.velocity(p)[:, 0], v, atol=1e-9)
    np.testing.assert_allclose(sol.acceleration(p)[:, 0], a, atol=1e-8)
    # the crank pin moves on its circle
    pin = sol.location(m.body("crank").point("pin"))
    np.testing.assert_allclose(np.hypot(pin[:, 0], pin[:, 1]), r, atol=1e-12)


def test_symbolic_outputs_agree_with_numeric():
    m = models.slider_crank()
    p = m.body("piston").point(0)
    sol = m.solve(0.1)
    expr = m.velocity(p)[0]
    assert np.isclose(sol.eval(expr), sol.velocity(p)[0])
    assert sol.location(p).shape == (2,)


def test_rod_angular_quantities_and_instant_center():
    r, L, w = 2.0, 6.0, 2 * np.pi
    m = models.slider_crank(crank=r, rod=L, speed=w)
    t = np.linspace(0.01, 0.99, 41)
    sol = m.solve(t)
    th = w * t
    phi = np.arcsin(-r * np.sin(th) / L)          # rod angle (from crank pin to piston)
    np.testing.assert_allclose(sol.angle("rod"), phi, atol=1e-10)
    dphi = -r * np.cos(th) * w / (L * np.cos(phi))
    np.testing.assert_allclose(sol.omega("rod"), dphi, atol=1e-9)
    # instant centre: the crank pin's velocity is perpendicular to (pin - IC) and the
    # piston's velocity to (piston - IC)
    ic = sol.instant_center("rod")
    pin = sol.location(m.body("crank").point("pin"))
    vpin = sol.velocity(m.body("crank").point("pin"))
    np.testing.assert_allclose(np.einsum("ij,ij->i", pin - ic, vpin), 0, atol=1e-8)
    piston = sol.location(m.body("piston").point(0))
    ic_x_expected = piston[:, 0]  # piston moves along x, so IC lies on its vertical
    np.testing.assert_allclose(ic[:, 0], ic_x_expected, atol=1e-8)


def test_solution_orders_and_named_access():
    m = models.slider_crank()
    sol = m.solve([0.0, 0.1], solution="location")
    assert sol.qd is None and sol.qdd is None
    with pytest.raises(Exception, match="no velocity data"):
        sol.velocity(m.body("piston").point(0))
    np.testing.assert_allclose(sol["piston.x"], sol["x4"])
    sol = m.solve([0.0, 0.1], solution="velocity")
    assert sol.qd is not None and sol.qdd is None


def test_interpolation_is_hermite_accurate():
    m = models.slider_crank()
    coarse = m.solve(np.linspace(0, 1, 121))
    fine_t = np.linspace(0.003, 0.997, 57)
    exact = m.solve(fine_t)
    interp = coarse.interpolate(fine_t)
    np.testing.assert_allclose(interp["piston.x"], exact["piston.x"], atol=2e-5)
    np.testing.assert_allclose(interp.coordinate("piston.x", 1), exact.coordinate("piston.x", 1),
                               atol=2e-3)


def test_dataframe_columns():
    pd = pytest.importorskip("pandas")
    m = models.slider_crank()
    df = m.solve(np.linspace(0, 1, 5)).to_dataframe()
    assert isinstance(df, pd.DataFrame)
    assert {"t", "piston.x", "piston.x_d", "piston.x_dd"} <= set(df.columns)
    assert len(df) == 5
