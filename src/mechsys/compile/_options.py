r"""Simplification and compile options of a model (Mech's manual 12.2 and 12.3).

``m.set_compile_options(process=..., opt_level=..., cse=...)`` sets them; each changes the
compiled code, so each enters the on-disk kernel cache key (the processed expressions are
what is fingerprinted; ``opt_level`` and ``cse`` are parts of the key).

* ``process`` -- Mech's ``$MechProcessFunction``: a function applied to every constraint
  equation as the model builds it (Mech's default is ``Chop``). ``None`` (default): the
  equations as the constraints write them. ``"chop"``: numbers smaller than ``1e-12`` times
  the largest number of the same equation become 0 -- the round-off of local coordinates
  such as :math:`\cos(\pi/2) = 6 \cdot 10^{-17}` -- relative, so the result does not depend on the unit of
  length. A callable ``f(expr) -> expr`` (``sympy.expand``, ``sympy.trigsimp``...) must
  return an *equal* expression: the multipliers and reactions are those of the processed
  equations.
* ``opt_level`` -- LLVM's optimisation level 0..3 for the SymEngine backend. ``None``
  (default, automatic): 3, and 0 for kernels of more than ``LARGE_KERNEL`` (500) outputs,
  whose optimisation costs seconds (a 256-link chain's free-motion kernel: 5.5 s at level 3,
  0.3 s at 0, evaluating 109 µs instead of 14 µs; such a kernel computes its distinct
  ``sin``/``cos`` once in a first stage, decision 0066). 0 compiles several times faster and
  evaluates about 1.5-8 times slower (a large model run for a few points); 3 everywhere
  suits a long run of a large model.
* ``cse`` -- common-subexpression elimination before compiling: ``None`` (default: on for
  models with Gen joints, whose nested poses share most subexpressions, decision 0010),
  ``True`` or ``False``.

Example::

    m.set_compile_options(process="chop", opt_level=1)
    m.compile_options          # {'process': 'chop', 'opt_level': 1, 'cse': None}
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import sympy as sp

from .._errors import ModelError, OptionError, close_match, option_fields
from ._backends import real_expression

#: relative size below which ``process="chop"`` drops a number
CHOP_RELATIVE = 1e-12
_UNSET = object()


@option_fields
@dataclass(frozen=True)
class CompileOptions:
    process: object = None
    opt_level: int | None = None
    cse: bool | None = None

    def as_dict(self) -> dict:
        return {"process": self.process, "opt_level": self.opt_level, "cse": self.cse}


def updated(opts: CompileOptions, process=_UNSET, opt_level=_UNSET, cse=_UNSET) -> CompileOptions:
    """``opts`` with the given options changed, each validated (:class:`ModelError` naming
    the option and its valid values)."""
    new = {}
    if process is not _UNSET:
        if not (process is None or process == "chop" or callable(process)):
            raise OptionError(f"compile option process must be None, 'chop' or a function "
                              f"f(expr) -> expr (Mech's $MechProcessFunction), got {process!r}"
                              f"{close_match(process, ('chop',))}")
        new["process"] = process
    if opt_level is not _UNSET:
        # NumPy integers too (a value read from an array); bools are not levels
        if opt_level is not None and (isinstance(opt_level, (bool, np.bool_)) or not isinstance(
                opt_level, (int, np.integer)) or not 0 <= opt_level <= 3):
            raise ModelError(f"compile option opt_level must be an integer 0, 1, 2 or 3 (LLVM's "
                             f"optimisation level) or None (automatic), got {opt_level!r}")
        new["opt_level"] = None if opt_level is None else int(opt_level)
    if cse is not _UNSET:
        if cse not in (None, True, False) or not isinstance(cse, (bool, type(None))):
            raise ModelError(f"compile option cse must be None (automatic), True or False, got "
                             f"{cse!r}")
        new["cse"] = cse
    return replace(opts, **new)


def chop(expr: sp.Expr, relative: float = CHOP_RELATIVE) -> sp.Expr:
    """``expr`` with the floating-point numbers smaller than ``relative`` times its largest
    number (in magnitude) replaced by 0."""
    floats = expr.atoms(sp.Float)
    if not floats:
        return expr
    nums = [abs(float(a)) for a in expr.atoms(sp.Number)]
    big = max(nums)
    small = {a: sp.S.Zero for a in floats if abs(float(a)) < relative * big}
    return expr.xreplace(small) if small else expr


def process_equation(opts: CompileOptions, expr: sp.Expr, owner: str) -> sp.Expr:
    """Apply the ``process`` option to one equation of ``owner`` (a constraint's label)."""
    expr = real_expression(expr, owner)   # complex constants, huge exponents (issue 34)
    f = opts.process
    if f is None:
        return expr
    if f == "chop":
        return chop(expr)
    try:
        out = sp.sympify(f(expr))
    except Exception as exc:  # a user function: report which equation it failed on
        raise ModelError(f"compile option process failed on an equation of {owner}: "
                         f"{type(exc).__name__}: {exc}") from None
    if not isinstance(out, sp.Expr):
        raise ModelError(f"compile option process returned {out!r} for an equation of {owner}; "
                         "it must return a SymPy expression")
    return real_expression(out, owner)


class Backend(str):
    """A backend name (``"symengine"``, ``"sympy"``) that also carries the LLVM optimisation
    level, so every kernel a :class:`System` compiles -- wherever it is compiled -- uses the
    model's setting; compares equal to its name."""

    opt_level: int | None = None

    def __new__(cls, name: str, opt_level: int | None = None):
        obj = super().__new__(cls, name)
        obj.opt_level = opt_level
        return obj


__all__ = ["Backend", "CompileOptions", "chop", "process_equation", "updated"]
