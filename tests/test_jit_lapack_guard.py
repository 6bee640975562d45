"""The compiled sweep's small LU (solvers/_jit_lapack.py): the sparse-structure solves give the
dense loops' numbers, and the bound that lets Newton skip the condition estimate never skips a
matrix the estimate (ours or LAPACK's, which the Python path calls) would call singular."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg.lapack as lapack

pytest.importorskip("numba")

from mechsys.solvers._jit_lapack import (  # noqa: E402
    GUARD_MARGIN,
    gecon1,
    getrf,
    getrs,
    inv_norm_bound,
    pattern_size,
    symbolic_pattern,
)
from mechsys.solvers._tolerances import RCOND_MIN  # noqa: E402

LIMIT = GUARD_MARGIN / RCOND_MIN     # the guard: anorm * bound <= LIMIT skips the estimate


def _sparse(rng, n, density):
    A = rng.standard_normal((n, n)) * (rng.random((n, n)) < density)
    A[np.arange(n), rng.permutation(n)] += rng.standard_normal(n)   # structurally nonsingular
    return A


def _near_singular(rng, n):
    """Singular values from 1 down to 1e-17 .. 1e-9, some columns scaled by 1e-8, then some
    entries zeroed (a mechanism's Jacobian is sparse)."""
    Uo, _ = np.linalg.qr(rng.standard_normal((n, n)))
    Vo, _ = np.linalg.qr(rng.standard_normal((n, n)))
    s = np.logspace(0, -rng.uniform(9, 17), n)
    A = (Uo * s) @ Vo.T
    if rng.random() < 0.5:
        A[:, rng.random(n) < 0.3] *= 1e-8
    if rng.random() < 0.5:
        A[rng.random((n, n)) < 0.2] = 0.0
    return A


def _m_matrix_at(rng, n, target):
    """``A = L U`` with ``M(L) = L``, ``M(U) = U`` (so ``|A^-1| = A^-1`` and the bound is
    exact), ``|l_ij| < 1`` (partial pivoting keeps the order), and the last pivot chosen so
    that the reciprocal condition number is about ``target``."""
    L = np.eye(n) - np.tril(rng.uniform(0, 0.9, (n, n)) * (rng.random((n, n)) < 0.5), -1)
    U = -np.triu(rng.uniform(0, 1, (n, n)) * (rng.random((n, n)) < 0.5), 1)
    U[np.arange(n), np.arange(n)] = rng.uniform(0.5, 1.5, n)
    for _ in range(6):
        A = L @ U
        rc = 1.0 / (np.abs(A).sum(axis=0).max() * np.abs(np.linalg.inv(A)).sum(axis=0).max())
        U[-1, -1] *= target / rc
    return L @ U


def _rowscaled(A):
    r = np.abs(A).max(axis=1)
    r[r == 0] = 1.0
    return A / r[:, None]


def _ours(A):
    """Transposed-storage factors, pivots, structure, anorm, our estimate and the bound."""
    n = A.shape[0]
    anorm = np.abs(A).sum(axis=0).max()
    AT = np.ascontiguousarray(A.T)
    piv = np.empty(n, np.int32)
    nz = np.empty(pattern_size(n), np.int32)
    info = getrf(AT, n, piv, nz)
    work = np.empty(2 * n)
    rc = gecon1(AT, n, anorm, work, work[n:], nz) if info == 0 else 0.0
    bound = inv_norm_bound(AT, n, nz, np.empty(n)) if info == 0 else np.inf
    return AT, piv, nz, info, anorm, rc, bound


def _lapack_rcond(A, anorm):
    lu, _, info = lapack.dgetrf(A)
    if info > 0:
        return 0.0
    return lapack.dgecon(lu, anorm, norm="1")[0]


def test_structure_solves_give_the_dense_numbers():
    """With ``nz`` the factors, the solves and the estimate equal the dense loops' (the skipped
    operations are ``x - 0 * y``), on sparse and on full matrices."""
    rng = np.random.default_rng(11)
    for trial in range(400):
        n = int(rng.integers(1, 16))
        A = _rowscaled(_sparse(rng, n, 0.25) if trial % 3 else _near_singular(rng, n))
        anorm = np.abs(A).sum(axis=0).max()
        AT, piv, nz, info, _, rc, _ = _ours(A)
        DT = np.ascontiguousarray(A.T)
        dpiv = np.empty(n, np.int32)
        assert getrf(DT, n, dpiv) == info
        np.testing.assert_array_equal(AT, DT)
        np.testing.assert_array_equal(piv, dpiv)
        if info:
            continue
        # the recorded structure is exactly the factors' nonzeros
        for j in range(n):
            assert list(nz[nz[j]:nz[j + 1]]) == [i for i in range(j + 1, n) if AT[j, i] != 0]
            assert list(nz[nz[n + 1 + j]:nz[n + 2 + j]]) == [i for i in range(j) if AT[j, i] != 0]
        b = rng.standard_normal(n)
        x1, x2 = b.copy(), b.copy()
        getrs(AT, n, piv, x1, nz)
        getrs(DT, n, dpiv, x2)
        np.testing.assert_array_equal(x1, x2)
        w = np.empty(2 * n)
        assert gecon1(DT, n, anorm, w, w[n:]) == rc


def _ranges(nz, n):
    return ([set(nz[nz[j]:nz[j + 1]]) for j in range(n)],
            [set(nz[nz[n + 1 + j]:nz[n + 2 + j]]) for j in range(n)])


def test_symbolic_structure_covers_the_factors_and_gives_their_numbers():
    """The structure the sweep computes once per pivot sequence (``symbolic_pattern`` of the
    Jacobian's structure) contains every nonzero of the factors, also where the numbers
    cancel or a structural entry is zero at this configuration, and the solves, the estimate
    and the bound with it give exactly the numbers of the recorded structure."""
    rng = np.random.default_rng(12)
    larger = 0
    for trial in range(400):
        n = int(rng.integers(1, 16))
        A = _rowscaled(_sparse(rng, n, 0.25) if trial % 3 else _near_singular(rng, n))
        S = np.ascontiguousarray((A != 0).T.astype(float))
        if trial % 4 == 0:                   # a structural entry that is zero right now
            S[rng.integers(n), rng.integers(n)] = 1.0
        AT, piv, nz, info, anorm, rc, bound = _ours(A)
        if info:
            continue
        snz = np.empty_like(nz)
        symbolic_pattern(S, n, piv, snz, np.empty((n, n)))
        lo, up = _ranges(nz, n)
        slo, sup = _ranges(snz, n)
        assert all(a <= b for a, b in zip(lo, slo)) and all(a <= b for a, b in zip(up, sup))
        for j in range(n):                   # each list ascending, as the solves expect
            assert list(snz[snz[j]:snz[j + 1]]) == sorted(slo[j])
            assert list(snz[snz[n + 1 + j]:snz[n + 2 + j]]) == sorted(sup[j])
        larger += sum(map(len, slo + sup)) > sum(map(len, lo + up))
        b = rng.standard_normal(n)
        x1, x2 = b.copy(), b.copy()
        getrs(AT, n, piv, x1, nz)
        getrs(AT, n, piv, x2, snz)
        np.testing.assert_array_equal(x1, x2)
        w = np.empty(2 * n)
        assert gecon1(AT, n, anorm, w, w[n:], snz) == rc
        assert inv_norm_bound(AT, n, snz, np.empty(n)) == bound
    assert larger > 20                       # the superset case is exercised


def test_bound_is_infinite_when_a_structural_zero_meets_an_overflow():
    """A pivot so small that ``M(U)^-1`` overflows: with a structure listing zeros (as
    ``symbolic_pattern`` may), ``0 * inf`` makes NaNs that a running maximum passes over; the
    bound must still be ``inf`` (not a finite number that would skip the estimate)."""
    n = 2
    AT = np.array([[1e-320, 0.0], [0.0, 1.0]])     # U = diag(1e-320, 1), L = I (transposed)
    piv = np.arange(n, dtype=np.int32)
    dense = np.empty(pattern_size(n), np.int32)
    symbolic_pattern(np.ones((n, n)), n, piv, dense, np.empty((n, n)))   # lists both zeros
    assert inv_norm_bound(AT, n, dense, np.empty(n)) == np.inf
    exact = np.empty(pattern_size(n), np.int32)
    symbolic_pattern(np.eye(n), n, piv, exact, np.empty((n, n)))
    assert inv_norm_bound(AT, n, exact, np.empty(n)) == np.inf


def test_bound_never_skips_a_singular_decision():
    """Over random and nearly singular matrices (rows scaled as in the sweep): the bound is
    at least the estimate, and whenever the guard passes, both our estimate and LAPACK's
    (the Python path's) are at least ``RCOND_MIN``; near the threshold the guard still
    passes where the bound is tight, so the property is tested where it matters."""
    rng = np.random.default_rng(2026)
    passed = near = 0
    for trial in range(3000):
        n = int(rng.integers(1, 15))
        kind = trial % 3
        if kind == 0:
            A = _rowscaled(_near_singular(rng, n))
        elif kind == 1:
            A = _rowscaled(_sparse(rng, n, 0.3))
        else:
            A = _m_matrix_at(rng, max(n, 2), 10 ** rng.uniform(np.log10(RCOND_MIN) - 0.5, -12))
        AT, _, _, info, anorm, rc, bound = _ours(A)
        if info or anorm == 0:
            continue
        ref = _lapack_rcond(A, anorm)
        if rc > 0:
            assert bound * (1 + 1e-12) >= 1.0 / (rc * anorm), trial   # est <= bound
        if anorm * bound <= LIMIT:
            passed += 1
            assert rc >= RCOND_MIN and ref >= RCOND_MIN, (trial, rc, ref, anorm * bound)
            if rc < 4 * RCOND_MIN:
                near += 1
        if kind == 2 and ref < RCOND_MIN:
            assert anorm * bound > LIMIT                   # such matrices go to the estimate
    assert passed > 1000
    assert near > 20          # matrices within a factor of four of the threshold were skipped


def test_bound_is_exact_for_comparison_matrices():
    """For ``A = L U`` with ``M(L) = L`` and ``M(U) = U`` the bound is ``||A^-1||_1`` itself."""
    rng = np.random.default_rng(5)
    for _ in range(50):
        n = int(rng.integers(2, 12))
        A = _m_matrix_at(rng, n, 1e-6)
        AT, piv, _, info, _, _, bound = _ours(A)
        assert info == 0 and np.all(piv == np.arange(n))
        exact = np.abs(np.linalg.inv(A)).sum(axis=0).max()
        assert bound == pytest.approx(exact, rel=1e-9)


def test_lists_elimination_is_the_dense_one():
    """``getrf_lists`` (the sweep's and the multiplier solves' LU: the elimination along the
    structure's lists and their fill, decision 0078) against the dense ``getrf``: the same
    pivots and ``info``, the same factors (their zeros may differ in sign, nothing else), and
    ``lists_pattern`` equal to ``symbolic_pattern`` of the same structure and pivots. Sparse
    and nearly singular matrices, exact ties (entries of one magnitude), a structural entry
    that is zero right now, and non-finite or subnormal entries (where the dense loops take
    over: ``0 * inf`` is NaN), some with the structure given with repeats."""
    from mechsys.solvers._jit_lapack import getrf_lists, lists_pattern
    from mechsys.solvers._jit_linalg import _structure

    rng = np.random.default_rng(13)
    for trial in range(301):
        n = int(rng.integers(1, 16))
        A = _rowscaled(_sparse(rng, n, 0.25) if trial % 3 else _near_singular(rng, n))
        if trial == 300:
            # a NaN multiplier meeting a structural zero of the pivot row: getrf skips the
            # zero (NaN * 0 would be NaN)
            n, A = 3, np.array([[1.0, 0.0, 1.0], [np.nan, 1.0, 0.0], [0.5, 0.0, 1.0]])
        if trial % 7 == 0:
            A[A != 0] = np.sign(A[A != 0])               # ties everywhere
        structural = A != 0
        if trial == 300:
            structural[0, 1] = True
        if trial % 4 == 0:
            structural[rng.integers(n), rng.integers(n)] = True
        if trial % 11 == 0:
            A[rng.integers(n), rng.integers(n)] = (np.inf, np.nan, 1e-310, -np.inf)[trial % 4]
            structural |= A != 0
        rows, cols = np.nonzero(structural)
        twice = trial % 5 == 0
        rows, cols = (np.tile(rows, 2), np.tile(cols, 2)) if twice else (rows, cols)
        S, W, P = _structure(rows.astype(np.int64), cols.astype(np.int64), n)
        DT = np.ascontiguousarray(A.T)
        LT = DT.copy()
        dpiv, lpiv = np.empty(n, np.int32), np.empty(n, np.int32)
        with np.errstate(all="ignore"):
            info = getrf(DT, n, dpiv)
            assert getrf_lists(LT, n, lpiv, S, W, P, True) == info
        np.testing.assert_array_equal(lpiv, dpiv)
        np.testing.assert_array_equal(LT, DT)            # (NaN == NaN here; -0.0 == 0.0)
        if trial == 300:
            assert LT[1, 1] == 1.0                       # (A(1, 1): not NaN)
        if info:
            continue
        mine, theirs = np.empty(pattern_size(n), np.int32), np.empty(pattern_size(n), np.int32)
        lists_pattern(n, W, P, mine)
        symbolic_pattern(np.ascontiguousarray(structural.T.astype(float)), n, dpiv, theirs,
                         np.empty((n, n)))
        assert _ranges(mine, n) == _ranges(theirs, n)
        # the structure alone for getrf's pivots (the small systems' use): the same lists
        again = np.empty(pattern_size(n), np.int32)
        assert getrf_lists(DT, n, dpiv, S, W, P, False) == 0
        lists_pattern(n, W, P, again)
        assert _ranges(again, n) == _ranges(theirs, n)
        for j in range(n):                               # (ascending, as the solves sum)
            assert list(mine[mine[j]:mine[j + 1]]) == sorted(mine[mine[j]:mine[j + 1]])
            assert list(mine[mine[n + 1 + j]:mine[n + 2 + j]]) == sorted(
                mine[mine[n + 1 + j]:mine[n + 2 + j]])
