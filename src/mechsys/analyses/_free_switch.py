r"""Free motion through stage changes (issue 14; Mech chapters 5 and 7.4 with ``SolveFree``).

``m.free(drop=[...])`` of a model with ``StageSwitch``/``TimeSwitch`` constraints or switched
loads returns a :class:`SwitchedFreeSystem`. Besides whole constraints, ``drop`` takes
``(switch, stage)`` pairs (stage numbered from 1): in that stage the switch constrains
nothing, e.g. a pendulum that swings freely (stage 1 dropped) until it latches (stage 2)::

    m.add(ms.StageSwitch((rod.q[2] > -beta, ms.RotationLock1(rod, -T)),
                         (True, ms.RotationLock1(rod, -beta))), name="latch")
    sol = m.free(drop=[("latch", 1)]).simulate((0, 1), at_switch="project")

**Events.** Every relation in the switches' tests (constraints and loads), written
``g = lhs - rhs``, is an event function of ``(T, q, qd, p)``. After each accepted
Runge-Kutta step the signs of all ``g`` are compared with the previous ones; where one
changed, its first zero in the step is located on the step's dense output (regula falsi
with the Anderson-Björck weight, :meth:`SwitchedFreeSystem._bracket`) down to a few ulps in
time, so the event time has the integrator's accuracy (the dense output's error). A ``g``
within rounding of zero (``16 eps (|lhs| + |rhs|)``) has no sign: a configuration held on a
boundary (a latched stop) makes no events, and the event is where ``g`` is first strictly on
the far side. After an event the event's relation is expected on the far side, or back on
the near side after a rebound, so a crossing within the first step after the restart is
not missed. The integration stops there, the tests are evaluated just past the zero, and

* a switched load only changes its force: the integration restarts at the event;
* a constraint stage change restarts in the new stage's free system, with positions
  projected onto its constraints (a change of ``Phi`` at the event is of the order of the
  integration error) and velocities by the **velocity policy** ``at_switch``:

  - ``None`` (default): the velocities must already satisfy the new stage
    (:math:`\lvert \Phi_q \dot q + \Phi_t \rvert` below ``1e-6`` in the unit-free scaling of the solver); if
    they
    do not, the change is an impact the model does not describe, and a :class:`ModelError`
    names the switch, the time and the options, rather than silently dropping velocity;
  - ``"project"``: keep the compatible part. The velocity after is the one closest to the
    velocity before in the kinetic-energy metric that satisfies the new stage,
    :math:`\begin{bmatrix} M & \Phi_q^T \\ \Phi_q & 0 \end{bmatrix} \begin{bmatrix} \dot q^+ \\ P
    \end{bmatrix} = \begin{bmatrix} M \dot q^- \\ -\Phi_t \end{bmatrix}` — a perfectly plastic impact whose
    impulse ``P`` the new constraints apply. The kinetic energy lost is reported;
  - ``("restitution", e)`` with ``0 <= e <= 1``: Newton's law on the new stage's rows,
    :math:`\Phi_q \dot q^+ + \Phi_t = -e (\Phi_q \dot q^- + \Phi_t)` by the same impulse equations: the motion
    rebounds off the new stage's constraint (a stop) and **continues in the old stage**.
    Once an approach speed falls below ``1e-6`` times that of the first impact on the same
    switch (the rebounds of a body settling on a stop come ever faster) the stage is taken
    with ``"project"``. ``e = 0`` is ``"project"``. The law acts on the position rows only:
    velocity constraints grip during the impact (below).

Each event is reported in ``sol.extra["events"]``: time, kind (``"stage"``; ``"load"`` when
only a switched load changed; ``"relation"`` when a relation crossed without changing any
stage), switch, stages, policy, kinetic energy before and after, energy lost, impulse. The
solution has every stage's free-system multipliers mapped into the rows of the full stage
system (a dropped constraint carries no force: its multipliers are zero), so
``sol.reaction`` and ``sol.stage`` work as for a kinematic sweep.

**Velocity constraints** (rolling, a knife edge; decisions 0053, 0060 and 0063) added
outside the switches hold in every stage; those inside a stage of a switch hold while that
stage is in effect (not in a dropped stage or switch). Each stage has the velocity rows
:math:`A \dot q + b = 0` of the constraints outside the switches and of those of its stages
(:meth:`SwitchedFreeSystem._rows`, each distinct set compiled once): its acceleration is the
bordered solve of :func:`~mechsys.analyses._nonholonomic.nonholonomic_acceleration`, every
projection is :func:`~mechsys.analyses._nonholonomic.project_state`. The velocity reset
of a stage change takes the new stage's position rows and velocity rows stacked,
:math:`G = [\Phi_q; A]`, :math:`g = [-\Phi_t; -b]`, in place of :math:`\Phi_q` and
:math:`-\Phi_t` above:

.. math::

    \begin{bmatrix} M & G^T \\ G & 0 \end{bmatrix}
    \begin{bmatrix} \dot q^+ \\ P \end{bmatrix} =
    \begin{bmatrix} M \dot q^- \\ g - E (G \dot q^- - g) \end{bmatrix}

with :math:`E` = ``e`` on the position rows and 0 on the velocity rows. So

* a velocity constraint that **starts** (a blade that touches down, a wheel that grips)
  removes the velocity it forbids by the impulse ``P`` it applies, perfectly plastically
  and in the kinetic-energy metric (a sliding body's lateral slip ``s`` at a blade under
  its centroid costs ``m s^2 / 2``); ``at_switch=None`` refuses it naming the switch unless
  the velocities already satisfy it; with ``("restitution", e)`` it grips too (a contact
  that grips does not rebound sideways), and if no position row of the new stage is
  approached the stage is simply taken, as with ``"project"``;
* one that **ends** drops its rows: no impulse, the velocities are kept (compatible, also
  under ``None``);
* one in effect before and after (outside the switches) keeps holding: the plastic impact
  keeps the rolling.

``impulse`` holds the new stage's position rows' impulses, then its velocity rows' (in the
order of their columns in ``mu``). ``sol.extra["mu"]`` has a column for every velocity row
of the model, named in ``sol.extra["velocity_multipliers"]``: those outside the switches
(``"knife[0]"``), then those inside the stages (``"edge.stage2[0]"``: switch, stage, row
within the stage), NaN where the row is not in effect. ``sol.reaction(switch, body)`` of a
stage with a velocity constraint is its :math:`-A^T \mu` plus the stage's position rows'
reaction. :meth:`SwitchedFreeSystem.linearize` linearises in the stage the tests choose at
the state. Example (a sliding sleigh whose blade touches down at ``t = 1``)::

    v = m.velocity(b.point("P"))
    m.add(ms.TimeSwitch(ms.Orthogonal1(v, b.vector((0, 1))), 1.0,
                        ms.Orthogonal1(v, b.vector((0, 1)))), name="edge")
    sol = m.free(drop=[("edge", 1)]).simulate((0, 3), at_switch="project",
                                              initial_condition={"x2_d": 0.5, "y2_d": 0.8})
"""

from __future__ import annotations

from collections.abc import Mapping
from numbers import Real
from types import SimpleNamespace

import numpy as np
import sympy as sp

from .._errors import ConvergenceError, MechError, ModelError
from .._symbols import T
from ..compile._stages import _cache
from ..constraints._switches import StageSwitch, velocity_members
from ..geometry._units import time_numbers
from ..loads._switched import check_switched_loads
from ..results._load_outputs import lambda_guess_vector
from ..results._solution import Solution
from ..solvers._free import free_acceleration, project, project_positions, scaling_at
from ..solvers._integrators import (
    ATOL,
    MAX_ERROR,
    MAX_STEP,
    RTOL,
    counting,
    plan_run,
    stepper_class,
)
from ..solvers._jit_free import PAUSE_STEPS, FreeStepper
from ..solvers._linalg import factor
from ._free import FreeSystem, accuracy_report, nonholonomic_accuracy
from ._multistage import _HeldValues, cached_tests, lambdify_exact, stage_system
from ._nonholonomic import (
    VelocityRows,
    checked_equations,
    nonholonomic_acceleration,
    project_state,
    row_names,
    switched_velocity_constraints,
    velocity_matrix,
)

#: velocities are compatible with a stage when its scaled velocity residual is below this
COMPATIBLE = 1e-6
#: a rebound whose approach speed is below this fraction of the first impact's latches
LATCH_FRACTION = 1e-6
#: the compiled stepper takes at most this many steps between two looks at the events (the
#: steps after one with an event are taken in vain) ...
RUN_STEPS = 64
#: ... and this many in its first run after an event, twice as many in each next run: the
#: rebounds of a body settling on a stop come a step or two apart
RUN_FIRST = 4
#: a relation within this fraction of ``|lhs| + |rhs|`` of its boundary has no sign
_BAND = 16 * np.finfo(float).eps


def _policy(at_switch):
    """``(name, e)`` of a checked velocity policy."""
    if at_switch is None:
        return None, None
    if at_switch == "project":
        return "project", 0.0
    if isinstance(at_switch, (tuple, list)) and len(at_switch) == 2 and \
            at_switch[0] == "restitution":
        e = at_switch[1]
        if isinstance(e, bool) or not isinstance(e, Real) or not 0 <= e <= 1:
            raise ModelError(f"at_switch=('restitution', e): e must be a number in [0, 1], got "
                             f"{e!r}")
        return ("project", 0.0) if e == 0 else ("restitution", float(e))
    raise ModelError(f"at_switch must be None (velocities must be compatible with the new stage), "
                     f"'project' (keep the compatible part, report the energy lost) or "
                     f"('restitution', e) with 0 <= e <= 1, got {at_switch!r}")


class _Events:
    """The relations of all tests (switched constraints and loads) as ``g = lhs - rhs``."""

    def __init__(self, model, system):
        lay = system.layout
        args = [T, *lay.q_symbols, *lay.qd_symbols, *lay.p_symbols]
        rels = [(r, False) for sw in model._switches() for t in sw.tests
                for r in t.atoms(sp.core.relational.Relational)]
        rels += [(r, True) for ld in model._loads if hasattr(ld, "relations")
                 for r in ld.relations()]
        exprs, sides, seen = [], [], set()
        self.of_load = set()      # the g of relations of switched loads
        for r, of_load in rels:
            g = sp.sympify(r.lhs - r.rhs)
            if not g.is_number and of_load:
                self.of_load.add(g)
            if g.is_number or g in seen:
                continue
            extra = g.free_symbols - set(args)
            if extra:
                raise ModelError(f"the switch test {r} uses {sorted(map(str, extra))}, which are "
                                 "not T, coordinates, velocities or parameters of the model")
            seen.add(g)
            exprs.append(g)
            sides += [sp.sympify(r.lhs), sp.sympify(r.rhs)]
        self.exprs = exprs
        self.f = lambdify_exact(args, sides) if exprs else None

    def __call__(self, t, y, p) -> np.ndarray:
        """The signs of the ``g``, zero within rounding of the boundary
        (``|g| <= 16 eps (|lhs| + |rhs|)``): a configuration held on a boundary (a latched
        stop) must not produce events from the last bits of its coordinates."""
        if self.f is None:
            return np.zeros(0)
        return _signs(np.array(self.f(t, *y, *p), dtype=float).reshape(-1, 2))

    def phi(self, t, y, p, i, s0) -> float:
        """``-s0 g_i - 16 eps (|lhs_i| + |rhs_i|)``: positive exactly where the sign of
        relation ``i`` (as :meth:`__call__`) is ``-s0``; continuous in the state."""
        v = np.array(self.f(t, *y, *p), dtype=float).reshape(-1, 2)[i]
        return float(-s0 * (v[0] - v[1]) - _BAND * (abs(v[0]) + abs(v[1])))

    def signs_over(self, t, Y, p) -> np.ndarray:
        """The signs (as :meth:`__call__`) at the states ``Y`` (K, 2n) at times ``t`` (K,),
        evaluated on all at once: ``(K, number of relations)``."""
        K = len(t)
        if self.f is None:
            return np.zeros((K, 0))
        try:
            sides = [np.broadcast_to(np.asarray(v, dtype=float), (K,))
                     for v in self.f(np.asarray(t, dtype=float), *np.asarray(Y).T, *p)]
        except (TypeError, ValueError):      # a side that does not evaluate on arrays
            return np.array([self(t[k], Y[k], p) for k in range(K)]).reshape(K, -1)
        # (the number of relations spelled out: with no states, K = 0, -1 could not be inferred)
        return _signs(np.stack(sides, axis=1).reshape(K, len(sides) // 2, 2))


def _signs(v: np.ndarray) -> np.ndarray:
    """``sign(lhs - rhs)`` of the pairs ``v[..., 0], v[..., 1]``, zero within
    ``16 eps (|lhs| + |rhs|)``."""
    g = v[..., 0] - v[..., 1]
    band = _BAND * (np.abs(v[..., 0]) + np.abs(v[..., 1]))
    return np.where(np.abs(g) > band, np.sign(g), 0.0)


class SwitchedFreeSystem(FreeSystem):
    """A free system of a model with switches: :meth:`simulate` passes through stage changes
    as events (module docstring). Only ``solution="dynamic"`` (free motion).
    ``velocity_constraints`` lists the velocity constraints outside the switches (held in
    every stage); those inside the stages are held stage by stage (decision 0063)."""

    # (loads that depend on the multipliers or accelerations beside velocity constraints:
    # not through the stage-by-stage stepper yet, refused naming them, decision 0068)
    _newton_with_rows = False

    def __init__(self, model, drop=(), solution: str = "dynamic", initial_guess=None,
                 initial_condition=None):
        if solution != "dynamic":
            raise ModelError(f"free(solution={solution!r}) of a model with stage or time switches "
                             "is not supported: equilibria with switches have no stage to start "
                             "from; use solution='dynamic' (free motion through stage changes), or "
                             "replace each switch by the constraint of the stage you need")
        items = list(drop) if isinstance(drop, list) or (
            isinstance(drop, tuple) and not self._is_pair(model, drop)) else [drop]
        plain, staged = [], []
        for c in items:
            if self._is_pair(model, c):
                sw = model.constraint(c[0])
                if not 1 <= c[1] <= len(sw.stages):
                    raise ModelError(f"free(drop=...): {sw.label()} has stages 1..{len(sw.stages)}, "
                                     f"got stage {c[1]!r}")
                staged.append((sw, int(c[1]) - 1))
            else:
                plain.append(c)
        self.stage_drops = staged
        # velocity constraints inside the stages (decision 0063): never rows of a stage
        # system; held as velocity rows in their stages except in dropped switches and
        # stages: (switch index, stage (0-based), constraint)
        dropped = [model.constraint(c) for c in plain]
        switches = model._switches()
        where = {id(sw): j for j, sw in enumerate(switches)}
        inside = switched_velocity_constraints(model)
        self._apart = [c for _, _, c in inside]
        self._inside = [(where[id(sw)], k - 1, c) for sw, k, c in inside
                        if all(sw is not d for d in dropped)
                        and all(not (sw is d and k - 1 == j) for d, j in staged)]
        self._stage_rows: dict = {}
        super().__init__(model, plain, solution, initial_guess, initial_condition)
        if self._inside:
            # every stage's rows are compiled on first use; their equations are checked
            # (linear in the rates, known symbols) now, naming the constraint at fault
            checked_equations(model, self.system, [c for _, _, c in self._inside])
        # the columns of sol.extra["mu"]: the rows outside the switches (in every stage),
        # then those inside the stages, switch by switch, stage by stage ("edge.stage2[0]")
        # (one owner per stage entry, named for row_names: the same constraint object may
        # stand in two stages)
        self._outside_rows = self._vrows
        owners = [] if self._vrows is None else list(self._vrows.owners)
        for j, k, c in self._inside:
            entry = SimpleNamespace(name=f"{switches[j].name}.stage{k + 1}")
            owners += [entry] * len(c.equations(model.space))
        self._columns = row_names(SimpleNamespace(owners=owners))

    @staticmethod
    def _is_pair(model, c) -> bool:
        if not (isinstance(c, tuple) and len(c) == 2 and isinstance(c[1], (int, np.integer))
                and not isinstance(c[1], bool)):
            return False
        try:
            return isinstance(model.constraint(c[0]), StageSwitch)
        except MechError:
            return False

    def _held_apart(self) -> list:
        # the velocity constraints inside the stages: rows of their own, stage by stage
        return list(self._apart)

    def _dropped(self) -> tuple:
        # (the velocity constraints are rows of their own, self._rows(combo), not of the
        # stages)
        return (tuple(self.dropped) + tuple(self.velocity_constraints)
                + tuple(self._held_apart()) + tuple(self.stage_drops))

    def _base(self, combo=None):
        """The full System of stage combination ``combo`` (the solution's rows), without any
        velocity constraint (their multipliers are ``sol.extra["mu"]``): the system
        ``results/_stagewise.py`` evaluates the outputs of that stage with."""
        return stage_system(self.model, combo, tuple(velocity_members(self.model)))

    def _rows(self, combo):
        """``(rows, columns)`` of stage combination ``combo``: the
        :class:`~mechsys.analyses._nonholonomic.VelocityRows` of the velocity constraints
        outside the switches and of those inside the stages in effect (None without any),
        and their columns in ``sol.extra["mu"]``. Each distinct set of constraints is
        compiled once (per model version); the stage systems share their coordinates and
        parameters (the same layout), so one set serves every combination that has it."""
        k0 = 0 if self._outside_rows is None else self._outside_rows.k
        active, cols, at = list(self.velocity_constraints), list(range(k0)), k0
        for j, k, c in self._inside:
            r = len(c.equations(self.model.space))
            if combo[j] == k:
                active.append(c)
                cols += range(at, at + r)
            at += r
        key = (self.model._version, tuple(cols))
        got = self._stage_rows.get(key)
        if got is None:
            if len(active) == len(self.velocity_constraints):
                rows = self._outside_rows
            else:
                rows = VelocityRows(self.model, self._free_system(combo), active)
            got = self._stage_rows[key] = (rows, np.array(cols, dtype=int))
        return got

    def _project(self, S, rows, t, q, qd, p, sc):
        """``(q, qd)`` on stage system ``S``'s constraints and its velocity rows ``rows``
        (:meth:`_rows`; one projection: :func:`~mechsys.solvers._free.project`, or with
        velocity constraints :func:`~mechsys.analyses._nonholonomic.project_state`)."""
        if rows is None:
            return project(S, t, q, qd, p, scaling=sc)
        return project_state(S, rows, t, q, qd, p, sc)

    def _acceleration(self, S, rows, t, q, qd, p, sc, kw):
        r"""``(qdd, multipliers)`` in stage system ``S`` with its velocity rows ``rows``: the
        multipliers of its rows, then (with velocity constraints,
        :func:`~mechsys.analyses._nonholonomic.nonholonomic_acceleration`) those of the
        velocity rows, :math:`\mu`."""
        if rows is None:
            return free_acceleration(S, t, q, qd, p, columns=sc.columns, **kw)[:2]
        return nonholonomic_acceleration(S, rows, t, q, qd, p)

    def _enter(self, combo):
        """Make ``combo`` the current stage: ``self.system`` and ``self._vrows`` (the start
        projection and the accuracy report use them)."""
        self.system = self._free_system(combo)
        self._vrows = self._rows(combo)[0]

    def _free_system(self, combo):
        return stage_system(self.model, combo, self._dropped())

    def linearize(self, state=None, inputs=(), outputs=(), coordinates=None, cyclic=(),
                  t: float | None = None, tolerance: float = 1e-6, speeds=None):
        """:meth:`FreeSystem.linearize` in the stage its tests choose at the state (as
        :meth:`solve`): that stage's position rows (dropped stages left out) and velocity
        rows (those of the constraints outside the switches and of the stages in effect,
        decision 0063)."""
        from ..results._solution import Solution, State

        if isinstance(state, (Solution, State)) or state is None or isinstance(state, Mapping):
            if isinstance(state, (Solution, State)):
                t0 = float(np.atleast_1d(state.t)[-1]) if t is None else float(t)
            else:
                t0 = 0.0 if t is None else float(t)
            q, _, p, _ = self._start(state)
            self._enter(cached_tests(self.model, self._base()).stages(t0, q, p, {}))
        return super().linearize(state, inputs=inputs, outputs=outputs,
                                 coordinates=coordinates, cyclic=cyclic, t=t,
                                 tolerance=tolerance, speeds=speeds)

    def _params(self, given=None) -> np.ndarray:
        # the model's parameters, then the held values of the switches' variables
        p = self.model._p()
        for over in (self._p_given, given or {}):
            for i, v in over.items():
                p[i] = v
        return p

    def solve(self, t: float = 0.0, initial_condition=None, lambda_guess=None,
              tolerance: float | None = None, max_iterations: int | None = None) -> Solution:
        """The free acceleration at one state, in the stage its tests choose there (a
        one-point :class:`Solution` with ``stage``, multipliers in the full stage's rows)."""
        if isinstance(t, bool) or not isinstance(t, Real) or not np.isfinite(t):
            raise ModelError(f"solve(t): t must be a finite number, got {t!r}")
        t = float(t)
        kw = self._newton(tolerance, max_iterations, "FreeSystem.solve")
        _check_times(self.model)
        if lambda_guess is not None:
            kw["lam_guess"] = lambda_guess_vector(self.system, self.model, lambda_guess)
        q, qd, p, held = self._start(initial_condition)
        combo = cached_tests(self.model, self._base()).stages(t, q, p, {})
        self._enter(combo)
        sc = scaling_at(self.system, t, q, p)
        q, qd = self._project_start(t, q, qd, p, held, sc)
        return self._assemble([t], [np.concatenate((q, qd))], [combo], p, kw, {}, sc, scalar=True)

    def simulate(self, t, initial_condition=None, at_switch=None, method: str = "dop853",
                 rtol: float = RTOL, atol: float = ATOL, max_step: float = MAX_STEP,
                 max_error=MAX_ERROR, max_events: int = 1000, tolerance: float | None = None,
                 max_iterations: int | None = None, starting_step_size: float | None = None,
                 **unknown) -> Solution:
        """Integrate the free motion through stage changes (see the module docstring).

        ``t``, ``initial_condition``, ``method`` (``"dop853"`` or ``"rk45"``: events need their
        dense output), ``rtol``/``atol``/``max_step``/``max_error``, ``starting_step_size``
        (the run's first step; after each event SciPy's own choice), ``tolerance``/
        ``max_iterations`` as :meth:`FreeSystem.simulate`; ``at_switch`` the velocity policy at a
        constraint stage change (``None``, ``"project"``, ``("restitution", e)``; velocity
        constraints that start there take a plastic impulse, those that end drop their rows:
        module docstring);
        ``max_events`` the number of events after which a :class:`ConvergenceError` is raised
        (e.g. a motion chattering on a switch boundary)."""
        run = plan_run("FreeSystem.simulate (with switches)", t, unknown, (
            "initial_condition", "at_switch", "method", "rtol", "atol", "max_step", "max_error",
            "max_events", "tolerance", "max_iterations", "starting_step_size"), method, rtol,
            atol, max_step, max_error=max_error, starting_step_size=starting_step_size,
            dense_output="with switches: events are located on the Runge-Kutta dense output",
            to_numbers=time_numbers(self.model))
        opt, t0, t1, t_eval = run.options, run.t0, run.t1, run.t_eval
        policy = _policy(at_switch)
        if isinstance(max_events, bool) or not isinstance(max_events, (int, np.integer)) or \
                max_events < 1:
            raise ModelError(f"max_events must be a positive integer, got {max_events!r}")
        kw = self._newton(tolerance, max_iterations, "FreeSystem.simulate")
        _check_times(self.model)
        model = self.model
        base = self._base()
        # the tests and the event relations, lambdified once per model version
        tests = cached_tests(model, base)
        cache = _cache(model)
        if "events" not in cache:
            cache["events"] = _Events(model, base)
        events = cache["events"]
        n = base.n
        q, qd, p, held_ic = self._start(initial_condition)
        held = _HeldValues(model, base, q)
        held.p = p
        combo = tests.stages(t0, q, p, {})
        self._enter(combo)
        sc = scaling_at(self.system, t0, q, p)
        q, qd = self._project_start(t0, q, qd, p, held_ic, sc)
        y = np.concatenate((q, qd))
        scale = np.concatenate((sc.columns, sc.columns))
        cls = stepper_class(opt.method)
        d = 1.0 if t1 > t0 else -1.0
        out_t, out_y, out_c = [t0], [y.copy()], [combo]
        ie = 1 if t_eval is not None else 0
        log, first_speed = [], {}
        fresh: dict = {}
        t_now, evals, steps, compiled_steps, interpreted_steps = t0, 0, 0, 0, 0
        plans: dict = {}
        known: dict = {}            # row -> (qdd, lambda) from the compiled loop
        while (t1 - t_now) * d > 0:
            S = self._free_system(combo)
            R = self._rows(combo)[0]            # this stage's velocity rows (or None)

            def rhs(tt, yy, S=S, R=R):
                return np.concatenate((yy[n:], self._acceleration(S, R, tt, yy[:n], yy[n:], p,
                                                                  sc, kw)[0]))

            # the compiled stepper of this stage takes the steps between events where it can
            fast = self._stepper(plans, combo, S, opt, p, sc, t_eval, t_now, y, kw, R)
            calls = None
            if opt.spec.implicit:       # its Jacobians' evaluations are not in nfev
                rhs, calls = counting(rhs)
            setup = [fast is not None]
            # the starting step is the run's first (Mech's StartingStepSize); after an event
            # SciPy chooses from the new stage's derivatives
            solver = cls(rhs if fast is None else fast.fun(rhs, setup), t_now, y, t1,
                         rtol=opt.rtol, atol=opt.atol * scale, max_step=opt.max_step,
                         first_step=None if log else opt.first_step)
            setup[0] = False
            g_ref = events(t_now, y, p)
            for i, side in fresh.items():   # the event just handled: the side the motion takes
                g_ref[i] = side
            hit = None
            pause = 0
            run = RUN_FIRST if log else RUN_STEPS
            while solver.status == "running":
                if fast is not None and pause == 0:
                    status, kept, g_ref, ie, crossing = self._compiled_steps(
                        fast, solver, events, p, g_ref, ie, t_eval, d, out_t, out_y, out_c,
                        combo, run, known)
                    run = min(2 * run, RUN_STEPS)
                    steps += kept
                    # (the loop's steps, compiled or interpreted: decision 0077)
                    if fast.tier == "interpreted":
                        interpreted_steps += kept
                    else:
                        compiled_steps += kept
                    if crossing is None or crossing == "python":
                        if crossing or status == 2:
                            # the step with the event (or one the loop handed over) in Python
                            pause = PAUSE_STEPS
                        continue
                    # the step with the event, taken again compiled with its dense output
                    t_old, dense, yp, g_new = crossing
                    steps += 1
                    if fast.tier == "interpreted":
                        interpreted_steps += 1
                    else:
                        compiled_steps += 1
                else:
                    pause = max(pause - 1, 0)
                    t_old = solver.t
                    msg = solver.step()
                    if solver.status == "failed":
                        raise MechError(f"integration failed at t = {solver.t:.6g}: {msg}")
                    steps += 1
                    dense = solver.dense_output()
                    # the events at the projected state (the state the motion goes on from;
                    # the compiled steps are projected in the loop)
                    yp = np.concatenate(self._project(S, R, solver.t, solver.y[:n],
                                                      solver.y[n:], p, sc))
                    g_new = events(solver.t, yp, p)
                crossed = [i for i in range(len(g_new)) if g_ref[i] != 0 and g_new[i] == -g_ref[i]]
                g_ref = np.where(g_ref == 0, g_new, g_ref)
                t_end = solver.t
                if crossed:
                    hit = min((self._bracket(events, dense, p, i, t_old, solver.t, g_ref[i])
                               for i in crossed), key=lambda h: h[1] * d)
                    t_end = hit[2]      # output times up to the old side of the event
                if t_eval is not None:
                    # before an event only the times strictly on its near side; a time on
                    # the boundary belongs to the new stage (a TimeSwitch's later stage at t_j)
                    while ie < len(t_eval) and (
                            ((t_eval[ie] - t_end) * d <= 0) if hit is None else (
                                (t_eval[ie] - t_end) * d <= 0 and
                                events(t_eval[ie], dense(t_eval[ie]), p)[hit[0]] == hit[3])):
                        yi = dense(t_eval[ie])
                        out_t.append(float(t_eval[ie]))
                        out_y.append(np.concatenate(self._project(S, R, t_eval[ie], yi[:n],
                                                                  yi[n:], p, sc)))
                        out_c.append(combo)
                        ie += 1
                if hit is not None:
                    break
                solver.y = yp
                solver.f = solver.fun(solver.t, yp)
                if t_eval is None:
                    out_t.append(float(solver.t))
                    out_y.append(yp.copy())
                    out_c.append(combo)
            evals += solver.nfev if calls is None else calls[0]
            if hit is None:
                t_now = t1
                break
            if len(log) >= max_events:
                raise ConvergenceError(
                    f"free motion with switches: more than max_events = {max_events} events by "
                    f"t = {hit[1]:.6g} (the motion chatters on a switch boundary, or a rebound "
                    "never settles); raise max_events or change the tests", time=hit[1])
            i_ev, te = hit[0], hit[1]
            ye = dense(te)
            new = tests.stages(te, ye[:n], p, {})
            s0 = hit[3]
            fresh = {i_ev: -s0}         # the motion goes on to the far side ...
            if new == combo:
                y = np.concatenate(self._project(S, R, te, ye[:n], ye[n:], p, sc))
                g = events.exprs[i_ev]
                log.append({"t": te, "kind": "load" if g in events.of_load else "relation",
                            "event": str(g)})
            else:
                held.update(ye[:n], combo)
                before = combo
                combo, y, entry = self._switch(combo, new, te, ye, p, sc, policy, first_speed)
                log.append(entry)
                if combo == before:     # ... unless it rebounded off the new stage
                    fresh = {i_ev: s0}
            t_now = te
            if t_eval is None:
                out_t.append(float(te))
                out_y.append(y.copy())
                out_c.append(combo)
        while t_eval is not None and ie < len(t_eval):   # an event exactly at the end time
            out_t.append(float(t_eval[ie]))
            out_y.append(y.copy())
            out_c.append(combo)
            ie += 1
        info = {"events": log, "evaluations": evals, "steps": steps, "method": opt.method,
                "rtol": opt.rtol, "atol": opt.atol, "compiled_steps": compiled_steps,
                "interpreted_steps": interpreted_steps}
        sol = self._assemble(out_t, out_y, out_c, p, kw, info, sc, known=known)
        # the run's own measure of its accuracy, in the last stage's kept constraints
        Y = np.hstack((sol.q, sol.qd))
        sol.extra["accuracy"] = accuracy_report(self.system, sc, sol.t, Y, p, opt.rtol,
                                                "FreeSystem.simulate (with switches)")
        if self._vrows is not None:
            # (in the last stage's velocity rows, as the holonomic accuracy in its rows)
            nonholonomic_accuracy(self.system, self._vrows, sol.t, Y, p, sc, opt.rtol,
                                  sol.extra["accuracy"], "FreeSystem.simulate (with switches)")
        elif self._columns:
            sol.extra["accuracy"]["nonholonomic"] = 0.0     # no velocity rows in that stage
        return sol

    @staticmethod
    def _stepper(plans, combo, S, opt, p, sc, t_eval, t_now, y, kw, rows=None):
        """The stepper of stage combination ``combo`` (planned once per run; its loop
        compiled, or interpreted with ``MECHSYS_JIT=0``: decision 0082), or None where the
        loop cannot run it (loads that depend on the multipliers beside velocity rows, ...).
        ``rows``: the stage's velocity rows (:meth:`_rows`), which the loop holds as the
        unswitched run does (kind ``ROLLING``: the acceleration of
        :func:`~mechsys.analyses._nonholonomic.nonholonomic_acceleration`, the projection of
        :func:`~mechsys.analyses._nonholonomic.project_state`; decision 0084)."""
        if combo not in plans:
            plans[combo] = FreeStepper.plan(S, opt.method, p, sc, None, False, True, t_eval,
                                            (t_now, y[:S.n]), newton=kw, rows=rows)
        fast = plans[combo]
        if fast is not None:
            fast.p[:] = p           # (the held values of the switches' variables change)
        return fast

    @staticmethod
    def _compiled_steps(fast, solver, events, p, g_ref, ie, t_eval, d, out_t, out_y, out_c,
                        combo, run=RUN_STEPS, known=None):
        """Up to ``run`` compiled steps (each projected), kept up to the first whose
        end state has an event relation on the other side (the Python loop's test, the
        signs of all steps evaluated at once). That step is taken again compiled, with its
        dense output (:meth:`FreeStepper.step_again`), and returned as ``crossing = (t_old,
        dense, y_end, signs at y_end)`` with the solver at its end, for the Python loop to
        locate the event; where the loop cannot take it again, the solver is put back to
        the start of that step, with its size, for the Python loop to take it
        (``crossing = "python"``). ``crossing`` is None without an event. ``known`` (dict):
        the accelerations and multipliers the loop computed at the rows it adds, by row
        (the solution's assembly reuses them). Returns
        ``(status, steps kept, g_ref, next output index, crossing)``."""
        t0, y0, f0 = solver.t, solver.y.copy(), solver.f.copy()
        status, T, Y, H, QDD, LAM, ie_new, _, _ = fast.advance(solver, ie, run)
        signs = events.signs_over(T, Y, p)
        crossing = None
        for j in range(len(T)):
            g_new = signs[j]
            if ((g_ref != 0) & (g_new == -g_ref)).any():
                crossing = j
                break
            g_ref = np.where(g_ref == 0, g_new, g_ref)
        kept = len(T) if crossing is None else crossing
        t_last = T[kept - 1] if kept else t0
        if t_eval is not None:
            while ie < ie_new and (t_eval[ie] - t_last) * d <= 0:
                if known is not None:
                    known[len(out_t)] = (fast.EQDD[ie].copy(), fast.ELAM[ie].copy())
                out_t.append(float(t_eval[ie]))
                out_y.append(fast.EY[ie].copy())
                out_c.append(combo)
                ie += 1
        else:
            for j in range(kept):
                if known is not None:
                    known[len(out_t)] = (QDD[j].copy(), LAM[j].copy())
                out_t.append(float(T[j]))
                out_y.append(Y[j].copy())
                out_c.append(combo)
        if crossing is None:
            return status, kept, g_ref, ie, None
        if kept:
            ts, ys = float(T[kept - 1]), Y[kept - 1].copy()
            fs = fast.rate(ys, QDD[kept - 1])
        else:
            ts, ys, fs = t0, y0, f0
        again = fast.step_again(solver, ts, ys, fs, abs(float(H[crossing])))
        if again is not None and again[0] == T[crossing] and np.array_equal(again[1],
                                                                              Y[crossing]):
            solver.t, solver.y = again[0], again[1]
            solver.f = fast.rate(again[1], QDD[crossing])
            solver.status = "running"
            return status, kept, g_ref, ie, (ts, again[2], again[1].copy(), signs[crossing])
        solver.t, solver.y, solver.f = ts, ys, fs
        solver.h_abs = abs(float(H[crossing]))
        solver.status = "running"
        return status, kept, g_ref, ie, "python"

    @staticmethod
    def _bracket(events, dense, p, i, ta, tb, s0):
        """``(i, b, a, s0)``: the first crossing of event ``i`` in ``[ta, tb]`` on the dense
        output, to a few ulps: ``b`` the first time strictly on the far side (sign ``-s0``
        beyond the rounding band), ``a`` the last time before it.

        The root of ``phi(t) = -s0 g(t) - band(t)``, positive exactly where the sign is
        ``-s0`` (:meth:`_Events.phi`), by regula falsi with the Anderson-Bjorck weight:
        ``c = b - phi_b (b - a) / (phi_b - phi_a)``; when the same end moves twice in a row
        the value kept at the other end is scaled by ``1 - phi_c / phi_old`` (by 1/2 when
        that is not positive), which keeps the bracket closing from both sides on curved
        ``phi``. Each trial is at least ``1.5 eps |t|`` inside the bracket, so once ``c``
        is at the root the next trial closes the bracket from the other side; a bracket
        that has not halved in three trials is bisected. A start not on the near side as
        evaluated (a restart on the boundary after a rebound: ``phi`` starts at zero and
        dips below it) is searched for the dip at 1/16 of the bracket from the start until
        a near point is found. About ten evaluations of the dense output instead of
        bisection's fifty."""
        eps = np.finfo(float).eps
        a, b = ta, tb
        fa, fb = events.phi(a, dense(a), p, i, s0), events.phi(b, dense(b), p, i, s0)
        # the far end: the crossing was seen at the projected state; where the dense output
        # does not show it there, bisection on the signs as seen (the start counts as near)
        far_ok = fb > 0
        side, width, stalled = 0, abs(b - a), 0
        for _ in range(200):
            span = max(abs(a), abs(b), 1e-300)
            if abs(b - a) <= 4 * eps * span:
                break
            tol = 1.5 * eps * span
            if far_ok and fa <= 0 and stalled < 3:
                c = b - fb * (b - a) / (fb - fa)
                lo, hi = min(a, b) + tol, max(a, b) - tol
                c = min(max(c, lo), hi) if np.isfinite(c) and lo < hi else 0.5 * (a + b)
            elif far_ok and fa > 0 and stalled < 3:
                # the start sits on the boundary (a restart after a rebound): the near side
                # is a dip just after it; look for it close to the start
                c = a + max((b - a) / 16, tol if b > a else -tol)
            else:
                c = 0.5 * (a + b)
                stalled = 0
            fc = events.phi(c, dense(c), p, i, s0)
            if fc > 0:
                if side == 1 and fb != 0:
                    m = 1.0 - fc / fb
                    fa *= m if m > 0 else 0.5
                b, fb, far_ok, side = c, fc, True, 1
            else:
                if side == -1 and fa != 0:
                    m = 1.0 - fc / fa
                    fb *= m if m > 0 else 0.5
                a, fa, side = c, fc, -1
            if abs(b - a) <= 0.5 * width:
                width, stalled = abs(b - a), 0
            else:
                stalled += 1
        return i, b, a, s0

    def _switch(self, old, new, te, ye, p, sc, policy, first_speed):
        """Positions and velocities in the new stage by the velocity policy; the event log."""
        n = self.system.n
        model = self.model
        names = [sw.name for j, sw in enumerate(model._switches()) if old[j] != new[j]]
        SB = self._free_system(new)
        q = project_positions(SB, te, ye[:n], p, scaling=sc)
        qd = ye[n:]
        M = SB.dynamics.terms(te, q, qd, np.zeros(SB.m), p, np.zeros(n))[0]
        RB = self._rows(new)[0]
        if RB is None:
            J, rhs = SB.velocity_rhs(te, q, p)
            J = np.asarray(J.toarray() if hasattr(J, "toarray") else J)
        else:
            # the new stage's velocity equations and its velocity rows A qd = -b stacked
            # (those outside the switches and those of the new stages): the reset keeps the
            # rolling, and a velocity constraint that starts here (a blade that touches
            # down, a wheel that grips) takes its impulse; one that ends just drops its rows
            J, rhs = velocity_matrix(SB, RB, te, q, p)
        m = J.shape[0]
        viol = J @ qd - rhs
        r = sc.rows(J) if m else np.zeros(0)
        speed = float(np.abs(viol / r).max(initial=0.0)) if m else 0.0
        ke0 = 0.5 * float(qd @ M @ qd)
        entry = {"t": te, "kind": "stage", "switch": names[0] if len(names) == 1 else names,
                 "from": [k + 1 for k in old], "to": [k + 1 for k in new],
                 "kinetic_energy_before": ke0}
        target, e = new, 0.0
        within = COMPATIBLE * (1.0 + np.abs(qd / sc.columns).max(initial=0.0))
        mh = SB.m                   # the position rows' velocity equations come first
        if speed <= within:
            entry["policy"] = "compatible"
            qd_new = self._project(SB, RB, te, q, qd, p, sc)[1]
        else:
            kind, e = policy
            if kind is None:
                raise ModelError(
                    f"free motion: switch {entry['switch']!r} changes from stage {entry['from']} "
                    f"to {entry['to']} at t = {te:.10g} with velocities its new stage does not "
                    f"allow (scaled velocity residual {speed:.3g}): an impact the model does not "
                    "describe. Choose what happens to the velocities with simulate(at_switch="
                    "'project') (keep the compatible part; the kinetic energy lost is reported) "
                    "or at_switch=('restitution', e) (rebound off the new stage's constraint)")
            if kind == "restitution":
                # Newton's law on the new stage's position rows only (the approach to a
                # stop); the velocity rows grip during the impact (a perfectly rough
                # contact: a blade or a wheel does not rebound sideways). Without an
                # approach there is nothing to rebound from: the stage is taken plastically
                approach = float(np.abs(viol[:mh] / r[:mh]).max(initial=0.0))
                key = tuple(names)
                if approach <= within:
                    kind, e = "project", 0.0
                elif approach <= LATCH_FRACTION * first_speed.setdefault(key, approach):
                    kind, e = "project", 0.0
                else:
                    target = old
            entry["policy"] = kind if kind == "project" else f"restitution e={e:g}"
            K = np.zeros((n + m, n + m))
            K[:n, :n], K[:n, n:], K[n:, :n] = M, J.T, J
            law = np.zeros(m)
            law[:mh] = e
            x = factor(K).solve(np.concatenate((M @ qd, rhs - law * viol)))
            qd_new = x[:n]
            entry["impulse"] = x[n:].copy()
        if target is old:       # a rebound: the old stage continues, its constraints exact
            SA = self._free_system(old)
            q, qd_new = self._project(SA, self._rows(old)[0], te, q, qd_new, p, sc)
        ke1 = 0.5 * float(qd_new @ M @ qd_new)
        entry.update(kinetic_energy_after=ke1, energy_lost=ke0 - ke1, stage_after=[k + 1 for k in target])
        return target, np.concatenate((q, qd_new)), entry

    def _assemble(self, out_t, out_y, out_c, p, kw, info, sc, scalar=False,
                  known=None) -> Solution:
        """The Solution: accelerations and multipliers per point in its stage's free system,
        the multipliers placed in the rows of the full stage system (dropped rows zero).
        ``known`` ({row: (qdd, lambda)}): those the compiled loop computed at the same states
        (the same numbers to rounding; rows with a NaN are computed here)."""
        model = self.model
        base = self._base()
        n, N = base.n, len(out_t)
        Y = np.array(out_y)
        QDD = np.empty((N, n))
        # (the stages may differ in position rows where a velocity constraint stands for
        # one: the widest stage's count, each stage's rows from the first column)
        LAM = np.zeros((N, max(self._base(c).m for c in {*out_c, None})))
        # every velocity row of the model has its column; NaN where a row is not in effect
        MU = np.full((N, len(self._columns)), np.nan)
        rows: dict = {}
        known = known or {}
        systems: dict = {}
        for k, (tk, yk, ck) in enumerate(zip(out_t, Y, out_c)):
            got = systems.get(ck)
            if got is None:
                got = systems[ck] = (self._free_system(ck), *self._rows(ck))
            S, R, cols = got
            kept = known.get(k)
            if kept is not None and np.isfinite(kept[0]).all() and np.isfinite(kept[1]).all() \
                    and len(kept[1]) == S.m + len(cols):
                qdd, lam = kept
            else:
                qdd, lam = self._acceleration(S, R, tk, yk[:n], yk[n:], p, sc, kw)
            QDD[k] = qdd
            MU[k, cols] = lam[S.m:]
            if ck not in rows:
                rows[ck] = _row_map(S, self._base(ck))
            src, dst = rows[ck]
            LAM[k, dst] = lam[src]
        switches = model._switches()
        C = np.array(out_c, dtype=int).reshape(N, len(switches))
        extra = {**info, "length_scale": sc.length}
        if switches:
            extra["stages"] = {sw.name: C[:, j] + 1 for j, sw in enumerate(switches)}
        if self._columns:
            # the velocity constraints' multipliers, as FreeSystem._result names them
            extra["velocity_multipliers"] = list(self._columns)
            extra["mu"] = MU
        self._enter(out_c[-1])
        return Solution(t=np.asarray(out_t, dtype=float), q=Y[:, :n].copy(), qd=Y[:, n:].copy(),
                        qdd=QDD, p=p, system=base, model=model, iterations=np.zeros(N, dtype=int),
                        lam=LAM, mode="free-dynamic", extra=extra, scalar=scalar)


def _check_times(model) -> None:
    """Switch times (TimeSwitch constraints and loads) increasing with the parameters now."""
    params = dict(zip(model._params, model._p()))
    for sw in model._switches():
        sw.check_times(params)
    check_switched_loads(model)


def _row_map(free, full) -> tuple[list[int], list[int]]:
    """``(rows of free, rows of full)``: the rows of ``free`` that ``full`` has too (same owner,
    same equation). A row holding a variable of a dropped stage (``v - v_held``) has no place
    in the full stage (which uses the variable): its multiplier is not a reaction and is left
    out. Kept on ``free`` (both are compiled once per model version)."""
    got = free.__dict__.get("_row_maps", {}).get(id(full))
    if got is not None and got[0] is full:
        return got[1]
    out = _match_rows(free, full)
    free.__dict__.setdefault("_row_maps", {})[id(full)] = (full, out)
    return out


def _match_rows(free, full) -> tuple[list[int], list[int]]:
    def key(o):
        return o if isinstance(o, str) else id(o)

    where = {}
    for i, (o, e) in enumerate(zip(full.layout.eq_owner, full.phi)):
        where.setdefault((key(o), sp.srepr(e)), i)
    src, dst = [], []
    for k, (o, e) in enumerate(zip(free.layout.eq_owner, free.phi)):
        i = where.get((key(o), sp.srepr(e)))
        if i is not None:
            src.append(k)
            dst.append(i)
    return src, dst


__all__ = ["SwitchedFreeSystem"]
