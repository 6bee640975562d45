r"""The compiled loops' own code, run by the Python interpreter: the first tier of a loop
that is not compiled yet (the sweep and the multiplier solves: decision 0075, and since
decision 0081 every sweep and multiplier job whose compiled loop is not loaded, and
``MECHSYS_JIT=0``'s; the free-motion Runge-Kutta stepper, its derivative and a path's
accelerations: decision 0077, and since decision 0082 ``MECHSYS_JIT=0``'s too).

A Numba dispatcher keeps the Python function it compiles (``dispatcher.py_func``); its code
object is the loop. :func:`interpreted` makes a plain Python function of that same code
object, whose globals are a copy of its module's with every dispatcher replaced by its own
interpreted function (recursively, each module's functions with their module's globals) and
the two intrinsics that have no Python meaning replaced by calls through :mod:`ctypes`:

* ``_kcall(addr, out, off, x, ctx)``: the SymEngine kernel
  ``void f(double *out, const double *x, void *ctx)`` at ``addr``, ``out`` from element
  ``off`` on (the compiled loop's instruction: the same machine code of the kernel);
* ``_ccall(addr, args)``: the C function at ``addr`` (SciPy's LAPACK) with each array of
  ``args`` passed by its data pointer and each integer as a pointer value;
* ``borrow(value)`` (reference counting switched off): ``value`` itself.

Nothing is re-written: the bytecode that runs is the one Numba compiles, so the two tiers
take the same branches and, with IEEE double arithmetic in both (NumPy's scalars here,
LLVM's without fast-math there; no fused multiply-add in either), compute the same numbers.
What differs is the cost: each scalar operation is an interpreted one (about 0.1 µs instead
of about 1 ns).

.. math:: \mathrm{interpreted}(f) = \mathrm{FunctionType}(f_{py}.\mathtt{\_\_code\_\_},
          G'(f_{py}.\mathtt{\_\_globals\_\_}))

Example::

    from mechsys.solvers._jit_interp import interpreted
    from mechsys.solvers._jit_sweep_loop import sweep_dense

    loop = interpreted(sweep_dense)      # a Python function: loop(*args) as sweep_dense(*args)
"""

from __future__ import annotations

import ctypes
import types
import weakref

import numpy as np

#: functions made so far: the Python function of a dispatcher -> its interpreted twin of code
_FUNCS: dict = {}
#: module globals (by id of the module's dict) -> the rebound copy
_GLOBALS: dict = {}
#: C function objects by (address, argument count)
_CFUNCS: dict = {}
#: kernel functions (three pointer arguments) by address alone: the hot path of ``_kcall``
_KFUNCS: dict = {}
#: data addresses of arrays: id -> (weak reference, address). An array's data never moves
#: (the loops do not resize), so its address is computed once; the weak reference tells a
#: live array from a new one that reuses a dead one's id. ``a.ctypes.data`` builds a ctypes
#: object each time, about 1 µs, a third of an interpreted kernel call (decision 0077)
_ADDRS: dict = {}


def _cfunc(addr, nargs: int):
    key = (int(addr), nargs)
    f = _CFUNCS.get(key)
    if f is None:
        proto = ctypes.CFUNCTYPE(None, *([ctypes.c_void_p] * nargs))
        f = _CFUNCS[key] = proto(key[0])
    return f


def _address(a: np.ndarray) -> int:
    """The data address of array ``a`` (cached for the arrays that live on: a run's work
    arrays; a view made per call is a new object, looked up anew)."""
    got = _ADDRS.get(id(a))
    if got is not None and got[0]() is a:
        return got[1]
    addr = a.ctypes.data
    try:
        ref = weakref.ref(a)
    except TypeError:                  # (not weakly referable: not cached)
        return addr
    if len(_ADDRS) >= 4096:
        _ADDRS.clear()
    _ADDRS[id(a)] = (ref, addr)
    return addr


def _kcall(addr, out, off, x, ctx):
    """The intrinsic ``_jit_calls._kcall`` through ctypes: the kernel at ``addr`` writes
    ``out[off:]`` from ``x`` (the arrays are C-contiguous float64, as in the loops)."""
    f = _KFUNCS.get(addr)
    if f is None:
        f = _KFUNCS[addr] = _cfunc(addr, 3)
    f(_address(out) + 8 * int(off), _address(x), int(ctx) or None)


def _ccall(addr, args):
    """The intrinsic ``_jit_calls._ccall`` through ctypes: arrays by their data pointers,
    integers as pointer values."""
    ptrs = [_address(a) if isinstance(a, np.ndarray) else (int(a) or None) for a in args]
    _cfunc(addr, len(ptrs))(*ptrs)


def _is_dispatcher(obj) -> bool:
    return hasattr(obj, "py_func") and hasattr(obj, "overloads")


def _borrow(value):
    """The intrinsic ``_jit_borrow.borrow`` (reference counting switched off: nothing to do
    in Python)."""
    return value


def _shims():
    from . import _jit_borrow, _jit_calls

    return {id(_jit_calls._kcall): _kcall, id(_jit_calls._ccall): _ccall,
            id(_jit_borrow.borrow): _borrow}


def _rebound(g: dict) -> dict:
    """The copy of module globals ``g`` seen by interpreted functions."""
    got = _GLOBALS.get(id(g))
    if got is not None and got[0] is g:
        return got[1]
    new = dict(g)
    _GLOBALS[id(g)] = (g, new)          # (before the values: functions calling each other)
    shims = _shims()
    for name, v in g.items():
        if _is_dispatcher(v):
            new[name] = interpreted(v)
        elif id(v) in shims:
            new[name] = shims[id(v)]
    return new


def interpreted(dispatcher):
    """The plain Python function running ``dispatcher``'s code (see the module docstring).
    ``dispatcher``: a Numba dispatcher (``nb.njit``); anything else is returned as it is."""
    if not _is_dispatcher(dispatcher):
        return dispatcher
    py = dispatcher.py_func
    got = _FUNCS.get(py)
    if got is not None:
        return got
    # (the globals are registered before they are filled: functions calling each other find
    # the same dict, filled by the time anything runs)
    fn = types.FunctionType(py.__code__, _rebound(py.__globals__), py.__name__, py.__defaults__,
                            py.__closure__)
    fn.__doc__, fn.__qualname__, fn.__module__ = py.__doc__, py.__qualname__, py.__module__
    _FUNCS[py] = fn
    return fn


__all__ = ["interpreted"]
