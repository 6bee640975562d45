r"""A restricted expression language for model files: safe to read from strangers.

SymPy's ``sympify``/``parse_expr`` run Python's ``eval`` on their input, so a model file
must never reach them. This module reads expressions with its own tokenizer and
recursive-descent parser and builds SymPy objects directly. The grammar::

    expr   := term (("+" | "-") term)*
    term   := unary (("*" | "/") unary)*
    unary  := ("-" | "+") unary | power
    power  := atom (("**" | "^") unary)?          (right-associative: 2**3**2 = 2**9)
    atom   := NUMBER | NAME | NAME "(" expr ("," expr)* ")" | "(" expr ")"

``NAME`` is a constant (``pi``, ``E``), a whitelisted function (:data:`FUNCTIONS`) or a
symbol the caller supplies (the model's time, parameters, variables and coordinates);
anything else is an error. Limits, each checked before SymPy
computes the step that would exceed it: :data:`MAX_LENGTH` characters, :data:`MAX_DEPTH`
nesting levels, :data:`MAX_OPERATIONS` operations, :data:`MAX_FACTORS` factors in a product,
number literals of at most :data:`MAX_DIGITS` digits, every number (literal or folded by
SymPy, e.g. ``10**400``) at most :data:`MAX_MAGNITUDE` in size, exponents of non-numeric
bases at most :data:`MAX_EXPONENT` and numbers in their base kept below
:data:`MAX_MAGNITUDE` by the power, and ``exp`` of numbers at most :data:`MAX_EXP_ARGUMENT`
(SymPy turns ``exp(10**9*log(2))`` into ``2**(10**9)``).

Writing uses :func:`to_text` (SymPy's ``str`` with floats printed exactly, shortest
round-tripping ``repr``), and :func:`parse` reads back everything it writes:

>>> import sympy as sp
>>> x = sp.Symbol("x")
>>> parse(to_text(sp.sin(x) ** 2 / 3 + 0.1), {"x": x}) == sp.sin(x) ** 2 / 3 + 0.1
True
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping

import sympy as sp
from sympy.printing.str import StrPrinter

from .._errors import ModelError

MAX_LENGTH = 20_000
MAX_DEPTH = 100
MAX_DIGITS = 40
MAX_MAGNITUDE = 1e300
#: the largest exponent of a power whose base is not a plain number (``sqrt(2)**(10**299)``
#: made SymPy compute 2**(5*10**298)); numbers to a power are held to :data:`MAX_MAGNITUDE`
MAX_EXPONENT = 1000
#: the largest number ``exp`` may be taken of (exp(709.8) is the largest double)
MAX_EXP_ARGUMENT = math.log(MAX_MAGNITUDE)
#: the most operations (+ - * / ** and function calls) of one expression
MAX_OPERATIONS = 500
#: the most factors of one product: the time derivatives a driver needs (gamma: the second)
#: of a product of k factors hold ~k**3/2 factors (160 factors: 2 million, minutes to compile)
MAX_FACTORS = 32

#: name -> (SymPy function, allowed argument counts)
FUNCTIONS: dict[str, tuple[object, tuple[int, ...]]] = {
    "sin": (sp.sin, (1,)), "cos": (sp.cos, (1,)), "tan": (sp.tan, (1,)),
    "asin": (sp.asin, (1,)), "acos": (sp.acos, (1,)), "atan": (sp.atan, (1,)),
    "atan2": (sp.atan2, (2,)), "sinh": (sp.sinh, (1,)), "cosh": (sp.cosh, (1,)),
    "tanh": (sp.tanh, (1,)), "sqrt": (sp.sqrt, (1,)), "exp": (sp.exp, (1,)),
    "log": (sp.log, (1,)), "Abs": (sp.Abs, (1,)), "abs": (sp.Abs, (1,)),
    "sign": (sp.sign, (1,)), "Heaviside": (sp.Heaviside, (1, 2)),
    "Min": (sp.Min, (2, 3, 4)), "Max": (sp.Max, (2, 3, 4)),
}
CONSTANTS = {"pi": sp.pi, "E": sp.E}
_NOT_FINITE = (sp.zoo, sp.oo, -sp.oo, sp.nan)

_TOKEN = re.compile(r"""
    (?P<ws>\s+)
  | (?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)
  | (?P<name>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<op>\*\*|<=|>=|[-+*/^(),<>&|~])
""", re.VERBOSE)

#: comparison operators of conditions (switch tests) and their SymPy relations
RELATIONS = {"<": sp.StrictLessThan, "<=": sp.LessThan, ">": sp.StrictGreaterThan,
             ">=": sp.GreaterThan}


class _Printer(StrPrinter):
    """``str`` with floats printed so that ``float(text)`` gives the same double back."""

    def _print_Float(self, expr):
        v = float(expr)
        if not math.isfinite(v):
            raise ModelError(f"cannot write the non-finite number {expr} to a model file")
        return repr(v)


def to_text(expr) -> str:
    """The text of a SymPy expression (or number) that :func:`parse` reads back equal."""
    e = sp.sympify(expr) if isinstance(expr, (int, float)) else expr
    if not isinstance(e, sp.Expr):
        raise ModelError(f"cannot write {expr!r} to a model file: not an expression")
    return _Printer().doprint(e)


def condition_text(cond) -> str:
    """The text of a SymPy condition (relations of expressions joined by ``&``, ``|``, ``~``,
    or ``True``/``False``) that :func:`parse_condition` reads back equal."""
    c = sp.sympify(cond) if isinstance(cond, bool) else cond
    if c is sp.true or c is sp.false:
        return str(c)
    if isinstance(c, sp.And | sp.Or):
        op = " & " if isinstance(c, sp.And) else " | "
        return op.join(f"({condition_text(a)})" for a in c.args)
    if isinstance(c, sp.Not):
        return f"~({condition_text(c.args[0])})"
    if isinstance(c, tuple(RELATIONS.values())):
        return f"{to_text(c.lhs)} {c.rel_op} {to_text(c.rhs)}"
    raise ModelError(f"cannot write the condition {cond!r} to a model file: conditions are "
                     "relations (<, <=, >, >=) of expressions joined by &, | and ~")


def _error(where: str, text: str, pos: int, why: str) -> ModelError:
    snippet = text[max(0, pos - 20): pos + 20]
    return ModelError(f"{where}: {why} at character {pos + 1} (near {snippet!r}); model files "
                      "allow numbers, the model's names, + - * / ** ^, parentheses and the "
                      f"functions {', '.join(sorted(FUNCTIONS))}")


def _tokens(text: str, where: str) -> list[tuple[str, str, int]]:
    out, pos = [], 0
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None:
            raise _error(where, text, pos, f"unexpected character {text[pos]!r}")
        kind = m.lastgroup
        if kind != "ws":
            out.append((kind, m.group(), pos))
        pos = m.end()
    out.append(("end", "", len(text)))
    return out


class _Parser:
    def __init__(self, text: str, names: Mapping[str, sp.Basic], where: str):
        self.text, self.names, self.where = text, names, where
        self.toks = _tokens(text, where)
        self.i = 0
        self.depth = 0
        self.ops = 0

    # -- helpers ----------------------------------------------------------------------
    def peek(self) -> tuple[str, str, int]:
        return self.toks[self.i]

    def take(self) -> tuple[str, str, int]:
        tok = self.toks[self.i]
        self.i += 1
        return tok

    def expect(self, value: str) -> None:
        kind, v, pos = self.take()
        if v != value or kind != "op":
            raise _error(self.where, self.text, pos, f"expected {value!r}, found {v or 'the end'!r}")

    def fail(self, why: str, pos: int | None = None) -> ModelError:
        return _error(self.where, self.text, self.peek()[2] if pos is None else pos, why)

    def enter(self) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.fail(f"nesting deeper than {MAX_DEPTH} levels")

    def op(self, pos: int) -> None:
        """Count one operation against :data:`MAX_OPERATIONS` (before SymPy performs it)."""
        self.ops += 1
        if self.ops > MAX_OPERATIONS:
            raise self.fail(f"more than {MAX_OPERATIONS} operations in one expression (the limit "
                            "MAX_OPERATIONS)", pos)

    def checked(self, value, pos: int):
        """Numbers SymPy folded (``10**400``) are held to the same magnitude limit."""
        if value in _NOT_FINITE:
            # log(0), 1/0.0 (SymPy's zoo, oo, nan are not Numbers): stopped here, where every
            # operation's result passes, so no later expression can hold one
            raise self.fail("the expression is not finite (a division by zero, log(0), ...)", pos)
        if isinstance(value, sp.Number):
            if value.is_finite is False or value.has(sp.nan, sp.zoo):
                raise self.fail("the expression is not finite", pos)
            if abs(value) > MAX_MAGNITUDE:
                raise self.fail(f"a number larger than {MAX_MAGNITUDE:g}", pos)
        return value

    # -- grammar ----------------------------------------------------------------------
    def expr(self):
        """A sum, built in one step (``Add`` of all terms): adding terms one by one makes
        SymPy merge each into the growing sum, quadratic in the number of terms. The numbers
        are folded as they come, each partial result held to the limits."""
        self.enter()
        first = self.term()
        terms, number = [], None
        for t, pos in [(first, None)] + list(self._more(("+", "-"), self.term)):
            if t.is_Number:
                number = t if number is None else self.checked(number + t, pos)
            else:
                terms.append(t)
        self.depth -= 1
        if not terms:
            return number
        if number is None and len(terms) == 1:
            return terms[0]
        return self.checked(sp.Add(*([] if number is None else [number]), *terms), 0)

    def _more(self, ops, operand):
        """``(signed operand, position)`` of each ``op operand`` that follows (``-x`` for a
        subtraction, ``1/x`` for a division), counted against :data:`MAX_OPERATIONS`."""
        while self.peek()[1] in ops and self.peek()[0] == "op":
            _, op, pos = self.take()
            self.op(pos)
            rhs = operand()
            if op == "-":
                yield -rhs, pos
            elif op == "/":
                if rhs.is_Number and rhs.is_zero:       # Float(0.0) != 0 in SymPy 1.13
                    raise self.fail("division by zero", pos)
                # a number stays a divisor (one rounding, as SymPy divides two numbers)
                yield (_Divisor(rhs) if rhs.is_Number else self.checked(1 / rhs, pos)), pos
            else:
                yield rhs, pos

    def term(self):
        """A product, built in one step like a sum (:meth:`expr`), at most
        :data:`MAX_FACTORS` factors."""
        first = self.unary()
        factors, number, n = [], None, 0
        for f, pos in [(first, None)] + list(self._more(("*", "/"), self.unary)):
            if isinstance(f, _Divisor):
                number = self.checked((sp.Integer(1) if number is None else number) / f.value, pos)
                continue
            if f.is_Number:
                number = f if number is None else self.checked(number * f, pos)
                continue
            n += _factors(f)
            if n > MAX_FACTORS:
                raise self.fail(f"a product of more than {MAX_FACTORS} factors (the limit "
                                "MAX_FACTORS)", pos)
            factors.append(f)
        if not factors:
            return number
        if number is None and len(factors) == 1:
            return factors[0]
        return self.checked(sp.Mul(*([] if number is None else [number]), *factors), 0)

    def unary(self):
        kind, v, pos = self.peek()
        if kind == "op" and v in ("-", "+"):
            self.take()
            self.enter()
            value = self.unary()
            self.depth -= 1
            return -value if v == "-" else value
        return self.power()

    def power(self):
        base = self.atom()
        kind, v, pos = self.peek()
        if kind == "op" and v in ("**", "^"):
            self.take()
            self.enter()
            exponent = self.unary()
            self.depth -= 1
            self.op(pos)
            if base.is_Number and exponent.is_Number:
                # fold only what stays small: 10**10**10 must not be computed
                b, e = abs(float(base)), float(exponent)
                if b == 0 and e < 0:
                    raise self.fail("zero to a negative power", pos)
                if b not in (0.0, 1.0) and abs(e * math.log10(b)) > math.log10(MAX_MAGNITUDE):
                    raise self.fail(f"a power larger than {MAX_MAGNITUDE:g} (or smaller than its "
                                    "inverse)", pos)
            elif exponent.is_Number:
                # whatever the base: SymPy multiplies out the numbers in it (sqrt(2)**(10**299)
                # is 2**(5*10**298), (2*T)**n holds 2**n)
                e = abs(float(exponent))
                if e > MAX_EXPONENT:
                    raise self.fail(f"an exponent of {float(exponent):g}; at most {MAX_EXPONENT} "
                                    "(the limit MAX_EXPONENT) unless the base is a number", pos)
                if e * _log10_numbers(base) > math.log10(MAX_MAGNITUDE):
                    raise self.fail(f"a power whose numbers grow past {MAX_MAGNITUDE:g}", pos)
            return self.checked(base ** exponent, pos)
        return base

    def atom(self):
        kind, v, pos = self.take()
        if kind == "num":
            digits = len(re.sub(r"[eE].*|\.", "", v).lstrip("0"))
            if digits > MAX_DIGITS:
                raise self.fail(f"a number with more than {MAX_DIGITS} digits", pos)
            if re.fullmatch(r"\d+", v):
                return self.checked(sp.Integer(int(v)), pos)
            f = float(v)
            if not math.isfinite(f) or abs(f) > MAX_MAGNITUDE:
                raise self.fail(f"a number larger than {MAX_MAGNITUDE:g}", pos)
            return sp.Float(f)
        if kind == "name":
            if self.peek()[1] == "(" and self.peek()[0] == "op":
                return self.call(v, pos)
            if v in self.names:
                return self.names[v]
            if v in CONSTANTS:
                return CONSTANTS[v]
            if v in FUNCTIONS:
                raise self.fail(f"function {v!r} used without arguments", pos)
            raise self.fail(f"unknown name {v!r} (not a parameter, variable, coordinate or T of "
                            "this model)", pos)
        if kind == "op" and v == "(":
            value = self.expr()
            self.expect(")")
            return value
        raise self.fail(f"expected a number, name or '(', found {v or 'the end'!r}", pos)

    # -- conditions (switch tests) -------------------------------------------------------
    def condition(self):
        self.enter()
        value = self.conjunction()
        while self.peek()[1] == "|" and self.peek()[0] == "op":
            self.take()
            value = sp.Or(value, self.conjunction())
        self.depth -= 1
        return value

    def conjunction(self):
        value = self.negation()
        while self.peek()[1] == "&" and self.peek()[0] == "op":
            self.take()
            value = sp.And(value, self.negation())
        return value

    def negation(self):
        kind, v, pos = self.peek()
        if kind == "op" and v == "~":
            self.take()
            self.enter()
            value = sp.Not(self.negation())
            self.depth -= 1
            return value
        if kind == "name" and v in ("True", "False"):
            self.take()
            return sp.true if v == "True" else sp.false
        if kind == "op" and v == "(":
            # a parenthesised condition, or an expression in parentheses starting a relation
            start, depth = self.i, self.depth
            try:
                self.take()
                value = self.condition()
                self.expect(")")
                if not (self.peek()[0] == "op" and self.peek()[1] in (*RELATIONS, "+", "-", "*",
                                                                      "/", "**", "^")):
                    return value
            except ModelError:
                pass
            self.i, self.depth = start, depth
        lhs = self.expr()
        kind, op, pos = self.take()
        if kind != "op" or op not in RELATIONS:
            raise self.fail(f"expected a comparison (<, <=, >, >=), found {op or 'the end'!r}", pos)
        return RELATIONS[op](lhs, self.expr())

    def call(self, name: str, pos: int):
        if name not in FUNCTIONS:
            raise self.fail(f"unknown function {name!r}", pos)
        fn, counts = FUNCTIONS[name]
        self.expect("(")
        args = [self.expr()]
        while self.peek()[1] == "," and self.peek()[0] == "op":
            self.take()
            args.append(self.expr())
        self.expect(")")
        if len(args) not in counts:
            raise self.fail(f"{name} takes {' or '.join(map(str, counts))} arguments, got "
                            f"{len(args)}", pos)
        self.op(pos)
        if name == "exp":
            # SymPy rewrites exp(n*log(2)) as 2**n and computes it: bound the numbers first
            for term in sp.Add.make_args(args[0]):
                if not term.free_symbols and _float(term) > MAX_EXP_ARGUMENT:
                    raise self.fail(f"exp of more than {MAX_EXP_ARGUMENT:.1f} (the limit "
                                    "MAX_EXP_ARGUMENT: exp(709.8) is the largest double)", pos)
        return self.checked(fn(*args), pos)


class _Divisor:
    """A number a product divides by (:meth:`_Parser.term`)."""

    __slots__ = ("value",)

    def __init__(self, value):
        self.value = value


def _factors(e) -> int:
    """The number of factors SymPy's product of ``e`` with something keeps (a Mul's args)."""
    return len(e.args) if isinstance(e, sp.Mul) else 1


def _float(term) -> float:
    """``term`` (no free symbols) as a float, for a bound (inf when too large to say)."""
    try:
        return float(abs(term.evalf(15)))
    except (TypeError, ValueError, OverflowError):
        return math.inf


def _log10_numbers(e) -> float:
    """The largest ``|log10|`` of the numbers in ``e`` (numerators and denominators)."""
    out = 0.0
    for n in e.atoms(sp.Number):
        for part in ((n.p, n.q) if isinstance(n, sp.Rational) else (float(n),)):
            a = abs(part)
            if a not in (0, 1):
                out = max(out, abs(math.log10(a)) if not isinstance(a, int) or a < 10**300
                          else len(str(a)))
    return out


def parse_condition(text: str, names: Mapping[str, sp.Basic] | None = None,
                    where: str = "condition"):
    """Read a condition (a switch test): relations ``<``, ``<=``, ``>``, ``>=`` of expressions
    of the restricted grammar, joined by ``&``, ``|``, ``~`` and parentheses, or ``True``/
    ``False``. Same limits and errors as :func:`parse`."""
    if not isinstance(text, str):
        raise ModelError(f"{where}: expected a condition (a string), got {type(text).__name__}")
    return _parse_whole(text, names, where, "condition")


def parse(text: str, names: Mapping[str, sp.Basic] | None = None, where: str = "expression"):
    """Read an expression of the restricted grammar (module docstring) into SymPy.

    ``names`` maps the allowed symbol names to their SymPy symbols; ``where`` names the place
    in the file for error messages. Bad input raises :class:`~mechsys.ModelError`.
    """
    if isinstance(text, bool) or not isinstance(text, (str, int, float)):
        raise ModelError(f"{where}: expected an expression (a string or a number), got "
                         f"{type(text).__name__}")
    if not isinstance(text, str):
        if not math.isfinite(text) or abs(text) > MAX_MAGNITUDE:
            raise ModelError(f"{where}: the number {text!r} is not finite or larger than "
                             f"{MAX_MAGNITUDE:g}")
        return sp.Integer(text) if isinstance(text, int) else sp.Float(text)
    return _parse_whole(text, names, where, "expression")


def _parse_whole(text: str, names, where: str, what: str):
    """``text`` as one ``what`` (``"expression"`` or ``"condition"``), nothing after it."""
    if len(text) > MAX_LENGTH:
        raise ModelError(f"{where}: {what} of {len(text)} characters; at most {MAX_LENGTH} "
                         "are allowed")
    p = _Parser(text, names or {}, where)
    value = p.expr() if what == "expression" else p.condition()
    kind, v, pos = p.peek()
    if kind != "end":
        raise p.fail(f"unexpected {v!r} after a complete {what}", pos)
    return value
