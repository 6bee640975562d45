r"""Nonholonomic systems (Mech's ``SetPath`` / ``SolvePath``, manual 10.5).

A fully constrained kinematic model carries *dummy* constraints that hold its place; ``path``
replaces them by *velocity constraints* :math:`\psi(q, \dot q, t) = 0` (normal constraint objects
whose geometry depends on velocities, e.g. ``Orthogonal1(m.velocity(p), body.vector(...))``,
a general ``Constraint`` with velocity terms, or a rolling contact such as ``RollingDisk2``,
which replaces a tuple of as many dummies as it has equations). At each instant the velocities
follow from the kept holonomic constraints and the velocity constraints together:

.. math::

    \Phi_q(q, t)\, \dot q + \Phi_t(q, t) &= 0 \qquad \text{(holonomic, } m - k \text{ rows)} \\
    \psi(q, \dot q, t) &= 0 \qquad \text{(nonholonomic, } k \text{ rows)}

(Newton on :math:`\dot q`; one step when :math:`\psi` is linear in :math:`\dot q`), and
:math:`q' = \dot q` is integrated with the same integrators as free motion;
``constraint_correction`` projects :math:`q` back onto the holonomic constraints after each
step. Accelerations come from the time derivative:

.. math::

    \Phi_q \ddot q = \gamma, \qquad \psi_{\dot q}\, \ddot q = -(\psi_q \dot q + \psi_t)

Parameters are read from the model when ``simulate`` runs (``m.set_parameters`` after
``m.path()`` takes effect); parameter values in ``initial_condition`` override them.
"""

from __future__ import annotations

from collections.abc import Mapping
from numbers import Real

import numpy as np
import scipy.sparse as sps

from .._errors import MechError, ModelError, SingularJacobianError
from .._symbols import T
from ..compile import compile_exprs
from ..constraints import ConstraintBase, velocity_rows
from ..geometry._units import resolve, time_numbers
from ..results._solution import Solution, State
from ..solvers._free import project_positions, scaling_at
from ..solvers._integrators import (
    ATOL,
    FIT_DEGREE,
    MAX_ERROR,
    MAX_STEP,
    RTOL,
    integrate,
    plan_run,
)
from ..solvers._jit_free import FreeStepper
from ..solvers._linalg import (
    Scaling,
    dependent_rows,
    factor,
    involved_rows,
    pattern_of,
    pattern_slots,
)
from ..solvers._tolerances import SPARSE_THRESHOLD, Singular
from ._free import accuracy_report


def _check_own(model, dummy, vc) -> None:
    """A velocity constraint replacing ``dummy`` must be new and built of ``model``'s bodies:
    the coordinate symbols of another model's bodies have the same names (``x2``, ``th2``), so
    a constraint on them would silently act on this model's body of the same number."""
    if vc.model is not None:
        where = "this model" if vc.model is model else "another model"
        raise ModelError(f"the replacement for {dummy.label()}: {vc.label()} is already a "
                         f"constraint of {where}; give a new velocity constraint object")
    for b in vc.bodies():
        if getattr(b, "model", None) is not model:
            raise ModelError(f"the replacement for {dummy.label()}: {vc.label()} uses body "
                             f"{getattr(b, 'name', b)!r} of another model; build it from this "
                             "model's bodies (m.body(...), m.velocity(...))")


class PathSystem:
    r"""A kinematic model with dummy constraints replaced by velocity constraints.

    Attributes: ``model``, ``replaced`` (``{dummy: velocity constraint}``), ``system`` (the
    compiled holonomic part), ``velocity_constraints`` (list), ``linear`` (whether the
    velocity constraints are linear in the velocities).

    At each instant the velocities solve the kept holonomic constraints and the velocity
    constraints :math:`\psi` together, and the accelerations their time derivatives:

    .. math::

        \Phi_q \dot q + \Phi_t &= 0, \qquad \psi(q, \dot q, t) = 0 \\
        \Phi_q \ddot q &= \gamma, \qquad
        \psi_{\dot q}\, \ddot q = -(\psi_q \dot q + \psi_t)

    (Newton on :math:`\dot q`, one step when :math:`\psi` is linear in :math:`\dot q`);
    ``simulate`` integrates :math:`q' = \dot q`.
    """

    def __init__(self, model, replace: Mapping, initial_condition=None):
        if not isinstance(replace, Mapping) or not replace:
            raise ModelError("path(replace={dummy_constraint: velocity_constraint, ...}) needs at "
                             "least one replacement")
        self.model = model
        self.replaced = {}
        seen = []
        for dummy, vc in replace.items():
            # a tuple of dummies gives their places to one velocity constraint of as many
            # equations (a rolling disk's two no-slip rows replace the dummies of x and y)
            group = [model.constraint(d) for d in (dummy if isinstance(dummy, tuple) else
                                                   (dummy,))]   # raises UnknownConstraintError
            if not group:
                raise ModelError("path(replace=...): an empty tuple of dummy constraints")
            d = group[0]
            if not isinstance(vc, ConstraintBase):
                raise ModelError(f"the replacement for {d.label()} must be a constraint object, "
                                 f"got {vc!r}")
            if any(vc is v for v in seen):
                raise ModelError(f"{vc.label()} replaces two entries of path(replace=...); give "
                                 "it once, with a tuple of the dummies it replaces as the key")
            seen.append(vc)
            _check_own(model, d, vc)
            # lengths given with units (a rolling radius of 300 mm) in the model's units, as
            # m.add does for the constraints of the model
            resolve(vc, model.units, vc.label())
            vc._cache.clear()
            vc.name = vc.name or ("velocity constraint replacing "
                                  + ", ".join(repr(g.name) for g in group))
            vc.number = vc.number if vc.number is not None else d.number
            for g in group:
                if g in self.replaced:
                    raise ModelError(f"path(replace=...): {g.label()} is replaced twice")
                self.replaced[g] = vc
        self.system = model._system_without(list(self.replaced), loads=[])
        layout = self.system.layout
        lay = layout
        self.velocity_constraints = list(dict.fromkeys(self.replaced.values()))
        psi, owners_psi = [], []
        allowed = set(lay.q_symbols) | set(lay.qd_symbols) | set(lay.p_symbols) | {T}
        gen = model._gen_substitution()  # slave bodies (Gen joints): their poses
        for vc in self.velocity_constraints:
            for e in vc.equations(model.space):
                e = e.xreplace(gen) if gen else e
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
        # psi_qd (the A of A qd + b), and rest = psi_q qd + psi_t of d psi/dt = A qdd + rest:
        # the same derivatives as the velocity_form of the rolling constraints (decision 0046)
        rows = velocity_rows(psi, list(lay.q_symbols), list(lay.qd_symbols))
        self.psi_qd = rows.A
        rest = list(rows.rho)
        self.linear = rows.linear
        args = lay.args()
        self._k = len(psi)
        n = self.system.n
        #: above SPARSE_THRESHOLD coordinates the kernel returns psi_qd's structural nonzeros
        #: only (at ``_b_rows``, ``_b_cols``) and the velocity system is solved sparse: a
        #: velocity constraint involves the few coordinates of its bodies, and a dense ``k x
        #: n`` block with a dense LU made each evaluation cost O(n^3)
        self._sparse = n > SPARSE_THRESHOLD
        if self._sparse:
            nz = [(i, j) for i in range(self._k) for j in range(n) if self.psi_qd[i, j] != 0]
            self._b_rows = np.array([i for i, _ in nz], dtype=np.int64)
            self._b_cols = np.array([j for _, j in nz], dtype=np.int64)
            block = [self.psi_qd[i, j] for i, j in nz]
        else:
            block = list(self.psi_qd)
        self._f = compile_exprs(args, list(psi) + block + rest, self.system.backend)
        self._p_given: dict[int, float] = {}
        self._q0 = model.guess()
        base = model.last_solution
        if base is not None:
            self._q0 = self._coordinates(base, "the model's last solution")
        if initial_condition is not None:
            self._q0, self._p_given = self._condition(initial_condition)

    def __repr__(self) -> str:
        names = ", ".join(d.name for d in self.replaced)
        return (f"<PathSystem: replaced {names}; {len(self.psi)} velocity equation(s); "
                f"{'linear' if self.linear else 'nonlinear'} in the velocities>")

    @property
    def _p(self) -> np.ndarray:
        """Parameter values now: the model's (by symbol), then this PathSystem's own."""
        return self._params()

    def _params(self, given=None) -> np.ndarray:
        values = self.model._params
        p = np.array([values[s] for s in self.system.layout.p_symbols], dtype=float)
        for over in (self._p_given, given or {}):
            for i, v in over.items():
                p[i] = v
        return p

    def _coordinates(self, sol, what):
        q = np.atleast_2d(sol.q)[-1].copy()
        if q.shape != (self.system.n,):
            raise ModelError(f"{what} has {q.size} coordinates, this path system "
                             f"{self.system.n}; it belongs to another model (or the model changed)")
        return q

    def _condition(self, cond):
        """``(q, {parameter index: value})`` from a Solution/State or a mapping of coordinate
        and parameter values on top of the PathSystem's start."""
        if isinstance(cond, (Solution, State)):
            return self._coordinates(cond, "initial_condition"), {}
        if not isinstance(cond, Mapping):
            raise ModelError("initial_condition must be a Solution, State or a mapping of "
                             "coordinate and parameter values")
        q = self._q0.copy()
        lay = self.system.layout
        pnames = [s.name for s in lay.p_symbols]
        given = {}
        for k, v in cond.items():
            name = k.name if hasattr(k, "name") else str(k)
            if isinstance(v, bool) or not isinstance(v, Real) or not np.isfinite(v):
                raise ModelError(f"initial_condition: the value of {name!r} must be a finite "
                                 f"number, got {v!r}")
            if name in pnames:
                given[pnames.index(name)] = float(v)
                continue
            try:
                q[lay.index(name)] = float(v)
            except ModelError:
                raise ModelError(f"initial_condition: {name!r} is not a coordinate or parameter "
                                 "of this model (velocities of a path follow from its "
                                 "constraints)") from None
        return q, given

    # -- the velocity solve -----------------------------------------------------------------
    def _psi(self, t, q, qd, p):
        """``(psi (k,), psi_qd (k, n), rest (k,))`` (up to ``SPARSE_THRESHOLD`` coordinates;
        above, :meth:`_sparse_factor`)."""
        out = self._f(self.system.pack(t, q, qd, p))
        k, n = self._k, self.system.n
        return out[:k], out[k : k + k * n].reshape(k, n), out[k + k * n :]

    def _pattern(self):
        """``(rows, cols, FixedPattern, slots)`` of the large velocity system ``K = [Phi_q;
        psi_qd]``: its entries in CSC order (rows matched to columns), analysed once (the
        compiled sparse LU's ordering whatever the band, as a system's Jacobian: the
        compiled stepper factorises the same matrices with the same function), and where
        each of the Jacobian's then ``psi_qd``'s kernel values goes among them."""
        got = self.__dict__.get("_vpattern")
        if got is None:
            s = self.system
            rows = np.concatenate((np.asarray(s.jac_rows, dtype=np.int64), s.m + self._b_rows))
            cols = np.concatenate((np.asarray(s.jac_cols, dtype=np.int64), self._b_cols))
            r, c, pat = pattern_of(rows, cols, s.n, match_rows=True, sparse=True)
            got = self._vpattern = (r, c, pat, pattern_slots(r, c, s.n, rows, cols))
        return got

    def _sparse_values(self, t, q, qd, p, jv, columns):
        """``K``'s values at ``(t, q, qd)`` (``jv`` the Jacobian's kernel values) gathered into
        its fixed pattern: ``(psi, rest, r, values of R^-1 K D)``, ``r`` the row scales of
        :meth:`Scaling.rows` (the same maxima)."""
        k, nb = self._k, self._b_rows.size
        r_, c_, _, slots = self._pattern()
        out = self._f(self.system.pack(t, q, qd, p))
        data = np.bincount(slots, weights=np.concatenate((jv, out[k:k + nb])),
                           minlength=r_.size)
        r = np.zeros(self.system.n)
        np.maximum.at(r, r_, np.abs(data) * columns[c_])
        r[~(r > 0)] = 1.0
        return out[:k], out[k + nb:], r, data * (columns[c_] / r[r_])

    def _sparse_factor(self, values, t):
        """The factorisation of :meth:`_sparse_values`' scaled ``K``; singular: the diagnosis
        of the dense path."""
        r_, c_, pat, _ = self._pattern()
        try:
            return pat.factor(values)
        except Singular:
            K = sps.csc_matrix((values, (r_, c_)), shape=(self.system.n,) * 2)
            raise self._singular(K, t) from None

    def velocities(self, t, q, qd_guess=None, tol=1e-12, max_iterations=20, p=None,
                   scaling=None):
        r"""Velocities ``qd`` (n,) at ``(t, q)`` from the holonomic and velocity constraints
        (parameters ``p``: default the model's current values). Converged when every
        equation's residual, divided by its row scale in the unit-free coordinates of
        ``scaling`` (:class:`~mechsys.solvers.Scaling`, default: at ``q``), is at most
        :math:`\mathit{tol}\, (1 + \max_j \lvert \dot q_j \rvert / c_j)`: the same relative
        accuracy in any unit of length."""
        s = self.system
        n = s.n
        p = self._p if p is None else p
        qd = np.zeros(n) if qd_guess is None else np.array(qd_guess, dtype=float)
        if self._sparse:
            if scaling is None:
                scaling = Scaling.of(s, q, s.velocity_rhs(t, q, p, True)[0])
            return self._velocities_sparse(t, q, qd, p, tol, max_iterations, scaling)
        J, rhs = s.velocity_rhs(t, q, p, False)
        if scaling is None:
            scaling = Scaling.of(s, q, J)
        for _ in range(max_iterations):
            psi, B, _ = self._psi(t, q, qd, p)
            R = np.concatenate((J @ qd - rhs, psi))
            K = np.vstack((J, B))
            r = scaling.rows(K)
            if np.abs(R / r).max(initial=0.0) <= tol * (
                    1 + np.abs(qd / scaling.columns).max(initial=0.0)):
                return qd
            try:
                qd = qd - factor(K).solve(R)
            except Singular:
                raise self._singular(K, t) from None
            if self.linear:
                return qd
        raise MechError(f"path: the velocity constraints did not converge at t = {t:.6g}")

    def _velocities_sparse(self, t, q, qd, p, tol, max_iterations, scaling):
        """:meth:`velocities` above ``SPARSE_THRESHOLD`` coordinates: the same Newton, with
        ``K`` gathered into its fixed pattern (no sparse-matrix objects per evaluation) and
        factorised by the pattern's LU."""
        s = self.system
        out = s.f_velocity(s.pack(t, q, None, p))
        jv, rhs = out[:s.nnz], -out[s.nnz:]
        jr, jc = s.jac_rows, s.jac_cols
        c = scaling.columns
        for _ in range(max_iterations):
            psi, _, r, values = self._sparse_values(t, q, qd, p, jv, c)
            R = np.concatenate((np.bincount(jr, weights=jv * qd[jc], minlength=s.m) - rhs, psi))
            if np.abs(R / r).max(initial=0.0) <= tol * (1 + np.abs(qd / c).max(initial=0.0)):
                return qd
            qd = qd - c * self._sparse_factor(values, t).solve(R / r)
            if self.linear:
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

    def accelerations(self, t, q, qd, p=None):
        """Accelerations ``qdd`` (n,) at ``(t, q, qd)`` (parameters as :meth:`velocities`)."""
        s = self.system
        p = self._p if p is None else p
        g = s.gamma_values(t, q, qd, p)
        if self._sparse:
            jv = s.f_velocity(s.pack(t, q, None, p))[:s.nnz]
            c = np.ones(s.n)             # (any positive column scales: the same solution)
            _, rest, r, values = self._sparse_values(t, q, qd, p, jv, c)
            return c * self._sparse_factor(values, t).solve(np.concatenate((g, -rest)) / r)
        J = s.jacobian(t, q, p)
        _, B, rest = self._psi(t, q, qd, p)
        K = np.vstack((J, B))
        try:
            return factor(K).solve(np.concatenate((g, -rest)))
        except Singular:
            raise self._singular(K, t) from None

    # -- integration -------------------------------------------------------------------------
    def simulate(self, t, initial_condition=None, method: str = "dop853", rtol: float = RTOL,
                 atol: float = ATOL, max_step: float = MAX_STEP, fit_degree=FIT_DEGREE,
                 max_error=MAX_ERROR, step_size=None, constraint_correction: bool = True,
                 diagnostics: bool = False, starting_step_size: float | None = None,
                 **unknown) -> Solution:
        """Integrate the path (Mech's ``SolvePath``); times and options as
        ``FreeSystem.simulate`` (checked the same way: unsorted or non-finite times, options
        that do not apply to ``method`` and unknown options raise :class:`ModelError`;
        ``max_error`` works with every method). Parameters are the model's at the call,
        overridden by those in ``initial_condition``. The solution's ``extra["drift"]`` holds
        the largest holonomic residual met."""
        run = plan_run("PathSystem.simulate", t, unknown, (
            "initial_condition", "method", "rtol", "atol", "max_step", "fit_degree", "max_error",
            "step_size", "constraint_correction", "diagnostics", "starting_step_size"), method,
            rtol, atol, max_step, fit_degree, max_error, step_size, constraint_correction,
            starting_step_size, to_numbers=time_numbers(self.model))
        opt, t0, t_eval = run.options, run.t0, run.t_eval
        s = self.system
        if initial_condition is None:
            q0, p = self._q0.copy(), self._params()
        else:
            q0, given = self._condition(initial_condition)
            p = self._params(given)
        sc = scaling_at(s, t0, q0, p)          # units of the coordinates, once per run
        q0 = project_positions(s, t0, q0, p, scaling=sc)
        last = [None]

        def rhs(tk, y):
            qd = self.velocities(tk, y, last[0], p=p, scaling=sc)
            last[0] = qd
            return qd

        def proj(tk, y):
            return project_positions(s, tk, y, p, scaling=sc)

        # the compiled stepper (solvers/_jit_free.py, kind PATH) takes the regular steps
        fast = FreeStepper.plan_path(self, opt.method, p, sc, opt.correction, t_eval)
        times, Q, res, m = integrate(rhs, proj, run, q0, scale=sc.columns, fast=fast)
        # velocities at the outputs: the compiled stepper's where it ran, else here
        known = res.diagnostics.get("derivatives")
        QD = np.array([known[0][k] if known is not None and np.all(np.isfinite(known[0][k]))
                       else self.velocities(tk, qk, p=p, scaling=sc)
                       for k, (tk, qk) in enumerate(zip(times, Q))])
        QDD = np.empty_like(QD)
        k0 = 0 if fast is None else fast.path_accelerations(self, times, Q, QD, QDD)
        for k in range(k0, len(times)):
            QDD[k] = self.accelerations(times[k], Q[k], QD[k], p)
        drift = max(np.abs(s.residual(tk, qk, p)).max(initial=0.0) for tk, qk in zip(times, Q))
        extra = {"evaluations": res.evaluations, "steps": res.steps, "method": m, "drift": drift,
                 "length_scale": sc.length,
                 "compiled_steps": res.diagnostics.get("compiled_steps", 0),
                 "interpreted_steps": res.diagnostics.get("interpreted_steps", 0),
                 "compiled_solver": None if fast is None else fast.solver}
        # the run's own measure of its accuracy (holonomic drift, coordinates' range)
        extra["accuracy"] = accuracy_report(s, sc, times, np.hstack((Q, QD)), p,
                                            opt.rtol if opt.runge_kutta else opt.max_error[0],
                                            "PathSystem.simulate")
        if diagnostics:
            extra["diagnostics"] = res.diagnostics
        return Solution(t=times, q=Q, qd=QD, qdd=QDD, p=p, system=s, model=self.model,
                        iterations=np.zeros(len(times), dtype=int), mode="path", extra=extra)
