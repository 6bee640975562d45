r"""The numeric tree recursions of the recursive Gen dynamics (decision 0016:
``compile._generalized.RecursiveDynamics``) as plain loops over arrays: run by Python when
Numba is missing, compiled by Numba (``_jit_tree.py``) otherwise, the same operations in the
same order. They live in the solver layer so that the compiled free-motion stepper
(``_jit_free_loop.py``, decision 0018) can compile them into its loop."""

from __future__ import annotations

import numpy as np


def _fill(x, s, t, q, qd, p, par, root, nqm, goff, gcols, P, Pd):
    """A joint kernel's arguments ``[t, P_master, Pd_master, g, gd, p]``."""
    x[0] = t
    nm = nqm[s]
    a = par[s]
    r = root[s]
    for i in range(nm):
        if a >= 0:
            x[1 + i] = P[a, i]
            x[1 + nm + i] = Pd[a, i]
        else:
            x[1 + i] = q[r + i]
            x[1 + nm + i] = qd[r + i]
    o = 1 + 2 * nm
    g0 = goff[s]
    k = goff[s + 1] - g0
    for j in range(k):
        x[o + j] = q[gcols[g0 + j]]
        x[o + k + j] = qd[gcols[g0 + j]]
    o += 2 * k
    for i in range(p.size):
        x[o + i] = p[i]


def _unpack(out, s, nq, nm, k, par, P, Pd, FP, Fg, H, HL, Mb, Qvb):
    """Store a joint kernel's outputs; ``h_s = F_P h_master + h_loc``."""
    for i in range(nq):
        P[s, i] = out[i]
        Pd[s, i] = out[nq + i]
    o = 2 * nq
    for i in range(nq):
        for j in range(nm):
            FP[s, i, j] = out[o + i * nm + j]
    o += nq * nm
    for i in range(nq):
        for j in range(k):
            Fg[s, i, j] = out[o + i * k + j]
    o += nq * k
    a = par[s]
    for i in range(nq):
        h = out[o + i]
        HL[s, i] = h
        if a >= 0:
            for j in range(nm):
                h += FP[s, i, j] * H[a, j]
        H[s, i] = h
    o += nq
    for i in range(nq):
        for j in range(nq):
            Mb[s, i, j] = out[o + i * nq + j]
    o += nq * nq
    for i in range(nq):
        Qvb[s, i] = out[o + i]


def _forward_py(kernels, kid, par, root, nqm, goff, gcols, nq, t, q, qd, p, P, Pd, FP, Fg, H,
                HL, Mb, Qvb):
    for s in range(len(kid)):
        nm = nqm[s]
        k = goff[s + 1] - goff[s]
        x = np.empty(1 + 2 * nm + 2 * k + p.size)
        _fill(x, s, t, q, qd, p, par, root, nqm, goff, gcols, P, Pd)
        _unpack(kernels[kid[s]](x), s, nq, nm, k, par, P, Pd, FP, Fg, H, HL, Mb, Qvb)


def _assemble(par, root, nqm, goff, gcols, nq, FP, Fg, H, Mb, Qvb, Qp, C, BQ, BV, X, Y, M, Q, Qv):
    """Add the slaves' terms to ``M``, ``Q``, ``Qv`` (in place): composite inertias ``C`` and
    forces ``BQ`` (applied), ``BV`` (velocity) backward, then the mass-matrix columns of
    each slave's coordinates by the walk to the root."""
    S = par.size
    for s in range(S):
        for i in range(nq):
            BQ[s, i] = Qp[s, i]
            v = Qvb[s, i]
            for j in range(nq):
                v -= Mb[s, i, j] * H[s, j]
            BV[s, i] = v
            for j in range(nq):
                C[s, i, j] = Mb[s, i, j]
    for s in range(S - 1, -1, -1):
        g0 = goff[s]
        for jj in range(goff[s + 1] - g0):
            col = gcols[g0 + jj]
            fq = 0.0
            fv = 0.0
            for i in range(nq):
                fq += Fg[s, i, jj] * BQ[s, i]
                fv += Fg[s, i, jj] * BV[s, i]
            Q[col] += fq
            Qv[col] += fv
        nm = nqm[s]
        if nm == 0:
            continue
        a = par[s]
        r = root[s]
        for i in range(nq):
            for j in range(nm):
                v = 0.0
                for l in range(nq):  # noqa: E741
                    v += C[s, i, l] * FP[s, l, j]
                Y[i, j] = v
        for i in range(nm):
            bq = 0.0
            bv = 0.0
            for l in range(nq):  # noqa: E741
                bq += FP[s, l, i] * BQ[s, l]
                bv += FP[s, l, i] * BV[s, l]
            if a >= 0:
                BQ[a, i] += bq
                BV[a, i] += bv
            else:
                Q[r + i] += bq
                Qv[r + i] += bv
            for j in range(nm):
                v = 0.0
                for l in range(nq):  # noqa: E741
                    v += FP[s, l, i] * Y[l, j]
                if a >= 0:
                    C[a, i, j] += v
                else:
                    M[r + i, r + j] += v
    for s in range(S):
        g0 = goff[s]
        k = goff[s + 1] - g0
        for i in range(nq):
            for jj in range(k):
                v = 0.0
                for l in range(nq):  # noqa: E741
                    v += C[s, i, l] * Fg[s, l, jj]
                X[i, jj] = v
        for ii in range(k):
            for jj in range(k):
                v = 0.0
                for l in range(nq):  # noqa: E741
                    v += Fg[s, l, ii] * X[l, jj]
                M[gcols[g0 + ii], gcols[g0 + jj]] += v
        a = s
        while nqm[a] > 0:
            nm = nqm[a]
            for i in range(nm):
                for jj in range(k):
                    v = 0.0
                    for l in range(nq):  # noqa: E741
                        v += FP[a, l, i] * X[l, jj]
                    Y[i, jj] = v
            for i in range(nm):
                for jj in range(k):
                    X[i, jj] = Y[i, jj]
            b = par[a]
            if b >= 0:
                b0 = goff[b]
                for ii in range(goff[b + 1] - b0):
                    for jj in range(k):
                        v = 0.0
                        for l in range(nq):  # noqa: E741
                            v += Fg[b, l, ii] * X[l, jj]
                        M[gcols[b0 + ii], gcols[g0 + jj]] += v
                        M[gcols[g0 + jj], gcols[b0 + ii]] += v
                a = b
            else:
                r = root[a]
                for i in range(nm):
                    for jj in range(k):
                        M[r + i, gcols[g0 + jj]] += X[i, jj]
                        M[gcols[g0 + jj], r + i] += X[i, jj]
                break


def _articulated(par, nqm, goff, gcols, nq, FP, Fg, HL, Mb, Qvb, Qp, Qd, Av, Ar, Ac, IA, PA, U,
                 L, Z, W, qdd, tol):
    r"""Free accelerations of a tree of slaves on ground with no constraint equations, in
    O(N): the articulated-body algorithm in pose coordinates. Backward, with ``IA_s``,
    ``PA_s`` the subtree's articulated inertia and force on the slave's pose (leaf: ``M_s``,
    ``Qv_s + Q_s``), ``U = IA F_g``, ``D = F_g^T U + A_s`` (Cholesky ``L``), ``Qd`` the forces
    applied to the coordinates themselves, ``A_s`` the inertia added on the joint's own
    coordinates (an armature: the entries ``Av[e]`` at ``(Ar[e], Ac[e])`` of the mass matrix
    that fall within the joint's coordinates; the caller sends entries across joints to the
    full system)::

        Ia = IA - U D^-1 U^T,   pa = PA - U D^-1 (F_g^T PA + Qd_g)
        IA_master += F_P^T Ia F_P,   PA_master += F_P^T (pa - Ia h_loc)

    forward, masters first (``pdd`` of ground = 0)::

        w = F_P pdd_master + h_loc,   g_dd = D^-1 (F_g^T PA + Qd_g - U^T w),   pdd = w + F_g g_dd

    Writes ``qdd``; returns -1, or the index of the slave whose ``D`` is not positive
    definite (no mass on that joint's motion: the caller falls back to the full system)."""
    S = par.size
    for s in range(S):
        for i in range(nq):
            PA[s, i] = Qvb[s, i] + Qp[s, i]
            for j in range(nq):
                IA[s, i, j] = Mb[s, i, j]
    for s in range(S - 1, -1, -1):
        g0 = goff[s]
        k = goff[s + 1] - g0
        big = 0.0
        for i in range(nq):
            big = max(big, abs(IA[s, i, i]))
        for i in range(nq):
            for jj in range(k):
                v = 0.0
                for l in range(nq):  # noqa: E741
                    v += IA[s, i, l] * Fg[s, l, jj]
                U[s, i, jj] = v
        for ii in range(k):      # Cholesky of D = Fg^T U, lower triangle in L
            for jj in range(ii + 1):
                v = 0.0
                for l in range(nq):  # noqa: E741
                    v += Fg[s, l, ii] * U[s, l, jj]
                ci, cj = gcols[g0 + ii], gcols[g0 + jj]
                for e in range(Av.size):
                    if Ar[e] == ci and Ac[e] == cj:
                        v += Av[e]
                for r in range(jj):
                    v -= L[s, ii, r] * L[s, jj, r]
                if ii == jj:
                    if not v > tol * big:
                        return s
                    L[s, ii, ii] = np.sqrt(v)
                else:
                    L[s, ii, jj] = v / L[s, jj, jj]
        nm = nqm[s]
        if nm == 0:
            continue
        a = par[s]
        # Z = D^-1 [U^T | Fg^T PA]  (k x (nq + 1)): forward and back substitution
        for c in range(nq + 1):
            for ii in range(k):
                if c < nq:
                    v = U[s, c, ii]
                else:
                    v = Qd[gcols[g0 + ii]]
                    for l in range(nq):  # noqa: E741
                        v += Fg[s, l, ii] * PA[s, l]
                for r in range(ii):
                    v -= L[s, ii, r] * Z[r, c]
                Z[ii, c] = v / L[s, ii, ii]
            for ii in range(k - 1, -1, -1):
                v = Z[ii, c]
                for r in range(ii + 1, k):
                    v -= L[s, r, ii] * Z[r, c]
                Z[ii, c] = v / L[s, ii, ii]
        # W[:, :nq] = Ia, W[:, nq] = pa - Ia h_loc
        for i in range(nq):
            for j in range(nq):
                v = IA[s, i, j]
                for ii in range(k):
                    v -= U[s, i, ii] * Z[ii, j]
                W[i, j] = v
            v = PA[s, i]
            for ii in range(k):
                v -= U[s, i, ii] * Z[ii, nq]
            for j in range(nq):
                v -= W[i, j] * HL[s, j]
            W[i, nq] = v
        for i in range(nm):
            v = 0.0
            for l in range(nq):  # noqa: E741
                v += FP[s, l, i] * W[l, nq]
            PA[a, i] += v
            for j in range(nm):
                v = 0.0
                for l in range(nq):  # noqa: E741
                    for r in range(nq):
                        v += FP[s, l, i] * W[l, r] * FP[s, r, j]
                IA[a, i, j] += v
    for s in range(S):
        g0 = goff[s]
        k = goff[s + 1] - g0
        nm = nqm[s]
        a = par[s]
        for i in range(nq):           # w, kept in W[:, 0]
            v = HL[s, i]
            for j in range(nm):
                v += FP[s, i, j] * PA[a, j]
            W[i, 0] = v
        for ii in range(k):
            v = Qd[gcols[g0 + ii]]
            for l in range(nq):  # noqa: E741
                v += Fg[s, l, ii] * PA[s, l] - U[s, l, ii] * W[l, 0]
            for r in range(ii):
                v -= L[s, ii, r] * Z[r, 0]
            Z[ii, 0] = v / L[s, ii, ii]
        for ii in range(k - 1, -1, -1):
            v = Z[ii, 0]
            for r in range(ii + 1, k):
                v -= L[s, r, ii] * Z[r, 0]
            Z[ii, 0] = v / L[s, ii, ii]
            qdd[gcols[g0 + ii]] = Z[ii, 0]
        for i in range(nq):           # pdd of this slave, in PA (no longer needed)
            v = W[i, 0]
            for ii in range(k):
                v += Fg[s, i, ii] * Z[ii, 0]
            PA[s, i] = v
    return -1
