"""Sensitivity to parameters (Mech 9.5, issue 15): exact derivatives by implicit
differentiation, checked against closed forms and central finite differences."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T


def slider_crank(r=2.0, L=6.0, mp=3.0, force=150.0, phase=0.0, loads=False):
    """Crank radius ``r``, rod length ``L`` as parameters; with ``loads``, masses, gravity
    and a force on the piston (piston mass ``mp`` a parameter)."""
    m = ms.Model2D()
    r_, L_ = m.parameter("r", r), m.parameter("L", L)
    mp_ = m.parameter("mp", mp)
    mass = {} if not loads else {"mass": 1.0, "inertia": 0.5, "centroid": (r_ / 2, 0)}
    crank = m.add_body("crank", points={"pin": (r_, 0)}, **mass)
    mass = {} if not loads else {"mass": 2.0, "inertia": L_**2 / 6, "centroid": (L_ / 2, 0)}
    rod = m.add_body("rod", points={"a": (0, 0), "b": (L_, 0)}, guess=((2, 0.5), -0.1), **mass)
    piston = m.add_body("piston", guess=((8, 0), 0), **({"mass": mp_} if loads else {}))
    m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)), name="crank pin")
    m.add(ms.Revolute2(crank.point("pin"), rod.point("a")), name="crank-rod")
    m.add(ms.Revolute2(rod.point("b"), piston.point(0)), name="wrist pin")
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), piston.axis((0, 0), (1, 0))), name="slider")
    m.add(ms.RotationLock1(crank, phase + 2 * sp.pi * T), name="drive")
    if loads:
        m.add_load(ms.Force(piston.point(0), (1, 0), -force))
        m.add_load(ms.Gravity((0, -1), 9.81))
    return m


def test_slider_crank_piston_sensitivities_match_closed_form():
    """x = r cos th + sqrt(L^2 - r^2 sin^2 th), th = 2 pi t: d/dL and d/dr of x, x_d, x_dd
    (derivatives of the closed form taken by SymPy in the test) to 1e-9 relative."""
    m = slider_crank()
    t = np.linspace(0, 1, 13)
    sens = m.sensitivity(["L", "r"]).solve(t)
    ts, rs, Ls = sp.symbols("t r L")
    x = rs * sp.cos(2 * sp.pi * ts) + sp.sqrt(Ls**2 - rs**2 * sp.sin(2 * sp.pi * ts) ** 2)
    for name, P in (("L", Ls), ("r", rs)):
        for order in range(3):
            ref_expr = sp.diff(sp.diff(x, ts, order), P).subs({rs: 2.0, Ls: 6.0})
            ref = sp.lambdify(ts, ref_expr, "numpy")(t) * np.ones_like(t)
            got = sens[name].coordinate("piston.x", order)
            err = np.abs(got - ref).max() / np.abs(ref).max()
            assert err < 1e-9, (name, order, err)
    # the output functions give the same numbers, and the sensitivity of the rod length
    # itself (a distance between two points it defines) is exactly 1 for L, 0 for r
    piston, rod = m.body("piston"), m.body("rod")
    np.testing.assert_allclose(sens["L"].location(piston.point(0))[:, 0],
                               sens["L"].coordinate("piston.x"), rtol=0, atol=1e-14)
    np.testing.assert_allclose(sens["L"].distance(rod.point("a"), rod.point("b")), 1.0, atol=1e-14)
    np.testing.assert_allclose(sens["r"].distance(rod.point("a"), rod.point("b")), 0.0, atol=1e-14)
    grad = sens.gradient(m.location(piston.point(0))[0])
    assert grad.shape == (13, 2)
    np.testing.assert_allclose(grad[:, 1], sens["r"].coordinate("piston.x"), atol=1e-14)
    # Mech's reading: a sensitivity is a velocity with the parameter as "time"
    assert sens.solution is m.last_solution
    again = m.last_solution.sensitivity("L")
    np.testing.assert_array_equal(again.dq[:, 0], sens.dq[:, 0])


@pytest.mark.parametrize("mode", ["static", "dynamic"])
def test_reaction_sensitivities_match_finite_differences(mode):
    """Drive torque and wrist-pin force of the loaded slider-crank: exact sensitivities vs
    central differences of the static (and inverse-dynamic) solutions."""
    t = np.array([0.0, 0.15, 0.4])
    base = slider_crank(loads=True, phase=0.3)
    sens = base.sensitivity(["L", "r", "mp"]).solve(t, solution=mode)

    def outputs(sol_or_view):
        torque = sol_or_view.reaction("drive", "crank")[1]
        force = sol_or_view.reaction("wrist pin", "piston")[0]
        return np.column_stack((torque, force))

    for name in ("L", "r", "mp"):
        value = base.parameters[name]
        h = 1e-6 * value
        vals = []
        for s in (1, -1):
            mm = slider_crank(loads=True, phase=0.3)
            mm.set_parameters(**{name: value + s * h})
            vals.append(outputs(mm.solve(t, solution=mode)))
        fd = (vals[0] - vals[1]) / (2 * h)
        got = outputs(sens[name])
        scale = max(np.abs(fd).max(), 1.0)
        assert np.abs(got - fd).max() < 1e-7 * scale, (name, np.abs(got - fd).max(), scale)
    if mode == "static":
        # at rest the velocities' sensitivities are zero by definition
        np.testing.assert_array_equal(sens["L"].qd, 0.0)


def test_sensitivity_of_a_given_state_and_unit_independence():
    """``of(State)`` differentiates one configuration; in millimetres the sensitivity of a
    length to a length is unchanged and the angle's is divided by 1000."""
    m = slider_crank()
    st = m.solve(np.array([0.1])).state(0)
    a = m.sensitivity(["L"]).of(st)
    mm = slider_crank(r=2000.0, L=6000.0)
    b = mm.sensitivity(["L"]).of(mm.solve(np.array([0.1])).state(0))
    np.testing.assert_allclose(b["L"].coordinate("piston.x"), a["L"].coordinate("piston.x"),
                               rtol=1e-12)
    np.testing.assert_allclose(b["L"].coordinate("rod.th") * 1000, a["L"].coordinate("rod.th"),
                               rtol=1e-12)


def test_bad_input_is_a_clear_error():
    m = slider_crank()
    m.parameter("unused", 1.0)
    with pytest.raises(ms.ModelError, match="'unused'.*not used by the model"):
        m.sensitivity(["L", "unused"]).solve(0.1)
    with pytest.raises(ms.ModelError, match="'nope' is not a parameter"):
        m.sensitivity("nope")
    with pytest.raises(ms.ModelError, match="at least one parameter"):
        m.sensitivity([])
    sens = m.sensitivity(["L"]).solve(0.1, solution="location")
    with pytest.raises(ms.ModelError, match="no sensitivity to 'r'"):
        sens["r"]
    with pytest.raises(ms.MechError, match="velocities"):
        _ = sens["L"].qd
    with pytest.raises(ms.ModelError, match="free motion"):
        m.sensitivity(["L"]).simulate((0, 1))


def test_singular_configuration_names_the_time():
    """Driven at the piston, the slider-crank locks at its dead centre: the Jacobian is
    singular there and the sensitivity says so, with the time."""
    m = ms.Model2D()
    L = m.parameter("L", 6.0)
    crank = m.add_body("crank", points={"pin": (2, 0)})
    rod = m.add_body("rod", points={"b": (L, 0)})
    piston = m.add_body("piston")
    m.add(ms.Revolute2((0, 0), crank.point(0)))
    m.add(ms.Revolute2(crank.point("pin"), rod.point(0)))
    m.add(ms.Revolute2(rod.point("b"), piston.point(0)))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), piston.axis((0, 0), (1, 0))))
    m.add(ms.RelativeX1(piston.point(0), 8 - T), name="piston drive")
    dead = ms.State(t=0.0, q=np.array([0, 0, 0, 2, 0, 0, 8, 0, 0.0]), qd=None, qdd=None,
                    system=m.compile())
    with pytest.raises(ms.SingularJacobianError, match="at t = 0") as err:
        m.sensitivity("L").of(dead)
    assert err.value.time == 0.0
