"""Issue 34: stability judged per mode, not against the stiffest mode (VibrationModes.stable,
.stability)."""

import numpy as np
import pytest

import mechsys as ms

L, MASS, G = 1.0, 1.0, 9.81


def pendulum_beside_stiff_spring(s_up=0.012, kb=1e16, c=0.0):
    """An inverted pendulum held up by a torsion spring slightly too weak (closed form
    ``s^2 = (m g L - kt) / (m L^2) = s_up^2``: it capsizes with ``e^(s_up t)``) beside a
    slider on a stiff spring (``omega = sqrt(kb / M)``, damper ``c``)."""
    m = ms.Model2D()
    kt = MASS * G * L - MASS * L**2 * s_up**2
    b = m.add_body("pend", mass=MASS, centroid=(L, 0), inertia=0, guess=((0, 0), np.pi / 2))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)))
    m.add_load(ms.TorsionSpring(m.ground, b, kt, free_angle=np.pi / 2))
    sl = m.add_body("slider", mass=1.0, centroid=(0, 0), inertia=1.0, guess=((0, -2), 0))
    m.add(ms.Translate2(m.ground.axis((0, -2), (1, 0)), sl.axis((0, 0), (1, 0))))
    m.add_load(ms.Spring(m.ground.point((-1, -2)), sl.point(0), kb, 1.0))
    if c:
        m.add_load(ms.Damper(m.ground.point((-1, -2)), sl.point(0), c))
    m.add_load(ms.Gravity((0, -1), G))
    return m


@pytest.mark.parametrize("kb", [1e4, 1e12, 1e16])
def test_a_capsizing_mode_beside_a_stiff_one_is_unstable(kb):
    m = pendulum_beside_stiff_spring(kb=kb)
    modes = m.vibration(at=m.guess())
    assert not modes.stable
    s = modes.eigenvalues
    # closed forms: +0.012 (real, growing) and i sqrt(kb) (undamped)
    assert s[0].real == pytest.approx(0.012, rel=1e-9) and s[0].imag == 0
    assert s[1].imag == pytest.approx(np.sqrt(kb), rel=1e-12) and s[1].real == 0
    assert modes.stability == ("unstable", "neutral")


def test_damped_stiff_mode_keeps_the_capsizing_one():
    # the state-space path: the soft pair +-0.012 was taken for a rigid-body double zero
    # (against the stiffest eigenvalue) and half of it dropped
    kb, c = 1e16, 1e3
    m = pendulum_beside_stiff_spring(kb=kb, c=c)
    modes = m.vibration(at=m.guess())
    s = modes.eigenvalues
    expect_stiff = (-c + 1j * np.sqrt(4 * kb - c * c)) / 2
    assert not modes.stable
    by = dict(zip(modes.stability, s))
    assert sorted(modes.stability) == ["stable", "stable", "unstable"]
    assert by["unstable"].real == pytest.approx(0.012, rel=1e-6)
    got_stiff = s[np.argmax(np.abs(s))]
    assert got_stiff.real == pytest.approx(expect_stiff.real, rel=1e-6)
    assert got_stiff.imag == pytest.approx(expect_stiff.imag, rel=1e-12)
    assert -0.012 == pytest.approx(min(x.real for x in s if abs(x) < 1), rel=1e-6)


def test_upright_pendulum_held_by_a_strong_spring_is_stable_and_neutral():
    m = pendulum_beside_stiff_spring(s_up=-0.0, kb=1e16)   # kt = m g L: a neutral equilibrium
    modes = m.vibration(at=m.guess())
    assert modes.stable and modes.stability == ("neutral", "neutral")
    assert abs(modes.eigenvalues[0]) <= 1e-6
    m = ms.Model2D()
    b = m.add_body("pend", mass=MASS, centroid=(L, 0), inertia=0, guess=((0, 0), np.pi / 2))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)))
    m.add_load(ms.TorsionSpring(m.ground, b, 2 * MASS * G * L, free_angle=np.pi / 2))
    m.add_load(ms.Gravity((0, -1), G))
    modes = m.vibration(at=m.guess())
    assert modes.stable and modes.omega[0] == pytest.approx(np.sqrt(G / L), rel=1e-12)
    assert "neutral" in repr(modes)


# -- a null-space basis that keeps a soft coordinate apart from a stiff one ---------------------

K_SOFT, M_SLIDER, M_ROTOR, J_ROTOR, PIN = 3.0, 2.0, 1.5, 0.5, (0.7, 0.3)


def slider_beside_stiff_rotor(k_stiff, c=0.0):
    """A slider on a soft spring (``K_SOFT``, damper ``c``) beside a rotor pinned off its
    centroid on a stiff torsion spring: the minimal-coordinate model is ``x`` and ``theta``,
    ``M_SLIDER x'' + c x' + K_SOFT x = 0`` and ``J_pin theta'' + k_stiff theta = 0`` with
    ``J_pin = J + m |pin|^2``. The constraints tie the rotor's position to its angle, so the
    null space of the Jacobian has a slider direction and a rotor direction; the SVD's
    orthonormal basis of it mixed them."""
    m = ms.Model2D()
    a = m.add_body("slider", mass=M_SLIDER, inertia=1.0, guess=((0, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), a.axis((0, 0), (1, 0))))
    m.add_load(ms.Spring(m.ground.point((-1, 0)), a.point(0), K_SOFT, 1.0))
    if c:
        m.add_load(ms.Damper(m.ground.point((-1, 0)), a.point(0), c))
    b = m.add_body("rotor", mass=M_ROTOR, inertia=J_ROTOR, points={"pin": PIN},
                   guess=((-PIN[0], 2 - PIN[1]), 0))
    m.add(ms.Revolute2(m.ground.point((0, 2)), b.point("pin")))
    m.add_load(ms.TorsionSpring(m.ground, b, k_stiff, free_angle=0))
    return m


def _rotor_omega2(k_stiff):
    return k_stiff / (J_ROTOR + M_ROTOR * (PIN[0] ** 2 + PIN[1] ** 2))


@pytest.mark.parametrize("k_stiff", [1e8, 1e12, 1e16])
def test_soft_eigenvalue_beside_a_stiff_one_is_kept(k_stiff):
    m = slider_beside_stiff_rotor(k_stiff)
    modes = m.vibration(at=m.guess())
    # closed forms of the minimal-coordinate model (the SVD basis gave 1 + 1.2e-9, 1 - 2e-5
    # and 0 for the soft one at these ratios)
    np.testing.assert_allclose(modes.omega ** 2, [K_SOFT / M_SLIDER, _rotor_omega2(k_stiff)],
                               rtol=1e-13)
    assert modes.stability == ("neutral", "neutral")
    # the basis moves the slider alone in one column and the rotor alone in the other
    P = modes.basis
    x = modes.coordinates.index("slider.x")
    col = np.flatnonzero(P[x])
    assert len(col) == 1 and np.flatnonzero(P[:, col[0]]).tolist() == [x]


@pytest.mark.parametrize("k_stiff", [1e8, 1e14])
def test_damped_soft_mode_beside_a_stiff_one(k_stiff):
    # the state-space path with the same basis: s = -c/2m +- i sqrt(k/m - (c/2m)^2)
    c = 0.5
    m = slider_beside_stiff_rotor(k_stiff, c=c)
    modes = m.vibration(at=m.guess())
    s_soft = complex(-c / (2 * M_SLIDER), np.sqrt(K_SOFT / M_SLIDER - (c / (2 * M_SLIDER)) ** 2))
    s = modes.eigenvalues
    assert abs(s[0] / s_soft - 1) < 1e-12
    assert abs(s[1] / (1j * np.sqrt(_rotor_omega2(k_stiff))) - 1) < 1e-12
    assert modes.stability == ("stable", "neutral")
