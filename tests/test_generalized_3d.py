"""Spatial generalized-coordinate joints: a three-GenRevolute5 arm against a Newton-Euler
recursion written here and against the absolute-coordinate model; the other 3D Gen joints
against the standard joints they replace."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms

G = 9.81
L = [1.0, 0.8, 0.6]
AXES = [(0, 0, 1), (0, 1, 0), (0, 1, 0)]
MASS = [1.0, 2.0, 3.0]
CENT = [(L[k] / 2, 0.05, 0.0) for k in range(3)]
INER = [(0.02, 0.05 + 0.01 * k, 0.06, 0.001, 0.0, 0.0) for k in range(3)]


def _rot(u, a):
    u = np.asarray(u, float) / np.linalg.norm(u)
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


def _quat(R):
    return np.asarray(ms.euler_parameters(R), float)


def _body(m, k, guess=None):
    return m.add_body(f"l{k}", points={"o": (0, 0, 0), "e": (L[k], 0, 0)}, mass=MASS[k],
                      centroid=CENT[k], inertia=INER[k], guess=guess)


def gen_arm(drivers=None):
    m = ms.Model3D()
    prev = m.ground.axis((0, 0, 0), AXES[0])
    for k in range(3):
        b = _body(m, k)
        m.add(ms.GenRevolute5(b.axis("o", AXES[k]), prev, (f"q{k}", 0.1)), name=f"j{k}")
        if k < 2:
            prev = b.axis("e", AXES[k + 1])
    m.add_load(ms.Gravity((0, 0, -1), G))
    if drivers:
        for k, f in enumerate(drivers):
            m.add(ms.Constraint(sp.Symbol(f"q{k}") - f), name=f"d{k}")
    return m


def frames(q):
    """Rotation matrices and origins of the links at joint angles q."""
    A, o = [], []
    Ak, ok = np.eye(3), np.zeros(3)
    for k in range(3):
        if k:
            ok = ok + A[-1] @ np.array([L[k - 1], 0, 0])
        Ak = (A[-1] if k else np.eye(3)) @ _rot(AXES[k], q[k])
        A.append(Ak)
        o.append(ok)
    return A, o


def newton_euler(q, qd, qdd):
    """Joint torques of the arm: forward recursion of angular and linear accelerations,
    backward recursion of forces and moments, tau_k = z_k . n_k."""
    A, o = frames(q)
    w, al, a_o = [], [], []
    wk, alk, aok = np.zeros(3), np.zeros(3), np.zeros(3)
    for k in range(3):
        Am = A[k - 1] if k else np.eye(3)
        z = Am @ np.array(AXES[k], float)
        if k:
            d = A[k - 1] @ np.array([L[k - 1], 0, 0])
            aok = aok + np.cross(alk, d) + np.cross(wk, np.cross(wk, d))
        alk = alk + qdd[k] * z + np.cross(wk, qd[k] * z)
        wk = wk + qd[k] * z
        w.append(wk)
        al.append(alk)
        a_o.append(aok)
    f_next, n_next = np.zeros(3), np.zeros(3)
    tau = np.zeros(3)
    g = np.array([0, 0, -G])
    for k in (2, 1, 0):
        rho = A[k] @ np.array(CENT[k])
        ac = a_o[k] + np.cross(al[k], rho) + np.cross(w[k], np.cross(w[k], rho))
        xx, yy, zz, xy, yz, zx = INER[k]
        Ic = A[k] @ np.array([[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]]) @ A[k].T
        F = MASS[k] * (ac - g)
        d = (o[k + 1] - o[k]) if k < 2 else np.zeros(3)
        n = Ic @ al[k] + np.cross(w[k], Ic @ w[k]) + np.cross(rho, F) + n_next + np.cross(d, f_next)
        f = F + f_next
        z = (A[k - 1] if k else np.eye(3)) @ np.array(AXES[k], float)
        tau[k] = z @ n
        f_next, n_next = f, n
    return tau


def test_arm_inverse_dynamics_vs_newton_euler():
    drivers = [0.3 + 0.8 * ms.T, -0.4 + 0.5 * ms.T**2, 0.7 - 0.6 * ms.T]
    m = gen_arm(drivers)
    assert m.compile().layout.q_names == ("q0", "q1", "q2")
    sol = m.solve([0.0, 0.5], solution="dynamic")
    for k in range(2):
        q = [float(np.ravel(sol[f"q{j}"])[k]) for j in range(3)]
        qd = [float(np.ravel(sol.coordinate(f"q{j}", 1))[k]) for j in range(3)]
        qdd = [float(np.ravel(sol.coordinate(f"q{j}", 2))[k]) for j in range(3)]
        tau = newton_euler(q, qd, qdd)
        got = [float(np.ravel(sol.reaction(f"d{j}", sp.Symbol(f"q{j}")))[k]) for j in range(3)]
        np.testing.assert_allclose(got, tau, atol=1e-9)
        assert np.abs(tau).max() > 1.0
    # the slaves' poses follow the joint frames
    A, o = frames([float(np.ravel(sol[f"q{j}"])[1]) for j in range(3)])
    np.testing.assert_allclose(np.ravel(sol.location(m.body("l2").point("e"))[1]),
                               o[2] + A[2] @ np.array([L[2], 0, 0]), atol=1e-12)


def abs_arm(q):
    A, o = frames(q)
    m = ms.Model3D()
    bodies = [_body(m, k, guess=(tuple(o[k]), tuple(_quat(A[k])))) for k in range(3)]
    prev = m.ground.axis((0, 0, 0), AXES[0])
    for k, b in enumerate(bodies):
        m.add(ms.Revolute5(b.axis("o", AXES[k]), prev), name=f"j{k}")
        if k < 2:
            prev = b.axis("e", AXES[k + 1])
    m.add_load(ms.Gravity((0, 0, -1), G))
    return m


def abs_arm_omegas(q0, qd0) -> dict:
    """Initial condition of :func:`abs_arm` with the joint rates ``qd0``: each link's angular
    velocity, the sum of the joint rates about the joint axes in global axes."""
    A, _ = frames(q0)
    w, om = np.zeros(3), {}
    for k in range(3):
        w = w + qd0[k] * ((A[k - 1] if k else np.eye(3)) @ np.array(AXES[k], float))
        om[("omega", f"l{k}")] = tuple(w)
    return om


def test_arm_forward_dynamics_vs_absolute_model():
    q0, qd0 = [0.3, -0.4, 0.7], [0.8, 0.0, -0.6]
    t = np.linspace(0, 0.6, 4)
    g = gen_arm()
    ic = {f"q{k}": q0[k] for k in range(3)} | {f"q{k}_d": qd0[k] for k in range(3)}
    sg = g.free().simulate(t, initial_condition=ic, rtol=1e-11, atol=1e-11)
    a = abs_arm(q0)
    sa = a.free().simulate(t, initial_condition=abs_arm_omegas(q0, qd0), rtol=1e-11, atol=1e-11)
    for k in range(3):
        pg = sg.location(g.body(f"l{k}").point("e"))
        pa = sa.location(a.body(f"l{k}").point("e"))
        np.testing.assert_allclose(pg, pa, atol=1e-7)
        np.testing.assert_allclose(np.asarray(sg.omega(f"l{k}")), np.asarray(sa.omega(f"l{k}")),
                                   atol=1e-6)
    # a joint reaction in 3D: Newton-Euler on the carried links vs the absolute multipliers
    Fg, Mg = sg.joint_reaction("j1")
    Fa, Ma = sa.reaction("j1", "l1")
    np.testing.assert_allclose(Fg, Fa, atol=1e-6)
    np.testing.assert_allclose(Mg, Ma, atol=1e-6)


@pytest.mark.parametrize("kind", ["GenTranslate5", "GenCylindrical4", "GenOrthoRevolute4"])
def test_other_3d_gen_joints_satisfy_the_standard_joint(kind):
    """The slave's pose from each Gen joint satisfies the standard joint's equations
    (Translate5, Cylindrical4, OrthoRevolute4) and the coordinates mean what the reference
    says (distance along axis2, angle between references, angles to the references)."""
    m = ms.Model3D()
    base = m.add_body("base", points={"p": (0.2, 0.1, 0.3)})
    sl = m.add_body("slave", points={"p": (0.1, -0.2, 0.4)})
    m.add(ms.GenRevolute5(base.axis(0, (1, 0, 0)), m.ground.axis((0, 0, 0), (1, 0, 0)), ("r", 0.4)))
    ax1 = sl.axis("p", (0, 1, 1), reference=(1, 0, 0))
    ax2 = base.axis("p", (0, 0, 1), reference=(1, 1, 0))
    vals = {"GenTranslate5": [0.7], "GenCylindrical4": [0.7, 0.9], "GenOrthoRevolute4": [0.5, 1.1]}[kind]
    names = ["a", "b"][: len(vals)]
    m.add(getattr(ms, kind)(ax1, ax2, *[(n, v) for n, v in zip(names, vals)]), name="gen")
    for n, v in zip(names, vals):
        m.add(ms.Constraint(sp.Symbol(n) - v))
    m.add(ms.Constraint(sp.Symbol("r") - 0.4))
    sol = m.solve(0.0, solution="location")
    std = {"GenTranslate5": ms.Translate5, "GenCylindrical4": ms.Cylindrical4,
           "GenOrthoRevolute4": ms.OrthoRevolute4}[kind](ax1, ax2)
    res = np.ravel(sol.eval(sp.Matrix(std.equations(m.space))))
    assert np.abs(res).max() < 1e-12
    u1, u2 = np.ravel(sol.eval(ax1.direction())), np.ravel(sol.eval(ax2.direction()))
    g1 = np.ravel(sol.eval(ax1.reference_vector().direction()))
    g2 = np.ravel(sol.eval(ax2.reference_vector().direction()))
    u1, u2 = u1 / np.linalg.norm(u1), u2 / np.linalg.norm(u2)
    d = np.ravel(sol.location(ax1.origin)) - np.ravel(sol.location(ax2.origin))
    if kind in ("GenTranslate5", "GenCylindrical4"):
        assert abs(d @ u2 - vals[0]) < 1e-12
        ang = np.arctan2(np.cross(g2, g1) @ u2, g2 @ g1)
        assert abs(ang - (0.0 if kind == "GenTranslate5" else vals[1])) < 1e-12
    else:
        assert abs(np.arctan2(np.cross(g2, u1) @ u2, g2 @ u1) - vals[0]) < 1e-12
        assert abs(np.arctan2(np.cross(g1, u2) @ u1, g1 @ u2) - vals[1]) < 1e-12


def test_gen_constraint_3d_matches_gen_revolute5():
    """GenConstraint(point1, point2, (angle, axis), (sym, guess)) is the hinge GenRevolute5
    gives for the same axis, with a slide in the master's local coordinates."""
    q, s = sp.symbols("q s")
    poses = []
    for kind in ("gen", "user"):
        m = ms.Model3D()
        base = m.add_body("base", points={"p": (0.3, 0.0, 0.2)})
        arm = m.add_body("arm", points={"tip": (0.5, 0.2, 0.1)}, mass=1.0, inertia=(0.1, 0.1, 0.1))
        m.add(ms.GenTranslate5(base.axis(0, (1, 0, 0)), m.ground.axis((0, 0, 0), (1, 0, 0)), (s, 0.1)))
        if kind == "gen":
            m.add(ms.GenRevolute5(arm.axis(0, (0, 0, 1)), base.axis("p", (0, 0, 1)), (q, 0.2)))
        else:
            m.add(ms.GenConstraint(arm.point(0), base.point("p"), (q, (0, 0, 1)), (q, 0.2)))
        m.add(ms.Constraint(q - 0.2 - ms.T))
        m.add(ms.Constraint(s - 0.1 - ms.T**2))
        sol = m.solve([0.0, 0.7])
        poses.append((sol.location(arm.point("tip")), sol.velocity(arm.point("tip")),
                      np.asarray(sol.alpha("arm"))))
    for a, b in zip(*poses):
        np.testing.assert_allclose(a, b, atol=1e-12)
