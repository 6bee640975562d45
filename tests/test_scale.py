"""The same mechanism in any unit of length, from 1e-6 to 1e6: same relative accuracy of
positions, velocities and accelerations, the same conditioning and DOF/redundancy report, and
no near-singular warning where the mechanism is healthy (issue 10, section 1)."""

import warnings

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from conftest import python_path
from mechsys import models
from mechsys.solvers import solve_position
from test_slider_crank import closed_form

SCALES = [1e-6, 1e-3, 1.0, 1e3, 1e6]


def _solve_quietly(m, t):
    with warnings.catch_warnings():
        warnings.simplefilter("error", ms.NearSingularWarning)
        return m.solve(t)


@pytest.mark.parametrize("s", SCALES)
def test_slider_crank_relative_accuracy_at_every_scale(s):
    r, L, w = 2.0 * s, 6.0 * s, 2 * np.pi
    m = models.slider_crank(crank=r, rod=L, speed=w)
    t = np.linspace(0, 1, 37)
    sol = _solve_quietly(m, t)
    p = m.body("piston").point(0)
    x, v, a = closed_form(r, L, 0.0, w, t)
    # errors relative to the size of the mechanism (1e-7 at s = 1e-6 before scaling)
    assert np.abs(sol.location(p)[:, 0] - x).max() / s < 1e-12
    assert np.abs(sol.velocity(p)[:, 0] - v).max() / (w * s) < 1e-11
    assert np.abs(sol.acceleration(p)[:, 0] - a).max() / (w**2 * s) < 1e-10
    np.testing.assert_allclose(sol.angle("crank"), w * t, rtol=0, atol=1e-12)
    # healthy everywhere: the scaled condition number does not depend on the unit
    assert np.all(sol.extra["rcond"] > 1e-2)


def test_slider_crank_diagnosis_is_unit_invariant():
    rconds, its = [], []
    for s in SCALES:
        m = models.slider_crank(crank=2.0 * s, rod=6.0 * s)
        sol = _solve_quietly(m, np.linspace(0, 1, 19))
        rconds.append(sol.extra["rcond"])
        its.append(sol.iterations)
        dof = m.dof()
        assert (int(dof), dof.rank, dof.gruebler, dof.redundant) == (0, 9, 0, [])
    for rc, it in zip(rconds[1:], its[1:]):
        np.testing.assert_allclose(rc, rconds[0], rtol=1e-6)
        np.testing.assert_array_equal(it, its[0])


def _four_bar_rocker():
    """Rocker angle of :func:`models.four_bar` (branch +1) as a function of T (crank angle T),
    with its first two derivatives, from the closed-form circle intersection."""
    T, a, b, c, d = sp.symbols("T a b c d", positive=True)
    ax, ay = a * sp.cos(T), a * sp.sin(T)
    dx, dy = ax - d, ay
    dist = sp.sqrt(dx**2 + dy**2)
    phi = sp.atan2(dy, dx) - sp.acos((c**2 + dist**2 - b**2) / (2 * c * dist))
    return [sp.lambdify((T, a, b, c, d), e) for e in (phi, phi.diff(T), phi.diff(T, 2))]


ROCKER = _four_bar_rocker()


@pytest.mark.parametrize("s", SCALES)
def test_four_bar_relative_accuracy_at_every_scale(s):
    a, b, c, d = 1.0 * s, 4.0 * s, 3.0 * s, 4.0 * s
    m = models.four_bar(ground=d, crank=a, coupler=b, rocker=c, speed=1.0, branch=1)
    t = np.linspace(0, 2 * np.pi, 61)
    sol = _solve_quietly(m, t)
    th, om, al = (f(t, a, b, c, d) for f in ROCKER)
    wrap = np.angle(np.exp(1j * (sol.angle("rocker") - th)))
    assert np.abs(wrap).max() < 1e-11
    assert np.abs(sol.omega("rocker") - om).max() < 1e-10
    assert np.abs(sol.alpha("rocker") - al).max() < 1e-9
    tip = sol.location(m.body("rocker").point("tip"))
    np.testing.assert_allclose(np.hypot(tip[:, 0] - d, tip[:, 1]) / s, 3.0, rtol=0, atol=1e-12)
    dof = m.dof()
    assert (int(dof), dof.rank, dof.redundant) == (0, 6, [])


@pytest.mark.parametrize("s", SCALES)
def test_redundant_slider_crank_is_reported_at_every_scale(s):
    """The piston's y fixed twice (slider and an extra RelativeY1): reported redundant in
    every unit, by dof() and by solve()."""
    m = models.slider_crank(crank=2.0 * s, rod=6.0 * s)
    m.add(ms.RelativeY1(m.body("piston").point(0), 0), name="extra")
    dof = m.dof()
    assert int(dof) == 0 and dof.gruebler == -1 and dof.rank == 9
    assert [c.name for c in dof.redundant] in (["slider"], ["extra"])
    # consistent: solved (issue 12), the report a warning
    with pytest.warns(ms.RedundantConstraintWarning,
                      match=r"\(rank 9 of 10 equations, 9 coordinates\)\. 1 dependent equation") as rec:
        m.solve(0.1)
    assert "'extra'" in str(rec[0].message) and "'slider'" in str(rec[0].message)
    # square but redundant: without the driver the model has m == n and rank n - 1
    m.remove("drive")
    dof = m.dof()
    assert int(dof) == 1 and dof.gruebler == 0
    assert [c.name for c in dof.redundant] in (["slider"], ["extra"])
    with pytest.raises(ms.SingularJacobianError, match=r"singular at t = 0\.1 \(rank 8 of 9"):
        m.solve(0.1)


@pytest.mark.parametrize("s", [1e-6, 1e6])
def test_position_solve_scaled_tolerance(s):
    """At 1e-6 the old absolute test accepted 1e-7 relative errors; at 1e6 the unscaled
    Jacobian looked singular. The scaled residual is reached to ftol at both."""
    m = models.slider_crank(crank=2.0 * s, rod=6.0 * s)
    system = m.compile()
    g = m.guess()
    g[system.layout.index("crank.th")] = 0.3         # a real Newton solve from the guess
    res = solve_position(system, 0.3 / (2 * np.pi), g, p=m._p())
    x, _, _ = closed_form(2.0 * s, 6.0 * s, 0.0, 2 * np.pi, 0.3 / (2 * np.pi))
    assert res.success and res.residual < 3e-12
    assert abs(res.q[system.layout.index("piston.x")] - x) / s < 1e-12


def test_sparse_path_agrees_with_dense(monkeypatch):
    """Above SPARSE_THRESHOLD coordinates the scaled Jacobian is factorised sparse, through
    the system's FixedPattern (the scaled values are swapped into the caller's matrix for
    the factorisation only)."""
    from mechsys.solvers import _kinematics, _linalg, _position, _tolerances

    m = models.four_bar_chain(25)                           # 153 coordinates: sparse
    t = np.linspace(0, 1, 11)
    sparse = m.solve(t)
    assert m.compile().n > _tolerances.SPARSE_THRESHOLD
    system = m.compile()
    J = system.jacobian(0.3, sparse.q[3], m._p(), sparse=True)
    before = J.toarray()
    sc = _linalg.Scaling.of(system, sparse.q[3], J)
    x = sc.factor(J).solve(np.ones(system.n))
    np.testing.assert_array_equal(J.toarray(), before)       # J is left as it was
    np.testing.assert_allclose(before @ x, 1.0, atol=1e-9)
    for mod in (_kinematics, _position):
        monkeypatch.setattr(mod, "SPARSE_THRESHOLD", 10**6)
    dense = m.solve(t)
    np.testing.assert_allclose(sparse.q, dense.q, atol=1e-10)
    np.testing.assert_allclose(sparse.qdd, dense.qdd, atol=1e-7)


@pytest.mark.parametrize("jit", ["0", "1"])
def test_inverse_dynamics_is_the_same_in_any_unit(monkeypatch, jit):
    """The loaded slider-crank built at length scale s (masses kept, gravity and inertias
    scaled with it): its multipliers are forces (times s) and moments (times s^2) of the same
    numbers at every scale, in the Python and the compiled multiplier solves. Before: the
    multiplier solve factorised the unscaled Jacobian, and at s = 1e6 refused it as singular."""
    monkeypatch.setenv("MECHSYS_JIT", jit)
    t = np.linspace(0.0, 1.0, 25)

    def lam(s):
        m = models.slider_crank_dynamic(crank=2 * s, rod=6 * s, g=9.81 * s,
                                        inertias=(0.4 * s**2, 5.0 * s**2, 0.0))
        return m.solve(t, solution="dynamic").lam

    ref = lam(1.0)
    big = np.abs(ref).max(axis=0)
    for s in SCALES:
        got = lam(s)
        ratio = got / np.where(ref == 0, 1.0, ref)
        for col in range(ref.shape[1]):
            keep = np.abs(ref[:, col]) > 1e-6 * max(big[col], 1e-300)
            if not keep.any():
                continue
            power = 1 if np.isclose(ratio[keep, col][0], s, rtol=1e-6) else 2
            np.testing.assert_allclose(ratio[keep, col], s**power, rtol=1e-9)


def _sliding_block(mass, mu=0.3, alpha=0.5, hold=True):
    """A block on an incline with Coulomb friction driven by the normal reaction; pushed along
    the incline at 1 m/s (``hold=False``) or released (the free motion)."""
    m = ms.Model2D()
    blk = m.add_body("block", mass=mass, inertia=0.1 * mass, guess=((0.0, 0.0), alpha))
    ca, sa = np.cos(alpha), np.sin(alpha)
    slide = m.add(ms.Translate2(blk.axis((0, 0), (1, 0)), m.ground.axis((0, 0), (ca, sa))),
                  name="slide")
    m.add(ms.RelativeX1(blk.point(0), ca * ms.T if hold else 0.0), name="push")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.add_load(ms.JointFriction(slide, mu=mu, v_eps=1e-4))
    return m


@pytest.mark.parametrize("jit", ["0", "1"])
def test_friction_is_the_same_at_any_scale_of_force(monkeypatch, jit):
    """Friction's Newton (statics, inverse dynamics, free motion) judged its convergence and
    regularised the reaction's magnitude in absolute units: a block of a few picograms got a
    push force 21 times too large (inverse dynamics), and a free acceleration wrong by
    125 %, silently; at 2e-15 kg the unscaled Newton matrix was declared singular. Now the
    forces scale with the mass (2e-15 kg to 2 kg, Python and compiled loops)."""
    monkeypatch.setenv("MECHSYS_JIT", jit)
    alpha, mu, g = 0.5, 0.3, 9.81
    ca, sa = np.cos(alpha), np.sin(alpha)
    t = np.linspace(0.1, 1.0, 4)
    push = {}
    for mass in (2.0, 2e-6, 2e-9, 2e-12, 2e-15):
        m = _sliding_block(mass, mu, alpha)
        for solution in ("kinematic", "dynamic"):      # (statics: no velocity, no friction)
            F, _ = m.solve(t, solution=solution).reaction("push", "block")
            push[mass, solution] = F[:, 0] / mass
        free = _sliding_block(mass, mu, alpha, hold=False)
        free.solve(0.0)
        sol = free.free(drop=["push"]).simulate(np.linspace(0, 0.5, 3), rtol=1e-10, atol=1e-12)
        assert (sol.extra["compiled_steps"] > 0) == (jit == "1")
        # slides down: a = g (sin a - mu cos a) once moving (v >> v_eps)
        acc = np.hypot(sol.qdd[-1, 0], sol.qdd[-1, 1])
        assert abs(acc / (g * (sa - mu * ca)) - 1) < 1e-6, (mass, acc)
    # pushed up at constant speed: F cos a = m g sin a + mu N, N = m g cos a + F sin a
    Fx = g * (sa + mu * ca) / (ca - mu * sa)
    for (mass, solution), f in push.items():
        np.testing.assert_allclose(f, Fx, rtol=1e-7, err_msg=f"{mass} {solution}")
        np.testing.assert_allclose(f, push[2.0, solution], rtol=1e-12, err_msg=f"{mass}")


def _chain_at_scale(loops, s):
    """``models.four_bar_chain(loops)`` with every length times ``s``."""
    from mechsys import Model2D, Revolute2, RotationLock1, T

    m = Model2D()
    th0 = np.pi / 2 + 0.2
    cranks = []
    for k in range(loops + 1):
        cranks.append(m.add_body(f"link{k}", points={"tip": (s, 0)}, guess=((k * s, 0), th0)))
        m.add(Revolute2(m.ground.point((k * s, 0)), cranks[-1].point(0)), name=f"pivot{k}")
    for k in range(loops):
        tip = (k * s + s * np.cos(th0), s * np.sin(th0))
        cp = m.add_body(f"coupler{k}", points={"end": (s, 0)}, guess=(tip, 0.0))
        m.add(Revolute2(cranks[k].point("tip"), cp.point(0)), name=f"left{k}")
        m.add(Revolute2(cp.point("end"), cranks[k + 1].point("tip")), name=f"right{k}")
    m.add(RotationLock1(cranks[0], th0 + 0.3 * sp.sin(T)), name="drive")
    return m


@pytest.mark.parametrize("jit", ["0", "1"])
def test_large_banded_sweep_is_the_same_in_any_unit(monkeypatch, jit):
    """The banded factorisation of a large sweep (decision 0030) works on the unit-free
    Jacobian: a chain of 183 coordinates built in millimetres, metres or kilometres gives the
    same angles, iterations and condition estimates, in the Python and the compiled loop."""
    monkeypatch.setenv("MECHSYS_JIT", jit)
    t = np.linspace(0, 2 * np.pi, 31)
    out = []
    for s in (1e-3, 1.0, 1e3):
        r = _chain_at_scale(30, s).solve(t)
        assert r.system.n == 183
        out.append((np.array([r.coordinate(f"link{k}.th") for k in range(31)]),
                    r.extra["rcond"], r.iterations))
    for ang, rc, its in out[1:]:
        np.testing.assert_allclose(ang, out[0][0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(rc, out[0][1], rtol=1e-12)
        np.testing.assert_array_equal(its, out[0][2])


def _friction_chain_at_scale(links, s):
    """``links`` rods of length ``s`` pinned end to end, hanging from the origin, with Coulomb
    friction of radius ``0.01 s`` in every pin (its turning regularised below 1e-3 rad/s)
    under gravity ``9.81 s``: the same angles at any ``s``."""
    m = ms.Model2D()
    prev = m.ground.point((0, 0))
    for k in range(links):
        b = m.add_body(f"l{k}", points={"a": (0, 0), "b": (s, 0)}, mass=1.0, centroid=(s / 2, 0),
                       inertia=s * s / 12, guess=((k * s, 0), 0.0))
        m.add(ms.Revolute2(prev, b.point("a")), name=f"j{k}")
        m.add(ms.RotationLock1(b, 0.0), name=f"lock{k}")
        m.add_load(ms.JointFriction(f"j{k}", mu=0.1, radius=0.01 * s, v_eps=1e-3))
        prev = b.point("b")
    m.add_load(ms.Gravity((0, -1), 9.81 * s))
    m.solve(0.0)
    return m.free(drop=[f"lock{k}" for k in range(links)])


def _stepper(monkeypatch, jit) -> None:
    """``"python"``: the Python stepper whole (``conftest.python_path``: what kernels without
    C entry points take); ``"1"``: the loop, compiled (``MECHSYS_JIT=0`` runs the same loop
    interpreted, the same numbers: decision 0082)."""
    monkeypatch.setenv("MECHSYS_JIT", "1")
    if jit == "python":
        python_path(monkeypatch)


@pytest.mark.parametrize("jit", ["python", "1"])
def test_large_friction_free_motion_is_the_same_in_any_unit(monkeypatch, jit):
    """The banded Newton of free motion with friction (160 unknowns, decision 0028) works on
    the unit-free Newton matrix and projections: the chain in millimetres, metres or
    kilometres swings through the same angles, in the Python and the compiled loop."""
    _stepper(monkeypatch, jit)
    t = np.linspace(0.0, 0.2, 5)
    out = []
    for s in (1e-3, 1.0, 1e3):
        free = _friction_chain_at_scale(32, s)
        assert free.system.n + free.system.m == 160
        sol = free.simulate(t, rtol=1e-10, atol=1e-12)
        assert (sol.extra["compiled_steps"] == sol.extra["steps"]) == (jit == "1")
        out.append(np.array([sol[f"l{k}.th"] for k in range(32)]))
    assert np.abs(out[1]).max() > 0.1                 # it swings
    for ang in out[::2]:
        np.testing.assert_allclose(ang, out[1], rtol=0, atol=1e-12)


@pytest.mark.parametrize("jit", ["python", "1"])
def test_wide_tree_free_motion_is_the_same_in_any_unit(monkeypatch, jit):
    """A coasting radial engine (245 unknowns, a star: the sparse LU of the augmented
    matrix's pattern, decision 0031) in millimetres, metres or kilometres (lengths, gravity
    and inertias scaled) turns through the same angles, in the Python and the compiled loop
    (its sparse kind)."""
    _stepper(monkeypatch, jit)
    t = np.linspace(0.0, 0.3, 4)
    out = []
    for s in (1e-3, 1.0, 1e3):
        m = models.radial_engine(20, crank=1.0 * s, rod=4.0 * s, g=9.81 * s)
        m.solve(0.0)
        free = m.free(drop=["drive"])
        sol = free.simulate(t, initial_condition={"crank.th_d": 3.0}, rtol=1e-10, atol=1e-12)
        assert (sol.extra["compiled_solver"] == "sparse") == (jit == "1")
        out.append(np.array([sol["crank.th"]] + [sol[f"rod{k}.th"] for k in range(20)]))
    assert np.abs(out[1][0] - out[1][0][0]).max() > 0.3    # it turns
    for ang in out[::2]:
        np.testing.assert_allclose(ang, out[1], rtol=0, atol=1e-10)


@pytest.mark.parametrize("jit", ["python", "1"])
def test_large_path_is_the_same_in_any_unit(monkeypatch, jit):
    """A tractor towing 60 trailers (183 coordinates: the sparse velocity system and
    projection, decision 0027) in millimetres, metres or kilometres (reach and speed scaled)
    steers every trailer through the same angles, and its blade along the same circle in
    units of the reach, in the Python and the compiled stepper."""
    _stepper(monkeypatch, jit)
    t = np.linspace(0.0, 3.0, 4)
    out = []
    for s in (1e-3, 1.0, 1e3):
        path = models.trailer_train(60, speed=2.0 * s, rate=0.4, reach=s)
        sol = path.simulate(t, rtol=1e-10, atol=1e-12)
        assert (sol.extra["compiled_solver"] == "path") == (jit == "1")
        blade = sol.location(path.model.body("tractor").point("blade")) / s
        out.append(np.vstack([blade.T] + [sol[f"trailer{k}.th"] for k in range(60)]))
    assert np.abs(out[1][2:]).max() > 0.1                 # the trailers swing
    for got in out[::2]:
        np.testing.assert_allclose(got, out[1], rtol=0, atol=1e-10)
