"""Sensitivity to parameters (Mech 9.5, issue 15): exact derivatives by implicit
differentiation, checked against closed forms and central finite differences."""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T


def slider_crank(r=2.0, L=6.0, mp=3.0, force=150.0, phase=0.0, loads=False, backend=None):
    """Crank radius ``r``, rod length ``L`` as parameters; with ``loads``, masses, gravity
    and a force on the piston (piston mass ``mp`` a parameter)."""
    m = ms.Model2D(backend=backend)
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


@pytest.mark.parametrize("backend", ["default", "sympy"])
def test_slider_crank_piston_sensitivities_match_closed_form(backend):
    """x = r cos th + sqrt(L^2 - r^2 sin^2 th), th = 2 pi t: d/dL and d/dr of x, x_d, x_dd
    (derivatives of the closed form taken by SymPy in the test) to 1e-9 relative, with the
    kernels derived by SymEngine (default when installed) and by SymPy."""
    m = slider_crank(backend=None if backend == "default" else backend)
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


def test_friction_and_damper_sensitivities_match_finite_differences():
    """Loads that depend on the reactions (Coulomb friction in the slider: the multiplier
    equations are nonlinear, (Phi_q^T - Q_lambda) dlambda/dp = ...) and on velocities (a
    damper), kinematic-load solution: sensitivities to the friction coefficient, the damping
    and the rod length vs central differences."""
    def build(**values):
        m = slider_crank(loads=True, phase=0.3)
        mu, c = m.parameter("mu", 0.2), m.parameter("c", 5.0)
        m.add_load(ms.JointFriction(m.constraint("slider"), mu=mu))
        m.add_load(ms.Damper(m.body("piston").point(0), (20, 0), c))
        m.set_parameters(values)
        return m

    def outputs(s):
        return np.column_stack((s.reaction("drive", "crank")[1], s.reaction("slider", "piston")[0]))

    t = np.array([0.05, 0.2, 0.4])
    base = build()
    sens = base.sensitivity(["mu", "c", "L"]).solve(t, solution="kinematic")
    for name in ("mu", "c", "L"):
        v = base.parameters[name]
        h = 1e-6 * v
        fd = (outputs(build(**{name: v + h}).solve(t, solution="kinematic"))
              - outputs(build(**{name: v - h}).solve(t, solution="kinematic"))) / (2 * h)
        got = outputs(sens[name])
        assert np.abs(got - fd).max() < 1e-7 * max(np.abs(fd).max(), 1.0), name


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
    with pytest.raises(ms.ModelError, match="not been solved yet"):
        m.sensitivity(["L"]).of()
    m.parameter("unused", 1.0)
    with pytest.raises(ms.ModelError, match="'unused'.*not used by the model"):
        m.sensitivity(["L", "unused"]).solve(0.1)
    with pytest.raises(ms.ModelError, match="'nope' is not a parameter"):
        m.sensitivity("nope")
    with pytest.raises(ms.ModelError, match="at least one parameter"):
        m.sensitivity([])
    sens = m.sensitivity(["L"]).solve(0.1, solution="location")
    assert m.sensitivity(["L"]).of().solution is m.last_solution     # Mech's LastSolve default
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


def test_optimisation_reaches_the_closed_form_optimum():
    """Choose r and L so the piston's dead-centre positions are X0 (crank at 0) and Xpi
    (crank at pi): x(0) = L + r, x(pi) = L - r, so r = (X0 - Xpi)/2, L = (X0 + Xpi)/2.
    BFGS with the exact gradient from the sensitivities reaches it."""
    from scipy.optimize import minimize

    m = slider_crank()
    t = np.linspace(0.0, 0.5, 5)                # crank angles 0 ... pi (a sweep follows)
    goal = np.array([9.5, 4.5])
    sens = m.sensitivity(["r", "L"])
    x_piston = m.location(m.body("piston").point(0))[0]

    def f_and_grad(x):
        m.set_parameters(r=x[0], L=x[1])
        sol = m.solve(t, solution="location")
        err = sol.coordinate("piston.x")[[0, -1]] - goal
        grad = sens.of(sol).gradient(x_piston)[[0, -1]]     # (2 times, 2 parameters)
        return float(err @ err), 2 * err @ grad

    res = minimize(f_and_grad, [2.0, 6.0], jac=True, method="BFGS", options={"gtol": 1e-12})
    np.testing.assert_allclose(res.x, [2.5, 7.0], rtol=1e-9)
    assert res.fun < 1e-18


def test_spatial_slider_crank_sensitivity_matches_closed_form():
    """Mech's spatial slider-crank (Euler parameters, section 1.3) with the rod length a
    parameter: d/dL of the piston's x, x_d and x_dd vs the closed form, and the rod's Euler
    parameters' sensitivities stay tangent to the normalisation (e . de/dL = 0)."""
    m = ms.Model3D()
    r, L = 2.0, m.parameter("L", 6.0)
    z = (0, 0, 1)
    crank = m.add_body("crank", points={"pin": (r, 0, 0)})
    rod = m.add_body("rod", points={"b": (L, 0, 0)}, guess=((r, 0, 0), (1, 0, 0, 0)))
    piston = m.add_body("piston", guess=((8, 0, 0), (1, 0, 0, 0)))
    m.add(ms.Revolute5(crank.axis(0, z), m.ground.axis((0, 0, 0), z)))
    m.add(ms.Spherical3(crank.point("pin"), rod.point(0)))
    m.add(ms.Universal4(rod.axis("b", (0, 1, 0)), piston.axis(0, z)))
    m.add(ms.Translate5(piston.axis(0, (1, 0, 0)), m.ground.axis((0, 0, 0), (1, 0, 0))))
    m.add(ms.RotationLock1(crank.axis(0, z), m.ground.axis((0, 0, 0), z), 2 * sp.pi * T))
    t = np.linspace(0.05, 0.45, 5)
    sens = m.sensitivity("L").solve(t)
    ts = sp.Symbol("t")
    Ls = sp.Symbol("L")
    x = r * sp.cos(2 * sp.pi * ts) + sp.sqrt(Ls**2 - r**2 * sp.sin(2 * sp.pi * ts) ** 2)
    for order in range(3):
        ref = sp.lambdify(ts, sp.diff(x, ts, order, Ls).subs(Ls, 6.0), "numpy")(t)
        got = sens["L"].coordinate("piston.x", order)
        assert np.abs(got - ref).max() < 1e-9 * np.abs(ref).max(), order
    sl = m.compile().layout.body_slices["rod"]
    e, de = sens.solution.q[:, sl][:, 3:], sens["L"].q[:, sl][:, 3:]
    np.testing.assert_allclose(np.einsum("ij,ij->i", e, de), 0.0, atol=1e-13)
