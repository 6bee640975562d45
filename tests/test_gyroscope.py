"""Gyroscope (examples/gyroscope.py) against Euler's equations and the precession formula;
the three rotor models (spinning rotor, GyroMoment, GyroFilter) against each other."""

import numpy as np
import pytest

from conftest import load_example

gyro = load_example("gyroscope")


def test_base_free_accelerates_about_z():
    m, s = gyro.free_acceleration("rotor", ("base lock",))
    np.testing.assert_allclose(s.alpha("base"), [0, 0, gyro.MZ / gyro.I_T], atol=1e-9)


def test_gimbal_free_gyroscopic_coupling():
    rate = 2.0
    m, s = gyro.free_acceleration("rotor", ("base lock", "gimbal lock"), base_rate=rate)
    # the spinning rotor's momentum I_s w_s Y turned by rate Z needs -I_s w_s rate X: the free
    # gimbal accelerates about X with I_T alpha = I_s w_s rate
    np.testing.assert_allclose(s.alpha("gimbal")[0], gyro.I_S * gyro.FREQ * rate / gyro.I_T,
                               rtol=1e-10)


def test_steady_precession_rate():
    precession = gyro.MZ / (gyro.I_S * gyro.FREQ)          # Omega = M / (I_s w_s)
    m, s = gyro.free_acceleration("rotor", ("base lock", "gimbal lock"),
                                  gimbal_rate=precession)
    np.testing.assert_allclose(s.alpha("gimbal"), 0, atol=1e-9)
    np.testing.assert_allclose(s.alpha("base"), 0, atol=1e-9)
    # a neighbouring rate is not steady
    m, s2 = gyro.free_acceleration("rotor", ("base lock", "gimbal lock"),
                                   gimbal_rate=1.1 * precession)
    assert abs(s2.alpha("base")[2]) > 1e-3


def test_rotor_obeys_euler_equations():
    m, s = gyro.free_acceleration("rotor", ("base lock", "gimbal lock"), base_rate=1.5,
                                  gimbal_rate=0.7)
    rotor = m.body("rotor")
    w, a = s.omega(rotor), s.alpha(rotor)
    J = np.diag([gyro.I_T, gyro.I_S, gyro.I_T])          # aligned with global at t = 0
    moment = sum(np.asarray(s.reaction(c, rotor, at=(0, 0, 0))[1])
                 for c in ("rotor axis", "spin"))
    np.testing.assert_allclose(moment, J @ a + np.cross(w, J @ w), atol=1e-9)


def test_gyromoment_reproduces_rotor_reactions():
    drop = ("base lock", "gimbal lock")
    _, full = gyro.free_acceleration("rotor", drop, base_rate=1.0)
    _, gm = gyro.free_acceleration("gyromoment", drop, base_rate=1.0)
    np.testing.assert_allclose(gm.alpha("gimbal"), full.alpha("gimbal"), atol=1e-9)
    for c, body in (("base axis", "base"), ("gimbal axis", "gimbal")):
        for a, b in zip(gm.reaction(c, body), full.reaction(c, body)):
            np.testing.assert_allclose(a, b, atol=1e-9)


@pytest.fixture(scope="module")
def responses():
    return {k: gyro.free_response(k, 1.0, rtol=1e-10, atol=1e-12)
            for k in ("rotor", "gyromoment", "gyrofilter")}


def test_three_models_give_the_same_motion(responses):
    t = np.linspace(0, 1.0, 11)
    ref = responses["rotor"][2].interpolate(t)
    for kind in ("gyromoment", "gyrofilter"):
        sol = responses[kind][2].interpolate(t)
        np.testing.assert_allclose(gyro.base_angle(sol), gyro.base_angle(ref), atol=1e-6)
        for c in ("gimbal.e0", "gimbal.e1", "gimbal.e2", "gimbal.e3"):
            np.testing.assert_allclose(sol[c], ref[c], atol=1e-6)


def test_gyroscope_energy(responses):
    for kind, (_, _, sol) in responses.items():
        assert abs(gyro.energy_drift(sol)) < 1e-5, kind
