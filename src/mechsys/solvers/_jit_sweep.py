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

The compiled loop handles the regular points. At the first point that needs the Python
path's care (Newton not converging, a singular Jacobian, a branch jump) it stops and
returns that point's index; the Python code takes that point with its whole logic
(retries, toggle handling, diagnostics), factorising the last solved point's Jacobian
again with the row scales the loop returns, so that its first position solve starts with
the same chord steps (decision 0020); then the loop resumes from the next point with that
point's chord (decision 0075). Results never depend on which path ran.

While the compiled loop is being compiled in the background (decision 0064) the same loop
runs interpreted (:mod:`._jit_interp`: its own code, the same numbers bit for bit) for
systems of up to :data:`INTERP_MAX` unknowns (dense kind), and hands over to the compiled
loop when that is ready (decision 0075). Its factorisations visit the Jacobian's structure
only (decision 0078), so its cost per point grows about as the nonzeros.

When it runs: the ``MECHSYS_JIT`` rule of :mod:`~mechsys.solvers._jit_runtime` (``auto``:
sweeps of at least ``AUTO_POINTS`` points), with the SymEngine LLVM backend's kernels
(two-stage ``Piecewise`` kernels of spline profiles included), for any square system, dense
or through its Jacobian's pattern (chains, trees, any branching). The Numba code is
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

import numpy as np

from .._errors import MechError
from ._jit_cache import notice
from ._jit_runtime import INTERP_MAX as _INTERP_MAX
from ._jit_runtime import NO_BAND, SPARSE, band_args, index, lapack, wanted
from ._jit_runtime import table as _table
from ._linalg import Scaling, _column_kinds, length_hint
from ._tolerances import RCOND_WARN, SPARSE_THRESHOLD

_state: dict = {"loop": None, "fill": None}


def plan(system, points: int, order: int):
    """The kernels' C entry points when the compiled loop should run this sweep, else None."""
    if not wanted(system, points, large_ok=True):
        return None
    kernels = [system.f_position]
    if order >= 1:
        kernels.append(system.f_velocity)
    if order >= 2:
        kernels.append(system.f_gamma)
    return _table(kernels)


#: the interpreted loop is the first tier of systems up to this many unknowns while the
#: compiled one is compiled in the background (``_jit_runtime.INTERP_MAX``, decisions 0075
#: and 0078)
INTERP_MAX = _INTERP_MAX
#: the sparse kind (above ``SPARSE_THRESHOLD`` unknowns) is not interpreted: the Python loop
#: takes its sweeps while the compiled loop is compiled (decision 0078 measured it
#: interpreted; ``benchmarks/interpreted_sweep.py --sparse`` sets this to see it)
INTERP_SPARSE = False
#: the interpreted loop runs in chunks of this many points, asking between them whether the
#: compiled loop is ready (it then takes the rest of the sweep: the same numbers)
INTERP_CHUNK = 256

#: CPU seconds of the kinematic sweep's compile from empty caches (the slider-crank's dense
#: kind; ``benchmarks/cold_start.py``, decision 0044), for the notice
_SWEEP_SECONDS = 30


def run(system, pointers, times, q0, p, order, options, scaling, rot, Q, QD, QDD, its, rconds,
        rprev, R=None, first=0, chord_start=False):
    """Fill ``Q``, ``QD``, ``QDD``, ``its``, ``rconds`` from point ``first`` on (the rows
    before it: the points solved before, which the predictor continues; ``scaling`` given
    then; ``chord_start``: point ``first - 1`` had the chord, of row scales ``rprev``);
    return ``(k, evals, scaling, compiled)``: the first point left to the Python loop
    (``len(times)`` when all are done), the number of kernel calls made, the
    :class:`~mechsys.solvers._linalg.Scaling` used (the given one, possibly None, when the
    loop did not run), and how many points the compiled loop solved.

    The loop runs compiled when its machine code is at hand; while it is being compiled in
    the background (decision 0064) the same loop runs interpreted (:mod:`._jit_interp`,
    decision 0075; up to :data:`INTERP_MAX` unknowns, else ``first`` is returned: every
    point is left to the Python loop) in chunks of :data:`INTERP_CHUNK` points, and the
    compiled loop takes over at the first chunk boundary after its compile is done. Both
    tiers run the same code and give the same numbers, bit for bit.

    ``scaling`` None: the loop takes ``Scaling.of`` the guess ``q0`` at the first time from
    its first evaluation (the same numbers). ``rprev`` (n,) receives the row scales of the
    last solved point's velocity factorisation (the chord the Python loop continues with).
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
    fn = compiled_loop(args(N, k, chord))
    if fn is None and ((large and not INTERP_SPARSE) or n > INTERP_MAX):
        # (the Python loop takes every point from ``first`` on, with the scaling it was
        # given; None: the caller's own)
        return k, 0, scaling, 0
    if fn is None:
        from ._jit_interp import interpreted

        loop = interpreted(_state["loop"])
        while k < N:
            end = min(N, k + INTERP_CHUNK)
            kk, e = loop(*args(end, k, chord))
            evals += e
            if kk < end:
                return int(kk), int(evals), _scaling(scaling, scale, columns), 0
            k = end
            chord = order >= 1 and bool(rc[k - 1] >= RCOND_WARN)
            fn = compiled_loop(args(N, k, chord)) if k < N else None
            if fn is not None:
                break
    done = k
    if k < N:
        k, e = fn(*args(N, k, chord))
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
        if bad:
            raise MechError(f"mechsys internal error: {bad} condition estimate(s) of a compiled "
                            "sweep proven regular came out singular; please report it")

    fill.kernel = system.f_velocity    # the pointer in ``pointers`` is valid while it lives
    return fill


__all__ = ["plan", "rcond_filler", "run"]
