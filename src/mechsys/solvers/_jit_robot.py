r"""The Python driver of the robot entry points' compiled forward dynamics over points
(``m.forward_dynamics``, ``analyses._robot``; decision 0073): it decides whether the loop
can run, gathers the recursive Gen dynamics' C entry points, and calls
``_jit_free_loop.gen_forward`` specialised on its kind. At each point ``k`` the loop solves

.. math:: M(q_k) \ddot q_k + \Phi_q^T \lambda_k = Q + Q_v + F_k, \qquad
          \Phi_q \ddot q_k = \gamma

with the evaluations of the compiled free-motion stepper (``_accel_gen``): a tree of Gen
joints without constraint equations by the articulated-body recursion, anything else by the
composite-body mass matrix in the augmented system (LU, regular pivots only). It stops at
the first point that needs the Python path's care and returns its index.

Example (what ``analyses._robot._forward_points`` does)::

    got = forward(system, 0.0, Q, QD, F)      # F (N, n): joint forces on the coordinates
    if got is not None:
        QDD, done = got                       # QDD[:done] filled
"""

from __future__ import annotations

import numpy as np

from ._jit_cache import notice
from ._jit_runtime import GenTree, available, index, kernel_entry

_state: dict = {"gen_forward": None}

#: the kinds of ``gen_forward`` (its literal argument)
_TREE, _AUGMENTED = 1, 0


def forward(system, t, Q, QD, F):
    """``(QDD (N, n), N')``: the accelerations at the first ``N'`` points of the states
    ``Q``, ``QD`` (N, n) under the forces ``F`` (N, n) on the coordinates, by the compiled
    loop; the points from ``N'`` on are the Python path's (values not finite, a joint that
    moves no mass, a redundant or singular system). None when the loop cannot run: not the
    recursive Gen dynamics, kernels without C entry points, Numba missing, or the loop being
    compiled in the background (decision 0064). The caller decides whether it should run
    (the ``MECHSYS_JIT`` rule)."""
    dyn = system.dynamics
    if not getattr(dyn, "recursive", False) or not available():
        return None
    entry = kernel_entry(dyn._main)
    if entry is None:
        return None
    gen = GenTree.of(system, dyn, entry[0])
    if gen is None:
        return None
    if _state["gen_forward"] is None:
        from ._jit_free_loop import gen_forward

        _state["gen_forward"] = gen_forward
    from ._jit_modes import entry as _entry

    N, n = len(Q), system.n
    QDD = np.empty((N, n))
    args = (np.asarray(entry[0], dtype=np.int64), gen.arrays, entry[1], np.full(N, float(t)),
            np.ascontiguousarray(Q, dtype=float), np.ascontiguousarray(QD, dtype=float),
            np.ascontiguousarray(F, dtype=float),
            np.ascontiguousarray(system.p_values, dtype=float), system.m,
            index(system.jac_rows), index(system.jac_cols), _TREE if gen.tree else _AUGMENTED,
            QDD)
    # (the kind as a literal: a tree's loop compiles no LU, the augmented one no recursion)
    fn = _entry(_state["gen_forward"], args, literal=(11,), say=lambda how: notice(
        "the recursive dynamics' forward dynamics", None, background=how == "background"))
    if fn is None:
        return None
    k = int(fn(*args))
    return QDD, k


__all__ = ["forward"]
