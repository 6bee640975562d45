r"""Symbolic residuals and Jacobians of the equilibrium problems of a free system.

Static equilibrium, unknowns :math:`x = (q, \lambda)`:

.. math::

    R = \begin{bmatrix} \Phi(q, t) \\ \Phi_q^T \lambda - Q(t, q, 0, \lambda) \end{bmatrix}

Velocity equilibrium at fixed ``q``, unknowns :math:`x = (\dot q, \lambda)`:

.. math::

    R = \begin{bmatrix} \Phi_q \dot q + \Phi_t \\ \Phi_q^T \lambda - Q(t, q, \dot q, \lambda)
        \end{bmatrix}

With velocity constraints :math:`A(q, t)\,\dot q + b(q, t) = 0` (``rows``, an
:class:`~mechsys.analyses._nonholonomic.VelocityRows`; decision 0055) their multipliers
:math:`\mu` join the unknowns, :math:`x = (q, \lambda, \mu)` (static) and
:math:`x = (\dot q, \lambda, \mu)` (kinematic):

.. math::

    R = \begin{bmatrix} \Phi \\ b \\ \Phi_q^T \lambda + A^T \mu - Q(t, q, 0, \lambda)
        \end{bmatrix}, \qquad
    R = \begin{bmatrix} \Phi_q \dot q + \Phi_t \\ A \dot q + b \\
        \Phi_q^T \lambda + A^T \mu - Q \end{bmatrix}

(at rest the velocity constraints allow :math:`\dot q = 0` only where :math:`b = 0`).

Jacobians are derived symbolically (sparse) and compiled once, on first use.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._symbols import T
from ._backends import compile_exprs
from ._derive import sparse_derivatives


class _Residual:
    def __init__(self, system, R, unknowns, args):
        self.system = system
        vals: list = []
        self.rows, self.cols = sparse_derivatives(R, list(unknowns), vals)
        self.size = len(R)
        self.nR = len(R)
        self.f = compile_exprs(args, list(R) + vals, system.backend,
                               cse=getattr(system, "cse", False))

    def _eval(self, x):
        out = self.f(x)
        K = np.zeros((self.size, self.size))
        np.add.at(K, (self.rows, self.cols), out[self.nR :])
        return out[: self.nR], K


def _mu_symbols(rows) -> list:
    """The velocity constraints' multipliers (none without ``rows``)."""
    return [sp.Dummy(f"mu{i}") for i in range(rows.k)] if rows is not None else []


def _with_rows(G, rows, mu):
    """``G + A^T mu`` (the balance's constraint forces with the velocity constraints')."""
    if rows is None:
        return G
    A = rows.A_sym
    return [g + sum((A[i, j] * mu[i] for i in range(rows.k)), sp.S.Zero)
            for j, g in enumerate(G)]


class StaticEquilibrium(_Residual):
    def __init__(self, system, rows=None):
        lay, dyn = system.layout, system.dynamics
        n = lay.n
        zero = dict.fromkeys(lay.qd_symbols + lay.qdd_symbols, 0)
        mu = _mu_symbols(rows)
        R = list(system.phi)
        if rows is not None:              # rest must be allowed: b(q, t) = 0
            R += list(rows.b_sym)
        G = [sp.S.Zero] * n
        for i, j, e in zip(system.jac_rows, system.jac_cols, system.jac_exprs):
            G[j] += e * system.lam_symbols[i]
        G = _with_rows(G, rows, mu)
        R += [G[j] - dyn.Q[j].subs(zero) for j in range(n)]
        args = [T, *lay.q_symbols, *system.lam_symbols, *mu, *lay.p_symbols]
        super().__init__(system, R, list(lay.q_symbols) + list(system.lam_symbols) + mu, args)

    def evaluate(self, t, q, lam, p):
        return self._eval(np.concatenate(([t], q, lam, p)))


class VelocityEquilibrium(_Residual):
    def __init__(self, system, rows=None):
        lay, dyn = system.layout, system.dynamics
        n = lay.n
        mu = _mu_symbols(rows)
        R = [sp.S.Zero] * system.m
        for i, j, e in zip(system.jac_rows, system.jac_cols, system.jac_exprs):
            R[i] += e * lay.qd_symbols[j]
        R = [r + pt for r, pt in zip(R, system.phi_t)]
        if rows is not None:              # the velocity constraints: A qd + b = 0
            qd = sp.Matrix(lay.qd_symbols)
            R += list(rows.A_sym * qd + rows.b_sym)
        G = [sp.S.Zero] * n
        for i, j, e in zip(system.jac_rows, system.jac_cols, system.jac_exprs):
            G[j] += e * system.lam_symbols[i]
        G = _with_rows(G, rows, mu)
        at_rest = dict.fromkeys(lay.qdd_symbols, 0)      # an equilibrium does not accelerate
        R += [G[j] - dyn.Q[j].subs(at_rest) for j in range(n)]
        args = [T, *lay.q_symbols, *lay.qd_symbols, *system.lam_symbols, *mu, *lay.p_symbols]
        super().__init__(system, R, list(lay.qd_symbols) + list(system.lam_symbols) + mu, args)

    def evaluate(self, t, q, qd, lam, p):
        return self._eval(np.concatenate(([t], q, qd, lam, p)))
