r"""Linearisation of a free system to state space (``free.linearize(...)``), about an
equilibrium or a steady motion.

The free motion (constraints ``Phi`` kept, ``lambda`` their multipliers, ``u`` the inputs)

.. math::  R = M(q)\,\ddot q + \Phi_q^T\lambda - Q(t, q, \dot q, u) - Q_v(q, \dot q) = 0,
           \qquad \Phi(q, t) = 0

is written in ``f = n - m`` coordinates ``y = h(q)`` (coordinate names or expressions the
user chooses, or independent coordinates picked by column-pivoted QR of the unit-free
``Phi_q``), which with the constraints form a chart of the configuration manifold:
:math:`K = \begin{bmatrix} \Phi_q \\ h_q \end{bmatrix}` is nonsingular. A perturbation ``(dy, dyd, du)`` of
the reference state
changes the full coordinates by

.. math::  \delta q = P\,\delta y, \quad
           \delta\dot q = P\,\delta\dot y + W\delta y, \quad
           P = K^{-1}\begin{bmatrix}0\\ I\end{bmatrix}, \quad
           W = -K^{-1}\begin{bmatrix}\tfrac12 c_{\dot q}\\ \dot y_q\end{bmatrix} P

(the velocity constraint :math:`\Phi_q \dot q + \Phi_t = 0` and :math:`\dot y = h_q \dot q` varied; its
derivative
:math:`d(\Phi_q \dot q + \Phi_t)/dq` is half the velocity derivative ``c_qd`` of the acceleration
constraint :math:`c = \Phi_q \ddot q - \gamma`). The accelerations and multipliers change by

.. math::  \begin{bmatrix}R_{\ddot q} & \Phi_q^T\\ \Phi_q & 0\end{bmatrix}
           \begin{bmatrix}\delta\ddot q\\ \delta\lambda\end{bmatrix}
           = -\begin{bmatrix}R_q\,\delta q + R_{\dot q}\,\delta\dot q + R_u\,\delta u\\
                              c_q\,\delta q + c_{\dot q}\,\delta\dot q\end{bmatrix}

(``R_q`` includes the geometric stiffness :math:`d(\Phi_q^T \lambda)/dq` of the reference
multipliers), and the chosen coordinates' accelerations
:math:`\ddot y = h_q \ddot q + (h_q \dot q)_q \dot q` by :math:`\delta \ddot y = \ddot y_q dq + \ddot
y_{\dot q} d\dot q + h_q d\ddot q`. With the
state ``x = (dy, dyd)``:

.. math::  \dot x = A x + B u, \quad y_{out} = C x + D u, \qquad
           A = \begin{bmatrix}0 & I\\ G_y & G_{\dot y}\end{bmatrix}, \quad
           B = \begin{bmatrix}0\\ G_u\end{bmatrix}

and an output ``o(t, q, qd, qdd, p)`` gives the rows ``o_q dq + o_qd dqd + o_qdd dqdd + o_u du``.
All derivatives are exact (symbolic, compiled once per model and set of inputs).

**Steady motion.** The linear system has constant coefficients when the reference is an
equilibrium or a steady motion in the chosen coordinates: every ``ydd = 0`` and the motion
does not change them, :math:`d(\ddot y)/dt = G_y \dot y = 0` (the coordinates that move are cyclic: the
motion does not depend on them). Both are checked (``tolerance``) and a
:class:`~mechsys.NotSteadyError` names the coordinate at fault. ``cyclic=[...]`` drops those
coordinates' positions from the state (their velocities stay), after checking that the
motion does not depend on them.

**Velocity constraints** :math:`\psi = A(q, t)\,\dot q + b = 0` (``k`` rows, rolling;
multipliers :math:`\mu`, decision 0053) enter the velocity chart (decision 0054): only
``f - k`` velocities are independent, the *speeds* :math:`v = S \dot y` (the rates of
``f - k`` chosen coordinates, named with ``speeds=`` or picked by column-pivoted QR of the
unit-free :math:`A P`). With :math:`K_v = \begin{bmatrix} \Phi_q \\ A \\ S h_q
\end{bmatrix}` nonsingular,

.. math::  \delta\dot q = P_v\,\delta v + W_v\,\delta y, \quad
           P_v = K_v^{-1}\begin{bmatrix}0\\ 0\\ I\end{bmatrix}, \quad
           W_v = -K_v^{-1}\begin{bmatrix}\tfrac12 c_{\dot q} P\\ \psi_q P\\
                                           S\,\dot y_q P\end{bmatrix}

and the acceleration solve is bordered by the rows :math:`a = A \ddot q + \rho = 0`
(:math:`\rho = \psi_q \dot q + \psi_t`), the reactions :math:`A^T \mu` adding their change
with :math:`q`:

.. math::  \begin{bmatrix}R_{\ddot q} & \Phi_q^T & A^T\\ \Phi_q & 0 & 0\\ A & 0 & 0
           \end{bmatrix}\begin{bmatrix}\delta\ddot q\\ \delta\lambda\\ \delta\mu
           \end{bmatrix} = -\begin{bmatrix}(R_q + (A^T\mu)_q)\,\delta q + R_{\dot q}\,
           \delta\dot q + R_u\,\delta u\\ c_q\,\delta q + c_{\dot q}\,\delta\dot q\\
           a_q\,\delta q + a_{\dot q}\,\delta\dot q\end{bmatrix}

The state is :math:`x = (\delta y, \delta v)`; the rate of :math:`y` is no longer
:math:`v`, so

.. math::  A = \begin{bmatrix} h_q W_v + \dot y_q P & h_q P_v\\
           S\,\partial\ddot y/\partial y & S\,\partial\ddot y/\partial v\end{bmatrix}

(:math:`h_q W + \dot y_q P = 0` and :math:`h_q P = I` without velocity constraints: the
holonomic ``A``). The chosen coordinates' third derivatives :math:`\ddot y_q` are then a
fourth-order central difference of their exact second derivatives
(``_Chart(difference=True)``).

Example::

    lin = bike.linearize(state, coordinates=coords, cyclic=["x", "y", "yaw", "rear", "front"],
                         speeds=["lean", "steer", "rear"])
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import sympy as sp

from .._errors import MechError, ModelError, NotSteadyError
from .._symbols import T
from ..compile._derive import sparse_derivatives
from ..solvers._free import free_acceleration, project, scaling_at
from ._nonholonomic import nonholonomic_acceleration, project_state

try:  # optional
    import symengine as se
except ImportError:  # pragma: no cover
    se = None


# -- the compiled derivatives of the equations of motion --------------------------------------
class LinearKernel:
    r"""Compiled exact derivatives of a system's equations of motion, shared by
    :func:`linearize` and :func:`~mechsys.analyses._vibration.vibration` (one implementation):

    * ``R_q, R_qd, R_qdd`` of :math:`R = M \ddot q + \Phi_q^T \lambda - Q - Q_v` (``__call__``);
    * ``c_q, c_qd`` of the acceleration constraint :math:`c = \Phi_q \ddot q - \gamma`
      (:meth:`constraints`, compiled on first use);
    * ``R_p`` for chosen parameters (:meth:`parameters`, compiled per set on first use).
    """

    def __init__(self, system):
        dyn = system.dynamics
        lay = system.layout
        if dyn.depends_on_lambda:
            raise ModelError(
                "linearisation: a load depends on the constraint multipliers (joint friction); "
                "Coulomb friction is not smooth at rest, so the motion has no linearisation. "
                "Remove the friction loads (m.remove_load) or replace them by viscous dampers")
        n = system.n
        self.native = se is not None and system.backend == "symengine"
        conv = self._conv = se.sympify if self.native else sp.sympify
        R = [conv(0)] * n
        for r, c, e in zip(dyn.M_rows, dyn.M_cols, dyn.for_compile("M")):
            R[r] = R[r] + conv(e) * conv(lay.qdd_symbols[c])
        for r, c, e in zip(system.jac_rows, system.jac_cols,
                           system.kinematic_exprs("jac", for_compile=self.native)):
            R[c] = R[c] + conv(e) * conv(system.lam_symbols[r])
        QQ = dyn.for_compile("Q+Qv") if self.native else [a + b for a, b in zip(dyn.Q, dyn.Qv)]
        self.R = [a - conv(b) for a, b in zip(R, QQ)]
        self.system, self.dyn, self.n = system, dyn, n
        self.parts, exprs = {}, []
        for key, wrt in (("q", lay.q_symbols), ("v", lay.qd_symbols), ("a", lay.qdd_symbols)):
            self.parts[key] = self._derivatives(self.R, wrt, exprs)
        from ..compile._backends import compile_exprs

        self._compile = lambda ex: compile_exprs(dyn.args(), ex, system.backend)
        self.f = self._compile(exprs)
        self._fc = None
        self._fp: dict = {}

    def _derivatives(self, E, wrt, exprs):
        """Rows and columns of the nonzero ``dE_i / dw_j`` (appended to ``exprs``)."""
        return sparse_derivatives(E, [self._conv(w) for w in wrt], exprs)

    def _dense(self, vals, parts, keys, shape):
        out, k = [], 0
        for key in keys:
            rows, cols = parts[key]
            A = np.zeros(shape(key))
            np.add.at(A, (rows, cols), vals[k : k + len(rows)])
            out.append(A)
            k += len(rows)
        return out

    def __call__(self, t, q, qd, qdd, lam, p):
        """``(R_q, R_qd, R_qdd)`` (n, n) at one state."""
        vals = self.f(self.dyn.pack(t, q, qd, lam, p, qdd))
        return tuple(self._dense(vals, self.parts, ("q", "v", "a"), lambda k: (self.n, self.n)))

    def constraints(self, t, q, qd, qdd, lam, p):
        r"""``(c_q, c_qd)`` (m, n) of :math:`c = \Phi_q \ddot q - \gamma` at one state."""
        system = self.system
        m = system.m
        if m == 0:
            return np.zeros((0, self.n)), np.zeros((0, self.n))
        if self._fc is None:
            lay, conv = system.layout, self._conv
            c = [conv(-g) for g in system.kinematic_exprs("gamma", for_compile=self.native)]
            for r, col, e in zip(system.jac_rows, system.jac_cols,
                                 system.kinematic_exprs("jac", for_compile=self.native)):
                c[r] = c[r] + conv(e) * conv(lay.qdd_symbols[col])
            exprs: list = []
            self._cparts = {key: self._derivatives(c, wrt, exprs) for key, wrt in
                            (("q", lay.q_symbols), ("v", lay.qd_symbols))}
            self._fc = self._compile(exprs)
        vals = self._fc(self.dyn.pack(t, q, qd, lam, p, qdd))
        return tuple(self._dense(vals, self._cparts, ("q", "v"), lambda k: (m, self.n)))

    def parameters(self, index: tuple, t, q, qd, qdd, lam, p):
        """``R_p`` (n, k) for the parameters at ``index`` (positions in ``layout.p_symbols``)."""
        f = self._fp.get(index)
        if f is None:
            syms = [self.system.layout.p_symbols[i] for i in index]
            exprs: list = []
            parts = {"p": self._derivatives(self.R, syms, exprs)}
            f = self._fp[index] = (self._compile(exprs), parts)
        vals = f[0](self.dyn.pack(t, q, qd, lam, p, qdd))
        return self._dense(vals, f[1], ("p",), lambda k: (self.n, len(index)))[0]


def linear_kernel(system) -> LinearKernel:
    """The :class:`LinearKernel` of ``system`` (built once, kept with the system)."""
    k = getattr(system, "_linear_kernel", None)
    if k is None:
        k = system._linear_kernel = LinearKernel(system)
    return k


# -- the result --------------------------------------------------------------------------------
@dataclass(frozen=True)
class LinearSystem:
    r"""A linearised free system :math:`x' = A x + B u`, :math:`y = C x + D u` (see
    :mod:`mechsys.analyses._linearize` for the equations).

    ``A`` (ns, ns), ``B`` (ns, nu), ``C`` (no, ns), ``D`` (no, nu); ``states`` the state
    names (the chosen coordinates, then their velocities ``<name>_d``; a cyclic coordinate
    has its velocity only); ``inputs``, ``outputs`` their names; ``coordinates`` the chosen
    coordinates (names or expressions as given); ``t``, ``q``, ``qd``, ``qdd``, ``p`` the
    reference state; ``basis`` ``P`` (n, f) with :math:`dq = P dy`. ``eigenvalues`` of ``A``
    (ascending by modulus); ``stability`` per eigenvalue ``"stable"`` (``Re s < 0``),
    ``"neutral"`` (:math:`\operatorname{Re} s = 0` on the eigenvalue's own scale) or
    ``"unstable"``; ``stable`` whether none is unstable. ``speeds``: with velocity
    constraints, the chosen coordinates whose rates are the independent velocities (their
    states ``<name>_d``; the other coordinates' rates follow from them), else empty.

    Each eigenvalue is judged on its own scale (as
    :attr:`~mechsys.VibrationModes.stability`): neutral when
    :math:`|\mathrm{Re}\,s| \le 10^{-7} s_{own}` or :math:`\le 10^{-12} \max|s|`, with
    :math:`s_{own} = |w|^T |A| |v| / |w^H v|` (``v``, ``w`` its right and left
    eigenvectors): the change of ``s`` that rounding of ``A``'s entries can cause, which
    the double zero eigenvalue of a rigid-body motion (:math:`w^H v = 0`) makes infinite.

    Example::

        lin = m.free().linearize(eq, inputs=["F"], outputs=["cart.x"])
        lin.eigenvalues, lin.stable, lin.to_scipy()
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple
    inputs: tuple
    outputs: tuple
    coordinates: tuple
    t: float
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    p: np.ndarray
    basis: np.ndarray
    eigenvalues: np.ndarray
    stability: tuple
    stable: bool
    model: object = field(repr=False)
    speeds: tuple = ()

    def to_scipy(self):
        """The system as :class:`scipy.signal.StateSpace` (continuous time)."""
        import scipy.signal as ss

        B = self.B if self.B.shape[1] else np.zeros((self.A.shape[0], 1))
        D = self.D if self.D.shape[1] else np.zeros((self.C.shape[0], 1))
        C = self.C if self.C.shape[0] else np.zeros((1, self.A.shape[0]))
        if not self.C.shape[0]:
            D = np.zeros((1, B.shape[1]))
        return ss.StateSpace(self.A, B, C, D)

    def to_control(self):
        """The system as ``control.StateSpace`` (python-control, an optional package: install
        it with ``pip install control``)."""
        try:
            import control
        except ImportError:
            raise MechError("to_control() needs the optional package python-control "
                            "(pip install control); to_scipy() needs nothing more") from None
        return control.ss(self.A, self.B, self.C, self.D, states=list(self.states),
                          inputs=list(self.inputs), outputs=list(self.outputs))

    def controllability(self) -> np.ndarray:
        """The controllability matrix ``[B, A B, ..., A^(ns-1) B]`` (ns, ns nu)."""
        blocks, X = [], self.B
        for _ in range(self.A.shape[0]):
            blocks.append(X)
            X = self.A @ X
        return np.hstack(blocks) if blocks else np.zeros((0, 0))

    @property
    def controllable(self) -> bool:
        """Whether every state can be reached from the inputs: the controllability matrix has
        full rank, judged on the unit-free form (each state divided by its own size)."""
        Cm = self.controllability()
        ns = self.A.shape[0]
        if ns == 0:
            return True
        if Cm.size == 0:
            return False
        # balance the states so that metres and millimetres judge alike
        d = sla.matrix_balance(self.A, separate=True, permute=False)[1][0]
        Cs = Cm / d[:, None]
        Cs = Cs / np.maximum(np.abs(Cs).max(axis=0), 1e-300)
        sv = np.linalg.svd(Cs, compute_uv=False)
        return bool(sv[ns - 1] > 1e-9 * sv[0]) if len(sv) >= ns else False

    def table(self) -> str:
        """A text table of the eigenvalues and their stability."""
        lines = [f"{'':>4} {'Re s':>14} {'Im s':>14} {'':>9}"]
        for i, (s, c) in enumerate(zip(self.eigenvalues, self.stability)):
            lines.append(f"{i:>4} {s.real:>14.6g} {s.imag:>14.6g} {c:>9}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"<LinearSystem: {len(self.states)} states {list(self.states)}, "
                f"{len(self.inputs)} input(s), {len(self.outputs)} output(s), "
                f"{'stable' if self.stable else 'UNSTABLE'}>\n" + self.table())


# -- the chosen coordinates and the outputs ------------------------------------------------------
def _as_expression(system, e, what: str):
    """``(name, SymPy expression)`` of a coordinate/output given by name (a coordinate,
    ``<name>_d``, ``<name>_dd`` or a parameter), by expression, or as ``(name, expression)``."""
    lay = system.layout
    if isinstance(e, str):
        for suffix, syms in (("_dd", lay.qdd_symbols), ("_d", lay.qd_symbols), ("", lay.q_symbols)):
            if suffix and not e.endswith(suffix):
                continue
            try:
                return e, syms[lay.index(e[: len(e) - len(suffix)])]
            except ModelError:
                continue
        pnames = [s.name for s in lay.p_symbols]
        if e in pnames:
            return e, lay.p_symbols[pnames.index(e)]
        raise ModelError(f"linearize {what}: {e!r} is not a coordinate ('<name>'), a velocity "
                         "('<name>_d'), an acceleration ('<name>_dd') or a parameter of this "
                         f"free system; coordinates are {list(lay.q_names)}")
    if isinstance(e, tuple) and len(e) == 2 and isinstance(e[0], str):
        name, expr = e
    else:
        name, expr = None, e
    try:
        expr = sp.sympify(expr)
    except (sp.SympifyError, TypeError):
        raise ModelError(f"linearize {what}: {e!r} is neither a name nor a SymPy "
                         "expression") from None
    if not isinstance(expr, sp.Expr):
        raise ModelError(f"linearize {what}: {e!r} is not a scalar expression")
    if system.gen_subs:
        expr = expr.xreplace(system.gen_subs)
    if name is None and expr in lay.q_symbols:  # a coordinate's symbol: its "body.x" name
        name = lay.q_names[lay.q_symbols.index(expr)]
    allowed = {*lay.q_symbols, *lay.qd_symbols, *lay.qdd_symbols, *lay.p_symbols, T}
    extra = expr.free_symbols - allowed
    if extra:
        raise ModelError(f"linearize {what}: {expr} uses {sorted(map(str, extra))}, which are "
                         "not coordinates, velocities, accelerations, parameters or T of this "
                         "free system")
    return (name or str(expr)), expr


class _Chart:
    r"""Compiled values and exact derivatives of the chosen coordinates ``y = h(q)``, of
    :math:`\dot y = h_q \dot q` and :math:`\ddot y = h_q \ddot q + (h_q \dot q)_q \dot q`,
    and of the outputs.

    ``difference=True`` (free systems with velocity constraints): ``ydd_q`` is a
    fourth-order central difference of the compiled exact ``ydd`` (steps ``1e-3`` in the
    unit-free coordinates: error about ``1e-11`` relative) and ``ydd_qd = 2 ydq`` exactly
    (``ydd`` is quadratic in ``qd`` through the Hessian of ``h``). The exact third
    derivatives of the angles a vehicle needs (a steer or a wheel angle as ``atan2`` of two
    bodies' Euler parameters) are megabytes of expression: the bicycle's chart took 14 s to
    compile with common subexpressions, and ran out of memory without them."""

    def __init__(self, system, coords: list, outputs: list, inputs: tuple,
                 difference: bool = False):
        lay = system.layout
        self.f, self.no, self.n = len(coords), len(outputs), system.n
        self.difference = difference
        pin = [lay.p_symbols[i] for i in inputs]
        # SymEngine differentiates expressions of Euler parameters (a lean's asin, a
        # heading's atan2) hundreds of times faster than SymPy: a rolling disk's chart
        # took 40 s in SymPy
        # (models with Gen joints compile through their slave substitution, in SymPy)
        native = se is not None and system.backend == "symengine" and not system.gen_subs
        conv = se.sympify if native else sp.sympify
        q, qd, qdd = ([conv(x) for x in syms] for syms in (lay.q_symbols, lay.qd_symbols,
                                                           lay.qdd_symbols))
        zero = conv(0)

        def diff(e, s):
            return e.diff(s) if s in e.free_symbols else zero

        exprs: list = []
        ydds: list = []
        cols: set = set()
        for h in coords:
            h = conv(h)
            hq = [diff(h, s) for s in q]
            cols |= {j for j, a in enumerate(hq) if a != 0}
            yd = sum((a * v for a, v in zip(hq, qd) if a != 0), zero)
            ydq = [diff(yd, s) for s in q]
            ydd = sum((a * v for a, v in zip(ydq, qd) if a != 0), zero) + sum(
                (a * v for a, v in zip(hq, qdd) if a != 0), zero)
            exprs += [h, yd, ydd, *hq, *ydq]
            if difference:
                ydds.append(ydd)
            else:
                exprs += [*[diff(ydd, s) for s in q], *[diff(ydd, s) for s in qd]]
        for o in outputs:
            o = conv(o)
            exprs += [o, *[diff(o, conv(s)) for s in (*q, *qd, *qdd, *pin)]]
        self.cols = sorted(cols)
        if native:
            from ..compile._backends import compile_exprs

            args = [T, *lay.q_symbols, *lay.qd_symbols, *lay.qdd_symbols, *system.lam_symbols,
                    *lay.p_symbols]
            self.fn = compile_exprs(args, exprs, system.backend)
            self.fydd = compile_exprs(args, ydds, system.backend) if difference else None
        else:
            self.fn = system.compile_expression(exprs)
            self.fydd = system.compile_expression(ydds) if difference else None
        self.np = len(pin)

    def __call__(self, t, q, qd, qdd, lam, p, steps=None) -> dict:
        """Values: ``y, yd, ydd`` (f,), ``hq, ydq, yddq, yddv`` (f, n); ``o`` (no,),
        ``oq, ov, oa`` (no, n), ``op`` (no, nu). ``steps`` (n,): the coordinates' unit-free
        units for the differences (default 1)."""
        x = np.concatenate(([t], q, qd, qdd, lam, p))
        v = self.fn(x)
        n, f, no = self.n, self.f, self.no
        per = (3 + 2 * n) if self.difference else (3 + 4 * n)
        Y = v[: f * per].reshape(f, per)
        O = v[f * per :].reshape(no, 1 + 3 * n + self.np)
        out = {"y": Y[:, 0], "yd": Y[:, 1], "ydd": Y[:, 2], "hq": Y[:, 3 : 3 + n],
               "ydq": Y[:, 3 + n : 3 + 2 * n], "o": O[:, 0], "oq": O[:, 1 : 1 + n],
               "ov": O[:, 1 + n : 1 + 2 * n], "oa": O[:, 1 + 2 * n : 1 + 3 * n],
               "op": O[:, 1 + 3 * n :]}
        if not self.difference:
            out["yddq"], out["yddv"] = Y[:, 3 + 2 * n : 3 + 3 * n], Y[:, 3 + 3 * n :]
            return out
        out["yddv"] = 2.0 * out["ydq"]
        D = np.zeros((f, n))
        for j in self.cols:
            h = 1e-3 * (1.0 if steps is None else steps[j])
            vals = []
            for k in (2, 1, -1, -2):
                xk = x.copy()
                xk[1 + j] += k * h
                vals.append(np.asarray(self.fydd(xk), dtype=float))
            D[:, j] = (-vals[0] + 8 * vals[1] - 8 * vals[2] + vals[3]) / (12 * h)
        out["yddq"] = D
        return out


def independent_coordinates(system, t, q, p, scaling) -> list:
    """Indices of ``f = n - m`` independent coordinates at ``q``: the columns column-pivoted QR
    of the unit-free ``Phi_q`` leaves out of its (well-conditioned) ``m`` pivots."""
    n, m = system.n, system.m
    if m == 0:
        return list(range(n))
    J = system.jacobian(t, q, p)
    Js = scaling.scaled(J)
    _, _, piv = sla.qr(Js, mode="economic", pivoting=True)
    return sorted(int(i) for i in piv[m:])


@dataclass(frozen=True)
class _Inputs:
    """The inputs by kind: ``params`` (positions in ``layout.p_symbols``), ``loads`` (load
    objects with a magnitude), ``rows`` (the equation row of each driver); ``kinds`` and
    ``names`` in the user's order, ``where`` each input's position in its kind's list."""

    names: tuple
    kinds: tuple
    where: tuple
    params: tuple
    loads: tuple
    rows: tuple


def _inputs(free, inputs) -> _Inputs:
    """Resolve the input names: a parameter of the loads, a named load with a magnitude
    (``Force``, ``Moment``, ``Load``: the input adds to the magnitude) or a kept constraint
    of one equation (a driver: the input is its equation's second time derivative, the
    driven acceleration). A parameter of the kept constraints moves the configuration
    itself and is refused."""
    system = free.system
    lay = system.layout
    pnames = [s.name for s in lay.p_symbols]
    used = None                 # (the kept constraints' symbols: only for parameter inputs)
    loads = {ld.name: ld for ld in system._loads if getattr(ld, "name", None)}
    names, kinds, where, params, lds, rows = [], [], [], [], [], []
    for u in inputs:
        name = u.name if isinstance(u, sp.Symbol) else u
        if not isinstance(name, str):
            raise ModelError(f"linearize inputs: name each input (a parameter, a named load or "
                             f"a kept driver), got {u!r}")
        if name in names:
            raise ModelError(f"linearize inputs: {name!r} is given twice")
        if name in pnames:
            if used is None:
                used = set()
                for e in system.phi:
                    used |= {s.name for s in sp.sympify(e).free_symbols}
            if name in used:
                raise ModelError(f"linearize inputs: parameter {name!r} appears in the kept "
                                 "constraints, so changing it moves the configuration rather "
                                 "than forcing it; inputs are parameters of the loads")
            kinds.append("parameter")
            where.append(len(params))
            params.append(pnames.index(name))
        elif name in loads:
            ld = loads[name]
            if not hasattr(ld, "magnitude"):
                raise ModelError(f"linearize inputs: load {name!r} ({ld.label()}) has no "
                                 "magnitude to vary (Force, Moment and Load have); make the "
                                 "quantity a parameter (m.parameter) and name the parameter")
            kinds.append("load")
            where.append(len(lds))
            lds.append(ld)
        else:
            row = _driver_row(free, name)
            if row is None:
                raise ModelError(
                    f"linearize inputs: {name!r} is not a parameter {pnames}, a named load "
                    f"{sorted(loads)} or a kept constraint of this free system; declare a "
                    "load magnitude with F = m.parameter('F', 0.0), or name the load "
                    "(m.add_load(load, name=...))")
            kinds.append("driver")
            where.append(len(rows))
            rows.append(row)
        names.append(name)
    return _Inputs(tuple(names), tuple(kinds), tuple(where), tuple(params), tuple(lds),
                   tuple(rows))


def _driver_row(free, name: str):
    """The equation row of the kept one-equation constraint ``name`` (None when no kept
    constraint has that name)."""
    lay = free.system.layout
    try:
        c = free.model.constraint(name)
    except ModelError:
        return None
    rows = [i for i, o in enumerate(lay.eq_owner) if o is c]
    if not rows:
        if any(c is d for d in free.dropped):
            raise ModelError(f"linearize inputs: constraint {name!r} is dropped from this free "
                             "system; a driver input needs the driver kept (m.free(drop=...) "
                             "without it)")
        return None
    if len(rows) != 1:
        raise ModelError(f"linearize inputs: constraint {name!r} has {len(rows)} equations; a "
                         "driver input prescribes one (a RotationLock1, a Distance1, ...): "
                         "drive each motion by a constraint of its own")
    return rows[0]


class _LoadInputs:
    """Compiled ``dQ/du`` (n, k) of loads whose magnitude is increased by ``u``."""

    def __init__(self, system, model, loads):
        import copy

        from ..compile._dynamics import generalized_forces

        u = sp.Symbol("_linearize_input")
        exprs = []
        for ld in loads:
            varied = copy.copy(ld)
            varied.magnitude = ld.magnitude + u
            Q = generalized_forces(model, [varied], system.layout)
            exprs += [sp.diff(sp.sympify(e), u).xreplace({u: 0}) for e in Q]
        self.k, self.n = len(loads), system.n
        self.dyn = system.dynamics
        from ..compile._backends import compile_exprs

        self.f = compile_exprs(self.dyn.args(), exprs, system.backend)

    def __call__(self, t, q, qd, qdd, lam, p) -> np.ndarray:
        v = self.f(self.dyn.pack(t, q, qd, lam, p, qdd))
        return np.asarray(v, dtype=float).reshape(self.k, self.n).T


# -- the linearisation --------------------------------------------------------------------------
def linearize(free, state=None, inputs: Sequence = (), outputs: Sequence = (),
              coordinates: Sequence | None = None, cyclic: Sequence = (),
              t: float | None = None, tolerance: float = 1e-6,
              speeds: Sequence | None = None) -> LinearSystem:
    r"""Linearise ``free`` (a :class:`~mechsys.FreeSystem`) about ``state``, an equilibrium or
    a steady motion, to state space (equations in :mod:`mechsys.analyses._linearize`).

    ``state``: a Solution/State (its last point), a mapping of coordinate, ``<name>_d``
    velocity and parameter values applied to the free system's start (as
    ``initial_condition``), or None (the free system's start); the state is projected on
    the kept constraints, keeping the values given. ``inputs``: names of parameters of the
    loads (``F = m.parameter("F", 0.0)``; the input is the parameter's change), of named
    loads with a magnitude (the input adds to it) or of kept one-equation drivers (the input
    is the driven acceleration; the driver's deviation and rate become states).
    ``outputs``: coordinate names, ``<name>_d``/``<name>_dd`` names or SymPy expressions of
    ``T``, coordinates, velocities, accelerations and parameters (optionally ``(name,
    expression)`` pairs). ``coordinates``: ``f`` coordinate names or expressions of the
    coordinates (independent with the constraints); default the independent coordinates
    chosen by column-pivoted QR. ``cyclic``: chosen coordinates whose positions leave the
    state (the motion must not depend on them). ``t``: the time (default the solution's,
    else 0). ``tolerance``: how far from steady the reference may be. ``speeds`` (free
    systems with velocity constraints only): the ``f - k`` chosen coordinates whose rates
    are the independent velocities (default: chosen by column-pivoted QR of the unit-free
    rows ``A P`` of the velocity constraints in the chosen coordinates' rates); the state
    is then ``(dy, dv)``, the chosen coordinates and the speeds' rates (section *Velocity
    constraints* of :mod:`mechsys.analyses._linearize`).

    .. math::  \dot x = A x + B u, \qquad y = C x + D u

    Example::

        eq = m.free(solution="static").solve()
        lin = m.free().linearize(eq, inputs=["F"], outputs=["cart.x"])
        lin.A, lin.B, lin.eigenvalues, lin.stability, lin.to_scipy()
    """
    from ..results._solution import Solution, State

    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float)) or not (
            0 < tolerance < 1):
        raise ModelError(f"linearize: tolerance must be a number in (0, 1), got {tolerance!r}")
    for what, v in (("inputs", inputs), ("outputs", outputs), ("cyclic", cyclic)):
        if isinstance(v, (str, sp.Basic)) or not isinstance(v, (list, tuple)):
            raise ModelError(f"linearize {what}: give a list, got {v!r}")
    system = free.system
    lay = system.layout
    n, m = system.n, system.m
    # the reference state
    if isinstance(state, (Solution, State)):
        t0 = float(np.atleast_1d(state.t)[-1]) if t is None else float(t)
        q, qd, p, _ = free._start(state)
    elif state is None or isinstance(state, Mapping):
        t0 = 0.0 if t is None else float(t)
        q, qd, p, held = free._start(state)
    else:
        raise ModelError(f"linearize: state must be a Solution, State, mapping or None, got "
                         f"{type(state).__name__}")
    vrows = getattr(free, "_vrows", None)
    if vrows is None and speeds is not None:
        raise ModelError("linearize speeds: this free system has no velocity constraints, so "
                         "the rates of all its chosen coordinates are the velocities; leave "
                         "speeds out")
    sc = scaling_at(system, t0, q, p)
    if isinstance(state, (Solution, State)):
        if vrows is None:
            q, qd = project(system, t0, q, qd, p, scaling=sc)
        else:
            q, qd = project_state(system, vrows, t0, q, qd, p, sc)
    else:
        q, qd = free._project_start(t0, q, qd, p, held, sc)
    if vrows is None:
        qdd, lam, _ = free_acceleration(system, t0, q, qd, p)
        mu = np.zeros(0)
    else:
        qdd, lam = nonholonomic_acceleration(system, vrows, t0, q, qd, p)
        lam, mu = lam[:m], lam[m:]
    J = system.jacobian(t0, q, p) if m else np.zeros((0, n))

    # the chosen coordinates
    if coordinates is None:
        idx = independent_coordinates(system, t0, q, p, sc)
        coord_names = [lay.q_names[i] for i in idx]
        coord_exprs = [lay.q_symbols[i] for i in idx]
    else:
        if isinstance(coordinates, (str, sp.Basic)) or not isinstance(coordinates,
                                                                      (list, tuple)):
            raise ModelError(f"linearize coordinates: give a list, got {coordinates!r}")
        # (parsed once per system and choice: SymPy's symbol sets of a vehicle's angle
        # expressions were a third of a bicycle's linearisation)
        parsed = system.__dict__.setdefault("_linear_parsed", {})
        try:
            pkey = tuple(coordinates)
            pairs = parsed.get(pkey)
        except TypeError:                         # (unhashable entries: parsed each call)
            pkey, pairs = None, None
        if pairs is None:
            pairs = [_as_expression(system, c, "coordinates") for c in coordinates]
            bad = [a for a, b in pairs if b.free_symbols - set(lay.q_symbols)]
            if bad:
                raise ModelError(f"linearize coordinates: {bad} must be expressions of the "
                                 "coordinates only (no velocities, parameters or T)")
            if pkey is not None:
                parsed[pkey] = pairs
        coord_names = [a for a, _ in pairs]
        coord_exprs = [b for _, b in pairs]
    f = n - m
    if len(coord_exprs) != f:
        raise ModelError(f"linearize coordinates: the free system has {f} degree(s) of "
                         f"freedom, so it takes {f} coordinate(s); got {len(coord_exprs)} "
                         f"({coord_names}); e.g. {_suggest(system, t0, q, p, sc)}")
    if len(set(coord_names)) != len(coord_names):
        raise ModelError(f"linearize coordinates: {coord_names} names one twice")
    ins = _inputs(free, inputs)
    if vrows is not None and ins.rows:
        raise ModelError(f"linearize inputs: driver inputs {list(ins.rows and ins.names)} with "
                         "velocity constraints are not supported; drive the motion by a load "
                         "(a named Force or Moment, or a parameter of the loads)")
    if vrows is not None and _explicit_time(system):
        raise ModelError("linearize: constraints or loads that depend on the time T together "
                         "with velocity constraints are not supported; linearise a model whose "
                         "reference motion is steady without explicit time")
    out_pairs = [_as_expression(system, o, "outputs") for o in outputs]
    cyc = []
    for c in cyclic:
        name = c if isinstance(c, str) else getattr(c, "name", None)
        if name not in coord_names:
            raise ModelError(f"linearize cyclic: {c!r} is not one of the chosen coordinates "
                             f"{coord_names}")
        cyc.append(coord_names.index(name))

    # compiled once per system and choice of coordinates, outputs and inputs
    cache = system.__dict__.setdefault("_linear_charts", {})
    key = (tuple(coord_exprs), tuple(e for _, e in out_pairs), ins.params, vrows is not None)
    chart = cache.get(key)
    if chart is None:
        chart = cache[key] = _Chart(system, coord_exprs, [e for _, e in out_pairs], ins.params,
                                    difference=vrows is not None)
    load_kernel = None
    if ins.loads:
        lkey = ("loads", tuple(id(ld) for ld in ins.loads))
        load_kernel = cache.get(lkey)
        if load_kernel is None:
            load_kernel = cache[lkey] = (_LoadInputs(system, free.model, ins.loads), ins.loads)
        load_kernel = load_kernel[0]
    kernel = linear_kernel(system)
    Rq, Rv, Ra = kernel(t0, q, qd, qdd, lam, p)
    cq, cv = kernel.constraints(t0, q, qd, qdd, lam, p)
    ch = chart(t0, q, qd, qdd, lam, p, steps=sc.columns)
    # R_u, and S_u: the driver inputs' place in the acceleration constraints
    nu = len(ins.names)
    Ru, Su = np.zeros((n, nu)), np.zeros((m, nu))
    Rp = kernel.parameters(ins.params, t0, q, qd, qdd, lam, p) if ins.params else None
    Ql = load_kernel(t0, q, qd, qdd, lam, p) if load_kernel is not None else None
    for j, (kind, w) in enumerate(zip(ins.kinds, ins.where)):
        if kind == "parameter":
            Ru[:, j] = Rp[:, w]
        elif kind == "load":
            Ru[:, j] = -Ql[:, w]
        else:
            Su[ins.rows[w], j] = 1.0

    # the chart: K = [Phi_q; h_q] must be nonsingular (judged unit-free)
    H = ch["hq"]
    Kc = np.vstack([J, H])
    Ks = Kc * sc.columns
    Ks = Ks / np.maximum(np.abs(Ks).max(axis=1), 1e-300)[:, None]
    sv = np.linalg.svd(Ks, compute_uv=False) if n else np.zeros(0)
    if n and not sv[-1] > 1e-10 * sv[0]:
        raise ModelError(
            f"linearize coordinates: {coord_names} are not independent with the kept "
            f"constraints at the reference state (the constraint Jacobian and their gradients "
            f"are singular, smallest singular value {sv[-1] / sv[0]:.1e} of the largest); "
            f"choose coordinates the constraints leave free, e.g. "
            f"{_suggest(system, t0, q, p, sc)}")
    # the driven equations' deviations join the chosen coordinates (after them): a driver
    # input turns its equation into a coordinate whose acceleration is the input
    drows = list(ins.rows)
    nd = len(drows)
    g = f + nd
    E = np.zeros((n, g))
    E[m:, :f] = np.eye(f)
    E[drows, f + np.arange(nd)] = 1.0
    # (numpy's solve: SciPy's lu_solve costs 30 ms a call on this machine's BLAS set-up)
    P = np.linalg.solve(Kc, E)
    if vrows is not None:
        return _linearize_rolling(
            free, vrows, ch, coord_names, speeds, cyc, ins, out_pairs, t0, q, qd, qdd, lam, mu,
            p, J, H, P, sc, Rq, Rv, Ra, Ru, cq, cv, tolerance)
    W = -np.linalg.solve(Kc, np.vstack([0.5 * cv @ P, ch["ydq"] @ P]))
    # columns: (dy, dyd, du)
    dq = np.hstack([P, np.zeros((n, g)), np.zeros((n, nu))])
    dqd = np.hstack([W, P, np.zeros((n, nu))])
    du = np.hstack([np.zeros((nu, 2 * g)), np.eye(nu)])
    Kkt = np.block([[Ra, J.T], [J, np.zeros((m, m))]])
    rhs = -np.vstack([Rq @ dq + Rv @ dqd + Ru @ du, cq @ dq + cv @ dqd - Su @ du])
    try:
        dqdd = np.linalg.solve(Kkt, rhs)[:n]
    except np.linalg.LinAlgError:
        raise ModelError("linearize: the mass matrix is singular on the free motions (a "
                         "massless body free to move); give it mass or constrain it") from None
    G = np.vstack([ch["yddq"] @ dq + ch["yddv"] @ dqd + H @ dqdd,
                   J[drows] @ dqdd + cq[drows] @ dq + cv[drows] @ dqd])
    A = np.zeros((2 * g, 2 * g))
    A[:g, g:] = np.eye(g)
    A[g:] = G[:, : 2 * g]
    Bm = np.vstack([np.zeros((g, nu)), G[:, 2 * g :]])
    no = len(out_pairs)
    Op = np.zeros((no, nu))
    for j, (kind, w) in enumerate(zip(ins.kinds, ins.where)):
        if kind == "parameter":
            Op[:, j] = ch["op"][:, w]
    O = ch["oq"] @ dq + ch["ov"] @ dqd + ch["oa"] @ dqdd + Op @ du
    Cm, Dm = O[:, : 2 * g], O[:, 2 * g :]

    along = None
    if _explicit_time(system):
        # constraints or loads that change with time (a driver, a time-varying force): the
        # accelerations' rate along the reference, d(ydd)/dt = G_y yd + d(ydd)/dt|_y, by a
        # central difference of the reduced accelerations at t -+ h along the motion
        def along(h):
            out = []
            for sgn in (1.0, -1.0):
                th = t0 + sgn * h
                qh, qdh = project(system, th, q + sgn * h * qd + 0.5 * h * h * qdd,
                                  qd + sgn * h * qdd, p, scaling=sc)
                qddh, lamh, _ = free_acceleration(system, th, qh, qdh, p)
                out.append(chart(th, qh, qdh, qddh, lamh, p)["ydd"])
            return (out[0] - out[1]) / (2 * h)
    _check_steady(system, coord_names, P[:, :f], Rq, Ra, G[:f, :f], ch["yd"], ch["ydd"], cyc, q,
                  qd, qdd, lam, p, t0, J, sc, tolerance, along)
    names = [*coord_names, *(ins.names[k] for k in range(nu) if ins.kinds[k] == "driver")]
    states = [*names, *(c + "_d" for c in names)]
    return _linear_system(free, A, Bm, Cm, Dm, states, cyc, coord_names, names, out_pairs,
                          ins, P, t0, q, qd, qdd, p)


def _coordinate_units(P, sc) -> np.ndarray:
    """The unit of each chosen coordinate: the change that moves the coordinates by one
    unit-free unit (positions in units of the length scale, angles in radians)."""
    reach = np.abs(P / sc.columns[:, None]).max(axis=0, initial=0.0)
    return np.where(reach > 0, 1.0 / np.where(reach > 0, reach, 1.0), 1.0)


def _linearize_rolling(free, vrows, ch, coord_names, speeds, cyc, ins, out_pairs, t0, q, qd,
                       qdd, lam, mu, p, J, H, P, sc, Rq, Rv, Ra, Ru, cq, cv, tolerance):
    r"""The linearisation with velocity constraints ``A qd + b = 0`` (``k`` rows, multipliers
    ``mu``): the state is ``(dy, dv)``, ``v = S yd`` the rates of ``f - k`` chosen
    coordinates (the speeds). Equations in the module docstring, section *Velocity
    constraints*."""
    system = free.system
    n, m, k = system.n, system.m, vrows.k
    f = P.shape[1]
    fv = f - k
    Av = vrows.evaluate(t0, q, qd, p)[0]
    psi_q, a_q, a_qd, F_q = vrows.derivatives(t0, q, qd, qdd, mu, p)
    unit = _coordinate_units(P, sc)
    # the speeds: named, or the chosen coordinates left out of the k well-conditioned pivots
    # of column-pivoted QR of the velocity rows in the chosen coordinates' rates (unit-free)
    AP = Av @ P
    if speeds is None:
        if k:
            rs = np.abs(AP * unit).max(axis=1)
            APs = AP * unit / np.where(rs > 0, rs, 1.0)[:, None]
            piv = sla.qr(APs, mode="economic", pivoting=True)[2]
            sp_idx = sorted(int(i) for i in piv[k:])
        else:
            sp_idx = list(range(f))
    else:
        if isinstance(speeds, (str, sp.Basic)) or not isinstance(speeds, (list, tuple)):
            raise ModelError(f"linearize speeds: give a list of chosen coordinates, got "
                             f"{speeds!r}")
        sp_idx = []
        for v in speeds:
            name = v if isinstance(v, str) else getattr(v, "name", None)
            if isinstance(name, str) and name not in coord_names and name.endswith("_d"):
                name = name[:-2]
            if name not in coord_names:
                raise ModelError(f"linearize speeds: {v!r} is not one of the chosen coordinates "
                                 f"{coord_names} (a speed is the rate of a chosen coordinate)")
            if coord_names.index(name) in sp_idx:
                raise ModelError(f"linearize speeds: {name!r} is named twice")
            sp_idx.append(coord_names.index(name))
        if len(sp_idx) != fv:
            raise ModelError(
                f"linearize speeds: the free system has {f} chosen coordinates and {k} "
                f"velocity constraint row(s), so it takes {fv} speed(s); got {len(sp_idx)} "
                f"({[coord_names[i] for i in sp_idx]})")
    S = np.zeros((fv, f))
    S[np.arange(fv), sp_idx] = 1.0
    # the velocity chart: [Phi_q; A; S h_q] nonsingular (unit-free rows and columns)
    Kv = np.vstack([J, Av, S @ H])
    Ks = Kv * sc.columns
    Ks = Ks / np.maximum(np.abs(Ks).max(axis=1), 1e-300)[:, None]
    sv = np.linalg.svd(Ks, compute_uv=False)
    if not sv[-1] > 1e-10 * sv[0]:
        names = [coord_names[i] for i in sp_idx]
        raise ModelError(
            f"linearize speeds: the rates of {names} are not independent velocities with the "
            f"velocity constraints ({', '.join(c.label() for c in vrows.constraints)}) at the "
            f"reference state (smallest singular value {sv[-1] / sv[0]:.1e} of the largest); "
            "name rates the constraints leave free (e.g. a lean, a steer and a wheel's "
            "rotation), or leave speeds out to have them chosen")
    Kinv = np.linalg.inv(Kv)
    Pv = Kinv[:, m + k:]
    Wv = -Kinv @ np.vstack([0.5 * cv @ P, psi_q @ P, S @ ch["ydq"] @ P])
    nu = len(ins.names)
    ns = f + fv
    dq = np.hstack([P, np.zeros((n, fv)), np.zeros((n, nu))])
    dqd = np.hstack([Wv, Pv, np.zeros((n, nu))])
    du = np.hstack([np.zeros((nu, ns)), np.eye(nu)])
    Kkt = np.block([[Ra, J.T, Av.T], [J, np.zeros((m, m + k))], [Av, np.zeros((k, m + k))]])
    rhs = -np.vstack([(Rq + F_q) @ dq + Rv @ dqd + Ru @ du, cq @ dq + cv @ dqd,
                      a_q @ dq + a_qd @ dqd])
    try:
        dqdd = np.linalg.solve(Kkt, rhs)[:n]
    except np.linalg.LinAlgError:
        raise ModelError("linearize: the mass matrix is singular on the free motions (a "
                         "massless body free to move); give it mass or constrain it") from None
    # the chosen coordinates' rates and accelerations: yd = h_q qd, ydd = h_q qdd + ydq qd
    Yd = H @ dqd + ch["ydq"] @ dq
    Ydd = ch["yddq"] @ dq + ch["yddv"] @ dqd + H @ dqdd
    A = np.vstack([Yd[:, :ns], S @ Ydd[:, :ns]])
    Bm = np.vstack([Yd[:, ns:], S @ Ydd[:, ns:]])
    O = ch["oq"] @ dq + ch["ov"] @ dqd + ch["oa"] @ dqdd
    for j, (kind, w) in enumerate(zip(ins.kinds, ins.where)):
        if kind == "parameter":
            O[:, ns + j] += ch["op"][:, w]
    Cm, Dm = O[:, :ns], O[:, ns:]
    _check_steady(system, coord_names, P, Rq + F_q, Ra, Ydd[:, :f], ch["yd"], ch["ydd"], cyc,
                  q, qd, qdd, lam, p, t0, J, sc, tolerance, reactions=Av.T @ mu)
    states = [*coord_names, *(coord_names[i] + "_d" for i in sp_idx)]
    if cyc:
        # (a dropped position must act on nothing kept: the accelerations were checked
        # above, the rates of the kept coordinates here, unit-free)
        su = np.concatenate([unit, unit[sp_idx]])
        As = A * su[None, :] / su[:, None]
        keep = [i for i in range(ns) if i not in cyc]
        big = max(float(np.abs(As[np.ix_(keep, keep)]).max(initial=0.0)), 1e-300)
        for j in cyc:
            col = np.abs(As[keep, j])
            if col.size and col.max() > tolerance * big:
                i = keep[int(np.argmax(col))]
                raise NotSteadyError(
                    f"linearize cyclic: {coord_names[j]!r} is not cyclic: the rate of "
                    f"{states[i]} depends on its position ({A[i, j]:.3g} per unit); leave it "
                    "out of cyclic=")
    return _linear_system(free, A, Bm, Cm, Dm, states, cyc, coord_names, coord_names,
                          out_pairs, ins, P, t0, q, qd, qdd, p,
                          speeds=tuple(coord_names[i] for i in sp_idx))


def _linear_system(free, A, Bm, Cm, Dm, states, cyc, coord_names, names, out_pairs, ins, P, t0,
                   q, qd, qdd, p, speeds=()) -> LinearSystem:
    """The :class:`LinearSystem` of both charts: the ``cyclic`` positions (state indices
    ``cyc``, checked not to act on the kept states by the caller) dropped after checking no
    output depends on them; eigenvalues judged; arrays read-only."""
    if cyc:
        for j in cyc:
            if Cm.shape[0] and np.abs(Cm[:, j]).max() > 1e-9 * max(np.abs(Cm).max(), 1e-300):
                r = int(np.argmax(np.abs(Cm[:, j])))
                raise ModelError(f"linearize cyclic: output {out_pairs[r][0]!r} depends on the "
                                 f"position of {coord_names[j]!r}, which cyclic= drops from "
                                 "the state; leave it out of cyclic or of the outputs")
        keep = [i for i in range(len(states)) if i not in cyc]
        A, Bm, Cm = A[np.ix_(keep, keep)], Bm[keep], Cm[:, keep]
        states = [states[i] for i in keep]
    s, stability = judge(A)
    for a in (A, Bm, Cm, Dm, P, s, q, qd, qdd, p):
        a.setflags(write=False)
    return LinearSystem(A=A, B=Bm, C=Cm, D=Dm, states=tuple(states), inputs=ins.names,
                        outputs=tuple(a for a, _ in out_pairs), coordinates=tuple(names),
                        t=t0, q=q, qd=qd, qdd=qdd, p=p, basis=P, eigenvalues=s,
                        stability=stability, stable="unstable" not in stability,
                        model=free.model, speeds=speeds)


def _suggest(system, t, q, p, sc) -> list:
    return [system.layout.q_names[i] for i in independent_coordinates(system, t, q, p, sc)]


def judge(A: np.ndarray) -> tuple:
    r"""Eigenvalues of ``A`` (ascending by modulus, then real part) and each one's stability,
    judged on its own scale (the rule of :attr:`~mechsys.VibrationModes.stability`):
    neutral when :math:`|\mathrm{Re}\,s| \le` ``NEUTRAL`` :math:`s_{own}` or
    ``ROUNDING`` :math:`\max|s|`, with :math:`s_{own} = |w|^T|A||v| / |w^H v|`."""
    from ._vibration import NEUTRAL, ROUNDING

    if A.shape[0] == 0:
        return np.zeros(0, dtype=complex), ()
    s, Wl, Vr = sla.eig(A, left=True, right=True)
    num = np.einsum("ik,ij,jk->k", np.abs(Wl), np.abs(A), np.abs(Vr))
    den = np.abs(np.einsum("ik,ik->k", Wl.conj(), Vr))
    with np.errstate(divide="ignore", invalid="ignore"):
        own = np.where(den > 0, num / den, np.inf)
    big = float(np.abs(s).max(initial=0.0))
    floor = np.maximum(NEUTRAL * own, ROUNDING * big)
    order = np.lexsort((s.real, np.round(np.abs(s), 12)))
    s, floor = s[order], floor[order]
    stability = tuple("neutral" if abs(x.real) <= fl else "unstable" if x.real > 0 else "stable"
                      for x, fl in zip(s, floor))
    return s, stability


def _explicit_time(system) -> bool:
    """Whether the kept constraints or the loads depend on the time ``T`` explicitly."""
    flag = getattr(system, "_linear_explicit_time", None)
    if flag is None:
        flag = any(T in sp.sympify(e).free_symbols for e in system.phi) or any(
            T in sp.sympify(e).free_symbols for e in system.dynamics.Q)
        system._linear_explicit_time = flag
    return flag


def _check_steady(system, names, P, Rq, Ra, Gy, yd, ydd, cyc, q, qd, qdd, lam, p, t, J, sc, tol,
                  along=None, reactions=None):
    r"""The reference must be an equilibrium or a steady motion in the chosen coordinates:
    ``ydd = 0`` and :math:`d(\ddot y)/dt = G_y \dot y = 0`; a ``cyclic`` coordinate's position must not
    act (``G_y`` column zero). Each measured as the generalized force it needs
    (``R_qdd P a``) against the forces acting (times the motion's rate for the rate)."""
    dyn = system.dynamics
    M, Q, Qv = dyn.terms(t, q, qd, lam, p, qdd)
    forces = np.abs(Q) + np.abs(Qv) + np.abs(M @ qdd) + (np.abs(J.T @ lam) if len(lam) else 0)
    if reactions is not None:                 # (the velocity constraints' A^T mu)
        forces = forces + np.abs(reactions)
    ref = float(np.max(forces, initial=0.0))
    # unit of each chosen coordinate: the change that moves the coordinates by one unit-free
    # unit (positions in units of L, angles in radians)
    reach = np.abs(P / sc.columns[:, None]).max(axis=0, initial=0.0)
    unit = np.where(reach > 0, 1.0 / np.where(reach > 0, reach, 1.0), 1.0)
    rate = float(np.max(np.abs(yd) / unit, initial=0.0))
    # and the forces a unit change of the coordinates brings (a pendulum hanging in a
    # minimal coordinate has no force acting at all, only its stiffness m g l), and the
    # inertial forces on the motion's own time scale (a sleigh sliding straight with no load
    # has no force acting either: its accelerations are rounding)
    ref = max(ref, float(np.abs(Rq @ (P * unit)).max(initial=0.0)),
              float(np.abs(Ra @ (P * unit)).max(initial=0.0)) * rate**2)

    def force(a):
        return float(np.abs(Ra @ (P @ a)).max(initial=0.0))

    bad = force(ydd)
    if bad > tol * ref and bad > 0:
        worst = np.argsort(-np.abs(ydd) / unit)[:3]
        listed = ", ".join(f"{names[i]} is {ydd[i]:.3g}" for i in worst if ydd[i] != 0)
        raise NotSteadyError(
            f"linearize: not a steady motion: acceleration of {listed} (unbalanced generalized "
            f"force {bad:.3g}, {bad / max(ref, 1e-300):.2e} of the forces acting). Linearise "
            "about an equilibrium (eq = m.free(solution='static').solve()) or a motion whose "
            "chosen coordinates have constant velocities")
    drift = Gy @ yd
    if along is not None:
        # the time scale of the motion and of the linear dynamics sets the step
        speed = max(rate, float(np.sqrt(np.abs(Gy).max(initial=0.0))), 1e-3)
        drift = along(1e-4 / speed)
        rate = speed
    bad = force(drift)
    if rate > 0 and bad > tol * ref * rate and bad > 0:
        worst = np.argsort(-np.abs(drift) / unit)[:3]
        moving = [names[j] for j in range(len(names)) if yd[j] != 0]
        listed = ", ".join(f"{names[i]} changes at {drift[i]:.3g}/s" for i in worst
                           if drift[i] != 0)
        what = (f"the motion of {moving}" + (" or the time" if along else "") if moving
                else "the time (a driver or load that depends on T)")
        raise NotSteadyError(
            f"linearize: not a steady motion: {what} changes the accelerations "
            f"(acceleration of {listed}); the coordinates that move must be cyclic (the "
            "motion must not depend on them) and drivers and loads steady. Choose "
            "coordinates in which the motion is steady, or linearise about an equilibrium")
    for j in cyc:
        col = Gy[:, j] * unit[j]
        if force(col) > tol * max(ref, 1e-300) and force(col) > 0:
            k = int(np.argmax(np.abs(col)))
            raise NotSteadyError(
                f"linearize cyclic: {names[j]!r} is not cyclic: the acceleration of "
                f"{names[k]} depends on its position ({Gy[k, j]:.3g} per unit); leave it out "
                "of cyclic=")


__all__ = ["LinearKernel", "LinearSystem", "independent_coordinates", "judge", "linear_kernel",
           "linearize"]
