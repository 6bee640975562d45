r"""The kinematic sweep compiled with Numba: the loop of :func:`~mechsys.solvers.sweep` with no
Python between the compiled equations.

Per point, exactly the arithmetic of the Python path (:mod:`mechsys.solvers._kinematics`,
:mod:`mechsys.solvers._position`, :class:`~mechsys.solvers._linalg.Scaling`): the predictor,
the damped Newton iteration on the unit-free equations :math:`R^{-1} \Phi_q D`, the velocity
:math:`\Phi_q \dot q = -\Phi_t` and acceleration :math:`\Phi_q \ddot q = \gamma` solves. The constraint
kernels are SymEngine's LLVM functions, called through their C entry points
(``void f(double *out, const double *in, void *ctx)``); the factorisations are LAPACK's
``dgetrf``/``dgecon``/``dgetrs``, the routines the Python path calls, their algorithms
written out in the loop (``_jit_lapack``). Above ``SPARSE_THRESHOLD`` unknowns both paths
factorise the Jacobian through its :class:`~mechsys.solvers._linalg.FixedPattern` (a row
matching and minimum-degree ordering analysed once per system, then the sparse LU of
``_jit_sparse``, the same compiled function in both paths; decision 0031). Both paths give
the same numbers to rounding.

The loop handles the regular points of every sweep (decision 0081). At the first point
that needs the Python code's care (Newton not converging, a singular Jacobian, a branch
jump) it stops and returns that point's index; the Python code takes that point with its
whole logic (retries, toggle handling, diagnostics), factorising the last solved point's
Jacobian again with the row scales the loop returns, so that its first position solve starts
with the same chord steps (decision 0020); then the loop resumes from the next point with
that point's chord (decision 0075). Sweeps with hooks (``pre_solve``, ``post_iterate``:
called inside Newton's iterations) run the Python code at every point. Kernels without C
entry points (the SymPy backend's) get one that calls their Python function
(:func:`~._jit_runtime.python_entry`, decision 0081).

The loop runs compiled or interpreted (:mod:`._jit_interp`: its own code, the same numbers
bit for bit), as :func:`~._jit_runtime.tier` chooses per job: compiled when its machine code
is loaded in the process, loaded (or compiled) when the job repays it, interpreted otherwise
and while a background compile runs (decision 0064), handing over to the compiled loop when
that is ready. ``MECHSYS_JIT=0``: always interpreted. Its factorisations visit the
Jacobian's structure only (decision 0078), so its cost per point grows about as the
nonzeros; any size and the sparse kind are interpreted. The Numba code is
``_jit_sweep_loop``; this module is its Python driver (the multiplier solves' driver is
``_jit_multipliers``; decision 0058).

Example (what ``_kinematics.sweep`` does)::

    pointers = plan(system, len(times), order=2)
    if pointers is not None:
        k, evals, scaling, compiled = run(system, pointers, times, q0, p, 2, options, None,
                                          rot, Q, QD, QDD, its, rconds, rprev)

Measured (slider-crank, 1000 points with velocities and accelerations): see
``docs/performance.md``, ``docs/decisions/0013-compiled-sweep.md`` and
``docs/decisions/0019-sweep-lu-structure-and-guard.md`` and
``docs/decisions/0020-sweep-chord-steps.md``, ``0023`` and ``0025``.
"""

from __future__ import annotations

import time

import numpy as np

from .._errors import MechError
from ._jit_cache import notice
from ._jit_runtime import (
    INTERP_SECONDS,
    INTERP_WAIT_MAX,
    NO_BAND,
    SPARSE,
    band_args,
    index,
    lapack,
    loaded,
    raise_callback_error,
    runnable,
    tier,
)
from ._jit_runtime import table as _table
from ._linalg import Scaling, _column_kinds, length_hint
from ._tolerances import RCOND_WARN, SPARSE_THRESHOLD

_state: dict = {"loop": None, "fill": None}


def plan(system, points: int, order: int):
    """The kernels' C entry points when the loop (compiled or interpreted) can take this
    sweep's regular points, else None (kernels without C entry points, a system the loop
    does not take: :func:`~._jit_runtime.runnable`). ``points``: the job's size (kept for
    the callers; the tier is :func:`~._jit_runtime.tier`'s, asked by :func:`run`)."""
    if not runnable(system, large_ok=True):
        return None
    kernels = [system.f_position]
    if order >= 1:
        kernels.append(system.f_velocity)
    if order >= 2:
        kernels.append(system.f_gamma)
    return _table(kernels)


#: CPU seconds of the kinematic sweep's compile from empty caches (the slider-crank's dense
#: kind; ``benchmarks/cold_start.py``, decision 0044), for the notice
_SWEEP_SECONDS = 30

#: the first interpreted chunk of a job waiting for its compiled loop (points); the next ones
#: are sized toward ``INTERP_SECONDS`` of CPU time each (at most 4 x the one before)
_FIRST_CHUNK = 16
#: a fixed size of those chunks (points) instead of the time rule (None): for tests, whose
#: hand-over must fall on a known point
INTERP_CHUNK = None


def run(system, pointers, times, q0, p, order, options, scaling, rot, Q, QD, QDD, its, rconds,
        rprev, R=None, first=0, chord_start=False, how=None):
    """Fill ``Q``, ``QD``, ``QDD``, ``its``, ``rconds`` from point ``first`` on (the rows
    before it: the points solved before, which the predictor continues; ``scaling`` given
    then; ``chord_start``: point ``first - 1`` had the chord, of row scales ``rprev``);
    return ``(k, evals, scaling, compiled)``: the first point left to the Python code (a
    point needing care; ``len(times)`` when all are done), the number of kernel calls made,
    the :class:`~mechsys.solvers._linalg.Scaling` used, and how many points the compiled
    loop solved (the others: the same loop interpreted).

    The tier (decision 0081): ``how`` is :func:`~._jit_runtime.tier`'s (default: asked for
    the ``len(times) - first`` points). The loop runs compiled when its machine code is
    loaded in this process (never with ``"interpreted"``); with ``"load"`` it is loaded, or
    compiled per ``MECHSYS_COMPILE``; while that compile runs in the background (decision
    0064) the same loop runs interpreted (:mod:`._jit_interp`, decision 0075; any size, the
    sparse kind and its chunks too) in chunks of about ``INTERP_SECONDS`` of CPU time, and
    the compiled loop takes over at the first chunk boundary after its compile is done.
    Otherwise the loop runs interpreted, whole. Every tier runs the same code and gives the
    same numbers, bit for bit.

    ``scaling`` None: the loop takes ``Scaling.of`` the guess ``q0`` at the first time from
    its first evaluation (the same numbers). ``rprev`` (n,) receives the row scales of the
    last solved point's velocity factorisation (the chord the Python code continues with).
    ``R`` (N, n): when given, a point whose condition estimate is proven to be at least
    ``RCOND_WARN`` gets ``RCOND_PENDING`` in ``rconds`` and its row scales in ``R``, for
    :func:`rcond_filler` (decision 0023); None: every estimate is computed in the loop."""
    from ._jit_modes import entry as _entry

    if _state["loop"] is None:
        from ._jit_sweep_loop import sweep_dense

        _state["loop"] = sweep_dense
    n = system.n
    dummy = np.zeros((1, n))
    qd_out = QD if QD is not None else dummy
    qdd_out = QDD if QDD is not None else dummy
    rc = rconds if rconds is not None else np.full(len(times), np.nan)
    lazy = R is not None
    trans, body = _column_kinds(system)
    bw, band = NO_BAND
    if n > SPARSE_THRESHOLD:
        bw, band = band_args(system)
        lazy = False                     # (the pivot ratio is always at hand)
        if scaling is None:
            # the Python path's scaling, from the sparse Jacobian at the guess (the loop's
            # own is computed on a dense matrix)
            scaling = Scaling.of(system, q0, system.jacobian(times[first], q0, p, True))
    if scaling is None:
        scale = np.zeros(2)
        columns = np.empty(n)
    else:
        scale = np.array([scaling.length, scaling.offset])
        columns = np.ascontiguousarray(scaling.columns, dtype=float)
    times = np.ascontiguousarray(times, dtype=float)
    head = (pointers, lapack())
    tail = (np.ascontiguousarray(q0, dtype=float),
            np.ascontiguousarray(system.p_values if p is None else p, dtype=float),
            index(system.jac_rows), index(system.jac_cols), columns, scale,
            float(options.ftol), int(options.max_iterations), bool(options.damping),
            int(order), index(rot), trans, index(body), length_hint(system), Q,
            qd_out, qdd_out, its, rc, rprev, lazy, R if lazy else dummy)
    large = bool(bw[0] == SPARSE)

    def args(end, start, chord):
        return (*head, times[:end], *tail, int(start), bool(chord), bw, band, large)

    def compiled_loop(a):
        # the loop specialised on its kind (the last argument: the sparse LU or the dense
        # one), compiling only that kind's solvers (decision 0044)
        return _entry(_state["loop"], a, literal=(len(a) - 1,), say=lambda how: notice(
            "the kinematic sweep" + (" (sparse)" if large else ""), _SWEEP_SECONDS,
            background=how == "background"))

    N = len(times)
    k, evals, chord = int(first), 0, bool(chord_start)
    how = tier(N - k, n) if how is None else how
    a = args(N, k, chord)
    # ("load": ``entry`` finds loaded machine code first, else loads or compiles it)
    fn = compiled_loop(a) if how == "load" else (
        loaded(_state["loop"], a, (len(a) - 1,)) if how == "loaded" else None)
    if fn is None and how == "load" and (large or n > INTERP_WAIT_MAX):
        # being compiled in the background: a large system's points go to the Python code
        # meanwhile (decision 0083), which asks for the compiled loop again after each point
        return k, 0, scaling, 0
    if fn is None:
        from ._jit_interp import interpreted

        loop = interpreted(_state["loop"])
        size = N - k if how != "load" else (INTERP_CHUNK or _FIRST_CHUNK)
        while k < N:
            end = min(N, k + size)
            clock = time.process_time()
            kk, e = loop(*args(end, k, chord))
            raise_callback_error()
            evals += e
            if kk < end:
                return int(kk), int(evals), _scaling(scaling, scale, columns), 0
            took = max(time.process_time() - clock, 1e-6)
            size = INTERP_CHUNK or max(1, int((end - k) * min(4.0, max(0.25, INTERP_SECONDS
                                                                          / took))))
            k = end
            chord = order >= 1 and bool(rc[k - 1] >= RCOND_WARN)
            fn = compiled_loop(args(N, k, chord)) if k < N else None
            if fn is not None:
                break
    done = k
    if k < N:
        k, e = fn(*args(N, k, chord))
        raise_callback_error()
        evals += e
    return int(k), int(evals), _scaling(scaling, scale, columns), int(k) - done


def _scaling(scaling, scale, columns):
    """The given scaling, or the one the loop computed into ``scale`` and ``columns``."""
    if scaling is None and scale[0] != 0.0:
        scaling = Scaling(float(scale[0]), columns, float(scale[1]))
    return scaling


def rcond_filler(system, pointers, times, Q, p, scaling, R):
    """A function ``fill(rconds)`` computing in place the estimates :func:`run` left
    ``RCOND_PENDING`` (``rconds`` may be a leading part of the sweep's): the same numbers the
    loop computes when it is not lazy (``_jit_sweep_loop.fill_rconds``)."""
    from ._jit_modes import entry as _entry

    if _state["fill"] is None:
        from ._jit_sweep_loop import fill_rconds

        _state["fill"] = fill_rconds
    args = (pointers, lapack(), np.ascontiguousarray(times, dtype=float), Q,
            np.ascontiguousarray(system.p_values if p is None else p, dtype=float),
            index(system.jac_rows), index(system.jac_cols),
            np.ascontiguousarray(scaling.columns, dtype=float), R)

    def fill(rconds: np.ndarray) -> None:
        k = len(rconds)
        a = (*args[:3], args[3][:k], *args[4:8], args[8][:k], rconds)
        # compiled when at hand, else (compiled in the background meanwhile) the same code
        # interpreted: the same numbers (decision 0075)
        fn = _entry(_state["fill"], a)
        if fn is None:
            from ._jit_interp import interpreted

            fn = interpreted(_state["fill"])
        bad = fn(*a)
        raise_callback_error()
        if bad:
            raise MechError(f"mechsys internal error: {bad} condition estimate(s) of a compiled "
                            "sweep proven regular came out singular; please report it")

    fill.kernel = system.f_velocity    # the pointer in ``pointers`` is valid while it lives
    return fill


__all__ = ["plan", "rcond_filler", "run"]
