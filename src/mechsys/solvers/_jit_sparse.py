r"""Sparse LU in Numba for the compiled loops: left-looking Gilbert-Peierls factorisation with
threshold partial pivoting that prefers the diagonal (the algorithm of CSparse's ``cs_lu``
and of KLU's kernel), and its solves.

The dense LU of ``_jit_lapack`` costs ``O(n^2)`` storage and at least ``O(n^2)`` work; a
tree-structured mechanism ordered leaves first (the caller applies a fill-reducing symmetric
permutation beforehand) has LU factors as sparse as its Jacobian, and this factorisation's
work is proportional to the arithmetic on them plus ``nnz(A)`` (an ``O(n)`` initialisation per
call aside): linear in ``n`` for such mechanisms.

**Algorithm** (:func:`lu_factor`). Column ``k`` of :math:`P A = L U` (``P`` the row permutation
chosen on the way, columns in their given order) comes from the sparse triangular solve
:math:`L_k x = A(:, k)`, ``L_k`` the ``k`` columns of ``L`` found so far (unit lower, padded with
the identity):

* the nonzero pattern of ``x`` is the set of rows reachable from the rows of ``A(:, k)`` in
  the graph with an edge ``j -> i`` for each ``l_ij != 0`` (Gilbert and Peierls); a depth-first
  search with an explicit stack (no recursion) lists it in topological order;
* the numeric solve visits that list in order: ``x_i -= l_ij x_j`` for each edge out of a
  pivotal row ``j``;
* the pivot is chosen among the rows not yet pivotal: row ``k`` when it is not yet pivotal
  and ``x_k != 0``, ``|x_k| >= tol max_i |x_i|``; otherwise the row of largest ``|x_i|`` (the
  smallest row index among equal magnitudes, as LAPACK's ``idamax`` on a dense matrix).
  ``tol = 1`` is partial pivoting (the pivots of dense Gaussian elimination up to ties),
  ``tol = 0`` keeps every nonzero diagonal;
* ``U(:, k)`` receives ``x`` on the pivotal rows and the pivot; ``L(:, k)`` the other rows'
  ``x_i`` divided by the pivot.

**Storage** (compressed sparse columns, 0-based, int64 indices, float64 values):

* ``A``: ``Ap`` (n+1,), ``Ai`` (nnz,), ``Ax`` (nnz,): rows ``Ai[Ap[k]:Ap[k+1]]`` of column
  ``k`` in any order; duplicate entries are summed.
* ``L``: ``Lp`` (n+1,), ``Li`` (capL,), ``Lx`` (capL,): the strictly lower entries only, the
  unit diagonal is *not* stored; column ``k`` in ``Lp[k] .. Lp[k+1]``, rows ``> k``.
* ``U``: ``Up`` (n+1,), ``Ui`` (capU,), ``Ux`` (capU,): column ``k`` in ``Up[k] .. Up[k+1]``,
  rows ``< k`` first, then the diagonal ``u_kk`` **last**: ``Ux[Up[k + 1] - 1]`` (and
  ``Ui[Up[k + 1] - 1] == k``).
* The rows of ``L`` and ``U`` are in the **pivoted** numbering (``0 .. n-1`` in pivot order),
  in no particular order within a column (the search's). ``pinv`` (n,): ``pinv[i] = k`` when
  row ``i`` of ``A`` is the ``k``-th pivot row, i.e. :math:`(P A)[\mathtt{pinv}[i], :] = A[i, :]`.
* Entries are structural: an ``x_i`` that cancels to zero is stored (as zero).

:math:`\mathit{nnz}(L) + \mathit{nnz}(U) = \mathit{nnz}(A)` exactly when the elimination makes no fill
(``nnz(L)`` without
the unit diagonal). Every function here is a :data:`~._jit_lapack.leaf`: no allocation, no
exception, no recursion; all storage belongs to the caller (sizes: :func:`work_sizes`).
:class:`SparseLU` is the Python-side convenience that allocates and retries.

**Status codes** of :func:`lu_factor`: ``0`` success; ``k + 1`` no nonzero pivot candidate
in column ``k`` (exactly singular: every candidate is zero, or there is none); ``-1`` the
storage of ``L`` or ``U`` is too small; ``-2`` a non-finite value (NaN, inf) in column ``k``'s
``x``; ``-3`` invalid arguments (an array shorter than its documented size, a decreasing
``Ap``, a row index outside ``0 .. n-1``). On any nonzero status the factors are incomplete
(and ``Li`` in the original row numbering): only the status means anything.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps

from ._jit_cache import check as _check_cache
from ._jit_lapack import leaf
from ._tolerances import Singular

_check_cache()   # stale cached loops go before anything here compiles (see _jit_cache)

#: largest finite double: ``not (abs(v) <= _BIG)`` is true exactly for NaN and +-inf
_BIG = 1.7976931348623157e308

OK = 0
CAPACITY = -1
NONFINITE = -2
BAD_ARGS = -3


#: ``iw`` holds ``IWORK n`` integers (:func:`work_sizes`)
IWORK = 3


def work_sizes(n):
    """Sizes ``(len(iw), len(xw))`` of :func:`lu_factor`'s work arrays for an ``n x n``
    matrix: ``iw`` (int64) holds the search's output/stack ``xi[0:n]``, its positions
    ``pstack[n:2n]`` and the marks ``mark[2n:3n]``; ``xw`` (float64) the dense ``x``.
    (Larger arrays are fine, e.g. ``4 n``.)"""
    return IWORK * n, n


@leaf
def _reach(n, Ap, Ai, k, Lp, Li, pinv, iw):
    """Nonzero pattern of ``x`` in :math:`L_k x = A(:, k)`, in topological order, into
    ``iw[top:n]``; returns ``top``. Depth-first search from each row of ``A(:, k)`` over the
    edges ``j -> Li[p]``, ``p`` in ``Lp[J] .. Lp[J+1]``, ``J = pinv[j] >= 0`` (``Li`` still
    in the original row numbering). ``iw[0:n]``: the stack grows from ``0`` while the finished
    rows fill from ``n`` down (they never meet: both hold distinct marked rows);
    ``iw[n:2n]``: where each stacked row resumes its edges; ``iw[2n:3n]``: ``mark[i] == k``
    once row ``i`` is visited in column ``k`` (a generation count: never cleared)."""
    ps = n
    mk = 2 * n
    top = n
    for p in range(Ap[k], Ap[k + 1]):
        r = Ai[p]
        if iw[mk + r] == k:
            continue
        head = 0
        iw[0] = r
        while head >= 0:
            j = iw[head]
            J = pinv[j]
            if iw[mk + j] != k:          # first visit: mark, start at its first edge
                iw[mk + j] = k
                iw[ps + head] = Lp[J] if J >= 0 else 0
            end = Lp[J + 1] if J >= 0 else 0
            q = iw[ps + head]
            done = True
            while q < end:
                i = Li[q]
                q += 1
                if iw[mk + i] != k:      # descend into i; j resumes after this edge
                    iw[ps + head] = q
                    head += 1
                    iw[head] = i
                    done = False
                    break
            if done:                     # every successor finished: j is finished
                head -= 1
                top -= 1
                iw[top] = j
    return top


@leaf
def lu_factor(n, Ap, Ai, Ax, tol, Lp, Li, Lx, Up, Ui, Ux, pinv, iw, xw):
    r""":math:`P A = L U` of the sparse ``A`` (n, n) (module docstring: algorithm, storage).

    ``A``: ``Ap`` (n+1,), ``Ai`` (nnz,), ``Ax`` (nnz,) in CSC; ``tol``: the diagonal is kept
    as pivot while ``|x_k| >= tol max |x_i|`` over the candidates (``0 <= tol <= 1``; 0.1
    is customary). Outputs: ``L`` in ``Lp`` (n+1,), ``Li``, ``Lx`` (capL,), unit diagonal
    not stored; ``U`` in ``Up`` (n+1,), ``Ui``, ``Ux`` (capU,), ``u_kk = Ux[Up[k+1] - 1]``;
    ``pinv`` (n,): ``pinv[i] = k`` for the ``k``-th pivot row ``i``. ``capL`` is the smaller
    of ``Li.size``, ``Lx.size``, ``capU`` likewise. Work: ``iw`` (int64, ``>= 3 n``) and
    ``xw`` (float64, ``>= n``) (:func:`work_sizes`); neither needs initialising.

    Returns 0, or ``k + 1`` (column ``k`` has no nonzero pivot candidate), ``-1`` (``capL``
    or ``capU`` too small: the check is exact, so the ``nnz`` of a previous factorisation
    with the same pivots suffices), ``-2`` (NaN or inf in a pivot column), ``-3`` (invalid
    arguments). Cost: ``O(n + nnz(A) + flops)``; no ``O(n)`` work per column.
    """
    if (n < 0 or Ap.size < n + 1 or Lp.size < n + 1 or Up.size < n + 1 or pinv.size < n
            or iw.size < 3 * n or xw.size < n):
        return BAD_ARGS
    if Ap[0] < 0 or Ap[n] > Ai.size or Ap[n] > Ax.size:
        return BAD_ARGS
    for k in range(n):
        if Ap[k + 1] < Ap[k]:
            return BAD_ARGS
    for p in range(Ap[0], Ap[n]):
        if Ai[p] < 0 or Ai[p] >= n:
            return BAD_ARGS
    capL = min(Li.size, Lx.size)
    capU = min(Ui.size, Ux.size)
    mk = 2 * n
    for i in range(n):                   # x is zero between columns (cleared on its pattern)
        pinv[i] = -1
        iw[mk + i] = -1
        xw[i] = 0.0
    lnz = 0
    unz = 0
    for k in range(n):
        Lp[k] = lnz
        Up[k] = unz
        top = _reach(n, Ap, Ai, k, Lp, Li, pinv, iw)
        for p in range(Ap[k], Ap[k + 1]):            # x = A(:, k)
            xw[Ai[p]] += Ax[p]
        for p in range(top, n):                      # x <- L_k^-1 x, topological order
            j = iw[p]
            J = pinv[j]
            if J < 0:
                continue
            xj = xw[j]
            if xj != 0.0:
                for q in range(Lp[J], Lp[J + 1]):
                    xw[Li[q]] -= Lx[q] * xj
        ipiv = -1                                    # pivot: largest candidate, first row
        big = -1.0
        nl = 0
        nu = 0
        finite = True
        for p in range(top, n):
            i = iw[p]
            t = abs(xw[i])
            if not (t <= _BIG):
                finite = False
            if pinv[i] < 0:
                nl += 1
                if t > big or (t == big and i < ipiv):
                    big = t
                    ipiv = i
            else:
                nu += 1
        if not finite:
            return NONFINITE
        if ipiv < 0 or big == 0.0:
            return k + 1
        if pinv[k] < 0 and xw[k] != 0.0 and abs(xw[k]) >= tol * big:
            ipiv = k                                 # the diagonal, big enough
        if unz + nu + 1 > capU or lnz + nl - 1 > capL:
            return CAPACITY
        pivot = xw[ipiv]
        for p in range(top, n):
            i = iw[p]
            J = pinv[i]
            if J >= 0:
                Ui[unz] = J
                Ux[unz] = xw[i]
                unz += 1
            elif i != ipiv:
                Li[lnz] = i
                Lx[lnz] = xw[i] / pivot
                lnz += 1
            xw[i] = 0.0
        Ui[unz] = k                                  # the diagonal last
        Ux[unz] = pivot
        unz += 1
        pinv[ipiv] = k
    Lp[n] = lnz
    Up[n] = unz
    for p in range(lnz):                             # L's rows into the pivoted numbering
        Li[p] = pinv[Li[p]]
    return OK


@leaf
def lu_solve(n, pinv, Lp, Li, Lx, Up, Ui, Ux, b, x, w):
    r"""``x = A^-1 b`` from :func:`lu_factor`'s factors (status 0): :math:`P A = L U`, so
    ``L y = P b`` (``(P b)[pinv[i]] = b[i]``), then ``U x = y``, both by columns. ``b`` (n,)
    is read only; ``x`` (n,) must not alias it; ``w`` (n,): not used (the solves share their
    arguments)."""
    for i in range(n):
        x[pinv[i]] = b[i]
    for k in range(n):                   # L y = P b, unit diagonal
        xk = x[k]
        if xk != 0.0:
            for p in range(Lp[k], Lp[k + 1]):
                x[Li[p]] -= Lx[p] * xk
    for k in range(n - 1, -1, -1):       # U x = y, u_kk last in column k
        e = Up[k + 1] - 1
        xk = x[k] / Ux[e]
        x[k] = xk
        if xk != 0.0:
            for p in range(Up[k], e):
                x[Ui[p]] -= Ux[p] * xk


@leaf
def lu_solve_t(n, pinv, Lp, Li, Lx, Up, Ui, Ux, b, x, w):
    r"""``x = A^-T b`` from :func:`lu_factor`'s factors (status 0): ``A^T = U^T L^T P``, so
    ``U^T z = b``, ``L^T y = z`` (dot products with the columns of ``U``, ``L``), and
    ``x[i] = y[pinv[i]]``. ``b`` (n,) is read only; ``x`` (n,) must not alias it; ``w`` (n,):
    work."""
    for i in range(n):
        w[i] = b[i]
    for k in range(n):                   # U^T z = b: z_k = (b_k - sum_i u_ik z_i) / u_kk
        e = Up[k + 1] - 1
        s = w[k]
        for p in range(Up[k], e):
            s -= Ux[p] * w[Ui[p]]
        w[k] = s / Ux[e]
    for k in range(n - 1, -1, -1):       # L^T y = z: y_k = z_k - sum_i l_ik y_i
        s = w[k]
        for p in range(Lp[k], Lp[k + 1]):
            s -= Lx[p] * w[Li[p]]
        w[k] = s
    for i in range(n):
        x[i] = w[pinv[i]]


@leaf
def lu_pivot_ratio(n, Up, Ux):
    r"""``min_k |u_kk| / max_k |u_kk|`` of :func:`lu_factor`'s ``U`` (status 0), a cheap
    indicator of near-singularity (not a condition estimate). 1.0 for ``n == 0`` (as
    ``gecon1``'s empty matrix); 0.0 when a diagonal is NaN or inf, or all are zero."""
    if n == 0:
        return 1.0
    lo = _BIG
    hi = 0.0
    for k in range(n):
        d = abs(Ux[Up[k + 1] - 1])
        if not (d <= _BIG):
            return 0.0
        if d < lo:
            lo = d
        if d > hi:
            hi = d
    if hi == 0.0:
        return 0.0
    return lo / hi


class SparseLU:
    """:func:`lu_factor` of a SciPy sparse (or dense) square ``A`` with Python-side storage:
    starts from ``capacity`` entries for each of ``L`` and ``U`` (default ``4 nnz(A) + n``)
    and doubles both on status -1. Raises :class:`~._tolerances.Singular` on an exactly zero
    pivot column or a non-finite value, ``ValueError`` on a non-square ``A``.

    Attributes: ``n``, ``nnz_L`` (without the unit diagonal), ``nnz_U`` (with the diagonal),
    ``pinv``, ``rcond`` (:func:`lu_pivot_ratio`), the raw arrays ``Lp, Li, Lx, Up, Ui, Ux``
    (trimmed to their ``nnz``) and the matrices :attr:`L` and :attr:`U` (pivoted numbering:
    :math:`P A = L U` with ``(P A)[pinv[i]] = A[i]``)."""

    def __init__(self, A, tol=0.1, capacity=None):
        A = sps.csc_matrix(A, dtype=np.float64, copy=True)
        A.sum_duplicates()
        n, m = A.shape
        if n != m:
            raise ValueError(f"SparseLU needs a square matrix, got {n} x {m}")
        Ap = A.indptr.astype(np.int64)
        Ai = A.indices.astype(np.int64)
        Ax = np.ascontiguousarray(A.data, dtype=np.float64)
        cap = int(capacity) if capacity is not None else 4 * A.nnz + n
        cap = max(cap, 1)
        ni, nx = work_sizes(n)
        iw = np.empty(ni, np.int64)
        xw = np.empty(nx, np.float64)
        Lp = np.empty(n + 1, np.int64)
        Up = np.empty(n + 1, np.int64)
        pinv = np.empty(n, np.int64)
        while True:
            Li = np.empty(cap, np.int64)
            Lx = np.empty(cap, np.float64)
            Ui = np.empty(cap, np.int64)
            Ux = np.empty(cap, np.float64)
            status = lu_factor(n, Ap, Ai, Ax, float(tol), Lp, Li, Lx, Up, Ui, Ux, pinv, iw, xw)
            if status != CAPACITY:
                break
            cap *= 2                     # L and U never exceed n (n + 1) / 2 each
        if status == NONFINITE:
            raise Singular("non-finite value in the sparse LU factorisation")
        if status > 0:
            raise Singular(f"exactly singular: column {status - 1} has no nonzero pivot")
        if status != OK:
            raise ValueError(f"lu_factor: invalid arguments (status {status})")
        self.n = n
        self.nnz_L = int(Lp[n])
        self.nnz_U = int(Up[n])
        self.Lp, self.Up, self.pinv = Lp, Up, pinv
        self.Li, self.Lx = Li[:self.nnz_L].copy(), Lx[:self.nnz_L].copy()
        self.Ui, self.Ux = Ui[:self.nnz_U].copy(), Ux[:self.nnz_U].copy()
        self.rcond = float(lu_pivot_ratio(n, Up, Ux))
        self._w = np.empty(n, np.float64)

    def _apply(self, fn, b):
        b = np.asarray(b, dtype=np.float64)
        if b.shape[0] != self.n or b.ndim not in (1, 2):
            raise ValueError(f"right-hand side of shape {b.shape} for a {self.n} x {self.n} matrix")
        cols = b[:, None] if b.ndim == 1 else b
        out = np.empty(cols.shape, np.float64)
        x = np.empty(self.n, np.float64)
        for j in range(cols.shape[1]):
            fn(self.n, self.pinv, self.Lp, self.Li, self.Lx, self.Up, self.Ui, self.Ux,
               np.ascontiguousarray(cols[:, j]), x, self._w)
            out[:, j] = x
        return out.reshape(b.shape)

    def solve(self, b):
        """``A^-1 b`` (``b``: (n,) or (n, r))."""
        return self._apply(lu_solve, b)

    def solve_transposed(self, b):
        """``A^-T b`` (``b``: (n,) or (n, r))."""
        return self._apply(lu_solve_t, b)

    @property
    def L(self):
        """Unit lower factor (n, n), CSC, diagonal included."""
        Lo = sps.csc_matrix((self.Lx, self.Li, self.Lp), shape=(self.n, self.n))
        return (Lo + sps.identity(self.n, format="csc")).tocsc()

    @property
    def U(self):
        """Upper factor (n, n), CSC."""
        return sps.csc_matrix((self.Ux, self.Ui, self.Up), shape=(self.n, self.n))


__all__ = ["SparseLU", "lu_factor", "lu_pivot_ratio", "lu_solve", "lu_solve_t", "work_sizes"]
