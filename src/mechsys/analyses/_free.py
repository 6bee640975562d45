r"""Underconstrained systems (Mech's ``SetFree`` / ``SolveFree``).

``free = model.free(drop=[...], solution=...)`` removes constraints from a fully
constrained, assembled model and builds the equations of the freed system once:

* ``solution="static"``: equilibrium configuration under the (conservative) loads;
* ``solution="kinematic"``: equilibrium velocity under velocity-dependent loads
  (inertial terms excluded, as in Mech);
* ``solution="dynamic"`` (default): free acceleration at a state (``solve``) and motion
  synthesis over time (``simulate``).

One FreeSystem serves many states through ``initial_condition=`` (a ``Solution``/``State``
or a mapping of coordinate, ``<coordinate>_d`` velocity and parameter values).

Parameters are read from the model each time ``solve``/``simulate`` runs (Mech's
``SolveFree`` reads ``InitialCondition``, then ``Parameters[]``, then the FreeSystem's own
start): ``m.set_parameters`` after ``m.free()`` takes effect, and parameter values given in
``initial_condition`` override the model's for that call (given to ``free()``, for every
call of this FreeSystem).
"""

from __future__ import annotations

from collections.abc import Mapping
from numbers import Integral, Real

import numpy as np

from .._errors import MechError, ModelError, choice
from .._progress import check_progress, reporter
from ..geometry._units import is_quantity, number, time_numbers
from ..loads._loads import check_load_values
from ..results._load_outputs import lambda_guess_vector
from ..results._solution import Solution, State
from ..solvers._free import (
    ConsistencyError,
    equilibrium_configuration,
    equilibrium_velocity,
    free_acceleration,
    hold_positions,
    project,
    project_holding,
    scaling_at,
)
from ..solvers._integrators import (
    ATOL,
    FIT_DEGREE,
    MAX_ERROR,
    MAX_STEP,
    RTOL,
    integrate,
    plan_run,
    reject_unknown,
)
from ..solvers._jit_free import FreeStepper
from ..solvers._linalg import Scaling
from ..solvers._position import describe_singular
from ..solvers._rank import InZone, project_regularized, zone_guard
from ..solvers._tolerances import SPARSE_THRESHOLD
from ._nonholonomic import (
    VelocityRows,
    nonholonomic_acceleration,
    project_state,
    project_velocities,
    row_names,
    velocity_constraints,
    velocity_drift,
)

KINDS = ("static", "kinematic", "dynamic")


def newton_options(tolerance, max_iterations, what: str) -> dict:
    """Checked Newton options (Mech's ``SolveFree`` tolerance and iteration limit) as keyword
    arguments for the solvers; ``None`` keeps the solver's default."""
    out = {}
    if tolerance is not None:
        if isinstance(tolerance, bool) or not isinstance(tolerance, Real) or not (
                0 < tolerance < 1):
            raise ModelError(f"{what}: tolerance must be a number in (0, 1), got {tolerance!r}")
        out["tol"] = float(tolerance)
    if max_iterations is not None:
        if isinstance(max_iterations, bool) or not isinstance(max_iterations, Integral) or \
                max_iterations < 1:
            raise ModelError(f"{what}: max_iterations must be a positive integer, got "
                             f"{max_iterations!r}")
        out["max_iterations"] = int(max_iterations)
    return out


_reject_unknown = reject_unknown     # (the name the other analyses import)


#: a free-motion run warns (:class:`~mechsys.DegradedAccuracyWarning`) when the kept
#: constraints' residual at its end -- positions in units of the model's length scale ``L``
#: (or radians), velocities relative to the run's largest rate -- exceeds this or
#: ``DRIFT_FACTOR`` times the run's own tolerance (``rtol``, or Adams' ``max_error``),
#: whichever is larger: a per-step tolerance accumulates over the steps, so a residual of a
#: few tolerances is the integration's normal error, ten times it is not
DRIFT_WARNING = 1e-6
DRIFT_FACTOR = 10.0


def accuracy_report(s, sc, t, Y, p, tol: float, what: str) -> dict:
    r"""The run's own measure of its accuracy (issue 34), recorded in ``sol.extra["accuracy"]``
    and warned about (:class:`~mechsys.DegradedAccuracyWarning`) when degraded. Computed once,
    after the run, from the states it returns (so the Python and the compiled steppers are
    judged alike):

    * ``position``: :math:`\max_i |\Phi_i| / r_i` at the last state, ``r_i`` the row scale of
      the unit-free Jacobian (an error in units of ``L``, or radians);
    * ``velocity``: :math:`\max_i |(\Phi_q \dot q + \Phi_t)_i| / r_i` over the run's
      largest rate :math:`\max_{k,j} |\dot q_{kj}| / c_j` (relative);
    * ``offset``: the largest position coordinate of the run over ``L``. Double precision
      resolves positions to :math:`\varepsilon \cdot` offset (units of ``L``); above the run's
      tolerance ``tol`` the tolerance cannot be met (a mechanism of unit size 1e11 from the
      origin: 2e-5).

    Warns when ``position`` or ``velocity`` exceeds ``max(DRIFT_WARNING, DRIFT_FACTOR tol)``,
    or when ``eps * offset`` exceeds ``tol``."""
    import warnings

    from .._errors import DegradedAccuracyWarning
    from ..solvers._linalg import _column_kinds

    n = s.n
    Q, QD = Y[:, :n], Y[:, n:]
    trans, _ = _column_kinds(s)
    L = sc.length
    # (the columns' largest magnitudes first, then one division per column: the same
    # numbers as dividing every row, since the column units are positive and a correctly
    # rounded division keeps the order; one pass over the run's states instead of three)
    top = np.abs(Y).max(axis=0, initial=0.0) if n else None
    offset = float(top[:n][trans].max(initial=0.0)) / L if n else 0.0
    rate = float((top[n:] / sc.columns).max(initial=0.0)) if n else 0.0
    pos = vel = 0.0
    if s.m and len(t) and np.isfinite(Y[-1]).all():
        q, qd = Q[-1], QD[-1]
        # (sparse above SPARSE_THRESHOLD coordinates: the same row maxima and products; a
        # dense Jacobian is O(n m) to build and scan, a tenth of a 1024-link chain's run)
        J, rhs = s.velocity_rhs(t[-1], q, p, n > SPARSE_THRESHOLD)
        r = sc.rows(J)
        pos = float(np.abs(s.residual(t[-1], q, p) / r).max(initial=0.0))
        v = np.abs((J @ qd - rhs) / r).max(initial=0.0)
        vel = float(v / rate) if rate > 0 else float(v)
    report = {"position": pos, "velocity": vel, "offset": offset}
    bound = max(DRIFT_WARNING, DRIFT_FACTOR * tol)
    eps = float(np.finfo(float).eps)
    if max(pos, vel) > bound:
        worst = "position" if pos >= vel else "velocity"
        warnings.warn(DegradedAccuracyWarning(
            f"{what}: the kept constraints have drifted by the end of the run (t = {t[-1]:.6g}): "
            f"position residual {pos:.2e} (units of the length scale L = {L:.3g}), velocity "
            f"residual {vel:.2e} (relative to the largest rate), above {bound:.0e}; keep "
            "constraint_correction=True (the default) or tighten rtol/max_error "
            "(sol.extra['accuracy'])", measure=max(pos, vel), threshold=bound), stacklevel=3)
        report["warned"] = worst
    if eps * offset > tol:
        warnings.warn(DegradedAccuracyWarning(
            f"{what}: coordinates reach {offset:.3g} times the model's length scale L = "
            f"{L:.3g} from the origin; double precision resolves positions there only to "
            f"{eps * offset:.1e} L, above the run's tolerance {tol:.0e}: place the mechanism "
            "near the origin of its coordinates (subtract a constant offset)",
            measure=eps * offset, threshold=tol), stacklevel=3)
        report["range"] = True
    return report


def _flag(box, value):
    """``value``, noting in ``box[0]`` that it is not ``None``."""
    if value is not None:
        box[0] = True
    return value


def _check_independent(system, t, q, p, scaling, J=None) -> None:
    """Dependent kept constraints at the start raise :class:`SingularJacobianError` naming
    them (the integration tolerates only singular instants on the way, not a redundancy).
    ``J``: the Jacobian at ``(t, q)`` as ``system.jacobian(t, q, p, system.n >
    SPARSE_THRESHOLD)`` returns it, when the caller has it (else it is evaluated here)."""
    if system.m:
        # (sparse above SPARSE_THRESHOLD coordinates: dependent_rows certifies full rank by a
        # sparse LU of J J^T there, and densifies only for its QR)
        if J is None:
            J = system.jacobian(t, q, p, system.n > SPARSE_THRESHOLD)
        if scaling.dependent_rows(J)[1]:
            raise describe_singular(system, system.jacobian(t, q, p), t, q, "free motion",
                                    scaling)


class FreeSystem:
    r"""A model with constraints dropped. Attributes: ``model``, ``dropped`` (constraints),
    ``system`` (the compiled System of the kept equations), ``kind``, ``linear`` (whether the
    highest-order unknowns enter linearly: no loads depending on multipliers, and for the
    velocity equilibrium loads linear in velocities), ``dof``, ``velocity_constraints`` (the
    kept velocity constraints :math:`A(q, t)\,\dot q + b(q, t) = 0`, rolling contacts or
    constraints of velocity expressions: free motion adds :math:`A^T \mu` to the equations of
    motion and :math:`A \ddot q = -\rho` to the constraints; ``docs/nonholonomic.md``,
    decision 0053).

    With the kept constraints :math:`\Phi(q, t) = 0` (:math:`m < n` equations), their
    Jacobian :math:`\Phi_q`, the mass matrix :math:`M`, the applied loads :math:`Q` and the
    centrifugal and gyroscopic terms :math:`Q_v`, each kind solves:

    .. math::

        \Phi(q, t) &= 0, \quad \Phi_q^T \lambda - Q(t, q, 0, \lambda) = 0
        \qquad \text{(static: unknowns } q, \lambda \text{)} \\
        \Phi_q \dot q + \Phi_t &= 0, \quad \Phi_q^T \lambda - Q(t, q, \dot q, \lambda) = 0
        \qquad \text{(kinematic: } \dot q, \lambda \text{ at fixed } q \text{)} \\
        M \ddot q + \Phi_q^T \lambda &= Q(t, q, \dot q, \lambda) + Q_v(q, \dot q), \quad
        \Phi_q \ddot q = \gamma \qquad \text{(dynamic: } \ddot q, \lambda \text{)}

    with :math:`\gamma = -(v_q \dot q + v_t)`, :math:`v = \Phi_q \dot q + \Phi_t` (the
    velocity equations, differentiated once more). The
    dynamic system is linear in :math:`(\ddot q, \lambda)` unless a load depends on the
    multipliers (friction: then Newton); ``simulate`` integrates it over time.

    With velocity constraints each kind adds :math:`A^T \mu` to its balance and their rows
    to its constraints (decision 0055): static :math:`b(q, t) = 0` (rest allowed), kinematic
    :math:`A \dot q + b = 0`, dynamic :math:`A \ddot q = -\rho` (with loads that depend on
    the multipliers or accelerations, the same Newton on the bordered system, decision 0068;
    not yet through switches). The static equilibria then
    form a family (the constraints remove velocities, not positions): the solve ends on one
    near the start, keeping the coordinates given in ``initial_condition``.

    Example (a wheel held by rolling on a slope: the friction is ``m g sin(slope)``)::

        eq = m.free(solution="static").solve(initial_condition={"wheel.x": 2.0})
        roll.tangential_force(eq)
    """

    def __init__(self, model, drop=(), solution: str = "dynamic", initial_guess=None,
                 initial_condition=None):
        choice(solution, KINDS, "free(solution=...)")
        self.model = model
        drop = drop if isinstance(drop, (list, tuple)) else [drop]
        self.dropped = [model.constraint(c) for c in drop]
        self.kind = solution
        # velocity (nonholonomic) constraints: rows A qd + b = 0 beside Phi = 0 (decision 0053)
        self.velocity_constraints = velocity_constraints(model, self.dropped)
        self.system = model._system_without(self.dropped + self.velocity_constraints
                                            + self._held_apart())
        if self.system.n == 0:
            raise ModelError("free(): the model has no moving bodies (or variables); add bodies "
                             "before freeing constraints")
        self._full, self._redundancy = self.system, None
        if solution == "static" and not model.load_list:
            raise ModelError(
                "free(solution='static'): the model has no loads, so every configuration the "
                "kept constraints allow is an equilibrium; add the loads (m.add_load) that "
                "determine it")
        self._eq = self._eqv = None
        # parameter values given here: {index in layout.p_symbols: value}, kept for every call
        self._p_given: dict[int, float] = {}
        self._q0, self._qd0 = self._state_from(
            initial_guess if initial_guess is not None else model.last_solution)
        # redundant but consistent kept constraints (Adams): the independent equations at
        # the start configuration are solved, the others' reactions shared (minimum norm)
        self.system, self._redundancy, _ = model._independent(self._full, 0.0, self._q0,
                                                               "free motion")
        if self.system.m > self.system.n:
            raise ModelError(f"free system is still overconstrained ({self.system.m} equations,"
                             f" {self.system.n} coordinates)")
        self._vrows = None
        every = self.velocity_constraints + self._held_apart()
        if every and not self._newton_with_rows:
            # (free motion holds them: the Newton of free_acceleration on the bordered
            # system, decision 0068; the stage-by-stage stepper of switches does not yet)
            dyn = self.system.dynamics
            if dyn.depends_on_lambda or dyn.depends_on_qdd:
                raise ModelError(
                    "free(): loads that depend on multipliers (friction) or accelerations "
                    "together with velocity constraints "
                    f"({', '.join(c.label() for c in every)}) in a model with stage or time "
                    "switches or event loads are not supported yet; remove those loads, the "
                    "velocity constraints or the switches")
        if self.velocity_constraints:
            # (the equilibria do not use rho = d(A qd + b)/dt: not derived for them)
            self._vrows = VelocityRows(model, self.system, self.velocity_constraints,
                                       rho=solution == "dynamic")
        self.dof = self.system.n - self.system.m - (self._vrows.k if self._vrows else 0)
        self._held0: dict = {"q": set(), "qd": set()}
        if initial_condition is not None:
            self._q0, self._qd0, self._p_given = self._apply_condition(
                initial_condition, self._q0, self._qd0, self._held0)

    #: whether loads that depend on the multipliers or accelerations may stand beside
    #: velocity constraints (the Newton on the bordered system, decision 0068)
    _newton_with_rows = True

    def _held_apart(self) -> list:
        """Velocity constraints held as rows of their own besides ``velocity_constraints``:
        none here (those inside the stages of switches, :class:`SwitchedFreeSystem`)."""
        return []

    # -- properties ------------------------------------------------------------------------
    @property
    def linear(self) -> bool:
        dyn = self.system.dynamics
        if dyn.depends_on_lambda:
            return False
        if self.kind == "dynamic" and dyn.depends_on_qdd and not dyn.linear_in_qdd:
            return False
        if self.kind == "kinematic":
            # linear in the velocities: no first derivative depends on a velocity (works for
            # any expression, e.g. Abs, tanh, sqrt, not only polynomials)
            qd = set(self.system.layout.qd_symbols)
            return not any(e.diff(v).free_symbols & qd
                           for e in dyn.Q for v in e.free_symbols & qd)
        return True

    def __repr__(self) -> str:
        names = ", ".join(c.name for c in self.dropped) or "none"
        if self.velocity_constraints:
            names += "; velocity constraints " + ", ".join(
                c.name for c in self.velocity_constraints)
        return (f"<FreeSystem ({self.kind}): dropped {names}; {self.dof} DOF; "
                f"{'linear' if self.linear else 'nonlinear'}>")

    def linearize(self, state=None, inputs=(), outputs=(), coordinates=None, cyclic=(),
                  t: float | None = None, tolerance: float = 1e-6, speeds=None):
        r"""Linearise about an equilibrium or a steady motion to state space
        :math:`\dot x = A x + B u`, :math:`y = C x + D u` (a :class:`~mechsys.LinearSystem`
        with ``A, B, C, D``, ``eigenvalues``, per-eigenvalue ``stability`` and
        ``to_scipy()``). ``state``: a Solution/State or a mapping of coordinate, velocity
        and parameter values (the free system's start by default); ``inputs``: parameter
        names (the loads' magnitudes); ``outputs``: names or expressions of the state;
        ``coordinates``: the state's coordinates (names or expressions; default independent
        coordinates chosen by column-pivoted QR); ``cyclic``: coordinates whose positions
        leave the state; ``speeds`` (with velocity constraints, rolling): the chosen
        coordinates whose rates are the independent velocities (default chosen by QR). A
        state that is not steady raises :class:`~mechsys.NotSteadyError`. See
        ``docs/vibration.md`` (state space) and decisions 0047, 0054.

        Example::

            lin = m.free().linearize(eq, inputs=["F"], outputs=["cart.x"])
            lin.eigenvalues, lin.stable, lin.to_scipy()
        """
        from ._linearize import linearize

        return linearize(self, state, inputs=inputs, outputs=outputs, coordinates=coordinates,
                         cyclic=cyclic, t=t, tolerance=tolerance, speeds=speeds)

    # -- initial conditions -----------------------------------------------------------------
    def _params(self, given=None) -> np.ndarray:
        """Parameter values now: the model's (by symbol, so parameters declared after
        ``free()`` do not shift them), then this FreeSystem's, then the call's overrides."""
        values = self.model._params
        p = np.array([values[s] for s in self.system.layout.p_symbols], dtype=float)
        for over in (self._p_given, given or {}):
            for i, v in over.items():
                p[i] = v
        return p

    def _state_from(self, base):
        """Start ``(q, qd)`` from a Solution/State, a mapping (on top of the model's last
        solution or guesses) or ``None`` (the model's guesses, zero velocities)."""
        n = self.system.n
        if base is None:
            return self.model.guess(), np.zeros(n)
        if isinstance(base, (Solution, State)):
            return self._from_solution(base, np.zeros(n), "initial_guess")
        if isinstance(base, Mapping):
            q, qd = self._state_from(self.model.last_solution)
            q, qd, given = self._apply_condition(base, q, qd)
            if given:
                raise ModelError(f"initial_guess: parameter values {sorted(given)} belong in "
                                 "initial_condition= (or m.set_parameters)")
            return q, qd
        raise ModelError(f"initial_guess must be a Solution, State or mapping, got {base!r}")

    def _from_solution(self, sol, qd, what):
        n = self.system.n
        q = np.atleast_2d(sol.q)[-1].copy()
        if q.shape != (n,):
            raise ModelError(f"{what}: the solution has {q.size} coordinates, this free system "
                             f"{n}; it belongs to another model (or the model changed)")
        if sol.qd is not None:
            qd = np.atleast_2d(sol.qd)[-1].copy()
        return q, qd

    def _apply_condition(self, cond, q, qd, held=None):
        """``(q, qd, {parameter index: value})`` with ``cond`` applied on top of ``q, qd``;
        ``held`` (a dict of two sets ``"q"``, ``"qd"``), when given, collects the indices of
        the coordinates and velocities the mapping sets: the start projection keeps them."""
        q, qd = q.copy(), qd.copy()
        held = {"q": set(), "qd": set()} if held is None else held
        if isinstance(cond, (Solution, State)):
            q, qd = self._from_solution(cond, qd, "initial_condition")
            return q, qd, {}
        if not isinstance(cond, Mapping):
            raise ModelError("initial_condition must be a Solution, State or a mapping of "
                             "coordinate / velocity ('<name>_d') / parameter values, or "
                             "('omega'|'omega_local', body): angular velocity")
        lay = self.system.layout
        pnames = [s.name for s in lay.p_symbols]
        given = {}
        angular = []
        for k, v in cond.items():
            if isinstance(k, tuple) and len(k) == 2 and k[0] in ("omega", "omega_local"):
                if is_quantity(v):      # an angular velocity: 1/time (rad/s, rpm, deg/s)
                    v = _in_model_units(v, self.model.units, f"initial_condition {k!r}",
                                        (0, 0, -1))
                angular.append((k[0], k[1], self._angular_value(k, v)))
                continue
            name = k.name if hasattr(k, "name") else str(k)
            if is_quantity(v):
                v = _in_model_units(v, self.model.units, f"initial_condition {name!r}",
                                    self._condition_dims(name, pnames))
            try:
                value = float(v)
            except (TypeError, ValueError):
                raise ModelError(f"initial_condition: the value of {name!r} must be a number, "
                                 f"got {v!r}") from None
            if not np.isfinite(value):
                raise ModelError(f"initial_condition: the value of {name!r} is {value}; give "
                                 "a finite number")
            if name in pnames:
                given[pnames.index(name)] = value
                continue
            target, key = (qd, name[:-2]) if name.endswith("_d") else (q, name)
            try:
                i = lay.index(key)
                target[i] = value
                held["qd" if target is qd else "q"].add(i)
            except ModelError:
                raise ModelError(f"initial_condition: {name!r} is not a coordinate, velocity "
                                 "('<coordinate>_d') or parameter of this model") from None
        for kind, body, w in angular:
            self._set_angular_velocity(q, qd, body, w, local=(kind == "omega_local"))
            sl = lay.body_slices[self.model.body(body).name]
            held["qd"].update(range(sl.start + self.model.space.dim, sl.stop))
            # kept as an angular velocity: the rates follow the attitude the start
            # projection gives (a changed length parameter turns the body a little)
            held.setdefault("omega", []).append((kind, body, w))
        return q, qd, given

    def _angular_value(self, key: tuple, v):
        """An angular velocity of an initial condition checked: a finite number in the
        plane, three finite numbers in space; :class:`ModelError` naming ``key`` else."""
        dim = self.model.space.dim
        want = "a number" if dim == 2 else "three numbers (wx, wy, wz)"
        try:
            w = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            w = None
        if w is None or w.shape != (() if dim == 2 else (3,)):
            raise ModelError(f"initial_condition {key!r}: an angular velocity in "
                             f"{'the plane' if dim == 2 else 'space'} is {want}, got {v!r}")
        if not np.all(np.isfinite(w)):
            raise ModelError(f"initial_condition {key!r}: the angular velocity is {v!r}; give "
                             f"{want}, finite")
        return float(w) if dim == 2 else w

    def _condition_dims(self, name: str, pnames: list) -> tuple | None:
        """The dimension ``(length, mass, time)`` a quantity given for ``name`` in an initial
        condition must have: a position coordinate a length, an angle or Euler parameter
        none, each ``_d`` one time less; None (its own) for a parameter or model variable."""
        from ..results._tables import _translational

        if name in pnames:
            return None
        rate = name.endswith("_d")
        key = name[:-2] if rate else name
        try:
            j = self.system.layout.index(key)
        except ModelError:
            return None                 # the unknown name is refused below, by name
        kind = _translational(self.system)[j]
        if kind is None:
            return None
        return (1 if kind else 0, 0, -1 if rate else 0)

    def _set_angular_velocity(self, q, qd, body, w, local):
        """Euler-parameter rates from an angular velocity: ``e_dot = E^T w / 2`` (global) or
        ``G^T w' / 2`` (local). Key: ``("omega", body)`` or ``("omega_local", body)``."""
        b = self.model.body(body)
        if b.gen_joint is not None:
            raise ModelError(f"initial_condition ({'omega'}, {b.name!r}): body {b.name!r} is the "
                             f"slave of {b.gen_joint.label()}; give the rates of its generalized "
                             f"coordinates ({', '.join(s.name + '_d' for s in b.gen_joint.coordinates)})")
        sl = self.system.layout.body_slices[b.name]
        if self.model.space.dim == 2:
            if len(q[sl]) == 4:  # orientation="euler": (ei, ej)' = w (-ej, ei)
                qd[np.arange(sl.start, sl.stop)[2:]] = self.model.space.rates_from_omega(q[sl][2:], float(w))
                return
            qd[sl][2] = float(w)
            return
        e0, e1, e2, e3 = q[sl][3:]
        s = -1.0 if local else 1.0
        E = np.array([[-e1, e0, -s * e3, s * e2], [-e2, s * e3, e0, -s * e1],
                      [-e3, -s * e2, s * e1, e0]])
        idx = np.arange(sl.start, sl.stop)[3:]
        qd[idx] = 0.5 * E.T @ np.asarray(w, dtype=float)

    def _start(self, initial_condition):
        """``(q, qd, p)`` of a call: the FreeSystem's start, ``initial_condition`` on top, and
        the parameters as they are now (the loads' stiffnesses, damping and friction
        coefficients checked with them: :func:`~mechsys.loads._loads.check_load_values`)."""
        held = {k: (list(v) if k == "omega" else set(v)) for k, v in self._held0.items()}
        if initial_condition is None:
            q, qd, p = self._q0.copy(), self._qd0.copy(), self._params()
        else:
            q, qd, given = self._apply_condition(initial_condition, self._q0, self._qd0, held)
            p = self._params(given)
        if self.model._loads:
            check_load_values(self.model._loads, dict(zip(self.system.layout.p_symbols, p)))
        return q, qd, p, held

    def _project_start(self, t, q, qd, p, held, scaling):
        """The start state on the constraints, keeping the values the user gave (the rest
        changes least); values the constraints do not allow are a ModelError naming them."""
        try:
            if held.get("omega") and self.system.m:
                # positions first, then the held angular velocities' Euler-parameter rates
                # on the attitude reached (rates derived on the unprojected attitude do not
                # satisfy its normalisation's rate, and holding them would fail)
                qd = qd.copy()
                q = hold_positions(self.system, t, q, p, scaling, sorted(held["q"]))
                for kind, body, w in held["omega"]:
                    self._set_angular_velocity(q, qd, body, w, local=(kind == "omega_local"))
            q, qd = project_holding(self.system, t, q, qd, p, scaling, sorted(held["q"]),
                                    sorted(held["qd"]))
            if self._vrows is None:
                return q, qd
            # the velocities once more, with the velocity constraints' rows A qd + b = 0
            qd, left = project_velocities(self.system, self._vrows, t, q, qd, p, scaling,
                                          sorted(held["qd"]))
            if left > 1e-8:
                raise ConsistencyError("velocities", left)
            return q, qd
        except ConsistencyError as exc:
            names = self.system.layout.q_names
            given = ([names[i] for i in sorted(held["q"])] if exc.held == "positions"
                     else [names[i] + "_d" for i in sorted(held["qd"])])
            raise ModelError(
                f"initial_condition: the given {exc.held} {given} are not allowed by the kept "
                f"constraints (scaled residual {exc.residual:.2e} left when they are held); "
                "give fewer of them (the others follow) or values that satisfy the "
                "constraints") from None

    def _result(self, t, Q, QD, QDD, LAM, p, its, extra=None, scalar=False):
        N = len(t)
        system = self.system
        if self._redundancy is not None:
            from ..solvers._rank import constraint_names as _constraint_names
            from ..solvers._rank import expand_multipliers

            system, d = self._full, self._redundancy
            extra = dict(extra or {}, redundant=_constraint_names(d.owners),
                         indeterminate=_constraint_names(d.involved))
            if LAM is not None:
                LAM = np.asarray(LAM).reshape(N, -1)
                LAM, MU = LAM[:, :self.system.m], LAM[:, self.system.m:]
                LAM = np.array([expand_multipliers(
                    J := system.jacobian(tk, qk, p), self.system.jacobian(tk, qk, p), lk,
                    Scaling.of(system, qk, J)) for tk, qk, lk in zip(t, np.asarray(Q).reshape(
                        N, -1), LAM)])
                LAM = np.hstack((LAM, MU))       # (the velocity constraints' mu after them)
        sol = Solution(t=np.asarray(t, dtype=float), q=np.asarray(Q).reshape(N, -1),
                       qd=None if QD is None else np.asarray(QD).reshape(N, -1),
                       qdd=None if QDD is None else np.asarray(QDD).reshape(N, -1),
                       p=p, system=system, model=self.model,
                       iterations=np.asarray(its, dtype=int).reshape(N), scalar=scalar,
                       lam=None if LAM is None else np.asarray(LAM).reshape(N, -1),
                       mode=f"free-{self.kind}", extra=extra or {})
        if self._vrows is not None:
            # the velocity constraints' multipliers: sol.lam[:, m:], named per row here
            sol.extra["velocity_multipliers"] = row_names(self._vrows)
            if sol.lam is not None:
                sol.extra["mu"] = sol.lam[:, system.m:]
        return sol
        return sol

    def _newton(self, tolerance, max_iterations, what):
        """Newton options; for the free acceleration only where Newton runs (loads depending
        on multipliers or accelerations): elsewhere they would be ignored, so they raise."""
        kw = newton_options(tolerance, max_iterations, what)
        dyn = self.system.dynamics if kw and self.kind == "dynamic" else None
        if dyn is not None and not (dyn.depends_on_lambda or dyn.depends_on_qdd):
            raise ModelError(
                f"{what}: tolerance and max_iterations control the Newton iteration, which this "
                "free acceleration does not use (no loads depend on multipliers or "
                "accelerations, so it is one linear solve); leave them out")
        return kw

    def _check_rest_allowed(self, t, q, p):
        """A static equilibrium is at rest: a velocity constraint whose term ``b(t)`` does not
        depend on the coordinates and does not vanish (a conveyor's prescribed speed) allows
        no rest anywhere; raise naming it (a ``b`` depending on ``q`` is a residual row of the
        Newton iteration instead)."""
        rows = self._vrows
        qs = set(self.system.layout.q_symbols)
        A, b, _ = rows.evaluate(t, q, np.zeros(self.system.n), p)
        # (unit-free: b over the row's scale, a rate in units of the length scale; a b that
        # is zero up to rounding, sin(pi) say, allows rest)
        r = scaling_at(self.system, t, q, p).rows(A)
        for e, c, value, ri in zip(rows.b_sym, rows.owners, b, r):
            if not (e.free_symbols & qs) and abs(value) > 1e-12 * ri:
                raise ModelError(
                    f"free(solution='static'): the velocity constraint {c.label()} does not "
                    f"allow rest (its term b = {value:.6g} in A qd + b = 0 does not vanish at "
                    "zero velocities), so the model has no static equilibrium; use "
                    "solution='kinematic' for the balance of velocity-dependent loads, or "
                    "simulate the motion")

    # -- single-state analyses ---------------------------------------------------------------
    def solve(self, t: float = 0.0, initial_condition=None, lambda_guess=None,
              tolerance: float | None = None, max_iterations: int | None = None) -> Solution:
        """Equilibrium configuration, equilibrium velocity or free acceleration at ``t``
        (by ``kind``). Returns a one-point :class:`Solution` (``q, qd, qdd, lam``).

        ``tolerance`` (equilibria: default 1e-12 on the unit-free residual — positions in
        units of the characteristic length, multipliers in units of the loads, each equation
        divided by its scale — relative to ``1 + max|q / L|``; free acceleration: 1e-10
        relative to the loads) and
        ``max_iterations`` (default 50; 30 for the free acceleration) control the Newton
        iteration of the equilibria and of a free acceleration whose loads depend on the
        multipliers (friction) or accelerations (Mech's ``SolveFree`` Newton options); a
        linear free acceleration takes no Newton options. ``lambda_guess`` starts the
        multipliers (default 1, as Mech)."""
        if isinstance(t, bool) or not isinstance(t, Real) or not np.isfinite(t):
            raise ModelError(f"solve(t): t must be a finite number, got {t!r}")
        t = float(t)
        kw = self._newton(tolerance, max_iterations, "FreeSystem.solve")
        q, qd, p, held = self._start(initial_condition)
        s = self.system
        lam0 = lambda_guess_vector(s, self.model, lambda_guess)
        rows = self._vrows
        if rows is not None and self.kind != "dynamic":
            # the velocity constraints' multipliers mu (the equilibria are linear in them)
            lam0 = np.concatenate((lam0, np.zeros(rows.k)))
        if self.kind == "static":
            if rows is not None:
                self._check_rest_allowed(t, q, p)
            if self._eq is None:
                from ..compile._free import StaticEquilibrium

                self._eq = StaticEquilibrium(s, rows)
            q, lam, its = equilibrium_configuration(self._eq, s, t, q, lam0, p, rows=rows,
                                                    held=sorted(held["q"]), **kw)
            return self._result([t], q, np.zeros_like(q), None, lam, p, [its], scalar=True)
        if self.kind == "kinematic":
            if self._eqv is None:
                from ..compile._free import VelocityEquilibrium

                qd_syms = set(s.layout.qd_symbols)
                if not any(e.free_symbols & qd_syms for e in s.dynamics.Q):
                    raise ModelError(
                        "free(solution='kinematic'): no load depends on the velocities, so no "
                        "velocity is an equilibrium (or every one is); add velocity-dependent "
                        "loads (dampers, speed-dependent moments). Inertial (centrifugal) terms "
                        "do not count, as in Mech")
                self._eqv = VelocityEquilibrium(s, rows)
            qd, lam, its = equilibrium_velocity(self._eqv, s, t, q, qd, lam0, p, rows=rows,
                                                **kw)
            return self._result([t], q, qd, None, lam, p, [its], scalar=True)
        # a free acceleration is only meaningful at a state the kept constraints allow: an
        # initial condition that is not (say only a crank speed) is projected onto them first,
        # as simulate() does (smallest change in the unit-free coordinates)
        q, qd = self._project_start(t, q, qd, p, held, scaling_at(s, t, q, p))
        if self._vrows is not None:
            # (mu starts at 1 as lambda does, for a friction load's Newton)
            guess = None if lambda_guess is None else np.concatenate(
                (lam0, np.ones(self._vrows.k)))
            qdd, lam = nonholonomic_acceleration(s, self._vrows, t, q, qd, p, guess, **kw)
            return self._result([t], q, qd, qdd, lam, p, [0], scalar=True)
        qdd, lam, its = free_acceleration(s, t, q, qd, p, lam0 if lambda_guess is not None
                                          else None, **kw)
        return self._result([t], q, qd, qdd, lam, p, [its], scalar=True)

    # -- motion synthesis --------------------------------------------------------------------
    def simulate(self, t, initial_condition=None, method: str = "dop853", rtol: float = RTOL,
                 atol: float = ATOL, max_step: float = MAX_STEP, fit_degree=FIT_DEGREE,
                 max_error=MAX_ERROR, step_size=None, constraint_correction: bool = True,
                 diagnostics: bool = False, tolerance: float | None = None,
                 max_iterations: int | None = None, progress=None,
                 starting_step_size: float | None = None, **unknown) -> Solution:
        """Integrate the free motion (Mech's ``SolveFree[fs, {t0, t1}]``).

        ``t``: ``(t0, t1)`` returns every accepted step; an array of strictly increasing (or,
        backwards, decreasing) finite times returns those times (dense output). Unsorted
        times, a single number or non-finite times raise :class:`ModelError` (for one instant
        use :meth:`solve`).

        ``method``: ``"dop853"`` (default) or ``"rk45"`` with ``rtol``/``atol``/``max_step``;
        ``"adams"`` (= ``"automatic"``), ``"predictor"`` or ``"corrector"`` for Mech's
        multistep integrator with ``fit_degree``, ``max_error`` and ``step_size``.
        ``max_error`` (Mech's accuracy option) works with every method: for the Runge-Kutta
        methods it sets ``rtol = atol = max_error``, so the local error of each coordinate
        and velocity per step stays below about ``max_error (1 + |y|)``; for Adams it is the
        step threshold ``a`` (or ``(a, b, c)``). An option that does not apply to the chosen
        method, or an unknown one, raises :class:`ModelError`. ``starting_step_size`` (Mech's
        ``StartingStepSize``): the first step an adaptive run tries (every method; not with a
        constant ``step_size``). ``tolerance``/
        ``max_iterations``: Newton options of the free acceleration (as :meth:`solve`).
        The initial state is projected onto the constraints first. See
        ``solvers/_integrators.py``.

        ``progress``: show a progress bar (tqdm: a text bar on stderr, a widget in Jupyter;
        ``None``, the default: only on a terminal, once the run has taken 2 s), or a callable
        ``progress(done, total)`` with the time span covered so far and the whole one. Either is
        advanced between the compiled stepper's chunks, so it costs nothing measurable. Ctrl-C
        (KeyboardInterrupt, also one raised by the callable) during the integration returns the
        solution so far, with ``sol.extra["interrupted"] = True`` and a warning (see docs/robustness_fuzz.md).
        """
        run = plan_run("FreeSystem.simulate", t, unknown, (
            "initial_condition", "method", "rtol", "atol", "max_step", "fit_degree", "max_error",
            "step_size", "constraint_correction", "diagnostics", "tolerance", "max_iterations",
            "progress", "starting_step_size"), method, rtol, atol, max_step, fit_degree,
            max_error, step_size, constraint_correction, starting_step_size,
            to_numbers=time_numbers(self.model))
        check_progress(progress, "FreeSystem.simulate")
        if self.kind != "dynamic":
            raise MechError("simulate() integrates the free motion: build the FreeSystem with "
                            "solution='dynamic'")
        opt, t0, t_stop, t_eval = run.options, run.t0, run.t1, run.t_eval
        kw = self._newton(tolerance, max_iterations, "FreeSystem.simulate")
        s = self.system
        n = s.n
        q0, qd0, p, held = self._start(initial_condition)
        sc = scaling_at(s, t0, q0, p)          # units of the coordinates, once per run
        q0, qd0 = self._project_start(t0, q0, qd0, p, held, sc)
        lam_box = [None]

        # loads linear in the multipliers: singular instants are passed (solvers/_rank.py)
        vrows = self._vrows
        robust = s.m > 0 and not (s.dynamics.depends_on_lambda or s.dynamics.depends_on_qdd) \
            and vrows is None      # (passing singular instants: holonomic rows only)
        zone = [False]                 # a derivative of this step came from the zone
        guard = None
        # (sparse above SPARSE_THRESHOLD coordinates: the same row maxima, without a dense
        # m x n Jacobian)
        J0 = s.jacobian(t0, q0, p, n > SPARSE_THRESHOLD) if robust else None
        rows0 = sc.rows(J0) if robust else None
        if robust:
            inner = zone_guard(s, sc, rows0)

            def guard(K, b, x):
                return _flag(zone, inner(K, b, x))

        def accel(tt, y, lam_guess=None):
            if vrows is not None:
                qdd, lam = nonholonomic_acceleration(s, vrows, tt, y[:n], y[n:], p, lam_guess,
                                                     columns=sc.columns, **kw)
                return y[n:], qdd, lam
            qdd, lam, _ = free_acceleration(s, tt, y[:n], y[n:], p, lam_guess, guard=guard,
                                            columns=sc.columns, **kw)
            return y[n:], qdd, lam

        def rhs(tt, y):
            qd, qdd, lam = accel(tt, y, lam_box[0])
            if s.dynamics.depends_on_lambda:
                lam_box[0] = lam
            return np.concatenate((qd, qdd))

        _check_independent(s, t0, q0, p, sc, None if rows0 is None else J0)

        def proj(tt, y):
            if vrows is not None:
                qq, vv = project_state(s, vrows, tt, y[:n], y[n:], p, sc)
                return np.concatenate((qq, vv))
            # rank-tolerant: the motion passes through singular instants (links collinear)
            try:
                qq, vv = project(s, tt, y[:n], y[n:], p, scaling=sc, rank_tolerant=robust)
            except InZone:
                qq, vv = project_regularized(s, tt, y[:n], y[n:], p, sc)
            return np.concatenate((qq, vv))

        def kinked():
            out, zone[0] = zone[0], False
            return out

        # the bar (or the user's callable) advances between the compiled stepper's chunks;
        # by default (progress=None, on a terminal) the bar appears once a run takes 2 s
        span = abs(t_stop - t0) or 1.0
        report, close = reporter(progress, span, "simulate", "", "FreeSystem.simulate",
                                 delay=2.0 if progress is None else 0.0, steps=1000)

        def monitor(tt):
            report(min(abs(tt - t0), span))

        # the compiled stepper (solvers/_jit_free.py) takes the regular steps when it can
        fast = FreeStepper.plan(s, opt.method, p, sc, rows0, robust, opt.correction,
                                t_eval, (t0, q0), newton=kw, rows=vrows)
        try:
            times, Y, res, m = integrate(rhs, proj, run, np.concatenate((q0, qd0)),
                                         scale=np.concatenate((sc.columns, sc.columns)),
                                         monitor=monitor if report is not None else None,
                                         kinked=kinked if robust else None, fast=fast)
        finally:
            close()
        # accelerations and multipliers: from the compiled stepper where it ran, else here
        QDD, LAM = res.diagnostics.get("derivatives") or (np.full((len(times), n), np.nan),
                                                          np.full((len(times), s.m + (
                                                              0 if vrows is None else vrows.k)),
                                                              np.nan))
        for k in np.nonzero(~(np.isfinite(QDD).all(axis=1) & np.isfinite(LAM).all(axis=1)))[0]:
            got = None if fast is None else fast.derivative(times[k], Y[k])
            if got is None:
                _, QDD[k], LAM[k] = accel(times[k], Y[k])
            else:
                QDD[k], LAM[k] = got[0][n:], got[1]
        extra = {"evaluations": res.evaluations, "steps": res.steps, "rejected": res.rejected,
                 "method": m, "length_scale": sc.length,
                 "compiled_steps": res.diagnostics.get("compiled_steps", 0),
                 "interpreted_steps": res.diagnostics.get("interpreted_steps", 0),
                 "compiled_solver": None if fast is None else fast.solver}
        if opt.runge_kutta:
            extra["rtol"], extra["atol"] = opt.rtol, opt.atol
        else:
            extra["max_error"] = opt.max_error
        # the run's own measure of its accuracy: constraint drift, coordinates' range
        extra["accuracy"] = accuracy_report(s, sc, times, Y, p, opt.rtol if opt.runge_kutta
                                         else opt.max_error[0], "FreeSystem.simulate")
        if vrows is not None:
            nonholonomic_accuracy(s, vrows, times, Y, p, sc, opt.rtol if opt.runge_kutta
                                  else opt.max_error[0], extra["accuracy"],
                                  "FreeSystem.simulate")
        if diagnostics:
            extra["diagnostics"] = res.diagnostics
        if res.message == "interrupted":
            import warnings

            extra["interrupted"] = True
            warnings.warn(f"simulate: interrupted at t = {times[-1]:.6g} (of {t_stop:.6g}); "
                          "returning the solution so far (sol.extra['interrupted'])",
                          RuntimeWarning, stacklevel=2)
        return self._result(times, Y[:, :n], Y[:, n:], QDD, LAM, p, np.zeros(len(times)),
                            extra=extra)


def nonholonomic_accuracy(s, vrows, times, Y, p, sc, tol, accuracy: dict, what: str) -> None:
    """``accuracy["nonholonomic"]``: the velocity constraints' scaled drift at the end of a
    run (:func:`~mechsys.analyses._nonholonomic.velocity_drift`), with a
    :class:`~mechsys.DegradedAccuracyWarning` above ``max(DRIFT_WARNING, DRIFT_FACTOR
    tol)`` (as :func:`accuracy_report` for the holonomic rows)."""
    n = s.n
    if not len(times) or not np.all(np.isfinite(Y[-1])):
        return
    drift = velocity_drift(s, vrows, times[-1], Y[-1, :n], Y[-1, n:], p, sc)
    accuracy["nonholonomic"] = drift
    bound = max(DRIFT_WARNING, DRIFT_FACTOR * tol)
    if drift > bound:
        import warnings

        from .._errors import DegradedAccuracyWarning

        warnings.warn(DegradedAccuracyWarning(
            f"{what}: the velocity constraints have drifted by the end of "
            f"the run (t = {times[-1]:.6g}): residual {drift:.2e} relative to the largest "
            f"rate, above {bound:.0e}; keep constraint_correction=True (the default) or "
            "tighten rtol/max_error (sol.extra['accuracy'])", measure=drift,
            threshold=bound), stacklevel=3)
        accuracy["warned"] = "nonholonomic"


def _in_model_units(value, units, what: str, dims):
    """A pint quantity (a number or an array: a 3D angular velocity) as numbers in the model's
    units, its dimension checked against ``dims`` when given: the magnitude times the
    conversion factor of its unit (the units here are linear: lengths, times, angles)."""
    factor = number(1 * value.units, units, what, dims)
    return np.asarray(value.magnitude, dtype=float) * factor
