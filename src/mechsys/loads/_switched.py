r"""Multistage loads (Mech 7.4.1): ``StageSwitch`` and ``TimeSwitch`` of loads.

Loads are cumulative, so a switch of loads is not "one of them" as for constraints:

* ``StageSwitch((test_1, loads_1), (test_2, loads_2), ...)`` applies **every** load set whose
  test is true at ``(T, q, qd, p)``, and none when no test is true (Mech's ``StageSwitch``
  of loads, unlike its ``Which``-like behaviour for constraints).
* ``TimeSwitch(loads_0, t_1, loads_1, ..., t_n, loads_n)`` applies ``loads_i`` for
  :math:`t_i \le T < t_{i+1}` (the first set before ``t_1``, the last after ``t_n``). A *leading*
  time ``TimeSwitch(t_0, loads_0, t_1, ...)`` applies nothing before ``t_0``; a *trailing*
  time ``TimeSwitch(..., loads_n, t_(n+1))`` applies nothing from ``t_(n+1)`` on. The times
  are numbers or expressions of parameters and must increase.

Each load set is a load or a (nested) list of loads. Every contribution of a set (point
force, body moment, direct generalized force) is multiplied by its indicator:

.. math::

    \chi_i = \begin{cases} 1 & \text{where } \mathit{test}_i \text{ holds} \\
                           0 & \text{otherwise} \end{cases}

(``Piecewise((1, test_i), (0, True))``)

so the switched load is an ordinary load expression: statics, inverse dynamics and free
motion use it unchanged, and the derivatives the equilibrium Newton needs are those of the
active set (the indicator's derivative is zero away from the switch). A test must be a SymPy
relation or Boolean (``x < 1``, ``sp.Eq(which, 2)``, ``sp.And(...)``), else a
:class:`ModelError` naming the switch. In free motion the switch's relations are events:
the integration stops where one changes sign and restarts, so the jump of the force is not
smeared over a step (``analyses/_free_switch.py``). A switched load has no potential energy
(the loads it holds may be conservative, the switch is not).
"""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError
from .._symbols import T, check_switch_times, switch_times
from ._loads import BodyMoment, DirectLoad, LoadBase, PointForce


def _flatten(loads, where: str) -> list:
    items = list(loads) if isinstance(loads, (list, tuple)) else [loads]
    out = []
    for ld in items:
        if isinstance(ld, (list, tuple)):
            out += _flatten(ld, where)
        elif isinstance(ld, LoadBase) and not isinstance(ld, SwitchedLoad):
            if ld.model is not None:
                raise ModelError(f"{where}: {ld.label()} is already in a model; a load inside a "
                                 "switch must not be added to the model itself")
            out.append(ld)
        else:
            raise ModelError(f"{where}: a load set is a load or a list of loads (not a switch), "
                             f"got {ld!r}")
    return out


def _boolean(test, where: str):
    """A SymPy Boolean (relation, combination, true/false), or a ModelError."""
    if isinstance(test, bool):
        return sp.true if test else sp.false
    try:
        b = sp.sympify(test)
    except (sp.SympifyError, TypeError):
        b = None
    if not isinstance(b, sp.logic.boolalg.Boolean):
        raise ModelError(f"{where}: test {test!r} is not True or False: write it as a relation "
                         "(x2 < 1, sp.Eq(which, 2)) or a Boolean combination (sp.And, sp.Or)")
    return b


def _times(raw, where: str) -> list:
    out = []
    for j, t in enumerate(raw, 1):
        try:
            te = sp.sympify(t)
        except (sp.SympifyError, TypeError):
            raise ModelError(f"{where}: switch time {j} ({t!r}) is not a number or expression of "
                             "parameters") from None
        if not isinstance(te, sp.Expr) or T in te.free_symbols:
            raise ModelError(f"{where}: switch time {j} ({te}) must be a number or an expression "
                             "of parameters (not of T)")
        out.append(te)
    return out


class SwitchedLoad(LoadBase):
    """A switch of load sets; built by ``StageSwitch``/``TimeSwitch`` given loads.
    Attributes: ``tests`` (one Boolean per set), ``sets`` (tuples of loads)."""

    mech_name = "StageSwitch"

    def __init__(self, tests, sets) -> None:
        super().__init__()
        self.tests = tuple(tests)
        self.sets = tuple(tuple(s) for s in sets)

    def bodies(self) -> list:
        return [b for s in self.sets for ld in s for b in ld.bodies()]

    def geometry(self) -> list:
        return [g for s in self.sets for ld in s for g in ld.geometry()]

    def check(self, model) -> None:
        for k, s in enumerate(self.sets, 1):
            for ld in s:
                try:
                    ld.check(model)
                except ModelError as exc:
                    raise ModelError(f"{self.label()}, load set {k}: {exc}") from None
        self.check_times(dict(zip(model._params, model._p())))

    def check_times(self, params: dict) -> None:
        """Nothing to check for a StageSwitch of loads (a TimeSwitch checks its times)."""

    def indicator(self, k: int) -> sp.Expr:
        """``Piecewise((1, test_k), (0, True))`` of set ``k`` (0-based)."""
        test = self.tests[k]
        if test == sp.true:
            return sp.S.One
        if test == sp.false:
            return sp.S.Zero
        return sp.Piecewise((sp.S.One, test), (sp.S.Zero, True))

    def contributions(self, model) -> list:
        out = []
        for k, s in enumerate(self.sets):
            chi = self.indicator(k)
            for ld in s:
                for c in ld.contributions(model):
                    if isinstance(c, PointForce):
                        out.append(PointForce(c.point, c.force * chi))
                    elif isinstance(c, BodyMoment):
                        out.append(BodyMoment(c.body, c.moment * chi))
                    elif isinstance(c, DirectLoad):
                        out.append(DirectLoad(c.symbol, c.magnitude * chi))
                    else:  # pragma: no cover - every load reduces to the three kinds
                        raise ModelError(f"{self.label()}: {ld.label()} gives a contribution "
                                         f"{type(c).__name__} that cannot be switched")
        return out

    def __repr__(self) -> str:
        n = sum(len(s) for s in self.sets)
        return f"<{self.label()}: {len(self.sets)} set(s), {n} load(s); add it with m.add_load>"

    def relations(self) -> list:
        """The relations of the tests (their ``lhs - rhs`` are the events of free motion)."""
        return [r for t in self.tests for r in t.atoms(sp.core.relational.Relational)]

    def label(self) -> str:
        kind = "TimeSwitch" if isinstance(self, TimeSwitchedLoad) else "StageSwitch"
        return f"load {self.name!r} ({kind} of loads)" if self.name else f"{kind} of loads"


class StageSwitchedLoad(SwitchedLoad):
    """``StageSwitch((test_1, loads_1), ...)`` of loads: every set whose test is true."""

    def __init__(self, *pairs) -> None:
        tests, sets = [], []
        for k, pair in enumerate(pairs, 1):
            if not (isinstance(pair, (list, tuple)) and len(pair) == 2):
                raise ModelError(f"StageSwitch of loads: argument {k} must be a (test, load or "
                                 f"list of loads) pair, got {pair!r}")
            tests.append(_boolean(pair[0], f"StageSwitch of loads, set {k}"))
            sets.append(_flatten(pair[1], f"StageSwitch of loads, set {k}"))
        super().__init__(tests, sets)


def _is_load_set(x) -> bool:
    if isinstance(x, (list, tuple)):
        return len(x) > 0 and all(_is_load_set(y) for y in x)
    return isinstance(x, LoadBase)


class TimeSwitchedLoad(SwitchedLoad):
    """``TimeSwitch([t_0,] loads_0, t_1, loads_1, ..., loads_n [, t_(n+1)])`` of loads."""

    mech_name = "TimeSwitch"

    def __init__(self, *args) -> None:
        where = "TimeSwitch of loads"
        args = list(args)
        leading = bool(args) and not _is_load_set(args[0])
        trailing = len(args) > 1 and not _is_load_set(args[-1])
        body = args[int(leading): len(args) - int(trailing)]
        if not body or len(body) % 2 == 0 or not all(_is_load_set(x) for x in body[0::2]):
            raise ModelError(f"{where}: give [t_0,] loads_0, t_1, loads_1, ..., loads_n [, t_(n+1)] "
                             "(load sets and switch times alternating, a load set first unless a "
                             f"leading time is given), got {len(args)} arguments")
        raw = ([args[0]] if leading else []) + body[1::2] + ([args[-1]] if trailing else [])
        self.times = tuple(_times(raw, where))
        self.leading, self.trailing = leading, trailing
        sets = [_flatten(s, f"{where}, set {k}") for k, s in enumerate(body[0::2], 1)]
        # set i is in effect from its start time (none: -inf) to the next time (none: +inf)
        starts = list(self.times) if leading else [None, *self.times]
        tests = []
        for i in range(len(sets)):
            lo, hi = starts[i], starts[i + 1] if i + 1 < len(starts) else None
            conds = ([T >= lo] if lo is not None else []) + ([T < hi] if hi is not None else [])
            tests.append(sp.And(*conds) if conds else sp.true)
        super().__init__(tests, sets)
        if all(t.is_number for t in self.times):
            self.check_times({})

    def switch_times(self, params: dict) -> list[float]:
        """Numeric switch times with the parameter values ``params`` ({symbol: value})."""
        return switch_times(self.label(), self.times, params)

    def check_times(self, params: dict) -> None:
        check_switch_times(self.label(), self.switch_times(params))


def check_switched_loads(model) -> None:
    """Check the switch times of the model's TimeSwitch loads with its current parameters
    (they may be parameters, changed after the load was added)."""
    loads = [ld for ld in model._loads if isinstance(ld, SwitchedLoad)]
    if loads:
        params = dict(zip(model._params, model._p()))
        for ld in loads:
            ld.check_times(params)


__all__ = ["StageSwitchedLoad", "SwitchedLoad", "TimeSwitchedLoad", "check_switched_loads"]
