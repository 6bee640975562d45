r"""Locked configurations (Mech's ``LockMech``, manual 12.5): a mechanism analysed again and
again at one configuration, for changing loads or inertia.

``m.lock(at, solution="location")`` solves (or takes) the configuration once and keeps the
coordinates ``q`` (and, with ``solution="velocity"`` or ``"acceleration"``, the velocities
``qd`` and accelerations ``qdd``); :meth:`LockedModel.solve` then gives static, kinematic or
inverse-dynamic solutions for new parameter values without solving the positions again:

.. math::  \Phi_q^T \lambda = Q(t, q, \dot q, p)  \quad\text{(static)}, \qquad
           \Phi_q^T \lambda = Q + Q_v - M \ddot q  \quad\text{(dynamic)}

with the orders not locked (velocities, accelerations) recomputed from
:math:`\Phi_q \dot q = -\Phi_t` and :math:`\Phi_q \ddot q = \gamma` for the new parameters.

Locking is only valid while the locked state still satisfies the constraints: a parameter
that moves the geometry (a length) would leave the locked coordinates wrong. Each solve
therefore checks the locked orders against the constraint equations with the new values
(on the unit-free scaled equations, see :class:`~mechsys.solvers._linalg.Scaling`) and
raises a :class:`~mechsys.ModelError` naming the parameters changed, instead of returning
reactions of an impossible configuration. A model changed after locking (bodies,
constraints, loads) must be locked again.

Example::

    pos = m.solve(0.1)                     # the configuration
    locked = m.lock(pos)
    for k in np.linspace(0, 1, 11):
        sol = locked.solve("static", parameters={"k": k})
        print(k, sol.reaction("slider"))
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import sympy as sp

from .._errors import ModelError, choice, parameter_value

#: largest scaled violation of a locked order by new parameter values (the position
#: solve converges to 1e-12; a geometry change of a part in 1e9 is a real change)
LOCK_TOL = 1e-9

_ORDERS = {"location": 0, "velocity": 1, "acceleration": 2}
_MODES = {"static": 0, "kinematic": 1, "dynamic": 2}


class LockedModel:
    """A model frozen at one configuration: see the module docstring.

    Attributes: ``t`` (float), ``q`` (n,), ``qd``/``qdd`` ((n,) or None when not locked),
    ``order`` (0 location, 1 velocity, 2 acceleration), ``parameters`` (the values at the
    lock, ``{name: value}``).
    """

    def __init__(self, model, at=0.0, solution: str = "location", guess=None):
        choice(solution, list(_ORDERS), "lock: solution", "the highest order to lock")
        if model._switches():
            raise ModelError("lock: models with StageSwitch/TimeSwitch constraints cannot be "
                             "locked (the stage would be frozen with the coordinates); solve "
                             "them with m.solve")
        order = _ORDERS[solution]
        self._model = model
        self.system = model.compile()
        self._version = model._version
        state = _state_of(model, at, solution, guess)
        self.t = float(state.t)
        self.q = np.array(state.q, dtype=float)
        self.qd = None if order < 1 else np.array(state.qd, dtype=float)
        self.qdd = None if order < 2 else np.array(state.qdd, dtype=float)
        self.order = order
        self.parameters = dict(model.parameters)
        self._p0 = model._p()
        from ..solvers._linalg import Scaling

        self._scaling = Scaling.of(self.system, self.q, self.system.jacobian(self.t, self.q, self._p0))

    def solve(self, solution: str = "static", parameters: Mapping | None = None, lambda_guess=None):
        """A :class:`~mechsys.Solution` (one point, at the locked time) for the parameter
        values ``parameters`` (``{name or symbol: value}``; the others keep their values at
        the lock). ``solution``: ``"static"``, ``"kinematic"``, ``"dynamic"``, or a kinematic
        order (``"location"``, ``"velocity"``, ``"acceleration"``)."""
        from ..results._load_outputs import lambda_guess_vector
        from ..results._solution import Solution
        from ..solvers import MultiplierOptions, solve_multipliers
        from ..solvers._kinematics import SweepResult, solve_acceleration, solve_velocity

        choice(solution, [*_ORDERS, *_MODES], "locked solve: solution")
        model, system = self._model, self.system
        if model._version != self._version:
            raise ModelError("locked solve: the model changed after m.lock(...) (bodies, constraints "
                             "or loads); lock it again")
        p, changed = self._parameter_vector(parameters)
        if model._loads:   # stiffnesses, damping, friction given as parameters: not negative
            from ..loads._loads import check_load_values

            check_load_values(model._loads, dict(zip(system.layout.p_symbols, p)))
        t, q = self.t, self.q
        self._check(system.residual(t, q, p), changed, "location")
        need = _ORDERS.get(solution, _MODES.get(solution))
        qd = qdd = None
        if need >= 1:
            if self.qd is not None:
                J, rhs = system.velocity_rhs(t, q, p)
                self._check(J @ self.qd - rhs, changed, "velocity")
                qd = self.qd
            else:
                qd = solve_velocity(system, t, q, p, self._scaling)
        if need >= 2:
            if self.qdd is not None:
                J = system.jacobian(t, q, p)
                self._check(J @ self.qdd - system.gamma_values(t, q, qd, p), changed, "acceleration")
                qdd = self.qdd
            else:
                qdd = solve_acceleration(system, t, q, qd, p, scaling=self._scaling)
        lam = None
        if solution in _MODES:
            opt = MultiplierOptions(lambda_guess=lambda_guess_vector(system, model, lambda_guess))
            lam1, _ = solve_multipliers(system, system.dynamics, t, q, qd, qdd, p, solution, opt)
            lam = lam1[None, :]
        res = SweepResult(np.array([t]), q[None, :].copy(), None if qd is None else qd[None, :].copy(),
                          None if qdd is None else qdd[None, :].copy(), np.zeros(1, dtype=int), 0,
                          min(need, 2))
        sol = Solution.from_sweep(model, system, res, p, scalar=True, lam=lam, mode=solution)
        sol.extra["locked"] = True
        return sol

    # -- helpers ---------------------------------------------------------------------------
    def _parameter_vector(self, parameters):
        p = self._p0.copy()
        if not parameters:
            return p, []
        if not isinstance(parameters, Mapping):
            raise ModelError(f"locked solve: parameters must be a mapping {{name: value}}, got "
                             f"{parameters!r}")
        names = list(self._model._params)
        changed = []
        for key, value in parameters.items():
            s = key if isinstance(key, sp.Symbol) else sp.Symbol(str(key))
            if s not in names:
                raise ModelError(f"locked solve: unknown parameter {key!r}; parameters are "
                                 f"{[x.name for x in names]}")
            v = parameter_value(s.name, value)
            i = names.index(s)
            if v != p[i]:
                changed.append(s.name)
            p[i] = v
        return p, changed

    def _check(self, residual, changed, what):
        r = np.abs(np.asarray(residual, dtype=float))
        if not r.size:
            return
        J = self.system.jacobian(self.t, self.q, self._p0)
        scaled = r / self._scaling.rows(J)
        worst = float(scaled.max())
        if worst > LOCK_TOL * (1.0 + self._scaling.offset):
            i = int(np.argmax(scaled))
            who = (f"the parameter(s) {changed}" if changed else "the parameter values")
            raise ModelError(
                f"locked solve: with {who} the locked {what} no longer satisfies the constraints "
                f"({self.system.layout.row_label(i)} is off by {r[i]:.3e}): these parameters move "
                "the mechanism, so its locked state is not valid for them. Solve with "
                "m.set_parameters(...) and m.solve(...) instead, or lock a lower order.")


def _state_of(model, at, solution, guess):
    """The state to lock: from a Solution (its only or last point) or State, else solved."""
    order = _ORDERS[solution]
    if hasattr(at, "q") and hasattr(at, "system"):
        if hasattr(at, "state"):
            if len(at.t) != 1:
                raise ModelError(f"lock: the solution has {len(at.t)} points; lock one of them with "
                                 "m.lock(sol.state(k))")
            at = at.state(0)
        if at.system is not model.compile():
            raise ModelError("lock: the state is from another model or an older version of this one")
        if order >= 1 and at.qd is None or order >= 2 and at.qdd is None:
            raise ModelError(f"lock: solution={solution!r} needs a state with "
                             f"{'velocities' if order == 1 else 'accelerations'}; solve with "
                             f"solution={solution!r} first")
        return at
    if np.ndim(at) != 0:
        raise ModelError(f"lock: give one time (or a one-point solution or a state), got {at!r}")
    return model.solve(at, solution=solution, guess=guess).state()
