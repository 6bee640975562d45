r"""Sensitivity results (Mech's ``SolveSensitivity``): derivatives of a solution with
respect to parameters.

A :class:`Sensitivity` holds, for ``N`` time points, ``k`` parameters and ``n`` coordinates,
``dq``, ``dqd``, ``dqdd`` ``(N, k, n)`` and ``dlam`` ``(N, k, m)``: ``dq[j, i]`` is
``dq/dp_i`` at time ``t[j]``. ``sens[param]`` is a :class:`ParameterSensitivity`, which has
every output function of a solution (``location``, ``velocity``, ``reaction``, ``eval``,
...) returning the derivative of that output with respect to the parameter:

.. math::  \frac{d f}{d p} = f_q \frac{dq}{dp} + f_{\dot q} \frac{d\dot q}{dp}
           + f_{\ddot q} \frac{d\ddot q}{dp} + f_\lambda \frac{d\lambda}{dp} + f_p

As in Mech, a sensitivity reads like a velocity: the rate of change of every quantity when
the parameter changes at unit rate (and time stands still).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from .._errors import MechError, ModelError
from ._load_outputs import LoadOutputs
from ._outputs import OutputFunctions


@dataclass(frozen=True, eq=False)
class Sensitivity:
    """Derivatives of ``solution`` with respect to ``parameters`` (names, in order).

    ``dq``, ``dqd``, ``dqdd``: ``(N, k, n)`` (``None`` for an order the solution lacks;
    zero-velocity statics have ``None`` and read as zeros); ``dlam``: ``(N, k, m)`` or
    ``None``; ``solution``: the :class:`~mechsys.Solution` differentiated.
    ``sens["L"]`` (name, symbol or index) is the :class:`ParameterSensitivity` of one
    parameter; ``sens.eval(expr)`` the derivatives of any expression for all parameters,
    ``(N, k) + shape``; ``sens.gradient(expr)`` the same with the parameter axis last.

    >>> sens = m.sensitivity(["L", "r"]).solve(np.linspace(0, 1, 11))   # doctest: +SKIP
    >>> sens["L"].location(piston.point(0))      # d(piston position)/dL, (11, 2)
    """

    solution: object
    parameters: tuple
    dq: np.ndarray
    dqd: np.ndarray | None
    dqdd: np.ndarray | None
    dlam: np.ndarray | None
    tangent: object = field(repr=False, default=None)

    @property
    def t(self) -> np.ndarray:
        return self.solution.t

    def __len__(self) -> int:
        return len(self.solution.t)

    def _index(self, param) -> int:
        name = getattr(param, "name", param)
        if isinstance(name, (int, np.integer)) and not isinstance(name, bool):
            if 0 <= name < len(self.parameters):
                return int(name)
        elif name in self.parameters:
            return self.parameters.index(name)
        raise ModelError(f"no sensitivity to {param!r}; this result has the parameters "
                         f"{list(self.parameters)} (ask m.sensitivity([...]) for others)")

    def __getitem__(self, param) -> ParameterSensitivity:
        return ParameterSensitivity(self, self._index(param))

    def coordinate(self, key, param, order: int = 0) -> np.ndarray:
        """``d(coordinate)/d(param)`` of one coordinate (``order`` 1: its velocity, 2: its
        acceleration)."""
        return self[param].coordinate(key, order)

    def _derivative(self, exprs) -> np.ndarray:
        """``(N, k, len(exprs))``: the directional derivative of flat expressions."""
        sol = self.solution
        key = tuple(sp.sympify(e) for e in exprs)
        # cached on the compiled kernels: every solution of one SensitivitySystem (an
        # optimiser's evaluations) reuses the compiled derivative of an output
        cache = self.tangent.kernels.expression_cache
        f = cache.get(key)
        if f is None:
            from ..compile._sensitivity import ExpressionTangent

            f = cache[key] = ExpressionTangent(self.tangent.kernels, key).f
        lay = sol.system.layout
        free = set().union(*(e.free_symbols for e in key)) if key else set()
        for order, syms in ((2, lay.qdd_symbols), (1, lay.qd_symbols)):
            if free & set(syms):
                sol._order(order)              # raises when the solution lacks this order
        if free & set(sol.system.lam_symbols) and sol.lam is None:
            raise MechError("this solution has no Lagrange multipliers (reactions), so it has "
                            "no reaction sensitivities; solve with solution='static', "
                            "'kinematic' or 'dynamic'")
        at_rest = sol._at_rest
        X = self.tangent.base(sol.t, sol.q, None if at_rest else sol.qd,
                              None if at_rest else sol.qdd, sol.lam, sol.p)
        D = self.tangent.directions(len(sol.t), sq=self.dq, sqd=self.dqd, sqdd=self.dqdd,
                                    slam=self.dlam)
        return self.tangent.evaluate(f, X, D)

    def eval(self, expr) -> np.ndarray:
        """Derivatives of a SymPy expression or matrix of ``T``, coordinates, velocities,
        accelerations, multipliers and parameters, for every parameter: shape
        ``(N, k) + expr.shape`` (``(N, k)`` for a scalar, ``(N, k, r)`` for a column)."""
        is_matrix = isinstance(expr, sp.MatrixBase)
        mat = sp.Matrix(expr) if is_matrix else sp.Matrix([sp.sympify(expr)])
        vals = self._derivative(list(mat))
        N, k = vals.shape[:2]
        if not is_matrix:
            out = vals[:, :, 0]
        elif mat.shape[1] == 1:
            out = vals
        else:
            out = vals.reshape((N, k) + mat.shape)
        return out[0] if self.solution.scalar else out

    def gradient(self, expr) -> np.ndarray:
        """:meth:`eval` with the parameter axis last: ``(N,) + shape + (k,)``, the gradient
        an optimiser wants (``(k,)`` for a scalar at a scalar time)."""
        out = np.asarray(self.eval(expr))
        axis = 0 if self.solution.scalar else 1
        return np.moveaxis(out, axis, -1)

    def __repr__(self) -> str:
        return (f"<Sensitivity to {list(self.parameters)}: {len(self)} time point(s), "
                f"{self.solution.system.n} coordinates>")


class ParameterSensitivity(OutputFunctions, LoadOutputs):
    """The derivatives of a solution with respect to one parameter: ``q``, ``qd``, ``qdd``
    ``(N, n)``, ``lam`` ``(N, m)`` and every output function of a solution (``location``,
    ``velocity``, ``acceleration``, ``angle``, ``omega``, ``reaction``, ``loads``, ``eval``,
    ...) giving ``d(output)/d(parameter)`` with the solution's shapes."""

    def __init__(self, sens: Sensitivity, index: int):
        self.sensitivity = sens
        self.index = index
        self.parameter = sens.parameters[index]
        self.system = sens.solution.system

    def _model(self):
        return self.sensitivity.solution.model

    def _finish(self, expr):
        return self.eval(expr)

    def eval(self, expr):
        """``d expr / d parameter`` over the solution (shapes as ``Solution.eval``)."""
        out = np.asarray(self.sensitivity.eval(expr))
        return out[self.index] if self.sensitivity.solution.scalar else out[:, self.index]

    def _array(self, a, what):
        if a is None:
            sol = self.sensitivity.solution
            if what in ("qd", "qdd") and sol._at_rest:
                return np.zeros_like(self.sensitivity.dq[:, self.index])
            lacks = {"qd": "velocities", "qdd": "accelerations"}.get(what, "multipliers")
            raise MechError(f"this sensitivity has no {what} derivatives: the solution has no "
                            f"{lacks}")
        return a[:, self.index]

    @property
    def q(self) -> np.ndarray:
        return self._array(self.sensitivity.dq, "q")

    @property
    def qd(self) -> np.ndarray:
        return self._array(self.sensitivity.dqd, "qd")

    @property
    def qdd(self) -> np.ndarray:
        return self._array(self.sensitivity.dqdd, "qdd")

    @property
    def lam(self) -> np.ndarray:
        return self._array(self.sensitivity.dlam, "lam")

    def coordinate(self, key, order: int = 0) -> np.ndarray:
        """``d(coordinate)/d(parameter)`` (order 1: of its velocity, 2: acceleration)."""
        if order not in (0, 1, 2):
            raise ModelError(f"order must be 0, 1 or 2, got {order!r}")
        j = self.system.layout.index(key)
        out = (self.q, self.qd, self.qdd)[order][:, j]
        return out[0] if self.sensitivity.solution.scalar else out

    def __getitem__(self, key):
        return self.coordinate(key)

    def __repr__(self) -> str:
        return f"<sensitivity to {self.parameter!r}: {len(self.sensitivity)} time point(s)>"
