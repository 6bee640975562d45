"""Each numerical leaf of the compiled loops on its own, against an independent reference
(SciPy's LAPACK, NumPy, closed forms), so that a failure names the leaf rather than a loop.

The loops' tests pin whole sweeps and runs against closed forms and independent ODEs; these
pin the pieces they are made of: the dense LU, its solves and condition estimate
(``_jit_lapack``: LAPACK's algorithms written out), and the free-motion stepper's block and
band Cholesky, block inverses, Runge-Kutta stage sums and Adams weights
(``_jit_free_loop``). The leaves run as their own code interpreted
(:func:`mechsys.solvers._jit_interp.interpreted`: the bytecode Numba compiles, which the
loops' tests show gives the compiled numbers bit for bit), so this file compiles nothing.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from scipy.linalg import lapack

pytest.importorskip("numba")

from mechsys.solvers import _jit_adams as jit_adams  # noqa: E402
from mechsys.solvers import _jit_free_loop as free_loop  # noqa: E402
from mechsys.solvers import _jit_lapack as jl  # noqa: E402
from mechsys.solvers._jit_interp import interpreted  # noqa: E402

RNG_SEEDS = range(6)
SIZES = (1, 2, 3, 9, 17, 30)


def leaf(module, name):
    """The leaf ``module.name`` as its own code, interpreted."""
    return interpreted(getattr(module, name))


def _matrix(rng, n, kind):
    """A test matrix: ``dense`` (Gaussian), ``sparse`` (a mechanism-like Jacobian: a few
    nonzeros a row plus a permuted diagonal) or ``graded`` (rows and columns scaled over ten
    orders of magnitude, which partial pivoting must follow)."""
    if kind == "dense":
        return rng.standard_normal((n, n))
    if kind == "sparse":
        A = rng.standard_normal((n, n)) * (rng.random((n, n)) < 3.0 / max(n, 1))
        A[np.arange(n), rng.permutation(n)] += rng.uniform(0.5, 2.0, n)
        return A
    A = rng.standard_normal((n, n))
    return (10.0 ** rng.uniform(-5, 5, n))[:, None] * A * (10.0 ** rng.uniform(-5, 5, n))


def _getrf(A, nz=False):
    """The leaf ``getrf`` on ``A``: ``(factors as a matrix, 0-based pivots, info, nz)``."""
    n = A.shape[0]
    AT = np.ascontiguousarray(A.T)
    piv = np.zeros(n, dtype=np.int32)
    pat = np.zeros(jl.pattern_size.py_func(n), dtype=np.int32) if nz else None
    info = leaf(jl, "getrf")(AT, n, piv, pat)
    return AT.T.copy(), piv, info, pat


@pytest.mark.parametrize("kind", ["dense", "sparse", "graded"])
@pytest.mark.parametrize("n", SIZES)
def test_getrf_is_dgetrf(n, kind):
    """The LU with partial pivoting: LAPACK's pivots and info, its factors to rounding."""
    for seed in RNG_SEEDS:
        A = _matrix(np.random.default_rng(seed), n, kind)
        LU, piv, info, _ = _getrf(A)
        lu, ipiv, linfo = lapack.dgetrf(A)
        assert info == linfo == 0
        np.testing.assert_array_equal(piv, ipiv)
        # factors of a backward-stable LU agree to about n u relative to the row scale
        scale = np.abs(lu).max(axis=1, keepdims=True)
        assert np.all(np.abs(LU - lu) <= 1e-13 * n * scale)
        L = np.tril(LU, -1) + np.eye(n)
        P = np.eye(n)
        for j, p in enumerate(piv):
            P[[j, p]] = P[[p, j]]
        np.testing.assert_allclose(L @ np.triu(LU), P @ A, rtol=0, atol=1e-13 * n * np.abs(A).max())


def test_getrf_singular_info_is_dgetrf():
    """An exactly zero pivot gives LAPACK's info (the first one, 1-based) and the
    elimination goes on past it, as dgetrf's does."""
    rng = np.random.default_rng(1)
    for n, zero in [(1, 0), (4, 0), (5, 2), (6, 5)]:
        A = rng.standard_normal((n, n))
        A[:, zero] = 0.0
        LU, piv, info, _ = _getrf(A)
        lu, ipiv, linfo = lapack.dgetrf(A)
        assert info == linfo == zero + 1
        np.testing.assert_array_equal(piv, ipiv)
        np.testing.assert_allclose(LU, lu, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("n", SIZES)
def test_getrf_structure_lists_the_nonzeros(n):
    """With ``nz`` the factors are the same bits, and ``nz`` lists exactly the nonzeros of
    ``L`` below and of ``U`` above the diagonal, column by column, ascending."""
    for seed in RNG_SEEDS:
        A = _matrix(np.random.default_rng(seed), n, "sparse")
        LU0, piv0, info0, _ = _getrf(A)
        LU, piv, info, nz = _getrf(A, nz=True)
        assert info == info0
        np.testing.assert_array_equal(piv, piv0)
        np.testing.assert_array_equal(LU, LU0)
        for j in range(n):
            below = nz[nz[j]:nz[j + 1]]
            above = nz[nz[n + 1 + j]:nz[n + 2 + j]]
            np.testing.assert_array_equal(below, np.flatnonzero(LU[j + 1:, j]) + j + 1)
            np.testing.assert_array_equal(above, np.flatnonzero(LU[:j, j]))


def _textbook_getrf(A):
    """Gaussian elimination with partial pivoting (first largest pivot), every row of every
    column visited, written out plainly: the reference of ``getrf``'s skips."""
    A = A.copy()
    n = A.shape[0]
    piv = np.zeros(n, dtype=np.int32)
    info = 0
    for j in range(n):
        p = j
        for i in range(j + 1, n):
            if abs(A[i, j]) > abs(A[p, j]):
                p = i
        piv[j] = p
        if A[p, j] != 0.0:
            A[[j, p]] = A[[p, j]]
            A[j + 1:, j] *= 1.0 / A[j, j]
        elif info == 0:
            info = j + 1
        for c in range(j + 1, n):
            if A[j, c] != 0.0:
                A[j + 1:, c] -= A[j + 1:, j] * A[j, c]
    return A, piv, info


def test_getrf_skips_only_exact_no_ops():
    """``getrf`` scales and updates each column's rows from its first to its last nonzero
    below the diagonal only (decision 0087): against the elimination that visits every row,
    the same pivots, ``info`` and factors as numbers (NaN where it has NaN; a zero's sign
    may differ), on sparse matrices (mechanism-like: a few nonzeros a row), some with an
    infinity, a NaN, a subnormal pivot (whose reciprocal is infinite: ``0 inv`` is NaN
    there) or a zero column (``info``)."""
    rng = np.random.default_rng(87)
    getrf = leaf(jl, "getrf")
    for trial in range(240):
        n = int(rng.integers(1, 13))
        A = _matrix(rng, n, "sparse")
        if trial % 6 == 1:
            A[rng.integers(n), rng.integers(n)] = (np.inf, np.nan, -np.inf)[trial % 3]
        if trial % 6 == 3:
            A[:, rng.integers(n)] *= 1e-310               # (subnormal pivots)
        if trial % 6 == 5:
            A[:, rng.integers(n)] = 0.0                    # (info)
        AT = np.ascontiguousarray(A.T)
        piv = np.zeros(n, dtype=np.int32)
        with np.errstate(all="ignore"):
            want, wpiv, winfo = _textbook_getrf(A)
            info = getrf(AT, n, piv)
        assert info == winfo
        np.testing.assert_array_equal(piv, wpiv)
        np.testing.assert_array_equal(AT.T, want)          # (NaN == NaN here; -0.0 == 0.0)


@pytest.mark.parametrize("structure", [False, True])
@pytest.mark.parametrize("n", SIZES)
def test_getrs_is_dgetrs(n, structure):
    """The solve from the factors (row interchanges, then L and U) against LAPACK's dgetrs on
    LAPACK's factors, and against the residual of the system itself."""
    for seed in RNG_SEEDS:
        rng = np.random.default_rng(seed)
        A = _matrix(rng, n, "sparse")
        b = rng.standard_normal(n)
        LU, piv, _, nz = _getrf(A, nz=structure)
        AT = np.ascontiguousarray(LU.T)
        x = b.copy()
        leaf(jl, "getrs")(AT, n, piv, x, nz)
        lu, ipiv, _ = lapack.dgetrf(A)
        want, info = lapack.dgetrs(lu, ipiv, b)
        assert info == 0
        cond = np.linalg.cond(A, 1)
        np.testing.assert_allclose(x, want, rtol=0, atol=1e-14 * n * cond * np.abs(want).max())
        assert np.abs(A @ x - b).max() <= 1e-13 * n * np.abs(A).max() * np.abs(x).max()


@pytest.mark.parametrize("name, lower, trans, unit", [
    ("_lower", True, 0, True), ("_upper", False, 0, False),
    ("_upper_t", False, 1, False), ("_lower_t", True, 1, True)])
@pytest.mark.parametrize("n", SIZES)
def test_triangular_solves_are_dtrsv(name, lower, trans, unit, n):
    """Each of the four triangular solves against SciPy's ``solve_triangular`` (LAPACK's
    dtrtrs) on the same triangle of the same stored matrix."""
    for seed in RNG_SEEDS:
        rng = np.random.default_rng(seed)
        M = rng.standard_normal((n, n))
        M[np.arange(n), np.arange(n)] = rng.uniform(1.0, 3.0, n) * rng.choice([-1, 1], n)
        b = rng.standard_normal(n)
        x = b.copy()
        leaf(jl, name)(np.ascontiguousarray(M.T), n, x)
        want = scipy.linalg.solve_triangular(M, b, lower=lower, trans=trans, unit_diagonal=unit)
        np.testing.assert_allclose(x, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


@pytest.mark.parametrize("structure", [False, True])
@pytest.mark.parametrize("n", SIZES)
def test_gecon1_is_dgecon(n, structure):
    """The one-norm reciprocal condition estimate: LAPACK's dgecon on LAPACK's factors, to
    rounding (the same estimator, taking the same decisions), over well-conditioned and
    nearly singular matrices."""
    for seed in RNG_SEEDS:
        rng = np.random.default_rng(seed)
        A = _matrix(rng, n, "sparse" if seed % 2 else "dense")
        if seed >= 3 and n > 1:              # nearly singular: two rows nearly equal
            A[-1] = A[0] + 10.0 ** (-2 * seed) * rng.standard_normal(n)
        anorm = np.abs(A).sum(axis=0).max()
        LU, piv, _, nz = _getrf(A, nz=structure)
        x, isgn = np.zeros(n), np.zeros(n)
        got = leaf(jl, "gecon1")(np.ascontiguousarray(LU.T), n, anorm, x, isgn, nz)
        lu, _, _ = lapack.dgetrf(A)
        want, info = lapack.dgecon(lu, anorm, norm="1")
        assert info == 0
        # (the factors agree to rounding, which the inverse amplifies by the condition:
        # relative u n / rcond in the estimate)
        np.testing.assert_allclose(got, want, rtol=1e-12 + 1e-14 * n / want)
        assert 0.0 < got <= 1.0 + 1e-15


def test_gecon1_edge_cases():
    """A zero matrix norm gives 0 (dgecon's convention), an empty matrix 1, and a 1 x 1 the
    exact reciprocal condition 1."""
    f = leaf(jl, "gecon1")
    assert f(np.zeros((2, 2)), 2, 0.0, np.zeros(2), np.zeros(2), None) == 0.0
    assert f(np.zeros((0, 0)), 0, 1.0, np.zeros(0), np.zeros(0), None) == 1.0
    assert f(np.array([[-4.0]]), 1, 4.0, np.zeros(1), np.zeros(1), None) == 1.0


def _band_store(S, bw):
    """``Sb[i, d] = S[i, i - d]`` (the loops' lower band storage)."""
    m = S.shape[0]
    Sb = np.zeros((m, bw + 1))
    for i in range(m):
        for d in range(min(bw, i) + 1):
            Sb[i, d] = S[i, i - d]
    return Sb


@pytest.mark.parametrize("m, bw", [(1, 0), (5, 1), (12, 3), (40, 3), (30, 7)])
def test_band_cholesky_and_solve(m, bw):
    """The free stepper's banded Cholesky and its solve against SciPy's
    ``cholesky_banded``/``cho_solve_banded``; the returned ratio is the smallest over the
    largest diagonal entry of the factor."""
    rng = np.random.default_rng(m + bw)
    B = np.zeros((m, m))
    for d in range(bw + 1):
        v = rng.standard_normal(m - d)
        B += np.diag(v, -d)
    S = B @ B.T + 0.1 * np.eye(m)            # positive definite, bandwidth <= 2 bw
    S[np.abs(np.subtract.outer(np.arange(m), np.arange(m))) > bw] = 0.0
    S += (np.abs(S).sum(axis=1).max()) * np.eye(m)   # still diagonally dominant after cutting
    Sb = _band_store(S, bw)
    ratio = leaf(free_loop, "_band_chol")(Sb, m, bw)
    ab = np.zeros((bw + 1, m))                # SciPy's lower band storage: ab[d, j] = S[j + d, j]
    for d in range(bw + 1):
        ab[d, :m - d] = np.diag(S, -d)
    cb = scipy.linalg.cholesky_banded(ab, lower=True)
    for d in range(bw + 1):
        np.testing.assert_allclose(Sb[d:, d], cb[d, :m - d], rtol=1e-13, atol=1e-15)
    assert ratio == pytest.approx(cb[0].min() / cb[0].max(), rel=1e-15)
    b = rng.standard_normal(m)
    x = b.copy()
    leaf(free_loop, "_band_solve")(Sb, m, bw, x)
    np.testing.assert_allclose(x, scipy.linalg.cho_solve_banded((cb, True), b), rtol=1e-12)


def test_band_cholesky_refuses_what_is_not_positive_definite():
    """-1 for an indefinite matrix, a zero pivot and a NaN (never a factor of garbage)."""
    f = leaf(free_loop, "_band_chol")
    for S in (np.array([[1.0, 2.0], [2.0, 1.0]]), np.zeros((2, 2)),
              np.array([[np.nan, 0.0], [0.0, 1.0]])):
        assert f(_band_store(S, 1), 2, 1) == -1.0


@pytest.mark.parametrize("sizes", [(3,), (1, 3, 6), (3, 3, 2, 7)])
def test_block_cholesky_inverse_and_product(sizes):
    """Per block of a block-diagonal mass matrix: the Cholesky factor (``_chol_blocks``)
    against NumPy's, the inverse from it (``_invert_blocks``, with the written-out 3 x 3
    case ``_invert3``) against NumPy's inverse, and ``_block_mul`` against the product."""
    rng = np.random.default_rng(len(sizes))
    bstart = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    boff = np.concatenate([[0], np.cumsum(np.square(sizes))]).astype(np.int64)
    blocks = []
    for z in sizes:
        G = rng.standard_normal((z, z))
        blocks.append(G @ G.T + z * np.eye(z))
    Mst = np.concatenate([b.ravel() for b in blocks])
    assert leaf(free_loop, "_chol_blocks")(Mst, bstart, boff, len(sizes))
    for b, z, o in zip(blocks, sizes, boff):
        L = np.tril(Mst[o:o + z * z].reshape(z, z))
        np.testing.assert_allclose(L, np.linalg.cholesky(b), rtol=1e-13, atol=1e-14)
    Minv = np.zeros_like(Mst)
    leaf(free_loop, "_invert_blocks")(Mst, Minv, bstart, boff, len(sizes), np.zeros(max(sizes) ** 2))
    src = rng.standard_normal(int(bstart[-1]))
    dst = np.zeros_like(src)
    for b, z, o, s in zip(blocks, sizes, boff, bstart):
        inv = Minv[o:o + z * z].reshape(z, z)
        np.testing.assert_allclose(inv, np.linalg.inv(b), rtol=1e-12, atol=1e-14)
        np.testing.assert_array_equal(inv, inv.T)
        leaf(free_loop, "_block_mul")(Minv, o, z, src, s, dst, s)
        np.testing.assert_allclose(dst[s:s + z], np.linalg.solve(b, src[s:s + z]), rtol=1e-12)


def test_block_cholesky_refuses_a_singular_block():
    Mst = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])       # 3 x 3, zero middle pivot
    ok = leaf(free_loop, "_chol_blocks")(Mst, np.array([0, 3]), np.array([0]), 1)
    assert not ok


def test_stage_sums_are_the_weighted_rows():
    """``_combine``: the Runge-Kutta stage sum ``sum_k c_k K_k`` over the first ``s`` stages,
    each coordinate summed in the order of ``k`` (bit for bit that sum)."""
    rng = np.random.default_rng(3)
    K = rng.standard_normal((16, 11))
    c = rng.standard_normal(16)
    for s in (0, 1, 7, 12):
        acc = np.full(11, np.nan)
        leaf(free_loop, "_combine")(K, c, s, acc)
        want = np.zeros(11)
        for k in range(s):
            want = want + K[k] * c[k]
        np.testing.assert_array_equal(acc, want)


def _adams(nodes, h):
    """``_jit_adams.weights`` of the scaled nodes ``nodes`` (a fresh cache): the weights and
    whether it succeeded."""
    cnt = len(nodes)
    times = np.asarray(nodes, dtype=float) * h + 2.5       # t_from = 2.5
    w = np.zeros(6)
    ok = leaf(jit_adams, "weights")(times, 0, cnt, 2.5, h, np.zeros((6, 6)), w,
                                    np.full(13, np.nan), np.zeros(6, dtype=np.int32))
    return w[:cnt], ok


@pytest.mark.parametrize("nodes, want", [
    ([0.0], [1.0]),                                              # Euler
    ([-1.0, 0.0], [-1 / 2, 3 / 2]),                              # Adams-Bashforth 2
    ([-3.0, -2.0, -1.0, 0.0], [-9 / 24, 37 / 24, -59 / 24, 55 / 24]),   # AB4
    ([0.0, 1.0], [1 / 2, 1 / 2]),                                # trapezoid (AM2)
    ([-2.0, -1.0, 0.0, 1.0], [1 / 24, -5 / 24, 19 / 24, 9 / 24]),       # Adams-Moulton 4
])
def test_adams_weights_are_the_classical_coefficients(nodes, want):
    """Constant steps: the classical Adams-Bashforth and Adams-Moulton coefficients, times h."""
    h = 0.01
    w, ok = _adams(nodes, h)
    assert ok
    np.testing.assert_allclose(w, h * np.array(want), rtol=1e-12)


def test_adams_weights_integrate_the_interpolant_on_uneven_nodes():
    """Uneven nodes (a step-size change): the weights integrate every polynomial of degree
    below the node count exactly over ``[t_from, t_from + h]`` (the Lagrange basis
    integrated by NumPy's polynomials)."""
    h = 0.003
    for nodes in ([-2.6, -1.1, 0.0], [-3.0, -1.5, -0.5, 0.0, 1.0], [-4.2, -3.0, -2.1, -1.0, 0.0, 1.0]):
        w, ok = _adams(nodes, h)
        assert ok
        x = np.array(nodes)
        for i in range(len(x)):
            others = np.delete(x, i)
            basis = np.polynomial.Polynomial.fromroots(others) / np.prod(x[i] - others)
            exact = basis.integ()(1.0) - basis.integ()(0.0)
            assert w[i] == pytest.approx(h * exact, rel=1e-10, abs=1e-15)


def test_adams_weights_refuse_repeated_nodes():
    """Two equal nodes (no interpolant): refused, not a weight of garbage."""
    _, ok = _adams([-1.0, 0.0, 0.0], 0.01)
    assert not ok


def _adams_history(N=2, nh=4, t=1.0, h=0.1):
    """The history arrays of an Adams run: ``nh`` stored derivative values at times
    ``t - (nh - 1) h .. t``, and the work arrays."""
    hist_t = np.zeros(6)
    hist_t[:nh] = t - h * np.arange(nh - 1, -1, -1)
    hist_f = np.zeros((6, N))
    work = (np.zeros((6, 6)), np.zeros(6), np.full(13, np.nan), np.zeros(6, dtype=np.int32))
    return hist_t, hist_f, work


def test_adams_predict_integrates_the_fit_and_ends_on_the_final_time():
    """A derivative linear in time is integrated exactly by the predictor; the step to try is
    the next one, or the rest of the interval where that is shorter."""
    predict = leaf(jit_adams, "predict")
    hist_t, hist_f, (V, w, cache, piv) = _adams_history(nh=3)
    hist_f[:3] = np.c_[2.0 * hist_t[:3], np.full(3, -1.0)]     # f = (2 t, -1)
    y, y_pred = np.array([1.0, 3.0]), np.zeros(2)
    code, h = predict(1.0, 0.1, 3, 5.0, 1.0, 3, y, hist_t, hist_f, V, w, cache, piv, y_pred)
    assert code == jit_adams.OK
    assert h == (1.0 + 0.1) - 1.0             # the step the stored time takes
    np.testing.assert_allclose(y_pred, [1.0 + (1.0 + h)**2 - 1.0, 3.0 - h], rtol=1e-13)
    code, h = predict(1.0, 0.1, 3, 1.04, 1.0, 3, y, hist_t, hist_f, V, w, cache, piv, y_pred)
    assert code == jit_adams.OK and h == pytest.approx(0.04, rel=1e-12)
    # a step the stored time does not take
    assert predict(1.0, 1e-17, 3, 5.0, 1.0, 3, y, hist_t, hist_f, V, w, cache, piv,
                   y_pred)[0] == jit_adams.SHORT


def _judged(err, a=1e-4, method=0, fixed=False, t=1.0, h=0.1):
    """``correct``'s code and error for a step whose corrector moves the prediction by
    ``err`` (one component), with the corrected value and derivative."""
    correct = leaf(jit_adams, "correct")
    hist_t, hist_f, (V, w, cache, piv) = _adams_history(N=1, nh=1, t=t, h=h)
    y = np.zeros(1)
    # one stored value f = 0 at t: the trapezoid y_c = h/2 (0 + f_pred); y_pred = 0
    f_pred = np.array([2.0 * err / h])
    y_pred, y_corr, f_new = np.zeros(1), np.zeros(1), np.zeros(1)
    code, e = correct(t, h, 1, 3, a, a / 10, fixed, method, y, hist_t, hist_f, y_pred, f_pred,
                      np.ones(1), V, w, np.zeros(6), cache, piv, y_corr, f_new)
    return code, e, y_corr, f_new


def test_adams_correct_judges_the_error_as_mech():
    """Mech's ``MaxError -> {a, b, c}``: above ``a`` the step is rejected; between ``b`` and
    ``a`` the corrected value; at most ``b`` the predicted one (automatic mode); the
    corrector mode always corrects; a constant step never rejects; an error that is not
    finite, or a rejection below the time's resolution, is not the loop's to take."""
    code, e, _, _ = _judged(3e-4)
    assert code == jit_adams.REJECTED and e == pytest.approx(3e-4, rel=1e-12)
    code, _, y_corr, _ = _judged(5e-5)
    assert code == jit_adams.CORRECTED and y_corr[0] == pytest.approx(5e-5, rel=1e-12)
    code, _, y_corr, f_new = _judged(5e-6)
    assert code == jit_adams.OK and y_corr[0] == 0.0 and f_new[0] == pytest.approx(1e-4)
    assert _judged(5e-6, method=2)[0] == jit_adams.CORRECTED
    assert _judged(5e-6, method=1)[0] == jit_adams.OK
    assert _judged(3e-4, fixed=True)[0] == jit_adams.CORRECTED
    assert _judged(np.inf)[0] == jit_adams.NONFINITE
    assert _judged(3e-4, t=1e12, h=1e-3)[0] == jit_adams.TOO_SMALL


def test_adams_commit_keeps_six_values_and_doubles_after_2k_small_errors():
    """The history keeps the last six derivative values; the step doubles once the last
    ``2k`` errors are all below ``c`` (and the count starts again), never with a constant
    step."""
    commit = leaf(jit_adams, "commit")
    for fixed in (False, True):
        hist_t, hist_f, _ = _adams_history(N=1, nh=1, t=0.0)
        y, recent = np.zeros(1), np.zeros(8)
        t, h, nh, nrec, hs = 0.0, 0.1, 1, 0, []
        for i in range(8):
            t += h
            nh, nrec, h = commit(t, h, 1e-7, nh, nrec, 2, 1e-6, fixed, y, hist_t, hist_f,
                                 np.array([i + 1.0]), np.array([10.0 * (i + 1)]), recent)
            hs.append(h)
        assert nh == 6 and y[0] == 8.0
        np.testing.assert_array_equal(hist_f[:, 0], 10.0 * np.arange(3, 9))
        assert hist_t[5] == pytest.approx(t)
        assert hs == ([0.1] * 8 if fixed else [0.1, 0.2, 0.2, 0.4, 0.4, 0.8, 0.8, 1.6])


def _scaled_case(rng, n):
    """A mechanism-like Jacobian ``J``, column scales ``c`` (lengths and angles) and the row
    scales ``r`` the loops take (the largest entry of each row of ``J D``)."""
    J = _matrix(rng, n, "sparse")
    columns = 10.0 ** rng.uniform(-2, 2, n)
    r = np.abs(J * columns).max(axis=1)
    return J, columns, r


@pytest.mark.parametrize("n", [3, 16, 40, 160])
def test_scaled_factor_and_solve(n):
    """``_jit_linalg._factor``/``_solve``: the LU of :math:`R^{-1} J D` (the written-out
    LAPACK below ``SMALL`` unknowns, LAPACK itself through its C address above) and the
    solve :math:`x = D B^{-1} R^{-1} b`, against NumPy's solve of :math:`J x = b` and
    LAPACK's dgecon of the scaled matrix; a guard returns ``RCOND_PENDING`` only for an
    estimate proven above it; a singular matrix gives -1."""
    from mechsys.solvers import _jit_linalg as jlin
    from mechsys.solvers._jit_runtime import lapack
    from mechsys.solvers._tolerances import RCOND_PENDING, RCOND_WARN

    factor, solve = leaf(jlin, "_factor"), leaf(jlin, "_solve")
    for seed in range(3):
        rng = np.random.default_rng(seed)
        J, columns, r = _scaled_case(rng, n)
        jr, jc = (a.astype(np.int64) for a in np.nonzero(J))
        work = interpreted(jlin._factor_work)(n, n, n)
        S, W, seen = interpreted(jlin._structure)(jr, jc, n)
        Jw, B, ipiv, nz, ibuf, cbuf, dbuf, wk, iwork, _ = work
        Jw[:] = J
        scaled = J * columns / r[:, None]
        want = lapack_rcond(scaled)
        for guard in (0.0, RCOND_WARN):
            got = factor(lapack(), Jw, r, columns, B, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf,
                         wk, iwork, guard)
            if got == RCOND_PENDING:
                assert guard > 0 and n <= 150 and want >= guard
            else:
                np.testing.assert_allclose(got, want, rtol=1e-12 + 1e-14 * n / want)
            b = rng.standard_normal(n)
            out = np.zeros(n)
            solve(lapack(), B, ipiv, nz, r, columns, b, out, ibuf, cbuf)
            x = np.linalg.solve(J, b)
            np.testing.assert_allclose(out, x, rtol=0, atol=1e-13 * n * np.linalg.cond(scaled, 1)
                                       * np.abs(x).max())
        Jw[:, n // 2] = 0.0                   # a zero column: singular
        assert factor(lapack(), Jw, r, columns, B, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf, wk,
                      iwork, 0.0) == -1.0


def lapack_rcond(A):
    """LAPACK's one-norm reciprocal condition estimate of ``A`` (dgetrf + dgecon)."""
    lu, _, info = lapack.dgetrf(A)
    assert info == 0
    return lapack.dgecon(lu, np.abs(A).sum(axis=0).max(), norm="1")[0]
