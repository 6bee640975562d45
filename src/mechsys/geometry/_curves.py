r"""Curves for cam and gear profiles: cubic splines (Mech's ``SplineFit``/``SplineFunction``)
and the involute of a circle (Mech's ``Involute``).

Both give SymPy expressions of a profile parameter that go into body points, e.g.
``cam.point(spline(a))``, so the constraint equations, their Jacobian and ``gamma`` are
derived *exactly* from them (``compile/_derive.py``), never by finite differences.

A spline becomes a ``Piecewise`` of cubic polynomials, nested as a binary search over the
knots (``log2(n)`` comparisons per evaluation); on the interval ``[t_k, t_k+1)``, with
:math:`h = u - t_k`:

.. math::

    s(u) = a_{0,k} + h\, (a_{1,k} + h\, (a_{2,k} + h\, a_{3,k}))

SymEngine differentiates that ``Piecewise`` piece by piece and compiles it with LLVM (see
``docs/decisions/0008-curves.md`` for the choice and its measurements).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg as sla
import sympy as sp

from .._errors import ModelError, choice

#: Mech's ``EndConditions`` settings (``Natural``, ``Closed``) and the strict periodic one.
END_CONDITIONS = ("natural", "closed", "periodic")


def _as_float_array(data, what: str) -> np.ndarray:
    try:
        arr = np.asarray(data, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ModelError(f"SplineFit: {what} must be numbers in a rectangular array ({exc})") from None
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"SplineFit: {what} contain a value that is not finite (nan or inf)")
    return arr


def _second_derivatives(t: np.ndarray, y: np.ndarray, end, closed: bool) -> np.ndarray:
    r"""Second derivatives ``M_i`` of the interpolating cubic at the knots, shape ``(n, d)``.

    Continuity of the first derivative at the interior knots gives, with ``h_i = t_i+1 - t_i``
    and ``D_i = (y_i+1 - y_i) / h_i``::

        h_i-1 M_i-1 + 2 (h_i-1 + h_i) M_i + h_i M_i+1 = 6 (D_i - D_i-1)

    Natural ends: ``M_0 = M_n = 0``. Given end slopes ``v0, vn``:
    ``2 h_0 M_0 + h_0 M_1 = 6 (D_0 - v0)``, ``h_n-1 M_n-1 + 2 h_n-1 M_n = 6 (vn - D_n-1)``.
    Closed (equal slope and curvature at the two ends): ``M_n = M_0`` and the knot-0 equation
    wraps around to ``h_n-1 M_n-1 + 2 (h_n-1 + h_0) M_0 + h_0 M_1 = 6 (D_0 - D_n-1)``.
    """
    n = len(t) - 1                      # intervals
    h = np.diff(t)
    D = np.diff(y, axis=0) / h[:, None]
    d = y.shape[1]
    if closed:
        A = np.zeros((n, n))
        rhs = np.empty((n, d))
        for i in range(n):
            hp, hi = h[i - 1], h[i]     # h[-1] is the last interval: the wrap-around
            A[i, i - 1] += hp
            A[i, i] += 2 * (hp + hi)
            A[i, (i + 1) % n] += hi
            rhs[i] = 6 * (D[i] - D[i - 1])
        M = np.linalg.solve(A, rhs)
        return np.vstack([M, M[:1]])
    ab = np.zeros((3, n + 1))           # banded storage: super-, main and sub-diagonal
    rhs = np.zeros((n + 1, d))
    ab[1, 1:n] = 2 * (h[:-1] + h[1:])
    ab[0, 2:] = h[1:]
    ab[2, :n - 1] = h[:-1]
    rhs[1:n] = 6 * (D[1:] - D[:-1])
    if end is None:                     # natural
        ab[1, 0] = ab[1, n] = 1.0
    else:
        v0, vn = end
        ab[1, 0], ab[0, 1], rhs[0] = 2 * h[0], h[0], 6 * (D[0] - v0)
        ab[1, n], ab[2, n - 1], rhs[n] = 2 * h[-1], h[-1], 6 * (vn - D[-1])
    return sla.solve_banded((1, 1), ab, rhs)


class SplineFunction:
    r"""A cubic spline curve through data points (Mech's ``SplineFunction``, made by
    :func:`SplineFit`); ``SplineFunction(data, ...)`` takes the same arguments as ``SplineFit``.

    The spline interpolates the points ``data[i]`` at the knots ``knots[i]`` (default
    ``0, 1, 2, ...``: the argument 0 gives the first point, 1 the second, as in Mech); it is
    a cubic polynomial between knots, with continuous value, slope and curvature (C2).

    * ``s(u)`` with a number or an array ``u``: the points, shape ``(d,)`` / ``(len(u), d)``
      (a scalar spline, made from one value per knot, gives ``()`` / ``(len(u),)``).
    * ``s(u)`` with a SymPy expression: a tuple of ``d`` exact SymPy expressions (one, not a
      tuple, for a scalar spline), to put into a body point: ``cam.point(s(a))``.
    * ``s.derivative(u, order)``: numeric derivatives with respect to the parameter.

    Outside ``[knots[0], knots[-1]]`` a *periodic* spline (closed, first point equal to the
    last) repeats with period ``knots[-1] - knots[0]``, so a cam parameter may run over several
    revolutions; any other spline continues with its end polynomials.
    """

    def __init__(self, data, end_conditions="natural", knots=None):
        y = _as_float_array(data, "the data points")
        self.scalar = y.ndim == 1
        if self.scalar:
            y = y[:, None]
        if y.ndim != 2 or y.shape[1] == 0:
            raise ModelError(f"SplineFit: data must be a list of numbers or of points (vectors of "
                             f"equal length), got an array of shape {y.shape}")
        n = len(y)
        closed, end = self._end(end_conditions, y)
        need = 3 if closed else 2
        if n < need:
            raise ModelError(f"SplineFit: a {'closed' if closed else 'open'} spline needs at "
                             f"least {need} data points, got {n}")
        if knots is None:
            t = np.arange(n, dtype=float)
        else:
            t = _as_float_array(knots, "the knots")
            if t.shape != (n,):
                raise ModelError(f"SplineFit: knots must be one number per data point ({n}), got "
                                 f"shape {t.shape}")
            bad = np.flatnonzero(np.diff(t) <= 0)
            if bad.size:
                i = int(bad[0])
                raise ModelError(f"SplineFit: knots must be strictly increasing; knot {i + 1} = "
                                 f"{float(t[i + 1])!r} does not exceed knot {i} = {float(t[i])!r}")
        scale = max(float(np.max(np.abs(y))), 1.0)
        self.periodic = closed and bool(np.allclose(y[0], y[-1], rtol=0, atol=1e-12 * scale))
        if end_conditions == "periodic" and not self.periodic:
            raise ModelError(f"SplineFit: periodic data must end where it starts: the first point "
                             f"{y[0].tolist()} differs from the last {y[-1].tolist()} (use "
                             f"end_conditions='closed' for equal end slopes only, as Mech's Closed)")
        if self.periodic:
            y = y.copy()
            y[-1] = y[0]                # identical within rounding: make it exact
        M = _second_derivatives(t, y, end, closed)
        h = np.diff(t)[:, None]
        #: coefficients ``(4, n-1, d)`` of ``a0 + a1 h + a2 h^2 + a3 h^3`` per interval
        self.coefficients = np.stack([
            y[:-1],
            np.diff(y, axis=0) / h - h * (2 * M[:-1] + M[1:]) / 6,
            M[:-1] / 2,
            np.diff(M, axis=0) / (6 * h),
        ])
        self.knots = t
        self._points = y
        self.data = y[:, 0] if self.scalar else y
        self.closed = closed
        self.end_conditions = end_conditions if isinstance(end_conditions, str) else "directions"

    @staticmethod
    def _end(end_conditions, y):
        if isinstance(end_conditions, str):
            key = end_conditions.lower()
            if key not in END_CONDITIONS:
                choice(end_conditions, END_CONDITIONS, "SplineFit: end_conditions",
                       "or two direction vectors")
            return key != "natural", None
        v = _as_float_array(end_conditions, "the end direction vectors")
        d = y.shape[1]
        if v.shape not in ((2, d),) + (((2,),) if d == 1 else ()):
            raise ModelError(f"SplineFit: end_conditions as directions must be two vectors of "
                             f"dimension {d} (start and end tangents), got shape {v.shape}")
        v = v.reshape(2, d)
        return False, (v[0], v[1])

    # -- properties ------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        return int(self.coefficients.shape[2])

    @property
    def domain(self) -> tuple[float, float]:
        """The parameter range ``(knots[0], knots[-1])`` of the data."""
        return float(self.knots[0]), float(self.knots[-1])

    @property
    def period(self) -> float:
        return float(self.knots[-1] - self.knots[0])

    def __repr__(self) -> str:
        kind = "periodic" if self.periodic else self.end_conditions
        return (f"SplineFunction(Cubic, {self.dim}D, {len(self.knots)} points, {kind}, "
                f"domain={self.domain})")

    # -- numeric evaluation ----------------------------------------------------------------
    def _locate(self, u):
        u = np.asarray(u, dtype=float)
        t = self.knots
        if self.periodic:               # reduce only what lies outside: knots stay exact
            u = np.where((u < t[0]) | (u > t[-1]), t[0] + np.mod(u - t[0], self.period), u)
        k = np.clip(np.searchsorted(t, u, side="right") - 1, 0, len(t) - 2)
        return u - t[k], k

    def derivative(self, u, order: int = 1):
        """The ``order``-th derivative (0..3) with respect to the parameter at number(s) ``u``
        (numeric; inside a model the derivatives are derived from the symbolic form)."""
        if isinstance(u, sp.Basic) and not u.is_number:
            raise ModelError("SplineFunction.derivative evaluates numbers; for a symbolic "
                             "argument use s(u), whose expressions mechsys differentiates exactly")
        if order not in (0, 1, 2, 3):
            raise ModelError(f"SplineFunction.derivative: order must be 0, 1, 2 or 3, got {order!r}")
        h, k = self._locate(u)
        c = self.coefficients[:, k]     # (4, ..., d)
        h = np.asarray(h)[..., None]
        if order == 0:
            out = c[0] + h * (c[1] + h * (c[2] + h * c[3]))
            # the last knot lies at the far end of the last interval: return its point exactly
            last = np.asarray(u) == self.knots[-1]
            if np.any(last):
                out = np.where(last[..., None], self._points[-1], out)
        elif order == 1:
            out = c[1] + h * (2 * c[2] + h * 3 * c[3])
        elif order == 2:
            out = 2 * c[2] + 6 * h * c[3]
        else:
            out = 6 * c[3] + 0 * h
        return out[..., 0] if self.scalar else out

    def __call__(self, u):
        if isinstance(u, sp.Basic) and not u.is_number:
            ex = self._exprs(u)
            return ex[0] if self.scalar else ex
        return self.derivative(u, 0)

    # -- symbolic form ---------------------------------------------------------------------
    def _exprs(self, u) -> tuple:
        u = sp.sympify(u)
        t = self.knots
        if self.periodic:
            # w = u reduced into [t0, tn): floor's derivative is zero wherever it is defined
            P = sp.Float(self.period)
            w = u - P * sp.floor((u - sp.Float(t[0])) / P)
        else:
            w = u
        return tuple(self._bisect(w, 0, len(t) - 1, j) for j in range(self.dim))

    def _bisect(self, w, lo: int, hi: int, j: int):
        """Piecewise over intervals ``lo..hi-1``, split at the middle knot (binary search)."""
        if hi - lo == 1:
            a0, a1, a2, a3 = (sp.Float(float(c)) for c in self.coefficients[:, lo, j])
            h = w - sp.Float(float(self.knots[lo]))
            return a0 + h * (a1 + h * (a2 + h * a3))
        mid = (lo + hi) // 2
        return sp.Piecewise((self._bisect(w, lo, mid, j), w < sp.Float(float(self.knots[mid]))),
                            (self._bisect(w, mid, hi, j), True))


def SplineFit(data, end_conditions="natural", knots=None) -> SplineFunction:  # noqa: N802 - Mech's name
    r"""A cubic interpolating spline through ``data`` (Mech's ``SplineFit``).

    ``data``: a list of points (2D, 3D or any dimension), or a list of numbers for a scalar
    function such as a cam's radius ``r(alpha)``.
    ``end_conditions`` (Mech's ``EndConditions``):

    * ``"natural"`` (default): zero curvature, :math:`s'' = 0`, at both ends;
    * ``"closed"``: equal slope and curvature at the two ends. As in Mech, the curve closes
      upon itself only when the last point is identical to the first; it then repeats beyond
      its knots (a closed cam profile);
    * ``"periodic"``: ``"closed"``, but points that do not close raise :class:`ModelError`;
    * two vectors ``(v0, v1)``: the tangents ``ds/du`` at the start and the end (magnitude
      and direction both count).

    ``knots``: the parameter value at each point, strictly increasing (Mech's values of the
    independent variable at each knot); default ``0, 1, ..., n-1``.

    Example, a closed cam profile from its radius at 37 angles::

        a = np.linspace(0, 2*np.pi, 37)
        r = ms.SplineFit(3 + np.sin(a)**2, "closed", knots=a)
        th = sp.Symbol("th")
        cam.point((r(th)*sp.cos(th), r(th)*sp.sin(th)))
    """
    return SplineFunction(data, end_conditions, knots)


def Involute(sym, center: Sequence, base_radius, pitch_radius, angle,  # noqa: N802 - Mech's name
             interference: bool = False) -> tuple[sp.Expr, sp.Expr]:
    r"""The involute gear-tooth profile ``(x, y)`` as SymPy expressions of ``sym`` (Mech's
    ``Involute[sym, {x, y}, baseradius, pitchradius, angle]``).

    With :math:`u` = ``sym``, :math:`r_b` the base radius, :math:`r_p` the pitch radius and
    :math:`s = \operatorname{sign}(r_p)` (a negative pitch radius makes the profile spiral
    clockwise):

    .. math::

        P(u) = c + \operatorname{Rot}(\beta)\, r_b\, (\cos u + u \sin u,\;
        s\, (\sin u - u \cos u))

    (:math:`c` = ``center``). The profile starts on the base circle at :math:`u = 0` and
    crosses the pitch circle :math:`\lvert P - c \rvert = r_p` at
    :math:`u_p = \sqrt{r_p^2 / r_b^2 - 1}`; :math:`\beta = \mathit{angle} - s\, \phi_p` with
    :math:`\phi_p = u_p - \arctan u_p` (the involute function of the pressure angle) puts
    that pitch point on the ray from ``center`` at ``angle``.

    For ``u < 0`` the natural equation gives the mirror image of the tooth; with
    ``interference=True`` the profile instead runs straight from the base circle to the
    center, :math:`P(u) = \mathit{center} + r_b (1 + u) (\cos \beta, \sin \beta)` for ``-1 <= u < 0``.
    ``base_radius`` and ``pitch_radius`` may be numbers or symbolic parameters; numbers are
    checked (``rb > 0``, ``|rp| >= rb``).
    """
    u = sp.sympify(sym)
    rb, rp = sp.sympify(base_radius), sp.sympify(pitch_radius)
    if rb.is_number:
        if not rb.is_real or not rb > 0:
            raise ModelError(f"Involute: the base radius must be positive, got {base_radius!r}")
    if rp.is_number:
        if not rp.is_real or rp.is_zero:
            raise ModelError(f"Involute: the pitch radius must be a nonzero number (negative for a "
                             f"clockwise profile), got {pitch_radius!r}")
        if rb.is_number and abs(rp) < rb:
            raise ModelError(f"Involute: the pitch radius {pitch_radius!r} is smaller than the base "
                             f"radius {base_radius!r}: the involute lies outside its base circle")
    try:
        cx, cy = (sp.sympify(c) for c in center)
    except (TypeError, ValueError):
        raise ModelError(f"Involute: center must be a 2D point (x, y), got {center!r}") from None
    s = sp.sign(rp) if not rp.is_number else (1 if rp > 0 else -1)
    arp = abs(rp) if rp.is_number else sp.Abs(rp)
    up = sp.sqrt(arp**2 / rb**2 - 1)
    beta = sp.sympify(angle) - s * (up - sp.atan(up))
    px = rb * (sp.cos(u) + u * sp.sin(u))
    py = s * rb * (sp.sin(u) - u * sp.cos(u))
    cb, sb = sp.cos(beta), sp.sin(beta)
    x = cx + cb * px - sb * py
    y = cy + sb * px + cb * py
    if interference:
        x = sp.Piecewise((x, u >= 0), (cx + rb * (1 + u) * cb, True))
        y = sp.Piecewise((y, u >= 0), (cy + rb * (1 + u) * sb, True))
    return x, y
