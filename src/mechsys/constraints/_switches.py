r"""Multistage constraints (Mech chapter 5): ``StageSwitch`` and ``TimeSwitch``.

A switch is one compound constraint of the model holding several *stages*; each stage is a
constraint or a list of constraints, and every stage removes the same number of degrees of
freedom. Which stage is in effect is decided at solve time:

* ``StageSwitch((test_1, stage_1), (test_2, stage_2), ...)``: the first stage whose test is
  true at ``(T, q, p)`` (tests are SymPy relations or Boolean combinations of them, e.g.
  ``x2 < 1``, ``sp.Eq(which, 2)``, ``sp.And(T > 1, th2 < pi)``, or ``True`` for "otherwise").
  A test must evaluate to True or False; a test that gives a number, or no test true, is an
  error naming the switch.
* ``TimeSwitch(stage_1, t_1, stage_2, t_2, ..., stage_k)``: stage ``j`` for
  ``t_{j-1} <= T < t_j``; the switch times are numbers or expressions of parameters and must
  increase. At ``T = t_j`` exactly the later stage is in effect.

The constraints inside a switch have no name or number of their own: the switch is the one
constraint of the model (its handle, name and number address it, its rows carry its label).

**Variables of constraints inside a switch** (curve parameters, rope lengths): they are
coordinates of the model in every stage. In a stage whose constraints do not use a variable,
the variable is *held* at the value it had when the stage took over, by the extra equation
:math:`v - v_{held} = 0` (``v_held`` a hidden parameter the multistage solver sets), so every stage
determines every coordinate and a stage's degree-of-freedom count is
``len(equations) - len(new variables)`` as for any constraint.
"""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError
from .._symbols import T, check_switch_times, free_symbols, switch_times
from ._base import ConstraintBase, Variable


def _as_stage(stage, where: str) -> tuple:
    items = list(stage) if isinstance(stage, (list, tuple)) else [stage]
    if not items:
        raise ModelError(f"{where}: a stage needs at least one constraint")
    for c in items:
        if not isinstance(c, ConstraintBase) or isinstance(c, StageSwitch):
            raise ModelError(f"{where}: a stage is a constraint or a list of constraints "
                             f"(not a switch), got {c!r}")
        if c.model is not None:
            raise ModelError(f"{where}: {c.label()} is already in a model; a constraint inside "
                             "a switch must not be added to the model itself")
    return tuple(items)


def _has_loads(items) -> bool:
    """Whether the arguments of a switch hold loads (then it is a switch of loads, Mech 7.4)."""
    from ..loads._loads import LoadBase

    def any_load(x):
        if isinstance(x, (list, tuple)):
            return any(any_load(y) for y in x)
        return isinstance(x, LoadBase)

    return any(any_load(x) for x in items)


def _as_test(test, where: str):
    if isinstance(test, bool):
        return sp.true if test else sp.false
    try:
        return sp.sympify(test)
    except (sp.SympifyError, TypeError):
        raise ModelError(f"{where}: test {test!r} is not a SymPy relation or Boolean") from None


def is_velocity_constraint(c, space, rates) -> bool:
    """Whether ``c`` is a velocity constraint: ``order == 1`` (the rolling classes) or
    equations that use the rates ``rates`` (a ``Constraint`` or ``Orthogonal1`` of velocity
    expressions). A switch is not one (its stages may hold some)."""
    if isinstance(c, StageSwitch):
        return False
    return getattr(c, "order", 0) == 1 or any(free_symbols(e) & rates
                                              for e in c.equations(space))


def velocity_members(model) -> list:
    """Every velocity constraint of ``model``: those added to it (in model order), then those
    inside the stages of its switches (switch by switch, stage by stage), each once."""
    rates = set(model.velocity_symbols().values())
    out = [c for c in model._constraints if is_velocity_constraint(c, model.space, rates)]
    for sw in model._constraints:
        if isinstance(sw, StageSwitch):
            for stage in sw.stages:
                out += [c for c in stage if is_velocity_constraint(c, model.space, rates)
                        and all(c is not x for x in out)]
    return out


class StageSwitch(ConstraintBase):
    """A compound constraint whose active stage is chosen by tests at solve time (Mech's
    ``StageSwitch[cnum, test1 -> con1, test2 -> con2, ...]``).

    ``StageSwitch((test_1, stage_1), (test_2, stage_2), ...)``: each stage a constraint or a
    list of constraints; the first stage whose test is true is in effect (stages are numbered
    from 1 in results, as in Mech). Tests use ``T``, coordinates and parameters.
    """

    mech_name = "StageSwitch"

    def __new__(cls, *args):
        # StageSwitch/TimeSwitch of loads (Mech 7.4.1): the same names build a switched load,
        # which the model takes with add_load (loads are cumulative: see loads/_switched.py)
        if _has_loads(args):
            from ..loads._switched import StageSwitchedLoad, TimeSwitchedLoad

            return (TimeSwitchedLoad if issubclass(cls, TimeSwitch) else StageSwitchedLoad)(*args)
        return super().__new__(cls, *args)

    def __init__(self, *pairs):
        super().__init__()
        if not pairs:
            raise ModelError("StageSwitch needs at least one (test, constraint) pair")
        tests, stages = [], []
        for k, pair in enumerate(pairs, 1):
            if not (isinstance(pair, (list, tuple)) and len(pair) == 2):
                raise ModelError(f"StageSwitch: argument {k} must be a (test, constraint or list "
                                 f"of constraints) pair, got {pair!r}")
            tests.append(_as_test(pair[0], f"StageSwitch stage {k}"))
            stages.append(_as_stage(pair[1], f"StageSwitch stage {k}"))
        self.tests = tuple(tests)
        self.stages = tuple(stages)

    # -- the constraint contract: the union of the stages for membership and variables ----
    def geometry(self):
        return [g for stage in self.stages for c in stage for g in c.geometry()]

    def sides(self):
        return None

    def new_variables(self) -> list[Variable]:
        out: list[Variable] = []
        for stage in self.stages:
            for c in stage:
                for v in c.new_variables():
                    if all(v.symbol != w.symbol for w in out):
                        out.append(v)
        return out

    def _build(self, space) -> list[sp.Expr]:
        """Stage 1's rows with ``v_held`` placeholders (the model's default stage)."""
        return self.stage_equations(space, 0)

    #: the stage whose rows :meth:`equations` shows (``None``: stage 1); set only while the
    #: outputs of a multistage solution are evaluated stage by stage (``results/_stagewise.py``)
    _view: int | None = None

    def equations(self, space) -> list[sp.Expr]:
        """The rows of stage 1, or of the stage being evaluated (see ``_view``: without its
        velocity constraints, whose multipliers a free motion keeps apart, decision 0063)."""
        if self._view is not None:
            return self.stage_equations(space, self._view, self.velocity_members(self._view))
        return super().equations(space)

    def velocity_members(self, k: int) -> list:
        """The velocity constraints of stage ``k`` (0-based; :func:`is_velocity_constraint`
        with the rates of the switch's model)."""
        if self.model is None:
            return []
        rates = set(self.model.velocity_symbols().values())
        return [c for c in self.stages[k] if is_velocity_constraint(c, self.model.space, rates)]

    # -- stages ---------------------------------------------------------------------------
    def held_symbol(self, var: sp.Symbol) -> sp.Symbol:
        """The hidden parameter a stage that does not use ``var`` holds it at."""
        return sp.Symbol(f"_held_{var.name}_{id(self):x}")

    def held_variables(self, space, k: int) -> list[sp.Symbol]:
        """Variables of the switch that stage ``k`` (0-based) does not use."""
        used = set()
        for c in self.stages[k]:
            used |= {v.symbol for v in c.new_variables()}
            for e in c.equations(space):
                used |= e.free_symbols
        return [v.symbol for v in self.new_variables() if v.symbol not in used]

    def stage_equations(self, space, k: int, without=()) -> list[sp.Expr]:
        """Rows of stage ``k`` (0-based): its constraints' equations (those of the constraints
        in ``without`` left out: free motion holds a stage's velocity constraints as rows of
        their own, decision 0063), then ``v - v_held`` for each variable of the switch it
        does not use."""
        eqs = [e for c in self.stages[k] if all(c is not w for w in without)
               for e in c.equations(space)]
        return eqs + [v - self.held_symbol(v) for v in self.held_variables(space, k)]

    def held_symbols(self) -> list[sp.Symbol]:
        return [self.held_symbol(v.symbol) for v in self.new_variables()]

    def check_stages(self, space, name: str | None = None) -> None:
        """Every stage must remove the same number of degrees of freedom."""
        who = f"StageSwitch {name!r}" if name else self.label()
        counts = []
        for stage in self.stages:
            n_eq = sum(len(c.equations(space)) for c in stage)
            n_var = sum(len(c.new_variables()) for c in stage)
            counts.append(n_eq - n_var)
        if len(set(counts)) > 1:
            desc = ", ".join(f"stage {k + 1} removes {n}" for k, n in enumerate(counts))
            raise ModelError(f"{who}: its stages remove different numbers of degrees of freedom "
                             f"({desc}); every stage must remove the same number, so that the "
                             "mechanism keeps its degrees of freedom when the stage changes")

    def switch_times(self, params: dict) -> None:
        """Only a TimeSwitch has switch times."""
        raise ModelError(f"{self.label()} is a StageSwitch; switch times belong to a TimeSwitch")

    def check_times(self, params: dict) -> None:
        """Nothing to check for a StageSwitch (a TimeSwitch checks its switch times)."""

    def stage_label(self, k: int) -> str:
        names = " + ".join(type(c).__name__ for c in self.stages[k])
        return f"stage {k + 1} ({names})"

    def label(self) -> str:
        kind = type(self).__name__
        if self.name is not None:
            return f"switch {self.name!r} ({kind}, constraint number {self.number})"
        return f"{kind} constraint"


class TimeSwitch(StageSwitch):
    """Stages that take over at switch times (Mech's ``TimeSwitch[cnum, con1, t1, con2, t2,
    ..., conk]``): ``TimeSwitch(stage_1, t_1, stage_2, ..., stage_k)``; stage ``j`` is in
    effect for ``t_{j-1} <= T < t_j``. Switch times are numbers or parameter expressions and
    must increase."""

    mech_name = "TimeSwitch"

    def __init__(self, *stages_and_times):
        if len(stages_and_times) < 3 or len(stages_and_times) % 2 == 0:
            raise ModelError("TimeSwitch takes stage_1, t_1, stage_2, ..., t_(k-1), stage_k: an "
                             f"odd number (at least 3) of arguments, got {len(stages_and_times)}")
        times = []
        for j, t in enumerate(stages_and_times[1::2], 1):
            try:
                te = sp.sympify(t)
            except (sp.SympifyError, TypeError):
                raise ModelError(f"TimeSwitch: switch time {j} ({t!r}) is not a number or "
                                 "expression of parameters") from None
            if T in te.free_symbols:
                raise ModelError(f"TimeSwitch: switch time {j} ({te}) must not depend on T")
            times.append(te)
        self.times = tuple(times)
        tests = [T < tj for tj in times] + [sp.true]
        super().__init__(*zip(tests, stages_and_times[0::2]))
        if all(t.is_number for t in times):
            self.check_times({})

    def switch_times(self, params: dict) -> list[float]:
        """Numeric switch times with the parameter values ``params`` ({symbol: value})."""
        return switch_times(self.label(), self.times, params)

    def check_times(self, params: dict) -> None:
        check_switch_times(self.label(), self.switch_times(params))


__all__ = ["StageSwitch", "TimeSwitch", "is_velocity_constraint", "velocity_members"]
