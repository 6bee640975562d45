"""Cam constraints (Mech manual 6.1) against closed forms, and their bad-input errors.

Every mechanism is driven by its cam angle; the follower's motion is compared with the
classical cam formulas worked out by hand (not from the constraint equations).
"""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T

a, b, g, d = sp.symbols("a b g d")
Z = (0, 0, 1)


# -- 2D ---------------------------------------------------------------------------------------


def _cam_2d(drive, follower_guess, slide_dir=(0, 1)):
    """A cam turning about the origin by ``drive`` and a follower translating along
    ``slide_dir`` through the origin (without turning)."""
    m = ms.Model2D()
    cam = m.add_body("cam", guess=((0, 0), 0))
    fol = m.add_body("follower", guess=(follower_guess, 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), cam.point(0)), name="bearing")
    m.add(ms.RotationLock1(cam, drive), name="drive")
    m.add(ms.Translate2(m.ground.axis((0, 0), slide_dir), fol.axis((0, 0), slide_dir)), name="guide")
    return m, cam, fol


def test_eccentric_cam_flat_follower_lift_is_e_one_minus_cos():
    R, e = 2.0, 0.5
    m, cam, fol = _cam_2d(T, (0, R - e))
    # a circle of radius R centred e below the cam's axis; the flat face is the follower's x axis
    m.add(ms.CamToLine1(cam.point((R * sp.cos(a), -e + R * sp.sin(a))), (a, np.pi / 2),
                        fol.axis((0, 0), (1, 0))), name="cam")
    assert m.dof() == 0
    th = np.linspace(0, 2 * np.pi, 37)
    sol = m.solve(th, solution="acceleration")
    lift = sol.location(fol.point(0))[:, 1] - (R - e)
    np.testing.assert_allclose(lift, e * (1 - np.cos(th)), atol=1e-12)
    np.testing.assert_allclose(sol.velocity(fol.point(0))[:, 1], e * np.sin(th), atol=1e-12)
    np.testing.assert_allclose(sol.acceleration(fol.point(0))[:, 1], e * np.cos(th), atol=1e-12)
    # the contact is the top of the circle: local angle pi/2 - th (unwrapped)
    np.testing.assert_allclose(sol.coordinate(a), np.pi / 2 - th, atol=1e-10)


def test_radial_point_follower_follows_r_of_theta_over_a_revolution():
    def r(x):
        return 2 + 0.4 * np.sin(x) + 0.2 * np.cos(3 * x)

    rs = 2 + 0.4 * sp.sin(a) + 0.2 * sp.cos(3 * a)
    # the cam turns clockwise, so the profile point at cam angle th passes the +x axis
    m, cam, fol = _cam_2d(-T, (r(0), 0), slide_dir=(1, 0))
    m.add(ms.CamToPoint1(cam.point((rs * sp.cos(a), rs * sp.sin(a))), (a, 0.0), fol.point(0)))
    th = np.linspace(0, 2 * np.pi, 73)
    sol = m.solve(th, solution="velocity")
    np.testing.assert_allclose(sol.location(fol.point(0))[:, 0], r(th), atol=1e-12)
    drdth = 0.4 * np.cos(th) - 0.6 * np.sin(3 * th)
    np.testing.assert_allclose(sol.velocity(fol.point(0))[:, 0], drdth, atol=1e-11)


@pytest.mark.parametrize("sign", [-1, 1], ids=["outside", "inside"])
def test_roller_follower_on_circular_cam_side_from_sign_of_radius(sign):
    Rc, e, rho = 2.0, 0.6, 0.5
    # the profile runs counterclockwise, so its left is the inside: radius < 0 puts the roller
    # outside the circle (distance Rc + rho from its centre), radius > 0 inside (Rc - rho)
    dist = Rc - sign * rho
    m, cam, fol = _cam_2d(T, (0, np.sqrt(dist**2 - e**2)))
    m.add(ms.CamToCircle1(cam.point((e + Rc * sp.cos(a), Rc * sp.sin(a))), (a, np.pi / 2),
                          fol.point(0), sign * rho))
    th = np.linspace(0, 2 * np.pi, 49)
    sol = m.solve(th, solution="acceleration")
    y = sol.location(fol.point(0))[:, 1]
    # the circle's centre is at e (cos th, sin th); the roller centre on the y axis
    y_exact = e * np.sin(th) + np.sqrt(dist**2 - (e * np.cos(th)) ** 2)
    np.testing.assert_allclose(y, y_exact, atol=1e-12)
    h = 1e-4  # velocity of the closed form by central differences
    dy = (e * np.sin(th + h) + np.sqrt(dist**2 - (e * np.cos(th + h)) ** 2)
          - e * np.sin(th - h) - np.sqrt(dist**2 - (e * np.cos(th - h)) ** 2)) / (2 * h)
    np.testing.assert_allclose(sol.velocity(fol.point(0))[:, 1], dy, atol=1e-7)


def test_cam_to_cam_2d_two_discs_keep_touching():
    # two circular discs: the driven one eccentric, the other follower disc translating on y
    R1, e, R2 = 1.5, 0.4, 0.7
    m, cam, fol = _cam_2d(T, (0, R1 + R2 - e))
    m.add(ms.CamToCam1(cam.point((R1 * sp.cos(a), -e + R1 * sp.sin(a))), (a, np.pi / 2),
                       fol.point((R2 * sp.cos(b), R2 * sp.sin(b))), (b, -np.pi / 2)))
    th = np.linspace(0, 2 * np.pi, 25)
    sol = m.solve(th)
    # centres e (sin th, -cos th) and (0, y): |distance| = R1 + R2
    y = sol.location(fol.point(0))[:, 1]
    y_exact = -e * np.cos(th) + np.sqrt((R1 + R2) ** 2 - (e * np.sin(th)) ** 2)
    np.testing.assert_allclose(y, y_exact, atol=1e-12)


# -- 3D ---------------------------------------------------------------------------------------


def _cam_3d(follower_guess, height=0.0, slide=(1, 0, 0)):
    """A cam turning about the global Z axis by T and a follower translating along ``slide``
    through ``(0, 0, height)``."""
    m = ms.Model3D()
    cam = m.add_body("cam")
    fol = m.add_body("follower", guess=(follower_guess, (1, 0, 0, 0)))
    m.add(ms.Revolute5(cam.axis(0, Z), m.ground.axis((0, 0, 0), Z)), name="bearing")
    m.add(ms.RotationLock1(cam.axis(0, Z), m.ground.axis((0, 0, 0), Z), T), name="drive")
    m.add(ms.Translate5(fol.axis(0, slide), m.ground.axis((0, 0, height), slide)), name="guide")
    return m, cam, fol


#: an eccentric drum: a cylinder of radius 2 about the cam's (0.5, 0) parallel to Z
RD, ED = 2.0, 0.5
DRUM = (ED + RD * sp.cos(a), RD * sp.sin(a), b)
TH = np.linspace(0, 2 * np.pi, 25)


def test_3d_point_follower_on_a_drum():
    m, cam, fol = _cam_3d((RD + ED, 0, 0.3), height=0.3)
    m.add(ms.CamToPoint1(cam.point(DRUM), (a, 0.0), (b, 0.3), fol.point(0)))
    sol = m.solve(TH)
    # the drum's axis is at ED (cos th, sin th): the follower on the x axis is where
    # (x - ED cos th)^2 + (ED sin th)^2 = RD^2
    x_exact = ED * np.cos(TH) + np.sqrt(RD**2 - (ED * np.sin(TH)) ** 2)
    np.testing.assert_allclose(sol.location(fol.point(0))[:, 0], x_exact, atol=1e-12)
    np.testing.assert_allclose(sol.coordinate(b), 0.3, atol=1e-12)


@pytest.mark.parametrize("kind", ["CamToSphere1", "CamToCam1"])
def test_3d_spherical_follower_on_a_drum(kind):
    rho = 0.4
    m, cam, fol = _cam_3d((RD + ED + rho, 0, 0.2), height=0.2)
    if kind == "CamToSphere1":  # t_a x t_b is the drum's outward normal: radius > 0 outside
        m.add(ms.CamToSphere1(cam.point(DRUM), (a, 0.0), (b, 0.2), fol.point(0), rho))
    else:  # the ball as a surface of the follower
        ball = (rho * sp.cos(g) * sp.cos(d), rho * sp.sin(g) * sp.cos(d), rho * sp.sin(d))
        m.add(ms.CamToCam1(cam.point(DRUM), (a, 0.0), (b, 0.2), fol.point(ball), (g, np.pi), (d, 0.0)))
    sol = m.solve(TH, solution="acceleration")
    x_exact = ED * np.cos(TH) + np.sqrt((RD + rho) ** 2 - (ED * np.sin(TH)) ** 2)
    np.testing.assert_allclose(sol.location(fol.point(0))[:, 0], x_exact, atol=1e-12)


@pytest.mark.parametrize("kind", ["CamToPlane1", "CurveToCam1", "CurveToPlane1"])
def test_3d_flat_follower_on_an_eccentric_drum(kind):
    m, cam, fol = _cam_3d((RD + ED, 0, 0))
    if kind == "CamToPlane1":  # an eccentric ball (a drum would touch along a line) against
        # the follower's face, the plane x = 0 of its body
        ball = (ED + RD * sp.cos(a) * sp.cos(b), RD * sp.sin(a) * sp.cos(b), RD * sp.sin(b))
        m.add(ms.CamToPlane1(cam.point(ball), (a, 0.0), (b, 0.1), fol.axis(0, (1, 0, 0))))
    elif kind == "CurveToCam1":  # the drum's rim (a circle at z = 0.1) against the face as a
        # surface (0, g, d)
        rim = (ED + RD * sp.cos(a), RD * sp.sin(a), 0.1)
        m.add(ms.CurveToCam1(cam.point(rim), (a, 0.0), fol.point((0, g, d)), (g, 0.0), (d, 0.1)))
    else:  # the rim against the face as a plane
        rim = (ED + RD * sp.cos(a), RD * sp.sin(a), 0.1)
        m.add(ms.CurveToPlane1(cam.point(rim), (a, 0.0), fol.axis(0, (1, 0, 0))))
    sol = m.solve(TH, solution="acceleration")
    np.testing.assert_allclose(sol.location(fol.point(0))[:, 0], RD + ED * np.cos(TH), atol=1e-12)
    np.testing.assert_allclose(sol.velocity(fol.point(0))[:, 0], -ED * np.sin(TH), atol=1e-12)
    np.testing.assert_allclose(sol.acceleration(fol.point(0))[:, 0], -ED * np.cos(TH), atol=1e-12)


def test_3d_rim_against_a_roller_with_a_parallel_axis():
    # CurveToCylinder1: the rim of the eccentric drum (a circle in z = 0) against a roller
    # of radius rho whose axis is parallel to Z through the follower's origin
    rho = 0.3
    m, cam, fol = _cam_3d((RD + ED + rho, 0, 0))
    rim = (ED + RD * sp.cos(a), RD * sp.sin(a), 0)
    m.add(ms.CurveToCylinder1(cam.point(rim), (a, 0.0), fol.axis(0, Z), rho))
    sol = m.solve(TH, solution="velocity")
    x_exact = ED * np.cos(TH) + np.sqrt((RD + rho) ** 2 - (ED * np.sin(TH)) ** 2)
    np.testing.assert_allclose(sol.location(fol.point(0))[:, 0], x_exact, atol=1e-12)


def test_3d_point_in_a_helical_slot_moves_by_the_lead():
    R, p = 1.0, 0.3  # helix radius and rise per radian
    m = ms.Model3D()
    cam = m.add_body("cam")
    fol = m.add_body("follower", guess=((R, 0, 0), (1, 0, 0, 0)))
    m.add(ms.Revolute5(cam.axis(0, Z), m.ground.axis((0, 0, 0), Z)), name="bearing")
    m.add(ms.RotationLock1(cam.axis(0, Z), m.ground.axis((0, 0, 0), Z), T), name="drive")
    # the follower keeps its orientation and stays in the plane y = 0: x and z are free
    m.add(ms.RotationLock3(fol))
    m.add(ms.RelativeY1(fol.point(0), 0))
    c = m.add(ms.CurveToPoint2(cam.point((R * sp.cos(a), R * sp.sin(a), p * a)), (a, 0.0), fol.point(0)))
    assert c.count_removed(m.space) == 2 and m.dof() == 0
    sol = m.solve(TH, solution="velocity")
    # the slot point in y = 0 has global angle a + th = 0: x = R, z = p a = -p th
    np.testing.assert_allclose(sol.location(fol.point(0))[:, 0], R, atol=1e-12)
    np.testing.assert_allclose(sol.location(fol.point(0))[:, 2], -p * TH, atol=1e-12)
    np.testing.assert_allclose(sol.velocity(fol.point(0))[:, 2], -p, atol=1e-12)


# -- bad input --------------------------------------------------------------------------------


def test_profile_not_depending_on_its_parameter_is_named():
    m = ms.Model2D()
    cam = m.add_body("cam")
    with pytest.raises(ms.GeometryError, match=r"CamToPoint1.*does not depend on its parameter 'a'"):
        ms.CamToPoint1(cam.point((1.0, b)), (a, 0.0), m.ground.point((0, 0)))


@pytest.mark.parametrize("kind", ["CamToCircle1", "CamToSphere1"])
def test_zero_radius_is_refused(kind):
    m = ms.Model2D()
    cam = m.add_body("cam")
    with pytest.raises(ms.GeometryError, match=rf"{kind}: radius must be a nonzero"):
        getattr(ms, kind)(cam.point((sp.cos(a), sp.sin(a))), (a, 0.0), (0, 0), 0)


@pytest.mark.parametrize("radius", [-1.0, 0])
def test_cylinder_radius_must_be_positive(radius):
    m = ms.Model3D()
    cam = m.add_body("cam")
    with pytest.raises(ms.GeometryError, match=r"CurveToCylinder1: the cylinder's radius must be positive"):
        ms.CurveToCylinder1(cam.point((sp.cos(a), sp.sin(a), 0)), (a, 0.0), m.ground.axis(0, Z), radius)


def test_wrong_number_of_parameters_for_the_model_is_named():
    m = ms.Model3D()
    cam = m.add_body("cam")
    c = ms.CamToPoint1(cam.point((sp.cos(a), sp.sin(a), 0)), (a, 0.0), (0, 0, 0))
    with pytest.raises(ms.ModelError, match=r"CamToPoint1.*3D model the profile is a surface of 2"):
        m.add(c)


def test_wrong_kind_of_model_is_named():
    m = ms.Model2D()
    cam = m.add_body("cam")
    with pytest.raises(ms.ModelError, match=r"CamToSphere1.*spatial"):
        m.add(ms.CamToSphere1(cam.point((sp.cos(a), sp.sin(a))), (a, 0.0), (0, 0), 1.0))


def test_follower_that_would_leave_the_profile_names_the_constraint_and_how_far():
    # a point follower held 1.5 from the centre of a cam circle of radius 1: no assembly
    m = ms.Model2D()
    cam = m.add_body("cam", guess=((0, 0), 0))
    fol = m.add_body("follower", guess=((1, 0), 0))
    m.add(ms.OriginLock2(cam))
    m.add(ms.RotationLock1(cam, 0))
    m.add(ms.RotationLock1(fol, 0))
    m.add(ms.RelativeDistance1(fol.point(0), m.ground.point((0, 0)), 1.5), name="arm")
    m.add(ms.CamToPoint1(cam.point((sp.cos(a), sp.sin(a))), (a, 0.3), fol.point(0)), name="cam")
    assert m.dof() == 0
    with pytest.raises(ms.ConvergenceError) as err:
        m.solve(0.0)
    msg = str(err.value)
    assert "constraint 'cam' (CamToPoint1, number 5), equation" in msg
    assert "did not converge" in msg and "max residual" in msg


# -- outputs: pressure angle and radius of curvature ------------------------------------------


def _roller_on_eccentric_circle(Rc=2.0, e=0.6, rho=0.5):
    m, cam, fol = _cam_2d(T, (0, np.sqrt((Rc + rho) ** 2 - e**2)))
    c = m.add(ms.CamToCircle1(cam.point((e + Rc * sp.cos(a), Rc * sp.sin(a))), (a, np.pi / 2),
                              fol.point(0), -rho), name="roller")
    return m, fol, c


def test_pressure_angle_of_a_roller_on_an_eccentric_circle():
    Rc, e, rho = 2.0, 0.6, 0.5
    m, fol, c = _roller_on_eccentric_circle(Rc, e, rho)
    th = np.linspace(0, 2 * np.pi, 37)
    sol = m.solve(th, solution="velocity")
    # the force acts along the line of centres: sin(phi) = e |cos th| / (Rc + rho)
    exact = np.arcsin(e * np.abs(np.cos(th)) / (Rc + rho))
    np.testing.assert_allclose(ms.pressure_angle(sol, "roller", direction=(0, 1)), exact, atol=1e-12)
    # by default the direction is the roller centre's velocity (undefined where it stops)
    moving = np.abs(np.cos(th)) > 1e-3
    phi = ms.pressure_angle(sol, c)
    np.testing.assert_allclose(phi[moving], exact[moving], atol=1e-9)
    # the model gives the symbolic expression
    assert isinstance(ms.pressure_angle(m, c, (0, 1)), sp.Expr)


def test_flat_faced_follower_has_zero_pressure_angle_and_needs_a_direction():
    R, e = 2.0, 0.5
    m, cam, fol = _cam_2d(T, (0, R - e))
    c = m.add(ms.CamToLine1(cam.point((R * sp.cos(a), -e + R * sp.sin(a))), (a, np.pi / 2),
                            fol.axis((0, 0), (1, 0))))
    sol = m.solve(np.linspace(0, 6, 7))
    np.testing.assert_allclose(ms.pressure_angle(sol, c, fol.vector((0, 1))), 0, atol=1e-12)
    with pytest.raises(ms.MechError, match=r"CamToLine1.*give the follower's direction of motion"):
        ms.pressure_angle(sol, c)


def test_profile_radius_of_curvature_ellipse_circle_and_helix():
    A, B = 2.0, 1.2
    m = ms.Model2D()
    cam = m.add_body("cam", guess=((0, 0), 0))
    fol = m.add_body("follower", guess=((A, 0), 0))
    m.add(ms.OriginLock2(cam))
    m.add(ms.RotationLock1(cam, -T))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), fol.axis((0, 0), (1, 0))))
    c = m.add(ms.CamToPoint1(cam.point((A * sp.cos(a), B * sp.sin(a))), (a, 0.0), fol.point(0)))
    sol = m.solve(np.linspace(0, 3, 13))
    al = sol.coordinate(a)
    exact = (A**2 * np.sin(al) ** 2 + B**2 * np.cos(al) ** 2) ** 1.5 / (A * B)
    np.testing.assert_allclose(ms.profile_radius(sol, c), exact, rtol=1e-12)
    np.testing.assert_allclose(exact[0], B**2 / A)  # the vertex on the major axis

    m2, fol2, c2 = _roller_on_eccentric_circle(Rc=2.0)
    np.testing.assert_allclose(ms.profile_radius(m2.solve([0.0, 1.0]), c2), 2.0, rtol=1e-12)

    R, p = 1.5, 0.4  # a helix: rho = (R^2 + p^2) / R
    m3 = ms.Model3D()
    cam3 = m3.add_body("cam")
    c3 = ms.CurveToPoint2(cam3.point((R * sp.cos(a), R * sp.sin(a), p * a)), (a, 0.0), (0, 0, 0))
    m3.add(c3)
    rho = ms.profile_radius(m3, c3)  # symbolic in the parameter, constant along a helix
    np.testing.assert_allclose(float(sp.simplify(rho)), (R**2 + p**2) / R, rtol=1e-12)


def test_profile_radius_of_a_surface_is_refused():
    m = ms.Model3D()
    cam = m.add_body("cam")
    c = m.add(ms.CamToPoint1(cam.point((a, b, a * b)), (a, 0.0), (b, 0.0), (0, 0, 0)))
    with pytest.raises(ms.MechError, match=r"CamToPoint1.*surface, which has two principal"):
        ms.profile_radius(m, c)
    with pytest.raises(ms.MechError, match="not a cam constraint"):
        ms.profile_radius(m, m.add(ms.RotationLock3(cam)))


def test_bad_parameter_pairs_are_named():
    m = ms.Model2D()
    cam = m.add_body("cam")
    circle = cam.point((sp.cos(a), sp.sin(a)))
    with pytest.raises(ms.ModelError, match=r"CamToPoint1: a cam parameter is a \(symbol, guess\) pair"):
        ms.CamToPoint1(circle, (1.0, 0.3), (0, 0))
    with pytest.raises(ms.ModelError, match=r"CamToCam1: each profile parameter needs its own symbol"):
        ms.CamToCam1(circle, (a, 0.0), cam.point((2 * sp.cos(a), sp.sin(a))), (a, 1.0))
    # the radius forgotten: not read as a profile without parameters and a symbolic point
    with pytest.raises(ms.ModelError, match=r"CamToCircle1: expected CamToCircle1\(.*point, radius\), got 3"):
        ms.CamToCircle1(circle, (a, 0.0), (0, 0))


def test_static_cam_contact_force_is_along_the_common_normal():
    """A flat follower pressed down by W on an eccentric cam: the contact force is W along the
    face's normal through the contact point, and the cam's driving torque is W e sin(th),
    which is virtual work: W d(lift)/d(th)."""
    R, e, W = 2.0, 0.5, 3.0
    m, cam, fol = _cam_2d(T, (0, R - e))
    locus = cam.point((R * sp.cos(a), -e + R * sp.sin(a)))
    m.add(ms.CamToLine1(locus, (a, np.pi / 2), fol.axis((0, 0), (1, 0))), name="cam")
    m.add_load(ms.Force(fol.point(0), (0, -1), W))
    th = np.linspace(0, 2 * np.pi, 13)
    st = m.solve(th, solution="static")
    F, M = st.reaction("cam", fol, at=locus)
    np.testing.assert_allclose(F, np.c_[0 * th, W + 0 * th], atol=1e-10)
    np.testing.assert_allclose(M, 0, atol=1e-10)        # no couple about the contact point
    np.testing.assert_allclose(st.reaction("drive", cam)[1], W * e * np.sin(th), atol=1e-10)
