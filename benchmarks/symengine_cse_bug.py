"""Reproduce the wrong results of SymEngine's ``Lambdify(..., cse=True)`` (found with
SymEngine 0.15.0), the reason mechsys compiles with ``cse=False``
(docs/decisions/0002-numeric-backend.md).

Run: ``.venv/bin/python benchmarks/symengine_cse_bug.py``. Prints, for the LLVM and the
lambda backend, what ``cse=True`` and ``cse=False`` return against the exact values, first
for a four-expression minimal case, then for the slider-crank's velocity function
(``Phi_q`` values and ``Phi_t``, the expressions mechsys compiles). Exit status 0 either way;
the last line says whether the bug is present in the installed SymEngine.
"""

from __future__ import annotations

import math

import numpy as np
import symengine as se


def minimal() -> bool:
    """Four outputs in four arguments, one of them unused. Returns True if cse=True is wrong."""
    x2, x4, y4, th4 = se.symbols("x2 x4 y4 th4")
    args = [x2, x4, y4, th4]
    exprs = [se.sin(th4), -se.cos(th4), x4 * se.cos(th4) + y4 * se.sin(th4), -se.cos(th4)]
    x = np.array([0.3, 1.5, -0.7, 0.4])
    exact = np.array([math.sin(0.4), -math.cos(0.4), 1.5 * math.cos(0.4) - 0.7 * math.sin(0.4),
                      -math.cos(0.4)])
    print(f"minimal case: args {args}\n  exprs {exprs}\n  at {x.tolist()}")
    print(f"  {'exact':<24}{np.array2string(exact, precision=6)}")
    wrong = False
    for backend in _backends():
        for cse in (False, True):
            got = se.Lambdify(args, exprs, backend=backend, cse=cse)(x).ravel()
            ok = np.allclose(got, exact, rtol=1e-12, atol=1e-12)
            wrong |= cse and not ok
            label = f"{backend}, cse={cse}"
            print(f"  {label:<24}{np.array2string(got, precision=6)}  {'ok' if ok else 'WRONG'}")
    return wrong


def slider_crank() -> bool:
    """The velocity function of mechsys' slider-crank, [Phi_q values, Phi_t], of
    x = [T, q, qd] (19 arguments). Returns True if cse=True is wrong."""
    import sympy as sp

    from mechsys import models

    system = models.slider_crank().compile()
    args = system.layout.args()
    exprs = list(system.jac_exprs) + list(system.phi_t)
    x = np.linspace(0.1, 0.9, len(args))
    exact = np.array([float(sp.sympify(e).subs(dict(zip(args, x, strict=True))))
                      for e in exprs])
    print(f"\nslider-crank velocity function: {len(exprs)} outputs of {len(args)} arguments")
    wrong = False
    for backend in _backends():
        for cse in (False, True):
            got = se.Lambdify(args, exprs, backend=backend, cse=cse)(x).ravel()
            bad = np.nonzero(~np.isclose(got, exact, rtol=1e-12, atol=1e-12))[0]
            wrong |= cse and bad.size > 0
            print(f"  {backend}, cse={cse}: {bad.size} wrong output(s)")
            for i in bad:
                print(f"    output {i}: {exprs[i]} = {got[i]:.6f}, exact {exact[i]:.6f}")
    return wrong


def _backends() -> list[str]:
    out = []
    for b in ("llvm", "lambda"):
        try:
            se.Lambdify([se.Symbol("a")], [se.Symbol("a")], backend=b)
            out.append(b)
        except (ValueError, TypeError, RuntimeError):
            pass
    return out


def main() -> int:
    print(f"symengine {se.__version__}")
    wrong = minimal()
    wrong |= slider_crank()
    print("\nBUG PRESENT: Lambdify(cse=True) returns wrong values" if wrong
          else "\nno wrong values: Lambdify(cse=True) agrees with the exact values here")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
