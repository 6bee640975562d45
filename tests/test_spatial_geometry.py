"""3D geometry (reference-direction rules, Plane, Line), body guesses in every Mech format,
angular velocity in global and local axes, the instant screw axis, and 3D input errors."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T


def rand_units(n, seed=0):
    v = np.random.default_rng(seed).standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


# -- reference directions --------------------------------------------------------------------


def test_default_reference_rule_is_unit_perpendicular_for_every_direction():
    dirs = np.vstack([rand_units(500), np.eye(3), -np.eye(3), [[1e-17, 0, -1], [0, 1e-9, -1]]])
    for u in dirs:
        g = ms.reference_direction(u)
        assert np.isclose(np.linalg.norm(g), 1, atol=1e-14)
        assert abs(g @ u) < 1e-14
    np.testing.assert_allclose(ms.reference_direction((0, 0, 1)), [1, 0, 0])
    np.testing.assert_allclose(ms.reference_direction((0, 0, -5)), [1, 0, 0])
    np.testing.assert_allclose(ms.reference_direction((2, 0, 0)), [0, 0, -1])


def test_reference_rules_are_continuous_within_a_hemisphere():
    # a path of directions in the lower hemisphere ending at -Z: smooth for the default
    # rule; the minimal-rotation rule (from +Z) is singular there
    s = np.linspace(0.0, 1.0, 201)
    path = np.column_stack([np.sin(1.5 * (1 - s)) * 0.6, np.sin(1.5 * (1 - s)) * 0.8,
                            -np.cos(1.5 * (1 - s))])
    g = np.array([ms.reference_direction(u) for u in path])
    assert np.abs(np.diff(g, axis=0)).max() < 0.02
    with pytest.raises(ms.GeometryError, match="singular for an axis along -Z"):
        ms.reference_direction((0, 0, -1), "minimal")
    # the two rules agree on the upper hemisphere
    for u in rand_units(50, 1):
        u[2] = abs(u[2])
        np.testing.assert_allclose(ms.reference_direction(u, "minimal"),
                                   ms.reference_direction(u), atol=1e-15)


def test_symbolic_reference_rule_matches_numeric():
    x, y, z = sp.symbols("x y z", real=True)
    g = ms.reference_direction((x, y, z))
    for u in rand_units(20, 2):
        gn = np.array(g.subs(dict(zip((x, y, z), u))), dtype=float).ravel()
        np.testing.assert_allclose(gn, ms.reference_direction(u), atol=1e-14)


def test_axis_reference_is_body_fixed_projected_and_rule_selectable():
    m = ms.Model3D()
    b = m.add_body("b")
    ax = b.axis(0, (0, 0, 2), (1, 0, 1))               # not perpendicular: projected
    g = ax.reference_vector()
    assert g.body is b
    np.testing.assert_allclose(np.array(g.local, dtype=float).ravel(), [1, 0, 0])
    low = (0.3, 0.2, -0.9)
    np.testing.assert_allclose(
        np.array(b.axis(0, low, "minimal").reference_vector().local, dtype=float).ravel(),
        ms.reference_direction(low, "minimal"))
    with pytest.raises(ms.GeometryError, match="parallel to the axis direction"):
        b.axis(0, (0, 0, 1), (0, 0, 3)).reference_vector()
    with pytest.raises(ms.GeometryError, match="reference must be a vector or one of"):
        ms.Axis((0, 0, 0), (0, 0, 1), "nearest")


def test_line_on_one_body_is_body_fixed():
    m = ms.Model3D()
    b = m.add_body("b", points={"a": (1, 0, 0), "c": (3, 0, 0)})
    line = b.line("a", "c")
    assert line.dir.body is b and line.dir.is_local_constant()
    np.testing.assert_allclose(np.array(line.dir.local, dtype=float).ravel(), [2, 0, 0])
    with pytest.raises(ms.GeometryError, match="two points coincide on body 'b'"):
        b.line("a", "a")


def test_plane_origin_normal_and_reference():
    m = ms.Model3D()
    b = m.add_body("b", points={"p": (1, 1, 0), "q": (3, 1, 0), "r": (1, 4, 0)})
    pl = ms.Plane(b, "p", "q", "r")
    assert pl.origin.label == "p"
    np.testing.assert_allclose(np.array(pl.dir.local, dtype=float).ravel(), [0, 0, 6])
    np.testing.assert_allclose(np.array(pl.reference_vector().local, dtype=float).ravel(),
                               [1, 0, 0])
    assert ms.Plane(b.point("p"), b.point("q"), b.point("r")).dir.body is b
    # as a vector it gives its normal
    assert ms.Orthogonal1(pl, b.vector((1, 0, 0))).v1 is pl.dir
    # across bodies: a global expression that knows its bodies
    c = m.add_body("c")
    pl2 = ms.Plane(b.point("p"), c.point((1, 0, 0)), (0, 0, 1))
    assert set(pl2.bodies()) == {b, c}
    with pytest.raises(ms.GeometryError, match="three points are collinear"):
        ms.Plane(b, (0, 0, 0), (1, 1, 1), (2, 2, 2))
    with pytest.raises(ms.GeometryError, match="2 coordinates; this model is 3D"):
        ms.Plane((0, 0), (1, 0), (0, 1))


# -- body guesses ----------------------------------------------------------------------------


def test_guess_in_every_mech_rotation_format():
    e = ms.euler_parameters((0.8, (1, -2, 2)))
    R = ms.rotation_matrix(e)
    forms = [tuple(e), tuple(0.8 * np.array([1, -2, 2]) / 3), (0.8, (1, -2, 2)), R,
             [(0.3, (1, -2, 2)), (0.5, (1, -2, 2))], [(0.8, (1, -2, 2)), (1, 0, 0, 0)]]
    m = ms.Model3D()
    for k, f in enumerate(forms):
        b = m.add_body(f"b{k}", guess=((1, 2, 3), f))
        g = np.asarray(b.guess)
        np.testing.assert_allclose(g[:3], [1, 2, 3])
        assert min(np.abs(g[3:] - e).max(), np.abs(g[3:] + e).max()) < 1e-14, f
    # an Euler-angle style sequence: z, then x' (rotated), then z''
    b = m.add_body("euler", guess=((0, 0, 0), [(0.1, (0, 0, 1)), (0.2, (1, 0, 0)),
                                               (0.3, (0, 0, 1))]))
    A = ms.rotation_matrix(tuple(b.guess[3:]))
    Rz = lambda a: np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])  # noqa: E731
    Rx = lambda a: np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])  # noqa: E731
    np.testing.assert_allclose(A, Rz(0.1) @ Rx(0.2) @ Rz(0.3), atol=1e-15)


# -- angular velocity, acceleration, instant screw axis --------------------------------------


def tumbling_body():
    """A body whose orientation follows a prescribed time history (RotationLock3) and whose
    origin moves on a helix-like path (OriginLock3 with a time-dependent offset)."""
    m = ms.Model3D()
    b = m.add_body("b", points={"p": (0.4, -0.3, 0.7)})
    m.add(ms.RotationLock3(b, None, (0.7 * T + 0.2 * T**2, (1, 2, 2)), (sp.sin(T), (0, 0, 1))))
    m.add(ms.OriginLock3(b, None, (sp.cos(T), sp.sin(2 * T), 0.5 * T)))
    return m, b


def rot_of_t(t):
    return ms.rotation_matrix([(0.7 * t + 0.2 * t**2, (1, 2, 2)), (np.sin(t), (0, 0, 1))])


def skew_to_vec(W):
    return np.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]]) / 2


def omega_fd(t, h=1e-5):
    """omega from omega~ = A' A^T by central differences of the prescribed rotation."""
    A = rot_of_t(t)
    return skew_to_vec((rot_of_t(t + h) - rot_of_t(t - h)) / (2 * h) @ A.T)


def test_omega_and_alpha_global_and_local_against_finite_differences():
    m, b = tumbling_body()
    t = np.array([0.2, 0.9, 1.7])
    sol = m.solve(t)
    for k, tk in enumerate(t):
        A, w = rot_of_t(tk), omega_fd(tk)
        np.testing.assert_allclose(sol.omega(b)[k], w, atol=1e-8)
        np.testing.assert_allclose(sol.omega(b, coordinates="local")[k], A.T @ w, atol=1e-8)
        alpha = (omega_fd(tk + 1e-4) - omega_fd(tk - 1e-4)) / 2e-4
        np.testing.assert_allclose(sol.alpha(b)[k], alpha, atol=1e-5)
        np.testing.assert_allclose(sol.alpha(b, coordinates="local")[k], A.T @ alpha, atol=1e-5)


def test_instant_screw_axis():
    m, b = tumbling_body()
    sol = m.solve(np.array([0.3, 1.1]))
    point, direction = sol.instant_center(b)
    assert point.shape == (2, 3) and direction.shape == (2, 3)
    np.testing.assert_allclose(direction, sol.omega(b), atol=1e-14)
    for k in range(2):
        w, r_o = sol.omega(b)[k], sol.location(b.point(0))[k]
        v_o = sol.velocity(b.point(0))[k]
        # every point on the screw axis moves along the axis, all with the same velocity
        for s in (0.0, 1.3, -2.0):
            r = point[k] + s * w
            v = v_o + np.cross(w, r - r_o)
            np.testing.assert_allclose(np.cross(v, w), 0, atol=1e-9)
            np.testing.assert_allclose(v, v_o + np.cross(w, point[k] - r_o), atol=1e-9)
    # a pure rotation about a fixed axis: the screw axis is that axis, with no slip
    m2 = ms.Model3D()
    c = m2.add_body("c")
    m2.add(ms.Revolute5(c.axis((1, 0, 0), (0, 1, 1)), m2.ground.axis((2, 1, 0), (0, 1, 1))))
    m2.add(ms.RotationLock1(c.axis((1, 0, 0), (0, 1, 1)), m2.ground.axis((2, 1, 0), (0, 1, 1)),
                            3 * T))
    s2 = m2.solve(0.4)
    p, d = s2.instant_center(c)
    np.testing.assert_allclose(np.cross(p - [2, 1, 0], [0, 1, 1]), 0, atol=1e-10)
    np.testing.assert_allclose(d, 3 * np.array([0, 1, 1]) / np.sqrt(2), atol=1e-10)


# -- errors ----------------------------------------------------------------------------------


def test_spatial_input_errors_name_the_culprit_and_the_fix():
    m = ms.Model3D()
    b = m.add_body("b")
    with pytest.raises(ms.ModelError, match="in 3D, RotationLock1 takes axes"):
        m.add(ms.RotationLock1(b, 0.3))
    with pytest.raises(ms.ModelError, match="ParaRevolute4 dist = 0 is singular; use Revolute5"):
        ms.ParaRevolute4(b.axis(), m.ground.axis((0, 0, 0), (1, 0, 0)), 0)
    with pytest.raises(ms.ModelError, match="use Cylindrical4"):
        ms.LineOnCylinder3(b.axis(), m.ground.axis((0, 0, 0), (1, 0, 0)), 0)
    with pytest.raises(ms.ModelError, match="included angle of 0 or pi is singular; use Parallel2"):
        m.add(ms.RelativeAngle1(b.vector((1, 0, 0)), (0, 1, 0), 0))
    with pytest.raises(ms.ModelError, match="for spatial models, not planar ones"):
        ms.Model2D().add(ms.Spherical3((0, 0), (1, 0)))
    with pytest.raises(ms.GeometryError, match="this model is 2D"):
        ms.Model2D().add_body("c").vector((1, 0, 0))
    with pytest.raises(ms.ModelError, match="RotationLock3 body1: expected a body"):
        ms.RotationLock3((0.3, (0, 0, 1)), b)
    with pytest.raises(ms.ModelError, match="cannot read"):
        ms.RotationLock3(b, None, (0.3, 1))


def test_rotation_lock3_with_ground_omitted():
    m = ms.Model3D()
    b = m.add_body("b", guess=((0, 0, 0), (0.5, (0, 0, 1))))
    m.add(ms.RotationLock3(b, (0.3 * T, (0, 0, 1)), (0.2, (1, 0, 0))))
    m.add(ms.OriginLock3(b))
    sol = m.solve(1.0)
    e = [sol[f"b.e{k}"] for k in range(4)]
    R = ms.rotation_matrix([(0.3, (0, 0, 1)), (0.2, (1, 0, 0))])
    np.testing.assert_allclose(ms.rotation_matrix(e), R, atol=1e-12)
