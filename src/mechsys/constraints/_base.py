r"""The constraint contract.

A constraint is a small set of scalar equations ``Phi_c(q, t, p) = 0`` built from the
geometry of (usually) two bodies. It may introduce new variables (a curve parameter, a rope
length); the degrees of freedom it removes are ``len(equations) - len(new_variables)``.

Subclasses set:

* ``dof_removed`` – the documented count (the digit in Mech's name), checked by the
  conformance suite;
* ``spaces`` – the model kinds it works in (``"planar"``, ``"spatial"``);
* ``_build(space)`` – the list of SymPy equations, in Mech's order.
"""

from __future__ import annotations

from typing import ClassVar

import sympy as sp

from .._errors import GeometryError, ModelError
from ..geometry._points import Geometry, as_vector


class Variable:
    """A variable introduced into the model (Mech's ``{sym, guess}``)."""

    def __init__(self, symbol: sp.Symbol | str, guess: float = 0.0):
        self.symbol = sp.Symbol(symbol) if isinstance(symbol, str) else symbol
        self.guess = float(guess)

    def __repr__(self) -> str:
        return f"Variable({self.symbol}, guess={self.guess})"


class ConstraintBase:
    """Base class of every constraint type."""

    dof_removed: ClassVar[int | None] = None
    spaces: ClassVar[tuple[str, ...]] = ("planar", "spatial")
    #: Mech's name; the registry is keyed by it.
    mech_name: ClassVar[str] = ""

    def __init__(self) -> None:
        self.name: str | None = None
        self.number: int | None = None
        self.model = None
        self._cache: dict = {}

    # -- contract -----------------------------------------------------------------------
    def geometry(self) -> list[Geometry]:
        """The geometric arguments (for dimension checks and body membership)."""
        return []

    def new_variables(self) -> list[Variable]:
        return []

    def _build(self, space) -> list[sp.Expr]:  # pragma: no cover - interface
        raise NotImplementedError

    # -- derived ------------------------------------------------------------------------
    def equations(self, space) -> list[sp.Expr]:
        """The constraint equations (cached per space)."""
        key = space.name
        if key not in self._cache:
            if space.name not in self.spaces:
                raise ModelError(
                    f"{self.label()} is for {' and '.join(self.spaces)} models, "
                    f"not {space.name} ones"
                )
            for g in self.geometry():
                g.check_dim(space.dim)
            eqs = [sp.sympify(e) for e in self._build(space)]
            self._cache[key] = eqs
        return self._cache[key]

    def bodies(self) -> list:
        seen = []
        for g in self.geometry():
            for b in g.bodies():
                if b not in seen:
                    seen.append(b)
        return seen

    def count_removed(self, space) -> int:
        return len(self.equations(space)) - len(self.new_variables())

    def label(self) -> str:
        kind = type(self).__name__
        if self.name is not None:
            return f"constraint {self.name!r} ({kind}, number {self.number})"
        return f"{kind} constraint"

    def __repr__(self) -> str:
        return f"<{self.label()}>"


def as_expr(value, what: str) -> sp.Expr:
    try:
        return sp.sympify(value)
    except (sp.SympifyError, TypeError) as exc:
        raise GeometryError(f"{what}: {value!r} is not a number or expression") from exc


class TwoVectors(ConstraintBase):
    """Base of constraints between ``vector1`` and ``vector2`` (axes and lines give their
    directions, tuples are global)."""

    def __init__(self, vector1, vector2):
        super().__init__()
        self.v1, self.v2 = as_vector(vector1), as_vector(vector2)

    def geometry(self):
        return [self.v1, self.v2]
