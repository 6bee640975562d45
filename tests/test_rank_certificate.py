"""The certificates of full row rank that spare the pivoted QR (solvers/_linalg): the sparse
one of large models (``_clearly_full_rank``) and the dense Cholesky one of small models
(``_clearly_full_rank_dense``). Neither claims full rank where the QR finds a dependent
row, and both claim it for well-conditioned Jacobians (else they save nothing)."""

import numpy as np
import pytest
import scipy.sparse as sps

from mechsys import models
from mechsys.solvers import _linalg
from mechsys.solvers._linalg import _clearly_full_rank, _clearly_full_rank_dense, dependent_rows


def _qr_rank(J):
    old = _linalg.CERTIFY
    try:
        _linalg.CERTIFY = False
        return dependent_rows(J)
    finally:
        _linalg.CERTIFY = old


def _with_singular_values(rng, m, n, s):
    U, _ = np.linalg.qr(rng.standard_normal((m, m)))
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return (U * s) @ V[:m]


@pytest.mark.parametrize("seed", range(6))
def test_never_claims_full_rank_for_a_dependent_or_near_dependent_matrix(seed):
    rng = np.random.default_rng(seed)
    m, n = 120, 150
    for smallest in (0.0, 1e-14, 1e-9, 1e-6):
        s = np.linspace(1.0, 0.5, m)
        s[-1 - seed % 3:] = smallest          # one to three (nearly) dependent rows
        J = _with_singular_values(rng, m, n, s)
        assert not _clearly_full_rank(J)
        assert not _clearly_full_rank(sps.csr_matrix(J))
    # a repeated row, the typical redundant constraint
    J = rng.standard_normal((m, n))
    J[7] = J[3]
    assert not _clearly_full_rank(J)
    rank, dep = dependent_rows(J)
    assert rank == m - 1 and dep in ([3], [7]) and (rank, dep) == _qr_rank(J)


@pytest.mark.parametrize("seed", range(4))
def test_well_conditioned_matrices_are_certified_and_agree_with_the_qr(seed):
    rng = np.random.default_rng(100 + seed)
    J = _with_singular_values(rng, 150, 200, np.linspace(1.0, 1e-3, 150))
    assert _clearly_full_rank(J)
    assert dependent_rows(J) == _qr_rank(J) == (150, [])


def test_a_long_chain_takes_the_certificate_and_the_results_do_not_change(monkeypatch):
    m = models.pendulum_chain(60)       # 120 pin equations, 180 coordinates
    m.solve(0.0)
    s = m.free(drop=[f"lock{k}" for k in range(60)]).system
    J = s.jacobian(0.0, s.guess, s.p_values)
    assert J.shape[0] >= _linalg.CERTIFY_ROWS
    assert _clearly_full_rank(J)
    assert dependent_rows(J) == _qr_rank(J) == (120, [])
    # redundant: the same chain with one pin written twice keeps its dependent row found
    J2 = sps.vstack([J, J[5]]).tocsr() if sps.issparse(J) else np.vstack([J, J[5]])
    assert not _clearly_full_rank(J2)
    assert dependent_rows(J2)[0] == 120


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("shape", [(1, 3), (4, 6), (8, 12), (20, 30), (9, 9)])
def test_dense_certificate_never_claims_a_dependent_matrix(seed, shape):
    rng = np.random.default_rng(200 + seed)
    m, n = shape
    for smallest in (0.0, 1e-14, 1e-9, 1e-6):
        if m == 1 and smallest:
            continue
        s = np.linspace(1.0, 0.5, m)
        s[-1 - seed % min(m, 3):] = smallest
        J = _with_singular_values(rng, m, n, s)
        assert not _clearly_full_rank_dense(J)
    if m > 1:
        J = rng.standard_normal((m, n))
        J[m - 1] = J[0] * 3.0                     # a repeated (scaled) row
        assert not _clearly_full_rank_dense(J)
        assert dependent_rows(J) == _qr_rank(J) and dependent_rows(J)[0] == m - 1
    for bad in (np.nan, np.inf):
        J = rng.standard_normal((m, n))
        J[0, 0] = bad
        assert not _clearly_full_rank_dense(J)
    assert not _clearly_full_rank_dense(rng.standard_normal((n + 1, n)))   # more rows than columns


@pytest.mark.parametrize("seed", range(4))
def test_dense_certificate_certifies_well_conditioned_and_agrees_with_the_qr(seed):
    rng = np.random.default_rng(300 + seed)
    for m, n in ((1, 3), (4, 6), (8, 12), (30, 40)):
        J = _with_singular_values(rng, m, n, np.linspace(1.0, 1e-3, m))
        assert _clearly_full_rank_dense(J) and _clearly_full_rank_dense(sps.csr_matrix(J))
        assert dependent_rows(J) == _qr_rank(J) == (m, [])
    # a pendulum chain's scaled Jacobian (the free-motion start check)
    m = models.pendulum_chain(4)
    m.solve(0.0)
    s = m.free(drop=[f"lock{k}" for k in range(4)]).system
    J = s.jacobian(0.0, s.guess, s.p_values)
    assert _clearly_full_rank_dense(J) and dependent_rows(J) == _qr_rank(J) == (8, [])
