"""Curves for cam and gear profiles: SplineFit / SplineFunction and Involute (issue 13).

Independent references: scipy's CubicSpline for the splines, the involute's own geometry
(radius rb sqrt(1 + u^2), polar angle u - atan u) for Involute, finite differences of the
solved sweep for the derivatives mechsys derives inside the constraint equations.
"""

import numpy as np
import pytest
import sympy as sp
from scipy.interpolate import CubicSpline

import mechsys as ms
from mechsys import T
from mechsys.compile import _derive, compile_exprs, time_derivative


def _data(n=12, d=2, seed=1, closed=False):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.2, 1.0, n))
    y = rng.normal(size=(n, d))
    if closed:
        y[-1] = y[0]
    return t, y


def _compiled_derivatives(expr_list, upto=2):
    """Compile exprs of T and their T-derivatives through mechsys' compile path."""
    exprs = list(expr_list)
    rows = [exprs]
    for _ in range(upto):
        rows.append([time_derivative(e, [], []) for e in rows[-1]])
    f = compile_exprs([T], [e for r in rows for e in r])
    return f, len(exprs)


# -- SplineFunction against scipy -------------------------------------------------------------

@pytest.mark.parametrize("bc", ["natural", "closed", "directions"])
def test_spline_matches_scipy_cubic_spline_with_two_derivatives(bc):
    t, y = _data(closed=bc == "closed")
    if bc == "directions":
        ends = ((1.0, -2.0), (0.5, 3.0))
        s = ms.SplineFit(y, ends, knots=t)
        ref = CubicSpline(t, y, bc_type=((1, np.array(ends[0])), (1, np.array(ends[1]))))
    else:
        s = ms.SplineFit(y, bc, knots=t)
        ref = CubicSpline(t, y, bc_type="natural" if bc == "natural" else "periodic")
    u = np.linspace(t[0], t[-1], 777)
    for order in range(3):
        np.testing.assert_allclose(s.derivative(u, order), ref(u, order), rtol=0, atol=1e-12)
    # the symbolic form, compiled as mechsys compiles constraint equations
    f, k = _compiled_derivatives(s(T))
    out = f.batch(u[:, None])
    for order in range(3):
        np.testing.assert_allclose(out[:, order * k:(order + 1) * k], ref(u, order), rtol=0,
                                   atol=1e-12)


def test_spline_reproduces_its_data_points_exactly():
    t, y = _data(n=9, d=3, closed=True)
    for bc in ("natural", "closed", "periodic"):
        s = ms.SplineFit(y, bc, knots=t)
        np.testing.assert_array_equal(s(t), y)
        np.testing.assert_array_equal(s(t[4]), y[4])
        # symbolic form at the knots: to rounding
        f, k = _compiled_derivatives(s(T), upto=0)
        np.testing.assert_allclose(f.batch(t[:, None]), y, rtol=0, atol=1e-14)


def test_default_knots_are_point_numbers_as_in_mech():
    pts = [(0.0, 0.0), (1.0, 2.0), (2.0, 0.0), (3.0, 1.0)]
    s = ms.SplineFit(pts)
    np.testing.assert_array_equal(s.knots, [0, 1, 2, 3])
    np.testing.assert_array_equal(s(1.0), pts[1])
    ref = CubicSpline(np.arange(4.0), np.array(pts), bc_type="natural")
    np.testing.assert_allclose(s(0.5), ref(0.5), atol=1e-15)   # halfway between points 1 and 2
    assert isinstance(s, ms.SplineFunction) and s.dim == 2 and not s.periodic


def test_scalar_spline_gives_one_expression_and_natural_ends_have_zero_curvature():
    a = np.linspace(0, np.pi, 7)
    r = ms.SplineFit(2 + np.sin(a), knots=a)
    assert r.scalar and isinstance(r(sp.Symbol("a")), sp.Piecewise)
    assert r(1.0).shape == ()
    np.testing.assert_allclose(r.derivative(np.array([0.0, np.pi]), 2), [0.0, 0.0], atol=1e-13)


def test_closed_spline_has_continuous_slope_and_curvature_and_repeats():
    t, y = _data(n=8, d=2, seed=3, closed=True)
    s = ms.SplineFit(y, "closed", knots=t)
    assert s.periodic and s.period == pytest.approx(t[-1] - t[0])
    for order in range(3):
        np.testing.assert_allclose(s.derivative(t[0], order), s.derivative(t[-1], order),
                                   atol=1e-12)
    u = np.linspace(t[0], t[-1], 50)
    f, k = _compiled_derivatives(s(T))
    here, later = f.batch(u[:, None]), f.batch((u + 3 * s.period)[:, None])
    np.testing.assert_allclose(later, here, atol=1e-11)


def test_c2_continuity_across_interior_knots():
    t, y = _data(n=10, d=2, seed=4)
    s = ms.SplineFit(y, knots=t)
    eps = 1e-9
    for order in range(3):
        left, right = s.derivative(t[1:-1] - eps, order), s.derivative(t[1:-1] + eps, order)
        np.testing.assert_allclose(left, right, atol=1e-6)
    # the third derivative does jump: it is a cubic spline, not a smoother curve
    assert np.max(np.abs(s.derivative(t[1:-1] - eps, 3) - s.derivative(t[1:-1] + eps, 3))) > 0.1


def test_closed_with_open_ends_follows_mech_equal_slope_and_curvature_only():
    t, y = _data(n=8, d=2, seed=5)          # last point differs from the first
    s = ms.SplineFit(y, "closed", knots=t)
    assert s.closed and not s.periodic
    np.testing.assert_array_equal(s(t[-1]), y[-1])
    for order in (1, 2):
        np.testing.assert_allclose(s.derivative(t[0], order), s.derivative(t[-1], order),
                                   atol=1e-12)


# -- derivatives inside constraint equations --------------------------------------------------

def _closed_profile():
    a = np.linspace(0, 2 * np.pi, 37)
    rad = 2 + 0.3 * np.sin(3 * a)
    return ms.SplineFit(np.column_stack([rad * np.cos(a), rad * np.sin(a)]), "closed", knots=a)


def test_body_following_a_closed_spline_of_time_has_the_spline_derivatives():
    prof = _closed_profile()
    m = ms.Model2D()
    b = m.add_body("b", guess=((2, 0), 0))
    x, y, th = b.q
    px, py = prof(2 * T)
    m.add(ms.Constraint([x - px, y - py, th]), name="follow")
    t = np.linspace(0, 7, 1401)            # 2T runs over more than two revolutions
    sol = m.solve(t)
    ref = [prof(2 * t), 2 * prof.derivative(2 * t, 1), 4 * prof.derivative(2 * t, 2)]
    for order in range(3):
        got = np.column_stack([sol.coordinate("b.x", order), sol.coordinate("b.y", order)])
        np.testing.assert_allclose(got, ref[order], rtol=0, atol=1e-11)
    # and against finite differences of the solved sweep itself
    dt = t[1] - t[0]
    pos = sol.coordinate("b.x")
    vel, acc = sol.coordinate("b.x", 1), sol.coordinate("b.x", 2)
    np.testing.assert_allclose((pos[2:] - pos[:-2]) / (2 * dt), vel[1:-1], atol=2e-3)
    # O(dt) where the third derivative jumps (the knots), O(dt^2) elsewhere
    np.testing.assert_allclose((vel[2:] - vel[:-2]) / (2 * dt), acc[1:-1], atol=0.1)
    # compiled by SymEngine (LLVM when built with it), not the SymPy fallback
    if "symengine" in ms.compile.available_backends():
        backends = {k.backend for k in sol.system._kernels.values()}
        assert backends and all(b.startswith("symengine") for b in backends), backends


def test_spline_of_a_new_variable_differentiates_through_the_jacobian():
    # y = f(s), x = s, x driven by c T: velocity f'(cT) c, acceleration f''(cT) c^2
    a = np.linspace(0, 4, 9)
    f = ms.SplineFit(np.sin(a) + 0.2 * a**2, knots=a)
    s = sp.Symbol("s")
    c = 0.7
    m = ms.Model2D()
    b = m.add_body("b", guess=((0.1, 0.1), 0))
    x, y, th = b.q
    m.add(ms.Constraint([x - s, y - f(s)], {s: 0.1}), name="on spline")
    m.add(ms.Constraint([x - c * T, th]), name="drive")
    t = np.linspace(0, 4 / c, 801)
    sol = m.solve(t)
    np.testing.assert_allclose(sol["b.y"], f(c * t), atol=1e-12)
    np.testing.assert_allclose(sol.coordinate("b.y", 1), c * f.derivative(c * t, 1), atol=1e-11)
    np.testing.assert_allclose(sol.coordinate("b.y", 2), c**2 * f.derivative(c * t, 2),
                               atol=1e-10)
    dt = t[1] - t[0]
    v = sol.coordinate("b.y", 1)
    np.testing.assert_allclose((sol["b.y"][2:] - sol["b.y"][:-2]) / (2 * dt), v[1:-1], atol=1e-3)


def test_symengine_derivation_drops_the_derivative_of_floor(monkeypatch):
    if _derive.se is None:
        pytest.skip("symengine not installed")
    q = [sp.Symbol("q1")]
    qd = [sp.Symbol("q1_d")]
    prof = _closed_profile()
    phi = [q[0] - prof(T + q[0] ** 2)[0]]
    assert _derive.symengine_safe(phi)
    rows, cols, _, _, _, native = _derive.derive_kinematics(phi, q, qd, T)
    exprs = native["jac"] + native["phi_t"] + native["gamma"]
    assert not any(e.has(sp.Derivative) for e in _derive.to_sympy_list(exprs))
    f = compile_exprs([T, *q, *qd], exprs)
    monkeypatch.setattr(_derive, "se", None)     # the SymPy path gives the same numbers
    _, _, jac, pt, gm, _ = _derive.derive_kinematics(phi, q, qd, T)
    g = compile_exprs([T, *q, *qd], jac + pt + gm, backend="sympy")
    X = np.array([[0.3, 0.4, -1.2], [7.5, 1.1, 0.8], [20.0, -0.6, 2.0]])
    np.testing.assert_allclose(f.batch(X), g.batch(X), rtol=1e-9, atol=1e-9)
    assert f.backend.startswith("symengine")


# -- Involute ---------------------------------------------------------------------------------

@pytest.mark.parametrize("rp", [1.3, -1.3])
def test_involute_points_satisfy_the_involute_equation(rp):
    u = sp.Symbol("u")
    rb, ang, c = 1.0, 0.4, (0.5, -0.2)
    x, y = ms.Involute(u, c, rb, rp, ang)
    f = sp.lambdify(u, [x, y])
    uu = np.linspace(0, 1.5, 31)
    px, py = (np.asarray(v) - ci for v, ci in zip(f(uu), c))
    # distance from the center: rb sqrt(1 + u^2) (the unwound string is tangent, length rb u)
    np.testing.assert_allclose(np.hypot(px, py), rb * np.sqrt(1 + uu**2), atol=1e-14)
    # polar angle advances by u - atan(u) (clockwise for a negative pitch radius)
    sgn = np.sign(rp)
    phase = np.unwrap(np.arctan2(py, px)) - sgn * (uu - np.arctan(uu))
    np.testing.assert_allclose(phase, phase[0], atol=1e-13)
    # i.e. about the center, rotated by beta = phase: x = rb (cos u + u sin u), ...
    beta = phase[0]
    lx = np.cos(beta) * px + np.sin(beta) * py
    ly = -np.sin(beta) * px + np.cos(beta) * py
    np.testing.assert_allclose(lx, rb * (np.cos(uu) + uu * np.sin(uu)), atol=1e-14)
    np.testing.assert_allclose(sgn * ly, rb * (np.sin(uu) - uu * np.cos(uu)), atol=1e-14)
    # the pitch point lies on the pitch circle, on the ray at `angle`
    up = np.sqrt(rp**2 / rb**2 - 1)
    pp = np.array(f(up)) - c
    np.testing.assert_allclose(np.hypot(*pp), abs(rp), atol=1e-14)
    np.testing.assert_allclose(np.arctan2(pp[1], pp[0]), ang, atol=1e-14)


def test_involute_with_interference_runs_straight_to_the_center():
    u = sp.Symbol("u")
    x, y = ms.Involute(u, (1.0, 2.0), 2.0, 2.5, 0.0, interference=True)
    f = compile_exprs([u], [x, y])
    p0 = f(np.array([0.0]))
    np.testing.assert_allclose(f(np.array([-1.0])), [1.0, 2.0], atol=1e-14)
    np.testing.assert_allclose(f(np.array([-0.5])), (np.array([1.0, 2.0]) + p0) / 2, atol=1e-14)
    # without it, negative u mirrors the tooth
    xm, ym = ms.Involute(u, (0, 0), 2.0, 2.5, 0.0)
    g = sp.lambdify(u, [xm, ym])
    a, b = np.array(g(0.7)), np.array(g(-0.7))
    np.testing.assert_allclose(np.hypot(*a), np.hypot(*b), atol=1e-14)


def test_involute_is_exact_inside_a_model():
    # a point body constrained to an involute of a variable u, driven along x: velocity and
    # acceleration from the derived Jacobian and gamma match finite differences
    u = sp.Symbol("u")
    ix, iy = ms.Involute(u, (0, 0), 1.0, 1.5, 0.3)
    m = ms.Model2D()
    b = m.add_body("b", guess=(tuple(float(v.subs(u, 0.5)) for v in (ix, iy)), 0))
    x, y, th = b.q
    m.add(ms.Constraint([x - ix, y - iy], {u: 0.5}), name="tooth")
    m.add(ms.Constraint([u - 0.5 - 0.3 * T**2, th]), name="drive")
    t = np.linspace(0, 1.5, 601)
    sol = m.solve(t)
    dt = t[1] - t[0]
    for name in ("b.x", "b.y"):
        p, v, a = (sol.coordinate(name, k) for k in range(3))
        np.testing.assert_allclose((p[2:] - p[:-2]) / (2 * dt), v[1:-1], atol=1e-5)
        np.testing.assert_allclose((v[2:] - v[:-2]) / (2 * dt), a[1:-1], atol=1e-4)


# -- bad input --------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, match", [
    (dict(data=[[0, 0], [1, 1], [2, 0]], knots=[0, 1, 1]),
     r"knots must be strictly increasing; knot 2 = 1.0 does not exceed knot 1 = 1.0"),
    (dict(data=[[0, 0], [1, 1], [2, 0]], knots=[0, 2, 1]), "strictly increasing"),
    (dict(data=[[0, 0], [1, 1], [2, 0]], knots=[0, 1]), r"one number per data point \(3\)"),
    (dict(data=[[0, 0]]), "open spline needs at least 2 data points, got 1"),
    (dict(data=[[0, 0], [0, 0]], end_conditions="closed"),
     "closed spline needs at least 3 data points, got 2"),
    (dict(data=[[0, 0], [1, 1], [2, 0]], end_conditions="periodic"),
     r"first point \[0.0, 0.0\] differs from the last \[2.0, 0.0\]"),
    (dict(data=[[0, 0], [1, np.nan], [2, 0]]), "not finite"),
    (dict(data=[[0, 0], [1, 1, 1], [2, 0]]), "rectangular"),
    (dict(data=[[0, 0], [1, 1], [2, 0]], end_conditions="clamped"), "end_conditions must be one of"),
    (dict(data=[[0, 0], [1, 1], [2, 0]], end_conditions=[(1, 0, 0), (1, 0, 0)]),
     "two vectors of dimension 2"),
])
def test_bad_spline_input_raises_model_error(kwargs, match):
    with pytest.raises(ms.ModelError, match=match):
        ms.SplineFit(**kwargs)


def test_spline_derivative_of_a_symbol_is_refused():
    s = ms.SplineFit([0.0, 1.0, 0.0])
    with pytest.raises(ms.ModelError, match="evaluates numbers"):
        s.derivative(sp.Symbol("u"))


@pytest.mark.parametrize("rb, rp, match", [
    (0.0, 1.0, "base radius must be positive, got 0.0"),
    (-1.0, 1.0, "base radius must be positive"),
    (1.0, 0.0, "pitch radius must be a nonzero number"),
    (1.0, 0.8, "pitch radius 0.8 is smaller than the base radius 1.0"),
    (1.0, -0.8, "smaller than the base radius"),
])
def test_bad_involute_radii_raise_model_error(rb, rp, match):
    with pytest.raises(ms.ModelError, match=match):
        ms.Involute(sp.Symbol("u"), (0, 0), rb, rp, 0)


def test_involute_accepts_symbolic_radii():
    rb, rp = sp.symbols("rb rp", positive=True)
    x, y = ms.Involute(sp.Symbol("u"), (0, 0), rb, rp, 0)
    val = x.subs({rb: 1, rp: 1.3, sp.Symbol("u"): np.sqrt(1.3**2 - 1)})
    num, _ = ms.Involute(sp.Symbol("u"), (0, 0), 1, 1.3, 0)
    assert float(val) == pytest.approx(float(num.subs(sp.Symbol("u"), np.sqrt(1.3**2 - 1))))


# -- floor's derivative, which periodic curves rely on ----------------------------------------

def test_saw_tooth_driver_of_a_scaled_time_solves():
    # Mod(2T, 1) -> 2T - floor(2T): SymPy's derivative is Subs(Derivative(floor(xi), xi), ..)
    # which used to survive as Subs(0, ..) and crash the compile (OverflowError in SymEngine)
    from mechsys import models

    m = models.slider_crank(drive=2 * sp.pi * sp.Mod(2 * T, 1))
    sol = m.solve([0.1, 0.6])
    np.testing.assert_allclose(sol["piston.x"][0], sol["piston.x"][1], atol=1e-12)
    np.testing.assert_allclose(sol.coordinate("crank.th", 1), [4 * np.pi, 4 * np.pi], atol=1e-12)


# -- compiling Piecewise profiles ---------------------------------------------------------------

def test_repeated_piecewise_compiles_once_and_agrees_with_sympy():
    from mechsys.compile import _backends

    if "symengine" not in _backends.available_backends():
        pytest.skip("symengine not installed")
    x, q = sp.symbols("x q")
    r = ms.SplineFit(np.array([1.0, 2.0, 0.5, 1.5, 1.0]), "closed")(x)
    exprs = [r * sp.cos(q), r * sp.sin(q) + r**2, q * r, q + 1,
             sp.Piecewise((q, x > 1), (-q, True))]
    pieces, reduced = _backends._split_piecewise([_backends._se.sympify(e) for e in exprs])
    # r (three times), r**2 (SymPy folds the power into the pieces) and the small one
    assert len(pieces) == 3
    assert not any(isinstance(e, _backends._se.Piecewise) for e in reduced)
    f = compile_exprs([x, q], exprs)
    g = compile_exprs([x, q], exprs, backend="sympy")
    X = np.array([[0.3, 0.4], [2.5, -1.0], [7.1, 2.0], [-3.3, 0.1]])
    np.testing.assert_allclose(f.batch(X), g.batch(X), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(f(X[1]), g(X[1]), rtol=1e-12, atol=1e-12)
    assert f.backend.startswith("symengine")
    once = compile_exprs([x, q], exprs, once=True)
    np.testing.assert_allclose(once.batch(X), g.batch(X), rtol=1e-12, atol=1e-12)
