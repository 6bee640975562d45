"""Numba code of the compiled kinematic sweep (imported only when it runs: see ``_jit_sweep.py``).

Every function mirrors one piece of the Python path, in the same order of floating-point
operations, so that both give the same numbers (the factorisations and solves it calls:
``_jit_linalg``; the kernels: ``_jit_calls``):

* ``_scaling``       ``Scaling.of`` at the guess (from the loop's first evaluation)
* the Newton step  ``solve_position`` with a given scaling and the previous point's
                     velocity factorisation as its chord (kept in ``B``, ``ipiv``, ``nz``
                     with its row scales ``rprev``)
* ``_predict``       ``_kinematics._predict``
* ``fill_rconds``    the condition estimates the loop proved regular and left for later
                     (``SweepResult.rcond``, decision 0023)
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ._jit_cache import check as _check_cache
from ._jit_calls import _eval_row
from ._jit_lapack import leaf
from ._jit_linalg import (
    _assemble,
    _band_rows,
    _band_values,
    _big_work,
    _factor,
    _factor_filled,
    _factor_work,
    _fill,
    _fill_nz,
    _no_structure,
    _rows,
    _rows_nz,
    _scaled_norm,
    _solve,
    _sparse_factor,
    _sparse_solve_scaled,
    _structure,
    _unique,
)
from ._jit_modes import within
from ._tolerances import (
    ARM_ROUNDOFF,
    CHORD_RATE,
    RCOND_MIN,
    RCOND_PENDING,
    RCOND_WARN,
    ROTATION_JUMP,
    ROTATION_SLACK,
    ROTATION_START,
)

_check_cache()   # stale cached loops go before anything here compiles (see _jit_cache)


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


@leaf
def _trial(ptrs, x, nin, out_pos, q, a, dq, qn, r, m):
    r"""The trial point of a step of :func:`sweep_dense`'s position solve, ``qn = q + a dq``
    (also the position kernel's ``q`` in ``x``), the kernel there (its residual and
    Jacobian values in ``out_pos``) and the residual's scaled max-norm, the measure the
    steps compare (``_jit_linalg._scaled_norm``):

    .. math::  q_n = q + a\,\delta q, \qquad
               \lVert R^{-1} \Phi(q_n) \rVert_\infty = \max_i |\Phi_i(q_n) / r_i|

    ``dq`` solves ``B dq = F``: the chord and polish steps take ``a = -1`` (``-1 * dq`` is
    ``-dq`` exactly), the damped Newton step ``dq`` negated and ``a`` its damping (1, 1/2,
    ...)."""
    for j in range(q.size):
        qn[j] = q[j] + a * dq[j]
        x[1 + j] = qn[j]
    _eval_row(ptrs, 0, x, nin, out_pos)
    return _scaled_norm(out_pos, r, m)


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
        S, W, seen = _no_structure()
    else:
        S, W, seen = _structure(jr, jc, n)
    AB, SI, data, tmp = _big_work(bw, n, si0, cr.size)
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
                anorm = _fill_nz(out_vel, jr, jc, r, columns, B, S)
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
                    # (its solve is the chord step's below, written twice on purpose: a
                    # shared helper for the solve, inlined by Numba, made the sweep 7-9 %
                    # slower, measured; the trial point's evaluation is _trial)
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
                    nn = _trial(ptrs, x, nin, out_pos, q, -1.0, dq, qn, r, m)
                    e += 1
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
                nn = _trial(ptrs, x, nin, out_pos, q, -1.0, dq, qn, r, m)
                e += 1
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
                if unique:
                    # B straight from the values, as the velocity's (the same entries as
                    # _fill of the assembled J: no n x n pass, decision 0078)
                    anorm = _fill_nz(jv, jr, jc, r, columns, B, S)
                    if _factor_filled(lapack, B, anorm, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf,
                                      work, iwork, RCOND_MIN) < 0:
                        break
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
                nn = _trial(ptrs, x, nin, out_pos, q, a, dq, qn, r, m)
                e += 1
                if not damping or nn <= (1 - 1e-4 * a) * norm or a < 1e-3 or norm <= tol:
                    break
                a *= 0.5
            for j in range(n):
                q[j] = qn[j]
            for i in range(m):
                F[i] = out_pos[i]
            if large or unique:                  # (a Newton step: J's values are current)
                for i in range(nnz):
                    jv[i] = out_pos[m + i]
                stale = True
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
                    anorm = _fill_nz(out_vel, jr, jc, r, columns, B, S)
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
            anorm = _fill_nz(out_vel, jr, jc, r, columns, B, S)
        else:
            _assemble(out_vel, 0, jr, jc, J)
            anorm = _fill(J, r, columns, B)
        rc = _factor_filled(lapack, B, anorm, ipiv, nz, S, W, seen, ibuf, cbuf, dbuf, work, iwork,
                            0.0)
        if rc < 0:
            bad += 1
        rconds[k] = rc
    return bad


__all__ = ["fill_rconds", "sweep_dense"]
