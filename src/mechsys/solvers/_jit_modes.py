"""Compile only what a run uses: the compiled loops specialised on their mode (decision 0044).

The free-motion loops (``_jit_free_loop.runge_kutta``, ``adams``, ``derivative``) and the
kinematic sweep hold every solver kind in one function (``blocks``: dense augmented, block,
Gen tree, path, Newton, sparse; the sweep: dense or sparse LU), chosen at run time. Numba
types, and so compiles, every function a loop can call, whichever kind a run takes: the
double pendulum paid for the sparse LU, the Newton with its banded pattern and the block
path it never runs (about two thirds of the first run's CPU, decision 0044).

Two pieces make the kind a compile-time constant without a second copy of any algorithm:

* :func:`entry`: the loop compiled for the argument types of a call with the mode argument
  typed as its value (Numba's ``Literal[int](k)``), and the machine code of that
  specialisation, called directly afterwards. A literal argument reaches every function the
  loop passes it to (Numba compiles the callee for the literal type too), so the mode is
  known wherever it is tested. Numba caches each specialisation under its own signature.
* :func:`within` at each call of a mode's solver: ``within(mode, lo, hi, fn, *args)`` is
  ``fn(*args)``, except that where ``mode`` is a literal outside ``[lo, hi]`` it is
  ``False`` and ``fn`` is never typed, hence never compiled. Called with a mode that is not a
  literal (a caller of the loop from Python through the plain dispatcher) it is always the
  call: the loop then holds every kind, as before.

The run-time tests (``if blocks == BLOCK``) stay where they were: the code between them is
the one implementation of each kind, and the specialised loop takes the same branches with
the same numbers as the general one (the tests compare both bit for bit).
"""

from __future__ import annotations

import numba as nb
import numba.core.options  # noqa: F401  (_LEAF_OPTIONS reads it)
from numba._dispatcher import compute_fingerprint as _compute_fingerprint
from numba.extending import overload


def within(mode, lo, hi, fn, *args):
    r"""``fn(*args)`` when ``lo <= mode <= hi``, else ``False``, for a solver ``fn`` returning
    a bool (False: hand over). In compiled code :func:`_within_impl` decides from the types:
    a literal ``mode`` outside the range compiles to ``False`` without typing ``fn``; any
    other mode compiles to the call (the caller's own test of ``mode`` guards it at run time).

    .. math:: \mathrm{within}(k, l, h, f, a) = \begin{cases} f(a) & l \le k \le h \\
              \mathrm{False} & \text{otherwise} \end{cases}

    Example (in a compiled loop whose ``blocks`` is a literal)::

        if blocks == BLOCK:
            ok = within(blocks, BLOCK, BLOCK, _accel_blocks, kp, x, ...)
    """
    return fn(*args) if lo <= mode <= hi else False


#: compiled as the loops' leaf functions (``_jit_lapack.leaf``): no reference counting of the
#: arrays it hands on (each call would otherwise count every one of them up and down)
_LEAF_OPTIONS = {"error_model": "numpy", **(
    {"_nrt": False} if hasattr(getattr(nb.core.options, "DefaultOptions", None), "_nrt") else {})}


@overload(within, prefer_literal=True, jit_options=_LEAF_OPTIONS)
def _within_impl(mode, lo, hi, fn, *args):
    k = getattr(mode, "literal_value", None)
    if isinstance(k, int) and not lo.literal_value <= k <= hi.literal_value:
        def skip(mode, lo, hi, fn, *args):
            return False
        return skip

    def call(mode, lo, hi, fn, *args):
        return fn(*args)
    return call


def signature(args, literal=()) -> tuple:
    """The Numba argument types of ``args`` (as the dispatcher types a call from Python),
    with the arguments at the positions ``literal`` typed as their values."""
    return tuple(nb.types.literal(a) if i in literal else nb.typeof(a)
                 for i, a in enumerate(args))


def in_cache(dispatcher, sig) -> bool:
    """Whether ``dispatcher`` holds ``sig`` compiled in this process or in Numba's on-disk
    cache (its index file lists the signatures it holds)."""
    if sig in dispatcher.overloads:
        return True
    try:
        index = dispatcher._cache._cache_file._load_index()
    except Exception:      # (an unreadable or foreign index: Numba compiles, so do we say)
        return False
    return any(key[0] == sig for key in index)


#: the entries found: ``(dispatcher, literal values, argument fingerprints) -> machine code``
_ENTRIES: dict = {}


def _fingerprint(a):
    """Numba's own key of the type of ``a`` (its C dispatcher's: dtype, dimensions, layout,
    for arrays and tuples of them), about 1 µs an argument; ``numba.typeof`` took about 100
    µs an argument (measured on the loaded 2-core machine), milliseconds for a loop's 40."""
    try:
        return _compute_fingerprint(a)
    except (TypeError, ValueError, NotImplementedError):   # (a type it does not key)
        return nb.typeof(a)


def entry(dispatcher, args, literal=(), say=None):
    """The machine code of ``dispatcher`` specialised for ``args`` with the arguments at the
    positions ``literal`` typed as their values (see the module docstring): compiled, or
    loaded from Numba's cache, on the first request; afterwards found by the arguments'
    type fingerprints. ``say(True)`` is called first when it has to compile (the caller's
    notice). Call it with the same arguments: ``entry(...)(*args)``. Example::

        fn = entry(runge_kutta, args, literal=(14,))
        status, steps, *rest = fn(*args)
    """
    key = (dispatcher, tuple(args[i] for i in literal), tuple(map(_fingerprint, args)))
    got = _ENTRIES.get(key)
    if got is not None:
        return got
    sig = signature(args, literal)
    cres = dispatcher.overloads.get(sig)
    if cres is not None:
        fn = cres.entry_point
    else:
        if say is not None and not in_cache(dispatcher, sig):
            say(True)
        fn = dispatcher.compile(sig)
    _ENTRIES[key] = fn
    return fn


__all__ = ["entry", "in_cache", "signature", "within"]
