r"""Random mechanisms for fuzz tests (``tests/test_fuzz.py``, ``benchmarks/fuzz_long.py``).

:func:`random_mechanism` builds a planar or spatial model from one seed:

1. a conformance case of a constraint type drawn from the whole registry
   (:data:`mechsys.testing.CASES`: every joint, cam, gear and general constraint), which comes
   with a configuration ``q`` that satisfies it at time ``t``;
2. up to ``extra`` more bodies, each pinned (``Revolute2`` in 2D, ``Spherical3`` in 3D) to a
   random point of a random body of the model (ground included) at a random pose: the pin's
   local point on the new body is computed so that ``q`` stays a solution;
3. random masses, centroids and inertias on every body, and sometimes gravity;
4. drivers (general ``Constraint`` ``q_j = q_j(t) + w (T - t)``) on coordinates chosen one by
   one so that each raises the Jacobian's rank, until no degree of freedom is left (or, with
   ``leave_dof``, one is left over).

:func:`check_mechanism` then asserts, on that model:

* only :class:`~mechsys.MechError` subclasses escape any call (the others are bugs);
* the Jacobian and ``gamma`` of the whole system match finite differences;
* ``m.dof()`` equals ``n - rank(Phi_q)`` with the rank taken independently (SVD of the
  equilibrated Jacobian; configurations whose singular values fall in a gray zone are not
  compared);
* a kinematic solve (positions, velocities, accelerations) over a few times satisfies the
  constraints to tolerance, and velocities :math:`\Phi_q \dot q = -\Phi_t`;
* the free acceleration with the drivers dropped satisfies :math:`\Phi_q \ddot q = \gamma`;
* the diagnostics (``m.singularity``) report the rank the solver sees.

It returns a dict of what was measured and what was skipped (``outcome``).
"""

from __future__ import annotations

import math

import numpy as np
import sympy as sp

from .._errors import ConstraintCountError, MechError, SingularJacobianError
from .._symbols import T
from ._checks import CASES, Case, check_gamma, check_jacobian

#: relative singular values between these bounds make the numerical rank ambiguous
GRAY = (1e-11, 1e-6)


class FuzzFailure(AssertionError):
    """A fuzz property failed: ``seed`` and ``what`` say which and where."""

    def __init__(self, seed, what: str):
        super().__init__(f"fuzz seed {seed}: {what}")
        self.seed, self.what = seed, what


def _rot2(th):
    c, s = math.cos(th), math.sin(th)
    return np.array([[c, -s], [s, c]])


def _rot3(e):
    e0, e1, e2, e3 = e / np.linalg.norm(e)
    return np.array([
        [e0**2 + e1**2 - e2**2 - e3**2, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)],
        [2 * (e1 * e2 + e0 * e3), e0**2 - e1**2 + e2**2 - e3**2, 2 * (e2 * e3 - e0 * e1)],
        [2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0**2 - e1**2 - e2**2 + e3**2]])


def _pose(model, values: dict, body):
    """``(r, A)`` of a body from the coordinate values ``{symbol name: value}``."""
    dim = model.space.dim
    if body.is_ground:
        return np.zeros(dim), np.eye(dim)
    v = np.array([values[s.name] for s in body.q], dtype=float)
    return v[:dim], (_rot2(v[2]) if dim == 2 else _rot3(v[3:]))


def _values(model, q) -> dict:
    # the layout order (bodies, then variables) without compiling the model
    return {s.name: float(x) for s, x in zip(model._coordinate_symbols(), q)}


def _vector(model, values: dict) -> np.ndarray:
    return np.array([values[s.name] for s in model._coordinate_symbols()], dtype=float)


def case_names() -> list[str]:
    """Every constraint type with a conformance case, sorted."""
    return sorted(CASES)


def random_mechanism(seed: int, extra: int | None = None, leave_dof: bool | None = None,
                     name: str | None = None):
    """``(model, q, t, drivers, info)``: a random consistent mechanism (see the module doc)."""
    rng = np.random.default_rng(seed)
    names = case_names()
    name = name or names[int(rng.integers(len(names)))]
    builders = CASES[name]
    builder = builders[int(rng.integers(len(builders)))]
    c = builder(rng)
    m, t = c.model, float(c.t)
    values = _values(m, c.q)
    dim = m.space.dim
    extra = int(rng.integers(0, 3)) if extra is None else extra
    for k in range(extra):
        bodies = m.bodies
        host = bodies[int(rng.integers(len(bodies)))]
        r1, A1 = _pose(m, values, host)
        p1 = rng.uniform(-1, 1, dim)
        P = r1 + A1 @ p1
        r2 = rng.uniform(-2, 2, dim)
        if dim == 2:
            th = float(rng.uniform(-np.pi, np.pi))
            A2, rot = _rot2(th), [th]
        else:
            e = rng.standard_normal(4)
            e /= np.linalg.norm(e)
            A2, rot = _rot3(e), list(e)
        p2 = A2.T @ (P - r2)
        b = m.add_body(f"fz{k}", points={"pin": tuple(float(x) for x in p2)})
        for s, v in zip(b.q, list(r2) + rot):
            values[s.name] = float(v)
        hp = host.point(tuple(float(x) for x in p1))
        joint = _pin(dim)
        m.add(joint(hp, b.point("pin")), name=f"fzpin{k}")
    # masses: every moving body, positive definite inertia
    for b in m.bodies[1:]:
        mass = float(rng.uniform(0.5, 2.0))
        cen = tuple(float(x) for x in rng.uniform(-0.5, 0.5, dim))
        if dim == 2:
            inertia = float(rng.uniform(0.05, 0.5))
        else:
            inertia = tuple(float(x) for x in rng.uniform(0.2, 0.3, 3))  # triangle inequality
        m.set_mass_properties(b, mass=mass, centroid=cen, inertia=inertia)
    if rng.random() < 0.5:
        from ..loads._loads import Gravity

        g = rng.standard_normal(dim)
        m.add_load(Gravity(tuple(float(x) for x in g), 9.81))
    q = _vector(m, values)
    s = m.compile()
    # evaluated once here (before the drivers are added): the quick unoptimised kernel
    J = s.jacobian_once(t, q, m._p())
    rank = _rank(J)[0]
    dof = s.n - rank
    leave = bool(rng.random() < 0.15) if leave_dof is None else leave_dof
    want = max(dof - 1, 0) if leave and dof > 0 else dof
    drivers = []
    order = rng.permutation(s.n)
    rows = [J[i] for i in range(J.shape[0])]
    syms = s.layout.q_symbols
    for j in order:
        if len(drivers) >= want:
            break
        e = np.zeros(s.n)
        e[j] = 1.0
        if _rank(np.vstack(rows + [e]))[0] > _rank(np.vstack(rows))[0] if rows else True:
            rows.append(e)
            w = float(rng.uniform(-0.5, 0.5))
            from ..constraints import Constraint

            drv = Constraint([syms[j] - (sp.Float(q[j]) + w * (T - t))])
            m.add(drv, name=f"fzdrive{len(drivers)}")
            drivers.append(drv.name)
    m.set_guess(dict(zip(syms, q)))
    info = {"seed": seed, "type": name, "dim": dim, "extra": extra, "n": s.n,
            "dof_before_drivers": dof, "drivers": len(drivers)}
    return m, q, t, drivers, info


def _pin(dim):
    from ..constraints import Revolute2, Spherical3

    return Revolute2 if dim == 2 else Spherical3


def _rank(J) -> tuple[int, bool]:
    """``(rank, ambiguous)`` of ``J`` after equilibration (rows, then columns, to unit max)."""
    J = np.asarray(J.toarray() if hasattr(J, "toarray") else J, dtype=float)
    if J.size == 0:
        return 0, False
    A = J.copy()
    r = np.abs(A).max(axis=1)
    r[r == 0] = 1.0
    A /= r[:, None]
    c = np.abs(A).max(axis=0)
    c[c == 0] = 1.0
    A /= c[None, :]
    sv = np.linalg.svd(A, compute_uv=False)
    if sv.size == 0 or sv[0] == 0:
        return 0, False
    rel = sv / sv[0]
    rank = int(np.sum(rel > math.sqrt(GRAY[0] * GRAY[1])))
    ambiguous = bool(np.any((rel > GRAY[0]) & (rel < GRAY[1])))
    return rank, ambiguous


def _guard(seed, what, f, *a, **k):
    """Call ``f``; a non-MechError exception is a fuzz failure (an internal error escaped)."""
    try:
        return f(*a, **k), None
    except MechError as exc:
        return None, exc
    except Exception as exc:  # noqa: BLE001 - exactly what the fuzzer looks for
        raise FuzzFailure(seed, f"{what} raised {type(exc).__name__}: {exc}") from exc


def check_mechanism(seed: int, extra: int | None = None, leave_dof: bool | None = None,
                    name: str | None = None, free_motion: bool = True) -> dict:
    """Build :func:`random_mechanism` (``seed``) and check the properties of the module doc.
    Raises :class:`FuzzFailure` on a violation; returns what was measured."""
    import warnings

    out, exc = _guard(seed, "building the model",
                      random_mechanism, seed, extra, leave_dof, name)
    if exc is not None:
        raise FuzzFailure(seed, f"a consistent random model could not be built: {exc!r}")
    m, q, t, drivers, info = out
    rng = np.random.default_rng(seed + 1)
    s = m.compile()
    p = m._p()
    res = {**info, "outcome": []}
    F = s.residual(t, q, p)
    if np.abs(F).max(initial=0.0) > 1e-8:
        raise FuzzFailure(seed, f"the built configuration does not satisfy the constraints "
                                f"({info['type']}): {np.abs(F).max():.2e}")
    c = Case(m, None, q, t, label=f"seed {seed} ({info['type']})")
    try:
        res["jacobian_fd"] = check_jacobian(c, rng)
        res["gamma_fd"] = check_gamma(c, rng)
    except AssertionError as err:
        raise FuzzFailure(seed, str(err)) from None
    # DOF against an independent rank (at the configuration, at t as the solver sees it)
    J = s.jacobian(t, q, p)
    rank, ambiguous = _rank(J)
    dof, exc = _guard(seed, "m.dof()", m.dof)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rep, exc2 = _guard(seed, "m.singularity()", m.singularity, q, t)
    if exc is None and not ambiguous and not getattr(dof, "singular_guess", ""):
        J0 = s.jacobian(0.0, q, p)
        r0, amb0 = _rank(J0)
        if not amb0 and int(dof) != s.n - r0:
            raise FuzzFailure(seed, f"m.dof() = {int(dof)} but n - rank(Phi_q(t=0)) = "
                                    f"{s.n} - {r0} ({info['type']})")
        res["outcome"].append("dof")
    if exc2 is None and not ambiguous and rep.rank != min(rank, s.m):
        if rep.rank != rank:
            raise FuzzFailure(seed, f"singularity() rank {rep.rank} != independent rank {rank}")
    # kinematic solve
    times = [t, t + 0.01, t + 0.03]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol, exc = _guard(seed, "m.solve", m.solve, times, "acceleration", q)
    s2 = m.compile()
    if exc is None:
        for k, tk in enumerate(sol.t):
            Fk = s2.residual(tk, sol.q[k], p)
            Jk, rhs = s2.velocity_rhs(tk, sol.q[k], p)
            from ..solvers._linalg import Scaling

            sc = Scaling.of(s2, sol.q[k], Jk)
            rows = sc.rows(Jk)
            pos = float(np.abs(Fk / rows).max(initial=0.0))
            if pos > 1e-8 * (1 + sc.offset):
                raise FuzzFailure(seed, f"solved point t = {tk} leaves a scaled residual {pos:.2e}")
            vel = np.abs(Jk @ sol.qd[k] - rhs) / (rows * (1 + np.abs(sol.qd[k] / sc.columns).max()))
            if vel.max(initial=0.0) > 1e-7:
                raise FuzzFailure(seed, f"velocities at t = {tk} violate Phi_q qd = -Phi_t by "
                                        f"{vel.max():.2e}")
        res["outcome"].append("solved")
    elif isinstance(exc, ConstraintCountError):
        if s2.n == s2.m:
            raise FuzzFailure(seed, f"square model ({s2.n} coordinates and equations) refused: {exc}")
        res["outcome"].append("count")
    elif isinstance(exc, SingularJacobianError) or "singular" in str(exc).lower():
        res["outcome"].append("singular")
    else:
        res["outcome"].append(type(exc).__name__)
    # free motion with the drivers dropped: Phi_q qdd = gamma
    if free_motion and drivers:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fs, exc = _guard(seed, "m.free", m.free, drivers)
            if exc is None:
                fsol, exc = _guard(seed, "free.solve", fs.solve, t)
        if exc is None:
            sf = fs.system
            qf, qdf, qddf = fsol.q[0], fsol.qd[0], fsol.qdd[0]
            Jf = sf.jacobian(t, qf, p)
            g = sf.gamma_values(t, qf, qdf, p)
            from ..solvers._linalg import Scaling

            sc = Scaling.of(sf, qf, Jf)
            rows = sc.rows(Jf)
            scale = 1.0 + np.abs(g / rows).max(initial=0.0) + np.abs(qddf / sc.columns).max(initial=0.0)
            err = float(np.abs((Jf @ qddf - g) / rows).max(initial=0.0))
            if err > 1e-7 * scale:
                raise FuzzFailure(seed, f"free acceleration violates Phi_q qdd = gamma by {err:.2e}")
            res["free_acceleration"] = err
            res["outcome"].append("free")
        else:
            res["outcome"].append("free-" + type(exc).__name__)
    return res


#: odd values for argument fuzzing: every public entry point must answer them with a MechError
WEIRD = [None, float("nan"), float("inf"), -1, 0, 10**9, 2.5, True, "", "x", "crank",
         (), [], [1, 2, 3], {}, {"crank.th": "a"}, np.zeros((2, 2)), np.array([np.nan]),
         object(), sp.Symbol("zz"), -1e-300, "T"]
