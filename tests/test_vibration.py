"""Linearised vibration (m.vibration): frequencies, damping ratios and mode shapes against
closed forms (double pendulum, spring-mass chain, damped oscillator, spherical pendulum,
gyroscopic whirl of a spinning rotor)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

import mechsys as ms


def double_pendulum(m1=1.3, m2=0.7, l1=1.1, l2=0.8, g=9.81, scale=1.0):
    l1, l2 = l1 * scale, l2 * scale
    m = ms.Model2D()
    a = m.add_body("a", points={"tip": (l1, 0)}, mass=m1, centroid=(l1, 0), inertia=0,
                   guess=((0, 0), -np.pi / 2 + 0.05))
    b = m.add_body("b", mass=m2, centroid=(l2, 0), inertia=0, guess=((0.05, -l1), -np.pi / 2 + 0.1))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)))
    m.add(ms.Revolute2(a.point("tip"), b.point(0)))
    m.add_load(ms.Gravity((0, -1), g * scale))
    return m


def double_pendulum_omega(m1=1.3, m2=0.7, l1=1.1, l2=0.8, g=9.81):
    # Lagrange, small angles: M = [[(m1+m2) l1^2, m2 l1 l2], [m2 l1 l2, m2 l2^2]],
    # K = diag((m1+m2) g l1, m2 g l2); det(K - w^2 M) = 0 solved in closed form
    a = m1 * m2 * l1**2 * l2**2
    b = -((m1 + m2) * g * l1 * m2 * l2**2 + m2 * g * l2 * (m1 + m2) * l1**2)
    c = (m1 + m2) * m2 * g**2 * l1 * l2
    disc = np.sqrt(b * b - 4 * a * c)
    return np.sqrt(np.array([(-b - disc) / (2 * a), (-b + disc) / (2 * a)]))


@pytest.mark.parametrize("scale", [1.0, 1000.0])
def test_double_pendulum_closed_form(scale):
    m = double_pendulum(scale=scale)
    eq = m.free(solution="static").solve()
    modes = m.vibration(at=eq)
    # frequencies are independent of the unit of length (g and lengths scaled together)
    assert modes.omega == pytest.approx(double_pendulum_omega(), rel=1e-9)
    assert modes.hz == pytest.approx(modes.omega / (2 * np.pi), rel=1e-15)
    assert np.all(modes.damping_ratio == 0) and modes.stable
    # mode shapes: mass-orthonormal in the reduced coordinates; in-phase first mode
    P, M = modes.basis, modes.mass
    assert modes.shapes.shape == (2, 6)
    th = [modes.coordinates.index("a.th"), modes.coordinates.index("b.th")]
    s0 = modes.shape(0)[th]
    assert s0[0] * s0[1] > 0
    s1 = modes.shape(1, ["a.th", "b.th"])
    assert s1[0] * s1[1] < 0
    Z = np.linalg.lstsq(P, modes.shapes.T, rcond=None)[0]
    assert Z.T @ M @ Z == pytest.approx(np.eye(2), abs=1e-9)


def test_equal_double_pendulum_textbook():
    m = double_pendulum(1.0, 1.0, 1.0, 1.0, 9.81)
    modes = m.vibration(at=m.free(solution="static").solve())
    assert modes.omega**2 == pytest.approx(9.81 * np.array([2 - np.sqrt(2), 2 + np.sqrt(2)]),
                                           rel=1e-9)


def chain(n, k, mass, c=0.0):
    """n equal sliders on the x axis, springs ground-1-2-...-n (fixed-free), unstretched."""
    m = ms.Model2D()
    prev = m.ground.point((0, 0))
    for i in range(n):
        b = m.add_body(f"m{i + 1}", mass=mass, inertia=0.1, guess=((i + 1.0, 0), 0))
        m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), b.axis((0, 0), (1, 0))))
        m.add_load(ms.Spring(prev, b.point(0), k, 1.0))
        if c:
            m.add_load(ms.Damper(prev, b.point(0), c))
        prev = b.point(0)
    return m


def test_spring_mass_chain_closed_form():
    n, k, mass = 5, 40.0, 0.8
    m = chain(n, k, mass)
    modes = m.vibration(at=m.guess())
    j = np.arange(1, n + 1)
    exact = 2 * np.sqrt(k / mass) * np.sin((2 * j - 1) * np.pi / (2 * (2 * n + 1)))
    assert modes.omega == pytest.approx(exact, rel=1e-9)
    # and the eigenvalues of the tridiagonal K with M = mass I
    K = 2 * k * np.eye(n) - k * np.eye(n, k=1) - k * np.eye(n, k=-1)
    K[-1, -1] = k
    assert modes.omega**2 == pytest.approx(sla.eigh(K, mass * np.eye(n), eigvals_only=True),
                                           rel=1e-9)
    # shapes: only the x coordinates move
    xs = [modes.coordinates.index(f"m{i + 1}.x") for i in range(n)]
    other = np.delete(modes.shapes, xs, axis=1)
    assert np.abs(other).max() < 1e-12


def test_damped_single_dof():
    k, mass, c = 250.0, 2.5, 6.0
    m = chain(1, k, mass, c)
    modes = m.vibration(at=m.guess())
    wn = np.sqrt(k / mass)
    zeta = c / (2 * np.sqrt(k * mass))
    assert len(modes) == 1
    assert modes.omega[0] == pytest.approx(wn, rel=1e-9)
    assert modes.damping_ratio[0] == pytest.approx(zeta, rel=1e-9)
    assert modes.damped_omega[0] == pytest.approx(wn * np.sqrt(1 - zeta**2), rel=1e-9)
    assert modes.stable


def test_spherical_pendulum_3d():
    L, g, mass = 0.9, 9.81, 2.0
    m = ms.Model3D()
    bob = m.add_body("bob", mass=mass, centroid=(0, 0, -L), inertia=(0.005, 0.005, 0.01, 0, 0, 0))
    m.add(ms.Spherical3(m.ground.point((0, 0, 0)), bob.point(0)))
    m.add_load(ms.Gravity((0, 0, -1), g))
    modes = m.vibration(at=m.guess())
    # two compound-pendulum modes w^2 = m g L / (m L^2 + J) and the free spin (zero)
    w = np.sqrt(mass * g * L / (mass * L**2 + 0.005))
    assert modes.omega == pytest.approx([0, w, w], rel=1e-9, abs=1e-9)


def test_gyroscopic_whirl_of_a_spinning_rotor():
    """A symmetric rotor on a spherical pivot, four tilt springs at one end, spinning at
    ``W`` about its axis (a steady motion): forward and backward whirl
    w = (+-Jp W + sqrt(Jp^2 W^2 + 4 Jt k_t)) / (2 Jt), k_t = 2 k a^2."""
    Jp, Jt, k, a, d = 0.02, 0.05, 300.0, 0.2, 0.1
    m = ms.Model3D()
    r = m.add_body("rotor", mass=3.0, inertia=(Jp, Jt, Jt, 0, 0, 0))
    m.add(ms.Spherical3(m.ground.point((0, 0, 0)), r.point(0)))
    for gy, gz in ((d, 0), (-d, 0), (0, d), (0, -d)):
        m.add_load(ms.Spring(r.point((a, 0, 0)), m.ground.point((a, gy, gz)), k, d))
    kt = 2 * k * a**2
    for spin in (0.0, 40.0, -25.0):
        # spin about the body (and global) x axis: e_dot = E^T omega / 2 at e = (1, 0, 0, 0)
        modes = m.vibration(at={"rotor.e1_d": spin / 2})
        root = np.sqrt(Jp**2 * spin**2 + 4 * Jt * kt)
        whirl = sorted([(root - Jp * abs(spin)) / (2 * Jt), (root + Jp * abs(spin)) / (2 * Jt)])
        # the spin itself is a free (zero-frequency) motion
        osc = modes.omega > 1e-6
        assert len(modes) == 3 and osc.sum() == 2
        assert modes.omega[osc] == pytest.approx(whirl, rel=1e-9)
        assert modes.damping_ratio[osc] == pytest.approx(0, abs=1e-9)
        assert modes.stable
    assert whirl[0] < np.sqrt(kt / Jt) < whirl[1]


def test_unstable_inverted_pendulum_and_errors():
    m = ms.Model2D()
    b = m.add_body("b", mass=1.0, centroid=(1.0, 0), inertia=0, guess=((0, 0), np.pi / 2))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)))
    m.add_load(ms.Gravity((0, -1), 9.81))
    modes = m.vibration(at=m.guess())
    assert not modes.stable
    assert modes.eigenvalues[0].real == pytest.approx(np.sqrt(9.81), rel=1e-9)
    with pytest.raises(ms.ModelError, match="not an equilibrium"):
        m.vibration(at={"b.th": 0.3})
    with pytest.raises(ms.ModelError, match="tolerance"):
        m.vibration(at=m.guess(), tolerance=2)
    with pytest.raises(ms.ModelError, match="mode number"):
        modes.shape(5)


def test_driver_dropped_and_mode_motion():
    m = double_pendulum()
    m.add(ms.RotationLock1(m.body("a"), -np.pi / 2), name="lock")
    with pytest.raises(ms.ModelError, match="no degree of freedom|not an equilibrium"):
        m.vibration(at=m.guess(), drop=[])
    eq = m.free(drop=["lock"], solution="static").solve()
    modes = m.vibration(at=eq, drop=["lock"])
    assert modes.omega == pytest.approx(double_pendulum_omega(), rel=1e-9)
    sol = modes.motion(1, amplitude=0.05, frames=9)
    assert sol.q.shape == (9, 6)
    # every frame satisfies the constraints and the largest excursion is the amplitude
    for q in sol.q:
        assert np.abs(sol.system.residual(0.0, q)).max() < 1e-10
    th = modes.coordinates.index("b.th")
    assert np.ptp(sol.q[:, th]) <= 2 * 0.05 + 1e-9
    assert sol.t[-1] == pytest.approx(2 * np.pi / modes.omega[1])


def test_mode_animation():
    m = chain(2, 10.0, 1.0)
    modes = m.vibration(at=m.guess())
    anim = modes.animate(0, frames=4)
    assert anim.frames == 4
    assert anim.times[-1] == pytest.approx(2 * np.pi / modes.omega[0])


def centrifugal_pendulum(R=0.3, l=0.08, W=50.0, orientation="angle"):
    """A pendulum pinned at radius R on a disc driven at W (no gravity)."""
    m = ms.Model2D(orientation=orientation)
    disc = m.add_body("disc", points={"pin": (R, 0)}, mass=2.0, inertia=0.1)
    pend = m.add_body("pend", mass=0.2, centroid=(l, 0), inertia=0, guess=((R, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), disc.point(0)))
    m.add(ms.RotationLock1(disc, W * ms.T), name="drive")
    m.add(ms.Revolute2(disc.point("pin"), pend.point(0)))
    return m


def test_centrifugal_pendulum_in_a_rotating_frame():
    """A pendulum pinned at radius R on a disc driven at W (no gravity): about its radial
    relative equilibrium it swings at W sqrt(R / l) (the centrifugal pendulum absorber)."""
    R, l, W = 0.3, 0.08, 50.0
    m = centrifugal_pendulum(R, l, W)
    modes = m.vibration(at=m.guess(), rotating=(W, (0, 0)))
    assert modes.omega == pytest.approx([W * np.sqrt(R / l)], rel=1e-9)
    # the velocities were those of the rotating frame, consistent with the driver
    assert modes.qd[m.compile().layout.index("pend.y")] == pytest.approx(W * R)
    # without the rotating frame the (orbiting) reference is not an equilibrium
    with pytest.raises(ms.ModelError, match="not an equilibrium"):
        m.vibration(at={"disc.th_d": W, "pend.th_d": W, "pend.y_d": W * R})


def test_bead_on_a_rotating_hoop_3d():
    """A bead (point mass on an arm of length a) on a hoop spinning at W about the vertical,
    with gravity: relative equilibrium cos(th0) = g / (a W^2), frequency W sin(th0)."""
    a, g, W = 0.5, 9.81, 6.0
    th0 = np.arccos(g / (a * W**2))
    m = ms.Model3D()
    hoop = m.add_body("hoop", mass=1.0, inertia=(0.1, 0.1, 0.2, 0, 0, 0))
    arm = m.add_body("arm", mass=0.3, centroid=(0, 0, -a), inertia=(0, 0, 0, 0, 0, 0))
    gz = m.ground.axis((0, 0, 0), (0, 0, 1), (1, 0, 0))
    hz = hoop.axis((0, 0, 0), (0, 0, 1), (1, 0, 0))
    m.add(ms.Revolute5(hz, gz))
    m.add(ms.RotationLock1(hz, gz, W * ms.T), name="spin")
    m.add(ms.Revolute5(arm.axis((0, 0, 0), (0, 1, 0)), hoop.axis((0, 0, 0), (0, 1, 0))))
    m.add_load(ms.Gravity((0, 0, -1), g))
    at = {"arm.e0": np.cos(th0 / 2), "arm.e2": np.sin(th0 / 2)}
    modes = m.vibration(at=at, rotating=(W, (0, 0, 0), (0, 0, 1)))
    assert modes.omega == pytest.approx([W * np.sin(th0)], rel=1e-9)
    # off the relative equilibrium the reference is refused
    with pytest.raises(ms.ModelError, match="not an equilibrium"):
        m.vibration(at={"arm.e0": np.cos(0.3), "arm.e2": np.sin(0.3)},
                    rotating=(W, (0, 0, 0), (0, 0, 1)))
    with pytest.raises(ms.ModelError, match="rotating="):
        m.vibration(at=at, rotating=(W, (0, 0)))
