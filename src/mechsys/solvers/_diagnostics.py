r"""Debugging tools of Mech's chapter 13: why a position solve failed, where the constraint
Jacobian is (nearly) singular, and the solver hooks ``pre_solve`` / ``post_iterate``.

Everything is measured on the unit-free equations of
:class:`~mechsys.solvers._linalg.Scaling` (:math:`\hat\Phi = R^{-1} \Phi`, coordinates in units of the
characteristic length ``L``), so the diagnosis does not depend on the unit of length.

*Failure to converge* (Mech 13.2). After a failed Newton solve,
:func:`diagnose_convergence` ranks

* the constraints by the largest scaled residual :math:`\lvert \Phi_i \rvert / r_i` of their equations (to
  first order the distance, in units of ``L`` or radians, from satisfying the equation), and
* the coordinates by how far Newton moved them, ``|q_end - q_start|_j / c_j`` (``c_j = L`` for
  positions, 1 for angles),

and picks a suggestion from the iteration history: one constraint holding a residual that no
longer decreases (the mechanism cannot assemble: a link too short to reach, a wrong
dimension), coordinates that wandered many lengths away (the guess is far from any assembled
position), a residual that oscillates (a toggle position, or a guess between two assembly
branches), or one still decreasing (more iterations).

*Mathematical anomalies* (Mech 13.3). :func:`diagnose_singularity` takes the singular value
decomposition :math:`\hat\Phi_q = U S V^T` of the scaled Jacobian. A singular value
``s_k <= threshold * s_max`` marks a (near-)dependency: its left singular vector ``u_k``
spans the (near) null space of ``Phi_q^T`` — :math:`u_k^T \Phi_q \approx 0`, a combination of equations
that does not constrain anything — and the equations with a large weight ``|u_k[i]|`` are the
constraints involved; its right singular vector ``v_k`` is the motion the constraints
(nearly) fail to control (the direction in which a toggle position can move, or the motion a
redundant set leaves undetermined at this instant).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._errors import ModelError
from ._linalg import rotation_columns

#: number of constraints / coordinates listed in a convergence diagnosis
TOP = 5
#: a coordinate that moved more than this many characteristic lengths (or radians x 2 pi)
#: during Newton diverged
WANDER = 10.0


def _label(owner) -> str:
    return owner.label() if hasattr(owner, "label") else str(owner)


def _bodies_of(owner) -> list[str]:
    bodies = getattr(owner, "bodies", None)
    if bodies is None:
        return []
    try:
        return [b.name for b in bodies() if not getattr(b, "is_ground", False)]
    except Exception:  # a constraint without resolvable bodies: name none rather than fail
        return []


@dataclass(frozen=True)
class ConvergenceDiagnosis:
    """What a failed position solve left behind (Mech 13.2), unit-free.

    constraints: ``((label, scaled residual), ...)`` worst first, one entry per constraint
    (the largest of its equations); coordinates: ``((name, move, scaled move), ...)`` the
    coordinates Newton moved most from its starting point (``move`` in the model's units,
    ``scaled move`` in units of ``L`` or radians); trend: ``"stalled"``, ``"diverged"``,
    ``"oscillating"`` or ``"decreasing"``; suggestion: what to try; text: all of it in words.
    """

    constraints: tuple
    coordinates: tuple
    trend: str
    suggestion: str
    text: str


def _trend(history, moved_far: bool) -> str:
    h = np.asarray([x for x in history if np.isfinite(x)], dtype=float)
    if moved_far:
        return "diverged"
    if h.size < 3:
        return "decreasing"
    tail = h[-min(6, h.size):]
    if tail[-1] < 0.5 * tail[0] and np.all(np.diff(tail) <= 0):
        return "decreasing"
    ups = int(np.sum(np.diff(tail) > 0))
    if ups >= 2:
        return "oscillating"
    return "stalled"


def diagnose_convergence(system, t, q_start, q_end, F, rows, scaling, history) -> ConvergenceDiagnosis:
    """Rank the constraints keeping a residual and the coordinates Newton moved most after a
    failed solve from ``q_start`` to ``q_end`` (residual ``F``, row scales ``rows``); see the
    module docstring. Example::

        try:
            m.solve(0.0)
        except ms.ConvergenceError as err:
            print(err.constraints[0], err.suggestion)
    """
    lay = system.layout
    F = np.asarray(F, dtype=float)
    r = np.ones_like(F) if rows is None else np.asarray(rows, dtype=float)
    scaled = np.abs(F / r)
    scaled[~np.isfinite(scaled)] = np.inf
    worst: dict = {}
    for i in np.argsort(-scaled):
        o = lay.eq_owner[i]
        key = id(o)
        if key not in worst:
            worst[key] = (o, float(scaled[i]))
    ranked = sorted(worst.values(), key=lambda x: -x[1])
    # list the constraints that keep a residual: those within 1e-3 of the worst one
    top = ranked[0][1] if ranked else 0.0
    listed = [(o, s) for o, s in ranked if s > 0 and s >= 1e-3 * top] or ranked[:1]
    cons = tuple((_label(o), s) for o, s in listed[:TOP])
    dq = np.asarray(q_end, dtype=float) - np.asarray(q_start, dtype=float)
    cols = scaling.columns if scaling is not None else np.ones_like(dq)
    sdq = np.abs(dq / cols)
    sdq[~np.isfinite(sdq)] = np.inf
    # an angle that turned by whole turns did not go anywhere: measure angles modulo 2 pi
    rot = np.asarray(rotation_columns(system), dtype=bool)
    if rot.shape == sdq.shape and rot.any():
        sdq[rot] = np.abs((dq[rot] + np.pi) % (2 * np.pi) - np.pi)
    order = [int(j) for j in np.argsort(-sdq)[:TOP] if sdq[j] > 0]
    coords = tuple((lay.q_names[j], float(dq[j]), float(sdq[j])) for j in order)
    far = bool(sdq.size and sdq.max() > WANDER)
    trend = _trend(history, far)
    top_owner = ranked[0][0] if ranked else None
    # the share of the residual held by the worst constraint: one culprit or many
    total = sum(s for _, s in ranked if np.isfinite(s)) or 1.0
    lone = bool(ranked) and np.isfinite(ranked[0][1]) and ranked[0][1] >= 0.5 * total
    name = _label(top_owner) if top_owner is not None else "the constraints"
    bodies = _bodies_of(top_owner) if top_owner is not None else []
    who = f" (bodies {', '.join(map(repr, bodies))})" if bodies else ""
    if trend == "diverged":
        j = order[0]
        suggestion = (f"Newton wandered far from the starting guess ({lay.q_names[j]} moved by "
                      f"{dq[j]:.3g}): the guess is far from any assembled position. Give guesses "
                      "near the assembled position (add_body(..., guess=...), m.set_guess(...) or "
                      "solve(..., guess=...)), starting with the bodies of "
                      f"{name}{who}.")
    elif lone and len(listed) == 1:
        suggestion = (f"only {name}{who} keeps a residual, and Newton cannot reduce it: the "
                      "mechanism probably cannot assemble with it (a link too short to reach, a "
                      "wrong dimension or parameter, a driver outside the reachable range). Check "
                      "its geometry and parameters; if it should assemble, give better guesses "
                      "for its bodies.")
    elif trend == "oscillating":
        suggestion = (f"the residual oscillates: the mechanism is probably near a toggle (lock-up) "
                      f"position or the guess lies between two assembly branches. Give a guess on "
                      f"the branch you want for the bodies of {name}{who}, or check with "
                      "m.singularity(...) where the Jacobian is singular.")
    elif trend == "decreasing":
        suggestion = ("the residual was still decreasing: raise max_iterations "
                      "(options={'max_iterations': ...}) or start from a better guess.")
    elif lone:
        suggestion = (f"{name}{who} keeps a residual that Newton cannot reduce: the mechanism "
                      "probably cannot assemble with it (a link too short to reach, a wrong "
                      "dimension or parameter, a driver outside the reachable range). Check its "
                      "geometry and parameters; if it should assemble, give better guesses for "
                      "its bodies.")
    else:
        suggestion = ("several constraints keep residuals that Newton cannot reduce: check that "
                      "the constraints are consistent (the mechanism can assemble at this time) "
                      "and give better guesses for the bodies involved.")
    lines = ["constraints keeping a residual (scaled |Phi|/r, worst first): "
             + "; ".join(f"{lab}: {s:.3e}" for lab, s in cons)]
    if coords:
        lines.append("coordinates moved most by Newton: "
                     + "; ".join(f"{nm}: {d:+.3e}" for nm, d, _ in coords))
    lines.append(f"residual history {trend}; suggestion: {suggestion}")
    return ConvergenceDiagnosis(cons, coords, trend, suggestion, "\n".join(lines))


@dataclass(frozen=True)
class SingularityReport:
    """Closeness of the constraint Jacobian to singularity at one configuration (Mech 13.3).

    rcond: ``s_m / s_1``, the reciprocal condition number of the rows of the scaled
    Jacobian (0 when its rows are dependent, always for more equations than coordinates);
    singular: ``rcond <= threshold``; rank: the numerical rank; groups: one entry per
    (near-)null direction ``k``: ``{"value": s_k / s_max, "constraints": [(label, [equation
    numbers], weight), ...], "coordinates": [(name, weight), ...]}`` — the equations with a
    large weight in ``u_k`` (the dependent ones) and the coordinates with a large weight in
    ``v_k`` (the motion left uncontrolled); text: all of it in words.
    """

    t: float
    rcond: float
    singular: bool
    rank: int
    threshold: float
    singular_values: np.ndarray
    groups: list = field(default_factory=list)
    text: str = ""

    def __str__(self) -> str:
        return self.text

    __repr__ = __str__


def diagnose_singularity(system, J, scaling, t: float = 0.0, threshold: float = 1e-6,
                         weight: float = 0.1) -> SingularityReport:
    """Singular and near-singular directions of ``J`` (see the module docstring): every
    singular value ``s_k <= threshold * s_max`` with the equations whose weight in ``u_k`` is
    at least ``weight`` times its largest, grouped by constraint."""
    if isinstance(threshold, bool) or not isinstance(threshold, (int, float)) \
            or not 0 < threshold < 1:
        raise ModelError(f"singularity: threshold must be a number in (0, 1), got {threshold!r}")
    import scipy.sparse as sps

    Js = scaling.scaled(J)
    Js = Js.toarray() if sps.issparse(Js) else np.asarray(Js, dtype=float)
    m, n = Js.shape
    lay = system.layout
    if m == 0 or n == 0:
        return SingularityReport(t, 1.0, False, 0, threshold, np.zeros(0), [],
                                 "no constraint equations or no coordinates: nothing is singular")
    U, S, Vt = np.linalg.svd(Js, full_matrices=True)
    smax = S[0] if S.size and S[0] > 0 else 1.0
    rel = S / smax
    eps_rank = max(m, n) * np.finfo(float).eps * 10
    rank = int(np.sum(rel > eps_rank))
    k_min = min(m, n)
    # s_m / s_1: the rows' independence (a tall Jacobian has dependent rows: 0)
    rcond = float(rel[m - 1]) if m <= n else 0.0
    if rcond <= eps_rank:
        rcond = 0.0
    # every left null vector: near-small singular values, and for m > n the exact left null
    # space (rows beyond n) too
    idx = [k for k in range(k_min) if rel[k] <= threshold] + list(range(k_min, m))
    groups = []
    for k in idx:
        u = U[:, k]
        big = np.abs(u).max()
        rows_k = [int(i) for i in np.nonzero(np.abs(u) >= weight * big)[0]]
        byc: dict = {}
        for i in rows_k:
            o = lay.eq_owner[i]
            e = byc.setdefault(id(o), [_label(o), [], 0.0])
            e[1].append(lay.eq_index[i] + 1)
            e[2] = max(e[2], float(abs(u[i]) / big))
        coords = []
        if k < n:
            v = Vt[k]
            vb = np.abs(v).max()
            coords = [(lay.q_names[j], float(v[j] / vb)) for j in np.nonzero(np.abs(v) >= weight * vb)[0]]
        groups.append({"value": float(rel[k]) if k < k_min else 0.0,
                       "constraints": [tuple(e) for e in byc.values()], "coordinates": coords})
    singular = rcond <= threshold
    where = f"at t = {t:.6g}"
    if not groups:
        text = (f"constraint Jacobian {where}: regular (reciprocal condition {rcond:.2e} > "
                f"threshold {threshold:.0e}, rank {rank} of {m} equations, {n} coordinates)")
    else:
        kind = "singular" if rcond == 0.0 or m > n else "nearly singular"
        lines = [f"constraint Jacobian {where}: {kind} (reciprocal condition {rcond:.2e}, rank "
                 f"{rank} of {m} equations, {n} coordinates); {len(groups)} dependent "
                 "combination(s) of equations:"]
        for g in groups:
            cs = ", ".join(f"{lab} (equation{'s' if len(eq) > 1 else ''} "
                           f"{', '.join(map(str, eq))})" for lab, eq, _ in g["constraints"])
            line = f"  s/s_max = {g['value']:.1e}: {cs}"
            if g["coordinates"]:
                line += "; uncontrolled motion along " + ", ".join(nm for nm, _ in g["coordinates"])
            lines.append(line)
        lines.append("  Either these constraints are redundant (remove or relax the dependent "
                     "equations), or the mechanism is at (or near) a toggle/lock-up position "
                     "where it cannot be driven as specified (move the driver, or drive another "
                     "joint).")
        text = "\n".join(lines)
    return SingularityReport(t, rcond, singular, rank, float(threshold), S / smax, groups, text)


# -- hooks (Mech's $MechPreSolve and $MechPostIterate) ------------------------------------------
@dataclass(frozen=True)
class Iteration:
    r"""What ``post_iterate`` receives after each Newton iteration of a position solve.

    t: time; iteration: 1, 2, ...; q: the new iterate (a copy, in layout order ``m.guess()``);
    residual: its scaled residual :math:`\max_i \lvert \Phi_i \rvert / r_i`; step: the Newton
    step taken (after damping); names: the coordinate names of ``q``.
    """

    t: float
    iteration: int
    q: np.ndarray
    residual: float
    step: np.ndarray
    names: tuple


@dataclass(frozen=True)
class Hooks:
    """``pre_solve(t)`` before each position solve of a sweep, ``post_iterate(Iteration)``
    after each Newton iteration; a hook returning ``False`` stops the solve."""

    pre_solve: object = None
    post_iterate: object = None

    @classmethod
    def make(cls, pre_solve, post_iterate) -> Hooks | None:
        for nm, f in (("pre_solve", pre_solve), ("post_iterate", post_iterate)):
            if f is not None and not callable(f):
                raise ModelError(f"solve: {nm} must be a callable (a function of "
                                 f"{'the time t' if nm == 'pre_solve' else 'an Iteration'}) or "
                                 f"None, got {f!r}")
        if pre_solve is None and post_iterate is None:
            return None
        return cls(pre_solve, post_iterate)


class Stopped(Exception):
    """Internal: a hook returned False (``Model.solve`` turns it into a partial solution or
    a :class:`~mechsys.MechError`)."""

    def __init__(self, hook: str, t: float, iteration: int | None = None):
        super().__init__(hook, t, iteration)
        self.hook, self.t, self.iteration = hook, t, iteration
        self.k = 0  # points completed before the stop (set by the sweep)

    def describe(self) -> str:
        if self.hook == "interrupted":       # (KeyboardInterrupt: Ctrl-C or a progress callback)
            return f"interrupted (KeyboardInterrupt) before t = {self.t:.6g}"
        at = f" at iteration {self.iteration}" if self.iteration is not None else ""
        return f"{self.hook} returned False at t = {self.t:.6g}{at}"
