r"""Branch guards of angle equations: telling the asked angle from the angle plus pi.

A rotational driver in its regular form (``RotationLock1`` with axes, ``RelativeAngle1`` in
2D, the 2D body form in Euler-parameter coordinates) is ``|f_p| sin(phi - a) = 0``: it holds
at ``phi = a`` and at ``phi = a + pi``, and Newton converges to either, whichever the guess is
nearer. No single smooth equation of an angle can avoid this (a periodic function has an
even number of zeros per turn), so the solvers test the root instead: with
``cos_err = |f_p| cos(phi - a)`` (:class:`~mechsys.constraints._angles.Branch`),

* a configuration with ``cos_err < 0`` (a guess or a sweep's prediction more than a quarter
  turn from the asked angle) is *aligned* before Newton starts: the body carrying the angle
  is turned by ``-(phi - a) = -atan2(sin_err, cos_err)`` about the axis (through the axis'
  origin), which puts ``phi`` on ``a`` and leaves a revolute about that axis assembled;
* a converged solution with ``cos_err < 0`` is on the wrong branch: it is aligned (turned
  by pi) and solved again, and a solution still on the wrong branch raises
  :class:`~mechsys.ConvergenceError` naming the constraint (decision 0033).

The guard is numeric (compiled once per system, like the kinematic kernels, as a function of
``[t, q, qd, p]``), so the solvers use it through ``system.branch_guard``.
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


class BranchGuard:
    """The branch tests of one system's angle equations (see the module doc)."""

    def __init__(self, system, items: list):
        lay = system.layout
        sub = getattr(system, "gen_subs", None) or {}
        space = system.space
        self.items = items
        self.labels = [it.owner.label() for it in items]
        self.kind = ("spatial" if space.dim == 3 else
                     "euler" if getattr(space, "orientation", "angle") == "euler" else "planar")
        self.dim = space.dim
        self.slices = []
        exprs = []
        for it in items:
            sl = None
            if it.body is not None and it.origin is not None:
                sl = lay.body_slices.get(it.body.name)
            self.slices.append(sl)
            parts = [it.cos_err, it.sin_err]
            if sl is not None:
                parts += list(it.origin)
                if self.dim == 3:
                    parts += list(it.axis)
            exprs += [sp.sympify(e).xreplace(sub) if sub else sp.sympify(e) for e in parts]
        self.size = [2 + (0 if sl is None else self.dim + (3 if self.dim == 3 else 0))
                     for sl in self.slices]
        # compiled like the kinematic kernels (a few evaluations per solve: unoptimised LLVM,
        # cheap to build; a lambdified NumPy function cost ~0.3 ms a call)
        self._f = compile_exprs(lay.args(), exprs, system.backend, once=True, cse=True)
        self._pack = system.pack

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
        at, turned = 0, False
        for j, size in enumerate(self.size):
            c, s = float(vals[at][0]), float(vals[at + 1][0])
            h = math.hypot(c, s)
            sl = self.slices[j]
            if sl is not None and h > 0 and c < WRONG * h:
                err = math.atan2(s, c)               # phi - a
                o = np.array([float(v[0]) for v in vals[at + 2: at + 2 + self.dim]])
                u = None
                if self.dim == 3:
                    u = np.array([float(v[0]) for v in vals[at + 2 + self.dim: at + size]])
                    nu = np.linalg.norm(u)
                    if not nu > 0:
                        at += size
                        continue
                    u = u / nu
                q[sl] = turn(self.kind, q[sl], self.items[j].sign * err, o, u)
                turned = True
                # later items are evaluated at the configuration before this turn: one pass
                # serves independent drivers; a second (rare) is left to the converged check
            at += size
        return q if turned else None

    def describe(self, bad, t) -> str:
        names = ", ".join(self.labels[j] for j in bad)
        return (f"position solve at t = {t:.6g}: {names} converged to the asked angle plus pi "
                "(its equation also holds half a turn off), and turning the body onto the asked "
                "angle and solving again did not reach it. Give a guess nearer the asked angle "
                "(add_body(..., guess=...) or guess=), or, in a sweep, finer time steps.")


def turn(kind: str, qb, angle: float, origin, axis=None) -> np.ndarray:
    """A body's coordinates ``qb`` turned rigidly by ``angle`` (rad) about the global
    ``axis`` (unit; 2D: the plane's normal) through the global point ``origin``:
    ``r' = o + R (r - o)``, ``A' = R A``. Angle coordinates add ``angle``; planar Euler
    parameters ``(ei, ej)`` turn as a 2D vector; spatial Euler parameters are multiplied on
    the left by the rotation's, ``p' = (cos(angle/2), sin(angle/2) u) p`` (Hamilton product)."""
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


def make_guard(system) -> BranchGuard | None:
    """The :class:`BranchGuard` of a system's angle equations, or None when it has none."""
    items, seen = [], set()
    for owner in system.layout.eq_owner:
        if id(owner) in seen or not hasattr(owner, "branch"):
            continue
        seen.add(id(owner))
        try:
            it = owner.branch(system.space)
        except (MechError, TypeError, ValueError, AttributeError):
            it = None       # geometry the test cannot take (the equations were built): no test
        if it is not None:
            items.append(it)
    return BranchGuard(system, items) if items else None
