r"""Time and naming of symbols. ``T`` is the time symbol used in drivers.

Time, coordinates, velocities and accelerations are *real* symbols, so that SymPy can
differentiate ``Abs``, ``sign`` or ``sqrt(x**2)`` of them (:math:`d\lvert x \rvert/dx =
\operatorname{sign}(x)`; for a
complex symbol the derivative stays unevaluated and cannot be compiled). SymEngine drops
assumptions when its expressions come back to SymPy: :func:`restore_assumptions` maps the
plain symbols of these names back to the real ones.
"""

from __future__ import annotations

import sympy as sp

#: The time symbol. Use it in any scalar argument to make a driver, e.g. ``2*pi*T``.
T = sp.Symbol("T", real=True)

# name -> real symbol, for every time/coordinate/velocity/acceleration symbol made here
_REAL: dict[str, sp.Symbol] = {"T": T}


def _real(name: str) -> sp.Symbol:
    s = _REAL.get(name)
    if s is None:
        s = _REAL[name] = sp.Symbol(name, real=True)
    return s


def coord_symbol(name: str) -> sp.Symbol:
    return _real(name)


def velocity_symbol(name: str) -> sp.Symbol:
    return _real(name + "_d")


def acceleration_symbol(name: str) -> sp.Symbol:
    return _real(name + "_dd")


#: Python float (its exact hexadecimal form) -> its SymPy number (:func:`number`); bounded
_NUMBERS: dict = {}
_NUMBERS_MAX = 4096


def number(value):
    """``sympy.sympify(value)``, for a Python ``float`` the same SymPy object for the same bits
    in this process: a new ``Float`` costs ~20 µs to make and as much again for each fact
    asked of it the first time (``is_real``, ``is_zero``: SymPy's deduction runs per object),
    and a large model gives thousands of bodies the same masses, inertias and point
    coordinates (decision 0086). Numbers are immutable in SymPy: sharing one is as making
    it again. Anything but a ``float`` is sympified as given.

    Example::

        number(0.5) is number(0.5)       # True; == sympy.Float(0.5)
    """
    if type(value) is not float:
        return sp.sympify(value)
    key = value.hex()           # (exact: 0.0 and -0.0 apart, unlike the floats as keys)
    got = _NUMBERS.get(key)
    if got is None:
        got = sp.sympify(value)
        if len(_NUMBERS) >= _NUMBERS_MAX:
            _NUMBERS.clear()
        _NUMBERS[key] = got
    return got


#: SymPy expression -> its free symbols (:func:`free_symbols`); bounded
_FREE: dict = {}
_FREE_MAX = 200_000


def free_symbols(expr) -> frozenset:
    """``expr.free_symbols`` of a SymPy expression, found once per expression in this process:
    SymPy walks the expression at every ask, and a large model's equations are asked several
    times in one build (the symbol check, the derivation, the velocity-constraint test, again
    for ``free()``'s system of the same equations: decision 0080).

    Example::

        free_symbols(T * x + 1)          # frozenset({T, x})
    """
    got = _FREE.get(expr)
    if got is None:
        got = frozenset(expr.free_symbols)
        if len(_FREE) >= _FREE_MAX:
            _FREE.clear()
        _FREE[expr] = got
    return got


def same_name_advice(extra, known) -> str:
    """What to say of the symbols of ``extra`` that share a name with a symbol of ``known``
    but not its assumptions (``sp.Symbol("T")``, a string such as ``"2*pi*T"``, a parameter
    made again with ``positive=True``): they are different symbols to SymPy, so the model
    does not know them, and declaring them again is impossible. ``""`` when there are none."""
    by_name = {k.name: k for k in known}
    hints = []
    for s in sorted(extra, key=str):
        k = by_name.get(s.name)
        if k is None:
            continue
        if k == T:
            use = ("use mechsys.T (from mechsys import T), e.g. 2*sp.pi*ms.T; a string "
                   "expression such as '2*pi*T' or sp.Symbol('T') makes a symbol T of its own")
        elif k.name.endswith("_d") or k.name.endswith("_dd") or k.is_real:
            use = "use the model's own symbol (a body's coordinate symbols are body.q)"
        else:
            use = (f"use the symbol that m.parameter({k.name!r}, ...) or m.variable returned "
                   f"(sp.Symbol({k.name!r}) without assumptions)")
        mine = {a: v for a, v in s.assumptions0.items() if v}
        theirs = {a: v for a, v in k.assumptions0.items() if v}
        hints.append(f"a symbol named {s.name!r} exists in the model with other assumptions "
                     f"({_assumed(theirs)}, this one {_assumed(mine)}): {use}")
    return "; ".join(hints)


def _assumed(a: dict) -> str:
    keys = [k for k in ("real", "positive", "negative", "nonnegative", "integer")
            if a.get(k)]
    return ", ".join(f"{k}=True" for k in keys) if keys else "no assumptions"


def restore_assumptions(expr):
    """``expr`` with every assumption-free symbol named like a time, coordinate, velocity or
    acceleration symbol replaced by that (real) symbol: undoes SymEngine's round trip."""
    if not isinstance(expr, sp.Basic):
        return expr
    back = {}
    for s in expr.free_symbols:
        r = _REAL.get(s.name)
        if r is not None and s is not r and s != r:
            back[s] = r
    return expr.xreplace(back) if back else expr


def switch_times(label: str, times, params: dict) -> list[float]:
    """Numeric switch times of a ``TimeSwitch`` (of constraints or of loads) named ``label``:
    each time (a number or an expression of parameters) with the values ``params``
    ({symbol: value}); a symbol that is not a parameter is a ``ModelError``."""
    from ._errors import ModelError

    out = []
    for j, tj in enumerate(times, 1):
        v = sp.sympify(tj).subs(params)
        if not v.is_number:
            raise ModelError(f"{label}: switch time {j} ({tj}) uses symbols "
                             f"{sorted(map(str, v.free_symbols))} that are not parameters; "
                             "declare them with m.parameter(name, value)")
        out.append(float(v))
    return out


def check_switch_times(label: str, ts) -> None:
    """A ``ModelError`` naming ``label`` unless the switch times ``ts`` strictly increase."""
    from ._errors import ModelError

    for j in range(1, len(ts)):
        if not ts[j] > ts[j - 1]:
            raise ModelError(f"{label}: switch times must increase, but switch time {j + 1} "
                             f"({ts[j]:.6g}) is not after switch time {j} ({ts[j - 1]:.6g}); "
                             "give them in increasing order")
