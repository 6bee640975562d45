r"""Numba code of the compiled free-motion stepper (imported only when it runs: see
``_jit_free.py``).

Each function mirrors one piece of the Python path, in the same order of operations where
the Python path fixes one:

* ``_accel``     ``solvers._free.free_acceleration`` (linear case) with the cheap test of
                 ``solvers._rank.zone_guard``: the augmented system ``[[M, J^T], [J, 0]]``
                 from the compiled kernel, solved by LAPACK ``dgesv`` (SciPy's own) or,
                 up to ``SMALL`` unknowns, by the same elimination written out here
* ``_min_norm``  ``solvers._free._min_norm``: :math:`D J^T (\hat J J^T)^{-1} b`, :math:`\hat J = R^{-1} J D`
* ``_project``   ``solvers._free.project`` (positions, then velocities)
* ``runge_kutta`` ``scipy.integrate._ivp.rk.rk_step`` for DOP853 and RK45, with their
                 error norms (``DOP853._estimate_error_norm``, ``RungeKutta``'s RMS norm of
                 :math:`K^T E h / \mathit{scale}`), step-size control (``_step_impl``) and dense output
                 (``Dop853DenseOutput``; ``RkDenseOutput`` with :math:`Q = K^T P`)
* ``_path_velocity`` ``analyses._path.PathSystem.velocities`` (a nonholonomic path's
                 derivative, velocity constraints linear in the velocities; decision 0027),
                 and ``path_accelerations`` its ``accelerations`` at the outputs; above
                 ``SMALL_LU`` coordinates ``_path_velocity_sparse`` (its ``_velocities_sparse``:
                 the fixed pattern and the compiled sparse LU)
* ``_newton_accel`` ``solvers._free.free_acceleration`` when the loads depend on the
                 multipliers or accelerations (its Newton on :math:`(\ddot q, \lambda)`)
* ``_accel_rows`` ``analyses._nonholonomic.nonholonomic_acceleration`` (velocity
                 constraints :math:`A \dot q + b = 0`, decision 0062): the augmented system
                 bordered by ``A``, :math:`-\rho` on the right; ``_project_rows`` its
                 ``project_velocities`` (the minimum-norm change onto
                 :math:`[\Phi_q; A] \dot q = [-\Phi_t; -b]`)
* ``gen_points`` the recursive Gen dynamics over given states: the multiplier solves'
                 right-hand sides and the robot entry points' inverse and forward dynamics
* ``_accel_gen`` ``compile._generalized.RecursiveDynamics`` (generalized coordinates,
                 decision 0018): the joint kernels, then the articulated-body recursion
                 (a tree of Gen joints) or the composite-body mass matrix in the augmented
                 system, solved as ``_accel`` does (``_solve_augmented``)

Anything the Python path would treat specially (a singular or non-finite augmented matrix,
multipliers large against the constraint forces: a singular instant near; a projection in
the zone of a singular Jacobian; a step size below SciPy's minimum) ends the compiled run
with status ``HANDOVER`` at the last accepted step, before the step that needed the care.
The Python integrator then continues from that state with its whole logic.

The matrices handed to LAPACK are stored transposed in C order, which is column-major
(Fortran) order of the matrix itself.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ._jit_adams import CORRECTED as ADAMS_CORRECTED
from ._jit_adams import OK as ADAMS_OK
from ._jit_adams import REJECTED as ADAMS_REJECTED
from ._jit_adams import commit as adams_commit
from ._jit_adams import correct as adams_correct
from ._jit_adams import predict as adams_predict
from ._jit_borrow import borrow
from ._jit_cache import check as _check_cache
from ._jit_calls import _ccall, _eval
from ._jit_lapack import GUARD_MARGIN, gecon1, getrf, getrs, inv_norm_bound, leaf, pattern_size
from ._jit_linalg import _assemble, _norm1, _rows, _rows_nz
from ._jit_linalg import _band_factor as _gb_factor
from ._jit_linalg import _band_solve as _gb_solve
from ._jit_linalg import _sparse_factor as _sp_factor
from ._jit_linalg import _sparse_solve_scaled as _sp_solve_scaled
from ._jit_modes import within
from ._jit_runtime import SMALL as SMALL_LU
from ._jit_runtime import SPARSE as SPARSE_BW
from ._jit_sparse import IWORK, lu_factor, lu_pivot_ratio, lu_solve
from ._jit_tree import articulated as _articulated
from ._jit_tree import assemble as _gen_assemble
from ._jit_tree import forward as _gen_forward
from ._tolerances import PIVOT_TOL, RCOND_MIN, ZONE

_check_cache()   # stale cached loops go before anything here compiles (see _jit_cache)

FINISHED, CHUNK, HANDOVER = 0, 1, 2

#: how ``_rhs`` evaluates the derivative (the loops' ``blocks`` argument): the augmented
#: system from one kernel, solved whole; the block path; generalized coordinates with the
#: recursive dynamics (decision 0018): a tree of Gen joints by the articulated-body recursion,
#: or the composite-body mass matrix in the augmented system
AUGMENTED, BLOCK, GEN_TREE, GEN_AUGMENTED = 0, 1, 2, 3
#: a nonholonomic path (``analyses._path.PathSystem``, Mech's ``SolvePath``): the state is
#: ``q`` alone and its derivative the velocities of the holonomic and velocity constraints
#: (``_path_velocity``); the projection is onto the positions only
PATH = 4
#: loads that depend on the multipliers (friction) or on the accelerations (added masses):
#: ``solvers._free.free_acceleration``'s Newton on :math:`(\ddot q, \lambda)` (``_newton_accel``)
NEWTON = 5
#: a large system whose augmented matrix has a wide band (a tree of many branches): the
#: Python path's ``FixedPattern`` of it, factorised by the compiled sparse LU it calls
#: (``_accel_sparse``), the projection through the Python path's pattern of ``[[I, J^T],
#: [J^, 0]]`` (``_min_norm_sparse``)
SPARSE = 6

#: free motion with velocity constraints :math:`A(q, t) \dot q + b(q, t) = 0` (decisions 0053, 0062):
#: the dense augmented system bordered by ``A`` (``_accel_rows``), the velocity projection
#: onto :math:`[\Phi_q; A] \dot q = [-\Phi_t; -b]` (``_project_rows``)
ROLLING = 7

#: augmented systems up to this size are solved by the loop's own elimination (``_lu_solve``);
#: larger ones by LAPACK ``dgesv``, whose call overhead no longer matters there
SMALL = 24

# SciPy's step-size control constants (scipy.integrate._ivp.rk)
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
#: the methods of :func:`runge_kutta`
DOP853, RK45 = 0, 1


@leaf
def _lu_solve(AT, b, N, piv):
    """``A x = b`` in place (``b`` becomes ``x``; ``AT`` holds ``A`` transposed and is
    overwritten) by ``_jit_lapack``'s ``dgetrf``/``dgetrs``, without LAPACK's call overhead.
    False at an exactly zero pivot (``dgesv``'s ``info > 0``)."""
    if getrf(AT, N, piv) > 0:
        return False
    getrs(AT, N, piv, b)
    return True


@nb.njit(cache=True, inline='always')
def _evalx(ptr, x, nin, out, ex, ph):
    """``_eval`` of a kernel whose repeated outputs are computed once (a CSE kernel:
    ``_backends._SymengineCompiled.c_entry``): the distinct values into ``ph``, then ``out[i]
    = ph[ex[i]]``; ``ex`` empty: straight into ``out``."""
    if ex.size == 0:
        _eval(ptr, x, nin, out)
        return
    _eval(ptr, x, nin, ph)
    for i in range(ex.size):
        out[i] = ph[ex[i]]


@leaf
def _accel(kp, lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc, rows0, columns,
           robust, ipiv, ibuf, rhs, b, qdd, lam, force, ex, ph):
    """Free acceleration at ``x = [t, q, qd, 0, p, 0]``: ``qdd`` (n,), ``lam`` (m,);
    False where the Python path would need its special handling."""
    _evalx(kp, x, nin, out, ex, ph)
    KTf[:] = 0.0                     # KT's flat view (made once: no reshape per call)
    for k in range(flat_t.size):
        KTf[flat_t[k]] = out[mp[k]]
    return _solve_augmented(lapack, KT, out, kk, out, kk - jr.size, n, m, jr, jc, rows0,
                            columns, robust, ipiv, ibuf, rhs, b, qdd, lam, force)


@nb.njit(cache=True, inline='always')
def _finite(KT, N):
    r"""Whether every entry of ``KT`` (N, N) is finite. First the sum, one reduction (one
    call in the interpreted tier instead of :math:`N^2` scalar tests: decision 0077): the
    sum of finite numbers is finite unless it overflows, and an infinite or NaN entry makes
    it infinite or NaN; only when it is not finite (a non-finite entry, or entries near
    :math:`10^{308}`) does the entry-by-entry test decide.

    .. math:: \mathrm{finite}(K) = \mathrm{isfinite}\Big(\sum_{ij} K_{ij}\Big) \lor
              \bigwedge_{ij} \mathrm{isfinite}(K_{ij})"""
    if np.isfinite(np.sum(KT)):
        return True
    for i in range(N):
        for j in range(N):
            if not np.isfinite(KT[i, j]):
                return False
    return True


@nb.njit(cache=True, inline='always')
def _all_finite(x, count):
    r"""Whether ``x[:count]`` is finite: the sum first, one reduction (as :func:`_finite`:
    one call in the interpreted tier instead of ``count`` scalar tests of about 1 µs each,
    decision 0087), entry by entry only when the sum is not finite."""
    if np.isfinite(np.sum(x[:count])):
        return True
    for i in range(count):
        if not np.isfinite(x[i]):
            return False
    return True


@leaf
def _dgesv(lapack, KT, b, N, ipiv, ibuf):
    """LAPACK ``dgesv`` (``lapack[3]``) on ``K x = b``, ``KT`` (N, N) holding ``K``
    transposed (C order: LAPACK's column order of ``K``), ``x`` over ``b``; whether it
    succeeded (no exactly zero pivot). The routine the Python path calls."""
    ibuf[0] = N          # n, nrhs, lda = ldb, info
    ibuf[1] = 1
    ibuf[2] = N
    ibuf[3] = 0
    _ccall(lapack[3], (ibuf[0:1], ibuf[1:2], KT, ibuf[2:3], ipiv, b, ibuf[2:3], ibuf[3:4]))
    return ibuf[3] == 0


@nb.njit(cache=True, inline='always')
def _solve_augmented(lapack, KT, rv, r0, jv, j0, n, m, jr, jc, rows0, columns, robust, ipiv,
                     ibuf, rhs, b, qdd, lam, force):
    """Solve the augmented system (``KT`` its matrix transposed, ``rv[r0:r0 + n + m]`` its
    right-hand side, ``jv[j0:]`` the Jacobian's values) with the checks of the Python path:
    ``qdd`` (n,), ``lam`` (m,); False: hand over."""
    N = n + m
    if not _finite(KT, N):
        return False
    big_rhs = 0.0
    for i in range(N):
        rhs[i] = rv[r0 + i]
        b[i] = rhs[i]
        v = abs(rhs[i])
        if v > big_rhs:
            big_rhs = v
    if N <= SMALL:
        if not _lu_solve(KT, b, N, ipiv):
            return False
    elif not _dgesv(lapack, KT, b, N, ipiv, ibuf):
        return False
    return _accepted(b, big_rhs, n, m, qdd, lam, robust, rows0, jv, j0, jr, jc, columns, force)


@nb.njit(cache=True, inline='always')
def _bounded(x, count, big_rhs):
    r"""Whether the first ``count`` entries of a solution are finite and not far beyond its
    right-hand side, as the Python path accepts it: :math:`\max_i |x_i| < 10^{15} (1 +
    \max |\mathit{rhs}|)` (NaN refused)."""
    big = 0.0
    for i in range(count):
        v = abs(x[i])
        if not v <= big:          # NaN too
            big = v
    return big < 1e15 * (1.0 + big_rhs)


@nb.njit(cache=True, inline='always')
def _accepted(x, big_rhs, n, m, qdd, lam, robust, rows0, jv, j0, jr, jc, columns, force):
    """The augmented system's solution ``x = [qdd; lam]`` as the Python path accepts it: not
    far beyond its right-hand side (``|x| < 1e15 (1 + max |rhs|)``, NaN refused), split into
    ``qdd`` and ``lam``, and, ``robust``, passing :func:`_zone_ok`. False: hand over."""
    if not _bounded(x, n + m, big_rhs):
        return False
    for j in range(n):
        qdd[j] = x[j]
    for i in range(m):
        lam[i] = x[n + i]
    return not robust or _zone_ok(rows0, lam, jv, j0, jr, jc, columns, force)


@leaf
def _accel_rows(kp, lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, ipiv, ibuf, rhs, b,
                qdd, lam, ex, ph, ri, rw):
    r"""Free acceleration with velocity constraints (``ROLLING``; the Python path's
    ``analyses._nonholonomic.nonholonomic_acceleration``) at ``x = [t, q, qd, 0, p, 0]``:

    .. math::

        \begin{bmatrix} M & \Phi_q^T & A^T \\ \Phi_q & 0 & 0 \\ A & 0 & 0 \end{bmatrix}
        \begin{bmatrix} \ddot q \\ \lambda \\ \mu \end{bmatrix} =
        \begin{bmatrix} Q + Q_v \\ \gamma \\ -\rho \end{bmatrix}

    the holonomic part from the free kernel (``kp``: its values scattered by ``flat_t`` into
    the transposed storage of the bordered matrix, ``KT`` (n + m + k)^2), ``A`` and
    :math:`\rho` from the rows' kernel (``ri = (info, expand)``, ``info = [kernel row (5), k,
    parameters]``, evaluated at ``[t, q, qd, p]``), solved as the Python path solves it
    (LAPACK ``dgesv``; the matrix and the answer checked as ``solvers._free._solve_fast`` does:
    finite, no zero pivot, ``|x| < 1e15 (1 + max |rhs|)``). ``qdd`` (n,), ``lam`` (m,),
    ``mu`` (``rw[13]``, k); False: hand over (the Python path decides)."""
    info, exr = ri
    xr, outr, phr, mu = rw[0], rw[1], rw[2], rw[13]
    k = info[5]
    npar = info[6]
    N = n + m
    Nk = N + k
    _evalx(kp, x, nin, out, ex, ph)
    KTf[:] = 0.0
    for i in range(flat_t.size):
        KTf[flat_t[i]] = out[mp[i]]
    # the rows' kernel takes [t, q, qd, p] (x holds [t, q, qd, lambda, p, qdd])
    for j in range(1 + 2 * n):
        xr[j] = x[j]
    for j in range(npar):
        xr[1 + 2 * n + j] = x[1 + 2 * n + m + j]
    _evalx(info, xr, 1 + 2 * n + npar, outr, exr, phr)
    for i in range(k):
        for j in range(n):
            a = outr[i * n + j]
            KT[j, N + i] = a            # K[N + i, j] = A[i, j]  (KT holds K transposed)
            KT[N + i, j] = a            # K[j, N + i] = A[i, j]
    if not _finite(KT, Nk):
        return False
    big_rhs = 0.0
    for i in range(Nk):
        rhs[i] = out[kk + i] if i < N else -outr[k * n + k + i - N]
        b[i] = rhs[i]
        v = abs(rhs[i])
        if v > big_rhs:
            big_rhs = v
    # LAPACK dgesv at every size, the routine the Python path calls: the same accelerations
    # bit for bit (the loop's own LU of small systems rounds differently, and a wobbling
    # coin amplified that to 1.4e-12 over 1200 steps)
    if not _dgesv(lapack, KT, b, Nk, ipiv, ibuf):
        return False
    if not _bounded(b, Nk, big_rhs):
        return False
    for j in range(n):
        qdd[j] = b[j]
    for i in range(m):
        lam[i] = b[n + i]
    for i in range(k):
        mu[i] = b[N + i]
    return True


@leaf
def _velocity_residual(G, y, n, lo, hi, v, off, r, Fs):
    r"""Rows ``lo`` to ``hi`` of the velocity projection's scaled residual (the dense
    ``G``, row scales ``r``) at the velocities ``y[n:]``, the constraints' right sides
    :math:`g_i = -v_{\mathrm{off} + i - \mathrm{lo}}` (``-Phi_t`` from the velocity kernel,
    ``-b`` from the velocity constraints' rows):

    .. math::  F_i = \Big(\sum_j G_{ij} \dot q_j - g_i\Big) / r_i"""
    for i in range(lo, hi):
        s = 0.0
        for j in range(n):
            s += G[i, j] * y[n + j]
        Fs[i] = (s - (-v[off + i - lo])) / r[i]


@leaf
def _velocity_corrected(y, dq, n):
    """The velocities ``y[n:]`` less the minimum-norm correction ``dq``; whether ``y`` is
    then finite (else hand over)."""
    for j in range(n):
        y[n + j] = y[n + j] - dq[j]
    return _all_finite(y, 2 * n)


@leaf
def _project_rows(pv, lapack, xk, nin_k, out_vel, jr, jc, columns, n, m, y, ibuf, cbuf, dbuf,
                  ex_vel, ph_vel, ri, rw):
    r"""The velocity projection with velocity constraints (``ROLLING``; the Python path's
    ``analyses._nonholonomic.project_velocities``): the smallest scaled change of
    :math:`\dot q` (``y[n:]``) onto

    .. math::  G \dot q = g, \qquad G = \begin{bmatrix} \Phi_q \\ A \end{bmatrix}, \quad
               g = \begin{bmatrix} -\Phi_t \\ -b \end{bmatrix}

    at the positions ``xk = [t, q, 0, p]`` (already projected), by ``_min_norm`` on ``G``
    (each row divided by its scale, as ``Scaling.rows``). False: hand over."""
    info, exr = ri
    xr, outr, phr, G, Gs, AG, rG, FsG, dqG, ybufG, workG, ipivG, iworkG = rw[:13]
    k = info[5]
    npar = info[6]
    nnz = jr.size
    G[:, :] = 0.0
    if m > 0:
        _evalx(pv, xk, nin_k, out_vel, ex_vel, ph_vel)
        for i in range(nnz):
            G[jr[i], jc[i]] += out_vel[i]
    for j in range(1 + 2 * n + npar):
        xr[j] = xk[j]
    _evalx(info, xr, 1 + 2 * n + npar, outr, exr, phr)
    for i in range(k):
        for j in range(n):
            G[m + i, j] = outr[i * n + j]
    _rows(G, columns, rG)
    _velocity_residual(G, y, n, 0, m, out_vel, nnz, rG, FsG)          # -Phi_t
    _velocity_residual(G, y, n, m, m + k, outr, k * n, rG, FsG)       # -b
    if not _min_norm(lapack, G, rG, columns, FsG, dqG, Gs, AG, ipivG, ibuf, cbuf, dbuf, workG,
                     iworkG, ybufG, False):
        return False
    return _velocity_corrected(y, dqG, n)


@leaf
def _zone_ok(rows0, lam, jv, j0, jr, jc, columns, force):
    """zone_guard's cheap test: multipliers large against the constraint forces they make
    (``J^T lam``, from the Jacobian values ``jv[j0:]`` of the kernel) mean a singular instant
    near. False: hand over."""
    m = lam.size
    if m == 0:
        return True
    bl = 0.0
    for i in range(m):
        v = abs(rows0[i] * lam[i])
        if v > bl:
            bl = v
    if bl == 0.0:
        return True
    force[:] = 0.0
    for k in range(jr.size):
        force[jc[k]] += jv[j0 + k] * lam[jr[k]]
    fmax = 0.0
    for j in range(columns.size):
        v = abs(columns[j] * force[j])
        if v > fmax:
            fmax = v
    return bl < fmax / ZONE and np.isfinite(bl)


@leaf
def _rhs(kp, lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc, rows0, columns, robust,
         ipiv, ibuf, rhs, b, qdd, lam, force, blocks, blk_i, blk_w, t, y, f):
    """``f = (qd, qdd)`` at ``(t, y)``; False: hand over. ``blocks``: how (``AUGMENTED``,
    ``BLOCK``, ``GEN_TREE``, ``GEN_AUGMENTED``); ``blk_i = (block structure, Gen tree,
    expansion maps of the three kernels)``, ``blk_w`` their work arrays (``_block_work``).
    ``PATH``: ``f = qd`` (n,) at ``(t, q = y)``, also left in ``qdd`` (the next evaluation's
    guess, as the Python path's)."""
    if blocks == ROLLING:
        x[0] = t
        for j in range(2 * n):
            x[1 + j] = y[j]
        if not within(blocks, ROLLING, ROLLING, _accel_rows, kp, lapack, x, nin, out, KT, KTf,
                      flat_t, mp, kk, n, m, ipiv, ibuf, rhs, b, qdd, lam, blk_i[2][0],
                      blk_w[2][0], blk_i[3], blk_w[3]):
            return False
        for j in range(n):
            f[j] = y[n + j]
            f[n + j] = qdd[j]
        return True
    if blocks >= PATH:
        # (one call site for the three kinds: a smaller body here kept the loops as fast as
        # before they existed)
        return within(blocks, PATH, SPARSE, _other_rhs, blocks, kp, lapack, ibuf, x, nin,
                      out, KT, n, m, jr, jc, columns, ipiv, rhs, b,
                      qdd, lam, blk_i, blk_w, t, y, f, rows0, robust, force)
    x[0] = t
    for j in range(2 * n):
        x[1 + j] = y[j]
    ex, ph = blk_i[2], blk_w[2]
    if blocks == BLOCK:
        Mst, Jst, Wst, Sb, u, Pst, Minv, Li = blk_w[0]
        if not within(blocks, BLOCK, BLOCK, _accel_blocks, kp, x, nin, out, kk, kk - jr.size,
                      n, m, jr, jc, rows0, columns, robust, blk_i[0], Mst, Jst, Wst, Sb, u,
                      Minv, Li, qdd, lam, force, ex[0], ph[0]):
            return False
    elif blocks >= GEN_TREE:
        if not within(blocks, GEN_TREE, GEN_AUGMENTED, _accel_gen, kp, lapack, x, nin, n, m,
                      jr, jc, rows0, columns, robust, ipiv, ibuf, rhs, b, qdd, lam, force,
                      blk_i[1], blk_w[1], ex[0], ph[0], blocks == GEN_TREE, y):
            return False
    elif not within(blocks, AUGMENTED, AUGMENTED, _accel, kp, lapack, x, nin, out, KT, KTf,
                    flat_t, mp, kk, n, m, jr, jc, rows0, columns, robust, ipiv, ibuf, rhs, b,
                    qdd, lam, force, ex[0], ph[0]):
        return False
    for j in range(n):
        f[j] = y[n + j]
        f[n + j] = qdd[j]
    return True


@leaf
def _other_rhs(blocks, kp, lapack, ibuf, x, nin, out, KT, n, m, jr, jc, columns, ipiv, rhs, b,
               qdd, lam, blk_i, blk_w, t, y, f, rows0, robust, force):
    """``_rhs`` of the kinds ``PATH`` (``f = qd``), ``SPARSE`` and ``NEWTON`` (``f = (qd,
    qdd)``; above ``SMALL_LU`` unknowns through the Newton matrix's banded pattern,
    ``_newton_accel_band``)."""
    if blocks == PATH and blk_i[0][7].size > 1:
        return within(blocks, PATH, PATH, _path_velocity_sparse, kp, x, out, n, m, jr, jc,
                      columns, qdd, blk_i[0], blk_w[0], blk_i[2][0], blk_w[2][0], blk_i[2][2],
                      blk_w[2][2], t, y, f)
    if blocks == PATH:
        return within(blocks, PATH, PATH, _path_velocity, kp, x, out, KT, n, m, jr, jc,
                      columns, ipiv, rhs, b, qdd, blk_i[0][0], blk_w[0], blk_i[2][0],
                      blk_w[2][0], blk_i[2][2], blk_w[2][2], t, y, f)
    if blocks == SPARSE:
        return within(blocks, SPARSE, SPARSE, _accel_sparse, kp, x, nin, out, n, m, jr, jc,
                      rows0, columns, robust, qdd, lam, force, blk_i[0], blk_w[0], blk_i[2][0],
                      blk_w[2][0], t, y, f)
    bi = blk_i[0]
    if bi[7].size > 1:
        return within(blocks, NEWTON, NEWTON, _newton_accel_band, kp, lapack, ibuf, x, nin,
                      out, n, m, jr, jc, ipiv, qdd, lam, bi[0], bi[1], bi[2], bi[3], bi[4],
                      bi[5], bi[6], bi[7], blk_w[0], blk_i[2][0], blk_w[2][0], t, y, f)
    return within(blocks, NEWTON, NEWTON, _newton_accel, kp, x, nin, out, KT, n, m, jr, jc,
                  ipiv, rhs, b, qdd, lam, bi[0], bi[1], bi[2], bi[3], bi[4], bi[5], bi[6],
                  blk_w[0], blk_i[2][0], blk_w[2][0], t, y, f)


@leaf
def _factor_checked(AT, n, ipiv, w1, w2):
    """LU of the matrix in ``AT`` (transposed storage) in place, as ``_linalg.factor``
    accepts it: False at an exactly zero pivot, a zero norm or a reciprocal condition
    estimate below ``RCOND_MIN``. ``w1``, ``w2`` (n,): work."""
    anorm = _norm1(AT, n)
    if getrf(AT, n, ipiv) > 0 or anorm == 0:
        return False
    return gecon1(AT, n, anorm, w1, w2) >= RCOND_MIN


@leaf
def _newton_args(x, xk, t, y, n, m, npar, lam, qdd, chain):
    """The arguments of the Newton's kernels at ``(t, y = (q, qd))`` and its start (both
    Newton loops): ``x = [t, q, qd, lambda, p, qdd = 0]`` (the parameters left) with
    ``lambda`` ones, or ``chain`` (the loads depend on the multipliers) the previous
    evaluation's ``lam``; ``qdd = 0``; ``xk = [t, q, 0, p]`` (the constraint kernels; the
    parameters from ``x``)."""
    x[0] = t
    for j in range(2 * n):
        x[1 + j] = y[j]
    xk[0] = t
    for j in range(n):
        xk[1 + j] = y[j]
        xk[1 + n + j] = 0.0
    for j in range(npar):
        xk[1 + 2 * n + j] = x[1 + 2 * n + m + j]
    for i in range(m):
        if chain == 0:
            lam[i] = 1.0
        x[1 + 2 * n + i] = lam[i]
    for j in range(n):
        qdd[j] = 0.0
        x[1 + 2 * n + m + npar + j] = 0.0


@leaf
def _newton_check(res, tmp, mag, out, kM, n, m, g, tolv, qdd, it, y, f):
    """The residuals of Newton iteration ``it`` finished and judged (``free_acceleration``'s
    unit-free test; both Newton loops). On entry ``res[:n]`` holds ``M qdd``, ``tmp[:n]``
    ``Phi_q^T lambda``, ``mag`` the sums of their terms' sizes, ``res[n:]`` ``Phi_q qdd``,
    ``tolv = [tol, c (n), rho (m)]``. Returns -1 (hand over) when a residual is not finite;
    1 when converged (after at least one step, each residual within ``tol`` of the size of
    its terms), with ``f = (qd, qdd)``; else 0."""
    e1 = 0.0
    e2 = 0.0
    size1 = 0.0
    size2 = 0.0
    for i in range(n):
        res[i] = ((res[i] + tmp[i]) - out[kM + i]) - out[kM + n + i]
        c = tolv[1 + i]
        e1 = max(e1, c * abs(res[i]))
        size1 = max(size1, c * (mag[i] + abs(out[kM + i]) + abs(out[kM + n + i])))
        size2 = max(size2, abs(qdd[i]) / c)
    for i in range(m):
        rho = tolv[1 + n + i]
        res[n + i] = res[n + i] - g[i]
        e2 = max(e2, abs(res[n + i]) / rho)
        size2 = max(size2, abs(g[i]) / rho)
    err = 0.0
    for i in range(n + m):
        v = abs(res[i])
        if not v <= err:             # NaN too
            err = v
    if not np.isfinite(err):
        return -1
    if it > 1 and e1 <= tolv[0] * size1 and e2 <= tolv[0] * size2:
        for j in range(n):
            f[j] = y[n + j]
            f[n + j] = qdd[j]
        return 1
    return 0


@leaf
def _load_derivatives(info, x, nin, od, oa, nD, nA):
    """The loads' derivatives of a Newton step (both Newton loops) at ``x``: ``dQ/dlambda``'s
    values (``nD``) in ``od`` and ``dQ/dqdd``'s (``nA``) in ``oa``, each kernel only where
    it has entries (``info``'s rows of them: see :func:`_newton_accel`)."""
    if nD > 0:
        _eval(info[16:21], x, nin, od)
    if nA > 0:
        _eval(info[21:26], x, nin, oa)


@leaf
def _newton_accel(kp, x, nin, out, KT, n, m, jr, jc, ipiv, w1, w2, qdd, lam, info, Mr, Mc, Dr,
                  Dc, Ar, Ac, nw, ex, ph, t, y, f):
    """Free acceleration when the loads depend on the multipliers or accelerations:
    ``solvers._free.free_acceleration``'s Newton, operation for operation. ``kp`` the
    dynamics kernel ``[t, q, qd, lambda, p, qdd] -> [M values (kM), Q, Qv]`` (its row;
    ``ex``, ``ph`` its output map and buffer, ``_evalx``); ``info = [kM, chain,
    max_iterations, nD, nA, npar, the rows (5 each) of the position, gamma, dQ/dlambda and
    dQ/dqdd kernels]``; ``Mr, Mc``, ``Dr, Dc``, ``Ar, Ac`` the nonzero positions of ``M``,
    ``dQ/dlambda``, ``dQ/dqdd``; ``nw = (x of the constraint kernels, their outputs,
    gamma, J (m, n), dQ/dlambda values, dQ/dqdd values, residual, [tol])``. From ``qdd = 0``
    and ``lambda`` = the previous evaluation's (``chain``: the loads depend on the
    multipliers) or ones::

        r = [M qdd + J^T lambda - Q - Qv;  J qdd - gamma]
        [[M - dQ/dqdd, J^T - dQ/dlambda], [J, 0]] dx = -r

    until, after at least one step, each residual is within ``tol`` of the size of its terms
    in the unit-free measure of ``free_acceleration`` (the column scales ``c`` in ``tolv[1:]``,
    ``tolv[0]`` the tolerance). ``f = (qd, qdd)``, and
    ``qdd``, ``lam`` the result; False (hand over: the Python path raises its diagnosis) at a singular matrix
    (reciprocal condition below ``RCOND_MIN``), a value not finite or no convergence."""
    xk, out_pos, g, J, od, oa, res, tolv = nw
    mag = res[n + m:]                    # (the sizes of the force residuals' terms)
    kM, chain, maxit, nD, nA, npar = info[0], info[1], info[2], info[3], info[4], info[5]
    N = n + m
    nin_k = 1 + 2 * n + npar
    _newton_args(x, xk, t, y, n, m, npar, lam, qdd, chain)
    if m > 0:
        _eval(info[6:11], xk, nin_k, out_pos)
        _assemble(out_pos, m, jr, jc, J)
        for j in range(n):
            xk[1 + n + j] = y[n + j]
        _eval(info[11:16], xk, nin_k, g)
    _evalx(kp, x, nin, out, ex, ph)
    for it in range(1, maxit + 1):
        # the residuals' sums and the sizes of their terms (w1: Phi_q^T lambda), then
        # free_acceleration's unit-free test (_newton_check)
        for i in range(n):
            res[i] = 0.0
            mag[i] = 0.0
        for e in range(kM):
            res[Mr[e]] += out[e] * qdd[Mc[e]]
            mag[Mr[e]] += abs(out[e] * qdd[Mc[e]])
        for i in range(n):
            acc = 0.0
            for j in range(m):
                acc += J[j, i] * lam[j]
                mag[i] += abs(J[j, i] * lam[j])
            w1[i] = acc
        for i in range(m):
            acc = 0.0
            rho = 0.0
            for j in range(n):
                acc += J[i, j] * qdd[j]
                rho = max(rho, abs(J[i, j]) * tolv[1 + j])
            if rho == 0.0:
                rho = 1.0
            tolv[1 + n + i] = rho            # (the Newton matrix's row scales below)
            res[n + i] = acc
        done = _newton_check(res, w1, mag, out, kM, n, m, g, tolv, qdd, it, y, f)
        if done != 0:
            return done > 0
        _load_derivatives(info, x, nin, od, oa, nD, nA)
        KT[:, :] = 0.0                   # K = [[M - A, J^T - D], [J, 0]], stored transposed
        for e in range(kM):
            KT[Mc[e], Mr[e]] += out[e]
        for e in range(nA):
            KT[Ac[e], Ar[e]] -= oa[e]
        for i in range(m):
            for j in range(n):
                KT[n + i, j] = J[i, j]
                KT[j, n + i] = J[i, j]
        for e in range(nD):
            KT[n + Dc[e], Dr[e]] -= od[e]
        # unit-free, as free_acceleration: K~ = diag(c/mu, 1/rho) K diag(c, mu/rho), mu the
        # size of C Meff C (KT[k, j] = Meff[j, k] in the first block)
        mu = 0.0
        for k in range(n):
            for j in range(n):
                mu = max(mu, abs(tolv[1 + j] * KT[k, j] * tolv[1 + k]))
        if mu == 0.0:
            mu = 1.0
        for j in range(N):               # column j of K: KT's row j
            sc = tolv[1 + j] if j < n else mu / tolv[1 + j]
            for i in range(N):
                KT[j, i] *= sc * (tolv[1 + i] / mu if i < n else 1.0 / tolv[1 + i])
        if not _factor_checked(KT, N, ipiv, w1, w2):
            return False
        for i in range(N):
            res[i] = -(res[i] * (tolv[1 + i] / mu if i < n else 1.0 / tolv[1 + i]))
        getrs(KT, N, ipiv, res)
        for j in range(N):
            res[j] *= tolv[1 + j] if j < n else mu / tolv[1 + j]
        for j in range(n):
            qdd[j] += res[j]
            x[1 + 2 * n + m + npar + j] = qdd[j]
        for i in range(m):
            lam[i] += res[n + i]
            x[1 + 2 * n + i] = lam[i]
        _evalx(kp, x, nin, out, ex, ph)
    return False


#: the header of ``_newton_accel_band``'s structure array: kl, ku, ld, the pattern's
#: entries, the Jacobian's distinct positions, the mass matrix's, dQ/dqdd's and
#: dQ/dlambda's entries, n; then the sparse LU's ``bw`` (``_jit_linalg.big_sizes``: ``SPARSE``,
#: the pattern's entries, capL, capU; zeros for a banded pattern) and the length of the
#: factors' float store (``ld (n + m)`` banded, ``big_sizes``' first size sparse)
BAND_HEAD = 14


@nb.njit(cache=True, inline='always')
def _nb_sparse(bnd, nj, N):
    """``(sparse, SI)`` of ``_newton_accel_band``'s structure ``bnd``: whether its pattern goes
    by the compiled sparse LU (a wide band: trees), and that LU's integer store (``_jit_linalg.
    _sparse_factor``'s ``SI``, after the diagonal's slots). (Inlined: it returns a view.)"""
    return bnd[9] == SPARSE_BW, bnd[_band_jmap(bnd, nj, N) + nj + 4 * bnd[4] + bnd[8]:]


@leaf
def _nb_factor(blapack, bnd, data, prow, pcol, pos, ones, AB, ipiv, bi, sparse, SI):
    """The Newton matrix's factorisation as the Python path's ``FixedPattern.factor`` makes
    it: LAPACK's ``dgbtrf`` for a banded pattern, else the compiled sparse LU (the same
    function); the pivot ratio or -1."""
    if sparse:
        return _sp_factor(data, prow, pcol, pos, ones, ones, AB, bnd[9:13], SI)
    return _gb_factor(blapack, data, prow, pcol, pos, ones, ones, AB, bnd[0:3], ipiv, bi)


@leaf
def _nb_solve(blapack, AB, bnd, ipiv, row_perm, perm, ones, b, out, tmp, bi, cbuf, sparse, SI):
    """Solve with :func:`_nb_factor`'s factors (``_BandFactor.solve``, ``_Permuted.solve``)."""
    if sparse:
        # (``tmp`` may be longer than the system: the sparse solve takes its size from it)
        _sp_solve_scaled(AB, bnd[9:13], SI, row_perm, perm, ones, ones, b, out,
                         tmp[:ones.size], False)
    else:
        _gb_solve(blapack, AB, bnd[0:3], ipiv, row_perm, perm, ones, ones, b, out, tmp, bi, cbuf)


@leaf
def _band_jmap(bnd, nj, N):
    """Where ``_newton_accel_band``'s structure array ``bnd`` holds the Jacobian's map: the
    offset ``o`` of ``uid`` (``nj``), followed by ``urow``, ``ucol``, ``sJ``, ``sJT`` (``U``
    each) and the diagonal's slots ``sdiag`` (``n``)."""
    return BAND_HEAD + 3 * bnd[3] + 2 * N + bnd[5] + bnd[6] + bnd[7]


@leaf
def _band_rows_of(vals, off, jr, columns, r, bnd, w):
    """The Jacobian's distinct values ``Jv`` (the first ``U`` entries of ``w``) from the
    kernel's values ``vals[off:]`` (duplicates summed, as ``_assemble``), and the row scales
    ``r_i = max_j |J_ij| c_j`` from them (``_rows``: the same maxima)."""
    m = r.size
    n = columns.size
    U = bnd[4]
    o = _band_jmap(bnd, jr.size, n + m)
    uid = bnd[o:o + jr.size]
    o += jr.size
    urow, ucol = bnd[o:o + U], bnd[o + U:o + 2 * U]
    Jv = w[0:U]
    for u in range(U):
        Jv[u] = 0.0
    for k in range(jr.size):
        Jv[uid[k]] += vals[off + k]
    _rows_nz(Jv, urow, ucol, columns, r)


@leaf
def _min_norm_band(lapack, bi, ipiv, r, columns, bvec, out, n, m, jr, bnd, w):
    r"""``_min_norm`` through the Newton matrix's banded pattern: the smallest ``z`` (``out =
    D z``) with ``J^ z = bvec``, :math:`\hat J = R^{-1} J D`, from the augmented system ``[[I, J^T],
    [J^, 0]] [z; -nu] = [0; bvec]`` (its entries are among the pattern's: the mass matrix's
    diagonal, ``Phi_q``, ``Phi_q^T``), factorised by ``dgbtrf``. The Jacobian's distinct
    values ``Jv`` are in ``w`` (``_band_rows_of``). False (hand over) at a pivot ratio below
    ``RCOND_MIN`` (``J`` without full rank)."""
    N = n + m
    P, U = bnd[3], bnd[4]
    o = BAND_HEAD
    pos, prow, pcol = bnd[o:o + P], bnd[o + P:o + 2 * P], bnd[o + 2 * P:o + 3 * P]
    o += 3 * P
    row_perm, perm = bnd[o:o + N], bnd[o + N:o + 2 * N]
    o = _band_jmap(bnd, jr.size, N) + jr.size
    urow, ucol, sJ, sJT = bnd[o:o + U], bnd[o + U:o + 2 * U], bnd[o + 2 * U:o + 3 * U], \
        bnd[o + 3 * U:o + 4 * U]
    sdiag = bnd[o + 4 * U:o + 4 * U + n]
    Jv, data, AB = w[0:U], w[U:U + P], w[U + P:U + P + bnd[13]]
    o2 = U + P + bnd[13]
    ones, tmp, sol, tmp2 = (w[o2:o2 + N], w[o2 + N:o2 + 2 * N], w[o2 + 2 * N:o2 + 3 * N],
                            w[o2 + 3 * N:o2 + 4 * N])
    for k in range(P):
        data[k] = 0.0
    for j in range(n):
        data[sdiag[j]] = 1.0
    for u in range(U):
        v = (Jv[u] * columns[ucol[u]]) / r[urow[u]]
        data[sJ[u]] += v
        data[sJT[u]] += v
    for i in range(N):
        ones[i] = 1.0
    sparse, SI = _nb_sparse(bnd, jr.size, N)
    if _nb_factor(lapack[4:6], bnd, data, prow, pcol, pos, ones, AB, ipiv, bi, sparse, SI) < 0:
        return False
    for j in range(n):
        tmp[j] = 0.0
    for i in range(m):
        tmp[n + i] = bvec[i]
    _nb_solve(lapack[4:6], AB, bnd, ipiv, row_perm, perm, ones, tmp, sol, tmp2, bi,
              bi[7:8].view(np.uint8), sparse, SI)
    for j in range(n):
        out[j] = columns[j] * sol[j]
    return True


@leaf
def _newton_accel_band(kp, lapack, bi, x, nin, out, n, m, jr, jc, ipiv, qdd, lam, info, Mr, Mc,
                       Dr, Dc, Ar, Ac, bnd, nw, ex, ph, t, y, f):
    r"""``_newton_accel`` for large systems: the same Newton on :math:`(\ddot q, \lambda)` and the same
    unit-free convergence test, with the Jacobian held by its distinct nonzeros and the
    Newton matrix by its fixed pattern (``_patterns.free_newton_pattern``), factorised as the
    Python path's ``FixedPattern.factor`` does: LAPACK's ``dgbtrf`` in the reverse
    Cuthill-McKee band (chains), or the compiled sparse LU in the minimum-degree ordering
    (trees of many branches, ``_nb_factor``): no dense ``(n + m)^2`` array, work linear in
    the number of bodies. ``bnd`` (int64): the head ``[kl, ku, ld, P, U, kM, nA, nD, n,
    sparse LU's bw (4), S]`` (``BAND_HEAD``), then the pattern's band (or sparse)
    positions, rows and columns (P each), ``row_perm`` and ``perm`` (n + m each), the
    pattern slots of the mass-matrix, ``dQ/dqdd`` and ``dQ/dlambda`` entries, the distinct
    Jacobian position of each Jacobian value (``jr.size``), the distinct positions' rows,
    columns, and slots in the ``Phi_q`` and ``Phi_q^T`` blocks (U each), the slots of the
    diagonal of the first block (n; ``_min_norm_band``), and for the sparse LU its integer
    store. ``nw[3]`` (1, U + P + S + 4 (n + m)) holds the Jacobian's values, the pattern's
    values, the factors' store (``S``: the band, or ``_jit_linalg.big_sizes``' float store)
    and four vectors. ``bi``: int32 work (8: LAPACK's integer arguments,
    the last one's bytes its character argument); ``lapack[4:6]``: ``dgbtrf``,
    ``dgbtrs``. False: hand over (as ``_newton_accel``)."""
    xk, out_pos, g, W, od, oa, res, tolv = nw
    mag = res[n + m:]
    kM, chain, maxit, nD, nA, npar = info[0], info[1], info[2], info[3], info[4], info[5]
    N = n + m
    nin_k = 1 + 2 * n + npar
    P, U = bnd[3], bnd[4]
    o = BAND_HEAD
    pos, prow, pcol = bnd[o:o + P], bnd[o + P:o + 2 * P], bnd[o + 2 * P:o + 3 * P]
    o += 3 * P
    row_perm, perm = bnd[o:o + N], bnd[o + N:o + 2 * N]
    o += 2 * N
    sM, sA, sD = bnd[o:o + kM], bnd[o + kM:o + kM + nA], bnd[o + kM + nA:o + kM + nA + nD]
    o = _band_jmap(bnd, jr.size, N)
    uid = bnd[o:o + jr.size]
    o += jr.size
    urow, ucol, sJ, sJT = bnd[o:o + U], bnd[o + U:o + 2 * U], bnd[o + 2 * U:o + 3 * U], \
        bnd[o + 3 * U:o + 4 * U]
    w = W[0]
    Jv, data, AB = w[0:U], w[U:U + P], w[U + P:U + P + bnd[13]]
    o2 = U + P + bnd[13]
    sparse, SI = _nb_sparse(bnd, jr.size, N)
    ones, tmp, sol = w[o2:o2 + N], w[o2 + N:o2 + 2 * N], w[o2 + 2 * N:o2 + 3 * N]
    blapack = lapack[4:6]
    cbuf = bi[7:8].view(np.uint8)        # (dgbtrs's character argument, in bi's last entry)
    _newton_args(x, xk, t, y, n, m, npar, lam, qdd, chain)
    for u in range(U):
        Jv[u] = 0.0
    if m > 0:
        _eval(info[6:11], xk, nin_k, out_pos)
        for k in range(jr.size):
            Jv[uid[k]] += out_pos[m + k]
        for j in range(n):
            xk[1 + n + j] = y[n + j]
        _eval(info[11:16], xk, nin_k, g)
    for i in range(N):
        ones[i] = 1.0
    # the rows' scales rho_i = max_j |Phi_ij| c_j (the constraint rows' test and scaling)
    for i in range(m):
        tolv[1 + n + i] = 0.0
    for u in range(U):
        v = abs(Jv[u]) * tolv[1 + ucol[u]]
        if v > tolv[1 + n + urow[u]]:
            tolv[1 + n + urow[u]] = v
    for i in range(m):
        if tolv[1 + n + i] == 0.0:
            tolv[1 + n + i] = 1.0
    _evalx(kp, x, nin, out, ex, ph)
    for it in range(1, maxit + 1):
        for i in range(N):
            res[i] = 0.0
        for i in range(n):
            mag[i] = 0.0
        for e in range(kM):
            res[Mr[e]] += out[e] * qdd[Mc[e]]
            mag[Mr[e]] += abs(out[e] * qdd[Mc[e]])
        for i in range(n):
            tmp[i] = 0.0
        for u in range(U):
            a = Jv[u] * lam[urow[u]]
            tmp[ucol[u]] += a
            mag[ucol[u]] += abs(a)
            res[n + urow[u]] += Jv[u] * qdd[ucol[u]]
        done = _newton_check(res, tmp, mag, out, kM, n, m, g, tolv, qdd, it, y, f)
        if done != 0:
            return done > 0
        _load_derivatives(info, x, nin, od, oa, nD, nA)
        # K = [[M - A, J^T - D], [J, 0]] at its pattern's entries
        for k in range(P):
            data[k] = 0.0
        for e in range(kM):
            data[sM[e]] += out[e]
        for e in range(nA):
            data[sA[e]] -= oa[e]
        for u in range(U):
            data[sJ[u]] += Jv[u]
            data[sJT[u]] += Jv[u]
        for e in range(nD):
            data[sD[e]] -= od[e]
        # unit-free as free_acceleration: rows diag(c/mu, 1/rho), columns diag(c, mu/rho)
        mu = 0.0
        for k in range(P):
            if prow[k] < n and pcol[k] < n:
                mu = max(mu, abs(tolv[1 + prow[k]] * data[k] * tolv[1 + pcol[k]]))
        if mu == 0.0:
            mu = 1.0
        for k in range(P):
            r_, c_ = prow[k], pcol[k]
            dr = tolv[1 + r_] / mu if r_ < n else 1.0 / tolv[1 + r_]
            dc = tolv[1 + c_] if c_ < n else mu / tolv[1 + c_]
            data[k] = (dr * data[k]) * dc
        if _nb_factor(blapack, bnd, data, prow, pcol, pos, ones, AB, ipiv, bi, sparse, SI) < 0:
            return False
        for i in range(N):
            tmp[i] = -((tolv[1 + i] / mu if i < n else 1.0 / tolv[1 + i]) * res[i])
        _nb_solve(blapack, AB, bnd, ipiv, row_perm, perm, ones, tmp, sol, res, bi, cbuf, sparse,
                  SI)
        for j in range(n):
            qdd[j] += tolv[1 + j] * sol[j]
            x[1 + 2 * n + m + npar + j] = qdd[j]
        for i in range(m):
            lam[i] += (mu / tolv[1 + n + i]) * sol[n + i]
            x[1 + 2 * n + i] = lam[i]
        _evalx(kp, x, nin, out, ex, ph)
    return False


# -- the sparse kind: the augmented matrix by the compiled sparse LU of its fixed pattern ----
#
# ``bi = (info, pos, kperm, Bp, Bi, perms, dpos, LUi, -)`` holds two matrices' structures.
# The first is the projection's ``[[I, J^T], [J^, 0]]`` (``_patterns.projection_pattern``, the
# Python path's): ``info[:7] = [N, nK, nB, k_M, k_J, capL, capU]``; stored entry ``s`` holds
# kernel value ``kperm[s] - k_M`` (the Jacobian's; ``k_M = 0``) and goes to ``Bx[pos[s]]``
# of ``B = P Q K P^T`` (``FixedPattern._pos``), whose CSC structure is ``Bp``, ``Bi``;
# ``perms = [row_perm, perm]``; ``dpos`` (n,) the identity's places in ``Bx``. The second
# (``_second``: free motion's augmented matrix, a path's velocity system) is appended to each
# array at the offsets ``info[SECOND:SECOND + 5]`` (pos and kperm, Bp, Bi, perms, dpos), its
# head at ``info[7:14]`` (for the augmented matrix: kernel value ``kperm[s]``,
# ``FreeKernel._perm``). ``LUi`` the sparse LU's integer storage ``[Lp | Up | pinv | iw | Li
# | Ui]`` (the stepper's own, sized for the larger). ``bw = (Bx, Lx, Ux, -, xw, sol, wv,
# tmp)``, each for the larger.
SECOND = 14


@nb.njit(cache=True, inline='always')
def _second(bi):
    """The second structure of ``bi`` (see above) in the same layout. (Inlined: it returns
    array views.)"""
    info = bi[0]
    o = info[SECOND:SECOND + 5]
    return (info[7:SECOND], bi[1][o[0]:], bi[2][o[0]:], bi[3][o[1]:], bi[4][o[2]:],
            bi[5][o[3]:], bi[6][o[4]:], bi[7])


@leaf
def _slu_factor(bi, bw):
    """``lu_factor`` of ``Bx`` (``_linalg._SparseFactor``: the same function and tolerance);
    returns the pivot ratio, or -1 (a status, storage too small, or a ratio not above
    ``RCOND_MIN``: the Python path raises ``Singular`` or grows the storage)."""
    info = bi[0]
    N, nB, capL, capU = info[0], info[2], info[5], info[6]
    LUi = bi[7]
    o = 2 * (N + 1) + (IWORK + 1) * N
    st = lu_factor(N, bi[3], bi[4], bw[0][:nB], PIVOT_TOL, LUi[:N + 1], LUi[o:o + capL],
                   bw[1], LUi[N + 1:2 * N + 2], LUi[o + capL:o + capL + capU], bw[2],
                   LUi[2 * N + 2:3 * N + 2], LUi[3 * N + 2:o], bw[4])
    if st != 0:
        return -1.0
    ratio = lu_pivot_ratio(N, LUi[N + 1:2 * N + 2], bw[2])
    return ratio if ratio > RCOND_MIN else -1.0


@leaf
def _slu_solve(bi, bw, rhs, x):
    """``K x = rhs`` with :func:`_slu_factor`'s factors (``_linalg._Permuted.solve``):
    ``rhs`` in the pattern's row order, the sparse solve, back in the unknowns' order."""
    info = bi[0]
    N, capL, capU = info[0], info[5], info[6]
    LUi, perms = bi[7], bi[5]
    o = 2 * (N + 1) + (IWORK + 1) * N
    sol, wv, tmp = bw[5], bw[6], bw[7]
    for i in range(N):
        tmp[i] = rhs[perms[i]]
    lu_solve(N, LUi[2 * N + 2:3 * N + 2], LUi[:N + 1], LUi[o:o + capL], bw[1],
             LUi[N + 1:2 * N + 2], LUi[o + capL:o + capL + capU], bw[2], tmp, sol, wv)
    for i in range(N):
        x[perms[N + i]] = sol[i]


@leaf
def _accel_sparse(kp, x, nin, out, n, m, jr, jc, rows0, columns, robust, qdd, lam, force, bi,
                  bw, ex, ph, t, y, f):
    """``f = (qd, qdd)`` at ``(t, y)`` by the sparse kind (``_free.free_acceleration`` for a
    large system: the kernel's CSC values into ``B``, its sparse LU, the solve); False: hand
    over (a singular or non-finite system, an answer the Python path would refuse, or,
    ``robust``, the zone guard's test of ``_solve_augmented``)."""
    b2 = _second(bi)                  # (the augmented matrix; the projection's comes first)
    info = b2[0]
    N, nK, nB, kM, kJ = info[0], info[1], info[2], info[3], info[4]
    pos, kperm = b2[1], b2[2]
    kk = kM + kJ
    x[0] = t
    for j in range(2 * n):
        x[1 + j] = y[j]
    _evalx(kp, x, nin, out, ex, ph)
    Bx = bw[0]
    for i in range(nB):
        Bx[i] = 0.0
    for s in range(nK):
        Bx[pos[s]] += out[kperm[s]]
    if _slu_factor(b2, bw) < 0:
        return False
    big_rhs = 0.0
    for i in range(N):
        v = abs(out[kk + i])
        if not v <= big_rhs:
            big_rhs = v
    sol = bw[4]                       # (the factorisation's work vector, free again)
    _slu_solve(b2, bw, out[kk:kk + N], sol)
    if not _accepted(sol, big_rhs, n, m, qdd, lam, robust, rows0, out, kM, jr, jc, columns,
                     force):
        return False
    for j in range(n):
        f[j] = y[n + j]
        f[n + j] = qdd[j]
    return True


@leaf
def _min_norm_sparse(r, columns, bvec, out, n, m, jr, jc, jv, bi, bw, robust):
    r"""``_free._min_norm`` of a large system, operation for operation: the smallest ``z``
    (``out = D z``) with ``J^ z = bvec``, :math:`\hat J = R^{-1} J D` (``jv`` the Jacobian's values,
    each entry once), from ``[[I, J^T], [J^, 0]] [z; -nu] = [0; bvec]`` through that
    matrix's pattern (``_patterns.projection_pattern``: the first structure of ``bi``) and the
    same sparse LU. False (hand over) at a pivot ratio below ``RCOND_MIN``, or, ``robust``,
    below ``ZONE^2``: the Python path's tests on the same pivots (the identity's and the
    Schur complements' of ``J^ J^T``): it hands over before the zone of a singular
    Jacobian."""
    info = bi[0]
    nK, nB, kM, kJ = info[1], info[2], info[3], info[4]
    pos, kperm, dpos = bi[1], bi[2], bi[6]
    Bx = bw[0]
    for i in range(nB):
        Bx[i] = 0.0
    for s in range(nK):
        k = kperm[s] - kM
        if k >= 0 and k < kJ:
            Bx[pos[s]] += jv[k] * (columns[jc[k]] / r[jr[k]])   # (Scaling.scaled's)
    for j in range(n):
        Bx[dpos[j]] += 1.0
    ratio = _slu_factor(bi, bw)
    if ratio < 0 or (robust and ratio < ZONE * ZONE):
        return False
    rhs = bw[4]
    for j in range(n):
        rhs[j] = 0.0
    for i in range(m):
        rhs[n + i] = bvec[i]
    sol = bw[3][0]
    _slu_solve(bi, bw, rhs, sol)
    for j in range(n):
        out[j] = columns[j] * sol[j]
    return True


@leaf
def _path_converged(R, r, out, last, columns, n, m, k, f):
    """The velocity Newton's test (``PathSystem.velocities``): ``R``'s last ``k`` entries from
    the velocity constraints' values ``out[:k]``; 1 (``f = last``) when every scaled residual
    ``|R_i| / r_i`` is within ``1e-12 (1 + max |qd_j| / c_j)``, -1 when one is not finite
    (hand over), else 0."""
    for i in range(k):
        R[m + i] = out[i]
    big = 0.0
    qmax = 0.0
    for i in range(n):
        v = abs(R[i] / r[i])
        if not v <= big:             # NaN too
            big = v
        v = abs(last[i] / columns[i])
        if v > qmax:
            qmax = v
    if not np.isfinite(big):
        return -1
    if big <= 1e-12 * (1.0 + qmax):
        for j in range(n):
            f[j] = last[j]
        return 1
    return 0


@leaf
def _path_step(dq, last, f, n, linear):
    """The Newton step ``last <- last - dq``: -1 (hand over) at a value not finite; 1 (``f =
    last``) when the velocity constraints are linear in the velocities (one step solves
    them), else 0."""
    for j in range(n):
        dq[j] = last[j] - dq[j]
        if not np.isfinite(dq[j]):
            return -1
    for j in range(n):
        last[j] = dq[j]
    if linear:
        for j in range(n):
            f[j] = last[j]
        return 1
    return 0


@leaf
def _path_velocity(kp, x, out, KT, n, m, jr, jc, columns, ipiv, w1, w2, last, info, pw, ex_psi,
                   ph_psi, ex_vel, ph_vel, t, q, f):
    """The velocities of a path at ``(t, q)``: ``analyses._path.PathSystem.velocities``,
    operation for operation. ``kp`` the
    velocity constraints' kernel ``[t, q, qd, p] -> [psi (k), psi_qd (k, n), rest (k)]``
    (its pointer-table row); ``info = [k, npar, the holonomic velocity kernel's row (5),
    linear]``, that kernel ``-> [Phi_q values, Phi_t]`` (``m`` rows); ``pw = (velocity kernel
    outputs, R, r, J (m, n), dq, ...)``. From
    the guess ``last`` (the previous evaluation's velocities, as the Python path's):

        K = [Phi_q; psi_qd],  R = [Phi_q qd + Phi_t; psi(qd)],  qd <- qd - K^-1 R

    unless ``R`` is already within the tolerance; once when the velocity constraints are
    linear in the velocities, else until it is (at most 20 steps). ``f = last = qd``; False
    where the Python path must decide (``K`` singular or nearly: its reciprocal condition
    below ``RCOND_MIN``; a value not finite; no convergence)."""
    out_vel, R, r, J, dq = pw[0], pw[1], pw[2], pw[3], pw[4]
    k = info[0]
    linear = info[7] != 0
    nnz = jr.size
    nin_k = 1 + 2 * n + info[1]          # [t, q, qd, p]: p is written by the loops' set-up
    x[0] = t
    for j in range(n):
        x[1 + j] = q[j]
        x[1 + n + j] = 0.0
    if m > 0:
        _evalx(info[2:7], x, nin_k, out_vel, ex_vel, ph_vel)
        _assemble(out_vel, 0, jr, jc, J)
    for _ in range(20):
        for j in range(n):
            x[1 + n + j] = last[j]
        _evalx(kp, x, nin_k, out, ex_psi, ph_psi)
        # K (transposed storage): the holonomic rows, then psi_qd (row-major k x n in ``out``)
        for i in range(m):
            for j in range(n):
                KT[j, i] = J[i, j]
        for i in range(k):
            for j in range(n):
                KT[j, m + i] = out[k + i * n + j]
        for i in range(n):
            rmax = 0.0
            for j in range(n):
                v = abs(KT[j, i] * columns[j])
                if v > rmax:
                    rmax = v
            r[i] = rmax if rmax > 0 else 1.0
        for i in range(m):
            acc = 0.0
            for j in range(n):
                acc += J[i, j] * last[j]
            R[i] = acc - (-out_vel[nnz + i])
        done = _path_converged(R, r, out, last, columns, n, m, k, f)
        if done != 0:
            return done > 0
        if not _factor_checked(KT, n, ipiv, w1, w2):
            return False
        for i in range(n):
            dq[i] = R[i]
        getrs(KT, n, ipiv, dq)
        done = _path_step(dq, last, f, n, linear)
        if done != 0:
            return done > 0
    return False                         # not converged: the Python path says so


# The sparse path (a path above ``SMALL_LU`` coordinates, ``FreeStepper.plan_path``): its
# velocity system ``K = [Phi_q; psi_qd]`` is the second structure of ``bi`` (see above
# ``_slu_factor``; ``_second``): ``K``'s entries' slots in ``kperm``, their rows then
# columns in ``dpos``; ``info[PATH_EXTRA:]`` = [k, npar, the holonomic velocity kernel's row
# (5), linear, nE (K's entries), nb (psi_qd's kernel nonzeros)];
# ``_jit_free._path_sparse_structure``.
PATH_EXTRA = 19


@nb.njit(cache=True, inline='always')
def _path_k(bi):
    """``(K's sparse-LU structure (_second, its entries' rows in the seventh place), nb, the
    columns of its entries)``. (Inlined: it returns array views, which a leaf, compiled
    without reference counting, must not hand to a caller that counts them.)"""
    s = _second(bi)
    nE, nb = bi[0][PATH_EXTRA + 8], bi[0][PATH_EXTRA + 9]
    biK = (s[0], s[1], s[2], s[3], s[4], s[5], s[6][:nE], s[7])
    return biK, nb, s[6][nE:2 * nE]


@leaf
def _path_k_values(biK, nb, ck, jv, nnz, psi_qd, columns, data, r):
    """``K``'s values in its pattern's entry order and its row scales (``analyses._path.
    PathSystem._sparse_values``, operation for operation): ``data`` (nE,) the sums of the
    Jacobian's values ``jv`` and ``psi_qd``'s nonzeros at their slots, ``r`` (n,) the largest
    ``|K_ij| c_j`` of each row (1 for an empty one)."""
    slots, rk = biK[2], biK[6]
    nE = rk.size
    for e in range(nE):
        data[e] = 0.0
    for s in range(nnz):
        data[slots[s]] += jv[s]
    for s in range(nb):
        data[slots[nnz + s]] += psi_qd[s]
    _rows_nz(data[:nE], rk, ck, columns, r)


@leaf
def _path_k_factor(biK, bw, ck, data, columns, r):
    """``_slu_factor`` of ``R^-1 K D`` from :func:`_path_k_values`' ``data`` and ``r``
    (``PathSystem._sparse_values``' scaled values, ``_linalg._SparseFactor``'s placement):
    the pivot ratio, or -1 (hand over)."""
    pos, rk = biK[1], biK[6]
    Bx = bw[0]
    for e in range(rk.size):
        Bx[pos[e]] = data[e] * (columns[ck[e]] / r[rk[e]])
    return _slu_factor(biK, bw)


@leaf
def _path_velocity_sparse(kp, x, out, n, m, jr, jc, columns, last, bi, bw, ex_psi, ph_psi,
                          ex_vel, ph_vel, t, q, f):
    """:func:`_path_velocity` above ``SMALL_LU`` coordinates (``PathSystem.
    _velocities_sparse``, operation for operation): ``K`` gathered into its fixed pattern and
    factorised by the compiled sparse LU, as the Python path does. ``bw[3]`` holds the
    vectors ``(-, velocity kernel outputs, R, r, K's values, dq)`` in its rows."""
    info = bi[0]
    k, npar = info[PATH_EXTRA], info[PATH_EXTRA + 1]
    linear = info[PATH_EXTRA + 7] != 0
    biK, nb, ck = _path_k(bi)
    W = bw[3]
    out_vel, R, r, data, dq = W[1], W[2], W[3], W[4], W[5]
    rhs = bw[4]
    nnz = jr.size
    nin_k = 1 + 2 * n + npar
    x[0] = t
    for j in range(n):
        x[1 + j] = q[j]
        x[1 + n + j] = 0.0
    if m > 0:
        _evalx(info[PATH_EXTRA + 2:PATH_EXTRA + 7], x, nin_k, out_vel, ex_vel, ph_vel)
    for _ in range(20):
        for j in range(n):
            x[1 + n + j] = last[j]
        _evalx(kp, x, nin_k, out, ex_psi, ph_psi)
        _path_k_values(biK, nb, ck, out_vel, nnz, out[k:k + nb], columns, data, r[:n])
        for i in range(m):
            R[i] = 0.0
        for s in range(nnz):
            R[jr[s]] += out_vel[s] * last[jc[s]]
        for i in range(m):
            R[i] = R[i] - (-out_vel[nnz + i])
        done = _path_converged(R, r, out, last, columns, n, m, k, f)
        if done != 0:
            return done > 0
        if _path_k_factor(biK, bw, ck, data, columns, r) < 0:
            return False
        for i in range(n):
            rhs[i] = R[i] / r[i]
        _slu_solve(biK, bw, rhs, dq)
        for j in range(n):
            dq[j] = columns[j] * dq[j]       # (the step in the unknowns' units)
        done = _path_step(dq, last, f, n, linear)
        if done != 0:
            return done > 0
    return False                         # not converged: the Python path says so


@nb.njit(cache=True)
def path_accelerations(kp, ex, times, Q, QD, p, jr, jc, k, bi, bw, QDD):
    """A path's accelerations at each output row (``analyses._path.PathSystem.accelerations``,
    operation for operation): ``[Phi_q; psi_qd] qdd = [gamma; -rest]``. ``kp`` (3, 5) the
    Jacobian's (position kernel; above ``SMALL_LU`` coordinates the velocity kernel, as the
    Python path), gamma and velocity-constraint kernels' rows, ``ex`` their output maps (CSE
    kernels); ``bi``, ``bw`` the stepper's structure and float work (above ``SMALL_LU``
    coordinates ``K`` by its pattern and the compiled sparse LU, unit column scales).
    Returns the first row left to the Python path (a singular or nearly singular matrix: it
    raises the diagnosis), ``len(times)`` when all are done."""
    N, n = Q.shape
    m = n - k
    nnz = jr.size
    npar = p.size
    nin = 1 + 2 * n + npar
    sparse = bi[7].size > 1
    x = np.zeros(nin + max(kp[0, 4], kp[1, 4], kp[2, 4], 0))
    for j in range(npar):
        x[1 + 2 * n + j] = p[j]
    nb = bi[0][PATH_EXTRA + 9] if sparse else 0
    out_J = np.empty(m + nnz)
    g = np.empty(m)
    out = np.empty(2 * k + (nb if sparse else k * n))
    ph = (np.zeros(ex[0].max() + 1 if ex[0].size else 1),
          np.zeros(ex[1].max() + 1 if ex[1].size else 1),
          np.zeros(ex[2].max() + 1 if ex[2].size else 1))
    side = 1 if sparse else n
    J = np.zeros((side if m else 0, side))
    KT = np.empty((side, side))
    ipiv = np.empty(side, dtype=np.int32)
    w = np.empty(2 * side)
    ones = np.ones(n)
    data = np.empty(bi[0][PATH_EXTRA + 8] if sparse else 1)
    r = np.empty(n)
    b = np.empty(n)
    sol = np.empty(n)
    tail = k + (nb if sparse else k * n)      # where ``rest`` starts in ``out``
    for row in range(N):
        x[0] = times[row]
        for j in range(n):
            x[1 + j] = Q[row, j]
            x[1 + n + j] = 0.0
        if m > 0:
            _evalx(kp[0], x, nin, out_J, ex[0], ph[0])
            if not sparse:
                _assemble(out_J, m, jr, jc, J)
        for j in range(n):
            x[1 + n + j] = QD[row, j]
        if m > 0:
            _evalx(kp[1], x, nin, g, ex[1], ph[1])
        _evalx(kp[2], x, nin, out, ex[2], ph[2])
        if sparse:
            biK, _, ck = _path_k(bi)
            _path_k_values(biK, nb, ck, out_J, nnz, out[k:k + nb], ones, data, r)
            if _path_k_factor(biK, bw, ck, data, ones, r) < 0:
                return row
            for i in range(m):
                b[i] = g[i] / r[i]
            for i in range(k):
                b[m + i] = -out[tail + i] / r[m + i]
            _slu_solve(biK, bw, b, sol)
            for j in range(n):
                b[j] = ones[j] * sol[j]
        else:
            for i in range(m):
                for j in range(n):
                    KT[j, i] = J[i, j]
                b[i] = g[i]
            for i in range(k):
                for j in range(n):
                    KT[j, m + i] = out[k + i * n + j]
                b[m + i] = -out[tail + i]
            if not _factor_checked(KT, n, ipiv, w, w[n:]):
                return row
            getrs(KT, n, ipiv, b)
        for j in range(n):
            if not np.isfinite(b[j]):
                return row
            QDD[row, j] = b[j]
    return N


@leaf
def _min_norm(lapack, J, r, columns, bvec, out, Js, A, ipiv, ibuf, cbuf, dbuf, work, iwork,
              ybuf, robust):
    r"""``out = D J^T (J^ J^T)^-1 bvec``; False at a singular (or, ``robust``, nearly singular:
    reciprocal condition below ``ZONE^2``) ``J^ J^T``.

    Up to ``SMALL_LU`` rows, ``getrf`` records the factors' nonzeros (in ``iwork``:
    ``pattern_size(m)`` entries), the solves and the condition estimate visit only those, and
    the estimate is not made where ``inv_norm_bound`` proves it at least twice the
    threshold :math:`\tau` (``ZONE^2`` robust, else ``RCOND_MIN``):

    .. math:: \lVert A \rVert_1 \, \beta \le \frac{1}{2 \tau} \implies
              \mathrm{rcond} \ge \frac{1}{\lVert A \rVert_1 \, \mathrm{est}} > \tau,
              \qquad \mathrm{est} \le \beta \, (1 + 10^{-10})

    (``beta`` the bound, which exceeds any estimate ``gecon1`` computes from these factors:
    ``_jit_lapack.inv_norm_bound``). Only "below the threshold or not" is read here, so the
    decision and the numbers are the dense loops' (a zero's sign aside; decision 0087); the
    interpreted tier saves the estimate's ten triangular solves."""
    m, n = J.shape
    # (rows through views, ``Jsi = Js[i]``: the same operations; the interpreted tier indexes
    # a view by one integer, faster than ``Js[i, j]``: decision 0077)
    for i in range(m):
        inv = 1.0 / r[i]
        Ji = J[i]
        Jsi = Js[i]
        for j in range(n):
            Jsi[j] = (Ji[j] * columns[j]) * inv
    for i in range(m):              # A = Js Js^T (symmetric: its transposed storage is itself)
        Jsi = Js[i]
        for k in range(i + 1):
            Jsk = Js[k]
            s = 0.0
            for j in range(n):
                s += Jsi[j] * Jsk[j]
            A[i, k] = s
            A[k, i] = s
    anorm = _norm1(A, m)             # (A symmetric: the same sums in the same order)
    small = m <= SMALL_LU
    nz = iwork
    if small:
        if getrf(A, m, ipiv, nz) > 0 or anorm == 0:
            return False
        guard = ZONE * ZONE if robust else RCOND_MIN
        rcond = np.inf
        if anorm * inv_norm_bound(A, m, nz, work) > GUARD_MARGIN / guard:
            rcond = gecon1(A, m, anorm, work, work[m:], nz)
    else:
        ibuf[0] = m
        ibuf[1] = m
        ibuf[2] = m
        ibuf[3] = 0
        _ccall(lapack[0], (ibuf[0:1], ibuf[1:2], A, ibuf[2:3], ipiv, ibuf[3:4]))
        if ibuf[3] > 0 or anorm == 0:
            return False
        cbuf[0] = 49         # '1': one-norm
        dbuf[0] = anorm
        dbuf[1] = 0.0
        _ccall(lapack[1], (cbuf[0:1], ibuf[1:2], A, ibuf[2:3], dbuf[0:1], dbuf[1:2], work,
                           iwork, ibuf[3:4]))
        rcond = dbuf[1]
    if rcond < RCOND_MIN or (robust and rcond < ZONE * ZONE):
        return False
    for i in range(m):
        ybuf[i] = bvec[i]
    if small:
        getrs(A, m, ipiv, ybuf, nz)
    else:
        cbuf[1] = 78         # 'N'
        ibuf[4] = 1
        _ccall(lapack[2], (cbuf[1:2], ibuf[1:2], ibuf[4:5], A, ibuf[2:3], ipiv, ybuf,
                           ibuf[2:3], ibuf[3:4]))
    for j in range(n):
        s = 0.0
        for i in range(m):
            s += Js[i, j] * ybuf[i]
        out[j] = columns[j] * s
    return True


@leaf
def _project(pp, pv, lapack, xk, nin_k, out_pos, out_vel, jr, jc, columns, offset, tol, maxit,
             robust, n, m, t, y, J, r, Fs, dq, Js, A, ipiv, ibuf, cbuf, dbuf, work, iwork, ybuf,
             blocks, blk_i, blk_w):
    """Project ``y = (q, qd)`` in place onto the constraints (``solvers._free.project``);
    False (``y`` then undefined): hand over. ``blocks``: by the block path when ``BLOCK``."""
    ex, ph = blk_i[2], blk_w[2]
    if blocks == BLOCK:
        return within(blocks, BLOCK, BLOCK, _project_blocks, pp, pv, xk, nin_k, out_pos,
                      out_vel, jr, jc, columns, offset, tol, maxit, robust, n, m, t, y, r, Fs,
                      dq, blk_i[0], blk_w[0][5], blk_w[0][3], ex, ph)
    # a large NEWTON system: the Jacobian by its distinct nonzeros, the minimum-norm
    # correction through the Newton matrix's banded pattern (_min_norm_band); the sparse kind:
    # the Jacobian's values straight from the kernels (each entry once), the correction
    # through the projection's pattern (_min_norm_sparse; also a large path's)
    band = blocks == NEWTON and blk_i[0][7].size > 1
    sparse = blocks == SPARSE or (blocks == PATH and blk_i[0][7].size > 1)
    nnz = jr.size
    xk[0] = t
    for j in range(n):
        xk[1 + n + j] = 0.0
    lim = tol * (1.0 + offset)
    for _ in range(maxit if m > 0 else 0):     # (velocity rows alone: no position rows)
        for j in range(n):
            xk[1 + j] = y[j]
        _evalx(pp, xk, nin_k, out_pos, ex[1], ph[1])
        if band:
            within(blocks, NEWTON, NEWTON, _band_rows_of, out_pos, m, jr, columns, r,
                   blk_i[0][7], blk_w[0][3][0])
        elif sparse:
            _rows_nz(out_pos[m:m + nnz], jr, jc, columns, r)
        else:
            _assemble(out_pos, m, jr, jc, J)
            _rows(J, columns, r)
        if _position_residual(out_pos, r, Fs, m) <= lim:
            break
        if band:
            if not within(blocks, NEWTON, NEWTON, _min_norm_band, lapack, ibuf, ipiv, r,
                          columns, Fs, dq, n, m, jr, blk_i[0][7], blk_w[0][3][0]):
                return False
        elif sparse:
            if not within(blocks, PATH, SPARSE, _min_norm_sparse, r, columns, Fs, dq, n, m,
                          jr, jc, out_pos[m:m + nnz], blk_i[0], blk_w[0], robust):
                return False
        elif not _min_norm(lapack, J, r, columns, Fs, dq, Js, A, ipiv, ibuf, cbuf, dbuf, work,
                           iwork, ybuf, robust):
            return False
        for j in range(n):
            y[j] -= dq[j]
    if blocks == PATH:                   # a path's state is q alone
        return _all_finite(y, n)
    for j in range(n):
        xk[1 + j] = y[j]
    if blocks == ROLLING:
        return within(blocks, ROLLING, ROLLING, _project_rows, pv, lapack, xk, nin_k, out_vel,
                      jr, jc, columns, n, m, y, ibuf, cbuf, dbuf, ex[2], ph[2], blk_i[3],
                      blk_w[3])
    _evalx(pv, xk, nin_k, out_vel, ex[2], ph[2])
    if sparse:
        _rows_nz(out_vel[:nnz], jr, jc, columns, r)
        for i in range(m):
            Fs[i] = 0.0
        for k in range(nnz):
            Fs[jr[k]] += out_vel[k] * y[n + jc[k]]
        for i in range(m):
            Fs[i] = (Fs[i] - (-out_vel[nnz + i])) / r[i]
        if not within(blocks, PATH, SPARSE, _min_norm_sparse, r, columns, Fs, dq, n, m, jr, jc,
                      out_vel[:nnz], blk_i[0], blk_w[0], robust):
            return False
    elif band:
        w = blk_w[0][3][0]
        bnd = blk_i[0][7]
        within(blocks, NEWTON, NEWTON, _band_rows_of, out_vel, 0, jr, columns, r, bnd, w)
        U = bnd[4]
        o = within(blocks, NEWTON, NEWTON, _band_jmap, bnd, jr.size, n + m) + jr.size
        for i in range(m):
            Fs[i] = 0.0
        for u in range(U):
            Fs[bnd[o + u]] += w[u] * y[n + bnd[o + U + u]]
        for i in range(m):
            Fs[i] = (Fs[i] - (-out_vel[nnz + i])) / r[i]
        if not within(blocks, NEWTON, NEWTON, _min_norm_band, lapack, ibuf, ipiv, r, columns,
                      Fs, dq, n, m, jr, blk_i[0][7], w):
            return False
    else:
        _assemble(out_vel, 0, jr, jc, J)
        _rows(J, columns, r)
        _velocity_residual(J, y, n, 0, m, out_vel, nnz, r, Fs)
        if not _min_norm(lapack, J, r, columns, Fs, dq, Js, A, ipiv, ibuf, cbuf, dbuf, work,
                         iwork, ybuf, robust):
            return False
    return _velocity_corrected(y, dq, n)


@leaf
def _position_residual(out_pos, r, Fs, m):
    r"""The position projection's scaled residual ``Fs`` (m,) from the constraint values
    ``out_pos[:m]`` and the row scales ``r``, and its max-norm (NaN where an entry is NaN:
    never within the limit),

    .. math::  F_i = \Phi_i / r_i, \qquad \lVert F \rVert_\infty"""
    big = 0.0
    for i in range(m):
        Fs[i] = out_pos[i] / r[i]
        v = abs(Fs[i])
        if not v <= big:
            big = v
    return big


@leaf
def _setup(x, p, n, m, blocks, lam):
    """The derivative's argument array at the start of a run: zeros and the parameters, at
    ``[t, q, qd, lambda = 0, p, qdd = 0]`` (free motion) or ``[t, q, qd, p]`` (a path, whose
    multipliers ``lam`` are none: NaN)."""
    x[:] = 0.0
    at = 1 + 2 * n if blocks == PATH else 1 + 2 * n + m
    for j in range(p.size):
        x[at + j] = p[j]
    if blocks == PATH:
        lam[:] = np.nan


@nb.njit(cache=True, inline='always')
def _combine(K, c, s, acc):
    r"""``acc[j] = sum_{k < s} K[k, j] c[k]`` (:math:`\sum_k c_k K_k`, the stages' sum), row
    by row of ``K``: for each coordinate the terms are added in the order of ``k``, from 0."""
    for j in range(acc.size):
        acc[j] = 0.0
    for k in range(s):
        ck = c[k]
        row = K[k]
        for j in range(acc.size):
            acc[j] += row[j] * ck


@nb.njit(cache=True)
def runge_kutta(kp, lapack, p, flat_t, mp, kk, n, m, jr, jc, rows0, columns, offset, robust,
                blocks, blk_i, ws, correction, ptol, pmaxit, method, Acoef, Bcoef, Ccoef, E3,
                E5, Dcoef, rtol, atol, max_step,
                t_bound, direction, state, y, f, t_eval, ie0, max_steps,
                T, Y, H, QDD, LAM, ET, EY, EQDD, ELAM, FD):
    """Accepted DOP853 or RK45 (``method``) steps from ``(state[0] = t, y, f, state[1] =
    h_abs)``; see the module docstring. The method's coefficients: DOP853's ``A`` (16, 16),
    ``B``, ``C``, ``E3``, ``E5``, ``D`` (its dense output's); RK45's ``A``, ``B``, ``C``,
    ``E`` (in ``E5``; ``E3`` unused) and ``P`` (in ``Dcoef``). ``FD`` (8, N2) or (0, N2):
    when it has rows, every step computes its dense output and leaves it there, ``F``
    (DOP853: 7 rows; RK45: ``Q^T``, 4 rows) and the state at the step's start in the last
    row (:class:`._jit_free.StepDense` evaluates it). Returns ``(status, steps, ie,
    evaluations, rejected, projections)``; the state arrays hold the last accepted
    (projected) state and its derivative."""
    N2 = n if blocks == PATH else 2 * n
    npar = p.size
    nin = 1 + 2 * n + m + npar + n                   # [t, q, qd, lambda, p, qdd]
    nin_k = 1 + 2 * n + npar                         # [t, q, qd, p]
    (x, xk, out, out_pos, out_vel, KT, KTf, ipiv, ibuf, cbuf, dbuf, rhsb, bb, qdd, lam, force,
     blk_w, J, r, Fs, dq, Js, Am, work, iwork, ybuf) = borrow(ws)
    (lapack, p, flat_t, mp, jr, jc, rows0, columns, blk_i, y, state, f, t_eval, atol) = borrow(
        (lapack, p, flat_t, mp, jr, jc, rows0, columns, blk_i, y, state, f, t_eval, atol))
    mu = blk_w[3][13]                # the velocity constraints' multipliers (ROLLING)
    _setup(x, p, n, m, blocks, lam)
    xk[:] = 0.0                      # [t, q, qd = 0 (positions), p]
    for j in range(npar):
        xk[1 + 2 * n + j] = p[j]
    K = np.empty((16, N2))
    ynew = np.empty(N2)
    fnew = np.empty(N2)
    ytmp = np.empty(N2)
    scale = np.empty(N2)
    F = np.empty((7, N2))
    yo = np.empty(N2)
    # the sums over the stages, accumulated stage by stage over contiguous rows of K (see
    # _combine): summed per coordinate over k in the same order as before, so the same
    # numbers; a sum per coordinate across the rows of K read one cache line per row and
    # coordinate, which at N2 = 6144 evicted everything else between two evaluations
    acc = np.empty(N2)
    acc3 = np.empty(N2)
    t = state[0]
    h_abs = state[1]
    evals = 0
    rejected = 0
    projections = 0
    steps = 0
    ie = ie0
    n_eval = t_eval.size
    rk45 = method == RK45
    n_stages = 6 if rk45 else 12
    # -1 / (error_estimator_order + 1)
    error_exponent = -1.0 / 5.0 if rk45 else -1.0 / 8.0
    while steps < max_steps:
        # -- one step of scipy's RungeKutta._step_impl --
        min_step = 10.0 * abs(np.nextafter(t, direction * np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step
        accepted = False
        was_rejected = False
        h = 0.0
        t_new = t
        while not accepted:
            if h_abs < min_step:
                return HANDOVER, steps, ie, evals, rejected, projections
            h = h_abs * direction
            t_new = t + h
            if direction * (t_new - t_bound) > 0:
                t_new = t_bound
            h = t_new - t
            h_abs = abs(h)
            for j in range(N2):
                K[0, j] = f[j]
            for s in range(1, n_stages):
                _combine(K, Acoef[s], s, acc)
                for j in range(N2):
                    ytmp[j] = y[j] + acc[j] * h
                evals += 1
                if not _rhs(kp[0], lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc, rows0,
                            columns, robust, ipiv, ibuf, rhsb, bb, qdd, lam, force, blocks, blk_i, blk_w,
                            t + Ccoef[s] * h, ytmp, K[s]):
                    return HANDOVER, steps, ie, evals, rejected, projections
            _combine(K, Bcoef, n_stages, acc)
            for j in range(N2):
                ynew[j] = y[j] + h * acc[j]
            evals += 1
            if not _rhs(kp[0], lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc, rows0,
                        columns, robust, ipiv, ibuf, rhsb, bb, qdd, lam, force,
                        blocks, blk_i, blk_w, t + h, ynew, fnew):
                return HANDOVER, steps, ie, evals, rejected, projections
            for j in range(N2):
                K[n_stages, j] = fnew[j]
            if rk45:
                # RungeKutta._estimate_error_norm: the RMS norm of (K^T E) h / scale
                e5 = 0.0
                _combine(K, E5, n_stages + 1, acc)
                for j in range(N2):
                    scale[j] = atol[j] + max(abs(y[j]), abs(ynew[j])) * rtol
                    a5 = acc[j] * h / scale[j]
                    e5 += a5 * a5
                error_norm = np.sqrt(e5) / np.sqrt(N2)
            else:
                # DOP853._estimate_error_norm
                e5 = 0.0
                e3 = 0.0
                _combine(K, E5, n_stages + 1, acc)
                _combine(K, E3, n_stages + 1, acc3)
                for j in range(N2):
                    scale[j] = atol[j] + max(abs(y[j]), abs(ynew[j])) * rtol
                    a5 = acc[j]
                    a3 = acc3[j]
                    a5 /= scale[j]
                    a3 /= scale[j]
                    e5 += a5 * a5
                    e3 += a3 * a3
                if e5 == 0 and e3 == 0:
                    error_norm = 0.0
                else:
                    error_norm = abs(h) * e5 / np.sqrt((e5 + 0.01 * e3) * N2)
            if error_norm < 1:
                if error_norm == 0:
                    factor = MAX_FACTOR
                else:
                    factor = min(MAX_FACTOR, SAFETY * error_norm ** error_exponent)
                if was_rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                accepted = True
            else:
                h_abs *= max(MIN_FACTOR, SAFETY * error_norm ** error_exponent)
                was_rejected = True
                rejected += 1
        # -- output times inside the step: the method's dense output, then projection --
        ie_step = ie
        dense = FD.shape[0] > 0 or (ie < n_eval and (t_eval[ie] - t_new) * direction <= 0)
        if dense and rk45:
            # RK45._dense_output_impl: Q = K^T P (rows 0-3 of F)
            for j in range(N2):
                for i in range(4):
                    d = 0.0
                    for k in range(n_stages + 1):
                        d += K[k, j] * Dcoef[k, i]
                    F[i, j] = d
        elif dense:
            for s in range(n_stages + 1, 16):
                _combine(K, Acoef[s], s, acc)
                for j in range(N2):
                    ytmp[j] = y[j] + acc[j] * h
                evals += 1
                if not _rhs(kp[0], lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc,
                            rows0, columns, robust, ipiv, ibuf, rhsb, bb, qdd, lam, force,
                            blocks, blk_i, blk_w,
                            t + Ccoef[s] * h, ytmp, K[s]):
                    return HANDOVER, steps, ie_step, evals, rejected, projections
            for j in range(N2):
                dy = ynew[j] - y[j]
                F[0, j] = dy
                F[1, j] = h * K[0, j] - dy
                F[2, j] = 2 * dy - h * (fnew[j] + K[0, j])
                for i in range(4):
                    d = 0.0
                    for k in range(16):
                        d += Dcoef[i, k] * K[k, j]
                    F[3 + i, j] = h * d
        if FD.shape[0] > 0:
            for j in range(N2):
                for i in range(4 if rk45 else 7):
                    FD[i, j] = F[i, j]
                FD[7, j] = y[j]
        if ie < n_eval and (t_eval[ie] - t_new) * direction <= 0:
            while ie < n_eval and (t_eval[ie] - t_new) * direction <= 0:
                xi = (t_eval[ie] - t) / h
                if rk45:
                    # RkDenseOutput: y_old + h Q [x, x^2, x^3, x^4]
                    for j in range(N2):
                        v = 0.0
                        pw = 1.0
                        for i in range(4):
                            pw *= xi
                            v += F[i, j] * pw
                        yo[j] = h * v + y[j]
                else:
                    for j in range(N2):
                        v = 0.0
                        for i in range(7):
                            v += F[6 - i, j]
                            if i % 2 == 0:
                                v *= xi
                            else:
                                v *= 1 - xi
                        yo[j] = v + y[j]
                if correction:
                    if not _project(kp[1], kp[2], lapack, xk, nin_k, out_pos, out_vel, jr, jc,
                                    columns, offset, ptol, pmaxit, robust, n, m, t_eval[ie], yo,
                                    J, r, Fs, dq, Js, Am, ipiv, ibuf, cbuf, dbuf, work, iwork,
                                    ybuf, blocks, blk_i, blk_w):
                        return HANDOVER, steps, ie_step, evals, rejected, projections
                    projections += 1
                if not _rhs(kp[0], lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc,
                            rows0, columns, robust, ipiv, ibuf, rhsb, bb, qdd, lam, force,
                            blocks, blk_i, blk_w, t_eval[ie],
                            yo, ytmp):
                    return HANDOVER, steps, ie_step, evals, rejected, projections
                ET[ie] = t_eval[ie]
                for j in range(N2):
                    EY[ie, j] = yo[j]
                for j in range(n):
                    EQDD[ie, j] = qdd[j]
                for i in range(m):
                    ELAM[ie, i] = lam[i]
                for i in range(mu.size):         # (velocity constraints' multipliers)
                    ELAM[ie, m + i] = mu[i]
                ie += 1
        # -- projection after the accepted step; the derivative at the projected state --
        if correction:
            if not _project(kp[1], kp[2], lapack, xk, nin_k, out_pos, out_vel, jr, jc, columns,
                            offset, ptol, pmaxit, robust, n, m, t_new, ynew, J, r, Fs, dq, Js,
                            Am, ipiv, ibuf, cbuf, dbuf, work, iwork, ybuf, blocks, blk_i, blk_w):
                return HANDOVER, steps, ie_step, evals, rejected, projections
            projections += 1
            evals += 1
            if not _rhs(kp[0], lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc, rows0,
                        columns, robust, ipiv, ibuf, rhsb, bb, qdd, lam, force,
                        blocks, blk_i, blk_w, t_new, ynew, fnew):
                return HANDOVER, steps, ie_step, evals, rejected, projections
        # -- commit --
        t = t_new
        for j in range(N2):
            y[j] = ynew[j]
            f[j] = fnew[j]
        T[steps] = t
        H[steps] = abs(h)
        for j in range(N2):
            Y[steps, j] = y[j]
        for j in range(n):
            QDD[steps, j] = f[N2 - n + j]      # accelerations (free motion), velocities (path)
        # the multipliers belong to the last evaluation, which was at (t, y) only when it
        # came after the output times (projection on) or no output was made in this step
        if correction or ie == ie_step:
            for i in range(m):
                LAM[steps, i] = lam[i]
            for i in range(mu.size):
                LAM[steps, m + i] = mu[i]
        else:
            for i in range(LAM.shape[1]):
                LAM[steps, i] = np.nan
        steps += 1
        state[0] = t
        state[1] = h_abs
        if direction * (t - t_bound) >= 0:
            return FINISHED, steps, ie, evals, rejected, projections
    return CHUNK, steps, ie, evals, rejected, projections


@nb.njit(cache=True)
def adams(kp, lapack, p, flat_t, mp, kk, n, m, jr, jc, rows0, columns, offset, robust,
          blocks, blk_i, ws, correction, ptol, pmaxit, k, a, b, c, method, fixed, inv_scale, t1, state, y,
          hist_t, hist_f, recent, max_steps, T, Y, H, E, QDD, LAM):
    """Accepted steps of Mech's Adams integrator: the steps of ``_jit_adams`` (written once,
    the Python driver ``solvers._integrators.integrate_adams`` calls them too) with the
    compiled derivative, from the run's state ``state`` (``_jit_adams.STATE``), ``y``, the
    derivative history ``hist_t`` (6,), ``hist_f`` (6, 2n) and the last errors ``recent``
    (8,): up to ``2 k`` of them. ``method``: 0 automatic, 1 predictor, 2 corrector.
    Returns ``(status, steps, evaluations, projections)``; the state arrays hold the last
    accepted state (and the step to try next)."""
    N2 = n if blocks == PATH else 2 * n
    npar = p.size
    nin = 1 + 2 * n + m + npar + n
    nin_k = 1 + 2 * n + npar
    (x, xk, out, out_pos, out_vel, KT, KTf, ipiv, ibuf, cbuf, dbuf, rhsb, bb, qdd, lam, force,
     blk_w, J, r, Fs, dq, Js, Am, work, iwork, ybuf) = borrow(ws)
    (lapack, p, flat_t, mp, jr, jc, rows0, columns, blk_i, y, state, hist_t, hist_f, recent) = borrow(
        (lapack, p, flat_t, mp, jr, jc, rows0, columns, blk_i, y, state, hist_t, hist_f, recent))
    mu = blk_w[3][13]                # the velocity constraints' multipliers (ROLLING)
    _setup(x, p, n, m, blocks, lam)
    xk[:] = 0.0                      # [t, q, qd = 0 (positions), p]
    for j in range(npar):
        xk[1 + 2 * n + j] = p[j]
    V = np.empty((6, 6))
    cache_p = np.full(13, -1.0)
    vpiv = np.empty(6, dtype=np.int32)
    cache_c = np.full(13, -1.0)
    w = np.empty(6)
    nodes = np.empty(6)
    y_pred = np.empty(N2)
    f_pred = np.empty(N2)
    y_corr = np.empty(N2)
    f_new = np.empty(N2)
    t = state[0]
    h = state[1]
    nh = int(state[2])
    nrec = int(state[3])
    rejected = int(state[4])
    window = 2 * k                   # Mech's doubling rule: the last 2n errors below c
    sign = 1.0 if t1 - t >= 0 else -1.0
    evals = 0
    projections = 0
    steps = 0
    while (t1 - t) * sign > 1e-14 * max(1.0, abs(t1)):
        if steps >= max_steps:
            break
        # (every code but OK, CORRECTED and REJECTED: the Python driver takes the step)
        code, h_try = adams_predict(t, h, nh, t1, sign, k, y, hist_t, hist_f, V, w, cache_p,
                                    vpiv, y_pred)
        if code != ADAMS_OK:
            return HANDOVER, steps, evals, projections
        t_new = t + h_try
        evals += 1
        if not _rhs(kp[0], lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc, rows0,
                    columns, robust, ipiv, ibuf, rhsb, bb, qdd, lam, force,
                    blocks, blk_i, blk_w, t_new, y_pred, f_pred):
            return HANDOVER, steps, evals, projections
        code, err = adams_correct(t, h_try, nh, k, a, b, fixed, method, y, hist_t, hist_f,
                                  y_pred, f_pred, inv_scale, V, w, nodes, cache_c, vpiv, y_corr,
                                  f_new)
        if code == ADAMS_REJECTED:
            h = h_try / 2
            rejected += 1
            continue
        if code == ADAMS_CORRECTED:
            evals += 1
            if not _rhs(kp[0], lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc, rows0,
                        columns, robust, ipiv, ibuf, rhsb, bb, qdd, lam, force,
                        blocks, blk_i, blk_w, t_new, y_corr, f_new):
                return HANDOVER, steps, evals, projections
        elif code != ADAMS_OK:
            return HANDOVER, steps, evals, projections
        if correction:
            if not _project(kp[1], kp[2], lapack, xk, nin_k, out_pos, out_vel, jr, jc, columns,
                            offset, ptol, pmaxit, robust, n, m, t_new, y_corr, J, r, Fs, dq, Js,
                            Am, ipiv, ibuf, cbuf, dbuf, work, iwork, ybuf, blocks, blk_i, blk_w):
                return HANDOVER, steps, evals, projections
            projections += 1
            evals += 1
            if not _rhs(kp[0], lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc, rows0,
                        columns, robust, ipiv, ibuf, rhsb, bb, qdd, lam, force,
                        blocks, blk_i, blk_w, t_new, y_corr, f_new):
                return HANDOVER, steps, evals, projections
        t = t_new
        nh, nrec, h = adams_commit(t, h, err, nh, nrec, window, c, fixed, y, hist_t, hist_f,
                                   y_corr, f_new, recent)
        T[steps] = t
        H[steps] = h_try
        E[steps] = err
        for j in range(N2):
            Y[steps, j] = y[j]
        for j in range(n):
            QDD[steps, j] = f_new[N2 - n + j]
        for i in range(m):
            LAM[steps, i] = lam[i]
        for i in range(mu.size):
            LAM[steps, m + i] = mu[i]
        steps += 1
        state[0] = t
        state[1] = h
        state[2] = nh
        state[3] = nrec
        state[4] = rejected
    if (t1 - t) * sign > 1e-14 * max(1.0, abs(t1)):
        return CHUNK, steps, evals, projections
    return FINISHED, steps, evals, projections


@nb.njit(cache=True)
def derivative(kp, lapack, p, flat_t, mp, kk, n, m, jr, jc, rows0, columns, robust, blocks,
               blk_i, ws, t, y, f, lam_out):
    """One derivative ``f = (qd, qdd)`` (2n,) and the multipliers ``lam_out`` (m,) at
    ``(t, y)``, as the loops compute them (``_rhs`` on the stepper's work arrays); False
    where the Python path must decide (the loops' hand-over)."""
    (x, xk, out, out_pos, out_vel, KT, KTf, ipiv, ibuf, cbuf, dbuf, rhsb, bb, qdd, lam, force,
     blk_w, J, r, Fs, dq, Js, Am, work, iwork, ybuf) = borrow(ws)
    (lapack, p, flat_t, mp, jr, jc, rows0, columns, blk_i, y, f, lam_out) = borrow(
        (lapack, p, flat_t, mp, jr, jc, rows0, columns, blk_i, y, f, lam_out))
    npar = p.size
    nin = 1 + 2 * n + m + npar + n
    _setup(x, p, n, m, blocks, lam)
    if not _rhs(kp[0], lapack, x, nin, out, KT, KTf, flat_t, mp, kk, n, m, jr, jc, rows0,
                columns, robust, ipiv, ibuf, rhsb, bb, qdd, lam, force, blocks, blk_i, blk_w,
                t, y, f):
        return False
    for i in range(m):
        lam_out[i] = lam[i]
    mu = blk_w[3][13]
    for i in range(mu.size):
        lam_out[m + i] = mu[i]
    return True


def workspace(kp, n, m, npar, kk, nnz, blocks, blk_i, bw):
    """The work arrays of ``runge_kutta`` and ``adams`` (their ``ws`` argument), allocated once per
    stepper by the Python caller: it owns them for the loops' whole run, which is what lets
    the loops borrow them (``_jit_borrow``: no reference counting in the inner calls).
    Plain NumPy, not compiled: it runs once per stepper, and compiling it (every kind's
    arrays) cost a tenth of the stepper's first compile (decision 0044).
    ``kp`` (3, 5) the kernels' rows, ``kk`` the kernel's outputs before the right-hand side,
    ``nnz`` the Jacobian's nonzeros, ``bw`` the block path's bandwidth."""
    nin = 1 + 2 * n + m + npar + n                   # [t, q, qd, lambda, p, qdd]
    nin_k = 1 + 2 * n + npar                         # [t, q, qd, p]
    # (ROLLING: the augmented system bordered by the k velocity rows)
    NN = n + m + (int(blk_i[3][0][5]) if blocks == ROLLING else 0)
    # the dense matrix: the augmented system, a path's velocity system (n x n), else unused
    side = NN if blocks == AUGMENTED or blocks == NEWTON or blocks == ROLLING else (
        n if blocks == PATH else 1)
    banded = ((blocks == NEWTON or blocks == PATH) and blk_i[0][7].size > 1) \
        or blocks == SPARSE
    if banded:
        side = 1                      # (the Newton matrix and projections by its pattern)
    KTf = np.empty(side * side)
    # (a path evaluates its two kernels at [t, q, qd, p] in the first array)
    first = max(nin + max(kp[0, 4], 0), nin_k + max(kp[0, 4], kp[2, 4], 0))
    if blocks == NEWTON:
        # (the loads' derivatives are evaluated at [t, q, qd, lambda, p, qdd] in the first
        # array: room for a first stage of theirs, a large kernel's gathered values)
        info = blk_i[0][0]
        first = max(first, nin + max(info[20], info[25], 0))
    return (np.zeros(first), np.zeros(nin_k + max(kp[1, 4], kp[2, 4])),
            np.empty(kk + n + m), np.empty(m + nnz), np.empty(nnz + m),
            KTf.reshape((side, side)), KTf,
            np.empty(max(NN, 1), dtype=np.int32), np.zeros(8, dtype=np.int32),
            np.zeros(2, dtype=np.uint8), np.zeros(2), np.empty(NN), np.empty(NN), np.zeros(n),
            np.empty(m), np.empty(n), _block_work(blocks, blk_i, n, m, bw, nnz),
            np.empty((1, 1) if banded else (m, n)),
            np.empty(m), np.empty(m), np.empty(n), np.empty((1, 1) if banded else (m, n)),
            np.empty((1, 1) if banded else (m, m)),
            np.empty(4 * max(m, 1)), np.empty(pattern_size.py_func(m), dtype=np.int32),
            np.empty(m))


def _block_work(blocks, blk_i, n, m, bw, nnz):
    """Work arrays of ``blk_i = (block structure, Gen tree, expansion maps)`` (see ``_rhs``):
    ``((Mst, Jst, Wst, Sb, u, Pst, Minv, Li), Gen work (_gen_work), (the three kernels'
    distinct outputs))``; a path's ``(velocity kernel outputs, R, r, J, dq, -, -, -)`` in the
    first (``_path_velocity``)."""
    if blocks == PATH and blk_i[0][7].size > 1:
        # the projection's and the velocity system's sparse LU (each array for the larger),
        # and the vectors of _path_velocity_sparse in the rows of the fourth
        info = blk_i[0][0]
        N, nE = info[0], info[PATH_EXTRA + 8]
        L = max(N, nnz + m, nE)
        bw_ = (np.zeros(max(info[2], info[9])), np.zeros(max(info[5], info[12])),
               np.zeros(max(info[6], info[13])), np.zeros((6, L)), np.zeros(N), np.zeros(N),
               np.zeros(N), np.zeros(N))
    elif blocks == PATH:
        bw_ = (np.zeros(nnz + m), np.zeros(n), np.zeros(n), np.zeros((m, n)), np.zeros(n),
               np.zeros(1), np.zeros(1), np.zeros(1))
    elif blocks == NEWTON:
        info = blk_i[0][0]
        pieces = max(info[10], info[15], 0)
        bnd = blk_i[0][7]
        # the Jacobian dense, or (banded) its values, the pattern's, the band storage and
        # three vectors (_newton_accel_band)
        J = np.zeros((m, n)) if bnd.size <= 1 else np.zeros(
            (1, bnd[4] + bnd[3] + bnd[13] + 4 * (n + m)))
        bw_ = (np.zeros(1 + 2 * n + info[5] + pieces), np.zeros(m + nnz), np.zeros(m),
               J, np.zeros(max(info[3], 1)), np.zeros(max(info[4], 1)),
               np.zeros(2 * n + m), np.zeros(1 + n + m))
    elif blocks == SPARSE:
        info = blk_i[0][0]
        N = info[0]
        bw_ = (np.zeros(max(info[2], info[9])), np.zeros(max(info[5], info[12])),
               np.zeros(max(info[6], info[13])), np.zeros((1, N)), np.zeros(N), np.zeros(N),
               np.zeros(N), np.zeros(N))
    elif blocks == BLOCK:
        boff, roff, bsize = blk_i[0][1], blk_i[0][4], blk_i[0][6]
        big = bsize.max() if bsize.size else 1
        bw_ = (np.zeros(boff[-1]), np.zeros(roff[-1]), np.zeros(roff[-1]),
               np.zeros((m, bw + 1)), np.zeros(n + m), np.zeros(roff[-1]), np.zeros(boff[-1]),
               np.zeros(big * big))
    else:
        bw_ = (np.zeros(1), np.zeros(1), np.zeros(1), np.zeros((1, 1)), np.zeros(1), np.zeros(1),
               np.zeros(1), np.zeros(1))
    ex = blk_i[2]
    ph = (np.zeros(ex[0].max() + 1 if ex[0].size else 1),
          np.zeros(ex[1].max() + 1 if ex[1].size else 1),
          np.zeros(ex[2].max() + 1 if ex[2].size else 1))
    # (_gen_work's Python function: it is compiled for gen_points, not needed here)
    return bw_, _gen_work.py_func(blocks, blk_i[1], n, m), ph, _rows_work(blocks, blk_i, n, m)


def _rows_work(blocks, blk_i, n, m):
    """Work arrays of the velocity constraints (``ROLLING``; ``blk_i[3] = (info, expand)``,
    ``info = [the rows' kernel row (5), k, parameters]``): ``(xr, outr, phr, G, Gs, AG, rG,
    FsG, dqG, ybufG, workG, ipivG, iworkG, mu)``: the rows' kernel's arguments ``[t, q, qd,
    p]`` (and its Piecewise values), outputs ``[A, b, rho]`` and distinct outputs, the
    projection's ``_min_norm`` arrays for ``G = [Phi_q; A]`` ((m + k) rows) and the
    multipliers ``mu`` (k,). The other kinds: the same types, empty (``mu`` size 0)."""
    if blocks != ROLLING:
        z = np.zeros(0)
        return (np.zeros(1), np.zeros(1), np.zeros(1), np.zeros((1, 1)), np.zeros((1, 1)),
                np.zeros((1, 1)), np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1),
                np.zeros(4), np.zeros(1, dtype=np.int32), np.zeros(1, dtype=np.int32), z)
    info, ex = blk_i[3]
    k, npar = int(info[5]), int(info[6])
    g = m + k
    return (np.zeros(1 + 2 * n + npar + max(int(info[4]), 0)), np.zeros(k * n + 2 * k),
            np.zeros(ex.max() + 1 if ex.size else 1), np.zeros((g, n)), np.zeros((g, n)),
            np.zeros((g, g)), np.zeros(g), np.zeros(g), np.zeros(n), np.zeros(g),
            np.zeros(4 * max(g, 1)), np.zeros(max(g, 1), dtype=np.int32),
            np.zeros(pattern_size.py_func(g), dtype=np.int32), np.zeros(k))


@nb.njit(cache=True)
def _gen_work(blocks, gi, n, m):
    """Work arrays of the recursive Gen dynamics (the same as
    ``compile._generalized.RecursiveDynamics._workspace``, plus the main kernel's arguments
    and outputs, the mass matrix, the augmented matrix and ``F``, forces added on the
    coordinates: zeros in free motion, the joint forces of the robot entry points'
    :func:`gen_forward`): tiny unless ``blocks`` is ``GEN_TREE`` or ``GEN_AUGMENTED``."""
    sc = gi[9]
    nq, S, kmax, nin_j, nout_j, nin_g, nout_g = sc[0], sc[4], sc[5], sc[6], sc[7], sc[8], sc[9]
    if blocks < GEN_TREE:
        S = nq = kmax = nin_j = nout_j = nin_g = nout_g = 1
    width = max(nq, kmax)
    z = np.zeros
    NN = n + m if blocks == GEN_AUGMENTED else 1
    nM = n if blocks == GEN_AUGMENTED else 1
    return (z((S, nq)), z((S, nq)), z((S, nq, nq)), z((S, nq, kmax)), z((S, nq)), z((S, nq)),
            z((S, nq, nq)), z((S, nq)), z((S, nq, nq)), z((S, nq)), z((S, nq)), z((nq, width)),
            z((nq, width)), z((S, nq, kmax)), z((S, kmax, kmax)), z((kmax, nq + 1)),
            z((nq, nq + 1)), z((S, nq)), z(nin_j), z(nout_j), z(nin_g), z(nout_g), z(max(n, 1)),
            z(max(n, 1)), z(max(n, 1)), z((nM, nM)), z((NN, NN)), z(max(n, 1)))


@leaf
def _gen_forward_main(kp, x, nin, n, m, gi, gw, ex, ph, y):
    """The recursive Gen dynamics' evaluations at ``x = [t, q, qd, lambda, p, qdd]``, ``y =
    (q, qd)``: the joint kernels masters first (``forward``), then the kernel of the rest
    (``kp``: absolute bodies' mass entries, Jacobian, ``Q``, ``Qv``, ``gamma`` and the loads
    on the slaves' poses, with the slaves' poses and velocities as extra arguments) into
    ``og`` of ``gw``, the slaves' loads into ``Qp``. False: a value that is not finite."""
    ptrs, kid, par, root, nqm, goff, gcols, Mr, Mc, sc = gi
    (P, Pd, FP, Fg, H, HL, Mb, Qvb, C, BQ, BV, X, Y, U, L, Z, W, Qp, xj, oj, xg, og, Q, Qv, Qd,
     M, KT, F) = gw
    nq, kM, kJ, kg, S = sc[0], sc[1], sc[2], sc[3], sc[4]
    npar = nin - (1 + 3 * n + m)
    p0 = 1 + 2 * n + m
    _gen_forward(ptrs, kid, par, root, nqm, goff, gcols, nq, x[0], y[:n], y[n:2 * n],
                 x[p0:p0 + npar], xj, oj, P, Pd, FP, Fg, H, HL, Mb, Qvb)
    for i in range(nin):                 # [t, q, qd, lambda, p, qdd, P, Pd]
        xg[i] = x[i]
    for s in range(S):
        for i in range(nq):
            xg[nin + s * nq + i] = P[s, i]
            xg[nin + (S + s) * nq + i] = Pd[s, i]
    _evalx(kp, xg, nin + 2 * S * nq, og, ex, ph)
    for k in range(kM + kJ + 2 * n + kg + S * nq):
        if not np.isfinite(og[k]):
            return False
    oq = kM + kJ + 2 * n + kg
    for s in range(S):
        for i in range(nq):
            Qp[s, i] = og[oq + s * nq + i]
    return True


@leaf
def _gen_mass(gi, gw, n):
    """``M``, ``Q``, ``Qv`` of ``gw`` by the composite bodies (``_gen_assemble``) after
    :func:`_gen_forward_main`."""
    ptrs, kid, par, root, nqm, goff, gcols, Mr, Mc, sc = gi
    (P, Pd, FP, Fg, H, HL, Mb, Qvb, C, BQ, BV, X, Y, U, L, Z, W, Qp, xj, oj, xg, og, Q, Qv, Qd,
     M, KT, F) = gw
    nq, kM, kJ = sc[0], sc[1], sc[2]
    o = kM + kJ
    M[:, :] = 0.0
    for k in range(kM):
        M[Mr[k], Mc[k]] = og[k]
    for j in range(n):
        Q[j] = og[o + j]
        Qv[j] = og[o + n + j]
    _gen_assemble(par, root, nqm, goff, gcols, nq, FP, Fg, H, Mb, Qvb, Qp, C, BQ, BV, X, Y, M,
                  Q, Qv)


@nb.njit(cache=True, inline='always')
def _gen_augmented(gi, gw, n, m, jr, jc):
    r"""After :func:`_gen_forward_main`: the augmented system of free motion by the
    composite bodies (:func:`_gen_mass`), its matrix transposed in ``KT`` of ``gw``
    (:math:`[[M, \Phi_q^T], [\Phi_q, 0]]`) and its right-hand side :math:`[Q + Q_v + F;
    \gamma]` over ``og[o:o + n + m]``, ``o = kM + kJ`` (the Jacobian's values before it
    stay)."""
    ptrs, kid, par, root, nqm, goff, gcols, Mr, Mc, sc = gi
    (P, Pd, FP, Fg, H, HL, Mb, Qvb, C, BQ, BV, X, Y, U, L, Z, W, Qp, xj, oj, xg, og, Q, Qv, Qd,
     M, KT, F) = gw
    kM, kJ = sc[1], sc[2]
    o = kM + kJ
    _gen_mass(gi, gw, n)
    KT[:, :] = 0.0
    for i in range(n):                   # K transposed (M is symmetric only to rounding)
        for j in range(n):
            KT[j, i] = M[i, j]
    for k in range(jr.size):
        v = og[kM + k]
        KT[n + jr[k], jc[k]] = v
        KT[jc[k], n + jr[k]] = v
    # (Q, Qv are copied out of og by _gen_mass)
    for j in range(n):
        og[o + j] = (Q[j] + Qv[j]) + F[j]
    for i in range(m):
        og[o + n + i] = og[o + 2 * n + i]


@leaf
def _accel_gen(kp, lapack, x, nin, n, m, jr, jc, rows0, columns, robust, ipiv, ibuf, rhs, b,
               qdd, lam, force, gi, gw, ex, ph, tree, y):
    """Free acceleration of a system with recursive Gen dynamics
    (``compile._generalized.RecursiveDynamics``, decision 0016) at ``x = [t, q, qd, 0, p,
    0]``, ``y = (q, qd)``: :func:`_gen_forward_main`; ``tree``: ``qdd`` by the
    articulated-body recursion (no constraint equation), else the composite-body mass matrix
    in the augmented system (:func:`_gen_augmented`), solved as ``_accel`` does. False: hand
    over (a joint whose motion carries no mass, a singular or non-finite system)."""
    ptrs, kid, par, root, nqm, goff, gcols, Mr, Mc, sc = gi
    (P, Pd, FP, Fg, H, HL, Mb, Qvb, C, BQ, BV, X, Y, U, L, Z, W, Qp, xj, oj, xg, og, Q, Qv, Qd,
     M, KT, F) = gw
    nq, kM, kJ = sc[0], sc[1], sc[2]
    if not _gen_forward_main(kp, x, nin, n, m, gi, gw, ex, ph, y):
        return False
    o = kM + kJ
    if tree:
        for j in range(n):
            Qd[j] = og[o + j] + og[o + n + j]
        if _articulated(par, nqm, goff, gcols, nq, FP, Fg, HL, Mb, Qvb, Qp, Qd, og[:kM], Mr, Mc,
                        C, BQ, U, L, Z, W, qdd, 1e-13) >= 0:
            return False
        for j in range(n):
            if not np.isfinite(qdd[j]):
                return False
        return True
    _gen_augmented(gi, gw, n, m, jr, jc)
    return _solve_augmented(lapack, KT, og, o, og, kM, n, m, jr, jc, rows0, columns, robust,
                            ipiv, ibuf, rhs, b, qdd, lam, force)


@nb.njit(cache=True, inline='always')
def _gen_cholesky(gi, gw, n, qdd):
    r"""After :func:`_gen_forward_main` on a system without constraint equations:
    :math:`\ddot q = M^{-1} (Q + Q_v + F)` by the composite-body mass matrix
    (:func:`_gen_mass`) and its Cholesky factor (:func:`_band_chol` with the full band, the
    block path's; ``KT`` of ``gw`` holds it), as the Python path's
    ``analyses._robot._forward_free``. False: hand over (``M`` not positive definite: the
    Python path names the joints; a value that is not finite)."""
    ptrs, kid, par, root, nqm, goff, gcols, Mr, Mc, sc = gi
    (P, Pd, FP, Fg, H, HL, Mb, Qvb, C, BQ, BV, X, Y, U, L, Z, W, Qp, xj, oj, xg, og, Q, Qv, Qd,
     M, KT, F) = gw
    _gen_mass(gi, gw, n)
    for i in range(n):                   # the lower triangle, band storage Sb[i, i - j]
        for j in range(i + 1):
            if not np.isfinite(M[i, j]):
                return False
            KT[i, i - j] = M[i, j]
    if _band_chol(KT, n, n - 1) < 0.0:
        return False
    for j in range(n):
        qdd[j] = (Q[j] + Qv[j]) + F[j]
    _band_solve(KT, n, n - 1, qdd)
    for j in range(n):
        if not np.isfinite(qdd[j]):
            return False
    return True


@nb.njit(cache=True, inline='always')
def _gen_regular(gi, gw, n, m, jr, jc, lapack, ipiv, ibuf, cbuf, sol, qdd):
    """After :func:`_gen_forward_main`: ``qdd`` from the augmented system
    (:func:`_gen_augmented`) by LAPACK's ``dgetrf``/``dgetrs`` (SciPy's, the Python path's
    ``scipy.linalg.lu_factor``: the same factors) when its pivots are regular, the Python
    path's rule (``analyses._robot._solve_regular``: the smallest above ``1e-11`` times the
    largest). False: hand over (a redundant or singular system, which the Python path solves
    by least squares or diagnoses; a value that is not finite)."""
    kM, kJ = gi[9][1], gi[9][2]
    _gen_augmented(gi, gw, n, m, jr, jc)
    og, KT = gw[21], gw[26]
    o = kM + kJ
    N = n + m
    for i in range(N):
        v = og[o + i]
        if not np.isfinite(v):
            return False
        sol[i] = v
    for i in range(N):
        for j in range(N):
            if not np.isfinite(KT[i, j]):
                return False
    ibuf[0] = N          # m, n, lda = ldb, info, nrhs
    ibuf[1] = N
    ibuf[2] = N
    ibuf[3] = 0
    ibuf[4] = 1
    _ccall(lapack[0], (ibuf[0:1], ibuf[1:2], KT, ibuf[2:3], ipiv, ibuf[3:4]))
    if ibuf[3] != 0:
        return False
    lo = np.inf
    hi = 0.0
    for j in range(N):
        d = abs(KT[j, j])
        lo = min(lo, d)
        hi = max(hi, d)
    if not lo > 1e-11 * hi:
        return False
    cbuf[0] = 78         # 'N': no transpose
    _ccall(lapack[2], (cbuf[0:1], ibuf[1:2], ibuf[4:5], KT, ibuf[2:3], ipiv, sol, ibuf[2:3],
                       ibuf[3:4]))
    for j in range(n):
        if not np.isfinite(sol[j]):
            return False
        qdd[j] = sol[j]
    return True


#: the modes of :func:`gen_points`: the right-hand sides of the multiplier solves (static,
#: kinematic, dynamic), forward dynamics without and with constraint equations
STATIC_LOADS, KINEMATIC_LOADS, DYNAMIC_LOADS, FORWARD_FREE, FORWARD_AUGMENTED = 0, 1, 2, 3, 4


@nb.njit(cache=True, inline='always')
def _gen_loads_point(gi, gw, n, mode, X, R, k):
    """After :func:`_gen_forward_main`: ``R[k]`` = ``Q`` (``STATIC_LOADS``,
    ``KINEMATIC_LOADS``) or ``Q + Qv - M X[k]`` (``DYNAMIC_LOADS``) by the composite bodies.
    False: a value that is not finite."""
    M, Qg, Qv = gw[25], gw[22], gw[23]
    _gen_mass(gi, gw, n)
    for i in range(n):
        if mode == DYNAMIC_LOADS:
            s = 0.0
            for j in range(n):
                s += M[i, j] * X[k, j]
            R[k, i] = (Qg[i] + Qv[i]) - s
        else:
            R[k, i] = Qg[i]
        if not np.isfinite(R[k, i]):
            return False
    return True


@nb.njit(cache=True, inline='always')
def _gen_forward_point(gi, gw, n, m, jr, jc, lapack, ipiv, ibuf, cbuf, sol, qdd, mode, X, R,
                       k):
    """After :func:`_gen_forward_main`: ``R[k]`` the accelerations under the forces ``X[k]``
    on the coordinates, ``FORWARD_FREE`` by :func:`_gen_cholesky`, ``FORWARD_AUGMENTED`` by
    :func:`_gen_regular`. False: hand over to the Python path."""
    Ft = gw[27]
    for j in range(n):
        Ft[j] = X[k, j]
    if mode == FORWARD_FREE:
        if not _gen_cholesky(gi, gw, n, qdd):
            return False
    elif not _gen_regular(gi, gw, n, m, jr, jc, lapack, ipiv, ibuf, cbuf, sol, qdd):
        return False
    for j in range(n):
        R[k, j] = qdd[j]
    return True


@nb.njit(cache=True)
def gen_points(kp, gi, ex, lapack, times, Q, QD, X, p, m, jr, jc, mode, R):
    r"""Evaluations of a system with recursive Gen dynamics at each point ``k`` of the states
    ``Q``, ``QD`` (N, n), by the recursion as :func:`_accel_gen` evaluates it (the Python
    path's ``RecursiveDynamics.terms``), into ``R[k]`` (n,):

    * the right-hand sides of the multiplier solves (``_jit_multipliers``, over a solved
      sweep, ``X`` its accelerations): ``Q`` (``mode`` ``STATIC_LOADS``: velocities taken
      zero; ``KINEMATIC_LOADS``) or :math:`Q + Q_v - M \ddot q` (``DYNAMIC_LOADS``; the
      robot entry point ``m.inverse_dynamics`` too), :func:`_gen_loads_point`;
    * forward dynamics (the robot entry point ``m.forward_dynamics``),
      ``X[k]`` the forces on the coordinates and ``R[k]`` the accelerations of

      .. math:: M \ddot q + \Phi_q^T \lambda = Q + Q_v + X_k, \qquad
                \Phi_q \ddot q = \gamma

      ``FORWARD_FREE`` (no constraint equation) by the Cholesky factor of ``M``
      (:func:`_gen_cholesky`), ``FORWARD_AUGMENTED`` by LU of the augmented system with
      regular pivots (:func:`_gen_regular`; ``jr``, ``jc`` the Jacobian's nonzero
      positions, ``lapack`` SciPy's ``dgetrf``, ``dgecon``, ``dgetrs``:
      ``_jit_runtime.lapack``).

    One specialisation for every ``mode`` (the inverse and forward dynamics of a session
    share one compile); the helpers of each point are inlined (``inline='always'``: a
    separate compiled function would have LLVM optimise the recursion's code once more with
    each caller). Returns the first point left to the Python path (``len(times)``: all
    done): values not finite; in forward dynamics also a mass matrix that is not positive
    definite or pivots that are not regular (the Python path diagnoses)."""
    N = times.size
    n = Q.shape[1]
    npar = p.size
    nin = 1 + 3 * n + m + npar
    gw = _gen_work(GEN_AUGMENTED, gi, n, m)
    ph = np.zeros(ex.max() + 1 if ex.size else 1)
    x = np.zeros(nin)
    y = np.zeros(2 * n)
    qdd = np.zeros(n)
    ipiv = np.zeros(n + m, dtype=np.int32)
    ibuf = np.zeros(5, dtype=np.int32)
    cbuf = np.zeros(1, dtype=np.uint8)
    sol = np.zeros(n + m)
    for j in range(npar):
        x[1 + 2 * n + m + j] = p[j]
    for k in range(N):
        x[0] = times[k]
        for j in range(n):
            x[1 + j] = Q[k, j]
            y[j] = Q[k, j]
            v = QD[k, j] if mode >= KINEMATIC_LOADS else 0.0
            x[1 + n + j] = v
            y[n + j] = v
        if not _gen_forward_main(kp, x, nin, n, m, gi, gw, ex, ph, y):
            return k
        if mode >= FORWARD_FREE:
            if not _gen_forward_point(gi, gw, n, m, jr, jc, lapack, ipiv, ibuf, cbuf, sol, qdd,
                                      mode, X, R, k):
                return k
        elif not _gen_loads_point(gi, gw, n, mode, X, R, k):
            return k
    return N


# -- block path: M block-diagonal (one block per body), the Schur complement banded --------
#
# With M = diag(M_b) symmetric positive definite per block, the augmented system
#     M qdd + J^T lam = f,   J qdd = gamma
# is solved as  u = M^-1 f,  W = M^-1 J^T,  S = J W,  S lam = J u - gamma,  qdd = u - W lam.
# S is symmetric positive definite when J has full row rank; rows i, k of J couple in S only
# through a common block, so S is banded (bandwidth ``bw``, fixed per model: chains and trees
# in their natural order give a few). Cost per evaluation: linear in the number of bodies.
# ``blk``: int64 arrays packed by ``_jit_free._Blocks`` (see there).
#
# A singular block (a body in Euler parameters: M_b e = 0) is made regular by the rows of J
# on that block alone (its normalisation row 2 e^T among them), listed after the mass
# matrix's positions in ``mpos``:
#     M_b += w J_i^T J_i,   f_b += w J_i^T gamma_i,   w = 1 / sum_t J_it^2 / (M_b)_tt
# Since J_i qdd = gamma_i, the exact solution (qdd, lam) of the augmented system solves the
# changed one too, which is regular: the same solution, a different route (_regularise).
# The structure's rows may be in another order than the system's (``rptr[m + 1:]``: the
# system's row at each place; a spatial model's normalisation rows come last in the system):
# S is banded in the structure's order, and lam and gamma are taken through the order.


@leaf
def _regularise(Mst, out, kk, n, m, Jst, mpos, kM, rptr, rblk, roff, bstart, boff, bsize):
    """The singular blocks made regular (see above): for each row ``i = mpos[kM:]`` (on one
    block ``b`` only; in the structure's order), ``M_b += w J_i^T J_i`` in ``Mst`` and ``w
    J_i^T gamma_i`` added to the block's loads ``out[kk + bstart[b]:]``, with ``J_i`` its
    segment in ``Jst``. A row that is zero on the block adds nothing. False (hand over): a
    diagonal entry not positive."""
    for a in range(kM, mpos.size):
        i = mpos[a]
        gi = rptr[m + 1 + i] if rptr.size > m + 1 else i
        p = rptr[i]
        b = rblk[p]
        o, z, s0, c0 = boff[b], bsize[b], roff[p], bstart[b]
        d = 0.0
        for t in range(z):
            mt = Mst[o + t * z + t]
            if not mt > 0.0:
                return False
            d += Jst[s0 + t] * Jst[s0 + t] / mt
        if d == 0.0:
            continue
        w = 1.0 / d
        g = w * out[kk + n + gi]
        for t in range(z):
            jt = w * Jst[s0 + t]
            for v in range(z):
                Mst[o + t * z + v] += jt * Jst[s0 + v]
            out[kk + c0 + t] += Jst[s0 + t] * g
    return True


@leaf
def _chol_blocks(Mst, bstart, boff, nblk):
    """Cholesky (lower, in place) of every block of M; False if one is not positive definite."""
    for b in range(nblk):
        nb_ = bstart[b + 1] - bstart[b]
        o = boff[b]
        for i in range(nb_):
            for j in range(i + 1):
                s = Mst[o + i * nb_ + j]
                for k in range(j):
                    s -= Mst[o + i * nb_ + k] * Mst[o + j * nb_ + k]
                if i == j:
                    if not s > 0.0:
                        return False
                    Mst[o + i * nb_ + i] = np.sqrt(s)
                else:
                    Mst[o + i * nb_ + j] = s / Mst[o + j * nb_ + j]
    return True


@leaf
def _invert_blocks(Mst, Minv, bstart, boff, nblk, Li):
    """``Minv`` (packed like ``Mst``): every block's inverse ``L^-T L^-1`` from its Cholesky
    factor in ``Mst`` (``Li``: work, at least the largest block squared). The products with
    ``M^-1`` are then small matrix-vector products, without divisions."""
    for b in range(nblk):
        nb_ = bstart[b + 1] - bstart[b]
        o = boff[b]
        if nb_ == 3:               # planar bodies: written out (the general loops cost 4x)
            _invert3(Mst, Minv, o)
            continue
        for j in range(nb_):
            Li[j * nb_ + j] = 1.0 / Mst[o + j * nb_ + j]
        for j in range(nb_):
            for i in range(j + 1, nb_):
                s = 0.0
                for k in range(j, i):
                    s -= Mst[o + i * nb_ + k] * Li[k * nb_ + j]
                Li[i * nb_ + j] = s * Li[i * nb_ + i]
        for i in range(nb_):
            for j in range(i + 1):
                s = 0.0
                for k in range(i, nb_):
                    s += Li[k * nb_ + i] * Li[k * nb_ + j]
                Minv[o + i * nb_ + j] = s
                Minv[o + j * nb_ + i] = s


@leaf
def _invert3(Mst, Minv, o):
    """``_invert_blocks`` for one 3 x 3 block at ``o``."""
    a = 1.0 / Mst[o]
    d = 1.0 / Mst[o + 4]
    f = 1.0 / Mst[o + 8]
    b = -Mst[o + 3] * a * d                              # L^-1 = [[a, 0, 0], [b, d, 0], [c, e, f]]
    e = -Mst[o + 7] * d * f
    c = -(Mst[o + 6] * a + Mst[o + 7] * b) * f
    Minv[o] = a * a + b * b + c * c                     # (L^-1)^T L^-1
    Minv[o + 1] = Minv[o + 3] = b * d + c * e
    Minv[o + 2] = Minv[o + 6] = c * f
    Minv[o + 4] = d * d + e * e
    Minv[o + 5] = Minv[o + 7] = e * f
    Minv[o + 8] = f * f


@leaf
def _block_mul(Minv, o, nb_, src, soff, dst, doff):
    """``dst[doff:doff + nb_] = M_b^-1 src[soff:soff + nb_]``."""
    if nb_ == 3:
        x0 = src[soff]
        x1 = src[soff + 1]
        x2 = src[soff + 2]
        dst[doff] = Minv[o] * x0 + Minv[o + 1] * x1 + Minv[o + 2] * x2
        dst[doff + 1] = Minv[o + 3] * x0 + Minv[o + 4] * x1 + Minv[o + 5] * x2
        dst[doff + 2] = Minv[o + 6] * x0 + Minv[o + 7] * x1 + Minv[o + 8] * x2
        return
    for i in range(nb_):
        s = 0.0
        for k in range(nb_):
            s += Minv[o + i * nb_ + k] * src[soff + k]
        dst[doff + i] = s


@leaf
def _band_chol(Sb, m, bw):
    """Banded Cholesky in place: ``Sb[i, d] = S[i, i - d]``; returns the smallest ratio
    ``L_ii / max L_jj`` (a cheap, optimistic conditioning measure), -1 if not positive
    definite."""
    for i in range(m):
        j0 = max(0, i - bw)
        for j in range(j0, i + 1):
            s = Sb[i, i - j]
            k0 = max(j0, j - bw)
            for k in range(k0, j):
                s -= Sb[i, i - k] * Sb[j, j - k]
            if j == i:
                if not s > 0.0:
                    return -1.0
                Sb[i, 0] = np.sqrt(s)
            else:
                Sb[i, i - j] = s / Sb[j, 0]
    lo = np.inf
    hi = 0.0
    for i in range(m):
        v = Sb[i, 0]
        lo = min(lo, v)
        hi = max(hi, v)
    return lo / hi if hi > 0 else -1.0


@leaf
def _band_solve(Sb, m, bw, x):
    for i in range(m):
        s = x[i]
        for k in range(max(0, i - bw), i):
            s -= Sb[i, i - k] * x[k]
        x[i] = s / Sb[i, 0]
    for i in range(m - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, min(m, i + bw + 1)):
            s -= Sb[k, k - i] * x[k]
        x[i] = s / Sb[i, 0]


@leaf
def _fill_rows(vals, j0, jpos, Jst, scale_rows, r, columns, jc, jr):
    """Per (row, block) segments of ``J`` (or of ``R^-1 J D`` with ``scale_rows``)."""
    Jst[:] = 0.0
    for k in range(jpos.size):
        v = vals[j0 + k]
        if scale_rows:
            v = (v * columns[jc[k]]) * (1.0 / r[jr[k]])
        Jst[jpos[k]] = v


@leaf
def _gram(A_st, B_st, segs, bsize, Sb):
    r"""``Sb`` (banded) of ``A B^T`` from per-(row, block) segments: rows couple through a
    common block only. ``segs`` (k, 3): row, segment offset and block of every segment,
    ordered by block and then row (``_Blocks``); each block adds, for every pair of its rows
    ``k <= i``, :math:`S_{ik} \mathrel{+}= A_{i,b} \cdot B_{k,b}` at band offset ``i - k``.
    An entry that several blocks couple receives their products in the order of the blocks,
    the order of the row's own segments."""
    Sb[:, :] = 0.0
    first = 0
    for a in range(segs.shape[0]):
        b = segs[a, 2]
        if a > 0 and b != segs[a - 1, 2]:
            first = a
        i = segs[a, 0]
        oi = segs[a, 1]
        z = bsize[b]
        for c in range(first, a + 1):
            ok = segs[c, 1]
            s = 0.0
            for t in range(z):
                s += A_st[oi + t] * B_st[ok + t]
            Sb[i, i - segs[c, 0]] += s


@leaf
def _accel_blocks(kp, x, nin, out, kk, kM, n, m, jr, jc, rows0, columns, robust, blk_i,
                  Mst, Jst, Wst, Sb, u, Minv, Li, qdd, lam, force, ex, ph):
    """``_accel`` by the block path (see above); False: hand over."""
    bstart, boff, rptr, rblk, roff, jpos, bsize, mpos, segs = blk_i
    nblk = bsize.size
    bw = Sb.shape[1] - 1
    _evalx(kp, x, nin, out, ex, ph)
    if not _all_finite(out, kk + n + m):
        return False
    Mst[:] = 0.0
    for k in range(kM):
        Mst[mpos[k]] = out[k]
    big_rhs = 0.0
    for j in range(n):
        big_rhs = max(big_rhs, abs(out[kk + j]))
    for i in range(m):
        big_rhs = max(big_rhs, abs(out[kk + n + i]))
    _fill_rows(out, kM, jpos, Jst, False, lam, columns, jc, jr)
    if mpos.size > kM and not _regularise(Mst, out, kk, n, m, Jst, mpos, kM, rptr, rblk,
                                          roff, bstart, boff, bsize):
        return False
    if not _chol_blocks(Mst, bstart, boff, nblk):
        return False
    _invert_blocks(Mst, Minv, bstart, boff, nblk, Li)
    for b in range(nblk):
        _block_mul(Minv, boff[b], bsize[b], out, kk + bstart[b], u, bstart[b])
    for i in range(m):                       # W = M^-1 J^T, segment by segment
        for p in range(rptr[i], rptr[i + 1]):
            b = rblk[p]
            _block_mul(Minv, boff[b], bsize[b], Jst, roff[p], Wst, roff[p])
    _gram(Jst, Wst, segs, bsize, Sb)
    for i in range(m):
        lam[i] = -out[kk + n + i]
    for k in range(jr.size):
        lam[jr[k]] += out[kM + k] * u[jc[k]]
    if _band_chol(Sb, m, bw) < 0:
        return False
    ordered = rptr.size > m + 1
    sol = lam
    if ordered:                      # the right-hand side in the structure's order
        sol = u[n:n + m]
        for i in range(m):
            sol[i] = lam[rptr[m + 1 + i]]
    _band_solve(Sb, m, bw, sol)
    for j in range(n):
        qdd[j] = u[j]
    for i in range(m):
        for p in range(rptr[i], rptr[i + 1]):
            b = rblk[p]
            o = bstart[b]
            for t in range(bsize[b]):
                qdd[o + t] -= Wst[roff[p] + t] * sol[i]
    if ordered:
        for i in range(m):
            lam[rptr[m + 1 + i]] = sol[i]
    if not (_bounded(qdd, n, big_rhs) and _bounded(lam, m, big_rhs)):
        return False
    return not robust or _zone_ok(rows0, lam, out, kM, jr, jc, columns, force)


@leaf
def _min_norm_blocks(vals, j0, jr, jc, columns, m, n, bvec, r, blk_i, Pst, Sb, robust, dq):
    """``_min_norm`` by the block path: ``A = J^ J^T`` banded (rows couple through common
    blocks), banded Cholesky; ``dq = D J^T A^-1 bvec``. False (hand over) when ``A`` is not
    positive definite or, ``robust``, when its Cholesky diagonal spreads by more than
    ``sqrt(ZONE)`` (an optimistic stand-in for the Python path's condition estimate: the
    hand-over comes before the zone of a singular Jacobian). ``bvec`` is overwritten."""
    bstart, boff, rptr, rblk, roff, jpos, bsize, mpos, segs = blk_i
    bw = Sb.shape[1] - 1
    _fill_rows(vals, j0, jpos, Pst, True, r, columns, jc, jr)
    _gram(Pst, Pst, segs, bsize, Sb)
    ratio = _band_chol(Sb, m, bw)
    if ratio < 0 or (robust and ratio * ratio < ZONE):
        return False
    y = bvec                      # (overwritten: the callers compute it again before use)
    if rptr.size > m + 1:         # in the structure's row order (dq: free until below)
        for i in range(m):
            dq[i] = y[rptr[m + 1 + i]]
        for i in range(m):
            y[i] = dq[i]
    _band_solve(Sb, m, bw, y)
    for j in range(n):
        dq[j] = 0.0
    for i in range(m):
        for p in range(rptr[i], rptr[i + 1]):
            b = rblk[p]
            o = bstart[b]
            for t in range(bsize[b]):
                dq[o + t] += Pst[roff[p] + t] * y[i]
    for j in range(n):
        dq[j] = columns[j] * dq[j]
    return True


@leaf
def _project_blocks(pp, pv, xk, nin_k, out_pos, out_vel, jr, jc, columns, offset, tol, maxit,
                    robust, n, m, t, y, r, Fs, dq, blk_i, Pst, Sb, ex, ph):
    """``_project`` by the block path."""
    xk[0] = t
    for j in range(n):
        xk[1 + n + j] = 0.0
    lim = tol * (1.0 + offset)
    for _ in range(maxit):
        for j in range(n):
            xk[1 + j] = y[j]
        _evalx(pp, xk, nin_k, out_pos, ex[1], ph[1])
        _rows_nz(out_pos[m:], jr, jc, columns, r)
        if _position_residual(out_pos, r, Fs, m) <= lim:
            break
        if not _min_norm_blocks(out_pos, m, jr, jc, columns, m, n, Fs, r, blk_i, Pst, Sb,
                                robust, dq):
            return False
        for j in range(n):
            y[j] -= dq[j]
    for j in range(n):
        xk[1 + j] = y[j]
    _evalx(pv, xk, nin_k, out_vel, ex[2], ph[2])
    nnz = jr.size
    _rows_nz(out_vel, jr, jc, columns, r)
    for i in range(m):
        Fs[i] = out_vel[nnz + i]          # J qd - (-Phi_t), accumulated below
    for k in range(nnz):
        Fs[jr[k]] += out_vel[k] * y[n + jc[k]]
    for i in range(m):
        Fs[i] = Fs[i] / r[i]
    if not _min_norm_blocks(out_vel, 0, jr, jc, columns, m, n, Fs, r, blk_i, Pst, Sb, robust,
                            dq):
        return False
    for j in range(n):
        y[n + j] = y[n + j] - dq[j]
    return _all_finite(y, 2 * n)
