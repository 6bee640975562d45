r"""Backends that turn a list of SymPy expressions into a fast numeric function.

Every backend returns a :class:`Compiled` object: ``f(x)`` evaluates all expressions at one
argument vector ``x`` (shape ``(nargs,)``) into shape ``(k,)``; ``f.batch(X)`` evaluates at
many, ``X`` of shape ``(N, nargs)`` into ``(N, k)``.

* ``"symengine"`` – SymEngine's ``Lambdify`` with the LLVM backend when SymEngine was built
  with it (the ``fast`` extra), *without* its common-subexpression elimination (SymEngine
  0.15's ``cse=True`` returns wrong values; LLVM's optimiser removes repeated work anyway).
  Preferred: see ``docs/decisions/0002-numeric-backend.md`` for the measurement.
  ``Piecewise`` (spline profiles) compiles in two stages, see :func:`_split_piecewise`.
  Expressions SymEngine cannot compile (``Mod``, ``Abs``...) go to SymPy instead.
* ``"sympy"`` – ``sympy.lambdify`` to NumPy with ``cse=True``; always available.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
import sympy as sp

try:  # optional
    import symengine as _se
except ImportError:  # pragma: no cover - depends on environment
    _se = None


class Compiled:
    """A compiled vector function of one flat argument vector."""

    backend = "?"
    nout: int

    def __call__(self, x: np.ndarray) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError

    def batch(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, dtype=float))
        return np.array([self(x) for x in X]).reshape(len(X), self.nout)


class _Empty(Compiled):
    backend = "none"

    def __init__(self):
        self.nout = 0

    def __call__(self, x):
        return np.zeros(0)

    def batch(self, X):
        return np.zeros((len(np.atleast_2d(X)), 0))


class _SympyCompiled(Compiled):
    backend = "sympy"

    def __init__(self, args: Sequence[sp.Symbol], exprs: Sequence[sp.Expr]):
        self.nout = len(exprs)
        self._f = sp.lambdify([list(args)], list(exprs), modules="numpy", cse=True)

    def __call__(self, x):
        return np.array(self._f(x), dtype=float)

    def batch(self, X):
        X = np.atleast_2d(np.asarray(X, dtype=float))
        cols = self._f(X.T)
        out = np.empty((X.shape[0], self.nout))
        for k, c in enumerate(cols):
            out[:, k] = c
        return out


def _split_piecewise(exprs):
    """``(pieces, reduced)``: the distinct outermost ``Piecewise`` of SymEngine ``exprs`` and
    ``exprs`` with each replaced by a new symbol (``{symbol: piecewise}``, insertion order).

    A spline profile's ``Piecewise`` (``geometry/_curves.py``) recurs tens of times in a
    Jacobian and ``gamma``; without CSE (``docs/decisions/0002``) LLVM would compile every
    copy: 60 s instead of 2 s for a 361-knot cam (``docs/decisions/0008-curves.md``)."""
    found: dict = {}
    seen: set = set()
    stack = list(exprs)
    while stack:
        e = stack.pop()
        if e in seen:
            continue
        seen.add(e)
        if isinstance(e, _se.Piecewise):
            found.setdefault(e, _se.Symbol(f"_mechsys_piecewise_{len(found)}"))
        else:
            stack.extend(e.args)
    if not found:
        return {}, list(exprs)
    return {v: k for k, v in found.items()}, [e.xreplace(found) for e in exprs]


def _lambdify(args, exprs, opt_level, cse=False):
    try:
        return _se.Lambdify(list(args), list(exprs), backend="llvm", cse=cse,
                            opt_level=opt_level), "symengine-llvm"
    except (ValueError, TypeError, RuntimeError):  # built without LLVM, or unsupported
        return _se.Lambdify(list(args), list(exprs), cse=cse), "symengine-lambda"


class _SymengineCompiled(Compiled):
    """SymEngine ``Lambdify``; expressions with ``Piecewise`` in two stages: the distinct
    ``Piecewise`` first (``_pre``), then the rest with their values as extra arguments."""

    backend = "symengine"

    def __init__(self, args, exprs, opt_level: int = 3, cse: bool = False):
        self.nout = len(exprs)
        exprs = [_se.sympify(e) for e in exprs]
        pieces, exprs = _split_piecewise(exprs)
        self._pre = None
        if pieces:
            self._pre, _ = _lambdify(args, list(pieces.values()), opt_level, cse)
            self._nargs = len(args)
            args = [*args, *pieces]
            self._buf = np.empty(len(args))     # [x, Piecewise values]: one call each
        self._f, self.backend = _lambdify(args, exprs, opt_level, cse)
        self._nin = len(args) - len(pieces)
        # SymEngine's unchecked entry point costs ~0.8 us a call instead of ~4 us: the
        # checks it skips (length, dtype, contiguity) are done here, once per call
        self._fast = hasattr(self._f, "unsafe_real") and (
            self._pre is None or hasattr(self._pre, "unsafe_real"))
        # the lambda backend may accept what it cannot evaluate: probe once
        probe = self(np.zeros(self._nin))
        del probe

    def __call__(self, x):
        x = np.ascontiguousarray(x, dtype=float)
        if x.shape != (self._nin,):
            raise ValueError(f"compiled function of {self._nin} arguments called with "
                             f"shape {x.shape}")
        if not self._fast:
            return self._slow(x)
        if self._pre is not None:
            buf = self._buf
            buf[:self._nargs] = x
            self._pre.unsafe_real(x, buf[self._nargs:])
            x = buf
        out = np.empty(self.nout)      # a new array per call: callers may keep the last one
        self._f.unsafe_real(x, out)
        return out

    def _slow(self, x):
        if self._pre is not None:
            buf = self._buf
            buf[:self._nargs] = x
            buf[self._nargs:] = self._pre(x)
            x = buf
        return self._f(x).reshape(self.nout)

    def batch(self, X):
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if self._pre is not None:
            X = np.hstack([X, self._pre(X).reshape(X.shape[0], -1)])
        return self._f(X).reshape(X.shape[0], self.nout)


def available_backends() -> list[str]:
    return (["symengine"] if _se is not None else []) + ["sympy"]


def default_backend() -> str:
    """``MECHSYS_BACKEND`` if set, else SymEngine when installed, else SymPy."""
    env = os.environ.get("MECHSYS_BACKEND")
    if env:
        return env
    return available_backends()[0]


def compile_exprs(args: Sequence[sp.Symbol], exprs: Sequence[sp.Expr],
                  backend: str | None = None, once: bool = False, cse: bool = False) -> Compiled:
    """Compile ``exprs`` as a function of the flat argument list ``args``.

    ``once``: the function is evaluated a few times only (``m.dof()``'s Jacobian): LLVM
    without optimisation compiles ~30 times faster (0.03 s instead of 1 s for a 600-coordinate
    chain's Jacobian) and evaluates ~1.5 times slower.

    ``cse``: common subexpressions first (SymEngine). Off by default (slow on the flat
    expressions of absolute coordinates); on for models with Gen joints, whose nested slave
    poses share most of their subexpressions (decision 0010: 10 times faster compiles)."""
    if not exprs:
        return _Empty()
    backend = backend or default_backend()
    if backend == "symengine":
        if _se is None:
            raise ImportError("the symengine backend needs `pip install mechsys[fast]`")
        from ._derive import symengine_safe

        sympy_exprs = [e for e in exprs if isinstance(e, sp.Basic)]
        if sympy_exprs and not symengine_safe(sympy_exprs):
            # SymEngine 0.15 crashes on some functions (Mod): keep them with SymPy
            return _SympyCompiled(args, [sp.sympify(e) for e in exprs])
        try:
            return _SymengineCompiled(args, exprs, opt_level=0 if once else 3, cse=cse)
        except (RuntimeError, TypeError, ValueError, NotImplementedError):
            # a function SymEngine cannot compile (e.g. Mod, Abs): SymPy can
            return _SympyCompiled(args, [sp.sympify(e) for e in exprs])
    if backend == "sympy":
        return _SympyCompiled(args, exprs)
    raise ValueError(f"unknown backend {backend!r}; choose from {available_backends()}")
