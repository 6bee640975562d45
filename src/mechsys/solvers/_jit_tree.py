"""Numba versions of the recursive Gen dynamics (``compile/_generalized.py``:
``RecursiveDynamics``; the loops in ``_tree.py``), imported only when Numba is installed.
``_fill``, ``_unpack``, ``_assemble`` and ``_articulated`` are the very
functions of the Python path, compiled; ``forward`` calls the joint kernels (SymEngine LLVM
code) through their C entry points like the compiled sweep (``solvers/_jit_calls.py``)."""

from __future__ import annotations

from ._jit_cache import check as _check_cache
from ._jit_calls import _kcall
from ._jit_lapack import leaf
from ._tree import _articulated, _assemble, _fill, _unpack

_check_cache()   # stale cached loops go before anything here compiles (see _jit_cache)

# leaves (decision 0025): they allocate nothing, so no reference counting on each call
_fill_nb = leaf(_fill)
_unpack_nb = leaf(_unpack)
assemble = leaf(_assemble)
articulated = leaf(_articulated)


@leaf
def forward(ptrs, kid, par, root, nqm, goff, gcols, nq, t, q, qd, p, xbuf, obuf, P, Pd, FP, Fg, H,
            HL, Mb, Qvb):
    """Masters first: each slave's kernel at its master's pose, then its outputs stored."""
    for s in range(kid.size):
        nm = nqm[s]
        k = goff[s + 1] - goff[s]
        x = xbuf[:1 + 2 * nm + 2 * k + p.size]
        _fill_nb(x, s, t, q, qd, p, par, root, nqm, goff, gcols, P, Pd)
        _kcall(ptrs[kid[s], 0], obuf, 0, x, ptrs[kid[s], 1])
        _unpack_nb(obuf, s, nq, nm, k, par, P, Pd, FP, Fg, H, HL, Mb, Qvb)
