r"""The compiled side of generalized-coordinate joints (``constraints/_generalized.py``):
the slaves' inertia projected symbolically on the independent coordinates and outputs of
slave symbols compiled in two stages (decision 0010; ``kin`` is the model's
``GenKinematics``), and the recursive dynamics for long chains (decision 0016:
``RecursiveDynamics``, per-joint kernels, composite and articulated-body recursions)."""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._errors import ModelError, choice
from .._symbols import acceleration_symbol, velocity_symbol
from ..solvers._tree import _articulated, _assemble, _forward_py


def project_inertia(body, Tb, Mb, Qvb, kin) -> tuple:
    r"""A slave's kinetic energy, mass matrix and velocity forces on the independent
    coordinates. With the pose ``p = P(q)``, :math:`\dot{p} = J \dot{q}` and :math:`\ddot{p} = J \ddot{q} +
    h` (:math:`h = \dot{J} \dot{q}`: ``p_ddot`` at ``q_ddot = 0``), Lagrange's equations transform
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


# -- recursive dynamics (decision 0016) ----------------------------------------------------
#
# For long Gen chains the symbolic J^T M_b J above is dense and grows like N^4 in size. The
# recursive path keeps the kinematics symbolic *per joint* (one small kernel per distinct
# joint: the slave's pose, its partial derivatives and the velocity-product terms, and the
# slave's own mass matrix and velocity forces) and evaluates the mass matrix and forces in
# the mixed coordinates numerically, by a composite-body recursion over the tree of slaves.

import os  # noqa: E402

#: ``MECHSYS_GEN_DYNAMICS=auto``: the recursive path is used from this many slave bodies on,
#: planar and spatial (measured: decision 0016; a 3D chain's symbolic matrix grows faster)
RECURSIVE_AUTO = {2: 8, 3: 4}


def gen_dynamics_mode() -> str:
    """``"auto"``, ``"symbolic"`` or ``"recursive"`` from ``MECHSYS_GEN_DYNAMICS``."""
    v = os.environ.get("MECHSYS_GEN_DYNAMICS", "").strip().lower()
    if v in ("", "auto"):
        return "auto"
    if v in ("symbolic", "recursive"):
        return v
    choice(v, ("auto", "symbolic", "recursive"), "the environment variable MECHSYS_GEN_DYNAMICS")
    raise AssertionError("unreachable")  # pragma: no cover - choice raised


class _Unsupported(Exception):
    """A model the recursive Gen dynamics does not cover (the reason is the message)."""


def make_dynamics(system, model, bodies, loads):
    """The :class:`~mechsys.compile._dynamics.Dynamics` of a system with Gen joints: the
    symbolic projection (few slaves, or ``MECHSYS_GEN_DYNAMICS=symbolic``) or
    :class:`RecursiveDynamics` (``auto`` from :data:`RECURSIVE_AUTO` slaves on: 8 planar, 4
    spatial; or ``recursive``). In ``auto`` a model the recursion does not cover goes to the symbolic
    path; forced, it raises ``ModelError`` with the reason."""
    from ._dynamics import Dynamics

    mode = gen_dynamics_mode()
    nslaves = sum(1 for b in bodies if b.gen_joint is not None)
    if mode == "symbolic" or (mode == "auto" and nslaves < RECURSIVE_AUTO[model.space.dim]):
        return Dynamics(system, model, bodies, loads)
    try:
        return RecursiveDynamics(system, model, bodies, loads)
    except _Unsupported as exc:
        if mode == "recursive":
            raise ModelError(f"MECHSYS_GEN_DYNAMICS=recursive: {exc}; use "
                             "MECHSYS_GEN_DYNAMICS=symbolic (or auto) for this model") from None
        return Dynamics(system, model, bodies, loads)


def _slave_order(bodies) -> list:
    """The slave bodies, every master before its slaves."""
    order, seen = [], set()

    def visit(b):
        if b in seen:
            return
        m = b.gen_joint.master
        if m is not None and getattr(m, "gen_joint", None) is not None:
            visit(m)
        seen.add(b)
        order.append(b)

    for b in bodies:
        if b.gen_joint is not None:
            visit(b)
    return order


def _joint_exprs(space, body, p_syms, conv):
    r"""The local kernel of one slave, as ``(args, exprs, nm, k)``: with ``P`` the master's
    pose (``nm`` = 0 for ground), ``g`` the joint's ``k`` coordinates and ``x = (P, g)``::

        p   = F(x, t)                                  the slave's pose
        pd  = F_x x_dot + F_t                          its velocity
        F_P, F_g                                       p's partial derivatives
        h   = sum_x (pd)_x x_dot + (pd)_t              p_ddot at x_ddot = 0
        M_b(p), Qv_b(p, pd)                            the slave's own inertia terms

    in generic symbols (``_gP0``, ``_gg0``...), so identical joints share one kernel."""
    from .._symbols import T as Tsym
    from ._dynamics import _mass_key, body_terms

    joint = body.gen_joint
    m = joint.master
    ground = m is None or m.is_ground
    native = conv is not sp.sympify and space.dim == 3
    r, rot = joint.pose(space, conv if native else None)
    F = [*r, *rot]
    coords = list(joint.coordinates)
    mq = [] if ground else list(m.q)
    allowed = set(mq) | set(coords) | set(p_syms) | {Tsym}
    if native:
        # (SymEngine's symbols, compared by name with the model's)
        names = {str(a) for a in allowed}
        extra = {x for e in F for x in e.free_symbols if str(x) not in names}
    else:
        extra = set().union(*(sp.sympify(e).free_symbols for e in F)) - allowed
    if extra:
        raise _Unsupported(f"{joint.label()}: the slave's pose uses {sorted(map(str, extra))}, "
                           "not only its master's pose and its own coordinates")
    nm, k, nq = len(mq), len(coords), len(body.q)
    P = [sp.Symbol(f"_gP{i}") for i in range(nm)]
    Pd = [sp.Symbol(f"_gPd{i}") for i in range(nm)]
    g = [sp.Symbol(f"_gg{i}") for i in range(k)]
    gd = [sp.Symbol(f"_ggd{i}") for i in range(k)]
    sub = {conv(a): conv(b) for a, b in [*zip(mq, P), *zip(coords, g)]}
    F = [conv(e).xreplace(sub) for e in F]
    X = [conv(s) for s in [*P, *g]]
    Xd = [conv(s) for s in [*Pd, *gd]]
    t = conv(Tsym)
    zero = conv(0)
    FX = [[f.diff(x) for x in X] for f in F]
    pd = [sum((row[j] * Xd[j] for j in range(len(X)) if row[j] != 0), zero) + f.diff(t)
          for f, row in zip(F, FX)]
    h = [sum((v.diff(x) * xd for x, xd in zip(X, Xd)), zero) + v.diff(t) for v in pd]
    rates = tuple(velocity_symbol(s.name) for s in body.q)
    _, Mb, Qvb = body_terms(space, tuple(body.q), rates, *_mass_key(space, body))
    pairs = [*zip(body.q, F), *zip(rates, pd)]
    bsub = {conv(a): b for a, b in pairs}
    if conv is sp.sympify:
        # (body_terms' expressions hold plain symbols, the model's coordinates are real ones:
        # SymPy tells them apart, so they are matched by name as SymEngine matches them)
        bsub.update({sp.Symbol(str(a)): b for a, b in pairs})
    Mb = [conv(e).xreplace(bsub) for row in Mb for e in row]
    Qvb = [conv(e).xreplace(bsub) for e in Qvb]
    exprs = [*F, *pd, *(FX[i][j] for i in range(nq) for j in range(nm)),
             *(FX[i][nm + j] for i in range(nq) for j in range(k)), *h, *Mb, *Qvb]
    return [Tsym, *P, *Pd, *g, *gd, *p_syms], exprs, nm, k


def _compile(args, exprs, backend):
    from ._backends import compile_exprs
    from ._derive import to_sympy_list

    if backend == "symengine":
        # (interpreted until the work pays for LLVM: the first inverse dynamics of an arm in
        # a fresh process, decision 0065)
        return compile_exprs(args, exprs, backend, first_use=True)
    return compile_exprs(args, to_sympy_list(exprs), backend)


class RecursiveDynamics:
    r"""Dynamics of a system with Gen joints evaluated by recursion over the tree of slaves
    (decision 0016). Per slave ``s`` (master ``a``, coordinates ``g_s``), from its joint
    kernel (:func:`_joint_exprs`)::

        J_s = F_P J_a + F_g E_s,          h_s = F_P h_a + h_loc       (forward, masters first)
        C_s = M_s + sum_c F_P,c^T C_c F_P,c                           (backward: composite)
        B_s = Q_s + Qv_s - M_s h_s + sum_c F_P,c^T B_c
        M[g_a, g_s] = F_g,a^T Phi_{s<-a}^T C_s F_g,s,  Phi_{s<-a} = F_P,s ... (walk up from s)
        Q[g_s] += F_g,s^T B_s

    (``Q_s`` the applied loads on the slave's pose coordinates); an absolute master ``a``
    receives :math:`F_P^T C_s F_P` and :math:`F_P^T B_s` on its own coordinates, ground nothing.
    This is the composite-rigid-body algorithm written in pose coordinates: O(N) kernel
    calls and O(N * depth) small products per evaluation, and a compile cost linear in the
    number of *distinct* joints. The absolute bodies' terms, the loads, the constraint
    Jacobian and ``gamma`` stay in one compiled kernel with the slaves' poses and
    velocities as extra arguments.

    The symbolic terms (``Q``, ``M_exprs``, ``Qv``, ``kinetic``, ``potential``, ``f_terms``)
    are those of the symbolic :class:`~mechsys.compile._dynamics.Dynamics`, made on first
    use (outputs of loads and reactions need them; free motion does not).

    Example::

        os.environ["MECHSYS_GEN_DYNAMICS"] = "recursive"   # or many Gen joints ("auto")
        M, Q, Qv = m.free().system.dynamics.terms(0.0, q, qd, [], p)
    """

    recursive = True

    def __init__(self, system, model, bodies, loads):
        from ._dynamics import _mass_key, body_terms, generalized_forces, multiplier_symbols

        try:
            import symengine as se
        except ImportError:  # pragma: no cover
            se = None
        self.system = system
        self._twin_args = (model, bodies, loads)
        self._twin = None
        self._kernel = None
        lay = system.layout
        self.lam = multiplier_symbols(lay)
        space = model.space
        conv = se.sympify if (se is not None and system.backend == "symengine") else sp.sympify
        index = {s: i for i, s in enumerate(lay.q_symbols)}
        order = _slave_order(bodies)
        S = len(order)
        nq = space.ncoord          # pose coordinates: 3 planar, 4 planar Euler, 7 spatial
        pos = {b: i for i, b in enumerate(order)}
        par = np.full(S, -1, dtype=np.int64)
        root = np.full(S, -1, dtype=np.int64)
        nqm = np.zeros(S, dtype=np.int64)
        goff = np.zeros(S + 1, dtype=np.int64)
        gcols: list = []
        kid = np.zeros(S, dtype=np.int64)
        kernels, keys = [], {}
        for s, b in enumerate(order):
            j = b.gen_joint
            mst = j.master
            if mst is not None and not mst.is_ground:
                if mst.gen_joint is not None:
                    par[s] = pos[mst]
                elif mst.name in lay.body_slices:
                    root[s] = lay.body_slices[mst.name].start
                else:
                    raise _Unsupported(f"{j.label()}: its master {mst.name!r} is not in the system")
            for c in j.coordinates:
                if c not in index:
                    raise _Unsupported(f"{j.label()}: coordinate {c} is not a coordinate of the system")
                gcols.append(index[c])
            goff[s + 1] = len(gcols)
            args, exprs, nm, _ = _joint_exprs(space, b, lay.p_symbols, conv)
            nqm[s] = nm
            # equal expressions hash equal (a printed form or a tree hash may depend on the
            # order SymEngine keeps the terms of a sum in)
            key = (tuple(map(str, args)), tuple(exprs))
            if key not in keys:
                keys[key] = len(kernels)
                kernels.append(_compile(args, exprs, system.backend))
            kid[s] = keys[key]
        self._tree = (kid, par, root, nqm, goff, np.array(gcols, dtype=np.int64), nq)
        self._kernels = kernels
        self.nslaves, self.nkernels = S, len(kernels)

        # the rest in one kernel: absolute bodies, loads, constraints; slave poses as arguments
        slave_q = {b: [0] * nq for b in order}
        Q = generalized_forces(model, loads, lay, slaves=slave_q)
        qd_of = dict(zip(lay.q_symbols, lay.qd_symbols))
        entries: dict = {}
        zero = conv(0)
        Qv = [zero] * lay.n
        for b in bodies:
            if b.gen_joint is not None:
                continue
            q = list(b.q)
            _, Mb, Qvb = body_terms(space, tuple(q), tuple(qd_of[s] for s in q), *_mass_key(space, b))
            for i, si in enumerate(q):
                for jj in range(len(q)):
                    if Mb[i][jj] != 0:
                        entries[(index[si], index[q[jj]])] = (
                            entries.get((index[si], index[q[jj]]), zero) + conv(Mb[i][jj]))
                Qv[index[si]] += conv(Qvb[i])
        pose_syms = [s for b in order for s in b.q]
        vel_syms = [velocity_symbol(s.name) for s in pose_syms]
        Qp = [e for b in order for e in slave_q[b]]
        lamset, qddset = set(self.lam), set(lay.qdd_symbols)
        slave_acc = {acceleration_symbol(s.name) for s in pose_syms}
        known = set(self.args()) | set(pose_syms) | set(vel_syms)
        # loads -c qdd_j with constant c on coordinates (a rotor's armature, decision 0048):
        # moved into the mass matrix, M_ij += c, as constant entries of the main kernel's mass
        # entries, so every path that assembles M (the Python one, the compiled stepper's,
        # the compiled multiplier solves') carries them; the articulated-body recursion adds
        # those within one joint's coordinates to that joint's D (decision 0057)
        self._M_added: dict = {}
        qdd_index = {a: j for j, a in enumerate(lay.qdd_symbols)}
        for i, e in enumerate(Q):
            e = sp.sympify(e)
            acc = e.free_symbols & qddset
            if not acc:
                continue
            coeffs = {a: sp.diff(e, a) for a in acc}
            if not all(c.is_number for c in coeffs.values()):
                continue                    # not constant: refused below
            for a, c in coeffs.items():
                key = (i, qdd_index[a])
                self._M_added[key] = self._M_added.get(key, 0.0) - float(c)
                entries[key] = entries.get(key, zero) + conv(-c)
            Q[i] = sp.expand(e - sum(c * a for a, c in coeffs.items()))
        self._M_rows = np.array([k[0] for k in entries], dtype=np.int64)
        self._M_cols = np.array([k[1] for k in entries], dtype=np.int64)
        for e in [*Q, *Qp]:
            fs = sp.sympify(e).free_symbols
            if fs & lamset or fs & qddset or fs & slave_acc:
                raise _Unsupported("a load depends on multipliers (friction) or accelerations")
            if fs - known:
                raise _Unsupported(f"a load uses unknown symbol(s) {sorted(map(str, fs - known))}")
        self.depends_on_lambda = self.depends_on_qdd = False
        self.linear_in_qdd = True
        qdset = set(lay.qd_symbols) | set(vel_syms)
        self.depends_on_qd = any(sp.sympify(e).free_symbols & qdset for e in [*Q, *Qp])
        jac = system.kinematic_exprs("jac", for_compile=True)
        gamma = system.kinematic_exprs("gamma", for_compile=True)
        exprs = [*entries.values(), *jac, *Q, *Qv, *gamma, *Qp]
        if conv is not sp.sympify:
            exprs = [conv(e) for e in exprs]
        else:
            from ._derive import to_sympy_list

            exprs = to_sympy_list(exprs)
        from ._backends import compile_exprs

        self._main = compile_exprs([*self.args(), *pose_syms, *vel_syms], exprs, system.backend,
                                   cse=system.cse, first_use=True)
        self._sizes = (len(entries), len(jac), lay.n, len(gamma), S * nq)
        import threading

        self._local = threading.local()      # work arrays per thread (sweeps may use threads)
        self._numba = None

    def __getstate__(self):
        """Without the per-thread work arrays and the kernels' C entry points (ctypes): a
        pickled free system (a sweep's payload) rebuilds them on first use."""
        state = dict(self.__dict__)
        state["_local"] = state["_numba"] = None
        # (the kernels leave out their C entry points themselves: _SymengineCompiled)
        return state

    def __setstate__(self, state):
        import threading

        self.__dict__.update(state)
        self._local = threading.local()

    # -- the symbolic twin -------------------------------------------------------------------
    def __getattr__(self, name):
        if name.startswith("__") or name in ("_twin", "_twin_args"):
            raise AttributeError(name)
        twin = self.__dict__.get("_twin")
        if twin is None:
            from ._dynamics import Dynamics

            twin = self.__dict__["_twin"] = Dynamics(self.system, *self._twin_args)
        return getattr(twin, name)

    def args(self) -> list:
        from ._dynamics import Dynamics

        return Dynamics.args(self)

    def pack(self, t, q, qd, lam, p, qdd=None):
        from ._dynamics import Dynamics

        return Dynamics.pack(self, t, q, qd, lam, p, qdd)

    def dQ_dlam(self, t, q, qd, lam, p, qdd=None) -> np.ndarray:
        return np.zeros((self.system.n, self.system.m))

    def dQ_dqdd(self, t, q, qd, lam, p, qdd=None) -> np.ndarray:
        return np.zeros((self.system.n, self.system.n))

    # -- numbers -----------------------------------------------------------------------------
    def _engine(self):
        """The Numba forward pass and assembly (the ``fast`` extra; off with
        ``MECHSYS_JIT=0``), or False for the plain-Python path (the same operations)."""
        if self._numba is None:
            self._numba = False
            from ..solvers import _jit_runtime

            if _jit_runtime.mode() != "off" and _jit_runtime.available():
                ptrs = [getattr(k, "c_function", lambda: None)() for k in self._kernels]
                if all(p is not None and p[2] == 0 for p in ptrs):
                    from ..solvers import _jit_tree as jit

                    self._numba = (jit, np.array([[p[0], p[1]] for p in ptrs], dtype=np.int64))
        return self._numba

    def plain_python(self):
        """A context in which this thread's evaluations take the plain-Python recursion
        (the same operations as the compiled one, see :meth:`_engine`): for a few
        evaluations, where loading Numba and its cached code (about 0.7 s CPU once per
        process; compiling it, several seconds once per installation) would not be
        recovered (the robot entry points on few points, decision 0057)."""
        from contextlib import contextmanager

        @contextmanager
        def ctx():
            before = getattr(self._local, "plain", False)
            self._local.plain = True
            try:
                yield
            finally:
                self._local.plain = before

        return ctx()

    def _workspace(self):
        kid, par, root, nqm, goff, gcols, nq = self._tree
        S = len(kid)
        kmax = max(1, int(np.diff(goff).max(initial=1)))
        width = max(nq, kmax)
        nin = 1 + 2 * nq + 2 * kmax + len(self.system.p_values)
        nout = nq * (4 + nq + kmax + nq)
        z = np.zeros
        return dict(P=z((S, nq)), Pd=z((S, nq)), FP=z((S, nq, nq)), Fg=z((S, nq, kmax)), H=z((S, nq)),
                    HL=z((S, nq)), Mb=z((S, nq, nq)), Qvb=z((S, nq)), C=z((S, nq, nq)), BQ=z((S, nq)),
                    BV=z((S, nq)), X=z((nq, width)), Y=z((nq, width)), x=z(nin), out=z(nout),
                    U=z((S, nq, kmax)), L=z((S, kmax, kmax)), Z=z((kmax, nq + 1)), W=z((nq, nq + 1)))

    def _forward(self, t, q, qd, lam, p):
        """Joint kernels (masters first), then the kernel of the rest: ``(out, eng, w)``."""
        kid, par, root, nqm, goff, gcols, nq = self._tree
        w = getattr(self._local, "work", None)
        if w is None:
            w = self._local.work = self._workspace()
        n = self.system.n
        q = np.asarray(q, dtype=float)
        qd = np.asarray(qd, dtype=float)
        p = np.asarray(p, dtype=float)
        if getattr(self._local, "plain", False):
            eng = False                      # (plain_python(): a few evaluations)
        else:
            eng = self._numba if self._numba is not None else self._engine()
        P, Pd = w["P"], w["Pd"]
        if eng:
            eng[0].forward(eng[1], kid, par, root, nqm, goff, gcols, nq, float(t), q, qd, p, w["x"],
                           w["out"], P, Pd, w["FP"], w["Fg"], w["H"], w["HL"], w["Mb"], w["Qvb"])
        else:
            _forward_py(self._kernels, kid, par, root, nqm, goff, gcols, nq, float(t), q, qd, p,
                        P, Pd, w["FP"], w["Fg"], w["H"], w["HL"], w["Mb"], w["Qvb"])
        out = self._main(np.concatenate(((t,), q, qd, lam, p, np.zeros(n), P.ravel(), Pd.ravel())))
        return out, eng, w

    def evaluate(self, t, q, qd, lam, p, K=None):
        """``(M (n, n), Q (n,), Qv (n,), Phi_q values, gamma)`` at one state (composite
        bodies); with ``K`` (zeros, at least ``(n, n)``) the mass matrix is written into
        ``K[:n, :n]``, which is returned as ``M``."""
        kid, par, root, nqm, goff, gcols, nq = self._tree
        out, eng, w = self._forward(t, q, qd, lam, p)
        n = self.system.n
        kM, kJ, _, kg, _ = self._sizes
        M = np.zeros((n, n)) if K is None else K[:n, :n]
        M[self._M_rows, self._M_cols] = out[:kM]
        o = kM + kJ
        Q = out[o:o + n]
        Qv = out[o + n:o + 2 * n]
        o += 2 * n
        Qp = out[o + kg:].reshape(len(kid), nq)
        (eng[0].assemble if eng else _assemble)(
            par, root, nqm, goff, gcols, nq, w["FP"], w["Fg"], w["H"], w["Mb"], w["Qvb"], Qp, w["C"],
            w["BQ"], w["BV"], w["X"], w["Y"], M, Q, Qv)
        return M, Q, Qv, out[kM:kM + kJ], out[o:o + kg]

    @property
    def tree_only(self) -> bool:
        """Only slaves on ground and their coordinates, no constraint equation: the free
        accelerations come from the O(N) articulated-body recursion (:meth:`accelerations`)."""
        kid, par, root, nqm, goff, gcols, nq = self._tree
        # inertia added on coordinates (an armature) joins the recursion when each entry
        # couples coordinates of one joint (it adds to that joint's D); across joints it
        # would couple two joints' D, which the recursion cannot hold: the full system then
        joint = np.empty(self.system.n, dtype=np.int64)
        for s in range(len(kid)):
            joint[gcols[goff[s]:goff[s + 1]]] = s
        return (self.system.m == 0 and len(gcols) == self.system.n and bool((root < 0).all())
                and all(joint[i] == joint[j] for i, j in self.__dict__.get("_M_added", {})))

    def accelerations(self, t, q, qd, p):
        """Free accelerations ``qdd`` (n,) by the articulated-body recursion
        (:func:`_articulated`) when :attr:`tree_only`, else None; None too when a joint's
        motion carries no mass (the full system then gives the diagnosis)."""
        if not self.tree_only:
            return None
        kid, par, root, nqm, goff, gcols, nq = self._tree
        out, eng, w = self._forward(t, q, qd, np.zeros(0), p)
        n = self.system.n
        kM, kJ, _, kg, _ = self._sizes
        o = kM + kJ
        Qd = out[o:o + n] + out[o + n:o + 2 * n]
        Qp = out[o + 2 * n + kg:].reshape(len(kid), nq)
        qdd = np.empty(n)
        bad = (eng[0].articulated if eng else _articulated)(
            par, nqm, goff, gcols, nq, w["FP"], w["Fg"], w["HL"], w["Mb"], w["Qvb"], Qp, Qd,
            out[:kM], self._M_rows, self._M_cols, w["C"], w["BQ"], w["U"], w["L"], w["Z"], w["W"],
            qdd, 1e-13)
        return qdd if bad < 0 else None

    def terms(self, t, q, qd, lam, p, qdd=None):
        """``(M (n, n) dense, Q (n,), Qv (n,))`` at one state, by the recursion."""
        M, Q, Qv, _, _ = self.evaluate(t, q, qd, lam, p)
        return M, Q, Qv

    def free_kernel(self, sparse: bool = False):
        """The augmented system of free motion (``FreeKernel``'s contract), by the recursion."""
        if self._kernel is None or self._kernel.sparse != sparse:
            self._kernel = _RecursiveFreeKernel(self, sparse)
        return self._kernel


class _RecursiveFreeKernel:
    """``(K, rhs)`` of free motion, ``K = [[M, Phi_q^T], [Phi_q, 0]]``, ``rhs = [Q + Qv;
    gamma]``, with ``M``, ``Q``, ``Qv`` from :meth:`RecursiveDynamics.evaluate`."""

    def __init__(self, dyn, sparse: bool):
        s = dyn.system
        self.dyn, self.sparse = dyn, sparse
        self.n, self.m = s.n, s.m
        self.N = s.n + s.m
        self._rows, self._cols = s.jac_rows, s.jac_cols
        #: ``(t, q, qd, p) -> qdd`` or None: the O(N) path of a pure tree (``solvers/_free.py``)
        self.accelerations = dyn.accelerations if dyn.tree_only else None

    def __call__(self, t, q, qd, lam, p):
        # dense even above the sparse threshold: the mass matrix of a chain in joint
        # coordinates is full, and LAPACK beats a sparse LU on it (the solvers accept both)
        n = self.n
        K = np.zeros((self.N, self.N))
        _, Q, Qv, jv, gamma = self.dyn.evaluate(t, q, qd, lam, p, K)
        K[self._cols, n + self._rows] = jv
        K[n + self._rows, self._cols] = jv
        return K, np.concatenate((Q + Qv, gamma))
