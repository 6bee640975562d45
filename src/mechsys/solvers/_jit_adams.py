r"""Mech's Adams integrator (``SolveFree``'s default), its step written once.

A step of degree :math:`d = \min(k, n_h - 1)` (``k`` the fit degree, :math:`n_h` the stored
derivative values) from :math:`(t, y)` with step :math:`h`:

.. math::

    y_p = y + \sum_{i=0}^{d} w_i f_{n_h - d - 1 + i}, \qquad
    y_c = y + \sum_{i=0}^{d'-1} w'_i f_{n_h - d' + i} + w'_{d'} f(t + h, y_p),

the weights integrating over :math:`[t, t + h]` the polynomial through the nodes (the
predictor: the last :math:`d + 1` values; the corrector: the last :math:`d' = \max(d, 1)`
and the prediction's), :math:`w = h V^{-T} (1, 1/2, \ldots)` with :math:`V_{ij} = x_i^j`,
:math:`x_i = (t_i - t) / h`. The error :math:`e = \max_j |y_{c,j} - y_{p,j}| / s_j` decides
(``max_error`` :math:`(a, b, c)`): :math:`e > a` halves the step and tries again; else the
corrected value (:math:`e > b`, or the corrector mode) or the predicted one is taken; the
step doubles when the last :math:`2k` errors are all below :math:`c` (decision 0022).

Each function below is one part of that step; both drivers call them: the compiled loop
(``_jit_free_loop.adams``, with the compiled derivative, the parts inlined) and
``_integrators.integrate_adams`` (the Python derivative: a first session's steps, and the
steps after a hand-over at a singular instant), which runs these same functions interpreted
(``_jit_interp``). The drivers keep the run's scalars (the time ``t``, the step ``h`` to try
next, the count ``nh`` of stored derivative values, the count ``nrec`` of kept errors, the
rejected steps) and hand them to each other with the arrays, which the parts update in
place: ``hist_t`` (6,), ``hist_f`` (6, N) the stored derivative values (the last 6) and
their times; ``recent`` (8,) the errors of the last accepted steps (the last ``2k``);
``V`` (6, 6), ``w`` (6,), ``nodes`` (6,), ``piv`` (6,) int32: work; ``cache`` (13,) per fit
(the predictor's and the corrector's): the last nodes and weights.

Example (a driver's step, ``f`` the derivative)::

    code, h_try = predict(t, h, nh, t1, sign, k, y, hist_t, hist_f, V, w, cache_p, piv, y_pred)
    f_pred = f(t + h_try, y_pred)
    code, err = correct(t, h_try, nh, k, a, b, fixed, method, y, hist_t, hist_f, y_pred,
                        f_pred, inv_scale, V, w, nodes, cache_c, piv, y_corr, f_new)
    if code == REJECTED:
        h = h_try / 2                       # and try again
    if code == CORRECTED:
        f_new = f(t + h_try, y_corr)
    t = t + h_try
    nh, nrec, h = commit(t, h, err, nh, nrec, 2 * k, c, fixed, y, hist_t, hist_f, y_corr,
                         f_new, recent)
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ._jit_lapack import getrf, getrs, leaf

#: the step's parts are inlined into the compiled loop (Numba's IR inlining), so that it
#: keeps its scalars in registers and its arrays' layout known, as one function
step = nb.njit(cache=True, inline="always")

#: :func:`predict`: the prediction is made; :func:`correct`: the predicted value is taken
#: (``y_corr``, ``f_new`` hold it and its derivative)
OK = 0
#: :func:`correct`: the corrected value is taken (``y_corr``); its derivative is the
#: driver's to evaluate into ``f_new``
CORRECTED = 1
#: :func:`correct`: the error exceeded ``a``; the driver halves the step and tries again
REJECTED = 2
#: the step cannot go on here: a step of zero in the stored time (:func:`predict`), a
#: singular fit, a non-finite error, or an error above ``a`` where half the step is below
#: the time's resolution (:func:`correct`). The compiled loop hands the step to the Python
#: driver, which raises (:data:`SHORT`) or evaluates again with its own derivative
SHORT, SINGULAR, NONFINITE, TOO_SMALL = 3, 4, 5, 6


@leaf
def weights(times, off, cnt, t_from, h, V, w, cache, piv):
    """``w[:cnt]``: the weights of the nodes ``times[off:off + cnt]`` over ``[t_from, t_from
    + h]`` (module docstring), the scaled nodes rounded to 1e-9 so that constant steps give
    the same weights (an offset rather than a slice: a view per call cost a sixth of the
    compiled step). ``cache`` (13,): the last call's node count, nodes and unscaled weights
    (``cache[0]`` count, nodes at 1..6, weights at 7..12): while the step is constant the
    nodes repeat. False where ``V`` is singular (coincident nodes)."""
    same = cache[0] == cnt
    for i in range(cnt):
        # np.round(v, 9) as Numba computes it (v * 1e9, rint, / 1e9), without its pow call
        x = np.rint((times[off + i] - t_from) / h * 1e9) / 1e9
        if x != cache[1 + i]:
            same = False
            cache[1 + i] = x
    if same:
        for j in range(cnt):
            w[j] = cache[7 + j] * h
        return True
    cache[0] = cnt
    for i in range(cnt):
        x = cache[1 + i]
        p = 1.0
        for j in range(cnt):
            V[i, j] = p            # V[i, j] = x_i^j; V holds (V^T) transposed
            p *= x
    for j in range(cnt):
        w[j] = 1.0 / (j + 1)
    if getrf(V[:cnt, :cnt], cnt, piv) > 0:
        cache[0] = -1.0
        return False
    getrs(V[:cnt, :cnt], cnt, piv, w)
    for j in range(cnt):
        cache[7 + j] = w[j]
        w[j] *= h
    return True


@step
def predict(t, h, nh, t1, sign, k, y, hist_t, hist_f, V, w, cache, piv, y_pred):
    """``(code, h_try)``: the step to try from ``t`` (``h``, shortened to end at ``t1``; the
    step the stored time takes: far from t = 0 the sum ``t + h`` rounds, and the fits
    integrate over the interval the new time closes), and the prediction ``y_pred`` (N,)
    from the ``nh`` stored values. ``code``: :data:`OK`, :data:`SHORT` (the step does not
    advance the stored time) or :data:`SINGULAR`."""
    h_try = h if (t + h - t1) * sign <= 0 else t1 - t
    h_try = (t + h_try) - t
    if h_try == 0:
        return SHORT, h_try
    deg = min(k, nh - 1)
    p0 = nh - (deg + 1)
    if not weights(hist_t, p0, deg + 1, t, h_try, V, w, cache, piv):
        return SINGULAR, h_try
    for j in range(y_pred.size):
        acc = 0.0
        for i in range(deg + 1):
            acc += w[i] * hist_f[p0 + i, j]
        y_pred[j] = y[j] + acc
    return OK, h_try


@step
def correct(t, h_try, nh, k, a, b, fixed, method, y, hist_t, hist_f, y_pred, f_pred,
            inv_scale, V, w, nodes, cache, piv, y_corr, f_new):
    """``(code, err)``: the correction ``y_corr`` of the step :func:`predict` made
    (``f_pred`` its derivative) and its error, judged. ``method``: 0 automatic, 1 predictor,
    2 corrector; ``fixed``: a constant step (no rejection). ``code``: :data:`OK` (the
    prediction is taken: copied into ``y_corr``, ``f_new``), :data:`CORRECTED`,
    :data:`REJECTED` (the driver halves the step and counts it), :data:`SINGULAR`,
    :data:`NONFINITE` or :data:`TOO_SMALL`."""
    deg = min(k, nh - 1)
    # the new point and the last deg values (two points at the start): the history rows
    # from c0 on, then the prediction's derivative (summed in that order)
    nc = deg + 1 if deg > 0 else 2
    c0 = nh - (nc - 1)
    for i in range(nc - 1):
        nodes[i] = hist_t[c0 + i]
    nodes[nc - 1] = t + h_try
    if not weights(nodes, 0, nc, t, h_try, V, w, cache, piv):
        return SINGULAR, 0.0
    err = 0.0
    for j in range(y_pred.size):
        acc = 0.0
        for i in range(nc - 1):
            acc += w[i] * hist_f[c0 + i, j]
        acc += w[nc - 1] * f_pred[j]
        y_corr[j] = y[j] + acc
        v = abs(y_corr[j] - y_pred[j]) * inv_scale[j]
        if not v <= err:
            err = v
    if not np.isfinite(err):
        return NONFINITE, err
    if not fixed and err > a:
        # (the shortest step: ten units of the last place of max(|t|, 1), as SciPy's)
        big = max(abs(t), 1.0)
        if abs(h_try) / 2 < 10.0 * (np.nextafter(big, np.inf) - big):
            return TOO_SMALL, err
        return REJECTED, err
    if method == 2 or (method == 0 and err > b):
        return CORRECTED, err
    for j in range(y_pred.size):
        y_corr[j] = y_pred[j]
        f_new[j] = f_pred[j]
    return OK, err


@step
def commit(t_new, h, err, nh, nrec, window, c, fixed, y, hist_t, hist_f, y_new, f_new, recent):
    """``(nh, nrec, h)`` after accepting the step to ``t_new``: the state ``y_new`` (copied
    into ``y``) and its derivative ``f_new`` into the history (the last 6 of the ``nh``
    values kept); its error ``err`` into ``recent`` (the last ``window`` of ``nrec``), the
    step ``h`` doubled when they are all below ``c`` (Mech's rule) unless ``fixed``."""
    for j in range(y.size):
        y[j] = y_new[j]
    if nh == 6:
        for i in range(5):
            hist_t[i] = hist_t[i + 1]
            for j in range(y.size):
                hist_f[i, j] = hist_f[i + 1, j]
        nh = 5
    hist_t[nh] = t_new
    for j in range(y.size):
        hist_f[nh, j] = f_new[j]
    nh += 1
    if nrec == window:
        for i in range(window - 1):
            recent[i] = recent[i + 1]
        nrec = window - 1
    recent[nrec] = err
    nrec += 1
    if not fixed and nrec >= window:
        big = 0.0
        for i in range(window):
            if recent[i] > big:
                big = recent[i]
        if big < c:
            h = 2 * h
            nrec = 0
    return nh, nrec, h
