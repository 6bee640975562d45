r"""Velocity (nonholonomic) constraints in free motion (issue 36 item 1, decision 0053).

A free system whose model holds velocity constraints :math:`\psi(q, \dot q, t) = 0` linear in the
rates, :math:`\psi = A(q, t)\,\dot q + b(q, t)` (the rolling contacts, a user ``Constraint``
of velocity expressions), moves by

.. math::

    \begin{bmatrix} M & \Phi_q^T & A^T \\ \Phi_q & 0 & 0 \\ A & 0 & 0 \end{bmatrix}
    \begin{bmatrix} \ddot q \\ \lambda \\ \mu \end{bmatrix} =
    \begin{bmatrix} Q + Q_v \\ \gamma \\ -\rho \end{bmatrix}, \qquad
    \rho = \psi_q \dot q + \psi_t

(:math:`\dot\psi = A \ddot q + \rho = 0`). The multipliers :math:`\mu` are the velocity
constraints' reactions: the generalized force they apply is :math:`-A^T \mu`. The state is
projected (after each step and at the start) onto :math:`\Phi = 0` and then, with the
smallest scaled velocity change, onto :math:`\Phi_q \dot q + \Phi_t = 0` and
:math:`A \dot q + b = 0` together.

These functions are the Python stepper's. The compiled free-motion stepper holds the same
rows (kind ``ROLLING``, decision 0062: ``solvers/_jit_free_loop._accel_rows`` is
:func:`nonholonomic_acceleration`, ``_project_rows`` the velocity half of
:func:`project_state`, operation for operation, on the same kernels: the free kernel and
:class:`VelocityRows`' ``A, b, rho``); it hands a step it cannot take to these, and the
event-driven stepper of switched systems uses only these.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps
import sympy as sp

from .._errors import ModelError, SingularJacobianError
from .._symbols import T
from ..compile import compile_exprs
from ..compile._derive import sparse_derivatives
from ..constraints import velocity_rows
from ..constraints._switches import is_velocity_constraint
from ..solvers._free import _solve_fast, free_acceleration, project_positions
from ..solvers._tolerances import SPARSE_THRESHOLD, Singular

try:  # optional
    import symengine as se
except ImportError:  # pragma: no cover
    se = None


def velocity_constraints(model, dropped=()) -> list:
    """The model's constraints (not in ``dropped``) that are velocity constraints: ``order ==
    1`` (the rolling classes) or equations that use the rates (a ``Constraint`` or
    ``Orthogonal1`` of velocity expressions). (Equations are cached per constraint.)"""
    rates = set(model.velocity_symbols().values())
    # (a switch is not one: the velocity constraints inside its stages are
    # switched_velocity_constraints, held stage by stage, decision 0063)
    gone = {id(d) for d in dropped}      # (a set: a 1024-link chain drops 1024 of 3072)
    return [c for c in model._constraints if id(c) not in gone
            and is_velocity_constraint(c, model.space, rates)]


class VelocityRows:
    r"""The compiled rows :math:`A(q, t)` (k, n), :math:`b(q, t)` (k,) and :math:`\rho(q,
    \dot q, t)` (k,) of the velocity constraints ``constraints`` on ``system`` (the free
    system's holonomic part: the same coordinates, in its order). ``owners[i]`` is the
    constraint of row ``i``. A constraint whose equations are not linear in the rates raises
    :class:`ModelError` naming it. ``A_sym``, ``b_sym`` keep the rows as SymPy matrices (the
    equilibria's residuals take them, decision 0055); ``rho=False`` (the equilibria, which
    do not need :math:`\rho`) leaves its costly derivatives out and ``evaluate`` returns
    zeros for it."""

    def __init__(self, model, system, constraints, rho: bool = True):
        lay = system.layout
        q, qd = list(lay.q_symbols), list(lay.qd_symbols)
        psi, owners = checked_equations(model, system, constraints)
        rows = velocity_rows(psi, q, qd, rho=rho)
        self.psi = psi                     # (kept for the linearisation's derivatives)
        self._derivs = None
        self.k, self.n = len(psi), system.n
        self.A_sym, self.b_sym, self.rho_sym = rows.A, rows.b, rows.rho
        self.owners = owners
        self.constraints = list(constraints)
        self.system = system
        self._f = compile_exprs(lay.args(), list(rows.A) + list(rows.b) + list(rows.rho),
                                system.backend)

    def evaluate(self, t, q, qd, p):
        """``(A (k, n), b (k,), rho (k,))`` at ``(t, q, qd)``."""
        out = np.asarray(self._f(self.system.pack(t, q, qd, p)), dtype=float).ravel()
        k, n = self.k, self.n
        rho = out[k * n + k:] if out.size > k * n + k else np.zeros(k)
        return out[:k * n].reshape(k, n), out[k * n:k * n + k], rho

    def derivatives(self, t, q, qd, qdd, mu, p):
        r"""Exact derivatives for the linearisation (:mod:`mechsys.analyses._linearize`), at
        one state with the rows' multipliers ``mu``: ``(psi_q, a_q, a_qd, F_q)`` with
        :math:`\psi = A \dot q + b` (its change with the positions, (k, n)),
        :math:`a = A \ddot q + \rho` (the acceleration rows, (k, n) each) and
        :math:`F = A^T \mu` (the rows' generalized force, (n, n)). Derived symbolically
        (SymEngine when the system's backend is) and compiled on first use."""
        if self._derivs is None:
            self._derivs = self._derive()
        f, parts = self._derivs
        vals = np.asarray(f(np.concatenate((self.system.pack(t, q, qd, p), qdd, mu))),
                          dtype=float).ravel()
        out, i = [], 0
        for (rows, cols), shape in zip(parts, ((self.k, self.n),) * 3 + ((self.n, self.n),)):
            D = np.zeros(shape)
            np.add.at(D, (rows, cols), vals[i:i + len(rows)])
            out.append(D)
            i += len(rows)
        return tuple(out)

    def _derive(self):
        lay = self.system.layout
        native = se is not None and self.system.backend == "symengine"
        conv = se.sympify if native else sp.sympify
        q = [conv(s) for s in lay.q_symbols]
        qd = [conv(s) for s in lay.qd_symbols]
        qdd = [conv(s) for s in lay.qdd_symbols]
        mu = [sp.Symbol(f"_mu{i}") for i in range(self.k)]
        muc = [conv(s) for s in mu]
        t = conv(T)
        psi = [conv(e) for e in self.psi]
        exprs: list = []
        parts = []

        def derive(E, wrt):
            parts.append(sparse_derivatives(E, wrt, exprs))

        # A = psi_qd, rho = psi_q qd + psi_t, a = A qdd + rho (each row against the
        # coordinates it contains)
        a, F = [], [conv(0)] * self.n
        for i, e in enumerate(psi):
            free = e.free_symbols
            r = e.diff(t) if t in free else conv(0)
            for j, (x, v, w) in enumerate(zip(q, qd, qdd)):
                if x in free:
                    r = r + e.diff(x) * v
                if v in free:
                    Aij = e.diff(v)
                    r = r + Aij * w
                    F[j] = F[j] + Aij * muc[i]
            a.append(r)
        derive(psi, q)
        derive(a, q)
        derive(a, qd)
        derive(F, q)
        args = [*lay.args(), *lay.qdd_symbols, *mu]
        return compile_exprs(args, exprs, self.system.backend), parts

    def residual(self, t, q, qd, p) -> np.ndarray:
        """:math:`A \\dot q + b` (k,)."""
        A, b, _ = self.evaluate(t, q, qd, p)
        return A @ qd + b


def checked_equations(model, system, constraints) -> tuple[list, list]:
    """``(psi, owners)``: the equations of the velocity ``constraints`` in the coordinates of
    ``system`` and the constraint of each row. A constraint that uses symbols the system
    does not know, or whose equations are not linear in the rates, raises
    :class:`ModelError` naming it."""
    lay = system.layout
    q, qd = list(lay.q_symbols), list(lay.qd_symbols)
    allowed = set(q) | set(qd) | set(lay.p_symbols) | {T}
    gen = model._gen_substitution()
    psi, owners = [], []
    for c in constraints:
        eqs = [e.xreplace(gen) if gen else e for e in c.equations(model.space)]
        for e in eqs:
            extra = e.free_symbols - allowed
            if extra:
                raise ModelError(f"{c.label()} uses unknown symbol(s) "
                                 f"{sorted(map(str, extra))}")
        if not velocity_rows(eqs, q, qd, rho=False).linear:
            raise ModelError(
                f"free(): the velocity constraint {c.label()} is not linear in the "
                "velocities, so it has no form A(q, t) qd + b(q, t) = 0 that free motion "
                "can hold; write it linear in the rates (e.g. a component of a velocity "
                "along a direction), or use a path system (m.path) for it")
        psi += eqs
        owners += [c] * len(eqs)
    return psi, owners


def nonholonomic_acceleration(system, rows: VelocityRows, t, q, qd, p, lam_guess=None,
                              **newton):
    r"""``(qdd (n,), multipliers (m + k,))`` of the free motion with velocity rows: the
    augmented system of the module docstring, solved dense (LAPACK). The multipliers are
    :math:`(\lambda, \mu)`. A singular matrix (dependent rows, or mass missing on a free
    motion) raises :class:`SingularJacobianError` naming the velocity constraints.

    Loads that depend on the multipliers (joint friction) or on the accelerations make the
    system nonlinear: then the Newton iteration of
    :func:`~mechsys.solvers._free.free_acceleration` runs on the bordered system (its
    ``rows``; ``lam_guess`` the start of :math:`(\lambda, \mu)`, ``newton`` its ``tol``,
    ``max_iterations`` and ``columns``; decision 0068).

    Example::

        qdd, lam_mu = nonholonomic_acceleration(free.system, free._vrows, 0.0, q, qd, p)
    """
    n, m, k = system.n, system.m, rows.k
    dyn = system.dynamics
    if dyn.depends_on_lambda or dyn.depends_on_qdd:
        A, _, rho = rows.evaluate(t, q, qd, p)
        try:
            qdd, lam, _ = free_acceleration(system, t, q, qd, p, lam_guess, rows=(A, rho),
                                            **newton)
        except Singular:
            raise _singular_rows(rows, t) from None
        return qdd, lam
    kern = dyn.free_kernel(n + m > SPARSE_THRESHOLD)
    K0, rhs0 = kern(t, q, qd, np.zeros(m), p)
    K0 = K0.toarray() if sps.issparse(K0) else np.asarray(K0)
    A, _, rho = rows.evaluate(t, q, qd, p)
    N = n + m + k
    K = np.zeros((N, N))
    K[:n + m, :n + m] = K0
    K[:n, n + m:] = A.T
    K[n + m:, :n] = A
    rhs = np.concatenate((rhs0, -rho))
    try:
        x = _solve_fast(K, rhs)
    except Singular:
        raise _singular_rows(rows, t) from None
    return x[:n], x[n:]


def _singular_rows(rows: VelocityRows, t) -> SingularJacobianError:
    """The error for a singular augmented system bordered by the velocity rows ``rows``."""
    names = ", ".join(sorted({c.label() for c in rows.constraints}))
    return SingularJacobianError(
        f"free acceleration at t = {t:.6g}: the augmented system with the velocity "
        f"constraints ({names}) is singular: their rows are dependent on each other or on "
        "the holonomic constraints (e.g. a no-slip row that is the derivative of a kept "
        "position constraint), or a free motion carries no mass; remove the redundant "
        "constraint or give the bodies mass and inertia", time=t)


def velocity_matrix(system, rows: VelocityRows, t, q, p):
    r"""``(G (m + k, n), g (m + k,))``: the velocity equations :math:`G \dot q = g` of the holonomic
    (:math:`\Phi_q \dot q = -\Phi_t`) and the velocity constraints (:math:`A \dot q = -b`) stacked."""
    if system.m:
        J, rhs = system.velocity_rhs(t, q, p)
        J = J.toarray() if sps.issparse(J) else np.asarray(J, dtype=float)
    else:                   # (no holonomic rows: a free body on a knife edge)
        J, rhs = np.zeros((0, system.n)), np.zeros(0)
    A, b, _ = rows.evaluate(t, q, np.zeros(system.n), p)
    return np.vstack((J, A)), np.concatenate((np.asarray(rhs, dtype=float), -b))


def project_velocities(system, rows: VelocityRows, t, q, qd, p, scaling, hold=()):
    r"""The smallest scaled change of ``qd`` (``hold``: indices kept as given) onto
    :math:`\Phi_q \dot q + \Phi_t = 0` and :math:`A \dot q + b = 0` (least squares in the
    unit-free columns of ``scaling``, each row divided by its scale). Returns ``(qd, left)``,
    ``left`` the scaled residual after the change (relative to the largest scaled rate)."""
    G, g = velocity_matrix(system, rows, t, q, p)
    r = scaling.rows(G)
    Gs = np.asarray(scaling.scaled(G, r), dtype=float).copy()
    Gs[:, list(hold)] = 0.0
    dx = np.linalg.lstsq(Gs, -(G @ qd - g) / r, rcond=1e-12)[0]
    qd = qd + scaling.columns * dx
    left = np.abs((G @ qd - g) / r).max(initial=0.0)
    return qd, left / (1.0 + np.abs(qd / scaling.columns).max(initial=0.0))


def project_state(system, rows: VelocityRows, t, q, qd, p, scaling, rank_tolerant=False):
    """``(q, qd)`` projected: positions onto ``Phi = 0``
    (:func:`~mechsys.solvers._free.project_positions`), then velocities by
    :func:`project_velocities`."""
    q = project_positions(system, t, q, p, scaling=scaling, rank_tolerant=rank_tolerant)
    qd, _ = project_velocities(system, rows, t, q, np.asarray(qd, dtype=float), p, scaling)
    return q, qd


def velocity_drift(system, rows: VelocityRows, t, q, qd, p, scaling) -> float:
    r"""The largest scaled velocity-constraint residual :math:`\max_i |(A \dot q + b)_i| /
    r_i` over the largest scaled rate (the ``accuracy["nonholonomic"]`` of a run)."""
    A, b, _ = rows.evaluate(t, q, qd, p)
    r = scaling.rows(A)
    rate = np.abs(qd / scaling.columns).max(initial=0.0)
    v = np.abs((A @ qd + b) / r).max(initial=0.0)
    return float(v / rate) if rate > 0 else float(v)


def row_names(rows: VelocityRows) -> list[str]:
    """The names of the rows' multipliers, ``"knife[0]"`` (constraint name, row within it):
    the columns of ``sol.extra["mu"]`` (``sol.extra["velocity_multipliers"]``). Rows of
    owners with the same name are counted together (the velocity constraints of one stage
    of a switch, ``"edge.stage2[0]"``, ``"edge.stage2[1]"``, decision 0063: ``rows`` is
    anything with ``owners``, each with a ``name``)."""
    count: dict = {}
    names = []
    for c in rows.owners:
        count[c.name] = count.get(c.name, 0) + 1
        names.append(f"{c.name}[{count[c.name] - 1}]")
    return names


def switched_velocity_constraints(model) -> list[tuple]:
    """``(switch, stage (1-based), constraint)`` of every velocity constraint inside a stage
    of a ``StageSwitch``/``TimeSwitch`` of ``model``, in the switches' order, stage by stage
    (free motion through stage changes holds them in their stages, decision 0063)."""
    rates = set(model.velocity_symbols().values())
    return [(sw, k + 1, c) for sw in model._switches() for k, stage in enumerate(sw.stages)
            for c in stage if is_velocity_constraint(c, model.space, rates)]


class RowTangent:
    r"""The parameter derivatives the velocity rows add to the forward sensitivities of free
    motion (decision 0055). With the multipliers :math:`\mu` and the accelerations held, the
    compiled Jacobians of

    .. math::

        f_1 = A^T \mu \ (n), \qquad f_2 = A \ddot q + \rho \ (k), \qquad
        f_3 = A \dot q + b \ (k)

    with respect to :math:`q`, :math:`\dot q` and the parameters ``params``: differentiating
    :math:`M \ddot q + \Phi_q^T \lambda + A^T \mu = Q + Q_v` and
    :math:`A \ddot q + \rho = 0` along a parameter adds :math:`f_{1,q} s_q + f_{1,p}` to the
    balance and the rows :math:`A s_{\ddot q} + f_{2,q} s_q + f_{2,\dot q} s_{\dot q} + f_{2,p}
    = 0`; the velocity level :math:`A s_{\dot q} + f_{3,q} s_q + f_{3,p} = 0` is what the
    sensitivities are projected onto."""

    def __init__(self, rows: VelocityRows, params):
        import sympy as sp

        system = rows.system
        lay = system.layout
        q, qd, qdd = list(lay.q_symbols), list(lay.qd_symbols), list(lay.qdd_symbols)
        mu = [sp.Dummy(f"mu{i}") for i in range(rows.k)]
        A = rows.A_sym
        f1 = A.T * sp.Matrix(mu)
        f2 = A * sp.Matrix(qdd) + rows.rho_sym
        f3 = A * sp.Matrix(qd) + rows.b_sym
        params = list(params)
        exprs = []
        for f, wrt in ((f1, q + params), (f2, q + qd + params), (f3, q + params)):
            exprs += list(f.jacobian(wrt)) if len(f) else []
        self.n, self.k, self.kp = system.n, rows.k, len(params)
        self._f = compile_exprs([T, *q, *qd, *qdd, *mu, *lay.p_symbols], exprs, system.backend)

    def evaluate(self, t, q, qd, qdd, mu, p) -> dict:
        """The Jacobians at one state: ``F1q`` (n, n), ``F1p`` (n, kp), ``F2q``, ``F2qd`` (k,
        n), ``F2p`` (k, kp), ``F3q`` (k, n), ``F3p`` (k, kp)."""
        n, k, kp = self.n, self.k, self.kp
        x = np.concatenate(([t], q, qd, qdd, mu, p))
        out = np.asarray(self._f(x), dtype=float).ravel()
        F1 = out[:n * (n + kp)].reshape(n, n + kp)
        o = n * (n + kp)
        F2 = out[o:o + k * (2 * n + kp)].reshape(k, 2 * n + kp)
        o += k * (2 * n + kp)
        F3 = out[o:o + k * (n + kp)].reshape(k, n + kp)
        return {"F1q": F1[:, :n], "F1p": F1[:, n:], "F2q": F2[:, :n], "F2qd": F2[:, n:2 * n],
                "F2p": F2[:, 2 * n:], "F3q": F3[:, :n], "F3p": F3[:, n:]}


def free_tangent_rows(tan, rt: RowTangent, rows: VelocityRows, t, q, qd, qdd, lam, p, sq, sqd):
    r"""``(sqdd (kp, n), slam (kp, m + k))`` of free motion with velocity rows at one state:
    the holonomic tangent (``solvers/_sensitivity.free_tangent``'s right-hand sides) bordered
    by :math:`A` and completed by :class:`RowTangent`'s terms (``lam`` holds
    :math:`(\lambda, \mu)`)."""
    K = tan.kernels
    system = K.system
    n, m, k = system.n, system.m, rows.k
    X = tan.base([t], q, qd, qdd, lam[:m], p)
    D = tan.directions(1, sq=sq[None], sqd=sqd[None])
    r1 = tan.evaluate(K.kernel("dynamics"), X, D)[0]
    r2 = tan.evaluate(K.kernel("acceleration"), X, D)[0] if m else np.zeros((tan.k, 0))
    F = rt.evaluate(t, q, qd, qdd, lam[m:], p)
    r1 = r1 + sq @ F["F1q"].T + F["F1p"].T
    r3 = sq @ F["F2q"].T + sqd @ F["F2qd"].T + F["F2p"].T
    M, _, _ = system.dynamics.terms(t, q, qd, lam[:m], p, qdd)
    A, _, _ = rows.evaluate(t, q, qd, p)
    N = n + m + k
    B = np.zeros((N, N))
    B[:n, :n] = M
    if m:
        J = system.jacobian(t, q, p)
        J = J.toarray() if sps.issparse(J) else np.asarray(J)
        B[:n, n:n + m] = J.T
        B[n:n + m, :n] = J
    B[:n, n + m:] = A.T
    B[n + m:, :n] = A
    rhs = -np.concatenate((r1, r2, r3), axis=1).T
    try:
        x = np.linalg.solve(B, rhs)
    except np.linalg.LinAlgError:
        raise SingularJacobianError(
            f"free-motion sensitivity at t = {t:.6g}: the augmented matrix with the velocity "
            "constraints is singular (dependent rows or a massless free motion); the "
            "trajectory's sensitivity is not defined there", time=t) from None
    return x[:n].T, x[n:].T


def row_sensitivity_targets(system, tan, rt: RowTangent, rows: VelocityRows, t, q, qd, p, sq):
    """``(G (m + k, n), bv (m + k, kp))``: the velocity rows of the holonomic and the velocity
    constraints stacked, and the right-hand sides ``G s_qd + bv = 0`` of the differentiated
    velocity equations for the position sensitivities ``sq`` (kp, n)."""
    m = system.m
    K = tan.kernels
    A, _, _ = rows.evaluate(t, q, qd, p)
    F = rt.evaluate(t, q, qd, np.zeros(system.n), np.zeros(rows.k), p)
    b3 = (sq @ F["F3q"].T + F["F3p"].T).T                     # (k, kp)
    if m:
        J = system.jacobian(t, q, p)
        J = J.toarray() if sps.issparse(J) else np.asarray(J)
        X = tan.base([t], q, qd, None, None, p)
        bv = tan.evaluate(K.kernel("velocity"), X, tan.directions(1, sq=sq[None]))[0].T
        return np.vstack((J, A)), np.vstack((bv, b3))
    return A, b3
