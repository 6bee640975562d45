r"""The general user constraint (Mech's ``Constraint``)."""

from __future__ import annotations

from collections.abc import Mapping

import sympy as sp

from .._errors import ModelError
from ._base import ConstraintBase, Variable


class Constraint(ConstraintBase):
    r"""Any equations :math:`f_k(q, T, p, s) = 0` in body coordinates, time, parameters and new
    variables. Removes ``len(equations) - len(variables)`` DOF.

    ``Constraint(equations, variables={s: guess})``; an equation may be an expression (``= 0``)
    or a SymPy ``Eq``. ``Constraint([], {s: guess})`` only introduces ``s`` (Mech's
    ``Constraint[cnum, {}, {s, guess}]``): it *adds* one degree of freedom.

    Example, a point on the parabola :math:`y = x^2` with its x as new variable::

        s = sp.Symbol("s")
        p = body.point("pin")
        m.add(ms.Constraint([m.location(p)[0] - s, m.location(p)[1] - s**2], {s: 0.5}))
    """

    mech_name = "Constraint"
    dof_removed = None

    def __init__(self, equations, variables=None):
        super().__init__()
        if isinstance(equations, (sp.Expr, sp.Eq, sp.Basic)) and not isinstance(equations, sp.MatrixBase):
            equations = [equations]
        eqs = []
        for e in list(equations):
            e = sp.sympify(e)
            if isinstance(e, sp.Equality):
                e = e.lhs - e.rhs
            eqs.append(e)
        self._equations = eqs
        self._vars: list[Variable] = []
        if variables:
            items = variables.items() if isinstance(variables, Mapping) else [
                (v, 0.0) if not isinstance(v, tuple) else v for v in variables
            ]
            for sym, guess in items:
                self._vars.append(sym if isinstance(sym, Variable) else Variable(sym, guess))
        if not eqs and not self._vars:
            raise ModelError("Constraint needs at least one equation or one new variable")

    def new_variables(self):
        return list(self._vars)

    def _build(self, space):
        return list(self._equations)
