r"""The load a generalized-coordinate joint transmits (``joint_reaction``; Mech 11.2 offers
none, a Gen joint not being a constraint): Newton-Euler on the bodies the joint carries."""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError
from .._symbols import acceleration_symbol, velocity_symbol
from ..constraints._generalized import GenJoint, gen_joints


def joint_generalized_load(model, joint: GenJoint, lams) -> list:
    r"""The load the master applies to the slave through ``joint``, generalized on the slave's
    own pose coordinates ``p_s``: Newton-Euler on the subtree the joint carries (the slave
    and every body whose chain of masters passes through it), moved rigidly with ``p_s``::

        G_s = sum_b (d p_b / d p_s)^T (M_b p_b_ddot - Qv_b - Q_b + Phi_c,p_b^T lambda_c)

    (``M_b``, ``Qv_b`` body ``b``'s inertia terms and ``Q_b`` its applied loads in its own
    pose coordinates, the last term the ordinary constraints acting on ``b``). Loads on the
    subtree's own generalized coordinates are internal to it and cancel. Expressions of the
    slaves' symbols (substituted on output)."""
    from .._symbols import restore_assumptions
    from ..compile._dynamics import _mass_key, body_terms
    from ..loads._loads import BodyMoment, PointForce

    space = model.space
    s = joint.slave
    children: dict = {}
    for c in gen_joints(model):
        children.setdefault(c.master, []).append(c)
    # subtree poses in the slave's symbols
    expr = {x: x for x in s.q}
    order = [s]
    stack = [s]
    while stack:
        b = stack.pop()
        for c in children.get(b, []):
            r, rot = c.pose(space)
            for x, e in zip(c.slave.q, [*r, *rot]):
                expr[x] = e.xreplace({k: v for k, v in expr.items() if k in e.free_symbols})
            order.append(c.slave)
            stack.append(c.slave)
    members = set(order)
    X = {b: [sp.S.Zero] * len(b.q) for b in order}
    for b in order:
        rates = tuple(velocity_symbol(x.name) for x in b.q)
        _, Mb, Qvb = body_terms(space, tuple(b.q), rates, *_mass_key(space, b))
        acc = [acceleration_symbol(x.name) for x in b.q]
        for a in range(len(b.q)):
            row = sp.Add(*(restore_assumptions(sp.sympify(Mb[a][k])) * acc[k]
                           for k in range(len(b.q)) if Mb[a][k] != 0))
            X[b][a] += row - restore_assumptions(sp.sympify(Qvb[a]))
    for ld in model._loads:
        for c in ld.contributions(model):
            if isinstance(c, PointForce) and c.point.body in members:
                b = c.point.body
                r = list(c.point.location())
                for a, x in enumerate(b.q):
                    X[b][a] -= sp.Add(*(ri.diff(x) * fi for ri, fi in zip(r, c.force)))
            elif isinstance(c, BodyMoment) and c.body in members:
                b = c.body
                rates = [velocity_symbol(x.name) for x in b.q]
                w = space.as_rotation_vector(space.omega(b.q[space.dim:], rates[space.dim:]))
                Mv = space.as_rotation_vector(c.moment)
                for a, v in enumerate(rates):
                    X[b][a] -= (w.diff(v).T * Mv)[0, 0]
    for c in model._constraints:
        if isinstance(c, GenJoint) or not (set(c.bodies()) & members):
            continue
        try:
            lam = lams(c)
        except ModelError:  # dropped by free(): no multipliers
            continue
        eqs = c.equations(space)
        for b in order:
            if b not in c.bodies():
                continue
            for a, x in enumerate(b.q):
                X[b][a] += sp.Add(*(e.diff(x) * la for e, la in zip(eqs, lam)))
    G = []
    for y in s.q:
        G.append(sp.Add(*(expr[x].diff(y) * X[b][a] for b in order
                          for a, x in enumerate(b.q) if X[b][a] != 0)))
    return G
