r"""Underconstrained (free) systems: free acceleration, equilibrium configuration and
equilibrium velocity. Pure numerics on a System and its Dynamics.

Free acceleration (``m < n`` equations), the augmented system:

.. math::

    \begin{bmatrix} M & \Phi_q^T \\ \Phi_q & 0 \end{bmatrix}
    \begin{bmatrix} \ddot q \\ \lambda \end{bmatrix} =
    \begin{bmatrix} Q(t, q, \dot q, \lambda) + Q_v(q, \dot q) \\ \gamma(t, q, \dot q) \end{bmatrix}

linear unless ``Q`` depends on ``lambda`` (friction): then Newton on :math:`(\ddot q, \lambda)` with
the Jacobian :math:`\begin{bmatrix} M & \Phi_q^T - \partial Q / \partial \lambda \\ \Phi_q & 0 \end{bmatrix}`.

Equilibrium configuration (static loads), unknowns :math:`(q, \lambda)`:

.. math::

    \Phi(q, t) = 0, \qquad \Phi_q^T \lambda - Q(t, q, 0, \lambda) = 0

Equilibrium velocity (velocity-dependent loads, inertial terms excluded), unknowns
:math:`(\dot q, \lambda)` at fixed ``q``:

.. math::

    \Phi_q \dot q + \Phi_t = 0, \qquad \Phi_q^T \lambda - Q(t, q, \dot q, \lambda) = 0
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sps
from scipy.linalg.lapack import dgesv as _dgesv

from .._errors import ConvergenceError, SingularJacobianError, SingularMassError
from ._linalg import Scaling, dependent_rows, factor, pattern_slots
from ._patterns import free_newton_pattern, projection_pattern
from ._position import describe_singular
from ._rank import InZone, kkt_rank_tolerant
from ._tolerances import SPARSE_THRESHOLD, ZONE, Singular


def _augmented(M, J, D=None, dense=False):
    n, m = M.shape[0], J.shape[0]
    JT = J.T if D is None else J.T - D
    if n + m > SPARSE_THRESHOLD and not dense:
        return sps.bmat([[sps.csc_matrix(M), sps.csc_matrix(JT)],
                         [sps.csc_matrix(J), None]], format="csc")
    K = np.zeros((n + m, n + m))
    K[:n, :n] = M
    K[:n, n:] = JT
    K[n:, :n] = J
    return K


def free_acceleration(system, t, q, qd, p, lam_guess=None, tol=1e-10, max_iterations=30,
                      guard=None, columns=None, rows=None):
    r"""``(qdd (n,), lambda (m,), iterations)`` of a free system at ``(t, q, qd)``.
    ``guard(K, rhs, x)`` (free motion, linear case): ``None`` to keep the solution ``x`` of
    the augmented system, or a replacement :math:`(\ddot q, \lambda)` near a singular instant
    (:func:`._rank.zone_guard`).

    ``rows``: ``(A (k, n), rho (k,))``, the velocity constraints' rows at this state
    (:class:`~mechsys.analyses._nonholonomic.VelocityRows`, decision 0068): the Newton below
    then runs on the bordered system, :math:`\Phi_q` stacked with :math:`A`, :math:`\gamma`
    with :math:`-\rho`, the multipliers :math:`(\lambda, \mu)` (``m + k`` of them, the
    loads reading the first ``m``; their derivative along :math:`\mu` is zero):

    .. math::

        \begin{bmatrix} M - \partial Q / \partial \ddot q & \Phi_q^T - \partial Q / \partial
        \lambda & A^T \\ \Phi_q & 0 & 0 \\ A & 0 & 0 \end{bmatrix}
        \begin{bmatrix} \Delta \ddot q \\ \Delta \lambda \\ \Delta \mu \end{bmatrix}
        = -\begin{bmatrix} r_1 \\ r_2 \end{bmatrix}, \qquad
        r_1 = M \ddot q + \Phi_q^T \lambda + A^T \mu - Q - Q_v, \quad
        r_2 = \begin{bmatrix} \Phi_q \ddot q - \gamma \\ A \ddot q + \rho \end{bmatrix}

    (dense; only for loads that depend on the multipliers or accelerations: the linear case
    is :func:`~mechsys.analyses._nonholonomic.nonholonomic_acceleration`'s one solve). A
    singular Newton matrix then raises the internal :class:`Singular` for the caller to name
    the velocity constraints. The column scales are those of :math:`\Phi_q` alone, as
    without rows.

    Loads that depend on the multipliers or accelerations: Newton on :math:`(\ddot q, \lambda)` from
    ``qdd = 0`` and ``lam_guess`` (default ones) with the residuals ``r1 = M qdd + Phi_q^T
    lambda - Q - Qv``, ``r2 = Phi_q qdd - gamma``, converged after at least one step when,
    unit-free (``c = columns``, the column scales of
    :class:`~mechsys.solvers._linalg.Scaling`, default those at ``q``; ``rho_i = max_j
    |Phi_ij| c_j``),

    .. math::

        \max_j c_j |r_{1j}| \le tol \max_j c_j \Big(\sum_k |M_{jk} \ddot q_k|
            + \sum_i |\Phi_{ij} \lambda_i| + |Q_j| + |Q_{v,j}|\Big), \qquad
        \max_i \frac{|r_{2i}|}{\rho_i} \le tol \max\Big(\max_j \frac{|\ddot q_j|}{c_j},
            \max_i \frac{|\gamma_i|}{\rho_i}\Big)

    (each residual against the size of its own terms: the same answer whatever the units of
    length, mass or force)."""
    dyn = system.dynamics
    n, m = system.n, system.m
    if rows is None and not (dyn.depends_on_lambda or dyn.depends_on_qdd):
        kern = dyn.free_kernel(n + m > SPARSE_THRESHOLD)
        direct = getattr(kern, "accelerations", None)  # a tree of Gen joints: O(N), no K
        if direct is not None and m == 0:
            qdd = direct(t, q, qd, p)
            if qdd is not None:
                return qdd, np.zeros(0), 0
        K, rhs = kern(t, q, qd, _ZERO_LAM.get(m) if m in _ZERO_LAM else _zeros(m), p)
        try:
            x = _solve_fast(K, rhs)
        except Singular:
            # a singular instant (dependent equations, e.g. links collinear): the
            # acceleration is still determined; solve with the independent combinations
            y = guard(K, rhs, None) if guard is not None else None
            return (*y, 0) if y is not None else _rank_tolerant(system, t, q, qd, p, K, rhs)
        if guard is not None:
            y = guard(K, rhs, x)
            if y is not None:
                return (*y, 0)
        return x[:n], x[n:], 0
    # large systems: the Jacobian's and the mass matrix's nonzeros (products by bincount, no
    # sparse-matrix objects per iteration), the Newton matrix's values straight into its
    # fixed pattern (_newton_values): no dense (n + m)^2 arrays
    pat = free_newton_pattern(system) if n + m > SPARSE_THRESHOLD and rows is None else None
    if rows is None:
        J = system.jacobian(t, q, p, pat is not None)
        g = system.gamma_values(t, q, qd, p)
    elif m:
        J = system.jacobian(t, q, p)
        J = J.toarray() if sps.issparse(J) else np.asarray(J, dtype=float)
        g = np.asarray(system.gamma_values(t, q, qd, p), dtype=float)
    else:                   # (no position rows: a free body on a knife edge)
        J, g = np.zeros((0, n)), np.zeros(0)
    c = Scaling.of(system, q, J).columns if columns is None else np.asarray(columns, dtype=float)
    k = 0
    if rows is not None:
        # the bordered system: the velocity rows below the position rows, their
        # multipliers mu after lambda (the loads see lambda only)
        A, rho_v = rows
        k = A.shape[0]
        J, g = np.vstack((J, A)), np.concatenate((g, -np.asarray(rho_v, dtype=float)))
    if pat is not None:
        Jd, Jr, Jc = J.data, J.indices, np.repeat(np.arange(n), np.diff(J.indptr))
        Mr, Mc = dyn.M_rows, dyn.M_cols
        rho = np.zeros(m)
        np.maximum.at(rho, Jr, np.abs(Jd) * c[Jc])
    else:
        rho = (np.abs(J) * c).max(axis=1, initial=0.0)
    rho[rho == 0] = 1.0
    lam = np.ones(m + k) if lam_guess is None else np.array(lam_guess, dtype=float)
    qdd = np.zeros(n)

    def terms(lam, qdd):
        if pat is None:
            return dyn.terms(t, q, qd, lam[:m], p, qdd)
        out = dyn.f_terms(dyn.pack(t, q, qd, lam, p, qdd))
        k = len(Mr)
        return out[:k], out[k:k + n], out[k + n:]

    Mm, Q, Qv = terms(lam, qdd)
    for it in range(1, max_iterations + 1):
        if pat is not None:
            Mq, JTl = Mm * qdd[Mc], Jd * lam[Jr]
            r1 = (np.bincount(Mr, Mq, n) + np.bincount(Jc, JTl, n)) - Q - Qv
            r2 = np.bincount(Jr, Jd * qdd[Jc], m) - g
        else:
            r1 = Mm @ qdd + J.T @ lam - Q - Qv
            r2 = J @ qdd - g
        e1, e2 = np.abs(c * r1).max(initial=0.0), np.abs(r2 / rho).max(initial=0.0)
        err = max(e1, e2)
        if it > 1:
            if pat is not None:
                mass = np.bincount(Mr, np.abs(Mq), n) + np.bincount(Jc, np.abs(JTl), n)
            else:
                mass = np.abs(Mm * qdd).sum(axis=1) + np.abs(J.T * lam).sum(axis=1)
            size1 = (c * (mass + np.abs(Q) + np.abs(Qv))).max(initial=0.0)
            size2 = max(np.abs(qdd / c).max(initial=0.0), np.abs(g / rho).max(initial=0.0))
            if e1 <= tol * size1 and e2 <= tol * size2:
                return qdd, lam, it - 1
        # the Newton matrix unit-free (its singularity test then does not depend on the units
        # of length and mass): rows diag(c/mu, 1/rho), columns diag(c, mu/rho), mu the size
        # of C Meff C; its blocks are C Meff C / mu, B^T, B (B = rho^-1 Phi_q C, entries <= 1)
        if pat is not None:
            rows, cols, pattern = pat
            K = _newton_values(system, dyn, Mm, J, t, q, qd, lam, p, qdd)
            first = (rows < n) & (cols < n)
            mu = np.abs(c[rows[first]] * K[first] * c[cols[first]]).max(initial=0.0) or 1.0
        else:
            D = dyn.dQ_dlam(t, q, qd, lam[:m], p, qdd)
            if k:                   # (the loads do not depend on mu)
                D = np.hstack((np.asarray(D, dtype=float).reshape(n, m), np.zeros((n, k))))
            Meff = Mm - dyn.dQ_dqdd(t, q, qd, lam[:m], p, qdd)
            mu = (c[:, None] * np.abs(Meff) * c[None, :]).max(initial=0.0) or 1.0
        dr = np.concatenate((c / mu, 1.0 / rho))
        dc = np.concatenate((c, mu / rho))
        try:
            if pat is not None:
                # the matrix's fixed pattern, analysed once (banded LU for chains): no sparse
                # matrix objects per iteration (they cost 10-20 times the factorisation)
                fac = pattern.factor((dr[rows] * K) * dc[cols])
            else:
                fac = factor(dr[:, None] * _augmented(Meff, J, D) * dc[None, :])
            dx = dc * fac.solve(-dr * np.concatenate((r1, r2)))
        except Singular:
            if rows is not None:
                raise               # (the caller names the velocity constraints)
            raise _singular_free(system, t, q, qd, p) from None
        qdd, lam = qdd + dx[:n], lam + dx[n:]
        Mm, Q, Qv = terms(lam, qdd)
    raise ConvergenceError(
        f"free acceleration at t = {t:.6g}: the loads that depend on multipliers (friction) or "
        f"accelerations did not converge in {max_iterations} iterations (residual {err:.3e}); "
        "try lambda_guess=.",
        time=t)


def _newton_values(system, dyn, Mv, J, t, q, qd, lam, p, qdd):
    """The values of ``[[M - dQ/dqdd, Phi_q^T - dQ/dlambda], [Phi_q, 0]]`` at the entries of
    its pattern (:func:`~._patterns.free_newton_pattern`, CSC order) from the mass matrix's
    nonzero values ``Mv`` (at ``dyn.M_rows``, ``dyn.M_cols``), the sparse Jacobian ``J`` (its
    stored entries placed through slots found once per structure) and the derivatives'
    nonzero values."""
    n = system.n
    rows, cols, _ = free_newton_pattern(system)
    key = (J.indptr.tobytes(), J.indices.tobytes())
    got = dyn.__dict__.get("_newton_slots")
    if got is None or got[0] is not system or got[1] != key:
        jcols = np.repeat(np.arange(n), np.diff(J.indptr))
        slot = lambda r, c: pattern_slots(rows, cols, n + system.m, r, c)    # noqa: E731
        got = (system, key, slot(dyn.M_rows, dyn.M_cols), slot(n + J.indices, jcols),
               slot(jcols, n + J.indices),
               slot(dyn.dA_rows, dyn.dA_cols) if dyn.depends_on_qdd else None,
               slot(dyn.dQ_rows, n + np.asarray(dyn.dQ_cols)) if dyn.depends_on_lambda else None)
        dyn.__dict__["_newton_slots"] = got
    _, _, sM, sJ, sJT, sA, sD = got
    K = np.bincount(sM, Mv, rows.size) + np.bincount(sJ, J.data, rows.size) \
        + np.bincount(sJT, J.data, rows.size)
    x = dyn.pack(t, q, qd, lam, p, qdd)
    if sA is not None:
        K -= np.bincount(sA, dyn.f_dQ_dqdd(x), rows.size)
    if sD is not None:
        K -= np.bincount(sD, dyn.f_dQ_dlam(x), rows.size)
    return K


def _rank_tolerant(system, t, q, qd, p, K, rhs):
    """Free acceleration at a singular ``Phi_q`` (:func:`._rank.kkt_rank_tolerant`), or the
    error of :func:`_singular_free` when the mass matrix is singular on the free motions."""
    n = system.n
    K = K.toarray() if sps.issparse(K) else K
    J = K[n:, :n]
    if not (np.all(np.isfinite(K)) and np.all(np.isfinite(rhs))):
        raise _singular_free(system, t, q, qd, p)
    sc = Scaling.of(system, q, J)
    try:
        qdd, lam, _ = kkt_rank_tolerant(K[:n, :n], J, rhs[:n], rhs[n:], sc.rows(J), sc.columns)
    except Singular:
        raise _singular_free(system, t, q, qd, p) from None
    return qdd, lam, 0


_ZERO_LAM: dict = {}


def _zeros(m):
    _ZERO_LAM[m] = np.zeros(m)
    return _ZERO_LAM[m]


def _solve_fast(K, rhs):
    """Solve the augmented system; LAPACK gesv for dense (a singular matrix raises), SuperLU
    for sparse, or the analysed pattern of the free kernel's matrix when it carries one
    (``K.pattern``, :class:`._linalg.FixedPattern`: banded LU for chains). A non-finite
    answer is treated as singular. (``K`` is never empty: a free system has coordinates, so
    gesv is never called with an illegal size, which would print to stderr.)"""
    if sps.issparse(K):
        pattern = getattr(K, "pattern", None)
        return (factor(K) if pattern is None else pattern.factor(K.data)).solve(rhs)
    if not np.all(np.isfinite(K)):
        raise Singular("non-finite augmented matrix")
    _, _, x, info = _dgesv(K, rhs)
    if info != 0:
        raise Singular("singular augmented matrix")
    big = np.abs(x).max(initial=0.0)
    if not big < 1e15 * (1.0 + np.abs(rhs).max(initial=0.0)):   # also catches NaN
        raise Singular("ill-conditioned augmented matrix")
    return x


def _singular_free(system, t, q, qd, p, what="free acceleration"):
    r"""The error for a singular augmented matrix ``[[M, J^T], [J, 0]]``. It is singular iff
    ``J`` loses rank (redundant constraints, lock-up: :func:`describe_singular`) or ``M`` is
    singular on the null space of ``J`` (the free motions): ``N^T M N v = 0`` for a basis
    ``N`` of ``ker J``. The motions ``N v`` then move no mass; the bodies whose coordinates
    they move are named, with what they lack (mass: translational diagonal of ``M`` zero;
    inertia: rotational diagonal zero)."""
    n, m = system.n, system.m
    J = system.jacobian(t, q, p) if m else np.zeros((0, n))
    J = J.toarray() if sps.issparse(J) else np.asarray(J, dtype=float)
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd)) and np.all(np.isfinite(J))):
        return SingularJacobianError(
            f"{what} at t = {t:.6g}: the state or the constraint Jacobian is not finite (a "
            "parameter or initial condition is NaN/inf, or the motion blew up before this "
            "time)", time=t)
    if m:
        rank, _ = dependent_rows(J)
        if rank < m:
            return describe_singular(system, J, t, q, what)
        _, _, vt = np.linalg.svd(J)
        N = vt[m:].T
    else:
        N = np.eye(n)
    M = system.dynamics.terms(t, q, qd, np.zeros(m), p, np.zeros(n))[0]
    Mr = N.T @ M @ N
    w, V = np.linalg.eigh(0.5 * (Mr + Mr.T))
    scale = max(np.abs(M).max(initial=0.0), 1e-300)
    D = N @ V[:, w <= 1e-12 * scale]
    lay = system.layout
    names, bodies = [], []
    if D.size:
        moving = np.abs(D).max(axis=1) > 1e-8 * np.abs(D).max()
        dim = system.space.dim
        diag = np.abs(np.diag(M)) <= 1e-12 * scale
        for body, sl in lay.body_slices.items():
            idx = np.arange(sl.start, sl.stop)
            if not moving[idx].any():
                continue
            lacks = [w for w, part in (("mass", idx[:dim]), ("inertia", idx[dim:]))
                     if diag[part].all() and moving[part].any()]
            coords = ", ".join(lay.q_names[i] for i in idx if moving[i])
            bodies.append(body)
            names.append(f"body {body!r} ({_mass_properties(system, body)}its free "
                         f"coordinates {coords} carry no {' or '.join(lacks) or 'mass'})")
        in_bodies = {i for sl in lay.body_slices.values() for i in range(sl.start, sl.stop)}
        names += [f"variable {lay.q_names[i]!r}" for i in range(n)
                  if moving[i] and i not in in_bodies]
    if not names:
        return SingularJacobianError(
            f"{what} at t = {t:.6g}: the augmented matrix [M J^T; J 0] is numerically singular "
            "although the constraints are independent and the mass matrix is regular on the free "
            "motions; check for huge or tiny masses, inertias or lengths", time=t, rank=m)
    return SingularMassError(
        f"{what} at t = {t:.6g}: the mass matrix is singular on the motions the kept "
        f"constraints leave free, so these motions move no mass and their accelerations are "
        f"undetermined: {'; '.join(names)}. Give the body mass and inertia "
        "(add_body(..., mass=, inertia=) or set_mass_properties) or constrain that motion.",
        time=t, rank=m, bodies=bodies)


def _mass_properties(system, body) -> str:
    """``"mass 0, inertia 0; "`` as the body was given (empty if the model is unknown)."""
    try:
        b = system._model.body(body)
    except Exception:  # noqa: BLE001 - a description only; never hide the real error
        return ""
    def fmt(v):
        try:
            return f"{float(v):g}"
        except (TypeError, ValueError):
            return str(v)

    inertia = 0 if b.inertia is None else b.inertia
    inertia = fmt(inertia) if np.ndim(inertia) == 0 else str(tuple(fmt(v) for v in inertia))
    return f"mass {fmt(b.mass)}, inertia {inertia}; "


def scaling_at(system, t, q, p) -> Scaling:
    """The unit-free scaling (:class:`Scaling`) of ``system`` at ``(t, q)``: characteristic
    length and column units, computed once per simulation."""
    q = np.asarray(q, dtype=float)
    # (sparse above SPARSE_THRESHOLD coordinates, as the projections take it: the lever arm
    # is the same maximum over the same nonzero entries; the dense 2048 x 3072 Jacobian of a
    # 1024-link chain cost a tenth of its 2 s run in allocation and scans)
    J = system.jacobian(t, q, p, system.n > SPARSE_THRESHOLD) if system.m else \
        np.zeros((0, system.n))
    return Scaling.of(system, q, J)


def project_positions(system, t, q, p, tol=1e-12, max_iterations=8, scaling=None,
                      rank_tolerant=False):
    r"""Minimum-norm correction of ``q`` onto ``Phi(q, t) = 0``, iterated, in the unit-free
    coordinates of ``scaling`` (positions in units of the characteristic length ``L``,
    angles in radians; each equation divided by its row scale ``r``)::

        J^ = R^-1 J D,   dq = -D J^T (J^ J^T)^-1 R^-1 Phi

    Converged when ``max_i |Phi_i| / r_i <= tol (1 + offset)``: the same relative accuracy
    in any unit of length. A singular ``J^ J^^T`` (dependent constraints, lock-up) raises
    :class:`SingularJacobianError` naming the constraints, unless ``rank_tolerant`` (free
    motion through a singular instant: see :func:`_min_norm`)."""
    q = np.array(q, dtype=float)
    if system.m == 0:
        return q
    guard = getattr(system, "branch_guard", None)
    if guard is None:
        return _project_positions(system, t, q, p, tol, max_iterations, scaling, rank_tolerant)
    for _ in range(2):
        if np.all(np.isfinite(q)):
            # a driven angle more than a quarter turn off (an initial condition far from the
            # driver) starts on the asked angle, not on its root half a turn off (0033)
            aligned = guard.align(t, q, p)
            q = q if aligned is None else aligned
        q = _project_positions(system, t, q, p, tol, max_iterations, scaling, rank_tolerant)
        if not guard.wrong(t, q, p):
            break
    return q


def _project_positions(system, t, q, p, tol, max_iterations, scaling, rank_tolerant):
    sparse = system.n > SPARSE_THRESHOLD
    for k in range(max_iterations):
        F, J = system.residual_and_jacobian(t, q, p, sparse)
        if scaling is None and k == 0:
            scaling = Scaling.of(system, q, J.toarray() if sparse else J)
        r = scaling.rows(J)
        Fs = F / r
        if np.abs(Fs).max(initial=0.0) <= tol * (1.0 + scaling.offset):
            break
        q -= _min_norm(system, J, r, scaling, Fs, t, q, rank_tolerant)
    return q


def _system_structure(system, J) -> bool:
    """Whether the CSC matrix ``J`` has the structure of the system's Jacobian (as
    ``System.assemble`` makes it)."""
    _, indices, indptr = system._csc_structure()
    return (J.shape == (system.m, system.n) and J.indices.size == indices.size
            and np.array_equal(J.indptr, indptr) and np.array_equal(J.indices, indices))


def _min_norm(system, J, r, scaling, b, t, q, rank_tolerant=False):
    r"""``D J^T (J^ J^T)^-1 b`` with ``J^ = R^-1 J D``: the smallest correction (in scaled
    coordinates) that changes the scaled residual by ``b``. ``rank_tolerant``: at or near a
    singular ``J^`` (reciprocal condition below ``ZONE^2``) raise the internal
    :class:`._rank.InZone` instead, for the caller's regularised projection.

    A sparse ``J`` (large systems) solves instead, through :func:`projection_pattern`,

    .. math::  \begin{bmatrix} I & \hat J^T \\ \hat J & 0 \end{bmatrix}
               \begin{bmatrix} z \\ -\nu \end{bmatrix} =
               \begin{bmatrix} 0 \\ b \end{bmatrix}, \qquad dq = D z

    (the same ``z = J^T (J^ J^T)^-1 b``; its pivots are the identity's and those of ``J^
    J^T``'s elimination, whose pivot ratio is the condition measure): no product ``J^
    J^T`` and no ordering per call, and the compiled steppers' numbers bit for bit."""
    Js = scaling.scaled(J, r)
    big = sps.issparse(Js) and _system_structure(system, Js)
    try:
        if big:
            pat, slots = projection_pattern(system)
            n, nz = system.n, Js.data.size
            data = np.zeros(slots.size)
            data[slots[:n]] = 1.0
            data[slots[n:n + nz]] = Js.data
            data[slots[n + nz:]] = Js.data
            fac = pat.factor(data)
        else:
            fac = factor(Js @ Js.T)
        if rank_tolerant and fac.rcond < ZONE**2:
            raise InZone
        if big:
            return scaling.columns * fac.solve(np.concatenate((np.zeros(n), b)))[:n]
        y = fac.solve(b)
    except Singular:
        if rank_tolerant:
            raise InZone from None
        raise describe_singular(system, J, t, q, "projection onto the constraints",
                                scaling=scaling) from None
    return scaling.columns * (Js.T @ y)


def project(system, t, q, qd, p, tol=1e-12, max_iterations=8, scaling=None,
            rank_tolerant=False):
    """Project ``(q, qd)`` onto the constraints: positions by :func:`project_positions`,
    then the smallest velocity change (scaled as there) with ``J qd = -Phi_t``."""
    q = project_positions(system, t, q, p, tol, max_iterations, scaling, rank_tolerant)
    if system.m == 0:
        return q, np.array(qd, dtype=float)
    sparse = system.n > SPARSE_THRESHOLD
    J, rhs = system.velocity_rhs(t, q, p, sparse)
    if scaling is None:
        scaling = Scaling.of(system, q, J.toarray() if sparse else J)
    r = scaling.rows(J)
    qd = qd - _min_norm(system, J, r, scaling, (J @ qd - rhs) / r, t, q, rank_tolerant)
    return q, qd


#: :func:`project_holding` of a large system takes the sparse minimum-norm correction while
#: the pivot ratio of ``J^ J^T`` (the held columns removed) is at least this; below, or
#: singular (held values that leave some equations without a free coordinate), the dense
#: least squares, which a 1445-unknown system paid 95 ms for at every start
HOLDING_RCOND = 1e-8


def project_holding(system, t, q, qd, p, scaling, hold_q=(), hold_qd=(), tol=1e-12,
                    max_iterations=8):
    """:func:`project`, keeping the coordinates ``hold_q`` and velocities ``hold_qd`` (index
    lists: the values a user gave in an initial condition) as they are: the others take the
    smallest change (unit-free, least squares) that satisfies the constraints. Given values
    that the constraints do not allow raise :class:`ConsistencyError` (``.held``: which of
    ``q``/``qd`` could not be met; ``.residual``: the scaled residual left)."""
    hold_q, hold_qd = list(hold_q), list(hold_qd)
    if not hold_q and not hold_qd:
        return project(system, t, q, qd, p, tol, max_iterations, scaling)
    q, qd = np.array(q, dtype=float), np.array(qd, dtype=float)
    if system.m == 0:
        return q, qd
    q = hold_positions(system, t, q, p, scaling, hold_q, tol, max_iterations)
    J, rhs = system.velocity_rhs(t, q, p, system.n > SPARSE_THRESHOLD)
    qd = hold_rates(system, J, rhs, qd, scaling, hold_qd, "velocities")
    return q, qd


def hold_positions(system, t, q, p, scaling, hold=(), tol=1e-12, max_iterations=8,
                   check: bool = True):
    r"""Gauss-Newton on ``Phi(q, t) = 0`` with the coordinates ``hold`` (indices) kept: each
    step the smallest unit-free change of the others (least squares on the scaled Jacobian
    with the held columns removed, see :func:`hold_rates`), until ``max_i |Phi_i| / r_i <= tol
    (1 + offset)`` or ``max_iterations``. ``check``: a scaled residual above ``1e-8 (1 +
    offset)`` left at the end raises :class:`ConsistencyError` (``"positions"``); without it
    the iterate is returned as it is (a continuation's step between two targets)."""
    q = np.array(q, dtype=float)
    hold = list(hold)
    sparse = system.n > SPARSE_THRESHOLD
    for _ in range(max_iterations):
        F, J = system.residual_and_jacobian(t, q, p, sparse)
        if np.abs(F / scaling.rows(J)).max(initial=0.0) <= tol * (1.0 + scaling.offset):
            return q
        q += _held_step(system, J, F, hold, scaling)
    if check:
        F, J = system.residual_and_jacobian(t, q, p, sparse)
        left = np.abs(F / scaling.rows(J)).max(initial=0.0)
        if left > 1e-8 * (1.0 + scaling.offset):
            raise ConsistencyError("positions", left)
    return q


def hold_rates(system, J, rhs, x, scaling, hold=(), what: str = "velocities"):
    r"""``x`` changed least (unit-free) so that ``J x = rhs``, the entries ``hold`` kept: the
    velocities (``J = Phi_q``, ``rhs = -Phi_t``) or the accelerations (``rhs = gamma``) of a
    state whose other coordinates follow from the given ones. A residual above ``1e-8 (1 +
    max |x / c|)`` left raises :class:`ConsistencyError` (``what``)."""
    x = np.array(x, dtype=float)
    if system.m == 0:
        return x
    r = scaling.rows(J)
    x += _held_step(system, J, J @ x - rhs, list(hold), scaling)
    left = np.abs((J @ x - rhs) / r).max(initial=0.0)
    if left > 1e-8 * (1.0 + np.abs(x / scaling.columns).max(initial=0.0)):
        raise ConsistencyError(what, left)
    return x


def _held_step(system, J, b, hold, scaling):
    """The least-squares, minimum-norm scaled correction ``dx`` with ``J dx = -b`` and the
    held columns fixed."""
    r = scaling.rows(J)
    if system.n > SPARSE_THRESHOLD:
        # large systems: the minimum-norm correction from J^ J^T (sparse), when the free
        # columns keep full row rank and it is well conditioned; else least squares below
        keep = np.ones(system.n)
        keep[hold] = 0.0
        Js = sps.csr_matrix(scaling.scaled(J, r)) @ sps.diags(keep)
        try:
            fac = factor(sps.csc_matrix(Js @ Js.T))
            if fac.rcond >= HOLDING_RCOND:
                return scaling.columns * (Js.T @ fac.solve(-b / r))
        except Singular:
            pass
    Js = np.asarray(scaling.scaled(J.toarray() if sps.issparse(J) else J, r))
    Js[:, hold] = 0.0
    dx = np.linalg.lstsq(Js, -b / r, rcond=1e-12)[0]
    return scaling.columns * dx


class ConsistencyError(Exception):
    """Internal: given initial values the constraints do not allow (the analysis names
    them in a ModelError)."""

    def __init__(self, held: str, residual: float):
        super().__init__(held)
        self.held, self.residual = held, residual


def _damped_newton(evaluate, x, n, t, what, hint, tol=1e-12, max_iterations=50,
                   col=None, row=None, minimum_norm=False, fixed=()):
    """Newton with Armijo backtracking on ``R(x) = 0``; ``evaluate(x) -> (R, K)``.

    ``col``/``row``: units of the unknowns and of the equations. Newton works on
    ``x^ = x / col``, ``R^ = R / row``, ``K^ = K col / row`` and converges when
    ``max |R^| <= tol (1 + max_{j < n} |x^_j|)`` (the first ``n`` unknowns are the coordinates
    or velocities): the same decision in any unit of length.

    ``minimum_norm``: for a family of solutions (a singular ``K^`` whose equations are
    consistent: the static equilibria with velocity constraints, decision 0055) each step is
    the smallest ``dx^`` of least squares (``lstsq``) instead of the LU solve, so the iteration
    ends on a solution near the start; the unknowns ``fixed`` (indices) do not move."""
    col = np.ones(len(x)) if col is None else col
    free_cols = np.setdiff1d(np.arange(len(x)), np.asarray(fixed, dtype=int))
    history = []
    for it in range(max_iterations + 1):
        R, K = evaluate(x)
        if row is None:
            row = np.ones(len(R))
        Rs = R / row
        err = np.abs(Rs).max(initial=0.0)
        history.append(err)
        # rounding grows with the coordinates (far from the origin), not with the multipliers
        if err <= tol * (1 + np.abs(x[:n] / col[:n]).max(initial=0.0)):
            return x, it
        try:
            if minimum_norm:
                Ks = (K * col / row[:, None])[:, free_cols]
                dx = np.zeros(len(x))
                dx[free_cols] = col[free_cols] * np.linalg.lstsq(Ks, -Rs, rcond=1e-12)[0]
            else:
                dx = col * factor(K * col / row[:, None]).solve(-Rs)
        except Singular:
            raise ConvergenceError(
                f"{what} at t = {t:.6g}: singular Jacobian (scaled residual {err:.3e}); {hint}",
                time=t, history=tuple(history)) from None
        a = 1.0
        while a > 1e-3:
            xn = x + a * dx
            Rn, _ = evaluate(xn)
            if np.abs(Rn / row).max(initial=0.0) < (1 - 1e-4 * a) * err:
                break
            a *= 0.5
        x = xn
    raise ConvergenceError(
        f"{what} at t = {t:.6g} did not converge in {max_iterations} iterations "
        f"(scaled residual {history[-1]:.3e}); start from a better guess (e.g. the previous "
        "solution).", time=t, history=tuple(history))


def _equilibrium_units(system, t, q, p, evaluate_without_multipliers, A=None):
    r"""Units of ``x = [v (n), lambda (m)]`` and ``R = [Phi-like rows (m), J^T lambda - Q
    (n)]`` for the equilibria. With the solver's :class:`Scaling` (columns ``c``, row scales
    ``r``) and a characteristic virtual work ``E = max_j |Q_j c_j|`` (the loads at the
    start; 1 without loads)::

        x units: [c, E / r],   R units: [r, E / c]

    so that positions are in units of ``L``, multipliers in units of the loads, and every
    equation is dimensionless. With velocity constraints (their rows ``A`` (k, n), row scales
    ``r_A``) ``x = [v, lambda, mu]`` and ``R = [Phi-like (m), velocity rows (k), balance
    (n)]``: ``x`` units ``[c, E / r, E / r_A]``, ``R`` units ``[r, r_A, E / c]``."""
    J = system.jacobian(t, q, p) if system.m else np.zeros((0, system.n))
    sc = Scaling.of(system, np.asarray(q, dtype=float), J)
    r = sc.rows(J) if system.m else np.zeros(0)
    rA = sc.rows(A) if A is not None else np.zeros(0)
    R0 = evaluate_without_multipliers()
    E = float(np.abs(R0[system.m + len(rA):] * sc.columns).max(initial=0.0))
    E = E if E > 0 and np.isfinite(E) else 1.0
    return (np.concatenate((sc.columns, E / r, E / rA)),
            np.concatenate((r, rA, E / sc.columns)))


def equilibrium_configuration(eq, system, t, q0, lam0, p, tol=1e-12, max_iterations=50,
                              rows=None, held=()):
    """Newton on ``(q, lambda)`` for the static equilibrium (``eq`` the compiled residual
    ``R(q, lambda)`` and its Jacobian, from ``compile._free``), in the unit-free variables of
    :func:`_equilibrium_units`. Returns ``(q, lam, its)``.

    With velocity constraints (``rows``, a ``VelocityRows``; ``lam0`` then holds ``(lambda,
    mu)``) the equilibria form a family (the constraints remove velocities, not positions):
    minimum-norm Newton steps end on the one near ``q0``, the coordinates ``held`` (indices)
    kept as given (decision 0055)."""
    n, m = system.n, system.m
    A = rows.evaluate(t, q0, np.zeros(n), p)[0] if rows is not None else None
    k = rows.k if rows is not None else 0
    col, row = _equilibrium_units(system, t, q0, p,
                                  lambda: eq.evaluate(t, q0, np.zeros(m + k), p)[0], A)
    x, its = _damped_newton(
        lambda x: eq.evaluate(t, x[:n], x[n:], p), np.concatenate((q0, lam0)), n, t,
        "equilibrium", "the loads may not fix the free coordinates (a neutral direction, e.g. "
        "no load along a free motion) or the guess is at a maximum of potential.", tol,
        max_iterations, col, row, minimum_norm=rows is not None, fixed=held)
    return x[:n], x[n:], its


def equilibrium_velocity(eqv, system, t, q, qd0, lam0, p, tol=1e-12, max_iterations=50,
                         rows=None):
    r"""Newton on :math:`(\dot q, \lambda)` for the velocity equilibrium at fixed ``q``
    (unit-free as :func:`equilibrium_configuration`); with velocity constraints (``rows``) on
    :math:`(\dot q, \lambda, \mu)`."""
    n, m = system.n, system.m
    A = rows.evaluate(t, q, np.zeros(n), p)[0] if rows is not None else None
    k = rows.k if rows is not None else 0
    col, row = _equilibrium_units(system, t, q, p,
                                  lambda: eqv.evaluate(t, q, qd0, np.zeros(m + k), p)[0], A)
    x, its = _damped_newton(
        lambda x: eqv.evaluate(t, q, x[:n], x[n:], p), np.concatenate((qd0, lam0)), n, t,
        "equilibrium velocity", "the velocity-dependent loads may not determine the free "
        "velocities.", tol, max_iterations, col, row)
    return x[:n], x[n:], its
