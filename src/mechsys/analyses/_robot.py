r"""Robot-style entry points on generalized-coordinate models (decision 0040):
``m.inverse_dynamics(q, qd, qdd)`` and ``m.forward_dynamics(q, qd, tau)``.

Both evaluate the model's equations of motion in its coordinates,
:math:`M(q) \ddot q = Q(q, \dot q, t) + Q_v(q, \dot q) + \tau` (:math:`Q` the model's loads,
gravity included; :math:`Q_v` the velocity terms; :math:`\tau` the joint forces, a torque on
an angle and a force on a slide), with the compiled terms the model already uses for free
motion (the recursive composite-body dynamics of decision 0016 from 4 spatial Gen joints on,
the symbolic projection below; no second algorithm):

.. math::

    \tau &= M \ddot q - Q - Q_v \qquad \text{(inverse dynamics)} \\
    \ddot q &= M^{-1} (Q + Q_v + \tau) \qquad \text{(forward dynamics, Cholesky)}

They apply to models whose coordinates are all generalized coordinates and which have no
constraint equation (a tree of Gen joints on ground: what ``from_urdf`` builds for a
fixed-base robot).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import ModelError


@dataclass(frozen=True)
class JointValues:
    """Values per joint coordinate over ``N`` points: ``values`` is ``(N, n)`` (``(n,)`` for
    one point), ``names`` the coordinates' names in column order; ``jv["elbow_joint"]`` is
    one column (or number)."""

    names: tuple
    values: np.ndarray

    def __getitem__(self, name: str):
        try:
            k = self.names.index(name)
        except ValueError:
            raise ModelError(f"no joint coordinate named {name!r}; the coordinates are "
                             f"{list(self.names)}") from None
        return self.values[..., k]

    def __array__(self, dtype=None, copy=None):
        return self.values if dtype is None else self.values.astype(dtype)

    def __len__(self) -> int:
        return len(self.names)

    def to_dict(self) -> dict:
        """``{name: values}``."""
        return {n: self[n] for n in self.names}


def _system(m, what: str):
    s = m.compile()
    if s.m:
        raise ModelError(f"{what} needs a model in generalized coordinates without constraint "
                         f"equations (a tree of Gen joints on ground); this one has {s.m} equations "
                         "(absolute bodies or closing constraints): use m.free().solve(...) for it")
    return s


def _points(s, value, what: str) -> tuple[np.ndarray, bool]:
    """``value`` as ``(N, n)`` in layout order, and whether it was a single point. A mapping
    ``{name: values}`` must name every coordinate."""
    names = list(s.layout.q_names)
    if isinstance(value, dict):
        missing = [n for n in names if n not in value]
        extra = [k for k in value if k not in names]
        if missing or extra:
            raise ModelError(f"{what}: give a value for each coordinate {names}"
                             + (f"; missing {missing}" if missing else "")
                             + (f"; unknown {extra}" if extra else ""))
        cols = [np.atleast_1d(np.asarray(value[n], dtype=float)) for n in names]
        single = all(np.ndim(value[n]) == 0 for n in names)
        try:
            arr = np.column_stack(np.broadcast_arrays(*cols))
        except ValueError:
            raise ModelError(f"{what}: the coordinates' values have different lengths") from None
    else:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"{what}: expected numbers, got {value!r}") from None
        single = arr.ndim == 1
        arr = np.atleast_2d(arr)
        if arr.ndim != 2 or arr.shape[1] != len(names):
            raise ModelError(f"{what}: expected shape (n,) or (N, n) with n = {len(names)} "
                             f"coordinates {names}, got {np.shape(value)}")
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"{what}: values must be finite")
    return arr, single


def _inputs(m, what, q, qd, x, xname):
    s = _system(m, what)
    Q, single = _points(s, q, f"{what}: q")
    QD, _ = _points(s, qd, f"{what}: qd")
    X, _ = _points(s, x, f"{what}: {xname}")
    N = max(len(Q), len(QD), len(X))
    try:
        Q, QD, X = (np.broadcast_to(a, (N, s.n)) for a in (Q, QD, X))
    except ValueError:
        raise ModelError(f"{what}: q, qd and {xname} have different numbers of points "
                         f"({len(Q)}, {len(QD)}, {len(X)})") from None
    return s, Q, QD, X, single


def inverse_dynamics(m, q, qd, qdd, t: float = 0.0) -> JointValues:
    r"""Joint forces ``tau = M(q) qdd - Q - Qv`` (see the module doc) at one point (``(n,)``
    arrays) or many (``(N, n)``), or from ``{joint name: values}``."""
    s, Q, QD, X, single = _inputs(m, "inverse_dynamics", q, qd, qdd, "qdd")
    d = s.dynamics
    p = s.p_values
    lam = np.zeros(0)
    out = np.empty((len(Q), s.n))
    for k in range(len(Q)):
        M, F, Fv = d.terms(float(t), Q[k], QD[k], lam, p)[:3]
        out[k] = M @ X[k] - F - Fv
    return JointValues(tuple(s.layout.q_names), out[0] if single else out)


def forward_dynamics(m, q, qd, tau, t: float = 0.0) -> JointValues:
    r"""Joint accelerations ``qdd = M(q)^-1 (Q + Qv + tau)`` (see the module doc) at one
    point or many. A mass matrix that is not positive definite (a joint that moves no mass)
    raises ``SingularMassError`` naming the joint."""
    from .._errors import SingularMassError

    s, Q, QD, X, single = _inputs(m, "forward_dynamics", q, qd, tau, "tau")
    d = s.dynamics
    p = s.p_values
    lam = np.zeros(0)
    out = np.empty((len(Q), s.n))
    names = tuple(s.layout.q_names)
    for k in range(len(Q)):
        M, F, Fv = d.terms(float(t), Q[k], QD[k], lam, p)[:3]
        try:
            L = np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            diag = np.diag(M)
            bad = [names[i] for i in range(s.n) if not diag[i] > 1e-14 * max(1.0, abs(diag).max())]
            raise SingularMassError(f"forward_dynamics: the mass matrix is singular at point {k}"
                                    + (f"; joints {bad} move no mass" if bad else "")
                                    + "; give the bodies they carry mass and inertia") from None
        y = np.linalg.solve(L, F + Fv + X[k])
        out[k] = np.linalg.solve(L.T, y)
    return JointValues(names, out[0] if single else out)


def forward_kinematics(m, q, point, t: float = 0.0, frame: bool = False) -> np.ndarray:
    r"""Global location ``r_b + A_b s'`` of ``point`` (a point of a body, ``body.point(...)``,
    or a link frame's name after ``from_urdf``/``from_mjcf``; or a list of them, evaluated
    together) at the coordinates ``q`` (``(n,)`` -> ``(3,)``, ``(N, n)`` -> ``(N, 3)``, or
    ``{name: values}``; a list of ``k`` points adds an axis: ``(k, 3)``, ``(N, k, 3)``).
    ``frame=True``: the 4x4 homogeneous pose instead (``[A_b R_f, r_b + A_b s']``, ``R_f`` a
    link frame's rotation on its body, identity for a body point). Poses of slave bodies come
    from the recursive dynamics' forward pass when the model uses it (no nested expression
    compiled), else from the compiled body coordinates."""
    s = m.compile()          # constraint equations allowed: q gives every coordinate
    many = isinstance(point, (list, tuple)) and not (len(point) == 3 and all(
        isinstance(v, (int, float)) for v in point))
    items = list(point) if many else [point]
    rep = getattr(m, "import_report", None)
    spec = []                                   # (body, local point, local rotation)
    for p_ in items:
        if isinstance(p_, str):
            if rep is None or p_ not in rep.frames:
                raise ModelError(f"forward_kinematics: {p_!r} is not a link frame of the imported "
                                 "model; give a body point (body.point(...))")
            bname, loc, R = rep.frames[p_]
            spec.append((m.body(bname), np.asarray(loc, float), np.asarray(R, float)))
        else:
            try:
                loc = np.array([float(v) for v in p_.local], dtype=float)
            except (AttributeError, TypeError):
                raise ModelError(f"forward_kinematics: {p_!r} is not a body point with numeric "
                                 "local coordinates, nor a link name") from None
            spec.append((p_.body if p_.body is not None else m.ground, loc, np.eye(3)))
    Q, single = _points(s, q, "forward_kinematics: q")
    bodies = list(dict.fromkeys(b for b, _, _ in spec))
    poses = _body_poses(s, Q, bodies, t)        # (N, nb, 4, 4)
    col = {b: i for i, b in enumerate(bodies)}
    out = np.empty((len(Q), len(spec), 4, 4))
    for i, (b, loc, R) in enumerate(spec):
        P = poses[:, col[b]]
        out[:, i] = np.eye(4)
        out[:, i, :3, :3] = P[:, :3, :3] @ R
        out[:, i, :3, 3] = P[:, :3, 3] + np.einsum("nij,j->ni", P[:, :3, :3], loc)
    if not frame:
        out = out[:, :, :3, 3]
    if not many:
        out = out[:, 0]
    return out[0] if single else out


def _euler_matrix(e) -> np.ndarray:
    e0, e1, e2, e3 = e
    return 2 * np.array([[e0 * e0 + e1 * e1 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2],
                         [e1 * e2 + e0 * e3, e0 * e0 + e2 * e2 - 0.5, e2 * e3 - e0 * e1],
                         [e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0 * e0 + e3 * e3 - 0.5]])


def _body_poses(s, Q, bodies, t) -> np.ndarray:
    """``(N, k, 4, 4)`` homogeneous poses of ``bodies`` at the coordinates ``Q``."""
    from ..compile._generalized import _slave_order

    d = s.dynamics
    recursive = getattr(d, "recursive", False)
    order = {b: i for i, b in enumerate(_slave_order(s._bodies))} if recursive else {}
    lay = s.layout
    out = np.zeros((len(Q), len(bodies), 4, 4))
    out[:, :, 3, 3] = 1.0
    symbolic = [b for b in bodies if not b.is_ground and not (recursive and b in order)
                and b.name not in lay.body_slices]
    f = None
    if symbolic:
        f = s.compile_expression([e for b in symbolic for e in (*b.r, *b.A)])
    zero, lam = np.zeros(s.n), np.zeros(s.m)
    for k, q in enumerate(Q):
        P = d._forward(float(t), q, zero, lam, s.p_values)[2]["P"] if recursive else None
        vals = None
        if f is not None:
            vals = np.asarray(f(np.concatenate(([t], q, np.zeros(2 * s.n + s.m), s.p_values))),
                              dtype=float).reshape(len(symbolic), 12)
        for i, b in enumerate(bodies):
            if b.is_ground:
                out[k, i, :3, :3] = np.eye(3)
                continue
            if recursive and b in order:
                pose = P[order[b]]
            elif b.name in lay.body_slices:
                pose = q[lay.body_slices[b.name]]
            else:
                v = vals[symbolic.index(b)]
                out[k, i, :3, 3], out[k, i, :3, :3] = v[:3], v[3:].reshape(3, 3)
                continue
            out[k, i, :3, 3] = pose[:3]
            out[k, i, :3, :3] = _euler_matrix(pose[3:7])
    return out
