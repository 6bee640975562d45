r"""Coupled systems (Mech's ``SetCouple`` / ``SolveCouple``, manual sections 9.1-9.4).

A couple turns model parameters into unknowns and adds as many conditions as there are new
unknowns. One mechanism is solved in ``K`` configurations at once (different times, guesses
and conditions, the same parameters)::

    cm = m.couple(unknowns=["c"], conditions=[sp.Eq(m.angle(rocker), 1.2)], t=0.5)
    res = cm.solve()
    res["c"], res.solution.location(rocker.point("B"))

For configuration ``k`` with time ``t_k`` the unknowns and equations are

=====================  ===========================================  ==========================
level                  unknowns                                     equations
=====================  ===========================================  ==========================
location               ``q_k``                                      :math:`\Phi(q_k, t_k, p) = 0`
velocity (9.3)         ``qd_k``                                     :math:`\Phi_q \dot q_k + \Phi_t = 0`
acceleration (9.3)     ``qdd_k``                                    :math:`\Phi_q \ddot q_k - \gamma = 0`
loads (9.4)            ``lambda_k``                                 :math:`\Phi_q^T \lambda_k = \mathrm{rhs}`
conditions             (``t_k`` when ``t=ms.Free``)                 :math:`g_k = 0`
=====================  ===========================================  ==========================

with the conditions :math:`g_k(T, q, \dot q, \ddot q, \lambda, p)` of configuration ``k``,
:math:`\mathrm{rhs} = Q(t, q, 0, \lambda)` (static), :math:`Q(t, q, \dot q, \lambda)` (kinematic) or
:math:`Q + Q_v - M \ddot q` (dynamic), as :mod:`mechsys.solvers._statics`; plus the unknown
parameters ``u``, shared by every configuration. The stacked system :math:`F(z) = 0`,
``z = [q_1, qd_1, qdd_1, lambda_1, t_1, ..., q_K, ..., u]``, is square when the model is
(``m = n``) and there are as many conditions as unknown parameters and free times.

**Solution level.** As Mech's ``Solution -> Automatic``: conditions with velocities need the
velocity level, with accelerations the acceleration level, with multipliers (reactions) the
load equations (static, kinematic with velocities, dynamic with accelerations). Inertial
loads are included only with ``solution="dynamic"`` (Mech 9.4.3). A ``solution`` lower than
the conditions need raises (Mech raises the level silently).

**Numerics.** The model part of one configuration (its equations and their exact Jacobian
with respect to the block's unknowns, the unknown parameters and time) is derived and
compiled once per couple and evaluated for all configurations in one batch call; each
configuration's conditions are compiled once. Newton's method with the Armijo line search of
the position solver runs on the unit-free form :math:`\hat F = S^{-1} F`,
:math:`\hat J = S^{-1} J C`: coordinates, velocities and accelerations are measured in units
of the characteristic length of :class:`~mechsys.solvers._linalg.Scaling` (rows of the
kinematic equations divided by the row sizes ``r`` of :math:`\Phi_q D`); multipliers in units of
``W / r_i`` and force rows by ``W / D_j``, with ``W`` the largest generalized load times
``D`` at the start (a work); each unknown parameter and free time in units in which its
largest effect on a model equation is 1 (so a length parameter, an angle and a time are all
treated without knowing their dimension); each condition row by its largest scaled entry.
Converged when every scaled residual is below ``ftol (1 + max|x| / L)``. The result does not
depend on the unit of length.
"""

from __future__ import annotations

import weakref
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from numbers import Real

import numpy as np
import scipy.sparse as sps
import sympy as sp

try:  # optional: native derivation (the ``fast`` extra)
    import symengine as se
except ImportError:  # pragma: no cover - depends on environment
    se = None

from .._errors import (
    ConstraintCountError,
    ConvergenceError,
    MechError,
    ModelError,
    SingularJacobianError,
    choice,
    unknown_options,
)
from .._symbols import T
from ..compile._backends import compile_exprs
from ..compile._derive import _diff, _rewrite_steps, symengine_safe, to_sympy_list
from ..results._solution import Solution, State
from ..solvers._kinematics import solve_acceleration, solve_velocity
from ..solvers._linalg import Scaling, dependent_rows, factor
from ..solvers._position import PositionOptions, solve_position
from ..solvers._tolerances import SPARSE_THRESHOLD, Singular

#: compiled kernels of couples, per System (dropped with it)
_KERNELS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

#: solution level -> (derivative order, with load equations)
LEVELS = {"location": (0, False), "velocity": (1, False), "acceleration": (2, False),
          "static": (0, True), "kinematic": (1, True), "dynamic": (2, True)}


class FreeTime:
    """Mech's ``Time -> Free``: the configuration's time is an unknown. ``ms.Free`` starts it
    from the configuration's default time; ``ms.Free(0.3)`` from 0.3."""

    def __init__(self, guess: float | None = None):
        if guess is not None:
            if isinstance(guess, bool) or not isinstance(guess, Real) or not np.isfinite(guess):
                raise ModelError(f"Free(guess): the starting time must be a finite number, got "
                                 f"{guess!r}")
            guess = float(guess)
        self.guess = guess

    def __call__(self, guess: float) -> FreeTime:
        return FreeTime(guess)

    def __repr__(self) -> str:
        return "Free" if self.guess is None else f"Free({self.guess:g})"


#: Mech's ``Time -> Free`` (see :class:`FreeTime`).
Free = FreeTime()


@dataclass(frozen=True)
class Configuration:
    """One configuration of a couple (Mech's ``{equations, Time -> t, InitialGuess -> ...}``).

    ``conditions``: a SymPy ``Eq(lhs, rhs)``, an expression meaning ``= 0``, a column matrix
    (one condition per entry) or a list of these. ``t``: the time (a number or ``ms.Free``).
    ``guess``: starting coordinates: an array ``(n,)``, a ``Solution``/``State`` (its point
    nearest ``t``; velocities and accelerations too) or a mapping of coordinate names.
    """

    conditions: object
    t: object = None
    guess: object = None


def _conditions(spec, where: str) -> list:
    """The conditions as a list of SymPy expressions meaning ``= 0``."""
    items = list(spec) if isinstance(spec, (list, tuple)) else [spec]
    out = []
    for c in items:
        if isinstance(c, sp.MatrixBase):
            out.extend(_conditions(list(c), where))
            continue
        try:
            e = sp.sympify(c)
        except (sp.SympifyError, TypeError):
            raise ModelError(f"{where}: condition {c!r} is not a SymPy equation or "
                             "expression") from None
        if isinstance(e, sp.Equality):
            if isinstance(e.lhs, sp.MatrixBase) or isinstance(e.rhs, sp.MatrixBase):
                out.extend(_conditions(list(sp.Matrix(e.lhs) - sp.Matrix(e.rhs)), where))
                continue
            e = e.lhs - e.rhs
        if not isinstance(e, sp.Expr) or isinstance(e, sp.logic.boolalg.Boolean):
            raise ModelError(f"{where}: condition {c!r} must be an equation Eq(lhs, rhs) or an "
                             "expression that is zero, not an inequality or a truth value")
        out.append(e)
    if not out:
        raise ModelError(f"{where}: no conditions; give at least one equation to satisfy")
    return out


class CoupleSystem:
    """A coupled system (Mech's ``CoupleSystem``), made by :meth:`Model.couple`; solve it with
    :meth:`solve`. Attributes: ``model``, ``system`` (the model's compiled System),
    ``unknowns`` (parameter names), ``configurations`` (:class:`Configuration`, as given),
    ``solution`` (the level: ``"location"`` ... ``"dynamic"``), ``size`` (equations = unknowns
    of the stacked system).

    Parameters are read from the model when :meth:`solve` runs; the unknown ones start from
    their guesses (``unknowns={"c": 3.0}``) or, without one, the model's current value."""

    def __init__(self, model, unknowns, conditions=None, t=None, guess=None,
                 configurations=None, solution: str | None = None):
        what = "couple"
        if model._switches():
            raise ModelError("couple(): models with stage or time switches are not supported; "
                             "replace each switch by the constraint of the stage you need")
        self.model = model
        s = self.system = model.compile()
        if s.n == 0:
            raise ModelError("couple(): the model has no moving bodies (or variables)")
        self._unknowns, self._u_guess = self._parse_unknowns(unknowns)
        if configurations is None:
            if conditions is None:
                raise ModelError(f"{what}: give conditions= (one configuration) or "
                                 "configurations=[ms.Configuration(conditions, t=..., guess=...), ...]")
            configurations = [Configuration(conditions, t, guess)]
            guess = None
        elif conditions is not None or t is not None:
            raise ModelError(f"{what}: give either conditions= and t= (one configuration) or "
                             "configurations=, not both")
        if isinstance(configurations, (Configuration, Mapping)):
            configurations = [configurations]
        self.configurations = tuple(self._configuration(c, k) for k, c in enumerate(configurations))
        if not self.configurations:
            raise ModelError(f"{what}: configurations= is empty")
        K = len(self.configurations)
        lay = s.layout
        self._conds = [_conditions(c.conditions, f"configuration {k + 1}")
                       for k, c in enumerate(self.configurations)]
        allowed = {T, *lay.q_symbols, *lay.qd_symbols, *lay.qdd_symbols, *s.lam_symbols,
                   *lay.p_symbols}
        used = set()
        for k, cs in enumerate(self._conds):
            for i, e in enumerate(cs):
                extra = e.free_symbols - allowed
                if extra:
                    raise ModelError(
                        f"configuration {k + 1}, condition {i + 1} ({e}) uses "
                        f"{sorted(map(str, extra))}, which are not T, coordinates, velocities, "
                        "accelerations, multipliers or parameters of the model")
                used |= e.free_symbols
        self.solution = self._level(solution, used)
        self._order, self._loads = LEVELS[self.solution]
        # parameters the equations can feel: constraints, loads and masses when used, conditions
        feel = set().union(*(e.free_symbols for e in s.phi)) | used
        if self._loads:
            dyn = s.dynamics
            feel |= set().union(*(sp.sympify(e).free_symbols for e in dyn.Q))
            if self._order == 2:
                feel |= set().union(*(e.free_symbols for e in list(dyn.M_exprs) + list(dyn.Qv)))
        for u in self._unknowns:
            if u not in feel:
                where = "constraints" + (", loads" if self._loads else "") + " or conditions"
                raise ModelError(
                    f"couple: parameter {u.name!r} is not used by the model's {where}, so no "
                    "condition can depend on it and the couple cannot determine it; unknowns "
                    "must be parameters that the constraints (or the loads of a load-dependent "
                    "couple) contain")
        time_dependent = T in feel or (self._loads and any(
            T in sp.sympify(e).free_symbols for e in s.dynamics.Q))
        self._free = [isinstance(c.t, FreeTime) for c in self.configurations]
        if not self._unknowns and not any(self._free):
            raise ModelError("couple: nothing to solve for; give unknowns= (parameters) or make "
                             "a configuration's time an unknown with t=ms.Free")
        self._t0 = [self._time(c, k, K, time_dependent) for k, c in enumerate(self.configurations)]
        self._count_check()
        self._guesses = [self._initial(c, guess, self._t0[k]) for k, c in
                         enumerate(self.configurations)]
        self._build()

    # -- input ------------------------------------------------------------------------------
    def _parse_unknowns(self, unknowns):
        m = self.model
        if isinstance(unknowns, (str, sp.Symbol)) or (
                isinstance(unknowns, tuple) and len(unknowns) == 2 and isinstance(unknowns[1], Real)):
            unknowns = [unknowns]
        items = list(unknowns.items()) if isinstance(unknowns, Mapping) else [
            u if isinstance(u, tuple) else (u, None) for u in unknowns]
        syms, guesses = [], {}
        params = {p.name: p for p in m._params}
        for spec, g in items:
            name = spec.name if isinstance(spec, sp.Symbol) else str(spec)
            if name not in params:
                if name == T.name:
                    raise ModelError("couple: time is made an unknown with t=ms.Free, not in "
                                     "unknowns=")
                try:
                    m._coordinate_by_name(name)
                    kind = "a coordinate (coordinates are always solved for)"
                except ModelError:
                    kind = "not a parameter of the model"
                raise ModelError(f"couple: unknown {name!r} is {kind}; unknowns are parameters "
                                 f"(the model has {sorted(params) or 'none'}); declare one with "
                                 "m.parameter(name, value) and use it in a constraint")
            s = params[name]
            if s in syms:
                raise ModelError(f"couple: parameter {name!r} is given twice in unknowns=")
            syms.append(s)
            if g is not None:
                try:
                    guesses[s] = float(g)
                except (TypeError, ValueError):
                    raise ModelError(f"couple: the guess of {name!r} must be a number, got "
                                     f"{g!r}") from None
                if not np.isfinite(guesses[s]):
                    raise ModelError(f"couple: the guess of {name!r} must be finite, got {g!r}")
        return syms, guesses

    @staticmethod
    def _configuration(c, k) -> Configuration:
        if isinstance(c, Configuration):
            return c
        if isinstance(c, Mapping):
            bad = set(c) - {"conditions", "t", "guess"}
            if bad or "conditions" not in c:
                raise ModelError(f"configuration {k + 1}: a mapping needs 'conditions' and may "
                                 f"have 't' and 'guess'; got keys {sorted(map(str, c))}")
            return Configuration(c["conditions"], c.get("t"), c.get("guess"))
        raise ModelError(f"configuration {k + 1}: give ms.Configuration(conditions, t=, guess=) "
                         f"or a mapping, got {c!r}")

    def _level(self, solution, used) -> str:
        lay, s = self.system.layout, self.system
        order = 2 if used & set(lay.qdd_symbols) else (1 if used & set(lay.qd_symbols) else 0)
        loads = bool(used & set(s.lam_symbols))
        auto = {(0, False): "location", (1, False): "velocity", (2, False): "acceleration",
                (0, True): "static", (1, True): "kinematic", (2, True): "dynamic"}[(order, loads)]
        if solution is None:
            return auto
        choice(solution, list(LEVELS), "couple: solution", "or None (automatic)")
        o, ld = LEVELS[solution]
        if o < order or (loads and not ld):
            need = ("accelerations" if order == 2 else "velocities" if order == 1 else "") + (
                (" and " if order else "") + "multipliers (reactions)" if loads else "")
            raise ModelError(f"couple: the conditions use {need}, which solution={solution!r} "
                             f"does not solve; use solution={auto!r} or higher, or leave "
                             "solution=None (automatic)")
        return solution

    def _time(self, c, k, K, time_dependent) -> float:
        if isinstance(c.t, FreeTime):
            if c.t.guess is not None:
                return c.t.guess
            last = self.model.last_solution
            return float(np.atleast_1d(last.t)[-1]) if last is not None else 0.0
        if c.t is None:
            if not time_dependent:
                return 0.0
            last = self.model.last_solution
            if K == 1 and last is not None:  # Mech: the time of the default guesses
                return float(np.atleast_1d(last.t)[-1])
            raise ModelError(f"configuration {k + 1}: the model depends on time T, so give the "
                             "time of the configuration (t=0.1) or make it an unknown (t=ms.Free)")
        if isinstance(c.t, bool) or not isinstance(c.t, Real) or not np.isfinite(c.t):
            raise ModelError(f"configuration {k + 1}: t must be a finite number or ms.Free, "
                             f"got {c.t!r}")
        return float(c.t)

    def _count_check(self):
        s, K = self.system, len(self.configurations)
        n, m, o = s.n, s.m, self._order
        per_u = n * (1 + o) + (m if self._loads else 0)
        per_e = m * (1 + o) + (n if self._loads else 0)
        nu, nf = len(self._unknowns), sum(self._free)
        nc = sum(len(c) for c in self._conds)
        unknowns = K * per_u + nu + nf
        equations = K * per_e + nc
        self.size = unknowns
        if unknowns == equations:
            return
        names = ", ".join(repr(u.name) for u in self._unknowns)
        parts = [f"{nu} parameter(s) ({names})"]
        if nf:
            parts.append(f"{nf} free time(s)")
        counts = ", ".join(f"configuration {k + 1}: {len(c)}" for k, c in enumerate(self._conds))
        msg = (f"couple: {nu + nf} unknown(s) ({' and '.join(parts)}) but {nc} condition(s) "
               f"({counts})")
        if n != m:
            msg += (f"; besides, the model has {n} coordinates and {m} equations, which adds "
                    f"{K * (per_u - per_e)} unknown(s) net over {K} configuration(s) at this "
                    "solution level")
        msg += (f": {unknowns} unknowns against {equations} equations in all. Give as many "
                "conditions as unknown parameters and free times"
                + (f" plus the {K * (per_u - per_e)} freedom(s) the model leaves" if n != m
                   else "") + ": ")
        diff = unknowns - equations
        msg += (f"add {diff} condition(s) or drop {diff} unknown(s)" if diff > 0
                else f"drop {-diff} condition(s) or add {-diff} unknown(s)")
        raise ConstraintCountError(msg)

    def _initial(self, c, default, t):
        """``(q, qd, qdd)`` to start configuration ``c`` from: its guess, the couple's guess,
        the model's last solution (the point nearest ``t``), or the model's guesses."""
        n = self.system.n
        src = c.guess if c.guess is not None else default
        if src is None:
            last = self.model.last_solution
            if last is not None and getattr(last, "system", None) is not None and \
                    tuple(last.system.layout.q_names) == tuple(self.system.layout.q_names):
                src = last
        if src is None:
            return self.model.guess(), None, None
        if isinstance(src, Solution):
            k = int(np.argmin(np.abs(np.atleast_1d(src.t) - t)))
            pick = lambda a: None if a is None else np.atleast_2d(a)[k].copy()
            out = (pick(src.q), pick(src.qd), pick(src.qdd))
        elif isinstance(src, State):
            out = (np.array(src.q, dtype=float), None if src.qd is None else np.array(src.qd),
                   None if src.qdd is None else np.array(src.qdd))
        else:
            out = (self.model._resolve_guess(self.system, src), None, None)
        if out[0].shape != (n,):
            raise ModelError(f"couple: the guess has {out[0].size} coordinates, the model {n}; "
                             "it belongs to another model (or the model changed)")
        return out

    # -- derivation and compilation -----------------------------------------------------------
    def _build(self):
        """Derive the equations of one configuration and their Jacobian once; compile the
        model block (shared by every configuration) and each configuration's conditions.
        With SymEngine the derivation starts from the System's native expressions and
        differentiates natively (SymPy's ``diff`` of a 3D ``gamma`` takes seconds)."""
        s = self.system
        lay = s.layout
        n, m, o = s.n, s.m, self._order
        dyn = s.dynamics if self._loads else None
        conds = [e for c in self._conds for e in c]
        native = (s._native is not None and symengine_safe(conds + (list(dyn.Q) if dyn else []))
                  and not any(sp.sympify(e).has(sp.floor) for e in s.phi))
        if native:
            S = se.sympify
            zero = se.Integer(0)
            phi, jac, phi_t, gamma = (s._native[k] for k in ("phi", "jac", "phi_t", "gamma"))
        else:
            S = sp.sympify
            zero = sp.S.Zero
            phi, jac, phi_t, gamma = [_rewrite_steps(e) for e in s.phi], s.jac_exprs, s.phi_t, s.gamma
        q, qd, qdd = ([S(x) for x in xs] for xs in (lay.q_symbols, lay.qd_symbols, lay.qdd_symbols))
        lam = [S(x) for x in s.lam_symbols]
        J = [[zero] * n for _ in range(m)]
        for i, j, e in zip(s.jac_rows, s.jac_cols, jac):
            J[i][j] = J[i][j] + e

        def dot(row, x):
            return sum((a * b for a, b in zip(row, x) if a != 0), zero)

        rows = list(phi)
        if o >= 1:
            rows += [dot(J[i], qd) + phi_t[i] for i in range(m)]
        if o >= 2:
            rows += [dot(J[i], qdd) - gamma[i] for i in range(m)]
        if dyn is not None:
            rhs = [S(e) for e in dyn.Q]
            if o == 2:
                M = [[zero] * n for _ in range(n)]
                Mvals = dyn._native["M"] if native else dyn.M_exprs
                Qv = dyn._native["Qv"] if native else dyn.Qv
                for i, j, e in zip(dyn.M_rows, dyn.M_cols, Mvals):
                    M[i][j] = M[i][j] + S(e)
                rhs = [rhs[j] + S(Qv[j]) - dot(M[j], qdd) for j in range(n)]
            elif o == 0:
                zero_qd = {x: zero for x in qd}
                rhs = [e.xreplace(zero_qd) if native else e.subs(zero_qd) for e in rhs]
            rows += [dot([J[i][j] for i in range(m)], lam) - rhs[j] for j in range(n)]
        # block columns: q, qd, qdd, lambda; then the unknown parameters, then T
        cols = q + (qd if o >= 1 else []) + (qdd if o >= 2 else []) + (lam if dyn else [])
        self._nb = len(cols)
        cols += [S(u) for u in self._unknowns] + [S(T)]
        self._native_derivation = native
        self._model_rows = len(rows)
        self._f_model, self._model_jac = self._compile(rows, cols, native)
        self._f_cond = [self._compile([S(e) for e in c], cols, native) for c in self._conds]
        self._u_index = [list(lay.p_symbols).index(u) for u in self._unknowns]
        self._u_off = self._layout()[1]

    def _compile(self, exprs, cols, native):
        """``(f, (rows, cols))``: ``f(x) = [exprs, nonzero d expr_i / d cols_j]`` with
        ``x = [t, q, qd, qdd, lambda, p]``."""
        index = {c: j for j, c in enumerate(cols)}
        r, c, d = [], [], []
        for i, e in enumerate(exprs):
            for w in sorted(e.free_symbols & index.keys(), key=lambda w: index[w]):
                de = e.diff(w) if native else _diff(e, w)
                if de != 0:
                    r.append(i)
                    c.append(index[w])
                    d.append(de)
        s = self.system
        lay = s.layout
        args = [T, *lay.q_symbols, *lay.qd_symbols, *lay.qdd_symbols, *s.lam_symbols,
                *lay.p_symbols]
        out = list(exprs) + d
        # couples rebuilt with the same equations (a sweep builds one per point) reuse the
        # compiled kernel of the model's System
        cache = _KERNELS.setdefault(s, {})
        key = (native, tuple(out))
        f = cache.get(key)
        if f is None:
            if native and s.backend != "symengine":
                out = to_sympy_list(out)
            f = cache[key] = compile_exprs(args, out, s.backend)
        return f, (np.array(r, dtype=int), np.array(c, dtype=int))

    # -- the stacked system ------------------------------------------------------------------
    def _layout(self):
        """Offsets of each configuration's block in ``z`` (block: nb, then its time if free)
        and of the parameters (last)."""
        offs, o = [], 0
        for free in self._free:
            offs.append(o)
            o += self._nb + (1 if free else 0)
        return offs, o

    def _args(self, z, offs, p_base, times):
        """The argument vectors ``[t, q, qd, qdd, lambda, p]`` (K, nargs) of the kernels."""
        s = self.system
        n, m, o, K = s.n, s.m, self._order, len(self._free)
        npar = len(p_base)
        X = np.zeros((K, 1 + 3 * n + m + npar))
        p = p_base.copy()
        p[self._u_index] = z[self._u_off:]
        for k in range(K):
            b = z[offs[k]: offs[k] + self._nb]
            X[k, 0] = z[offs[k] + self._nb] if self._free[k] else times[k]
            X[k, 1: 1 + n] = b[:n]
            if o >= 1:
                X[k, 1 + n: 1 + 2 * n] = b[n: 2 * n]
            if o >= 2:
                X[k, 1 + 2 * n: 1 + 3 * n] = b[2 * n: 3 * n]
            if self._loads:
                X[k, 1 + 3 * n: 1 + 3 * n + m] = b[n * (1 + o):]
            X[k, 1 + 3 * n + m:] = p
        return X

    def _evaluate(self, z, offs, p_base, times, with_jacobian=True):
        """Residual ``F`` and (dense or CSC) Jacobian of the stacked system at ``z``."""
        X = self._args(z, offs, p_base, times)
        R = self._model_rows
        out = self._f_model.batch(X)
        Fs, Jr, Jc, Jv = [], [], [], []
        row = 0
        nb = self._nb
        for k in range(len(self._free)):
            col_map = np.concatenate((offs[k] + np.arange(nb), self._u_off + np.arange(
                len(self._unknowns)), [offs[k] + nb if self._free[k] else -1]))
            parts = [(out[k], self._model_jac, R)]
            fc, (cr, cc) = self._f_cond[k]
            parts.append((fc(X[k]), (cr, cc), len(self._conds[k])))
            for vals, (rr, cc_), nrow in parts:
                Fs.append(vals[:nrow])
                gc = col_map[cc_]
                keep = gc >= 0
                Jr.append(row + rr[keep])
                Jc.append(gc[keep])
                Jv.append(vals[nrow:][keep])
                row += nrow
        F = np.concatenate(Fs)
        if not with_jacobian:
            return F, None
        N = self.size
        Jr, Jc, Jv = np.concatenate(Jr), np.concatenate(Jc), np.concatenate(Jv)
        if N > SPARSE_THRESHOLD:
            J = sps.csc_matrix((Jv, (Jr, Jc)), shape=(N, N))
        else:
            J = np.zeros((N, N))
            np.add.at(J, (Jr, Jc), Jv)
        return F, J

    # -- solving ---------------------------------------------------------------------------
    def solve(self, t=None, guess=None, options: PositionOptions | Mapping | None = None
              ) -> CoupleSolution:
        """Solve the couple (Mech's ``SolveCouple``); returns a :class:`CoupleSolution`.

        ``t``: new times of the configurations (a number for one configuration, else one per
        configuration), Mech's ``InitialCondition -> {Time -> t1, ...}``: the couple is solved
        again there without rebuilding; for a free time it is the starting value.
        ``guess``: a previous :class:`CoupleSolution` to start from (all its coordinates,
        velocities, multipliers, parameters and times); default the guesses the couple was
        built with. Unlike Mech, a solve never changes what the next starts from.
        ``options``: :class:`~mechsys.PositionOptions` (``ftol``, ``max_iterations``,
        ``damping``) or a mapping of its fields.
        """
        opt = self._options(options)
        s, K = self.system, len(self._free)
        n, o = s.n, self._order
        times = self._times(t)
        # the model's parameter values now, by symbol (parameters declared later do not shift)
        p_base = np.array([self.model._params[sym] for sym in s.layout.p_symbols], dtype=float)
        offs = self._layout()[0]
        z = np.zeros(self.size)
        z[self._u_off:] = [self._u_guess.get(u, p_base[i]) for u, i in
                           zip(self._unknowns, self._u_index)]
        starts = self._guesses
        if guess is not None:
            if not isinstance(guess, CoupleSolution) or guess.couple is not self:
                raise ModelError("CoupleSystem.solve: guess= must be a CoupleSolution of this "
                                 "couple (a previous result), or None")
            sol = guess.solution
            starts = [(sol.q[k], None if sol.qd is None else sol.qd[k],
                       None if sol.qdd is None else sol.qdd[k]) for k in range(K)]
            z[self._u_off:] = [guess.unknowns[u.name] for u in self._unknowns]
            if t is None:
                times = np.array(guess.times, dtype=float)
        p0 = p_base.copy()
        p0[self._u_index] = z[self._u_off:]
        scalings = []
        for k in range(K):
            q0, qd0, qdd0 = self._consistent(times[k], *starts[k], p0)
            b = offs[k]
            z[b: b + n] = q0
            if o >= 1 and qd0 is not None:
                z[b + n: b + 2 * n] = qd0
            if o >= 2 and qdd0 is not None:
                z[b + 2 * n: b + 3 * n] = qdd0
            if self._free[k]:
                z[b + self._nb] = times[k]
            Jq = s.jacobian(times[k], q0, p0)
            scalings.append(Scaling.of(s, q0, Jq))
        if self._loads:
            self._start_multipliers(z, offs, p_base, times, scalings)
        S, C = self._scales(z, offs, p_base, times, scalings)
        tol = opt.ftol * (1.0 + max(sc.offset for sc in scalings))
        F, J = self._evaluate(z, offs, p_base, times)
        history = [_norm(F, S)]
        it = 0
        while True:
            norm = history[-1]
            if not np.all(np.isfinite(F)):
                raise ConvergenceError(
                    "couple: the equations are not finite at the current iterate (a coordinate "
                    "or parameter left the domain of an expression); give better guesses",
                    residuals=F.copy(), history=tuple(history))
            if norm <= tol and it > 0:
                break
            if it >= opt.max_iterations:
                raise ConvergenceError(
                    f"couple did not converge in {opt.max_iterations} iterations (scaled residual "
                    f"{norm:.3e} > {tol:.1e}). Largest residuals:\n{self._table(F, S)}\n"
                    "Give better guesses (unknowns={name: value}, guess= or per-configuration "
                    "guesses), or check that the conditions can be met.",
                    residuals=F.copy(), history=tuple(history))
            try:
                dz = -C * factor(_scaled(J, S, C)).solve(F / S)
            except Singular:
                raise self._singular(J, S, C) from None
            a = 1.0
            while True:
                zn = z + a * dz
                Fn, _ = self._evaluate(zn, offs, p_base, times, with_jacobian=False)
                nn = _norm(Fn, S)
                if not opt.damping or nn <= (1 - 1e-4 * a) * norm or a < 1e-3:
                    break
                a *= 0.5
            z = zn
            F, J = self._evaluate(z, offs, p_base, times)
            history.append(_norm(F, S))
            it += 1
        return self._result(z, offs, p_base, times, it, history)

    def _consistent(self, t, q, qd, qdd, p):
        """A start on the constraints at the starting parameters: the position solved from
        the guess, and velocities and accelerations solved there (a velocity couple started
        at rest would have a singular Jacobian: at ``qd = 0`` no velocity depends on the
        parameters). Where the model does not assemble at the start, the raw guess."""
        s = self.system
        if s.m != s.n:
            return q, qd, qdd
        try:
            q = solve_position(s, t, q, p=p).q
            if self._order >= 1:
                qd = solve_velocity(s, t, q, p)
            if self._order >= 2:
                qdd = solve_acceleration(s, t, q, qd, p)
        except MechError:
            pass
        return q, qd, qdd

    @staticmethod
    def _options(options) -> PositionOptions:
        if options is None:
            return PositionOptions()
        if isinstance(options, Mapping):
            fields = PositionOptions.__dataclass_fields__
            unknown_options("options (PositionOptions)", set(options) - set(fields), fields)
            return PositionOptions(**options)
        if not isinstance(options, PositionOptions):
            raise ModelError(f"options must be a PositionOptions or a mapping of its fields, got "
                             f"{options!r}")
        return options

    def _times(self, t) -> np.ndarray:
        K = len(self._free)
        if t is None:
            return np.array(self._t0, dtype=float)
        vals = [t] if (K == 1 and isinstance(t, Real)) else t
        if isinstance(vals, (str, bytes)) or not isinstance(vals, Sequence | np.ndarray) or \
                len(vals) != K:
            raise ModelError(f"CoupleSystem.solve: t must give one time per configuration ({K}), "
                             f"got {t!r}")
        out = []
        for k, v in enumerate(vals):
            if isinstance(v, bool) or not isinstance(v, Real) or not np.isfinite(v):
                raise ModelError(f"CoupleSystem.solve: the time of configuration {k + 1} must be "
                                 f"a finite number, got {v!r}")
            out.append(float(v))
        return np.array(out)

    def _start_multipliers(self, z, offs, p_base, times, scalings):
        """Multipliers at the start: least squares of the (linear in lambda) load rows."""
        s = self.system
        n, m, o = s.n, s.m, self._order
        lo = n * (1 + o)
        F, J = self._evaluate(z, offs, p_base, times)
        J = J.toarray() if sps.issparse(J) else J
        R = self._model_rows
        stride = [R + len(c) for c in self._conds]
        row = 0
        for k in range(len(self._free)):
            r0 = row + m * (1 + o)
            A = J[r0: r0 + n, offs[k] + lo: offs[k] + lo + m]
            rhs = -F[r0: r0 + n] + A @ z[offs[k] + lo: offs[k] + lo + m]
            z[offs[k] + lo: offs[k] + lo + m] = np.linalg.lstsq(A, rhs, rcond=None)[0]
            row += stride[k]

    def _scales(self, z, offs, p_base, times, scalings):
        """Row scales ``S`` and column scales ``C`` of the unit-free form (module docstring)."""
        s = self.system
        n, m, o, K = s.n, s.m, self._order, len(self._free)
        F, J = self._evaluate(z, offs, p_base, times)
        J = J.toarray() if sps.issparse(J) else np.asarray(J)
        N = self.size
        S, C = np.zeros(N), np.zeros(N)
        model_rows = np.zeros(N, dtype=bool)
        R = self._model_rows
        row = 0
        for k in range(K):
            sc, b = scalings[k], offs[k]
            Jq = s.jacobian(times[k], z[b: b + n], self._p_at(z, p_base))
            r = sc.rows(Jq)
            for lev in range(1 + o):
                C[b + lev * n: b + (lev + 1) * n] = sc.columns
                S[row + lev * m: row + (lev + 1) * m] = r
            if self._loads:
                lo = b + n * (1 + o)
                fr = row + m * (1 + o)
                lam = z[lo: lo + m]
                rhs = J[fr: fr + n, lo: lo + m] @ lam - F[fr: fr + n]   # = rhs of J^T lam = rhs
                W = float(np.abs(sc.columns * rhs).max(initial=0.0))
                W = W if W > 0 else 1.0
                C[lo: lo + m] = W / r
                S[fr: fr + n] = W / sc.columns
            model_rows[row: row + R] = True
            row += R + len(self._conds[k])
        # unknown parameters and free times: unit in which the largest effect on a model row is 1
        extra = list(range(self._u_off, N)) + [offs[k] + self._nb for k in range(K) if self._free[k]]
        for j in extra:
            col = np.abs(J[model_rows, j]) / S[model_rows]
            big = col.max(initial=0.0)
            C[j] = 1.0 / big if big > 0 else max(abs(z[j]), 1.0)
        # condition rows: by their largest scaled entry
        cond = ~model_rows
        sizes = np.abs(J[cond] * C).max(axis=1) if cond.any() else np.zeros(0)
        sizes[~(sizes > 0)] = 1.0
        S[cond] = sizes
        return S, C

    def _p_at(self, z, p_base):
        p = p_base.copy()
        p[self._u_index] = z[self._u_off:]
        return p

    # -- diagnosis ---------------------------------------------------------------------------
    def _labels(self):
        """Labels of the stacked rows and columns (for errors)."""
        s = self.system
        lay = s.layout
        n, m, o = s.n, s.m, self._order
        rows, cols = [], []
        kinds = ["", "velocity equation of ", "acceleration equation of "]
        for k, cs in enumerate(self._conds):
            pre = f"configuration {k + 1}: " if len(self._conds) > 1 else ""
            for lev in range(1 + o):
                rows += [pre + kinds[lev] + lay.row_label(i) for i in range(m)]
            if self._loads:
                rows += [pre + f"load balance on {lay.q_names[j]}" for j in range(n)]
            rows += [pre + f"condition {i + 1} ({e} = 0)" for i, e in enumerate(cs)]
            names = list(lay.q_names)
            cols += [pre + f"coordinate {x}" for x in names]
            if o >= 1:
                cols += [pre + f"velocity {x}_d" for x in names]
            if o >= 2:
                cols += [pre + f"acceleration {x}_dd" for x in names]
            if self._loads:
                cols += [pre + f"multiplier {lam}" for lam in s.lam_symbols]
            if self._free[k]:
                cols.append(f"the time of configuration {k + 1} (t=ms.Free)")
        cols += [f"parameter {u.name!r}" for u in self._unknowns]
        return rows, cols

    def _table(self, F, S, k=8):
        rows, _ = self._labels()
        order = np.argsort(-np.abs(F / S))[:k]
        return "\n".join(f"  {rows[i]}: {F[i]:+.3e}" for i in order)

    def _singular(self, J, S, C) -> SingularJacobianError:
        Jh = _scaled(J, S, C)
        Jh = Jh.toarray() if sps.issparse(Jh) else Jh
        rank, dep = dependent_rows(Jh)
        rows, cols = self._labels()
        _, sv, Vt = np.linalg.svd(Jh)
        null = Vt[rank:]
        free_cols = [j for j in range(Jh.shape[1])
                     if null.size and np.abs(null[:, j]).max() > 1e-6]
        unknown_cols = [cols[j] for j in free_cols if j >= self._u_off or "time of" in cols[j]]
        msg = (f"couple: the Jacobian of the coupled system is singular (rank {rank} of "
               f"{self.size} equations and unknowns). ")
        if unknown_cols:
            msg += ("The conditions do not determine " + ", ".join(unknown_cols)
                    + " independently: ")
        msg += "dependent equations: " + "; ".join(rows[i] for i in dep) + ". "
        msg += ("A condition may not depend on the unknowns at all, two conditions may say the "
                "same thing, or the mechanism may be at a lock-up; change the conditions or "
                "the unknowns, or start elsewhere.")
        return SingularJacobianError(msg, dependent=[rows[i] for i in dep], rank=rank)

    # -- results -----------------------------------------------------------------------------
    def _result(self, z, offs, p_base, times, its, history) -> CoupleSolution:
        s = self.system
        n, o, K = s.n, self._order, len(self._free)
        p = self._p_at(z, p_base)
        tt = np.array([z[offs[k] + self._nb] if self._free[k] else times[k] for k in range(K)])
        blocks = [z[offs[k]: offs[k] + self._nb] for k in range(K)]
        Q = np.array([b[:n] for b in blocks])
        QD = np.array([b[n: 2 * n] for b in blocks]) if o >= 1 else None
        QDD = np.array([b[2 * n: 3 * n] for b in blocks]) if o >= 2 else None
        LAM = np.array([b[n * (1 + o):] for b in blocks]) if self._loads else None
        for a in (tt, Q, QD, QDD, LAM):
            if a is not None:
                a.setflags(write=False)
        sol = Solution(t=tt, q=Q, qd=QD, qdd=QDD, p=p, system=s, model=self.model,
                       iterations=np.full(K, its), lam=LAM, mode=self.solution,
                       message="couple solved")
        configs = tuple(Solution(t=tt[k: k + 1], q=Q[k: k + 1],
                                 qd=None if QD is None else QD[k: k + 1],
                                 qdd=None if QDD is None else QDD[k: k + 1], p=p, system=s,
                                 model=self.model, iterations=np.array([its]), scalar=True,
                                 lam=None if LAM is None else LAM[k: k + 1], mode=self.solution,
                                 message="couple solved")
                        for k in range(K))
        unknowns = {u.name: float(z[self._u_off + i]) for i, u in enumerate(self._unknowns)}
        params = {sym.name: float(v) for sym, v in zip(s.layout.p_symbols, p)}
        return CoupleSolution(unknowns=unknowns, times=tt, solution=sol, configurations=configs,
                              parameters=params, iterations=its, residual=float(history[-1]),
                              history=tuple(history), couple=self)

    def __repr__(self) -> str:
        names = ", ".join(u.name for u in self._unknowns)
        nf = sum(self._free)
        return (f"<CoupleSystem ({self.solution}): unknowns {names}"
                + (f" and {nf} free time(s)" if nf else "")
                + f"; {len(self._conds)} configuration(s); {self.size} equations>")


def _norm(F, S) -> float:
    return float(np.abs(F / S).max()) if F.size else 0.0


def _scaled(J, S, C):
    if sps.issparse(J):
        return sps.csc_matrix(sps.diags(1.0 / S) @ J @ sps.diags(C))
    return (J * C) / S[:, None]


@dataclass(frozen=True, eq=False)
class CoupleSolution:
    """The result of :meth:`CoupleSystem.solve` (Mech's ``SolveCouple`` rules).

    ``unknowns``: ``{parameter name: value}``; ``times`` (K,): each configuration's time
    (solved when free); ``solution``: a :class:`~mechsys.Solution` over the ``K``
    configurations (one "point" each, with the solved parameters), so every output works on
    it (``res.solution.location(p)`` is ``(K, dim)``); ``configurations``: one single-point
    Solution per configuration; ``parameters``: all parameter values with the solved ones
    (``m.set_parameters(res.parameters)`` keeps them, as Mech does); ``iterations``,
    ``residual`` (scaled), ``history``. ``res["c"]`` is an unknown's value; output functions
    (``res.location``, ``res.eval`` ...) are those of ``solution``.
    """

    unknowns: dict
    times: np.ndarray
    solution: Solution
    configurations: tuple
    parameters: dict
    iterations: int
    residual: float
    history: tuple = field(default=())
    couple: object = None

    def __getitem__(self, name):
        key = name.name if isinstance(name, sp.Symbol) else str(name)
        if key in self.unknowns:
            return self.unknowns[key]
        if key == T.name and len(self.times) == 1:
            return float(self.times[0])
        raise ModelError(f"{name!r} is not an unknown of this couple; unknowns are "
                         f"{sorted(self.unknowns)} (times: res.times)")

    def __len__(self) -> int:
        return len(self.configurations)

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return getattr(self.solution, name)
        except AttributeError:
            raise AttributeError(f"CoupleSolution has no attribute {name!r}") from None

    def __repr__(self) -> str:
        vals = ", ".join(f"{k}={v:.6g}" for k, v in self.unknowns.items())
        return (f"<CoupleSolution: {vals}; times {np.array2string(self.times, precision=6)}; "
                f"{self.iterations} Newton iterations>")


__all__ = ["Configuration", "CoupleSolution", "CoupleSystem", "Free", "FreeTime"]
