"""Small dense LU in Numba for the compiled loops: LAPACK's algorithms without the call.

For the 5-30 unknowns of a mechanism's Jacobian a call of SciPy's LAPACK through its C
address costs about 0.7 µs of overhead, more than the arithmetic; a sweep point makes
about ten such calls. These functions perform the same algorithms as the routines the
Python path calls (``scipy.linalg.lapack``):

* ``getrf``  ``dgetrf``: Gaussian elimination with partial pivoting (first largest pivot),
  unit lower ``L`` and upper ``U`` in place, ``info > 0`` at an exactly zero pivot;
* ``getrs``  ``dgetrs`` with ``trans = 'N'``: row interchanges, then the two triangular solves;
* ``gecon1`` ``dgecon`` with ``norm = '1'``: Higham's refinement of Hager's estimator of
  ``||A^-1||_1`` (LAPACK ``dlacn2``: at most five iterations, then the alternating-sign
  test vector) with the triangular solves of ``dlatrs`` in its unscaled case (``dtrsv``).

The loops sum in their own order, so the results agree with LAPACK's to rounding (the
condition estimate takes the same decisions, hence the same value up to rounding).
Matrices are stored transposed in C order (column-major order of the matrix): entry
``A(i, j)`` is ``AT[j, i]``.
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True)
def getrf(AT, n, piv):
    """LU of ``A`` (n, n) in place; ``piv[j]``: the row swapped with row ``j`` (0-based).
    Returns LAPACK's ``info``: 0, or ``j + 1`` for the first exactly zero pivot."""
    info = 0
    for j in range(n):
        p = j
        big = abs(AT[j, j])
        for i in range(j + 1, n):
            v = abs(AT[j, i])
            if v > big:
                big = v
                p = i
        piv[j] = p
        if AT[j, p] != 0.0:
            if p != j:
                for c in range(n):
                    tmp = AT[c, j]
                    AT[c, j] = AT[c, p]
                    AT[c, p] = tmp
            inv = 1.0 / AT[j, j]
            for i in range(j + 1, n):
                AT[j, i] *= inv
        elif info == 0:
            info = j + 1
        for c in range(j + 1, n):
            a = AT[c, j]
            if a != 0.0:
                for i in range(j + 1, n):
                    AT[c, i] -= AT[j, i] * a
    return info


@nb.njit(cache=True)
def getrs(AT, n, piv, x):
    """``x <- A^-1 x`` from :func:`getrf`'s factors."""
    for j in range(n):
        p = piv[j]
        if p != j:
            tmp = x[j]
            x[j] = x[p]
            x[p] = tmp
    _lower(AT, n, x)
    _upper(AT, n, x)


@nb.njit(cache=True)
def _lower(AT, n, x):            # L x = b, L unit lower (dtrsv 'L', 'N', 'U')
    for j in range(n):
        xj = x[j]
        if xj != 0.0:
            for i in range(j + 1, n):
                x[i] -= xj * AT[j, i]


@nb.njit(cache=True)
def _upper(AT, n, x):            # U x = b (dtrsv 'U', 'N', 'N')
    for j in range(n - 1, -1, -1):
        if x[j] != 0.0:
            x[j] /= AT[j, j]
            xj = x[j]
            for i in range(j):
                x[i] -= xj * AT[j, i]


@nb.njit(cache=True)
def _upper_t(AT, n, x):          # U^T x = b (dtrsv 'U', 'T', 'N')
    for j in range(n):
        s = x[j]
        for i in range(j):
            s -= AT[j, i] * x[i]
        x[j] = s / AT[j, j]


@nb.njit(cache=True)
def _lower_t(AT, n, x):          # L^T x = b (dtrsv 'L', 'T', 'U')
    for j in range(n - 1, -1, -1):
        s = x[j]
        for i in range(j + 1, n):
            s -= AT[j, i] * x[i]
        x[j] = s


@nb.njit(cache=True)
def _inv(AT, n, x, transposed):
    """``x <- A^-1 x`` (``transposed``: ``A^-T x``) without the row interchanges, as
    ``dgecon`` applies them: the estimate concerns ``U^-1 L^-1``."""
    if transposed:
        _upper_t(AT, n, x)
        _lower_t(AT, n, x)
    else:
        _lower(AT, n, x)
        _upper(AT, n, x)


@nb.njit(cache=True)
def _asum(x, n):
    s = 0.0
    for i in range(n):
        s += abs(x[i])
    return s


@nb.njit(cache=True)
def _iamax(x, n):
    k = 0
    big = abs(x[0])
    for i in range(1, n):
        v = abs(x[i])
        if v > big:
            big = v
            k = i
    return k


@nb.njit(cache=True)
def gecon1(AT, n, anorm, x, isgn):
    """LAPACK ``dgecon`` (one-norm) on :func:`getrf`'s factors: the reciprocal condition
    estimate ``1 / (||A||_1 est(||A^-1||_1))``. ``x`` (n,), ``isgn`` (n,): work arrays."""
    if n == 0:
        return 1.0
    if anorm == 0.0:
        return 0.0
    for i in range(n):
        x[i] = 1.0 / n
    _inv(AT, n, x, False)
    if n == 1:
        est = abs(x[0])
    else:
        est = _asum(x, n)
        for i in range(n):
            x[i] = 1.0 if x[i] >= 0.0 else -1.0
            isgn[i] = x[i]
        _inv(AT, n, x, True)
        j = _iamax(x, n)
        it = 2
        while True:
            for i in range(n):
                x[i] = 0.0
            x[j] = 1.0
            _inv(AT, n, x, False)
            estold = est
            est = _asum(x, n)
            changed = False
            for i in range(n):
                xs = 1.0 if x[i] >= 0.0 else -1.0
                if xs != isgn[i]:
                    changed = True
                    break
            if not changed or est <= estold:
                break
            for i in range(n):
                x[i] = 1.0 if x[i] >= 0.0 else -1.0
                isgn[i] = x[i]
            _inv(AT, n, x, True)
            jlast = j
            j = _iamax(x, n)
            if x[jlast] != abs(x[j]) and it < 5:
                it += 1
                continue
            break
        alt = 1.0
        for i in range(n):
            x[i] = alt * (1.0 + i / (n - 1))
            alt = -alt
        _inv(AT, n, x, False)
        temp = 2.0 * (_asum(x, n) / (3 * n))
        if temp > est:
            est = temp
    if est == 0.0 or not np.isfinite(est):
        return 0.0
    return (1.0 / est) / anorm
