"""Large free systems: the augmented matrix's fixed sparsity pattern is analysed once and only
refactored numerically per evaluation (issue 11, "sparse at scale").

Checked against dense LU on the same matrices, against the dense free-acceleration path on a
chain above the sparse threshold, and for singular matrices (which must still raise)."""

import numpy as np
import pytest
import scipy.sparse as sps

import mechsys as ms
from conftest import python_path
from mechsys import models
from mechsys.solvers import _free, _linalg, _patterns, _tolerances
from mechsys.solvers._linalg import FixedPattern
from mechsys.solvers._tolerances import Singular


def _csc(A):
    A = sps.csc_matrix(A)
    A.sort_indices()
    return A


def _banded_kkt(nb, rng):
    """An augmented matrix shaped like a chain's ``[[M, J^T], [J, 0]]`` (3 coordinates and
    2 joint rows per body, joint k on bodies k - 1 and k), rows and columns shuffled so the
    ordering has to be found."""
    n, m = 3 * nb, 2 * nb
    M = np.zeros((n, n))
    J = np.zeros((m, n))
    for k in range(nb):
        B = rng.normal(size=(3, 3))
        M[3 * k : 3 * k + 3, 3 * k : 3 * k + 3] = B @ B.T + 3 * np.eye(3)
        for b in (k - 1, k):
            if b >= 0:
                J[2 * k : 2 * k + 2, 3 * b : 3 * b + 3] = rng.normal(size=(2, 3))
    K = np.block([[M, J.T], [J, np.zeros((m, m))]])
    p = rng.permutation(n + m)
    return K[p][:, p]


def _arrow(N, rng):
    """Diagonal plus a full first row and column: any ordering leaves a wide band."""
    A = np.diag(rng.uniform(1, 2, N) * 10)
    A[0, :] = rng.normal(size=N)
    A[:, 0] = rng.normal(size=N)
    A[0, 0] = 50.0
    return A


@pytest.mark.parametrize("kind", ["banded", "sparse", "superlu"])
def test_fixed_pattern_solves_like_dense_lu(monkeypatch, kind):
    """Banded LU for a chain's pattern; for a wide one the sparse LU in a minimum-degree
    ordering, compiled or (without Numba) SuperLU's with the same ordering and pivoting."""
    monkeypatch.setattr(_linalg, "COMPILED_LU", kind != "superlu")
    rng = np.random.default_rng(3)
    A = _banded_kkt(40, rng) if kind == "banded" else _arrow(400, rng)
    K = _csc(A)
    pat = FixedPattern(K.indptr, K.indices, K.shape[0])
    assert pat.banded == (kind == "banded")
    if kind == "banded":
        assert pat.kl + pat.ku <= 16          # a chain: band widths independent of its length
    for _ in range(3):                        # new values, same pattern: refactor only
        data = K.data * rng.uniform(0.5, 2.0, K.data.size)
        B = sps.csc_matrix((data, K.indices, K.indptr), shape=K.shape).toarray()
        b = rng.normal(size=K.shape[0])
        x = pat.factor(data).solve(b)
        ref = np.linalg.solve(B, b)
        np.testing.assert_allclose(x, ref, rtol=0, atol=1e-11 * np.abs(ref).max())
        assert np.abs(B @ x - b).max() < 1e-11 * np.abs(b).max() * np.abs(B).max()
        if kind != "banded":
            np.testing.assert_allclose(B.T @ pat.factor(data).solve_transposed(b), b,
                                       atol=1e-11 * np.abs(b).max() * np.abs(B).max())
    if kind != "banded":
        # the minimum-degree ordering eliminates the arrow's hub last: no fill, where a fresh
        # SuperLU (COLAMD) fills more; L's unit diagonal not counted
        fresh = _linalg.factor(K)._lu
        fac = pat.factor(K.data)
        assert type(fac).__name__ == {"sparse": "_SparseFactor", "superlu": "_SuperFactor"}[kind]
        assert fac.fill == K.nnz
        assert K.nnz <= fresh.L.nnz + fresh.U.nnz - K.shape[0]


@pytest.mark.parametrize("kind", ["banded", "sparse", "superlu"])
def test_fixed_pattern_detects_singular_matrices(monkeypatch, kind):
    monkeypatch.setattr(_linalg, "COMPILED_LU", kind != "superlu")
    rng = np.random.default_rng(5)
    A = _banded_kkt(30, rng) if kind == "banded" else _arrow(400, rng)
    K = _csc(A)
    pat = FixedPattern(K.indptr, K.indices, K.shape[0])
    pat.factor(K.data)                        # regular (and, for SuperLU, fixes the ordering)
    for scale in (0.0, 1e-18):                # a zero row; a row far below roundoff
        data = K.data.copy()
        data[K.indices == 5] *= scale
        with pytest.raises(Singular):
            pat.factor(data)
        if scale == 0.0:                      # as the general sparse factorisation decides
            with pytest.raises(Singular):
                _linalg.factor(sps.csc_matrix((data, K.indices, K.indptr), shape=K.shape))
    bad = K.data.copy()
    bad[7] = np.nan
    with pytest.raises(Singular):
        pat.factor(bad)


def _chain_free(n):
    m = models.pendulum_chain(n)
    m.solve(0.0)
    return m.free(drop=[f"lock{k}" for k in range(n)])


def _state(free, rng):
    s = free.system
    sol = free.solve(0.0, initial_condition={f"l{k}.th_d": float(v) for k, v in
                                             enumerate(rng.normal(size=len(s.layout.body_slices)))})
    return sol.q[0], sol.qd[0], sol.p


@pytest.mark.parametrize("band_work", [_linalg.BAND_WORK, -1])
def test_sparse_free_acceleration_agrees_with_dense(monkeypatch, band_work):
    """A 32-link chain (160 unknowns: above the sparse threshold) moving: the analysed
    pattern (banded LU, or SuperLU with its ordering reused when the band is too wide) gives
    the dense solution's accelerations and multipliers to roundoff."""
    monkeypatch.setattr(_linalg, "BAND_WORK", band_work)
    free = _chain_free(32)
    s = free.system
    assert s.n + s.m > _tolerances.SPARSE_THRESHOLD
    rng = np.random.default_rng(1)
    q, qd, p = _state(free, rng)
    kern = s.dynamics.free_kernel(True)
    assert kern.pattern.banded == (band_work >= 0)
    sp_qdd, sp_lam, _ = _free.free_acceleration(s, 0.0, q, qd, p)
    sp_qdd2, _, _ = _free.free_acceleration(s, 0.0, q, qd, p)   # second call: refactor only
    np.testing.assert_array_equal(sp_qdd, sp_qdd2)
    monkeypatch.setattr(_free, "SPARSE_THRESHOLD", 10**6)
    de_qdd, de_lam, _ = _free.free_acceleration(s, 0.0, q, qd, p)
    np.testing.assert_allclose(sp_qdd, de_qdd, rtol=0, atol=1e-10 * np.abs(de_qdd).max())
    np.testing.assert_allclose(sp_lam, de_lam, rtol=0, atol=1e-10 * np.abs(de_lam).max())


def test_large_friction_newton_through_its_pattern(monkeypatch):
    """A 32-link chain with Coulomb friction in every joint (160 unknowns): the Newton
    matrix ``[[M, Phi_q^T - dQ/dlambda], [Phi_q, 0]]`` is factorised through its fixed
    pattern (banded), no sparse matrices per iteration: accelerations and multipliers as
    the dense Newton's, and the equations of motion hold at them."""
    m = models.pendulum_chain(32)
    for k in range(32):
        m.add_load(ms.JointFriction(f"j{k}", mu=0.3, radius=0.02, v_eps=1e-3))
    m.solve(0.0)
    free = m.free(drop=[f"lock{k}" for k in range(32)])
    s = free.system
    assert s.n + s.m > _tolerances.SPARSE_THRESHOLD and s.dynamics.depends_on_lambda
    rng = np.random.default_rng(5)
    q, qd, p = _state(free, rng)
    qdd, lam, its = _free.free_acceleration(s, 0.0, q, qd, p)
    rows, cols, pattern = _patterns.free_newton_pattern(s)
    assert pattern.banded and pattern.kl + pattern.ku < 40 and its >= 1
    monkeypatch.setattr(_free, "SPARSE_THRESHOLD", 10**6)
    de_qdd, de_lam, _ = _free.free_acceleration(s, 0.0, q, qd, p)
    np.testing.assert_allclose(qdd, de_qdd, rtol=0, atol=1e-10 * np.abs(de_qdd).max())
    np.testing.assert_allclose(lam, de_lam, rtol=0, atol=1e-10 * np.abs(de_lam).max())
    # the converged equations of motion, evaluated independently
    M, Q, Qv = s.dynamics.terms(0.0, q, qd, lam, p, qdd)
    J = s.jacobian(0.0, q, p)
    res = M @ qdd + J.T @ lam - Q - Qv
    assert np.abs(res).max() <= 1e-9 * (np.abs(Q).max() + np.abs(J.T @ lam).max())


def test_sparse_free_system_with_a_massless_link_is_diagnosed():
    """A massless, inertia-free last link leaves its rotation free of mass: the banded
    factorisation meets a zero pivot and the error names the link, as on the dense path."""
    m = models.pendulum_chain(32)
    m.set_mass_properties("l31", mass=0, inertia=0)
    m.solve(0.0)
    free = m.free(drop=[f"lock{k}" for k in range(32)])
    assert free.system.n + free.system.m > _tolerances.SPARSE_THRESHOLD
    with pytest.raises(ms.SingularMassError, match="l31"):
        free.solve(0.0)


@pytest.mark.parametrize("compiled", [True, False])
def test_jacobian_pattern_matches_rows_to_columns(monkeypatch, compiled):
    """A constraint Jacobian's row i has nothing to do with coordinate i: the rows are
    matched to the columns (a zero-free diagonal) before the symmetric ordering. On a chain
    the band is then as narrow as for 3 loops, where the symmetric ordering alone spans the
    chain; the solves are those of dense LU. A system's Jacobian is then factorised by the
    sparse LU in a minimum-degree ordering (little fill on a chain): compiled, or SuperLU's
    where Numba is missing."""
    monkeypatch.setattr(_linalg, "COMPILED_LU", compiled)
    rng = np.random.default_rng(7)
    s = models.four_bar_chain(40).compile()
    pat = s.jacobian_pattern()
    assert pat is s.jacobian_pattern() and pat.kl + pat.ku <= 10
    assert not pat.banded
    _, indices, indptr = s._csc_structure()
    assert FixedPattern(indptr, indices, s.n).kl > 50       # without the matching
    J = s.jacobian(0.4, s.guess + 0.01 * rng.normal(size=s.n), None, sparse=True)
    assert J.mechsys_pattern is pat
    b = rng.normal(size=s.n)
    fac = _linalg.factor(J)
    assert type(fac).__name__ == ("_SparseFactor" if compiled else "_SuperFactor")
    assert fac.fill <= len(indices) + s.n
    np.testing.assert_allclose(J.toarray() @ fac.solve(b), b, atol=1e-10)
    np.testing.assert_allclose(J.toarray().T @ fac.solve_transposed(b), b, atol=1e-10)
    # a matrix with rows shuffled: the matching finds its diagonal again
    A = _banded_kkt(30, rng)
    P = rng.permutation(A.shape[0])
    K = _csc(A[P])
    shuffled = FixedPattern(K.indptr, K.indices, K.shape[0], match_rows=True)
    assert shuffled.banded and shuffled.kl + shuffled.ku <= 24
    np.testing.assert_allclose(A[P] @ shuffled.factor(K.data).solve(b[:A.shape[0]]),
                               b[:A.shape[0]], atol=1e-9)


def test_structurally_singular_jacobian_pattern_still_raises():
    """A pattern without a perfect matching (an empty column) keeps the rows' order, and its
    matrices are singular as before."""
    A = np.eye(6) * 2.0
    A[:, 3] = 0.0
    A[3, 4] = 1.0
    K = _csc(A)
    K.eliminate_zeros()
    pat = FixedPattern(K.indptr, K.indices, 6, match_rows=True)
    np.testing.assert_array_equal(np.sort(pat.row_perm), np.arange(6))
    with pytest.raises(Singular):
        pat.factor(K.data)


def test_wide_free_system_solves_through_the_sparse_lu(monkeypatch):
    """A radial engine coasting under gravity (its driver dropped; every rod on the crank pin,
    so the augmented matrix's band is as wide as the engine): the pattern takes the sparse LU
    (rows matched to columns first: the multipliers' zero block then pivots on the diagonal
    with little fill), which gives the dense path's accelerations and multipliers, and the
    motion conserves energy."""
    m = models.radial_engine(20, g=9.81)
    m.solve(0.0)
    free = m.free(drop=["drive"])
    s = free.system
    kern = s.dynamics.free_kernel(True)
    assert s.n + s.m > _tolerances.SPARSE_THRESHOLD and not kern.pattern.banded
    sol0 = free.solve(0.0, initial_condition={"crank.th_d": 3.0})
    q, qd, p = sol0.q[0], sol0.qd[0], sol0.p
    fac = kern.pattern.factor(kern(0.0, q, qd, np.zeros(s.m), p)[0].data)
    assert fac.fill < 2 * kern.pattern.indices.size
    sp_qdd, sp_lam, _ = _free.free_acceleration(s, 0.0, q, qd, p)
    monkeypatch.setattr(_free, "SPARSE_THRESHOLD", 10**6)
    de_qdd, de_lam, _ = _free.free_acceleration(s, 0.0, q, qd, p)
    np.testing.assert_allclose(sp_qdd, de_qdd, rtol=0, atol=1e-10 * np.abs(de_qdd).max())
    np.testing.assert_allclose(sp_lam, de_lam, rtol=0, atol=1e-10 * np.abs(de_lam).max())
    monkeypatch.undo()
    python_path(monkeypatch)      # (the Python stepper whole: its pattern's LU every step)
    run = free.simulate((0.0, 0.3), initial_condition={"crank.th_d": 3.0}, method="DOP853",
                        rtol=1e-10, atol=1e-12)
    energy = run.body_energy() + run.potential_energy()
    assert np.abs(energy - energy[0]).max() < 1e-7 * np.abs(energy[0])


def test_large_initial_condition_projection_is_sparse(monkeypatch):
    """Initial values given for some coordinates of a large system (183 coordinates): the
    others take the minimum-norm correction from the sparse ``J^ J^T`` with the held columns
    removed, the dense least squares' answer (which cost O(n^3) at every start); values the
    constraints cannot meet still raise, through the least squares."""
    from mechsys.solvers._linalg import Scaling

    m = models.radial_engine(30, g=9.81)
    m.solve(0.0)
    free = m.free(drop=["drive"])
    s = free.system
    q0 = s.guess + 0.01 * np.random.default_rng(2).normal(size=s.n)
    qd0 = np.zeros(s.n)
    crank = s.layout.index("crank.th")
    qd0[crank] = 3.0
    sc = Scaling.of(s, q0, s.jacobian(0.0, q0, s.p_values))
    got = _free.project_holding(s, 0.0, q0, qd0, s.p_values, sc, [crank], [crank])
    monkeypatch.setattr(_free, "HOLDING_RCOND", np.inf)          # the dense least squares
    ref = _free.project_holding(s, 0.0, q0, qd0, s.p_values, sc, [crank], [crank])
    for a, b in zip(got, ref):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-10)
    assert got[0][crank] == q0[crank] and got[1][crank] == 3.0
    assert np.abs(s.residual(0.0, got[0])).max() < 1e-10
    monkeypatch.undo()
    # a piston held where its rod cannot reach
    far = s.layout.index("piston0.x")
    bad = got[0].copy()
    bad[far] += 10.0
    with pytest.raises(_free.ConsistencyError):
        _free.project_holding(s, 0.0, bad, got[1], s.p_values, sc, [crank, far], [crank])
