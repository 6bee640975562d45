r"""Dynamic terms of a compiled system: mass matrix, applied and velocity-dependent forces.

Per body ``b`` with kinetic energy (written once for 2D and 3D)::

    T_b = m |v_c|^2 / 2 + omega'^T J' omega' / 2,   v_c = d/dt (r + A c'),
    omega' = body-local angular velocity, J' = centroidal inertia in body axes

Lagrange's equations give, on that body's coordinates,

    M_b  = d^2 T_b / d qd_b^2
    Qv_b = dT_b/dq_b - (d^2 T_b / d qd_b dq_b) qd_b      (centrifugal, gyroscopic)

and the applied generalized forces come from the loads by virtual work (``_loads``).
With one multiplier ``lambda_i`` per constraint equation, the equations of motion are::

    M qdd + Phi_q^T lambda = Q(t, q, qd, lambda) + Qv(q, qd)

Numeric functions take ``x = [t, q (n), qd (n), lambda (m), p]``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps
import sympy as sp

from .._symbols import T
from ._backends import compile_exprs
from ._derive import hessian_terms, time_derivative


def multiplier_symbols(layout) -> tuple:
    """One Lagrange multiplier symbol per equation row: ``lam<cnum>_<k>`` (constraint number
    and equation index from 1) or ``lamN_<body>`` for Euler-parameter normalisation."""
    out = []
    for owner, k in zip(layout.eq_owner, layout.eq_index):
        num = getattr(owner, "number", None)
        if num is not None:
            out.append(sp.Symbol(f"lam{num}_{k + 1}"))
        else:
            body = str(owner).split("'")[1] if "'" in str(owner) else str(len(out))
            out.append(sp.Symbol(f"lamN_{body}"))
    return tuple(out)


def body_kinetic_energy(space, body, qd_of) -> sp.Expr:
    """``T_b`` as an expression of the body's coordinates and velocities."""
    if body.is_ground:
        return sp.S.Zero
    q = list(body.q)
    qd = [qd_of[s] for s in q]
    rc = body.r + body.A * body.centroid
    vc = rc.applyfunc(lambda e: time_derivative(e, q, qd))
    w = space.as_rotation_vector(space.omega(q[space.dim :], qd[space.dim :], local=True))
    J = space.inertia_matrix(body.inertia)
    trans = body.mass * (vc.T * vc)[0, 0] / 2
    rot = (w.T * J * w)[0, 0] / 2
    return (trans + rot) if body.mass != 0 or any(J) else sp.S.Zero


def generalized_forces(model, loads, layout) -> list:
    """Applied generalized forces ``Q`` (n,) of ``loads`` by virtual work."""
    from ..loads._loads import BodyMoment, DirectLoad, PointForce

    n = layout.n
    qd_of = dict(zip(layout.q_symbols, layout.qd_symbols))
    index = {s: i for i, s in enumerate(layout.q_symbols)}
    Q = [sp.S.Zero] * n
    for load in loads:
        for c in load.contributions(model):
            if isinstance(c, DirectLoad):
                if c.symbol not in index:
                    raise KeyError(c.symbol)
                Q[index[c.symbol]] += c.magnitude
                continue
            if isinstance(c, PointForce):
                body = c.point.body
                if body is None or body.is_ground:
                    continue
                v = c.point.location().applyfunc(
                    lambda e, b=body: time_derivative(e, b.q, [qd_of[s] for s in b.q]))
                F = sp.Matrix(c.force)
                for s in body.q:
                    Jcol = v.diff(qd_of[s])
                    Q[index[s]] += (Jcol.T * F)[0, 0]
            elif isinstance(c, BodyMoment):
                body = c.body
                if body.is_ground:
                    continue
                rot = body.q[model.space.dim :]
                w = model.space.as_rotation_vector(
                    model.space.omega(rot, [qd_of[s] for s in rot], local=False))
                M = model.space.as_rotation_vector(c.moment)
                for s in body.q:
                    Q[index[s]] += (w.diff(qd_of[s]).T * M)[0, 0]
    return Q


class Dynamics:
    """Symbolic and compiled dynamic terms of one :class:`System`.

    Attributes: ``lam`` (m,) multiplier symbols; ``M_rows/M_cols/M_exprs`` the sparse mass
    matrix; ``Q`` (n,) applied, ``Qv`` (n,) velocity-dependent generalized forces;
    ``kinetic`` {body name: T_b}; ``potential`` total potential energy of conservative loads
    (gravity, linear springs, or None when none); ``depends_on_lambda`` whether ``Q``
    depends on multipliers (friction) and then ``dQ_dlam`` (n, m) sparse values.
    Compiled: ``f_terms(x) -> [M values, Q, Qv]`` and ``f_dQ_dlam(x)``.
    """

    def __init__(self, system, model, bodies, loads):
        lay = system.layout
        self.system = system
        self.lam = multiplier_symbols(lay)
        qd_of = dict(zip(lay.q_symbols, lay.qd_symbols))
        index = {s: i for i, s in enumerate(lay.q_symbols)}
        rows, cols, vals, Qv = [], [], [], [sp.S.Zero] * lay.n
        self.kinetic = {}
        for b in bodies:
            Tb = body_kinetic_energy(model.space, b, qd_of)
            self.kinetic[b.name] = Tb
            if Tb == 0:
                continue
            q = list(b.q)
            qd = [qd_of[s] for s in q]
            Mb, Qvb = hessian_terms(Tb, q, qd)
            for i, si in enumerate(q):
                for j in range(len(q)):
                    if Mb[i][j] != 0:
                        rows.append(index[si])
                        cols.append(index[q[j]])
                        vals.append(Mb[i][j])
                Qv[index[si]] += Qvb[i]
        self.M_rows = np.array(rows, dtype=int)
        self.M_cols = np.array(cols, dtype=int)
        self.M_exprs = vals
        self.Qv = list(Qv)
        self.Q = generalized_forces(model, loads, lay)
        pots = [ld.potential(model) for ld in loads]
        self.potential = sum((p for p in pots if p is not None), sp.S.Zero) if any(
            p is not None for p in pots) else None
        lamset = set(self.lam)
        self.depends_on_lambda = any(e.free_symbols & lamset for e in self.Q)
        self.depends_on_qd = any(e.free_symbols & set(lay.qd_symbols) for e in self.Q)
        qddset = set(lay.qdd_symbols)
        #: loads that depend on accelerations (added mass, inertial couplings): free
        #: accelerations are then found by Newton on (qdd, lambda)
        self.depends_on_qdd = any(e.free_symbols & qddset for e in self.Q)
        self.linear_in_qdd = all(
            sp.diff(e, a, b) == 0 for e in self.Q if e.free_symbols & qddset
            for a in (e.free_symbols & qddset) for b in (e.free_symbols & qddset))
        args = self.args()
        allowed = set(args)
        for i, e in enumerate(self.Q):
            extra = e.free_symbols - allowed
            if extra:
                from .._errors import ModelError

                raise ModelError(
                    f"the applied force on coordinate {lay.q_names[i]} uses unknown symbol(s) "
                    f"{sorted(map(str, extra))}; loads may use T, coordinates, velocities, "
                    "accelerations, parameters and constraint multipliers")
        self.f_terms = compile_exprs(args, list(vals) + list(self.Q) + self.Qv, system.backend)
        self._kernel = None
        if self.depends_on_lambda:
            self.dQ_rows, self.dQ_cols, self.f_dQ_dlam = self._sparse_derivative(self.lam, args)
        if self.depends_on_qdd:
            self.dA_rows, self.dA_cols, self.f_dQ_dqdd = self._sparse_derivative(
                lay.qdd_symbols, args)

    def _sparse_derivative(self, wrt, args):
        """Rows, columns and compiled values of the nonzero ``dQ_i / d wrt_j``."""
        dr, dc, dv = [], [], []
        for i, e in enumerate(self.Q):
            for j, w in enumerate(wrt):
                if w in e.free_symbols:
                    dr.append(i)
                    dc.append(j)
                    dv.append(sp.diff(e, w))
        return (np.array(dr, dtype=int), np.array(dc, dtype=int),
                compile_exprs(args, dv, self.system.backend))

    def free_kernel(self, sparse: bool = False) -> FreeKernel:
        """The compiled augmented system of free motion (built once, cached)."""
        if self._kernel is None or self._kernel.sparse != sparse:
            self._kernel = FreeKernel(self.system, sparse)
        return self._kernel

    def args(self) -> list:
        lay = self.system.layout
        return [T, *lay.q_symbols, *lay.qd_symbols, *self.lam, *lay.p_symbols, *lay.qdd_symbols]

    def pack(self, t, q, qd, lam, p, qdd=None) -> np.ndarray:
        n = self.system.n
        return np.concatenate(([t], q, qd, lam, p, np.zeros(n) if qdd is None else qdd))

    def terms(self, t, q, qd, lam, p, qdd=None):
        """``(M (n, n) dense, Q (n,), Qv (n,))`` at one state (``qdd`` only matters for
        acceleration-dependent loads)."""
        n = self.system.n
        out = self.f_terms(self.pack(t, q, qd, lam, p, qdd))
        k = len(self.M_exprs)
        M = np.zeros((n, n))
        np.add.at(M, (self.M_rows, self.M_cols), out[:k])
        return M, out[k : k + n], out[k + n :]

    def dQ_dlam(self, t, q, qd, lam, p, qdd=None) -> np.ndarray:
        n, m = self.system.n, self.system.m
        D = np.zeros((n, m))
        if self.depends_on_lambda:
            np.add.at(D, (self.dQ_rows, self.dQ_cols),
                      self.f_dQ_dlam(self.pack(t, q, qd, lam, p, qdd)))
        return D

    def dQ_dqdd(self, t, q, qd, lam, p, qdd=None) -> np.ndarray:
        n = self.system.n
        D = np.zeros((n, n))
        if self.depends_on_qdd:
            np.add.at(D, (self.dA_rows, self.dA_cols),
                      self.f_dQ_dqdd(self.pack(t, q, qd, lam, p, qdd)))
        return D

    def mass_matrix_sparse(self, vals):
        n = self.system.n
        return sps.csc_matrix((vals, (self.M_rows, self.M_cols)), shape=(n, n))


class FreeKernel:
    r"""The augmented system of free motion in one compiled call::

        K = [[M, Phi_q^T], [Phi_q, 0]]   (n + m, n + m),   rhs = [Q + Qv ; gamma]

    Values are scattered into ``K`` through precomputed flat indices (dense) or a fixed CSC
    pattern (sparse, ``n + m`` above the sparse threshold): no symbolic or Python-level
    assembly work per evaluation beyond one compiled call.
    """

    def __init__(self, system, sparse: bool):
        dyn = system.dynamics
        n, m = system.n, system.m
        N = n + m
        self.n, self.m, self.N, self.sparse = n, m, N, sparse
        self.dyn = dyn
        jac = system.kinematic_exprs("jac", for_compile=True)
        gamma = system.kinematic_exprs("gamma", for_compile=True)
        exprs = list(dyn.M_exprs) + list(jac)
        exprs += [a + b for a, b in zip(dyn.Q, dyn.Qv)] + list(gamma)
        self.k_M, self.k_J = len(dyn.M_exprs), len(jac)
        self._zeros = np.zeros(n)
        self.f = compile_exprs(dyn.args(), exprs, system.backend)
        rows = np.concatenate((dyn.M_rows, system.jac_cols, n + system.jac_rows))
        cols = np.concatenate((dyn.M_cols, n + system.jac_rows, system.jac_cols))
        self._map = np.concatenate((np.arange(self.k_M), self.k_M + np.arange(self.k_J),
                                    self.k_M + np.arange(self.k_J)))
        if sparse:
            order = np.lexsort((rows, cols))        # CSC: by column, then row
            self._perm = self._map[order]
            self._indices = rows[order]
            counts = np.bincount(cols, minlength=N)
            self._indptr = np.concatenate(([0], np.cumsum(counts)))
        else:
            self._flat = rows * N + cols

    def __call__(self, t, q, qd, lam, p):
        out = self.f(np.concatenate(([t], q, qd, lam, p, self._zeros)))
        kk = self.k_M + self.k_J
        vals = out[:kk]
        rhs = out[kk:]
        if self.sparse:
            K = sps.csc_matrix((vals[self._perm], self._indices, self._indptr),
                               shape=(self.N, self.N))
        else:
            K = np.zeros((self.N, self.N))
            K.flat[self._flat] = vals[self._map]
        return K, rhs
