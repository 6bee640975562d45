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
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._errors import MechError, ModelError
from ..results._load_outputs import lambda_guess_vector
from ..results._solution import Solution, State
from ..solvers._free import (
    equilibrium_configuration,
    equilibrium_velocity,
    free_acceleration,
    project,
)
from ..solvers._integrators import integrate

KINDS = ("static", "kinematic", "dynamic")


class FreeSystem:
    """A model with constraints dropped. Attributes: ``model``, ``dropped`` (constraints),
    ``system`` (the compiled System of the kept equations), ``kind``, ``linear`` (whether the
    highest-order unknowns enter linearly: no loads depending on multipliers, and for the
    velocity equilibrium loads linear in velocities), ``dof``."""

    def __init__(self, model, drop=(), solution: str = "dynamic", initial_guess=None,
                 initial_condition=None):
        if solution not in KINDS:
            raise ModelError(f"free(solution=...) must be one of {KINDS}, got {solution!r}")
        self.model = model
        drop = drop if isinstance(drop, (list, tuple)) else [drop]
        self.dropped = [model.constraint(c) for c in drop]
        self.kind = solution
        self.system = model._system_without(self.dropped)
        if self.system.m > self.system.n:
            raise ModelError(f"free system is still overconstrained ({self.system.m} equations,"
                             f" {self.system.n} coordinates)")
        self.dof = self.system.n - self.system.m
        self._eq = self._eqv = None
        base = initial_guess if initial_guess is not None else model.last_solution
        self._q0, self._qd0, self._lam0 = self._state_from(base)
        self._p0 = model._p()
        if initial_condition is not None:
            self._q0, self._qd0, self._p0 = self._apply_condition(initial_condition)

    # -- properties ------------------------------------------------------------------------
    @property
    def linear(self) -> bool:
        dyn = self.system.dynamics
        if dyn.depends_on_lambda:
            return False
        if self.kind == "dynamic" and dyn.depends_on_qdd and not dyn.linear_in_qdd:
            return False
        if self.kind == "kinematic":
            qd = set(self.system.layout.qd_symbols)
            return all(not (e.free_symbols & qd) or e.as_poly(*(e.free_symbols & qd)).is_linear
                       for e in dyn.Q)
        return True

    def __repr__(self) -> str:
        names = ", ".join(c.name for c in self.dropped) or "none"
        return (f"<FreeSystem ({self.kind}): dropped {names}; {self.dof} DOF; "
                f"{'linear' if self.linear else 'nonlinear'}>")

    # -- initial conditions -----------------------------------------------------------------
    def _state_from(self, base):
        n = self.system.n
        if base is None:
            return self.model.guess(), np.zeros(n), None
        if isinstance(base, (Solution, State)):
            q = np.atleast_2d(base.q)[-1].copy()
            qd = np.zeros(n) if base.qd is None else np.atleast_2d(base.qd)[-1].copy()
            lam = None
            return q, qd, lam
        if isinstance(base, Mapping):
            q, qd, _ = self._apply_condition(base)
            return q, qd, None
        raise ModelError(f"initial_guess must be a Solution, State or mapping, got {base!r}")

    def _apply_condition(self, cond, q=None, qd=None, p=None):
        q = self._q0.copy() if q is None else q.copy()
        qd = self._qd0.copy() if qd is None else qd.copy()
        p = self._p0.copy() if p is None else p.copy()
        if isinstance(cond, (Solution, State)):
            q = np.atleast_2d(cond.q)[-1].copy()
            if cond.qd is not None:
                qd = np.atleast_2d(cond.qd)[-1].copy()
            return q, qd, p
        if not isinstance(cond, Mapping):
            raise ModelError("initial_condition must be a Solution, State or a mapping of "
                             "coordinate / velocity ('<name>_d') / parameter values, or "
                             "('omega'|'omega_local', body): angular velocity")
        lay = self.system.layout
        pnames = [s.name for s in lay.p_symbols]
        angular = []
        for k, v in cond.items():
            if isinstance(k, tuple) and len(k) == 2 and k[0] in ("omega", "omega_local"):
                angular.append((k[0], k[1], v))
                continue
            name = k.name if hasattr(k, "name") else str(k)
            if name in pnames:
                p[pnames.index(name)] = float(v)
                continue
            target, key = (qd, name[:-2]) if name.endswith("_d") else (q, name)
            try:
                target[lay.index(key)] = float(v)
            except ModelError:
                raise ModelError(f"initial_condition: {name!r} is not a coordinate, velocity "
                                 "('<coordinate>_d') or parameter of this model") from None
        for kind, body, w in angular:
            self._set_angular_velocity(q, qd, body, w, local=(kind == "omega_local"))
        return q, qd, p

    def _set_angular_velocity(self, q, qd, body, w, local):
        """Euler-parameter rates from an angular velocity: ``e_dot = E^T w / 2`` (global) or
        ``G^T w' / 2`` (local). Key: ``("omega", body)`` or ``("omega_local", body)``."""
        b = self.model.body(body)
        sl = self.system.layout.body_slices[b.name]
        if self.model.space.dim == 2:
            qd[sl][2] = float(w)
            return
        e0, e1, e2, e3 = q[sl][3:]
        s = -1.0 if local else 1.0
        E = np.array([[-e1, e0, -s * e3, s * e2], [-e2, s * e3, e0, -s * e1],
                      [-e3, -s * e2, s * e1, e0]])
        idx = np.arange(sl.start, sl.stop)[3:]
        qd[idx] = 0.5 * E.T @ np.asarray(w, dtype=float)

    def _start(self, initial_condition):
        if initial_condition is None:
            return self._q0.copy(), self._qd0.copy(), self._p0.copy()
        return self._apply_condition(initial_condition)

    def _result(self, t, Q, QD, QDD, LAM, p, its, extra=None, scalar=False):
        N = len(t)
        sol = Solution(t=np.asarray(t, dtype=float), q=np.asarray(Q).reshape(N, -1),
                       qd=None if QD is None else np.asarray(QD).reshape(N, -1),
                       qdd=None if QDD is None else np.asarray(QDD).reshape(N, -1),
                       p=p, system=self.system, model=self.model,
                       iterations=np.asarray(its, dtype=int).reshape(N), scalar=scalar,
                       lam=None if LAM is None else np.asarray(LAM).reshape(N, -1),
                       mode=f"free-{self.kind}", extra=extra or {})
        return sol

    # -- single-state analyses ---------------------------------------------------------------
    def solve(self, t: float = 0.0, initial_condition=None, lambda_guess=None) -> Solution:
        """Equilibrium configuration, equilibrium velocity or free acceleration at ``t``
        (by ``kind``). Returns a one-point :class:`Solution` (``q, qd, qdd, lam``)."""
        q, qd, p = self._start(initial_condition)
        s = self.system
        lam0 = lambda_guess_vector(s, self.model, lambda_guess)
        if self.kind == "static":
            if self._eq is None:
                from ..compile._free import StaticEquilibrium

                self._eq = StaticEquilibrium(s)
            q, lam, its = equilibrium_configuration(self._eq, s, t, q, lam0, p)
            return self._result([t], q, np.zeros_like(q), None, lam, p, [its], scalar=True)
        if self.kind == "kinematic":
            if self._eqv is None:
                from ..compile._free import VelocityEquilibrium

                self._eqv = VelocityEquilibrium(s)
            qd, lam, its = equilibrium_velocity(self._eqv, s, t, q, qd, lam0, p)
            return self._result([t], q, qd, None, lam, p, [its], scalar=True)
        qdd, lam, its = free_acceleration(s, t, q, qd, p, lam0 if lambda_guess is not None
                                          else None)
        return self._result([t], q, qd, qdd, lam, p, [its], scalar=True)

    # -- motion synthesis --------------------------------------------------------------------
    def simulate(self, t, initial_condition=None, method: str = "dop853", rtol: float = 1e-8,
                 atol: float = 1e-10, max_step: float = np.inf, fit_degree="cubic",
                 max_error=1e-4, step_size=None, constraint_correction: bool = True,
                 diagnostics: bool = False) -> Solution:
        """Integrate the free motion (Mech's ``SolveFree[fs, {t0, t1}]``).

        ``t``: ``(t0, t1)`` returns every accepted step; an array returns those times
        (dense output). ``method``: ``"dop853"`` (default) or ``"rk45"`` with ``rtol``/``atol``;
        ``"adams"`` (= ``"automatic"``), ``"predictor"`` or ``"corrector"`` for Mech's
        multistep integrator with ``fit_degree`` and ``max_error``. The initial state is
        projected onto the constraints first. See ``solvers/_integrators.py``.
        """
        if self.kind != "dynamic":
            raise MechError("simulate() integrates the free motion: build the FreeSystem with "
                            "solution='dynamic'")
        s = self.system
        n = s.n
        q0, qd0, p = self._start(initial_condition)
        q0, qd0 = project(s, float(np.atleast_1d(t)[0]), q0, qd0, p)
        lam_box = [None]

        def rhs(tt, y):
            qdd, lam, _ = free_acceleration(s, tt, y[:n], y[n:], p, lam_box[0])
            if s.dynamics.depends_on_lambda:
                lam_box[0] = lam
            return np.concatenate((y[n:], qdd))

        def proj(tt, y):
            qq, vv = project(s, tt, y[:n], y[n:], p)
            return np.concatenate((qq, vv))

        times, Y, res, m = integrate(
            rhs, proj, t, np.concatenate((q0, qd0)), method, rtol, atol, max_step, fit_degree,
            max_error, step_size, constraint_correction)
        QDD = np.empty((len(times), n))
        LAM = np.empty((len(times), s.m))
        for k, (tk, yk) in enumerate(zip(times, Y)):
            QDD[k], LAM[k], _ = free_acceleration(s, tk, yk[:n], yk[n:], p)
        extra = {"evaluations": res.evaluations, "steps": res.steps, "rejected": res.rejected,
                 "method": m}
        if diagnostics:
            extra["diagnostics"] = res.diagnostics
        return self._result(times, Y[:, :n], Y[:, n:], QDD, LAM, p, np.zeros(len(times)),
                            extra=extra)

