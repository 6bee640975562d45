"""Redundant but consistent constraints, solved as Adams does (issue 12): the dependent
equations (pivoted QR of the scaled Jacobian at the start) are left out with a
RedundantConstraintWarning; the motion is that of the non-redundant model; reactions are
exact where determinate, minimum-norm and flagged where not; ``dof()`` gives the mobility
beside Gruebler's count. Every check is against an independent model or closed form."""

import warnings

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T

G = 9.81
Z = (0, 0, 1)
LENGTHS = {"crank": 1.0, "coupler": 4.0, "rocker": 3.0}


def four_bar_3d(masses=False):
    """Ground 4, crank 1, coupler 4, rocker 3 in the xy plane, four parallel Revolute5
    joints (3 dependent equations), crank driven at angle T."""
    m = ms.Model3D()
    g = m.ground
    kw = {name: {} for name in LENGTHS}
    if masses:
        for name, L in LENGTHS.items():
            kw[name] = {"mass": L, "centroid": (L / 2, 0, 0),
                        "inertia": (0.01 * L, L**3 / 12, L**3 / 12)}
    a = m.add_body("crank", points={"tip": (1, 0, 0)}, guess=((0, 0, 0), (1, 0, 0, 0)),
                   **kw["crank"])
    c = m.add_body("coupler", points={"end": (4, 0, 0)}, guess=((1, 0, 0), (0.8, Z)),
                   **kw["coupler"])
    r = m.add_body("rocker", points={"tip": (3, 0, 0)}, guess=((4, 0, 0), (1.7, Z)),
                   **kw["rocker"])
    m.add(ms.Revolute5(a.axis(0, Z), g.axis((0, 0, 0), Z)), name="A")
    m.add(ms.Revolute5(a.axis("tip", Z), c.axis(0, Z)), name="B")
    m.add(ms.Revolute5(c.axis("end", Z), r.axis("tip", Z)), name="C")
    m.add(ms.Revolute5(r.axis(0, Z), g.axis((4, 0, 0), Z)), name="D")
    m.add(ms.RotationLock1(a.axis(0, Z), g.axis((0, 0, 0), Z), T), name="drive")
    if masses:
        m.add_load(ms.Gravity((0, -1, 0), G))
    return m


def four_bar_2d(masses=False):
    """The same four-bar as a planar model (no redundancy)."""
    m = ms.Model2D()
    g = m.ground
    kw = {name: {} for name in LENGTHS}
    if masses:
        for name, L in LENGTHS.items():
            kw[name] = {"mass": L, "centroid": (L / 2, 0), "inertia": L**3 / 12}
    a = m.add_body("crank", points={"tip": (1, 0)}, guess=((0, 0), 0.0), **kw["crank"])
    c = m.add_body("coupler", points={"end": (4, 0)}, guess=((1, 0), 0.8), **kw["coupler"])
    r = m.add_body("rocker", points={"tip": (3, 0)}, guess=((4, 0), 1.7), **kw["rocker"])
    m.add(ms.Revolute2(g.point((0, 0)), a.point(0)), name="A")
    m.add(ms.Revolute2(a.point("tip"), c.point(0)), name="B")
    m.add(ms.Revolute2(c.point("end"), r.point("tip")), name="C")
    m.add(ms.Revolute2(g.point((4, 0)), r.point(0)), name="D")
    m.add(ms.RotationLock1(a, T), name="drive")
    if masses:
        m.add_load(ms.Gravity((0, -1), G))
    return m


def planar_angle(sol, body):
    """Rotation about z of a 3D body from its Euler parameters."""
    e0, e3 = sol.coordinate(f"{body}.e0"), sol.coordinate(f"{body}.e3")
    return np.unwrap(2 * np.arctan2(e3, e0))


def test_redundant_3d_four_bar_moves_like_the_planar_one():
    m3 = four_bar_3d()
    t = np.linspace(0.0, 2 * np.pi, 25)
    with pytest.warns(ms.RedundantConstraintWarning, match=r"3 dependent equation\(s\)") as rec:
        s3 = m3.solve(t)
    msg = str(rec[0].message)
    assert "Gruebler count says -3" in msg and "0 degree(s) of freedom (mobility)" in msg
    s2 = four_bar_2d().solve(t)
    for body in ("coupler", "rocker"):
        np.testing.assert_allclose(planar_angle(s3, body), np.unwrap(s2.angle(body)), rtol=0,
                                   atol=1e-10)
        for k in ("x", "y"):
            for order in (0, 1, 2):
                np.testing.assert_allclose(s3.coordinate(f"{body}.{k}", order),
                                           s2.coordinate(f"{body}.{k}", order), rtol=0,
                                           atol=1e-9)
    assert 1 <= len(s3.extra["redundant"]) <= 3 and set(s3.extra["redundant"]) <= set("ABCD")
    assert s3.extra["indeterminate"] == ["A", "B", "C", "D"]
    # every equation holds, the three left out too
    s = m3.compile()
    assert max(np.abs(s.residual(tk, qk)).max() for tk, qk in zip(s3.t, s3.q)) < 1e-10


def test_redundant_3d_four_bar_free_motion_matches_the_planar_one():
    """Released with the crank at 1 rad turning at 1 rad/s, under gravity: the same motion
    as the planar model, reactions in the plane the same; the drive reaction is gone."""
    runs = {}
    for name, build in (("3d", four_bar_3d), ("2d", four_bar_2d)):
        m = build(masses=True)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ms.RedundantConstraintWarning)
            m.solve(1.0)
            free = m.free(drop=["drive"])
        runs[name] = free.simulate(np.linspace(0.0, 1.5, 16))
    s3, s2 = runs["3d"], runs["2d"]
    np.testing.assert_allclose(planar_angle(s3, "crank"), s2.angle("crank"), rtol=0, atol=1e-8)
    np.testing.assert_allclose(planar_angle(s3, "rocker"), s2.angle("rocker"), rtol=0,
                               atol=1e-8)
    assert s3.extra["indeterminate"] == ["A", "B", "C", "D"]
    # the pin forces in the plane are determinate: the same as the planar model's
    F3 = np.asarray(s3.reaction("B", "coupler")[0], dtype=float)
    F2 = np.asarray(s2.reaction("B", "coupler")[0], dtype=float)
    np.testing.assert_allclose(F3[:, :2], F2, rtol=0, atol=1e-6 * np.abs(F2).max())


def bricard(drive=None):
    """The orthogonal Bricard linkage (six equal links of length 1, consecutive axes
    perpendicular, no offsets), assembled on six edges of the unit cube: ground is the link
    P0-P1; joint J_k at P_k."""
    P = [np.array(p, dtype=float) for p in
         [(0, 0, 0), (1, 0, 0), (1, 1, 0), (1, 1, 1), (0, 1, 1), (0, 0, 1)]]
    A = [(0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 0)]
    m = ms.Model3D()
    g = m.ground
    links = [g]
    for k in range(1, 6):
        links.append(m.add_body(f"link{k}", points={"next": tuple(P[(k + 1) % 6] - P[k])},
                                guess=(tuple(P[k]), (1, 0, 0, 0))))
    m.add(ms.Revolute5(g.axis(tuple(P[1]), A[1]), links[1].axis(0, A[1])), name="J1")
    for k in range(2, 6):
        m.add(ms.Revolute5(links[k - 1].axis("next", A[k]), links[k].axis(0, A[k])),
              name=f"J{k}")
    m.add(ms.Revolute5(links[5].axis("next", A[0]), g.axis(tuple(P[0]), A[0])), name="J0")
    if drive is not None:
        m.add(ms.RotationLock1(links[1].axis(0, A[1]), g.axis(tuple(P[1]), A[1]), drive),
              name="drive")
    return m


def test_bricard_linkage_has_mobility_one_and_moves():
    """Gruebler-Kutzbach: 5 bodies x 6 - 6 joints x 5 = 0; the Jacobian rank says 1."""
    dof = bricard().dof()
    assert int(dof) == 1 and dof.gruebler == 0 and dof.rank == 34
    assert len(dof.redundant) == 1
    m = bricard(drive=-T)
    t = np.linspace(0.0, 1.0, 21)
    with pytest.warns(ms.RedundantConstraintWarning, match="mobility"):
        sol = m.solve(t)
    s = m.compile()
    p = s.p_values
    for tk, qk, vk, ak in zip(sol.t, sol.q, sol.qd, sol.qdd):
        assert np.abs(s.residual(tk, qk)).max() < 1e-11           # all 36 equations
        J, rhs = s.velocity_rhs(tk, qk, p)
        assert np.abs(J @ vk - rhs).max() < 1e-9
        assert np.abs(J @ ak - s.gamma_values(tk, qk, vk, p)).max() < 1e-8
    # it moves: the far link turns, continuously
    e = sol.q[:, s.layout.index("link3.e0"):s.layout.index("link3.e3") + 1]
    turn = 2 * np.degrees(np.arccos(np.clip(np.abs(e[:, 0]), 0, 1)))
    assert turn[-1] > 30 and np.abs(np.diff(sol.q, axis=0)).max() < 0.2


def parallelogram_with_extra_bar():
    """Three cranks (length 1, mass 1) pinned at x = 0, 1, 2 and one coupler (length 2,
    mass 2) through their tips: Gruebler 0, mobility 1. Crank0 held at angle theta."""
    m = ms.Model2D()
    g = m.ground
    th = sp.pi / 3 + T
    cr = [m.add_body(f"crank{k}", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0),
                     inertia=1 / 12, guess=((float(k), 0), 1.0)) for k in range(3)]
    c = m.add_body("coupler", points={f"p{k}": (float(k), 0) for k in range(3)}, mass=2.0,
                   centroid=(1.0, 0), inertia=2 * 4 / 12, guess=((0.5, 0.9), 0.0))
    for k in range(3):
        m.add(ms.Revolute2(g.point((float(k), 0)), cr[k].point(0)), name=f"A{k}")
        m.add(ms.Revolute2(cr[k].point("tip"), c.point(f"p{k}")), name=f"B{k}")
    m.add(ms.RotationLock1(cr[0], th), name="hold")
    m.add_load(ms.Gravity((0, -1), G))
    return m


@pytest.mark.parametrize("mode", ["static", "dynamic"])
def test_parallelogram_with_extra_bar_reactions(mode):
    """Statics and inverse dynamics: the holding moment (determinate) is the one-DOF
    closed form; the pin forces balance the loads; the pins are flagged indeterminate."""
    m = parallelogram_with_extra_bar()
    dof = m.dof()
    assert int(dof) == 0 and dof.gruebler == -1
    t = np.linspace(0.0, 1.0, 5)
    with pytest.warns(ms.RedundantConstraintWarning, match=r"1 dependent equation"):
        sol = m.solve(t, solution=mode)
    th = np.pi / 3 + t
    # one DOF: V = g (3 x 0.5 + 2) sin(theta), T = (3 / 3 + 2) theta'^2 / 2; theta' = 1 and
    # theta'' = 0, so the holding moment is dV/dtheta in statics and inverse dynamics alike
    torque = 3.5 * G * np.cos(th)
    M_hold = np.asarray(sol.reaction("hold", "crank0")[1], dtype=float).reshape(len(t))
    np.testing.assert_allclose(M_hold, torque, rtol=1e-9)
    assert sorted(sol.extra["indeterminate"]) == ["A0", "A1", "A2", "B0", "B1", "B2"]
    # load balance of the whole mechanism: ground pins carry weight and inertia forces
    F = sum(np.asarray(sol.reaction(f"A{k}", f"crank{k}")[0], dtype=float) for k in range(3))
    w = 1.0                            # theta' (rad/s)
    # centroid accelerations: cranks 0.5 w^2, coupler w^2, towards the pivots (centripetal)
    inertia = np.zeros((len(t), 2))
    if mode == "dynamic":
        for mass, r in ((1.0, 0.5), (1.0, 0.5), (1.0, 0.5), (2.0, 1.0)):
            inertia += mass * r * w**2 * np.column_stack((-np.cos(th), -np.sin(th)))
    weight = np.array([0.0, -5.0 * G])
    np.testing.assert_allclose(F + weight, inertia, rtol=0, atol=1e-9)
    # the multipliers satisfy the load equations exactly
    s = m.compile()
    qd = sol.qd[2] if mode == "dynamic" else np.zeros(s.n)
    M, Q, Qv = s.dynamics.terms(t[2], sol.q[2], qd, sol.lam[2], s.p_values)
    acc = M @ sol.qdd[2] if mode == "dynamic" else 0.0
    np.testing.assert_allclose(s.jacobian(t[2], sol.q[2]).T @ sol.lam[2],
                               Q + (Qv - acc if mode == "dynamic" else 0.0), rtol=0, atol=1e-9)


def test_double_bearing_shaft():
    """A shaft in two coaxial Revolute5 bearings (5 dependent equations): mobility 1 by
    rank, Gruebler -4; driven, the bearings together carry the weight (the split between
    them is indeterminate and flagged)."""
    m = ms.Model3D()
    g = m.ground
    shaft = m.add_body("shaft", points={"far": (0, 0, 1)}, mass=3.0, centroid=(0, 0, 0.5),
                       inertia=(0.3, 0.3, 0.05), guess=((0, 0, 0), (1, 0, 0, 0)))
    m.add(ms.Revolute5(shaft.axis(0, Z), g.axis((0, 0, 0), Z)), name="bearing 1")
    m.add(ms.Revolute5(shaft.axis("far", Z), g.axis((0, 0, 1), Z)), name="bearing 2")
    m.add_load(ms.Gravity((0, -1, 0), G))
    dof = m.dof()
    assert int(dof) == 1 and dof.gruebler == -4
    m.add(ms.RotationLock1(shaft.axis(0, Z), g.axis((0, 0, 0), Z), 2 * T), name="drive")
    t = np.linspace(0.0, 1.0, 6)
    with pytest.warns(ms.RedundantConstraintWarning, match=r"5 dependent equation"):
        sol = m.solve(t, solution="dynamic")
    np.testing.assert_allclose(planar_angle(sol, "shaft"), 2 * t, rtol=0, atol=1e-12)
    F = sum(np.asarray(sol.reaction(b, "shaft")[0], dtype=float)
            for b in ("bearing 1", "bearing 2"))
    np.testing.assert_allclose(F, np.tile([0.0, 3.0 * G, 0.0], (len(t), 1)), rtol=0,
                               atol=1e-9)
    assert sorted(sol.extra["indeterminate"]) == ["bearing 1", "bearing 2"]
    # the minimum-norm share: symmetric about the centroid, half the weight each
    F1 = np.asarray(sol.reaction("bearing 1", "shaft")[0], dtype=float)
    np.testing.assert_allclose(F1[:, 1], 1.5 * G, rtol=1e-9)


def test_inconsistent_redundancy_raises():
    """Two coaxial bearings whose axes do not agree cannot be solved: an error names them."""
    m = ms.Model3D()
    g = m.ground
    shaft = m.add_body("shaft", points={"far": (0, 0, 1)}, guess=((0, 0, 0), (1, 0, 0, 0)))
    m.add(ms.Revolute5(shaft.axis(0, Z), g.axis((0, 0, 0), Z)), name="bearing 1")
    m.add(ms.Revolute5(shaft.axis("far", Z), g.axis((0.01, 0, 1), Z)), name="bearing 2")
    m.add(ms.RotationLock1(shaft.axis(0, Z), g.axis((0, 0, 0), Z), T), name="drive")
    with pytest.warns(ms.RedundantConstraintWarning), \
            pytest.raises(ms.ConstraintCountError, match="inconsistent") as err:
        m.solve(0.0)
    assert "'bearing 1'" in str(err.value) and "'bearing 2'" in str(err.value)
