r"""Nonholonomic systems (Mech's ``SetPath`` / ``SolvePath``, manual 10.5).

A fully constrained kinematic model carries *dummy* constraints that hold its place; ``path``
replaces them by *velocity constraints* ``psi(q, qd, t) = 0`` (normal constraint objects
whose geometry depends on velocities, e.g. ``Orthogonal1(m.velocity(p), body.vector(...))``,
or a general ``Constraint`` with velocity terms). At each instant the velocities follow
from the kept holonomic constraints and the velocity constraints together::

    Phi_q(q, t) qd + Phi_t(q, t) = 0          (holonomic, m - k rows)
    psi(q, qd, t)                = 0          (nonholonomic, k rows)

(Newton on ``qd``; one step when ``psi`` is linear in ``qd``), and ``q' = qd`` is integrated
with the same integrators as free motion; ``constraint_correction`` projects ``q`` back onto
the holonomic constraints after each step. Accelerations come from the time derivative::

    Phi_q qdd = gamma,      psi_qd qdd = -(psi_q qd + psi_t)
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import sympy as sp

from .._errors import MechError, ModelError, SingularJacobianError
from .._symbols import T
from ..compile import compile_exprs
from ..constraints import ConstraintBase
from ..results._solution import Solution
from ..solvers._free import project_positions
from ..solvers._integrators import integrate
from ..solvers._linalg import Singular, dependent_rows, factor, involved_rows


class PathSystem:
    """A kinematic model with dummy constraints replaced by velocity constraints.

    Attributes: ``model``, ``replaced`` (``{dummy: velocity constraint}``), ``system`` (the
    compiled holonomic part), ``velocity_constraints`` (list), ``linear`` (whether the
    velocity constraints are linear in the velocities)."""

    def __init__(self, model, replace: Mapping, initial_condition=None):
        if not isinstance(replace, Mapping) or not replace:
            raise ModelError("path(replace={dummy_constraint: velocity_constraint, ...}) needs at "
                             "least one replacement")
        self.model = model
        self.replaced = {}
        for dummy, vc in replace.items():
            d = model.constraint(dummy)          # raises UnknownConstraintError
            if not isinstance(vc, ConstraintBase):
                raise ModelError(f"the replacement for {d.label()} must be a constraint object, "
                                 f"got {vc!r}")
            vc.name = vc.name or f"velocity constraint replacing {d.name!r}"
            vc.number = vc.number if vc.number is not None else d.number
            self.replaced[d] = vc
        self.system = model._system_without(list(self.replaced), loads=[])
        layout = self.system.layout
        lay = layout
        self.velocity_constraints = list(self.replaced.values())
        psi, owners_psi = [], []
        allowed = set(lay.q_symbols) | set(lay.qd_symbols) | set(lay.p_symbols) | {T}
        for vc in self.velocity_constraints:
            for e in vc.equations(model.space):
                extra = e.free_symbols - allowed
                if extra:
                    raise ModelError(f"{vc.label()} uses unknown symbol(s) "
                                     f"{sorted(map(str, extra))}")
                psi.append(e)
                owners_psi.append(vc)
        n, mh = self.system.n, self.system.m
        if mh + len(psi) != n:
            raise ModelError(
                f"path: {mh} holonomic + {len(psi)} velocity equations for {n} velocities; "
                "replace each dummy constraint by velocity constraints with as many equations")
        self.psi = psi
        self.psi_owners = owners_psi
        qd = list(lay.qd_symbols)
        q = list(lay.q_symbols)
        self.psi_qd = sp.Matrix(psi).jacobian(qd)
        rest = []
        for e in psi:
            r = sp.diff(e, T)
            for a, b in zip(q, qd):
                if a in e.free_symbols:
                    r += sp.diff(e, a) * b
            rest.append(r)
        self.linear = all(sp.diff(x, v) == 0 for x in self.psi_qd for v in qd)
        args = lay.args()
        self._f = compile_exprs(args, list(psi) + list(self.psi_qd) + rest, self.system.backend)
        self._k = len(psi)
        self._q0 = model.guess()
        self._p = model._p()
        base = model.last_solution
        if base is not None:
            self._q0 = np.atleast_2d(base.q)[-1].copy()
        if initial_condition is not None:
            self._q0 = self._condition(initial_condition)

    def __repr__(self) -> str:
        names = ", ".join(d.name for d in self.replaced)
        return (f"<PathSystem: replaced {names}; {len(self.psi)} velocity equation(s); "
                f"{'linear' if self.linear else 'nonlinear'} in the velocities>")

    def _condition(self, cond):
        q = self._q0.copy()
        if hasattr(cond, "q"):
            return np.atleast_2d(cond.q)[-1].copy()
        lay = self.system.layout
        for k, v in cond.items():
            q[lay.index(k.name if hasattr(k, "name") else str(k))] = float(v)
        return q

    # -- the velocity solve -----------------------------------------------------------------
    def _psi(self, t, q, qd):
        out = self._f(self.system.pack(t, q, qd, self._p))
        k, n = self._k, self.system.n
        return out[:k], out[k : k + k * n].reshape(k, n), out[k + k * n :]

    def velocities(self, t, q, qd_guess=None, tol=1e-12, max_iterations=20):
        """Velocities ``qd`` (n,) at ``(t, q)`` from the holonomic and velocity constraints."""
        s = self.system
        n = s.n
        J, rhs = s.velocity_rhs(t, q, self._p)
        qd = np.zeros(n) if qd_guess is None else np.array(qd_guess, dtype=float)
        for _ in range(max_iterations):
            psi, B, _ = self._psi(t, q, qd)
            R = np.concatenate((J @ qd - rhs, psi))
            if np.abs(R).max(initial=0.0) <= tol * (1 + np.abs(qd).max(initial=0.0)):
                return qd
            K = np.vstack((J, B))
            try:
                qd = qd - factor(K).solve(R)
            except Singular:
                raise self._singular(K, t) from None
            if self.linear:
                psi, B, _ = self._psi(t, q, qd)
                return qd
        raise MechError(f"path: the velocity constraints did not converge at t = {t:.6g}")

    def _singular(self, K, t):
        rank, dep = dependent_rows(K)
        owners = list(self.system.layout.eq_owner) + self.psi_owners
        names = []
        for i in sorted(set(dep) | set(involved_rows(K, rank))):
            o = owners[i]
            lab = o.label() if hasattr(o, "label") else str(o)
            if lab not in names:
                names.append(lab)
        return SingularJacobianError(
            f"path: the velocity system is singular at t = {t:.6g} (rank {rank} of {K.shape[0]});"
            f" the dependency involves: {', '.join(names)}. A velocity constraint that "
            "repeats a holonomic one (or another velocity constraint) cannot fix the velocities.",
            time=t, rank=rank)

    def accelerations(self, t, q, qd):
        s = self.system
        J = s.jacobian(t, q, self._p)
        g = s.gamma_values(t, q, qd, self._p)
        _, B, rest = self._psi(t, q, qd)
        try:
            return factor(np.vstack((J, B))).solve(np.concatenate((g, -rest)))
        except Singular:
            raise self._singular(np.vstack((J, B)), t) from None

    # -- integration -------------------------------------------------------------------------
    def simulate(self, t, initial_condition=None, method: str = "dop853", rtol: float = 1e-8,
                 atol: float = 1e-10, max_step: float = np.inf, fit_degree="cubic",
                 max_error=1e-4, step_size=None, constraint_correction: bool = True,
                 diagnostics: bool = False) -> Solution:
        """Integrate the path (Mech's ``SolvePath``); options as ``FreeSystem.simulate``.
        The solution's ``extra["drift"]`` holds the largest holonomic residual met."""
        s = self.system
        q0 = self._q0.copy() if initial_condition is None else self._condition(initial_condition)
        q0 = self._project(float(np.atleast_1d(t)[0]), q0)
        last = [None]

        def rhs(tk, y):
            qd = self.velocities(tk, y, last[0])
            last[0] = qd
            return qd

        def proj(tk, y):
            return self._project(tk, y)

        times, Q, res, m = integrate(rhs, proj, t, q0, method, rtol, atol, max_step, fit_degree,
                                     max_error, step_size, constraint_correction)
        QD = np.array([self.velocities(tk, qk) for tk, qk in zip(times, Q)])
        QDD = np.array([self.accelerations(tk, qk, vk) for tk, qk, vk in zip(times, Q, QD)])
        drift = max(np.abs(s.residual(tk, qk, self._p)).max(initial=0.0) for tk, qk in zip(times, Q))
        extra = {"evaluations": res.evaluations, "steps": res.steps, "method": m, "drift": drift}
        if diagnostics:
            extra["diagnostics"] = res.diagnostics
        return Solution(t=times, q=Q, qd=QD, qdd=QDD, p=self._p, system=s, model=self.model,
                        iterations=np.zeros(len(times), dtype=int), mode="path", extra=extra)

    def _project(self, t, q):
        return project_positions(self.system, t, q, self._p)
