"""The SymEngine and SymPy derivation paths give the same Jacobian, gamma and Lagrange terms."""

import numpy as np
import pytest

from mechsys import models
from mechsys.compile import _derive

se = pytest.importorskip("symengine")


def _numeric(exprs, subs):
    return np.array([float(e.subs(subs)) for e in exprs])


def test_kinematic_derivation_paths_agree(monkeypatch):
    m = models.four_bar()
    s = m.compile()
    lay = s.layout
    from mechsys import T

    fast = _derive.derive_kinematics(s.phi, lay.q_symbols, lay.qd_symbols, T)
    monkeypatch.setattr(_derive, "se", None)
    slow = _derive.derive_kinematics(s.phi, lay.q_symbols, lay.qd_symbols, T)
    assert fast[0] == slow[0] and fast[1] == slow[1]
    rng = np.random.default_rng(0)
    subs = {sym: rng.standard_normal() for sym in (*lay.q_symbols, *lay.qd_symbols)}
    subs[T] = 0.37
    native = fast[5]
    for k, key in ((2, "jac"), (3, "phi_t"), (4, "gamma")):
        f = _derive.to_sympy_list(native[key]) if native is not None else fast[k]
        np.testing.assert_allclose(_numeric(f, subs), _numeric(slow[k], subs), atol=1e-12)


def test_lagrange_terms_paths_agree(monkeypatch):
    import sympy as sp

    q = sp.symbols("a b")
    qd = sp.symbols("ad bd")
    Tk = (q[0] ** 2 + sp.cos(q[1])) * qd[0] ** 2 / 2 + q[0] * qd[0] * qd[1] + sp.sin(q[1]) * qd[1] ** 2
    M1, Q1 = _derive.hessian_terms(Tk, q, qd)
    monkeypatch.setattr(_derive, "se", None)
    M2, Q2 = _derive.hessian_terms(Tk, q, qd)
    subs = dict(zip((*q, *qd), (0.3, -0.4, 1.1, 0.7)))
    for i in range(2):
        for j in range(2):
            assert abs(float(M1[i][j].subs(subs)) - float(M2[i][j].subs(subs))) < 1e-12
        assert abs(float(Q1[i].subs(subs)) - float(Q2[i].subs(subs))) < 1e-12
