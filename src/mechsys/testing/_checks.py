r"""Conformance checks run over every constraint type (cf. scikit-learn's ``check_estimator``).

A *case* is a small model holding one constraint and a configuration ``q`` built *by hand*
to satisfy it (not solved for). Checks:

1. residual: :math:`\Phi(q, t) = 0` at the built configuration;
2. Jacobian: ``Phi_q`` equals central finite differences of ``Phi`` at a perturbed ``q``;
3. gamma: along an arbitrary smooth path ``q(t)`` (polynomial plus sine terms)

   .. math::

       \frac{d^2 \Phi}{dt^2} = \Phi_q \ddot q - \gamma

   so :math:`\gamma` must equal
   :math:`\Phi_q \ddot q - (\Phi(t+h) - 2 \Phi(t) + \Phi(t-h)) / h^2`;
4. DOF: ``len(equations) - len(new variables)`` equals the documented ``dof_removed``.

A *velocity* constraint (``constraint.order == 1``: the rolling contacts) is not part of the
case's model, which holds its holonomic part (``constraint.holonomic()``); the case adds
rates ``qd`` built by hand so that the contact does not slip. Its checks (decision 0046):

1. residual: :math:`\psi(q, \dot q) = 0` and the holonomic part's :math:`\Phi(q) = 0`;
2. Jacobians: ``A = psi_qd`` of :func:`~mechsys.linear_velocity_form` and ``psi_q`` (which
   linearisation needs) equal central finite differences of ``psi``, and ``b = psi(q, 0)``;
3. acceleration rows: along the same smooth path ``q(t)`` with :math:`\dot q = q'(t)`,
   :math:`d \psi / dt = A \ddot q + \rho` with ``rho`` of :func:`~mechsys.constraints.velocity_rows`
   (what path systems integrate with);
4. DOF: the number of velocity equations equals ``dof_removed``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

CASES: dict[str, list[Callable]] = {}


@dataclass
class Case:
    """model: a Model holding ``constraint``; q: (n,) satisfying configuration at time ``t``."""

    model: object
    constraint: object
    q: np.ndarray
    t: float = 0.3
    label: str = ""
    tolerances: dict = field(default_factory=dict)
    #: rates at ``q`` for velocity constraints (the contact does not slip), else None
    qd: np.ndarray | None = None


def case(name: str):
    """Register a case builder ``f(rng) -> Case`` for constraint type ``name``."""

    def deco(f):
        CASES.setdefault(name, []).append(f)
        return f

    return deco


def pose_vector(model, poses: dict) -> np.ndarray:
    """Coordinates (n,) from ``{body: q_b}`` plus ``{symbol: value}`` for variables. A
    planar pose ``(x, y, th)`` given for a body in degenerate Euler parameters
    (``Model2D(orientation="euler")``) becomes ``(x, y, cos th, sin th)``."""
    system = model.compile()
    q = np.zeros(system.n)
    for key, val in poses.items():
        if hasattr(key, "q") and not isinstance(key, type):
            sl = system.layout.body_slices[key.name]
            if sl.stop - sl.start == 4 and len(val) == 3 and model.space.dim == 2:
                val = [val[0], val[1], np.cos(float(val[2])), np.sin(float(val[2]))]
            q[sl] = val
        else:
            q[system.layout.index(key)] = val
    return q


def check_residual(c: Case, tol: float = 1e-10) -> float:
    s = c.model.compile()
    r = s.residual(c.t, c.q)
    err = float(np.abs(r).max(initial=0.0))
    assert err < tol, f"{c.label}: residual {r} at the built configuration"
    return err


def _perturbed(c: Case, rng) -> np.ndarray:
    return c.q + 0.1 * rng.standard_normal(c.q.shape)


def check_jacobian(c: Case, rng, h: float = 1e-6, tol: float = 1e-6) -> float:
    s = c.model.compile()
    q = _perturbed(c, rng)
    J = s.jacobian(c.t, q)
    Jfd = np.empty_like(J)
    for j in range(len(q)):
        e = np.zeros_like(q)
        e[j] = h
        Jfd[:, j] = (s.residual(c.t, q + e) - s.residual(c.t, q - e)) / (2 * h)
    err = float(np.abs(J - Jfd).max(initial=0.0))
    scale = 1.0 + float(np.abs(J).max(initial=0.0))
    assert err < tol * scale, f"{c.label}: Jacobian differs from finite differences by {err}"
    return err


def check_gamma(c: Case, rng, h: float = 1e-4, tol: float = 1e-5) -> float:
    s = c.model.compile()
    n = len(c.q)
    q0 = _perturbed(c, rng)
    v, a, b, w = (rng.standard_normal(n) for _ in range(4))

    def path(tau):
        dt = tau - c.t
        return q0 + v * dt + 0.5 * a * dt**2 + 0.2 * b * np.sin(w * dt)

    qd0 = v + 0.2 * b * w
    qdd0 = a
    d2 = (s.residual(c.t + h, path(c.t + h)) - 2 * s.residual(c.t, q0)
          + s.residual(c.t - h, path(c.t - h))) / h**2
    J = s.jacobian(c.t, q0)
    gamma_fd = J @ qdd0 - d2
    gamma = s.gamma_values(c.t, q0, qd0)
    err = float(np.abs(gamma - gamma_fd).max(initial=0.0))
    scale = 1.0 + float(np.abs(gamma_fd).max(initial=0.0))
    assert err < tol * scale, f"{c.label}: gamma {gamma} vs numerical {gamma_fd}"
    return err


def check_dof(c: Case) -> int:
    con = c.constraint
    removed = con.count_removed(c.model.space)
    if con.dof_removed is not None:
        assert removed == con.dof_removed, (
            f"{c.label}: removes {removed} DOF, documented {con.dof_removed}")
    return removed


def _velocity_functions(c: Case):
    """Numeric ``psi(t, q, qd)``, ``A(t, q)``, ``b(t, q)``, ``rho(t, q, qd)`` and
    ``psi_q(t, q, qd)`` of a velocity constraint, compiled as the path systems compile them
    (SymPy's lambdify took minutes to print a disk's derivatives)."""
    import sympy as sp

    from .._symbols import T
    from ..compile import compile_exprs
    from ..constraints import velocity_rows

    m = c.model
    rates = m.velocity_symbols()
    q = list(m._coordinate_symbols())
    qd = [rates[s] for s in q]
    psi = sp.Matrix(c.constraint.equations(m.space))
    A, b = c.constraint.velocity_form(m)
    rho = velocity_rows(list(psi), q, qd).rho
    args = [T, *q, *qd]
    fns = [compile_exprs(args, list(e), once=True) for e in (psi, A, b, rho, psi.jacobian(q))]

    def call(f, t, qv, qdv):
        return np.asarray(f(np.concatenate(([t], qv, qdv))), dtype=float)

    return [lambda t, qv, qdv, f=f: call(f, t, qv, qdv) for f in fns]


def check_velocity_case(c: Case, rng) -> dict:
    """The four checks of a velocity constraint (see the module doc); returns the errors."""
    psi, A, b, rho, psi_q = _velocity_functions(c)
    n = len(c.q)
    tol = c.tolerances.get("residual", 1e-10)
    hol = c.model.compile().residual(c.t, c.q)
    r = np.concatenate((psi(c.t, c.q, c.qd).ravel(), hol))
    res = float(np.abs(r).max(initial=0.0))
    assert res < tol, f"{c.label}: residual {r} at the built (q, qd)"
    q, qd = _perturbed(c, rng), rng.standard_normal(n)
    h = 1e-6
    Afd, Qfd = np.empty((len(r) - len(hol), n)), np.empty((len(r) - len(hol), n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        Afd[:, j] = (psi(c.t, q, qd + e) - psi(c.t, q, qd - e)).ravel() / (2 * h)
        Qfd[:, j] = (psi(c.t, q + e, qd) - psi(c.t, q - e, qd)).ravel() / (2 * h)
    Av, Qv = A(c.t, q, qd).reshape(Afd.shape), psi_q(c.t, q, qd).reshape(Qfd.shape)
    jac = max(float(np.abs(Av - Afd).max(initial=0.0)) / (1 + np.abs(Av).max(initial=0.0)),
              float(np.abs(Qv - Qfd).max(initial=0.0)) / (1 + np.abs(Qv).max(initial=0.0)))
    assert jac < 1e-6, f"{c.label}: A or psi_q differs from finite differences by {jac}"
    lin = float(np.abs(Av @ qd + b(c.t, q, qd).ravel() - psi(c.t, q, qd).ravel()).max())
    assert lin < 1e-10 * (1 + np.abs(Av).max() * np.abs(qd).max()), (
        f"{c.label}: psi != A qd + b ({lin})")
    v, a, bb, w = (rng.standard_normal(n) for _ in range(4))

    def path(tau):
        dt = tau - c.t
        return q + v * dt + 0.5 * a * dt**2 + 0.2 * bb * np.sin(w * dt)

    def rate(tau):
        dt = tau - c.t
        return v + a * dt + 0.2 * bb * w * np.cos(w * dt)

    hh = 1e-5
    d1 = (psi(c.t + hh, path(c.t + hh), rate(c.t + hh))
          - psi(c.t - hh, path(c.t - hh), rate(c.t - hh))).ravel() / (2 * hh)
    qdd = a                 # q''(c.t): the sine term's second derivative vanishes there
    qd0 = rate(c.t)
    pred = A(c.t, q, qd0).reshape(Afd.shape) @ qdd + rho(c.t, q, qd0).ravel()
    gam = float(np.abs(pred - d1).max(initial=0.0))
    assert gam < 1e-5 * (1 + np.abs(d1).max(initial=0.0)), (
        f"{c.label}: d psi/dt = {d1}, A qdd + rho = {pred}")
    return {"residual": res, "jacobian": jac, "gamma": gam, "dof": check_dof(c)}


def check_constraint_case(c: Case, seed: int = 0) -> dict:
    """Run all four checks on one case; returns the measured errors."""
    rng = np.random.default_rng(seed)
    if getattr(c.constraint, "order", 0) == 1:
        return check_velocity_case(c, rng)
    return {
        "residual": check_residual(c, c.tolerances.get("residual", 1e-10)),
        "jacobian": check_jacobian(c, rng),
        "gamma": check_gamma(c, rng),
        "dof": check_dof(c),
    }


def iter_cases(seed: int = 0):
    """Yield ``(name, Case)`` for every registered builder."""
    for name, builders in CASES.items():
        for k, f in enumerate(builders):
            rng = np.random.default_rng(seed + 17 * k)
            c = f(rng)
            c.label = c.label or f"{name}[{k}]"
            yield name, c
