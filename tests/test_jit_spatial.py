"""Large spatial models (Euler parameters) in the compiled free-motion loop.

Their mass matrix has a singular 4 x 4 block per body (``M e = 0`` along the Euler
parameters), so the block path (Schur complement on ``M^-1``) cannot take them. Above 150
unknowns the loop factorises the augmented matrix by the compiled sparse LU of its pattern
(the sparse kind), while the Python path keeps LAPACK's band LU: two independent
factorisations of the same equations. Checks: every step compiled, the 2D chain's motion
when the spatial chain swings in a plane, energy and constraints kept out of the plane,
the Python path's motion (same steps: to rounding; adaptive: to the tolerance) and the
model's accelerations at the outputs."""

import numpy as np
import pytest

from conftest import simulate_both
from mechsys import ModelError, models
from mechsys.solvers._free import free_acceleration
from mechsys.solvers._jit_free import _Blocks

pytest.importorskip("numba")

LINKS = 24                  # 168 coordinates + 96 equations: above the sparse threshold


def _free(links=LINKS, zigzag=0.0):
    m = models.spatial_chain(links, zigzag=zigzag)
    m.solve(0.0)
    return m.free(drop=[f"lock{k}" for k in range(links)])


_both = simulate_both


def _gap(free, sol):
    s = free.system
    return max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(sol.t, sol.q))


def test_planar_swing_is_the_planar_chain():
    """With every rod along X the chain swings in the XZ plane: the planar chain of the same
    rods (block path), X and Z for x and y, to the tolerance; no motion along Y."""
    grid = np.linspace(0.0, 0.5, 6)
    sol = _free().simulate(grid, rtol=1e-10, atol=1e-12)
    assert sol.extra["compiled_solver"] == "sparse"
    assert sol.extra["compiled_steps"] == sol.extra["steps"] > 5
    m2 = models.pendulum_chain(LINKS)
    m2.solve(0.0)
    flat = m2.free(drop=[f"lock{k}" for k in range(LINKS)]).simulate(grid, rtol=1e-10,
                                                                      atol=1e-12)
    assert flat.extra["compiled_solver"] == "block"
    for k in range(LINKS):
        np.testing.assert_allclose(sol[f"l{k}.x"], flat[f"l{k}.x"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(sol[f"l{k}.z"], flat[f"l{k}.y"], rtol=0, atol=1e-9)
        assert np.abs(sol[f"l{k}.y"]).max() < 1e-12
    assert np.abs(sol.q[-1] - sol.q[0]).max() > 0.1          # it did move


@pytest.mark.parametrize("method", ["dop853", "adams"])
def test_out_of_plane_fall_compiled(monkeypatch, method):
    """A zigzag chain falls out of any plane: every step compiled, loops closed, Euler
    parameters of unit norm, the energy kept, the Python path's motion within the tolerance
    and the model's accelerations and multipliers at the loop's outputs."""
    free = _free(zigzag=0.3)
    grid = np.linspace(0.0, 0.5, 6)
    opts = dict(rtol=1e-10, atol=1e-12) if method == "dop853" else dict(max_error=1e-10)
    py, jit = _both(monkeypatch, free, grid, method=method, **opts)
    assert jit.extra["compiled_solver"] == "sparse" and py.extra["compiled_steps"] == 0
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 5
    np.testing.assert_allclose(jit.q, py.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(jit.qd, py.qd, rtol=0, atol=1e-7)
    assert _gap(free, jit) < 1e-10
    for k in range(LINKS):
        e = np.column_stack([jit[f"l{k}.e{i}"] for i in range(4)])
        np.testing.assert_allclose(np.linalg.norm(e, axis=1), 1.0, rtol=0, atol=1e-10)
    kinetic, potential = jit.body_energy(), jit.potential_energy()
    energy = kinetic + potential                  # zero at the start: at rest, Z = 0
    assert np.abs(energy - energy[0]).max() < 1e-8 * np.abs(potential).max()
    assert np.abs(jit["l5.y"] - jit["l5.y"][0]).max() > 0.1       # out of the plane
    s = free.system
    for k in (2, 5):
        qdd, lam, _ = free_acceleration(s, float(jit.t[k]), jit.q[k], jit.qd[k], s.p_values)
        np.testing.assert_allclose(jit.qdd[k], qdd, rtol=0, atol=1e-10 * np.abs(qdd).max())
        np.testing.assert_allclose(jit.lam[k], lam, rtol=0, atol=1e-10 * np.abs(lam).max())


def test_same_steps_agree_to_rounding(monkeypatch):
    """Every step accepted at ``max_step`` in both loops: the two factorisations (sparse LU
    in the loop, band LU in Python) give the same motion to 1e-12."""
    free = _free(zigzag=0.3)
    grid = np.linspace(0.0, 0.2, 3)
    py, jit = _both(monkeypatch, free, grid, rtol=1e6, atol=1e6, max_step=2e-3)
    assert jit.extra["compiled_steps"] == jit.extra["steps"] == py.extra["steps"] >= 100
    scale = np.abs(py.q).max(axis=0) + 1.0
    assert (np.abs(jit.q - py.q) / scale).max() <= 1e-12
    assert (np.abs(jit.qd - py.qd) / (np.abs(py.qd).max(axis=0) + 1.0)).max() <= 1e-12


def test_mid_size_spatial_model_runs_dense_not_block(monkeypatch):
    """Between 24 and 150 unknowns a spatial chain takes the dense augmented system. Its
    Euler-parameter blocks can pass a plain Cholesky with a pivot at the rounding level
    (turned rods): the block path's test reads the unit-diagonal form, so they do not
    select it (before, they did, and the loop handed every step back to Python)."""
    free = _free(links=10, zigzag=0.3)
    s = free.system
    assert 24 < s.n + s.m <= 150
    q0 = free.solve(0.0).q[0]
    assert _Blocks.of(s, s.p_values, (0.0, q0)) is None
    monkeypatch.setenv("MECHSYS_JIT", "1")
    sol = free.simulate(np.linspace(0.0, 0.3, 4), rtol=1e-9, atol=1e-11)
    assert sol.extra["compiled_solver"] == "augmented"
    assert sol.extra["compiled_steps"] == sol.extra["steps"] > 5
    # planar chains still take the block path
    m2 = models.pendulum_chain(10)
    m2.solve(0.0)
    f2 = m2.free(drop=[f"lock{k}" for k in range(10)])
    q2 = f2.solve(0.0).q[0]
    assert _Blocks.of(f2.system, f2.system.p_values, (0.0, q2)) is not None


@pytest.mark.parametrize("bad", [dict(n_links=0), dict(n_links=2.0), dict(n_links=True),
                                 dict(n_links=2, g=float("nan")), dict(n_links=2, zigzag="0.3"),
                                 dict(n_links=2, zigzag=float("inf"))])
def test_spatial_chain_refuses_bad_input(bad):
    with pytest.raises(ModelError, match="spatial_chain"):
        models.spatial_chain(**bad)
