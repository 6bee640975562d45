r"""Tangent (directional-derivative) kernels for parameter sensitivities (Mech's
``SetSensitivity``, manual section 9.5).

For the residuals of each level of a solution, with :math:`z = (q, \dot q, \ddot q, \lambda, p_s)` (the
coordinates, velocities, accelerations, multipliers and the *selected* parameters ``p_s``):

.. math::

    \text{position:} \quad & \Phi(t, q, p) \quad (m) \\
    \text{velocity:} \quad & V = \Phi_q \dot q + \Phi_t \quad (m) \\
    \text{acceleration:} \quad & A = \Phi_q \ddot q - \gamma \quad (m) \\
    \text{loads:} \quad & R = \Phi_q^T \lambda - Q \quad (n)
        \quad \text{statics, kinematic loads} \\
    \text{dynamics:} \quad & R = \Phi_q^T \lambda - (Q + Q_v - M \ddot q) \quad (n)
        \quad \text{inverse dynamics, free motion}

each kernel returns the directional derivative :math:`dF = \sum_j dF/dz_j dz_j` for a direction
``dz = (dq, dqd, dqdd, dlambda, dp)``, derived symbolically once (SymEngine when the system
was derived with it, else SymPy) and compiled as a function of
:math:`[t, q, \dot q, \ddot q, \lambda, p, dq, d\dot q, d\ddot q, d\lambda, dp]`. A sensitivity solve sets the
direction of the unknown of its level to zero and solves, for example, at the velocity level
:math:`\Phi_q d\dot q/dp = -(V_q dq/dp + V_p)` (``V_qd = Phi_q``). A derivative is linear in the
direction, so one compiled call serves every parameter and every time point (``batch``).
"""

from __future__ import annotations

import sympy as sp

from .._symbols import T
from ._backends import compile_exprs
from ._derive import _diff, _rewrite_steps

try:  # optional
    import symengine as se
except ImportError:  # pragma: no cover
    se = None

LEVELS = ("position", "velocity", "acceleration", "loads", "dynamics")


class TangentKernels:
    r"""Compiled directional derivatives of a :class:`~mechsys.compile.System`'s residuals
    with respect to :math:`(q, \dot q, \ddot q, \lambda)` and the parameters ``params`` (a subset of
    ``layout.p_symbols``). Kernels are derived and compiled on first use, per level."""

    def __init__(self, system, params):
        self.system = system
        lay = system.layout
        self.params = tuple(params)
        n, m, k = lay.n, lay.m, len(self.params)
        lam = tuple(system.lam_symbols)
        self.base = [T, *lay.q_symbols, *lay.qd_symbols, *lay.qdd_symbols, *lam, *lay.p_symbols]
        self.dirs = [sp.Symbol(f"_sens_d{j}") for j in range(3 * n + m + k)]
        self.wrt = [*lay.q_symbols, *lay.qd_symbols, *lay.qdd_symbols, *lam, *self.params]
        self._kernels: dict = {}
        #: compiled output derivatives (:class:`ExpressionTangent`), by expression tuple
        self.expression_cache: dict = {}
        # SymEngine differentiates ~100x faster; floors and the functions it cannot
        # differentiate stay with SymPy (as compile/_derive.py decides for the Jacobian)
        self._native = (se is not None and system.backend == "symengine"
                        and system._native is not None
                        and not any(sp.sympify(e).has(sp.floor) for e in system.phi))

    # -- residual expressions of each level -----------------------------------------------
    def _exprs(self, level: str) -> list:
        s = self.system
        lay = s.layout
        n, m = lay.n, lay.m
        native = self._native
        cv = (lambda e: se.sympify(e)) if native else (lambda e: sp.sympify(e))
        zero = cv(0)
        if level == "position":
            return list(s._native["phi"]) if native else list(s.phi)
        jac = s.kinematic_exprs("jac", for_compile=native)
        rows, cols = s.jac_rows, s.jac_cols
        if level in ("velocity", "acceleration"):
            vec = lay.qd_symbols if level == "velocity" else lay.qdd_symbols
            out = [zero] * m
            for i, j, e in zip(rows, cols, jac):
                out[i] = out[i] + e * cv(vec[j])
            last = s.kinematic_exprs("phi_t" if level == "velocity" else "gamma", for_compile=native)
            sign = 1 if level == "velocity" else -1
            return [o + sign * e for o, e in zip(out, last)]
        dyn = s.dynamics
        out = [zero] * n
        lam = s.lam_symbols
        for i, j, e in zip(rows, cols, jac):            # Phi_q^T lambda
            out[j] = out[j] + e * cv(lam[i])
        out = [o - cv(q) for o, q in zip(out, dyn.Q)]
        if level == "dynamics":
            Mv = dyn.for_compile("M") if native else dyn.M_exprs
            for i, j, e in zip(dyn.M_rows, dyn.M_cols, Mv):
                out[i] = out[i] + e * cv(lay.qdd_symbols[j])
            Qv = dyn.for_compile("Qv") if native else dyn.Qv
            out = [o - cv(e) for o, e in zip(out, Qv)]
        return out

    def _tangent(self, exprs) -> list:
        """``sum_j dF/dz_j dz_j`` of each expression."""
        native = self._native
        if native:
            wrt = [se.sympify(w) for w in self.wrt]
            dirs = [se.sympify(d) for d in self.dirs]
        else:
            wrt, dirs = self.wrt, self.dirs
        index = {w: i for i, w in enumerate(wrt)}
        out = []
        for e in exprs:
            if not native:
                e = _rewrite_steps(sp.sympify(e))
            acc = se.Integer(0) if native else sp.S.Zero
            for s_ in e.free_symbols:
                i = index.get(s_)
                if i is not None:
                    d = e.diff(s_) if native else _diff(e, s_)
                    if d != 0:
                        acc = acc + d * dirs[i]
            out.append(acc)
        return out

    def kernel(self, level: str):
        """The compiled tangent of ``level`` (one of :data:`LEVELS`)."""
        f = self._kernels.get(level)
        if f is None:
            f = compile_exprs(self.base + self.dirs, self._tangent(self._exprs(level)),
                              self.system.backend)
            self._kernels[level] = f
        return f

    def uses(self) -> dict:
        """``{parameter: where}`` for the selected parameters that appear in the constraint
        equations (``"constraints"``), else in the loads or mass properties (``"loads"``),
        else in the bodies' points (``"points"``: outputs such as a coupler point's location
        depend on them); parameters used nowhere are absent."""
        s = self.system
        found = {}
        phi_syms = set().union(*(sp.sympify(e).free_symbols for e in s.phi)) if s.phi else set()
        for p in self.params:
            if p in phi_syms:
                found[p] = "constraints"
        rest = [p for p in self.params if p not in found]
        if rest and (s._loads or any(b.mass != 0 for b in s._bodies)):
            dyn = s.dynamics
            syms = set()
            for e in [*dyn.Q, *dyn.M_exprs, *dyn.Qv]:
                syms |= sp.sympify(e).free_symbols
            for p in rest:
                if p in syms:
                    found[p] = "loads"
        rest = [p for p in self.params if p not in found]
        for b in s._bodies if rest else ():
            # a point of a body that no constraint uses (a coupler point): outputs depend on it
            for coords in [*b.points.values(), b.centroid]:
                syms = set().union(*(sp.sympify(c).free_symbols for c in coords))
                for p in rest:
                    if p in syms:
                        found.setdefault(p, "points")
        return found


class ExpressionTangent:
    r"""The compiled directional derivative of user expressions of
    :math:`[t, q, \dot q, \ddot q, \lambda, p]` (an output: a location, a reaction, any ``sol.eval``
    expression), with the same argument order as :class:`TangentKernels`."""

    def __init__(self, kernels: TangentKernels, exprs):
        self.exprs = [sp.sympify(e) for e in exprs]
        allowed = set(kernels.base)
        for e in self.exprs:
            extra = e.free_symbols - allowed
            if extra:
                from .._errors import ModelError

                raise ModelError(
                    f"expression {e} has symbols {sorted(map(str, extra))} that are not "
                    "coordinates, velocities, accelerations, multipliers, parameters or T "
                    "of this model")
        out = []
        index = {w: i for i, w in enumerate(kernels.wrt)}
        for e in self.exprs:
            e = _rewrite_steps(e)
            acc = sp.S.Zero
            for s_ in e.free_symbols:
                i = index.get(s_)
                if i is not None:
                    acc += _diff(e, s_) * kernels.dirs[i]
            out.append(acc)
        self.f = compile_exprs(kernels.base + kernels.dirs, out, kernels.system.backend)
