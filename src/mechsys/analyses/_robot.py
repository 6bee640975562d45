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

On a model without constraint equations (a tree of Gen joints on ground: what
``from_urdf`` builds for a fixed-base robot) every coordinate is a joint coordinate.

A model with constraint equations :math:`\Phi(q, t) = 0` (absolute bodies: ``coordinates=
"absolute"``, a floating base, closed loops) moves by the augmented system of free motion,
with the joint forces ``tau`` acting on the *actuated* coordinates only (``S`` selects them;
by default every coordinate that is not an absolute body's, i.e. the joint coordinates):

.. math::

    M \ddot q + \Phi_q^T \lambda &= Q + Q_v + S^T \tau \\
    \Phi_q \ddot q &= \gamma

Forward dynamics solves it for :math:`(\ddot q, \lambda)`; inverse dynamics solves the first rows for
``(lambda, tau)`` (least squares, then checked: the state must satisfy the constraints, the
unactuated rows must balance -- a floating base's acceleration is not free to choose -- and
``tau`` must be unique, i.e. no actuated coordinate may be moved by the constraints alone).
A mapping ``{name: values}`` may name only some coordinates (as many as the model has
degrees of freedom, e.g. the joint coordinates); the others are then solved from the
constraints: positions by the Gauss-Newton solver that keeps given coordinates
(``solvers/_free.hold_positions``, the one free motion starts with) from the model's guess
(continued in steps of at most ``0.25`` in the given coordinates, so the branch is the
guess's), velocities from :math:`\Phi_q \dot q = -\Phi_t` and accelerations from
:math:`\Phi_q \ddot q = \gamma`.

Over many points (from :data:`AUTO_POINTS` with ``MECHSYS_JIT`` unset) the recursive Gen
dynamics runs compiled: inverse dynamics on a model without equations, and forward dynamics
on any model with the recursive dynamics (the Cholesky factor of ``M`` without equations,
the augmented system by LU with regular pivots with them), are one compiled loop over the
points (``solvers._jit_gen_points``, decisions 0057 and 0073), which hands a point it cannot
take (a mass matrix that is not positive definite, a redundant system) and the rest to the
Python loop; over few, the plain-Python recursion (no Numba to load: decision 0057). The
symbolic dynamics (fewer than 4 spatial Gen joints, absolute coordinates) evaluates its
compiled kernels point by point from Python.

Example::

    m = ms.from_urdf("ur5.urdf")
    tau = m.inverse_dynamics(q, qd, qdd)          # (N, 6) arrays -> JointValues
    tau["elbow_joint"]
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


def _system(m):
    return m.compile()


#: ``MECHSYS_JIT`` unset (auto): the robot entry points take the compiled loops from this
#: many points on. Loading Numba and its cached code costs about 0.7 s CPU once per process
#: (compiling it, several seconds once per installation); the plain-Python recursion costs
#: about 6 ms a point on a 9-joint arm (the Panda), so about 110 points pay for the loading
#: (measured: decision 0057)
AUTO_POINTS = 100


def _compiled(N: int) -> bool:
    """Whether evaluations over ``N`` points take the compiled loops (``MECHSYS_JIT``: ``0``
    never, ``1`` always, ``auto`` from :data:`AUTO_POINTS` points)."""
    from ..solvers import _jit_runtime

    mode = _jit_runtime.mode()
    return mode == "on" or (mode == "auto" and N >= AUTO_POINTS)


def _evaluations(s, N: int):
    """The context of ``N`` evaluations of ``s``'s dynamics: the plain-Python recursion of
    the recursive Gen dynamics unless :func:`_compiled` (the symbolic dynamics' kernels are
    machine code either way)."""
    from contextlib import nullcontext

    d = s.dynamics
    if getattr(d, "recursive", False) and not _compiled(N):
        return d.plain_python()
    return nullcontext()


def _loads_compiled(s, t, Q, QD, QDD):
    """``Q + Qv - M qdd`` at the ``N`` points by the compiled loop over points of the
    recursive Gen dynamics (``solvers._jit_gen_points``, the one the compiled multiplier
    solves and the forward dynamics use; decisions 0057, 0073) as ``(R (N', n), N')``, ``N'``
    the points done before the first with values that are not finite; None when it cannot
    run (no C entry points, not the recursive dynamics, Numba missing, being compiled in the
    background)."""
    from ..solvers import _jit_gen_points as jp

    N = len(Q)
    Q, QD, QDD = (np.ascontiguousarray(np.broadcast_to(a, (N, s.n))) for a in (Q, QD, QDD))
    return jp.points(s, np.full(N, float(t)), Q, QD, QDD, jp.DYNAMIC_LOADS)


def _points(s, value, what: str, partial: bool = False):
    """``(values, single, held)``: ``value`` as ``(N, n)`` in layout order and whether it was
    a single point; or, when ``partial`` and a mapping names only some coordinates,
    ``(N, k)`` in layout order of those and ``held`` their layout indices (else None)."""
    names = list(s.layout.q_names)
    held = None
    if isinstance(value, dict):
        extra = [k for k in value if k not in names]
        missing = [n for n in names if n not in value]
        if extra or (missing and not partial):
            raise ModelError(f"{what}: give a value for each coordinate {names}"
                             + (f"; missing {missing}" if missing and not partial else "")
                             + (f"; unknown {extra}" if extra else ""))
        given = [n for n in names if n in value]
        if missing:
            held = np.array([names.index(n) for n in given], dtype=int)
        cols = [np.atleast_1d(np.asarray(value[n], dtype=float)) for n in given]
        single = all(np.ndim(value[n]) == 0 for n in given)
        try:
            arr = np.column_stack(np.broadcast_arrays(*cols)) if cols else np.zeros((1, 0))
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
    return arr, single, held


def _broadcast(what, arrays, labels):
    N = max(len(a) for a in arrays)
    try:
        return [np.broadcast_to(a, (N, a.shape[1])) for a in arrays]
    except ValueError:
        raise ModelError(f"{what}: {', '.join(labels)} have different numbers of points "
                         f"({', '.join(str(len(a)) for a in arrays)})") from None


def _complete(s, what, t, Q, held, QD=None, QDD=None, heldd=None, helddd=None):
    r"""Full states from the values of the coordinates ``held`` (layout indices): positions
    on :math:`\Phi(q, t) = 0` by the position solver that keeps given coordinates
    (:func:`~mechsys.solvers._free.hold_positions`: Gauss-Newton in the other coordinates,
    the one the start of free motion uses) from the model's guess, then each point from the
    last, continued in steps of at most 0.25 in the held coordinates; velocities from
    :math:`\Phi_q \dot q = -\Phi_t` and accelerations from :math:`\Phi_q \ddot q = \gamma`
    with the given entries kept (:func:`~mechsys.solvers._free.hold_rates`). ``Q`` etc. are
    ``(N, n)`` when their ``held*`` is None (given in full)."""
    from ..solvers._free import ConsistencyError, hold_positions, hold_rates, scaling_at

    n = s.n
    t = float(t)
    p = s.p_values
    names = s.layout.q_names
    N = max(len(a) for a in (Q, QD, QDD) if a is not None)
    out_q = np.empty((N, n))
    q = np.array(s.guess, dtype=float)
    scaling = scaling_at(s, t, q, p)
    if held is not None:
        # the given coordinates must determine the others (as many independent ones as the
        # model has degrees of freedom): else a least-squares step picks one of many
        dep = np.setdiff1d(np.arange(n), held)
        J = s.jacobian(t, q, p)
        J = J.toarray() if hasattr(J, "toarray") else J
        if np.linalg.matrix_rank(J[:, dep]) < len(dep):
            raise ModelError(
                f"{what}: the coordinates given ({[names[i] for i in held]}) do not "
                f"determine the others; give as many independent coordinates as the "
                f"model has degrees of freedom (coordinates {list(names)})")
    for k in range(N):
        target = Q[min(k, len(Q) - 1)]
        if held is None:
            out_q[k] = target
            continue
        steps = max(1, int(np.ceil(np.abs(target - q[held]).max(initial=0.0) / 0.25)))
        start = q[held].copy()
        for j in range(1, steps + 1):
            q[held] = start + (target - start) * j / steps
            # the steps between may be off the constraints (a held quaternion interpolated is
            # not a unit one): a few iterations there, convergence asked at the end
            last = j == steps
            try:
                q = hold_positions(s, t, q, p, scaling, held, max_iterations=50 if last else 8,
                                   check=last)
            except ConsistencyError as exc:
                raise ModelError(f"{what}: the positions do not assemble at point {k} (scaled "
                                 f"residual {exc.residual:.3e} left); give values nearer the "
                                 "model's guess or a path in smaller steps") from None
        out_q[k] = q
    res = [out_q]
    for X, hx, order in ((QD, heldd, 1), (QDD, helddd, 2)):
        if X is None:
            res.append(None)
            continue
        full = np.empty((N, n))
        for k in range(N):
            x = X[min(k, len(X) - 1)]
            if hx is None:
                full[k] = x
                continue
            if order == 1:
                J, rhs = s.velocity_rhs(t, out_q[k], p)
            else:
                J = s.jacobian(t, out_q[k], p)
                rhs = s.gamma_values(t, out_q[k], res[1][k], p)
            y = np.zeros(n)
            y[hx] = x
            try:
                full[k] = hold_rates(s, J, rhs, y, scaling, hx,
                                     "velocities" if order == 1 else "accelerations")
            except ConsistencyError as exc:
                raise ModelError(f"{what} at point {k}: the given coordinates' {exc.held} "
                                 f"violate the constraints (scaled residual {exc.residual:.3e});"
                                 " give independent coordinates only") from None
        res.append(full)
    return res


def _state(m, what, q, qd, x=None, xname="", t=0.0):
    """``(s, Q, QD, X, single)`` with full states (``(N, n)``), completed from the
    constraints when ``q``/``qd``/``x`` (``qdd``) are mappings naming only some coordinates
    (``X`` is returned as given when ``xname`` is ``"tau"``)."""
    s = _system(m)
    partial = s.m > 0
    Q, single, hq = _points(s, q, f"{what}: q", partial)
    QD, _, hd = _points(s, qd, f"{what}: qd", partial)
    X, hx = None, None
    if x is not None and xname == "qdd":
        X, _, hx = _points(s, x, f"{what}: qdd", partial)
    arrays = [a for a in (Q, QD, X) if a is not None]
    _broadcast(what, arrays, ["q", "qd", xname][:len(arrays)])
    if s.m:
        given = (hq is None, hd is None, hx is None)   # given in full: checked, else solved
        Q, QD, X = _complete(s, what, t, Q, hq, QD, X, hd, hx)
        if any(given):
            _check_state(s, what, t, Q, QD, X, given)
    else:
        N = max(len(a) for a in arrays)
        Q, QD = (np.broadcast_to(a, (N, s.n)) for a in (Q, QD))
        if X is not None:
            X = np.broadcast_to(X, (N, s.n))
    return s, Q, QD, X, single


def _check_state(s, what, t, Q, QD, QDD, given=(True, True, True)):
    """States given in full must satisfy the constraints (positions, velocities,
    accelerations) to 1e-8 (relative): the dynamics of a state off them mean nothing.
    ``given``: which of the three were given in full (the others were solved)."""
    for k in range(len(Q)):
        bad = []
        if given[0]:
            F = s.residual(float(t), Q[k])
            bad.append(("positions", np.abs(F).max(initial=0.0), 1e-8 * max(1.0, np.abs(Q[k]).max())))
        J, rhs = s.velocity_rhs(float(t), Q[k])
        J = J.toarray() if hasattr(J, "toarray") else J
        if given[1]:
            v = J @ QD[k] - rhs
            bad.append(("velocities", np.abs(v).max(initial=0.0),
                        1e-8 * max(1.0, np.abs(J).max() * np.abs(QD[k]).max())))
        if QDD is not None and given[2]:
            a = J @ QDD[k] - s.gamma_values(float(t), Q[k], QD[k])
            bad.append(("accelerations", np.abs(a).max(initial=0.0),
                        1e-8 * max(1.0, np.abs(J).max() * np.abs(QDD[k]).max())))
        for kind, err, tol_ in bad:
            if err > tol_:
                raise ModelError(f"{what}: the {kind} of point {k} violate the constraint equations "
                                 f"(residual {err:.3e}); give a consistent state, or a mapping "
                                 "of the independent coordinates only (the others are solved)")


def _actuated(s, what, actuated) -> np.ndarray:
    """Layout indices of the coordinates the joint forces act on (default: all of a model
    without equations; else those not of an absolute body)."""
    names = list(s.layout.q_names)
    if actuated is None:
        if not s.m:
            return np.arange(s.n)
        body = set()
        for sl in s.layout.body_slices.values():
            body.update(range(*sl.indices(s.n)))
        return np.array([i for i in range(s.n) if i not in body], dtype=int)
    if isinstance(actuated, str):
        actuated = [actuated]
    unknown = [a for a in actuated if a not in names]
    if unknown:
        raise ModelError(f"{what}: actuated names {unknown} are not coordinates of the model "
                         f"({names})")
    return np.array(sorted({names.index(a) for a in actuated}), dtype=int)


def _added_inertia(s, what, t, q, qd):
    """``-dQ/dqdd`` of loads linear in the accelerations (an armature ``-a qdd``) where the
    dynamics keep them in ``Q`` (the symbolic path; the recursion moves them into ``M``),
    or None."""
    d = s.dynamics
    if not getattr(d, "depends_on_qdd", False):
        return None
    if not d.linear_in_qdd:
        raise ModelError(f"{what}: a load depends nonlinearly on the accelerations; use "
                         "m.free().simulate(...) for this model")
    return -d.dQ_dqdd(float(t), q, qd, np.zeros(s.m), s.p_values)


def _augmented(s, t, q, qd, what="dynamics"):
    """``(M, F, J, gamma)``: mass matrix (with inertia added on coordinates), ``Q + Qv`` at
    zero accelerations, ``Phi_q`` and ``gamma`` at one state."""
    K, rhs = s.dynamics.free_kernel()(float(t), q, qd, np.zeros(s.m), s.p_values)
    K = np.array(K.toarray() if hasattr(K, "toarray") else K, dtype=float)
    n = s.n
    add = _added_inertia(s, what, t, q, qd)
    if add is not None:
        K[:n, :n] += add
    return K[:n, :n], rhs[:n], K[n:, :n], rhs[n:], K, rhs


def _solve_regular(A, b):
    """``A^-1 b`` by LU when ``A`` is square and its pivots are regular (the usual case: an
    absolute-coordinate robot, a free base), else None (the caller's SVD path handles
    redundant or non-square systems; an SVD per point costs ten LUs)."""
    import warnings

    from scipy.linalg import lu_factor, lu_solve

    if A.shape[0] != A.shape[1]:
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lu, piv = lu_factor(A, check_finite=False)
    d = np.abs(np.diag(lu))
    if not d.size or d.min() <= 1e-11 * d.max():
        return None
    return lu_solve((lu, piv), b, check_finite=False)


def _no_multiplier_loads(s, what):
    if getattr(s.dynamics, "depends_on_lambda", False):
        raise ModelError(f"{what}: the model's loads depend on constraint reactions (friction); "
                         "use m.free().simulate(...) for it")


def inverse_dynamics(m, q, qd, qdd, t: float = 0.0, actuated=None) -> JointValues:
    r"""Joint forces: :math:`\tau = M(q) \ddot q - Q - Q_v` (see the module doc) at one point (``(n,)``
    arrays) or many (``(N, n)``), or from ``{joint name: values}``; on a model with
    constraint equations the forces on the ``actuated`` coordinates (names; default the
    joint coordinates) that, with the constraints' reactions, give ``qdd``."""
    what = "inverse_dynamics"
    s, Q, QD, X, single = _state(m, what, q, qd, qdd, "qdd", t)
    d = s.dynamics
    p = s.p_values
    names = s.layout.q_names
    act = _actuated(s, what, actuated)
    out = np.empty((len(Q), len(act)))
    if not s.m:
        if len(act) != s.n:
            raise ModelError(f"{what}: a model without constraint equations is actuated on every "
                             "coordinate (actuated= applies to models with equations)")
        lam = np.zeros(0)
        done = 0
        if _compiled(len(Q)):
            got = _loads_compiled(s, t, Q, QD, X)
            if got is not None:
                done = got[1]
                out[:done] = -got[0]          # tau = M qdd - (Q + Qv)
        with _evaluations(s, len(Q) - done):
            for k in range(done, len(Q)):
                # (loads on the accelerations, an armature's -a qdd, taken at this qdd)
                M, F, Fv = d.terms(float(t), Q[k], QD[k], lam, p, X[k])[:3]
                out[k] = M @ X[k] - F - Fv
        return JointValues(tuple(names), out[0] if single else out)
    _no_multiplier_loads(s, what)
    with _evaluations(s, len(Q)):
        return _inverse_constrained(s, what, t, Q, QD, X, act, names, single)


def _inverse_constrained(s, what, t, Q, QD, X, act, names, single):
    out = np.empty((len(Q), len(act)))
    n, m_ = s.n, s.m
    S = np.zeros((len(act), n))
    S[np.arange(len(act)), act] = 1.0
    for k in range(len(Q)):
        M, F, J = _augmented(s, t, Q[k], QD[k], what)[:3]
        A = np.hstack((J.T, -S.T))                # Phi_q^T lambda - S^T tau = Q + Qv - M qdd
        b = F - M @ X[k]
        x = _solve_regular(A, b)
        if x is not None:                         # square and regular: unique, exact
            out[k] = x[m_:]
            continue
        U, sv, Vt = np.linalg.svd(A, full_matrices=True)
        tol = 1e-10 * max(sv.max(initial=0.0), 1.0)
        rank = int(np.sum(sv > tol))
        null = Vt[rank:]
        if null.size and np.abs(null[:, m_:]).max() > 1e-8:
            amb = [names[act[i]] for i in np.unique(np.nonzero(np.abs(null[:, m_:]) > 1e-8)[1])]
            raise ModelError(f"{what}: the forces on {amb} are not unique: the constraints alone "
                             "can move or hold those coordinates; actuate fewer coordinates")
        x = Vt[:rank].T @ ((U[:, :rank].T @ b) / sv[:rank])
        r = A @ x - b
        scale = max(1.0, np.abs(F).max(), np.abs(M @ X[k]).max())
        if np.abs(r).max() > 1e-8 * scale:
            i = int(np.argmax(np.abs(r)))
            raise ModelError(f"{what}: at point {k} no forces on the actuated coordinates give "
                             f"this qdd (the equation of motion of {names[i]!r} is off by "
                             f"{r[i]:.3e}): an unactuated coordinate's acceleration (a floating "
                             "base's) is not free to choose; give it actuated=... or a qdd from "
                             "forward_dynamics")
        out[k] = x[m_:]
    return JointValues(tuple(names[i] for i in act), out[0] if single else out)


def forward_dynamics(m, q, qd, tau, t: float = 0.0, actuated=None) -> JointValues:
    r"""Joint accelerations ``qdd = M(q)^-1 (Q + Qv + tau)`` (see the module doc) at one
    point or many; on a model with constraint equations ``tau`` acts on the ``actuated``
    coordinates (default the joint coordinates, as :func:`inverse_dynamics` returns them)
    and the result has every coordinate's acceleration. A mass matrix that is not positive
    definite (a joint that moves no mass) raises ``SingularMassError`` naming the joint."""
    what = "forward_dynamics"
    s, Q, QD, _, single = _state(m, what, q, qd, None, "tau", t)
    names = tuple(s.layout.q_names)
    act = _actuated(s, what, actuated)
    if isinstance(tau, JointValues):
        tau = tau.values
    X = np.atleast_2d(np.asarray(tau, dtype=float)) if not isinstance(tau, dict) else None
    if isinstance(tau, dict):
        unknown = [k_ for k_ in tau if k_ not in [names[i] for i in act]]
        missing = [names[i] for i in act if names[i] not in tau]
        if unknown or missing:
            raise ModelError(f"{what}: tau names the actuated coordinates "
                             f"{[names[i] for i in act]}" + (f"; missing {missing}" if missing else "")
                             + (f"; unknown {unknown}" if unknown else ""))
        X = np.column_stack(np.broadcast_arrays(*[np.atleast_1d(np.asarray(tau[names[i]], float))
                                                  for i in act]))
    if X.ndim != 2 or X.shape[1] != len(act) or not np.all(np.isfinite(X)):
        raise ModelError(f"{what}: tau must be finite numbers of shape (k,) or (N, k) with k = "
                         f"{len(act)} actuated coordinates {[names[i] for i in act]}, got "
                         f"{np.shape(tau)}")
    Q, QD, X = _broadcast(what, [Q, QD, X], ["q", "qd", "tau"])
    with _evaluations(s, len(Q)):
        return _forward_points(s, what, t, Q, QD, X, act, names, single)


def _forward_points(s, what, t, Q, QD, X, act, names, single):
    """The accelerations at the ``N`` points: the compiled loop over points from
    :data:`AUTO_POINTS` on (``solvers._jit_gen_points``, the recursive Gen dynamics,
    decision 0073), then the Python loop from the first point it left (all of them when it
    cannot run), which gives every diagnosis."""
    out = np.empty((len(Q), s.n))
    if not s.m and len(act) != s.n:
        raise ModelError(f"{what}: a model without constraint equations is actuated on every "
                         "coordinate (actuated= applies to models with equations)")
    if s.m:
        _no_multiplier_loads(s, what)
    done = 0
    if _compiled(len(Q)):
        from ..solvers import _jit_gen_points as jp

        F = np.zeros((len(Q), s.n))
        F[:, act] = X
        got = jp.points(s, np.full(len(Q), float(t)), Q, QD, F,
                        jp.FORWARD_AUGMENTED if s.m else jp.FORWARD_FREE)
        if got is not None:
            done = got[1]
            out[:done] = got[0][:done]
    for k in range(done, len(Q)):
        out[k] = (_forward_augmented if s.m else _forward_free)(s, what, t, Q[k], QD[k], X[k],
                                                                act, names, k)
    return JointValues(names, out[0] if single else out)


def _forward_free(s, what, t, q, qd, tau, act, names, k):
    r""":math:`\ddot q = M^{-1} (Q + Q_v + \tau)` at one state of a model without constraint
    equations, by the Cholesky factor of the mass matrix (the compiled loop's algorithm,
    ``_jit_free_loop._gen_cholesky``), whose failure names the joints. (Not the O(N)
    articulated-body recursion: in pose coordinates it costs more than the composite-body
    mass matrix and its Cholesky factor up to a dozen joints, 2.4 times as much in plain
    Python on the Panda; decision 0073.)"""
    from .._errors import SingularMassError

    d = s.dynamics
    p = s.p_values
    M, F, Fv = d.terms(float(t), q, qd, np.zeros(0), p)[:3]
    add = _added_inertia(s, what, t, q, qd)
    if add is not None:
        M = M + add
    try:
        L = np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        diag = np.diag(M)
        bad = [names[i] for i in range(s.n) if not diag[i] > 1e-14 * max(1.0, abs(diag).max())]
        raise SingularMassError(f"forward_dynamics: the mass matrix is singular at point {k}"
                                + (f"; joints {bad} move no mass" if bad else "")
                                + "; give the bodies they carry mass and inertia") from None
    y = np.linalg.solve(L, F + Fv + tau)
    return np.linalg.solve(L.T, y)


def _forward_augmented(s, what, t, q, qd, tau, act, names, k):
    """The accelerations at one state of a model with constraint equations: the augmented
    system by LU when regular, else least squares (redundant constraints), refusing
    accelerations the system does not determine."""
    from .._errors import SingularMassError

    n = s.n
    K, rhs = _augmented(s, t, q, qd, what)[4:]
    rhs = rhs.copy()
    rhs[act] += tau
    y = _solve_regular(K, rhs)
    if y is not None:
        return y[:n]
    # least squares: consistently redundant constraints (a planar loop closed by a
    # Spherical3) leave the multipliers, not the accelerations, undetermined
    U, sv, Vt = np.linalg.svd(K)
    tol = 1e-11 * max(sv.max(initial=0.0), 1.0)
    rank = int(np.sum(sv > tol))
    null = Vt[rank:]
    if null.size and np.abs(null[:, :n]).max() > 1e-8:
        free_ = [names[i] for i in np.unique(np.nonzero(np.abs(null[:, :n]) > 1e-8)[1])]
        raise SingularMassError(f"{what}: the accelerations of {free_} are not determined at "
                                f"point {k} (they move no mass); give the bodies they carry "
                                "mass and inertia")
    y = Vt[:rank].T @ ((U[:, :rank].T @ rhs) / sv[:rank])
    return y[:n]


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
    Q, single, held = _points(s, q, "forward_kinematics: q", partial=s.m > 0)
    if held is not None:
        Q = _complete(s, "forward_kinematics", t, Q, held)[0]
    bodies = list(dict.fromkeys(b for b, _, _ in spec))
    with _evaluations(s, len(Q)):
        poses = _body_poses(s, Q, bodies, t)    # (N, nb, 4, 4)
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
