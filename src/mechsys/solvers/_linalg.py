r"""Linear algebra for the constraint Jacobian: factorisation with a conditioning check, and
rank-revealing diagnosis of dependent equations.

Small systems (``n <= SPARSE_THRESHOLD``) use dense LU with LAPACK's reciprocal condition
estimate; larger ones sparse SuperLU. A matrix whose reciprocal condition number falls
below ``RCOND_MIN`` is treated as singular and diagnosed with a pivoted QR of ``Phi_q^T``:
its last ``m - rank`` pivots are the dependent equations.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

SPARSE_THRESHOLD = 150
RCOND_MIN = 1e-13


class Singular(Exception):
    """Raised by :func:`factor` when the matrix is numerically singular."""


class Factor:
    """A factorised square matrix; ``solve(b)`` for one or several right-hand sides."""

    def __init__(self, J):
        self.sparse = sps.issparse(J)
        if self.sparse:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", sps.SparseEfficiencyWarning)
                    self._lu = spla.splu(sps.csc_matrix(J))
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
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", sla.LinAlgWarning)
                lu, piv, info = sla.lapack.dgetrf(J)
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


def factor(J) -> Factor:
    return Factor(J)


def dependent_rows(J, tol: float | None = None) -> tuple[int, list[int]]:
    """Rank of ``J`` and the rows (equations) that depend on the others.

    Pivoted QR of ``J^T``: the columns of ``J^T`` (rows of ``J``) chosen last are the
    dependent ones.
    """
    J = J.toarray() if sps.issparse(J) else np.asarray(J, dtype=float)
    m, n = J.shape
    if m == 0:
        return 0, []
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
