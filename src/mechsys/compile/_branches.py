r"""Branch guards of angle equations: telling the asked angle from the angle plus pi.

A rotational driver in its regular form (``RotationLock1`` with axes, ``RelativeAngle1`` in
2D, the 2D body form in Euler-parameter coordinates) is :math:`\lvert f_p \rvert \sin(\phi - a) = 0`: it holds
at ``phi = a`` and at ``phi = a + pi``, and Newton converges to either, whichever the guess is
nearer. No single smooth equation of an angle can avoid this (a periodic function has an
even number of zeros per turn), so the solvers test the root instead: with
:math:`\mathit{cos\_err} = \lvert f_p \rvert \cos(\phi - a)` (:class:`~mechsys.constraints._angles.Branch`),

* a configuration with ``cos_err < 0`` (a guess or a sweep's prediction more than a quarter
  turn from the asked angle) is *aligned* before Newton starts: the body carrying the angle
  is turned by :math:`-(\phi - a) = -\operatorname{atan2}(\mathit{sin\_err}, \mathit{cos\_err})` about the
  axis (through the axis'
  origin), which puts ``phi`` on ``a`` and leaves a revolute about that axis assembled;
* a converged solution with ``cos_err < 0`` is on the wrong branch: it is aligned (turned
  by pi) and solved again, and a solution still on the wrong branch raises
  :class:`~mechsys.ConvergenceError` naming the constraint (decision 0033).

A body that is the slave of a Gen joint (Mech ch. 11) has no coordinates of its own: it is
turned through the generalized coordinates of its joint (the body's own joint first, then up
its chain of masters), by Newton's method on ``phi - a`` over those coordinates (one step for
the revolute joints, where the angle is linear in the joint's angle); the first regular body
up the chain is turned rigidly as above, carrying its slaves.

The guard is numeric (compiled once per system, like the kinematic kernels, as a function of
``[t, q, qd, p]``), so the solvers use it through ``system.branch_guard``. A stage system of
a model with switches (``StageSwitch``/``TimeSwitch``, ``compile/_stages.py``) has the guard
of the drivers of its own stages (``system.switch_stages``): each stage combination tests the
angles it asks for.
"""

from __future__ import annotations

import math

import numpy as np
import sympy as sp

from .._errors import MechError
from ._backends import compile_exprs

#: ``cos_err / hypot(cos_err, sin_err)`` below this is the wrong branch (a quarter turn off
#: and more); the margin keeps rounding at a right angle from flipping a regular guess
WRONG = -1e-6

#: a guess is turned onto the asked angle when ``cos_err / hypot`` is below this: the wrong
#: side, and a quarter turn off to within 1e-6 rad, where the equation's derivative
#: ``|f_p| cos(phi - a)`` vanishes and Newton cannot start (a sweep whose steps turn a crank
#: by exactly a quarter turn predicted such guesses and stopped on a singular Jacobian)
ALIGN = 1e-6

#: turning a Gen joint's slave through the joint's coordinates (:meth:`BranchGuard.align`):
#: at most this many Newton steps, to this angle error (rad), with central differences of
#: this step (rad or length units); a squared gain below ``MIN_GAIN`` means the coordinates
#: do not turn the angle (a sliding joint: its master is turned instead)
TURN_STEPS = 8
TURN_TOL = 1e-12
DIFF_STEP = 1e-6
MIN_GAIN = 1e-8


class BranchGuard:
    """The branch tests of one system's angle equations (see the module doc). ``labels``:
    the name of each item's constraint in messages (default: its owner's label)."""

    def __init__(self, system, items: list, labels: list | None = None):
        lay = system.layout
        sub = getattr(system, "gen_subs", None) or {}
        space = system.space
        self.items = items
        self.labels = list(labels) if labels is not None else [it.owner.label() for it in items]
        self.kind = ("spatial" if space.dim == 3 else
                     "euler" if getattr(space, "orientation", "angle") == "euler" else "planar")
        self.dim = space.dim
        self.slices = []      # the regular body turned rigidly (None: none)
        self.gen_cols = []    # per item: the coordinate indices of each Gen joint up the chain
        exprs = []
        for it in items:
            sl, cols, body = None, [], it.body
            # a Gen joint's slave is turned through its joint's coordinates, then its masters'
            while body is not None and getattr(body, "gen_joint", None) is not None:
                joint = body.gen_joint
                idx = [lay.q_symbols.index(c) for c in joint.coordinates
                       if c in lay.q_symbols]
                if idx:       # (a system that fixed the joint's coordinates has none)
                    cols.append((body, np.array(idx, dtype=int)))
                body = joint.master
                if body is not None and getattr(body, "is_ground", False):
                    body = None
            if body is not None and it.origin is not None:
                sl = lay.body_slices.get(body.name)
            self.slices.append(sl)
            self.gen_cols.append(cols)
            parts = [it.cos_err, it.sin_err]
            if sl is not None:
                parts += list(it.origin)
                if self.dim == 3:
                    parts += list(it.axis)
            exprs += [sp.sympify(e).xreplace(sub) if sub else sp.sympify(e) for e in parts]
        self.size = [2 + (0 if sl is None else self.dim + (3 if self.dim == 3 else 0))
                     for sl in self.slices]
        self.offsets = list(np.cumsum([0, *self.size[:-1]]))
        # compiled like the kinematic kernels (a few evaluations per solve: unoptimised LLVM,
        # cheap to build; a lambdified NumPy function cost ~0.3 ms a call)
        self._f = compile_exprs(lay.args(), exprs, system.backend, once=True, cse=True)
        self._pack = system.pack
        self._system = system
        self._orient = None   # the slaves' rotation coordinates, compiled on first need

    def _values(self, t, Q, p) -> list:
        """The expressions at the rows of ``Q`` ((N, n)) and times ``t`` ((N,)): a list of
        (N,) arrays."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        t = np.broadcast_to(np.asarray(t, dtype=float), (len(Q),))
        out = np.array([np.asarray(self._f(self._pack(ti, qi, None, p)), dtype=float).ravel()
                        for ti, qi in zip(t, Q)])
        return list(out.T)

    def wrong_rows(self, t, Q, p=None) -> np.ndarray:
        """(N, items) bool: row ``i`` is on the wrong branch of item ``j``."""
        vals = self._values(t, Q, p)
        out = np.zeros((len(vals[0]) if vals else 0, len(self.items)), dtype=bool)
        at = 0
        for j, size in enumerate(self.size):
            c, s = vals[at], vals[at + 1]
            h = np.hypot(c, s)
            with np.errstate(invalid="ignore", divide="ignore"):
                out[:, j] = (h > 0) & (c < WRONG * h)
            at += size
        return out

    def wrong(self, t, q, p=None) -> list:
        """Indices of the items whose branch test fails at ``(t, q)``."""
        return list(np.flatnonzero(self.wrong_rows(t, q, p)[0]))

    def align(self, t, q, p=None):
        """``q`` with each body whose angle is on the wrong side turned onto its asked angle
        (a copy), or None when every test passes or no failing item can be turned."""
        q = np.array(q, dtype=float)
        vals = self._values(t, q, p)
        turned = False
        for j, size in enumerate(self.size):
            at = self.offsets[j]
            c, s = float(vals[at][0]), float(vals[at + 1][0])
            h = math.hypot(c, s)
            if not (h > 0 and c < ALIGN * h):
                continue
            # later items are evaluated at the configuration before this turn: one pass
            # serves independent drivers; a second (rare) is left to the converged check
            moved = None
            for body, cols in self.gen_cols[j]:
                moved = self._turn_coordinates(t, q, p, j, cols)
                if moved is not None:
                    # the body's own slaves keep their orientations, as a rigid turn of a
                    # body with coordinates of its own leaves the other bodies where they are
                    moved = self._keep_descendants(t, q, moved, p, body)
                    break
            if moved is not None:
                q, turned = moved, True
                continue
            sl = self.slices[j]
            if sl is None:
                continue
            err = math.atan2(s, c)               # phi - a
            o = np.array([float(v[0]) for v in vals[at + 2: at + 2 + self.dim]])
            u = None
            if self.dim == 3:
                u = np.array([float(v[0]) for v in vals[at + 2 + self.dim: at + size]])
                nu = np.linalg.norm(u)
                if not nu > 0:
                    continue
                u = u / nu
            q[sl] = turn(self.kind, q[sl], self.items[j].sign * err, o, u)
            turned = True
        return q if turned else None

    def _error(self, t, q, p, j: int) -> float:
        """``phi - a`` of item ``j`` at ``(t, q)`` (rad, in ``(-pi, pi]``; NaN when the
        angle is undefined)."""
        v = np.asarray(self._f(self._pack(t, q, None, p)), dtype=float).ravel()
        c, s = v[self.offsets[j]], v[self.offsets[j] + 1]
        return math.atan2(s, c) if math.hypot(c, s) > 0 else math.nan

    def _turn_coordinates(self, t, q, p, j: int, cols: np.ndarray):
        """``q`` with the generalized coordinates ``cols`` of one Gen joint moved so that item
        ``j``'s angle reaches the asked one, or None when they do not turn it.

        Newton on ``e(q) = phi - a`` with the minimum-norm step over ``cols``:
        :math:`\\Delta q = -e\\, g / (g^T g)`, :math:`g = \\partial e / \\partial q_{cols}`
        by central differences (``e`` is smooth near its root; a revolute joint's angle is
        linear in ``phi``: one step)."""
        q = q.copy()
        e = self._error(t, q, p, j)
        for _ in range(TURN_STEPS):
            if not math.isfinite(e):
                return None
            if abs(e) <= TURN_TOL:
                break
            g = np.empty(len(cols))
            for i, c in enumerate(cols):
                hi, lo = q.copy(), q.copy()
                hi[c] += DIFF_STEP
                lo[c] -= DIFF_STEP
                # differences of wrapped angles: the wrap at +-pi must not enter g
                g[i] = math.remainder(self._error(t, hi, p, j) - self._error(t, lo, p, j),
                                      2 * math.pi) / (2 * DIFF_STEP)
            gg = float(g @ g)
            if not gg > MIN_GAIN:   # these coordinates do not turn this angle
                return None
            q[cols] -= e * g / gg
            e = self._error(t, q, p, j)
        return q if math.isfinite(e) and abs(e) < math.pi / 2 else None

    def _descendants(self, body) -> list:
        """The Gen-joint slaves whose chain of masters passes through ``body``."""
        out = []
        for b in self._system._bodies:
            m = b.gen_joint.master if getattr(b, "gen_joint", None) is not None else None
            while m is not None and m is not body:
                m = m.gen_joint.master if getattr(m, "gen_joint", None) is not None else None
            if m is body:
                out.append(b)
        return out

    def _orientations(self, t, q, p, bodies) -> list:
        """The rotation coordinates of the slave ``bodies`` at ``(t, q)`` (one array each)."""
        if self._orient is None:
            sys_ = self._system
            slaves = [b for b in sys_._bodies if getattr(b, "gen_joint", None) is not None]
            exprs, at = [], {}
            for b in slaves:
                rot = list(b.q[self.dim:])
                at[b.name] = slice(len(exprs), len(exprs) + len(rot))
                exprs += [sp.sympify(sys_.gen_subs.get(c, c)) for c in rot]
            self._orient = (compile_exprs(sys_.layout.args(), exprs, sys_.backend, once=True,
                                          cse=True), at)
        f, at = self._orient
        v = np.asarray(f(self._pack(t, q, None, p)), dtype=float).ravel()
        return [v[at[b.name]] for b in bodies]

    def _turned_by(self, old, new) -> np.ndarray:
        """The rotation from each ``old`` orientation to the ``new`` one, as a residual that
        vanishes only when they are the same rotation: the angle (2D), the vector part of
        ``old^-1 new`` with a non-negative scalar part (3D)."""
        out = []
        for o, n in zip(old, new):
            if self.kind == "planar":
                out.append([math.remainder(n[0] - o[0], 2 * math.pi)])
            elif self.kind == "euler":
                out.append([math.atan2(o[0] * n[1] - o[1] * n[0], o[0] * n[0] + o[1] * n[1])])
            else:
                w = o[0] * n[0] + o[1:] @ n[1:]
                v = o[0] * n[1:] - n[0] * o[1:] - np.cross(o[1:], n[1:])
                out.append(v if w >= 0 else -v)
        return np.concatenate(out) if out else np.zeros(0)

    def _keep_descendants(self, t, q_old, q, p, body):
        """``q`` with the coordinates of ``body``'s Gen-joint descendants moved so that each
        keeps its orientation at ``q_old``: Gauss-Newton, minimum-norm steps (``lstsq``),
        central differences; what the joints cannot hold (a sliding joint) is left."""
        desc = self._descendants(body)
        if not desc:
            return q
        qs = self._system.layout.q_symbols
        cols = np.array(sorted({qs.index(c) for b in desc for c in b.gen_joint.coordinates
                                if c in qs}), dtype=int)
        if not cols.size:
            return q
        target = self._orientations(t, q_old, p, desc)
        q = q.copy()
        r = self._turned_by(target, self._orientations(t, q, p, desc))
        for _ in range(TURN_STEPS):
            if not np.all(np.isfinite(r)) or np.abs(r).max() <= TURN_TOL:
                break
            J = np.empty((len(r), len(cols)))
            for i, c in enumerate(cols):
                hi, lo = q.copy(), q.copy()
                hi[c] += DIFF_STEP
                lo[c] -= DIFF_STEP
                J[:, i] = (self._turned_by(target, self._orientations(t, hi, p, desc))
                           - self._turned_by(target, self._orientations(t, lo, p, desc))
                           ) / (2 * DIFF_STEP)
            step = np.linalg.lstsq(J, r, rcond=None)[0]
            q_new = q.copy()
            q_new[cols] -= step
            r_new = self._turned_by(target, self._orientations(t, q_new, p, desc))
            if not np.abs(r_new).max() < np.abs(r).max():
                break           # held as far as the joints allow
            q, r = q_new, r_new
        return q

    def describe(self, bad, t) -> str:
        names = ", ".join(self.labels[j] for j in bad)
        fixed = [j for j in bad if self.slices[j] is None and not self.gen_cols[j]]
        why = ("turning the body onto the asked angle and solving again did not reach it"
               if not fixed else
               "no single moving body carries the angle of "
               + ", ".join(self.labels[j] for j in fixed)
               + " (its vectors are on ground, between points or global), so the solver "
                 "cannot turn it onto the asked angle")
        return (f"position solve at t = {t:.6g}: {names} converged to the asked angle plus pi "
                f"(its equation also holds half a turn off), and {why}. Give a guess nearer the "
                "asked angle (add_body(..., guess=...) or guess=), or, in a sweep, finer time "
                "steps.")


def turn(kind: str, qb, angle: float, origin, axis=None) -> np.ndarray:
    r"""A body's coordinates ``qb`` turned rigidly by ``angle`` (rad) about the global
    ``axis`` (unit; 2D: the plane's normal) through the global point ``origin``:
    :math:`r' = o + R (r - o)`, :math:`A' = R A`. Angle coordinates add ``angle``; planar Euler
    parameters ``(ei, ej)`` turn as a 2D vector; spatial Euler parameters are multiplied on
    the left by the rotation's, :math:`p' = (\cos(\mathit{angle}/2), \sin(\mathit{angle}/2) u) p` (Hamilton
    product)."""
    qb = np.array(qb, dtype=float)
    c, s = math.cos(angle), math.sin(angle)
    if kind in ("planar", "euler"):
        R = np.array([[c, -s], [s, c]])
        qb[:2] = origin + R @ (qb[:2] - origin)
        if kind == "planar":
            qb[2] += angle
        else:
            qb[2:4] = R @ qb[2:4]
        return qb
    u = np.asarray(axis, dtype=float)
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    R = np.eye(3) + s * K + (1 - c) * (K @ K)        # Rodrigues
    qb[:3] = origin + R @ (qb[:3] - origin)
    w1, v1 = math.cos(angle / 2), math.sin(angle / 2) * u
    w2, v2 = qb[3], qb[4:7].copy()
    qb[3] = w1 * w2 - v1 @ v2
    qb[4:7] = w1 * v2 + w2 * v1 + np.cross(v1, v2)
    return qb


def _constraints(system):
    """``(constraint, label)`` of every constraint whose equations the system holds, once:
    a switch (StageSwitch, TimeSwitch) gives the constraints of the stage its rows come from
    (``system.switch_stages``; a model's own system holds every switch's first stage)."""
    stages = getattr(system, "switch_stages", None) or {}
    seen = set()
    for owner in system.layout.eq_owner:
        if id(owner) in seen:
            continue
        seen.add(id(owner))
        if hasattr(owner, "stage_equations"):
            k = stages.get(id(owner), 0)
            if k is None:         # dropped in this stage (free motion): only its held rows
                continue
            for c in owner.stages[k]:
                yield c, f"{owner.label()}, {owner.stage_label(k)}"
        elif hasattr(owner, "branch"):
            yield owner, owner.label()


def make_guard(system) -> BranchGuard | None:
    """The :class:`BranchGuard` of a system's angle equations, or None when it has none."""
    items, labels = [], []
    for c, label in _constraints(system):
        if not hasattr(c, "branch"):
            continue
        try:
            it = c.branch(system.space)
        except (MechError, TypeError, ValueError, AttributeError):
            it = None       # geometry the test cannot take (the equations were built): no test
        if it is not None:
            items.append(it)
            labels.append(label)
    return BranchGuard(system, items, labels) if items else None
