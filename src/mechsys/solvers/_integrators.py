r"""Integrators for the equations of motion of a free system, ``y = (q, qd)``,
:math:`y' = (\dot q, \ddot q(t, q, \dot q))` with ``qdd`` from the augmented system.

Two families, selected by ``method``:

* ``"dop853"`` (default), ``"rk45"``: SciPy's explicit Runge-Kutta steppers with error
  control (``rtol``, ``atol``); after every accepted step the state is projected back
  onto the position and velocity constraints (``constraint_correction=True``, default),
  which keeps the index-1 formulation from drifting.
* ``"adams"``: Mech's ``SolveFree`` integrator. An adaptive multistep Adams-Bashforth
  predictor and Adams-Moulton corrector of degree ``fit_degree`` (1 linear ... 4 quartic)
  built by polynomial fits through the past derivative values at their actual times (so
  step changes need no restart). With ``max_error = (a, b, c)`` (a number ``e`` means
  ``(e, e/10, e/100)``) and the error :math:`\mathit{err} = \max \lvert y_{\mathrm{corrector}} -
  y_{\mathrm{predictor}} \rvert` of a step:

  - ``err > a``: reject, back up, halve the step;
  - ``b < err <= a``: accept the corrected (Adams-Moulton) value;
  - ``err <= b``: accept the predicted value (``method_adams="automatic"``);
  - the step doubles when the error of each of the last ``2 fit_degree`` steps (since the
    last change of the step size) is below ``c``: Mech's ``MaxError`` rule, "doubled if
    the maximum error in any of the last 2n steps drops below c, where n is the degree
    of the integrand fitting polynomial" (decision 0022).

  ``method_adams`` ``"predictor"`` never corrects, ``"corrector"`` always does; a constant
  ``step_size`` turns the adaptation off. ``constraint_correction`` projects after each step.

``starting_step_size`` (Mech's ``StartingStepSize``, "effective only if StepSize ->
Automatic") is the first step an adaptive run tries: the Adams step starts there and halves
or doubles by the rule above (default ``min(|t1 - t0| / 100, 1e-3)``); the Runge-Kutta
methods try it first and shrink it if its error is too large (default: SciPy's estimate from
the first derivatives). With a constant Adams ``step_size`` it is refused rather than ignored.

Options are checked up front by :func:`integration_options` (one place for free and path
systems): every option must apply to the chosen method, and ``max_error`` (Mech's accuracy
option) is honoured by every method. With the Runge-Kutta methods it becomes
``rtol = atol = max_error``: SciPy accepts a step when the (RMS) estimate of its local error
``e_i`` satisfies :math:`e_i \le \mathit{atol} + \mathit{rtol} \lvert y_i \rvert = \mathit{max\_error}\,
(1 + \lvert y_i \rvert)`, the same absolute
per-step budget as Adams' ``a`` for variables of order one (Mech's assumption) and relative
for large ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from numbers import Integral, Real

import numpy as np

from .._errors import MechError, ModelError, unknown_options
from . import _methods
from ._jit_free import PAUSE_STEPS

FIT_DEGREES = {"linear": 1, "quadratic": 2, "cubic": 3, "quartic": 4}


@dataclass
class IntegrationResult:
    """t (N,), y (N, 2n) states at accepted steps; evaluations of the derivative;
    diagnostics: per accepted step ``(t, h, err)``; ``rejected``: the rejected steps (None
    for an implicit method: SciPy does not report its rejected attempts)."""

    t: np.ndarray
    y: np.ndarray
    evaluations: int
    steps: int
    rejected: int | None
    message: str
    diagnostics: dict = field(default_factory=dict)


class _Rows:
    """Rows gathered one at a time (Python steps) or in blocks (the compiled stepper's
    arrays, kept as they are): ``array()`` joins them once at the end, so that long runs do
    not turn every compiled row into a Python object."""

    __slots__ = ("_blocks", "_n")

    def __init__(self, *rows):
        self._blocks, self._n = [], 0
        for r in rows:
            self.append(r)

    def append(self, row) -> None:
        self._blocks.append(np.asarray(row, dtype=float)[None].copy())
        self._n += 1

    def extend(self, block) -> None:
        if len(block):
            self._blocks.append(np.asarray(block, dtype=float))
            self._n += len(block)

    def __len__(self) -> int:
        return self._n

    def trim(self, n: int) -> None:
        """Keep the first ``n`` rows."""
        while self._n > n:
            last = self._blocks[-1]
            drop = min(len(last), self._n - n)
            self._blocks[-1] = last[:len(last) - drop]
            self._n -= drop
            if not len(self._blocks[-1]):
                self._blocks.pop()

    def array(self, width: int | None = None) -> np.ndarray:
        if not self._blocks:
            return np.empty((0,) if width is None else (0, width))
        return np.concatenate(self._blocks)


def integrate_rk(fun, project, t0, t1, y0, method="dop853", rtol=1e-8, atol=1e-10,
                 max_step=np.inf, first_step=None, correction=True,
                 t_eval=None, scale=None, kinked=None, monitor=None,
                 fast=None) -> IntegrationResult:
    """Explicit Runge-Kutta with projection after each accepted step. With ``t_eval``
    the states at those times come from each step's dense output (then projected).
    ``kinked()`` (optional), asked after each step: whether the derivative had a kink in it
    (a singular instant of free motion); the output times in such a step are then reached
    by integrating from the step's start to each of them (the dense output polynomial
    assumes a smooth derivative).
    ``scale`` (len(y0),): the unit of each component; the absolute tolerance of component
    ``i`` is ``atol * scale[i]``.
    ``fast`` (optional, DOP853 or RK45): a compiled stepper (:class:`._jit_free.FreeStepper`) that
    takes the regular steps of the same SciPy solver; after a handover this loop takes
    :data:`._jit_free.PAUSE_STEPS` steps itself. The accelerations and multipliers it
    computed come back in ``diagnostics["derivatives"]``: ``(qdd (rows, n), lam (rows, m))``
    per output row, NaN rows where the caller must evaluate them."""
    cls = stepper_class(method)
    implicit = _methods.get(method).implicit
    if implicit:
        fun, calls = counting(fun)
    if scale is not None:
        atol = atol * np.asarray(scale, dtype=float)
    # SciPy's set-up (first derivative, initial step) by the compiled derivative where it
    # can (the same numbers to rounding, a quarter of the time); the Python steps after
    # hand-overs by the Python derivative
    setup = [fast is not None]
    solver = cls(fun if fast is None else fast.fun(fun, setup), t0, np.array(y0, dtype=float),
                 t1, rtol=rtol, atol=atol, max_step=max_step, first_step=first_step)
    setup[0] = False
    ts, ys, hs = _Rows(t0), _Rows(solver.y), _Rows()
    extra = 0
    ev_t, ev_y = _Rows(), _Rows()
    te = None if t_eval is None else np.asarray(t_eval, dtype=float)
    ie = 0
    d = 1.0 if t1 >= t0 else -1.0          # direction: t_eval is ordered along it
    if te is not None:
        while ie < len(te) and (te[ie] - t0) * d <= 0:
            ev_t.append(te[ie])
            ev_y.append(solver.y.copy())
            ie += 1
    rejected = 0
    message = "finished"
    known = []        # blocks (first output row, qdd, lam) from the compiled stepper
    pause = 0
    try:
        while solver.status == "running":
            if fast is not None and pause == 0:
                status, T, Yc, H, QDD, LAM, ie_new, rej, proj = fast.advance(solver, ie)
                if te is not None:
                    known.append((len(ev_t), fast.EQDD[ie:ie_new], fast.ELAM[ie:ie_new]))
                    ev_t.extend(te[ie:ie_new].copy())
                    ev_y.extend(fast.EY[ie:ie_new].copy())
                    ie = ie_new
                else:
                    known.append((len(ts), QDD, LAM))
                ts.extend(T)
                ys.extend(Yc)
                hs.extend(H)
                rejected += rej
                extra += proj
                if len(T) and monitor is not None:
                    monitor(solver.t)
                if status == 2:        # handover: this loop takes the next steps
                    pause = PAUSE_STEPS
                continue
            pause = max(pause - 1, 0)
            before = solver.nfev
            t_prev, y_prev = solver.t, solver.y.copy()
            msg = solver.step()
            if solver.status == "failed":
                raise MechError(f"integration failed at t = {solver.t:.6g}: {msg}")
            # every attempt costs n_stages evaluations (FSAL); more than one attempt: rejections
            # (an implicit step's attempts are not visible: SciPy reports no count)
            if not implicit:
                rejected += max((solver.nfev - before) // solver.n_stages - 1, 0)
            kink = kinked() if kinked is not None else False
            if te is not None and ie < len(te) and (te[ie] - solver.t) * d <= 0:
                dense = solver.dense_output() if not kink else _restarted(
                    cls, fun, t_prev, y_prev, rtol, atol, max_step)
                while ie < len(te) and (te[ie] - solver.t) * d <= 0:
                    yi = dense(te[ie])
                    ev_t.append(te[ie])
                    ev_y.append(project(te[ie], yi) if correction else yi)
                    extra += 1 if correction else 0
                    ie += 1
            if correction:
                yp = project(solver.t, solver.y)
                # the stepper keeps the derivative at its current state (FSAL): refresh it
                # (solver.fun counts this evaluation in solver.nfev)
                solver.y = yp
                solver.f = solver.fun(solver.t, yp)
                extra += 1
            hs.append(solver.step_size)
            ts.append(solver.t)
            ys.append(solver.y)
            if monitor is not None:
                monitor(solver.t)
    except KeyboardInterrupt:
        # Ctrl-C: keep the steps accepted so far (an interrupted step is dropped whole: the
        # lists grow only after a step and its projection are complete)
        message = "interrupted"
        n_ok = min(len(ts), len(ys))
        ts.trim(n_ok)
        ys.trim(n_ok)
        n_ev = min(len(ev_t), len(ev_y))
        ev_t.trim(n_ev)
        ev_y.trim(n_ev)
    ts, ys = ts.array(), ys.array(len(y0))
    diag = {"step_size": hs.array(), "step_times": ts}
    if fast is not None:
        _compiled_derivatives(diag, fast, known, len(ev_t) if te is not None else len(ts))
    if te is not None:
        diag["t_eval"] = (ev_t.array(), ev_y.array(len(y0)))
    diag["projections"] = extra
    return IntegrationResult(ts, ys, calls[0] if implicit else solver.nfev, len(ts) - 1,
                             None if implicit else rejected, message, diag)


def _compiled_derivatives(diag, fast, known, rows) -> None:
    """``diag["derivatives"] = (qdd (rows, n), lam (rows, m + k))`` (k: velocity rows) from
    the compiled stepper's blocks ``(first row, qdd, lam)`` (NaN rows: evaluated by the
    caller), and the count of compiled steps."""
    QDD, LAM = np.full((rows, fast.n), np.nan), np.full((rows, fast.nl), np.nan)
    for k, qdd, lam in known:
        j = min(len(qdd), rows - k)     # Ctrl-C can leave a block beyond the rows kept
        if j > 0:
            QDD[k:k + j], LAM[k:k + j] = qdd[:j], lam[:j]
    diag["derivatives"] = (QDD, LAM)
    diag["compiled_steps"] = fast.steps
    diag["interpreted_steps"] = fast.interpreted_steps


def counting(fun):
    """``(fun', calls)``: ``fun`` counting its evaluations in ``calls[0]``. SciPy's ``nfev``
    leaves out the evaluations of an implicit method's finite-difference Jacobians (its
    ``fun_vectorized``), which cost as much as the others: the count of an implicit run is
    taken here."""
    calls = [0]

    def counted(t, y):
        calls[0] += 1
        return fun(t, y)
    return counted, calls


def _restarted(cls, fun, t0, y0, rtol, atol, max_step):
    """``y(te)`` by a fresh integration from ``(t0, y0)`` that ends at ``te``."""
    def at(te):
        if te == t0:
            return y0.copy()
        sub = cls(fun, t0, y0.copy(), te, rtol=rtol, atol=atol, max_step=max_step)
        while sub.status == "running":
            msg = sub.step()
            if sub.status == "failed":
                raise MechError(f"integration failed at t = {sub.t:.6g}: {msg}")
        return sub.y
    return at


def least_step(t: float) -> float:
    """The shortest step Mech's Adams integrator takes at time ``t``: ten units of the last
    place of ``max(|t|, 1)`` (SciPy's least step, with a floor near t = 0); the rule of
    ``_jit_adams.correct``."""
    m = max(abs(t), 1.0)
    return 10.0 * (np.nextafter(m, np.inf) - m)


def integrate_adams(fun, project, t0, t1, y0, fit_degree="cubic", max_error=1e-4,
                    method="automatic", step_size=None, correction=False,
                    first_step=None, max_steps=2_000_000, scale=None,
                    monitor=None, fast=None) -> IntegrationResult:
    """Mech's adaptive Adams-Bashforth / Adams-Moulton integrator (see module doc): the
    steps of :mod:`._jit_adams` (written once; the compiled loop calls them too), here
    interpreted with the Python derivative ``fun``. ``scale`` (len(y0),): the unit of each
    component; the error estimate is ``max_i |y_corr_i - y_pred_i| / scale_i``. ``fast``:
    a compiled stepper (:meth:`._jit_free.FreeStepper.advance_adams`) that takes the regular
    steps from this loop's state, as in :func:`integrate_rk`: the two share the history
    arrays, so that each hands the run to the other as it is."""
    from . import _jit_adams as A
    from ._jit_interp import interpreted

    predict, correct, commit = (interpreted(f) for f in (A.predict, A.correct, A.commit))
    k = FIT_DEGREES[fit_degree] if isinstance(fit_degree, str) else int(fit_degree)
    if not 1 <= k <= 4:
        raise MechError("fit_degree must be Linear/Quadratic/Cubic/Quartic (1..4)")
    if np.ndim(max_error) == 0:
        a = float(max_error)
        a, b, c = a, a / 10, a / 100
    else:
        a, b, c = (float(v) for v in max_error)
    if method not in ("automatic", "predictor", "corrector"):
        raise MechError("method must be 'automatic', 'predictor' or 'corrector'")
    code = {"automatic": 0, "predictor": 1, "corrector": 2}[method]
    fixed = step_size is not None
    window = 2 * k           # Mech: the step doubles after 2n steps below c (n: the degree)
    span = t1 - t0
    h = step_size or first_step or min(abs(span) / 100, 1e-3)
    h = float(np.copysign(h, span))
    y = np.array(y0, dtype=float)
    N = len(y)
    inv = np.ascontiguousarray(np.broadcast_to(
        1.0 if scale is None else 1.0 / np.asarray(scale, dtype=float), (N,)), dtype=float)
    t, nh, nrec, rejected = float(t0), 1, 0, 0
    hist_t, hist_f, recent = np.zeros(6), np.zeros((6, N)), np.zeros(8)
    hist_t[0] = t
    hist_f[0] = fun(t, y.copy())
    nfev = 1
    V, w, nodes, piv = np.empty((6, 6)), np.empty(6), np.empty(6), np.empty(6, dtype=np.int32)
    cache_p, cache_c = np.full(13, -1.0), np.full(13, -1.0)
    y_pred, f_pred, y_corr, f_new = (np.empty(N) for _ in range(4))
    sign = 1.0 if span >= 0 else -1.0
    end = 1e-14 * max(1.0, abs(t1))
    ts, ys, steps_h, steps_e = _Rows(t0), _Rows(y), _Rows(), _Rows()
    message = "finished"
    known = []        # blocks (first row, qdd, lam) from the compiled stepper
    pause = 0
    options = (k, (a, b, c), code, fixed, inv, t1)
    try:
        while (t1 - t) * sign > end:
            if len(ts) > max_steps:
                raise MechError(f"adams: more than {max_steps} steps; loosen max_error")
            if fast is not None and pause == 0:
                state = np.array([t, h, nh, nrec, rejected], dtype=float)
                status, T, Yc, H, E, QDD, LAM, ev, proj = fast.advance_adams(
                    state, y, hist_t, hist_f, recent, options)
                nfev += ev
                if len(T):
                    known.append((len(ts), QDD, LAM))
                    ts.extend(T)
                    ys.extend(Yc)
                    steps_h.extend(H)
                    steps_e.extend(E)
                    t, h, nh, nrec, rejected = (float(state[0]), float(state[1]),
                                                int(state[2]), int(state[3]), int(state[4]))
                    if monitor is not None:
                        monitor(t)
                if status == 2:        # handover: this loop takes the next steps
                    pause = PAUSE_STEPS
                continue
            pause = max(pause - 1, 0)
            got, h_try = predict(t, h, nh, t1, sign, k, y, hist_t, hist_f, V, w, cache_p, piv,
                                 y_pred)
            if got == A.SHORT:
                raise ModelError(f"adams: at t = {t:g} a step of {h:g} does not advance the "
                                 "time; give a larger starting_step_size or step_size, or "
                                 "measure time from a nearer origin")
            if got != A.OK:
                raise MechError(f"adams: at t = {t:.10g} the fit through the last derivative "
                                "values is singular (their times coincide)")
            t_new = t + h_try
            f_pred[:] = fun(t_new, y_pred.copy())
            nfev += 1
            got, err = correct(t, h_try, nh, k, a, b, fixed, code, y, hist_t, hist_f, y_pred,
                               f_pred, inv, V, w, nodes, cache_c, piv, y_corr, f_new)
            if got == A.REJECTED:
                h = h_try / 2
                rejected += 1
                continue
            if got == A.TOO_SMALL:
                # (the step cannot shrink further: accepting it would break max_error silently)
                raise MechError(f"adams: at t = {t:.10g} the error {err:.3g} of a step of "
                                f"{abs(h_try):.3g} exceeds max_error {a:g}, and half that step "
                                f"would be below the time's resolution there "
                                f"({least_step(t):.3g}); loosen max_error, or measure time "
                                "from a nearer origin")
            if got == A.NONFINITE:
                raise MechError(f"adams: at t = {t:.10g} the error of a step of "
                                f"{abs(h_try):.3g} is not finite: the derivative is NaN or "
                                "infinite there (check the loads and the model's singular "
                                "positions)")
            if got == A.SINGULAR:
                raise MechError(f"adams: at t = {t:.10g} the corrector's fit is singular "
                                "(the step is below the times' resolution)")
            if got == A.CORRECTED:
                f_new[:] = fun(t_new, y_corr.copy())
                nfev += 1
            if correction:
                y_corr[:] = project(t_new, y_corr.copy())
                f_new[:] = fun(t_new, y_corr.copy())
                nfev += 1
            t = t_new
            nh, nrec, h = commit(t, h, err, nh, nrec, window, c, fixed, y, hist_t, hist_f, y_corr,
                                 f_new, recent)
            ts.append(t)
            ys.append(y)
            steps_h.append(h_try)
            steps_e.append(err)
            if monitor is not None:
                monitor(t)
    except KeyboardInterrupt:
        # Ctrl-C: keep the steps accepted so far (see integrate_rk)
        message = "interrupted"
        n_ok = min(len(ts), len(ys))
        ts.trim(n_ok)
        ys.trim(n_ok)
    diag = {"step_size": steps_h.array(), "max_error": steps_e.array()}
    if fast is not None:
        _compiled_derivatives(diag, fast, known, len(ts))
    return IntegrationResult(ts.array(), ys.array(N), nfev, len(ts) - 1, rejected, message, diag)


#: the spellings of each family (from the registry, ``_methods``)
RK_METHODS = _methods.family_names("runge_kutta")
ADAMS_METHODS = _methods.family_names("adams")
_RTOL_MIN = 100 * np.finfo(float).eps         # SciPy raises smaller rtol to this silently


class _Default(float):
    """A default option value: equal to the number (signatures and docs show it), but
    recognisable by identity, so that an option the caller did not give is told from one
    given with the same value."""


class _DefaultStr(str):
    """A default string option, recognisable by identity (see :class:`_Default`)."""


RTOL, ATOL, MAX_STEP, MAX_ERROR = _Default(1e-8), _Default(1e-10), _Default(np.inf), _Default(1e-4)
FIT_DEGREE = _DefaultStr("cubic")


def _given(value, default) -> bool:
    return value is not default and value is not None


@dataclass(frozen=True)
class IntegrationOptions:
    """Checked integration options. ``method`` is ``"dop853"``, ``"rk45"``, or an Adams mode
    (``"automatic"``, ``"predictor"``, ``"corrector"``; ``name`` keeps the caller's spelling);
    ``rtol``/``atol``/``max_step`` for Runge-Kutta; ``degree``/``max_error`` ``(a, b, c)``/
    ``step_size`` for Adams; ``correction`` the projection after each step; ``first_step``
    the adaptive run's first step (``starting_step_size``; None: the method's own choice)."""

    name: str
    method: str
    rtol: float = 1e-8
    atol: float = 1e-10
    max_step: float = np.inf
    degree: int = 3
    max_error: tuple = (1e-4, 1e-5, 1e-6)
    step_size: float | None = None
    correction: bool = True
    first_step: float | None = None

    @property
    def spec(self) -> _methods.Method:
        """The method's registry entry."""
        return _methods.get(self.method)

    @property
    def runge_kutta(self) -> bool:
        return self.spec.runge_kutta


def stepper_class(method: str):
    """The SciPy stepper class (public ``scipy.integrate``) of a Runge-Kutta method's Python
    path, from the registry."""
    # Imported here, not at module level: scipy.integrate (with the scipy.optimize it pulls in)
    # costs ~0.3 s, and a user who only solves kinematics or inverse dynamics never steps an ODE
    # (decision 0061; tests/test_import_cost.py guards it).
    import scipy.integrate

    return getattr(scipy.integrate, _methods.get(method).scipy)


def _positive(name, value, allow_inf=False) -> float:
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ModelError(f"{name} must be a positive number, got {value!r}")
    v = float(value)
    if not (v > 0 and (np.isfinite(v) or (allow_inf and v == np.inf))):
        raise ModelError(f"{name} must be a positive{'' if allow_inf else ', finite'} number, "
                         f"got {value!r}")
    return v


def _max_error(value, runge_kutta: bool) -> tuple:
    if np.ndim(value) == 0:
        a = _positive("max_error", value)
        return a, a / 10, a / 100
    if runge_kutta:
        raise ModelError("max_error=(a, b, c) sets the Adams integrator's step thresholds; with "
                         "a Runge-Kutta method give one number (the per-step error budget)")
    vals = list(value) if isinstance(value, (list, tuple, np.ndarray)) else []
    if len(vals) != 3:
        raise ModelError(f"max_error must be a number or (a, b, c), got {value!r}")
    a, b, c = (_positive(f"max_error[{k}]", v) for k, v in enumerate(vals))
    if not c <= b <= a:
        raise ModelError(f"max_error=(a, b, c) needs c <= b <= a (halve above a, correct above "
                         f"b, double below c), got {tuple(vals)}")
    return a, b, c


def integration_options(method="dop853", rtol=RTOL, atol=ATOL, max_step=MAX_STEP,
                        fit_degree=FIT_DEGREE, max_error=MAX_ERROR, step_size=None,
                        constraint_correction=True,
                        starting_step_size=None) -> IntegrationOptions:
    """Check the options of ``simulate`` against ``method`` and resolve them.

    Raises :class:`ModelError` for an unknown method, a value out of range, or an option
    that the method does not use (``fit_degree``/``step_size`` with Runge-Kutta;
    ``rtol``/``atol``/``max_step`` with Adams; ``max_error`` together with ``rtol``/``atol``).
    ``max_error`` with Runge-Kutta gives ``rtol = atol = max_error`` (module doc).
    ``starting_step_size``: positive and finite, refused with a constant Adams ``step_size``
    (it would be ignored); checked against the run's times by :func:`checked_steps`, which
    every ``simulate`` calls before it computes anything."""
    first = None if starting_step_size is None else _positive("starting_step_size",
                                                                starting_step_size)
    spec = _methods.get(method)          # (unknown: OptionError naming the closest method)
    m = method.lower()
    if not isinstance(constraint_correction, (bool, np.bool_)):
        raise ModelError(f"constraint_correction must be True or False, got "
                         f"{constraint_correction!r}")
    given = {k for k, v, d in (("rtol", rtol, RTOL), ("atol", atol, ATOL),
                               ("max_step", max_step, MAX_STEP), ("fit_degree", fit_degree, FIT_DEGREE),
                               ("step_size", step_size, None)) if _given(v, d)}
    if spec.runge_kutta:
        wrong = [k for k in ("fit_degree", "step_size") if k in given and k not in spec.options]
        if wrong:
            raise ModelError(f"{' and '.join(wrong)} apply only to the Adams integrator "
                             f"(method='adams'); method={method!r} takes rtol, atol, max_step "
                             "or max_error")
        if _given(max_error, MAX_ERROR):
            both = [k for k, v, d in (("rtol", rtol, RTOL), ("atol", atol, ATOL)) if _given(v, d)]
            if both:
                raise ModelError(f"give either max_error or {' and '.join(both)}: with method="
                                 f"{method!r} max_error sets rtol = atol = max_error")
            rtol = atol = _max_error(max_error, True)[0]
        rtol, atol = _positive("rtol", rtol), _positive("atol", atol)
        if rtol < _RTOL_MIN:
            raise ModelError(f"rtol={rtol:g} is below what double precision can meet "
                             f"({_RTOL_MIN:.1e}); use a larger rtol")
        return IntegrationOptions(method, m, rtol=rtol, atol=atol,
                                  max_step=_positive("max_step", max_step, allow_inf=True),
                                  correction=bool(constraint_correction), first_step=first)
    wrong = [k for k in ("rtol", "atol", "max_step") if k in given and k not in spec.options]
    if wrong:
        raise ModelError(f"{' and '.join(wrong)} apply only to the Runge-Kutta methods "
                         f"('dop853', 'rk45'); the Adams integrator takes max_error, fit_degree "
                         "and step_size")
    if isinstance(fit_degree, str) and fit_degree.lower() in FIT_DEGREES:
        degree = FIT_DEGREES[fit_degree.lower()]
    elif isinstance(fit_degree, Integral) and not isinstance(fit_degree, bool) and \
            1 <= fit_degree <= 4:
        degree = int(fit_degree)
    else:
        raise ModelError(f"fit_degree must be one of {list(FIT_DEGREES)} (or 1..4), got "
                         f"{fit_degree!r}")
    if step_size is not None:
        if isinstance(step_size, Real) and not isinstance(step_size, bool) and step_size <= 0:
            raise ModelError(f"step_size must be positive (the direction of integration comes "
                             f"from the times), got {step_size!r}")
        step_size = _positive("step_size", step_size)
        if first is not None:
            raise ModelError("starting_step_size is the first step of an adaptive run (Mech's "
                             "StartingStepSize, effective only with StepSize -> Automatic); "
                             f"step_size={step_size:g} fixes every step: give one of the two")
    return IntegrationOptions(method, spec.name, degree=degree,
                              max_error=_max_error(max_error, False), step_size=step_size,
                              correction=bool(constraint_correction), first_step=first)


def output_times(t) -> tuple[float, float, np.ndarray | None]:
    """``(t0, t1, t_eval)`` from ``simulate``'s ``t``: a tuple ``(t0, t1)`` (every accepted
    step, ``t_eval`` None) or an array of at least two output times. Times must be finite,
    and output times strictly monotonic (increasing, or decreasing to integrate backwards):
    unsorted times are rejected rather than sorted, so that ``sol.t`` is exactly ``t``."""
    if type(t) is tuple and len(t) == 2 and all(type(v) in _PLAIN for v in t):
        # (the common call, ``(t0, t1)`` in Python numbers: the checks below without NumPy,
        # a tenth of their cost; anything unusual takes the general path and its messages)
        t0, t1 = float(t[0]), float(t[1])
        if math.isfinite(t0) and math.isfinite(t1) and t1 - t0 != 0:
            return t0, t1, None
    if np.ndim(t) == 0:
        raise ModelError(f"simulate(t={t!r}): give the interval (t0, t1) or an array of output "
                         "times; for the state at one time use solve(t)")
    try:
        tt = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"simulate: the times must be numbers, got {t!r}") from None
    if tt.ndim != 1 or tt.size < 2:
        raise ModelError(f"simulate: give (t0, t1) or a 1-D array of at least two times, got "
                         f"shape {tt.shape}")
    if not np.all(np.isfinite(tt)):
        raise ModelError(f"simulate: the times must be finite, got {tt[~np.isfinite(tt)][:3]}")
    d = np.diff(tt)
    if isinstance(t, tuple) and len(tt) == 2:
        if d[0] == 0:
            raise ModelError(f"simulate: t0 and t1 are equal ({tt[0]:g}); nothing to integrate")
        return float(tt[0]), float(tt[1]), None
    if not (np.all(d > 0) or np.all(d < 0)):
        k = int(np.nonzero(d * np.sign(d[0] or 1.0) <= 0)[0][0]) if d[0] != 0 else 0
        raise ModelError(
            f"simulate: the output times must be strictly monotonic (increasing, or decreasing "
            f"to integrate backwards); t[{k}] = {tt[k]:g}, t[{k + 1}] = {tt[k + 1]:g}. "
            "Sort them (np.sort) or integrate each direction separately")
    return float(tt[0]), float(tt[-1]), tt


def checked_steps(opt: IntegrationOptions, t0: float, t1: float) -> None:
    """Check the given step lengths against the run's times ``[t0, t1]``: the first step
    (``starting_step_size``) and Adams' constant ``step_size`` must advance the time at
    ``t0`` and ``t1`` (at least :func:`least_step`: a shorter one leaves ``t + h == t`` and
    the Adams fit through equal times is singular), and the first step must fit in the
    interval and within ``max_step``. Raises :class:`ModelError`."""
    if opt.first_step is None and opt.step_size is None:
        return                                 # (nothing given to check)
    least = least_step(max(abs(t0), abs(t1)))
    for name, h in (("starting_step_size", opt.first_step), ("step_size", opt.step_size)):
        if h is not None and h < least:
            raise ModelError(f"{name}={h:g} does not advance the time: at t = "
                             f"{max(abs(t0), abs(t1)):g} a step must be at least {least:.3g} "
                             "(ten units of the last place of the time); give a longer step or "
                             "measure time from a nearer origin")
    h = opt.first_step
    if h is None:
        return
    if h > abs(t1 - t0):
        raise ModelError(f"starting_step_size={h:g} is longer than the interval "
                         f"[{t0:g}, {t1:g}] ({abs(t1 - t0):g}); give a smaller first step")
    if opt.runge_kutta and h > opt.max_step:
        raise ModelError(f"starting_step_size={h:g} exceeds max_step={opt.max_step:g}; give a "
                         "first step within max_step")


@dataclass(frozen=True)
class Run:
    """One ``simulate`` request, parsed once by :func:`plan_run`: the checked ``options``,
    the interval ``t0 -> t1`` and the output times ``t_eval`` (None: every accepted step)."""

    options: IntegrationOptions
    t0: float
    t1: float
    t_eval: np.ndarray | None


def reject_unknown(where: str, unknown: dict, known) -> None:
    """:class:`~mechsys.OptionError` naming the unknown options, the closest known one to
    each and the known ones (none: nothing)."""
    unknown_options(where, unknown, known)


#: the types of a time or step length that no unit conversion changes (exactly these, with
#: the defaults' marker type: any other subclass, e.g. ``bool``, takes the general path)
_PLAIN = (float, int, _Default)


def _plain(value) -> bool:
    """``value`` is None, a Python ``float`` or ``int``, or a tuple of them: nothing in it a
    unit conversion (``plan_run``'s ``to_numbers``) would change."""
    if value is None or type(value) in _PLAIN:
        return True
    return type(value) is tuple and all(v is None or type(v) in _PLAIN for v in value)


def plan_run(where: str, t, unknown: dict, known, method="dop853", rtol=RTOL, atol=ATOL,
             max_step=MAX_STEP, fit_degree=FIT_DEGREE, max_error=MAX_ERROR, step_size=None,
             constraint_correction=True, starting_step_size=None,
             dense_output: str | None = None, to_numbers=None) -> Run:
    """The protocol every ``simulate`` (free, switched, path, sensitivity) follows before it
    computes anything, in one place and in this order: (1) options not in ``known`` are
    refused (:func:`reject_unknown`); (2) ``method`` is looked up in the registry
    (``_methods``) and the integration options checked against it
    (:func:`integration_options`); ``dense_output``: the run needs a method with a dense
    output, the text says why (events); (3) the times ``t`` are parsed (:func:`output_times`);
    (4) the step lengths are checked against them (:func:`checked_steps`). Returns the
    :class:`Run` that :func:`integrate` takes, so ``t`` and the options are parsed once.
    ``to_numbers(value, what)``, when given, turns the times and step lengths given as pint
    quantities into numbers in the model's time unit first (decision 0043; the caller's, since
    the units belong to a model), so that NumPy never strips their unit."""
    reject_unknown(where, unknown, known)
    if to_numbers is not None and not all(map(_plain, (t, max_step, step_size,
                                                        starting_step_size))):
        t, max_step, step_size, starting_step_size = (
            to_numbers(v, f"{where}: {name}") for name, v in (
                ("t", t), ("max_step", max_step), ("step_size", step_size),
                ("starting_step_size", starting_step_size)))
    if dense_output is not None:
        spec = _methods.find(method)
        if spec is None or not spec.dense_output:
            ok = " or ".join(repr(n) for n, m in _methods.METHODS.items() if m.dense_output)
            raise ModelError(f"simulate(method={method!r}) {dense_output}; use method={ok}")
    opt = integration_options(method, rtol, atol, max_step, fit_degree, max_error, step_size,
                              constraint_correction, starting_step_size)
    t0, t1, t_eval = output_times(t)
    checked_steps(opt, t0, t1)
    return Run(opt, t0, t1, t_eval)


def integrate(fun, project, run: Run, y0, scale=None, kinked=None, monitor=None, fast=None):
    """Integrate ``y' = fun(t, y)`` as the :class:`Run` ``run`` asks (the dispatch shared by
    free, path and sensitivity runs, by the method's family in the registry). ``run.t_eval``
    None returns every accepted step; output times return those times (RK dense output, or
    cubic Hermite with ``fun`` at the Adams steps).
    ``scale`` (len(y0),): the unit of each component (the characteristic length for position
    coordinates and their rates, 1 for angles), so that absolute tolerances and
    ``max_error`` mean the same in any unit of length. Returns ``(times, Y, result,
    method)``. ``fast``: a compiled stepper for the Runge-Kutta path (:func:`integrate_rk`).
    ``monitor(t)`` is called after each accepted step (progress); a
    KeyboardInterrupt ends the integration with the steps so far (``result.message`` is
    ``"interrupted"``)."""
    opt, t0, t1, t_eval = run.options, run.t0, run.t1, run.t_eval
    if opt.runge_kutta:
        res = integrate_rk(fun, project, t0, t1, y0, opt.method, opt.rtol, opt.atol,
                           opt.max_step, opt.first_step, correction=opt.correction,
                           t_eval=t_eval, scale=scale, kinked=kinked, monitor=monitor,
                           fast=fast)
        times, Y = res.diagnostics["t_eval"] if t_eval is not None else (res.t, res.y)
    else:
        res = integrate_adams(fun, project, t0, t1, y0, opt.degree, opt.max_error, opt.method,
                              opt.step_size, opt.correction, first_step=opt.first_step,
                              scale=scale, monitor=monitor, fast=fast)
        times, Y = res.t, res.y
        if t_eval is not None and res.message == "interrupted":
            # only the output times the integration reached
            t_eval = t_eval[(t_eval - res.t[-1]) * np.sign(t1 - t0) <= 0]
        if t_eval is not None and len(times) < 2:
            times, Y = times[:1], Y[:1]          # interrupted before the first step: t0 only
        elif t_eval is not None:
            from scipy.interpolate import CubicHermiteSpline

            if t1 < t0:                      # backwards: interpolate on rising times
                times, Y = times[::-1], Y[::-1]
            # the derivatives at the steps: from the compiled stepper where it ran
            known = res.diagnostics.pop("derivatives", None)
            if known is not None and t1 < t0:
                known = (known[0][::-1], known[1][::-1])
            F = np.array([fast.rate(yk, known[0][i])
                          if known is not None and np.all(np.isfinite(known[0][i]))
                          else fun(tk, yk) for i, (tk, yk) in enumerate(zip(times, Y))])
            Y = CubicHermiteSpline(times, Y, F, axis=0)(t_eval)
            times = t_eval
    return np.asarray(times, dtype=float), np.asarray(Y), res, opt.name.lower()
