"""Large spatial models (Euler parameters) in the compiled free-motion loop.

Their mass matrix has a singular 4 x 4 block per body (``M e = 0`` along the Euler
parameters). The block path makes each such block regular with the rows of the Jacobian on
that body alone (the normalisation row among them: ``M_b + w J_i^T J_i``, loads ``+ w J_i^T
gamma_i``, the same solution since ``J_i qdd = gamma_i``) and takes the rows in an order
that keeps ``J M^-1 J^T`` banded (the system lists the normalisation rows last). Where the
block path cannot run (here forced by ``BLOCK_WORK = 0``), the loop factorises the
augmented matrix by the compiled sparse LU of its pattern's sparse twin, while the Python
path keeps LAPACK's band LU. Checks: every step compiled, the 2D chain's motion when the
spatial chain swings in a plane, energy and constraints kept out of the plane, the model's
accelerations at the outputs (decision 0032: the Python path's solve, to rounding) and the
interpreted loop's numbers bit for bit over the first steps (``MECHSYS_JIT=0``, decision
0082)."""

import numpy as np
import pytest

from conftest import simulate_both
from mechsys import ModelError, models
from mechsys.solvers import _jit_free
from mechsys.solvers._free import free_acceleration
from mechsys.solvers._jit_free import _Blocks, _regular

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
    assert sol.extra["compiled_solver"] == "block"
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


def _kind(monkeypatch, kind):
    """``"sparse"``: no block path (its work limit set to zero), the sparse twin instead."""
    if kind == "sparse":
        monkeypatch.setattr(_jit_free, "BLOCK_WORK", 0.0)


@pytest.mark.parametrize("kind", ["block", "sparse"])
@pytest.mark.parametrize("method", ["dop853", "adams"])
def test_out_of_plane_fall_compiled(monkeypatch, method, kind):
    """A zigzag chain falls out of any plane: every step compiled, loops closed, Euler
    parameters of unit norm, the energy kept and the model's accelerations and multipliers
    at the loop's outputs; interpreted, the loop's first steps bit for bit (DOP853)."""
    free = _free(zigzag=0.3)
    grid = np.linspace(0.0, 0.5, 6)
    opts = dict(rtol=1e-10, atol=1e-12) if method == "dop853" else dict(max_error=1e-10)
    _kind(monkeypatch, kind)
    if method == "dop853":
        # (Mech's Adams is compared bit for bit on the small systems: an interpreted step of
        # this chain costs tenths of a second)
        _both(monkeypatch, free, (0.0, 0.01), method=method, **opts)
    jit = free.simulate(grid, method=method, **opts)
    assert jit.extra["compiled_solver"] == kind
    assert jit.extra["compiled_steps"] == jit.extra["steps"] > 5
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


@pytest.mark.parametrize("kind", ["block", "sparse"])
def test_same_steps_solve_as_the_band_lu(monkeypatch, kind):
    """Every step accepted at ``max_step``: at each output the loop's solve (regularised
    blocks, or the sparse LU) gives the accelerations and multipliers of the Python path's
    band LU (``free_acceleration``) to 1e-10 (the interpreted tier of these solves: the
    out-of-plane fall)."""
    free = _free(zigzag=0.3)
    _kind(monkeypatch, kind)
    monkeypatch.setenv("MECHSYS_JIT", "1")
    jit = free.simulate(np.linspace(0.0, 0.2, 5), rtol=1e6, atol=1e6, max_step=2e-3)
    assert jit.extra["compiled_solver"] == kind
    assert jit.extra["compiled_steps"] == jit.extra["steps"] >= 100
    s = free.system
    for k in range(len(jit.t)):
        qdd, lam, _ = free_acceleration(s, float(jit.t[k]), jit.q[k], jit.qd[k], s.p_values)
        assert np.abs(jit.qdd[k] - qdd).max() <= 1e-10 * (np.abs(qdd).max() + 1.0)
        assert np.abs(jit.lam[k] - lam).max() <= 1e-10 * (np.abs(lam).max() + 1.0)


def test_euler_blocks_made_regular(monkeypatch):
    """A turned rod's Euler-parameter block is singular; the block path's test (on its
    unit-diagonal form) says so, and its own rows make it regular. A mid-size chain (110
    unknowns: its rows in the system's order) then runs the block path, every step compiled
    (before: "block" chosen on a plain Cholesky that passed at the rounding level, every
    step handed back to Python). Above 150 unknowns the rows are reordered to a band of 6
    whatever the length. A planar chain keeps its structure: no regularised block, its rows
    in their order."""
    free = _free(links=10, zigzag=0.3)
    s = free.system
    q0 = free.solve(0.0).q[0]
    M = s.dynamics.terms(0.0, q0, np.zeros(s.n), np.zeros(s.m), s.p_values)[0]
    # every rod's block (x, y, z, e0..e3) is singular (rank 6 of 7)
    for k in range(10):
        B = M[7 * k:7 * k + 7, 7 * k:7 * k + 7]
        ev = np.linalg.eigvalsh(B)
        assert abs(ev[0]) < 1e-12 * ev[-1] and ev[1] > 1e-4 * ev[-1]
        assert not _regular(B)
    blocks = _Blocks.of(s, s.p_values, (0.0, q0))
    kM = len(s.dynamics.M_rows)
    assert blocks.arrays[7].size > kM                 # regularising rows listed
    assert blocks.arrays[2].size == s.m + 1           # the system's row order
    big = _free(links=LINKS, zigzag=0.3)
    b24 = _Blocks.of(big.system, big.system.p_values, (0.0, big.solve(0.0).q[0]))
    assert b24.arrays[2].size == 2 * big.system.m + 1 and b24.bandwidth == 6
    monkeypatch.setenv("MECHSYS_JIT", "1")
    sol = free.simulate(np.linspace(0.0, 0.3, 4), rtol=1e-9, atol=1e-11)
    assert sol.extra["compiled_solver"] == "block"
    assert sol.extra["compiled_steps"] == sol.extra["steps"] > 5
    assert _gap(free, sol) < 1e-10
    m2 = models.pendulum_chain(10)
    m2.solve(0.0)
    f2 = m2.free(drop=[f"lock{k}" for k in range(10)])
    q2 = f2.solve(0.0).q[0]
    b2 = _Blocks.of(f2.system, f2.system.p_values, (0.0, q2))
    assert b2.arrays[7].size == len(f2.system.dynamics.M_rows)
    assert b2.arrays[2].size == f2.system.m + 1


@pytest.mark.parametrize("loops,ordered,band", [(2, False, 9), (10, False, 41), (15, True, 5)])
def test_rows_reordered_only_for_wide_bands(loops, ordered, band):
    """The block path reorders the rows only above 150 unknowns, when their own band exceeds
    16 and the order halves it: the n-four-bar lists its equations by kind (band 61 at 15
    loops, 185 unknowns; 5 in order). Smaller ones keep the system's order (2 loops: band 9;
    10 loops, 125 unknowns: band 41), and with it the hand-over test near their singular
    instants, on which the examples' comparison of the two loops and the robustness table
    rely."""
    m = models.n_four_bar(loops, 9.81)
    m.solve(0.0)
    free = m.free(drop=["hold"])
    s = free.system
    blocks = _Blocks.of(s, s.p_values, (0.0, free.solve(0.0).q[0]))
    assert (blocks.arrays[2].size > s.m + 1) == ordered
    assert blocks.bandwidth == band


@pytest.mark.parametrize("case", ["spatial", "four_bar"])
def test_gram_by_blocks_is_the_band_of_the_product(case):
    """``_jit_free_loop._gram`` (each block couples its rows, decision 0074) against the dense
    product ``A B^T`` of the per-(row, block) segments laid out as ``m x n`` matrices:
    equal inside the band, and the product has nothing outside it. The spatial chain has
    rows on one block (the normalisation) and on two; the 15-loop n-four-bar its rows in
    the reordered (banded) structure."""
    from mechsys.solvers._jit_free_loop import _gram

    if case == "spatial":
        free = _free(6, zigzag=0.3)
    else:
        m = models.n_four_bar(15, 9.81)
        m.solve(0.0)
        free = m.free(drop=["hold"])
    s = free.system
    blocks = _Blocks.of(s, s.p_values, (0.0, free.solve(0.0).q[0]))
    bstart, _, rptr, rblk, roff, _, bsize, _, segs = blocks.arrays
    m_ = s.m
    rng = np.random.default_rng(7)
    A_st, B_st = rng.normal(size=roff[-1]), rng.normal(size=roff[-1])
    A, B = np.zeros((m_, s.n)), np.zeros((m_, s.n))
    for i in range(m_):
        for p in range(rptr[i], rptr[i + 1]):
            b, o, z = rblk[p], roff[p], bsize[rblk[p]]
            A[i, bstart[b]:bstart[b] + z] = A_st[o:o + z]
            B[i, bstart[b]:bstart[b] + z] = B_st[o:o + z]
    S = A @ B.T
    bw = blocks.bandwidth
    Sb = np.full((m_, bw + 1), np.nan)
    _gram.py_func(A_st, B_st, segs, bsize, Sb)
    i, k = np.tril_indices(m_)
    inside = i - k <= bw
    assert np.allclose(Sb[i[inside], (i - k)[inside]], S[i[inside], k[inside]], rtol=1e-13,
                       atol=1e-13)
    assert not np.any(S[i[~inside], k[~inside]])


def test_units_of_length_do_not_change_the_motion():
    """The same chain in metres and in millimetres (rods of 1000 mm, g = 9810 mm/s^2): the
    block test and the regularising weight are free of units, so both take the block path
    with the same rows, and the Euler parameters agree over the fall."""
    grid = np.linspace(0.0, 0.5, 6)
    runs = []
    for length, g in ((1.0, 9.81), (1000.0, 9810.0)):
        m = models.spatial_chain(LINKS, g=g, zigzag=0.3, length=length)
        m.solve(0.0)
        free = m.free(drop=[f"lock{k}" for k in range(LINKS)])
        sol = free.simulate(grid, rtol=1e-10, atol=1e-12 * length)
        assert sol.extra["compiled_solver"] == "block"
        assert sol.extra["compiled_steps"] == sol.extra["steps"]
        q0 = free.solve(0.0).q[0]
        rows = _Blocks.of(free.system, free.system.p_values, (0.0, q0)).arrays[7]
        runs.append((sol, rows, length))
    (a, ra, _), (b, rb, scale) = runs
    np.testing.assert_array_equal(ra, rb)
    for k in range(LINKS):
        for i in range(4):
            np.testing.assert_allclose(a[f"l{k}.e{i}"], b[f"l{k}.e{i}"], rtol=0, atol=1e-8)
        np.testing.assert_allclose(a[f"l{k}.z"], b[f"l{k}.z"] / scale, rtol=0, atol=1e-8)


@pytest.mark.parametrize("bad", [dict(n_links=0), dict(n_links=2.0), dict(n_links=True),
                                 dict(n_links=2, g=float("nan")), dict(n_links=2, zigzag="0.3"),
                                 dict(n_links=2, zigzag=float("inf")), dict(n_links=2, length=0.0),
                                 dict(n_links=2, length=-1.0)])
def test_spatial_chain_refuses_bad_input(bad):
    with pytest.raises(ModelError, match="spatial_chain"):
        models.spatial_chain(**bad)
