"""Free motion: closed forms, an independent minimal-coordinate ODE and conservation."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import mechsys as ms


def pendulum(L=1.0, g=9.81, angle0=0.0):
    m = ms.Model2D()
    b = m.add_body("bar", mass=1.0, centroid=(L, 0), inertia=0.0, guess=((0, 0), angle0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, angle0), name="hold")
    m.add_load(ms.Gravity((0, -1), g))
    m.solve(0.0)
    return m, m.free(drop=["hold"])


def ball_bob():
    """A rigid body on a ball joint at the origin under gravity (3D, Euler parameters),
    assembled, and its free system (the attitude lock ``hold`` dropped)."""
    m = ms.Model3D()
    b = m.add_body("bob", mass=2.0, centroid=(0, 0, -1.0), inertia=(0.05, 0.08, 0.04, 0.01, 0, 0),
                   guess=((0, 0, 0), (0.5, (1, 0, 0))))
    m.add(ms.Spherical3(b.point(0), m.ground.point((0, 0, 0))), name="ball")
    m.add(ms.RotationLock3(b, (0.5, (1, 0, 0))), name="hold")
    m.add_load(ms.Gravity((0, 0, -1), 9.81))
    m.solve(0.0)
    return m, m.free(drop=["hold"])


def _crossing(sol, key, level):
    """First time after t0 where coordinate `key` crosses `level`, by cubic Hermite root."""
    from scipy.interpolate import CubicHermiteSpline
    from scipy.optimize import brentq

    y, yd = sol.coordinate(key) - level, sol.coordinate(key, 1)
    k = np.nonzero(np.sign(y[1:]) != np.sign(y[:-1]))[0][0]
    spl = CubicHermiteSpline(sol.t[k:k + 2], y[k:k + 2], yd[k:k + 2])
    return brentq(spl, sol.t[k], sol.t[k + 1])


@pytest.mark.parametrize("method", ["dop853", "adams"])
def test_large_amplitude_period_matches_elliptic_integral(method):
    L, g = 1.0, 9.81
    m, free = pendulum(L, g, 0.0)          # released horizontal: amplitude 90 degrees
    T0 = 2 * np.pi * np.sqrt(L / g)
    t = np.linspace(0, 0.5 * T0, 2001)
    kw = {"rtol": 1e-11, "atol": 1e-12} if method == "dop853" else {"max_error": 1e-9,
                                                                      "fit_degree": "quartic"}
    sol = free.simulate(t, method=method, **kw)
    quarter = _crossing(sol, "bar.th", -np.pi / 2)    # reaches the bottom
    ratio = 4 * quarter / T0
    tol = 1e-9 if method == "dop853" else 1e-6
    assert abs(ratio - 1.1803405990160962) < tol


def double_pendulum_model():
    m = ms.Model2D()
    a = m.add_body("a", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0), inertia=1 / 12)
    b = m.add_body("b", mass=1.0, centroid=(0.5, 0), inertia=1 / 12, guess=((1, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)), name="j1")
    m.add(ms.Revolute2(a.point("tip"), b.point(0)), name="j2")
    m.add(ms.RotationLock1(a, 0.0), name="lock1")
    m.add(ms.RotationLock1(b, 0.0), name="lock2")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    return m, m.free(drop=["lock1", "lock2"])


def minimal_double_pendulum():
    """Equations of motion of two uniform rods (m = 1, L = 1) in the absolute link angles,
    derived here by Lagrange with SymPy (independent of mechsys)."""
    t = sp.Symbol("t")
    th1, th2 = sp.Function("th1")(t), sp.Function("th2")(t)
    g = 9.81
    c1 = sp.Matrix([sp.cos(th1), sp.sin(th1)]) / 2
    p1 = 2 * c1
    c2 = p1 + sp.Matrix([sp.cos(th2), sp.sin(th2)]) / 2
    v1, v2 = c1.diff(t), c2.diff(t)
    Tk = (v1.dot(v1) + v2.dot(v2)) / 2 + (th1.diff(t) ** 2 + th2.diff(t) ** 2) / 24
    V = g * (c1[1] + c2[1])
    Lg = Tk - V
    eqs = [sp.diff(Lg.diff(q.diff(t)), t) - Lg.diff(q) for q in (th1, th2)]
    a1, a2, w1, w2, x1, x2 = sp.symbols("a1 a2 w1 w2 x1 x2")
    rep = {th1.diff(t, 2): a1, th2.diff(t, 2): a2}
    eqs = [e.subs(rep) for e in eqs]
    rep = {th1.diff(t): w1, th2.diff(t): w2}
    eqs = [e.subs(rep) for e in eqs]
    rep = {th1: x1, th2: x2}
    eqs = [e.subs(rep) for e in eqs]
    sol = sp.solve(eqs, [a1, a2], dict=True)[0]
    f = sp.lambdify((x1, x2, w1, w2), [sol[a1], sol[a2]], "numpy")
    return lambda _t, y: [y[2], y[3], *f(*y)]


def test_double_pendulum_against_minimal_ode_and_energy():
    m, free = double_pendulum_model()
    t = np.linspace(0, 3.0, 61)
    sol = free.simulate(t, rtol=1e-11, atol=1e-12)
    ref = solve_ivp(minimal_double_pendulum(), (0, 3.0), [0, 0, 0, 0], method="DOP853",
                    rtol=1e-12, atol=1e-13, t_eval=t)
    np.testing.assert_allclose(sol["a.th"], ref.y[0], atol=2e-7)
    np.testing.assert_allclose(sol["b.th"], ref.y[1], atol=2e-7)
    E = sol.body_energy() + sol.potential_energy()
    assert np.ptp(E) < 1e-8 * 9.81 * 2


def test_two_link_arm_free_acceleration_closed_form():
    # links of length 1, mass 1, centroidal inertia 1/12; unit tip force at angle phi
    m = ms.Model2D()
    a = m.add_body("l1", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0), inertia=1 / 12,
                   guess=((0, 0), 0.3))
    b = m.add_body("l2", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0), inertia=1 / 12,
                   guess=((np.cos(0.3), np.sin(0.3)), 1.2))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)))
    m.add(ms.Revolute2(a.point("tip"), b.point(0)))
    m.add(ms.RelativeAngle1(a.vector((1, 0)), (1, 0), 0.3), name="set1")
    m.add(ms.RelativeAngle1(b.vector((1, 0)), a.vector((1, 0)), 0.9), name="set2")
    phi = m.parameter("loadangle", 0.0)
    m.add_load(ms.Force(b.point("tip"), (sp.cos(phi), sp.sin(phi)), 1.0))
    m.solve(0.0)
    free = m.free(drop=["set1", "set2"])
    th1, q2 = 0.3, 0.9                      # absolute angle of link 1, relative angle of 2
    for ang in np.linspace(0, 2 * np.pi, 7):
        s = free.solve(0.0, initial_condition={"loadangle": ang})
        # joint space: M(q2) [th1dd, q2dd] = J^T F, M of a two-rod arm
        c2 = np.cos(q2)
        M11 = 1 / 3 + 1 + 1 / 3 + c2
        M12 = 1 / 3 + c2 / 2
        M22 = 1 / 3
        Mj = np.array([[M11, M12], [M12, M22]])
        t1, t12 = th1, th1 + q2
        Jt = np.array([[-np.sin(t1) - np.sin(t12), -np.sin(t12)],
                       [np.cos(t1) + np.cos(t12), np.cos(t12)]])
        F = np.array([np.cos(ang), np.sin(ang)])
        acc = np.linalg.solve(Mj, Jt.T @ F)
        np.testing.assert_allclose(s.coordinate("l1.th", 2), acc[0], atol=1e-12)
        np.testing.assert_allclose(s.coordinate("l2.th", 2), acc[0] + acc[1], atol=1e-12)


def test_constraint_drift_over_1000_periods():
    L, g = 0.25, 9.81
    m, free = pendulum(L, g, -0.5)
    T0 = 2 * np.pi * np.sqrt(L / g)
    sol = free.simulate((0.0, 1000 * T0), rtol=1e-6, atol=1e-8)
    s = free.system
    drift = max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(sol.t, sol.q))
    assert drift < 1e-10
    vdrift = max(np.abs(s.jacobian(tk, qk) @ vk).max() for tk, qk, vk in zip(sol.t, sol.q, sol.qd))
    assert vdrift < 1e-10
    E = sol.body_energy() + sol.potential_energy()
    assert np.ptp(E) < 1e-3 * abs(E[0])


def test_spherical_pendulum_conserves_energy_and_vertical_momentum():
    """A rigid body on a ball joint under gravity (3D, Euler parameters): energy and the
    angular momentum about the vertical through the pivot are conserved."""
    m, free = ball_bob()
    sol = free.simulate((0.0, 3.0), initial_condition={("omega", "bob"): (0.3, -0.4, 2.0)},
                        rtol=1e-10, atol=1e-12)
    E = sol.body_energy() + sol.potential_energy()
    assert np.ptp(E) < 1e-7 * abs(E).max()
    # angular momentum about the pivot, z component: H = m rc x vc + A Jc A^T w
    bob = m.body("bob")
    rc = sol.location(bob.point((0, 0, -1.0)))
    vc = sol.velocity(bob.point((0, 0, -1.0)))
    w = sol.omega(bob)
    A = sol.eval(bob.A)
    xx, yy, zz, xy, yz, zx = 0.05, 0.08, 0.04, 0.01, 0, 0
    Jc = np.array([[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]])
    H = 2.0 * np.cross(rc, vc) + np.einsum("nij,jk,nlk,nl->ni", A, Jc, A, w)
    assert np.ptp(H[:, 2]) < 1e-7 * np.abs(H).max()
    assert np.ptp(H[:, 0]) > 1e-2            # the other components do change


def test_acceleration_dependent_load_acts_as_added_mass():
    """A load -m_a a_P at the bob (added mass, depending on accelerations) makes the free
    pendulum move like one of mass m + m_a under the weight of m alone."""
    L, m0, ma, g = 1.2, 2.0, 0.5, 9.81
    m = ms.Model2D()
    b = m.add_body("bar", mass=m0, centroid=(L, 0), inertia=0.0, guess=((0, 0), -0.3))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, -0.3), name="hold")
    m.add_load(ms.Gravity((0, -1), g))
    acc = m.acceleration(b.point((L, 0)))
    m.add_load(ms.Force(b.point((L, 0)), -ma * acc, mode="relative"))
    m.solve(0.0)
    free = m.free(drop=["hold"])
    assert free.system.dynamics.depends_on_qdd and free.linear
    for th, w in ((-0.3, 0.0), (0.4, 1.5), (-2.0, -0.7)):
        s = free.solve(0.0, initial_condition={"bar.th": th, "bar.x": 0, "bar.y": 0,
                                               "bar.th_d": w})
        expected = -m0 * g * L * np.cos(th) / ((m0 + ma) * L**2)
        assert s.coordinate("bar.th", 2) == pytest.approx(expected, rel=1e-10)
    sol = free.simulate((0.0, 1.0), rtol=1e-10, atol=1e-12)
    # energy of the equivalent system (kinetic of m + m_a, potential of m) is conserved
    th, w = sol["bar.th"], sol.coordinate("bar.th", 1)
    E = 0.5 * (m0 + ma) * (L * w) ** 2 + m0 * g * L * np.sin(th)
    assert np.ptp(E) < 1e-8


def test_held_angular_velocity_follows_the_attitude_the_start_projection_gives():
    """``("omega", body)`` with a length parameter changed in the same initial condition: the
    start projection moves (and turns) the body onto the constraints first, then the Euler
    parameters' rates are taken from the angular velocity on the attitude reached. (Rates
    derived on the old attitude could not be held: a ``ModelError`` before.)"""
    m = ms.Model3D()
    L = m.parameter("L", 1.0)
    b = m.add_body("bob", mass=2.0, inertia=(0.05, 0.08, 0.04),
                   guess=((0.3, 0.0, -0.9), (0.3, (0, 1, 0))))
    m.add(ms.Spherical3(b.point((L, 0, 1.0)), m.ground.point((0, 0, 0))), name="ball")
    m.add(ms.RotationLock3(b, (0.3, (0, 1, 0))), name="hold")
    m.add_load(ms.Gravity((0, 0, -1), 9.81))
    m.solve(0.0)
    w = np.array([0.3, -0.4, 2.0])
    for kind in ("omega", "omega_local"):
        s = m.free(drop=["hold"]).solve(0.0, initial_condition={(kind, "bob"): w, "L": 1.3})
        e, ed = s.q[0, 3:7], s.qd[0, 3:7]
        e0, e1, e2, e3 = e
        sg = 1.0 if kind == "omega" else -1.0      # E (global) or G (local)
        E = np.array([[-e1, e0, -sg * e3, sg * e2], [-e2, sg * e3, e0, -sg * e1],
                      [-e3, -sg * e2, sg * e1, e0]])
        np.testing.assert_allclose(2 * E @ ed, w, atol=1e-12)
        assert abs(e @ e - 1) < 1e-12 and abs(e @ ed) < 1e-12
        # the pivot point, now at (1.3, 0, 1) on the body, stays at the origin
        A = np.eye(3) * (e0**2 - e[1:] @ e[1:]) + 2 * np.outer(e[1:], e[1:]) + 2 * e0 * np.array(
            [[0, -e3, e2], [e3, 0, -e1], [-e2, e1, 0]])
        np.testing.assert_allclose(s.q[0, :3] + A @ [1.3, 0, 1.0], 0, atol=1e-12)
        v_pivot = s.qd[0, :3] + np.cross(A @ w if kind == "omega_local" else w, A @ [1.3, 0, 1.0])
        np.testing.assert_allclose(v_pivot, 0, atol=1e-12)


@pytest.mark.parametrize("w, says", [
    ((0.3, float("nan"), 2.0), "finite"),
    ((0.3, -0.4), "three numbers"),
    ("fast", "three numbers"),
    (2.0, "three numbers"),
])
def test_a_bad_angular_velocity_in_an_initial_condition_names_its_key(w, says):
    """``("omega", body)`` must be three finite numbers in space (one in the plane): NaN, a
    wrong length or a string is refused with the key named, not passed to SciPy (which said
    only that ``y0`` must be finite) or to NumPy's shape error."""
    _, free = ball_bob()
    with pytest.raises(ms.ModelError, match=rf"\('omega', 'bob'\).*{says}"):
        free.simulate((0.0, 0.1), initial_condition={("omega", "bob"): w})


def test_a_nan_planar_angular_velocity_is_refused_by_name():
    _, free = pendulum(0.25, 9.81, -0.5)
    with pytest.raises(ms.ModelError, match=r"\('omega', 'bar'\).*finite"):
        free.simulate((0.0, 0.1), initial_condition={("omega", "bar"): float("nan")})
    with pytest.raises(ms.ModelError, match=r"\('omega', 'bar'\).*a number"):
        free.simulate((0.0, 0.1), initial_condition={("omega", "bar"): (1.0, 2.0)})
