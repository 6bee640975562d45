r"""What every compiled loop needs from Python, whichever it is: whether compiled loops run
at all (``MECHSYS_JIT``, Numba importable), the C entry points of the compiled kernels and of
LAPACK that the loops call, and the arrays of a large Jacobian's fixed pattern.

The drivers of the loops (``_jit_sweep``, ``_jit_multipliers``, ``_jit_free``) import this
module; it imports no driver and no loop (decision 0058), and Numba only when
:func:`available` is first asked.

Which tier runs a loop (``MECHSYS_JIT``). The free-motion stepper (``_jit_free``): ``0``
never compiled, ``1`` whenever possible, unset (``auto``) from :data:`AUTO_POINTS` points
(its own rule, unchanged). The kinematic sweep and the multiplier solves (decision 0081):
their loop takes the regular points of every job, compiled or interpreted
(:mod:`._jit_interp`: the same code, the same numbers bit for bit), so the tier may depend on
the process's state without changing a number; :func:`tier` chooses it per job:

* ``0``: never compiled: the loop interpreted;
* ``1``: compiled (loaded from Numba's cache, or compiled per ``MECHSYS_COMPILE``; the loop
  interpreted while a background compile runs);
* ``auto``: compiled when its machine code is already loaded in this process; else, when the
  job is big enough to repay loading Numba's cache (about 0.7 s CPU once per process) or
  compiling, as for ``1``; else interpreted. Big enough: at least :data:`AUTO_POINTS` points,
  or a predicted interpreted time that reaches :data:`AUTO_SECONDS` together with that of the
  small jobs run interpreted before in the process (:math:`T_{before}`):

.. math:: \text{load} \iff N \ge N_{auto} \;\vee\; T_{before} + N\, n\, c_{int} \ge T_{auto}

with :math:`c_{int}` = :data:`INTERP_SECONDS_PER_UNKNOWN` (the interpreted loop's cost per
point and unknown, decisions 0078, 0081). Possible means: Numba importable (a core
dependency since decision 0041: it holds the loops' code even when nothing is compiled), as
many equations as coordinates, and a dense system (``n <= SPARSE_THRESHOLD``) or a larger
one through its Jacobian's pattern (:func:`runnable`).

Example::

    from mechsys.solvers import _jit_runtime

    if _jit_runtime.runnable(system, large_ok=True):
        table = _jit_runtime.table([system.f_position, system.f_velocity])
        how = _jit_runtime.tier(points=5000, n=system.n)    # "interpreted", "loaded", "load"
"""

from __future__ import annotations

import ctypes
import os
import weakref

import numpy as np

from .._errors import ModelError, slow_path_warning
from ._jit_cache import compile_policy
from ._linalg import _sparse_lu
from ._tolerances import SPARSE_THRESHOLD

#: ``auto``: a job of at least this many points loads (or compiles) its compiled loop
AUTO_POINTS = 1000

#: ``auto``: a sweep or multiplier job whose interpreted run is predicted to take at least
#: this many CPU seconds loads (or compiles) its compiled loop (loading Numba and the cached
#: machine code costs about 0.7 s once per process; decision 0081)
AUTO_SECONDS = 0.5

#: the interpreted sweep's cost per point and unknown (CPU s): 40-90 µs measured on 9 to 63
#: unknowns (decisions 0078, 0081; the machine's load moves it), the multiplier solves'
#: about half; the prediction of :func:`tier`
INTERP_SECONDS_PER_UNKNOWN = 80e-6

#: while the compiled loop of a ``"load"`` job is compiled in the background (decision 0064)
#: the interpreted loop is the first tier of sweeps and multiplier solves of up to this many
#: unknowns (the dense kind); larger systems and the sparse kind take the Python code
#: meanwhile, whose point costs 10-30 x less there (decision 0083: 195 µs against 5.8 ms
#: at 63 unknowns). ``MECHSYS_JIT=0`` and the small jobs of ``auto`` interpret at any size
INTERP_WAIT_MAX = 64
#: the same for the multiplier solves with loads that depend on the multipliers (friction:
#: Newton on dense matrices)
INTERP_WAIT_MAX_DENSE = 24

#: while the compiled loop is compiled in the background, the interpreted loop asks for it
#: again after about this many CPU seconds of interpreted work (decision 0081): a large first
#: job costs at most about the compile, then runs compiled from the next point
INTERP_SECONDS = 0.3

#: up to this many unknowns the LU and condition estimate are computed in the loop
#: (``_jit_lapack``: LAPACK's algorithms, without the call overhead, skipping the zero
#: multipliers and visiting only the factors' nonzeros); above, LAPACK is called. That is
#: every size the compiled sweep takes: a mechanism's Jacobian is sparse, and the written-out
#: LU beat LAPACK's blocked one on the four-bar chains of 33 to 147 unknowns by 1.6-2.6 x
#: (decision 0019, amended); the Numba code is ``_jit_linalg``
SMALL = SPARSE_THRESHOLD

#: ``bw[0]`` of a pattern factorised by the sparse LU (``_jit_sparse``, a wide band: trees);
#: ``bw = (SPARSE, nnz, capL, capU)`` with ``nnz`` the pattern's entries and ``capL``,
#: ``capU`` the storage of the factors. The factors and work arrays live in the float array
#: ``AB = [Bx (nnz) | Lx (capL) | Ux (capU) | 3 work (n)]`` and the int array
#: ``SI = [Bp (n + 1) | Bi (nnz) | Lp (n + 1) | Up (n + 1) | pinv (n) | iw (IWORK n) |
#: Li (capL) | Ui (capU)]``, whose head is ``B = P Q A P^T``'s CSC structure
SPARSE = -2

_PLANS: dict = {}    # table(): kernel ids -> (kernels, pointer table)
_state: dict = {"failed": None, "lapack": None, "band_lapack": None, "callback_error": None,
                "interpreted": 0.0}


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


def pointer(kernel):
    """``(address, context)`` of a compiled kernel's C entry point, or None."""
    get = getattr(kernel, "c_function", None)
    return get() if get is not None else None


def table(kernels):
    """The pointer table of ``kernels`` (one row each: address, context, first-stage address,
    its context, Piecewise values; rows of zeros up to three), or None when one has no C
    entry point and cannot be given one (:func:`python_entry`). Kept per kernel objects,
    which the entry holds (their entry points live as long as they do; not on the system: a
    pickled copy must not carry another process's addresses). For the sweep's and the
    multiplier solves' loops (the free-motion stepper reads :func:`kernel_entry`, which
    makes the same entries, decision 0084)."""
    key = tuple(id(k) for k in kernels)
    got = _PLANS.get(key)
    if got is not None and all(a is b for a, b in zip(got[0], kernels)):
        return got[1]
    ptrs = [pointer(k) or python_entry(k) for k in kernels]
    if any(p is None for p in ptrs):
        return None
    while len(ptrs) < 3:
        ptrs.append((0, 0, 0, 0, 0))
    rows = np.array(ptrs, dtype=np.int64)
    if len(_PLANS) >= 64:
        _PLANS.clear()
    _PLANS[key] = (tuple(kernels), rows)
    return rows


#: the C entry points made for Python kernels: kernel -> (ctypes callback, row); an entry
#: lives as long as its kernel (whoever holds a pointer table holds its kernels)
_PY_ENTRIES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_KERNEL_PROTO = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
_DOUBLE_P = ctypes.POINTER(ctypes.c_double)


def python_entry(kernel):
    r"""A C entry point ``void f(double *out, const double *x, void *ctx)`` for a kernel that
    has none (the SymPy backend's: ``nargs`` arguments, ``nout`` outputs), as a pointer-table
    row ``(address, 0, 0, 0, 0)``, or None when the kernel does not say its sizes. The entry
    is a :mod:`ctypes` callback running the kernel's Python function (decision 0081): the
    loops (compiled, or interpreted) call it as they call a SymEngine kernel, so the kernel's
    numbers are the Python path's,

    .. math:: \mathrm{out}[0:n_{out}] = f(x[0:n_{args}])

    A Python exception cannot cross the C frames of a compiled loop: the entry catches it
    and writes NaN, so that the loop hands that point to the Python code, which calls the
    kernel itself and raises the error there; an interrupt (``KeyboardInterrupt``) is kept
    and raised by :func:`raise_callback_error` when the loop returns. Example::

        row = python_entry(system.f_position)      # (address, 0, 0, 0, 0)
    """
    nargs, nout = getattr(kernel, "nargs", None), getattr(kernel, "nout", None)
    if nargs is None or nout is None:
        return None
    try:
        got = _PY_ENTRIES.get(kernel)
    except TypeError:                  # (not weakly referable: no entry)
        return None
    if got is not None:
        return got[1]

    def call(out, x, ctx):
        o = np.ctypeslib.as_array(ctypes.cast(out, _DOUBLE_P), shape=(nout,))
        try:
            o[:] = kernel(np.ctypeslib.as_array(ctypes.cast(x, _DOUBLE_P), shape=(nargs,)).copy())
        except BaseException as exc:     # noqa: BLE001 (nothing may cross the C frames)
            o[:] = np.nan
            if not isinstance(exc, Exception) and _state["callback_error"] is None:
                _state["callback_error"] = exc

    cb = _KERNEL_PROTO(call)
    row = (ctypes.cast(cb, ctypes.c_void_p).value, 0, 0, 0, 0)
    _PY_ENTRIES[kernel] = (cb, row)
    return row


def raise_callback_error() -> None:
    """Raise the interrupt (``KeyboardInterrupt``, ``SystemExit``) a Python kernel's entry
    point (:func:`python_entry`) caught while a loop ran, if any."""
    exc = _state["callback_error"]
    if exc is not None:
        _state["callback_error"] = None
        raise exc


def runnable(system, large_ok: bool = False) -> bool:
    """Whether the sweep's or the multiplier solves' loop can take this system's points at
    all (compiled or interpreted): Numba importable (the loops' code lives in its
    dispatchers), as many equations as coordinates, and ``n <= SPARSE_THRESHOLD`` or, with
    ``large_ok``, the Jacobian's ``FixedPattern`` (the sweep, and the multiplier solves; with
    friction, when its Newton matrix's pattern is banded or sparse-factorisable)."""
    if system.n == 0 or system.m != system.n:
        return False
    if system.n > SPARSE_THRESHOLD and not (large_ok and patterned(system)):
        return False
    return available()


def tier(points: int, n: int) -> str:
    """The tier of a sweep or multiplier job of ``points`` points and ``n`` unknowns (the rule
    of the module docstring): ``"interpreted"`` (never compiled: ``MECHSYS_JIT=0``),
    ``"loaded"`` (compiled only when its machine code is already loaded in this process,
    else interpreted: an ``auto`` job too small to repay loading it) or ``"load"`` (load it,
    or compile it per ``MECHSYS_COMPILE``; interpreted meanwhile). Every tier gives the same
    numbers, bit for bit: the choice changes the cost only. The predicted interpreted time of
    the ``"loaded"`` jobs adds up per process: once it reaches :data:`AUTO_SECONDS`, the
    next job loads the compiled loop (many small jobs repay the load together)."""
    m = mode()
    if m == "off":
        return "interpreted"
    cost = points * n * INTERP_SECONDS_PER_UNKNOWN
    if m == "on" or points >= AUTO_POINTS or _state["interpreted"] + cost >= AUTO_SECONDS:
        return "load"
    _state["interpreted"] += cost      # (many small jobs repay the load together)
    return "loaded"


def loaded(dispatcher, args, literal=()):
    """The machine code of ``dispatcher`` specialised for ``args`` (as
    ``_jit_modes.entry``) when it is already loaded in this process, else None: nothing is
    read from the disk cache and nothing compiled (an ``auto`` job too small to repay that)."""
    if not dispatcher.overloads:
        return None          # (nothing of this loop loaded yet: no typing of the arguments)
    from ._jit_modes import _ENTRIES, _fingerprint, signature

    key = (dispatcher, tuple(args[i] for i in literal), tuple(map(_fingerprint, args)))
    got = _ENTRIES.get(key)
    if got is not None:
        return got
    cres = dispatcher.overloads.get(signature(args, literal))
    if cres is None:
        return None
    _ENTRIES[key] = cres.entry_point
    return cres.entry_point


def index(a) -> np.ndarray:
    """``a`` as int64 (no copy when it is already)."""
    return np.asarray(a, dtype=np.int64)


def capsule_address(capsule) -> int:
    """The C address held by a ``PyCapsule`` (SciPy's ``cython_lapack.__pyx_capi__`` entries)."""
    api = ctypes.pythonapi
    api.PyCapsule_GetName.restype = ctypes.c_char_p
    api.PyCapsule_GetName.argtypes = [ctypes.py_object]
    api.PyCapsule_GetPointer.restype = ctypes.c_void_p
    api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
    return api.PyCapsule_GetPointer(capsule, api.PyCapsule_GetName(capsule))


def _jacobian_pattern(system):
    pattern = getattr(system, "jacobian_pattern", None)
    return pattern() if pattern is not None else None


def patterned(system) -> bool:
    """The system's Jacobian has a ``FixedPattern`` whose sparse LU the loops call (the
    compiled one, ``_jit_sparse``: also the Python path's)."""
    pat = _jacobian_pattern(system)
    return pat is not None and pat.size > 0 and not pat.banded and _sparse_lu() is not None


#: the (unused) sparse-LU arguments of a dense system's loop
NO_BAND = (np.array([-1, 0, 0, 0], dtype=np.int64), (np.zeros(0, dtype=np.int64),) * 7)


def band_args(system):
    """``(bw, band)`` of ``_jit_sweep_loop.sweep_dense`` for a system above ``SPARSE_THRESHOLD``
    unknowns: its Jacobian's ``FixedPattern`` (the arrays kept on the pattern, made once):
    ``bw = (SPARSE, nnz, capL, capU)`` (the factors' storage as the Python path has grown it
    so far) and ``band = (slot, rows, cols, pos, row_perm, perm, head)``, ``head`` the CSC
    structure of ``B = P Q A P^T``."""
    pat = system.jacobian_pattern()
    got = getattr(pat, "_jit_band", None)
    if got is None:
        slot, rows, indptr = system._csc_structure()
        cols = np.repeat(np.arange(system.n), np.diff(indptr))
        head = np.concatenate([pat.s_indptr, pat.s_indices])
        got = tuple(index(a) for a in (slot, rows, cols, pat._pos, pat.row_perm, pat.perm, head))
        pat._jit_band = got
    return np.array([SPARSE, pat.s_indices.size, *pat._cap], dtype=np.int64), got


def band_lapack() -> np.ndarray:
    """The C addresses of SciPy's ``dgbtrf`` and ``dgbtrs``."""
    if _state.get("band_lapack") is None:
        from scipy.linalg import cython_lapack

        caps = cython_lapack.__pyx_capi__
        _state["band_lapack"] = np.array([capsule_address(caps[f]) for f in ("dgbtrf", "dgbtrs")],
                                         dtype=np.int64)
    return _state["band_lapack"]


def lapack() -> np.ndarray:
    """The C addresses of SciPy's ``dgetrf``, ``dgecon`` and ``dgetrs``."""
    if _state["lapack"] is None:
        from scipy.linalg import cython_lapack

        caps = cython_lapack.__pyx_capi__
        _state["lapack"] = np.array([capsule_address(caps[f]) for f in ("dgetrf", "dgecon", "dgetrs")],
                                    dtype=np.int64)
    return _state["lapack"]


def kernel_entry(kernel):
    """``(row, expand)`` of a kernel's C entry points (``_SymengineCompiled.c_entry``: the
    pointer-table row and the map of its repeated outputs, an empty array when there are
    none); for a kernel without LLVM code that says its sizes (the SymPy backend's), the
    :func:`python_entry` made of its Python function (every output written: no map;
    decision 0084); else None."""
    get = getattr(kernel, "c_entry", None)
    e = get() if get is not None else None
    if e is None:
        row = python_entry(kernel)
        return None if row is None else (row, np.zeros(0, dtype=np.int64))
    row, expand = e
    return row, (np.zeros(0, dtype=np.int64) if expand is None
                 else np.asarray(expand, dtype=np.int64))


class GenTree:
    """The recursive Gen dynamics (``compile._generalized.RecursiveDynamics``) as the
    compiled loop evaluates it (``_jit_free_loop._accel_gen``): ``arrays = (joint kernel
    entry points (kernels, 2), kid, par, root, nqm, goff, gcols, M_rows, M_cols, sizes)``
    with ``sizes = [nq, kM, kJ, kg, slaves, kmax, joint inputs, joint outputs, main inputs,
    main outputs]``; ``tree``: the articulated-body recursion (no constraint equation)."""

    def __init__(self, arrays, tree):
        self.arrays, self.tree = arrays, bool(tree)

    @staticmethod
    def none():
        z = np.zeros(1, dtype=np.int64)
        return (np.zeros((1, 2), dtype=np.int64), z, z, z, z, z, z, z, z,
                np.ones(10, dtype=np.int64))

    @classmethod
    def of(cls, system, dyn, main_row):
        """The structure, or None when a joint kernel has no C entry point and none can be
        made (:func:`python_entry`: a kernel that does not say its sizes), or a two-stage
        one (then the Python code runs). The entry points are the kernels' own, whatever
        ``MECHSYS_JIT`` said when the dynamics first ran (``RecursiveDynamics._engine``
        settles on its plain-Python recursion under ``0``; that choice is the Python
        code's alone: decision 0084)."""
        ptrs = [pointer(k) or python_entry(k) for k in dyn._kernels]
        if any(p is None or p[2] != 0 for p in ptrs):
            return None
        kid, par, root, nqm, goff, gcols, nq = dyn._tree
        kM, kJ, _, kg, _ = dyn._sizes
        n, m = system.n, system.m
        S = len(kid)
        kmax = max(1, int(np.diff(goff).max(initial=1)))
        npar = len(system.p_values)
        nin = 1 + 3 * n + m + npar
        sizes = [nq, kM, kJ, kg, S, kmax, 1 + 2 * nq + 2 * kmax + npar,
                 nq * (4 + nq + kmax + nq), nin + 2 * S * nq + max(int(main_row[4]), 0),
                 kM + kJ + 2 * n + kg + S * nq]
        i64 = np.int64
        arrays = (np.array([[p[0], p[1]] for p in ptrs], dtype=i64),
                  *(np.ascontiguousarray(a, dtype=i64)
                    for a in (kid, par, root, nqm, goff, gcols, dyn._M_rows, dyn._M_cols)),
                  np.array(sizes, dtype=i64))
        return cls(arrays, dyn.tree_only)


__all__ = ["AUTO_POINTS", "INTERP_WAIT_MAX", "INTERP_WAIT_MAX_DENSE",
           "AUTO_SECONDS", "INTERP_SECONDS", "INTERP_SECONDS_PER_UNKNOWN", "NO_BAND",
           "GenTree", "available", "band_args", "band_lapack", "capsule_address", "compile_policy",
           "index", "kernel_entry", "lapack", "loaded", "mode", "patterned", "pointer",
           "python_entry", "raise_callback_error", "runnable", "table", "tier"]
