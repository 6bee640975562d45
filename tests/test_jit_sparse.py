"""The compiled sparse LU (solvers/_jit_sparse.py): Gilbert-Peierls with diagonal-preferring
threshold pivoting. Solutions against SciPy's SuperLU and NumPy, the factors' storage
conventions, pivoting (saddle points; dense partial pivoting at tol = 1), the status codes,
and that a tree ordered leaves first factors without fill."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

nb = pytest.importorskip("numba")

from mechsys.solvers._jit_sparse import (  # noqa: E402
    SparseLU,
    lu_factor,
    lu_pivot_ratio,
    lu_solve,
    lu_solve_t,
    work_sizes,
)
from mechsys.solvers._tolerances import Singular  # noqa: E402


def _random(rng, n, density):
    """Random nonsymmetric sparse matrix, structurally nonsingular (a random permutation added)."""
    A = sps.random(n, n, density=density, random_state=rng, format="lil")
    A = A.toarray()
    A[A != 0] = rng.standard_normal(np.count_nonzero(A))
    A[rng.permutation(n), np.arange(n)] += rng.standard_normal(n) + np.sign(rng.standard_normal(n))
    return sps.csc_matrix(A)


def _raw(A, capacity=None, tol=0.1):
    """lu_factor on fresh arrays; returns (status, arrays dict)."""
    A = sps.csc_matrix(A)
    n = A.shape[0]
    cap = 4 * A.nnz + n if capacity is None else capacity
    capL, capU = (cap, cap) if np.isscalar(cap) else cap
    ni, nx = work_sizes(n)
    f = dict(Lp=np.zeros(n + 1, np.int64), Li=np.zeros(capL, np.int64), Lx=np.zeros(capL),
             Up=np.zeros(n + 1, np.int64), Ui=np.zeros(capU, np.int64), Ux=np.zeros(capU),
             pinv=np.zeros(n, np.int64))
    st = lu_factor(n, A.indptr.astype(np.int64), A.indices.astype(np.int64), A.data.astype(float),
                   tol, f["Lp"], f["Li"], f["Lx"], f["Up"], f["Ui"], f["Ux"], f["pinv"],
                   np.full(ni, 12345, np.int64), np.full(nx, np.nan))   # garbage work arrays
    return st, f


def _residual(A, x, b):
    return np.linalg.norm(A @ x - b) / (sla.norm(A, 1) * np.linalg.norm(x) + np.linalg.norm(b))


@pytest.mark.parametrize("n", [1, 2, 3, 7, 20, 60, 150, 300])
@pytest.mark.parametrize("density", [0.02, 0.1, 0.4])
@pytest.mark.parametrize("seed", [0, 1])
def test_random_against_splu(n, density, seed):
    rng = np.random.default_rng(1000 * n + seed + int(100 * density))
    A = _random(rng, n, density)
    Ad = A.toarray()
    lu = SparseLU(A)
    ref = spla.splu(A)
    for _ in range(2):
        b = rng.standard_normal(n)
        x = lu.solve(b)
        y = lu.solve_transposed(b)
        assert _residual(Ad, x, b) < 1e-14
        assert _residual(Ad.T, y, b) < 1e-14
        cond = np.linalg.cond(Ad, 1)
        xs, ys = ref.solve(b), ref.solve(b, trans="T")
        assert np.linalg.norm(x - xs) <= 1e-13 * cond * np.linalg.norm(xs)
        assert np.linalg.norm(y - ys) <= 1e-13 * cond * np.linalg.norm(ys)
    X = rng.standard_normal((n, 3))              # several right-hand sides at once
    Y = lu.solve(X)
    for j in range(3):
        assert _residual(Ad, Y[:, j], X[:, j]) < 1e-14


@pytest.mark.parametrize("seed", range(4))
def test_factor_storage_conventions(seed):
    """P A = L U with (P A)[pinv[i]] = A[i]; rows in pivoted numbering; U's diagonal last in
    each column; L's unit diagonal not stored, its rows below k; U's other rows above k."""
    rng = np.random.default_rng(seed)
    n = 80
    A = _random(rng, n, 0.05)
    lu = SparseLU(A, tol=0.3)
    assert sorted(lu.pinv) == list(range(n))
    PA = np.empty((n, n))
    PA[lu.pinv] = A.toarray()
    assert np.allclose(lu.L.toarray() @ lu.U.toarray(), PA, atol=1e-12 * np.abs(PA).max())
    for k in range(n):
        ui = lu.Ui[lu.Up[k]:lu.Up[k + 1]]
        assert ui[-1] == k and np.all(ui[:-1] < k)
        assert np.all(lu.Li[lu.Lp[k]:lu.Lp[k + 1]] > k)
    d = lu.Ux[lu.Up[1:] - 1]
    assert lu.rcond == pytest.approx(np.abs(d).min() / np.abs(d).max())
    assert lu.nnz_L == lu.Lp[-1] and lu.nnz_U == lu.Up[-1]


def test_row_order_and_duplicates():
    """Rows of a column in any order, duplicates summed: the same solution."""
    rng = np.random.default_rng(5)
    n = 40
    A = _random(rng, n, 0.1)
    b = rng.standard_normal(n)
    x0 = SparseLU(A).solve(b)
    Ap = A.indptr.astype(np.int64)
    Ai = A.indices.astype(np.int64).copy()
    Ax = A.data.copy()
    for k in range(n):                           # shuffle within columns
        s = slice(Ap[k], Ap[k + 1])
        perm = rng.permutation(Ap[k + 1] - Ap[k])
        Ai[s], Ax[s] = Ai[s][perm], Ax[s][perm]
    B = sps.csc_matrix((Ax, Ai, Ap), shape=(n, n))
    st, f = _raw(B)
    assert st == 0
    x = np.empty(n)
    lu_solve(n, f["pinv"], f["Lp"], f["Li"], f["Lx"], f["Up"], f["Ui"], f["Ux"], b, x, np.empty(n))
    assert np.allclose(x, x0, rtol=1e-10, atol=1e-12)
    # every entry split in two halves: duplicates, summed
    Ap2 = 2 * Ap
    Ai2 = np.repeat(Ai, 2)
    Ax2 = np.repeat(Ax / 2, 2)
    C = sps.csc_matrix((Ax2, Ai2, Ap2), shape=(n, n))
    st, f = _raw(C)
    assert st == 0
    lu_solve(n, f["pinv"], f["Lp"], f["Li"], f["Lx"], f["Up"], f["Ui"], f["Ux"], b, x, np.empty(n))
    assert np.allclose(x, x0, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("tol", [0.0, 0.1, 1.0])
@pytest.mark.parametrize("seed", range(3))
def test_saddle_point_needs_off_diagonal_pivots(tol, seed):
    """[[M, J^T], [J, 0]] (M diagonal positive, J full row rank). With the multipliers
    ordered first, [[0, J], [J^T, M]], the zero diagonal block forces pivots off the
    diagonal; with M first, the Schur complement -J M^-1 J^T fills it."""
    rng = np.random.default_rng(seed)
    nm, nc = 30, 12
    M = sps.diags(rng.uniform(1, 3, nm))
    J = sps.random(nc, nm, density=0.15, random_state=rng) + sps.eye(nc, nm)
    n = nm + nc
    for first in ("M", "0"):
        if first == "M":
            K = sps.bmat([[M, J.T], [J, None]], format="csc")
        else:
            K = sps.bmat([[None, J], [J.T, M]], format="csc")
        Kd = K.toarray()
        assert np.linalg.matrix_rank(Kd) == n
        lu = SparseLU(K, tol=tol)
        if first == "0":
            prow = np.argsort(lu.pinv)                 # prow[k]: the k-th pivot row
            assert prow[0] >= nc                       # K[0, 0] = 0: a row of J^T instead
            assert not np.array_equal(prow, np.arange(n))
        b = rng.standard_normal(n)
        x = lu.solve(b)
        assert _residual(Kd, x, b) < 1e-14
        assert np.allclose(x, np.linalg.solve(Kd, b), rtol=1e-9, atol=1e-11)
        y = lu.solve_transposed(b)
        assert _residual(Kd.T, y, b) < 1e-14


def test_diagonal_preferred_when_large_enough():
    rng = np.random.default_rng(3)
    n = 50
    A = _random(rng, n, 0.1).toarray()
    A[np.arange(n), np.arange(n)] = 0.0
    A += np.diag(np.abs(A).sum(axis=0) * 0.2 + 1)     # diagonal >= 0.2 of each column's mass
    lu = SparseLU(sps.csc_matrix(A), tol=0.01)
    assert np.array_equal(lu.pinv, np.arange(n))
    lu1 = SparseLU(sps.csc_matrix(A), tol=1.0)         # partial pivoting moves some rows
    assert not np.array_equal(lu1.pinv, np.arange(n))
    b = rng.standard_normal(n)
    assert np.allclose(lu.solve(b), lu1.solve(b), rtol=1e-9)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("n", [1, 2, 6, 15, 40])
def test_tol_one_is_dense_partial_pivoting(seed, n):
    """tol = 1 chooses LAPACK getrf's pivots (distinct magnitudes: no ties)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    if seed % 2:
        A *= rng.random((n, n)) < 0.5                  # sparse too
        A[rng.permutation(n), np.arange(n)] += 1.0 + rng.random(n)
    _, piv = sla.lu_factor(A)
    perm = np.arange(n)
    for j, p in enumerate(piv):
        perm[j], perm[p] = perm[p], perm[j]
    ref = np.empty(n, np.int64)
    ref[perm] = np.arange(n)                           # row perm[k] is the k-th pivot row
    lu = SparseLU(sps.csc_matrix(A), tol=1.0)
    assert np.array_equal(lu.pinv, ref)
    P, L, U = sla.lu(A)
    assert np.allclose(lu.U.toarray(), U, atol=1e-12 * np.abs(U).max())


def _tree(rng, branches, depth, bs, hub_first=False):
    """A hub block and ``branches`` chains of ``depth`` blocks, ``bs x bs`` dense blocks,
    diagonally weighted; ordered leaves first (tips, ..., bases, hub) unless ``hub_first``."""
    nb_ = 1 + branches * depth
    order = []                                         # block numbers: hub 0, chain c level d
    for d in range(depth - 1, -1, -1):
        order += [1 + c * depth + d for c in range(branches)]
    order = [0] + order[::-1] if hub_first else order + [0]   # root first: bases, ..., tips
    pos = {blk: i for i, blk in enumerate(order)}
    edges = []
    for c in range(branches):
        prev = 0
        for d in range(depth):
            edges.append((prev, 1 + c * depth + d))
            prev = 1 + c * depth + d
    N = nb_ * bs
    rows, cols, vals = [], [], []

    def block(bi, bj, diag=False):
        B = rng.standard_normal((bs, bs))
        if diag:
            B += np.eye(bs) * (2 * bs + 10)
        for r in range(bs):
            for c in range(bs):
                rows.append(pos[bi] * bs + r)
                cols.append(pos[bj] * bs + c)
                vals.append(B[r, c])
    for blk in range(nb_):
        block(blk, blk, diag=True)
    for a, b in edges:
        block(a, b)
        block(b, a)
    return sps.csc_matrix((vals, (rows, cols)), shape=(N, N))


def test_star_leaves_first_has_no_fill():
    """Arrow matrix (hub last): nnz(L) + nnz(U) = nnz(A); hub first: dense fill."""
    rng = np.random.default_rng(0)
    n = 200
    A = sps.lil_matrix((n, n))
    A.setdiag(10.0 + rng.random(n))
    A[n - 1, :n - 1] = rng.standard_normal(n - 1)
    A[:n - 1, n - 1] = rng.standard_normal(n - 1)[:, None]
    A = A.tocsc()
    lu = SparseLU(A)
    assert lu.nnz_L + lu.nnz_U == A.nnz
    p = np.r_[n - 1, np.arange(n - 1)]                 # hub first: the worst ordering
    lu_bad = SparseLU(A[p][:, p])
    assert lu_bad.nnz_L + lu_bad.nnz_U > n * n // 2
    b = rng.standard_normal(n)
    assert _residual(A.toarray(), lu.solve(b), b) < 1e-14


@pytest.mark.parametrize("bs", [1, 3])
def test_tree_fill_grows_linearly(bs):
    """A star of 40 (then 80) branches of 3 blocks, leaves first: no fill beyond nnz(A), so
    the factors (hence the work) grow linearly with the number of branches."""
    rng = np.random.default_rng(1)
    counts = []
    for branches in (40, 80):
        A = _tree(rng, branches, 3, bs)
        lu = SparseLU(A)
        assert lu.nnz_L + lu.nnz_U == A.nnz
        assert np.array_equal(lu.pinv, np.arange(A.shape[0]))   # diagonal weighted: kept
        b = rng.standard_normal(A.shape[0])
        assert _residual(A.toarray(), lu.solve(b), b) < 1e-14
        assert _residual(A.T.toarray(), lu.solve_transposed(b), b) < 1e-14
        counts.append(lu.nnz_L + lu.nnz_U)
    blocks = [1 + 40 * 3, 1 + 80 * 3]
    per_edge = 2 * bs * bs                             # two coupling blocks per tree edge
    for c, nbk in zip(counts, blocks, strict=True):
        assert c == nbk * bs * bs + (nbk - 1) * per_edge
    hub_first = _tree(rng, 40, 3, bs, hub_first=True)     # the same tree, root first
    bad = SparseLU(hub_first)
    assert bad.nnz_L + bad.nnz_U > 3 * hub_first.nnz


def test_zero_column_is_singular():
    rng = np.random.default_rng(2)
    n = 30
    A = _random(rng, n, 0.1)
    A.data[A.indptr[17]:A.indptr[18]] = 0.0            # stored zeros
    assert A.indptr[18] > A.indptr[17]
    st, _ = _raw(A)
    assert st == 17 + 1
    A2 = A.copy()
    A2.eliminate_zeros()                               # structurally empty column too
    st, _ = _raw(A2)
    assert st == 18
    with pytest.raises(Singular):
        SparseLU(A2)


def test_equal_columns_and_zero_row():
    rng = np.random.default_rng(4)
    n = 25
    A = _random(rng, n, 0.2).toarray()
    A[:, 9] = A[:, 4]
    st, f = _raw(sps.csc_matrix(A))
    if st == 0:                                        # rounding left a tiny pivot
        assert lu_pivot_ratio(n, f["Up"], f["Ux"]) < 1e-12
    else:
        assert st > 0
    # exact arithmetic (small integers, pivots +-1): the dependent column's pivot is exactly 0
    B = np.eye(n) + np.diag(np.ones(n - 1), -1)
    B[:, 6] = B[:, 3] + B[:, 5]
    st, _ = _raw(sps.csc_matrix(B), tol=1.0)
    assert st == 7
    C = _random(rng, n, 0.2).toarray()
    C[11, :] = 0.0                                     # a zero row: no candidate at the end
    st, _ = _raw(sps.csc_matrix(C))
    assert st > 0


def test_capacity_status_and_exact_sizes():
    rng = np.random.default_rng(6)
    n = 60
    A = _random(rng, n, 0.08)
    st, _ = _raw(A, capacity=(1, 1))
    assert st == -1
    st, _ = _raw(A, capacity=(0, 10**6))
    assert st == -1
    st, f = _raw(A)
    assert st == 0
    nl, nu = int(f["Lp"][-1]), int(f["Up"][-1])
    assert _raw(A, capacity=(nl, nu))[0] == 0          # the check is exact
    assert _raw(A, capacity=(nl - 1, nu))[0] == -1
    assert _raw(A, capacity=(nl, nu - 1))[0] == -1
    lu = SparseLU(A, capacity=1)                       # grows and retries
    assert (lu.nnz_L, lu.nnz_U) == (nl, nu)
    b = rng.standard_normal(n)
    assert _residual(A.toarray(), lu.solve(b), b) < 1e-14


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_input(bad):
    rng = np.random.default_rng(7)
    n = 20
    A = _random(rng, n, 0.2)
    A.data[A.nnz // 2] = bad
    st, _ = _raw(A)
    assert st == -2
    with pytest.raises(Singular):
        SparseLU(A)


def test_pivot_ratio_edge_cases():
    Up = np.array([0, 1, 2, 3], np.int64)
    assert lu_pivot_ratio(3, Up, np.array([2.0, -4.0, 1.0])) == 0.25
    assert lu_pivot_ratio(3, Up, np.array([2.0, np.nan, 1.0])) == 0.0
    assert lu_pivot_ratio(3, Up, np.array([2.0, np.inf, 1.0])) == 0.0
    assert lu_pivot_ratio(3, Up, np.array([0.0, 0.0, 0.0])) == 0.0
    assert lu_pivot_ratio(0, Up[:1], np.zeros(0)) == 1.0


def test_empty_and_invalid_arguments():
    st, f = _raw(sps.csc_matrix((0, 0)))
    assert st == 0 and f["Lp"][0] == 0 and f["Up"][0] == 0
    lu = SparseLU(sps.csc_matrix((0, 0)))
    assert lu.solve(np.zeros(0)).shape == (0,) and lu.rcond == 1.0
    n = 3
    A = sps.csc_matrix(np.eye(n))
    args = [A.indptr.astype(np.int64), A.indices.astype(np.int64), A.data, 0.1,
            np.zeros(n + 1, np.int64), np.zeros(9, np.int64), np.zeros(9),
            np.zeros(n + 1, np.int64), np.zeros(9, np.int64), np.zeros(9), np.zeros(n, np.int64)]
    assert lu_factor(n, *args, np.zeros(3 * n, np.int64), np.zeros(n)) == 0
    assert lu_factor(n, *args, np.zeros(3 * n - 1, np.int64), np.zeros(n)) == -3
    bad = [a.copy() if isinstance(a, np.ndarray) else a for a in args]
    bad[1][1] = n                                      # a row index out of range
    assert lu_factor(n, *bad, np.zeros(3 * n, np.int64), np.zeros(n)) == -3
    with pytest.raises(ValueError):
        SparseLU(sps.csc_matrix(np.ones((2, 3))))


def test_callable_from_a_compiled_loop():
    """A nopython loop refactorises and solves with caller-owned storage."""
    @nb.njit
    def sweep(n, Ap, Ai, Ax, Lp, Li, Lx, Up, Ui, Ux, pinv, iw, xw, b, x, w, out):
        total = 0
        for s in range(out.shape[0]):
            for p in range(Ax.size):
                Ax[p] *= 1.0 + 1e-3 * s
            st = lu_factor(n, Ap, Ai, Ax, 0.1, Lp, Li, Lx, Up, Ui, Ux, pinv, iw, xw)
            total += st
            lu_solve(n, pinv, Lp, Li, Lx, Up, Ui, Ux, b, x, w)
            for i in range(n):
                out[s, 0, i] = x[i]
            lu_solve_t(n, pinv, Lp, Li, Lx, Up, Ui, Ux, b, x, w)
            for i in range(n):
                out[s, 1, i] = x[i]
        return total

    rng = np.random.default_rng(8)
    n = 40
    A = _random(rng, n, 0.1)
    Ax = A.data.astype(float).copy()
    ni, nx = work_sizes(n)
    cap = 4 * A.nnz + n
    b = rng.standard_normal(n)
    out = np.empty((5, 2, n))
    total = sweep(n, A.indptr.astype(np.int64), A.indices.astype(np.int64), Ax,
                  np.empty(n + 1, np.int64), np.empty(cap, np.int64), np.empty(cap),
                  np.empty(n + 1, np.int64), np.empty(cap, np.int64), np.empty(cap),
                  np.empty(n, np.int64), np.empty(ni, np.int64), np.empty(nx),
                  b, np.empty(n), np.empty(n), out)
    assert total == 0
    scale = 1.0
    for s in range(5):
        scale *= 1.0 + 1e-3 * s
        As = A.toarray() * scale
        assert np.allclose(out[s, 0], np.linalg.solve(As, b), rtol=1e-9, atol=1e-12)
        assert np.allclose(out[s, 1], np.linalg.solve(As.T, b), rtol=1e-9, atol=1e-12)
