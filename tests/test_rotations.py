"""Rotation utilities: round trips on random rotations (including near 180 degrees) against
an independent Rodrigues formula, sequences, symbolic use, conversions."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T
from mechsys.geometry._rotations import matrix_elements


def rodrigues(angle, axis):
    """Independent reference: R = cos a I + sin a [u]x + (1 - cos a) u u^T."""
    u = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.cos(angle) * np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * np.outer(u, u)


def same_rotation_params(e1, e2, tol):
    e1, e2 = np.asarray(e1, float), np.asarray(e2, float)
    return min(np.abs(e1 - e2).max(), np.abs(e1 + e2).max()) < tol


def random_angle_axes(n=300, seed=3):
    rng = np.random.default_rng(seed)
    axes = rng.standard_normal((n, 3))
    angles = rng.uniform(0, np.pi, n)
    # a third of them within 1e-3 .. 1e-12 of 180 degrees, some exactly 180, some near 0
    k = n // 3
    angles[:k] = np.pi - 10.0 ** rng.uniform(-12, -3, k)
    angles[k:k + 10] = np.pi
    angles[k + 10:k + 20] = 10.0 ** rng.uniform(-12, -4, 10)
    return angles, axes


def test_matrix_from_angle_axis_matches_rodrigues():
    for ang, ax in zip(*random_angle_axes(100)):
        np.testing.assert_allclose(ms.rotation_matrix((ang, ax)), rodrigues(ang, ax), atol=1e-14)
        np.testing.assert_allclose(ms.rotation_matrix(ang * ax / np.linalg.norm(ax)),
                                   rodrigues(ang, ax), atol=1e-14)


def test_round_trips_on_random_rotations_including_near_180_degrees():
    worst = {"matrix->params": 0.0, "angle": 0.0, "axis": 0.0, "virtual": 0.0}
    for ang, ax in zip(*random_angle_axes()):
        u = ax / np.linalg.norm(ax)
        R = rodrigues(ang, u)
        e_true = np.r_[np.cos(ang / 2), np.sin(ang / 2) * u]
        # matrix -> Euler parameters (Shepperd): accurate even at 180 degrees
        e = ms.euler_parameters(R)
        err = min(np.abs(e - e_true).max(), np.abs(e + e_true).max())
        worst["matrix->params"] = max(worst["matrix->params"], err)
        assert e[0] >= 0 and np.isclose(np.linalg.norm(e), 1)
        # parameters -> angle-axis -> parameters
        a2, u2 = ms.rotation(e)
        worst["angle"] = max(worst["angle"], abs(a2 - ang))
        if ang > 1e-6:
            worst["axis"] = max(worst["axis"], min(np.abs(u2 - u).max(), np.abs(u2 + u).max()))
        assert same_rotation_params(ms.euler_parameters((a2, u2)), e, 1e-12)
        # virtual rotation round trip
        v = ms.virtual_rotation(R)
        worst["virtual"] = max(worst["virtual"], np.abs(ms.rotation_matrix(v) - R).max())
        assert same_rotation_params(ms.euler_parameters(v), e, 1e-12)
        # parameters -> matrix
        np.testing.assert_allclose(ms.rotation_matrix(e), R, atol=1e-14)
    assert worst["matrix->params"] < 1e-12, worst
    assert worst["angle"] < 1e-12, worst
    assert worst["axis"] < 1e-10, worst
    assert worst["virtual"] < 1e-13, worst


def test_exactly_180_degrees_about_each_axis_and_diagonals():
    for u in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, -1, 1), (-2, 1, 3)]:
        R = rodrigues(np.pi, u)
        e = ms.euler_parameters(R)
        un = np.asarray(u, float) / np.linalg.norm(u)
        assert same_rotation_params(e, np.r_[0, un], 1e-15)
        ang, ax = ms.rotation(R)
        assert np.isclose(ang, np.pi)
        assert min(np.abs(ax - un).max(), np.abs(ax + un).max()) < 1e-15


def test_zero_rotation_and_normalized_option():
    assert ms.rotation((1, 0, 0, 0))[0] == 0.0
    np.testing.assert_array_equal(ms.virtual_rotation(np.eye(3)), 0)
    np.testing.assert_array_equal(ms.euler_parameters((0.0, (0, 0, 0))), [1, 0, 0, 0])
    ang, ax = ms.rotation((np.cos(0.4), 0, 0, np.sin(0.4)), normalized=False)
    assert np.isclose(ang, 0.8) and np.allclose(ax, [0, 0, np.sin(0.4)])
    # assume a unit axis: a non-unit axis is then used as given
    e = ms.euler_parameters((0.6, (0, 0, 2)), normalized=True)
    assert np.isclose(e[3], 2 * np.sin(0.3))


def test_sequence_of_rotations_is_intrinsic():
    rng = np.random.default_rng(5)
    a1, a2, a3 = rng.standard_normal((3, 3))
    seq = [(0.7, a1), (-1.2, a2), tuple(0.3 * a3)]
    R = ms.rotation_matrix(seq)
    # Mech: axis2 is in the frame turned by rotation 1 (intrinsic): R = R1 R2 R3 ...
    expect = rodrigues(0.7, a1) @ rodrigues(-1.2, a2) @ rodrigues(0.3 * np.linalg.norm(a3), a3)
    np.testing.assert_allclose(R, expect, atol=1e-14)
    # ... equivalently all about fixed axes in reverse order: R3 first, then R2 taken to the
    # fixed frame, ...
    e = ms.euler_parameters(seq)
    np.testing.assert_allclose(ms.rotation_matrix(e), expect, atol=1e-14)
    # EulerMultiply is the matrix product
    q1, q2 = ms.euler_parameters((0.7, a1)), ms.euler_parameters((-1.2, a2))
    np.testing.assert_allclose(ms.rotation_matrix(ms.quaternion_product(q1, q2)),
                               rodrigues(0.7, a1) @ rodrigues(-1.2, a2), atol=1e-14)
    np.testing.assert_allclose(ms.rotation_matrix(ms.EulerInverse(q1)), rodrigues(0.7, a1).T,
                               atol=1e-14)


def test_symbolic_rotations():
    e = ms.euler_parameters((2 * T, (0, 0, 1)))
    assert isinstance(e, sp.MatrixBase) and e[3] == sp.sin(T)
    A = ms.rotation_matrix((T, (1, 0, 0)))
    np.testing.assert_allclose(np.array(A.subs(T, 0.4), dtype=float), rodrigues(0.4, (1, 0, 0)),
                               atol=1e-15)
    m = ms.Model3D()
    b = m.add_body("b")
    assert ms.rotation_matrix(b) == b.A
    ang, axis = ms.rotation(b)
    vals = {s: v for s, v in zip(b.q[3:], [np.cos(0.3), 0, 0.6, 0.8 * np.sin(0.3) / 1.0])}
    assert ang.free_symbols <= set(b.q)
    assert float(ang.subs(vals)) == pytest.approx(2 * np.arctan2(
        np.hypot(0.6, 0.8 * np.sin(0.3)), np.cos(0.3)))


def test_projected_angle_and_robustness_to_drifted_parameters():
    # angle of x turned 0.9 about z, from x, projected on the XY plane
    v = rodrigues(0.9, (0, 0, 1)) @ np.array([1.0, 0, 0.5])
    assert np.isclose(ms.projected_angle(v, (1, 0, 0), (0, 0, 1)), 0.9)
    assert np.isclose(ms.projected_angle(v, (1, 0, 0), (0, 0, -1)), -0.9)
    # body vectors from Euler parameters that drifted off the unit sphere (|e| = 1.03):
    # A(e) is then 1.0609 times a rotation; the projected angle is unchanged and finite,
    # where an arccos of a normalised dot product would leave its domain
    rng = np.random.default_rng(11)
    for _ in range(50):
        e = rng.standard_normal(4)
        e *= 1.03 / np.linalg.norm(e)
        A = np.array(matrix_elements(e), dtype=float)
        R = ms.rotation_matrix(e)
        for vec in (np.array([1.0, 0.2, 0]), np.array([0.3, -1, 0.4])):
            a_drift = ms.projected_angle(A @ vec, (1, 0, 0), (0, 0, 1))
            a_true = ms.projected_angle(R @ vec, (1, 0, 0), (0, 0, 1))
            assert np.isfinite(a_drift) and abs(a_drift - a_true) < 1e-13
    # parallel-ish vectors at +-pi stay finite
    assert np.isclose(abs(ms.projected_angle((-1, 1e-17, 0), (1, 0, 0), (0, 0, 1))), np.pi)
    # arrays broadcast
    vs = np.array([rodrigues(a, (0, 0, 1)) @ [1, 0, 0] for a in (0.1, -2.0, 3.0)])
    np.testing.assert_allclose(ms.projected_angle(vs, (1, 0, 0), (0, 0, 1)), [0.1, -2.0, 3.0])


def test_projected_angle_about_an_axis_uses_its_reference():
    m = ms.Model3D()
    ax = m.ground.axis((0, 0, 0), (0, 0, 1))          # default reference: +X
    v = (np.cos(0.5), np.sin(0.5), 2.0)
    assert float(ms.projected_angle(ms.Vector(None, v), ax)) == pytest.approx(0.5)


@pytest.mark.parametrize("coords", ["XYZ", "YZX", "ZXY"])
def test_cylindrical_and_spherical_round_trips(coords):
    rng = np.random.default_rng(2)
    P = rng.uniform(-3, 3, (50, 3))
    np.testing.assert_allclose(ms.cylindrical_to_xyz(ms.xyz_to_cylindrical(P, coords), coords),
                               P, atol=1e-13)
    np.testing.assert_allclose(ms.spherical_to_xyz(ms.xyz_to_spherical(P, coords), coords),
                               P, atol=1e-13)


def test_coordinate_conventions():
    # default: altitude along Z, angle zero on +X (Y = 0)
    np.testing.assert_allclose(ms.xyz_to_cylindrical((0, 2, 5)), [2, np.pi / 2, 5])
    np.testing.assert_allclose(ms.XYZToCylindrical((3, 0, -1)), [3, 0, -1])
    # YZX: altitude along X, angle from +Y towards +Z
    np.testing.assert_allclose(ms.xyz_to_cylindrical((5, 0, 2), "YZX"), [2, np.pi / 2, 5])
    # ZXY: altitude along Y, angle from +Z towards +X
    np.testing.assert_allclose(ms.xyz_to_cylindrical((2, 5, 0), "ZXY"), [2, np.pi / 2, 5])
    # spherical: (radius, base angle, altitude angle above the base plane)
    np.testing.assert_allclose(ms.xyz_to_spherical((1, 0, 1)), [np.sqrt(2), 0, np.pi / 4])
    np.testing.assert_allclose(ms.xyz_to_spherical((0, 0, -2)), [2, 0, -np.pi / 2])
    np.testing.assert_allclose(ms.spherical_to_xyz((2, np.pi / 2, 0), "YZX"), [0, 0, 2],
                               atol=1e-15)
    with pytest.raises(ms.ModelError, match="coordinates must be one of"):
        ms.xyz_to_cylindrical((1, 2, 3), "XZY")
    # symbolic points stay symbolic
    x = sp.Symbol("x")
    assert isinstance(ms.xyz_to_cylindrical((x, 1, 2)), sp.MatrixBase)


def test_intersection_point_and_vector_helpers():
    m = ms.Model3D()
    plane = ms.Plane((0, 0, 2), (1, 0, 2), (0, 1, 2))           # z = 2
    line = m.ground.axis((1, 1, 0), (1, 0, 1))
    np.testing.assert_allclose(ms.intersection_point(line, plane), [3, 1, 2])
    with pytest.raises(ms.GeometryError, match="parallel"):
        ms.intersection_point(m.ground.axis((0, 0, 0), (1, 0, 0)), plane)
    m2 = ms.Model2D()
    np.testing.assert_allclose(ms.IntersectionPoint(m2.ground.axis((0, 1), (1, 0)),
                                                    m2.ground.axis((3, 0), (1, 1))), [4, 1])
    b = m.add_body("b", points={"p": (1, 2, 2)})
    assert ms.magnitude((3, 4, 0)) == 5.0
    np.testing.assert_allclose(ms.unit((0, 0, 2)), [0, 0, 1])
    assert ms.distance((0, 0, 0), (1, 2, 2)) == 3.0
    unit_e = dict(zip(b.q[3:], [0.5, 0.5, -0.5, 0.5]))
    assert float(ms.magnitude(b.vector("p")).subs(unit_e)) == pytest.approx(3.0)
    d = ms.distance(b.point("p"), (0, 0, 0))
    assert d.free_symbols <= set(b.q)
    with pytest.raises(ms.GeometryError):
        ms.unit((0, 0, 0))


def test_mech_names_are_aliases():
    assert ms.EulerParameters is ms.euler_parameters
    assert ms.RotationMatrix is ms.rotation_matrix
    assert ms.Rotation is ms.rotation and ms.VirtualRotation is ms.virtual_rotation
    assert ms.ProjectedAngle is ms.projected_angle
    assert ms.XYZToSpherical is ms.xyz_to_spherical and ms.SphericalToXYZ is ms.spherical_to_xyz
    assert ms.CylindricalToXYZ is ms.cylindrical_to_xyz
    assert ms.Magnitude is ms.magnitude and ms.Unit is ms.unit
    assert ms.Direction is ms.direction and ms.Distance is ms.distance


def test_bad_rotation_formats_are_named():
    with pytest.raises(ms.ModelError, match="cannot read"):
        ms.euler_parameters((1, 2))
    with pytest.raises(ms.GeometryError, match="zero vector"):
        ms.euler_parameters((0.5, (0, 0, 0)))
    with pytest.raises(ms.ModelError, match="rotation guess of body 'b'"):
        ms.Model3D().add_body("b", guess=((0, 0, 0), (1, 2)))
