r"""Symbolic differentiation for the compiled system, done in SymEngine when it is installed.

SymPy's ``diff`` spends most of its time in the assumptions system; SymEngine derives the
same Jacobian and ``gamma`` about 100 times faster (measured on the 3D gyroscope: 3.5 s
against 0.03 s, plus 0.3 s to convert the results back to SymPy for inspection). Results
are returned as SymPy expressions (what users inspect) and, when SymEngine did the work,
also as SymEngine expressions that the SymEngine backend compiles without converting again.
See ``docs/decisions/0004-symbolic-derivation.md``.

For every equation :math:`\phi_i` (free symbols restricted to the coordinates it uses):

.. math::

    J_{ij} &= \partial \phi_i / \partial q_j \qquad \text{(only nonzero entries)} \\
    v_i &= \textstyle\sum_j J_{ij} \dot q_j + \partial \phi_i / \partial T \\
    \gamma_i &= -\left( \textstyle\sum_j \partial v_i / \partial q_j \, \dot q_j
                + \partial v_i / \partial T \right)
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._symbols import T, free_symbols, restore_assumptions
from ._backends import function_atoms

try:  # optional
    import symengine as se
except ImportError:  # pragma: no cover
    se = None


_SAFE = (sp.sin, sp.cos, sp.tan, sp.exp, sp.log, sp.asin, sp.acos, sp.atan, sp.sinh, sp.cosh,
         sp.tanh, sp.atan2)
_SAFE_ALL = (*_SAFE, sp.Piecewise, sp.floor)


def symengine_safe(exprs) -> bool:
    """Whether SymEngine may differentiate these expressions: elementary functions, plus
    ``Piecewise`` and ``floor`` (splines, periodic curves: SymEngine 0.15 differentiates a
    ``Piecewise`` piece by piece and LLVM compiles both; :func:`_freeze_steps` keeps
    ``floor`` out of the derivatives). SymEngine 0.15 crashes differentiating ``Mod``;
    ``ceiling``, ``sign``, ``Abs``... stay with SymPy."""
    if se is None:
        return False
    for e in exprs:
        e = sp.sympify(e)
        # one traversal (shared with the other checks, decision 0080): every function
        # application and Max/Min (not Functions in SymPy); the refused ones (Mod, ceiling,
        # sign, Abs, Heaviside, DiracDelta) are not _SAFE_ALL
        for f in function_atoms(e):
            if isinstance(f, (sp.Function, sp.Max, sp.Min)) and not isinstance(f, _SAFE_ALL):
                return False
    return True


def _freeze_steps(e):
    """``(E, thaw)``: SymEngine ``E`` of the SymPy ``e`` with each ``floor(g)`` replaced by a
    new symbol, and the map back. Differentiating ``E`` then gives ``floor``'s derivative
    its value almost everywhere, zero (as :func:`_drop_step_derivatives` does for SymPy);
    SymEngine would leave an uncompilable ``Derivative(floor(x), x)``. Cheaper than removing
    that from every derivative (a traversal of each: seconds for a spline cam's ``gamma``)."""
    E = se.sympify(e)
    floors = {f for f in function_atoms(e) if isinstance(f, sp.floor)}
    if not floors:
        return E, {}
    frozen = {se.sympify(f): se.Symbol(f"_mechsys_floor_{k}")
              for k, f in enumerate(sorted(floors, key=sp.default_sort_key))}
    return E.xreplace(frozen), {s: f for f, s in frozen.items()}


def _thaw(x, thaw):
    return x.xreplace(thaw) if thaw else x


def _rewrite_steps(e):
    """``Mod(a, b) -> a - b floor(a/b)`` so SymPy can differentiate it."""
    return e.replace(lambda x: isinstance(x, sp.Mod), lambda x: x.args[0] - x.args[1] * sp.floor(
        x.args[0] / x.args[1]))


def _drop_step_derivatives(e):
    """Derivatives of piecewise-constant functions (floor, ceiling, sign) vanish almost
    everywhere; SymPy leaves them unevaluated (``Subs(Derivative(floor(x), x), ...)``,
    ``DiracDelta``): set them to zero so the expression can be compiled."""
    if not e.has(sp.Derivative, sp.Subs, sp.DiracDelta):
        return e
    # the chain rule on floor(g(x)) gives Subs(Derivative(floor(xi), xi), xi, g) g': drop the
    # Subs whole first (``replace`` works bottom-up and would leave an uncompilable Subs(0, ..))
    subs = [x for x in e.atoms(sp.Subs) if x.has(sp.floor, sp.ceiling, sp.sign)]
    if subs:
        e = e.xreplace({x: sp.S.Zero for x in subs})
    return e.replace(
        lambda x: (isinstance(x, (sp.Derivative, sp.Subs))
                   and x.has(sp.floor, sp.ceiling, sp.sign)) or isinstance(x, sp.DiracDelta),
        lambda x: sp.S.Zero)


def _diff(e, s):
    return _drop_step_derivatives(sp.diff(e, s))


def to_sympy_list(xs) -> list:
    return [_to_sympy(x) for x in xs]


def _to_sympy(x):
    if se is not None and isinstance(x, se.Basic):
        return restore_assumptions(sp.sympify(x))      # SymEngine drops "real"
    return x


def sparse_derivatives(E, wrt, exprs: list) -> tuple[np.ndarray, np.ndarray]:
    r"""The nonzero entries of :math:`\partial E_i / \partial w_j`: their rows and columns,
    the derivatives appended to ``exprs`` in that order (each expression differentiated only
    by the symbols of ``wrt`` it holds; SymPy or SymEngine expressions and symbols alike).
    Assemble with ``np.add.at(D, (rows, cols), values)``."""
    index = {w: j for j, w in enumerate(wrt)}
    rows, cols = [], []
    for i, e in enumerate(E):
        for j in sorted(index[w] for w in e.free_symbols if w in index):
            d = e.diff(wrt[j])
            if d != 0:
                rows.append(i)
                cols.append(j)
                exprs.append(d)
    return np.array(rows, dtype=int), np.array(cols, dtype=int)


#: per-equation derivatives (SymEngine): systems of one model share most equations -- the
#: kinematic system, ``free()`` without the driver, ``path()``, the stages of a switch, the
#: locked systems -- so each equation is differentiated once per process. Keyed by the
#: equation and the (coordinate, velocity) symbol pairs it involves.
_DERIVED: dict = {}
_DERIVED_MAX = 200_000


#: SymPy symbol -> its SymEngine symbol: the conversion costs ~10 us, and the derivation of
#: a large model converts each coordinate, velocity and time symbol thousands of times
_SE_SYMBOLS: dict = {}


def se_symbol(s):
    """``symengine.sympify(s)``, remembered for plain SymPy symbols (anything else, numbers
    included, is converted each time: ``Float(1.0) == 1`` in SymPy, so a number could not
    be a key).

    Example::

        se_symbol(sp.Symbol("x", real=True)) == symengine.Symbol("x")   # True
    """
    if type(s) is not sp.Symbol:
        return se.sympify(s)
    out = _SE_SYMBOLS.get(s)
    if out is None:
        out = se.sympify(s)
        if len(_SE_SYMBOLS) >= _DERIVED_MAX:
            _SE_SYMBOLS.clear()
        _SE_SYMBOLS[s] = out
    return out


def _derive_one(e, mine, mine_d):
    """``(phi, [(q_j, d phi / d q_j)], phi_t, gamma)`` of one equation (SymEngine), for its
    coordinates ``mine`` (in column order) and their velocities ``mine_d``."""
    E, thaw = _freeze_steps(e)
    free = E.free_symbols
    Ts = se_symbol(T)
    jac = []
    v = se.Integer(0)
    for s, sd in zip(mine, mine_d):
        d = E.diff(se_symbol(s))
        if d != 0:
            jac.append((s, _thaw(d, thaw)))
            v += d * se_symbol(sd)
    et = E.diff(Ts) if Ts in free else se.Integer(0)
    v += et
    fv = v.free_symbols
    gm = v.diff(Ts) if Ts in fv else se.Integer(0)
    for s, sd in zip(mine, mine_d):
        a = se_symbol(s)
        if a in fv:
            gm += v.diff(a) * se_symbol(sd)
    return _thaw(E, thaw), jac, _thaw(et, thaw), _thaw(-gm, thaw)


def derive_kinematics(phi, q, qd, T):
    """``(rows, cols, jac, phi_t, gamma, native)`` for equations ``phi``.

    Without SymEngine, ``jac``, ``phi_t``, ``gamma`` are SymPy lists and ``native`` is
    ``None``; with it they are ``None`` and ``native`` holds them as SymEngine expressions
    (keys ``"phi", "jac", "phi_t", "gamma"``), converted to SymPy only when asked
    (:func:`to_sympy_list`).
    """
    index = {s: j for j, s in enumerate(q)}
    rows, cols = [], []
    if not symengine_safe(phi):
        jac, phi_t, gamma = [], [], []
        for i, e in enumerate(phi):
            e = _rewrite_steps(e)
            free = e.free_symbols
            v = sp.S.Zero
            for s in sorted((s for s in free if s in index), key=index.get):
                d = _diff(e, s)
                if d != 0:
                    rows.append(i)
                    cols.append(index[s])
                    jac.append(d)
                    v += d * qd[index[s]]
            et = _diff(e, T) if T in free else sp.S.Zero
            phi_t.append(et)
            v += et
            fv = v.free_symbols
            gm = _diff(v, T) if T in fv else sp.S.Zero
            for a, b in zip(q, qd):
                if a in fv:
                    gm += _diff(v, a) * b
            gamma.append(-gm)
        return rows, cols, jac, phi_t, gamma, None
    n_phi, n_jac, n_pt, n_gm = [], [], [], []
    for i, e in enumerate(phi):
        e = sp.sympify(e)
        mine = sorted((s for s in free_symbols(e) if s in index), key=index.get)
        key = (e, tuple((s, qd[index[s]]) for s in mine))
        hit = _DERIVED.get(key)
        if hit is None:
            hit = _derive_one(e, mine, [qd[index[s]] for s in mine])
            if len(_DERIVED) >= _DERIVED_MAX:
                _DERIVED.clear()
            _DERIVED[key] = hit
        e_phi, e_jac, e_pt, e_gm = hit
        n_phi.append(e_phi)
        for s, d in e_jac:
            rows.append(i)
            cols.append(index[s])
            n_jac.append(d)
        n_pt.append(e_pt)
        n_gm.append(e_gm)
    native = {"phi": n_phi, "jac": n_jac, "phi_t": n_pt, "gamma": n_gm}
    # SymPy versions are made lazily (System): 3D gammas can be megabytes of text
    return rows, cols, None, None, None, native


def hessian_terms(T_expr, q, qd):
    """Lagrange terms of a kinetic energy ``T(q, qd)`` (SymPy in, SymPy out)::

        M_ij = d^2 T / d qd_i d qd_j,   Qv_i = dT/dq_i - sum_j d^2 T / d qd_i d q_j qd_j
    """
    n = len(q)
    if not symengine_safe([T_expr]):
        p = [sp.diff(T_expr, v) for v in qd]
        M = [[sp.diff(p[i], qd[j]) for j in range(n)] for i in range(n)]
        Qv = [sp.diff(T_expr, q[i]) - sum((sp.diff(p[i], sj) * vj for sj, vj in zip(q, qd)),
                                          sp.S.Zero) for i in range(n)]
        return M, Qv
    Ts, thaw = _freeze_steps(sp.sympify(T_expr))
    qs = [se.sympify(s) for s in q]
    qds = [se.sympify(s) for s in qd]
    p = [Ts.diff(v) for v in qds]
    M = [[_to_sympy(_thaw(p[i].diff(qds[j]), thaw)) for j in range(n)] for i in range(n)]
    Qv = []
    for i in range(n):
        acc = Ts.diff(qs[i])
        for sj, vj in zip(qs, qds):
            acc -= p[i].diff(sj) * vj
        Qv.append(_to_sympy(_thaw(se.expand(acc), thaw)))
    return M, Qv


def time_derivative(expr, q, qd, qdd=None):
    r"""Total time derivative :math:`\frac{d}{dt} f(q, \dot q, t) = f_q \dot q + f_{\dot q} \ddot q + f_t`
    of a SymPy
    expression, with ``q``/``qd``/``qdd`` lists of corresponding symbols. Piecewise-constant
    parts (``Mod``'s jumps, ``floor``) differentiate to zero."""
    expr = sp.sympify(expr)
    if expr.has(sp.Mod):
        expr = _rewrite_steps(expr)
    free = expr.free_symbols
    out = _diff(expr, T) if T in free else sp.S.Zero
    for a, b in zip(q, qd):
        if a in free:
            out += _diff(expr, a) * b
    if qdd is not None:
        for a, b in zip(qd, qdd):
            if a in free:
                out += _diff(expr, a) * b
    return out
