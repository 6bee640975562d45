"""Beyond Mech: sensitivities of free-motion trajectories (forward sensitivity equations
integrated with the motion) vs central finite differences of tight simulations."""

import numpy as np
import pytest

import mechsys as ms

TIGHT = {"rtol": 1e-12, "atol": 1e-14}


def pendulum(L=1.5, g=9.81):
    """A point mass on a massless rod of length ``L`` (a parameter of the pivot point, so the
    start position itself depends on it), released from -1 rad."""
    m = ms.Model2D()
    Ls = m.parameter("L", L)
    bob = m.add_body("bob", points={"pivot": (-Ls, 0)}, mass=1.0, inertia=0.0, guess=((L, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), bob.point("pivot")), name="pin")
    m.add(ms.RotationLock1(bob, -1.0), name="hold")
    m.add_load(ms.Gravity((0, -1), g))
    m.solve(0.0, solution="location")
    return m


def double_pendulum(L1=1.0, m2=1.0):
    m = ms.Model2D()
    L = m.parameter("L1", L1)
    M2 = m.parameter("m2", m2)
    a = m.add_body("a", points={"tip": (L, 0)}, mass=1.0, centroid=(L / 2, 0), inertia=L**2 / 12)
    b = m.add_body("b", mass=M2, centroid=(0.5, 0), inertia=M2 / 12, guess=((L1, 0), 0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)), name="j1")
    m.add(ms.Revolute2(a.point("tip"), b.point(0)), name="j2")
    m.add(ms.RotationLock1(a, 0.0), name="lock1")
    m.add(ms.RotationLock1(b, 0.0), name="lock2")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0, solution="location")
    return m


def central(make, name, value, h, run):
    out = []
    for s in (1, -1):
        out.append(run(make(**{name: value + s * h})))
    return (out[0] - out[1]) / (2 * h)


def test_pendulum_angle_sensitivity_to_length():
    ic = {"bob.th": -1.0, "bob.th_d": 0.0}
    t = np.linspace(0, 2.0, 5)
    m = pendulum()
    sens = m.sensitivity(["L"], free=m.free(drop=["hold"])).simulate(t, initial_condition=ic,
                                                                     rtol=1e-10, atol=1e-12)

    def run(mm):
        sol = mm.free(drop=["hold"]).simulate(t, initial_condition=ic, **TIGHT)
        return np.column_stack((sol["bob.th"], sol.coordinate("bob.th", 1), sol["bob.x"]))

    fd = central(pendulum, "L", 1.5, 1e-5, run)
    got = np.column_stack((sens["L"].coordinate("bob.th"), sens["L"].coordinate("bob.th", 1),
                           sens["L"].coordinate("bob.x")))
    assert np.abs(got - fd).max() < 1e-7 * np.abs(fd).max()
    # the held start angle does not move; the bob's start position moves along the rod
    assert got[0, 0] == 0.0
    np.testing.assert_allclose(got[0, 2], np.cos(-1.0), rtol=1e-12)
    # the motion itself is the free motion of the same start
    plain = m.free(drop=["hold"]).simulate(t, initial_condition=ic, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(sens.solution["bob.th"], plain["bob.th"], atol=1e-8)


def test_double_pendulum_final_state_sensitivity():
    t = np.array([0.0, 0.8])
    m = double_pendulum()
    free = m.free(drop=["lock1", "lock2"])
    ic = {"a.th": 0.0, "b.th": 0.0, "a.th_d": 0.0, "b.th_d": 0.0}
    sens = m.sensitivity(["L1", "m2"], free=free).simulate(t, initial_condition=ic,
                                                           rtol=1e-10, atol=1e-12)

    def run(mm):
        sol = mm.free(drop=["lock1", "lock2"]).simulate(t, initial_condition=ic, **TIGHT)
        return np.concatenate((sol.q[-1], sol.qd[-1]))

    for name, value in (("L1", 1.0), ("m2", 1.0)):
        fd = central(double_pendulum, name, value, 1e-5, run)
        got = np.concatenate((sens[name].q[-1], sens[name].qd[-1]))
        assert np.abs(got - fd).max() < 1e-6 * np.abs(fd).max(), (name, got, fd)


def test_free_sensitivity_does_not_depend_on_the_unit_of_length():
    """The same pendulum in millimetres: d(angle)/dL is 1000 times smaller, d(x)/dL the same,
    with the same integration steps (the tolerances of the sensitivities scale with it)."""
    ic = {"bob.th": -1.0, "bob.th_d": 0.0}
    t = np.linspace(0, 1.0, 3)
    out = []
    for L, g in ((1.5, 9.81), (1500.0, 9810.0)):
        m = pendulum(L, g)
        out.append(m.sensitivity("L", free=m.free(drop=["hold"])).simulate(t, initial_condition=ic))
    m_, mm = out
    np.testing.assert_allclose(mm["L"].coordinate("bob.th") * 1000, m_["L"].coordinate("bob.th"),
                               rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(mm["L"].coordinate("bob.x"), m_["L"].coordinate("bob.x"),
                               rtol=1e-7, atol=1e-9)
    assert mm.solution.extra["steps"] == m_.solution.extra["steps"]


def test_free_sensitivity_bad_input():
    m = pendulum()
    with pytest.raises(ms.ModelError, match="solution='dynamic'"):
        m.sensitivity("L", free=m.free(drop=["hold"], solution="static"))
    with pytest.raises(ms.ModelError, match="FreeSystem of this model"):
        m.sensitivity("L", free=pendulum().free(drop=["hold"]))
    sens = m.sensitivity("L", free=m.free(drop=["hold"]))
    with pytest.raises(ms.ModelError, match="simulate"):
        sens.solve(0.0)
    with pytest.raises(ms.ModelError, match="unknown option"):
        sens.simulate((0, 1), rtool=1e-9)
    sol = m.free(drop=["hold"]).simulate((0, 0.1))
    with pytest.raises(ms.ModelError, match="free-dynamic solution"):
        m.sensitivity("L").of(sol)


def test_free_sensitivity_takes_the_starting_step_size():
    m = pendulum()
    sens = m.sensitivity("L", free=m.free(drop=["hold"]))
    ic = {"bob.th": -1.0, "bob.th_d": 0.0}
    got = sens.simulate((0, 0.5), initial_condition=ic, starting_step_size=2e-5, rtol=1e-10,
                        atol=1e-12)
    assert got.solution.t[1] - got.solution.t[0] == pytest.approx(2e-5, rel=1e-12)
    ref = sens.simulate((0, 0.5), initial_condition=ic, rtol=1e-10, atol=1e-12)
    assert ref.solution.t[1] - ref.solution.t[0] != pytest.approx(2e-5, rel=1e-3)
    np.testing.assert_allclose(got["L"].coordinate("bob.th")[-1],
                               ref["L"].coordinate("bob.th")[-1], rtol=1e-7)
    with pytest.raises(ms.ModelError, match="longer than the interval"):
        sens.simulate((0, 0.5), starting_step_size=1.0)
