r"""Small dense LU in Numba for the compiled loops: LAPACK's algorithms without the call.

For the 5-30 unknowns of a mechanism's Jacobian a call of SciPy's LAPACK through its C
address costs about 0.7 µs of overhead, more than the arithmetic; a sweep point makes
about ten such calls. For larger mechanisms (up to the 150 unknowns of the compiled loops)
the sparsity wins instead: the elimination skips zero multipliers and the solves visit
only the factors' nonzeros, 1.6-2.6 x faster than LAPACK's blocked LU on chains of 33 to
147 unknowns (decision 0019, amended). These functions perform the same algorithms as the
routines the Python path calls (``scipy.linalg.lapack``):

* ``getrf``  ``dgetrf``: Gaussian elimination with partial pivoting (first largest pivot),
  unit lower ``L`` and upper ``U`` in place, ``info > 0`` at an exactly zero pivot;
* ``getrs``  ``dgetrs`` with ``trans = 'N'``: row interchanges, then the two triangular solves;
* ``gecon1`` ``dgecon`` with ``norm = '1'``: Higham's refinement of Hager's estimator of
  :math:`\lVert A^{-1} \rVert_1` (LAPACK ``dlacn2``: at most five iterations, then the alternating-sign
  test vector) with the triangular solves of ``dlatrs`` in its unscaled case (``dtrsv``).

The loops sum in their own order, so the results agree with LAPACK's to rounding (the
condition estimate takes the same decisions, hence the same value up to rounding).
Matrices are stored transposed in C order (column-major order of the matrix): entry
``A(i, j)`` is ``AT[j, i]``.

**Sparse factors** (``nz``, an int32 array of :func:`pattern_size` ``(n)`` entries): a
mechanism's Jacobian has two to six nonzeros a row and its LU factors stay nearly as sparse
(the slider-crank's 9 x 9: 8 entries below the diagonal of ``L``, 17 in ``U``, of 81).
Given ``nz``, ``getrf`` records where the nonzeros of ``L`` and ``U`` are (its elimination
already skips zero multipliers); ``getrs``, ``gecon1`` and :func:`inv_norm_bound` then
visit only those. Every operation skipped is ``x - 0 * y`` with ``y`` finite, which leaves
``x`` unchanged, and the remaining ones run in the same order: the numbers are those of the
dense loops (up to the sign of a zero, which no decision reads). Without ``nz`` the dense
loops run (the free-motion stepper's callers). :func:`symbolic_pattern` gives a structure
that holds for every matrix of a given sparsity and pivot sequence, so the compiled sweep
makes it once per pivot sequence instead of recording it after each factorisation
(decision 0025).

**The elimination along the structure** (:func:`getrf_lists`, decision 0078; the sweep's
and the multiplier solves' LU from ``LIST_LU_MIN`` unknowns): ``getrf``'s elimination
visiting only the structure's lists and their fill, which are :func:`symbolic_pattern`'s
structure for the pivots it takes (:func:`lists_pattern` writes it as ``nz``): the same
pivots and factors (up to the sign of a zero) at a cost in the factors' nonzeros instead of
``n^2``, for the compiled loops and above all for their code run by the interpreter
(:mod:`._jit_interp`), which pays per statement. (:func:`symbolic_pattern` stays as the
dense statement of that structure, against which the tests check the lists.)

Layout of ``nz`` (0-based, positions absolute): ``nz[j] .. nz[j + 1]`` hold the rows
``i > j`` with ``L(i, j) != 0`` of column ``j``, ascending; ``nz[n + 1 + j] .. nz[n + 2 + j]``
the rows ``i < j`` with ``U(i, j) != 0``, ascending.
"""

from __future__ import annotations

import numba as nb
import numba.core.options  # noqa: F401  (leaf below reads it)
import numpy as np

from ._jit_cache import check as _check_cache

_check_cache()   # stale cached loops go before anything here compiles (see _jit_cache)

#: The compiled loops' leaf functions (they allocate nothing; their callers hold every array
#: they pass): compiled without reference counting. With it, each call incremented and
#: decremented the count of every array argument on entry and exit, atomic operations that
#: took 10-15 % of the sweep (measured: ``NRT_incref``/``NRT_decref`` in a profile). NumPy's
#: error model: no zero test before each division (every divisor here is guarded).
#: (``_nrt`` is Numba's own option name, not documented: a Numba without it gets the plain
#: decorator rather than an error at the first compilation.)
leaf = nb.njit(cache=True, error_model="numpy", **(
    {"_nrt": False} if hasattr(getattr(nb.core.options, "DefaultOptions", None), "_nrt") else {}))

#: :func:`inv_norm_bound` exceeds what ``gecon1`` can compute from the same factors up to a
#: relative ``(4 n^2 + 8 n + 20) u`` (``n <= 32``: below 5e-13); the compiled sweep's guard
#: leaves a factor of two (``_jit_linalg._factor``)
GUARD_MARGIN = 0.5


@nb.njit(cache=True)
def pattern_size(n):
    """Length of the ``nz`` array of an ``n x n`` factorisation."""
    return n * n + n + 2


@leaf
def getrf(AT, n, piv, nz=None):
    """LU of ``A`` (n, n) in place; ``piv[j]``: the row swapped with row ``j`` (0-based).
    Returns LAPACK's ``info``: 0, or ``j + 1`` for the first exactly zero pivot. With ``nz``
    (see the module docstring) ``nz`` receives the factors' nonzero structure."""
    # (each column of the transposed storage through a row view, ``lj = AT[j]``: the same
    # operations; the interpreted tier (decision 0075) indexes a view by one integer, about
    # 1.5 x faster than ``AT[j, i]``; compiled, the same code: decision 0077)
    # (the column's rows below the diagonal that are not zero lie in lo .. hi, found by the
    # pivot search; the scaling and the updates skip the zeros outside, ``x - 0 a = x`` and
    # ``0 inv = 0`` for finite ``a`` and ``inv`` (a zero's sign aside), and take every row
    # where either is not finite: the same numbers, and the interpreted tier, which pays
    # per statement, visits a sparse column's nonzero span only: decision 0087)
    info = 0
    for j in range(n):
        lj = AT[j]
        p = j
        big = abs(lj[j])
        lo = n
        hi = j
        for i in range(j + 1, n):
            v = abs(lj[i])
            if v != 0.0:                 # (NaN too)
                hi = i
                if lo == n:
                    lo = i
                if v > big:
                    big = v
                    p = i
        piv[j] = p
        if lj[p] != 0.0:
            if p != j:                   # (p in lo .. hi: the span holds the old diagonal)
                for c in range(n):
                    AT[c, j], AT[c, p] = AT[c, p], AT[c, j]
            inv = 1.0 / lj[j]
            if not abs(inv) < np.inf:    # (a subnormal pivot: 0 inv is NaN)
                lo = j + 1
                hi = n - 1
            for i in range(lo, hi + 1):
                lj[i] *= inv
        elif info == 0:
            info = j + 1
        for c in range(j + 1, n):
            a = AT[c, j]
            if a != 0.0:
                ac = AT[c]
                if abs(a) < np.inf:
                    for i in range(lo, hi + 1):
                        ac[i] -= lj[i] * a
                else:                    # (0 a is NaN)
                    for i in range(j + 1, n):
                        ac[i] -= lj[i] * a
    if nz is not None:
        _pattern(AT, n, nz)
    return info


@leaf
def _pattern(AT, n, nz):
    """The nonzero structure of the factors in ``AT`` into ``nz`` (module docstring)."""
    pl = 2 * n + 2
    pu = pl + (n * (n - 1)) // 2
    for j in range(n):
        nz[j] = pl
        nz[n + 1 + j] = pu
        for i in range(j):               # branch-free: the zeros are unpredictable
            nz[pu] = i
            pu += AT[j, i] != 0.0
        for i in range(j + 1, n):
            nz[pl] = i
            pl += AT[j, i] != 0.0
    nz[n] = pl
    nz[2 * n + 1] = pu


@leaf
def symbolic_pattern(S, n, piv, nz, W):
    """``nz`` (module docstring) for the factors of any matrix whose nonzeros lie within the
    structure ``S`` (n, n; transposed storage, nonzero where ``A`` may be) and whose
    elimination takes the pivots ``piv``: :func:`getrf`'s steps on the structure (row
    interchanges, and fill wherever a multiplier and a pivot-row entry may both be nonzero).
    Every nonzero the numbers can produce is in it, so it may replace the recorded ``nz``:
    the operations it adds are ``x - 0 * y`` (the sweep computes it once per pivot sequence,
    not after every factorisation). ``W`` (n, n): work."""
    for c in range(n):
        for i in range(n):
            W[c, i] = 1.0 if S[c, i] != 0.0 else 0.0
    for j in range(n):
        p = piv[j]
        if p != j:
            for c in range(n):
                tmp = W[c, j]
                W[c, j] = W[c, p]
                W[c, p] = tmp
        for c in range(j + 1, n):
            if W[c, j] != 0.0:
                for i in range(j + 1, n):
                    if W[j, i] != 0.0:
                        W[c, i] = 1.0
    _pattern(W, n, nz)


#: from this many unknowns the compiled loops factorise along the lists (:func:`getrf_lists`);
#: below, the dense :func:`getrf` costs less, compiled and interpreted (its ``n^2`` zero tests
#: are few), and the lists only give the factors' structure when the pivots change
#: (decision 0078)
LIST_LU_MIN = 17


@nb.njit(cache=True)
def lists_size(n):
    """Rows of the ``W`` work array of :func:`getrf_lists` (``n`` columns)."""
    return 3 * n + 4


@leaf
def getrf_lists(AT, n, piv, S, W, P, numeric):
    r""":func:`getrf` visiting the structure only: the same pivots, the same ``info`` and the
    same factors (up to the sign of a zero), at a cost that grows with the factors' nonzeros
    instead of ``n^2``. It eliminates along lists of the nonzero structure, updated with the
    fill as it goes, which are the symbolic factorisation of ``S`` with these pivots
    (:func:`symbolic_pattern`'s structure; :func:`lists_pattern` writes it as ``nz``).

    Why the numbers are :func:`getrf`'s: an entry outside the structure is an exact zero
    (zero in ``A``, and every update of it is ``x - l a`` with ``l`` or ``a`` outside the
    structure too, hence zero). So the pivot search over the structural rows finds the same
    first largest entry (ties to the lower position, as the dense loop's strict ``>`` in
    ascending order), the row interchange over the two rows' structural columns moves every
    nonzero, and the updates ``A(i, c) -= l_i a_c`` skipped are those with ``a_c = 0``
    (which :func:`getrf` skips too) or ``l_i = 0``: ``x - 0 a = x`` for a finite ``a`` (a
    zero ``x`` may come out with the other sign, which nothing reads). Each entry is updated
    once per step, so the order within a step is immaterial.

    Not finite: the skipped updates are exact while every ``a_c`` and every pivot's
    reciprocal is finite (``0 * inf`` is NaN). Where one is not, :func:`getrf`'s dense loops
    take over (the column's update at once, the rest from the next step on: the zeros
    outside the structure may no longer be zeros), on the same matrix, so that the numbers
    are then :func:`getrf`'s exactly, ``NaN`` included; the lists keep following the pivots.

    ``S`` (:func:`_jit_linalg._structure`, int32 (2n + 2, n)): ``S[c, :S[2n, c]]`` the
    structural rows of column ``c``, ascending; ``S[n + r, :S[2n + 1, r]]`` the structural
    columns of row ``r``. ``W`` (int32 (:func:`lists_size` ``(n)``, n), holding ``S``'s lists
    on entry, with ``S``'s flags): ``W[c, :W[2n, c]]`` the rows (by identity: the row's position in ``A``) of
    column ``c``'s structure, ``W[n + r, :W[2n + 1, r]]`` row ``r``'s columns, ``W[2n + 2]``,
    ``W[2n + 3]`` the positions and identities of the current column's rows below the
    diagonal, ``W[2n + 4 + c, r]`` one when ``(r, c)`` is in the structure (the lists and
    flags past ``S``'s are the fill, dropped on the next call). ``P`` (int32 (3, n)):
    ``P[1]`` receives the position of each row, ``P[2]`` the row at each position
    (``P[0]``: the caller's). Returns LAPACK's ``info``. ``numeric`` False: the structure
    only, for the pivots given in ``piv`` (``AT`` untouched, 0 returned): the lists of the
    factors that :func:`getrf` made with them.
    (Written for the interpreter too, which runs it as the first tier (decision 0078): few
    statements per entry visited, whole-row copies as slice assignments.)

    Example::

        info = getrf_lists(B, n, ipiv, S, W, P, True)    # then lists_pattern(n, W, P, nz)
    """
    cl = 2 * n                       # W[cl, c], W[cl + 1, r]: the lists' lengths
    sc = 2 * n + 2                   # the current column's rows below the diagonal
    fl = 2 * n + 4                   # W[fl + c, r]: (r, c) in the structure
    pos = P[1]
    rid = P[2]
    for c in range(n):               # (the lists are S's, then the fill: drop the fill)
        W[cl, c] = S[cl, c]
        W[cl + 1, c] = S[cl + 1, c]
        pos[c] = c
        rid[c] = c
    dense = False
    info = 0
    for j in range(n):
        # the pivot (the first largest below the diagonal) and the column's rows below it
        p = j if numeric else piv[j]
        pv = abs(AT[j, j])
        nl = 0
        kp = -1
        for r in W[j, :W[cl, j]]:
            i = pos[r]
            if i > j:
                W[sc, nl] = i
                W[sc + 1, nl] = r
                if not numeric:
                    if i == p:
                        kp = nl
                else:
                    v = abs(AT[j, i])
                    if v > pv or (v == pv and i < p):
                        pv = v
                        p = i
                        kp = nl
                nl += 1
        if dense and numeric:
            p = j
            pv = abs(AT[j, j])
            for i in range(j + 1, n):
                v = abs(AT[j, i])
                if v > pv:
                    pv = v
                    p = i
            kp = -1
            for k in range(nl):
                if W[sc, k] == p:
                    kp = k
        piv[j] = p
        if p != j:                       # (then A(p, j) != 0: p moved on a larger |A(i, j)|)
            a_id = rid[j]
            b_id = rid[p]
            if not numeric:
                pass
            elif dense:
                for c in range(n):
                    AT[c, j], AT[c, p] = AT[c, p], AT[c, j]
            else:
                for c in W[n + a_id, :W[cl + 1, a_id]]:
                    AT[c, j], AT[c, p] = AT[c, p], AT[c, j]
                for c in W[n + b_id, :W[cl + 1, b_id]]:
                    if W[fl + c, a_id] == 0:
                        AT[c, j], AT[c, p] = AT[c, p], AT[c, j]
            pos[a_id] = p
            pos[b_id] = j
            rid[j] = b_id
            rid[p] = a_id
            # the pivot row left the rows below the diagonal, the row it replaced (at p now)
            # joins them where it has an entry in this column
            if kp < 0:                   # (dense: a pivot outside the structure)
                W[sc, nl] = p
                W[sc + 1, nl] = a_id
                nl += 1
                kp = nl - 1
            if W[fl + j, a_id] != 0:
                W[sc + 1, kp] = a_id
            else:
                nl -= 1
                W[sc, kp] = W[sc, nl]
                W[sc + 1, kp] = W[sc + 1, nl]
        if not numeric:
            pass
        elif AT[j, j] != 0.0:
            inv = 1.0 / AT[j, j]
            if not abs(inv) < np.inf:
                dense = True             # (a subnormal pivot: 0 * inv is NaN in getrf)
            if dense:
                for i in range(j + 1, n):
                    AT[j, i] *= inv
            else:
                for i in W[sc, :nl]:
                    AT[j, i] *= inv
        elif info == 0:
            info = j + 1
        # the elimination, with the fill of the structure: row j's columns c > j, column
        # j's rows below j
        jid = rid[j]
        spoilt = False
        for c in W[n + jid, :W[cl + 1, jid]]:
            if c > j:
                a = AT[c, j]
                # (getrf skips a zero a: so does this loop, l * 0 being NaN for l not finite)
                live = numeric and not dense and a != 0.0
                if live and not abs(a) < np.inf:
                    # a non-finite a: getrf's update of the whole column (0 * a is NaN),
                    # and its loops from the next step on (the zeros outside the
                    # structure may be NaN now)
                    live = False
                    spoilt = True
                    for i in range(j + 1, n):
                        AT[c, i] -= AT[j, i] * a
                for k in range(nl):
                    r = W[sc + 1, k]
                    if W[fl + c, r] == 0:
                        W[fl + c, r] = 1
                        W[c, W[cl, c]] = r
                        W[cl, c] += 1
                        W[n + r, W[cl + 1, r]] = c
                        W[cl + 1, r] += 1
                    if live:
                        AT[c, W[sc, k]] -= AT[j, W[sc, k]] * a
        if dense and numeric:
            for c in range(j + 1, n):
                a = AT[c, j]
                if a != 0.0:
                    for i in range(j + 1, n):
                        AT[c, i] -= AT[j, i] * a
        dense = dense or spoilt
    for c in range(n):                   # (the fill's flags back to zero)
        for r in W[c, S[cl, c]:W[cl, c]]:
            W[fl + c, r] = 0
    return info


@leaf
def lists_pattern(n, W, P, nz):
    """``nz`` (module docstring) of the structure :func:`getrf_lists` left in ``W`` with the
    positions ``P[1]``: each column's rows below and above the diagonal, sorted (insertion:
    the lists are short). Equal to :func:`symbolic_pattern` of the same structure and pivots.
    """
    cl = 2 * n
    pos = P[1]
    pl = 2 * n + 2
    pu = pl + (n * (n - 1)) // 2
    for j in range(n):
        nz[j] = pl
        nz[n + 1 + j] = pu
        l0 = pl
        u0 = pu
        for k in range(W[cl, j]):
            i = pos[W[j, k]]
            if i > j:
                q = pl
                while q > l0 and nz[q - 1] > i:
                    nz[q] = nz[q - 1]
                    q -= 1
                nz[q] = i
                pl += 1
            elif i < j:
                q = pu
                while q > u0 and nz[q - 1] > i:
                    nz[q] = nz[q - 1]
                    q -= 1
                nz[q] = i
                pu += 1
    nz[n] = pl
    nz[2 * n + 1] = pu


@leaf
def getrs(AT, n, piv, x, nz=None):
    """``x <- A^-1 x`` from :func:`getrf`'s factors (``nz``: as given to it)."""
    for j in range(n):
        p = piv[j]
        if p != j:
            tmp = x[j]
            x[j] = x[p]
            x[p] = tmp
    _inv(AT, n, x, False, nz)


@leaf
def _lower(AT, n, x):            # L x = b, L unit lower (dtrsv 'L', 'N', 'U')
    for j in range(n):
        xj = x[j]
        if xj != 0.0:
            lj = AT[j]
            for i in range(j + 1, n):
                x[i] -= xj * lj[i]


@leaf
def _upper(AT, n, x):            # U x = b (dtrsv 'U', 'N', 'N')
    for j in range(n - 1, -1, -1):
        if x[j] != 0.0:
            uj = AT[j]
            x[j] /= uj[j]
            xj = x[j]
            for i in range(j):
                x[i] -= xj * uj[i]


@leaf
def _upper_t(AT, n, x):          # U^T x = b (dtrsv 'U', 'T', 'N')
    for j in range(n):
        uj = AT[j]
        s = x[j]
        for i in range(j):
            s -= uj[i] * x[i]
        x[j] = s / uj[j]


@leaf
def _lower_t(AT, n, x):          # L^T x = b (dtrsv 'L', 'T', 'U')
    for j in range(n - 1, -1, -1):
        lj = AT[j]
        s = x[j]
        for i in range(j + 1, n):
            s -= lj[i] * x[i]
        x[j] = s


@leaf
def _inv(AT, n, x, transposed, nz=None):
    """``x <- A^-1 x`` (``transposed``: ``A^-T x``) without the row interchanges, as
    ``dgecon`` applies them: the estimate concerns ``U^-1 L^-1``."""
    if nz is None:
        if transposed:
            _upper_t(AT, n, x)
            _lower_t(AT, n, x)
        else:
            _lower(AT, n, x)
            _upper(AT, n, x)
    elif transposed:
        # the same four solves visiting only the factors' nonzeros (U^T, then L^T; below L,
        # then U), written in place: a call per triangle cost about as much as the triangle
        # at this size. No test for a zero x[j] as the dense loops have (an unpredictable
        # branch that skips only exact no-ops here). They divide by the pivots as dtrsv
        # does: multiplying by reciprocals would differ by rounding, which a nearly singular
        # matrix (a dead centre) amplifies beyond the 1e-12 the two paths agree to.
        # (two statements an entry, which the interpreted tier pays per statement; the same
        # operations)
        for j in range(n):
            s = x[j]
            for k in range(nz[n + 1 + j], nz[n + 2 + j]):
                s -= AT[j, nz[k]] * x[nz[k]]
            x[j] = s / AT[j, j]
        for j in range(n - 1, -1, -1):
            s = x[j]
            for k in range(nz[j], nz[j + 1]):
                s -= AT[j, nz[k]] * x[nz[k]]
            x[j] = s
    else:
        for j in range(n):
            xj = x[j]
            for k in range(nz[j], nz[j + 1]):
                x[nz[k]] -= xj * AT[j, nz[k]]
        for j in range(n - 1, -1, -1):
            xj = x[j] / AT[j, j]
            x[j] = xj
            for k in range(nz[n + 1 + j], nz[n + 2 + j]):
                x[nz[k]] -= xj * AT[j, nz[k]]


@leaf
def _asum(x, n):
    s = 0.0
    for i in range(n):
        s += abs(x[i])
    return s


@leaf
def _iamax(x, n):
    k = 0
    big = abs(x[0])
    for i in range(1, n):
        v = abs(x[i])
        if v > big:
            big = v
            k = i
    return k


@leaf
def gecon1(AT, n, anorm, x, isgn, nz=None):
    """LAPACK ``dgecon`` (one-norm) on :func:`getrf`'s factors: the reciprocal condition
    estimate ``1 / (||A||_1 est(||A^-1||_1))``. ``x`` (n,), ``isgn`` (n,): work arrays;
    ``nz``: as given to ``getrf``."""
    if n == 0:
        return 1.0
    if anorm == 0.0:
        return 0.0
    for i in range(n):
        x[i] = 1.0 / n
    _inv(AT, n, x, False, nz)
    if n == 1:
        est = abs(x[0])
    else:
        est = _asum(x, n)
        for i in range(n):
            x[i] = 1.0 if x[i] >= 0.0 else -1.0
            isgn[i] = x[i]
        _inv(AT, n, x, True, nz)
        j = _iamax(x, n)
        it = 2
        while True:
            for i in range(n):
                x[i] = 0.0
            x[j] = 1.0
            _inv(AT, n, x, False, nz)
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
            _inv(AT, n, x, True, nz)
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
        _inv(AT, n, x, False, nz)
        temp = 2.0 * (_asum(x, n) / (3 * n))
        if temp > est:
            est = temp
    if est == 0.0 or not np.isfinite(est):
        return 0.0
    return (1.0 / est) / anorm


@leaf
def inv_norm_bound(AT, n, nz, y):
    r"""An upper bound of ``||U^-1 L^-1||_1`` from :func:`getrf`'s factors (``info == 0``),
    in two triangular solves (``gecon1`` makes about ten): ``||M(U)^-1 M(L)^-1||_1`` with
    ``M(T)`` the comparison matrix (``|t_ii|`` on, ``-|t_ij|`` off the diagonal), whose
    inverse is nonnegative and bounds ``|T^-1|`` entrywise (Higham, *Accuracy and Stability
    of Numerical Algorithms*, 2nd ed., Thm 8.12). Its largest column sum is the largest
    entry of ``z`` in ``M(U)^T y = e``, ``M(L)^T z = y``: additions of nonnegative numbers
    only, so the computed value is within a relative ``(2n + 2) u`` of the exact one.

    Why it bounds what ``gecon1`` computes from the same factors (``u``: the unit roundoff,
    ``gamma_n = n u / (1 - n u)``): each of its triangular solves returns ``x^`` with
    ``(T + dT) x^ = b``, ``|dT| <= gamma_n |T|`` (Higham Thm 8.5), and
    ``M(T + dT) >= (1 - gamma_n) (D - c |N|)`` with ``T = D + N`` (diagonal, off-diagonal)
    and ``c = (1 + gamma_n) / (1 - gamma_n)``, whose inverse is at most ``c^(n-1)`` times
    ``M(T)^-1`` (a Neumann series of a nilpotent matrix: ``n`` terms). Hence
    ``|x^| <= K^2 M(U)^-1 M(L)^-1 |b|``, ``K = c^(n-1) / (1 - gamma_n) <= 1 + (2 n^2 + n) u``,
    and every estimate ``gecon1`` forms (``||x^||_1 / ||b||_1``, summed with rounding, for
    ``b`` = ``1/n``, ``e_j`` and its alternating test vector) is at most
    ``(1 + (4 n^2 + 8 n + 20) u)`` times the exact bound, of which this value is within
    ``(2 n + 2) u``. (No overflow or underflow: the sweep's rows are scaled to a largest
    entry of one.) ``y`` (n,): work. Returns ``inf`` when the bound is not finite.
    """
    for j in range(n):               # M(U)^T y = e: forward, y_j = (1 + sum |u_ij| y_i) / |u_jj|
        s = 1.0
        for k in range(nz[n + 1 + j], nz[n + 2 + j]):
            s += abs(AT[j, nz[k]]) * y[nz[k]]
        y[j] = s / abs(AT[j, j])
    big = 0.0
    total = 0.0                      # (an inf in y can meet a zero of a symbolic_pattern:
    for j in range(n - 1, -1, -1):   # 0 * inf is NaN, which "s > big" would pass over)
        s = y[j]                     # M(L)^T z = y: backward, z_j = y_j + sum |l_ij| z_i
        for k in range(nz[j], nz[j + 1]):
            s += abs(AT[j, nz[k]]) * y[nz[k]]
        y[j] = s
        total += s
        if s > big:
            big = s
    if not np.isfinite(total):
        return np.inf
    return big
