r"""The fixed sparsity patterns of a system's large matrices, analysed once per system (or
dynamics) and shared by the Python solvers and the compiled loops, which factorise the same
matrices through the same :class:`~mechsys.solvers._linalg.FixedPattern`:

* :func:`projection_pattern`: the projection's ``[[I, J^T], [J, 0]]`` (free motion);
* :func:`free_newton_pattern`: free motion's Newton matrix
  ``[[M - dQ/dqdd, Phi_q^T - dQ/dlambda], [Phi_q, 0]]`` (loads that depend on the
  accelerations or multipliers);
* :func:`multiplier_newton_pattern`: the multiplier solves' Newton matrix
  ``Phi_q^T - dQ/dlambda`` (friction over a sweep).

Each is the union of the blocks' nonzeros, in CSC order, so that one factorisation's
analysis (row matching, fill-reducing order, band) serves every time step or point. For the
multiplier matrix of a square system, with ``J = Phi_q``:

.. math:: K = J^T - \frac{\partial Q}{\partial \lambda}, \qquad
          \operatorname{pattern}(K) = \operatorname{pattern}(J^T) \cup
          \operatorname{pattern}(\partial Q / \partial \lambda)

Here so that the solvers (``_free``, ``_statics``) and the drivers of their compiled loops
(``_jit_free``, ``_jit_multipliers``) import them from below both (decision 0058).

Example::

    rows, cols, pattern = multiplier_newton_pattern(system)
    factor = pattern.factor(values)          # values of K at (rows, cols), CSC order
"""

from __future__ import annotations

import numpy as np

from ._linalg import pattern_of, pattern_slots


def projection_pattern(system):
    """``(FixedPattern, slots)`` of the projection's matrix ``[[I, J^T], [J, 0]]`` (``n + m``)
    of a system's sparse Jacobian, analysed once per system (the compiled sparse LU's
    minimum-degree ordering): ``slots`` (n + 2 nnz,) the places among the pattern's entries
    of the identity's diagonal, then of ``J``'s entries in its CSC order
    (``System._csc_structure``), then of ``J^T``'s. The compiled steppers project through
    the same pattern (``_jit_free_loop._min_norm_sparse``)."""
    got = system.__dict__.get("_projection_pattern")
    if got is None:
        n, m = system.n, system.m
        _, indices, indptr = system._csc_structure()
        jr = indices.astype(np.int64)
        jc = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
        d = np.arange(n, dtype=np.int64)
        rows = np.concatenate((d, n + jr, jc))
        cols = np.concatenate((d, jc, n + jr))
        r, c, pat = pattern_of(rows, cols, n + m, sparse=True)
        got = system.__dict__["_projection_pattern"] = (
            pat, pattern_slots(r, c, n + m, rows, cols))
    return got


def free_newton_pattern(system):
    """``(rows, cols, FixedPattern)`` of the Newton matrix ``[[M - dQ/dqdd, Phi_q^T -
    dQ/dlambda], [Phi_q, 0]]`` of a large system: every entry the dense matrix can hold
    (the mass matrix's, ``dQ/dqdd``'s, the Jacobian's and ``dQ/dlambda``'s nonzeros, the
    positions the dense blocks are filled from), in CSC order, made once per dynamics."""
    dyn = system.dynamics
    got = dyn.__dict__.get("_newton_pattern")
    if got is not None and got[0] is system:
        return got[1]
    n, m = system.n, system.m
    jr, jc = np.asarray(system.jac_rows, dtype=np.int64), np.asarray(system.jac_cols, dtype=np.int64)
    r = [np.asarray(dyn.M_rows, dtype=np.int64), jc, n + jr]
    c = [np.asarray(dyn.M_cols, dtype=np.int64), n + jr, jc]
    if dyn.depends_on_qdd:
        r.append(np.asarray(dyn.dA_rows, dtype=np.int64))
        c.append(np.asarray(dyn.dA_cols, dtype=np.int64))
    if dyn.depends_on_lambda:
        r.append(np.asarray(dyn.dQ_rows, dtype=np.int64))
        c.append(n + np.asarray(dyn.dQ_cols, dtype=np.int64))
    got = pattern_of(np.concatenate(r), np.concatenate(c), n + m)
    dyn.__dict__["_newton_pattern"] = (system, got)
    return got


def multiplier_newton_pattern(system):
    """``(rows, cols, FixedPattern)`` of the multiplier Newton matrix ``Phi_q^T -
    dQ/dlambda`` (n, m) of a square system: the transposed Jacobian's and ``dQ/dlambda``'s
    nonzeros in CSC order, rows matched to columns (decision 0030), made once per
    dynamics."""
    dyn = system.dynamics
    got = dyn.__dict__.get("_multiplier_pattern")
    if got is not None and got[0] is system:
        return got[1]
    n = system.n
    r = np.concatenate((np.asarray(system.jac_cols, dtype=np.int64),
                        np.asarray(dyn.dQ_rows, dtype=np.int64)))
    c = np.concatenate((np.asarray(system.jac_rows, dtype=np.int64),
                        np.asarray(dyn.dQ_cols, dtype=np.int64)))
    got = pattern_of(r, c, n, match_rows=True)
    dyn.__dict__["_multiplier_pattern"] = (system, got)
    return got


__all__ = ["free_newton_pattern", "multiplier_newton_pattern", "projection_pattern"]
