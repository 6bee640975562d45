r"""The compiled system: the model's equations in symbolic form and as numeric functions.

Built once per model version by :meth:`Model.compile`; immutable afterwards.

Symbolic content (``n`` coordinates ``q``, ``m`` equations):

* :math:`\Phi(q, t, p)`, ``(m,)``: the constraint equations;
* :math:`\Phi_q`, ``(m, n)``, sparse: ``rows``, ``cols``, ``exprs`` ``(nnz,)``;
* :math:`\Phi_t`, ``(m,)``;
* :math:`\gamma`, ``(m,)``: :math:`\gamma = -\left( (\Phi_q \dot q)_q \dot q + 2 \Phi_{qt} \dot q
  + \Phi_{tt} \right)`.

``gamma`` is derived per equation as :math:`-(v_q \dot q + v_t)` with :math:`v = \Phi_q \dot q + \Phi_t`,
which
is the same expression. Numeric functions take one flat argument vector
``x = [t, q (n), qd (n), p (np)]``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sps
import sympy as sp

from .._errors import ModelError
from .._symbols import T, acceleration_symbol, velocity_symbol
from ..solvers._linalg import FixedPattern
from ._backends import Compiled, compile_exprs, default_backend, gc_paused
from ._dynamics import Dynamics, multiplier_symbols
from ._options import Backend


@dataclass(frozen=True)
class Layout:
    """Index layout of the coordinates, equations and parameters.

    q_symbols, qd_symbols, qdd_symbols : tuples (n,) of SymPy symbols
    q_names   : tuple (n,) of ``"body.coord"`` or variable names
    p_symbols : tuple (np,) of parameter symbols
    eq_owner  : tuple (m,) of the constraint (or ``"normalization of body"`` label) per row
    eq_index  : tuple (m,) of the row's index inside its constraint
    """

    q_symbols: tuple
    qd_symbols: tuple
    qdd_symbols: tuple
    q_names: tuple
    p_symbols: tuple
    eq_owner: tuple
    eq_index: tuple
    body_slices: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.q_symbols)

    @property
    def m(self) -> int:
        return len(self.eq_owner)

    def index(self, key) -> int:
        """Index of a coordinate given by symbol, symbol name or ``"body.coord"`` name."""
        if isinstance(key, sp.Symbol):
            for lst in (self.q_symbols,):
                if key in lst:
                    return lst.index(key)
            key = key.name
        if not isinstance(key, str):
            from .._errors import ModelError

            raise ModelError(f"a coordinate is named by a string (\"crank.th\", \"th2\") or a "
                             f"symbol, got {key!r}; coordinates are {list(self.q_names)}")
        names = [s.name for s in self.q_symbols]
        if key in names:
            return names.index(key)
        if key in self.q_names:
            return self.q_names.index(key)
        from .._errors import ModelError

        raise ModelError(f"no coordinate {key!r}; coordinates are {list(self.q_names)}")

    def row_label(self, i: int) -> str:
        owner = self.eq_owner[i]
        lab = owner.label() if hasattr(owner, "label") else str(owner)
        return f"{lab}, equation {self.eq_index[i] + 1}"

    def owners_of(self, rows) -> list:
        out = []
        for i in rows:
            o = self.eq_owner[i]
            if o not in out:
                out.append(o)
        return out

    def args(self) -> list:
        return [T, *self.q_symbols, *self.qd_symbols, *self.p_symbols]


class System:
    """Compiled, immutable system of a model.

    Attributes: ``layout`` (:class:`Layout`), ``phi``, ``jac_rows``/``jac_cols``/``jac_exprs``,
    ``phi_t``, ``gamma`` (SymPy), ``p_values`` (np,) and the compiled functions ``f_position``
    -> ``[Phi (m), Phi_q values (nnz)]``, ``f_velocity`` -> ``[Phi_q values, Phi_t]``,
    ``f_gamma`` -> ``gamma``; all of ``x = [t, q, qd, p]``.
    """

    @gc_paused()
    def __init__(self, space, layout: Layout, phi, p_values, guess, backend: str | None = None,
                 version: int = 0, model=None, loads=()):
        self.space = space
        self.layout = layout
        self.version = version
        opts = getattr(model, "_compile_opts", None)   # m.set_compile_options (12.3)
        self.backend = Backend(backend or default_backend(), opts.opt_level if opts else 3)
        self.p_values = np.asarray(p_values, dtype=float)
        self.guess = np.asarray(guess, dtype=float)
        q, qd = layout.q_symbols, layout.qd_symbols
        self.phi = list(phi)
        from ._derive import derive_kinematics

        rows, cols, jac, phi_t, gamma, native = derive_kinematics(self.phi, q, qd, T)
        self.jac_rows = np.array(rows, dtype=int)
        self.jac_cols = np.array(cols, dtype=int)
        self._native = native
        self._sympy = {} if native is not None else {"jac": jac, "phi_t": phi_t, "gamma": gamma}
        self._kernels: dict = {}
        self._eval_cache: dict = {}
        self._model = model
        self._loads = tuple(loads)
        self._bodies = tuple(model.bodies[1:]) if model is not None else ()
        self._dynamics = None

        self.lam_symbols = multiplier_symbols(layout)
        #: whether the model has Gen joints (slave bodies), known without their nested poses
        self.has_gen = model is not None and any(
            getattr(b, "gen_joint", None) is not None for b in self._bodies)
        self._gen_subs = None if self.has_gen else {}
        self._model_version = getattr(model, "_version", None)
        cache = getattr(model, "_gen_cache", None)
        if self.has_gen and cache is not None and cache[0] == self._model_version:
            # derived already (the model's equations used them): kept as of this version
            self._gen_subs = model._gen_substitution()
        #: compile with common subexpressions (nested slave poses share most of theirs)
        self.cse = self.has_gen if opts is None or opts.cse is None else opts.cse

    @property
    def gen_subs(self) -> dict:
        """Slave-body symbol -> expression in this layout's coordinates (Gen joints), derived
        on first use: the recursive dynamics of a tree (an imported robot's first inverse
        dynamics) never needs the nested poses, which take seconds for a deep chain
        (decision 0057)."""
        if self._gen_subs is None:
            if getattr(self._model, "_version", None) != self._model_version:
                raise ModelError("this compiled system belongs to an earlier state of its model "
                                 "(bodies, constraints or loads changed since); compile or solve "
                                 "again")
            self._gen_subs = self._model._gen_substitution()
        return self._gen_subs

    def kinematic_exprs(self, key: str, for_compile: bool = False) -> list:
        """``"jac"`` (nonzero Jacobian entries), ``"phi_t"`` or ``"gamma"``: SymPy lists (made
        on first use), or, ``for_compile`` with the SymEngine backend, SymEngine lists."""
        if self._native is not None and for_compile and self.backend == "symengine":
            return self._native[key]
        if key not in self._sympy:
            from ._derive import to_sympy_list

            self._sympy[key] = to_sympy_list(self._native[key])
        return self._sympy[key]

    def _kernel(self, name: str, keys: tuple) -> Compiled:
        """Compile one kinematic kernel on first use (``m.dof()`` needs only the Jacobian, a
        position-only sweep no ``gamma``): the LLVM compile is most of a large model's cost."""
        k = self._kernels.get(name)
        if k is None:
            parts, sections = [], []
            for key in keys:
                if key == "phi":
                    native = self._native is not None and self.backend == "symengine"
                    block = self._native["phi"] if native else self.phi
                else:
                    block = self.kinematic_exprs(key, for_compile=True)
                parts += block
                sections.append(len(block))
            # (the blocks as sections: the Jacobian of the position and velocity kernels is
            # then compiled once when they are compiled in parts, decision 0080)
            k = self._kernels[name] = compile_exprs(self.layout.args(), parts, self.backend,
                                                    cse=self.cse, sections=sections)
        return k

    @property
    def branch_guard(self):
        """The :class:`~mechsys.compile._branches.BranchGuard` of the angle equations that
        also hold half a turn off (None when there are none): the solvers test their roots
        with it (decision 0033). Built on first use."""
        if not hasattr(self, "_branch_guard"):
            from ._branches import make_guard

            self._branch_guard = make_guard(self)
        return self._branch_guard

    @property
    def length_hint(self) -> float:
        """The largest numeric local coordinate of the bodies' points and centroids (0 when
        none): a length of the model's geometry, for the unit-free scaling of the solvers when
        the constraint equations show no lever arm (:class:`mechsys.solvers.Scaling`)."""
        if not hasattr(self, "_length_hint"):
            big = 0.0
            for b in self._bodies:
                for coords in [*b.points.values(), b.centroid]:
                    for c in coords:
                        if getattr(c, "is_number", False) and c.is_real:
                            big = max(big, abs(float(c)))
            self._length_hint = big
        return self._length_hint

    @property
    def f_position(self) -> Compiled:
        """``x -> [Phi (m), Phi_q values (nnz)]``."""
        return self._kernel("position", ("phi", "jac"))

    @property
    def f_velocity(self) -> Compiled:
        """``x -> [Phi_q values (nnz), Phi_t (m)]``."""
        return self._kernel("velocity", ("jac", "phi_t"))

    @property
    def f_gamma(self) -> Compiled:
        """``x -> gamma (m)``."""
        return self._kernel("gamma", ("gamma",))

    @property
    def jac_exprs(self) -> list:
        """Nonzero entries of ``Phi_q`` (SymPy), at ``(jac_rows, jac_cols)``."""
        return self.kinematic_exprs("jac")

    @property
    def phi_t(self) -> list:
        return self.kinematic_exprs("phi_t")

    @property
    def gamma(self) -> list:
        return self.kinematic_exprs("gamma")

    @property
    def dynamics(self):
        """Mass matrix, applied and velocity-dependent forces (derived and compiled on first
        use: kinematics-only work never pays for them)."""
        if self._dynamics is None:
            if self.has_gen:  # Gen joints: symbolic or recursive (compile/_generalized.py)
                from ._generalized import make_dynamics

                self._dynamics = make_dynamics(self, self._model, self._bodies, self._loads)
            else:
                self._dynamics = Dynamics(self, self._model, self._bodies, self._loads)
        return self._dynamics

    # -- numeric helpers (x = [t, q, qd, p]) ------------------------------------------
    @property
    def n(self) -> int:
        return self.layout.n

    @property
    def m(self) -> int:
        return self.layout.m

    @property
    def nnz(self) -> int:
        return len(self.jac_rows)

    def pack(self, t: float, q, qd=None, p=None) -> np.ndarray:
        n = self.n
        x = np.empty(1 + 2 * n + len(self.p_values))
        x[0] = t
        x[1 : 1 + n] = q
        x[1 + n : 1 + 2 * n] = 0.0 if qd is None else qd
        x[1 + 2 * n :] = self.p_values if p is None else p
        return x

    def assemble(self, vals: np.ndarray, sparse: bool = False):
        """Jacobian ``(m, n)`` from its nonzero values (dense, or CSC when ``sparse``).

        Sparse: the CSC structure of the pattern is made once (``_csc_structure``); each call
        sums the values into it in their own order (as the dense path) and builds the matrix
        from ``(data, indices, indptr)``: about 20 µs instead of 100 µs for SciPy's
        conversion from coordinates, called several times a point by large sweeps."""
        if sparse:
            inv, indices, indptr = self._csc_structure()
            data = np.bincount(inv, weights=vals, minlength=len(indices))
            J = sps.csc_matrix((data, indices, indptr), shape=(self.m, self.n), copy=False)
            # a square Jacobian is factorised through its pattern, analysed once
            # (``_linalg.factor``)
            J.mechsys_pattern = self.jacobian_pattern()
            return J
        J = np.zeros((self.m, self.n))
        np.add.at(J, (self.jac_rows, self.jac_cols), vals)
        return J

    def jacobian_pattern(self):
        """The :class:`~mechsys.solvers._linalg.FixedPattern` of the square Jacobian's CSC
        structure (None when ``m != n``), made once: its factorisations reuse the ordering
        found here: a sparse LU in a minimum-degree ordering (compiled when Numba is
        installed, else SuperLU's with the same ordering and pivoting). Shared with the
        compiled sweep and multiplier loops (``_jit_sweep.run``), which call the same LU."""
        if self.m != self.n:
            return None
        got = self.__dict__.get("_jac_pattern")
        if got is None:
            _, indices, indptr = self._csc_structure()
            got = self.__dict__["_jac_pattern"] = FixedPattern(indptr, indices, self.n,
                                                                 match_rows=True,
                                                                 sparse=True)
        return got

    def _csc_structure(self):
        """``(inv, indices, indptr)``: the position in CSC order of each nonzero value (equal
        positions for duplicates), and the CSC row indices and column pointers."""
        got = self.__dict__.get("_csc_struct")
        if got is None:
            r = np.asarray(self.jac_rows, dtype=np.int64)
            c = np.asarray(self.jac_cols, dtype=np.int64)
            uniq, inv = np.unique(c * max(self.m, 1) + r, return_inverse=True)
            indices = (uniq % max(self.m, 1)).astype(np.int32)
            indptr = np.searchsorted(uniq // max(self.m, 1), np.arange(self.n + 1)).astype(np.int32)
            got = self.__dict__["_csc_struct"] = (inv.ravel(), indices, indptr)
        return got

    def residual(self, t: float, q, p=None) -> np.ndarray:
        return self.f_position(self.pack(t, q, None, p))[: self.m]

    def jacobian_once(self, t: float, q, p=None) -> np.ndarray:
        """Dense ``Phi_q`` for a one-off evaluation (``m.dof()``): uses the compiled position
        kernel when it exists, else a quickly compiled, unoptimised Jacobian-only kernel."""
        if "position" in self._kernels:
            return self.jacobian(t, q, p)
        if "pos_once" in self._kernels:
            return self.position_once(t, q, p)[1]
        k = self._kernels.get("jac_once")
        if k is None:
            k = self._kernels["jac_once"] = compile_exprs(
                self.layout.args(), self.kinematic_exprs("jac", for_compile=True), self.backend,
                once=True, cse=self.cse)
        return self.assemble(k(self.pack(t, q, None, p)))

    def position_once(self, t: float, q, p=None):
        """``(Phi, Phi_q)`` (dense) for a few evaluations (``m.dof()``'s assembly of a guess):
        the compiled position kernel when it exists, else a quickly compiled, unoptimised one
        (as :meth:`jacobian_once`)."""
        if "position" in self._kernels:
            return self.residual_and_jacobian(t, q, p)
        k = self._kernels.get("pos_once")
        if k is None:
            native = self._native is not None and self.backend == "symengine"
            parts = list(self._native["phi"] if native else self.phi)
            parts += self.kinematic_exprs("jac", for_compile=True)
            k = self._kernels["pos_once"] = compile_exprs(self.layout.args(), parts, self.backend,
                                                          once=True, cse=self.cse)
        out = k(self.pack(t, q, None, p))
        return out[: self.m], self.assemble(out[self.m:])

    def jacobian(self, t: float, q, p=None, sparse: bool = False):
        vals = self.f_position(self.pack(t, q, None, p))[self.m :]
        return self.assemble(vals, sparse)

    def residual_and_jacobian(self, t, q, p=None, sparse=False):
        out = self.f_position(self.pack(t, q, None, p))
        return out[: self.m], self.assemble(out[self.m :], sparse)

    def velocity_rhs(self, t, q, p=None, sparse=False):
        """``(Phi_q, -Phi_t)`` at ``(t, q)``."""
        out = self.f_velocity(self.pack(t, q, None, p))
        return self.assemble(out[: self.nnz], sparse), -out[self.nnz :]

    def gamma_values(self, t, q, qd, p=None) -> np.ndarray:
        return self.f_gamma(self.pack(t, q, qd, p))

    # -- evaluating arbitrary expressions ---------------------------------------------
    def compile_expression(self, exprs) -> Compiled:
        r"""Compile any expressions of :math:`T, q, \dot q, \ddot q, \lambda, p` (cached) as a function of
        :math:`[t, q, \dot q, \ddot q, \lambda, p]`."""
        key = tuple(sp.sympify(e) for e in exprs)
        f = self._eval_cache.get(key)
        if f is None:
            lay = self.layout
            args = [T, *lay.q_symbols, *lay.qd_symbols, *lay.qdd_symbols, *self.lam_symbols,
                    *lay.p_symbols]
            if self.gen_subs:  # slave-body symbols: their values first (Gen joints)
                from ._generalized import compile_with_slaves

                f = self._eval_cache[key] = compile_with_slaves(self, args, key)
                return f
            allowed = set(args)
            for e in key:
                extra = e.free_symbols - allowed
                if extra:
                    from .._errors import ModelError

                    raise ModelError(
                        f"expression {e} has symbols {sorted(map(str, extra))} that are not "
                        "coordinates, velocities, accelerations, multipliers, parameters or T "
                        "of this model"
                    )
            f = compile_exprs(args, list(key), self.backend, cse=self.cse)
            self._eval_cache[key] = f
        return f


def make_layout(bodies, variables, parameters, eq_owner, eq_index) -> Layout:
    q, names, slices = [], [], {}
    for b in bodies:
        if getattr(b, "gen_joint", None) is not None:  # a slave: its pose is substituted
            continue
        start = len(q)
        q.extend(b.q)
        names.extend(f"{b.name}.{c}" for c in b.space.coordinate_names)
        slices[b.name] = slice(start, len(q))
    for v in variables:
        q.append(v.symbol)
        names.append(v.symbol.name)
    qd = tuple(velocity_symbol(s.name) for s in q)
    qdd = tuple(acceleration_symbol(s.name) for s in q)
    return Layout(
        q_symbols=tuple(q),
        qd_symbols=qd,
        qdd_symbols=qdd,
        q_names=tuple(names),
        p_symbols=tuple(parameters),
        eq_owner=tuple(eq_owner),
        eq_index=tuple(eq_index),
        body_slices=slices,
    )
