r"""Backends that turn a list of SymPy expressions into a fast numeric function.

Every backend returns a :class:`Compiled` object: ``f(x)`` evaluates all expressions at one
argument vector ``x`` (shape ``(nargs,)``) into shape ``(k,)``; ``f.batch(X)`` evaluates at
many, ``X`` of shape ``(N, nargs)`` into ``(N, k)``.

* ``"symengine"`` – SymEngine's ``Lambdify`` with the LLVM backend when SymEngine was built
  with it (the ``fast`` extra), *without* its common-subexpression elimination (SymEngine
  0.15's ``cse=True`` returns wrong values; LLVM's optimiser removes repeated work anyway).
  Preferred: see ``docs/decisions/0002-numeric-backend.md`` for the measurement.
  ``Piecewise`` (spline profiles) compiles in two stages, see :func:`_split_piecewise`; so
  does a large unoptimised kernel, whose first stage computes the distinct ``sin``/``cos``
  and copies the arguments its second stage reads (:func:`_split_trig`,
  :func:`_gather_stage`, ``docs/decisions/0066-two-stage-large-kernels.md``).
  Expressions SymEngine cannot compile (``Mod``, ``Abs``...) go to SymPy instead.
* ``"sympy"`` – ``sympy.lambdify`` to NumPy with ``cse=True``; always available.
"""

from __future__ import annotations

import gc
import os
import threading
from collections.abc import Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import sympy as sp

from .._errors import choice, slow_path_warning
from . import _cache

try:  # a core dependency (decision 0041); SymPy's lambdify serves where it cannot be imported
    import symengine as _se
except ImportError as _exc:  # pragma: no cover - depends on environment
    _se = None
    _se_error = _exc


# -- the cyclic garbage collector, paused while the symbolic build allocates --------------
_GC = {"depth": 0, "was_enabled": False, "lock": threading.Lock()}


@contextmanager
def gc_paused():
    """Pause Python's cyclic garbage collector for the enclosed symbolic work (nested and
    threaded uses pause it once; it is re-enabled as it was when the outermost ends).

    Deriving and compiling a large model allocates millions of short-lived objects (SymPy
    and SymEngine expression wrappers, none in reference cycles: reference counting frees
    them), and each allocation burst triggers the collector's full passes over every live
    object, the library's own included: 0.55 s of the 1024-link chain's 6.5 s build went to
    seven such passes (decision 0079). No value changes; what becomes garbage in cycles
    meanwhile is collected after.

    Example::

        with gc_paused():
            kernel = compile_exprs(args, exprs)
    """
    with _GC["lock"]:
        if _GC["depth"] == 0:
            _GC["was_enabled"] = gc.isenabled()
            gc.disable()
        _GC["depth"] += 1
    try:
        yield
    finally:
        with _GC["lock"]:
            _GC["depth"] -= 1
            if _GC["depth"] == 0 and _GC["was_enabled"]:
                gc.enable()


# -- the numbers an expression may hold ------------------------------------------------------
#: integer exponents at or above this magnitude are not exact in a double (2**53); SymEngine's
#: LLVM code reads them as 64-bit integers and wraps them modulo 2**64 (issue 34: a driver
#: ``T**(2**64 + 1)`` ran as ``T``), so they are rewritten with float exponents
BIG_EXPONENT = 2**53


def _complex_constant(expr):
    """The first complex constant of a SymPy or SymEngine ``expr`` (``I``, ``zoo``, a number
    valued function such as ``asin(2)`` or ``(-2)**(1/3)`` that is not real), or None."""
    if isinstance(expr, sp.Basic):
        if expr.has(sp.I):
            return sp.I
        if expr.has(sp.zoo):
            return sp.zoo
        for a in expr.atoms(sp.Function, sp.Pow):
            if a.is_number and a.is_real is False:
                return a
        return None
    if _se is not None and isinstance(expr, _se.Basic):
        if expr.has(_se.I):
            return _se.I
        if expr.has(_se.zoo):
            return _se.zoo
    return None


def _big_powers(expr) -> list:
    atoms = expr.atoms(sp.Pow) if isinstance(expr, sp.Basic) else expr.atoms(_se.Pow)
    return [a for a in atoms if a.args[1].is_Integer and abs(int(a.args[1])) >= BIG_EXPONENT]


def real_expression(expr, owner: str | None = None):
    r"""``expr`` ready for real double-precision code (the one check at the boundary where
    SymPy or SymEngine expressions become numbers).

    * A complex constant (``sqrt(-1)``, :math:`\log(-1) = i \pi`, ``"I"``, ``asin(2)``) was dropped to
      its real part with only a NumPy warning: it raises :class:`~mechsys.ModelError` showing
      the expression (and ``owner``, the constraint or load, when given).
    * An integer exponent ``n`` with ``|n| >= 2**53`` is rewritten with a float exponent:
      ``b**n = b**float(n)`` for even ``n``, ``b * |b|**float(n - 1)`` for odd ``n`` (every
      double at or above ``2**53`` is an even integer, so the odd power keeps the sign of
      ``b`` through its first factor); exact to double precision (``|b|**n`` is 0, 1 or
      infinite there), where the integer would wrap modulo ``2**64`` in compiled code.
    """
    if not isinstance(expr, sp.Basic) and not (_se is not None and isinstance(expr, _se.Basic)):
        return expr
    if isinstance(expr, sp.Basic) and _plainly_real(expr):
        return expr
    c = _complex_constant(expr)
    if c is not None:
        from .._errors import ModelError

        who = f"{owner}: " if owner else ""
        raise ModelError(f"{who}the expression {expr} holds the complex constant {c}; mechsys "
                         "computes in real numbers (a complex value would be cut to its real "
                         "part): write the real expression meant (sqrt(-1), log(-1), 'I' are "
                         "complex)")
    big = _big_powers(expr)
    while big:
        sym = isinstance(expr, sp.Basic)
        F = sp.Float if sym else _se.RealDouble
        P = (lambda b, e: sp.Pow(b, e, evaluate=False)) if sym else _se.Pow
        A = sp.Abs if sym else _se.Abs
        rep = {}
        for a in big:
            b, n = a.args[0], int(a.args[1])
            # (the odd power as b |b|**(n - 1): b * b**float(n - 1) would merge back into
            # b**float(n), and the float exponent has lost the parity)
            rep[a] = P(b, F(float(n))) if n % 2 == 0 else b * P(A(b), F(float(n - 1)))
        expr = expr.xreplace(rep)
        big = _big_powers(expr)
    return expr


#: SymPy expression -> its atoms of :data:`_ATOM_TYPES` (:func:`function_atoms`)
_ATOMS: dict = {}
_ATOMS_MAX = 200_000
#: what the checks before a compile look for in a SymPy expression: powers, functions,
#: ``Max``/``Min``, ``I``, ``zoo``
_ATOM_TYPES = (sp.Pow, sp.Function, sp.Max, sp.Min, type(sp.I), type(sp.zoo))


def function_atoms(expr: sp.Basic) -> frozenset:
    """``expr.atoms(Pow, Function, Max, Min, I, zoo)`` of a SymPy expression, found once per
    expression in this process: :func:`real_expression` (at every equation's processing),
    :func:`~mechsys.compile._derive.symengine_safe` and the ``floor`` search of the
    derivation each asked SymPy for a traversal of every equation, again for ``free()``'s
    system of the same equations (about 0.1 s of a 1024-link chain, decision 0080).

    Example::

        function_atoms(sp.sin(x) + x**2)     # frozenset({sin(x), x**2})
    """
    got = _ATOMS.get(expr)
    if got is None:
        got = frozenset(expr.atoms(*_ATOM_TYPES))
        if len(_ATOMS) >= _ATOMS_MAX:
            _ATOMS.clear()
        _ATOMS[expr] = got
    return got


def _plainly_real(expr: sp.Basic) -> bool:
    """Whether the SymPy ``expr`` certainly holds nothing :func:`real_expression` acts on: one
    traversal for all it looks for (``I``, ``zoo``, number-valued functions and powers,
    powers with huge integer exponents) instead of four."""
    kinds = (sp.Pow, sp.Function, type(sp.I), type(sp.zoo))
    for a in function_atoms(expr):
        if not isinstance(a, kinds):
            continue
        if not isinstance(a, (sp.Pow, sp.Function)) or a.is_number:
            return False
        if isinstance(a, sp.Pow) and a.args[1].is_Integer and abs(int(a.args[1])) >= BIG_EXPONENT:
            return False
    return True


def real_expressions(exprs, atoms=None) -> list:
    """:func:`real_expression` of each of ``exprs``. SymEngine lists are first searched once
    as a whole for what it looks for (imaginary and complex numbers, complex infinity,
    powers): when none of it occurs, nothing can change and the per-expression searches are
    skipped (about 0.1 ms an expression in Python: a second of a 1024-link chain).
    ``atoms``: that search made already (:func:`_search`: it also serves the kernel's
    stages); the list itself is returned when nothing changes."""
    exprs = exprs if isinstance(exprs, list) else list(exprs)
    if atoms is None:
        atoms = _search(exprs)
    if atoms is not None and not _flagged(atoms):
        return exprs
    return [real_expression(e) for e in exprs]


def _flagged(atoms) -> bool:
    """Whether the atoms found by :func:`_search` hold anything :func:`real_expression` acts
    on: a complex number, complex infinity, or a power with an integer exponent of magnitude
    at least :data:`BIG_EXPONENT`."""
    from symengine.lib.symengine_wrapper import ComplexBase

    return any(isinstance(a, (ComplexBase, type(_se.zoo))) or (
        isinstance(a, _se.Pow) and a.args[1].is_Integer
        and abs(int(a.args[1])) >= BIG_EXPONENT) for a in atoms)


def _search(exprs):
    """The atoms of a list of SymEngine expressions that the compile boundary acts on, found
    in one traversal of the distinct nodes (0.19 s for the 50,000 outputs of a 1024-link
    chain's kernels, where SymEngine's ``atoms`` took 0.69 s): complex numbers and
    infinity, powers (:func:`real_expressions`), ``Piecewise`` (:func:`_split_piecewise`),
    ``sin`` and ``cos`` (:func:`_split_trig`). None unless every expression is a SymEngine
    one."""
    if _se is None or not exprs or not all(isinstance(e, _se.Basic) for e in exprs):
        return None
    from symengine.lib.symengine_wrapper import ComplexBase

    kinds = (ComplexBase, type(_se.zoo), _se.Pow, _se.Piecewise, _se.sin, _se.cos)
    # (leaves of these types hold nothing searched for: not visited, a third of the nodes)
    plain = {_se.Symbol, _se.Integer, _se.RealDouble, _se.Rational,
             *(type(_se.Integer(k)) for k in (0, 1, -1))}
    # each distinct node once: SymEngine's own ``atoms`` walks the expression *tree*,
    # visiting a shared subexpression once per occurrence, which for a Gen joint's nested
    # pose and its derivatives (a DAG with much sharing) cost 0.2 to 0.4 s of a 7-joint
    # arm's first inverse dynamics (decision 0065)
    found: set = set()
    seen: set = set()
    stack = [e for e in exprs if type(e) not in plain]
    while stack:
        e = stack.pop()
        if e in seen:
            continue
        seen.add(e)
        if isinstance(e, kinds):
            found.add(e)
        stack.extend([a for a in e.args if type(a) not in plain])
    return found


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
        #: the length of the argument vector (the sweep's and multiplier solves' loops call
        #: the kernel through a C entry point made of it: ``solvers._jit_runtime.table``)
        self.nargs = len(args)
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


def _split_piecewise(exprs, atoms=None):
    """``(pieces, reduced)``: the distinct outermost ``Piecewise`` of SymEngine ``exprs`` and
    ``exprs`` with each replaced by a new symbol (``{symbol: piecewise}``, insertion order).
    ``atoms``: the result of a search of ``exprs`` for ``Piecewise`` (and other types)
    already made, else one is made here.

    A spline profile's ``Piecewise`` (``geometry/_curves.py``) recurs tens of times in a
    Jacobian and ``gamma``; without CSE (``docs/decisions/0002``) LLVM would compile every
    copy: 60 s instead of 2 s for a 361-knot cam (``docs/decisions/0008-curves.md``)."""
    exprs = list(exprs)
    if atoms is None:
        # one search in C++ (the Python walk below costs ~40 ms a 10,000-output kernel)
        atoms = _se.DenseMatrix(len(exprs), 1, exprs).atoms(_se.Piecewise) if exprs else ()
    if not any(isinstance(a, _se.Piecewise) for a in atoms):
        return {}, exprs
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
    return {v: k for k, v in found.items()}, xreplace_all(exprs, found)


def xreplace_all(exprs: Sequence, mapping: dict) -> list:
    """``[e.xreplace(mapping) for e in exprs]`` for SymEngine ``exprs`` in one call.

    SymEngine converts the Python ``mapping`` to its C++ map on every ``xreplace``: with a
    few thousand entries that is ~2 ms an expression (40 s for the 18,428 outputs of a
    1024-link chain's free-motion kernel). The expressions are wrapped as the arguments of
    one undefined function, replaced in a single call (one conversion, shared
    subexpressions visited once) and unwrapped; a function's arguments are kept as given.

    Example::

        x, s = symengine.symbols("x s")
        xreplace_all([symengine.sin(x) * 2, x + 1], {symengine.sin(x): s})   # [2*s, 1 + x]
    """
    exprs = list(exprs)
    if not exprs or not mapping:
        return exprs
    return list(_se.Function("_mechsys_all")(*exprs).xreplace(mapping).args)


#: a kernel with more outputs than this and compiled without LLVM's optimiser (level 0)
#: computes the distinct ``sin``/``cos`` of its arguments in a first stage (see
#: :func:`_split_trig`); below it the optimiser merges the repeated calls itself
STAGE_TRIG = 500


def _split_trig(exprs, avoid=(), atoms=None):
    r"""``(values, reduced)``: the distinct ``sin(a)``, ``cos(a)`` of SymEngine ``exprs`` whose
    arguments hold none of the symbols ``avoid``, and ``exprs`` with each replaced by a new
    symbol (``{symbol: sin or cos}``). ``atoms``: a search of ``exprs`` for ``sin`` and
    ``cos`` (and other types) already made, else one is made here.

    Unoptimised LLVM code (large kernels: :data:`LARGE_KERNEL`) calls ``sin`` and ``cos``
    wherever they occur: in a chain's mass matrix, Jacobian and ``gamma`` each angle's
    ``sin`` and ``cos`` occur many times. Computed once in a first stage, the 1024-link
    free-motion kernel evaluates 8 times faster (364 -> 45 us) and compiles in 1.2 s instead
    of 1.9 s (decision 0066). The reduced expressions are the same terms with the value of
    :math:`\sin a` read from an argument instead of computed: equal to rounding (a product
    may be ordered differently)."""
    if atoms is None:
        atoms = _se.DenseMatrix(len(exprs), 1, list(exprs)).atoms(_se.sin, _se.cos)
    found = {a for a in atoms if isinstance(a, (_se.sin, _se.cos))}
    if avoid:
        avoid = set(avoid)
        found = {a for a in found if not (a.free_symbols & avoid)}
    if not found:
        return {}, list(exprs)
    # a fixed order (the cache key of both stages depends on it): by printed form
    ordered = sorted(found, key=str)
    names = {a: _se.Symbol(f"_mechsys_trig_{i}") for i, a in enumerate(ordered)}
    return {v: k for k, v in names.items()}, xreplace_all(exprs, names)


def _gather_stage(args, stage: dict, exprs, free=None) -> tuple[list, list, list]:
    r"""``(pre_args, pre_values, main_args)`` of a two-stage kernel whose second stage reads
    only the first stage's values: the first stage, on the arguments ``pre_args`` (a prefix
    of ``args``: those up to the last it uses), writes ``pre_values`` = the arguments the
    reduced ``exprs`` use, copied, then the ``stage`` values; the second stage takes
    ``main_args`` = those copies' symbols and the ``stage`` symbols, in that order.

    SymEngine's LLVM code loads every declared argument at its entry and finds an argument
    by a linear search of the list (per occurrence of a symbol): a kernel declaring the
    11,265 arguments of a 1024-link chain's dynamics but using 1,024 of them and its 2,048
    stage values compiles in 1.3-1.6 s, on the 3,072 it uses in 0.66 s (decision 0066).
    ``free``: the free symbols of ``exprs`` when found already (:func:`_shapes`)."""
    names = [_name(a) for a in args]
    if free is None:
        free = _se.DenseMatrix(len(exprs), 1, list(exprs)).free_symbols if exprs else ()
    used = {_name(a): a for a in free}
    # (by name: SymPy and SymEngine symbols of one name are one argument; the kept ones are
    # the SymEngine symbols found in the expressions, not converted again)
    copied = [used[nm] for nm in names if nm in used]
    values = [*copied, *stage.values()]
    if not values:
        return list(args), [], list(args)
    # what the first stage reads: the copied arguments and those of the stage values
    stage_values = list(stage.values())
    needs = set(used).union(_name(a) for a in _se.DenseMatrix(
        len(stage_values), 1, stage_values).free_symbols) if stage_values else set(used)
    last = max((i for i, nm in enumerate(names) if nm in needs), default=0)
    return list(args[:last + 1]), values, [*copied, *stage]


#: llvmlite's target of :func:`_offset_entry` (looked up once)
_TRAMPOLINE: dict = {}


#: the one machine-code routine every :class:`_GatherStage` calls (built once a process)
_GATHER: dict = {}


def _gather_routine() -> int:
    r"""Address of ``void gather(double *out, const double *x, int64 *table)``, built with
    llvmlite once per process (~10 ms): for ``i < table[0]``, with ``c = table[1 + i]``,

    .. math:: \mathrm{out}_i = x_{c \gg 2},\ \sin x_{c \gg 2}\ \text{or}\ \cos x_{c \gg 2}
              \quad (c \mathbin{\&} 3 = 0, 1, 2)

    or, for ``c & 3 = 3``, :math:`\mathrm{out}_i = \mathrm{out}_{c \gg 2}` (a value computed
    earlier in the table, copied: the inputs of a second stage compiled in parts,
    :func:`_part_table`). ``sin`` and ``cos`` are LLVM's intrinsics, lowered to calls of the C
    library's ``sin`` and ``cos``, as in SymEngine's LLVM kernels: the same values to the last
    bit."""
    if "address" in _GATHER:
        return _GATHER["address"]
    import llvmlite.binding as llvm
    from llvmlite import ir

    if "target" not in _TRAMPOLINE:
        llvm.initialize_native_target()
        llvm.initialize_native_asmprinter()
        _TRAMPOLINE["target"] = llvm.Target.from_default_triple()
    f64, i64 = ir.DoubleType(), ir.IntType(64)
    mod = ir.Module(name="mechsys_gather")
    fn = ir.Function(mod, ir.FunctionType(ir.VoidType(), [f64.as_pointer(), f64.as_pointer(),
                                                          ir.IntType(8).as_pointer()]),
                     name="gather")
    sin = mod.declare_intrinsic("llvm.sin", [f64])
    cos = mod.declare_intrinsic("llvm.cos", [f64])
    entry, loop, bx, bsin, bcos, bcopy, store, done = (fn.append_basic_block(n) for n in (
        "entry", "loop", "x", "sin", "cos", "copy", "store", "done"))
    out, x, ctx = fn.args
    b = ir.IRBuilder(entry)
    table = b.bitcast(ctx, i64.as_pointer())
    n = b.load(table)
    b.cbranch(b.icmp_signed(">", n, ir.Constant(i64, 0)), loop, done)
    b = ir.IRBuilder(loop)
    i = b.phi(i64)
    i.add_incoming(ir.Constant(i64, 0), entry)
    code = b.load(b.gep(table, [b.add(i, ir.Constant(i64, 1))]))
    j = b.ashr(code, ir.Constant(i64, 2))
    # (each branch reads its own source: for a copy, j indexes out, not x)
    switch = b.switch(b.and_(code, ir.Constant(i64, 3)), bx)
    switch.add_case(ir.Constant(i64, 1), bsin)
    switch.add_case(ir.Constant(i64, 2), bcos)
    switch.add_case(ir.Constant(i64, 3), bcopy)
    b = ir.IRBuilder(bx)
    v = b.load(b.gep(x, [j]))
    b.branch(store)
    b = ir.IRBuilder(bsin)
    vs = b.call(sin, [b.load(b.gep(x, [j]))])
    b.branch(store)
    b = ir.IRBuilder(bcos)
    vc = b.call(cos, [b.load(b.gep(x, [j]))])
    b.branch(store)
    b = ir.IRBuilder(bcopy)
    vo = b.load(b.gep(out, [j]))
    b.branch(store)
    b = ir.IRBuilder(store)
    r = b.phi(f64)
    for val, block in ((v, bx), (vs, bsin), (vc, bcos), (vo, bcopy)):
        r.add_incoming(val, block)
    b.store(r, b.gep(out, [i]))
    nxt = b.add(i, ir.Constant(i64, 1))
    i.add_incoming(nxt, store)
    b.cbranch(b.icmp_signed("<", nxt, n), loop, done)
    ir.IRBuilder(done).ret_void()
    parsed = llvm.parse_assembly(str(mod))
    parsed.verify()
    engine = llvm.create_mcjit_compiler(parsed, _TRAMPOLINE["target"].create_target_machine())
    engine.finalize_object()
    _GATHER["engine"] = engine            # owns the code: kept for the process's life
    _GATHER["address"] = engine.get_function_address("gather")
    return _GATHER["address"]


def _gather_table(pre_args, values) -> np.ndarray | None:
    """The table of :func:`_gather_routine` for a first stage on ``pre_args`` whose
    ``values`` are each an argument, or ``sin`` or ``cos`` of one; None for anything else
    (a ``Piecewise``, ``sin`` of a sum, arguments of one name twice): SymEngine compiles
    that first stage."""
    index: dict = {}
    for k, a in enumerate(pre_args):
        index.setdefault(_name(a), k)
    if len(index) != len(pre_args):
        return None
    codes = np.empty(len(values) + 1, dtype=np.int64)
    codes[0] = len(values)
    sym, sin, cos = _se.Symbol, _se.sin, _se.cos
    for k, v in enumerate(values):
        t = type(v)
        if t is sym:
            op, a = 0, v
        elif t is sin or t is cos:
            a = v.args[0]
            if type(a) is not sym:
                return None
            op = 1 if t is sin else 2
        else:
            return None
        j = index.get(a.name)
        if j is None:
            return None
        codes[k + 1] = 4 * j + op
    return codes


class _GatherStage:
    r"""A first stage (decision 0066) that only copies arguments and takes ``sin``/``cos``
    of arguments, as the first stage of a chain's kernels does: one shared loop of machine
    code (:func:`_gather_routine`) reading a table, instead of SymEngine's LLVM compile of
    the same straight-line code (0.1 to 0.25 s per kernel of the 1024-link chain: SymEngine
    finds each argument by a linear search, and emits every call of ``sin`` at its place;
    decision 0079). The values are the same to the last bit (the same C library ``sin``
    and ``cos``). It offers what :class:`_SymengineCompiled` asks of a SymEngine stage:
    ``unsafe_real``, a call on one or many argument rows, ``as_ctypes`` and pickling.

    Example::

        g = _GatherStage(3, _gather_table([t, x, th], [se.sin(th), x]))
        g(np.array([0.0, 2.0, 0.5]))          # [sin(0.5), 2.0]
    """

    def __init__(self, nin: int, table: np.ndarray):
        self.nin, self.nout = nin, int(table[0])
        self._table = np.ascontiguousarray(table, dtype=np.int64)
        self._bind()

    def _bind(self) -> None:
        import ctypes

        proto = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
        self._fn = proto(_gather_routine())
        self._ctx = ctypes.c_void_p(self._table.ctypes.data)

    def unsafe_real(self, x: np.ndarray, out: np.ndarray) -> None:
        """``out[:] = values(x)``; ``x`` and ``out`` contiguous float64 (not checked)."""
        self._fn(out.ctypes.data, x.ctypes.data, self._ctx)

    def __call__(self, x) -> np.ndarray:
        x = np.ascontiguousarray(x, dtype=float)
        if x.ndim == 1:
            out = np.empty(self.nout)
            self.unsafe_real(x, out)
            return out
        out = np.empty((x.shape[0], self.nout))
        for row, o in zip(x, out):
            self.unsafe_real(np.ascontiguousarray(row), o)
        return out

    def as_ctypes(self):
        """``(function, context)`` as SymEngine's ``Lambdify.as_ctypes`` gives them."""
        return self._fn, self._ctx

    def __getstate__(self):
        return {"nin": self.nin, "nout": self.nout, "_table": self._table}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._bind()


#: a gathered second stage (:func:`_gather_stage`) with more outputs than this is compiled
#: in parts of this many outputs, each declaring only the arguments it reads (decision 0080)
PART_OUTPUTS = 1024


def _spans(n: int, sections, size: int) -> list:
    """``[(start, stop)]``: ``n`` outputs cut in parts of at most ``size``, a part never
    straddling two of ``sections`` (the lengths of consecutive blocks of the outputs, such
    as a position kernel's ``Phi`` and ``Phi_q``; None: one block). A block compiled in the
    same parts in two kernels (the Jacobian of the position, velocity and free-motion
    kernels) is then the same compile unit in each: compiled once, loaded from the kernel
    cache by the others."""
    spans, start = [], 0
    for length in (sections if sections and sum(sections) == n else (n,)):
        stop = start + length
        spans += [(a, min(a + size, stop)) for a in range(start, stop, size)]
        start = stop
    return spans


#: outputs of one shape (:func:`_shapes`) that occur at least this many times in a gathered
#: second stage are computed by functions compiled once per shape (decision 0086); the others
#: in parts of at most :data:`PART_OUTPUTS`. (A function costs ~1.5 ms to compile besides
#: ~20 µs an output: one for 64 outputs pays when it serves three batches or more.)
SHAPE_MIN = 192
#: how many outputs of one shape a shape function computes, largest first (each class of
#: outputs is cut into batches of these sizes; what is left joins the parts)
SHAPE_BATCHES = (64,)


def _shapes(exprs) -> list:
    """``[(shape, symbols)]`` of each of the SymEngine ``exprs``: ``shape`` an exact record of
    the expression's graph with each symbol written as its number of first occurrence
    (``s0``, ``s1``, ... in the walk's order), ``symbols`` those symbols in that order.

    Two outputs of one shape are the same expression up to the names of their symbols, with
    the terms of every sum and the factors of every product in the same order, each symbol
    in the same place: SymEngine's code generator (which reads an argument by its position,
    never by its name) emits the same instructions for both. Each distinct node of an
    output is written once, numbered, as its type and exact data (the hexadecimal form of a
    double) or its children's numbers in their order, as :func:`_fingerprint` writes it.

    Example::

        x, y, u, v = symengine.symbols("x y u v")
        _shapes([2.5 * x + y, 2.5 * u + v])   # the same shape: s0, s1 = x, y and u, v
    """
    fsym, leaf = _se.FunctionSymbol, _shape_leaf
    out = []
    for root in exprs:
        args = root.args
        if not args:                  # (most outputs of a large kernel: a number, a symbol)
            syms = []
            out.append((leaf(root, syms), syms))
            continue
        if not isinstance(root, fsym) and not any([a.args for a in args]):
            # a node of leaves (a coefficient times a symbol): the records the walk below
            # writes, without its bookkeeping
            syms, lines, ids = [], [], {}
            for a in reversed(args):          # (the walk's order: the last child first)
                if a not in ids:
                    ids[a] = len(lines)
                    lines.append(leaf(a, syms))
            lines.append(type(root).__name__ + "(" + ",".join([str(ids[a]) for a in args])
                         + ")")
            out.append(("|".join(lines), syms))
            continue
        out.append(_shape_walk(root))
    return out


def _shape_walk(root) -> tuple:
    """``(shape, symbols)`` of one SymEngine expression (:func:`_shapes`): each distinct node
    once, in post-order (the last child first), without recursion (deep expressions)."""
    syms: list = []
    lines: list = []
    _records(root, {}, lines, lambda e: _shape_leaf(e, syms))
    return "|".join(lines), syms


def _shape_leaf(e, syms) -> str:
    """The record of leaf ``e`` in a shape (:func:`_shapes`): a symbol as its number of first
    occurrence (appended to ``syms``), anything else as :func:`_leaf_record`."""
    if isinstance(e, _se.Symbol):
        syms.append(e)
        return "s" + str(len(syms) - 1)
    return _leaf_record(e)


def _leaf_record(e) -> str:
    """The exact record of a leaf: a double's hexadecimal form, else its type and printed
    form (a symbol's name, an integer, a rational)."""
    t = type(e)
    return "f:" + float(e).hex() if t is _se.RealDouble else t.__name__ + ":" + str(e)


def _records(root, ids: dict, lines: list, leaf) -> None:
    """Append to ``lines`` the records of ``root``'s distinct nodes not yet in ``ids``
    (node -> its number, updated), in post-order (the last child first), without recursion
    (deep expressions): a leaf as ``leaf(e)``, any other node as its type (a function
    symbol's with its name) and its children's numbers in their order. The one walk behind
    :func:`_fingerprint` (its leaves :func:`_leaf_record`) and :func:`_shapes` (its symbols
    numbered)."""
    fsym = _se.FunctionSymbol
    stack = [(root, None)]
    while stack:
        e, args = stack.pop()
        if args is None:
            if e in ids:
                continue
            args = e.args
            if not args:
                ids[e] = len(lines)
                lines.append(leaf(e))
                continue
            stack.append((e, args))
            stack.extend([(a, None) for a in args if a not in ids])
            continue
        if e in ids:
            continue
        name = type(e).__name__
        if isinstance(e, fsym):
            name += ":" + e.get_name()
        ids[e] = len(lines)
        lines.append(name + "(" + ",".join([str(ids[a]) for a in args]) + ")")


def _disjoint(members, shapes, size: int) -> list | None:
    """``size`` of ``members`` (output numbers) no two of which share a symbol, the first
    found in order, or None: the outputs a shape function is compiled from, each on its own
    arguments (:func:`_shape_plan`)."""
    chosen, taken = [], set()
    for i in members:
        syms = shapes[i][1]
        if taken.isdisjoint(syms):
            chosen.append(i)
            taken.update(syms)
            if len(chosen) == size:
                return chosen
    return None


def _shape_plan(main_args, shapes, sections, size: int):
    """``(units, models, direct)`` of a gathered second stage (:func:`_gather_stage`) on
    ``main_args`` whose outputs have ``shapes`` (:func:`_shapes`), or None when an output
    reads a symbol outside ``main_args`` (the stage is then compiled whole, which reports it).

    ``units``: ``[(members, used, spec)]``, each computing the outputs ``members`` into
    consecutive places of a scratch area, from the values ``main_args[m]`` for ``m`` in
    ``used`` (written by the first stage in that order, :func:`_part_table`):

    * ``spec = (shape, n)``: ``n`` outputs of one shape, each on its own symbols in the
      order of its shape (``used`` repeats a value two of them read), computed by the one
      function of that shape and size (compiled from the outputs ``models[spec]``, ``n`` of
      that shape sharing no symbol: :func:`_compile_parts`). A shape that occurs at least
      :data:`SHAPE_MIN` times is cut in batches of :data:`SHAPE_BATCHES` outputs (the rest
      joins the other outputs);
    * ``spec = None``: up to ``size`` other outputs, in order, never from two of
      ``sections`` (as :func:`_spans`), compiled as they are on the symbols they read in
      their order of first occurrence.

    ``direct``: the units' outputs are the stage's outputs in order (no scatter needed).

    A chain of 1024 links has 10,236 position-kernel outputs of 7 shapes and 18,428
    free-motion outputs of 16: about thirty functions for the whole build instead of 57
    parts of up to 1024 outputs (decision 0086)."""
    pos = {a: i for i, a in enumerate(main_args)}
    for _, syms in shapes:
        for s in syms:
            if s not in pos:
                return None
    n = len(shapes)
    classes: dict = {}
    for i, (shape, _) in enumerate(shapes):
        classes.setdefault(shape, []).append(i)
    units, models = [], {}
    batched = set()
    for shape, members in classes.items():
        if len(members) < SHAPE_MIN:
            continue
        rest = members
        for k in SHAPE_BATCHES:
            if len(rest) < k:
                continue
            model = models.get((shape, k)) or _disjoint(members, shapes, k)
            if model is None:
                continue
            models[(shape, k)] = model
            whole = len(rest) - len(rest) % k
            for a in range(0, whole, k):
                batch = rest[a:a + k]
                used = [pos[s] for i in batch for s in shapes[i][1]] or [0]
                units.append((batch, used, (shape, k)))
            batched.update(rest[:whole])
            rest = rest[whole:]
    others = [i for i in range(n) if i not in batched] if batched else list(range(n))
    for start, stop in _spans(n, sections, n):
        block = [i for i in others if start <= i < stop] if batched else others[start:stop]
        for a in range(0, len(block), size):
            members = block[a:a + size]
            seen: dict = {}
            for i in members:
                for s in shapes[i][1]:
                    seen.setdefault(pos[s], None)
            units.append((members, list(seen) or [0], None))
    order = [i for members, _, _ in units for i in members]
    direct = order == list(range(n))
    return units, models, direct


def _part_table(table: np.ndarray, plan: list) -> np.ndarray:
    """The gather table (:func:`_gather_routine`) that writes, part after part, the inputs of
    each unit of ``plan`` (:func:`_shape_plan`'s units), from ``table``, the one writing each of the
    second stage's arguments once: a value's first occurrence is computed as there, a
    repeated one copied from it (code ``4 p + 3``): each ``sin`` and ``cos`` still once."""
    base = table[1:].tolist()
    codes: list = []
    first: dict = {}
    for _, used, _ in plan:
        for m in used:
            p = first.get(m)
            if p is None:
                first[m] = len(codes)
                codes.append(base[m])
            else:
                codes.append(4 * p + 3)
    return np.array([len(codes), *codes], dtype=np.int64)


#: the shape functions compiled in this process (:func:`_compile_parts`), by optimisation
#: level, size and shape: every batch of that shape in every kernel calls the one function
_SHAPE_FUNCS: dict = {}
_SHAPE_FUNCS_MAX = 4096


def _compile_parts(main_args, exprs, plan, opt_level, mode):
    """``(parts, backend)``: the units of ``plan`` (:func:`_shape_plan`) compiled
    (:class:`_Parts`). A shape function is compiled once a process from its model outputs,
    on their symbols in the order of their shapes, and kept in the kernel cache under its
    shape, size and optimisation level (names play no part: SymEngine's code reads
    arguments by position); the other units as parts, each on the symbols it reads."""
    units, models, direct = plan
    parts, off, o, backend = [], 0, 0, "symengine-llvm"
    for members, used, spec in units:
        if spec is None:
            f, b = _lambdify([main_args[m] for m in used], [exprs[i] for i in members],
                             opt_level, False, mode)
        else:
            shape, k = spec
            memo = (opt_level, k, shape)
            f = _SHAPE_FUNCS.get(memo)
            b = "symengine-llvm"
            if f is None:
                model = models[spec]
                args = [s for i in model for s in _shape_symbols(exprs[i])] or [main_args[0]]
                key = None
                if _cache.cache_dir() is not None:
                    key = _cache.entry_key(("shape", str(opt_level), _host(), str(k), shape))
                f, b = _lambdify(args, [exprs[i] for i in model], opt_level, False, mode,
                                 key=key)
                if b == "symengine-llvm":
                    if len(_SHAPE_FUNCS) >= _SHAPE_FUNCS_MAX:
                        _SHAPE_FUNCS.clear()
                    _SHAPE_FUNCS[memo] = f
        if b != "symengine-llvm":
            backend = b
        parts.append((f, off, len(used), o, len(members)))
        off += len(used)
        o += len(members)
    scatter = None
    if not direct:
        scatter = np.empty(len(exprs), dtype=np.int64)
        at = 0
        for members, _, _ in units:
            scatter[members] = np.arange(at, at + len(members))
            at += len(members)
    return _Parts(parts, len(exprs), scatter), backend


def _shape_symbols(e) -> list:
    """The symbols of ``e`` in the order of its shape (:func:`_shapes`)."""
    return _shapes([e])[0][1]


#: the one machine-code routine every :class:`_Parts` calls (built once a process)
_PARTS: dict = {}


def _parts_routine() -> int:
    r"""Address of ``void parts(double *out, const double *v, int64 *t)``, built with llvmlite
    once per process (~10 ms). With :math:`n = t_0` units, :math:`n_s = t_1` values and
    :math:`n_o = t_2` outputs to scatter, the destination :math:`d = v + n_s` (a scratch area
    after the values) when :math:`n_o > 0`, else ``out``:

    .. math:: f_u(d + o_u,\ v + i_u,\ c_u) \quad (u < n;\ f_u, c_u, i_u, o_u = t_{3 + 4u \ldots 6 + 4u}),
              \qquad \mathrm{out}_j = d_{t_{3 + 4n + j}} \quad (j < n_o)

    Each unit is a SymEngine function (a shape function called for one batch, or a part)."""
    if "address" in _PARTS:
        return _PARTS["address"]
    import llvmlite.binding as llvm
    from llvmlite import ir

    if "target" not in _TRAMPOLINE:
        llvm.initialize_native_target()
        llvm.initialize_native_asmprinter()
        _TRAMPOLINE["target"] = llvm.Target.from_default_triple()
    f64, i64, i8p = ir.DoubleType(), ir.IntType(64), ir.IntType(8).as_pointer()
    f64p = f64.as_pointer()
    fty = ir.FunctionType(ir.VoidType(), [f64p, f64p, i8p])
    mod = ir.Module(name="mechsys_parts")
    fn = ir.Function(mod, fty, name="parts")
    entry, uloop, ucheck, sloop, done = (fn.append_basic_block(n) for n in (
        "entry", "units", "scatter_check", "scatter", "done"))
    out, v, ctx = fn.args
    b = ir.IRBuilder(entry)
    t = b.bitcast(ctx, i64.as_pointer())
    n = b.load(t)
    ns = b.load(b.gep(t, [ir.Constant(i64, 1)]))
    no = b.load(b.gep(t, [ir.Constant(i64, 2)]))
    scratch = b.gep(v, [ns])
    dst = b.select(b.icmp_signed(">", no, ir.Constant(i64, 0)), scratch, out)
    b.cbranch(b.icmp_signed(">", n, ir.Constant(i64, 0)), uloop, ucheck)
    b = ir.IRBuilder(uloop)
    u = b.phi(i64)
    u.add_incoming(ir.Constant(i64, 0), entry)
    base = b.add(b.mul(u, ir.Constant(i64, 4)), ir.Constant(i64, 3))
    f = b.inttoptr(b.load(b.gep(t, [base])), fty.as_pointer())
    c = b.inttoptr(b.load(b.gep(t, [b.add(base, ir.Constant(i64, 1))])), i8p)
    i = b.load(b.gep(t, [b.add(base, ir.Constant(i64, 2))]))
    o = b.load(b.gep(t, [b.add(base, ir.Constant(i64, 3))]))
    b.call(f, [b.gep(dst, [o]), b.gep(v, [i]), c])
    un = b.add(u, ir.Constant(i64, 1))
    u.add_incoming(un, uloop)
    b.cbranch(b.icmp_signed("<", un, n), uloop, ucheck)
    b = ir.IRBuilder(ucheck)
    b.cbranch(b.icmp_signed(">", no, ir.Constant(i64, 0)), sloop, done)
    b = ir.IRBuilder(sloop)
    j = b.phi(i64)
    j.add_incoming(ir.Constant(i64, 0), ucheck)
    first = b.add(b.mul(n, ir.Constant(i64, 4)), ir.Constant(i64, 3))
    src = b.load(b.gep(t, [b.add(first, j)]))
    b.store(b.load(b.gep(scratch, [src])), b.gep(out, [j]))
    jn = b.add(j, ir.Constant(i64, 1))
    j.add_incoming(jn, sloop)
    b.cbranch(b.icmp_signed("<", jn, no), sloop, done)
    ir.IRBuilder(done).ret_void()
    parsed = llvm.parse_assembly(str(mod))
    parsed.verify()
    engine = llvm.create_mcjit_compiler(parsed, _TRAMPOLINE["target"].create_target_machine())
    engine.finalize_object()
    _PARTS["engine"] = engine            # owns the code: kept for the process's life
    _PARTS["address"] = engine.get_function_address("parts")
    return _PARTS["address"]


class _Parts:
    r"""A gathered second stage computed by units (:func:`_shape_plan`): unit ``k`` reads its
    ``n_k`` inputs at offset ``i_k`` of the values the first stage writes
    (:func:`_part_table`) and writes its ``m_k`` outputs at offset ``o_k`` of a scratch area
    (after those values), from which ``scatter`` puts each output in its place (None: the
    units write the outputs in order, directly). It offers what :class:`_SymengineCompiled`
    asks of a SymEngine ``Lambdify``: ``unsafe_real``, a call on one or many rows,
    ``as_ctypes`` (the shared routine :func:`_parts_routine` with a table of the units as
    context) and pickling. Every output is computed by the code SymEngine generates for
    its expression: the same values to the last bit. ``nscratch``: the scratch values the
    C entry point needs after the ``nin`` values.

    Example::

        shapes = _shapes(exprs)
        plan = _shape_plan(args, shapes, None, 1024)
        parts = _compile_parts(args, exprs, plan, 0, "llvm")[0]
        v = np.concatenate([x[used] for _, used, _ in plan[0]])  # what the first stage writes
        parts(v)                                  # == Lambdify(args, exprs)(x), bit for bit
    """

    def __init__(self, parts: list, nout: int, scatter: np.ndarray | None = None):
        self.parts, self.nout, self.scatter = parts, nout, scatter
        self.nin = sum(p[2] for p in parts)
        self.nscratch = 0 if scatter is None else nout

    def _bind(self):
        """The C entry point and its table (addresses of the units' functions: made in this
        process, never pickled); kept with the functions' owners."""
        import ctypes

        owners, rows = [], []
        for f, i, _n, o, _k in self.parts:
            cfun, ctx = f.as_ctypes()
            owners.append((cfun, ctx))
            rows += [ctypes.cast(cfun, ctypes.c_void_p).value, ctx.value or 0, i, o]
        scatter = [] if self.scatter is None else self.scatter.tolist()
        table = np.array([len(self.parts), self.nin, len(scatter), *rows, *scatter],
                         dtype=np.int64)
        proto = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
        self._entry = (owners, table, proto(_parts_routine()),
                       ctypes.c_void_p(table.ctypes.data))
        return self._entry

    def unsafe_real(self, v: np.ndarray, out: np.ndarray) -> None:
        """``out[:] = values(v)``; ``v`` contiguous float64 with ``nscratch`` more places
        after its ``nin`` values, ``out`` contiguous (not checked)."""
        entry = self.__dict__.get("_entry") or self._bind()
        entry[2](out.ctypes.data, v.ctypes.data, entry[3])

    def __call__(self, V) -> np.ndarray:
        V = np.ascontiguousarray(V, dtype=float)
        if V.ndim == 1:
            out = np.empty(self.nout)
            for f, i, n, o, k in self.parts:
                out[o:o + k] = np.asarray(f(V[i:i + n])).reshape(k)
            return out if self.scatter is None else out[self.scatter]
        rows = V.shape[0]
        out = np.empty((rows, self.nout))
        for f, i, n, o, k in self.parts:
            out[:, o:o + k] = np.asarray(f(np.ascontiguousarray(V[:, i:i + n]))).reshape(rows, k)
        return out if self.scatter is None else out[:, self.scatter]

    def as_ctypes(self):
        """``(function, context)`` as SymEngine's ``Lambdify.as_ctypes`` gives them."""
        entry = self.__dict__.get("_entry") or self._bind()
        return entry[2], entry[3]

    def __getstate__(self):
        return {"parts": self.parts, "nout": self.nout, "nin": self.nin,
                "scatter": self.scatter, "nscratch": self.nscratch}

    def __setstate__(self, state):
        self.__dict__.update(state)

def _offset_entry(keep, main, offset: int):
    """``(owners, (address, context))`` of a C function ``g(out, x, ctx) = f(out, x + offset,
    ctx)`` for the entry point ``main = (address of f, ctx)``: the compiled loops call every
    kernel's second stage with ``x`` (``solvers/_jit_calls._eval``); a gathered second stage
    (:func:`_gather_stage`) reads its values after the ``offset`` arguments. Three
    instructions compiled by llvmlite (Numba's code generator, ~4 ms)."""
    import llvmlite.binding as llvm
    from llvmlite import ir

    if "target" not in _TRAMPOLINE:
        llvm.initialize_native_target()
        llvm.initialize_native_asmprinter()
        _TRAMPOLINE["target"] = llvm.Target.from_default_triple()
    mod = ir.Module(name="mechsys_offset_entry")
    dp, vp = ir.DoubleType().as_pointer(), ir.IntType(8).as_pointer()
    fty = ir.FunctionType(ir.VoidType(), [dp, dp, vp])
    fn = ir.Function(mod, fty, name="entry")
    b = ir.IRBuilder(fn.append_basic_block())
    out, x, ctx = fn.args
    target = b.inttoptr(ir.Constant(ir.IntType(64), main[0]), fty.as_pointer())
    b.call(target, [out, b.gep(x, [ir.Constant(ir.IntType(64), offset)]), ctx])
    b.ret_void()
    parsed = llvm.parse_assembly(str(mod))
    parsed.verify()
    # (an execution engine owns its target machine: one each, never shared)
    engine = llvm.create_mcjit_compiler(parsed, _TRAMPOLINE["target"].create_target_machine())
    engine.finalize_object()
    return (keep, engine), (engine.get_function_address("entry"), main[1])


class _NotCached(Exception):
    """A kernel asked for from the on-disk cache only (``mode="cached"``) is not there."""


def _lambdify(args, exprs, opt_level, cse=False, mode="llvm", key=False):
    """``(SymEngine Lambdify, backend name)``. ``mode``: ``"llvm"`` loads the LLVM kernel
    from the on-disk cache or compiles (and stores) it; ``"cached"`` only loads it, raising
    :class:`_NotCached` when it is not there; ``"lambda"`` builds SymEngine's interpreted
    kernel (no LLVM: cheap to build, for a few evaluations, see :class:`_FirstUse`).
    ``key``: the kernel's cache key when the caller made it (a shape function's,
    :func:`_compile_parts`; None: not cached), else :func:`_cache_key`."""
    if mode == "lambda":
        # (named: SymEngine's default backend is LLVM when it was built with it)
        return (_se.Lambdify(list(args), list(exprs), backend="lambda", cse=cse),
                "symengine-lambda")
    if key is False:
        key = _cache_key(args, exprs, opt_level, cse)
    if key is not None:
        f = _cache.load(key)
        if f is not None:
            return f, "symengine-llvm"
    if mode == "cached":
        raise _NotCached
    try:
        f = _se.Lambdify(list(args), list(exprs), backend="llvm", cse=cse, opt_level=opt_level)
    except (ValueError, TypeError, RuntimeError):  # built without LLVM, or unsupported
        return _se.Lambdify(list(args), list(exprs), cse=cse), "symengine-lambda"
    if key is not None:
        _cache.store(key, f)
    return f, "symengine-llvm"


# -- on-disk cache of compiled kernels (compile/_cache.py: private, authenticated, no pickle) --
cache_dir = _cache.cache_dir


def _host() -> str:
    import platform

    cpu = platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith(("model name", "flags")):
                cpu += "|" + line
    except OSError:
        pass
    return cpu


def _cache_key(args, exprs, opt_level, cse=False) -> str | None:
    """The cache key of a kernel: its exact equations (:func:`_fingerprint`), argument names,
    optimisation options and this machine's CPU (LLVM compiles for the host CPU); the cache
    adds the library versions (:func:`mechsys.compile._cache.entry_key`). None when caching
    is off."""
    if _cache.cache_dir() is None:
        return None
    return _cache.entry_key((str(opt_level), f"cse={bool(cse)}", _host(),
                             repr([_name(a) for a in args]), _fingerprint(exprs)))


def _name(symbol) -> str:
    """``str(symbol)``: a plain symbol's name without SymPy's printer (~0.1 ms a symbol);
    anything else (a ``Dummy`` prints as ``_name``, a function as ``f(t)``) printed."""
    if type(symbol) is sp.Symbol or (_se is not None and type(symbol) is _se.Symbol):
        return symbol.name
    return str(symbol)


#: fingerprints of the expression lists compiled in this process (:func:`_fingerprint`):
#: a part two kernels share (decision 0080) is hashed once; bounded, as the derivatives
_FINGERPRINTS: dict = {}
_FINGERPRINTS_MAX = 512


def _fingerprint(exprs) -> str:
    """An exact hash of SymEngine expressions. Their printed form is not enough: it rounds
    floating-point numbers to 15 digits, so two models differing in the 16th digit of a
    length would share a kernel (and it orders the terms of a sum canonically, where the
    compiled code adds them in the order of the expression). Each distinct node is written
    once, numbered, as its type and its exact data (the hexadecimal form of a double, a
    symbol's name) or its children's numbers in their order; the hash is that of the whole
    record (a serialisation of the expressions' graph: about twice as fast as hashing each
    node, decision 0080). A list hashed before in this process is looked up."""
    import hashlib

    exprs = tuple(exprs)
    got = _FINGERPRINTS.get(exprs)
    if got is not None:
        return got
    ids: dict = {}          # node -> its number
    lines: list = []        # node k's record
    for root in exprs:
        _records(root, ids, lines, _leaf_record)
    lines.append("=" + ",".join([str(ids[e]) for e in exprs]))
    got = hashlib.sha256("\n".join(lines).encode()).hexdigest()
    if len(_FINGERPRINTS) >= _FINGERPRINTS_MAX:
        _FINGERPRINTS.clear()
    _FINGERPRINTS[exprs] = got
    return got


def _entry_point(f):
    """``(owners, (address, context))`` of a SymEngine LLVM ``Lambdify``'s C function (the
    owners keep the ctypes objects, and so the addresses, alive)."""
    import ctypes

    fn, ctx = f.as_ctypes()
    return (fn, ctx), (ctypes.cast(fn, ctypes.c_void_p).value, ctx.value or 0)


class _SymengineCompiled(Compiled):
    """SymEngine ``Lambdify``; expressions with ``Piecewise`` in two stages: the distinct
    ``Piecewise`` first (``_pre``), then the rest with their values as extra arguments. A
    large unoptimised kernel computes the distinct ``sin``/``cos`` of its arguments in that
    first stage too (:func:`_split_trig`)."""

    backend = "symengine"

    def __init__(self, args, exprs, opt_level: int = 3, cse: bool = False, atoms=None,
                 mode: str = "llvm", sections=None):
        self.nout = len(exprs)
        exprs = [_se.sympify(e) for e in exprs]
        if cse:
            # SymEngine's CSE names its temporaries x0, x1, ..., avoiding only the symbols that
            # occur in the expressions: an argument of such a name that does not occur (a
            # coordinate x4 absent from a mass matrix) was then read as the temporary (wrong
            # values). Such arguments get names no temporary can take.
            import re

            ren = {_se.sympify(a): _se.Symbol(f"_mechsys_arg{i}") for i, a in enumerate(args)
                   if re.fullmatch(r"x\d+", str(a))}
            if ren:
                exprs = list(_se.DenseMatrix(len(exprs), 1, exprs).xreplace(ren))
                args = [ren.get(_se.sympify(a), a) for a in args]
        nin = len(args)
        staged = not cse and opt_level == 0 and len(exprs) > STAGE_TRIG
        # one search of the expressions for what the stages take out (each costs ~0.1 s on
        # the 18,000 outputs of a 1024-link chain's free-motion kernel)
        if atoms is None or cse:        # (CSE renames arguments: search the renamed)
            atoms = _search(exprs) or set()
        pieces, exprs = _split_piecewise(exprs, atoms)
        pre_args, pre_values, main_args = args, list(pieces.values()), [*args, *pieces]
        self._gather = False
        if staged:
            # a large unoptimised kernel (decision 0066): the distinct sin/cos once, in the
            # first stage beside the Piecewise values (with CSE they are computed once
            # already), and the second stage reads only what it uses, gathered by the first
            # (the trig functions searched again only in what the Piecewise split left)
            trig, exprs = _split_trig(exprs, avoid=pieces, atoms=None if pieces else atoms)
            # a large second stage in parts (decision 0080): their symbols found once, for
            # the parts and the gathering both
            # its outputs' shapes (decision 0086): their symbols found once, for the units
            # and the gathering both
            if len(exprs) > PART_OUTPUTS and mode != "lambda":
                shapes = _shapes(exprs)
                free = {s for _, syms in shapes for s in syms}
            else:
                shapes = free = None
            pre_args, pre_values, main_args = _gather_stage(args, {**pieces, **trig}, exprs,
                                                            free)
            self._gather = bool(pre_values)
            if not self._gather:
                pre_args, pre_values, main_args = args, [], list(args)
        self._pre = None
        self._npieces = len(pre_values)
        plan = None
        if pre_values:
            # a first stage of copies and sin/cos of arguments (a chain's): the shared
            # gather loop, no compile (decision 0079); anything else: SymEngine's
            table = _gather_table(pre_args, pre_values) if staged and mode != "lambda" \
                else None
            if table is not None:
                # a large second stage in parts, each on the arguments it reads, gathered
                # part after part by the first stage (decision 0080)
                plan = _shape_plan(main_args, shapes, sections, PART_OUTPUTS) \
                    if shapes else None
                if plan is not None:
                    table = _part_table(table, plan[0])
                    # (the values the units read, then the scratch area of their outputs)
                    self._npieces = int(table[0]) + (0 if plan[2] else len(exprs))
                self._pre, self._pre_backend = _GatherStage(len(pre_args), table), "gather"
            else:
                self._pre, self._pre_backend = _lambdify(pre_args, pre_values, opt_level,
                                                         cse, mode)
            self._pre_nin = len(pre_args)   # the first stage reads x[:_pre_nin]
            self._nargs = nin
            self._buf = np.empty(nin + self._npieces)   # [x, first-stage values]
        args = main_args
        self._expand = None
        if cse:
            # SymEngine 0.15's CSE returns wrong values for repeated outputs (decision 0002):
            # compile each distinct output once and copy it to every place it occurs
            distinct = list(dict.fromkeys(exprs))
            if len(distinct) < len(exprs):
                where = {e: i for i, e in enumerate(distinct)}
                self._expand = np.array([where[e] for e in exprs], dtype=np.intp)
                # (every output, for the compiled loops that take no expansion map:
                # :meth:`c_function` compiles them without CSE when first asked)
                self._plain_src = (list(args), list(exprs), opt_level)
                exprs = distinct
        self._nf = len(exprs)
        if plan is not None:
            self._f, self.backend = _compile_parts(args, exprs, plan, opt_level, mode)
        else:
            self._f, self.backend = _lambdify(args, exprs, opt_level, cse, mode)
        self._nin = nin
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
            x = buf[self._nargs:] if self._gather else buf
        out = np.empty(self._nf)       # a new array per call: callers may keep the last one
        self._f.unsafe_real(x, out)
        return out if self._expand is None else out[self._expand]

    def __getstate__(self):
        """Without the C entry points (ctypes objects, which do not pickle): a free system
        that ran in a compiled loop still pickles (a sweep's payload); they are made again
        on first use."""
        state = dict(self.__dict__)
        state.pop("_cfun", None)
        state.pop("_pfun", None)
        return state

    def c_function(self):
        """C entry points ``void f(double *out, const double *x, void *context)`` of the
        kernel, for compiled loops (``solvers/_jit_runtime.py``): ``(address, context, pre_address,
        pre_context, pieces)``. With ``Piecewise`` (two stages, see the class) the first stage
        at ``pre_address`` writes the ``pieces`` values after the ``x`` arguments and the
        kernel reads ``[x, pieces]``; otherwise ``pre_address`` is 0. None when a stage is not
        LLVM code. Valid while this object lives.

        A CSE kernel with repeated outputs (``_expand``, see :meth:`c_entry`) computes each
        distinct value once, which a loop without the expansion map cannot read: for those
        loops (the kinematic sweep, the multiplier solves) its outputs are compiled once more
        without SymEngine's CSE (LLVM's optimiser still removes the repeated work), every
        output written, on the first call (and kept in the on-disk kernel cache)."""
        entry = self.c_entry()
        if entry is None or self._expand is None:
            return None if entry is None else entry[0]
        if not hasattr(self, "_pfun"):
            args, exprs, opt_level = self._plain_src
            f, backend = _lambdify(args, exprs, opt_level, False)
            if backend != "symengine-llvm":
                self._pfun = None
            else:
                keep, main = _entry_point(f)
                self._pfun = (f, keep, (*main, *entry[0][2:]))   # owners kept alive
        return None if self._pfun is None else self._pfun[2]

    def c_entry(self):
        """``(row, expand)``: the C entry points of :meth:`c_function` and, for a CSE kernel
        whose repeated outputs are computed once (``_expand``), the index array that maps
        each output to the distinct value the C function writes (``out[i] =
        distinct[expand[i]]``; None when the outputs are all distinct). None when a stage is
        not LLVM code. The compiled free-motion stepper (``solvers/_jit_free.py``) expands
        the values itself, so the CSE kernels of generalized coordinates serve it too."""
        if self.backend != "symengine-llvm" or (
                self._pre is not None and self._pre_backend not in ("symengine-llvm",
                                                                    "gather")):
            return None
        if not hasattr(self, "_cfun"):
            keep, main = _entry_point(self._f)
            if self._gather:
                # the second stage reads the first stage's values only: called at x + nin
                keep, main = _offset_entry(keep, main, self._nargs)
            keep_pre, pre = _entry_point(self._pre) if self._pre is not None else (None, (0, 0))
            self._cfun = (keep, keep_pre, (*main, *pre, self._npieces))  # owners kept alive
        return self._cfun[2], self._expand

    def _slow(self, x):
        if self._pre is not None:
            buf = self._buf
            buf[:self._nargs] = x
            values = self._pre(x[:self._pre_nin])
            buf[self._nargs:self._nargs + len(values)] = values
            x = buf[self._nargs:] if self._gather else buf
        out = self._f(x).reshape(self._nf)
        return out if self._expand is None else out[self._expand]

    def batch(self, X):
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if self._pre is not None:
            P = self._pre(X[:, :self._pre_nin]).reshape(X.shape[0], -1)
            X = P if self._gather else np.hstack([X, P])
        out = self._f(X).reshape(X.shape[0], self._nf)
        return out if self._expand is None else out[:, self._expand]


#: a first-use kernel (:class:`_FirstUse`) compiles its LLVM code after this many calls
FIRST_USE_CALLS = 1000
#: ... or for a ``batch`` of this many points
FIRST_USE_ROWS = 100


class _FirstUse(Compiled):
    """A SymEngine kernel whose LLVM code is compiled when the work pays for it.

    Until then it evaluates the same expressions with SymEngine's interpreted ``Lambdify``
    (``backend="lambda"``) after common-subexpression elimination (the repeated-output and
    argument-name workarounds of :class:`_SymengineCompiled` included): about 0.05 s to
    build the nine joint kernels and the main kernel of the Panda arm where LLVM takes about
    0.7 s; a call then costs 6 to 50 µs instead of 1.5 to 6 µs, so about 2000 calls would
    pay for LLVM's 0.07 s a kernel. The LLVM kernel (exactly the one :func:`compile_exprs`
    makes without ``first_use``) replaces it

    * at once, when the on-disk kernel cache holds it (loading costs milliseconds);
    * after :data:`FIRST_USE_CALLS` calls, or for a ``batch`` of :data:`FIRST_USE_ROWS`
      points or more;
    * when a compiled loop asks for its C entry points (:meth:`c_entry`,
      :meth:`c_function`), and before pickling (the interpreted kernel does not pickle).

    Both evaluate the same expressions; they may differ in the last bits (the order of the
    floating-point operations differs), never more (decision 0065).

    Example::

        f = compile_exprs(args, exprs, first_use=True)   # cheap to build
        f(x)                                             # interpreted, first calls
        f.c_entry()                                      # LLVM from here on
    """

    backend = "symengine"

    def __init__(self, args, exprs, opt_level: int, cse: bool):
        import threading

        self.nout = len(exprs)
        #: the length of the argument vector: where LLVM refuses the kernel, the compiled
        #: loops call it through a C entry point made of its Python call
        #: (``solvers._jit_runtime.python_entry``) rather than leave it to the Python code
        self.nargs = len(args)
        self._src = (list(args), list(exprs), opt_level, cse)
        self._calls = 0
        self._lock = threading.Lock()
        self._cheap = None
        try:
            self._full = _SymengineCompiled(args, exprs, opt_level=opt_level, cse=cse,
                                            mode="cached")
        except _NotCached:
            self._full = None
            self._cheap = _SymengineCompiled(args, exprs, opt_level=opt_level, cse=True,
                                             mode="lambda")

    def full(self) -> Compiled:
        """The LLVM kernel, compiled (or loaded from the cache) on the first request. A
        kernel LLVM refuses keeps the interpreted one (its C entry points are then None)."""
        f = self._full
        if f is None:
            with self._lock:
                f = self._full
                if f is None:
                    args, exprs, opt_level, cse = self._src
                    try:
                        f = _SymengineCompiled(args, exprs, opt_level=opt_level, cse=cse)
                    except (RuntimeError, TypeError, ValueError, NotImplementedError):
                        f = self._cheap
                    self._full = f
        return f

    def __call__(self, x):
        f = self._full
        if f is not None:
            return f(x)
        self._calls += 1
        if self._calls > FIRST_USE_CALLS:
            return self.full()(x)
        return self._cheap(x)

    def batch(self, X):
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if self._full is None and X.shape[0] < FIRST_USE_ROWS:
            return self._cheap.batch(X)
        return self.full().batch(X)

    def c_entry(self):
        """:meth:`_SymengineCompiled.c_entry` of the LLVM kernel (compiled now if not yet)."""
        return self.full().c_entry()

    def c_function(self):
        """:meth:`_SymengineCompiled.c_function` of the LLVM kernel (compiled now if not
        yet)."""
        return self.full().c_function()

    def __getstate__(self):
        self.full()
        state = dict(self.__dict__)
        state.pop("_lock")
        state["_cheap"] = None
        return state

    def __setstate__(self, state):
        import threading

        self.__dict__.update(state)
        self._lock = threading.Lock()


def available_backends() -> list[str]:
    return (["symengine"] if _se is not None else []) + ["sympy"]


def default_backend() -> str:
    """``MECHSYS_BACKEND`` if set, else SymEngine when installed, else SymPy."""
    env = os.environ.get("MECHSYS_BACKEND")
    if env:
        return choice(env, available_backends(), "the environment variable MECHSYS_BACKEND")
    if _se is None:
        slow_path_warning("symengine", _se_error)
    return available_backends()[0]


#: kernels with more outputs than this compile without LLVM optimisation: ~15 times faster
#: to compile, ~3 times slower to evaluate (a 256-link chain's free kernel: 4.5 s -> 0.2 s)
LARGE_KERNEL = 500


@gc_paused()
def compile_exprs(args: Sequence[sp.Symbol], exprs: Sequence[sp.Expr],
                  backend: str | None = None, once: bool = False, cse: bool = False,
                  first_use: bool = False, sections: Sequence[int] | None = None) -> Compiled:
    """Compile ``exprs`` as a function of the flat argument list ``args``.

    ``once``: the function is evaluated a few times only (``m.dof()``'s Jacobian): LLVM
    without optimisation compiles ~30 times faster (0.03 s instead of 1 s for a 600-coordinate
    chain's Jacobian) and evaluates ~1.5 times slower.

    ``cse``: common subexpressions first (SymEngine). Off by default (slow on the flat
    expressions of absolute coordinates); on for models with Gen joints, whose nested slave
    poses share most of their subexpressions (decision 0010: 10 times faster compiles).

    ``first_use``: SymEngine evaluates the expressions without LLVM until the work pays for
    compiling them (:class:`_FirstUse`; the LLVM kernel at once when the on-disk cache has
    it): the first result of a fresh process sooner, the same numbers to the last bits.

    ``sections``: the lengths of consecutive blocks of ``exprs`` (``[len(phi), len(jac)]``):
    a large kernel compiled in parts (decision 0080) never puts two blocks in one part, so a
    block two kernels share is compiled once (then loaded from the kernel cache)."""
    if not exprs:
        return _Empty()
    # every expression that becomes numeric code passes here: complex constants refused,
    # huge integer exponents made floats (the constraints and loads were checked with their
    # names already, this catches what was derived from them or built elsewhere)
    exprs = list(exprs)
    atoms = _search(exprs)
    checked = real_expressions(exprs, atoms)
    if checked is not exprs:      # rewritten: what was found no longer describes them
        exprs, atoms = checked, None
    backend = backend or default_backend()
    if backend == "symengine":
        if _se is None:
            raise ImportError("the symengine backend needs SymEngine, a core dependency of mechsys: "
                              "`pip install symengine`")
        from ._derive import symengine_safe

        sympy_exprs = [e for e in exprs if isinstance(e, sp.Basic)]
        if sympy_exprs and not symengine_safe(sympy_exprs):
            # SymEngine 0.15 crashes on some functions (Mod): keep them with SymPy
            return _SympyCompiled(args, [sp.sympify(e) for e in exprs])
        try:
            # the model's level (compile._options.Backend); automatic (None): 3, but LLVM's
            # optimiser costs superlinear time in a kernel's size (decision
            # 0017-fixed-pattern-sparse-solve.md), so large kernels compile unoptimised
            level = getattr(backend, "opt_level", None)
            if level is None:
                level = 0 if len(exprs) > LARGE_KERNEL else 3
            if first_use and not once:
                return _FirstUse(args, exprs, level, cse)
            return _SymengineCompiled(args, exprs, opt_level=0 if once else level, cse=cse,
                                      atoms=atoms, sections=sections)
        except (RuntimeError, TypeError, ValueError, NotImplementedError):
            # a function SymEngine cannot compile (e.g. Mod, Abs): SymPy can
            return _SympyCompiled(args, [sp.sympify(e) for e in exprs])
    if backend == "sympy":
        return _SympyCompiled(args, exprs)
    choice(backend, available_backends(), "backend")
    raise AssertionError("unreachable")  # pragma: no cover - choice raised
