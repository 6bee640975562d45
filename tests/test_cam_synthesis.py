r"""The cam-synthesis example (examples/cam_synthesis.py): a roller follower on a spline cam
fitted to a cycloidal rise-dwell-return-dwell law reproduces the law to the spline's
accuracy; and free motion of a cammed model conserves energy.

Pressure angle of a translating roller follower with offset ``e`` (the example uses
``e = 0``). The roller centre is at ``(e, d0 + s)`` in the fixed frame, with
``d0 = sqrt((Rb + rr)^2 - e^2)``; in cam coordinates (cam turned by ``theta``) it is
``p = R(-theta) (e, d0 + s)``, the pitch curve, with tangent
``dp/dtheta = R(-theta) (d0 + s, s' - e)``. The common normal at the contact passes through
the roller centre and is normal to the pitch curve (the profile is its parallel curve), so
in the fixed frame it is ``(s' - e, -(d0 + s))``; the follower moves along ``(0, 1)``, so

    tan(phi) = |s' - e| / (d0 + s)  =  |s' - e| / (sqrt((Rb + rr)^2 - e^2) + s),

``(ds/dtheta) / (Rb + rr + s)`` for a radial follower.

Error bounds. The profile ``P(theta)`` (pitch curve moved by ``rr`` along its normal) is
sampled at ``n`` equally spaced cam angles, every transition of the law among them, and
interpolated by a periodic cubic spline. ``P''`` contains the jerk ``s'''``, which jumps at
the transitions of a cycloidal law, so the interpolation error is not ``O(h^4)`` (a
``C^4`` curve) but measured as about ``h^3`` in the lift (the jump is tangential to the
profile, which the follower does not feel to first order), ``h^2`` in the velocity and
``h`` in the acceleration (one power of ``h`` lost per derivative). Measured with 361
sweep points (max over the revolution, lift relative to the rise H):

    knots   lift/H   ds/dth   d2s/dth2  pressure angle
      25   2.8e-4   3.2e-3   1.0e-1    7.3e-4
      49   1.9e-5   4.1e-4   2.6e-2    1.1e-4
      73   4.7e-6   1.8e-4   1.5e-2    5.2e-5
     145   5.8e-7   4.6e-5   7.1e-3    1.3e-5    (721 points)
     361   3.7e-8   7.3e-6   3.0e-3    2.1e-6    (721 points)

The bounds below are these measurements with a factor of about 2 of margin.
"""

import importlib.util
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T

_spec = importlib.util.spec_from_file_location(
    "cam_synthesis", Path(__file__).resolve().parents[1] / "examples" / "cam_synthesis.py")
cs = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cs)


def test_law_derivatives_match_numerical_differences():
    # the closed-form s' and s'' of the law against central differences of s
    th = np.linspace(0.01, 2 * np.pi - 0.01, 997)
    d = 1e-5
    s, v, a = cs.law(th)
    sp_, _, _ = cs.law(th + d)
    sm, _, _ = cs.law(th - d)
    np.testing.assert_allclose(v, (sp_ - sm) / (2 * d), atol=1e-8)
    vp = cs.law(th + d)[1]
    vm = cs.law(th - d)[1]
    # atol: a difference straddling a transition sees the jump of s''' (about 18): d * 18 / 4
    np.testing.assert_allclose(a, (vp - vm) / (2 * d), atol=1e-4)
    assert s.max() == pytest.approx(cs.H) and s.min() == 0.0


def test_spline_cam_reproduces_the_law_at_49_knots():
    # 49 knots (7.5 degrees apart) keep the test cheap: a spline cam of many knots takes
    # seconds to compile (the table above)
    e = cs.errors(49, 361)
    assert e["lift"] < 4e-5                  # measured 1.9e-5 H
    assert e["velocity"] < 8e-4              # 4.1e-4
    assert e["acceleration"] < 5e-2          # 2.6e-2 (peak of the law: 2 pi H / beta^2 = 1.43)
    assert e["pressure angle"] < 2.5e-4      # 1.1e-4 rad, against the closed form above


def test_contact_parameter_is_the_cam_angle():
    # the profile's knot k is touched at cam angle knot k: the contact parameter follows theta
    th, *_, sol, (_, _, _, _, _) = cs.sweep(49, 361)
    np.testing.assert_allclose(sol.coordinate(cs.A), th, atol=1e-4)


def test_error_falls_with_the_number_of_knots():
    e25, e49 = (cs.errors(n, 361) for n in (25, 49))
    order = {k: np.log(e25[k] / e49[k]) / np.log(2) for k in e25}
    # observed orders (h halves from 25 to 49 knots): lift 3.9, velocity 3.0, acceleration
    # 2.0 (tending to 3, 2, 1 as the knots grow: the table in the module docstring)
    assert 3.0 < order["lift"] < 4.5
    assert order["velocity"] > 1.8
    assert order["acceleration"] > 0.9


def test_example_main_prints_the_table_and_plots(tmp_path, capsys):
    table = cs.main(str(tmp_path / "cam.png"), knot_counts=(25, 49))
    assert set(table) == {25, 49}
    out = capsys.readouterr().out
    assert "knots" in out and "2.84e-04" in out
    assert (tmp_path / "cam.png").stat().st_size > 10_000
    assert (tmp_path / "cam_snapshot.png").stat().st_size > 5_000


def test_periodic_spline_profile_in_a_cam_constraint_compiles():
    # regression: the cam constraints differentiated a periodic spline (its parameter reduced
    # by floor) with plain SymPy, leaving Subs(Derivative(floor)) that crashed the compile
    a = sp.Symbol("a")
    kn = np.linspace(0, 2 * np.pi, 13)
    pts = np.c_[2 * np.cos(kn), 2 * np.sin(kn)]
    pts[-1] = pts[0]
    spl = ms.SplineFit(pts, "closed", knots=kn)
    m = ms.Model2D()
    cam = m.add_body("cam", guess=((0, 0), 0))
    fol = m.add_body("follower", guess=((0, 2.5), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), cam.point(0)))
    m.add(ms.RotationLock1(cam, T))
    m.add(ms.Translate2(m.ground.axis((0, 0), (0, 1)), fol.axis((0, 0), (0, 1))))
    c = m.add(ms.CamToCircle1(cam.point(tuple(spl(a))), (a, np.pi / 2), fol.point(0), -0.5))
    sol = m.solve(np.linspace(0, 2 * np.pi, 9), solution="acceleration")
    y = sol.location(fol.point(0))[:, 1]
    assert np.all(np.abs(y - 2.5) < 5e-3)    # a 12-knot spline of a circle of radius 2
    assert np.all(np.abs(ms.profile_radius(sol, c) - 2) < 0.1)


def test_free_motion_of_a_cam_conserves_energy():
    # an eccentric disc cam (radius R, eccentricity e, inertia J, free to turn) lifts a roller
    # follower of mass mf pressed down by gravity; the cam is started at w0 (15 J, enough to
    # lift the follower over the top, 9.8 J). No friction,
    # so kinetic + potential energy stays constant to the integration tolerance, while energy
    # passes back and forth between cam and follower (the follower rises by 2 e).
    a = sp.Symbol("a")
    R, e, rr, J, mf, w0 = 2.0, 0.5, 0.4, 0.3, 1.0, 10.0
    m = ms.Model2D()
    cam = m.add_body("cam", mass=2.0, centroid=(0, 0), inertia=J, guess=((0, 0), 0))
    fol = m.add_body("follower", mass=mf, centroid=(0, 0), inertia=0.1,
                     guess=((0, R + rr - e), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), cam.point(0)), name="bearing")
    m.add(ms.RotationLock1(cam, 0.0), name="drive")
    m.add(ms.Translate2(m.ground.axis((0, 0), (0, 1)), fol.axis((0, 0), (0, 1))), name="guide")
    m.add(ms.CamToCircle1(cam.point((R * sp.cos(a), -e + R * sp.sin(a))), (a, np.pi / 2),
                          fol.point(0), -rr), name="cam")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    free = m.free(drop=["drive"])
    # the contact parameter's velocity too, consistent with w0 (given cam.th_d alone, the start
    # projection shares the velocity out with a_d and the cam starts slower). The contact lies
    # on the line from the disc's centre e (sin th, -cos th) to the roller's (0, y), at global
    # angle psi = atan2(y + e cos th, -e sin th), so at th = 0 dpsi/dth = e / (y + e) =
    # e / (R + rr), and a = psi - th: a_d = -(1 - e / (R + rr)) w0.
    ad0 = -(1 - e / (R + rr)) * w0
    sol = free.simulate(np.linspace(0, 3, 301), initial_condition={"cam.th_d": w0, "a_d": ad0},
                        rtol=1e-10, atol=1e-12)
    E = sol.body_energy() + sol.potential_energy()
    y = sol.location(fol.point(0))[:, 1]
    assert np.ptp(y) > 0.9                   # the follower really goes up and down (2e = 1)
    assert np.ptp(sol["cam.th"]) > 2 * np.pi  # the cam makes more than a revolution
    # energy at the start: the cam's spin, the follower at rest on its lowest point
    assert sol.coordinate("cam.th", 1)[0] == pytest.approx(w0, rel=1e-12)
    assert E[0] == pytest.approx(0.5 * J * w0**2 + mf * 9.81 * (R + rr - e), rel=1e-9)
    assert np.ptp(E) < 1e-7 * abs(E[0])      # measured 2.7e-10 relative


def test_order_is_limited_by_the_profile_parametrisation():
    # why not h^4: the spline through the profile points P(theta) misses the curve by O(h^2)
    # (its P'' jumps, along the tangent), while the same spline through the pitch curve
    # p(theta) = R(-theta) (e, d0 + s) (only p''' jumps) misses it by O(h^4). Measured:
    # profile 2.5e-4 -> 6.4e-5 (order 1.98), pitch curve 2.4e-5 -> 1.5e-6 (order 4.03).
    def pitch(th):
        s = cs.law(th)[0]
        return np.stack([np.sin(th) * (cs.D0 + s), np.cos(th) * (cs.D0 + s)], axis=-1)

    u = np.linspace(0, 2 * np.pi, 20001)

    def miss(curve, n):
        kn = np.linspace(0, 2 * np.pi, n)
        pts = curve(kn)
        pts[-1] = pts[0]
        spl = ms.SplineFit(pts, "closed", knots=kn)
        return np.abs(spl(u) - curve(u)).max()   # spl(u): (len(u), 2)

    assert cs.E == 0.0                       # pitch() above is the radial case
    order_profile = np.log2(miss(cs.profile_points, 49) / miss(cs.profile_points, 97))
    order_pitch = np.log2(miss(pitch, 49) / miss(pitch, 97))
    assert 1.8 < order_profile < 2.2
    assert 3.8 < order_pitch < 4.3
