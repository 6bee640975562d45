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
path's care (Newton not converging, a singular or nearly singular Jacobian, a branch jump)
it stops and returns that point's index; the Python loop takes over from there with its
whole logic (retries, toggle handling, diagnostics). It factorises the last solved point's
Jacobian again, with the row scales the compiled loop returns, so that its first position
solve starts with the same chord steps (decision 0020). Results never depend on which path
ran.

When it runs (``MECHSYS_JIT``): ``0`` never, ``1`` whenever possible, unset (``auto``) when
the sweep has at least :data:`AUTO_POINTS` points: loading Numba and the cached machine code
costs about 0.7 s CPU once per process, which a short sweep would not recover. (The choice
depends on the sweep alone, never on what ran before in the process.) Possible means: Numba
importable (a core dependency since decision 0041), the SymEngine LLVM backend (two-stage
``Piecewise`` kernels of spline profiles included), as many equations as coordinates, and a
dense system (``n <= SPARSE_THRESHOLD``) or a larger one through its Jacobian's pattern (chains, trees, any
branching).

Measured (slider-crank, 1000 points with velocities and accelerations): see
``docs/performance.md``, ``docs/decisions/0013-compiled-sweep.md`` and
``docs/decisions/0019-sweep-lu-structure-and-guard.md`` and
``docs/decisions/0020-sweep-chord-steps.md``, ``0023`` and ``0025``.
"""

from __future__ import annotations

import ctypes
import os

import numpy as np

from .._errors import MechError, ModelError, slow_path_warning
from ._linalg import RCOND_MIN, SPARSE_THRESHOLD, Scaling, _column_kinds, length_hint

#: ``auto``: the compiled loop is used for sweeps of at least this many points
AUTO_POINTS = 1000

_PLANS: dict = {}    # plan(): kernel ids -> (kernels, pointer table)
_state: dict = {"loaded": False, "loop": None, "fill": None, "lapack": None, "failed": None,
                "multipliers": None}


def mode() -> str:
    """``"off"``, ``"on"`` or ``"auto"`` from ``MECHSYS_JIT`` (``0/off/false/no``,
    ``1/on/true/yes``, unset or ``auto``). Anything else raises :class:`ModelError`: a
    misspelled ``MECHSYS_JIT=of`` must not quietly mean the opposite."""
    v = os.environ.get("MECHSYS_JIT", "").strip().lower()
    if v in ("0", "off", "false", "no"):
        return "off"
    if v in ("1", "on", "true", "yes"):
        return "on"
    if v in ("", "auto"):
        return "auto"
    raise ModelError(f"MECHSYS_JIT={os.environ['MECHSYS_JIT']!r}: use 0 (never compiled loops), "
                     "1 (whenever possible) or auto (unset: the default)")


def available() -> bool:
    """Numba can be imported."""
    if _state["failed"] is None:
        try:
            import llvmlite  # noqa: F401
            import numba  # noqa: F401

            _state["failed"] = False
        except ImportError as exc:
            _state["failed"] = True
            slow_path_warning("numba", exc)
    return not _state["failed"]



def _pointer(kernel):
    """``(address, context)`` of a compiled kernel's C entry point, or None."""
    get = getattr(kernel, "c_function", None)
    return get() if get is not None else None


def plan(system, points: int, order: int):
    """The kernels' C entry points when the compiled loop should run this sweep, else None."""
    if not _wanted(system, points, large_ok=True):
        return None
    kernels = [system.f_position]
    if order >= 1:
        kernels.append(system.f_velocity)
    if order >= 2:
        kernels.append(system.f_gamma)
    return _table(kernels)


def _table(kernels):
    """The pointer table of ``kernels`` (one row each: address, context, first-stage address,
    its context, Piecewise values; rows of zeros up to three), or None when one has no C
    entry point. Kept per kernel objects, which the entry holds (their entry points live
    as long as they do; not on the system: a pickled copy must not carry another process's
    addresses)."""
    key = tuple(id(k) for k in kernels)
    got = _PLANS.get(key)
    if got is not None and all(a is b for a, b in zip(got[0], kernels)):
        return got[1]
    ptrs = [_pointer(k) for k in kernels]
    if any(p is None for p in ptrs):
        return None
    while len(ptrs) < 3:
        ptrs.append((0, 0, 0, 0, 0))
    table = np.array(ptrs, dtype=np.int64)
    if len(_PLANS) >= 64:
        _PLANS.clear()
    _PLANS[key] = (tuple(kernels), table)
    return table


def _wanted(system, points: int, large_ok: bool = False) -> bool:
    """Whether a compiled loop should run for ``points`` points of this system (the
    ``MECHSYS_JIT`` rule of the module docstring; Numba importable). ``large_ok``: the loop
    also takes systems above ``SPARSE_THRESHOLD`` unknowns through their Jacobian's
    ``FixedPattern`` (the sweep, and the multiplier solves; with friction, when its Newton
    matrix's pattern is banded)."""
    m = mode()
    if m == "off" or system.n == 0 or system.m != system.n:
        return False
    if system.n > SPARSE_THRESHOLD and not (large_ok and _patterned(system)):
        return False
    if m == "auto" and points < AUTO_POINTS:
        return False
    return available()


def multipliers(system, times, Q, QD, QDD, p, mode_name: str, LAM, guess=1.0, tol=1e-10,
                max_iterations=50, columns=None, points=None) -> int:
    """Fill ``LAM`` (N, m) with the multipliers of the solved sweep ``Q``, ``QD``, ``QDD``
    (N, n) in compiled code (``_jit_multipliers``) from point 0 on; return the first point
    left to the Python path (``len(times)`` when all are done, 0 when the compiled loop
    cannot run: a dynamics without C entry points (SymPy fallbacks), or the ``MECHSYS_JIT``
    rule). The recursive Gen dynamics' right-hand sides come from :func:`_recursive_loads`
    first (that dynamics never has loads that depend on the multipliers: a model with them
    gets the symbolic Gen dynamics, ``compile/_generalized.make_dynamics``).
    ``mode_name``: ``"static"``, ``"kinematic"`` or ``"dynamic"``. Loads that depend on the
    multipliers (friction): Newton from ``guess`` (scalar or (m,)) at the first point,
    with ``tol`` and ``max_iterations`` of :class:`~mechsys.solvers.MultiplierOptions`.
    ``columns`` (n,): the unit-free form's column scales (``Scaling.columns``; None: 0 is
    returned, the Python path scales itself).
    ``points``: the size of the whole job, for the ``auto`` rule (default ``len(times)``)."""
    N = len(times)
    dyn = system.dynamics
    recursive = getattr(dyn, "recursive", False)
    large = system.n > SPARSE_THRESHOLD
    kband = _multiplier_band(system) if large and dyn.depends_on_lambda else _NO_KBAND
    # (the recursive dynamics of generalized coordinates has no f_terms kernel: its
    # right-hand sides come first, from the recursion in compiled code)
    if not N or columns is None or not _wanted(
            system, N if points is None else points,
            large_ok=not dyn.depends_on_lambda or kband is not None):
        return 0
    code = {"static": 0, "kinematic": 1, "dynamic": 2}[mode_name]
    if (code >= 1 and QD is None) or (code == 2 and QDD is None):
        return 0
    Rpre = np.zeros((0, system.n))
    if recursive:
        got = _recursive_loads(system, times, Q, QD, QDD, p, code)
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
        dr, dc = _index(dyn.dQ_rows), _index(dyn.dQ_cols)
    else:
        dr = dc = np.zeros(0, dtype=np.int64)
    table = _table(kernels)
    if table is None:
        return 0
    from ._jit_cache import notice
    from ._jit_loop import SPARSE as _SPARSE_BW
    from ._jit_modes import entry

    if _state.get("multipliers") is None:
        from ._jit_multipliers import multipliers as loop

        _state["multipliers"] = loop
    _state["loaded"] = True
    dummy = np.zeros((1, system.n))
    bw, band = _band_args(system) if system.n > SPARSE_THRESHOLD else _NO_BAND
    args = (
        table, _lapack(), np.ascontiguousarray(times, dtype=float),
        np.ascontiguousarray(Q, dtype=float),
        dummy if code == 0 else np.ascontiguousarray(QD, dtype=float),
        dummy if code < 2 else np.ascontiguousarray(QDD, dtype=float),
        np.ascontiguousarray(system.p_values if p is None else p, dtype=float),
        _index(system.jac_rows), _index(system.jac_cols), _index(dyn.M_rows),
        _index(dyn.M_cols), len(dyn.M_rows), code, LAM, dr, dc,
        np.broadcast_to(np.asarray(guess, dtype=float), (system.m,)).copy(), float(tol),
        int(max_iterations), np.ascontiguousarray(columns, dtype=float), _band_lapack(), bw,
        band, kband, Rpre, bool(bw[0] == _SPARSE_BW))
    # specialised on the last argument: only the dense or only the sparse solves compiled
    # (decision 0044)
    return int(entry(_state["multipliers"], args, literal=(len(args) - 1,), say=lambda _: notice(
        "the multiplier solves" + (" (sparse)" if args[-1] else ""), _MULTIPLIER_SECONDS))(*args))


def _recursive_loads(system, times, Q, QD, QDD, p, code):
    """``(R (N', n), N')``: the right-hand sides of the multiplier solves of a system with
    recursive Gen dynamics at the first ``N'`` points (up to the first whose values are not
    finite, which the Python path reports), by ``_jit_free_loop.gen_loads``; None when its
    kernels have no C entry points."""
    from ._jit_free import _entry, _Gen

    dyn = system.dynamics
    entry = _entry(dyn._main)
    if entry is None:
        return None
    gen = _Gen.of(system, dyn, entry[0])
    if gen is None:
        return None
    if _state.get("gen_loads") is None:
        from ._jit_cache import notice
        from ._jit_free_loop import gen_loads

        # (every compile of more than about a second is announced: decision 0044)
        notice("the recursive dynamics' loads", None, ("_jit_free_loop", "gen_loads"))

        _state["gen_loads"] = gen_loads
    N, n = len(times), system.n
    R = np.empty((N, n))
    dummy = np.zeros((1, n))
    k = _state["gen_loads"](
        np.asarray(entry[0], dtype=np.int64), gen.arrays, entry[1],
        np.ascontiguousarray(times, dtype=float), np.ascontiguousarray(Q, dtype=float),
        dummy if code == 0 else np.ascontiguousarray(QD, dtype=float),
        dummy if code < 2 else np.ascontiguousarray(QDD, dtype=float),
        np.ascontiguousarray(system.p_values if p is None else p, dtype=float), system.m,
        code, R)
    return R[:k], int(k)


def _index(a) -> np.ndarray:
    """``a`` as int64 (no copy when it is already)."""
    return np.asarray(a, dtype=np.int64)


def _capsule_address(capsule) -> int:
    api = ctypes.pythonapi
    api.PyCapsule_GetName.restype = ctypes.c_char_p
    api.PyCapsule_GetName.argtypes = [ctypes.py_object]
    api.PyCapsule_GetPointer.restype = ctypes.c_void_p
    api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
    return api.PyCapsule_GetPointer(capsule, api.PyCapsule_GetName(capsule))


def _jacobian_pattern(system):
    pattern = getattr(system, "jacobian_pattern", None)
    return pattern() if pattern is not None else None


def _patterned(system) -> bool:
    """The system's Jacobian has a ``FixedPattern`` whose sparse LU the loops call (the
    compiled one, ``_jit_sparse``: also the Python path's)."""
    from ._linalg import _sparse_lu

    pat = _jacobian_pattern(system)
    return pat is not None and pat.size > 0 and not pat.banded and _sparse_lu() is not None


#: the dense sweep's (unused) sparse-LU arguments
#: CPU seconds of the kinematic sweep's compile from empty caches (the slider-crank's dense
#: kind; ``benchmarks/cold_start.py``, decision 0044), for the notice
_SWEEP_SECONDS = 30
#: the same for the multiplier solves (the slider-crank's inverse dynamics less its sweep)
_MULTIPLIER_SECONDS = 8

_NO_BAND = (np.array([-1, 0, 0, 0], dtype=np.int64), (np.zeros(0, dtype=np.int64),) * 7)


#: the multiplier loop's (unused) Newton band arguments
_NO_KBAND = (np.array([-1, 0, 1, 0], dtype=np.int64), (np.zeros(0, dtype=np.int64),) * 8)


def _multiplier_band(system):
    """``(kbw, (pos, rows, cols, row_perm, perm, sJT, sD, head))`` of the multiplier Newton
    matrix ``Phi_q^T - dQ/dlambda`` of a large square system (friction): its
    ``FixedPattern`` (``_statics._newton_pattern``, the Python path's), and the slot in it of
    each of the Jacobian's CSC entries (transposed) and each ``dQ/dlambda`` entry. Banded:
    ``kbw = (kl, ku, ld, 0)`` (LAPACK's band LU); else (trees of many branches) ``kbw =
    (SPARSE, entries, capL, capU)`` (the factors' storage as the Python path has grown it so
    far) and ``head`` the CSC structure of ``B = P Q K P^T`` (the compiled sparse LU, the
    Python path's). None when the Jacobian has no compiled pattern, or the Newton
    matrix's pattern is not banded and there is no compiled LU."""
    from ._linalg import _sparse_lu, pattern_slots
    from ._statics import _newton_pattern

    if not _patterned(system):
        return None
    rows, cols, pat = _newton_pattern(system)
    if not pat.banded and (_sparse_lu() is None or not hasattr(pat, "s_indptr")):
        return None
    got = getattr(pat, "_jit_kband", None)
    if got is None:
        n = system.n
        _, (_, jrows, jcols, _, _, _, _) = _band_args(system)

        def slot(r, c):
            return pattern_slots(rows, cols, n, r, c)

        dyn = system.dynamics
        head = (np.zeros(0) if pat.banded
                else np.concatenate((pat.s_indptr, pat.s_indices)))
        got = pat._jit_kband = tuple(_index(a) for a in (
            pat._pos, rows, cols, pat.row_perm, pat.perm, slot(jcols, jrows),
            slot(dyn.dQ_rows, dyn.dQ_cols), head))
    from ._jit_loop import SPARSE

    kbw = [pat.kl, pat.ku, pat._ld, 0] if pat.banded else [SPARSE, rows.size, *pat._cap]
    return np.array(kbw, dtype=np.int64), got


def _band_args(system):
    """``(bw, band)`` of ``_jit_loop.sweep_dense`` for a system above ``SPARSE_THRESHOLD``
    unknowns: its Jacobian's ``FixedPattern`` (the arrays kept on the pattern, made once):
    ``bw = (SPARSE, nnz, capL, capU)`` (the factors' storage as the Python path has grown it
    so far) and ``band = (slot, rows, cols, pos, row_perm, perm, head)``, ``head`` the CSC
    structure of ``B = P Q A P^T``."""
    from ._jit_loop import SPARSE

    pat = system.jacobian_pattern()
    got = getattr(pat, "_jit_band", None)
    if got is None:
        slot, rows, indptr = system._csc_structure()
        cols = np.repeat(np.arange(system.n), np.diff(indptr))
        head = np.concatenate([pat.s_indptr, pat.s_indices])
        got = tuple(_index(a) for a in (slot, rows, cols, pat._pos, pat.row_perm, pat.perm,
                                        head))
        pat._jit_band = got
    return np.array([SPARSE, pat.s_indices.size, *pat._cap], dtype=np.int64), got


def _band_lapack() -> np.ndarray:
    """The C addresses of SciPy's ``dgbtrf`` and ``dgbtrs``."""
    if _state.get("band_lapack") is None:
        from scipy.linalg import cython_lapack

        caps = cython_lapack.__pyx_capi__
        _state["band_lapack"] = np.array([_capsule_address(caps[f]) for f in ("dgbtrf", "dgbtrs")],
                                         dtype=np.int64)
    return _state["band_lapack"]


def _lapack() -> np.ndarray:
    if _state["lapack"] is None:
        from scipy.linalg import cython_lapack

        caps = cython_lapack.__pyx_capi__
        _state["lapack"] = np.array([_capsule_address(caps[f]) for f in ("dgetrf", "dgecon", "dgetrs")],
                                    dtype=np.int64)
    return _state["lapack"]


def run(system, pointers, times, q0, p, order, options, scaling, rot, Q, QD, QDD, its, rconds,
        rprev, R=None, first=0, chord_start=False):
    """Fill ``Q``, ``QD``, ``QDD``, ``its``, ``rconds`` from point ``first`` on (the rows
    before it: the points solved before, which the predictor continues; ``scaling`` given
    then; ``chord_start``: point ``first - 1`` had the chord, of row scales ``rprev``);
    return ``(k, evals,
    scaling)``: the first point left to the Python loop (``len(times)`` when all are done),
    the number of kernel calls made, and the :class:`~mechsys.solvers._linalg.Scaling` used.
    ``scaling`` None: the loop takes ``Scaling.of`` the guess ``q0`` at the first time from
    its first evaluation (the same numbers). ``rprev`` (n,) receives the row scales of the
    last solved point's velocity factorisation (the chord the Python loop continues with).
    ``R`` (N, n): when given, a point whose condition estimate is proven to be at least
    ``RCOND_WARN`` gets ``RCOND_PENDING`` in ``rconds`` and its row scales in ``R``, for
    :func:`rcond_filler` (decision 0023); None: every estimate is computed in the loop."""
    from ._jit_cache import notice as _notice
    from ._jit_loop import SPARSE as _SPARSE_BW
    from ._jit_modes import entry as _entry

    if _state["loop"] is None:
        from ._jit_loop import sweep_dense

        _state["loop"] = sweep_dense
    _state["loaded"] = True
    n = system.n
    dummy = np.zeros((1, n))
    qd_out = QD if QD is not None else dummy
    qdd_out = QDD if QDD is not None else dummy
    rc = rconds if rconds is not None else np.full(len(times), np.nan)
    lazy = R is not None
    trans, body = _column_kinds(system)
    bw, band = _NO_BAND
    if n > SPARSE_THRESHOLD:
        bw, band = _band_args(system)
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
    args = (pointers, _lapack(), np.ascontiguousarray(times, dtype=float),
            np.ascontiguousarray(q0, dtype=float),
            np.ascontiguousarray(system.p_values if p is None else p, dtype=float),
            _index(system.jac_rows), _index(system.jac_cols), columns, scale,
            float(options.ftol), int(options.max_iterations), bool(options.damping),
            int(order), _index(rot), trans, _index(body), length_hint(system), Q,
            qd_out, qdd_out, its, rc, rprev, lazy, R if lazy else dummy, int(first),
            bool(chord_start), bw, band, bool(bw[0] == _SPARSE_BW))
    # the loop specialised on its kind (the last argument: the sparse LU or the dense one),
    # compiling only that kind's solvers (decision 0044)
    k, evals = _entry(_state["loop"], args, literal=(len(args) - 1,), say=lambda _: _notice(
        "the kinematic sweep" + (" (sparse)" if args[-1] else ""), _SWEEP_SECONDS))(*args)
    if scaling is None:
        scaling = Scaling(float(scale[0]), columns, float(scale[1]))
    return int(k), int(evals), scaling


def rcond_filler(system, pointers, times, Q, p, scaling, R):
    """A function ``fill(rconds)`` computing in place the estimates :func:`run` left
    ``RCOND_PENDING`` (``rconds`` may be a leading part of the sweep's): the same numbers the
    loop computes when it is not lazy (``_jit_loop.fill_rconds``)."""
    if _state["fill"] is None:
        from ._jit_loop import fill_rconds

        _state["fill"] = fill_rconds
    fill_rconds = _state["fill"]
    args = (pointers, _lapack(), np.ascontiguousarray(times, dtype=float), Q,
            np.ascontiguousarray(system.p_values if p is None else p, dtype=float),
            _index(system.jac_rows), _index(system.jac_cols),
            np.ascontiguousarray(scaling.columns, dtype=float), R)

    def fill(rconds: np.ndarray) -> None:
        k = len(rconds)
        bad = fill_rconds(*args[:3], args[3][:k], *args[4:8], args[8][:k], rconds)
        if bad:
            raise MechError(f"mechsys internal error: {bad} condition estimate(s) of a compiled "
                            "sweep proven regular came out singular; please report it")

    fill.kernel = system.f_velocity    # the pointer in ``pointers`` is valid while it lives
    return fill


__all__ = ["AUTO_POINTS", "RCOND_MIN", "available", "mode", "multipliers", "plan", "rcond_filler",
           "run"]
