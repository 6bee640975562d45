"""Recursive dynamics of Gen joints (decision 0016): the composite-body mass matrix and forces
and the articulated-body accelerations against the symbolic projection (decision 0010), the
minimal ODE and Newton-Euler recursion of the other generalized-coordinate tests, and the
Numba path against the plain-Python one."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import mechsys as ms
from mechsys.compile._generalized import RecursiveDynamics
from test_generalized import T_OUT, Y0, _four_bar, gen_pendulum, minimal_rhs
from test_generalized_3d import gen_arm, newton_euler

RNG = np.random.default_rng(7)


def _dynamics(monkeypatch, build, mode, jit="1"):
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", mode)
    monkeypatch.setenv("MECHSYS_JIT", jit)
    m = build()
    s = m.free().system
    d = s.dynamics
    assert isinstance(d, RecursiveDynamics) == (mode == "recursive")
    return m, s, d


def _state(s):
    return RNG.normal(size=s.n), RNG.normal(size=s.n)


def _compare_terms(monkeypatch, build, tol=1e-10, states=2):
    """M, Q, Qv and the free accelerations of both paths at random states."""
    _, s1, d1 = _dynamics(monkeypatch, build, "symbolic")
    _, s2, d2 = _dynamics(monkeypatch, build, "recursive")
    for _ in range(states):
        q, qd = _state(s1)
        q = s1.guess + 0.1 * q if s1.m else q     # near the assembled guess when constrained
        lam = np.zeros(s1.m)
        for a, b in zip(d1.terms(0.2, q, qd, lam, s1.p_values), d2.terms(0.2, q, qd, lam, s2.p_values)):
            np.testing.assert_allclose(b, a, atol=tol * (1 + np.abs(a).max()), rtol=0)
        K1, r1 = d1.free_kernel()(0.2, q, qd, lam, s1.p_values)
        K2, r2 = d2.free_kernel()(0.2, q, qd, lam, s2.p_values)
        x1 = np.linalg.solve(K1, r1)
        np.testing.assert_allclose(np.linalg.solve(K2, r2), x1, atol=tol * (1 + np.abs(x1).max()))
        if d2.tree_only:
            qdd = d2.accelerations(0.2, q, qd, s2.p_values)
            np.testing.assert_allclose(qdd, x1[:s1.n], atol=tol * (1 + np.abs(x1).max()))
    return d2


def test_double_pendulum_terms_and_articulated_accelerations(monkeypatch):
    d = _compare_terms(monkeypatch, gen_pendulum)
    assert d.tree_only and d.nslaves == 2


def test_double_pendulum_trajectory_vs_minimal_ode(monkeypatch):
    m, s, d = _dynamics(monkeypatch, gen_pendulum, "recursive")
    sol = m.free().simulate(T_OUT, initial_condition={"t1": Y0[0], "t2": Y0[1], "t1_d": Y0[2],
                                                      "t2_d": Y0[3]}, rtol=1e-12, atol=1e-12)
    ref = solve_ivp(minimal_rhs, (0, T_OUT[-1]), Y0, t_eval=T_OUT, rtol=1e-12, atol=1e-12,
                    method="DOP853")
    np.testing.assert_allclose(np.ravel(sol["t1"]), ref.y[0], atol=1e-8)
    np.testing.assert_allclose(np.ravel(sol["t2"]), ref.y[1], atol=1e-8)


def test_arm_3d_terms_and_newton_euler(monkeypatch):
    """The 3-link GenRevolute5 arm (Euler-parameter poses): both paths agree, and the
    torques M qdd - Q - Qv of the recursion are those of the Newton-Euler recursion."""
    d = _compare_terms(monkeypatch, gen_arm, states=1)
    assert d.tree_only
    s = d.system
    q, qd, qdd = RNG.normal(size=3), RNG.normal(size=3), RNG.normal(size=3)
    M, Q, Qv = d.terms(0.0, q, qd, np.zeros(0), s.p_values)
    np.testing.assert_allclose(M @ qdd - Q - Qv, newton_euler(q, qd, qdd), atol=1e-9)


def test_four_bar_closed_on_gen_chain(monkeypatch):
    """Mixed coordinates: a Gen crank and coupler (and an absolute or Gen rocker) closed by a
    Revolute2; the closing constraint acts through its Jacobian, the recursion gives M."""
    for gen_rocker in (True, False):
        def build(g=gen_rocker):
            m = _four_bar(g)[0]
            for b, (mass, j) in zip(("crank", "coupler", "rocker"), ((1.0, 0.1), (2.0, 0.3), (1.5, 0.2))):
                m.set_mass_properties(b, mass=mass, inertia=j, centroid=(0.5, 0.1))
            m.add_load(ms.Gravity((0, -1), 9.81))
            return m
        d = _compare_terms(monkeypatch, build, states=1)
        assert not d.tree_only
        # the same motion as the symbolic path
        sols = []
        for mode in ("symbolic", "recursive"):
            monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", mode)
            m = build()
            m.solve(0.0)
            sols.append(m.free(drop=["drive"]).simulate([0.0, 0.5], rtol=1e-10, atol=1e-12))
        np.testing.assert_allclose(np.ravel(sols[1]["th"]), np.ravel(sols[0]["th"]), atol=1e-8)


def _mixed():
    """A cart with its own coordinates on a slide, a pendulum of two Gen links on it (one a
    GenTranslate2 telescope), a spring to a slave point, a damper, a moment on a slave and a
    torque on a joint angle: every kind of contribution the recursion adds."""
    m = ms.Model2D()
    cart = m.add_body("cart", points={"o": (0, 0)}, mass=3.0, inertia=0.4, centroid=(0.1, 0.0))
    a = m.add_body("a", points={"o": (0, 0), "e": (1, 0)}, mass=1.0, inertia=0.1, centroid=(0.5, 0.1))
    b = m.add_body("b", points={"o": (0, 0), "e": (0.7, 0)}, mass=0.5, inertia=0.05,
                   centroid=(0.3, -0.05))
    m.add(ms.Translate2(cart.axis("o"), m.ground.axis((0, 0))), name="slide")
    m.add(ms.GenRevolute2(a.axis("o"), cart.axis("o"), ("phi", 0.4)), name="hinge")
    m.add(ms.GenTranslate2(b.axis("o"), a.axis("e"), ("s", 0.1)), name="tele")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.add_load(ms.Spring(b.point("e"), m.ground.point((2, 1)), stiffness=7.0, free_length=0.5))
    m.add_load(ms.Damper(a.point("e"), m.ground.point((0, 2)), damping=0.8))
    m.add_load(ms.Moment("b", 0.6, reaction="a"))
    m.add_load(ms.Load(sp.Symbol("phi"), -0.3 * sp.Symbol("phi")))
    return m


def test_absolute_master_and_loads(monkeypatch):
    d = _compare_terms(monkeypatch, _mixed)
    assert not d.tree_only        # the cart's coordinates and its slide: the composite path


def slide_chain(links=6):
    """A planar chain of GenRevolute2 joints with a GenTranslate2 slide in it (three distinct
    joint kernels), links with offset centroids."""
    m = ms.Model2D()
    master = m.ground.axis((0, 0))
    for k in range(links):
        b = m.add_body(f"l{k}", points={"tip": (1, 0)}, mass=1.5, inertia=0.1, centroid=(0.5, 0.02))
        joint = ms.GenTranslate2 if k == 3 else ms.GenRevolute2
        m.add(joint(b.axis(0), master, (f"q{k}", 0.1)), name=f"j{k}")
        master = b.axis("tip")
    m.add_load(ms.Gravity((0, -1), 9.81))
    return m


def test_chain_numba_and_python_paths_agree(monkeypatch):
    chain = slide_chain

    _, s, d1 = _dynamics(monkeypatch, chain, "recursive", jit="1")
    assert d1._engine()
    _, _, d2 = _dynamics(monkeypatch, chain, "recursive", jit="0")
    assert not d2._engine()
    # identical joints share a kernel: on ground, revolute on a link, the slide
    assert (d1.nslaves, d1.nkernels) == (6, 3)
    q, qd = _state(s)
    for a, b in zip(d1.terms(0.0, q, qd, [], s.p_values), d2.terms(0.0, q, qd, [], s.p_values)):
        np.testing.assert_allclose(a, b, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(d1.accelerations(0.0, q, qd, s.p_values),
                               d2.accelerations(0.0, q, qd, s.p_values), rtol=1e-13, atol=1e-13)
    _compare_terms(monkeypatch, chain, states=1)


def test_massless_tip_falls_back_to_the_diagnosis(monkeypatch):
    """A slave without mass or inertia at the end of the chain: no articulated inertia on its
    joint, and the free acceleration raises the symbolic path's SingularMassError."""
    def build():
        m = gen_pendulum()
        m.set_mass_properties("b", mass=0, inertia=0)
        return m

    for mode in ("symbolic", "recursive"):
        m, s, d = _dynamics(monkeypatch, build, mode)
        if mode == "recursive":
            assert d.accelerations(0.0, np.zeros(2), np.zeros(2), s.p_values) is None
        with pytest.raises(ms.SingularMassError, match="'t2'"):
            m.free().solve(0.0)


def test_mode_option(monkeypatch):
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "fast")
    with pytest.raises(ms.ModelError, match="MECHSYS_GEN_DYNAMICS"):
        _ = gen_pendulum().free().system.dynamics
    # a Gen joint whose pose uses another joint's coordinate: forced -> refused, auto -> symbolic
    def build():
        m = ms.Model2D()
        a = m.add_body("a", points={"o": (0, 0)}, mass=1, inertia=0.1)
        b = m.add_body("b", points={"o": (0, 0)}, mass=1, inertia=0.1)
        m.add(ms.GenConstraint(a.point("o"), m.ground.point((0, 0)), "u", ("u", 0.1)), name="ja")
        m.add(ms.GenConstraint(b.point("o"), m.ground.point(("u", 1)), "v", ("v", 0.2)), name="jb")
        return m
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "recursive")
    with pytest.raises(ms.ModelError, match="jb"):
        _ = build().free().system.dynamics
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "auto")
    assert not isinstance(build().free().system.dynamics, RecursiveDynamics)


def test_cse_kernel_with_an_absent_argument_named_like_a_temporary():
    """SymEngine's CSE names its temporaries x0, x1, ...: an argument ``x4`` that does not
    occur in the expressions (an absolute body's coordinate, absent from a mass-matrix
    block) must not be confused with one (a wrong mass matrix of a four-bar on a Gen chain
    before the fix in ``compile/_backends.py``)."""
    from mechsys.compile._backends import compile_exprs

    x4, th, phi = sp.symbols("x4 th phi")
    s, c, s2, c2 = sp.sin(th), sp.cos(th), sp.sin(th + phi), sp.cos(th + phi)
    exprs = [(s2 + 0.2 * c2) * s + (c2 - 0.2 * s2) * c + 0.5 * s2**2 + 0.5 * c2**2,
             (2 * s + s2) * s + (2 * c + c2) * c + 0.26 * s**2, c2 * s2 + s * c + 0.3]
    x = np.array([7.0, 0.6, 0.6])
    want = [float(e.subs({th: 0.6, phi: 0.6})) for e in exprs]
    for backend in ("symengine", "sympy"):
        np.testing.assert_allclose(compile_exprs([x4, th, phi], exprs, backend, cse=True)(x), want,
                                   rtol=1e-14)


def test_free_system_pickles(monkeypatch):
    """A sweep's payload may carry a free system: the recursion's per-thread work arrays and
    C entry points are rebuilt after unpickling."""
    import pickle

    m, s, d = _dynamics(monkeypatch, gen_pendulum, "recursive")
    free = m.free()
    a = free.solve(0.0, initial_condition={"t1_d": 0.5}).qdd
    b = pickle.loads(pickle.dumps(free)).solve(0.0, initial_condition={"t1_d": 0.5}).qdd
    np.testing.assert_allclose(b, a, rtol=1e-15)


def test_other_3d_gen_joints(monkeypatch):
    """A spatial chain of a universal joint (two angles), a cylindrical joint (slide and
    angle) and a prismatic joint: the joints with two coordinates and the slides, on Euler-
    parameter poses; both paths agree on M, Q, Qv and the accelerations."""
    def build():
        m = ms.Model3D()
        bs = [m.add_body(f"b{k}", points={"o": (0, 0, 0), "e": (0.8, 0, 0)}, mass=1.0 + k,
                         centroid=(0.4, 0.05, 0.02), inertia=(0.02, 0.05, 0.06, 0.001, 0.0, 0.002))
              for k in range(3)]
        m.add(ms.GenOrthoRevolute4(bs[0].axis("o", (1, 0, 0)), m.ground.axis((0, 0, 0), (0, 0, 1)),
                                   ("a0", 0.2), ("b0", 0.3)), name="u")
        m.add(ms.GenCylindrical4(bs[1].axis("o", (1, 0, 0)), bs[0].axis("e", (1, 0, 0)),
                                 ("s1", 0.1), ("c1", 0.4)), name="cyl")
        m.add(ms.GenTranslate5(bs[2].axis("o", (0, 1, 0)), bs[1].axis("e", (0, 1, 0)), ("s2", 0.2)),
              name="pri")
        m.add_load(ms.Gravity((0, 0, -1), 9.81))
        # (a spring to a slave point makes the symbolic path's compile minutes long)
        m.add_load(ms.Force(bs[2].point("e"), (1, 2, -1), 3.0))
        m.add_load(ms.Moment("b1", (0.2, -0.1, 0.3), 0.5, reaction="b0"))
        return m

    d = _compare_terms(monkeypatch, build, states=1)
    assert d.tree_only and d.nslaves == 3 and d.system.n == 5
    monkeypatch.setenv("MECHSYS_GEN_DYNAMICS", "auto")
    assert not isinstance(build().free().system.dynamics, RecursiveDynamics)   # 3 < 4 slaves
