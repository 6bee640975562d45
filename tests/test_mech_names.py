"""Mech names completed for issue 34 (docs/mech_to_mechsys.md): PolarToXY, PointToLocal,
VectorToLocal, VelocityTerms, AccelerationTerms, TimeInterpolate, ArcLength,
ClearParameters, Reaction's Point / All / list / parameter forms, and Centrifugal's identity.
Each against a closed form or an identity of the equations."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T
from mechsys.models import slider_crank, slider_crank_dynamic

R, L = 2.0, 6.0


@pytest.fixture(scope="module")
def crank_solution():
    m = slider_crank(R, L)
    t = np.linspace(0.0, 1.0, 41)
    return m, m.solve(t)


def _piston_x(t):
    th = 2 * np.pi * t
    return R * np.cos(th) + np.sqrt(L**2 - (R * np.sin(th)) ** 2)


def test_polar_to_xy_numeric_and_symbolic():
    np.testing.assert_allclose(ms.polar_to_xy((2.0, np.pi / 6)), [np.sqrt(3), 1.0], rtol=1e-15)
    pts = ms.PolarToXY([[1.0, 0.0], [2.0, np.pi / 2], [3.0, np.pi]])
    np.testing.assert_allclose(pts, [[1, 0], [0, 2], [-3, 0]], atol=1e-15)
    r, a = sp.symbols("r a")
    assert sp.simplify(ms.polar_to_xy((r, a)) - sp.Matrix([r * sp.cos(a), r * sp.sin(a)])) == \
        sp.zeros(2, 1)
    with pytest.raises(ms.ModelError, match="radius, angle"):
        ms.polar_to_xy((1.0, 2.0, 3.0))


def test_point_and_vector_to_local(crank_solution):
    m, sol = crank_solution
    crank, rod, piston = (m.body(n) for n in ("crank", "rod", "piston"))
    th = 2 * np.pi * sol.t
    # a point of the body itself: its own local coordinates, at every time
    np.testing.assert_allclose(sol.point_to_local(rod, rod.point("b")),
                               np.tile([L, 0.0], (len(sol.t), 1)), atol=1e-12)
    # the piston's origin seen from the crank: R(-th) (x_p, 0)
    xp = _piston_x(sol.t)
    want = np.column_stack((np.cos(th) * xp, -np.sin(th) * xp))
    np.testing.assert_allclose(sol.point_to_local(crank, piston.point(0)), want, atol=1e-10)
    # ground's X axis in crank axes, and the symbolic form on the model
    np.testing.assert_allclose(sol.vector_to_local(crank, m.ground.vector((1, 0))),
                               np.column_stack((np.cos(th), -np.sin(th))), atol=1e-12)
    loc = m.point_to_local(crank, crank.point("pin"))
    assert sp.simplify(loc - sp.Matrix([R, 0])) == sp.zeros(2, 1)


def test_velocity_and_acceleration_terms_close_the_constraint_derivatives(crank_solution):
    m, sol = crank_solution
    # the driver th - 2 pi T: its velocity term is -2 pi, its acceleration term 0
    assert abs(float(m.velocity_terms("drive")[0]) + 2 * np.pi) < 1e-14
    np.testing.assert_allclose(sol.velocity_terms("drive")[:, 0], -2 * np.pi)
    np.testing.assert_allclose(sol.acceleration_terms("drive")[:, 0], 0.0, atol=1e-12)
    # J qd + velocity_terms = 0 and J qdd + acceleration_terms = 0 for every constraint
    J = sol.jacobian(ms.All, ms.All)
    vt, at = sol.velocity_terms(ms.All), sol.acceleration_terms(ms.All)
    assert vt.shape == at.shape == (len(sol.t), J.shape[1])
    np.testing.assert_allclose(np.einsum("kij,kj->ki", J, sol.qd) + vt, 0.0, atol=1e-9)
    np.testing.assert_allclose(np.einsum("kij,kj->ki", J, sol.qdd) + at, 0.0, atol=1e-8)
    # the rod-crank pin has a nonzero acceleration term (centripetal), -gamma of equations()
    eq = m.equations("crank-rod")
    assert sp.simplify(m.acceleration_terms("crank-rod") + eq.gamma) == sp.zeros(2, 1)


def test_time_interpolate_against_the_closed_form(crank_solution):
    m, sol = crank_solution
    piston = m.body("piston")
    tt = np.linspace(0.0, 1.0, 301)
    got = sol.time_interpolate(m.location(piston.point(0))[0], tt)
    assert np.abs(np.ravel(got) - _piston_x(tt)).max() < 2e-4        # cubic Hermite, h = 1/40
    np.testing.assert_allclose(np.ravel(sol.time_interpolate(T, tt)), tt, atol=1e-12)


def test_arc_length_of_a_point_path(crank_solution):
    m, sol = crank_solution
    crank, piston = m.body("crank"), m.body("piston")
    # the crank pin runs on a circle at constant speed: s = R 2 pi t
    s = sol.arc_length(crank.point("pin"))
    assert s.shape == sol.t.shape and s[0] == 0.0
    np.testing.assert_allclose(s, R * 2 * np.pi * sol.t, rtol=1e-6)
    # the piston goes out and back over one revolution: 2 strokes of 2 R
    assert abs(sol.arc_length(piston.point(0))[-1] - 4 * R) < 2e-3
    # positions only: the chords, a lower bound within the chord error
    loc = m.solve(sol.t, solution="location")
    chord = loc.arc_length(crank.point("pin"))[-1]
    assert 2 * np.pi * R * (1 - 1e-2) < chord < 2 * np.pi * R


def test_clear_parameters():
    m = ms.Model2D()
    k = m.parameter("k", 2.0)
    m.parameter("unused", 1.0)
    b = m.add_body("b", mass=1.0, guess=((1, 0), 0))
    m.add(ms.RelativeDistance1(m.ground.point((0, 0)), b.point(0), k), name="link")
    with pytest.raises(ms.ModelError, match=r"k by .*link"):
        m.clear_parameters()                      # all: k is still used, nothing removed
    assert set(m.parameters) == {"k", "unused"}
    with pytest.raises(ms.ModelError, match="unknown parameter"):
        m.clear_parameters("nope")
    m.clear_parameters("unused")
    assert set(m.parameters) == {"k"}


def _hanging_mass():
    """A mass on a massless link of parameter length L from the ground origin."""
    m = ms.Model2D()
    length = m.parameter("len", 1.5)
    b = m.add_body("bob", mass=2.0, guess=((0, -1.5), 0))
    m.add(ms.RelativeDistance1(m.ground.point((0, 0)), b.point(0), length), name="link")
    m.add(ms.RelativeX1(m.ground.point((0, 0)), b.point(0), 0.0), name="hold x")
    m.add(ms.RotationLock1(b, 0.0), name="hold angle")
    m.add_load(ms.Gravity((0, -1), 9.81))
    return m, b, length


def test_reaction_on_a_parameter_is_the_link_tension():
    m, b, length = _hanging_mass()
    sol = m.solve(0.0, solution="static")
    tension = sol.reaction("link", length)
    assert abs(float(tension) - 2.0 * 9.81) < 1e-9                 # m g: positive in tension
    assert abs(float(sol.reaction(ms.All, length)) - float(tension)) < 1e-12
    # the force the link applies to the bob is m g upwards
    F, _ = sol.reaction("link", b)
    np.testing.assert_allclose(np.ravel(F), [0.0, 2.0 * 9.81], atol=1e-9)


def test_reaction_point_all_and_list_forms():
    m = slider_crank_dynamic(piston_force=5 * sp.sin(2 * sp.pi * T))
    sol = m.solve(np.linspace(0.0, 0.5, 6), solution="dynamic")
    rod = m.body("rod")
    # Reaction[cnum, Point[bnum, lpnt]] is the reaction on that body about that point
    F1, M1 = sol.reaction("wrist pin", rod.point("a"))
    F2, M2 = sol.reaction("wrist pin", rod, at=rod.point("a"))
    np.testing.assert_allclose(F1, F2)
    np.testing.assert_allclose(M1, M2)
    # a list sums, and All is the total reaction on the body, as Loads[b, Type -> Reaction]
    Fl, Ml = sol.reaction(["crank-rod", "wrist pin"], rod)
    Fa, Fb = sol.reaction("crank-rod", rod), sol.reaction("wrist pin", rod)
    np.testing.assert_allclose(Fl, Fa[0] + Fb[0], atol=1e-9)
    np.testing.assert_allclose(Ml, Fa[1] + Fb[1], atol=1e-9)
    FA, MA = sol.reaction(ms.All, rod)
    FL, ML = sol.loads(rod, type="reaction", coordinates="global")
    np.testing.assert_allclose(FA, FL, atol=1e-9)
    np.testing.assert_allclose(MA, ML, atol=1e-9)
    np.testing.assert_allclose(FA, Fl, atol=1e-9)                  # only two joints hold the rod
    with pytest.raises(ms.ModelError, match="empty"):
        sol.reaction([], rod)


def test_centrifugal_sign_against_the_dynamic_loads():
    # mechsys: dynamic = centrifugal - M qdd (= -(inertial load), so applied + reaction +
    # dynamic = 0); the manual's MassMatrix page writes Centrifugal + M . Acceleration
    m = slider_crank_dynamic()
    sol = m.solve(np.linspace(0.0, 0.5, 6), solution="dynamic")
    M = sol.mass_matrix()
    C = np.asarray(sol.centrifugal()).reshape(sol.qdd.shape)
    lhs = C - np.einsum("kij,kj->ki", M, sol.qdd)
    dyn = np.asarray(sol.loads(ms.All, type="dynamic")).reshape(sol.qdd.shape)
    np.testing.assert_allclose(lhs, dyn, atol=1e-9)
    total = sum(np.asarray(sol.loads(ms.All, type=k)).reshape(sol.qdd.shape)
                for k in ("applied", "reaction", "dynamic"))
    np.testing.assert_allclose(total, 0.0, atol=1e-8)
    assert np.abs(C).max() > 1.0      # the rod's and crank's spin matter here


def test_rotation_planar_forms():
    th = 2.5
    assert abs(ms.rotation((np.cos(th), np.sin(th))) - th) < 1e-15
    assert abs(ms.Rotation((3 * np.cos(th), 3 * np.sin(th))) - th) < 1e-15     # any scale
    A = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    assert abs(ms.rotation(A) - th) < 1e-15
    assert abs(float(ms.rotation(sp.Matrix(A))) - th) < 1e-15
    with pytest.raises(ms.GeometryError, match="not a 2 x 2 rotation"):
        ms.rotation(np.diag([1.0, -1.0]))                  # a reflection
    m = slider_crank(R, L)
    crank = m.body("crank")
    assert ms.rotation(crank) == crank.q[2]                # the planar body's angle symbol
    # the 3D forms are unchanged
    ang, axis = ms.rotation((np.pi / 2, (0, 0, 1)))
    assert abs(ang - np.pi / 2) < 1e-15 and np.allclose(axis, [0, 0, 1])


def test_composite_inertia_rotation_element():
    # a slender rod (m = 3, length 2) along the body's Y axis, given in its own axes (along x)
    m_, l_ = 3.0, 2.0
    own = (0.0, m_ * l_**2 / 12, m_ * l_**2 / 12)
    M, c, J = ms.composite_inertia([(m_, (0.0, 0.0, 0.0), own, (np.pi / 2, (0, 0, 1)))])
    np.testing.assert_allclose(J, [1.0, 0.0, 1.0, 0.0, 0.0, 0.0], atol=1e-12)
    # two such rods crossing at (1, 0, 0) and (-1, 0, 0): the parallel-axis sum by hand
    M, c, J = ms.CompositeInertia([(m_, (1.0, 0, 0), own), (m_, (-1.0, 0, 0), own, (0, 0, np.pi / 2))])
    assert M == 6.0 and np.allclose(c, 0.0)
    # Ixx: rod 1 (along x) 0 + 0; rod 2 (along y) 1 + 0; Iyy: 1 + 3 + 0 + 3; Izz: 1 + 3 + 1 + 3
    np.testing.assert_allclose(J, [1.0, 7.0, 8.0, 0.0, 0.0, 0.0], atol=1e-12)
    with pytest.raises(ValueError, match="planar part has no rotation"):
        ms.composite_inertia([(1.0, (0.0, 0.0), 0.5, 0.3)])
