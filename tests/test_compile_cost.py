"""Derive and compile each part once per model (issue 10, section 3).

No wall-clock limits: the tests check *what* is derived and compiled, and that the shared,
template-derived body terms equal an independent computation of the kinetic energy.
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import models
from mechsys.compile._dynamics import body_terms


def chain(n):
    return models.pendulum_chain(n)


def test_dof_compiles_only_a_quick_jacobian():
    m = chain(5)
    m.dof()
    kernels = set(m.compile()._kernels)
    # (a Gruebler count <= 0 and guesses not assembled: dof assembles them first, with the
    # quickly compiled position kernel, decision 0035)
    assert kernels in ({"jac_once"}, {"pos_once"}), kernels
    m.solve(0.0)
    assert {"position", "velocity", "gamma"} <= set(m.compile()._kernels)


def test_dof_after_a_solve_reuses_the_position_kernel():
    m = chain(3)
    m.solve(0.0)
    before = set(m.compile()._kernels)
    m.dof()
    assert set(m.compile()._kernels) == before


def test_velocity_and_acceleration_kernels_compile_on_first_use():
    m = chain(2)
    s = m.compile()
    s.residual(0.0, m.guess())
    assert set(s._kernels) == {"position"}


def test_body_terms_are_shared_between_the_model_and_its_free_system():
    m = chain(6)
    m.solve(0.0, solution="dynamic")
    misses = body_terms.cache_info().misses
    free = m.free(drop=[f"lock{k}" for k in range(6)])
    free.solve(0.0)
    assert body_terms.cache_info().misses == misses   # nothing derived again


def test_free_motion_does_not_compile_the_inverse_dynamics_terms():
    m = chain(2)
    free = m.free(drop=["lock0", "lock1"])
    free.simulate((0, 0.05))
    assert free.system.dynamics._f_terms is None


def _omega_local(e, ed):
    e0, e1, e2, e3 = e
    G = np.array([[-e1, e0, e3, -e2], [-e2, -e3, e0, e1], [-e3, e2, -e1, e0]])
    return 2 * G @ ed


def _rotation(e):
    e0, e1, e2, e3 = e
    return np.array([
        [e0**2 + e1**2 - e2**2 - e3**2, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)],
        [2 * (e1 * e2 + e0 * e3), e0**2 - e1**2 + e2**2 - e3**2, 2 * (e2 * e3 - e0 * e1)],
        [2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0**2 - e1**2 - e2**2 + e3**2]])


def test_spatial_mass_matrix_gives_the_kinetic_energy_of_newton_euler():
    """1/2 qd^T M qd == 1/2 m |v_c|^2 + 1/2 w'^T J w' at random states (offset centroid, full
    inertia tensor): the template derivation against a direct numerical one."""
    mass, c = 2.5, np.array([0.3, -0.2, 0.45])
    J = (0.5, 0.8, 1.1, 0.12, -0.07, 0.05)
    xx, yy, zz, xy, yz, zx = J
    Jm = np.array([[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]])
    m = ms.Model3D()
    b = m.add_body("b", mass=mass, centroid=tuple(c), inertia=J)
    M = m.mass_matrix(b)
    sub_syms = list(b.q)
    rng = np.random.default_rng(3)
    for _ in range(3):
        e = rng.normal(size=4)
        e /= np.linalg.norm(e)
        q = np.concatenate((rng.normal(size=3), e))
        ed = rng.normal(size=4)
        ed -= (ed @ e) * e                                  # keeps |e| = 1
        qd = np.concatenate((rng.normal(size=3), ed))
        Mn = np.array(M.subs(dict(zip(sub_syms, q))), dtype=float)
        A = _rotation(e)
        w_local = _omega_local(e, ed)
        v_c = qd[:3] + A @ np.cross(w_local, c)
        T_ref = 0.5 * mass * v_c @ v_c + 0.5 * w_local @ Jm @ w_local
        assert np.isclose(0.5 * qd @ Mn @ qd, T_ref, rtol=1e-12)


def test_planar_mass_matrix_closed_form():
    m = ms.Model2D()
    b = m.add_body("b", mass=3.0, centroid=(0.4, -0.1), inertia=0.7)
    x, y, th = b.q
    sx = 0.4 * sp.cos(th) + 0.1 * sp.sin(th)      # A c', x component
    sy = 0.4 * sp.sin(th) - 0.1 * sp.cos(th)
    ref = sp.Matrix([[3, 0, -3 * sy], [0, 3, 3 * sx], [-3 * sy, 3 * sx, 0.7 + 3 * 0.17]])
    diff = (m.mass_matrix(b) - ref).applyfunc(sp.simplify)
    assert all(abs(float(d)) < 1e-12 for d in diff)
