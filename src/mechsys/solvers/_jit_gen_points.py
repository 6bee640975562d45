r"""The Python driver of ``_jit_free_loop.gen_points``: the recursive Gen dynamics
(``compile._generalized.RecursiveDynamics``) evaluated at many given states in one compiled
loop. It decides whether the loop can run, gathers the C entry points of the joint kernels
and of the main kernel, and calls the loop. Its users: the right-hand sides of the compiled
multiplier solves (``_jit_multipliers``, decision 0057), the robot entry points'
inverse dynamics (the same right-hand sides) and forward dynamics (decision 0073),

.. math:: M(q_k) \ddot q_k + \Phi_q^T \lambda_k = Q + Q_v + \tau_k, \qquad
          \Phi_q \ddot q_k = \gamma

(without constraint equations by the Cholesky factor of ``M``, with them by LU of the
augmented system when its pivots are regular). One compiled function serves every kind, so
a session compiles (or loads) it once. The loop stops at the first point that needs the
Python path's care and returns its index.

Example (what ``analyses._robot._forward_points`` does)::

    got = points(system, times, Q, QD, F, FORWARD_FREE)   # F (N, n): forces on coordinates
    if got is not None:
        QDD, done = got                                    # rows [:done] computed
"""

from __future__ import annotations

import numpy as np

from ._jit_cache import notice
from ._jit_runtime import (
    GenTree,
    available,
    index,
    kernel_entry,
    lapack,
    loaded,
    raise_callback_error,
)

#: the kinds (``_jit_free_loop``'s constants of the same names)
STATIC_LOADS, KINEMATIC_LOADS, DYNAMIC_LOADS, FORWARD_FREE, FORWARD_AUGMENTED = 0, 1, 2, 3, 4

_state: dict = {"gen_points": None}


def _c(a) -> np.ndarray:
    """``a`` as a writable C-ordered float array: a read-only one (a broadcast view) is
    another Numba type, whose compile would be a second specialisation of the loop."""
    a = np.ascontiguousarray(a, dtype=float)
    return a if a.flags.writeable else a.copy()


def points(system, times, Q, QD, X, mode: int, p=None, how: str = "load"):
    """``(R (N', n), N')``: ``gen_points``' values at the first ``N'`` points of the states
    ``Q``, ``QD`` (N, n) (``QD`` may be ``(1, n)`` for ``STATIC_LOADS``), ``X`` (N, n) the
    accelerations (``DYNAMIC_LOADS``; ``(1, n)`` below) or the forces on the coordinates
    (``FORWARD_*``); the points from ``N'`` on are the Python path's. None when the loop
    cannot run: not the recursive Gen dynamics, a kernel without C entry points that none
    can be made for (:func:`~._jit_runtime.python_entry`: SymPy kernels get one, decision
    0084; an interrupt inside one is raised when the loop returns), Numba missing, or the
    loop being compiled in the background (decision 0064). The caller decides whether it
    should run (the ``MECHSYS_JIT`` rule). ``p``: the parameter values
    (default the system's). ``how``: the tier (:func:`~._jit_runtime.tier`; the multiplier
    solves' job, decision 0081): ``"load"`` (the default) the compiled loop, loaded or compiled
    (None while a background compile runs); ``"loaded"`` compiled when already loaded in the
    process, else interpreted; ``"interpreted"`` the same code interpreted (the same numbers
    bit for bit)."""
    dyn = system.dynamics
    if not getattr(dyn, "recursive", False) or not available():
        return None
    entry = kernel_entry(dyn._main)
    if entry is None:
        return None
    gen = GenTree.of(system, dyn, entry[0])
    if gen is None:
        return None
    if _state["gen_points"] is None:
        from ._jit_free_loop import gen_points

        _state["gen_points"] = gen_points
    from ._jit_modes import entry as _entry

    N, n = len(times), system.n
    R = np.empty((N, n))
    args = (np.asarray(entry[0], dtype=np.int64), gen.arrays, entry[1], lapack(), _c(times),
            _c(Q),
            _c(QD), _c(X), _c(system.p_values if p is None else p), system.m,
            index(system.jac_rows), index(system.jac_cols), int(mode), R)
    # (every compile of more than about a second is announced: decision 0044; None: being
    # compiled in the background, decision 0064, and the Python path computes the points)
    fn = loaded(_state["gen_points"], args) if how == "loaded" else None
    if how == "load":
        fn = _entry(_state["gen_points"], args, say=lambda how: notice(
            "the recursive dynamics over points", None, background=how == "background"))
        if fn is None:
            return None
    if fn is None:
        from ._jit_interp import interpreted

        fn = interpreted(_state["gen_points"])
    k = int(fn(*args))
    # (an interrupt a Python kernel's entry point caught: decision 0084)
    raise_callback_error()
    return R[:k], k


__all__ = ["DYNAMIC_LOADS", "FORWARD_AUGMENTED", "FORWARD_FREE", "KINEMATIC_LOADS",
           "STATIC_LOADS", "points"]
