"""Mech chapter 13 tools: failure-to-converge diagnosis (13.2), singular and near-singular
positions (13.3), the equations of motion as SymPy objects (13.4) and the solver hooks
(``$MechPreSolve``, ``$MechPostIterate``)."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys.solvers._diagnostics import diagnose_convergence


def crank_and_short_link(scale=1.0, link=1.75):
    """After Mech 13.2.1: a crank (radius 1) driven from angle 0 with a link whose end must
    stay on the line y = 2; at t = 0 the crank tip is at height 0, so a link of length 1.75
    cannot reach the line (a link of 2.5 can)."""
    m = ms.Model2D()
    crank = m.add_body("crank", points={"tip": (scale, 0)}, guess=((0, 0), 0.3))
    rod = m.add_body("rod", points={"end": (link * scale, 0)}, guess=((scale, 0), 1.2))
    m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)), name="pivot")
    m.add(ms.Revolute2(crank.point("tip"), rod.point(0)), name="joint")
    m.add(ms.PointOnLine1(rod.point("end"), m.ground.axis((0, 2.0 * scale), (1, 0))), name="reach")
    m.add(ms.RotationLock1(crank, ms.T), name="drive")
    return m


def test_inconsistent_constraint_is_named_with_a_suggestion():
    m = crank_and_short_link()
    with pytest.raises(ms.ConvergenceError) as info:
        m.solve(0.0)
    err = info.value
    # only the unreachable distance keeps a residual: it is the one named, first
    assert len(err.constraints) == 1 and "'reach'" in err.constraints[0][0]
    # the residual it keeps: |end - (3, 0)| can be no less than 3 - 1 - 1.75 = 0.25; the
    # scaled residual is that distance's square / its row scale, positive and finite
    assert 0 < err.constraints[0][1] < np.inf
    assert "cannot assemble" in err.suggestion and "'rod'" in err.suggestion
    assert err.diagnosis is not None and err.diagnosis.text in str(err)
    names = [c[0] for c in err.coordinates]
    assert set(names) <= set(m.compile().layout.q_names) and names
    # the exception keeps the raw residual vector and the iteration history too
    assert err.residuals.shape == (m.compile().m,) and len(err.history) == 51


def test_convergence_diagnosis_does_not_depend_on_the_unit_of_length():
    from mechsys.solvers._linalg import Scaling

    out = []
    for scale in (1.0, 1000.0):
        m = crank_and_short_link(scale)
        s = m.compile()
        q0 = m.guess()
        q1 = q0 + np.where(s.layout.q_names.index("rod.x") == np.arange(s.n), 0.2 * scale, 0.0)
        q1[s.layout.index("crank.th")] -= 0.3
        J = s.jacobian(0.0, q0)
        sc = Scaling.of(s, q0, J)
        F = s.residual(0.0, q1)
        out.append(diagnose_convergence(s, 0.0, q0, q1, F, sc.rows(J), sc, [1.0, 0.9, 0.9, 0.9]))
        with pytest.raises(ms.ConvergenceError) as info:
            m.solve(0.0)
        assert "'reach'" in info.value.constraints[0][0]
    a, b = out
    assert [c[0] for c in a.constraints] == [c[0] for c in b.constraints]
    for (_, ra), (_, rb) in zip(a.constraints, b.constraints):
        assert ra == pytest.approx(rb, rel=1e-9)
    # moves in units of L / radians agree; raw moves of positions scale with the unit
    assert [c[0] for c in a.coordinates] == [c[0] for c in b.coordinates]
    for (_, _, sa), (_, _, sb) in zip(a.coordinates, b.coordinates):
        assert sa == pytest.approx(sb, rel=1e-9)
    assert a.trend == b.trend and a.suggestion == b.suggestion


def test_diagnosis_classifies_divergence_and_slow_convergence():
    m = crank_and_short_link(link=2.5)  # assembles
    s = m.compile()
    sol = m.solve(0.0, "location")
    q0 = sol.q[0]
    F = s.residual(0.0, q0)
    from mechsys.solvers._linalg import Scaling

    sc = Scaling.of(s, q0, s.jacobian(0.0, q0))
    far = q0.copy()
    far[s.layout.index("rod.x")] += 50.0  # 50 lengths away
    d = diagnose_convergence(s, 0.0, q0, far, F + 1e-3, None, sc, [1, 2, 4, 8])
    assert d.trend == "diverged" and "rod.x" in d.suggestion
    assert d.coordinates[0][0] == "rod.x" and d.coordinates[0][1] == pytest.approx(50.0)
    d = diagnose_convergence(s, 0.0, q0, q0, F + 1e-3, None, sc, [1, 0.3, 0.1, 0.03, 0.01])
    assert d.trend == "decreasing" and "max_iterations" in d.suggestion
    d = diagnose_convergence(s, 0.0, q0, q0, F + 1e-3, None, sc, [1, 0.5, 0.9, 0.4, 0.95, 0.5])
    assert d.trend == "oscillating"


def _stretched_arm(angle=0.0):
    """Two unit links, the second's tip pinned to ground at distance 2 cos(angle): singular
    when stretched (angle 0), regular otherwise."""
    m = ms.Model2D()
    a = m.add_body("a", points={"tip": (1, 0)}, guess=((0, 0), angle))
    b = m.add_body("b", points={"tip": (1, 0)}, guess=((np.cos(angle), np.sin(angle)), -angle))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)), name="root")
    m.add(ms.Revolute2(a.point("tip"), b.point(0)), name="elbow")
    m.add(ms.Revolute2(b.point("tip"), m.ground.point((2 * np.cos(angle), 0))), name="hand")
    return m


def test_singular_position_reports_the_constraints_and_the_uncontrolled_motion():
    m = _stretched_arm(0.0)
    rep = m.singularity()
    assert rep.singular and rep.rcond == 0.0 and rep.rank == 5
    assert len(rep.groups) == 1
    g = rep.groups[0]
    assert {lab.split("'")[1] for lab, _, _ in g["constraints"]} == {"root", "elbow", "hand"}
    # the horizontal (first) equations of the three pins depend: stretched along x, they
    # involve only x_a and x_b (three rows, rank 2)
    assert all(eq == [1] for _, eq, _ in g["constraints"])
    s = m.compile()
    J = s.jacobian(0.0, m.guess())
    xrows = [i for i in range(s.m) if s.layout.eq_index[i] == 0]
    assert len(xrows) == 3 and np.linalg.matrix_rank(J[xrows]) == 2
    # uncontrolled motion: the elbow moving up (a.th, b.th, b.y), which keeps every pin
    # closed to first order
    moving = dict(g["coordinates"])
    assert set(moving) == {"a.th", "b.th", "b.y"}
    v = np.zeros(s.n)
    for nm, w in moving.items():
        v[s.layout.index(nm)] = w
    assert np.abs(J @ v).max() < 1e-12
    assert "root" in str(rep) and "toggle" in str(rep)


def test_near_singular_position_and_threshold():
    angle = 1e-4
    m = _stretched_arm(angle)
    m.solve(0.0, "location")
    q = m.last_solution.q[0]
    rep = m.singularity(q)
    assert not rep.singular and rep.rcond > 0
    # s_min / s_max of a nearly stretched arm is proportional to the angle
    rep2 = _stretched_arm(2 * angle).singularity(_stretched_arm(2 * angle).solve(0.0, "location"))
    assert rep2.rcond / rep.rcond == pytest.approx(2.0, rel=1e-3)
    loose = m.singularity(q, threshold=1e-3)
    assert loose.singular and loose.groups and "nearly singular" in str(loose)
    with pytest.raises(ms.ModelError, match="threshold"):
        m.singularity(q, threshold=2)


def test_redundant_constraints_are_an_exact_singularity():
    m = ms.Model2D()
    b = m.add_body("b")
    m.add(ms.OriginLock2(b), name="fix")
    m.add(ms.RotationLock1(b, 0.0), name="lock")
    m.add(ms.RotationLock1(b, 0.0), name="lock_again")
    rep = m.singularity()
    assert rep.singular and len(rep.groups) == 1
    assert {lab.split("'")[1] for lab, _, _ in rep.groups[0]["constraints"]} == {"lock", "lock_again"}


def pendulum(L=1.3, g=9.81, mass=2.0):
    m = ms.Model2D()
    b = m.add_body("bar", mass=mass, centroid=(L, 0), inertia=0.0, guess=((0, 0), -0.4))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add_load(ms.Gravity((0, -1), g))
    return m


def test_equations_give_the_pendulum_motion_in_closed_form():
    L, g = 1.3, 9.81
    m = pendulum(L, g)
    eq = m.equations()
    q, qd = eq.q, eq.qd
    # Jacobian and gamma from their definitions, independently with SymPy
    assert sp.simplify(eq.jacobian - eq.phi.jacobian(q)) == sp.zeros(2, 3)
    Jqd = eq.jacobian * qd
    gamma = -Jqd.jacobian(q) * qd
    assert sp.simplify(eq.gamma - gamma) == sp.zeros(2, 1)
    # equations of motion: [M J^T; J 0] [qdd; lam] = [Q + Qv; gamma]
    th, thd = 0.7, -1.1
    subs = dict(zip(q, [0, 0, th])) | dict(zip(qd, [0, 0, thd]))
    M = np.array(eq.mass_matrix.subs(subs), dtype=float)
    J = np.array(eq.jacobian.subs(subs), dtype=float)
    rhs = np.concatenate([np.array((eq.loads + eq.centrifugal).subs(subs), dtype=float).ravel(),
                          np.array(eq.gamma.subs(subs), dtype=float).ravel()])
    K = np.block([[M, J.T], [J, np.zeros((2, 2))]])
    qdd = np.linalg.solve(K, rhs)[:3]
    assert qdd[2] == pytest.approx(-g / L * np.cos(th), rel=1e-12)
    # one constraint's rows only
    e1 = m.equations("pivot")
    assert e1.phi.shape == (2, 1) and len(e1.rows) == 2 and e1.lam.shape == (2, 1)


def test_equations_display():
    eq = pendulum().equations()
    assert "jacobian =" in eq.pretty() and "gamma =" in str(eq)
    lx = eq.latex("jacobian")
    assert lx.startswith(r"\Phi_q = ") and r"\begin{matrix}-1 & 0 & 0" in lx
    assert eq._repr_latex_().startswith("$") and r"\gamma" in eq._repr_latex_()
    assert "Equations" in repr(eq)
    with pytest.raises(ms.ModelError, match="part must be one of .*got 'lagrangian'"):
        eq.pretty("lagrangian")
    with pytest.raises(ms.UnknownConstraintError, match="nope"):
        pendulum().equations("nope")


def driven_crank():
    m = ms.Model2D()
    crank = m.add_body("crank", points={"tip": (1, 0)}, guess=((0, 0), 0.1))
    rod = m.add_body("rod", points={"end": (2.5, 0)}, guess=((1, 0), -0.2))
    slider = m.add_body("slider", guess=((3.4, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)), name="pivot")
    m.add(ms.Revolute2(crank.point("tip"), rod.point(0)), name="joint")
    m.add(ms.Revolute2(rod.point("end"), slider.point(0)), name="pin")
    m.add(ms.Translate2(slider.axis((0, 0), (1, 0)), m.ground.axis((0, 0), (1, 0))), name="slide")
    m.add(ms.RotationLock1(crank, ms.T), name="drive")
    return m


def test_hooks_are_called_with_the_documented_arguments():
    m = driven_crank()
    times, its = [], []
    sol = m.solve([0.0, 0.2, 0.4], pre_solve=times.append,
                  post_iterate=lambda it: its.append(it))
    assert times == [0.0, 0.2, 0.4]
    assert its and all(isinstance(it, ms.Iteration) for it in its)
    assert {it.t for it in its} == {0.0, 0.2, 0.4}
    assert its[0].names == sol.names and its[0].q.shape == (sol.q.shape[1],)
    # per point: iterations count 1, 2, ...; the last iterate is the solution
    for k, t in enumerate([0.0, 0.2, 0.4]):
        mine = [it for it in its if it.t == t]
        assert [it.iteration for it in mine] == list(range(1, len(mine) + 1))
        assert len(mine) == sol.iterations[k]
        np.testing.assert_allclose(mine[-1].q, sol.q[k], atol=1e-14)
        assert mine[-1].residual <= 1e-11
    # the step is the difference of successive iterates
    a, b = its[0], its[1]
    np.testing.assert_allclose(b.q - a.q, b.step, atol=1e-14)


def test_hooks_can_stop_the_solve():
    m = driven_crank()
    sol = m.solve([0.0, 0.2, 0.4, 0.6], pre_solve=lambda t: t < 0.3)
    assert list(sol.t) == [0.0, 0.2] and "pre_solve returned False at t = 0.4" in sol.extra["stopped"]
    ref = m.solve([0.0, 0.2])
    np.testing.assert_allclose(sol.q, ref.q, atol=1e-13)
    with pytest.raises(ms.MechError, match="post_iterate returned False at t = 0 at iteration 2"):
        m.solve(0.0, post_iterate=lambda it: it.iteration < 2)
    with pytest.raises(ms.ModelError, match="pre_solve must be a callable"):
        m.solve(0.0, pre_solve=3)
    with pytest.raises(ms.ModelError, match="post_iterate must be a callable"):
        m.solve(0.0, post_iterate="print")
    # other return values (None, True) go on
    assert len(m.solve([0.0, 0.1], pre_solve=lambda t: None, post_iterate=lambda it: True)) == 2
