r"""Velocity, acceleration and kinematic sweeps of a fully constrained system.

Velocity :math:`\Phi_q \dot q = -\Phi_t`; acceleration :math:`\Phi_q \ddot q = \gamma`, both solved on the
unit-free scaled Jacobian (:class:`~mechsys.solvers._linalg.Scaling`), whose reciprocal
condition number ``rcond`` is the unit-invariant measure of closeness to a lock-up.

A sweep over times ``t_0 < t_1 < ...`` solves each position by Newton from a predictor of the
previous point, so it follows one assembly branch:

* the Taylor predictor :math:`q + \dot q\, dt + \ddot q\, dt^2 / 2` (as far as solved) when the previous
  point is well conditioned (``rcond >= RCOND_WARN``), with ``+ q3 dt^3 / 6 + q4 dt^4 / 24``
  when the two (three) points before are too: ``q3``, ``q4`` from the divided differences
  of their accelerations (``a = qdd[k-1, k-2]``, ``b = qdd[k-1, k-2, k-3]``:
  :math:`q_3 = a + b\, dt_{k-1}`, :math:`q_4 = 2 b`), an ``O(dt^5)`` prediction;
* the secant ``q_k + (q_k - q_{k-1}) dt_k / dt_{k-1}`` when it is not (and in location-only
  sweeps, which have no ``qd``): at and next to a
  toggle (lock-up) position ``qd`` and ``qdd`` are undefined or meaningless, and the secant
  continues the branch through the singular point with continuous angles (for a slider-crank
  driven at the piston through a dead centre: the crank keeps turning the same way);
* right after a first point that is nearly singular (no secant yet), the first-order step
  :math:`\dot q\, dt` shortened to turn at most ``ROTATION_START``: its direction, not its size, is
  meaningful there;
* the secant also replaces a Taylor prediction that moves a rotational coordinate by far
  more than the previous step did (``> ROTATION_SLACK + 4 |secant step|``).

Newton starts with chord steps on the previous point's velocity factorisation when that
point is well conditioned (:func:`~mechsys.solvers._position.solve_position`, decision 0020):
at fine sampling the predictor is within the tolerance and one chord step reaches rounding,
so a regular point factorises its Jacobian once, for the velocity and acceleration.

A point whose solved rotational coordinates lie more than ``ROTATION_JUMP`` (a quarter turn)
from the prediction is solved again from the previous point; if it still jumps, the sweep
stops with a :class:`ConvergenceError` naming the time: it never returns a jump by whole
turns. Points below ``RCOND_WARN`` raise one :class:`NearSingularWarning` naming the first.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sps

from .._errors import ConvergenceError, ModelError, SingularJacobianError
from . import _jit_runtime, _jit_sweep
from ._diagnostics import Stopped
from ._linalg import Scaling, rotation_indices
from ._position import PositionOptions, PositionResult, describe_singular, solve_position
from ._rank import continue_position, continue_rates
from ._tolerances import (
    RCOND_PENDING,
    RCOND_WARN,
    ROTATION_JUMP,
    ROTATION_SLACK,
    ROTATION_START,
    SPARSE_THRESHOLD,
    Singular,
)

ORDERS = {"location": 0, "velocity": 1, "acceleration": 2}

#: with a ``progress`` callback the compiled loop runs in chunks of about this many seconds
#: (the first of ``FIRST_CHUNK`` points), the callback called between them (decision 0039)
CHUNK_SECONDS = 0.1
FIRST_CHUNK = 64


def solve_velocity(system, t: float, q, p=None, scaling: Scaling | None = None) -> np.ndarray:
    r"""Velocities ``qd`` (n,) from :math:`\Phi_q \dot q = -\Phi_t` at ``(t, q)``."""
    sparse = system.n > SPARSE_THRESHOLD
    J, rhs = system.velocity_rhs(t, q, p, sparse)
    sc = scaling or Scaling.of(system, q, J)
    try:
        return sc.factor(J).solve(rhs)
    except Singular:
        raise describe_singular(system, J, t, q, "velocity solve", sc) from None


def solve_acceleration(system, t: float, q, qd, p=None, J=None,
                       scaling: Scaling | None = None) -> np.ndarray:
    r"""Accelerations ``qdd`` (n,) from :math:`\Phi_q \ddot q = \gamma` at ``(t, q, qd)``."""
    if J is None:
        J = system.jacobian(t, q, p, system.n > SPARSE_THRESHOLD)
    sc = scaling or Scaling.of(system, q, J)
    g = system.gamma_values(t, q, qd, p)
    try:
        return sc.factor(J).solve(g)
    except Singular:
        raise describe_singular(system, J, t, q, "acceleration solve", sc) from None


@dataclass(frozen=True)
class SweepResult:
    """Raw arrays of a sweep: t (N,), q/qd/qdd (N, n) (None when not solved),
    iterations (N,) Newton iterations per point, evaluations (total function calls),
    ``rcond`` (N,) the velocity factorisation's reciprocal condition estimate per point
    (None below ``order`` 1).

    ``rcond_raw`` may hold ``RCOND_PENDING`` entries (a compiled sweep proved them to be at
    least ``RCOND_WARN`` and left them for later); ``fill(rcond_raw)`` computes them in
    place. Reading ``rcond`` does that first: the estimate is computed once, on demand.
    ``scaling``: the sweep's :class:`~mechsys.solvers._linalg.Scaling` (the multiplier solves
    over the sweep use it too), or None."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray | None
    qdd: np.ndarray | None
    iterations: np.ndarray
    evaluations: int
    order: int
    rcond_raw: np.ndarray | None = None
    fill: Callable[[np.ndarray], None] | None = field(default=None, repr=False, compare=False)
    scaling: Scaling | None = field(default=None, repr=False, compare=False)
    #: the error that ended a ``partial`` sweep before its last time (None: all solved)
    stopped: Exception | None = field(default=None, repr=False, compare=False)
    #: (n,) the row scales of the last point's velocity factorisation when it is the next
    #: point's chord (``rcond >= RCOND_WARN``), else None: what ``prior`` continues with
    rows: np.ndarray | None = field(default=None, repr=False, compare=False)
    #: how many of the points the compiled loop solved (the rest: the same loop interpreted,
    #: decision 0075, or the Python loop)
    compiled: int = field(default=0, compare=False)

    @property
    def rcond(self) -> np.ndarray | None:
        if self.fill is not None:
            self.fill(self.rcond_raw)
            object.__setattr__(self, "fill", None)     # (frozen: the estimates are final now)
        return self.rcond_raw

    @property
    def rcond_pending(self) -> bool:
        """Whether reading ``rcond`` still has estimates to compute."""
        return self.fill is not None


#: a step between two solved points that turns a rotational coordinate by more than this (rad)
#: is coarse: the sweep checks it by continuation in substeps (decision 0035)
STEP_CHECK = np.pi / 6
#: the substeps of that check turn a rotational coordinate by about this much (rad) at most
SUBSTEP = np.pi / 12
#: a step is divided into at most this many substeps at once, and divided again at most
#: ``SPLIT_DEPTH`` times
SPLIT_MAX = 64
SPLIT_DEPTH = 4
#: two solutions of one point are the same assembly when no rotational coordinate differs by
#: more than this (rad) and no other by more than this times the model's length
SAME_BRANCH = 1e-6


def sweep(system, times, guess, order: int = 2, options: PositionOptions | None = None,
          p=None, scaling: Scaling | None = None, hooks=None, prior=None, partial: bool = False,
          points: int | None = None, progress: Callable[[int], None] | None = None,
          _depth: int = 0) -> SweepResult:
    r"""Kinematic solution at each of ``times`` (1D, any order; continuation follows the
    given order). ``order`` 0 = location, 1 = + velocity, 2 = + acceleration. ``scaling``
    defaults to the one of ``guess`` at the first time. ``hooks``
    (:class:`~mechsys.solvers._diagnostics.Hooks`): ``pre_solve(t)`` before each point's
    position solve; a hook returning False raises ``Stopped`` carrying the points solved so
    far (``partial``, a :class:`SweepResult`).

    **Coarse steps keep the branch** (decision 0035). The predictor of the loops is exact
    only for small steps; over a step that turns a rotational coordinate by more than
    ``STEP_CHECK`` Newton may land on another assembly branch (a four-bar's rocker mirrored)
    that is still within ``ROTATION_JUMP`` of the prediction, or a driven coordinate may move
    by more than ``ROTATION_JUMP`` in one step (a crank driven at coarse times, which the
    position-only sweep cannot predict). Each such step, solved or failed by that jump, is
    done again by
    continuation from the point before it in ``S`` substeps
    (``S = ceil(rotation / SUBSTEP)``, at most ``SPLIT_MAX``; 4 for a failed step, divided
    again when a substep fails, ``SPLIT_DEPTH`` levels), which follows the drivers' motion
    on the branch of the previous point. When the continuation ends on another configuration
    (no rotational coordinate within ``SAME_BRANCH`` rad, or another coordinate within
    ``SAME_BRANCH L``) the sweep takes the continuation's point and solves the times after it
    again from there. The substeps are not part of the result; the points of fine sweeps
    (every step below ``STEP_CHECK``) are those of the loops alone.

    For a sweep that continues another (the runs of a multistage sweep):

    * ``prior``: ``(times, Q, QD, QDD, rconds[, rows])`` of the points solved just before
      ``times[0]`` (``QD``/``QDD``/``rconds`` None where ``order`` has none; three points
      are all the predictor uses; ``rows`` the ``SweepResult.rows`` of the sweep they end,
      or None). The first point is predicted from them, and starts Newton with the last
      one's chord when ``rows`` is given, exactly as in one long sweep; ``guess`` is not
      used, ``scaling`` must be given.
    * ``partial``: a point whose position solve fails (:class:`ConvergenceError`,
      :class:`SingularJacobianError`) ends the sweep: the result holds the points before it,
      ``stopped`` the error.
    * ``points``: the size of the whole job, for the compiled loop's ``auto`` rule
      (default ``len(times)``)."""
    times = np.atleast_1d(np.asarray(times, dtype=float))
    halted = None       # a hook's stop in the first run: its points are checked, then it goes on
    try:
        res = _sweep_loop(system, times, guess, order, options, p, scaling, hooks, prior, True,
                          points, progress)
    except Stopped as exc:
        if exc.k == 0 or prior is not None:
            raise
        halted, res, times = exc, exc.partial, times[:exc.k]
    rot = rotation_indices(system)
    if prior is not None:
        prior = _check_prior(prior, system.n, order)
    # the solved points so far, prior ones first (not part of the result): lists of arrays
    parts = [] if prior is None else [_as_part(prior, order)]
    n_prior = 0 if prior is None else 1
    evals, at, first = 0, 0, True       # ``at``: index in ``times`` of res's first point
    stop, rows = None, None
    while True:
        evals += res.evaluations
        sc = res.scaling if res.scaling is not None else scaling
        k, step = (None, None) if _depth >= SPLIT_DEPTH else _first_coarse(parts, res.q, rot)
        if k is None and getattr(res.stopped, "lost_branch", False) and _depth < SPLIT_DEPTH \
                and (len(res.t) or any(len(pt[0]) for pt in parts)):
            k, step = len(res.t), None        # a step that jumped after a solved point: divide it
        if k is None:
            if first and halted is None:     # the loops' result, untouched
                if res.stopped is not None and not partial:
                    raise res.stopped
                return res
            parts.append(_as_part(res, order))
            stop, rows = res.stopped, res.rows
            break
        first = False
        part = _as_part(res, order)           # (computes the pending estimates)
        t_k = times[at + k]
        head = _cut(part, k)
        before = _tail([pt for pt in parts + [head] if len(pt[0])], 3)
        S = 4 if step is None else int(min(SPLIT_MAX, max(2, np.ceil(step / SUBSTEP))))
        t0 = before[0][-1]
        sub_t = t0 + (t_k - t0) * np.arange(1, S + 1) / S
        sub_t[-1] = t_k
        try:
            sub = sweep(system, sub_t, None, order, options, p, sc, None, before, True,
                        None, _depth=_depth + 1)
        except ModelError:
            sub = None
        evals += 0 if sub is None else sub.evaluations
        if sub is None or sub.stopped is not None:
            if step is None:                   # the step cannot be done in substeps either
                parts.append(part)
                stop = res.stopped
                break
            # the check could not be made (the substeps stopped): keep the loop's point
            parts.append(_cut(part, k + 1))
            at += k + 1
            res = _sliced(res, k + 1, order)
            continue
        got = _cut(_as_part(sub, order), S - 1, S)
        if step is not None and _same_point(got[1][0], part[1][k], rot, sc):
            parts.append(_cut(part, k + 1))   # the loop's point was on the branch
            at += k + 1
            res = _sliced(res, k + 1, order)
            continue
        parts += [head, got]                   # the continuation's point replaces it
        at += k + 1
        if at >= len(times):
            break
        try:
            res = _sweep_loop(system, times[at:], None, order, options, p, sc, hooks,
                              _tail(parts, 3), True, points)
        except Stopped as exc:
            # a hook stopped the sweep again from a point: the partial result holds every
            # point before the stop, not only those of this run
            got = exc.partial
            kept = [pt for pt in parts[n_prior:] if len(pt[0])]
            exc.partial = _from_parts(kept + [_as_part(got, order)], system.n, order,
                                      evals + got.evaluations, sc, None, None)
            exc.k = len(exc.partial.t)
            raise
    if stop is not None and not partial:
        raise stop
    out = _from_parts([pt for pt in parts[n_prior:] if len(pt[0])], system.n, order, evals,
                      sc, stop, rows)
    if halted is not None:
        halted.partial, halted.k = out, len(out.t)
        raise halted
    return out


def _from_parts(parts, n: int, order: int, evals: int, sc, stop, rows) -> SweepResult:
    """One :class:`SweepResult` of the solved parts ``[t, Q, QD, QDD, rconds, its]``."""
    if not parts:
        empty = np.empty((0, n))
        cat = [np.empty(0), empty, empty if order >= 1 else None, empty if order >= 2 else None,
               np.empty(0) if order >= 1 else None, np.empty(0, dtype=int)]
    else:
        cat = [None if parts[0][i] is None else np.concatenate([pt[i] for pt in parts])
               for i in range(6)]
    t, Q, QD, QDD, rc, its = cat
    return SweepResult(t, Q, QD, QDD, its, evals, order, rc, None, sc, stop, rows)


def _as_part(src, order: int) -> list:
    """``[t, Q, QD, QDD, rconds, its]`` of a SweepResult (its estimates computed) or a
    ``prior`` tuple (copies)."""
    if isinstance(src, SweepResult):
        rc = None if src.rcond_raw is None else np.array(src.rcond)
        return [np.array(src.t), np.array(src.q), None if src.qd is None else np.array(src.qd),
                None if src.qdd is None else np.array(src.qdd), rc, np.array(src.iterations)]
    t, Q, QD, QDD, rc = src[:5]
    return [np.array(t), np.array(Q), None if order < 1 else np.array(QD),
            None if order < 2 else np.array(QDD), None if order < 1 else np.array(rc),
            np.zeros(len(t), dtype=int)]


def _cut(part, a, b=None) -> list:
    """Rows ``[:a]`` (or ``[a:b]``) of a part."""
    sl = slice(None, a) if b is None else slice(a, b)
    return [None if X is None else X[sl] for X in part]


def _tail(parts, m: int):
    """The last ``m`` points of ``parts`` as a ``prior`` tuple."""
    X = [None if parts[0][i] is None else np.concatenate([pt[i] for pt in parts])[-m:]
         for i in range(5)]
    return tuple(X)


def _first_coarse(parts, Q, rot):
    """``(k, rotation)`` of the first point of ``Q`` reached from the point before it (the
    last of ``parts``, or the previous one of ``part``) by a step turning a rotational
    coordinate by more than ``STEP_CHECK``; ``(None, None)`` if none."""
    if not rot.size or not len(Q):
        return None, None
    prev = [pt[1][-1:] for pt in parts if len(pt[1])][-1:]
    seq = np.concatenate(prev + [Q])[:, rot]
    steps = np.abs(np.diff(seq, axis=0)).max(axis=1)
    off = 1 - len(prev)       # index in part of steps[0]'s end point
    big = np.flatnonzero(steps > STEP_CHECK)
    if not big.size:
        return None, None
    return int(big[0]) + off, float(steps[big[0]])


def _same_point(a, b, rot, sc) -> bool:
    d = np.abs(np.asarray(a) - np.asarray(b))
    other = np.ones(len(d), dtype=bool)
    other[rot] = False
    length = sc.length if sc is not None else 1.0
    return bool(d[rot].max(initial=0.0) <= SAME_BRANCH
                and d[other].max(initial=0.0) <= SAME_BRANCH * max(length, 1e-300))


def _sliced(res: SweepResult, a: int, order: int) -> SweepResult:
    """The points ``a:`` of ``res`` (its estimates computed), same stop and scaling."""
    rc = None if res.rcond_raw is None else np.array(res.rcond)[a:]
    return SweepResult(res.t[a:], res.q[a:], None if res.qd is None else res.qd[a:],
                       None if res.qdd is None else res.qdd[a:], res.iterations[a:], 0, order,
                       rc, None, res.scaling, res.stopped, res.rows)


def _sweep_loop(system, times, guess, order: int = 2, options: PositionOptions | None = None,
                p=None, scaling: Scaling | None = None, hooks=None, prior=None,
                partial: bool = False, points: int | None = None,
                progress: Callable[[int], None] | None = None) -> SweepResult:
    """The sweep's loops without the coarse-step checks of :func:`sweep`, which calls it:
    the loop of ``_jit_sweep`` (compiled, or its code interpreted: decision 0081) for the
    regular points of every sweep, the Python code for each point it leaves (after which the
    loop resumes) and for every point when the loop cannot run (hooks; a system the loop
    does not take: more equations than coordinates, or a kernel without C entry points that
    none can be made for).
    Kinematic solution at each of ``times`` (1D, any order; continuation follows the given
    order). ``order`` 0 = location,
    1 = + velocity, 2 = + acceleration. ``scaling`` defaults to the one of ``guess`` at the
    first time. ``hooks``
    (:class:`~mechsys.solvers._diagnostics.Hooks`): ``pre_solve(t)`` before each point's
    position solve; a hook returning False raises ``Stopped`` carrying the points solved so
    far (``partial``, a :class:`SweepResult`).

    ``prior``, ``partial`` and ``points`` as in :func:`sweep`.

    ``progress(done)``: called with the number of points of ``times`` solved so far, between
    chunks of the loop (about ``CHUNK_SECONDS`` each: the loop is resumed where it
    stopped, with the same chord, so the numbers are those of one call) and about as often
    in the Python code; unlike the hooks it keeps the loop. A ``KeyboardInterrupt``
    (Ctrl-C, or raised by ``progress``) stops the sweep: ``Stopped("interrupted")`` carries
    the points solved before it (``partial``)."""
    times = np.atleast_1d(np.asarray(times, dtype=float))
    P = 0
    if prior is not None:
        prior = _check_prior(prior, system.n, order)
        if scaling is None:
            raise ModelError("sweep: a sweep continuing prior points needs their scaling "
                             "(scaling=, the SweepResult.scaling of the sweep they come from)")
        P = len(prior[0])
        times = np.concatenate([prior[0], times])
    n, N = system.n, len(times)
    sparse = n > SPARSE_THRESHOLD
    Q = np.empty((N, n))
    QD = np.empty((N, n)) if order >= 1 else None
    QDD = np.empty((N, n)) if order >= 2 else None
    its = np.zeros(N, dtype=int)
    rconds = np.full(N, np.nan) if order >= 1 else None
    if P:
        for X, Xp in zip((Q, QD, QDD, rconds), prior[1:]):
            if X is not None:
                X[:P] = Xp
    q0 = np.asarray(guess, dtype=float) if P == 0 else Q[P - 1]
    guard = getattr(system, "branch_guard", None)   # angle equations with a root at + pi
    if guard is not None and P == 0 and N and np.all(np.isfinite(q0)):
        aligned = guard.align(times[0], q0, p)
        q0 = q0 if aligned is None else aligned
    sc = scaling
    evals = 0
    rot = rotation_indices(system)  # indices of angles / Euler parameters
    k0 = P
    chord = None    # the previous point's velocity factorisation: Newton's first steps reuse it
    # hooks (pre_solve, post_iterate) run in the Python loop only; otherwise the loop takes
    # every regular point, compiled or interpreted as the job's tier says (decision 0081)
    pointers = _jit_sweep.plan(system, N - P if points is None else points, order) \
        if N > P and hooks is None else None
    how = None if pointers is None else _jit_runtime.tier(N - P if points is None else points, n)
    start = None    # the first point's equations at the guess, evaluated for the scaling
    if sc is None and N and pointers is None:
        F0, J0 = system.residual_and_jacobian(times[0], q0, p, sparse)
        sc, start = Scaling.of(system, q0, J0), (F0, J0)
    fill = None
    prior_rows = prior[5] if P and order >= 1 and rconds[P - 1] >= RCOND_WARN else None
    rows_last = prior_rows     # the chord's rows of the last point solved
    compiled = 0
    rprev = np.ones(n) if prior_rows is None else np.array(prior_rows, dtype=float)
    R = np.empty((N, n)) if order >= 1 and pointers is not None else None   # pending estimates' rows

    def loop_from(first: int, chord_start: bool) -> int:
        """The loop (compiled, or the same code interpreted) from point ``first``; returns the
        first point it leaves to the Python code below (the points before it are solved),
        with ``chord`` the chord of the point before it."""
        nonlocal sc, start, rows_last, fill, evals, compiled, chord
        args = (system, pointers, times, q0, p, order, options or PositionOptions(), sc, rot, Q,
                QD, QDD, its, rconds, rprev, R, first, chord_start)
        interrupted = False
        if progress is None:
            k, done, sc, got = _jit_sweep.run(*args, how=how)
        else:
            k, done, sc, got, interrupted = _run_chunks(args, progress, P, how)
        k = max(int(k), first)
        if sc is None and N:
            # the loop stopped before its first evaluation gave the scaling: the Python
            # code's, as above
            F0, J0 = system.residual_and_jacobian(times[0], q0, p, sparse)
            sc, start = Scaling.of(system, q0, J0), (F0, J0)
        ran = k
        if guard is not None and k > first:
            # a row on the wrong root of an angle equation (a prediction more than a quarter
            # turn off): it and the rows after it are solved again below
            bad = np.flatnonzero(guard.wrong_rows(times[first:k], Q[first:k], p).any(axis=1))
            k = k if not bad.size else first + int(bad[0])
        if k > first:
            rows_last = rprev.copy() if order >= 1 and rconds[k - 1] >= RCOND_WARN else None
        if fill is None and order >= 1 and (rconds[first:k] == RCOND_PENDING).any():
            fill = _jit_sweep.rcond_filler(system, pointers, times[P:], Q[P:], p, sc, R[P:])
        evals += done
        # (the compiled loop's rows are the last ones it solved; the guard's redone rows are
        # the last ones too)
        compiled += max(0, got - (ran - k))
        if interrupted:
            raise _interrupted(k, P, times, Q, QD, QDD, its, evals, order, rconds, fill, compiled)
        if first < k < N:
            chord = None
            if order >= 1 and rconds[k - 1] >= RCOND_WARN:
                # the chord the loop had: the same matrix, factorised again (not counted as an
                # evaluation: the all-Python sweep has it at hand)
                try:
                    chord = sc.factor(system.jacobian(times[k - 1], Q[k - 1], p, sparse), rprev)
                except Singular:
                    chord = None
        return k

    if pointers is not None:
        # the regular points in the loop; the first one needing care is left to the Python
        # code below (the loop takes the scaling from its first evaluation when none is given)
        k0 = loop_from(P, prior_rows is not None)

    def points():
        """The points the Python code takes: each point the loop leaves to it, after which
        the loop resumes from the next point with that point's chord (decisions 0075,
        0081: also after a stretch of points needing care, so that the Python code takes
        no regular point); every point when the loop cannot run (hooks, ...: see
        :func:`_sweep_loop`)."""
        k = k0
        while k < N:
            yield k
            k += 1
            if pointers is None or k >= N:
                continue
            if order >= 1 and chord is not None:
                rprev[:] = rows_last
            k = loop_from(k, order >= 1 and chord is not None)

    if k0 == P and prior_rows is not None:
        # the last prior point's chord, as the long sweep has it (also when the compiled
        # loop left the first point to this loop)
        try:
            chord = sc.factor(system.jacobian(times[P - 1], Q[P - 1], p, sparse), prior_rows)
        except Singular:
            chord = rows_last = None
    end, stopped = N, None
    clock = time.perf_counter()
    k = k0
    try:
        for k in points():
            t = times[k]
            if progress is not None and k > k0 and time.perf_counter() - clock > CHUNK_SECONDS:
                progress(k - P)
                clock = time.perf_counter()
            try:
                if hooks is not None and hooks.pre_solve is not None and hooks.pre_solve(float(t)) is False:
                    raise Stopped("pre_solve", float(t))
                g = q0 if k == 0 else _predict(Q, QD, QDD, rconds, times, k, rot)
                if guard is not None and k > 0:
                    # a prediction more than a quarter turn from a driven angle starts on it
                    aligned = guard.align(t, g, p)
                    g = g if aligned is None else aligned
                res = _solve_point(system, t, g, Q[k - 1] if k else None, options, p, sc, rot,
                                   times[k - 1] if k else None, hooks, chord,
                                   start if k == 0 else None)
            except Stopped as exc:
                raise _stopped(exc, k, times, Q, QD, QDD, its, evals, order, rconds, fill,
                               sc) from None
            q = res.q
            had_chord, chord = chord is not None, None
            its[k] = res.iterations
            evals += res.evaluations
            Q[k] = q
            if order >= 1:
                J, rhs = system.velocity_rhs(t, q, p, sparse)
                try:
                    # the position solve's row scales (from the predictor's Jacobian) serve here too
                    fac = sc.factor(J, res.rows)
                except Singular:
                    fac = None
                if fac is None and had_chord:
                    # chord steps do not factorise the Jacobian, so they can converge at a singular
                    # instant without noticing: solve the point again with Newton alone, which
                    # diagnoses it (and approaches it: the rates below use that)
                    try:
                        res = _solve_point(system, t, g, Q[k - 1], options, p, sc, rot, times[k - 1],
                                           hooks)
                    except Stopped as exc:
                        raise _stopped(exc, k, times, Q, QD, QDD, its, evals, order, rconds,
                                       fill, sc) from None
                    q = res.q
                    its[k] = res.iterations
                    evals += res.evaluations
                    Q[k] = q
                    J, rhs = system.velocity_rhs(t, q, p, sparse)
                    try:
                        fac = sc.factor(J, res.rows)
                    except Singular:
                        fac = None
                if fac is None:
                    if k == 0:
                        err = describe_singular(system, J, t, q, "velocity solve", sc)
                        raise SingularJacobianError(
                            f"{err} Sweep stopped at point {k} of {N}.", time=t,
                            dependent=err.dependent, rank=err.rank) from None
                    # a singular instant on the way (the driver still moves the mechanism): the
                    # rates the equations leave open continue those of the previous points
                    J = np.asarray(J.toarray() if sps.issparse(J) else J)
                    vd, ad = _rates_before(system, t, res.approach, p, sc)
                    if vd is None:
                        vd, ad = _extrapolate(QD, times, k), _extrapolate(QDD, times, k) \
                            if order >= 2 else None
                    QD[k] = continue_rates(J, rhs, vd, sc, res.rows)
                    rconds[k] = 0.0
                    if order >= 2:
                        QDD[k] = continue_rates(J, system.gamma_values(t, q, QD[k], p), ad, sc,
                                                res.rows)
                    continue
                qd = fac.solve(rhs)
                QD[k] = qd
                rconds[k] = fac.rcond
                # the next point's chord: only from a well-conditioned point (near a toggle Newton
                # keeps its fresh Jacobian)
                chord = fac if fac.rcond >= RCOND_WARN else None
                rows_last = None if chord is None else res.rows
                evals += 1
                if order >= 2:
                    QDD[k] = fac.solve(system.gamma_values(t, q, qd, p))
                    evals += 1
    except (ConvergenceError, SingularJacobianError) as exc:
        if not partial:
            raise
        end, stopped = k, exc     # (the points before k are complete)
    except KeyboardInterrupt:
        raise _interrupted(k, P, times, Q, QD, QDD, its, evals, order, rconds, fill,
                           compiled) from None
    if progress is not None and N > k0:
        progress(end - P)
    if guard is not None and end > P:
        # every path above tests its roots; this states the result's contract once more
        wrong = guard.wrong_rows(times[P:end], Q[P:end], p)
        if wrong.any():
            i = int(np.flatnonzero(wrong.any(axis=1))[0])
            raise ConvergenceError(guard.describe(list(np.flatnonzero(wrong[i])), times[P + i]),
                                   time=times[P + i])
    if P or end < N:
        times, Q, its = times[P:end], Q[P:end], its[P:end]
        QD, QDD, rconds = (None if X is None else X[P:end] for X in (QD, QDD, rconds))
    if rconds is not None and (rconds < RCOND_WARN).any():    # (NaN: not solved, no warning)
        import warnings

        from .._errors import NearSingularWarning

        bad = times[rconds < RCOND_WARN]
        warnings.warn(NearSingularWarning(
            f"the constraint Jacobian is nearly singular at {len(bad)} time point(s), first at "
            f"t = {bad[0]:.6g} (reciprocal condition {np.nanmin(rconds):.1e}): the mechanism is "
            "close to a lock-up or toggle position; velocities and accelerations there are large "
            "and sensitive, and the sweep continued through it on the branch its previous "
            "points followed. Solution.extra['rcond'] has the value at every point."),
            stacklevel=3)
    if end > P:       # (a last point near a singular instant has no chord)
        rows_last = rows_last if order >= 1 and rconds[-1] >= RCOND_WARN else None
    return SweepResult(times, Q, QD, QDD, its, evals, order, rconds, fill, sc, stopped,
                       rows_last, compiled)


def _run_chunks(args, progress, base: int, how: str | None = None):
    """``_jit_sweep.run(*args)`` in chunks of points, ``progress(done)`` between them; returns
    ``(k, evaluations, scaling, compiled, interrupted)`` (``compiled``: the points the
    compiled loop solved, the others the interpreted loop's). Each chunk resumes the loop at
    the point where the last one ended (``first``), with that point's chord (``chord_start``)
    rebuilt from its coordinates and row scales exactly as the loop builds it, so the numbers
    are those of one call. Chunks grow (or shrink) toward ``CHUNK_SECONDS`` each, at most 4x
    per chunk; a ``KeyboardInterrupt`` (Ctrl-C during a chunk, or from ``progress``) ends the
    run with the points of the chunks before it (``interrupted`` True). ``progress`` is told
    the points solved since ``base``. ``how``: the job's tier (:func:`._jit_runtime.tier`)."""
    (system, pointers, times, q0, p, order, options, sc, rot, Q, QD, QDD, its, rconds, rprev,
     R, first, chord_start) = args
    N, k, evals, size, compiled = len(times), first, 0, FIRST_CHUNK, 0
    while k < N:
        end = min(N, k + size)
        clock = time.perf_counter()
        try:
            kk, done, sc, got = _jit_sweep.run(system, pointers, times[:end], q0, p, order,
                                               options, sc, rot, Q, QD, QDD, its, rconds, rprev,
                                               R, k, chord_start, how=how)
        except KeyboardInterrupt:
            return k, evals, sc, compiled, True   # (the points of this chunk are not all known)
        evals += done
        compiled += got
        if kk < end:                          # left to the Python loop
            return kk, evals, sc, compiled, False
        k = end
        chord_start = order >= 1 and bool(rconds[k - 1] >= RCOND_WARN)
        try:
            progress(k - base)
        except KeyboardInterrupt:
            return k, evals, sc, compiled, True
        took = max(time.perf_counter() - clock, 1e-6)
        size = max(1, int(size * min(4.0, max(0.25, CHUNK_SECONDS / took))))
    return k, evals, sc, compiled, False


def _interrupted(k, P, times, Q, QD, QDD, its, evals, order, rconds, fill, compiled) -> Stopped:
    """A ``Stopped("interrupted")`` carrying the points ``P .. k - 1`` (all complete)."""
    exc = Stopped("interrupted", float(times[min(k, len(times) - 1)]))
    exc.k = k - P
    exc.partial = SweepResult(times[P:k], Q[P:k], None if QD is None else QD[P:k],
                              None if QDD is None else QDD[P:k], its[P:k], evals, order,
                              None if rconds is None else rconds[P:k], fill,
                              compiled=min(compiled, k - P))
    return exc


def _check_prior(prior, n: int, order: int) -> tuple:
    """``prior = (times (P,), Q (P, n), QD, QDD (P, n) or None, rconds (P,) or None)`` as
    arrays, with what ``order`` needs present and finite; else a :class:`ModelError`."""
    try:
        t, *rest = prior
        Q, QD, QDD, rc, *rows = rest
        if len(rows) > 1:
            raise ValueError
    except (TypeError, ValueError):
        raise ModelError("sweep: prior must be (times, Q, QD, QDD, rconds[, rows]) of the "
                         f"points solved before, got {type(prior).__name__}") from None
    rows = rows[0] if rows else None
    if rows is not None:
        rows = np.asarray(rows, dtype=float)
        if rows.shape != (n,) or not (np.isfinite(rows).all() and (rows > 0).all()):
            raise ModelError(f"sweep: prior rows must be {n} positive row scales (a "
                             "SweepResult.rows), or None")
    t = np.atleast_1d(np.asarray(t, dtype=float))
    P = len(t)
    need = {"Q": (Q, (P, n)), "QD": (QD, (P, n)) if order >= 1 else None,
            "QDD": (QDD, (P, n)) if order >= 2 else None,
            "rconds": (rc, (P,)) if order >= 1 else None}
    out = {}
    for name, spec in need.items():
        if spec is None:
            continue
        X, shape = spec
        X = None if X is None else np.asarray(X, dtype=float)
        # (an estimate may be RCOND_PENDING, inf)
        bad = None if X is None else (np.isnan(X) if name == "rconds" else ~np.isfinite(X))
        if X is None or X.shape != shape or bad.any():
            raise ModelError(f"sweep: prior {name} must be an array of shape {shape} of "
                             f"finite numbers for a sweep of order {order} (got "
                             f"{None if X is None else X.shape})")
        out[name] = X
    if not P or not np.isfinite(t).all():
        raise ModelError("sweep: prior times must be one or more finite numbers")
    return (t, out["Q"], out.get("QD"), out.get("QDD"), out.get("rconds"), rows)


def _stopped(exc, k, times, Q, QD, QDD, its, evals, order, rconds, fill=None, sc=None):
    """``exc`` (a ``Stopped``) carrying the ``k`` points solved so far."""
    exc.k = k
    exc.partial = SweepResult(times[:k], Q[:k], None if QD is None else QD[:k],
                              None if QDD is None else QDD[:k], its[:k], evals,
                              order, None if rconds is None else rconds[:k], fill, sc)
    return exc


def _predict(Q, QD, QDD, rconds, times, k: int, rot) -> np.ndarray:
    """Starting point of point ``k`` from the points before it (see the module docstring)."""
    q, dt = Q[k - 1], times[k] - times[k - 1]
    secant = None
    if k >= 2:
        dt0 = times[k - 1] - times[k - 2]
        secant = q + (q - Q[k - 2]) * (dt / dt0) if dt0 != 0 else q
    if QD is None or (rconds[k - 1] < RCOND_WARN and secant is not None):
        return q if secant is None else secant
    if rconds[k - 1] < RCOND_WARN:
        # the sweep starts at a near-toggle point: qd points along the branch (the near-null
        # direction of Phi_q) but its size is meaningless, so take a bounded first-order step
        step = QD[k - 1] * dt
        big = np.abs(step[rot]).max(initial=0.0)
        return q + (step * (ROTATION_START / big) if big > ROTATION_START else step)
    g = q + QD[k - 1] * dt
    if QDD is not None:
        g = g + 0.5 * QDD[k - 1] * dt * dt
        if secant is not None and dt0 != 0 and rconds[k - 2] >= RCOND_WARN:
            # the third (and fourth) derivative from the last two (three) accelerations, by
            # divided differences: an O(dt^4) (O(dt^5)) prediction, close enough for one chord
            # step of the position solve to reach rounding (decision 0020)
            a = (QDD[k - 1] - QDD[k - 2]) / dt0
            c3 = dt * dt * dt / 6.0
            dt1 = times[k - 2] - times[k - 3] if k >= 3 else 0.0
            if dt1 != 0 and dt0 + dt1 != 0 and rconds[k - 3] >= RCOND_WARN:
                b = (a - (QDD[k - 2] - QDD[k - 3]) / dt1) / (dt0 + dt1)
                g = g + (a + b * dt0) * c3 + b * (dt * dt * dt * dt / 12.0)
            else:
                g = g + a * c3
    if secant is not None and rot.size:
        qr = q[rot]
        if np.abs(g[rot] - qr).max() > ROTATION_SLACK + 4 * np.abs(secant[rot] - qr).max():
            return secant
    return g


def _solve_point(system, t, g, q_prev, options, p, sc, rot, t_prev=None, hooks=None,
                 chord=None, start=None):
    """Newton from the prediction ``g`` (starting with chord steps on ``chord``, the
    previous point's factorisation, when given; ``start``: the equations at ``g``, already
    evaluated, as ``solve_position`` takes them); again from ``q_prev`` (plain Newton) when
    that fails or when the result jumps (a rotational coordinate further than
    ``ROTATION_JUMP`` from ``g``). At a singular instant after the first point, minimum-norm
    Gauss-Newton from ``g`` (:func:`._rank.continue_position`) continues the branch."""
    kw = {} if hooks is None else {"hooks": hooks}  # (the plain call stays as it was)
    if chord is not None:
        kw["chord"] = chord
    if start is not None:
        kw["start"] = start
    try:
        res = solve_position(system, t, g, options, p, sc, **kw)
        if q_prev is None or _jump(res.q, g, rot) <= ROTATION_JUMP:
            return res
    except (ConvergenceError, SingularJacobianError) as exc:
        if q_prev is None or np.array_equal(g, q_prev):
            raise
        if isinstance(exc, SingularJacobianError):
            opt = options or PositionOptions()
            g, near = _approach(system, t, t_prev, q_prev, options, p, sc, g)
            got = continue_position(system, t, g, p, sc, opt.ftol, opt.max_iterations)
            if got is not None and _jump(got[0], g, rot) <= ROTATION_JUMP:
                q, its, evals, norm = got
                F, J = system.residual_and_jacobian(t, q, p)
                return PositionResult(q, True, 0, "converged at a singular instant", its, evals,
                                      norm, (norm,), sc.rows(J), near)
    # the predictor can throw the guess far away where velocities are huge (near a
    # toggle): start again from the previous position
    kw.pop("chord", None)
    kw.pop("start", None)
    res = solve_position(system, t, q_prev, options, p, sc, **kw)
    jump = _jump(res.q, q_prev, rot)
    if jump > ROTATION_JUMP:
        i = rot[np.argmax(np.abs(res.q[rot] - q_prev[rot]))]
        err = ConvergenceError(
            f"kinematic sweep at t = {t:.6g}: a rotational coordinate "
            f"({system.layout.q_names[i]}) jumped by {jump:.3g} rad from the previous point, so "
            "the sweep lost its assembly branch (near a lock-up or toggle position, or too "
            "coarse sampling). Sample more finely, or stop the sweep before this time.",
            time=t, residuals=system.residual(t, res.q, p),
            history=res.history)
        err.lost_branch = True     # (sweep divides such a step: a coarse step, not a lock-up)
        raise err
    return res


#: the approach to a singular instant stops this fraction of the last step before it
APPROACH = 2.0**-14


def _approach(system, t, t_prev, q_prev, options, p, sc, g):
    """A prediction of the position at the singular instant ``t`` good enough to pick the
    continuous branch there (where the solutions of ``Phi = 0`` cross): positions at
    ``t - dt / 2, t - dt / 4, ... , t - APPROACH dt`` (regular instants, Newton from the
    secant of the previous two), then their secant at ``t``. Its error is of the order of
    ``APPROACH^2`` of the step's, where the step's own prediction ``g`` (returned when an
    intermediate solve fails) has an error of the order of the step's curvature. Returns
    ``(prediction, (t_a, q_a))`` with the last regular instant solved (``None`` on failure).
    """
    ts, qs = [t_prev], [np.asarray(q_prev, dtype=float)]
    frac = 0.5
    try:
        while frac >= APPROACH:
            tk = t - frac * (t - t_prev)
            guess = qs[-1] if len(ts) < 2 else qs[-1] + (qs[-1] - qs[-2]) * (
                (tk - ts[-1]) / (ts[-1] - ts[-2]))
            ts.append(tk)
            qs.append(solve_position(system, tk, guess, options, p, sc).q)
            frac *= 0.5
    except (ConvergenceError, SingularJacobianError):
        return g, None
    return qs[-1] + (qs[-1] - qs[-2]) * ((t - ts[-1]) / (ts[-1] - ts[-2])), (ts[-1], qs[-1])


def _rates_before(system, t, near, p, sc):
    """Predicted ``(qd, qdd)`` at the singular instant ``t`` from the regular instant
    ``near = (t_a, q_a)`` just before it: ``qd_a + qdd_a (t - t_a)`` and ``qdd_a`` (the
    acceleration's own error is of order ``t - t_a``). ``(None, None)`` without it."""
    if near is None:
        return None, None
    ta, qa = near
    try:
        va = solve_velocity(system, ta, qa, p, sc)
        aa = solve_acceleration(system, ta, qa, va, p, scaling=sc)
    except SingularJacobianError:
        return None, None
    return va + aa * (t - ta), aa


def _extrapolate(X, times, k: int) -> np.ndarray:
    """Linear extrapolation of the rows ``X[k-2], X[k-1]`` to ``times[k]`` (``X[k-1]`` when
    there is one previous point, or a step of zero length)."""
    if k < 2 or times[k - 1] == times[k - 2]:
        return X[k - 1].copy()
    w = (times[k] - times[k - 1]) / (times[k - 1] - times[k - 2])
    return X[k - 1] + w * (X[k - 1] - X[k - 2])


def _jump(q, ref, rot) -> float:
    return float(np.abs(q[rot] - ref[rot]).max()) if rot.size else 0.0
