"""Mass-property utilities against textbook values."""

import numpy as np

import mechsys as ms


def test_parallel_axis_2d_round_trip():
    J = ms.parallel_axis((0.3, 0.4), 2.0, 1.0)
    assert np.isclose(J, 1.0 + 2.0 * 0.25)
    assert np.isclose(ms.parallel_axis((0.3, 0.4), -2.0, J), 1.0)


def test_parallel_axis_3d_rod_about_end():
    m, L = 3.0, 2.0
    Jc = (m * L**2 / 12, m * L**2 / 12, 0.0)  # slender rod along z, centroidal
    J = ms.parallel_axis((0, 0, L / 2), m, Jc)
    np.testing.assert_allclose(J[:3], [m * L**2 / 3, m * L**2 / 3, 0.0])
    np.testing.assert_allclose(J[3:], 0.0)
    # rotated centroidal frame: rod along x instead of z
    Rz_to_x = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], dtype=float)
    J2 = ms.parallel_axis((0, 0, 0), m, Jc, rotation=Rz_to_x)
    np.testing.assert_allclose(J2[:3], [0.0, m * L**2 / 12, m * L**2 / 12], atol=1e-12)


def test_principal_axes_recovers_rotation():
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    D = np.diag([1.0, 2.0, 3.5])
    w, V = ms.principal_axes(Q @ D @ Q.T)
    np.testing.assert_allclose(w, [1.0, 2.0, 3.5])
    np.testing.assert_allclose(V @ np.diag(w) @ V.T, Q @ D @ Q.T, atol=1e-12)
    assert np.isclose(np.linalg.det(V), 1.0)


def test_composite_of_two_point_masses():
    M, c, J = ms.composite_inertia([(1.0, (0.0, 0.0), 0.0), (1.0, (2.0, 0.0), 0.0)])
    assert M == 2.0 and np.allclose(c, (1.0, 0.0)) and np.isclose(J, 2.0)
    M, c, J = ms.composite_inertia([(1.0, (0, 0, 0), (0, 0, 0)), (3.0, (0, 0, 4), (0, 0, 0))])
    assert np.allclose(c, (0, 0, 3))
    np.testing.assert_allclose(J[:3], [1 * 9 + 3 * 1, 12.0, 0.0])
