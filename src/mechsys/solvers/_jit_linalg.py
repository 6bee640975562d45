r"""The compiled counterpart of ``_linalg``: the scaled factorisations and solves of the
compiled loops, in the Python path's order of floating-point operations so that both give
the same numbers (decisions 0019, 0030, 0031).

Each function mirrors one piece of the Python path:

* ``_assemble``      ``System.assemble`` (dense ``Phi_q`` from its nonzero values)
* ``_rows``          ``Scaling.rows``
* ``_factor``        ``Scaling.factor`` -> ``Factor`` (LAPACK dgetrf + dgecon on :math:`R^{-1} J D`;
                     up to ``SMALL`` unknowns their algorithms from ``_jit_lapack``)
* ``_solve``         ``ScaledFactor.solve``
* ``_band_*``,      the same, above ``SPARSE_THRESHOLD`` unknowns, through the Jacobian's
  ``_sparse_*``      ``FixedPattern`` (``System.assemble``'s CSC values, ``Scaling.rows``,
                     the compiled sparse LU, the pivot ratio; decisions 0030, 0031);
                     ``_band_factor``/``_band_solve``: LAPACK ``dgbtrf``/``dgbtrs`` on a
                     band, for the banded patterns of free motion's and the multipliers'
                     Newton matrices

The unit-free matrix factorised is, with row scales ``r`` and column scales ``c``:

.. math:: B = R^{-1} J D, \qquad R = \operatorname{diag}(r), \quad D = \operatorname{diag}(c)

The matrices handed to LAPACK are stored transposed in C order, which is column-major
(Fortran) order of the matrix itself. The helpers that allocate nothing are compiled
without reference counting (``_jit_lapack.leaf``, decision 0025). Used by the sweep
(``_jit_sweep_loop``), the multiplier solves (``_jit_multipliers_loop``) and the free-motion
stepper (``_jit_free_loop``); split out of the sweep's module so that those do not import
the sweep (decision 0058). Example (inside a compiled loop)::

    ok = _factor(lapack, J, r, columns, B, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf, work,
                 iwork, rc, guard)
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ._jit_cache import check as _check_cache
from ._jit_calls import _ccall
from ._jit_lapack import (
    GUARD_MARGIN,
    LIST_LU_MIN,
    gecon1,
    getrf,
    getrf_lists,
    inv_norm_bound,
    leaf,
    lists_pattern,
    lists_size,
    pattern_size,
)
from ._jit_runtime import SMALL, SPARSE
from ._jit_sparse import IWORK, lu_factor, lu_pivot_ratio, lu_solve, lu_solve_t
from ._tolerances import PIVOT_TOL, RCOND_MIN, RCOND_PENDING

_check_cache()   # stale cached loops go before anything here compiles (see _jit_cache)


@leaf
def _assemble(vals, off, jr, jc, J):
    J[:, :] = 0.0
    for k in range(jr.size):
        J[jr[k], jc[k]] += vals[off + k]


@leaf
def _rows(J, columns, r):
    n = J.shape[0]
    for i in range(n):
        big = 0.0
        Ji = J[i]                 # (a row view: the interpreted tier's faster indexing)
        for j in range(J.shape[1]):
            v = abs(Ji[j] * columns[j])
            if v > big:
                big = v
        r[i] = big if big > 0 else 1.0


@leaf
def _rows_nz(vals, jr, jc, columns, r):
    """:func:`_rows` from the nonzero values (each position once): the same maxima."""
    m = r.size
    for i in range(m):
        r[i] = 0.0
    for k in range(jr.size):
        v = abs(vals[k] * columns[jc[k]])
        if v > r[jr[k]]:
            r[jr[k]] = v
    for i in range(m):
        if not r[i] > 0:
            r[i] = 1.0


@leaf
def _norm1(B, n):
    """One-norm of the matrix stored transposed in ``B``: its largest column sum."""
    anorm = 0.0
    for j in range(n):
        s = 0.0
        for i in range(n):
            s += abs(B[j, i])
        if s > anorm:
            anorm = s
    return anorm


@leaf
def _norm1_nz(B, n, S):
    """:func:`_norm1` summing only the structure ``S`` (:func:`_structure`; each column's rows
    ascending): the same sums in the same order, since an entry outside it is a zero and
    ``s + 0 = s`` for the running ``s >= 0``. (A cost in the nonzeros instead of ``n^2``: the
    interpreted tier pays per element, decision 0078.)"""
    anorm = 0.0
    for j in range(n):
        s = 0.0
        for k in range(S[2 * n, j]):
            s += abs(B[j, S[j, k]])
        if s > anorm:
            anorm = s
    return anorm


@leaf
def _fill(J, r, columns, B):
    """``B`` = :math:`R^{-1} J D` in transposed storage; returns its one-norm."""
    n = J.shape[0]
    for i in range(n):
        inv = 1.0 / r[i]
        for j in range(n):
            B[j, i] = (J[i, j] * columns[j]) * inv
    return _norm1(B, n)


@leaf
def _fill_nz(vals, jr, jc, r, columns, B, S):
    """:func:`_fill` of the Jacobian whose nonzero values are ``vals`` (each position once:
    ``sweep_dense`` checks), without assembling it: the same entries (``0.0 + v`` as
    :func:`_assemble` forms them, so even the sign of a zero is the same), the same norm
    (:func:`_norm1_nz` over its structure ``S``)."""
    B[:, :] = 0.0
    for k in range(jr.size):
        i = jr[k]
        j = jc[k]
        B[j, i] = ((0.0 + vals[k]) * columns[j]) * (1.0 / r[i])
    return _norm1_nz(B, r.size, S)


@leaf
def _fill_nz_t(vals, jr, jc, r, columns, B, S):
    """``B[i, j] = (J_ij c_j) / r_i`` from the nonzero values (each position once): the C
    order of :math:`R^{-1} J D`, which is the transposed storage of its transpose (the
    multiplier solves factorise :math:`B^T`), the operations of the dense fill
    ``inv = 1 / r_i; B[i, j] = (J_ij c_j) inv`` (``0.0 + v`` as :func:`_assemble` forms the
    entry); returns the one-norm of that transpose (:func:`_norm1_nz` over ``S``, the
    structure of :math:`J^T`)."""
    B[:, :] = 0.0
    for k in range(jr.size):
        i = jr[k]
        j = jc[k]
        B[i, j] = ((0.0 + vals[k]) * columns[j]) * (1.0 / r[i])
    return _norm1_nz(B, r.size, S)


@leaf
def _factor(lapack, J, r, columns, B, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf, work, iwork,
            guard):
    """LU of :math:`R^{-1} J D` into ``B`` (transposed storage): :func:`_fill`, then
    :func:`_factor_filled`."""
    return _factor_filled(lapack, B, _fill(J, r, columns, B), ipiv, nz, S, W, seen, ibuf, cbuf,
                          dbuf, work, iwork, guard)


@leaf
def _factor_filled(lapack, B, anorm, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf, work, iwork,
                   guard):
    """LU of the matrix in ``B`` (transposed storage, one-norm ``anorm``); returns its
    reciprocal condition number, or -1 when singular (the Python path's ``Singular``: an
    exact zero pivot or an estimate below ``RCOND_MIN``).

    Up to ``SMALL`` unknowns the LU is :func:`getrf_lists` (LAPACK's elimination visiting
    the Jacobian's structure ``S`` and its fill only, decision 0078; below ``LIST_LU_MIN``
    unknowns the dense :func:`getrf`, the same numbers), and the factors' nonzero structure
    ``nz`` (used by the solves and estimates) is written again (:func:`lists_pattern`) only
    when the pivots differ from ``seen[0]`` (those it was made for); ``W``: the lists' work;
    :func:`_structure` makes the three.

    ``guard`` > 0 (up to ``SMALL`` unknowns): when :func:`inv_norm_bound` proves that the
    estimate is at least ``guard`` it is not computed and ``RCOND_PENDING`` (``inf``) is
    returned. Newton's steps pass ``RCOND_MIN`` (only "singular or not" matters there), the
    sweep's velocity factorisation ``RCOND_WARN`` (its estimate is computed later, on
    demand: :func:`fill_rconds`). The decision is the estimate's own: the bound exceeds
    anything ``gecon1`` can compute from these factors (``_jit_lapack.inv_norm_bound``),
    with a margin of ``1 / GUARD_MARGIN``. ``guard`` 0: the estimate, always."""
    n = B.shape[0]
    if n <= SMALL:
        # LAPACK's algorithms written out (_jit_lapack): the calls' overhead dominated
        small = n < LIST_LU_MIN
        info = getrf(B, n, ipiv) if small else getrf_lists(B, n, ipiv, S, W, seen, True)
        if info > 0 or anorm == 0:
            return -1.0
        same = True
        for j in range(n):
            if ipiv[j] != seen[0, j]:
                same = False
        if not same:
            # the factors' structure (symbolic: every matrix of this structure and these
            # pivots), written once per pivot sequence
            if small:
                getrf_lists(B, n, ipiv, S, W, seen, False)
            lists_pattern(n, W, seen, nz)
            for j in range(n):
                seen[0, j] = ipiv[j]
        if guard > 0 and anorm * inv_norm_bound(B, n, nz, work) <= GUARD_MARGIN / guard:
            return RCOND_PENDING
        rcond = gecon1(B, n, anorm, work, work[n:], nz)
    else:
        ibuf[0] = n          # m, n, lda
        ibuf[1] = n
        ibuf[2] = n
        ibuf[3] = 0          # info
        _ccall(lapack[0], (ibuf[0:1], ibuf[1:2], B, ibuf[2:3], ipiv, ibuf[3:4]))
        if ibuf[3] > 0 or anorm == 0:
            return -1.0
        cbuf[0] = 49         # '1': one-norm
        dbuf[0] = anorm
        dbuf[1] = 0.0
        _ccall(lapack[1], (cbuf[0:1], ibuf[1:2], B, ibuf[2:3], dbuf[0:1], dbuf[1:2], work, iwork,
                           ibuf[3:4]))
        rcond = dbuf[1]
    if rcond < RCOND_MIN:
        return -1.0
    return rcond


@nb.njit(cache=True)
def _factor_work(m, n, nd):
    """The work arrays of :func:`_factor` and :func:`_solve`: ``J`` (m, n), ``B`` (n, n),
    pivots, the factors' pattern ``nz``, LAPACK's integer, character and real buffers, its
    work arrays, and the row scales ``r`` (m,). ``nd``: the dense matrices' size (``n``, or
    1 for a banded sweep, which uses only the pivots, buffers and row scales)."""
    md = m if nd == n else 1
    return (np.empty((md, nd)), np.empty((nd, nd)), np.empty(n, dtype=np.int32),
            np.empty(pattern_size(nd), dtype=np.int32), np.zeros(5, dtype=np.int32),
            np.zeros(2, dtype=np.uint8), np.zeros(2), np.empty(4 * n), np.empty(n, dtype=np.int32),
            np.empty(m))


@nb.njit(cache=True)
def _structure(jr, jc, n):
    """``S``, ``W``, ``seen`` of :func:`_factor_filled` for the square matrix whose nonzeros
    are at rows ``jr``, columns ``jc`` (repeats allowed): ``S`` (int32 (2n + 2, n)) its
    structure as lists, ascending (``S[c, :S[2n, c]]`` column ``c``'s rows, ``S[n + r,
    :S[2n + 1, r]]`` row ``r``'s columns: ``_jit_lapack.getrf_lists``), ``W`` the lists'
    work (holding ``S``'s lists and flags), ``seen`` (int32 (3, n)): no pivots seen yet
    (``seen[0]``), and the rows' positions."""
    mark = np.zeros((n, n), dtype=np.bool_)
    for k in range(jr.size):
        mark[jr[k], jc[k]] = True
    S = np.zeros((2 * n + 2, n), dtype=np.int32)
    W = np.zeros((lists_size(n), n), dtype=np.int32)
    for c in range(n):
        for r in range(n):
            if mark[r, c]:
                S[c, S[2 * n, c]] = r
                S[2 * n, c] += 1
                S[n + r, S[2 * n + 1, r]] = c
                S[2 * n + 1, r] += 1
                W[2 * n + 4 + c, r] = 1
    W[:2 * n + 2, :] = S
    seen = np.zeros((3, n), dtype=np.int32)
    seen[0, :] = -1
    return S, W, seen


@nb.njit(cache=True)
def _unique(jr, jc, m, n):
    """No (row, column) twice among the Jacobian's nonzeros."""
    seen = np.zeros((m, n), dtype=np.bool_)
    for k in range(jr.size):
        if seen[jr[k], jc[k]]:
            return False
        seen[jr[k], jc[k]] = True
    return True


@nb.njit(cache=True)
def _no_structure():
    """:func:`_structure`'s arrays for a loop that does not factorise dense matrices."""
    return (np.zeros((1, 1), dtype=np.int32), np.zeros((1, 1), dtype=np.int32),
            np.full((3, 1), -1, dtype=np.int32))


@leaf
def _solve(lapack, B, ipiv, nz, r, columns, b, out, ibuf, cbuf):
    n = r.size
    for i in range(n):
        out[i] = b[i] / r[i]
    if n <= SMALL:
        # getrs(B, n, ipiv, out, nz) written out (the same operations in the same order): the
        # calls cost about half as much as the solve itself at this size
        # (two statements an entry: the interpreted tier pays per statement)
        for j in range(n):
            p = ipiv[j]
            if p != j:
                out[j], out[p] = out[p], out[j]
        for j in range(n):
            xj = out[j]
            for k in range(nz[j], nz[j + 1]):
                out[nz[k]] -= xj * B[j, nz[k]]
        for j in range(n - 1, -1, -1):
            xj = out[j] / B[j, j]
            out[j] = xj
            for k in range(nz[n + 1 + j], nz[n + 2 + j]):
                out[nz[k]] -= xj * B[j, nz[k]]
    else:
        cbuf[1] = 78         # 'N': no transpose
        ibuf[1] = n          # n, lda = ldb (set here too: a solve never relies on an earlier factor call)
        ibuf[2] = n
        ibuf[4] = 1          # nrhs
        _ccall(lapack[2], (cbuf[1:2], ibuf[1:2], ibuf[4:5], B, ibuf[2:3], ipiv, out, ibuf[2:3],
                           ibuf[3:4]))
    for i in range(n):
        out[i] = columns[i] * out[i]


@leaf
def _band_values(vals, off, slot, data):
    """``System.assemble(sparse=True)``'s CSC values ``data`` (one per stored entry) from the
    nonzero values ``vals[off:]``: duplicates summed in their order, as ``np.bincount``."""
    for s in range(data.size):
        data[s] = 0.0
    for k in range(slot.size):
        data[slot[k]] += vals[off + k]


@leaf
def _band_rows(data, cr, cc, columns, r):
    """``Scaling.rows`` of the CSC Jacobian (stored entry ``s`` at row ``cr[s]``, column
    ``cc[s]``): the same maxima."""
    for i in range(r.size):
        r[i] = 0.0
    for s in range(data.size):
        v = abs(data[s]) * columns[cc[s]]
        if v > r[cr[s]]:
            r[cr[s]] = v
    for i in range(r.size):
        if not r[i] > 0:
            r[i] = 1.0


@leaf
def _band_factor(blapack, data, cr, cc, pos, r, columns, AB, bw, ipiv, bi):
    """``Scaling.factor`` of a CSC Jacobian through its ``FixedPattern`` (``_linalg``): the
    scaled values ``data * (c / r)`` scattered into LAPACK's band storage ``AB`` (flat,
    column-major, ``bw = (kl, ku, ld)``) at the pattern's positions ``pos``, then ``dgbtrf``
    (SciPy's, through its C address ``blapack[0]``: the routine the Python path calls).
    Returns the pivot ratio ``min |u_jj| / max |u_jj|``, or -1 when singular (an exact zero
    pivot, a ratio not above ``RCOND_MIN``, a non-finite pivot), as ``_BandFactor``."""
    kl, ku, ld = bw[0], bw[1], bw[2]
    n = r.size
    for i in range(AB.size):
        AB[i] = 0.0
    for s in range(data.size):
        AB[pos[s]] += data[s] * (columns[cc[s]] / r[cr[s]])
    bi[0] = n            # m, n, kl, ku, ldab, info
    bi[1] = n
    bi[2] = kl
    bi[3] = ku
    bi[4] = ld
    bi[5] = 0
    _ccall(blapack[0], (bi[0:1], bi[1:2], bi[2:3], bi[3:4], AB, bi[4:5], ipiv, bi[5:6]))
    if bi[5] > 0:
        return -1.0
    dmin = np.inf
    dmax = 0.0
    for j in range(n):
        d = abs(AB[kl + ku + j * ld])
        if not d == d:
            return -1.0
        if d < dmin:
            dmin = d
        if d > dmax:
            dmax = d
    if not dmin > RCOND_MIN * dmax:
        return -1.0
    return dmin / dmax


@leaf
def _dgbtrs(blapack, AB, bw, ipiv, x, n, trans, bi, cbuf):
    """LAPACK ``dgbtrs`` (``blapack[1]``) on :func:`_band_factor`'s factors, one right-hand
    side ``x`` solved in place; ``trans``: ``78`` ('N') or ``84`` ('T')."""
    cbuf[1] = trans
    bi[1] = n            # n, kl, ku, ldab, info, nrhs
    bi[2] = bw[0]
    bi[3] = bw[1]
    bi[4] = bw[2]
    bi[5] = 0
    bi[6] = 1
    _ccall(blapack[1], (cbuf[1:2], bi[1:2], bi[2:3], bi[3:4], bi[6:7], AB, bi[4:5], ipiv, x,
                        bi[1:2], bi[5:6]))


@leaf
def _band_solve(blapack, AB, bw, ipiv, row_perm, perm, r, columns, b, out, tmp, bi, cbuf):
    """``ScaledFactor.solve`` of :func:`_band_factor`'s factors: ``b / r`` in the pattern's
    row order, ``dgbtrs``, back to the coordinates' order, times ``c``."""
    n = r.size
    for i in range(n):
        out[i] = b[i] / r[i]
    for i in range(n):
        tmp[i] = out[row_perm[i]]
    _dgbtrs(blapack, AB, bw, ipiv, tmp, n, 78, bi, cbuf)
    for i in range(n):
        out[perm[i]] = tmp[i]
    for i in range(n):
        out[i] = columns[i] * out[i]


@leaf
def big_sizes(bw, n):
    """The sizes of ``AB`` and ``SI`` for the sparse LU that ``bw`` describes (``bw[0] ==
    SPARSE``), else 1 and 1 (a dense loop)."""
    if bw[0] == SPARSE:
        return bw[1] + bw[2] + bw[3] + 3 * n, bw[1] + (IWORK + 4) * n + 3 + bw[2] + bw[3]
    return 1, 1


@nb.njit(cache=True)
def _big_work(bw, n, head, nvals):
    """The work arrays of :func:`_sparse_factor` and :func:`_sparse_solve_scaled` for the
    sparse LU that ``bw`` describes (a dense loop's: of size 1, :func:`big_sizes`): the
    factors' float store ``AB``, the integer store ``SI`` starting with ``B``'s CSC
    structure ``head``, the nonzero values ``data`` (``nvals``,) and a solve's ``tmp``
    (n,)."""
    fsize, isize = big_sizes(bw, n)
    AB = np.zeros(fsize)
    SI = np.zeros(isize, dtype=np.int64)
    for i in range(head.size):
        SI[i] = head[i]
    return AB, SI, np.empty(nvals), np.empty(n)


@leaf
def _sparse_factor(data, cr, cc, pos, r, columns, AB, bw, SI):
    """:func:`_band_factor` through the sparse LU (``_linalg._SparseFactor``, the Python
    path's: the same function): the scaled values ``data * (c / r)`` at their positions in
    ``B = P Q A P^T``, ``lu_factor``, the pivot ratio of ``U``'s diagonal."""
    n = r.size
    nb_, capL, capU = bw[1], bw[2], bw[3]
    Bx = AB[:nb_]
    Lx = AB[nb_:nb_ + capL]
    Ux = AB[nb_ + capL:nb_ + capL + capU]
    xw = AB[nb_ + capL + capU:nb_ + capL + capU + n]
    o = n + 1 + nb_
    Bp = SI[:n + 1]
    Bi = SI[n + 1:o]
    Lp = SI[o:o + n + 1]
    Up = SI[o + n + 1:o + 2 * n + 2]
    pinv = SI[o + 2 * n + 2:o + 3 * n + 2]
    o2 = o + (3 + IWORK) * n + 2
    iw = SI[o + 3 * n + 2:o2]
    Li = SI[o2:o2 + capL]
    Ui = SI[o2 + capL:o2 + capL + capU]
    for i in range(nb_):
        Bx[i] = 0.0
    for s in range(data.size):
        Bx[pos[s]] += data[s] * (columns[cc[s]] / r[cr[s]])
    if lu_factor(n, Bp, Bi, Bx, PIVOT_TOL, Lp, Li, Lx, Up, Ui, Ux, pinv, iw, xw) != 0:
        return -1.0
    ratio = lu_pivot_ratio(n, Up, Ux)
    if not ratio > RCOND_MIN:
        return -1.0
    return ratio


@leaf
def _sparse_solve(AB, bw, SI, x, trans):
    """``B x = x`` (``trans``: ``B^T x = x``) in place with :func:`_sparse_factor`'s factors."""
    n = x.size
    nb_, capL, capU = bw[1], bw[2], bw[3]
    o = nb_ + capL + capU
    Lx = AB[nb_:nb_ + capL]
    Ux = AB[nb_ + capL:o]
    y = AB[o + n:o + 2 * n]
    w = AB[o + 2 * n:o + 3 * n]
    o = n + 1 + nb_
    Lp = SI[o:o + n + 1]
    Up = SI[o + n + 1:o + 2 * n + 2]
    pinv = SI[o + 2 * n + 2:o + 3 * n + 2]
    o2 = o + (3 + IWORK) * n + 2
    Li = SI[o2:o2 + capL]
    Ui = SI[o2 + capL:o2 + capL + capU]
    if trans:
        lu_solve_t(n, pinv, Lp, Li, Lx, Up, Ui, Ux, x, y, w)
    else:
        lu_solve(n, pinv, Lp, Li, Lx, Up, Ui, Ux, x, y, w)
    for i in range(n):
        x[i] = y[i]


@leaf
def _sparse_solve_scaled(AB, bw, SI, row_perm, perm, r, columns, b, out, tmp, trans):
    """``ScaledFactor.solve`` of :func:`_sparse_factor`'s factors: ``b / r`` in the pattern's
    row order, the sparse LU's solve, back to the coordinates' order, times ``c``; ``trans``:
    ``solve_transposed``, ``lambda`` with ``J^T lambda = b``: ``c b`` in the pattern's column
    order, the transposed solve, back in the rows' order, over ``r``."""
    n = r.size
    first, second = (perm, row_perm) if trans else (row_perm, perm)
    for i in range(n):
        out[i] = columns[i] * b[i] if trans else b[i] / r[i]
    for i in range(n):
        tmp[i] = out[first[i]]
    _sparse_solve(AB, bw, SI, tmp, trans)
    for i in range(n):
        out[second[i]] = tmp[i]
    for i in range(n):
        out[i] = out[i] / r[i] if trans else columns[i] * out[i]


@leaf
def _scaled_norm(F, r, m):
    norm = 0.0
    for i in range(m):
        v = abs(F[i] / r[i])
        if v > norm:
            norm = v
    return norm


__all__ = ["big_sizes"]
