r"""Numba loop of the multiplier solves over a solved sweep (imported only when it runs: see
``_jit_multipliers.multipliers``): statics, kinematic loads and inverse dynamics at every point,

.. math::

    \text{static:} \quad & \Phi_q^T \lambda = Q(t, q, 0) \\
    \text{kinematic:} \quad & \Phi_q^T \lambda = Q(t, q, \dot q) \\
    \text{dynamic:} \quad & \Phi_q^T \lambda = Q(t, q, \dot q, \ddot q) + Q_v(q, \dot q) - M(q) \ddot q

each point's operations those of :func:`~mechsys.solvers._statics.solve_multipliers` (the
Python path), in the same order:

* ``Phi_q`` from the position kernel (``System.jacobian``), assembled dense;
* its unit-free form :math:`B = R^{-1} \Phi_q D` (the sweep's column scales, the row scales of
  the point: ``_rows``), and ``B^T`` factorised by LU with partial pivoting and its reciprocal condition
  estimated (``Factor``: LAPACK ``dgetrf`` + ``dgecon``; up to ``SMALL`` unknowns their
  algorithms from ``_jit_lapack``). ``B`` in C order *is* ``B^T`` in the transposed storage
  the LAPACK helpers use, so no transpose is formed;
* ``M``, ``Q``, ``Qv`` from the dynamics kernel (``Dynamics.terms``); :math:`M \ddot q` from the
  mass matrix's nonzeros (the Python path multiplies the dense ``M``: the same to rounding);
* one solve (``dgetrs``) of :math:`B^T (R \lambda) = D \mathrm{rhs}`; or, for loads that depend on the
  multipliers (friction), Newton with :math:`D (\Phi_q^T - dQ/d\lambda) R^{-1}` from the previous
  point's multipliers.

Above ``SPARSE_THRESHOLD`` unknowns the Python path factorises :math:`R^{-1} \Phi_q D` itself
through the Jacobian's ``FixedPattern`` and solves it transposed; so does this loop, with
the same operations: the sparse LU of ``_jit_sparse`` (``_jit_linalg._sparse_factor``,
``_sparse_solve_scaled``). With friction, the Newton matrix goes through its own
pattern (the Python path's ``_patterns.multiplier_newton_pattern``: LAPACK's band LU when banded,
else the same compiled sparse LU), and the residual
:math:`\Phi_q^T \lambda - \mathrm{rhs}` is formed from the Jacobian's CSC values (the Python path: a dense
``Phi_q``; the same to rounding, and both stop on the same tolerance).

A point that the Python path would refuse (an exactly zero pivot, a reciprocal condition
below ``RCOND_MIN``) or whose multipliers come out non-finite ends the loop there: the
Python path takes that point and the rest, with its diagnostics.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ._jit_cache import check as _check_cache
from ._jit_calls import _eval_row
from ._jit_lapack import leaf
from ._jit_linalg import (
    _assemble,
    _band_factor,
    _band_rows,
    _band_solve,
    _band_values,
    _big_work,
    _factor_filled,
    _factor_work,
    _fill_nz_t,
    _no_structure,
    _norm1_nz,
    _rows,
    _rows_nz,
    _solve,
    _sparse_factor,
    _sparse_solve_scaled,
    _structure,
    _unique,
    big_sizes,
)
from ._jit_modes import within
from ._jit_runtime import SPARSE
from ._tolerances import RCOND_MIN

_check_cache()   # stale cached loops go before anything here compiles (see _jit_cache)

STATIC, KINEMATIC, DYNAMIC = 0, 1, 2


@leaf
def _loads(ptrs, xd, nin_d, out_dyn, mode, QDD, k, mr, mc, kM, n, Mq, rhs):
    """The right-hand side at the arguments ``xd``: ``Q`` (static, kinematic) or ``Q + Qv -
    M qdd`` (dynamic, the product from ``M``'s nonzeros: the Python path multiplies the dense
    ``M`` with BLAS, whose order of summation is its own, so the two agree to rounding).
    False when a value is not finite (the Python path raises the error naming it)."""
    _eval_row(ptrs, 1, xd, nin_d, out_dyn)
    if mode == DYNAMIC:
        for i in range(n):
            Mq[i] = 0.0
        for e in range(kM):
            Mq[mr[e]] += out_dyn[e] * QDD[k, mc[e]]
        for i in range(n):
            rhs[i] = (out_dyn[kM + i] + out_dyn[kM + n + i]) - Mq[i]
    else:
        for i in range(n):
            rhs[i] = out_dyn[kM + i]
    for i in range(n):
        if not np.isfinite(rhs[i]):
            return False
    return True


@nb.njit(cache=True)
def multipliers(ptrs, lapack, times, Q, QD, QDD, p, jr, jc, mr, mc, kM, mode, LAM, dr, dc,
                guess, tol, maxit, cols, blapack, bw, band, kband, Rpre, banded):
    """``LAM[k]`` (m,) at each point ``k`` from 0 on; returns the first point left to the
    Python path (``len(times)`` when all are done).

    ``ptrs`` (3, 5): the position kernel ``x = [t, q, qd, p] -> [Phi, Phi_q values]``, the
    dynamics kernel ``x = [t, q, qd, lambda, p, qdd] -> [M values (kM), Q, Qv]`` and, for
    loads that depend on the multipliers, the kernel of ``dQ/dlambda``'s values at ``(dr,
    dc)`` (rows of the pointer table, see ``_jit_runtime.table``; a row of zeros and empty ``dr``
    otherwise); ``jr``, ``jc`` the Jacobian's nonzero positions, ``mr``, ``mc`` the mass
    matrix's. ``Q``, ``QD``, ``QDD`` (N, n): the sweep's states (``QD``, ``QDD`` are read
    only in the modes that use them). ``mode``: ``STATIC``, ``KINEMATIC``, ``DYNAMIC``.
    ``cols`` (n,): the column scales of the unit-free form (the sweep's ``Scaling.columns``).

    Loads that depend on the multipliers (``ptrs[2, 0] != 0``, friction): Newton on ``R =
    Phi_q^T lambda - rhs(lambda)`` with the matrix ``Phi_q^T - dQ/dlambda``, from ``guess``
    (m,) at the first point and from the previous point's multipliers after it, converged
    when ``max_j c_j |R_j| <= tol max_j c_j (sum_i |Phi_ij lambda_i| + |rhs_j|)`` (``c =
    cols``: unit-free, relative to the terms of ``R``), at most ``maxit`` iterations
    (``MultiplierOptions``).
    The Python path's ``J.T @ lambda`` sums with BLAS, so the two can stop one iteration
    apart at the tolerance: they agree to it, not to rounding.

    ``bw[0] >= 0``: a large system through its Jacobian's pattern (``bw``, ``band`` as in
    ``_jit_sweep_loop.sweep_dense``): the Jacobian's values in its CSC order. With loads that
    depend on the multipliers, the Newton matrix through its own pattern (the Python path's
    ``_patterns.multiplier_newton_pattern``): ``kband = (kbw, (pos, rows, cols, row_perm, perm, sJT,
    sD, head))``, ``sJT`` the slot of each Jacobian CSC entry (transposed), ``sD`` of each
    ``dQ/dlambda`` entry, ``kbw`` a band's ``(kl, ku, ld, 0)`` or the sparse LU's ``bw``
    (``big_sizes``) with ``head`` its ``B``'s CSC structure; the residual from the
    Jacobian's CSC values.

    ``Rpre`` (N, n): the right-hand sides given (the recursive Gen dynamics, which has no
    dynamics kernel: ``_jit_free_loop.gen_points``; ``ptrs[1]`` is then zeros and never
    called), or (0, n): from the dynamics kernel. ``banded``: ``bw[0] == SPARSE``, given apart so
    that a caller can pass it as a literal (``_jit_modes.entry``: the sparse and banded
    solves are then compiled only for the systems that use them; decision 0044).
    """
    N = times.size
    n = Q.shape[1]
    m = n
    npar = p.size
    nnz = jr.size
    nin = 1 + 2 * n + npar
    nin_d = 1 + 2 * n + m + npar + n
    newton = ptrs[2, 0] != 0
    x = np.zeros(nin + max(ptrs[0, 4], 0))
    xd = np.zeros(nin_d + max(ptrs[1, 4], ptrs[2, 4], 0))  # lambda = 0 unless the loads read it
    for j in range(npar):
        x[1 + 2 * n + j] = p[j]
        xd[1 + 2 * n + m + j] = p[j]
    out_pos = np.empty(m + nnz)
    out_dyn = np.empty(kM + 2 * n)
    out_d = np.empty(max(dr.size, 1))
    kbw = kband[0]
    if banded and newton and kbw[0] == -1:
        return 0                     # (not taken: _jit_multipliers sends these to Python)
    slot, cr, cc, pos, row_perm, perm, si0 = band
    kpos, krow, kcol, krow_perm, kperm, sJT, sD, khead = kband[1]
    Kd = np.empty(krow.size)
    ksparse = kbw[0] == SPARSE       # (the Newton matrix by the sparse LU: trees)
    ksize, kisize = big_sizes(kbw, n)
    AB2 = np.zeros(ksize if ksparse else (n * kbw[2] if banded and newton else 1))
    SI2 = np.zeros(kisize, dtype=np.int64)
    for i in range(khead.size):
        SI2[i] = khead[i]
    mag = np.empty(n)
    nd = 1 if banded else n          # the dense matrices are not used when banded
    J, B, ipiv, nz, ibuf, cbuf, dbuf, work, iwork, r = _factor_work(m, n, nd)
    # Newton's matrix Phi_q^T - dQ/dlambda: its own factors and structure (both terms')
    _, K, ipiv2, nz2, _, _, _, _, _, _ = _factor_work(m, n, nd if newton else 1)
    if banded:
        S, W, seen = _no_structure()
        S2, W2, seen2 = S, W, seen
        unique = False
    else:
        S, W, seen = _structure(jc, jr, n)           # the structure of Phi_q^T
        # (of Phi_q^T - dQ/dlambda)
        S2, W2, seen2 = _structure(np.concatenate((jc, dr)), np.concatenate((jr, dc)), n)
        unique = _unique(jr, jc, m, n)
    AB, SI, data, tmp = _big_work(bw, n, si0, cr.size)
    bi = np.zeros(8, dtype=np.int32)
    ones = np.ones(n)
    Mq = np.empty(n)
    rhs = np.empty(n)
    R = np.empty(n)
    dl = np.empty(m)
    lam = np.empty(m)
    for i in range(m):
        lam[i] = guess[i]
    for k in range(N):
        t = times[k]
        x[0] = t
        xd[0] = t
        for j in range(n):
            x[1 + j] = Q[k, j]
            xd[1 + j] = Q[k, j]
        _eval_row(ptrs, 0, x, nin, out_pos)
        if banded:
            _band_values(out_pos, m, slot, data)
            _band_rows(data, cr, cc, cols, r)
            if within(banded, 1, 1, _sparse_factor, data, cr, cc, pos, r, cols, AB, bw,
                      SI) < 0:
                return k
        else:
            if newton or not unique:                  # (Newton's residual reads J)
                _assemble(out_pos, m, jr, jc, J)
            if unique:
                # B = R^-1 J D (C order) = B^T stored transposed, from the nonzero values:
                # the entries and row scales of the dense loops below (decision 0078)
                _rows_nz(out_pos[m:], jr, jc, cols, r)
                anorm = _fill_nz_t(out_pos[m:], jr, jc, r, cols, B, S)
            else:
                _rows(J, cols, r)
                for i in range(m):
                    inv = 1.0 / r[i]
                    for j in range(n):
                        B[i, j] = (J[i, j] * cols[j]) * inv
                anorm = _norm1_nz(B, n, S)
            # (guard RCOND_MIN: only "singular or not" is read, so the estimate is skipped
            # where its bound proves it regular, as in the sweep's Newton steps: the same
            # decision, decision 0078)
            if _factor_filled(lapack, B, anorm, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf,
                              work, iwork, RCOND_MIN) < 0:
                return k
        if mode != STATIC:
            for j in range(n):
                xd[1 + n + j] = QD[k, j]
        if mode == DYNAMIC:
            for j in range(n):
                xd[1 + 2 * n + m + npar + j] = QDD[k, j]
        if not newton:
            if Rpre.shape[0] > 0:
                for i in range(n):
                    rhs[i] = Rpre[k, i]
            elif not _loads(ptrs, xd, nin_d, out_dyn, mode, QDD, k, mr, mc, kM, n, Mq, rhs):
                return k
            if banded:
                within(banded, 1, 1, _sparse_solve_scaled, AB, bw, SI, row_perm, perm, r, cols,
                       rhs, lam, tmp, True)
            else:
                for j in range(n):
                    rhs[j] = cols[j] * rhs[j]
                _solve(lapack, B, ipiv, nz, ones, ones, rhs, dl, ibuf, cbuf)
                for i in range(m):
                    lam[i] = dl[i] / r[i]
        else:
            done = False
            for _ in range(maxit):
                for i in range(m):
                    xd[1 + 2 * n + i] = lam[i]
                if not _loads(ptrs, xd, nin_d, out_dyn, mode, QDD, k, mr, mc, kM, n, Mq, rhs):
                    return k
                err = 0.0
                size = 0.0
                if banded:
                    for i in range(n):
                        R[i] = 0.0
                        mag[i] = 0.0
                    for e in range(cr.size):       # R = Phi_q^T lambda from the CSC values
                        v = data[e] * lam[cr[e]]
                        R[cc[e]] += v
                        mag[cc[e]] += abs(v)
                for i in range(n):
                    if banded:
                        acc = R[i]
                        mi = mag[i]
                    else:
                        acc = 0.0
                        mi = 0.0
                        for j in range(m):
                            acc += J[j, i] * lam[j]
                            mi += abs(J[j, i] * lam[j])
                    R[i] = acc - rhs[i]
                    err = max(err, cols[i] * abs(R[i]))
                    size = max(size, cols[i] * (mi + abs(rhs[i])))
                if err <= tol * size:
                    done = True
                    break
                _eval_row(ptrs, 2, xd, nin_d, out_d)
                if banded:
                    # Phi_q^T - dQ/dlambda at its pattern's entries, unit-free as the Python
                    # path: (c_row K) / r_col
                    for e in range(Kd.size):
                        Kd[e] = 0.0
                    for e in range(cr.size):
                        Kd[sJT[e]] += data[e]
                    for e in range(dr.size):
                        Kd[sD[e]] -= out_d[e]
                    for e in range(Kd.size):
                        Kd[e] = (cols[krow[e]] * Kd[e]) / r[kcol[e]]
                    if ksparse:
                        if within(banded, 1, 1, _sparse_factor, Kd, krow, kcol, kpos, ones,
                                  ones, AB2, kbw, SI2) < 0:
                            return k
                    elif within(banded, 1, 1, _band_factor, blapack, Kd, krow, kcol, kpos,
                                ones, ones, AB2, kbw, ipiv2, bi) < 0:
                        return k
                    for j in range(n):
                        R[j] = cols[j] * R[j]
                    if ksparse:
                        within(banded, 1, 1, _sparse_solve_scaled, AB2, kbw, SI2, krow_perm,
                               kperm, ones, ones, R, dl, tmp, False)
                    else:
                        within(banded, 1, 1, _band_solve, blapack, AB2, kbw, ipiv2, krow_perm,
                               kperm, ones, ones, R, dl, tmp, bi, cbuf)
                    for i in range(m):
                        lam[i] = lam[i] - dl[i] / r[i]
                    continue
                for i in range(m):                   # K^T = Phi_q - (dQ/dlambda)^T
                    for j in range(n):
                        K[i, j] = J[i, j]
                for e in range(dr.size):
                    K[dc[e], dr[e]] -= out_d[e]
                for i in range(m):                   # unit-free: D K R^-1 (as the linear solve)
                    for j in range(n):
                        K[i, j] = (cols[j] * K[i, j]) / r[i]
                if _factor_filled(lapack, K, _norm1_nz(K, n, S2), ipiv2, nz2, S2, W2, seen2, ibuf, cbuf,
                                  dbuf, work, iwork, RCOND_MIN) < 0:
                    return k
                for j in range(n):
                    R[j] = cols[j] * R[j]
                _solve(lapack, K, ipiv2, nz2, ones, ones, R, dl, ibuf, cbuf)
                for i in range(m):
                    lam[i] = lam[i] - dl[i] / r[i]
            if not done:
                return k
        for i in range(m):
            if not np.isfinite(lam[i]):
                return k
            LAM[k, i] = lam[i]
    return N
