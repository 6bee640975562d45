"""Borrowed arrays for the compiled loops: the same data without reference counting.

Numba counts references to every array it passes to a function that LLVM does not inline:
an atomic increment on entry and a decrement on exit, per array and per call. The loops'
inner functions take dozens of work arrays (the free-motion derivative about 80, nested
calls included), so at a few nanoseconds per count this bookkeeping cost more than the
arithmetic of a small system (measured: a call passing 40 arrays, 490 ns counted against
97 ns borrowed; see decision 0021).

:func:`borrow` returns its argument (an array, or a tuple of arrays, nested tuples and
scalars) with each array's owner pointer (``meminfo``) and Python parent cleared: the
same data, shape and strides, but Numba's reference counting of the copy does nothing.

**Safety contract**: a borrowed array does not keep its data alive. Borrow only arrays
whose owner outlives every use of the borrowed copy; in this package that means the
arguments of a compiled loop called from Python (the Python caller holds them for the
call's duration), never an array allocated inside the loop (Numba frees a local after its
last use, which may precede the borrowed copy's uses), and never return a borrowed array
or store it anywhere that outlives the call.

Example (inside an ``@nb.njit`` function whose arguments come from Python)::

    work = borrow(work)          # the tuple of work arrays, counted no more
"""

from __future__ import annotations

from numba.core import cgutils, types
from numba.extending import intrinsic

_PLAIN = (types.Number, types.Boolean, types.NoneType)


def _supported(ty) -> bool:
    """Arrays, scalars, and tuples of them (nested): what :func:`borrow` accepts."""
    if isinstance(ty, types.BaseTuple):
        return all(_supported(t) for t in ty.types)
    return isinstance(ty, (types.Array, *_PLAIN))


def _strip(context, builder, ty, value):
    """``value`` of Numba type ``ty`` with every array's meminfo and parent set to null."""
    if isinstance(ty, types.Array):
        ary = context.make_array(ty)(context, builder, value=value)
        ary.meminfo = cgutils.get_null_value(ary.meminfo.type)
        ary.parent = cgutils.get_null_value(ary.parent.type)
        return ary._getvalue()
    if isinstance(ty, types.BaseTuple):
        out = value
        for i, member in enumerate(ty.types):
            item = builder.extract_value(value, i)
            out = builder.insert_value(out, _strip(context, builder, member, item), i)
        return out
    return value                       # a scalar: nothing counted


@intrinsic
def borrow(typingctx, value):
    """``value`` (an array or a possibly nested tuple of arrays and scalars) with reference
    counting switched off for its arrays; see the module docstring for when it is safe."""
    if not _supported(value):
        return None                    # a typing error: e.g. a list would need counting

    def codegen(context, builder, signature, args):
        return _strip(context, builder, signature.args[0], args[0])

    return value(value), codegen


__all__ = ["borrow"]
