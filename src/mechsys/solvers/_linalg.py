r"""Linear algebra for the constraint Jacobian: factorisation with a conditioning check, and
rank-revealing diagnosis of dependent equations.

Small systems (``n <= SPARSE_THRESHOLD``) use dense LU with LAPACK's reciprocal condition
estimate; larger ones sparse SuperLU, or, for matrices of one fixed pattern factorised again
and again (free motion's augmented matrix, a system's Jacobian), :class:`FixedPattern`: the
pattern analysed once, banded LU for chains, a sparse LU in a minimum-degree ordering for
trees. A matrix whose reciprocal condition number falls
below ``RCOND_MIN`` is treated as singular and diagnosed with a pivoted QR of ``Phi_q^T``:
its last ``m - rank`` pivots are the dependent equations.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla
from scipy.linalg.lapack import dgbtrf as _dgbtrf
from scipy.linalg.lapack import dgbtrs as _dgbtrs
from scipy.sparse.csgraph import maximum_bipartite_matching, reverse_cuthill_mckee

from ._tolerances import ARM_ROUNDOFF, PIVOT_TOL, RCOND_MIN, Singular

#: :class:`FixedPattern` solves banded (LAPACK) while ``N (kl + ku)^2``, the banded LU's
#: work, is at most this, else with SuperLU: the two cost the same near it (measured on
#: chains, grids and trees: ``docs/decisions/0017-fixed-pattern-sparse-solve.md``)
BAND_WORK = 8e6
#: the same bound when the compiled sparse LU is there (``_jit_sparse``): it overtakes LAPACK's
#: banded LU much earlier (free motion of radial engines, Python path: ``N (kl + ku)^2`` =
#: 1.05e6, banded 29.5 ms, sparse 16.6 ms; chains, 8e4: banded 34 ms, sparse 37 ms;
#: decision 0031)
BAND_WORK_SPARSE = 2e5


class Factor:
    """A factorised square matrix; ``solve(b)`` for one or several right-hand sides."""

    def __init__(self, J):
        self.sparse = sps.issparse(J)
        if self.sparse:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", sps.SparseEfficiencyWarning)
                    self._lu = spla.splu(_csc(J))
            except RuntimeError as exc:  # "Factor is exactly singular"
                raise Singular(str(exc)) from None
            d = np.abs(self._lu.U.diagonal())
            if d.min() <= RCOND_MIN * d.max():
                raise Singular("tiny pivot")
            # pivot ratio: a cheap (optimistic) stand-in for the reciprocal condition number
            rcond = float(d.min() / d.max()) if d.size else 1.0
        else:
            J = np.asarray(J, dtype=float)
            if J.shape[0] != J.shape[1]:
                raise Singular("not square")
            if J.shape[0] == 0:          # nothing to solve; LAPACK would print "illegal value"
                self._lu, self._piv, self.rcond = None, None, 1.0
                return
            anorm = np.abs(J).sum(axis=0).max() if J.size else 0.0
            lu, piv, info = sla.lapack.dgetrf(J)  # the raw LAPACK call never warns
            if info > 0 or anorm == 0:
                raise Singular("exact zero pivot")
            rcond, _ = sla.lapack.dgecon(lu, anorm, norm="1")
            if rcond < RCOND_MIN:
                raise Singular(f"reciprocal condition {rcond:.2e}")
            self._lu, self._piv = lu, piv
        #: estimate of the reciprocal condition number (1-norm; pivot ratio when sparse)
        self.rcond = float(rcond)

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self.sparse:
            return self._lu.solve(np.asarray(b, dtype=float))
        if self._lu is None:
            return np.zeros_like(np.asarray(b, dtype=float))
        x, info = sla.lapack.dgetrs(self._lu, self._piv, b)
        return x

    def solve_transposed(self, b: np.ndarray) -> np.ndarray:
        """``J^T y = b`` from the same factors."""
        if self.sparse:
            return self._lu.solve(np.asarray(b, dtype=float), trans="T")
        if self._lu is None:
            return np.zeros_like(np.asarray(b, dtype=float))
        x, info = sla.lapack.dgetrs(self._lu, self._piv, b, trans=1)
        return x


def factor(J):
    """The factorisation of ``J``: :class:`Factor`, or, for a square CSC Jacobian assembled
    by a system (``System.assemble``, which attaches the system's
    :class:`FixedPattern` as ``J.mechsys_pattern``), the pattern's factorisation (banded LU
    for chains; the ordering analysed once instead of at every call). Each has ``rcond``
    and ``solve(b)``, and raises :class:`Singular` alike."""
    pat = getattr(J, "mechsys_pattern", None)
    if pat is not None and J.format == "csc" and J.indptr is pat.indptr \
            and len(J.data) == len(pat.indices):
        return pat.factor(J.data)
    return Factor(J)


class FixedPattern:
    r"""Square sparse matrices of one fixed CSC pattern (``indptr``, ``indices``), analysed
    once and then factorised numerically for each new set of values ``data``.

    Analysis: a reverse Cuthill-McKee ordering ``p`` of the symmetrised pattern
    (``A + A^T``) and the band widths ``kl``, ``ku`` of ``P A P^T``. With ``match_rows``
    (a constraint Jacobian, whose row ``i`` has nothing to do with column ``i``) the rows
    are first permuted to put a nonzero on the diagonal (a maximum bipartite matching of
    rows to columns, ``Q``), and the ordering is that of ``Q A``: ``(P Q A P^T) (P x) = P Q
    b``. Without it, the symmetric ordering of a chain's Jacobian has the width of the
    whole chain (its pinned coordinates' single-entry rows come first). For chains, and any
    mechanism whose bodies and joints form a path, the augmented matrix of free motion
    ``[[M, Phi_q^T], [Phi_q, 0]]`` is then banded with widths independent of the number
    of bodies, and LAPACK's banded LU with partial pivoting (``dgbtrf``) costs
    ``O(N kl (kl + ku))``: linear in the number of bodies. The values are scattered into
    the band storage through precomputed positions (no sparse-matrix objects per
    evaluation)::

        (P A P^T) (P x) = P b,    AB[kl + ku + i - j, j] = (P A P^T)_ij

    Patterns with wide bands (trees with many branches; ``N (kl + ku)^2 > BAND_WORK``, or
    ``BAND_WORK_SPARSE`` when the compiled sparse LU is available) take
    a fill-reducing symmetric ordering instead (multiple minimum degree of ``Q A + (Q
    A)^T``, :func:`_minimum_degree`; ``perm`` and ``row_perm`` are then that ordering's, and
    ``kl``, ``ku`` still the reverse Cuthill-McKee band's) and a sparse LU of ``B = P Q A
    P^T`` with threshold partial pivoting that keeps the diagonal while ``|b_kk| >=
    PIVOT_TOL max_i |b_ik|``: the compiled Gilbert-Peierls LU of ``_jit_sparse`` when Numba
    can be imported (the compiled loops call the same function, so both give the same
    numbers), else SuperLU with the same ordering and pivoting rule. A tree eliminated leaves
    first has no fill: the cost per factorisation is linear in the number of bodies whatever
    the branching. ``B``'s CSC structure is ``s_indptr``, ``s_indices``, and ``_pos`` the
    position in it of each stored value. ``sparse`` (a system's Jacobian): the sparse LU
    whatever the band; the compiled one beats LAPACK's banded LU on chains too, and one
    ordering for every installation keeps the pivot ratio (the condition estimate of large
    sweeps, which depends on the ordering) the same with and without Numba (decision 0031).

    Singular matrices raise :class:`Singular` as :class:`Factor` does for sparse ones: an
    exact zero pivot, or a pivot ratio ``min |u_ii| / max |u_ii| <= RCOND_MIN`` (also for
    non-finite values).

    Example::

        pat = FixedPattern(K.indptr, K.indices, K.shape[0])
        x = pat.factor(K.data).solve(b)       # K x = b
    """

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, size: int,
                 match_rows: bool = False, sparse: bool = False):
        self.indptr = np.asarray(indptr, dtype=np.int32)
        self.indices = np.asarray(indices, dtype=np.int32)
        self.size = N = int(size)
        rows = self.indices.astype(np.int64)
        cols = np.repeat(np.arange(N), np.diff(self.indptr))
        pat = sps.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(N, N))
        #: row_of[i]: the row of A that becomes row i of Q A (the identity without matching)
        row_of = np.arange(N)
        if match_rows and N:
            got = maximum_bipartite_matching(pat, perm_type="row").astype(np.int64)
            if (got >= 0).all():         # else structurally singular: no diagonal to find
                row_of = got
        pat_q = pat[row_of]
        perm = reverse_cuthill_mckee((pat_q + pat_q.T).tocsr(),
                                     symmetric_mode=True).astype(np.int64)
        inv = np.empty(N, dtype=np.int64)
        inv[perm] = np.arange(N)
        qinv = np.empty(N, dtype=np.int64)
        qinv[row_of] = np.arange(N)
        pr, pc = inv[qinv[rows]], inv[cols]
        #: the right-hand side's entries in the order of P Q A's rows
        self.row_perm = row_of[perm]
        self.kl = kl = int((pr - pc).max(initial=0))
        self.ku = ku = int((pc - pr).max(initial=0))
        self.perm = perm
        limit = BAND_WORK if _sparse_lu() is None else min(BAND_WORK, BAND_WORK_SPARSE)
        self.banded = N > 0 and N * (kl + ku) ** 2 <= limit and not sparse
        if self.banded:
            self._ld = 2 * kl + ku + 1
            # flat position in the Fortran-ordered (ld, N) band storage of each stored value
            self._pos = (kl + ku + pr - pc) + pc * self._ld
        elif N:
            # a wide band (trees): a fill-reducing symmetric ordering instead, sparse LU. Its
            # diagonal pivots need a zero-free diagonal: rows matched to columns for every
            # pattern (free motion's augmented matrix has a zero block, whose columns would
            # otherwise pivot off the diagonal and fill: 7.7 nonzeros per entry on a chain)
            if not match_rows:
                got = maximum_bipartite_matching(pat, perm_type="row").astype(np.int64)
                if (got >= 0).all():
                    row_of = got
                    pat_q = pat[row_of]
                    qinv[row_of] = np.arange(N)
            perm, fill = _minimum_degree(pat_q)
            inv[perm] = np.arange(N)
            pr, pc = inv[qinv[rows]], inv[cols]
            self.perm, self.row_perm = perm, row_of[perm]
            # P Q A P^T in CSC: each stored value's position in it (``_pos``), its structure
            order = np.lexsort((pr, pc))
            self._pos = np.empty(rows.size, dtype=np.int64)
            self._pos[order] = np.arange(rows.size)
            self.s_indptr = np.searchsorted(pc[order], np.arange(N + 1)).astype(np.int64)
            self.s_indices = pr[order].astype(np.int64)
            #: the sizes of L's and U's storage the next factorisation starts from: twice
            #: the fill of diagonal pivots (more is rare; the storage grows when it happens)
            self._cap = [2 * fill + N, 2 * fill + N]

    def factor(self, data: np.ndarray):
        """Factorise the matrix with these values (in the pattern's order)."""
        if self.banded:
            return _BandFactor(self, data)
        if _sparse_lu() is not None:
            return _SparseFactor(self, data)
        return _SuperFactor(self, data)


def pattern_slots(rows, cols, size: int, r, c) -> np.ndarray:
    """The positions of the entries ``(r[k], c[k])`` among a pattern's entries ``(rows,
    cols)`` in CSC order (as :func:`pattern_of` returns them): where to add each term's
    values into the pattern's. Every entry must be in the pattern."""
    key = np.asarray(cols, dtype=np.int64) * size + np.asarray(rows, dtype=np.int64)
    want = np.asarray(c, dtype=np.int64) * size + np.asarray(r, dtype=np.int64)
    k = np.searchsorted(key, want)
    if not np.array_equal(key[np.minimum(k, key.size - 1)], want):
        raise AssertionError("an entry is missing from the pattern it was built from")
    return k


def pattern_of(rows, cols, size: int, match_rows: bool = False, sparse: bool = False):
    """``(rows, cols, FixedPattern)`` of a square matrix whose entries can be nonzero at
    ``(rows[k], cols[k])`` (duplicates merged): the entries' rows and columns in CSC order
    (gather a dense matrix's values as ``A[rows, cols]``) and their pattern (``match_rows``,
    ``sparse``: :class:`FixedPattern`'s)."""
    key = np.unique(np.asarray(cols, dtype=np.int64) * size + np.asarray(rows, dtype=np.int64))
    r, c = key % size, key // size
    return r, c, FixedPattern(np.searchsorted(c, np.arange(size + 1)), r, size,
                              match_rows=match_rows, sparse=sparse)


class _BandFactor:
    """LAPACK banded LU of a :class:`FixedPattern` matrix; ``solve(b)``."""

    def __init__(self, pat: FixedPattern, data: np.ndarray):
        N, ld, kl, ku = pat.size, pat._ld, pat.kl, pat.ku
        ab = np.bincount(pat._pos, weights=data, minlength=ld * N).reshape(N, ld).T
        lu, ipiv, info = _dgbtrf(ab, kl, ku, overwrite_ab=1)
        if info > 0:
            raise Singular("exact zero pivot")
        d = np.abs(lu[kl + ku])
        if not d.min() > RCOND_MIN * d.max():        # also NaN
            raise Singular("tiny pivot")
        self.rcond = float(d.min() / d.max())
        self._lu, self._ipiv, self._pat = lu, ipiv, pat

    def solve(self, b: np.ndarray) -> np.ndarray:
        pat = self._pat
        y, info = _dgbtrs(self._lu, pat.kl, pat.ku, np.asarray(b, dtype=float)[pat.row_perm],
                          self._ipiv)
        x = np.empty_like(y)
        x[pat.perm] = y
        return x

    def solve_transposed(self, b: np.ndarray) -> np.ndarray:
        """``A^T y = b`` from the same factors: ``(P Q A P^T)^T (P Q y) = P b``."""
        pat = self._pat
        z, info = _dgbtrs(self._lu, pat.kl, pat.ku, np.asarray(b, dtype=float)[pat.perm],
                          self._ipiv, trans=1)
        y = np.empty_like(z)
        y[pat.row_perm] = z
        return y


class _Permuted:
    """``solve``/``solve_transposed`` of a factorisation of ``B = P Q A P^T`` (a
    :class:`FixedPattern`'s ordering) by the subclass's ``_solve(b, trans)`` of ``B``."""

    def solve(self, b: np.ndarray) -> np.ndarray:
        pat = self._pat
        y = self._solve(np.asarray(b, dtype=float)[pat.row_perm], False)
        x = np.empty_like(y)
        x[pat.perm] = y
        return x

    def solve_transposed(self, b: np.ndarray) -> np.ndarray:
        """``A^T y = b`` from the same factors: ``B^T (P Q y) = P b``."""
        pat = self._pat
        z = self._solve(np.asarray(b, dtype=float)[pat.perm], True)
        y = np.empty_like(z)
        y[pat.row_perm] = z
        return y

    def _check(self, d: np.ndarray) -> None:
        """The pivot ratio of ``U``'s diagonal ``d`` as :class:`_BandFactor` judges it."""
        d = np.abs(d)
        if not d.min() > RCOND_MIN * d.max():        # also NaN
            raise Singular("tiny pivot")
        self.rcond = float(d.min() / d.max())


class _SparseFactor(_Permuted):
    """The compiled sparse LU (``_jit_sparse``: left-looking, threshold partial pivoting
    that keeps the diagonal while ``|b_kk| >= PIVOT_TOL max_i |b_ik|``) of ``B = P Q A P^T``
    in the :class:`FixedPattern`'s minimum-degree ordering."""

    def __init__(self, pat: FixedPattern, data: np.ndarray):
        lu = _sparse_lu()
        N = pat.size
        Bx = np.zeros(pat.s_indices.size)
        Bx[pat._pos] = data
        Lp, Up = np.empty(N + 1, dtype=np.int64), np.empty(N + 1, dtype=np.int64)
        pinv = np.empty(N, dtype=np.int64)
        iw, xw = np.empty(lu.IWORK * N, dtype=np.int64), np.empty(N)
        while True:
            capL, capU = pat._cap
            Li, Ui = np.empty(capL, dtype=np.int64), np.empty(capU, dtype=np.int64)
            Lx, Ux = np.empty(capL), np.empty(capU)
            info = lu.lu_factor(N, pat.s_indptr, pat.s_indices, Bx, PIVOT_TOL, Lp, Li, Lx, Up,
                                Ui, Ux, pinv, iw, xw)
            if info != -1:
                break
            pat._cap = [2 * capL, 2 * capU]            # fill beyond the storage: grow, again
        if info > 0:
            raise Singular("exact zero pivot")
        if info < 0:
            raise Singular("non-finite values")
        self._f = (N, pinv, Lp, Li, Lx, Up, Ui, Ux)
        self._pat = pat
        #: entries of L (without its unit diagonal) and U
        self.fill = int(Lp[N] + Up[N])
        # the pivot ratio as the compiled loops take it (the same function)
        self.rcond = float(lu.lu_pivot_ratio(N, Up, Ux))
        if not self.rcond > RCOND_MIN:
            raise Singular("tiny pivot")

    def _solve(self, b: np.ndarray, trans: bool) -> np.ndarray:
        lu = _sparse_lu()
        x, w = np.empty_like(b), np.empty_like(b)
        (lu.lu_solve_t if trans else lu.lu_solve)(*self._f, b, x, w)
        return x


class _SuperFactor(_Permuted):
    """SuperLU of ``B = P Q A P^T`` (the :class:`FixedPattern`'s minimum-degree ordering,
    kept: ``permc_spec="NATURAL"``) with the same threshold pivoting as :class:`_SparseFactor`:
    the solve where Numba is missing."""

    def __init__(self, pat: FixedPattern, data: np.ndarray):
        N = pat.size
        Bx = np.zeros(pat.s_indices.size)
        Bx[pat._pos] = data
        B = sps.csc_matrix((Bx, pat.s_indices, pat.s_indptr), shape=(N, N))
        try:
            self._lu = spla.splu(B, permc_spec="NATURAL", diag_pivot_thresh=PIVOT_TOL)
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise Singular(str(exc)) from None
        self._pat = pat
        #: entries of L (without its unit diagonal) and U
        self.fill = int(self._lu.L.nnz + self._lu.U.nnz - N)
        self._check(self._lu.U.diagonal())

    def _solve(self, b: np.ndarray, trans: bool) -> np.ndarray:
        return self._lu.solve(b, trans="T" if trans else "N")


#: whether :class:`FixedPattern` may use the compiled sparse LU (tests switch it off to check
#: the SuperLU fallback)
COMPILED_LU = True
_LU: dict = {}


def _sparse_lu():
    """The compiled sparse LU module (``_jit_sparse``) when Numba can be imported (and
    :data:`COMPILED_LU`), else None."""
    if not COMPILED_LU:
        return None
    if "mod" not in _LU:
        try:
            from . import _jit_sparse
        except ImportError:
            _jit_sparse = None
        _LU["mod"] = _jit_sparse
    return _LU["mod"]


def _minimum_degree(pat) -> tuple[np.ndarray, int]:
    """A fill-reducing symmetric ordering of the pattern ``pat + pat^T`` (``pat``: N x N
    sparse): SuperLU's multiple minimum degree, postordered, as SuperLU computes it for
    ``permc_spec="MMD_AT_PLUS_A"``. SciPy exposes that ordering only through a
    factorisation, so a matrix of the pattern made strictly diagonally dominant is factorised
    once (its diagonal pivots keep the order symmetric). Returns ``perm``: the rows and
    columns in their new order, and the number of entries of the factors' triangles with the
    diagonal pivots of that factorisation (the larger of ``L``'s and ``U``'s). For a tree the
    elimination of its leaves first makes no fill, so the LU costs ``O(N)`` where the band of
    a star of branches is as wide as the star."""
    S = (abs(pat) + abs(pat).T).tocsc()
    S.data[:] = 1.0
    S = (S + sps.diags(np.asarray(S.sum(axis=0)).ravel() + 1.0)).tocsc()
    lu = spla.splu(S, permc_spec="MMD_AT_PLUS_A")
    return np.argsort(lu.perm_c).astype(np.int64), max(lu.L.nnz, lu.U.nnz)


#: from this many rows on, :func:`dependent_rows` first tries the sparse certificate
#: :func:`_clearly_full_rank` (the dense pivoted QR costs O(m^2 n): 0.3 s at m = 512)
CERTIFY_ROWS = 100
#: whether :func:`dependent_rows` tries a certificate before the QR (tests compare both)
CERTIFY = True
#: reciprocal condition of ``J J^T`` above which ``J`` has full row rank for the QR test:
#: ``rcond(J J^T) = (sigma_min / sigma_max)^2 >= 1e-8`` gives ``|R_kk| >= sigma_min >=
#: 1e-4 sigma_max``, far above the QR threshold ``~1e3 max(m, n) eps |R_00|``
CERTIFY_RCOND = 1e-8


def _clearly_full_rank(J) -> bool:
    """Whether ``J`` (m x n) certainly has full row rank by the test of
    :func:`dependent_rows`, from a sparse LU of ``G = J J^T`` and an estimate of its
    reciprocal condition number (Hager's 1-norm estimate of ``G^-1``, a few solves):
    linear cost for chains and trees, where the dense QR is cubic. False means "not
    certain": the caller runs the QR. The margin (1e-8 against the QR's ~1e-19 for the
    same property in ``G``) absorbs the estimate's underestimation of ``||G^-1||``."""
    Js = sps.csr_matrix(J)
    G = (Js @ Js.T).tocsc()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            lu = spla.splu(G)
    except RuntimeError:
        return False
    m = G.shape[0]
    gnorm = float(abs(G).sum(axis=0).max())
    if not np.isfinite(gnorm) or gnorm == 0.0:
        return False
    # Hager's method for ||G^-1||_1 (G symmetric: G^-T = G^-1)
    x = np.full(m, 1.0 / m)
    est, j_last = 0.0, -1
    for _ in range(5):
        y = lu.solve(x)
        if not np.all(np.isfinite(y)):
            return False
        est = max(est, float(np.abs(y).sum()))
        z = lu.solve(np.where(y >= 0, 1.0, -1.0))
        j = int(np.argmax(np.abs(z)))
        if abs(z[j]) <= z @ x or j == j_last:
            break
        x = np.zeros(m)
        x[j] = 1.0
        j_last = j
    # Higham's extra vector (alternating, growing): catches what the iteration misses
    alt = np.array([(-1.0) ** i * (1.0 + i / max(m - 1, 1)) for i in range(m)])
    est = max(est, 2.0 * float(np.abs(lu.solve(alt)).sum()) / (3.0 * m))
    return 1.0 / (gnorm * est) >= CERTIFY_RCOND


def _clearly_full_rank_dense(J) -> bool:
    """:func:`_clearly_full_rank` for a small ``J``: Cholesky of ``G = J J^T`` (LAPACK
    ``dpotrf``) and LAPACK's estimate of its reciprocal condition (``dpocon``, the same
    1-norm estimator), in about a tenth of the pivoted QR's time. False: not certain (``G``
    not numerically positive definite, or too ill-conditioned for the certificate); the
    caller then runs the QR."""
    J = J.toarray() if sps.issparse(J) else np.asarray(J, dtype=float)
    if J.shape[0] > J.shape[1] or not np.isfinite(J).all():
        return False
    G = J @ J.T
    c, info = sla.lapack.dpotrf(G, lower=0)
    if info != 0:
        return False
    gnorm = float(np.abs(G).sum(axis=0).max())
    if not np.isfinite(gnorm) or gnorm == 0.0:
        return False
    rcond, info = sla.lapack.dpocon(c, gnorm)      # (upper, as dpotrf gave it)
    return info == 0 and rcond >= CERTIFY_RCOND


def dependent_rows(J, tol: float | None = None) -> tuple[int, list[int]]:
    """Rank of ``J`` and the rows (equations) that depend on the others.

    Pivoted QR of ``J^T``: the columns of ``J^T`` (rows of ``J``) chosen last are the
    dependent ones. A well-conditioned ``J J^T`` (reciprocal condition estimate at least
    ``CERTIFY_RCOND``) certifies full row rank first, without the QR.
    """
    m = J.shape[0]
    if m == 0:
        return 0, []
    if tol is None and CERTIFY and (_clearly_full_rank(J) if m >= CERTIFY_ROWS
                                    else _clearly_full_rank_dense(J)):
        return m, []
    J = J.toarray() if sps.issparse(J) else np.asarray(J, dtype=float)
    m, n = J.shape
    _, R, piv = sla.qr(J.T, pivoting=True, mode="economic")
    d = np.abs(np.diag(R))
    if tol is None:
        tol = max(m, n) * np.finfo(float).eps * (d[0] if d.size else 0.0) * 1e3
    rank = int((d > tol).sum())
    return rank, sorted(int(i) for i in piv[rank:])


def involved_rows(J, rank: int, tol: float = 1e-8) -> list[int]:
    """Rows (equations) taking part in the linear dependency of ``J`` of the given rank:
    those with a non-negligible weight in a basis of the left null space (``J^T y = 0``).
    :func:`dependent_rows` picks *which* rows to drop; this says which rows are *involved*
    (for example both of two constraints that fix the same coordinate)."""
    J = J.toarray() if sps.issparse(J) else np.asarray(J, dtype=float)
    if rank >= J.shape[0]:
        return []
    U, _, _ = sla.svd(J, full_matrices=True)
    null = U[:, rank:]
    return sorted(int(i) for i in np.nonzero(np.abs(null).max(axis=1) > tol)[0])


class Scaling:
    r"""The unit-free form of the constraint equations used by every kinematic decision.

    A change of the unit of length multiplies the position coordinates and every length of a
    model by one factor; the angles (and Euler parameters) do not change. Tolerances and
    conditioning measured on the raw Jacobian then depend on the unit. The solvers therefore
    decide on

    .. math::  \hat\Phi = R^{-1} \Phi, \qquad \hat\Phi_{\hat q} = R^{-1} \Phi_q D

    with ``D = diag(c)``: ``c_j = L`` for the position coordinates of the bodies and 1 for
    angles, Euler parameters and model variables (whose dimension mechsys cannot know), so
    that ``q = D q_hat`` measures positions in units of ``L``; and ``R = diag(r)`` with
    ``r_i = max_j |(Phi_q D)_ij|``, the size of row ``i`` in those units (1 for an empty row),
    which makes each equation dimensionless whatever its own dimension (length, length^2,
    angle, none). ``|Phi_i| / r_i`` is then, to first order, how far (in units of ``L``, or
    radians) the coordinates are from satisfying equation ``i``.

    ``L``, the characteristic length, is the largest lever arm of the constraint equations at
    a reference configuration: for each equation and body the ratio of the largest
    rotational to the largest translational Jacobian entry (for a point of a body the
    distance of the point from the body origin, for a distance or a point-on-line equation a
    distance of the geometry). It falls back to the system's ``length_hint`` (the largest
    local coordinate of the bodies' points and centroids), then to the largest position
    coordinate, then to 1 (a model without lengths). ``L`` scales exactly with the unit, so
    the scaled Jacobian, its condition number and its rank are unit-invariant. ``offset`` is
    the largest position coordinate divided by ``L`` (a mechanism far from the origin): the
    convergence test allows for the rounding of the coordinates with it.
    """

    def __init__(self, length: float, columns: np.ndarray, offset: float = 1.0):
        self.length = float(length)
        self.columns = columns
        self.offset = float(offset)

    @classmethod
    def of(cls, system, q, J) -> Scaling:
        """The scaling of ``system`` at the reference configuration ``q`` with Jacobian ``J``."""
        n = system.n
        trans, body = _column_kinds(system)
        q = np.asarray(q, dtype=float)
        big = float(np.abs(q[trans]).max(initial=0.0)) if n else 0.0
        if not np.isfinite(big):
            big = 0.0
        arm = _lever_arm(J, trans, body)
        hint = length_hint(system)
        # a lever arm that is round-off of the model's lengths is no length: a crank pin in
        # line with its rod (a dead centre at the reference configuration) leaves only
        # 1e-16-sized rotational entries, and L = 1e-16 would make every solve "singular"
        ref = hint if hint > 0 else big
        if ref > 0 and arm <= ARM_ROUNDOFF * ref:
            arm = 0.0
        L = arm if arm > 0 else (hint if hint > 0 else (big if big > 0 else 1.0))
        columns = np.where(trans, L, 1.0)
        return cls(L, columns, big / L)

    def rows(self, J) -> np.ndarray:
        """Row scales ``r`` (m,) of the Jacobian ``J``."""
        if sps.issparse(J):
            # on the CSC arrays: building scipy matrices costs more than the arithmetic
            J = _csc(J)
            r = np.zeros(J.shape[0])
            np.maximum.at(r, J.indices, np.abs(J.data) * self._nz_columns(J))
        else:
            r = np.abs(J * self.columns).max(axis=1) if J.size else np.zeros(J.shape[0])
        r[~(r > 0)] = 1.0  # an empty (or NaN) row: nothing to measure it by
        return r

    def scaled(self, J, r: np.ndarray | None = None):
        """``R^-1 J D`` (dense or sparse like ``J``)."""
        r = self.rows(J) if r is None else r
        if sps.issparse(J):
            Js = _csc(J).copy()
            Js.data *= self._nz_columns(Js) / r[Js.indices]
            return Js
        return (np.asarray(J, dtype=float) * self.columns) * (1.0 / r)[:, None]

    def _nz_columns(self, J) -> np.ndarray:
        """Column scale of every stored entry of the CSC matrix ``J``."""
        return np.repeat(self.columns, np.diff(J.indptr))

    def factor(self, J, r: np.ndarray | None = None) -> ScaledFactor:
        """Factorise the scaled Jacobian; its ``solve(b)`` solves ``J x = b``."""
        r = self.rows(J) if r is None else r
        if sps.issparse(J) and J.format == "csc":
            # swap the scaled values in for the factorisation only: no new scipy matrix
            # (whose construction costs more than the arithmetic); J is unchanged afterwards
            raw = J.data
            J.data = raw * (self._nz_columns(J) / r[J.indices])
            try:
                fac = factor(J)
            finally:
                J.data = raw
        else:
            fac = Factor(self.scaled(J, r))
        return ScaledFactor(fac, r, self.columns)

    def dependent_rows(self, J) -> tuple[int, list[int]]:
        """:func:`dependent_rows` of the scaled Jacobian (unit-invariant rank)."""
        return dependent_rows(self.scaled(J))

    def involved_rows(self, J, rank: int) -> list[int]:
        """:func:`involved_rows` of the scaled Jacobian."""
        return involved_rows(self.scaled(J), rank)


class ScaledFactor:
    """A :class:`Factor` of ``R^-1 J D``; ``solve(b)`` returns ``x`` with ``J x = b``."""

    def __init__(self, fac: Factor, rows: np.ndarray, columns: np.ndarray):
        self._fac, self._rows, self._columns = fac, rows, columns
        #: reciprocal condition number of the scaled matrix (unit-invariant)
        self.rcond = fac.rcond

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._columns * self._fac.solve(np.asarray(b, dtype=float) / self._rows)

    def solve_transposed(self, b: np.ndarray) -> np.ndarray:
        """``lambda`` with ``J^T lambda = b``: ``(R^-1 J D)^T (R lambda) = D b``."""
        return self._fac.solve_transposed(self._columns * np.asarray(b, dtype=float)) / self._rows


def length_hint(system) -> float:
    """The system's ``length_hint`` (0.0 when it has none): :class:`Scaling`'s fallback length."""
    return float(getattr(system, "length_hint", 0.0) or 0.0)


def _csc(J):
    return J if J.format == "csc" else sps.csc_matrix(J)


def _column_kinds(system) -> tuple[np.ndarray, np.ndarray]:
    """Per coordinate: is it a body position coordinate; which body (-1: a variable).
    (Read-only arrays, kept on the system for its layout: every sweep asks twice.)"""
    n, dim, layout = system.n, system.space.dim, system.layout
    got = getattr(system, "_column_kinds_of", None)
    if got is not None and got[0] is layout and got[1] == n and got[2] == dim:
        return got[3], got[4]
    trans = np.zeros(n, dtype=bool)
    body = np.full(n, -1)
    for k, sl in enumerate(layout.body_slices.values()):
        body[sl] = k
        trans[sl.start : sl.start + dim] = True
    trans.setflags(write=False)
    body.setflags(write=False)
    try:
        system._column_kinds_of = (layout, n, dim, trans, body)
    except (AttributeError, TypeError):  # a frozen or slotted stand-in: no cache
        pass
    return trans, body


#: above this many entries a dense Jacobian with less than 5 % nonzeros goes to the scatter
#: of its nonzero entries in :func:`_lever_arm` instead of :func:`_lever_arm_dense`
LEVER_DENSE_MAX = 250_000


def _lever_arm(J, trans: np.ndarray, body: np.ndarray) -> float:
    """Largest ratio, over equations and bodies, of the largest rotational to the largest
    translational Jacobian entry (a length: see :class:`Scaling`)."""
    if sps.issparse(J):
        c = sps.coo_matrix(J)
        i, j, v = c.row, c.col, np.abs(c.data)
    else:
        J = np.asarray(J, dtype=float)
        # a large, mostly empty dense Jacobian (a 1024-link chain's: 2048 x 3072, 0.1 %
        # filled) by its nonzero entries: the maxima over every row and column group cost
        # 0.3 s there, the scatter of its 8,000 entries milliseconds (the same maxima: the
        # zeros add nothing to a maximum of absolute values)
        sparse_enough = J.size > LEVER_DENSE_MAX and np.count_nonzero(J) * 20 < J.size
        arm = None if sparse_enough else _lever_arm_dense(J, trans, body)
        if arm is not None:
            return arm
        i, j = np.nonzero(J)
        v = np.abs(J[i, j])
    keep = (body[j] >= 0) & np.isfinite(v)
    i, j, v = i[keep], j[keep], v[keep]
    if not v.size:
        return 0.0
    nb = int(body.max()) + 1
    key = i * nb + body[j]
    size = (int(i.max()) + 1) * nb
    tmax = np.zeros(size)
    rmax = np.zeros(size)
    np.maximum.at(tmax, key[trans[j]], v[trans[j]])
    np.maximum.at(rmax, key[~trans[j]], v[~trans[j]])
    ok = (tmax > 0) & (rmax > 0)
    return float((rmax[ok] / tmax[ok]).max()) if ok.any() else 0.0


def _lever_arm_dense(J: np.ndarray, trans: np.ndarray, body: np.ndarray) -> float | None:
    """:func:`_lever_arm` of a dense ``J`` whose bodies' columns are contiguous, each with
    translational and then rotational ones (every body of a layout): the largest entries per
    row and column group by one ``maximum.reduceat`` (the general scatter costs several
    times more). The same maxima and ratios, hence the same value. None when the columns
    are not so grouped."""
    groups = _groups(trans, body)
    if groups is None or J.shape[0] == 0:
        return None
    cols, starts = groups
    A = np.abs(J[:, cols])
    A[~np.isfinite(A)] = 0.0
    M = np.maximum.reduceat(A, starts, axis=1)
    tmax, rmax = M[:, 0::2], M[:, 1::2]
    ok = (tmax > 0) & (rmax > 0)
    return float((rmax[ok] / tmax[ok]).max()) if ok.any() else 0.0


_GROUPS: dict = {}


def _groups(trans: np.ndarray, body: np.ndarray):
    """``(cols, starts)`` of :func:`_lever_arm_dense` (kept per column layout), or None."""
    key = (trans.tobytes(), body.tobytes())
    if key in _GROUPS:
        return _GROUPS[key]
    cols = np.flatnonzero(body >= 0)
    out = None
    if cols.size:
        b, tr = body[cols], trans[cols]
        new = np.ones(cols.size, dtype=bool)
        new[1:] = (b[1:] != b[:-1]) | (tr[1:] != tr[:-1])
        starts = np.flatnonzero(new)
        gb, gt = b[starts], tr[starts]
        # each body exactly one translational group followed by one rotational group
        if gb.size % 2 == 0 and np.all(gb[0::2] == gb[1::2]) and np.all(gt[0::2]) \
                and not np.any(gt[1::2]) and np.unique(gb).size == gb.size // 2:
            out = (cols, starts)
    if len(_GROUPS) > 256:
        _GROUPS.clear()
    _GROUPS[key] = out
    return out


def rotation_columns(system) -> np.ndarray:
    """Mask (n,) of the bodies' rotational coordinates (angles, Euler parameters)."""
    trans, body = _column_kinds(system)
    return (body >= 0) & ~trans


def rotation_indices(system) -> np.ndarray:
    """Indices (int64, read-only) of :func:`rotation_columns` (kept with the column kinds)."""
    trans, body = _column_kinds(system)
    got = getattr(system, "_rotation_indices_of", None)
    if got is not None and got[0] is trans:
        return got[1]
    idx = np.flatnonzero((body >= 0) & ~trans).astype(np.int64)
    idx.setflags(write=False)
    try:
        system._rotation_indices_of = (trans, idx)
    except (AttributeError, TypeError):  # a frozen or slotted stand-in: no cache
        pass
    return idx
