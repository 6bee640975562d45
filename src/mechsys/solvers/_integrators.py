r"""Integrators for the equations of motion of a free system, ``y = (q, qd)``,
``y' = (qd, qdd(t, q, qd))`` with ``qdd`` from the augmented system.

Two families, selected by ``method``:

* ``"dop853"`` (default), ``"rk45"``: SciPy's explicit Runge-Kutta steppers with error
  control (``rtol``, ``atol``); after every accepted step the state is projected back
  onto the position and velocity constraints (``constraint_correction=True``, default),
  which keeps the index-1 formulation from drifting.
* ``"adams"``: Mech's ``SolveFree`` integrator. An adaptive multistep Adams-Bashforth
  predictor and Adams-Moulton corrector of degree ``fit_degree`` (1 linear ... 4 quartic)
  built by polynomial fits through the past derivative values at their actual times (so
  step changes need no restart). With ``max_error = (a, b, c)`` (a number ``e`` means
  ``(e, e/10, e/100)``) and the error ``err = max |y_corrector - y_predictor|`` of a step:

  - ``err > a``: reject, back up, halve the step;
  - ``b < err <= a``: accept the corrected (Adams-Moulton) value;
  - ``err <= b``: accept the predicted value (``method_adams="automatic"``);
  - the step doubles when the sum of the errors of the last four steps is below ``c``.

  ``method_adams`` ``"predictor"`` never corrects, ``"corrector"`` always does; a constant
  ``step_size`` turns the adaptation off. ``constraint_correction`` projects after each step.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import DOP853, RK45

from .._errors import MechError

FIT_DEGREES = {"linear": 1, "quadratic": 2, "cubic": 3, "quartic": 4}


@dataclass
class IntegrationResult:
    """t (N,), y (N, 2n) states at accepted steps; evaluations of the derivative;
    diagnostics: per accepted step ``(t, h, err)`` and rejected-step count."""

    t: np.ndarray
    y: np.ndarray
    evaluations: int
    steps: int
    rejected: int
    message: str
    diagnostics: dict = field(default_factory=dict)


def integrate_rk(fun, project, t0, t1, y0, method="dop853", rtol=1e-8, atol=1e-10,
                 max_step=np.inf, first_step=None, correction=True,
                 t_eval=None) -> IntegrationResult:
    """Explicit Runge-Kutta with projection after each accepted step. With ``t_eval``
    the states at those times come from each step's dense output (then projected)."""
    cls = {"dop853": DOP853, "rk45": RK45}[method]
    solver = cls(fun, t0, np.array(y0, dtype=float), t1, rtol=rtol, atol=atol,
                 max_step=max_step, first_step=first_step)
    ts, ys, hs = [t0], [solver.y.copy()], []
    extra = 0
    ev_t, ev_y = [], []
    te = None if t_eval is None else np.asarray(t_eval, dtype=float)
    ie = 0
    d = 1.0 if t1 >= t0 else -1.0          # direction: t_eval is ordered along it
    if te is not None:
        while ie < len(te) and (te[ie] - t0) * d <= 0:
            ev_t.append(te[ie])
            ev_y.append(solver.y.copy())
            ie += 1
    rejected = 0
    while solver.status == "running":
        before = solver.nfev
        msg = solver.step()
        if solver.status == "failed":
            raise MechError(f"integration failed at t = {solver.t:.6g}: {msg}")
        # every attempt costs n_stages evaluations (FSAL); more than one attempt: rejections
        rejected += max((solver.nfev - before) // solver.n_stages - 1, 0)
        if te is not None and ie < len(te) and (te[ie] - solver.t) * d <= 0:
            dense = solver.dense_output()
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
        ys.append(solver.y.copy())
    diag = {"step_size": np.array(hs), "step_times": np.array(ts)}
    if te is not None:
        diag["t_eval"] = (np.array(ev_t), np.array(ev_y))
    diag["projections"] = extra
    return IntegrationResult(np.array(ts), np.array(ys), solver.nfev, len(ts) - 1, rejected,
                             "finished", diag)


def _adams_weights(times, t_from, h):
    """Weights w_i with  int_{t_from}^{t_from+h} P(s) ds = sum w_i f_i  for the polynomial
    P interpolating values at ``times`` (scaled by h for conditioning).

    The weights are ``h`` times those of the scaled nodes ``x = (times - t_from) / h``, which
    repeat while the step is constant (e.g. -3, -2, -1, 0): cached on ``x`` rounded to 1e-9
    (exact for the rounded nodes; a node moved by 1e-9 h changes the step by ~1e-9 h^2 f',
    far below any error budget, and constants stay exact)."""
    key = tuple(round((ti - t_from) / h, 9) for ti in times)
    w = _WEIGHTS.get(key)
    if w is None:
        k = len(key)
        V = np.vander(np.array(key), k, increasing=True)   # P = sum c_j ((s - t_from)/h)^j
        # c = V^-1 f  ->  integral = (1/(j+1)) . V^-1 f  ->  weights = V^-T (1/(j+1))
        w = np.linalg.solve(V.T, 1.0 / np.arange(1, k + 1))
        if len(_WEIGHTS) < 4096:
            _WEIGHTS[key] = w
    return h * w


_WEIGHTS: dict = {}


def integrate_adams(fun, project, t0, t1, y0, fit_degree="cubic", max_error=1e-4,
                    method="automatic", step_size=None, correction=False,
                    first_step=None, max_steps=2_000_000) -> IntegrationResult:
    """Mech's adaptive Adams-Bashforth / Adams-Moulton integrator (see module doc)."""
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
    span = t1 - t0
    h = step_size or first_step or min(abs(span) / 100, 1e-3)
    h = float(np.copysign(h, span))
    t, y = float(t0), np.array(y0, dtype=float)
    f = fun(t, y)
    nfev = 1
    hist_t, hist_f = [t], [f]
    ts, ys, steps_h, steps_e = [t], [y.copy()], [], []
    recent: list[float] = []
    rejected = 0
    while (t1 - t) * np.sign(span) > 1e-14 * max(1.0, abs(t1)):
        if len(ts) > max_steps:
            raise MechError(f"adams: more than {max_steps} steps; loosen max_error")
        h_try = h if (t + h - t1) * np.sign(span) <= 0 else t1 - t
        deg = min(k, len(hist_t) - 1)
        # predictor: fit through the last deg+1 derivative values
        pt, pf = hist_t[-(deg + 1):], hist_f[-(deg + 1):]
        w = _adams_weights(pt, t, h_try)
        y_pred = y + sum(wi * fi for wi, fi in zip(w, pf))
        f_pred = fun(t + h_try, y_pred)
        nfev += 1
        # corrector: fit through the new point and the last deg values (degree deg)
        ct = hist_t[-deg:] + [t + h_try] if deg > 0 else [t, t + h_try]
        cf = hist_f[-deg:] + [f_pred] if deg > 0 else [f, f_pred]
        wc = _adams_weights(ct, t, h_try)
        y_corr = y + sum(wi * fi for wi, fi in zip(wc, cf))
        err = float(np.abs(y_corr - y_pred).max())
        if step_size is None and err > a and abs(h_try) > 1e-14 * max(1.0, abs(t)):
            h = h_try / 2
            rejected += 1
            continue
        if method == "corrector" or (method == "automatic" and err > b):
            y_new = y_corr
            f_new = fun(t + h_try, y_new)
            nfev += 1
        else:
            y_new, f_new = y_pred, f_pred
        t = t + h_try
        if correction:
            y_new = project(t, y_new)
            f_new = fun(t, y_new)
            nfev += 1
        y = y_new
        hist_t.append(t)
        hist_f.append(f_new)
        if len(hist_t) > 6:
            hist_t, hist_f = hist_t[-6:], hist_f[-6:]
        ts.append(t)
        ys.append(y.copy())
        steps_h.append(h_try)
        steps_e.append(err)
        recent.append(err)
        if step_size is None and len(recent) >= 4 and sum(recent[-4:]) < c:
            h = 2 * h
            recent.clear()
    return IntegrationResult(np.array(ts), np.array(ys), nfev, len(ts) - 1, rejected, "finished",
                             {"step_size": np.array(steps_h), "max_error": np.array(steps_e)})


RK_METHODS = ("dop853", "rk45")
ADAMS_METHODS = ("adams", "automatic", "predictor", "corrector")


def integrate(fun, project, t, y0, method="dop853", rtol=1e-8, atol=1e-10, max_step=np.inf,
              fit_degree="cubic", max_error=1e-4, step_size=None, correction=True):
    """Integrate ``y' = fun(t, y)`` with the named method (the dispatch shared by free and
    path systems). ``t``: a tuple ``(t0, t1)`` returns every accepted step; an array returns
    those times (RK dense output, or cubic Hermite with ``fun`` at the Adams steps).
    Returns ``(times, Y, result, method)``."""
    tt = np.atleast_1d(np.asarray(t, dtype=float))
    t0, t1 = float(tt[0]), float(tt[-1])
    t_eval = tt if len(tt) > 2 or (len(tt) == 2 and not isinstance(t, tuple)) else None
    m = method.lower()
    if m in RK_METHODS:
        res = integrate_rk(fun, project, t0, t1, y0, m, rtol, atol, max_step,
                           correction=correction, t_eval=t_eval)
        times, Y = res.diagnostics["t_eval"] if t_eval is not None else (res.t, res.y)
    elif m in ADAMS_METHODS:
        mode = "automatic" if m == "adams" else m
        res = integrate_adams(fun, project, t0, t1, y0, fit_degree, max_error, mode, step_size,
                              correction)
        times, Y = res.t, res.y
        if t_eval is not None:
            from scipy.interpolate import CubicHermiteSpline

            if t1 < t0:                      # backwards: interpolate on rising times
                times, Y = times[::-1], Y[::-1]
            F = np.array([fun(tk, yk) for tk, yk in zip(times, Y)])
            Y = CubicHermiteSpline(times, Y, F, axis=0)(t_eval)
            times = t_eval
    else:
        raise MechError(f"unknown method {method!r}; choose from {RK_METHODS + ADAMS_METHODS}")
    return np.asarray(times, dtype=float), np.asarray(Y), res, m
