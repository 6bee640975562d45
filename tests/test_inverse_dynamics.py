"""Inverse dynamics against Lagrange's equations derived independently in the test, the
power balance and the per-body load balance."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T, models

R, L, M1, M2, M3, J1, J2, G = 2.0, 6.0, 1.5, 2.0, 3.0, 0.4, 5.0, 9.81


def driven_crank(damping=0.0):
    drive = 2 * sp.pi * T + sp.Rational(3, 10) * sp.sin(3 * T)
    m = models.slider_crank(crank=R, rod=L, drive=drive)
    for name, mass, c, J in (("crank", M1, (R / 2, 0), J1), ("rod", M2, (L / 2, 0), J2),
                             ("piston", M3, (0, 0), 0.0)):
        m.set_mass_properties(name, mass=mass, centroid=c, inertia=J)
    m.add_load(ms.Gravity((0, -1), G))
    if damping:
        m.add_load(ms.Damper(m.body("piston").point(0), (20.0, 0.0), damping))
    return m, drive


def lagrange_torque(drive, t_values, damping=0.0):
    """Driving torque on the crank from Lagrange's equations in the crank angle alone."""
    t = sp.Symbol("t")
    th = sp.Function("th")(t)
    xp = R * sp.cos(th) + sp.sqrt(L**2 - (R * sp.sin(th)) ** 2)
    phi = sp.atan2(-R * sp.sin(th), xp - R * sp.cos(th))
    c1 = sp.Matrix([R / 2 * sp.cos(th), R / 2 * sp.sin(th)])
    c2 = sp.Matrix([(R * sp.cos(th) + xp) / 2, R * sp.sin(th) / 2])
    v1, v2 = c1.diff(t), c2.diff(t)
    Tk = (M1 * v1.dot(v1) + J1 * th.diff(t) ** 2 + M2 * v2.dot(v2) + J2 * phi.diff(t) ** 2
          + M3 * xp.diff(t) ** 2) / 2
    V = G * (M1 * c1[1] + M2 * c2[1])
    Lg = Tk - V
    thd = th.diff(t)
    tau = (Lg.diff(thd)).diff(t) - Lg.diff(th)
    if damping:  # damper along the x axis to (20, 0): generalized force -c xd dx/dth
        tau += damping * xp.diff(t) * xp.diff(th)
    drv = drive.subs(T, t)
    tau = tau.subs(th.diff(t, 2), drv.diff(t, 2)).subs(thd, drv.diff(t)).subs(th, drv)
    f = sp.lambdify(t, tau, "numpy")
    return f(t_values)


@pytest.fixture(scope="module")
def solved():
    m, drive = driven_crank()
    t = np.linspace(0, 1, 81)
    return m, drive, t, m.solve(t, solution="dynamic")


def test_driving_torque_matches_lagrange(solved):
    m, drive, t, sol = solved
    _, torque = sol.reaction("drive", "crank")
    np.testing.assert_allclose(torque, lagrange_torque(drive, t), rtol=1e-8, atol=1e-8)


def test_power_balance(solved):
    m, drive, t, sol = solved
    # driver power = d/dt (kinetic + potential), differentiated numerically on a fine grid
    tf = np.linspace(0.1, 0.9, 801)
    fine = m.solve(tf, solution="dynamic")
    E = fine.body_energy() + fine.potential_energy()
    dE = np.gradient(E, tf, edge_order=2)
    P = fine.power("drive")
    np.testing.assert_allclose(P[5:-5], dE[5:-5], rtol=1e-4, atol=1e-3 * np.abs(P).max())


def test_power_balance_with_damper():
    c = 4.0
    m, drive = driven_crank(damping=c)
    tf = np.linspace(0.1, 0.9, 801)
    sol = m.solve(tf, solution="dynamic")
    E = sol.body_energy() + sol.potential_energy()
    dE = np.gradient(E, tf, edge_order=2)
    xd = sol.velocity(m.body("piston").point(0))[:, 0]
    dissipated = c * xd**2
    P = sol.power("drive")
    np.testing.assert_allclose(P[5:-5], dE[5:-5] + dissipated[5:-5], rtol=1e-4,
                               atol=1e-3 * np.abs(P).max())
    _, torque = sol.reaction("drive", "crank")
    np.testing.assert_allclose(torque, lagrange_torque(drive, tf, damping=c), rtol=1e-8,
                               atol=1e-7)


@pytest.mark.parametrize("body", ["crank", "rod", "piston"])
def test_applied_reaction_dynamic_balance(solved, body):
    m, drive, t, sol = solved
    total = (sol.loads(body, "applied") + sol.loads(body, "reaction")
             + sol.loads(body, "dynamic"))
    np.testing.assert_allclose(total, 0, atol=1e-8)
    # and as force/moment pairs at the origin
    parts = [sol.loads(body, k, coordinates="global") for k in ("applied", "reaction", "dynamic")]
    np.testing.assert_allclose(sum(p[0] for p in parts), 0, atol=1e-8)
    np.testing.assert_allclose(sum(p[1] for p in parts), 0, atol=1e-8)


def test_mass_matrix_and_kinetic_energy(solved):
    m, drive, t, sol = solved
    Mc = m.mass_matrix("rod")
    assert Mc.shape == (3, 3)
    Mnum = sol.mass_matrix()
    assert Mnum.shape == (len(t), 9, 9)
    qd = sol.qd
    Tk = 0.5 * np.einsum("ni,nij,nj->n", qd, Mnum, qd)
    np.testing.assert_allclose(Tk, sol.body_energy(), rtol=1e-12)


def test_kinematic_mode_uses_velocity_loads_without_inertia():
    m, drive = driven_crank(damping=2.0)
    sol = m.solve(np.linspace(0, 1, 11), solution="kinematic")
    assert sol.qdd is None
    # crank torque balances gravity and damper only: check with virtual power
    xd = sol.velocity(m.body("piston").point(0))[:, 0]
    P_damper = -2.0 * xd**2
    # power of gravity = -d/dt(potential) = -(dV/dq . qd)
    sol_dyn = m.solve(np.linspace(0, 1, 11), solution="dynamic")
    V = sp.Matrix([m.potential_energy()])
    dV = m.time_derivative(V)[0]
    P_grav = -sol_dyn.eval(dV)
    np.testing.assert_allclose(sol.power("drive") + P_damper + P_grav, 0, atol=1e-8)
