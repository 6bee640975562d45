r"""The compiled side of generalized-coordinate joints (``constraints/_generalized.py``):
the slaves' inertia projected on the independent coordinates and outputs of slave symbols
compiled in two stages (decision 0010). ``kin`` is the model's ``GenKinematics``."""

from __future__ import annotations

import numpy as np

from .._errors import ModelError
from .._symbols import acceleration_symbol, velocity_symbol


def project_inertia(body, Tb, Mb, Qvb, kin) -> tuple:
    r"""A slave's kinetic energy, mass matrix and velocity forces on the independent
    coordinates. With the pose ``p = P(q)``, ``p_dot = J q_dot`` and ``p_ddot = J q_ddot +
    h`` (``h = J_dot q_dot``: ``p_ddot`` at ``q_ddot = 0``), Lagrange's equations transform
    as::

        M_q  = J^T M_b(P) J
        Qv_q = J^T (Qv_b(P, J q_dot) - M_b(P) h)

    (``M_b``, ``Qv_b`` the body's terms in its own pose coordinates, ``_dynamics``).
    Returns ``(T, {(i, j): M_ij}, {i: Qv_i})`` with layout indices."""
    conv = kin.conv
    p = list(body.q)
    n = len(p)
    deps = sorted(set().union(*(kin.jac[s].keys() for s in p)))
    k = len(deps)
    zero = conv(0)
    J = [[kin.jac[s].get(i, zero) for i in deps] for s in p]
    h = [kin.acceleration(s) for s in p]
    qdd0 = {conv(a): zero for a in _layout_qdd(kin)}
    h = [e.xreplace(qdd0) for e in h]
    sub = {conv(s): kin.pos[s] for s in p}
    sub.update({conv(velocity_symbol(s.name)): kin.velocity(s) for s in p})
    Ms = [[conv(e).xreplace(sub) if e != 0 else zero for e in row] for row in Mb]
    Qs = [conv(e).xreplace(sub) for e in Qvb]
    MJ = [[sum((Ms[a][b] * J[b][j] for b in range(n) if Ms[a][b] != 0 and J[b][j] != 0), zero)
           for j in range(k)] for a in range(n)]
    blocks = {}
    for i in range(k):
        for j in range(i, k):
            v = sum((J[a][i] * MJ[a][j] for a in range(n) if J[a][i] != 0 and MJ[a][j] != 0), zero)
            if v != 0:
                blocks[(deps[i], deps[j])] = v
                if i != j:
                    blocks[(deps[j], deps[i])] = v
    rest = [Qs[a] - sum((Ms[a][b] * h[b] for b in range(n) if Ms[a][b] != 0 and h[b] != 0), zero)
            for a in range(n)]
    forces = {}
    for i in range(k):
        v = sum((J[a][i] * rest[a] for a in range(n) if J[a][i] != 0 and rest[a] != 0), zero)
        if v != 0:
            forces[deps[i]] = v
    return conv(Tb).xreplace(sub), blocks, forces


def _layout_qdd(kin) -> list:
    return [acceleration_symbol(s.name) for s in kin.index]


def _native_values(system) -> dict:
    kin = system._model._gen_kinematics()
    return {**kin.pos, **kin.vel, **kin.acc}


def slave_dependencies(system, symbols) -> set:
    """The layout symbols (``q``, ``qd``, ``qdd``) that the slave symbols among ``symbols``
    stand for."""
    native = _native_values(system)
    out = set()
    for s in symbols:
        if s in native:
            out |= system.gen_subs[s].free_symbols
    return out


class _TwoStage:
    """A compiled output of slave-body symbols: their values from the layout's coordinates
    first (one kernel, common subexpressions shared), then the output itself with them as
    extra arguments; substituting the nested slave poses into every output instead would
    copy the chain into each (minutes for a 3D arm's joint reaction)."""

    def __init__(self, pre, main, nout):
        self.pre, self.main, self.nout = pre, main, nout

    def __call__(self, x):
        x = np.asarray(x, dtype=float)
        return self.main(np.concatenate((x, self.pre(x))))

    def batch(self, X):
        X = np.atleast_2d(np.asarray(X, dtype=float))
        return self.main.batch(np.hstack((X, self.pre.batch(X).reshape(X.shape[0], -1))))


def compile_with_slaves(system, args, exprs):
    """Compile ``exprs`` (of ``args`` and slave-body symbols) as a function of ``args``."""
    from ._backends import compile_exprs

    native = _native_values(system)
    free = set().union(*(e.free_symbols for e in exprs)) if exprs else set()
    slaves = sorted((s for s in free if s in native), key=lambda s: s.name)
    extra = free - set(args) - set(slaves)
    if extra:
        raise ModelError(f"expression {exprs[0]} has symbols {sorted(map(str, extra))} that are not "
                         "coordinates, velocities, accelerations, multipliers, parameters or T "
                         "of this model")
    main = compile_exprs([*args, *slaves], list(exprs), system.backend, cse=True)
    if not slaves:
        return main
    pre = compile_exprs(args, [native[s] for s in slaves], system.backend, cse=True)
    return _TwoStage(pre, main, len(exprs))
