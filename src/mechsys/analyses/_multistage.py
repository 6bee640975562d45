r"""Multistage kinematics (Mech chapter 5): sweeps across stage changes, ``FindSwitchTime``
and ``FindTime``. Decision record: docs/decisions/0009-multistage.md.

**Systems.** A *stage combination* is one stage index per switch of the model. Its
:class:`~mechsys.compile.System` (the model's equations with each switch's rows replaced by
those of its stage) is compiled on first use and cached on the model until the model changes;
every combination has the same coordinates and the same parameter vector (the model's
parameters, then the hidden ``v_held`` values of the switches' variables), so positions,
velocities and outputs are comparable across stages.

**Sweep.** In the given order of times. A point where the stage may change gets the stage
logic: predict from the previous points (the kinematic sweep's predictor), solve the
positions in the current combination, evaluate every switch's tests at the solved
``(T, q, p)``; if they choose another stage, solve again in that combination from the same
prediction, until the tests confirm the stage the point was solved in. The points after it
go in runs of that combination, each one kinematic sweep continuing the points before it
(compiled where the sweep's loop is; ``RUNS`` points, doubling while the runs are kept
whole); the tests, evaluated on a run's points at once, keep it up to the
first point they send to another combination (or the first that fails), which gets the stage
logic (decision 0029). A stage is therefore recorded only where its own test holds at its own solution. When
the current combination has no solution at a point (a stage past its end), the combination
the tests choose at the predicted point is tried instead.
Tests that keep choosing each other (A's solution says B, B's says A) raise a
:class:`ModelError` naming the switch. Velocities and accelerations are those of the stage in
effect (one-sided at a switch point). Positions are continuous across a switch exactly when
the two stages agree there, which is what :func:`find_switch_time` finds.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import sympy as sp
from sympy.printing.numpy import NumPyPrinter

from .._errors import ConvergenceError, MechError, ModelError, choice
from .._symbols import T
from ..compile import System
from ..compile._stages import _cache, stage_system
from ..constraints._switches import StageSwitch, TimeSwitch
from ..solvers import ORDERS, PositionOptions, _jit_sweep, sweep
from ..solvers._kinematics import SweepResult, _predict
from ..solvers._linalg import Scaling, rotation_indices

#: the solutions with multipliers (Model.solve's load modes) and their kinematic order
MODES = {"static": 0, "kinematic": 1, "dynamic": 2}

#: a point may change its stage combination at most this many times before the tests are
#: declared inconsistent (each change must lead to a combination not tried yet anyway)
MAX_STAGE_CHANGES = 8


class _ExactFloats(NumPyPrinter):
    """NumPy printer that writes floats with all their digits (SymPy's default writes 15
    significant digits, which moves a test's threshold such as ``-pi/3`` by ~1e-15: a
    configuration exactly on a stage's boundary would choose the other stage)."""

    def _print_Float(self, expr):
        return repr(float(expr))


def lambdify_exact(args, expr):
    """``sympy.lambdify`` to NumPy with floats printed exactly (:class:`_ExactFloats`)."""
    return sp.lambdify(args, expr, modules="numpy", printer=_ExactFloats(
        {"fully_qualified_modules": False, "inline": True, "allow_unknown_functions": True,
         "user_functions": {}}))


class _Tests:
    """The switches' tests compiled once per solve as numeric functions of ``(T, q, p)``."""

    def __init__(self, model, system: System):
        self.switches = model._switches()
        lay = system.layout
        args = [T, *lay.q_symbols, *lay.p_symbols]
        allowed = set(args)
        self.funcs = []
        for sw in self.switches:
            fs = []
            for k, test in enumerate(sw.tests):
                extra = test.free_symbols - allowed
                if extra:
                    raise ModelError(
                        f"{sw.label()}: the test of stage {k + 1} ({test}) uses "
                        f"{sorted(map(str, extra))}, which are not T, coordinates or parameters "
                        "of the model; declare parameters with m.parameter(name, value)")
                fs.append(lambdify_exact(args, test))
            self.funcs.append(fs)

    def stage_of(self, j: int, t: float, q, p) -> int:
        """The stage (0-based) switch ``j`` chooses at ``(t, q, p)``: its first true test."""
        sw = self.switches[j]
        for k, f in enumerate(self.funcs[j]):
            val = f(t, *q, *p)
            if not isinstance(val, (bool, np.bool_)):
                raise ModelError(
                    f"{sw.label()}: the test of stage {k + 1} ({sw.tests[k]}) gave {val!r} at "
                    f"t = {t:.6g}, not True or False. Write tests as relations (x2 < 1, "
                    "sp.Eq(which, 2)) or Boolean combinations of them (sp.And, sp.Or), or True "
                    "for 'otherwise'")
            if val:
                return k
        tests = "; ".join(f"stage {k + 1}: {s}" for k, s in enumerate(sw.tests))
        raise ModelError(
            f"{sw.label()}: no test is true at t = {t:.6g} ({tests}), so no stage is in effect; "
            "make the tests cover every configuration, e.g. True as the last test")

    def stages(self, t, q, p, forced: Mapping) -> tuple:
        return tuple(forced[j] if j in forced else self.stage_of(j, t, q, p)
                     for j in range(len(self.switches)))

    def stages_over(self, t, Q, p, forced: Mapping) -> np.ndarray:
        """The combinations ``(L, switches)`` at the points ``t`` (L,), ``Q`` (L, n): the
        tests evaluated on all points at once, each point's stage its first true test (as
        :meth:`stages`, which serves point by point where a test does not give one Boolean
        per point, and raises its errors)."""
        L = len(t)
        out = np.empty((L, len(self.switches)), dtype=int)
        cols = list(np.asarray(Q, dtype=float).T)
        for j in range(len(self.switches)):
            if j in forced:
                out[:, j] = forced[j]
                continue
            left = np.ones(L, dtype=bool)      # points with no true test so far
            for k, f in enumerate(self.funcs[j]):
                val = np.asarray(f(t, *cols, *p))
                if val.dtype != np.bool_ or val.shape not in ((), (L,)):
                    return np.array([self.stages(t[i], Q[i], p, forced) for i in range(L)],
                                    dtype=int).reshape(L, -1)
                hit = left & val
                out[hit, j] = k
                left &= ~hit
                if not left.any():
                    break
            if left.any():
                i = int(np.argmax(left))
                self.stage_of(j, t[i], Q[i], p)    # raises: no test true there
        return out


def cached_tests(model, base: System) -> _Tests:
    """The switches' tests of ``model`` (``base``: its first stage combination), lambdified
    once per model version (FindTime solves many single points; free motion restarts at
    every event)."""
    cache = _cache(model)
    if "tests" not in cache:
        cache["tests"] = _Tests(model, base)
    return cache["tests"]


class _HeldValues:
    """The values the switches' variables are held at, as the tail of the parameter vector:
    while a stage uses a variable its value follows the solution; a stage that does not use
    it holds the last value solved before it took over."""

    def __init__(self, model, system: System, q0):
        self.switches = model._switches()
        self.space = model.space
        self.n_params = len(model._params)
        self.slots = []  # (switch index, variable symbol, coordinate index)
        for j, sw in enumerate(self.switches):
            for v in sw.new_variables():
                self.slots.append((j, v.symbol, system.layout.index(v.symbol)))
        self.p = model._p()
        self.update(q0, None)

    def update(self, q, stages) -> None:
        for i, (j, sym, iq) in enumerate(self.slots):
            if stages is None or sym not in self.switches[j].held_variables(self.space, stages[j]):
                self.p[self.n_params + i] = q[iq]


def _switch_index(model, switch) -> int:
    sw = model.constraint(switch)
    if not isinstance(sw, StageSwitch):
        raise ModelError(f"{sw.label()} is not a StageSwitch or TimeSwitch")
    return model._switches().index(sw)


def solve_stages(model, times, guess, solution: str, options: PositionOptions | None,
                 scalar: bool, forced: Mapping | None = None, lambda_guess=None):
    """``Model.solve`` of a model with switches (see the module docstring). ``forced``:
    ``{switch index: stage index}`` fixes stages regardless of their tests (FindSwitchTime).
    With ``solution`` ``"static"``, ``"kinematic"`` or ``"dynamic"`` the multipliers of each
    point are those of the stage combination in effect there (its Jacobian rows)."""
    from ..results._solution import Solution

    choice(solution, [*ORDERS, *MODES], "solution")
    order = ORDERS.get(solution, MODES.get(solution))
    res, stages, scalings = _sweep_stages(model, np.atleast_1d(times), guess, order, options,
                                          forced or {})
    lam = None
    if solution in MODES:
        lam = _multipliers_by_stage(model, res, stages, solution, lambda_guess, scalings)
    base = stage_system(model, None)
    sol = Solution.from_sweep(model, base, res, model._p(), scalar=scalar, lam=lam, mode=solution)
    sw = model._switches()
    sol.extra["stages"] = {s.name: stages[:, j] + 1 for j, s in enumerate(sw)}
    return sol


def _multipliers_by_stage(model, res, stages, mode, lambda_guess, scalings):
    """Multipliers ``(N, m)``, each point with the system of its stage combination (every
    combination has ``m`` rows: see :meth:`StageSwitch.stage_equations`): one
    :func:`~mechsys.solvers._statics.multipliers_over` per run of points in one combination
    (compiled where the sweep's loops are), with that combination's scaling; each point's
    guess the previous point's multipliers, across runs too."""
    from ..results._load_outputs import lambda_guess_vector
    from ..solvers._statics import multipliers_over

    N = len(res.t)
    held = _HeldValues(model, stage_system(model, None), res.q[0])
    change = np.flatnonzero((stages[1:] != stages[:-1]).any(axis=1)) + 1
    lam = guess = None
    for a, b in zip([0, *change], [*change, N]):
        comb = tuple(int(s) for s in stages[a])
        system = stage_system(model, comb)
        if lam is None:
            lam = np.empty((N, system.m))
            guess = lambda_guess_vector(system, model, lambda_guess)
        # (the held values enter only rows v - v_held, whose Jacobian does not depend on them)
        held.update(res.q[a], comb)
        sc = scalings.get(comb)
        if sc is None:
            sc = Scaling.of(system, res.q[a], system.jacobian(res.t[a], res.q[a], held.p))
        lam[a:b] = multipliers_over(
            system, res.t[a:b], res.q[a:b], None if res.qd is None else res.qd[a:b],
            None if res.qdd is None else res.qdd[a:b], held.p, mode, guess, sc, points=N)
        guess = lam[b - 1]
    return lam


#: a multistage sweep solves the points after a stage change in runs of one combination,
#: each one sweep continuing the one before as one long sweep would (its predictor history and
#: chord): the first ``RUNS[0]`` long, each run the tests confirm to its end twice as long as
#: the one before, up to ``RUNS[1]``. A run that passes its stage's end has solved the points
#: after it in vain, so the Python loop (a point costs about two sweep calls) keeps runs
#: short, the compiled one (a point costs a hundredth of a call) long: ``RUNS_COMPILED``
RUNS = (8, 32)
RUNS_COMPILED = (64, 1024)


class _StageSweep:
    """The state of one multistage sweep (arrays of the points solved so far, held values,
    the combinations' scalings); see :func:`_sweep_stages`."""

    def __init__(self, model, times, guess, order, options, forced):
        self.model, self.times, self.order, self.options = model, times, order, options
        self.forced = forced
        base = stage_system(model, None)
        self.tests = tests = cached_tests(model, base)
        self.guess = np.asarray(guess, dtype=float)
        self.held = _HeldValues(model, base, guess)
        N, n = len(times), base.n
        self.Q = np.empty((N, n))
        self.QD = np.empty((N, n)) if order >= 1 else None
        self.QDD = np.empty((N, n)) if order >= 2 else None
        self.rconds = np.full(N, np.nan) if order >= 1 else None
        self.its = np.zeros(N, dtype=int)
        self.stages = np.zeros((N, len(tests.switches)), dtype=int)
        self.rot = rotation_indices(base)
        self.scalings: dict = {}
        self.evals = 0
        self.fills: list = []    # (first point, count, fill) of runs with pending estimates
        self.rows = None         # the chord's rows after the last kept point (a whole run)
        self.runs = RUNS_COMPILED if _jit_sweep.plan(base, N, order) is not None else RUNS

    def fill(self):
        """``fill(rconds)`` for the sweep's result: each run's pending estimates."""
        fills = self.fills

        def fill(rconds: np.ndarray) -> None:
            for k, count, f in fills:
                if k < len(rconds):
                    f(rconds[k:min(k + count, len(rconds))])
        return fill

    def prediction(self, k: int) -> np.ndarray:
        if k == 0:
            return self.guess
        return _predict(self.Q, self.QD, self.QDD, self.rconds, self.times, k, self.rot)

    def run(self, comb, k: int, length: int) -> SweepResult:
        """Points ``k, k + 1, ...`` (``length`` of them) solved in combination ``comb`` as one
        sweep continuing the points before ``k``; it ends early at a point that fails."""
        system = stage_system(self.model, comb)
        p = self.held.p.copy()      # (a run's pending estimates are computed with its own)
        sc = self.scalings.get(comb)
        if sc is None:
            pred = self.prediction(k)
            sc = self.scalings[comb] = Scaling.of(system, pred,
                                                  system.jacobian(self.times[k], pred, p))
        P = min(k, 3)
        # the chord continues only within one combination
        rows = self.rows if k and tuple(self.stages[k - 1]) == tuple(comb) else None
        prior = None if k == 0 else tuple(
            None if X is None else X[k - P:k] for X in (self.times, self.Q, self.QD, self.QDD,
                                                        self.rconds)) + (rows,)
        got = sweep(system, self.times[k:k + length], self.guess if k == 0 else None,
                    self.order, self.options, p, sc, prior=prior, partial=True,
                    points=len(self.times))
        self.evals += got.evaluations
        return got

    def keep(self, got: SweepResult, k: int, count: int, comb) -> None:
        """Record the first ``count`` points of ``got`` as points ``k ...`` in ``comb``."""
        self.rows = got.rows if count == len(got.t) else None
        if not count:
            return
        sl = slice(k, k + count)
        self.Q[sl], self.its[sl], self.stages[sl] = got.q[:count], got.iterations[:count], comb
        if self.order >= 1:
            # estimates left pending by a compiled run stay pending (decision 0023): the
            # predictor reads them as such, as in one long sweep
            self.QD[sl], self.rconds[sl] = got.qd[:count], got.rcond_raw[:count]
            if got.rcond_pending:
                self.fills.append((k, count, got.fill))
        if self.order >= 2:
            self.QDD[sl] = got.qdd[:count]
        self.held.update(self.Q[k + count - 1], comb)

    def point(self, k: int, current):
        """Point ``k`` with the stage logic of the module docstring; returns its combination."""
        t, p, tests, forced = self.times[k], self.held.p, self.tests, self.forced
        pred = self.prediction(k)
        if current is None:
            current = tests.stages(t, pred, p, forced)
        tried = [current]
        while True:
            got = self.run(current, k, 1)
            if got.stopped is not None:
                # the stage may have no solution past its end (a track that stops): if the
                # tests at the prediction choose another stage, try that one
                new = tests.stages(t, pred, p, forced)
                if new == current or new in tried:
                    raise got.stopped
                tried.append(new)
                current = new
                continue
            new = tests.stages(t, got.q[0], p, forced)
            if new == current:
                break
            if new in tried or len(tried) > MAX_STAGE_CHANGES:
                names = [sw.label() for j, sw in enumerate(tests.switches)
                         if new[j] != current[j]]
                raise ModelError(
                    f"{', '.join(names)}: the tests are inconsistent at t = {t:.6g}: solved in "
                    f"stage(s) {[s + 1 for s in current]} they choose {[s + 1 for s in new]}, "
                    "and solved there they choose back; make the tests agree with the stages' "
                    "own solutions (e.g. test a coordinate the stages share)")
            tried.append(new)
            current = new
        self.keep(got, k, 1, current)
        return current


def _sweep_stages(model, times, guess, order, options, forced):
    """The multistage sweep (module docstring): a point where the stage may change gets the
    stage logic (:meth:`_StageSweep.point`); the points after it go in runs of its
    combination (:meth:`_StageSweep.run`), kept up to the first point whose tests choose
    another combination or which fails, where the stage logic takes over again. Returns the
    :class:`SweepResult`, the stages ``(N, switches)`` and the combinations' scalings."""
    switches = model._switches()
    params = dict(zip(model._params, model._p()))
    for sw in switches:
        sw.check_times(params)
    st = _StageSweep(model, times, guess, order, options, forced)
    N = len(times)
    k, current, length, care = 0, None, st.runs[0], True
    while k < N:
        if care:
            current = st.point(k, current)
            k, care = k + 1, False
            continue
        ask = min(length, N - k)
        got = st.run(current, k, ask)
        ok = len(got.t)
        if ok:
            same = (st.tests.stages_over(got.t, got.q, st.held.p, forced)
                    == np.asarray(current)).all(axis=1)
            ok = ok if same.all() else int(np.argmin(same))
        st.keep(got, k, ok, current)
        k += ok
        if ok == ask:
            length = min(2 * length, st.runs[1])
        else:
            length, care = st.runs[0], True
    res = SweepResult(times, st.Q, st.QD, st.QDD, st.its, st.evals, order, st.rconds,
                      st.fill() if st.fills else None)
    return res, st.stages, st.scalings


# -- finding times ------------------------------------------------------------------------
def _range(model, t_range, what: str) -> tuple[float, float]:
    if t_range is None:
        last = model.last_solution
        if last is None or len(np.atleast_1d(last.t)) < 2:
            raise ModelError(f"{what}: give t_range=(t_start, t_end) (or solve a sweep first: "
                             "its time span is the default range)")
        tt = np.atleast_1d(last.t)
        return float(tt.min()), float(tt.max())
    try:
        a, b = (float(x) for x in t_range)
    except (TypeError, ValueError):
        raise ModelError(f"{what}: t_range must be two numbers (t_start, t_end), got "
                         f"{t_range!r}") from None
    if not (np.isfinite(a) and np.isfinite(b) and b > a):
        raise ModelError(f"{what}: t_range must be finite with t_end > t_start, got {t_range!r}")
    return a, b


def _root(values, solve, t_range, samples, what) -> float:
    """First zero of ``values(solution)`` ((N,) over a location sweep ``solve(times, guess)``)
    in ``t_range``: bracketed on ``samples`` equal steps, refined by Brent's method on position
    solves continued from the bracket's left point, to ``1e-13`` relative."""
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 2:
        raise ModelError(f"{what}: samples must be an integer >= 2, got {samples!r}")
    a, b = t_range
    ts = np.linspace(a, b, int(samples))
    sol = solve(ts, None)
    f = values(sol)
    hits = np.flatnonzero(f == 0.0)
    cross = np.flatnonzero(np.sign(f[:-1]) * np.sign(f[1:]) < 0)
    first = min([*hits, *(cross + 0.5)], default=None)
    if first is None:
        raise ConvergenceError(
            f"{what}: no crossing in the range searched, t in [{a:.6g}, {b:.6g}] ({samples} "
            f"samples; the function goes from {f[0]:.4g} to {f[-1]:.4g} without changing sign); "
            "give another t_range, or more samples if it touches zero between them")
    if first == int(first):
        return float(ts[int(first)])
    i = int(first)

    def at(t):
        return float(values(solve([t], sol.q[i]))[0])

    # Imported here so that `import mechsys` does not load scipy.optimize (decision 0061).
    from scipy.optimize import brentq

    tol = 1e-13 * max(1.0, abs(a), abs(b))
    return float(brentq(at, ts[i], ts[i + 1], xtol=tol, rtol=4 * np.finfo(float).eps))


def _location_solver(model, guess, forced=None, solution="location"):
    """``solve(times, guess)`` -> Solution (location, or ``solution``), without touching
    ``last_solution``."""
    from ..results._solution import Solution

    def start(ts, g):
        if g is not None:
            return g
        if guess is not None:
            return model._resolve_guess(model.compile(), guess)
        # as Mech, start from the last solution (its point nearest the first time), which
        # keeps the assembly branch the user swept; else the model's guesses
        last = model.last_solution
        if last is not None and np.shape(last.q)[-1] == model.compile().n:
            tt, qq = np.atleast_1d(last.t), np.atleast_2d(last.q)
            return qq[int(np.argmin(np.abs(tt - ts[0])))].copy()
        return model.guess()

    if model._switches():
        return lambda ts, g: solve_stages(model, ts, start(ts, g), solution, None, False, forced)
    system, p = model.compile(), model._p()
    order = ORDERS[solution]
    return lambda ts, g: Solution.from_sweep(
        model, system, sweep(system, ts, start(ts, g), order, None, p), p)


def find_time(model, condition, t_range=None, samples: int = 64, guess=None) -> float:
    r"""The first time in ``t_range`` at which ``condition`` holds on the model's solution
    (Mech's ``FindTime``): ``condition`` is a SymPy ``Eq(lhs, rhs)`` or an expression ``f``
    (meaning ``f = 0``) of ``T``, coordinates and parameters, e.g. ``sp.Eq(x4, 5)`` (a
    coordinate reaches a value) or ``m.location(p)[0] - 3`` (a point reaches a position).

    ``guess``: coordinates to start the sweep from (default: the last solution's point
    nearest the range's start, else the model's guesses). The sweep over ``samples`` equally
    spaced times of ``t_range`` (default: the span of
    the last solution) brackets the first sign change of ``f``; Brent's method on position
    solves refines it to ``1e-13`` relative. No sign change raises a
    :class:`ConvergenceError` giving the range searched. Stages change as in ``solve``."""
    what = "FindTime"
    try:
        e = sp.sympify(condition)
    except (sp.SympifyError, TypeError):
        raise ModelError(f"{what}: condition {condition!r} is not a SymPy equation or "
                         "expression") from None
    if isinstance(e, sp.Equality):
        e = e.lhs - e.rhs
    if isinstance(e, sp.logic.boolalg.Boolean) or not isinstance(e, sp.Expr):
        raise ModelError(f"{what}: condition {condition!r} must be an equation Eq(lhs, rhs) or "
                         "an expression that is zero at the time sought, not an inequality")
    lay = model.compile().layout
    extra = e.free_symbols - {T, *lay.q_symbols, *lay.p_symbols}
    if extra:
        raise ModelError(f"{what}: condition {e} uses {sorted(map(str, extra))}, which are not "
                         "T, coordinates or parameters of the model")
    rng = _range(model, t_range, what)
    return _root(lambda s: np.atleast_1d(s.eval(e)), _location_solver(model, guess), rng, samples,
                 what)


def find_switch_time(model, switch, n: int, t_range=None, required_equations=("all", "sum"),
                     samples: int = 64, guess=None, tangent: bool = False) -> float:
    r"""The time at which the stages on either side of switch time ``n`` (1-based, as Mech:
    between stage ``n`` and stage ``n + 1``) of ``switch`` both hold (Mech's
    ``FindSwitchTime``).

    ``required_equations=(first, second)`` (Mech's ``RequiredEquations``): one side ``"all"``,
    the other ``"sum"`` (the sum of its rows, default ``("all", "sum")``) or a 1-based row
    number. The positions are solved with the ``"all"`` side in effect (the other switches'
    stages by their tests) and the other side's selected equation ``g`` is evaluated there;
    the switch time is the first zero of ``g(t)`` in ``t_range`` (default: the span of the last
    solution), bracketed on ``samples`` points and refined by Brent's method to ``1e-13``
    relative. This is Mech's condition (the augmented system with ``T`` unknown) solved as a
    scalar root; no sign change raises a :class:`ConvergenceError` with the range searched.
    Works for a ``TimeSwitch`` (whose given times are then guesses) and a ``StageSwitch``.

    ``tangent=True``: the stages *touch* without crossing (``g`` has a double zero, as where
    a Geneva pin enters its slot tangentially): the time is the zero of ``dg/dt`` along the
    solution, accepted only if ``|g|`` there is below ``1e-8`` times the model's length
    (else a :class:`ConvergenceError`). (Mech's ``TangentConstraint`` option plays this role;
    its exact form was not available to us, so this option has its own name.)
    """
    what = "FindSwitchTime"
    j = _switch_index(model, switch)
    sw = model._switches()[j]
    what = f"FindSwitchTime({sw.name!r}, {n})"
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n < len(sw.stages):
        raise ModelError(f"{what}: n must be a switch time number 1..{len(sw.stages) - 1} of "
                         f"{sw.label()}, got {n!r}")
    try:
        first, second = required_equations
    except (TypeError, ValueError):
        raise ModelError(f"{what}: required_equations must be a pair (first, second), got "
                         f"{required_equations!r}") from None
    sides = [(n - 1, first), (n, second)]
    alls = [s for s in sides if s[1] == "all"]
    if len(alls) != 1:
        raise ModelError(f"{what}: required_equations needs 'all' on exactly one side and 'sum' "
                         f"or one row number on the other, got {required_equations!r}")
    (k_all, _), (k_sel, sel) = alls[0], next(s for s in sides if s[1] != "all")
    rows = sw.stage_equations(model.space, k_sel)
    if sel == "sum":
        g = sp.Add(*rows)
    elif isinstance(sel, (int, np.integer)) and not isinstance(sel, bool) and 1 <= sel <= len(rows):
        g = rows[int(sel) - 1]
    else:
        raise ModelError(f"{what}: the selected side of required_equations must be 'sum' or a "
                         f"row number 1..{len(rows)} of {sw.stage_label(k_sel)}, got {sel!r}")
    if g.free_symbols & set(sw.held_symbols()):
        raise MechError(f"{what}: the selected row holds a variable of the switch; select a row "
                        "of the stage's own constraints")
    rng = _range(model, t_range, what)
    if not tangent:
        return _root(lambda s: np.atleast_1d(s.eval(g)),
                     _location_solver(model, guess, {j: k_all}), rng, samples, what)
    gd = model.time_derivative(g)
    ts = _root(lambda s: np.atleast_1d(s.eval(gd)),
               _location_solver(model, guess, {j: k_all}, "velocity"), rng, samples, what)
    gap = float(_location_solver(model, guess, {j: k_all})([ts], None).eval(g)[0])
    length = max(model.compile().length_hint, 1e-300)
    if abs(gap) > 1e-8 * length:
        raise ConvergenceError(
            f"{what}: with tangent=True, dg/dt is zero at t = {ts:.6g} but the stages do not "
            f"touch there (selected equation {gap:.3g}, model length {length:.3g}); the stages "
            "cross instead (use tangent=False) or do not meet in the range searched", time=ts)
    return ts


def switch_times(model, switch) -> list[float]:
    """The numeric switch times of a TimeSwitch with the model's current parameter values."""
    sw = model._switches()[_switch_index(model, switch)]
    if not isinstance(sw, TimeSwitch):
        raise ModelError(f"{sw.label()} is a StageSwitch; only a TimeSwitch has switch times")
    return sw.switch_times(dict(zip(model._params, model._p())))


# Mech's names
FindSwitchTime = find_switch_time
FindTime = find_time

__all__ = ["FindSwitchTime", "FindTime", "find_switch_time", "find_time", "solve_stages",
           "stage_system", "switch_times"]
