"""Model2D(orientation="euler"): Mech's 2D degenerate Euler parameters (manual 12.4.1).

Every analysis is checked against the same model in the default angle coordinates (a second
formulation), the Jacobians against central finite differences, and the option's handling
of bad input and of the features that need an angle coordinate.
"""

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import ModelError, T


def wrap(d):
    return np.angle(np.exp(1j * np.asarray(d, dtype=float)))


def four_bar(orientation):
    a, b, c, d = 1.0, 4.0, 3.0, 4.0
    m = ms.Model2D(orientation=orientation)
    g = m.ground
    crank = m.add_body("crank", points={"A": (a, 0)}, guess=((0, 0), 0), mass=1,
                       inertia=0.1, centroid=(0.5, 0))
    coupler = m.add_body("coupler", points={"A": (0, 0), "B": (b, 0)}, guess=((a, 0), 0.9),
                         mass=2, inertia=1.0, centroid=(2, 0.1))
    rocker = m.add_body("rocker", points={"B": (c, 0)}, guess=((d, 0), 1.8), mass=1.5,
                        inertia=0.5, centroid=(1.5, 0))
    m.add(ms.Revolute2(g.point((0, 0)), crank.point(0)), name="O2")
    m.add(ms.Revolute2(crank.point("A"), coupler.point("A")), name="A")
    m.add(ms.Revolute2(coupler.point("B"), rocker.point("B")), name="B")
    m.add(ms.Revolute2(g.point((d, 0)), rocker.point(0)), name="O4")
    m.add(ms.RotationLock1(crank, 2 * T), name="drive")
    m.add_load(ms.Gravity((0, -1), 9.81))
    return m


def double_pendulum(orientation):
    m = ms.Model2D(orientation=orientation)
    b1 = m.add_body("link1", points={"O": (0, 0), "P": (1.0, 0)}, mass=1.0, inertia=1 / 12,
                    centroid=(0.5, 0), guess=((0, 0), 0.7))
    b2 = m.add_body("link2", points={"P": (0, 0), "Q": (0.8, 0)}, mass=0.7,
                    inertia=0.7 * 0.64 / 12, centroid=(0.4, 0.05),
                    guess=((np.cos(0.7), np.sin(0.7)), -0.4))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b1.point("O")), name="O")
    m.add(ms.Revolute2(b1.point("P"), b2.point("P")), name="P")
    m.add(ms.RotationLock1(b1, 0.7), name="hold1")
    m.add(ms.RotationLock1(b2, -0.4), name="hold2")
    m.add_load(ms.Gravity((0, -1), 9.81))
    return m


def test_coordinates_are_x_y_ei_ej_with_one_normalisation_per_body():
    m = four_bar("euler")
    crank = m.body("crank")
    assert [s.name for s in crank.q] == ["x2", "y2", "ei2", "ej2"]
    assert np.allclose(m.body("coupler").guess, [1, 0, np.cos(0.9), np.sin(0.9)])
    eqs = list(m.equations().phi)
    assert len(eqs) == len(four_bar("angle").equations().phi) + 3   # one normalisation per body
    ei, ej = crank.q[2:]
    assert any(sp.expand(e - (ei**2 + ej**2 - 1)) == 0 for e in eqs)
    # no sine or cosine of a coordinate in any equation (manual 12.4.1)
    q = {s for b in m.bodies[1:] for s in b.q}
    for e in eqs:
        for f in e.atoms(sp.sin, sp.cos):
            assert not (f.free_symbols & q), e
    sol = m.solve(0.3, solution="location")
    loc = np.asarray(sol.location([m.body("coupler")]), dtype=float).ravel()   # Location[3]
    th = sol.angle("coupler")
    assert np.allclose(loc, [sol["x3"], sol["y3"], np.cos(th), np.sin(th)], atol=1e-14)
    e2 = np.array([sol["ei3"], sol["ej3"]])
    assert abs(np.hypot(*e2) - 1) < 1e-12
    assert abs(np.arctan2(e2[1], e2[0]) - sol.angle("coupler")) < 1e-14


def test_four_bar_sweep_matches_angle_coordinates():
    t = np.linspace(0, np.pi, 19)   # the crank turns a full revolution (drive 2 T)
    a, e = (four_bar(o).solve(t, solution="acceleration") for o in ("angle", "euler"))
    for body in ("crank", "coupler", "rocker"):
        assert np.abs(wrap(a.angle(body) - e.angle(body))).max() < 1e-9
        assert np.abs(a.omega(body) - e.omega(body)).max() < 1e-9
        assert np.abs(a.alpha(body) - e.alpha(body)).max() < 1e-9
    for f in ("location", "velocity", "acceleration"):
        pa = getattr(a, f)(a.model.body("coupler").point("B"))
        pe = getattr(e, f)(e.model.body("coupler").point("B"))
        assert np.abs(np.asarray(pa) - np.asarray(pe)).max() < 1e-9


def test_statics_and_inverse_dynamics_reactions_match():
    t = np.linspace(0, 1, 5)
    for kind in ("static", "dynamic"):
        a, e = (four_bar(o).solve(t, solution=kind) for o in ("angle", "euler"))
        for c, b in (("drive", "crank"), ("O4", "rocker"), ("B", "coupler")):
            Fa, Ma = a.reaction(c, b)
            Fe, Me = e.reaction(c, b)
            scale = 1 + np.abs(Fa).max()
            assert np.abs(np.asarray(Fa) - np.asarray(Fe)).max() < 1e-9 * scale, (kind, c)
            assert np.abs(np.asarray(Ma) - np.asarray(Me)).max() < 1e-9 * scale, (kind, c)


def test_double_pendulum_free_motion_matches_angle_coordinates():
    t = np.linspace(0, 2, 21)
    out = {}
    for o in ("angle", "euler"):
        m = double_pendulum(o)
        ic = {("omega", "link1"): 0.5, ("omega", "link2"): -1.0}
        sol = m.free(drop=["hold1", "hold2"]).simulate(t, initial_condition=ic, rtol=1e-12,
                                                      atol=1e-12)
        out[o] = sol
    a, e = out["angle"], out["euler"]
    for body in ("link1", "link2"):
        assert np.abs(wrap(a.angle(body) - e.angle(body))).max() < 1e-9
        assert np.abs(a.omega(body) - e.omega(body)).max() < 1e-9
    qa, qe = (s.location(s.model.body("link2").point("Q")) for s in (a, e))
    assert np.abs(qa - qe).max() < 1e-9
    # the Euler parameters stay normalised along the motion
    assert np.abs(np.hypot(e["ei3"], e["ej3"]) - 1).max() < 1e-10


def test_jacobian_matches_finite_differences():
    m = four_bar("euler")
    s = m.compile()
    rng = np.random.default_rng(3)
    q = s.guess + 0.1 * rng.standard_normal(s.n)
    p = np.array([m._params[x] for x in s.layout.p_symbols], dtype=float)
    J = s.jacobian(0.4, q, p)
    h = 1e-6
    fd = np.column_stack([(s.residual(0.4, q + h * ei, p) - s.residual(0.4, q - h * ei, p))
                          / (2 * h) for ei in np.eye(s.n)])
    assert np.abs(J - fd).max() < 1e-8


def test_torsion_spring_equilibrium_matches():
    out = {}
    for o in ("angle", "euler"):
        m = ms.Model2D(orientation=o)
        rod = m.add_body("rod", points={"pivot": (-0.5, 0)}, mass=2.0, inertia=1 / 6,
                         guess=((0.5, 0), 0.0))
        m.add(ms.Revolute2(rod.point("pivot"), m.ground.point((0, 0))), name="pivot")
        m.add_load(ms.Gravity((0, -1), 9.81))
        m.add_load(ms.TorsionSpring(m.ground, rod, 40.0, 0.3))
        out[o] = m.free(solution="static").solve()
    th = out["angle"].angle("rod")
    assert abs(th - out["euler"].angle("rod")) < 1e-9
    # closed form: k (th - th0) = -m g c cos(th)
    assert abs(40.0 * (th - 0.3) + 2.0 * 9.81 * 0.5 * np.cos(th)) < 1e-9


def test_bad_orientation():
    with pytest.raises(ModelError, match="orientation must be one of 'angle', 'euler'"):
        ms.Model2D(orientation="eulr")


def test_model_file_keeps_the_orientation(tmp_path):
    m = four_bar("euler")
    path = m.save(tmp_path / "fb.json")
    back = ms.load(path)
    assert back.orientation == "euler" and [s.name for s in back.body("crank").q][2:] == [
        "ei2", "ej2"]
    a, b = m.solve(0.2, solution="velocity"), back.solve(0.2, solution="velocity")
    assert abs(a.omega("rocker") - b.omega("rocker")) < 1e-12
    assert ms.load(four_bar("angle").save(tmp_path / "fa.json")).orientation == "angle"


def test_drawing_places_the_bodies_as_in_angle_coordinates():
    pytest.importorskip("matplotlib")
    from mechsys import draw as d

    t = np.linspace(0, 1, 4)
    frames = [d.Scene(m).evaluate(m.solve(t, solution="location"))
              for m in (four_bar("angle"), four_bar("euler"))]
    a, e = (fr.items for fr in frames)
    assert [it.kind for it in a] == [it.kind for it in e] and len(a) > 5
    for ia, ie in zip(a, e):
        xa = np.broadcast_to(ia.xyz, (len(t),) + ia.xyz.shape[1:])
        xe = np.broadcast_to(ie.xyz, (len(t),) + ie.xyz.shape[1:])
        np.testing.assert_allclose(xe, xa, rtol=0, atol=1e-9)   # (NaN: line breaks)


def _planar_cases():
    from mechsys.constraints import REGISTRY
    from mechsys.testing import CASES

    out = []
    for name, builders in CASES.items():
        if "planar" not in getattr(REGISTRY.get(name), "spaces", ("planar",)):
            continue
        for k, f in enumerate(builders):
            out.append((name, k, f))
    return out


def test_every_planar_constraint_case_in_euler_parameters(monkeypatch):
    """The conformance cases (residual at a hand-built configuration, Jacobian and gamma
    against finite differences, DOF count) rebuilt with degenerate Euler parameters: every
    planar constraint type, the gears in Mech's Euler form included."""
    from mechsys.testing import check_constraint_case

    monkeypatch.setattr(ms.Model2D.__init__, "__defaults__", (None, "euler"))
    done = set()
    for name, k, f in _planar_cases():
        c = f(np.random.default_rng(17 * k))
        if c.model.space.dim != 2:
            continue
        assert c.model.orientation == "euler"
        c.label = f"{name}[{k}] (euler)"
        errs = check_constraint_case(c)
        assert errs["residual"] < 1e-10, (c.label, errs)
        done.add(name)
    assert len(done) >= 15 and {"Revolute2", "RotationLock1", "RelativeAngle1"} <= done
    assert {"TwoGears1", "TwoGears2", "TwoPulleys1", "TwoPulleys2", "RackAndPinion1",
            "RackAndPinion2"} <= done


def _gear_train(orientation, kind):
    """Gear (or pulley, or rack) pair, wheel 1 on a pin driven through more than two turns
    with a growing speed; wheel 2 on a pin (``...1`` forms), or its centre on the x axis
    (``...2`` forms: their distance equation places it); a rack sliding along y = -1."""
    m = ms.Model2D(orientation=orientation)
    g1 = m.add_body("g1", guess=((0, 0), 0.3), mass=1.0, inertia=0.5)
    m.add(ms.Revolute2(m.ground.point((0, 0)), g1.point((0, 0))), name="pin1")
    cls = getattr(ms, kind)
    if kind.startswith("RackAndPinion"):
        rack = m.add_body("rack", guess=((0.1, -1.0), 0.0), mass=3.0, inertia=1.0)
        if kind == "RackAndPinion1":
            m.add(ms.Translate2(m.ground.axis((0, -1), (1, -1)), rack.axis((0, 0), (1, 0))),
                  name="slide")
        else:
            m.add(ms.RotationLock1(rack, 0.0), name="keep")
        m.add(cls(g1.point((0, 0)), 1.0, rack.axis((0, 0), (1, 0)), 0.3), name="mesh")
    else:
        g2 = m.add_body("g2", guess=((3.05, 0.05), -0.2), mass=2.0, inertia=2.0)
        extra = (3.0,) if kind.startswith("TwoPulleys") else ()
        if kind.endswith("1"):
            m.add(ms.Revolute2(m.ground.point((3, 0)), g2.point((0, 0))), name="pin2")
        else:
            m.add(ms.PointOnLine1(g2.point((0, 0)), m.ground.axis((0, 0), (1, 0))),
                  name="track")
        m.add(cls(g1.point((0, 0)), 1.0, g2.point((0, 0)), 2.0, *extra, 0.5), name="mesh")
    m.add(ms.RotationLock1(g1, 3 * sp.pi * ms.T + 2 * ms.T**2), name="drive")
    return m


@pytest.mark.parametrize("kind", ["TwoGears1", "TwoGears2", "TwoPulleys1", "TwoPulleys2",
                                  "RackAndPinion1", "RackAndPinion2"])
def test_gears_in_euler_parameters_turn_as_in_angles(kind):
    """Mech's Euler form of the planar gears (the variable is the angle e1 from the line of
    centres to wheel 1's x axis; each wheel's angle equation in its own frame): over two
    turns of the driver the driven body moves exactly as in angle coordinates --
    positions, velocities, accelerations -- and the driving torque is the same."""
    t = np.linspace(0.0, 1.4, 29)
    sols = {o: _gear_train(o, kind).solve(t, solution="dynamic") for o in ("angle", "euler")}
    a, e = sols["angle"], sols["euler"]
    body = "rack" if kind.startswith("Rack") else "g2"
    np.testing.assert_allclose(np.unwrap(e.angle(body)), np.unwrap(a.angle(body)), atol=1e-9)
    for k in (0, 1, 2):
        for c in ("x", "y"):
            np.testing.assert_allclose(e.coordinate(f"{body}.{c}", k),
                                       a.coordinate(f"{body}.{c}", k), atol=1e-8)
    np.testing.assert_allclose(e.omega(body), a.omega(body), atol=1e-8)
    np.testing.assert_allclose(e.alpha(body), a.alpha(body), atol=1e-7)
    # the driver's torque: inverse dynamics through the gear equations
    _, Ma = a.reaction("drive", "g1")
    _, Me = e.reaction("drive", "g1")
    assert np.abs(np.asarray(Ma)).max() > 0.1              # the gears do take a torque
    np.testing.assert_allclose(np.asarray(Me), np.asarray(Ma), rtol=1e-7, atol=1e-7)


def test_gear_pair_free_motion_in_euler_parameters():
    """Two meshing gears on pins, released with gear 1 turning: the free motion (several
    turns) is the angle model's, and the speeds keep the ratio -rad1/rad2."""
    out = {}
    for o in ("angle", "euler"):
        m = _gear_train(o, "TwoGears1")
        m.solve(0.0)
        free = m.free(drop=["drive"])
        out[o] = free.simulate(np.linspace(0.0, 3.0, 31), initial_condition={("omega", "g1"): 5.0},
                               rtol=1e-11, atol=1e-13)
    a, e = out["angle"], out["euler"]
    np.testing.assert_allclose(np.unwrap(e.angle("g2")), np.unwrap(a.angle("g2")), atol=1e-7)
    np.testing.assert_allclose(e.omega("g2"), -0.5 * e.omega("g1"), atol=1e-8)
    assert np.unwrap(e.angle("g1"))[-1] - np.unwrap(e.angle("g1"))[0] > 4 * np.pi


def test_parameter_sensitivity_matches_angle_coordinates():
    out = {}
    for o in ("angle", "euler"):
        m = ms.Model2D(orientation=o)
        r = m.parameter("r", 2.0)
        L = m.parameter("L", 6.0)
        crank = m.add_body("crank", points={"pin": (r, 0)})
        rod = m.add_body("rod", points={"b": (L, 0)}, guess=((2, 0.5), -0.1))
        piston = m.add_body("piston", guess=((8, 0), 0))
        m.add(ms.Revolute2((0, 0), crank.point(0)), name="main")
        m.add(ms.Revolute2(crank.point("pin"), rod.point(0)), name="crank pin")
        m.add(ms.Revolute2(rod.point("b"), piston.point(0)), name="wrist pin")
        m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), piston.axis((0, 0), (1, 0))),
              name="slider")
        m.add(ms.RotationLock1(crank, 2 * sp.pi * T), name="drive")
        s = m.sensitivity(["L", "r"]).solve(np.linspace(0, 1, 7))
        out[o] = (s["L"].coordinate("piston.x"), s["r"].angle(rod), s["r"].omega(rod),
                  s["L"].alpha(rod))
    for a, e in zip(out["angle"], out["euler"]):
        assert np.abs(np.asarray(a) - np.asarray(e)).max() < 1e-9
    assert np.abs(out["angle"][0]).max() > 0.5          # d x_piston / dL is about 1


def _gen_models(orientation):
    """A Gen double pendulum (slave of a slave), a four-bar closed on a Gen chain with an
    absolute rocker, a Gen slide with a spring."""
    out = {}
    m = ms.Model2D(orientation=orientation)
    b1 = m.add_body("l1", points={"O": (0, 0), "P": (1.0, 0)}, mass=1.0, inertia=1 / 12,
                    centroid=(0.5, 0))
    b2 = m.add_body("l2", points={"P": (0, 0), "Q": (0.8, 0)}, mass=0.7,
                    inertia=0.7 * 0.64 / 12, centroid=(0.4, 0.05))
    m.add(ms.GenRevolute2(b1.axis("O"), m.ground.axis((0, 0)), ("phi1", 0.7)), name="j1")
    m.add(ms.GenRevolute2(b2.axis("P"), b1.axis("P"), ("phi2", -1.1)), name="j2")
    m.add_load(ms.Gravity((0, -1), 9.81))
    out["pendulum"] = m
    m = ms.Model2D(orientation=orientation)
    crank = m.add_body("crank", points={"o": (0, 0), "e": (1.0, 0)}, mass=1.0, inertia=0.1)
    coupler = m.add_body("coupler", points={"o": (0, 0), "e": (3.0, 0)}, mass=2.0, inertia=1.0)
    rocker = m.add_body("rocker", points={"o": (0, 0), "e": (2.5, 0)}, guess=((3.2, 0), 1.8),
                        mass=1.5, inertia=0.6)
    m.add(ms.GenRevolute2(crank.axis("o"), m.ground.axis((0, 0)), ("th", 0.5)), name="j1")
    m.add(ms.GenRevolute2(coupler.axis("o"), crank.axis("e"), ("phi", 0.5)), name="j2")
    m.add(ms.Revolute2(rocker.point("o"), m.ground.point((3.2, 0))), name="j4")
    m.add(ms.Revolute2(coupler.point("e"), rocker.point("e")), name="close")
    m.add(ms.Constraint(sp.Symbol("th") - 0.5 - 2 * ms.T), name="drive")
    m.add_load(ms.Gravity((0, -1), 9.81))
    out["four_bar"] = m
    m = ms.Model2D(orientation=orientation)
    u = (np.cos(0.5), np.sin(0.5))
    cart = m.add_body("cart", points={"o": (0, 0)}, mass=2.0, inertia=0.05, centroid=(0.1, 0.05))
    m.add(ms.GenTranslate2(cart.axis("o"), m.ground.axis((0, 0), u), ("s", 0.25)), name="slide")
    m.add_load(ms.Spring(cart.point("o"), m.ground.point((-u[0], -u[1])), stiffness=40.0,
                         free_length=1.0))
    m.add_load(ms.Gravity((0, -1), 9.81))
    out["slide"] = m
    return out


def test_gen_joints_in_euler_parameters_match_angle_coordinates():
    """Gen joints in Euler coordinates: the slave's (ei, ej) are the master's turned by the
    joint angle (the Gen coordinate counts the turns). Free motion of the Gen double
    pendulum and slide, the driven four-bar closed on a Gen chain (positions to
    accelerations, inverse-dynamic reactions) all as in angle coordinates."""
    A, E = _gen_models("angle"), _gen_models("euler")
    t = np.linspace(0.0, 2.0, 21)
    for name, names in (("pendulum", ("phi1", "phi2")), ("slide", ("s",))):
        a = A[name].free().simulate(t, rtol=1e-11, atol=1e-13)
        e = E[name].free().simulate(t, rtol=1e-11, atol=1e-13)
        assert E[name].compile().n == len(names)           # as many coordinates as DOF
        for k in names:
            np.testing.assert_allclose(e[k], a[k], atol=1e-8)
    b = "l2"
    np.testing.assert_allclose(np.unwrap(e.angle("cart")), np.unwrap(a.angle("cart")), atol=1e-12)
    pa = A["pendulum"].free().simulate(t, rtol=1e-11, atol=1e-13)
    pe = E["pendulum"].free().simulate(t, rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(np.unwrap(pe.angle(b)), np.unwrap(pa.angle(b)), atol=1e-8)
    np.testing.assert_allclose(pe.omega(b), pa.omega(b), atol=1e-7)
    a = A["four_bar"].solve(t, solution="dynamic")
    e = E["four_bar"].solve(t, solution="dynamic")
    for k in (0, 1, 2):
        np.testing.assert_allclose(e.coordinate("rocker.x", k), a.coordinate("rocker.x", k),
                                   atol=1e-9)
    np.testing.assert_allclose(e.alpha("coupler"), a.alpha("coupler"), atol=1e-8)
    for c, body in (("close", "rocker"), ("j4", "rocker")):
        Fa, Ma = a.reaction(c, body)
        Fe, Me = e.reaction(c, body)
        np.testing.assert_allclose(np.asarray(Fe), np.asarray(Fa), rtol=1e-8, atol=1e-8)
        np.testing.assert_allclose(np.asarray(Me), np.asarray(Ma), rtol=1e-8, atol=1e-8)


def test_recursive_gen_dynamics_in_euler_parameters():
    """Eight Gen links (the recursive dynamics' range, decision 0016): the same free motion
    in both orientations; the recursion sizes each pose by the space (4 coordinates here)."""
    from mechsys.compile._generalized import RecursiveDynamics

    out = {}
    for o in ("angle", "euler"):
        m = ms.Model2D(orientation=o)
        master = m.ground
        for k in range(8):
            b = m.add_body(f"l{k}", points={"o": (0, 0), "e": (1.0, 0)}, mass=1.0,
                           inertia=1 / 12, centroid=(0.5, 0))
            axis = master.axis((0, 0)) if k == 0 else master.axis("e")
            m.add(ms.GenRevolute2(b.axis("o"), axis, (f"a{k}", 0.1 * (k + 1))), name=f"j{k}")
            master = b
        m.add_load(ms.Gravity((0, -1), 9.81))
        free = m.free()
        assert isinstance(free.system.dynamics, RecursiveDynamics)
        out[o] = free.simulate(np.linspace(0.0, 0.5, 6), rtol=1e-10, atol=1e-12)
    for k in range(8):
        np.testing.assert_allclose(out["euler"][f"a{k}"], out["angle"][f"a{k}"], atol=1e-8)


def test_vibration_modes_match_angle_coordinates():
    """m.vibration in Euler coordinates: the perturbation of a body's rotation is a small
    global angle, ``d(ei, ej) = (-ej, ei) dtheta``; the frequencies, damping ratios and mode
    shapes (as angles) are those of the angle model."""
    out = {}
    for o in ("angle", "euler"):
        m = ms.Model2D(orientation=o)
        b1 = m.add_body("link1", points={"O": (0, 0), "P": (1.0, 0)}, mass=1.0,
                        inertia=1 / 12, centroid=(0.5, 0), guess=((0, 0), -1.4))
        b2 = m.add_body("link2", points={"P": (0, 0), "Q": (0.8, 0)}, mass=0.7,
                        inertia=0.7 * 0.64 / 12, centroid=(0.4, 0.05),
                        guess=((np.cos(-1.4), np.sin(-1.4)), -1.7))
        m.add(ms.Revolute2(m.ground.point((0, 0)), b1.point("O")), name="O")
        m.add(ms.Revolute2(b1.point("P"), b2.point("P")), name="P")
        m.add(ms.RotationLock1(b1, -1.4), name="hold1")
        m.add(ms.RotationLock1(b2, -1.7), name="hold2")
        m.add_load(ms.Gravity((0, -1), 9.81))
        m.add_load(ms.Damper(m.body("link1").point("P"), m.ground.point((2.0, -1.0)),
                             damping=0.3))
        eq = m.free(drop=["hold1", "hold2"], solution="static").solve()
        out[o] = (m, m.vibration(at=eq, drop=["hold1", "hold2"]))
    (ma, a), (me, e) = out["angle"], out["euler"]
    assert a.stable and len(a.hz) == 2 and np.all(a.damping_ratio > 0)
    np.testing.assert_allclose(e.hz, a.hz, rtol=1e-8)
    np.testing.assert_allclose(e.damping_ratio, a.damping_ratio, rtol=1e-7, atol=1e-10)
    ia = [ma.compile().layout.q_names.index(f"{b}.th") for b in ("link1", "link2")]
    for k in range(2):
        sa, se = a.shape(k), e.shape(k)
        q = e.q
        names = list(me.compile().layout.q_names)
        th = []
        for b in ("link1", "link2"):
            i, j = names.index(f"{b}.ei"), names.index(f"{b}.ej")
            th.append(q[i] * se[j] - q[j] * se[i])       # dtheta = ei dej - ej dei
        va, ve = np.asarray(sa)[ia], np.asarray(th)
        scale = va[np.argmax(np.abs(va))] / ve[np.argmax(np.abs(va))]
        np.testing.assert_allclose(ve * scale, va, rtol=1e-7, atol=1e-9)


def test_centrifugal_pendulum_in_a_rotating_frame_in_euler_parameters():
    """The rotating-frame linearisation (frame velocities ``d(ei, ej)/dt = w (-ej, ei)``):
    the centrifugal pendulum absorber swings at ``W sqrt(R / l)``, as in angles."""
    from test_vibration import centrifugal_pendulum

    R, l, W = 0.3, 0.08, 50.0
    m = centrifugal_pendulum(R, l, W, orientation="euler")
    modes = m.vibration(at=m.guess(), rotating=(W, (0, 0)))
    assert modes.omega == pytest.approx([W * np.sqrt(R / l)], rel=1e-9)
    assert modes.qd[m.compile().layout.index("pend.ej")] == pytest.approx(W)
