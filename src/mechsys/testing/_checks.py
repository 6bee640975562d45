r"""Conformance checks run over every constraint type (cf. scikit-learn's ``check_estimator``).

A *case* is a small model holding one constraint and a configuration ``q`` built *by hand*
to satisfy it (not solved for). Checks:

1. residual: ``Phi(q, t) = 0`` at the built configuration;
2. Jacobian: ``Phi_q`` equals central finite differences of ``Phi`` at a perturbed ``q``;
3. gamma: along an arbitrary smooth path ``q(t)`` (polynomial plus sine terms)::

       d^2 Phi / dt^2 = Phi_q qdd - gamma

   so ``gamma`` must equal ``Phi_q qdd - (Phi(t+h) - 2 Phi(t) + Phi(t-h)) / h^2``;
4. DOF: ``len(equations) - len(new variables)`` equals the documented ``dof_removed``.
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


def check_constraint_case(c: Case, seed: int = 0) -> dict:
    """Run all four checks on one case; returns the measured errors."""
    rng = np.random.default_rng(seed)
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
