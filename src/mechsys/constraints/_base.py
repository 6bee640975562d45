r"""The constraint contract.

A constraint is a small set of scalar equations :math:`\Phi_c(q, t, p) = 0` built from the
geometry of (usually) two bodies. It may introduce new variables (a curve parameter, a rope
length); the degrees of freedom it removes are ``len(equations) - len(new_variables)``.

Subclasses set:

* ``dof_removed`` – the documented count (the digit in Mech's name), checked by the
  conformance suite;
* ``spaces`` – the model kinds it works in (``"planar"``, ``"spatial"``);
* ``_build(space)`` – the list of SymPy equations, in Mech's order.
"""

from __future__ import annotations

import math
from typing import ClassVar

import sympy as sp

from .._errors import GeometryError, ModelError
from .._signature import InitSignature
from .._symbols import number
from ..geometry._points import Axis, Geometry, Point, Vector, as_vector
from ..geometry._units import is_quantity, placeholder


class Variable:
    """A variable introduced into the model (Mech's ``{sym, guess}``)."""

    def __init__(self, symbol: sp.Symbol | str, guess: float = 0.0):
        self.symbol = sp.Symbol(symbol) if isinstance(symbol, str) else symbol
        if not isinstance(self.symbol, sp.Symbol):
            raise ModelError(f"a variable is a name or a SymPy symbol, got {symbol!r}")
        try:
            self.guess = float(guess)
        except (TypeError, ValueError):
            raise ModelError(f"guess of variable {self.symbol.name!r} must be a number, "
                             f"got {guess!r}") from None
        if not math.isfinite(self.guess):
            raise ModelError(f"guess of variable {self.symbol.name!r} must be finite, got {guess!r}")

    def __repr__(self) -> str:
        return f"Variable({self.symbol}, guess={self.guess})"


class ConstraintBase:
    """Base class of every constraint type."""

    dof_removed: ClassVar[int | None] = None
    spaces: ClassVar[tuple[str, ...]] = ("planar", "spatial")
    #: Mech's name; the registry is keyed by it.
    mech_name: ClassVar[str] = ""
    #: 0: position equations ``Phi(q, t) = 0``; 1: velocity equations linear in the rates,
    #: ``A(q, t) qd + b(q, t) = 0`` (the rolling constraints; decision 0046)
    order: ClassVar[int] = 0

    # the signature shown by help() and the API reference is __init__'s, not __new__'s
    __signature__ = InitSignature()

    def __new__(cls, *args, **kwargs):
        # the constructor's arguments, kept for model files (mechsys.io): a constraint is
        # written as its Mech name and these arguments
        self = super().__new__(cls)
        self._init_args = (args, kwargs)
        return self

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

    def sides(self) -> tuple[list[Geometry], list[Geometry]] | None:
        """The two things a two-body constraint joins, whose bodies must differ; ``None``
        for constraints on one thing (drivers such as ``RotationLock1(body, angle)``,
        ``RelativeX1(point, x)``). Default: the two geometric arguments when there are
        exactly two; constraints with extra arguments (offsets, a third axis) override."""
        g = self.geometry()
        return ([g[0]], [g[1]]) if len(g) == 2 else None

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
            self._check_sides()
            eqs = [sp.sympify(e) for e in self._build(space)]
            self._cache[key] = eqs
        return self._cache[key]

    def _check_sides(self) -> None:
        """Both sides on one rigid body (or both on ground) with constant local geometry give
        equations that are constant in the coordinates: redundant, or impossible. Geometry
        with symbols (time, variables, parameters) and constraints that add variables are
        left alone: they may still mean something."""
        sides = self.sides()
        if sides is None or self.new_variables():
            return
        owners = []
        for side in sides:
            if any(_local_symbols(g) for g in side):
                return
            owners.append({b for g in side for b in g.bodies() if not getattr(b, "is_ground", False)})
        if owners[0] != owners[1] or len(owners[0]) > 1:
            return
        where = f"body {next(iter(owners[0])).name!r}" if owners[0] else "ground"
        raise GeometryError(
            f"{self.label()}: {_describe(sides[0])} and {_describe(sides[1])} are both on {where}, "
            "so its equations do not depend on the coordinates (redundant or impossible); "
            "join geometry of two different bodies (ground is m.ground)")

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


def _local_symbols(g) -> set:
    """Free symbols of the local coordinates a geometric object is built from."""
    if isinstance(g, Axis):
        out = _local_symbols(g.origin) | _local_symbols(g.dir)
        return out | (_local_symbols(g.reference) if g.reference is not None else set())
    if isinstance(g, Vector) and g.local is None:
        return set().union(*(_local_symbols(p) for p in g.points))
    local = getattr(g, "local", None)
    return set(local.free_symbols) if local is not None else set()


def _describe(side) -> str:
    g = side[0]
    if isinstance(g, Point):
        return f"point {g.label!r}" if g.label else f"point {tuple(g.local)}"
    return f"{type(g).__name__.lower()} {g!r}"


def as_expr(value, what: str) -> sp.Expr:
    if is_quantity(value):  # converted to the model's units when the constraint is added
        return placeholder(value, what)
    try:
        # (a float: the same SymPy number for the same bits, decision 0086)
        return number(value) if type(value) is float else sp.sympify(value)
    except (sp.SympifyError, TypeError, ValueError, AttributeError, SyntaxError, NameError) as exc:
        raise GeometryError(f"{what}: {value!r} is not a number or expression") from exc


class TwoVectors(ConstraintBase):
    """Base of constraints between ``vector1`` and ``vector2`` (axes and lines give their
    directions, tuples are global)."""

    def __init__(self, vector1, vector2):
        super().__init__()
        self.v1, self.v2 = as_vector(vector1), as_vector(vector2)
        for k, v in ((1, self.v1), (2, self.v2)):
            v.check_nonzero(f"{type(self).__name__} vector{k}")

    def geometry(self):
        return [self.v1, self.v2]
