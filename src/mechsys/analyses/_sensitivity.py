r"""Sensitivity to parameters (Mech's ``SetSensitivity`` / ``SolveSensitivity``, manual 9.5),
and beyond Mech, sensitivities of free-motion trajectories.

``sens = m.sensitivity(["L", "r"])`` names the parameters; ``sens.solve(t, solution=...)``
solves the model as ``m.solve`` does and differentiates the solution exactly, by implicit
differentiation of the compiled equations (``solvers/_sensitivity.py``):

.. math::

    \Phi_q \frac{\partial q}{\partial p} = -\Phi_p, \qquad
    \Phi_q \frac{\partial \dot q}{\partial p} = -\left(V_q \frac{\partial q}{\partial p}
    + V_p\right), \qquad \dots

(:math:`V = \Phi_q \dot q + \Phi_t`, the velocity equations)

``sens.of(solution)`` differentiates a solution already at hand (``sol.sensitivity([...])``
says the same). ``m.sensitivity([...], free=fs).simulate(t, ...)`` integrates the forward
sensitivity equations of free motion together with the motion itself.

The system reads the model's parameter values when it runs, not when it is built.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._errors import ModelError
from ..geometry._units import time_numbers
from ..results._sensitivity import Sensitivity
from ..results._solution import Solution, State
from ..solvers._integrators import ATOL, FIT_DEGREE, MAX_ERROR, MAX_STEP, RTOL


def _parameter_symbols(model, parameters) -> tuple:
    if isinstance(parameters, (str, sp.Symbol)):
        parameters = [parameters]
    try:
        items = list(parameters)
    except TypeError:
        raise ModelError(f"sensitivity: parameters must be a name, a symbol or a list of them, "
                         f"got {parameters!r}") from None
    if not items:
        raise ModelError("sensitivity: give at least one parameter, e.g. m.sensitivity(['L'])")
    out = []
    known = list(model._params)
    for item in items:
        name = getattr(item, "name", item)
        if not isinstance(name, str):
            raise ModelError(f"sensitivity: a parameter is given by name or symbol, got {item!r}")
        s = sp.Symbol(name)
        if s not in model._params:
            raise ModelError(f"sensitivity: {name!r} is not a parameter of the model; parameters "
                             f"are {[p.name for p in known]} (declare one with m.parameter(name, "
                             "value))")
        if s in out:
            raise ModelError(f"sensitivity: parameter {name!r} is listed twice")
        out.append(s)
    return tuple(out)


class SensitivitySystem:
    r"""Sensitivities of a model's solutions to ``parameters`` (Mech's ``SensitivitySystem``).

    The derivatives with respect to each parameter :math:`p` solve the differentiated
    equations of the solution, with the Jacobian the solve already factorised:

    .. math::

        \Phi_q \frac{\partial q}{\partial p} &= -\Phi_p \\
        \Phi_q \frac{\partial \dot q}{\partial p} &= -\left(V_q \frac{\partial q}{\partial p}
        + V_p\right), \qquad V = \Phi_q \dot q + \Phi_t

    and likewise for the accelerations and, for static and dynamic solutions, the
    multipliers.

    ``solve(t, solution=..., guess=..., options=..., lambda_guess=...)`` solves the model
    like :meth:`Model.solve` and returns a :class:`~mechsys.Sensitivity`; ``of(solution)``
    differentiates a given solution; with ``free=`` (a dynamic :class:`FreeSystem`),
    ``simulate(t, initial_condition=..., ...)`` integrates the free motion with its
    sensitivities. Every parameter must appear in the constraints, loads, mass properties or
    body points (else :class:`ModelError`); a singular Jacobian raises
    :class:`SingularJacobianError` naming the time.

    >>> sens = m.sensitivity(["L", "r"])                        # doctest: +SKIP
    >>> s = sens.solve(np.linspace(0, 1, 11))                   # solve, then differentiate
    >>> s["L"].location(piston.point(0))                        # d(location)/dL, (11, 2)
    """

    def __init__(self, model, parameters, free=None):
        self.model = model
        self.params = _parameter_symbols(model, parameters)
        self.free = free
        if free is not None:
            from ._free import FreeSystem

            if not isinstance(free, FreeSystem) or free.model is not model:
                raise ModelError("sensitivity(free=...) takes a FreeSystem of this model "
                                 "(m.free(drop=[...]))")
            if free.kind != "dynamic":
                raise ModelError("sensitivity(free=...): trajectory sensitivities need a free "
                                 "system built with solution='dynamic'")
        self._tangents: dict = {}

    @property
    def parameters(self) -> tuple:
        return tuple(p.name for p in self.params)

    def __repr__(self) -> str:
        kind = "free motion" if self.free is not None else "solutions"
        return f"<SensitivitySystem of {kind} to {list(self.parameters)}>"

    def _tangent(self, system, also=frozenset()):
        """The tangent kernels of ``system`` (cached per compiled system), after checking
        that every parameter is used (by the system, or among the symbols ``also``: the
        velocity constraints' rows)."""
        from ..compile._sensitivity import TangentKernels
        from ..solvers._sensitivity import Tangent

        key = id(system)
        hit = self._tangents.get(key)
        if hit is not None and hit[0] is system:
            return hit[1]
        for p in self.params:
            if p not in system.layout.p_symbols:
                raise ModelError(f"sensitivity: parameter {p.name!r} was declared after this "
                                 "solution was computed; solve again")
        kern = TangentKernels(system, self.params)
        used = kern.uses()
        unused = [p.name for p in self.params if p not in used and p not in also]
        if unused:
            raise ModelError(
                f"sensitivity: parameter(s) {unused} are not used by the model's constraints, "
                "loads, mass properties or body points, so nothing depends on them; use them in "
                "the model "
                "or leave them out of m.sensitivity([...])")
        tan = Tangent(kern)
        self._tangents[key] = (system, tan)
        return tan

    # -- solutions ---------------------------------------------------------------------------
    def solve(self, t=0.0, solution: str = "acceleration", guess=None, options=None,
              lambda_guess=None) -> Sensitivity:
        """Solve the model (as :meth:`Model.solve`, same arguments) and differentiate the
        solution: a :class:`~mechsys.Sensitivity` with ``dq``, ``dqd``, ``dqdd`` and, with
        ``solution="static" | "kinematic" | "dynamic"``, ``dlam``."""
        if self.free is not None:
            raise ModelError("this SensitivitySystem was built for free motion: use "
                             ".simulate(t, ...)")
        sol = self.model.solve(t, solution=solution, guess=guess, options=options,
                               lambda_guess=lambda_guess)
        return self.of(sol)

    def of(self, solution=None) -> Sensitivity:
        """Differentiate a kinematic, static, kinematic-load or inverse-dynamic
        :class:`~mechsys.Solution` (or :class:`~mechsys.State`) of this model with respect to
        the parameters, at its own parameter values. Without an argument, the model's last
        solution (Mech's default ``InitialCondition -> Automatic``: ``LastSolve[]``)."""
        from ..solvers._sensitivity import kinematic_sensitivities

        sol = solution
        if sol is None:
            sol = self.model.last_solution
            if sol is None:
                raise ModelError("sensitivity.of(): the model has not been solved yet; give a "
                                 "solution, or use .solve(t)")
        if isinstance(sol, State):
            sol = Solution(t=np.array([sol.t]), q=sol.q[None], qd=None if sol.qd is None
                           else sol.qd[None], qdd=None if sol.qdd is None else sol.qdd[None],
                           p=self.model._p(), system=sol.system, model=self.model,
                           iterations=np.zeros(1, dtype=int), scalar=True)
        if not isinstance(sol, Solution):
            raise ModelError(f"sensitivity.of() takes a Solution or State, got {solution!r}")
        if sol.model is not self.model:
            raise ModelError("sensitivity.of(): the solution belongs to another model")
        if sol.mode.startswith("free-") or sol.mode == "path":
            raise ModelError(f"sensitivity.of(): a {sol.mode} solution is not a solution of the "
                             "fully constrained model; for free motion use "
                             "m.sensitivity([...], free=fs).simulate(...)")
        if sol.extra.get("stages"):
            raise ModelError("sensitivity.of(): solutions of multistage models (StageSwitch, "
                             "TimeSwitch) change their equations between points; "
                             "differentiate each stage's model on its own")
        if sol.system.m != sol.system.n:
            raise ModelError(f"sensitivity needs a fully constrained model ({sol.system.n} "
                             f"coordinates, {sol.system.m} equations)")
        tan = self._tangent(sol.system)
        orders = 0 if sol.qd is None else (1 if sol.qdd is None else 2)
        modes = ("static", "kinematic", "dynamic")
        mode = sol.mode if sol.mode in modes else None
        q = np.atleast_2d(sol.q)
        sq, sqd, sqdd, slam = kinematic_sensitivities(
            tan, np.atleast_1d(sol.t), q, sol.qd, sol.qdd, sol.lam, np.asarray(sol.p), orders,
            mode, at_rest=sol._at_rest)
        return Sensitivity(solution=sol, parameters=self.parameters, dq=sq, dqd=sqd,
                           dqdd=sqdd, dlam=slam, tangent=tan)

    # -- free motion ---------------------------------------------------------------------------
    def simulate(self, t, initial_condition=None, method: str = "dop853", rtol: float = RTOL,
                 atol: float = ATOL, max_step: float = MAX_STEP, fit_degree=FIT_DEGREE,
                 max_error=MAX_ERROR, step_size=None, constraint_correction: bool = True,
                 starting_step_size: float | None = None, **unknown) -> Sensitivity:
        r"""Integrate the free motion of ``free`` and its forward sensitivities together:
        the state ``(q, qd)`` and, per parameter,
        :math:`(s_q, s_{\dot q}) = \partial (q, \dot q) / \partial p` with

        .. math::  \dot s_q = s_{\dot q}, \qquad \dot s_{\dot q} = s_{\ddot q}(q, \dot q,
                   s_q, s_{\dot q})

        from the differentiated augmented system (``solvers/_sensitivity.free_tangent``).
        The options are those of :meth:`FreeSystem.simulate`; the error control covers the
        sensitivities too (each in units of its coordinate per unit of the parameter's
        size), and after each step the sensitivities are projected, like the state, onto the
        differentiated constraints :math:`\Phi_q s_q = -\Phi_p` and its velocity form.

        At the start, the coordinates and velocities given in ``initial_condition`` are held
        (their sensitivity is zero) and the others follow the constraints with the smallest
        unit-free change, as the start projection of free motion does. Returns a
        :class:`~mechsys.Sensitivity` whose ``solution`` is the free motion.

        With velocity constraints :math:`A \dot q + b = 0` (rolling contacts) the tangent
        system is bordered by :math:`A` and takes the rows' parameter derivatives
        (:class:`~mechsys.analyses._nonholonomic.RowTangent`); the start and the projection
        hold the differentiated rows too, and ``dlam`` holds
        :math:`(\partial\lambda/\partial p, \partial\mu/\partial p)` (decision 0055)."""
        from ..solvers._free import free_acceleration, project, scaling_at
        from ..solvers._integrators import integrate, plan_run
        from ..solvers._sensitivity import free_tangent, held_least_squares

        fs = self.free
        if fs is None:
            raise ModelError("simulate() integrates free motion: build the system with "
                             "m.sensitivity([...], free=m.free(drop=[...]))")
        run = plan_run("SensitivitySystem.simulate", t, unknown, (
            "initial_condition", "method", "rtol", "atol", "max_step", "fit_degree", "max_error",
            "step_size", "constraint_correction", "starting_step_size"), method, rtol, atol,
            max_step, fit_degree, max_error, step_size, constraint_correction, starting_step_size,
            to_numbers=time_numbers(self.model))
        t0 = run.t0
        s = fs.system
        also = frozenset()
        if fs._vrows is not None:
            also = frozenset().union(*(e.free_symbols for e in fs._vrows.A_sym),
                                     *(e.free_symbols for e in fs._vrows.b_sym))
        tan = self._tangent(s, also)
        n, m, k = s.n, s.m, tan.k
        q0, qd0, p, held = fs._start(initial_condition)
        sc = scaling_at(s, t0, q0, p)
        q0, qd0 = fs._project_start(t0, q0, qd0, p, held, sc)
        K = tan.kernels
        rows = fs._vrows                  # velocity constraints (decision 0055)
        rt = None
        if rows is not None and (s.dynamics.depends_on_lambda or s.dynamics.depends_on_qdd):
            # (the bordered tangent, free_tangent_rows, leaves out the loads' derivatives
            # along the multipliers and accelerations: refused rather than wrong, 0068)
            raise ModelError(
                "sensitivity of free motion: loads that depend on the multipliers (joint "
                "friction) or on the accelerations together with velocity constraints "
                f"({', '.join(c.label() for c in rows.constraints)}) are not supported yet; "
                "simulate the free motion itself (m.free().simulate), or take central "
                "differences of whole runs")
        if rows is not None:
            from ._nonholonomic import (
                RowTangent,
                free_tangent_rows,
                nonholonomic_acceleration,
                project_state,
                row_sensitivity_targets,
            )

            rt = RowTangent(rows, self.params)
        if m:
            X = tan.base([t0], q0, qd0, None, None, p)
            J = s.jacobian(t0, q0, p)
            b = tan.evaluate(K.kernel("position"), X, tan.directions(1))[0].T
            sq0 = held_least_squares(s, J, sc, b, sorted(held["q"]))
            bv = tan.evaluate(K.kernel("velocity"), X, tan.directions(1, sq=sq0[None]))[0].T
            sqd0 = held_least_squares(s, J, sc, bv, sorted(held["qd"]))
        else:
            sq0 = sqd0 = np.zeros((k, n))
        if rows is not None:
            # the start velocities follow the velocity constraints too (their sensitivities
            # with them), the given ones held
            G, bv = row_sensitivity_targets(s, tan, rt, rows, t0, q0, qd0, p, sq0)
            sqd0 = held_least_squares(s, G, sc, bv, sorted(held["qd"]))
        pscale = np.where(p[[s.layout.p_symbols.index(x) for x in self.params]] != 0,
                          np.abs(p[[s.layout.p_symbols.index(x) for x in self.params]]), 1.0)
        lam_box = [None]

        def unpack(y):
            return (y[:n], y[n:2 * n], y[2 * n : 2 * n + k * n].reshape(k, n),
                    y[2 * n + k * n :].reshape(k, n))

        def tangent_at(tt, y):
            q, qd, sq, sqd = unpack(y)
            if rows is not None:
                qdd, lam = nonholonomic_acceleration(s, rows, tt, q, qd, p)
                sqdd, slam = free_tangent_rows(tan, rt, rows, tt, q, qd, qdd, lam, p, sq, sqd)
                return qdd, lam, sqdd, slam
            qdd, lam, _ = free_acceleration(s, tt, q, qd, p, lam_box[0])
            if s.dynamics.depends_on_lambda:
                lam_box[0] = lam
            sqdd, slam = free_tangent(tan, tt, q, qd, qdd, lam, p, sq, sqd)
            return qdd, lam, sqdd, slam

        def rhs(tt, y):
            qdd, _, sqdd, _ = tangent_at(tt, y)
            return np.concatenate((y[n : 2 * n], qdd, y[2 * n + k * n :], sqdd.ravel()))

        def proj(tt, y):
            q, qd, sq, sqd = unpack(y)
            if rows is not None:
                q, qd = project_state(s, rows, tt, q, qd, p, sc)
                sq, sqd = _project_sensitivities(s, tan, sc, tt, q, qd, p, sq, sqd,
                                                 (rt, rows))
            else:
                q, qd = project(s, tt, q, qd, p, scaling=sc)
                if m:
                    sq, sqd = _project_sensitivities(s, tan, sc, tt, q, qd, p, sq, sqd)
            return np.concatenate((q, qd, sq.ravel(), sqd.ravel()))

        col = sc.columns
        sens_scale = np.concatenate([col / ps for ps in pscale])
        scale = np.concatenate((col, col, sens_scale, sens_scale))
        y0 = np.concatenate((q0, qd0, sq0.ravel(), sqd0.ravel()))
        times, Y, res, mname = integrate(rhs, proj, run, y0, scale=scale)
        N = len(times)
        mk = m + (rows.k if rows is not None else 0)       # (lambda, mu)
        QDD, LAM = np.empty((N, n)), np.empty((N, mk))
        SQ, SQD = np.empty((N, k, n)), np.empty((N, k, n))
        SQDD, SLAM = np.empty((N, k, n)), np.empty((N, k, mk))
        for j, (tj, yj) in enumerate(zip(times, Y)):
            lam_box[0] = None
            QDD[j], LAM[j], SQDD[j], SLAM[j] = tangent_at(tj, yj)
            _, _, SQ[j], SQD[j] = unpack(yj)
        extra = {"evaluations": res.evaluations, "steps": res.steps, "rejected": res.rejected,
                 "method": mname, "length_scale": sc.length}
        sol = fs._result(times, Y[:, :n], Y[:, n : 2 * n], QDD, LAM, p, np.zeros(N), extra=extra)
        for a in (SQ, SQD, SQDD, SLAM):
            a.setflags(write=False)
        return Sensitivity(solution=sol, parameters=self.parameters, dq=SQ, dqd=SQD, dqdd=SQDD,
                           dlam=SLAM, tangent=tan)


def _project_sensitivities(s, tan, sc, t, q, qd, p, sq, sqd, velocity_rows=None):
    """The smallest (unit-free) corrections of ``sq``, ``sqd`` ``(k, n)`` that satisfy the
    differentiated constraints ``Phi_q s_q + Phi_p = 0`` and
    ``Phi_q s_qd + V_q s_q + V_p = 0`` (the sensitivity of the state projection); with
    ``velocity_rows`` (``(RowTangent, VelocityRows)``) also the velocity constraints'
    ``A s_qd + (A qd + b)_q s_q + (A qd + b)_p = 0``."""
    from ..solvers._sensitivity import held_least_squares

    K = tan.kernels
    if s.m:
        J = s.jacobian(t, q, p)
        X = tan.base([t], q, qd, None, None, p)
        b = tan.evaluate(K.kernel("position"), X, tan.directions(1))[0].T + J @ sq.T
        sq = sq + held_least_squares(s, J, sc, b, [])
    if velocity_rows is not None:
        from ._nonholonomic import row_sensitivity_targets

        G, bv = row_sensitivity_targets(s, tan, *velocity_rows, t, q, qd, p, sq)
        sqd = sqd + held_least_squares(s, G, sc, bv + G @ sqd.T, [])
        return sq, sqd
    bv = tan.evaluate(K.kernel("velocity"), X, tan.directions(1, sq=sq[None]))[0].T + J @ sqd.T
    sqd = sqd + held_least_squares(s, J, sc, bv, [])
    return sq, sqd

