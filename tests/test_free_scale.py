"""Free and path motion give the same relative accuracy in any unit of length (issue 10).

The same double pendulum is built in units where its links are ``s`` long and gravity is
``9.81 s``: the motion in time is then identical (sqrt(g / L) does not change), positions
scale by ``s`` and angles do not. Before the fix the projection tolerance and the
integrators' absolute tolerances were in the model's unit of length: at 1e6 the projection
could not reach 1e-12 (rounding), at 1e-6 it accepted errors a million times larger
relative to the mechanism than at 1.
"""

import numpy as np
import pytest

import mechsys as ms
from mechsys import T

SCALES = (1e-6, 1e-3, 1.0, 1e3, 1e6)


def double_pendulum(s, th=(0.3, 0.5)):
    m = ms.Model2D()
    a = m.add_body("a", points={"tip": (s, 0)}, mass=1.0, centroid=(s / 2, 0),
                   inertia=s**2 / 12, guess=((0, 0), th[0]))
    b = m.add_body("b", points={"tip": (s, 0)}, mass=1.0, centroid=(s / 2, 0),
                   inertia=s**2 / 12, guess=((s * np.cos(th[0]), s * np.sin(th[0])), th[1]))
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)), name="j0")
    m.add(ms.Revolute2(a.point("tip"), b.point(0)), name="j1")
    m.add(ms.RotationLock1(a, th[0]), name="lock0")
    m.add(ms.RotationLock1(b, th[1]), name="lock1")
    m.add_load(ms.Gravity((0, -1), 9.81 * s))
    m.solve(0.0)
    return m, m.free(drop=["lock0", "lock1"])


@pytest.mark.parametrize("method, options", [
    ("dop853", {"rtol": 1e-9, "atol": 1e-9}),
    ("dop853", {"max_error": 1e-8}),
    ("adams", {"max_error": 1e-5}),
])
def test_double_pendulum_is_the_same_in_any_unit(method, options):
    t = np.linspace(0, 1.0, 6)
    runs = {}
    for s in SCALES:
        m, free = double_pendulum(s)
        sol = free.simulate(t, method=method, **options)
        runs[s] = sol
        # the constraints hold to the same relative accuracy (Adams' output points are
        # Hermite interpolants between projected steps, hence the looser bound)
        tip = sol.location(m.body("a").point("tip")) - sol.location(m.body("b").point(0))
        assert np.abs(tip).max() / s < (1e-10 if method == "dop853" else 1e-7)
    ref = runs[1.0]
    for s, sol in runs.items():
        assert np.isclose(sol.extra["length_scale"] / s, ref.extra["length_scale"], rtol=1e-12)
        # same steps, same angles, positions scaled by s
        assert sol.extra["steps"] == ref.extra["steps"], (s, sol.extra["steps"])
        np.testing.assert_allclose(sol["a.th"], ref["a.th"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(sol["b.th"], ref["b.th"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(sol["b.x"] / s, ref["b.x"], rtol=0, atol=1e-9)


def caster(s):
    V, trail, th0 = s, 0.3 * s, np.pi - 0.05
    m = ms.Model2D()
    c = m.add_body("caster", points={"wheel": (trail, 0.0)}, guess=((0, 0), th0))
    m.add(ms.Revolute2(c.point(0), m.ground.point((-V * T, 0))), name="pivot")
    m.add(ms.RotationLock1(c, th0), name="dummy")
    m.solve(0.0)
    rolling = ms.Orthogonal1(m.velocity(c.point("wheel")), c.vector((0, 1)))
    return m.path(replace={"dummy": rolling})


def test_caster_path_is_the_same_in_any_unit():
    t = np.linspace(0, 1.0, 5)
    ref = caster(1.0).simulate(t, max_error=1e-9)
    closed = 2 * np.arctan(np.tan((np.pi - 0.05) / 2) * np.exp(-t / 0.3))
    for s in SCALES:
        sol = caster(s).simulate(t, max_error=1e-9)
        assert sol.extra["steps"] == ref.extra["steps"]
        np.testing.assert_allclose(sol["caster.th"], closed, rtol=0, atol=1e-7)
        assert sol.extra["drift"] / s < 1e-10


def test_static_equilibrium_is_the_same_in_any_unit():
    """A horizontal tip force equal to one link's weight holds the arm at the closed-form
    angles at every scale. Before: at 1e-6 the absolute tolerance accepted the unmoved guess;
    at 1e6 Newton could not reach it (rounding)."""
    ref = None
    for s in SCALES:
        m, _ = double_pendulum(s, th=(-1.0, -0.5))
        m.add_load(ms.Force(m.body("b").point("tip"), (1, 0), 9.81 * s))
        st = m.free(drop=["lock0", "lock1"], solution="static").solve(0.0)
        th = np.array([st["a.th"], st["b.th"]])
        if ref is None:
            ref = th
        np.testing.assert_allclose(th, ref, rtol=0, atol=1e-10)
    # balance (angles from +x, weights m g at the link centres, F = m g at the tip):
    # link b about the elbow: F s sin(-th_b) = m g (s/2) cos(th_b)  ->  tan(th_b) = -1/2
    # whole arm about the shoulder: F s (sin(-th_a) + sin(-th_b)) = m g (3 s/2 cos th_a
    #   + s/2 cos th_b)  ->  tan(th_a) = -3/2
    np.testing.assert_allclose(ref, [np.arctan(-1.5), np.arctan(-0.5)], atol=1e-10)
