"""Model files (docs/model_files.md): the restricted expression parser, save/load round trips
of every conformance case, solved examples, and malicious files rejected."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from mechsys import ModelError
from mechsys._symbols import T, coord_symbol
from mechsys.io._expr import parse, to_text

x, L = coord_symbol("x2"), sp.Symbol("L")
NAMES = {"T": T, "x2": x, "L": L}


def _round_trip_exprs():
    rng = np.random.default_rng(7)
    base = [T, x, L, sp.Integer(3), sp.Rational(-2, 7), sp.Float(0.1), sp.Float(float(rng.normal()))]
    fns = [sp.sin, sp.cos, sp.tan, sp.asin, sp.acos, sp.atan, sp.sqrt, sp.exp, sp.log, sp.Abs,
           sp.sign, sp.sinh, sp.cosh, sp.tanh, sp.Heaviside]
    out = [sp.pi * T, sp.E ** x, sp.atan2(x, L), sp.Min(x, L), sp.Max(T, 2 * x), -x ** 2,
           (x + L) ** -2, 2 ** T, x ** sp.Rational(3, 2), sp.Float(1e-300) * x, sp.Float(-1.5e200) + L]
    for k in range(40):
        a, b = (base[i] for i in rng.integers(0, len(base), 2))
        f = fns[k % len(fns)]
        c = float(rng.uniform(-5, 5))
        out.append([f(a * b + c) / (L + 2), a - f(b) ** 3 * c, f(a) * f(b) - a / (1 + b ** 2),
                    sp.Float(c) * f(a + 1) ** b][k % 4])
    return [e for e in out if not e.has(sp.I)]  # real expressions only (log of a negative)


@pytest.mark.parametrize("expr", _round_trip_exprs(), ids=lambda e: str(e)[:30])
def test_expression_round_trip(expr):
    text = to_text(expr)
    back = parse(text, NAMES)
    # SymPy distributes numbers over sums while building (7*(a + 1) -> 7*a + 7), so the tree
    # may differ from the original's; the value may not: equal symbolically and numerically
    assert back == expr or sp.simplify(back - expr) == 0, (text, back)
    vals = {T: 0.37, x: 0.81, L: 2.3}
    assert complex(back.subs(vals).evalf(30)) == pytest.approx(complex(expr.subs(vals).evalf(30)),
                                                                rel=1e-14, abs=1e-300)


@pytest.mark.parametrize("text,value", [
    ("1 + 2*3", 7), ("2**3**2", 512), ("2^3", 8), ("-2**2", -4), ("(-2)**2", 4), ("2**-1", 0.5),
    ("--3", 3), ("1.5e3", 1500), (".5", 0.5), ("atan2(1, 1)*4", np.pi), ("sqrt(16)/2", 2),
    ("abs(-3)", 3), ("Heaviside(0, 1)", 1), ("Max(1, 2, 3)", 3), ("E", np.e), ("7/2", 3.5),
])
def test_expression_values(text, value):
    assert float(parse(text, NAMES)) == pytest.approx(value, rel=1e-15)


@pytest.mark.parametrize("text,why", [
    ("__import__('os').system('x')", "unexpected character"),
    ("x2.__class__", "unexpected character '.'"),
    ("lambda: 1", "unexpected character ':'"),
    ("eval(1)", "unknown function 'eval'"),
    ("os", "unknown name 'os'"),
    ("1e999", "larger than"),
    ("9" * 50, "more than 40 digits"),
    ("10**400", "power larger"),
    ("10**10**10", "power larger"),
    ("1e200*1e200", "larger than"),
    ("(" * 5000 + "1" + ")" * 5000, "nesting deeper"),
    ("-" * 5000 + "1", "nesting deeper"),
    ("1" + "+1" * 20000, "characters; at most"),
    ("1/0", "division by zero"),
    ("sin(1, 2)", "takes 1 arguments"),
    ("sin", "without arguments"),
    ("1 2", "unexpected '2'"),
    ("(1", "expected ')'"),
    ("", "expected a number"),
    ("0**-1", "zero to a negative power"),
])
def test_expression_rejected(text, why):
    with pytest.raises(ModelError, match="model files allow|at most") as err:
        parse(text, NAMES, where="file.json: bodies[0].mass")
    assert why in str(err.value)
    if "at most" not in str(err.value):
        assert "file.json: bodies[0].mass" in str(err.value)
