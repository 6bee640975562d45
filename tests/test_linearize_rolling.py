"""Linearisation with velocity (nonholonomic) constraints (issue 36 item 3, decision 0054).

Closed form: a thin disk rolling upright at spin ``Omega`` (forward speed ``R Omega``) on a
plane, mass ``m``, moments of inertia ``I_a`` about its axle and ``I_d`` about a diameter.
The angular momentum balance about the contact point, linearised in the lean ``phi`` and the
heading rate ``psi'`` (derivation in docs/vibration.md, section *Velocity constraints*),

.. math::  (I_d + m R^2)\\,\\phi'' = (I_a + m R^2)\\,\\Omega\\,\\psi' + m g R\\,\\phi, \\qquad
           I_d\\,\\psi'' = -I_a\\,\\Omega\\,\\phi'

gives ``s = 0`` twice (a steady turn, the spin) and

.. math::  s^2 = -\\frac{I_a (I_a + m R^2)\\,\\Omega^2 / I_d - m g R}{I_d + m R^2}

(a uniform disk, ``I_a = m R^2 / 2``, ``I_d = m R^2 / 4``: ``s^2 = -4 (3\\Omega^2 - g/R)/5``, self-stable
above ``v^2 = g R / 3``; Neimark & Fufaev, *Dynamics of Nonholonomic Systems*, 1972, ch. V;
O'Reilly, Nonlinear Dynamics 10, 1996, 287-305). The whole ``A`` is also checked against
central differences of the nonlinear free motion (the Python stepper's right-hand side with
the velocity constraints) in the chosen coordinates and speeds.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys.analyses._linearize import _Chart
from mechsys.analyses._nonholonomic import nonholonomic_acceleration

R, G, MASS = 0.3, 9.81, 1.3
IA, ID = 0.6 * MASS * R**2, 0.3 * MASS * R**2      # not a uniform disk: both enter


def rolling_disk():
    m = ms.Model3D()
    disk = m.add_body("disk", guess=((0, 0, R), (1, 0, 0, 0)), mass=MASS, inertia=(ID, IA, ID))
    roll = ms.RollingDisk2(m.ground.axis((0, 0, 0), (0, 0, 1)), disk.axis(0, (0, 1, 0)), R)
    m.add(roll.holonomic(), name="touch")
    m.add(roll, name="roll")
    m.add_load(ms.Gravity((0, 0, -1), G))
    axle, d = disk.A[:, 1], disk.A[:, 0]
    forward = sp.Matrix([axle[1], -axle[0], 0])        # the heading, horizontal
    coords = ["disk.x", "disk.y", ("heading", sp.atan2(-axle[0], axle[1])),
              ("lean", sp.asin(axle[2])),
              ("spin", sp.atan2(forward.cross(d).dot(axle), forward.dot(d)))]
    return m, coords


CYCLIC = ["disk.x", "disk.y", "heading", "spin"]


def upright(spin):
    return {("omega", "disk"): (0.0, spin, 0.0), "disk.x_d": R * spin}


@pytest.fixture(scope="module")
def disk():
    m, coords = rolling_disk()
    return m, m.free(), coords


@pytest.mark.parametrize("spin", [2.0, 9.0])
def test_upright_rolling_disk_closed_form(disk, spin):
    m, fs, coords = disk
    lin = fs.linearize(upright(spin), coordinates=coords, cyclic=CYCLIC,
                       speeds=["lean", "heading", "spin"])
    assert lin.states == ("lean", "lean_d", "heading_d", "spin_d")
    assert lin.speeds == ("lean", "heading", "spin") and lin.A.shape == (4, 4)
    s2 = -(IA * (IA + MASS * R**2) * spin**2 / ID - MASS * G * R) / (ID + MASS * R**2)
    root = np.sqrt(complex(s2))
    s = lin.eigenvalues
    assert np.sort(np.abs(s))[:2] == pytest.approx([0, 0], abs=1e-12)
    big = s[np.argsort(np.abs(s))[2:]]
    assert np.sort_complex(big) == pytest.approx(np.sort_complex([root, -root]), rel=1e-10)
    # the lean/heading block of the closed form itself (states lean, lean', heading')
    Jc = ID + MASS * R**2
    assert lin.A[1, 0] == pytest.approx(MASS * G * R / Jc, rel=1e-10)
    assert lin.A[1, 2] == pytest.approx((IA + MASS * R**2) * spin / Jc, rel=1e-10)
    assert lin.A[2, 1] == pytest.approx(-IA * spin / ID, rel=1e-10)
    assert ("unstable" in lin.stability) == (s2 > 0)
    # the speeds chosen by QR (none named) give the same eigenvalues
    auto = fs.linearize(upright(spin), coordinates=coords, cyclic=CYCLIC)
    assert len(auto.speeds) == 3
    assert np.sort(np.abs(auto.eigenvalues))[2:] == pytest.approx(np.abs(big), rel=1e-10)


def _state_map(fs, coords, speeds, q0, qd0, p):
    """The nonlinear right-hand side ``(y, v) -> (y', v')`` of the free motion with the
    velocity constraints, in the chosen coordinates and speeds: positions by Newton on
    ``[Phi; h(q) - y] = 0``, velocities from ``[Phi_q; A; S h_q] qd = [0; -b; v]``,
    accelerations by the Python stepper's bordered solve."""
    system, rows = fs.system, fs._vrows
    lay = system.layout
    exprs = [lay.q_symbols[lay.index(c)] if isinstance(c, str) else c[1] for c in coords]
    chart = _Chart(system, exprs, [], ())
    names = [c if isinstance(c, str) else c[0] for c in coords]
    sel = [names.index(s) for s in speeds]
    n, m = system.n, system.m
    zeros_lam = np.zeros(m)

    def values(q, qd, qdd):
        return chart(0.0, q, qd, qdd, zeros_lam, p)

    y0 = values(q0, qd0, np.zeros(n))["y"]

    def rhs(y, v):
        q = q0.copy()
        for _ in range(30):
            ch = values(q, np.zeros(n), np.zeros(n))
            r = np.concatenate([system.residual(0.0, q, p), ch["y"] - y])
            dq = np.linalg.solve(np.vstack([system.jacobian(0.0, q, p), ch["hq"]]), -r)
            q = q + dq
            if np.abs(dq).max() < 1e-15:
                break
        H = values(q, np.zeros(n), np.zeros(n))["hq"]
        A, b, _ = rows.evaluate(0.0, q, np.zeros(n), p)
        K = np.vstack([system.jacobian(0.0, q, p), A, H[sel]])
        qd = np.linalg.solve(K, np.concatenate([np.zeros(m), -b, v]))
        qdd, _ = nonholonomic_acceleration(system, rows, 0.0, q, qd, p)
        ch = values(q, qd, qdd)
        return ch["yd"], ch["ydd"][sel]

    return y0, rhs


def test_state_matrix_against_central_differences_of_the_nonlinear_motion(disk):
    m, fs, coords = disk
    speeds = ["lean", "heading", "spin"]
    # a leaning, turning reference is not steady (checked below): the whole A is compared
    # on the steady upright motion, without dropping the cyclic positions
    lin = fs.linearize(upright(6.0), coordinates=coords, speeds=speeds)
    assert lin.states == ("disk.x", "disk.y", "heading", "lean", "spin", "lean_d",
                          "heading_d", "spin_d")
    y0, rhs = _state_map(fs, coords, speeds, np.array(lin.q), np.array(lin.qd), lin.p)
    # the reference speeds: lean and heading still, the spin 6 rad/s
    x0 = np.concatenate([y0, [0.0, 0.0, 6.0]])
    f0 = np.concatenate(rhs(x0[:5], x0[5:]))
    Afd = np.zeros((8, 8))
    for j in range(8):
        h = 1e-6
        xp, xm = x0.copy(), x0.copy()
        xp[j] += h
        xm[j] -= h
        Afd[:, j] = (np.concatenate(rhs(xp[:5], xp[5:])) - np.concatenate(rhs(xm[:5], xm[5:]))
                     ) / (2 * h)
    assert np.abs(f0[5:]).max() < 1e-12            # steady: the speeds do not change
    scale = np.abs(lin.A).max()
    assert np.abs(lin.A - Afd).max() < 1e-7 * scale


def test_not_steady_and_bad_speeds_are_named(disk):
    m, fs, coords = disk
    # leaning by 0.2 rad without the turn that balances it: the lean accelerates
    state = {"disk.e1": np.sin(0.1), ("omega", "disk"): (0.0, 6 * np.cos(0.2), 6 * np.sin(0.2))}
    with pytest.raises(ms.NotSteadyError, match="not a steady motion: acceleration of.*lean"):
        fs.linearize(state, coordinates=coords, cyclic=CYCLIC, speeds=["lean", "heading",
                                                                       "spin"])
    with pytest.raises(ms.ModelError, match="takes 3 speed"):
        fs.linearize(upright(6.0), coordinates=coords, speeds=["lean", "spin"])
    with pytest.raises(ms.ModelError, match="'roll' is not one of the chosen coordinates"):
        fs.linearize(upright(6.0), coordinates=coords, speeds=["lean", "spin", "roll"])
    # x and y rates are fixed by the spin and heading (no slip): not independent speeds
    with pytest.raises(ms.ModelError, match="not independent velocities"):
        fs.linearize(upright(6.0), coordinates=coords, speeds=["disk.x", "disk.y", "lean"])
    with pytest.raises(ms.ModelError, match="no velocity constraints"):
        m.free(drop=["roll"]).linearize(coordinates=coords, speeds=["lean"])
