r"""Dynamic terms of a compiled system: mass matrix, applied and velocity-dependent forces.

Per body ``b`` with kinetic energy (written once for 2D and 3D)

.. math::

    T_b &= m \lvert v_c \rvert^2 / 2 + \omega'^T J' \omega' / 2 \\
    v_c &= \frac{d}{dt} (r + A c')

with :math:`\omega'` the body-local angular velocity and :math:`J'` the centroidal inertia in
body axes.

Lagrange's equations give, on that body's coordinates,

.. math::

    M_b &= \partial^2 T_b / \partial \dot q_b^2 \\
    Q_{v,b} &= \partial T_b / \partial q_b - (\partial^2 T_b / \partial \dot q_b \partial q_b)
        \, \dot q_b \qquad \text{(centrifugal, gyroscopic)}

and the applied generalized forces come from the loads by virtual work (``_loads``).
With one multiplier :math:`\lambda_i` per constraint equation, the equations of motion are

.. math::

    M \ddot q + \Phi_q^T \lambda = Q(t, q, \dot q, \lambda) + Q_v(q, \dot q)

Numeric functions take :math:`x = [t, q (n), \dot q (n), \lambda (m), p]`.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import scipy.sparse as sps
import sympy as sp

from .._symbols import T, velocity_symbol
from ..solvers._linalg import FixedPattern
from ._backends import compile_exprs, gc_paused, real_expression
from ._derive import hessian_terms, se_symbol, time_derivative, to_sympy_list

try:  # optional
    import symengine as se
except ImportError:  # pragma: no cover
    se = None


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
    q = tuple(body.q)
    return body_terms(space, q, tuple(qd_of[s] for s in q), *_mass_key(space, body))[0]


def _mass_key(space, body) -> tuple:
    """Hashable mass properties of a body: ``(m, centroid (dim,), inertia entries)`` with the
    inertia as ``J`` (2D) or its symmetric part ``(Jxx, Jyy, Jzz, Jxy, Jyz, Jzx)`` (3D): only
    the symmetric part enters ``w^T J w``."""
    if space.dim == 2:
        # the scalar itself (space.inertia_matrix would wrap it in a 1 x 1 SymPy Matrix)
        jkey = (sp.sympify(0 if body.inertia is None else body.inertia),)
    else:
        J = space.inertia_matrix(body.inertia)
        jkey = (J[0, 0], J[1, 1], J[2, 2], (J[0, 1] + J[1, 0]) / 2, (J[1, 2] + J[2, 1]) / 2,
                (J[2, 0] + J[0, 2]) / 2)
    return sp.sympify(body.mass), tuple(body.centroid), jkey


@functools.lru_cache(maxsize=4)
def _body_template(space) -> tuple:
    """Kinetic energy, mass matrix and velocity forces of one body with *symbolic* mass
    properties and generic coordinates, derived once per space::

        T = m/2 |d/dt (r + A c')|^2 + 1/2 w'^T J w',
        M_ij = d^2 T / d qd_i d qd_j,   Qv_i = dT/dq_i - sum_j d^2 T / d qd_i d q_j qd_j

    Each body then only substitutes its own symbols and values (``body_terms``): a 256-link
    chain derives this once instead of 256 times. Expressions are SymEngine's when it is
    installed (substitution there is ~50 times faster than SymPy's), else SymPy's.
    """
    dim = space.dim
    nq = space.ncoord
    q = sp.symbols(f"_q0:{nq}")
    qd = sp.symbols(f"_qd0:{nq}")
    m = sp.Symbol("_m")
    c = sp.Matrix(sp.symbols(f"_c0:{dim}"))
    if dim == 2:
        jsyms = (sp.Symbol("_J"),)
        J = sp.Matrix([[jsyms[0]]])
    else:
        jsyms = sp.symbols("_Jxx _Jyy _Jzz _Jxy _Jyz _Jzx")
        xx, yy, zz, xy, yz, zx = jsyms
        J = sp.Matrix([[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]])
    rot, rot_d = list(q[dim:]), list(qd[dim:])
    syms = (q, qd, m, tuple(c), jsyms)
    if se is not None:
        return (syms, *_body_template_native(space, q, qd, m, list(c), J))
    rc = sp.Matrix(q[:dim]) + space.rotation_matrix(rot) * c
    vc = rc.applyfunc(lambda e: time_derivative(e, q, qd))
    w = space.as_rotation_vector(space.omega(rot, rot_d, local=True))
    T = m * (vc.T * vc)[0, 0] / 2 + (w.T * J * w)[0, 0] / 2
    M, Qv = hessian_terms(T, list(q), list(qd))
    return syms, T, M, Qv


def _body_template_native(space, q, qd, m, c, J) -> tuple:
    """``(T, M, Qv)`` of :func:`_body_template` derived in SymEngine: the rotation matrix
    and the local angular velocity are built by the space in SymPy (a few small
    expressions), the rest (the centroid's velocity, ``T`` and its derivatives) in SymEngine,
    about ten times faster than in SymPy (0.2 s of a spatial arm's first inverse dynamics,
    decision 0065). The same polynomial as the SymPy derivation (no ``Mod`` or other
    step function can occur in it, so no :func:`hessian_terms` rewriting is needed)."""
    dim, n = space.dim, len(q)
    cv = se.sympify
    Q, QD = [cv(s) for s in q], [cv(s) for s in qd]
    A = space.rotation_matrix(list(q[dim:]))
    C = [cv(s) for s in c]
    rc = [Q[i] + sum((cv(A[i, j]) * C[j] for j in range(dim)), cv(0)) for i in range(dim)]
    vc = [sum((e.diff(a) * b for a, b in zip(Q, QD)), cv(0)) for e in rc]
    w = [cv(e) for e in space.as_rotation_vector(space.omega(list(q[dim:]), list(qd[dim:]),
                                                             local=True))]
    Jn = [[cv(J[i, j]) for j in range(J.shape[1])] for i in range(J.shape[0])]
    T = cv(m) * sum((v * v for v in vc), cv(0)) / 2 + sum(
        (w[i] * Jn[i][j] * w[j] for i in range(len(w)) for j in range(len(w))), cv(0)) / 2
    p = [T.diff(v) for v in QD]
    M = [[p[i].diff(QD[j]) for j in range(n)] for i in range(n)]
    Qv = []
    for i in range(n):
        acc = T.diff(Q[i])
        for sj, vj in zip(Q, QD):
            acc -= p[i].diff(sj) * vj
        Qv.append(se.expand(acc))
    return T, M, Qv


@functools.lru_cache(maxsize=4096)
def body_terms(space, q: tuple, qd: tuple, mass, centroid: tuple, inertia: tuple) -> tuple:
    """``(T_b, M_b (nq x nq nested lists), Qv_b (nq,))`` of one body, SymEngine expressions
    when SymEngine is installed (else SymPy). Memoized: the systems derived from one model
    (the full model, its free and path systems, a re-compile after a constraint edit)
    share them."""
    (gq, gqd, gm, gc, gJ), T, M, Qv = _body_template(space)
    if mass == 0 and all(j == 0 for j in inertia):
        z = sp.S.Zero
        return z, [[z] * len(q) for _ in q], [z] * len(q)
    pairs = [*zip(gq, q), *zip(gqd, qd), (gm, mass), *zip(gc, centroid), *zip(gJ, inertia)]
    if se is not None:
        # (symbols and the shared mass properties converted once: ~10 us each)
        sub = {se_symbol(k): se_symbol(v) for k, v in pairs}
        # one substitution of all the body's terms at once: SymEngine converts the Python
        # dict on every xreplace call (13 calls a planar body, 57 a spatial one)
        nq = len(q)
        flat = [T, *(e for row in M for e in row), *Qv]
        done = [se.expand(e) for e in se.DenseMatrix(len(flat), 1, flat).xreplace(sub)]
        return done[0], [done[1 + i * nq: 1 + (i + 1) * nq] for i in range(nq)], done[1 + nq * nq:]
    else:
        sub = dict(pairs)
        rep = lambda e: sp.expand(e.xreplace(sub))
    return rep(T), [[rep(e) for e in row] for row in M], [rep(e) for e in Qv]


def _real_contribution(c, owner: str):
    """A load's contribution with its expressions checked for real double-precision code
    (:func:`~mechsys.compile._backends.real_expression`, naming the load)."""
    from dataclasses import replace

    from ..loads._loads import BodyMoment, DirectLoad, PointForce

    if isinstance(c, DirectLoad):
        return replace(c, magnitude=real_expression(sp.sympify(c.magnitude), owner))
    if isinstance(c, PointForce):
        # (a force already fit, as gravity's constant one: kept, not copied entry by entry
        # into a new matrix, ~0.1 ms a body)
        if all(real_expression(e, owner) is e for e in c.force):
            return c
        return replace(c, force=c.force.applyfunc(lambda e: real_expression(e, owner)))
    if isinstance(c, BodyMoment):
        M = c.moment
        M = M.applyfunc(lambda e: real_expression(e, owner)) if isinstance(M, sp.MatrixBase) \
            else real_expression(sp.sympify(M), owner)
        return replace(c, moment=M)
    return c


def generalized_forces(model, loads, layout, slaves: dict | None = None) -> list:
    """Applied generalized forces ``Q`` (n,) of ``loads`` by virtual work. With ``slaves``
    (a dict, recursive Gen dynamics: ``compile/_generalized.py``) the forces on slave bodies
    are not projected: ``slaves[body]`` receives them on the slave's own pose coordinates, and
    slave symbols stay in ``Q``."""
    from ..loads._loads import BodyMoment, DirectLoad, PointForce

    n = layout.n
    qd_of = dict(zip(layout.q_symbols, layout.qd_symbols))
    index = {s: i for i, s in enumerate(layout.q_symbols)}
    if slaves is not None:
        # (the recursion keeps the slaves' loads on their poses: whether a body is a slave
        # is all it asks, not the nested poses, decision 0057)
        gen = any(getattr(b, "gen_joint", None) is not None for b in model.bodies[1:])
    else:
        gen = model._gen_substitution() if hasattr(model, "_gen_substitution") else {}
    projected: dict = {}  # layout index -> the slaves' projected loads
    Q = [sp.S.Zero] * n
    for load in loads:
        for c in load.contributions(model):
            c = _real_contribution(c, load.label())
            if isinstance(c, DirectLoad):
                if c.symbol not in index:
                    raise KeyError(c.symbol)
                Q[index[c.symbol]] += c.magnitude
                continue
            if isinstance(c, PointForce):
                body = c.point.body
                if body is None or body.is_ground:
                    continue
                F = list(c.force)
                slave = gen and body.gen_joint is not None
                # (the recursion keeps a slave's loads on its own pose coordinates, which the
                # closed form gives as for an absolute body; projected slaves differentiate)
                fast = None if slave and slaves is None else \
                    _point_force_terms(model.space, body, c.point, F)
                if fast is not None and slave:
                    _collect(slaves, body, fast)
                    continue
                if fast is not None:
                    for s, v in zip(body.q, fast):
                        Q[index[s]] += v
                    continue
                # virtual work: d(velocity)/d(qd_s) = d(location)/d(q_s) for a body point
                r = list(c.point.location())
                if slave and slaves is not None:
                    _collect(slaves, body, [sp.Add(*(ri.diff(s) * fi for ri, fi in zip(r, F)))
                                            for s in body.q])
                    continue
                if slave:  # a slave: project on q (J^T Q_p)
                    _project(projected, body, [sp.Add(*(ri.diff(s) * fi for ri, fi in zip(r, F)))
                                               for s in body.q], model)
                    continue
                for s in body.q:
                    # scalar diffs: Matrix.diff goes through SymPy's array derivatives (slow)
                    Q[index[s]] += sp.Add(*(ri.diff(s) * fi for ri, fi in zip(r, F)))
            elif isinstance(c, BodyMoment):
                body = c.body
                if body.is_ground:
                    continue
                rot = body.q[model.space.dim :]
                M = model.space.as_rotation_vector(c.moment)
                if gen and body.gen_joint is not None:
                    rates = [velocity_symbol(s.name) for s in body.q]
                    w = model.space.as_rotation_vector(
                        model.space.omega(rot, rates[model.space.dim:], local=False))
                    wq = [(w.diff(v).T * M)[0, 0] for v in rates]
                    if slaves is not None:
                        _collect(slaves, body, wq)
                    else:
                        _project(projected, body, wq, model)
                    continue
                w = model.space.as_rotation_vector(
                    model.space.omega(rot, [qd_of[s] for s in rot], local=False))
                for s in body.q:
                    Q[index[s]] += (w.diff(qd_of[s]).T * M)[0, 0]
    if gen and slaves is None:  # load magnitudes of slave coordinates (a spring to a slave point)
        slaves = set(gen)
        Q = [e.xreplace(gen) if (e := sp.sympify(q)).free_symbols & slaves else e for q in Q]
        from .._symbols import restore_assumptions

        for i, v in projected.items():  # slaves' loads, projected natively (SymEngine)
            Q[i] += restore_assumptions(sp.sympify(v))
    return Q


def _rotation_derivatives(body) -> list:
    """``dA/ds`` (entries, nested lists) of ``body``'s rotation matrix for each of its
    rotational coordinates ``s``, differentiated once per body and kept on it (every point
    load on the body reuses them)."""
    cached = body.__dict__.get("_dA_cache")
    if cached is not None and cached[0] is body.A:
        return cached[1]
    A = body.A
    dim = A.rows
    rot = body.q[dim:]
    # (A[0, 0] is cos(th): tested by type and argument, no cos made to compare with)
    a00 = A[0, 0]
    if dim == 2 and len(rot) == 1 and type(a00) is sp.cos and a00.args == (rot[0],):
        # A(th) = [[c, -s], [s, c]]: dA/dth = A [[0, -1], [1, 0]], no differentiation (SymPy's
        # diff costs ~1 ms an entry: 4 s of a 1024-link chain)
        out = [[[A[0, 1], -A[0, 0]], [A[1, 1], -A[1, 0]]]]
    elif se is not None:
        # SymEngine differentiates ~100 times faster; the round trip drops the symbols' real
        # assumption, which restore_assumptions puts back
        from .._symbols import restore_assumptions

        sA = [[se.sympify(A[i, j]) for j in range(dim)] for i in range(dim)]
        out = [[[restore_assumptions(sp.sympify(sA[i][j].diff(se.sympify(s))))
                 for j in range(dim)] for i in range(dim)] for s in rot]
    else:
        # entry by entry: Matrix.diff goes through SymPy's array derivatives (slower still)
        out = [[[A[i, j].diff(s) for j in range(dim)] for i in range(dim)] for s in rot]
    body._dA_cache = (A, out)
    return out


def _point_force_terms(space, body, point, F) -> list | None:
    r"""Virtual work of the force ``F`` (global) at a body-fixed point ``c'`` of ``body``
    (``r_P = r + A c'``) on the body's coordinates, in closed form::

        Q_r = F,    Q_s = (dA/ds c')^T F = sum_ij F_i (dA/ds)_ij c'_j   (s rotational)

    with ``dA/ds`` differentiated once per body (:func:`_rotation_derivatives`) and the
    products of zero coordinates or force components left out (gravity on a rod: two terms
    of eight), instead of differentiating every point's location expression or substituting
    into a generic template (10 ms a body in SymPy: 5 s of a 512-link chain's build); None
    when the point is not such a point (its local coordinates depend on the body's
    coordinates), for the general path."""
    from ..geometry._points import Point

    if type(point) is not Point or point.body is not body:
        return None
    local = list(point.local)
    q = tuple(body.q)
    if any(e.free_symbols & set(q) for e in local):
        return None
    dim = space.dim
    out = [sp.sympify(f) for f in F[:dim]]
    pairs = [(i, j, out[i] * local[j]) for i in range(dim) for j in range(dim)
             if out[i] != 0 and local[j] != 0]
    for dA in _rotation_derivatives(body):
        out.append(sp.Add(*(_times(dA[i][j], w) for i, j, w in pairs)))
    return out


def _times(a, w):
    r"""``a * w``. For ``a`` the cosine or sine of a symbol (a planar rotation matrix's
    entry) and ``w`` a Float other than 0 and :math:`\pm 1`, SymPy's product is the
    two-factor ``Mul`` of ``w`` and ``a``; built directly: ``Mul``'s general flattening makes
    a new Float coefficient whose first ``is_zero`` runs SymPy's fact deduction (~0.2 ms, a
    fifth of a 1024-link chain's dynamics, decision 0079). The same expression (equal,
    same ``srepr``)."""
    if type(w) is sp.Float and (type(a) is sp.cos or type(a) is sp.sin) \
            and type(a.args[0]) is sp.Symbol:
        v = float(w)
        if math.isfinite(v) and v not in (0.0, 1.0, -1.0):
            return sp.Mul._from_args((w, a), True)
    return a * w


def _collect(out: dict, body, Qp) -> None:
    """Add ``Qp`` (on the slave's pose coordinates) to ``out[body]``."""
    prev = out.get(body)
    out[body] = list(Qp) if prev is None else [a + b for a, b in zip(prev, Qp)]


def _project(out: dict, body, Qp, model) -> None:
    """Add a slave's generalized force ``Qp`` (on its own pose coordinates, SymPy, in the
    slave's symbols) to ``out`` ({layout index: value}) as ``J^T Qp`` (``J`` its pose
    Jacobian, ``constraints/_generalized.GenKinematics``), natively: SymEngine when
    installed, where the slave symbols are replaced by their expressions too."""
    kin = model._gen_kinematics()
    conv = kin.conv
    native = kin.native_subs
    for s, f in zip(body.q, Qp):
        if f == 0:
            continue
        fn = conv(f).xreplace(native)
        for i, d in kin.jac[s].items():
            out[i] = out[i] + d * fn if i in out else d * fn


class Dynamics:
    """Symbolic and compiled dynamic terms of one :class:`System`.

    Attributes: ``lam`` (m,) multiplier symbols; ``M_rows/M_cols/M_exprs`` the sparse mass
    matrix; ``Q`` (n,) applied, ``Qv`` (n,) velocity-dependent generalized forces;
    ``kinetic`` {body name: T_b}; ``potential`` total potential energy of conservative loads
    (gravity, linear springs, or None when none); ``depends_on_lambda`` whether ``Q``
    depends on multipliers (friction) and then ``dQ_dlam`` (n, m) sparse values.
    Compiled: ``f_terms(x) -> [M values, Q, Qv]`` and ``f_dQ_dlam(x)``.
    """

    @gc_paused()
    def __init__(self, system, model, bodies, loads):
        lay = system.layout
        self.system = system
        self.lam = multiplier_symbols(lay)
        qd_of = dict(zip(lay.q_symbols, lay.qd_symbols))
        index = {s: i for i, s in enumerate(lay.q_symbols)}
        # accumulate natively: a SymPy zero plus a SymEngine term would turn SymPy and lose
        # the real assumptions of the symbols
        zero = se.Integer(0) if se is not None else sp.S.Zero
        Qv = [zero] * lay.n
        entries: dict = {}  # (row, col) -> value: slaves' projected blocks overlap
        kinetic = {}
        gen = system.gen_subs
        for b in bodies:
            q = list(b.q)
            slave = gen and b.gen_joint is not None
            rates = tuple(velocity_symbol(s.name) if slave else qd_of[s] for s in q)
            Tb, Mb, Qvb = body_terms(model.space, tuple(q), rates, *_mass_key(model.space, b))
            if Tb == 0:
                kinetic[b.name] = Tb
                continue
            if slave:  # the slave's inertia projected on the coordinates it depends on
                from ._generalized import project_inertia

                kinetic[b.name], blocks, forces = project_inertia(b, Tb, Mb, Qvb,
                                                                  model._gen_kinematics())
                for key, v in blocks.items():
                    entries[key] = entries[key] + v if key in entries else v
                for i, v in forces.items():
                    Qv[i] += v
                continue
            kinetic[b.name] = Tb
            for i, si in enumerate(q):
                for j in range(len(q)):
                    if Mb[i][j] != 0:
                        key = (index[si], index[q[j]])
                        entries[key] = entries[key] + Mb[i][j] if key in entries else Mb[i][j]
                Qv[index[si]] += Qvb[i]
        rows = [k[0] for k in entries]
        cols = [k[1] for k in entries]
        vals = list(entries.values())
        self.M_rows = np.array(rows, dtype=int)
        self.M_cols = np.array(cols, dtype=int)
        # native (SymEngine) expressions feed the compiler; SymPy copies are made on first use
        self._native = {"M": vals, "Qv": Qv, "kinetic": kinetic}
        self._sympy: dict = {}
        self.Q = generalized_forces(model, loads, lay)
        self._potential = (model, tuple(loads))
        # each force's free symbols once (SymPy walks the expression on every ask)
        free = [e.free_symbols for e in self.Q]
        lamset = set(self.lam)
        self.depends_on_lambda = any(f & lamset for f in free)
        qdset = set(lay.qd_symbols)           # once: not per load term (N^2 for N bodies)
        self.depends_on_qd = any(f & qdset for f in free)
        qddset = set(lay.qdd_symbols)
        #: loads that depend on accelerations (added mass, inertial couplings): free
        #: accelerations are then found by Newton on (qdd, lambda)
        self.depends_on_qdd = any(f & qddset for f in free)
        self.linear_in_qdd = all(
            sp.diff(e, a, b) == 0 for e, f in zip(self.Q, free) if f & qddset
            for a in (f & qddset) for b in (f & qddset))
        args = self.args()
        allowed = set(args)
        for i, f in enumerate(free):
            extra = f - allowed
            if extra:
                from .._errors import ModelError

                raise ModelError(
                    f"the applied force on coordinate {lay.q_names[i]} uses unknown symbol(s) "
                    f"{sorted(map(str, extra))}; loads may use T, coordinates, velocities, "
                    "accelerations, parameters and constraint multipliers")
        self._f_terms = None
        self._kernel = None
        if self.depends_on_lambda:
            self.dQ_rows, self.dQ_cols, self.f_dQ_dlam = self._sparse_derivative(self.lam, args)
        if self.depends_on_qdd:
            self.dA_rows, self.dA_cols, self.f_dQ_dqdd = self._sparse_derivative(
                lay.qdd_symbols, args)

    @property
    def potential(self):
        """Total potential energy of the conservative loads (gravity, linear springs), or
        None when there are none (made on first use)."""
        if isinstance(self._potential, tuple):
            model, loads = self._potential
            pots = [p for p in (ld.potential(model) for ld in loads) if p is not None]
            self._potential = sp.Add(*pots) if pots else None
            if self._potential is not None and self.system.gen_subs:
                self._potential = self._potential.xreplace(self.system.gen_subs)
        return self._potential

    def _sympy_copy(self, key):
        if key not in self._sympy:
            nat = self._native[key]
            if isinstance(nat, dict):
                self._sympy[key] = dict(zip(nat, to_sympy_list(nat.values())))
            else:
                self._sympy[key] = to_sympy_list(nat)
        return self._sympy[key]

    @property
    def M_exprs(self) -> list:
        """Nonzero mass-matrix entries (SymPy) at ``(M_rows, M_cols)``."""
        return self._sympy_copy("M")

    @property
    def Qv(self) -> list:
        """Velocity-dependent generalized forces (n,), SymPy."""
        return self._sympy_copy("Qv")

    @property
    def kinetic(self) -> dict:
        """``{body name: kinetic energy}`` (SymPy)."""
        return self._sympy_copy("kinetic")

    def for_compile(self, key: str) -> list:
        """``"M"``, ``"Qv"`` or ``"Q+Qv"`` as the compiler wants them: native SymEngine
        expressions with the SymEngine backend, SymPy otherwise."""
        if self.system.backend == "symengine" and se is not None:
            if key == "Q+Qv":
                return [se.sympify(a) + b for a, b in zip(self.Q, self._native["Qv"])]
            return list(self._native[key])
        if key == "Q+Qv":
            return [a + b for a, b in zip(self.Q, self.Qv)]
        return list(self._sympy_copy(key))

    @property
    def f_terms(self):
        """Compiled ``x -> [M values, Q, Qv]`` (on first use: free motion does not need it)."""
        if self._f_terms is None:
            Q = [se.sympify(e) for e in self.Q] if (
                self.system.backend == "symengine" and se is not None) else list(self.Q)
            self._f_terms = compile_exprs(self.args(), self.for_compile("M") + Q
                                          + self.for_compile("Qv"), self.system.backend,
                                          cse=self.system.cse)
        return self._f_terms

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
                compile_exprs(args, dv, self.system.backend, cse=self.system.cse))

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
        k = len(self.M_rows)
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
    assembly work per evaluation beyond one compiled call. The sparse pattern is analysed
    once (:class:`~mechsys.solvers._linalg.FixedPattern`, attribute ``pattern``, also
    ``K.pattern``): banded LU after a reverse Cuthill-McKee ordering for chains.
    """

    @gc_paused()
    def __init__(self, system, sparse: bool):
        dyn = system.dynamics
        n, m = system.n, system.m
        N = n + m
        self.n, self.m, self.N, self.sparse = n, m, N, sparse
        self.dyn = dyn
        jac = system.kinematic_exprs("jac", for_compile=True)
        gamma = system.kinematic_exprs("gamma", for_compile=True)
        M, forces = dyn.for_compile("M"), dyn.for_compile("Q+Qv")
        exprs = M + list(jac) + forces + list(gamma)
        self.k_M, self.k_J = len(dyn.M_rows), len(jac)
        self._zeros = np.zeros(n)
        # (the blocks as sections: the Jacobian's parts are those of the position kernel's,
        # compiled once, decision 0080)
        self.f = compile_exprs(dyn.args(), exprs, system.backend, cse=system.cse,
                               sections=[len(M), len(jac), len(forces), len(gamma)])
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
            # the pattern is analysed once (ordering, band widths); each evaluation only
            # swaps the values of one reused matrix and refactors numerically
            self.pattern = FixedPattern(self._indptr, self._indices, N)
            self._K = sps.csc_matrix((np.zeros(len(order)), self.pattern.indices,
                                      self.pattern.indptr), shape=(N, N))
            self._K.pattern = self.pattern
        else:
            self._flat = rows * N + cols

    def __call__(self, t, q, qd, lam, p):
        out = self.f(np.concatenate(([t], q, qd, lam, p, self._zeros)))
        kk = self.k_M + self.k_J
        vals = out[:kk]
        rhs = out[kk:]
        if self.sparse:
            # one matrix object, new values: valid until the next call (the free
            # acceleration uses it at once); ``K.pattern`` solves it (``_free._solve_fast``)
            K = self._K
            K.data = vals[self._perm]
        else:
            K = np.zeros((self.N, self.N))
            K.flat[self._flat] = vals[self._map]
        return K, rhs
