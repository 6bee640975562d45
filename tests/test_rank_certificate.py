"""The sparse certificate of full row rank that spares large models the dense pivoted QR
(solvers/_linalg._clearly_full_rank): it never claims full rank where the QR finds a
dependent row, and it does claim it for well-conditioned Jacobians (else it saves nothing)."""

import numpy as np
import pytest
import scipy.sparse as sps

from mechsys import models
from mechsys.solvers import _linalg
from mechsys.solvers._linalg import _clearly_full_rank, dependent_rows


def _qr_rank(J):
    old = _linalg.CERTIFY_ROWS
    try:
        _linalg.CERTIFY_ROWS = 10**9
        return dependent_rows(J)
    finally:
        _linalg.CERTIFY_ROWS = old


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
