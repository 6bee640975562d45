"""Numba code of the compiled kinematic sweep (imported only when it runs: see ``_jit_sweep.py``).

Every function mirrors one piece of the Python path, in the same order of floating-point
operations, so that both give the same numbers:

* ``_eval``          ``System.f_position`` / ``f_velocity`` / ``f_gamma`` at ``[t, q, qd, p]``
* ``_assemble``      ``System.assemble`` (dense ``Phi_q`` from its nonzero values)
* ``_rows``          ``Scaling.rows``
* ``_scaling``       ``Scaling.of`` at the guess (from the loop's first evaluation)
* ``_factor``        ``Scaling.factor`` -> ``Factor`` (LAPACK dgetrf + dgecon on ``R^-1 J D``;
                     up to ``SMALL`` unknowns their algorithms from ``_jit_lapack``)
* ``_solve``         ``ScaledFactor.solve``
* ``_band_*``,      the same, above ``SPARSE_THRESHOLD`` unknowns, through the Jacobian's
  ``_sparse_*``      ``FixedPattern`` (``System.assemble``'s CSC values, ``Scaling.rows``,
                     the compiled sparse LU, the pivot ratio; decisions 0030, 0031);
                     ``_band_factor``/``_band_solve``: LAPACK ``dgbtrf``/``dgbtrs`` on a
                     band, for the banded patterns of free motion's and the multipliers'
                     Newton matrices
* ``_newton``        ``solve_position`` with a given scaling and the previous point's
                     velocity factorisation as its chord (kept in ``B``, ``ipiv``, ``nz``
                     with its row scales ``rprev``)
* ``_predict``       ``_kinematics._predict``
* ``fill_rconds``    the condition estimates the loop proved regular and left for later
                     (``SweepResult.rcond``, decision 0023)

The matrices handed to LAPACK are stored transposed in C order, which is column-major
(Fortran) order of the matrix itself. The helpers that allocate nothing are compiled
without reference counting (``_jit_lapack.leaf``, decision 0025).
"""

from __future__ import annotations

import numba as nb
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ._jit_cache import check as _check_cache
from ._jit_lapack import GUARD_MARGIN, gecon1, getrf, inv_norm_bound, leaf, pattern_size, symbolic_pattern
from ._jit_modes import within
from ._jit_sparse import IWORK, lu_factor, lu_pivot_ratio, lu_solve, lu_solve_t
from ._tolerances import (
    ARM_ROUNDOFF,
    CHORD_RATE,
    PIVOT_TOL,
    RCOND_MIN,
    RCOND_PENDING,
    RCOND_WARN,
    ROTATION_JUMP,
    ROTATION_SLACK,
    ROTATION_START,
    SPARSE_THRESHOLD,
)

_check_cache()   # stale cached loops go before anything here compiles (see _jit_cache)

#: up to this many unknowns the LU and condition estimate are computed in the loop
#: (``_jit_lapack``: LAPACK's algorithms, without the call overhead, skipping the zero
#: multipliers and visiting only the factors' nonzeros); above, LAPACK is called. That is
#: every size the compiled sweep takes: a mechanism's Jacobian is sparse, and the written-out
#: LU beat LAPACK's blocked one on the four-bar chains of 33 to 147 unknowns by 1.6-2.6 x
#: (decision 0019, amended)
SMALL = SPARSE_THRESHOLD


@intrinsic
def _ccall(typingctx, addr, args):
    """Call ``void f(void *, ...)`` at ``addr``: each array of the tuple ``args`` passes its
    data pointer, each integer passes as a pointer value (a context)."""
    sig = types.void(addr, args)

    def codegen(context, builder, signature, llargs):
        vp = ir.IntType(8).as_pointer()
        tup_ty = signature.args[1]
        vals = cgutils.unpack_tuple(builder, llargs[1], len(tup_ty))
        ptrs = []
        for ty, val in zip(tup_ty, vals):
            if isinstance(ty, types.Array):
                ptrs.append(builder.bitcast(context.make_array(ty)(context, builder, val).data, vp))
            else:
                ptrs.append(builder.inttoptr(val, vp))
        fn = builder.inttoptr(llargs[0], ir.FunctionType(ir.VoidType(), [vp] * len(ptrs)).as_pointer())
        builder.call(fn, ptrs)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _kcall(typingctx, addr, out, off, x, ctx):
    """Call the kernel ``void f(double *out, const double *x, void *ctx)`` at ``addr`` with
    ``out`` starting at element ``off``. The arrays pass as arguments, not in a tuple as to
    :func:`_ccall`: building a tuple of arrays increments and decrements their reference
    counts (atomic operations), which cost 10-15 % of the sweep, measured."""
    sig = types.void(addr, out, off, x, ctx)

    def codegen(context, builder, signature, llargs):
        vp = ir.IntType(8).as_pointer()
        o = context.make_array(signature.args[1])(context, builder, llargs[1])
        a = context.make_array(signature.args[3])(context, builder, llargs[3])
        optr = builder.gep(o.data, [llargs[2]])
        fn = builder.inttoptr(llargs[0], ir.FunctionType(ir.VoidType(), [vp, vp, vp]).as_pointer())
        builder.call(fn, [builder.bitcast(optr, vp), builder.bitcast(a.data, vp),
                          builder.inttoptr(llargs[4], vp)])
        return context.get_dummy_value()

    return sig, codegen


@leaf
def _eval(ptr, x, nin, out):
    """One kernel (a row of the pointer table: see ``_jit_runtime.table``) at ``x[:nin]``; a
    two-stage kernel first writes its ``Piecewise`` values into ``x[nin:]``."""
    if ptr[2] != 0:
        _kcall(ptr[2], x, nin, x, ptr[3])
    _kcall(ptr[0], out, 0, x, ptr[1])


@leaf
def _eval_row(ptrs, row, x, nin, out):
    """:func:`_eval` of row ``row`` of the pointer table, given the table: a view of the row
    per call costs its reference counting, about as much as a small kernel."""
    if ptrs[row, 2] != 0:
        _kcall(ptrs[row, 2], x, nin, x, ptrs[row, 3])
    _kcall(ptrs[row, 0], out, 0, x, ptrs[row, 1])


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
        for j in range(J.shape[1]):
            v = abs(J[i, j] * columns[j])
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
def _fill(J, r, columns, B):
    """``B`` = ``R^-1 J D`` in transposed storage; returns its one-norm."""
    n = J.shape[0]
    for i in range(n):
        inv = 1.0 / r[i]
        for j in range(n):
            B[j, i] = (J[i, j] * columns[j]) * inv
    return _norm1(B, n)


@leaf
def _fill_nz(vals, jr, jc, r, columns, B):
    """:func:`_fill` of the Jacobian whose nonzero values are ``vals`` (each position once:
    ``sweep_dense`` checks), without assembling it: the same entries (``0.0 + v`` as
    :func:`_assemble` forms them, so even the sign of a zero is the same), the same norm."""
    B[:, :] = 0.0
    for k in range(jr.size):
        i = jr[k]
        j = jc[k]
        B[j, i] = ((0.0 + vals[k]) * columns[j]) * (1.0 / r[i])
    return _norm1(B, r.size)


@leaf
def _factor(lapack, J, r, columns, B, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf, work, iwork,
            guard):
    """LU of ``R^-1 J D`` into ``B`` (transposed storage): :func:`_fill`, then
    :func:`_factor_filled`."""
    return _factor_filled(lapack, B, _fill(J, r, columns, B), ipiv, nz, S, W, seen, ibuf, cbuf,
                          dbuf, work, iwork, guard)


@leaf
def _factor_filled(lapack, B, anorm, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf, work, iwork,
                   guard):
    """LU of the matrix in ``B`` (transposed storage, one-norm ``anorm``); returns its
    reciprocal condition number, or -1 when singular (the Python path's ``Singular``: an
    exact zero pivot or an estimate below ``RCOND_MIN``).

    Up to ``SMALL`` unknowns the factors' nonzero structure ``nz`` (used by the solves and
    estimates) is :func:`symbolic_pattern` of the Jacobian's structure ``S`` (n, n, transposed
    storage), made again only when the pivots differ from ``seen`` (n,), those it was made
    for (``W`` (n, n): its work); :func:`_structure` makes the three.

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
        if getrf(B, n, ipiv) > 0 or anorm == 0:
            return -1.0
        same = True
        for j in range(n):
            if ipiv[j] != seen[j]:
                same = False
        if not same:
            # the factors' structure, once per pivot sequence: recording it after every
            # factorisation cost 6 % of the sweep
            symbolic_pattern(S, n, ipiv, nz, W)
            for j in range(n):
                seen[j] = ipiv[j]
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
    """``S``, ``W``, ``seen`` of :func:`_factor_filled`: the square Jacobian's structure from
    its nonzeros' rows and columns (transposed storage), work, no pivots seen yet."""
    S = np.zeros((n, n))
    for k in range(jr.size):
        S[jc[k], jr[k]] = 1.0
    return S, np.empty((n, n)), np.full(n, -1, dtype=np.int32)


@leaf
def _solve(lapack, B, ipiv, nz, r, columns, b, out, ibuf, cbuf):
    n = r.size
    for i in range(n):
        out[i] = b[i] / r[i]
    if n <= SMALL:
        # getrs(B, n, ipiv, out, nz) written out (the same operations in the same order): the
        # calls cost about half as much as the solve itself at this size
        for j in range(n):
            p = ipiv[j]
            if p != j:
                tmp = out[j]
                out[j] = out[p]
                out[p] = tmp
        for j in range(n):
            xj = out[j]
            for k in range(nz[j], nz[j + 1]):
                i = nz[k]
                out[i] -= xj * B[j, i]
        for j in range(n - 1, -1, -1):
            xj = out[j] / B[j, j]
            out[j] = xj
            for k in range(nz[n + 1 + j], nz[n + 2 + j]):
                i = nz[k]
                out[i] -= xj * B[j, i]
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


#: ``bw[0]`` of a pattern factorised by the sparse LU (``_jit_sparse``, a wide band: trees);
#: ``bw = (SPARSE, nnz, capL, capU)`` with ``nnz`` the pattern's entries and ``capL``,
#: ``capU`` the storage of the factors. The factors and work arrays live in the float array
#: ``AB = [Bx (nnz) | Lx (capL) | Ux (capU) | 3 work (n)]`` and the int array
#: ``SI = [Bp (n + 1) | Bi (nnz) | Lp (n + 1) | Up (n + 1) | pinv (n) | iw (IWORK n) |
#: Li (capL) | Ui (capU)]``, whose head is ``B = P Q A P^T``'s CSC structure
SPARSE = -2


@leaf
def big_sizes(bw, n):
    """The sizes of ``AB`` and ``SI`` for the sparse LU that ``bw`` describes (``bw[0] ==
    SPARSE``), else 1 and 1 (a dense loop)."""
    if bw[0] == SPARSE:
        return bw[1] + bw[2] + bw[3] + 3 * n, bw[1] + (IWORK + 4) * n + 3 + bw[2] + bw[3]
    return 1, 1



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


@leaf
def _jump(q, ref, rot):
    big = 0.0
    for j in rot:
        v = abs(q[j] - ref[j])
        if v > big:
            big = v
    return big


@leaf
def _predict(Q, QD, QDD, rconds, times, k, rot, order, g, sec):
    n = Q.shape[1]
    dt = times[k] - times[k - 1]
    have_secant = k >= 2
    if have_secant:
        dt0 = times[k - 1] - times[k - 2]
        for j in range(n):
            sec[j] = Q[k - 1, j] + (Q[k - 1, j] - Q[k - 2, j]) * (dt / dt0) if dt0 != 0 else Q[k - 1, j]
    if order == 0 or (rconds[k - 1] < RCOND_WARN and have_secant):
        for j in range(n):
            g[j] = sec[j] if have_secant else Q[k - 1, j]
        return
    if rconds[k - 1] < RCOND_WARN:
        big = 0.0
        for j in rot:
            v = abs(QD[k - 1, j] * dt)
            if v > big:
                big = v
        f = ROTATION_START / big if big > ROTATION_START else 1.0
        for j in range(n):
            step = QD[k - 1, j] * dt
            g[j] = Q[k - 1, j] + (step * f if big > ROTATION_START else step)
        return
    for j in range(n):
        g[j] = Q[k - 1, j] + QD[k - 1, j] * dt
    if order >= 2:
        for j in range(n):
            g[j] = g[j] + 0.5 * QDD[k - 1, j] * dt * dt
        if have_secant and dt0 != 0 and rconds[k - 2] >= RCOND_WARN:
            c3 = dt * dt * dt / 6.0
            dt1 = times[k - 2] - times[k - 3] if k >= 3 else 0.0
            if dt1 != 0 and dt0 + dt1 != 0 and rconds[k - 3] >= RCOND_WARN:
                c4 = dt * dt * dt * dt / 12.0
                for j in range(n):
                    a = (QDD[k - 1, j] - QDD[k - 2, j]) / dt0
                    b = (a - (QDD[k - 2, j] - QDD[k - 3, j]) / dt1) / (dt0 + dt1)
                    g[j] = g[j] + (a + b * dt0) * c3 + b * c4
            else:
                for j in range(n):
                    a = (QDD[k - 1, j] - QDD[k - 2, j]) / dt0
                    g[j] = g[j] + a * c3
    if have_secant and rot.size:
        a = 0.0
        b = 0.0
        for j in rot:
            a = max(a, abs(g[j] - Q[k - 1, j]))
            b = max(b, abs(sec[j] - Q[k - 1, j]))
        if a > ROTATION_SLACK + 4 * b:
            for j in range(n):
                g[j] = sec[j]


@nb.njit(cache=True)
def _scaling(J, q, trans, body, nbody, hint, columns):
    """``Scaling.of(system, q, J)`` (``_linalg``): fills ``columns`` and returns the length
    ``L`` and the offset. The same comparisons and divisions, hence the same numbers: ``big``
    the largest position coordinate (0 when one is not finite), the lever arm the largest
    ratio, over rows and bodies, of the largest rotational to the largest translational
    entry (entries not finite count as 0), then the same choice of ``L``."""
    n = q.size
    m = J.shape[0]
    big = 0.0
    finite = True
    for j in range(n):
        if trans[j]:
            v = abs(q[j])
            if not np.isfinite(v):
                finite = False
            elif v > big:
                big = v
    if not finite:
        big = 0.0
    tmax = np.zeros(nbody)
    rmax = np.zeros(nbody)
    arm = 0.0
    for i in range(m):
        tmax[:] = 0.0
        rmax[:] = 0.0
        for j in range(n):
            b = body[j]
            v = abs(J[i, j])
            if b < 0 or not np.isfinite(v):
                continue
            if trans[j]:
                if v > tmax[b]:
                    tmax[b] = v
            elif v > rmax[b]:
                rmax[b] = v
        for b in range(nbody):
            if tmax[b] > 0 and rmax[b] > 0:
                ratio = rmax[b] / tmax[b]
                if ratio > arm:
                    arm = ratio
    ref = hint if hint > 0 else big
    if ref > 0 and arm <= ARM_ROUNDOFF * ref:
        arm = 0.0
    L = arm if arm > 0 else (hint if hint > 0 else (big if big > 0 else 1.0))
    for j in range(n):
        columns[j] = L if trans[j] else 1.0
    return L, big / L


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
def sweep_dense(ptrs, lapack, times, q0, p, jr, jc, columns, scale, ftol, maxit, damping, order,
                rot, trans, body, hint, Q, QD, QDD, its, rconds, rprev, lazy, R, first,
                chord_start, bw, band, large):
    """The sweep's regular points (see the module docstring); returns ``(k, evaluations)``
    with ``k`` the first point left to the Python loop. ``rprev`` (n,) receives the row
    scales of the last solved point's velocity factorisation (the chord of the next point:
    the Python loop refactorises it from them when it takes over). ``lazy``: a point whose
    condition estimate is proven to be at least ``RCOND_WARN`` gets ``RCOND_PENDING`` in
    ``rconds`` and its velocity factorisation's row scales in ``R`` (N, n), from which
    :func:`fill_rconds` computes the estimate when it is asked for (decision 0023).

    ``scale`` (2,): ``Scaling.length`` and ``offset`` with ``columns`` (n,) its column
    scales; ``scale[0] == 0``: the scaling of ``q0`` at the first time is computed from the
    first evaluation (:func:`_scaling`, with the columns' kinds ``trans``, ``body`` and the
    system's ``length_hint``) and returned in ``scale`` and ``columns``. The Newton
    tolerance is ``ftol (1 + offset)``. ``first``: the first point to solve; the rows
    before it of ``Q``, ``QD``, ``QDD``, ``rconds`` are the points solved before the sweep
    (the predictor's history: a multistage sweep's runs), and ``scale`` is given then;
    ``chord_start``: point ``first - 1`` had the chord (its velocity factorisation, made again
    here from ``Q[first - 1]`` and its row scales ``rprev``), as in one long sweep.

    ``bw[0] == SPARSE``: a large system (above ``SPARSE_THRESHOLD`` unknowns) solved as the
    Python path solves it, through the Jacobian's ``FixedPattern`` (the compiled sparse LU of
    ``_jit_sparse`` in the pattern's minimum-degree ordering, the function the Python path
    calls): ``bw = (SPARSE, nnz, capL, capU)``, ``band = (slot, cr, cc, pos, row_perm, perm,
    head)`` (each nonzero value's CSC entry; each entry's row, column and position in ``B =
    P Q A P^T``; the pattern's row and column orders; ``B``'s CSC structure). Its condition
    estimate is the pivot ratio, always computed (never pending); ``scale`` must be given.
    ``large``: ``bw[0] == SPARSE``, given apart so that a caller can pass it as a literal
    (``_jit_modes.entry``: the sparse LU is then compiled only for the sweeps that use it;
    decision 0044)."""
    n = q0.size
    m = n
    nnz = jr.size
    npar = p.size
    N = times.size
    nin = 1 + 2 * n + npar
    x = np.zeros(nin + max(ptrs[0, 4], ptrs[1, 4], ptrs[2, 4]))
    for j in range(npar):
        x[1 + 2 * n + j] = p[j]
    out_pos = np.empty(m + nnz)
    out_vel = np.empty(nnz + m)
    out_gam = np.empty(m)
    slot, cr, cc, pos, row_perm, perm, si0 = band
    nd = 1 if large else n          # the dense matrices are not used when large
    J, B, ipiv, nz, ibuf, cbuf, dbuf, work, iwork, r = _factor_work(m, n, nd)
    if large:
        S, W, seen = np.empty((1, 1)), np.empty((1, 1)), np.full(1, -1, dtype=np.int32)
    else:
        S, W, seen = _structure(jr, jc, n)
    fsize, isize = big_sizes(bw, n)
    AB = np.zeros(fsize)
    SI = np.zeros(isize, dtype=np.int64)
    for i in range(si0.size):
        SI[i] = si0[i]
    data = np.empty(cr.size)
    tmp = np.empty(n)
    F = np.empty(m)
    q = np.empty(n)
    g = np.empty(n)
    dq = np.empty(n)
    qn = np.empty(n)
    sec = np.empty(n)
    rhs = np.empty(m)
    jv = np.empty(nnz)
    unique = not large and _unique(jr, jc, m, n)
    nbody = 0
    for j in range(n):
        if body[j] + 1 > nbody:
            nbody = body[j] + 1
    tol = ftol * (1.0 + scale[1])
    # (not a conditional inside the call below: Numba would copy every argument through a
    # phi, each copy with its reference count)
    vguard = RCOND_WARN if lazy else 0.0
    evals = 0
    # B, ipiv, nz hold the previous point's velocity factorisation while have_chord is set
    have_chord = False
    if first > 0 and chord_start:
        # the chord of point first - 1, made as the loop makes it after solving that point
        x[0] = times[first - 1]
        for j in range(n):
            x[1 + j] = Q[first - 1, j]
            x[1 + n + j] = 0.0
            r[j] = rprev[j]
        _eval_row(ptrs, 1, x, nin, out_vel)
        if large:
            _band_values(out_vel, 0, slot, data)
            have_chord = within(large, 1, 1, _sparse_factor, data, cr, cc, pos,
                                r, columns, AB, bw, SI) >= RCOND_WARN
        else:
            if unique:
                anorm = _fill_nz(out_vel, jr, jc, r, columns, B)
            else:
                _assemble(out_vel, 0, jr, jc, J)
                anorm = _fill(J, r, columns, B)
            have_chord = _factor_filled(lapack, B, anorm, ipiv, nz, S, W, seen, ibuf, cbuf,
                                        dbuf, work, iwork, vguard) >= RCOND_WARN
    for k in range(first, N):
        t = times[k]
        x[0] = t
        if k == 0:
            for j in range(n):
                g[j] = q0[j]
        else:
            _predict(Q, QD, QDD, rconds, times, k, rot, order, g, sec)
        # -- Newton (solve_position) from g --
        for j in range(n):
            q[j] = g[j]
            x[1 + j] = q[j]
            x[1 + n + j] = 0.0
        _eval_row(ptrs, 0, x, nin, out_pos)
        e = 1
        for i in range(m):
            F[i] = out_pos[i]
        # J at q is assembled only when a Newton step needs it (stale: its values are in jv);
        # the row scales come from the values (the same numbers as from J: no duplicates)
        for i in range(nnz):
            jv[i] = out_pos[m + i]
        stale = True
        if k == 0 and scale[0] == 0.0:
            # the scaling of q0 (= g) from this evaluation (the Python path's _scaling)
            _assemble(jv, 0, jr, jc, J)
            scale[0], scale[1] = _scaling(J, g, trans, body, nbody, hint, columns)
            tol = ftol * (1.0 + scale[1])
        if large:
            _band_values(jv, 0, slot, data)
            _band_rows(data, cr, cc, columns, r)
        elif unique:
            _rows_nz(jv, jr, jc, columns, r)
        else:
            _assemble(jv, 0, jr, jc, J)
            stale = False
            _rows(J, columns, r)
        norm = _scaled_norm(F, r, m)
        it = 0
        ok = False
        chord = have_chord
        polish = have_chord              # converge to rounding (_position.solve_position)
        last_chord = True                # B holds the chord (rows rprev), else Newton's (r)
        prev = np.inf                    # scaled residual before the last step
        while True:
            finite = True
            for i in range(m):
                if not np.isfinite(F[i]):
                    finite = False
            if not finite:
                break
            if norm <= tol and it > 0:
                if polish and prev > tol and it < maxit:
                    # one more step with the last factorisation, kept while within tol
                    # (the step is the chord step's below, written twice on purpose: a shared
                    # helper, inlined by Numba, made the sweep 7-9 % slower, measured)
                    if large and last_chord:
                        within(large, 1, 1, _sparse_solve_scaled, AB, bw, SI, row_perm, perm,
                               rprev, columns, F, dq, tmp, False)
                    elif large:
                        within(large, 1, 1, _sparse_solve_scaled, AB, bw, SI, row_perm, perm,
                               r, columns, F, dq, tmp, False)
                    elif last_chord:
                        _solve(lapack, B, ipiv, nz, rprev, columns, F, dq, ibuf, cbuf)
                    else:
                        _solve(lapack, B, ipiv, nz, r, columns, F, dq, ibuf, cbuf)
                    for j in range(n):
                        dq[j] = -dq[j]
                        qn[j] = q[j] + dq[j]
                        x[1 + j] = qn[j]
                    _eval_row(ptrs, 0, x, nin, out_pos)
                    e += 1
                    nn = 0.0
                    for i in range(m):
                        v = abs(out_pos[i] / r[i])
                        if v > nn:
                            nn = v
                    if nn <= tol:
                        for j in range(n):
                            q[j] = qn[j]
                        for i in range(m):
                            F[i] = out_pos[i]
                        norm = nn
                        it += 1
                ok = True
                break
            if it >= maxit:
                break
            if chord:
                # chord step with the previous point's factorisation (_position.solve_position)
                if large:
                    within(large, 1, 1, _sparse_solve_scaled, AB, bw, SI, row_perm, perm,
                           rprev, columns, F, dq, tmp, False)
                else:
                    _solve(lapack, B, ipiv, nz, rprev, columns, F, dq, ibuf, cbuf)
                for j in range(n):
                    dq[j] = -dq[j]
                    qn[j] = q[j] + dq[j]
                    x[1 + j] = qn[j]
                _eval_row(ptrs, 0, x, nin, out_pos)
                e += 1
                nn = 0.0
                for i in range(m):
                    v = abs(out_pos[i] / r[i])
                    if v > nn:
                        nn = v
                if nn <= CHORD_RATE * norm:
                    for j in range(n):
                        q[j] = qn[j]
                    for i in range(m):
                        F[i] = out_pos[i]
                    for i in range(nnz):
                        jv[i] = out_pos[m + i]
                    stale = True
                    prev = norm
                    norm = nn
                    it += 1
                    continue
                chord = False            # too slow: a Newton step from q with its own Jacobian
                have_chord = False       # (B is overwritten)
            last_chord = False
            if large:
                _band_values(jv, 0, slot, data)
                if within(large, 1, 1, _sparse_factor, data, cr, cc, pos,
                          r, columns, AB, bw, SI) < 0:
                    break
                within(large, 1, 1, _sparse_solve_scaled, AB, bw, SI, row_perm, perm,
                       r, columns, F, dq, tmp, False)
            else:
                if stale:
                    _assemble(jv, 0, jr, jc, J)
                    stale = False
                if _factor(lapack, J, r, columns, B, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf,
                           work, iwork, RCOND_MIN) < 0:
                    break
                _solve(lapack, B, ipiv, nz, r, columns, F, dq, ibuf, cbuf)
            for j in range(n):
                dq[j] = -dq[j]
            a = 1.0
            while True:
                for j in range(n):
                    qn[j] = q[j] + a * dq[j]
                    x[1 + j] = qn[j]
                _eval_row(ptrs, 0, x, nin, out_pos)
                e += 1
                nn = 0.0
                for i in range(m):
                    v = abs(out_pos[i] / r[i])
                    if v > nn:
                        nn = v
                if not damping or nn <= (1 - 1e-4 * a) * norm or a < 1e-3 or norm <= tol:
                    break
                a *= 0.5
            for j in range(n):
                q[j] = qn[j]
            for i in range(m):
                F[i] = out_pos[i]
            if large:                            # (a Newton step: J is current)
                for i in range(nnz):
                    jv[i] = out_pos[m + i]
            else:
                _assemble(out_pos, m, jr, jc, J)
            prev = norm
            norm = nn
            it += 1
        if not ok:
            return k, evals
        if k > 0 and _jump(q, g, rot) > ROTATION_JUMP:
            return k, evals
        # -- velocity and acceleration with the Newton's row scales --
        if order >= 1:
            for j in range(n):
                x[1 + j] = q[j]
            _eval_row(ptrs, 1, x, nin, out_vel)
            if large:
                _band_values(out_vel, 0, slot, data)
                rc = within(large, 1, 1, _sparse_factor, data, cr, cc, pos, r, columns, AB, bw, SI)
            else:
                if unique:   # (B straight from the values: assembling J first cost 4 %)
                    anorm = _fill_nz(out_vel, jr, jc, r, columns, B)
                else:
                    _assemble(out_vel, 0, jr, jc, J)
                    anorm = _fill(J, r, columns, B)
                rc = _factor_filled(lapack, B, anorm, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf,
                                    work, iwork, vguard)
            if rc < 0:
                return k, evals
            if rc == RCOND_PENDING:
                for i in range(m):
                    R[k, i] = r[i]
            # the chord of the next point: only from a well-conditioned point (near a toggle
            # Newton keeps its fresh Jacobian)
            have_chord = rc >= RCOND_WARN
            for i in range(m):
                rprev[i] = r[i]
            for i in range(m):
                rhs[i] = -out_vel[nnz + i]
            if large:
                within(large, 1, 1, _sparse_solve_scaled, AB, bw, SI, row_perm, perm,
                       r, columns, rhs, dq, tmp, False)
            else:
                _solve(lapack, B, ipiv, nz, r, columns, rhs, dq, ibuf, cbuf)
            for j in range(n):
                QD[k, j] = dq[j]
            rconds[k] = rc
            e += 1
            if order >= 2:
                for j in range(n):
                    x[1 + n + j] = dq[j]
                _eval_row(ptrs, 2, x, nin, out_gam)
                if large:
                    within(large, 1, 1, _sparse_solve_scaled, AB, bw, SI, row_perm, perm,
                           r, columns, out_gam, dq, tmp, False)
                else:
                    _solve(lapack, B, ipiv, nz, r, columns, out_gam, dq, ibuf, cbuf)
                for j in range(n):
                    QDD[k, j] = dq[j]
                e += 1
        for j in range(n):
            Q[k, j] = q[j]
        its[k] = it
        evals += e
    return N, evals


@nb.njit(cache=True)
def fill_rconds(ptrs, lapack, times, Q, p, jr, jc, columns, R, rconds):
    """The condition estimates :func:`sweep_dense` left ``RCOND_PENDING``: each point's
    velocity factorisation made again, from the same Jacobian (``f_velocity`` at ``Q[k]``)
    and row scales ``R[k]`` with the same code, so the same number as the loop would have
    computed. Returns the number of points found singular (none can be: their bound proved
    the estimate to be at least ``RCOND_WARN``)."""
    n = Q.shape[1]
    m = n
    nnz = jr.size
    npar = p.size
    nin = 1 + 2 * n + npar
    x = np.zeros(nin + ptrs[1, 4])
    for j in range(npar):
        x[1 + 2 * n + j] = p[j]
    out_vel = np.empty(nnz + m)
    J, B, ipiv, nz, ibuf, cbuf, dbuf, work, iwork, r = _factor_work(m, n, n)
    S, W, seen = _structure(jr, jc, n)
    unique = _unique(jr, jc, m, n)
    bad = 0
    for k in range(rconds.size):
        if rconds[k] != RCOND_PENDING:
            continue
        x[0] = times[k]
        for j in range(n):
            x[1 + j] = Q[k, j]
        for i in range(m):
            r[i] = R[k, i]
        _eval_row(ptrs, 1, x, nin, out_vel)
        if unique:                       # (as the loop forms B)
            anorm = _fill_nz(out_vel, jr, jc, r, columns, B)
        else:
            _assemble(out_vel, 0, jr, jc, J)
            anorm = _fill(J, r, columns, B)
        rc = _factor_filled(lapack, B, anorm, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf, work, iwork,
                            0.0)
        if rc < 0:
            bad += 1
        rconds[k] = rc
    return bad
