r"""The Python driver of the compiled multiplier solves over a solved sweep (the Numba loop:
``_jit_multipliers_loop``; decision 0026): it decides whether the loop runs, gathers the
kernels' C entry points and the fixed patterns' arrays, and calls the loop specialised on
its kind (dense or sparse LU, decision 0044).

At each point ``k`` the loop solves, as :func:`~mechsys.solvers._statics.solve_multipliers`
does, in the unit-free form of the Jacobian, :math:`B = R^{-1} \Phi_q D`:

.. math:: B^T (R \lambda_k) = D\, \mathrm{rhs}_k, \qquad
          \mathrm{rhs} = Q(t, q, \dot q, \lambda) + Q_v(q, \dot q) - M(q) \ddot q

(Newton on :math:`\lambda` when the loads depend on it: friction). It stops at the first
point that needs the Python path's care and returns its index; the Python path goes on
from there.

Example (what ``_statics.multipliers_over`` does)::

    done = multipliers(system, times, Q, QD, QDD, p, "dynamic", LAM, columns=sc.columns)
    # LAM[:done] filled; the Python path solves the points from ``done`` on
"""

from __future__ import annotations

import numpy as np

from ._jit_cache import notice
from ._jit_runtime import (
    INTERP_WAIT_MAX,
    INTERP_WAIT_MAX_DENSE,
    NO_BAND,
    SPARSE,
    band_args,
    band_lapack,
    index,
    lapack,
    loaded,
    patterned,
    raise_callback_error,
    runnable,
    tier,
)
from ._jit_runtime import table as _table
from ._linalg import _sparse_lu, pattern_slots
from ._patterns import multiplier_newton_pattern
from ._tolerances import SPARSE_THRESHOLD

_state: dict = {"multipliers": None}

#: CPU seconds of the multiplier solves' compile from empty caches (the slider-crank's inverse
#: dynamics less its sweep; ``benchmarks/cold_start.py``, decision 0044), for the notice
_MULTIPLIER_SECONDS = 8

def multipliers(system, times, Q, QD, QDD, p, mode_name: str, LAM, guess=1.0, tol=1e-10,
                max_iterations=50, columns=None, points=None) -> int:
    """Fill ``LAM`` (N, m) with the multipliers of the solved sweep ``Q``, ``QD``, ``QDD``
    (N, n) by the loop ``_jit_multipliers_loop.multipliers`` from point 0 on; return the first
    point left to the Python code (a point needing care; ``len(times)`` when all are done, 0
    when the loop cannot run: a kernel without C entry points that none can be made for
    (:func:`~._jit_runtime.python_entry`), a system :func:`~._jit_runtime.runnable`
    refuses). The loop runs compiled or interpreted (the same
    code, the same numbers bit for bit) as :func:`~._jit_runtime.tier` chooses (decision
    0081): compiled when loaded in the process, loaded (or compiled) when the job repays it,
    interpreted otherwise, under ``MECHSYS_JIT=0`` and while a background compile runs (the
    points are independent: the job then runs interpreted whole). The recursive Gen
    dynamics' right-hand sides come from :func:`_recursive_loads` first (that dynamics
    never has loads that depend on the multipliers: a model with them
    gets the symbolic Gen dynamics, ``compile/_generalized.make_dynamics``).
    ``mode_name``: ``"static"``, ``"kinematic"`` or ``"dynamic"``. Loads that depend on the
    multipliers (friction): Newton from ``guess`` (scalar or (m,)) at the first point,
    with ``tol`` and ``max_iterations`` of :class:`~mechsys.solvers.MultiplierOptions`.
    ``columns`` (n,): the unit-free form's column scales (``Scaling.columns``; None: 0 is
    returned, the Python path scales itself).
    ``points``: the size of the whole job, for :func:`~._jit_runtime.tier` (default
    ``len(times)``)."""
    N = len(times)
    dyn = system.dynamics
    recursive = getattr(dyn, "recursive", False)
    large = system.n > SPARSE_THRESHOLD
    kband = _multiplier_band(system) if large and dyn.depends_on_lambda else _NO_KBAND
    # (the recursive dynamics of generalized coordinates has no f_terms kernel: its
    # right-hand sides come first, from the recursion in compiled code)
    if not N or columns is None or not runnable(
            system, large_ok=not dyn.depends_on_lambda or kband is not None):
        return 0
    how = tier(N if points is None else points, system.n)
    code = {"static": 0, "kinematic": 1, "dynamic": 2}[mode_name]
    if (code >= 1 and QD is None) or (code == 2 and QDD is None):
        return 0
    Rpre = np.zeros((0, system.n))
    if recursive:
        got = _recursive_loads(system, times, Q, QD, QDD, p, code, how)
        if got is None:
            return 0
        Rpre, N = got
        if N == 0:
            return 0
        times, Q = times[:N], Q[:N]
        QD = None if QD is None else QD[:N]
        QDD = None if QDD is None else QDD[:N]
    kernels = [system.f_position] if recursive else [system.f_position, dyn.f_terms]
    if dyn.depends_on_lambda:
        kernels.append(dyn.f_dQ_dlam)
        dr, dc = index(dyn.dQ_rows), index(dyn.dQ_cols)
    else:
        dr = dc = np.zeros(0, dtype=np.int64)
    table = _table(kernels)
    if table is None:
        return 0
    from ._jit_modes import entry

    if _state.get("multipliers") is None:
        from ._jit_multipliers_loop import multipliers as loop

        _state["multipliers"] = loop
    dummy = np.zeros((1, system.n))
    bw, band = band_args(system) if system.n > SPARSE_THRESHOLD else NO_BAND
    args = (
        table, lapack(), np.ascontiguousarray(times, dtype=float),
        np.ascontiguousarray(Q, dtype=float),
        dummy if code == 0 else np.ascontiguousarray(QD, dtype=float),
        dummy if code < 2 else np.ascontiguousarray(QDD, dtype=float),
        np.ascontiguousarray(system.p_values if p is None else p, dtype=float),
        index(system.jac_rows), index(system.jac_cols), index(dyn.M_rows),
        index(dyn.M_cols), len(dyn.M_rows), code, LAM, dr, dc,
        np.broadcast_to(np.asarray(guess, dtype=float), (system.m,)).copy(), float(tol),
        int(max_iterations), np.ascontiguousarray(columns, dtype=float), band_lapack(), bw,
        band, kband, Rpre, bool(bw[0] == SPARSE))
    # specialised on the last argument: only the dense or only the sparse solves compiled
    # (decision 0044)
    literal = (len(args) - 1,)
    fn = loaded(_state["multipliers"], args, literal) if how == "loaded" else None
    if how == "load":
        fn = entry(_state["multipliers"], args, literal=literal, say=lambda how: notice(
            "the multiplier solves" + (" (sparse)" if args[-1] else ""), _MULTIPLIER_SECONDS,
            background=how == "background"))
    if fn is None and how == "load" and (large or system.n > (
            INTERP_WAIT_MAX_DENSE if dyn.depends_on_lambda else INTERP_WAIT_MAX)):
        # being compiled in the background: a large system's points go to the Python code
        # meanwhile (decision 0083)
        return 0
    if fn is None:
        # not loaded, or being compiled in the background (decision 0064): the same loop
        # interpreted, the same numbers bit for bit (decisions 0075, 0081; its factorisation
        # visits the structure only, decision 0078)
        from ._jit_interp import interpreted

        fn = interpreted(_state["multipliers"])
    done = int(fn(*args))
    raise_callback_error()
    return done


def _recursive_loads(system, times, Q, QD, QDD, p, code, how="load"):
    """``(R (N', n), N')``: the right-hand sides of the multiplier solves of a system with
    recursive Gen dynamics at the first ``N'`` points (up to the first whose values are not
    finite, which the Python path reports), by ``_jit_free_loop.gen_points``
    (``_jit_gen_points``; ``how``: the job's tier, :func:`~._jit_runtime.tier`); None when
    its kernels have no C entry points."""
    from ._jit_gen_points import points

    n = system.n
    dummy = np.zeros((1, n))
    QD, QDD = dummy if code == 0 else QD, dummy if code < 2 else QDD
    got = points(system, times, Q, QD, QDD, code, p, how)
    if got is None and how == "load":
        # (being compiled in the background: the same loop interpreted meanwhile)
        got = points(system, times, Q, QD, QDD, code, p, "interpreted")
    return got


#: the multiplier loop's (unused) Newton band arguments
_NO_KBAND = (np.array([-1, 0, 1, 0], dtype=np.int64), (np.zeros(0, dtype=np.int64),) * 8)


def _multiplier_band(system):
    """``(kbw, (pos, rows, cols, row_perm, perm, sJT, sD, head))`` of the multiplier Newton
    matrix ``Phi_q^T - dQ/dlambda`` of a large square system (friction): its
    ``FixedPattern`` (``_patterns.multiplier_newton_pattern``, the Python path's) and the slot in it
    of each of the Jacobian's CSC entries (transposed) and each ``dQ/dlambda`` entry. Banded:
    ``kbw = (kl, ku, ld, 0)`` (LAPACK's band LU); else (trees of many branches) ``kbw =
    (SPARSE, entries, capL, capU)`` (the factors' storage as the Python path has grown it so
    far) and ``head`` the CSC structure of ``B = P Q K P^T`` (the compiled sparse LU, the
    Python path's). None when the Jacobian has no compiled pattern, or the Newton
    matrix's pattern is not banded and there is no compiled LU."""
    if not patterned(system):
        return None
    rows, cols, pat = multiplier_newton_pattern(system)
    if not pat.banded and (_sparse_lu() is None or not hasattr(pat, "s_indptr")):
        return None
    got = getattr(pat, "_jit_kband", None)
    if got is None:
        n = system.n
        _, (_, jrows, jcols, _, _, _, _) = band_args(system)

        def slot(r, c):
            return pattern_slots(rows, cols, n, r, c)

        dyn = system.dynamics
        head = (np.zeros(0) if pat.banded
                else np.concatenate((pat.s_indptr, pat.s_indices)))
        got = pat._jit_kband = tuple(index(a) for a in (
            pat._pos, rows, cols, pat.row_perm, pat.perm, slot(jcols, jrows),
            slot(dyn.dQ_rows, dyn.dQ_cols), head))
    kbw = [pat.kl, pat.ku, pat._ld, 0] if pat.banded else [SPARSE, rows.size, *pat._cap]
    return np.array(kbw, dtype=np.int64), got


__all__ = ["multipliers"]
