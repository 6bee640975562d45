"""The model factories of ``mechsys.models`` that the tests and benchmarks lean on: their
motion against closed forms, and their refusal of input that cannot make a mechanism."""

import numpy as np
import pytest

from mechsys import ModelError, models


def test_radial_engine_follows_the_slider_crank_closed_form():
    """Each cylinder of a 9-cylinder radial engine is a slider-crank whose crank angle is
    the engine's minus the cylinder's own: the piston's distance from the axis is
    ``c cos(phi) + sqrt(r^2 - c^2 sin(phi)^2)``, and its speed that expression's rate."""
    m = models.radial_engine(9, crank=1.5, rod=5.0, speed=3.0)
    t = np.linspace(0.0, 2.0, 41)
    sol = m.solve(t)
    assert sol.system.n == 57 and sol.system.m == 57
    for k in range(9):
        phi = 3.0 * t - 2 * np.pi * k / 9
        root = np.sqrt(25.0 - (1.5 * np.sin(phi)) ** 2)
        s = 1.5 * np.cos(phi) + root
        ds = -1.5 * np.sin(phi) * 3.0 * (1 + 1.5 * np.cos(phi) / root)
        x, y = sol.coordinate(f"piston{k}.x"), sol.coordinate(f"piston{k}.y")
        u = np.array([np.cos(2 * np.pi * k / 9), np.sin(2 * np.pi * k / 9)])
        np.testing.assert_allclose(x * u[0] + y * u[1], s, rtol=0, atol=1e-10)
        np.testing.assert_allclose(x * u[1] - y * u[0], 0.0, rtol=0, atol=1e-10)
        v = sol.coordinate(f"piston{k}.x", 1) * u[0] + sol.coordinate(f"piston{k}.y", 1) * u[1]
        np.testing.assert_allclose(v, ds, rtol=0, atol=1e-9)


@pytest.mark.parametrize("kw", [dict(cylinders=0), dict(cylinders=2.5), dict(cylinders=True),
                                dict(cylinders="9"), dict(crank=0.0), dict(crank=4.0),
                                dict(rod=float("nan")), dict(crank=-1.0)])
def test_radial_engine_refuses_what_cannot_be_an_engine(kw):
    args = dict(cylinders=5, crank=1.0, rod=4.0) | kw
    with pytest.raises(ModelError, match="radial_engine"):
        models.radial_engine(**args)


def test_trailer_train_rolls_its_tractor_on_the_closed_form_circle():
    """Three trailers behind a tractor steered at 0.5 rad/s at speed 1: the tractor's blade
    on the circle of radius 2, every trailer's blade without side slip, pins closed."""
    path = models.trailer_train(3, speed=1.0, rate=0.5, reach=2.0)
    m = path.model
    assert path.system.n == 12 and len(path.psi) == 5 and path.linear
    t = np.linspace(0.0, 4.0, 9)
    sol = path.simulate(t, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(sol.location(m.body("tractor").point("blade")),
                               np.c_[2 * np.sin(0.5 * t), 2 * (1 - np.cos(0.5 * t))], atol=1e-9)
    for k in range(3):
        v = sol.velocity(m.body(f"trailer{k}").point("blade"))
        th = sol.coordinate(f"trailer{k}.th")
        np.testing.assert_allclose(-v[:, 0] * np.sin(th) + v[:, 1] * np.cos(th), 0.0,
                                   atol=1e-9)
    assert sol.extra["drift"] < 1e-10


@pytest.mark.parametrize("kw", [{"trailers": -1}, {"trailers": 2.5}, {"trailers": True},
                                {"trailers": "3"}, {"speed": float("nan")}, {"rate": "fast"},
                                {"reach": 0.0}, {"reach": -1.0}, {"reach": float("inf")}])
def test_trailer_train_refuses_bad_input(kw):
    with pytest.raises(ModelError, match="trailer_train"):
        models.trailer_train(**({"trailers": 2} | kw))


@pytest.mark.parametrize("bad", [dict(links=0), dict(links=2.0), dict(links=True),
                                 dict(links=2, g=float("nan")), dict(links=2, g="9.81")])
def test_driven_gen_arm_refuses_bad_input(bad):
    with pytest.raises(ModelError, match="driven_gen_arm"):
        models.driven_gen_arm(**bad)


def test_driven_gen_arm_follows_its_drivers():
    """The joint angles are the drivers' closed form; the coordinates are the joint angles."""
    t = np.linspace(0.0, 1.0, 11)
    sol = models.driven_gen_arm(3).solve(t)
    assert sol.system.n == 3
    for k in range(3):
        np.testing.assert_allclose(sol[f"q{k}"], 0.3 * np.sin((k + 1) * t), rtol=0, atol=1e-12)
