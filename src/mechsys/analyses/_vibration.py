r"""Linearised vibration: natural frequencies, damping ratios and mode shapes of a mechanism
about an equilibrium or a steady motion (``m.vibration(at=...)``).

The equations of free motion (constraints ``drop``-ped as in ``m.free``) are

.. math::  R(q, \dot q, \ddot q, \lambda, t) = M(q)\ddot q + \Phi_q^T\lambda - Q - Q_v = 0,
           \qquad \Phi(q, t) = 0.

**Perturbation coordinates.** A small change of each body's pose is measured by its position
change and a *global* small rotation (``dtheta`` in 2D, a rotation vector ``dphi`` in 3D):
:math:`dq = B dp` with ``B = I`` in 2D angles, :math:`d(e_i, e_j) = (-e_j, e_i) d\theta` in planar Euler
parameters and, per 3D body, :math:`de = E(e)^T d\phi / 2` (``E`` of :math:`\omega = 2 E(e) \dot{e}`):
the Euler forms keep their normalisation to first order.
The constrained perturbations are the null space of :math:`\Phi_q B` (computed on the unit-free
scaled Jacobian, see :class:`~mechsys.solvers._linalg.Scaling`): :math:`dp = N z` with ``f`` =
number of degrees of freedom independent coordinates ``z``, and :math:`P = B N`; ``N`` is chosen
by a column-pivoted QR so that each ``z_k`` is one perturbation coordinate
(:func:`_null_basis`: a soft coordinate is not mixed with a stiff one).

**Linearisation.** With ``A_q = dR/dq``, ``A_v = dR/dqd``, ``A_a = dR/dqdd`` (derived
symbolically, so the stiffness includes the *geometric stiffness* :math:`d(\Phi_q^T \lambda)/dq`
of the multipliers and the load stiffness ``-dQ/dq``; the inertia terms
:math:`d(M \ddot q)/dq` and ``-dQv/dq, -dQv/dqd`` give the centrifugal and gyroscopic terms)
and :math:`dq = P z`, :math:`d\dot q = P z' + P' z`, :math:`d\ddot q = P z'' + 2 P' z' + P'' z` (:math:`P' =
B(\dot{e}) N`: the perturbation frame turns with a rotating body), projecting on ``P^T`` (which
removes the multiplier changes, since :math:`\Phi_q P = 0`):

.. math::

    M_r z'' + C_r z' + K_r z &= 0, \\
    M_r &= P^T A_a P, \quad C_r = P^T (A_v P + 2 A_a P'), \quad
    K_r = P^T (A_q P + A_v P' + A_a P'').

Its eigenvalues ``s`` (:math:`\det(s^2 M_r + s C_r + K_r) = 0`) give, per oscillatory mode, the
natural frequency :math:`\omega_n = \lvert s \rvert` [rad/s], :math:`\mathit{hz} = \omega_n / (2 \pi)` [Hz],
the damping ratio
:math:`\zeta = -\operatorname{Re}(s)/\lvert s \rvert` and the damped frequency ``|Im s|``. At an equilibrium
(``qd = 0``)
:math:`P' = P'' = 0`; ``K_r`` is then the Hessian of the potential plus :math:`\lambda^T \Phi`.

**Steady motion.** The linearisation is taken at the instant of the reference state. It has
constant coefficients -- and the eigenvalues mean what they say -- when the reference motion
is steady in the perturbation frame: every body at rest, translating uniformly or spinning
at a constant rate about an axis that is fixed in space and about which its inertia (and
the loads on it) are symmetric (a rotor in bearings, a sleeping top). The reference state
must be an equilibrium or such a steady motion: the linear and global angular accelerations
of the bodies must vanish (checked; ``tolerance``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from .._errors import ModelError
from ..solvers._free import free_acceleration, project, project_positions, scaling_at
from ._linearize import linear_kernel


def _E(e) -> np.ndarray:
    r"""``E(e)`` (3, 4) of the global angular velocity :math:`\omega = 2 E(e) \dot{e}`."""
    e0, e1, e2, e3 = e
    return np.array([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])


def _rotation_block(space, rot) -> np.ndarray:
    r"""Rotation coordinates' change per unit global small rotation of a body: 2D angle
    ``[[1]]``; planar Euler parameters :math:`d(e_i, e_j) = (-e_j, e_i) d\theta`; 3D
    :math:`de = E(e)^T d\phi / 2`. Linear in ``rot`` except for the angle."""
    if space.dim == 3:
        return 0.5 * _E(rot).T
    if space.ncoord == 4:                       # orientation="euler"
        return np.array([[-rot[1]], [rot[0]]])
    return np.ones((1, 1))


def _frame(system, q) -> np.ndarray:
    """``B`` (n, n_min): coordinate changes per unit position change / global small rotation
    of each body (and per unit change of each model variable)."""
    n, dim = system.n, system.space.dim
    nrot = 1 if dim == 2 else 3
    B = np.zeros((n, _frame_columns(system).size))
    covered = np.zeros(n, dtype=bool)
    c = 0
    for sl in system.layout.body_slices.values():
        covered[sl] = True
        B[sl.start : sl.start + dim, c : c + dim] = np.eye(dim)
        B[sl.start + dim : sl.stop, c + dim : c + dim + nrot] = _rotation_block(
            system.space, q[sl.start + dim : sl.stop])
        c += dim + nrot
    for i in np.flatnonzero(~covered):  # model variables (gear angles, curve parameters)
        B[i, c] = 1.0
        c += 1
    return B


def _frame_columns(system) -> np.ndarray:
    """Per perturbation coordinate: is it a position change (measured in units of the
    characteristic length ``L``, as :class:`Scaling` does) rather than a rotation or a
    variable change."""
    dim = system.space.dim
    out = []
    for _ in system.layout.body_slices:
        out += [True] * dim + [False] * (1 if dim == 2 else 3)
    nvar = system.n - sum(sl.stop - sl.start for sl in system.layout.body_slices.values())
    return np.array(out + [False] * nvar, dtype=bool)


@dataclass(frozen=True)
class VibrationModes:
    r"""Modes of a linearised mechanism (see :mod:`mechsys.analyses._vibration`).

    The perturbations :math:`\delta q = P z` of the :math:`f` independent coordinates
    :math:`z` obey the reduced linear equations, whose eigenvalues :math:`s` are the modes:

    .. math::

        M_r \ddot z + C_r \dot z + K_r z = 0, \qquad
        \det(s^2 M_r + s C_r + K_r) = 0

    ``eigenvalues`` (k,) complex :math:`s` (one per oscillatory pair, :math:`\operatorname{Im}
    s \ge 0`; each real eigenvalue -- overdamped or statically unstable motion -- is a mode
    of its own); ``omega`` (k,) natural frequencies :math:`\omega_n = \lvert s \rvert`
    [rad/s]; ``hz`` (k,) the same in Hz, :math:`\omega_n / 2\pi`; ``damped_omega`` (k,)
    :math:`\lvert \operatorname{Im} s \rvert`; ``damping_ratio`` (k,) :math:`\zeta =
    -\operatorname{Re} s / \lvert s \rvert` (``nan`` for a zero eigenvalue: a rigid-body
    mode); ``shapes`` (k, n) the coordinate changes :math:`\delta q` of each mode in all the
    coordinates (real and mass-normalised, :math:`z^T M_r z = 1`, for an undamped
    conservative system; else complex with the largest unit-free component 1);
    ``coordinates`` the coordinate names; ``t``, ``q``, ``qd`` the reference state;
    ``mass``, ``damping``, ``stiffness`` the reduced :math:`M_r, C_r, K_r` (f, f) and
    ``basis`` :math:`P` (n, f); ``stability`` (k,) each mode's class, ``"stable"``
    (:math:`\operatorname{Re} s < 0`: decays), ``"neutral"`` (:math:`\operatorname{Re} s = 0`
    within the mode's own accuracy: an undamped oscillation, or a zero eigenvalue -- a
    rigid-body motion or a neutral equilibrium, which the linearisation cannot decide) or
    ``"unstable"`` (:math:`\operatorname{Re} s > 0`: grows); ``stable`` whether no mode is
    unstable. Each eigenvalue is judged on its own scale: :math:`\lvert \operatorname{Re} s
    \rvert \le 10^{-7} s_\text{own}` or :math:`\le 10^{-12} \max \lvert s \rvert` is neutral,
    with

    .. math::

        s_\text{own} = \sqrt{\frac{\lvert z \rvert^T \lvert K_r \rvert \lvert z \rvert}
        {\lvert z^H M_r z \rvert}} + \frac{\lvert z \rvert^T \lvert C_r \rvert \lvert z
        \rvert}{\lvert z^H M_r z \rvert}

    the size of the terms the mode's eigenvalue comes from (not the stiffest mode's).
    """

    eigenvalues: np.ndarray
    omega: np.ndarray
    hz: np.ndarray
    damped_omega: np.ndarray
    damping_ratio: np.ndarray
    shapes: np.ndarray
    coordinates: tuple
    t: float
    q: np.ndarray
    qd: np.ndarray
    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    basis: np.ndarray
    stable: bool
    stability: tuple
    system: object = field(repr=False)
    model: object = field(repr=False)
    p: np.ndarray = field(repr=False)
    columns: np.ndarray = field(repr=False)

    def __len__(self) -> int:
        return len(self.omega)

    #: the fields with a known unit: (power of time, unit of the angle or ratio)
    _UNITS = {"eigenvalues": (-1, ""), "omega": (-1, "rad"), "damped_omega": (-1, "rad"),
              "hz": (-1, ""), "damping_ratio": (0, ""), "t": (1, "")}

    def quantity(self, name: str):
        r"""The field ``name`` (``"omega"``, ``"hz"``, ``"damped_omega"``, ``"eigenvalues"``,
        ``"damping_ratio"``, ``"t"``) as a pint Quantity in the model's declared time unit
        (``m.set_units``): ``omega`` in rad/s, ``hz`` in 1/s (cycles per second: Hz) when the
        unit is seconds. A field of no single unit (``shapes``, ``mass``, ...) is refused by
        name. Example: ``modes.quantity("omega").to("rpm")`` (pint counts a radian as 1 and a
        revolution as :math:`2\pi`: convert the angular ``omega`` to rpm, not ``hz``). Needs
        pint."""
        from .._errors import choice
        from ..geometry._units import _registry

        choice(name, list(self._UNITS), "VibrationModes.quantity: field")
        units = getattr(self.model, "units", None) or {}
        if "time" not in units:
            raise ModelError("VibrationModes.quantity: frequencies in units need the model's "
                             "time unit: declare it with m.set_units(time=...) first")
        ureg = _registry()
        power, angle = self._UNITS[name]
        unit = ureg.Unit(units["time"]) ** power
        if angle == "rad":
            unit = ureg.Unit("radian") * unit
        return ureg.Quantity(np.asarray(getattr(self, name)), unit)

    def shape(self, k: int, coordinates=None) -> np.ndarray:
        """Mode ``k``'s coordinate changes (all coordinates, or the named ones)."""
        v = self.shapes[self._index(k)]
        if coordinates is None:
            return v
        return np.array([v[self.system.layout.index(c)] for c in coordinates])

    def _index(self, k) -> int:
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not (
                -len(self) <= k < len(self)):
            raise ModelError(f"mode number must be an integer in 0..{len(self) - 1}, got {k!r}")
        return int(k) % len(self)

    def motion(self, k: int, amplitude: float | None = None, cycles: float = 1.0,
               frames: int = 40):
        r"""A :class:`~mechsys.Solution` of mode ``k`` over ``cycles`` periods (``frames``
        points): :math:`q(t) = q_\text{ref} + a \operatorname{Re}(\text{shape}\; e^{s t})`
        with the decay/growth removed (:math:`e^{i \omega_d t}`), each point projected onto
        the constraints. ``amplitude`` :math:`a` is the largest unit-free coordinate change
        (positions in units of the characteristic length, rotations in radians); default 0.1.
        A mode without oscillation (:math:`\omega_d = 0`) is shown over a unit time as
        :math:`\sin(2 \pi t)`."""
        from ..results._solution import Solution

        k = self._index(k)
        if isinstance(frames, bool) or not isinstance(frames, (int, np.integer)) or frames < 2:
            raise ModelError(f"frames must be an integer >= 2, got {frames!r}")
        if not (np.isfinite(cycles) and cycles > 0):
            raise ModelError(f"cycles must be a positive number, got {cycles!r}")
        a = 0.1 if amplitude is None else float(amplitude)
        if not np.isfinite(a):
            raise ModelError(f"amplitude must be finite, got {amplitude!r}")
        v = self.shapes[k]
        big = np.abs(v / self.columns).max(initial=0.0)
        v = v * (a / big) if big > 0 else v
        wd = self.damped_omega[k]
        period = 2 * np.pi / wd if wd > 0 else 1.0
        t = np.linspace(0.0, cycles * period, int(frames))
        phase = np.exp(1j * 2 * np.pi * t / period)
        sc = scaling_at(self.system, self.t, self.q, self.p)
        Q = np.array([project_positions(self.system, self.t, self.q + np.real(v * ph), self.p,
                                        scaling=sc) for ph in phase])
        return Solution(t=t, q=Q, qd=None, qdd=None, p=self.p, system=self.system,
                        model=self.model, iterations=np.zeros(len(t), dtype=int),
                        mode="vibration", extra={"mode": k, "omega": float(self.omega[k])})

    def animate(self, k: int, path=None, amplitude: float | None = None, cycles: float = 1.0,
                frames: int = 40, **kw):
        """Animate mode ``k`` (:meth:`motion` drawn with :func:`mechsys.draw.animate`; ``path``
        ``.gif``/``.mp4``/``.html`` writes a file, other keywords go to the animation). The
        title says which mode and its natural frequency (``title=`` replaces it), numbered
        as in :meth:`table`."""
        from .. import draw

        kw.setdefault("title", f"mode {k}: {self.hz[k]:.4g} Hz")
        return draw.animate(self.motion(k, amplitude, cycles, frames), path=path, **kw)

    def table(self) -> str:
        """A text table: mode, natural frequency [Hz, rad/s], damping ratio."""
        lines = [f"{'mode':>4} {'f [Hz]':>14} {'omega [rad/s]':>14} {'zeta':>10} {'':>8}"]
        for i, (h, w, z, c) in enumerate(zip(self.hz, self.omega, self.damping_ratio,
                                             self.stability)):
            lines.append(f"{i:>4} {h:>14.6g} {w:>14.6g} {z:>10.4g} {c:>8}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"<VibrationModes: {len(self)} mode(s) at t = {self.t:.6g}, "
                f"{'stable' if self.stable else 'UNSTABLE'}>\n" + self.table())


def _reference(model, system, at, t):
    """``(t, q, qd)`` of the reference state given as ``at``."""
    n = system.n
    lay = system.layout
    if at is None:
        at = model.last_solution
        if at is None:
            raise ModelError("vibration: give the reference state at= (an equilibrium Solution "
                             "from m.free(solution='static').solve(), a State, a mapping of "
                             "coordinate and '<coordinate>_d' values, or a coordinate array)")
    if hasattr(at, "q") and hasattr(at, "system"):
        q = np.atleast_2d(at.q)[-1].astype(float)
        if q.shape != (n,):
            raise ModelError(f"vibration: the reference solution has {q.size} coordinates, the "
                             f"model {n}; it belongs to another model (or the model changed)")
        qd = np.zeros(n) if at.qd is None else np.atleast_2d(at.qd)[-1].astype(float)
        t0 = float(np.atleast_1d(at.t)[-1]) if t is None else float(t)
        return t0, q, qd
    t0 = 0.0 if t is None else float(t)
    if isinstance(at, Mapping):
        q, qd = model.guess(), np.zeros(n)
        for k, v in at.items():
            name = k.name if hasattr(k, "name") else str(k)
            try:
                value = float(v)
            except (TypeError, ValueError):
                raise ModelError(f"vibration at=: the value of {name!r} must be a number, "
                                 f"got {v!r}") from None
            if name.endswith("_d"):
                qd[lay.index(name[:-2])] = value
            else:
                q[lay.index(name)] = value
        return t0, q, qd
    try:
        q = np.asarray(at, dtype=float)
    except (TypeError, ValueError):
        q = None
    if q is None or q.shape != (n,):
        raise ModelError(f"vibration at=: expected a Solution/State, a mapping or an array of "
                         f"{n} coordinates {list(lay.q_names)}, got {at!r}")
    return t0, q, np.zeros(n)


def vibration(model, at=None, drop=(), t=None, tolerance: float = 1e-6,
              rotating=None) -> VibrationModes:
    """Linearised vibration modes of ``model`` about the reference state ``at`` (see the
    module docstring for the equations). ``drop``: constraints removed first (drivers), as
    in ``m.free``; ``t``: time of the linearisation (default the reference solution's time,
    else 0); ``tolerance``: how far from steady the reference may be (the unbalanced
    generalized force, relative to the forces acting, in the independent coordinates);
    ``rotating``: ``(omega, center)`` (2D) or ``(omega, center, axis)`` (3D) -- linearise in
    a frame turning at ``omega`` [rad/s] about that point (and axis), in which the reference
    motion is an equilibrium (a relative equilibrium: centrifugal pendulum, rotating hoop).

    Example::

        eq = m.free(solution="static").solve()
        modes = m.vibration(at=eq)
        modes.hz, modes.damping_ratio, modes.shape(0), modes.animate(0, "mode0.gif")
    """
    if not (isinstance(tolerance, (int, float)) and 0 < tolerance < 1):
        raise ModelError(f"vibration: tolerance must be a number in (0, 1), got {tolerance!r}")
    drop = drop if isinstance(drop, (list, tuple)) else [drop]
    dropped = [model.constraint(c) for c in drop]
    system = model._system_without(dropped)
    n = system.n
    if n == 0:
        raise ModelError("vibration: the model has no moving bodies (or variables)")
    p = np.array([model._params[s] for s in system.layout.p_symbols], dtype=float)
    t0, q, qd = _reference(model, system, at, t)
    W = _rotation_rate(rotating, system.space.dim)
    if W is not None and not np.any(qd):  # at rest in the rotating frame
        qd = _frame_velocities(system, q, *W)
    sc = scaling_at(system, t0, q, p)
    q, qd = project(system, t0, q, qd, p, scaling=sc)
    qdd, lam, _ = free_acceleration(system, t0, q, qd, p)

    # independent perturbation coordinates: null space of the scaled Phi_q B
    B = _frame(system, q)
    trans = _frame_columns(system)
    D = np.where(trans, sc.length, 1.0)
    J = system.jacobian(t0, q, p) if system.m else np.zeros((0, n))
    # rows scaled as the solvers scale Phi_q (a normalisation row of Phi_q B is zero only
    # up to rounding: scaling it by its own size would turn the rounding into a constraint)
    JB = (J @ B) * D / (sc.rows(J)[:, None] if J.shape[0] else 1.0)
    N = D[:, None] * _null_basis(JB)
    f = N.shape[1]
    if f == 0:
        raise ModelError("vibration: the kept constraints leave no degree of freedom at the "
                         "reference state; drop the drivers (drop=[...]) whose motion should be free")
    P = B @ N
    # the perturbation frame turns with the bodies: B is linear in e, so P' = B(e_dot) N
    # the exact derivatives of the equations of motion: the same kernel as free.linearize
    Aq, Av, Aa = linear_kernel(system)(t0, q, qd, qdd, lam, p)
    Pd = _rate(system, qd) @ N
    Pdd = _rate(system, qdd) @ N
    if W is not None:  # the perturbation frame turns with the rotating frame: R' = W R
        Wm = _frame_rotation(system, W[0])
        Pd = Pd + B @ Wm @ N
        Pdd = Pdd + 2 * _rate(system, qd) @ Wm @ N + B @ Wm @ Wm @ N
    Mr = P.T @ Aa @ P
    Cr = P.T @ (Av @ P + 2 * Aa @ Pd)
    Kr = P.T @ (Aq @ P + Av @ Pd + Aa @ Pdd)

    _check_steady(system, B, P, q, qd, qdd, lam, p, t0, tolerance, W, Aq)
    s, Z, real = _eigen(Mr, Cr, Kr)
    shapes = (P @ Z).T
    unit = np.where(_coordinate_translation(system), sc.length, 1.0)
    if not real:  # largest unit-free component 1 and real
        for i in range(len(shapes)):
            v = shapes[i] / unit
            j = int(np.argmax(np.abs(v)))
            if abs(v[j]) > 0:
                shapes[i] = shapes[i] / v[j]
    omega = np.abs(s)
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(omega > 0, -s.real / np.where(omega > 0, omega, 1.0), np.nan) + 0.0
    floor = _neutral_floor(Mr, Cr, Kr, Z, s)
    stability = tuple("neutral" if abs(x.real) <= fl else "unstable" if x.real > 0 else "stable"
                      for x, fl in zip(s, floor))
    for a in (s, omega, zeta, shapes, Mr, Cr, Kr, P):
        a.setflags(write=False)
    return VibrationModes(
        eigenvalues=s, omega=omega, hz=omega / (2 * np.pi), damped_omega=np.abs(s.imag),
        damping_ratio=zeta, shapes=shapes, coordinates=tuple(system.layout.q_names), t=t0,
        q=q, qd=qd, mass=Mr, damping=Cr, stiffness=Kr, basis=P,
        stable="unstable" not in stability, stability=stability,
        system=system, model=model, p=p, columns=unit)


#: the null-space basis from independent coordinates is used while the dependent block's
#: condition number (2-norm, column-pivoted QR's ``R_11``) stays below this, else the SVD's
PARTITION_COND = 1e8


def _null_basis(JB: np.ndarray) -> np.ndarray:
    r"""A basis ``N`` (n, f) of the null space of ``JB`` (m, n) made of *independent
    coordinates*: the rank ``r`` from the singular values (above ``1e-10`` of the largest),
    the ``r`` dependent coordinates ``d`` from a column-pivoted QR, ``JB[:, piv] = Q R``,
    and the others ``i`` independent:

    .. math::  N_{i} = I, \qquad N_{d} = -R_{11}^{-1} R_{12}.

    Each column of ``N`` moves one independent coordinate and only the coordinates the
    constraints tie to it, so parts of the mechanism that the constraints do not couple
    stay apart in ``z``, and ``K_r = P^T K P`` holds no sum of a stiff and a soft term that
    cancels. The SVD's orthonormal basis is any rotation of the null space (its singular
    values there are all zero): it mixed a soft coordinate with a stiff one, and the soft
    eigenvalue was lost in the stiff one's rounding (issue 34: a slider on a spring of 1
    beside a rotor on one of 1e14 gave 0 instead of 1). The SVD basis stays the fallback
    when the dependent block is ill-conditioned (``PARTITION_COND``), where the partition
    would amplify rounding instead.

    Example: ``_null_basis(np.array([[1.0, -1.0, 0.0]]))`` is ``[[1, 0], [1, 0], [0, 1]]``
    (up to the order of its columns)."""
    n = JB.shape[1]
    if not JB.size:
        return np.eye(n)
    _, sv, Vt = sla.svd(JB)
    rank = int(np.sum(sv > 1e-10 * max(sv.max(initial=0.0), 1.0)))
    if rank == 0:
        return np.eye(n)
    _, R, piv = sla.qr(JB, mode="economic", pivoting=True)
    R11, R12 = R[:rank, :rank], R[:rank, rank:]
    if np.linalg.cond(R11) < PARTITION_COND:
        X = sla.solve_triangular(R11, R12)
        if np.all(np.isfinite(X)):
            N = np.zeros((n, n - rank))
            N[piv[rank:], :] = np.eye(n - rank)
            N[piv[:rank], :] = -X
            # the independent coordinates in the model's order (the modes do not depend on
            # it; a stable order keeps ``basis``, ``mass`` and ``stiffness`` readable)
            return N[:, np.argsort(piv[rank:], kind="stable")]
    return Vt[rank:].T


#: a mode is neutral when ``|Re s| <= NEUTRAL * (its own frequency scale)``: the double zero
#: eigenvalue of a rigid-body motion is computed to about the square root of the rounding
NEUTRAL = 1e-7
#: and, whatever its own scale, when ``|Re s| <= ROUNDING * max |s|``: the eigensolver's
#: absolute accuracy, below which no sign is known
ROUNDING = 1e-12


def _mode_scale(M, C, K, Z) -> np.ndarray:
    """Each mode's own frequency scale ``sqrt(|z|^T |K| |z| / m) + |z|^T |C| |z| / m`` with
    ``m = |z^H M z|`` [1/s]: the size of the terms its eigenvalue comes from (a mode of a
    soft spring is judged against that spring, not against the stiffest one of the model)."""
    a = np.abs(Z)
    m = np.abs(np.einsum("ik,ij,jk->k", Z.conj(), M, Z))
    m = np.maximum(m, 1e-14 * np.einsum("ik,ij,jk->k", a, np.abs(M), a) + 1e-300)
    k = np.einsum("ik,ij,jk->k", a, np.abs(K), a)
    c = np.einsum("ik,ij,jk->k", a, np.abs(C), a)
    return np.sqrt(k / m) + c / m


def _neutral_floor(M, C, K, Z, s) -> np.ndarray:
    """Per mode, the ``|Re s|`` at or below which the mode is neutral (see ``NEUTRAL``)."""
    big = float(np.abs(s).max(initial=0.0))
    return np.maximum(NEUTRAL * _mode_scale(M, C, K, Z), ROUNDING * big)


def _coordinate_translation(system) -> np.ndarray:
    dim = system.space.dim
    out = np.zeros(system.n, dtype=bool)
    for sl in system.layout.body_slices.values():
        out[sl.start : sl.start + dim] = True
    return out


def _rotation_rate(rotating, dim):
    """``(W (3, 3) = omega n~, center (dim,))`` of ``rotating`` or None."""
    if rotating is None:
        return None
    form = "(omega, center)" if dim == 2 else "(omega, center, axis)"
    if not isinstance(rotating, (tuple, list)) or len(rotating) != (2 if dim == 2 else 3):
        raise ModelError(f"vibration rotating=: give {form} in {dim}D, got {rotating!r}")
    try:
        om = float(rotating[0])
        c = np.asarray(rotating[1], dtype=float)
        n = np.array([0.0, 0.0, 1.0]) if dim == 2 else np.asarray(rotating[2], dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"vibration rotating=: give {form} as numbers, got {rotating!r}") from None
    if c.shape != (dim,) or n.shape != (3,) or not (np.all(np.isfinite(c)) and np.isfinite(om)):
        raise ModelError(f"vibration rotating=: give {form}: a rate, a {dim}D point"
                         + ("" if dim == 2 else " and a 3D direction") + f", got {rotating!r}")
    norm = np.linalg.norm(n)
    if not norm > 0:
        raise ModelError("vibration rotating=: the axis direction is zero")
    n = n / norm
    W = om * np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return W, c


def _frame_rotation(system, W) -> np.ndarray:
    """``W`` acting on the perturbation coordinates: positions and 3D rotation vectors turn,
    a planar angle does not, model variables do not."""
    dim = system.space.dim
    nmin = _frame_columns(system).size
    R = np.zeros((nmin, nmin))
    c = 0
    for _ in system.layout.body_slices:
        R[c : c + dim, c : c + dim] = W[:dim, :dim]
        if dim == 3:
            R[c + 3 : c + 6, c + 3 : c + 6] = W
            c += 6
        else:
            c += 3
    return R


def _frame_velocities(system, q, W, c) -> np.ndarray:
    """Velocities of every body carried by the rotating frame: ``rdot = W (r - c)``,
    ``omega = w`` (``thdot = omega`` in 2D; ``e_dot = E(e)^T w / 2`` in 3D)."""
    dim = system.space.dim
    qd = np.zeros(system.n)
    w = np.array([W[2, 1], W[0, 2], W[1, 0]])
    for sl in system.layout.body_slices.values():
        qd[sl.start : sl.start + dim] = W[:dim, :dim] @ (q[sl.start : sl.start + dim] - c)
        qd[sl.start + dim : sl.stop] = _rotation_block(system.space, q[sl.start + dim : sl.stop]) \
            @ (w[2:] if dim == 2 else w)
    return qd


def _rate(system, x) -> np.ndarray:
    """``B(x)`` with the Euler parameters replaced by ``x``'s entries and no translation or
    variable part: the time derivative of ``B`` along a motion with rates ``x``."""
    B = _frame(system, x)
    space = system.space
    if space.dim == 2 and space.ncoord == 3:    # a planar angle's B is constant
        return np.zeros_like(B)
    keep = np.zeros_like(B)
    for sl in system.layout.body_slices.values():
        keep[sl.start + space.dim : sl.stop] = B[sl.start + space.dim : sl.stop]
    return keep


def _check_steady(system, B, P, q, qd, qdd, lam, p, t, tol, W=None, Aq=None):
    """The reference must be an equilibrium or a steady motion: the bodies' linear and
    global angular accelerations vanish (in a rotating frame ``W``: equal ``W rdot`` and
    ``W omega``, those of a motion carried by the frame). Measured as the generalized force
    ``M B a`` that the remaining accelerations ``a`` need, relative to the forces acting."""
    dyn = system.dynamics
    Mm, Q, Qv = dyn.terms(t, q, qd, lam, p, qdd)
    # minimal accelerations a (positions: r_dd; 3D rotations: alpha = 2 E(e) e_dd)
    a = np.linalg.lstsq(B, qdd, rcond=None)[0]
    if system.space.dim == 3:
        c = 0
        for sl in system.layout.body_slices.values():
            a[c + 3 : c + 6] = 2 * _E(q[sl.start + 3 : sl.stop]) @ qdd[sl.start + 3 : sl.stop]
            c += 6
    if W is not None:  # the accelerations of a motion carried by the rotating frame
        v = np.linalg.lstsq(B, qd, rcond=None)[0]
        if system.space.dim == 3:
            c = 0
            for sl in system.layout.body_slices.values():
                v[c + 3 : c + 6] = 2 * _E(q[sl.start + 3 : sl.stop]) @ qd[sl.start + 3 : sl.stop]
                c += 6
        a = a - _frame_rotation(system, W[0]) @ v
    # on every coordinate, not only the free ones: a driven or orbiting body that accelerates
    # turns the constraints' tangent space with time, which the frozen linearisation misses
    unsteady = Mm @ (B @ a)
    J = system.jacobian(t, q, p) if system.m else np.zeros((0, system.n))
    forces = np.abs(Q) + np.abs(Qv) + np.abs(Mm @ qdd) + np.abs(J.T @ lam)
    ref = float(forces.max(initial=0.0))
    if Aq is not None:  # and the forces of a unit-free displacement (P's columns are unit
        # steps): a pendulum hanging in a generalized coordinate has no force acting at all
        ref = max(ref, float(np.abs(Aq @ P).max(initial=0.0)))
    bad = float(np.abs(unsteady).max(initial=0.0))
    if bad > tol * ref and bad > 0:
        names = system.layout.q_names
        worst = np.argsort(-np.abs(B @ a))[:3]
        listed = ", ".join(f"{names[i]}_dd = {(B @ a)[i]:.3g}" for i in worst)
        raise ModelError(
            f"vibration: the reference state is not an equilibrium or steady motion (unbalanced "
            f"generalized force {bad:.3g}, {bad / ref:.2e} of the forces acting; accelerations "
            f"{listed}). Solve for the equilibrium first: eq = m.free(solution='static').solve() "
            "and pass at=eq (or give a steadily rotating state)")


def _eigen(M, C, K):
    """Eigenvalues ``s`` (one per oscillatory pair) and the ``z`` eigenvectors (f, k) of
    ``s^2 M + s C + K``; ``real`` when the symmetric undamped path was taken."""
    f = M.shape[0]
    size = max(np.abs(M).max(initial=0.0), 1e-300)
    ksize = max(np.abs(K).max(initial=0.0), 1e-300)
    undamped = np.abs(C).max(initial=0.0) <= 1e-12 * np.sqrt(size * ksize)
    symmetric = (np.abs(K - K.T).max(initial=0.0) <= 1e-9 * ksize
                 and np.abs(M - M.T).max(initial=0.0) <= 1e-12 * size)
    if undamped and symmetric:
        try:
            w2, Z = sla.eigh((K + K.T) / 2, (M + M.T) / 2)
        except np.linalg.LinAlgError:
            w2 = None
        if w2 is not None:
            # each mode on its own scale (issue 34): the Rayleigh quotient z^T K z (z^T M z = 1)
            # is accurate to the rounding of the terms it sums, |z|^T |K| |z|, which for a soft
            # mode beside a stiff one is far below the stiffest eigenvalue
            Ks = (K + K.T) / 2
            w2 = np.einsum("ik,ij,jk->k", Z, Ks, Z)
            own = np.einsum("ik,ij,jk->k", np.abs(Z), np.abs(Ks), np.abs(Z))
            w2 = np.where(np.abs(w2) <= 1e-13 * own, 0.0, w2)
            s = np.where(w2 >= 0, 1j * np.sqrt(np.abs(w2)), np.sqrt(np.abs(w2)) + 0j)
            order = np.argsort(np.abs(s), kind="stable")
            return s[order], Z[:, order], True
    # state space  [I 0; 0 M] x' = [0 I; -K -C] x
    A = np.block([[np.zeros((f, f)), np.eye(f)], [-K, -C]])
    E = np.block([[np.eye(f), np.zeros((f, f))], [np.zeros((f, f)), M]])
    w, V = sla.eig(A, E)
    ok = np.isfinite(w)
    w, V = w[ok], V[:, ok]
    scale = max(np.abs(w).max(initial=0.0), 1e-300)
    keep = (w.imag > 1e-12 * scale) | (np.abs(w.imag) <= 1e-12 * scale)
    w, V = w[keep], V[:f, keep]
    w = np.where(np.abs(w.imag) <= 1e-12 * scale, w.real + 0j, w)
    # a rigid-body motion gives a double zero eigenvalue (position and velocity): one mode.
    # Zero on the mode's own scale (issue 34): against the largest eigenvalue, a slightly
    # unstable soft mode beside a stiff one was taken for one and could be dropped
    own = _mode_scale(M, C, K, V)
    zero = np.flatnonzero(np.abs(w) <= np.maximum(NEUTRAL * own, ROUNDING * scale))
    drop = zero[(len(zero) + 1) // 2 :]
    w, V = np.delete(w, drop), np.delete(V, drop, axis=1)
    order = np.lexsort((w.real, np.abs(w)))
    return w[order], V[:, order], False


__all__ = ["VibrationModes", "vibration"]
