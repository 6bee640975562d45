r"""Calls into C from compiled code: the SymEngine kernels' C entry points
(``void f(double *out, const double *in, void *ctx)``) and any C function by its address
(SciPy's LAPACK), as Numba intrinsics, without a Python object on the way.

A kernel's row of the pointer table (``_jit_runtime.table``) is ``(address, context,
first-stage address, its context, Piecewise values)``: a two-stage kernel (spline profiles,
``Piecewise``) first evaluates its inner values ``y = g(x)`` into the tail of ``out`` and then
``f([x, y])``:

.. math:: \mathrm{out} = f(x) \quad\text{or}\quad
          \mathrm{out} = f\big(x \,\|\, g(x)\big)

A leaf of the compiled code (decision 0058): the sweep, free-motion, multiplier and tree
loops all call the kernels through here. Example (inside a compiled loop)::

    _eval(ptrs[0], x, nin, out)          # out <- Phi(t, q, p)
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ._jit_cache import check as _check_cache
from ._jit_lapack import leaf

_check_cache()   # stale cached loops go before anything here compiles (see _jit_cache)


@intrinsic
def _ccall(typingctx, addr, args):
    """Call ``void f(void *, ...)`` at ``addr``: each array of the tuple ``args`` passes its
    data pointer, each integer passes as a pointer value (a context)."""
    sig = types.void(addr, args)

    def codegen(context, builder, signature, llargs):
        vp = ir.IntType(8).as_pointer()
        tup_ty = signature.args[1]
        vals = cgutils.unpack_tuple(builder, llargs[1], len(tup_ty))
        ptrs = []
        for ty, val in zip(tup_ty, vals):
            if isinstance(ty, types.Array):
                ptrs.append(builder.bitcast(context.make_array(ty)(context, builder, val).data, vp))
            else:
                ptrs.append(builder.inttoptr(val, vp))
        fn = builder.inttoptr(llargs[0], ir.FunctionType(ir.VoidType(), [vp] * len(ptrs)).as_pointer())
        builder.call(fn, ptrs)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _kcall(typingctx, addr, out, off, x, ctx):
    """Call the kernel ``void f(double *out, const double *x, void *ctx)`` at ``addr`` with
    ``out`` starting at element ``off``. The arrays pass as arguments, not in a tuple as to
    :func:`_ccall`: building a tuple of arrays increments and decrements their reference
    counts (atomic operations), which cost 10-15 % of the sweep, measured."""
    sig = types.void(addr, out, off, x, ctx)

    def codegen(context, builder, signature, llargs):
        vp = ir.IntType(8).as_pointer()
        o = context.make_array(signature.args[1])(context, builder, llargs[1])
        a = context.make_array(signature.args[3])(context, builder, llargs[3])
        optr = builder.gep(o.data, [llargs[2]])
        fn = builder.inttoptr(llargs[0], ir.FunctionType(ir.VoidType(), [vp, vp, vp]).as_pointer())
        builder.call(fn, [builder.bitcast(optr, vp), builder.bitcast(a.data, vp),
                          builder.inttoptr(llargs[4], vp)])
        return context.get_dummy_value()

    return sig, codegen


@leaf
def _eval(ptr, x, nin, out):
    """One kernel (a row of the pointer table: see ``_jit_runtime.table``) at ``x[:nin]``; a
    two-stage kernel first writes its ``Piecewise`` values into ``x[nin:]``."""
    if ptr[2] != 0:
        _kcall(ptr[2], x, nin, x, ptr[3])
    _kcall(ptr[0], out, 0, x, ptr[1])


@leaf
def _eval_row(ptrs, row, x, nin, out):
    """:func:`_eval` of row ``row`` of the pointer table, given the table: a view of the row
    per call costs its reference counting, about as much as a small kernel."""
    if ptrs[row, 2] != 0:
        _kcall(ptrs[row, 2], x, nin, x, ptrs[row, 3])
    _kcall(ptrs[row, 0], out, 0, x, ptrs[row, 1])


__all__ = ["_ccall", "_eval", "_eval_row", "_kcall"]
