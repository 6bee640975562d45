"""CamPlot (Mech 6.1.1) and PitchCircle: cam profiles and gears in pictures."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T
from mechsys import draw as d


def disk_cam():
    m = ms.Model2D()
    e = m.parameter("e", 0.3)
    cam = m.add_body("cam")
    m.add(ms.Revolute2(m.ground.point((0, 0)), cam.point(0)))
    m.add(ms.RotationLock1(cam, 2 * sp.pi * T), name="drive")
    a = sp.Symbol("a")
    r = 1 + e * sp.cos(a)
    return m, cam, a, cam.point((r * sp.cos(a), r * sp.sin(a))), e


def test_profile_points_lie_on_the_rotated_profile():
    m, cam, a, profile, _ = disk_cam()
    sol = m.solve(np.linspace(0, 0.25, 3))
    fr = d.Scene(m, [d.CamPlot(profile, (a, 0, 2 * sp.pi), samples=73)]).evaluate(sol)
    (item,) = fr.items
    assert item.closed                                   # 0 .. 2 pi: the ends meet
    xyz = np.broadcast_to(item.xyz, (len(sol.t),) + item.xyz.shape[1:])
    aa = np.linspace(0, 2 * np.pi, 73)
    for k, th in enumerate(2 * np.pi * sol.t):
        rr = 1 + 0.3 * np.cos(aa)                        # the model's parameter value
        ref = np.c_[rr * np.cos(aa + th), rr * np.sin(aa + th)]
        np.testing.assert_allclose(xyz[k], ref, atol=1e-12)


def test_profile_uses_the_solutions_parameter_values():
    m, cam, a, profile, e = disk_cam()
    m.set_parameters(e=0.1)
    sol = m.solve(0.0)
    (item,) = d.Scene(m, [d.CamPlot(profile, (a, 0, np.pi))]).evaluate(sol).items
    assert not item.closed                               # half a profile stays open
    r = np.hypot(*np.asarray(item.xyz).reshape(-1, 2).T)
    assert np.isclose(r.max(), 1.1) and np.isclose(r.min(), 0.9)


def test_spatial_surface_is_drawn_by_parameter_lines():
    m = ms.Model3D()
    cam = m.add_body("cam")
    m.add(ms.Spherical3(m.ground.point((0, 0, 0)), cam.point(0)))
    m.add(ms.RotationLock3(cam, (1, 0, 0, 0)))
    u, v = sp.symbols("u v")
    surf = cam.point((u, v, 0.2 * u**2))
    sol = m.solve(0.0)
    items = d.Scene(m, [d.CamPlot(surf, (u, -1, 1), (v, -1, 1), samples=13)]).evaluate(sol).items
    assert len(items) == 26
    for it in items:
        p = np.asarray(it.xyz).reshape(-1, 3)
        np.testing.assert_allclose(p[:, 2], 0.2 * p[:, 0] ** 2, atol=1e-12)


def test_camplot_errors_name_the_problem():
    m, cam, a, profile, _ = disk_cam()
    with pytest.raises(ms.ModelError, match="does not depend"):
        d.CamPlot(cam.point((1, 0)), (a, 0, 1))
    with pytest.raises(ms.ModelError, match="low < high"):
        d.CamPlot(profile, (a, 1, 0))
    with pytest.raises(ms.ModelError, match=r"\(symbol, low, high\)"):
        d.CamPlot(profile, a)
    with pytest.raises(ms.ModelError, match="locus point"):
        d.CamPlot((1, 0), (a, 0, 1))
    b = sp.Symbol("b")
    sol = m.solve(0.0)
    with pytest.raises(ms.ModelError, match="neither its parameters"):
        d.Scene(m, [d.CamPlot(cam.point((a * b, a)), (a, 0, 1))]).evaluate(sol)


def test_pitch_circle_turns_with_its_gear():
    m, cam, a, profile, _ = disk_cam()
    sol = m.solve(np.linspace(0, 0.25, 3))
    rim, ticks = d.Scene(m, [d.PitchCircle(cam, 0, 2.0, teeth=12)]).evaluate(sol).items
    rim_xyz = np.broadcast_to(rim.xyz, (3,) + rim.xyz.shape[1:])
    np.testing.assert_allclose(np.hypot(*rim_xyz[1].T), 2.0, atol=1e-12)
    tip = np.broadcast_to(ticks.xyz, (3,) + ticks.xyz.shape[1:])[:, 1]
    th = 2 * np.pi * sol.t
    np.testing.assert_allclose(tip, 2.24 * np.c_[np.cos(th), np.sin(th)], atol=1e-12)
    assert np.isnan(ticks.xyz[0]).any() and ticks.xyz.shape[-2] == 3 * 13
    with pytest.raises(ms.GeometryError, match="radius must be positive"):
        d.PitchCircle(cam, 0, 0.0)
    with pytest.raises(ms.ModelError, match="teeth"):
        d.PitchCircle(cam, 0, 1.0, teeth=2)


def test_pitch_circle_in_3d_lies_normal_to_its_axis():
    m = ms.Model3D()
    g = m.add_body("gear")
    m.add(ms.Spherical3(m.ground.point((0, 0, 0)), g.point(0)))
    m.add(ms.RotationLock3(g, (1, 0, 0, 0)))
    sol = m.solve(0.0)
    rim, ticks = d.Scene(m, [d.PitchCircle(g, (0, 0, 1), 0.5, axis=(1, 0, 0),
                                           mark=(0, 1, 0))]).evaluate(sol).items
    p = np.asarray(rim.xyz).reshape(-1, 3)
    np.testing.assert_allclose(p[:, 0], 0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(p[:, 1], p[:, 2] - 1), 0.5, atol=1e-12)
    np.testing.assert_allclose(np.asarray(ticks.xyz).reshape(-1, 3)[1], [0, 0.56, 1], atol=1e-12)


def _dashed_circles(items, dim):
    out = []
    for it in items:
        if it.kind == "line" and it.style.get("linestyle") == "--":
            out.append(np.asarray(it.xyz).reshape(-1, dim))
    return out


def test_default_drawing_shows_the_pitch_circles_of_a_gear_pair():
    m = ms.Model2D()
    g1 = m.add_body("g1", guess=((0, 0), 0))
    g2 = m.add_body("g2", guess=((3, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), g1.point(0)))
    m.add(ms.Revolute2(m.ground.point((3, 0)), g2.point(0)))
    m.add(ms.TwoGears1(g1.point(0), 1.0, g2.point(0), 2.0, 0.0))
    m.add(ms.RotationLock1(g1, T), name="drive")
    sol = m.solve(0.5)
    circles = _dashed_circles(d.Scene(m).evaluate(sol).items, 2)
    radii = sorted(float(np.hypot(*(c - c.mean(axis=0)).T).mean()) for c in circles)
    np.testing.assert_allclose(radii, [1.0, 2.0], rtol=1e-3)


def test_default_drawing_of_spatial_gears_lies_normal_to_their_axes():
    m = ms.Model3D()
    g1 = m.add_body("g1", guess=((0, 0, 0), (1, 0, 0, 0)))
    g2 = m.add_body("g2", guess=((3, 0, 0), (1, 0, 0, 0)))
    m.add(ms.Revolute5(m.ground.axis((0, 0, 0), (0, 0, 1)), g1.axis(0, (0, 0, 1))))
    m.add(ms.TwoPulleys5(g1.axis(0, (0, 0, 1)), 1.0, g2.axis(0, (0, 0, 1)), 0.5, 3.0, 0.0))
    m.add(ms.RelativeY1(g2.point(0), 0.0))
    m.add(ms.RotationLock1(g1.axis(0, (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)), T),
          name="drive")
    sol = m.solve(0.2)
    circles = _dashed_circles(d.Scene(m).evaluate(sol).items, 3)
    assert len(circles) == 2
    for c in circles:
        np.testing.assert_allclose(c[:, 2], 0.0, atol=1e-12)


def test_default_drawing_of_every_gear_example():
    """Every gear type's default picture builds (LeadScrew5 and OrthogonalGears5 have no
    pitch radius to draw; racks draw their pinion)."""
    import runpy
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "examples"
    for name in ("gear_screw_jack.py", "gear_planetary.py"):
        ns = runpy.run_path(str(root / name))
        m = next(v for v in ns.values() if isinstance(v, ms.Model))
        d.Scene(m).evaluate(m.last_solution)
    r = 0.6
    m = ms.Model3D()
    pinion = m.add_body("pinion")
    rack = m.add_body("rack", guess=((0, -r, 0), (1, 0, 0, 0)))
    m.add(ms.Revolute5(m.ground.axis((0, 0, 0), (0, 0, 1)), pinion.axis(0, (0, 0, 1))))
    m.add(ms.RackAndPinion5(pinion.axis(0, (0, 0, 1), (1, 0, 0)), r, ("a", 0.0),
                            rack.axis(0, (0, 0, 1), (1, 0, 0)), 0.0))
    m.add(ms.RotationLock1(rack.axis(0, (0, 0, 1), (1, 0, 0)),
                           m.ground.axis((0, 0, 0), (0, 0, 1), (1, 0, 0)), 0.0))
    m.add(ms.RotationLock1(pinion.axis(0, (0, 0, 1)), m.ground.axis((0, 0, 0), (0, 0, 1)), T))
    sol = m.solve(0.3)
    circles = _dashed_circles(d.Scene(m).evaluate(sol).items, 3)
    assert len(circles) == 1
    # the pinion's pitch circle: about its axis (z) through the origin
    np.testing.assert_allclose(np.linalg.norm(circles[0], axis=1), r, atol=1e-12)
