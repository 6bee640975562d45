r"""A rolling coin: free rolling of a thin disk on a plane under gravity (nonholonomic dynamics).

A coin (a thin uniform disk of radius ``R`` and mass ``M``: moments ``I_a = M R^2 / 2`` about
its axis and ``I_d = M R^2 / 4`` about a diameter) touches the ground plane
(``roll.holonomic()``) and rolls on it without slipping (``RollingDisk2``, a velocity
constraint kept by ``m.free()``: decision 0053). Nothing drives it; it moves under gravity
from its start. The script checks three things.

**Angles and the minimal equations.** The heading ``psi`` turns the rolling direction
``e1 = (cos psi, sin psi, 0)`` about the vertical ``z``; the lean ``theta`` tilts the disk
about ``e1``, so that its axis is ``e2 = cos(theta) h + sin(theta) z`` (``h = z x e1``) and
``e3 = e1 x e2 = cos(theta) z - sin(theta) h`` points from the contact ``P`` to the centre
``G = P + R e3`` (a positive lean tilts the coin to the right of its rolling direction). The
frame ``(e1, e2, e3)`` turns at ``Omega = psi' z + theta' e1``; the disk at
``omega = Omega + phi' e2``, with the spin about its axis ``s = omega . e2 = phi' + psi'
sin(theta)``. No slip gives ``v_G = omega x (R e3) = R s e1 - R theta' e2`` and the contact
point runs along the heading at ``P' = R phi' e1``. Euler's law about ``G`` with the contact
force ``F = M a_G + M g z`` (Newton), ``dH/dt = -R e3 x F``, in the frame ``(e1, e2, e3)``
(``H = (I_d theta', I_a s, I_d psi' cos(theta))``) gives the three equations (derived here;
they are the classical equations of the rolling disk, e.g. O'Reilly, *Nonlinear Dynamics* 10,
1996, with its angles)::

    (I_d + M R^2) theta'' = -I_d psi'^2 sin(theta) cos(theta)
                            + (I_a + M R^2) psi' s cos(theta) + M g R sin(theta)
    (I_a + M R^2) s'      = -M R^2 psi' theta' cos(theta)
    I_d cos(theta) psi''  = 2 I_d psi' theta' sin(theta) - I_a theta' s

**(i) Steady turning.** With ``theta' = 0``, constant lean, spin and turning rate
``psi' = W``, the first equation is the steady-turning relation of the thin disk::

    I_d sin(theta) cos(theta) W^2 - (I_a + M R^2) s cos(theta) W - M g R sin(theta) = 0

(a quadratic in ``W``: for a given lean and spin the coin turns slowly towards its lean, the
root used here, or fast the other way) and the contact point runs on a circle of radius
``R (s - W sin(theta)) / W``. The turning rate is also solved from a guess with mechsys
alone (the rate at which its free acceleration of the lean vanishes, by the secant method on
``free.solve``), and the coin started on it keeps lean, spin and turning rate.

**(ii) Free rolling** from a start that is not steady (leaning, rolling straight, a lean rate):
the coin wobbles and turns. The script integrates the three equations above with SciPy's
``solve_ivp`` (its own code, in the angles, with the contact point integrated) and compares
the contact point, the centre, the axis and the spin with mechsys's motion.

**(iii) Over 10 s** the energy (kinetic plus potential) is conserved and the constraints hold
at position and velocity level; the script prints the numbers.

Run: python examples/rolling_coin.py
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.optimize import newton

import mechsys as ms

R, M, G = 0.1, 0.2, 9.81                       # a large coin (a disk): m, kg, m/s^2
IA, ID = M * R**2 / 2, M * R**2 / 4
TOL = dict(rtol=1e-10, atol=1e-12)


def quaternion(theta, psi):
    """Euler parameters of the coin's attitude: lean ``theta`` about ``x`` (the local axis
    ``y`` tilts to ``(0, cos, sin)``), then the heading ``psi`` about ``z``."""
    a, b = np.array([np.cos(psi / 2), 0, 0, np.sin(psi / 2)]), \
        np.array([np.cos(theta / 2), np.sin(theta / 2), 0, 0])
    return (a[0] * b[0] - a[1:] @ b[1:], *(a[0] * b[1:] + b[0] * a[1:] + np.cross(a[1:], b[1:])))


def frame(theta, psi):
    """``(e1, e2, e3)`` of the docstring."""
    e1 = np.array([np.cos(psi), np.sin(psi), 0.0])
    h = np.array([-np.sin(psi), np.cos(psi), 0.0])
    e2 = np.cos(theta) * h + np.sin(theta) * np.array([0, 0, 1.0])
    return e1, e2, np.cross(e1, e2)


def build(theta, psi=0.0):
    """The coin leaning by ``theta`` with heading ``psi``, touching the plane ``z = 0`` at the
    origin; the coin's axis is its local ``y``."""
    m = ms.Model3D()
    e3 = frame(theta, psi)[2]
    coin = m.add_body("coin", guess=(tuple(R * e3), quaternion(theta, psi)), mass=M,
                      inertia=(ID, IA, ID))
    roll = ms.RollingDisk2(m.ground.axis((0, 0, 0), (0, 0, 1)), coin.axis(0, (0, 1, 0)), R)
    m.add(roll.holonomic(), name="touch")
    m.add(roll, name="roll")
    m.add_load(ms.Gravity((0, 0, -1), G))
    return m, coin, roll


def start(m, theta, theta_d, psi_d, spin):
    """Simulate-ready: the free system and the coin's angular velocity ``omega = theta' e1 +
    s e2 + psi' (z - sin(theta) e2)`` (the centre's velocity follows from no slip)."""
    e1, e2, _ = frame(theta, 0.0)
    w = theta_d * e1 + spin * e2 + psi_d * (np.array([0, 0, 1.0]) - np.sin(theta) * e2)
    return m.free(), {("omega", "coin"): w}


def angles(sol, coin):
    """Lean, heading (unwrapped), spin about the axis and the axis itself, from the solution."""
    e0, e1, e2, e3 = sol.q[:, 3:7].T
    axis = np.c_[2 * (e1 * e2 - e0 * e3), e0**2 - e1**2 + e2**2 - e3**2, 2 * (e2 * e3 + e0 * e1)]
    theta = np.arcsin(axis[:, 2])
    psi = np.unwrap(np.arctan2(-axis[:, 0], axis[:, 1]))
    spin = np.einsum("ij,ij->i", sol.omega(coin), axis)
    return theta, psi, spin, axis


def minimal_ode(t, theta0, theta_d0, psi_d0, spin0):
    """The docstring's three equations with SciPy, state ``(theta, theta', psi, psi', s, x_P,
    y_P)``; returns the solution's ``y`` at ``t`` (written without mechsys)."""
    def rhs(_, y):
        th, thd, psi, psid, s = y[:5]
        c, sn = np.cos(th), np.sin(th)
        thdd = (-ID * psid**2 * sn * c + (IA + M * R**2) * psid * s * c + M * G * R * sn) \
            / (ID + M * R**2)
        sd = -M * R**2 * psid * thd * c / (IA + M * R**2)
        psidd = (2 * ID * psid * thd * sn - IA * thd * s) / (ID * c)
        phid = s - psid * sn                          # the contact runs at R phi' along e1
        return [thd, thdd, psid, psidd, sd, R * phid * np.cos(psi), R * phid * np.sin(psi)]

    y0 = [theta0, theta_d0, 0.0, psi_d0, spin0, 0.0, 0.0]
    return solve_ivp(rhs, (t[0], t[-1]), y0, t_eval=t, method="DOP853", **TOL).y


def turning_rate_from_guess(theta, spin, guess):
    """The steady turning rate from mechsys's dynamics alone: the ``W`` at which the lean's
    acceleration vanishes when the coin leans by ``theta``, spins at ``spin`` and turns at
    ``W`` with no lean rate (``sin(theta)`` is the axis' ``z`` component ``a_z``, and at
    ``theta' = 0``, ``a_z'' = cos(theta) theta''``)."""
    m, coin, roll = build(theta)
    a_z = (coin.A * sp.Matrix([0, 1, 0]))[2]
    a_zdd = m.time_derivative(m.time_derivative(a_z))
    free = m.free()

    def lean_acceleration(W):
        _, ic = start(m, theta, 0.0, W, spin)
        return float(np.ravel(free.solve(0.0, initial_condition=ic).eval(a_zdd))[0]) \
            / np.cos(theta)

    return newton(lean_acceleration, guess, tol=1e-14)


def steady_turning(theta=0.3, spin=15.0):
    """(i): started on the steady relation; returns the largest deviations of lean, spin and
    turning rate, and the contact path with its closed-form circle radius."""
    W = min(np.roots([ID * np.sin(theta) * np.cos(theta), -(IA + M * R**2) * spin * np.cos(theta),
                      -M * G * R * np.sin(theta)]), key=abs).real
    m, coin, roll = build(theta)
    free, ic = start(m, theta, 0.0, W, spin)
    # one full turn
    sol = free.simulate(np.linspace(0, 2 * np.pi / abs(W), 61), initial_condition=ic, **TOL)
    th, psi, s, _ = angles(sol, coin)
    dev = (np.abs(th - theta).max(), np.abs(s - spin).max(), np.abs(psi - W * sol.t).max())
    c = sol.location(roll.contact_point())
    radius = R * (spin - W * np.sin(theta)) / W
    centre = c[0] + radius * np.array([0, 1.0, 0])       # (W < 0: a turn to the right)
    off = np.abs(np.linalg.norm(c[:, :2] - centre[:2], axis=1) - abs(radius)).max()
    return W, radius, dev, off, c, centre


def free_rolling(theta0=0.2, theta_d0=3.0, psi_d0=0.0, spin0=10.0, t_end=10.0):
    """(ii) and (iii): a non-steady start, mechsys against the minimal ODE over ``t_end``."""
    m, coin, roll = build(theta0)
    free, ic = start(m, theta0, theta_d0, psi_d0, spin0)
    t = np.linspace(0, t_end, 501)
    sol = free.simulate(t, initial_condition=ic, **TOL)
    th, psi, s, axis = angles(sol, coin)
    y = minimal_ode(t, theta0, theta_d0, psi_d0, spin0)
    P = np.c_[y[5], y[6], 0 * t]
    e = [frame(a, b) for a, b in zip(y[0], y[2])]
    G_ode = P + R * np.array([f[2] for f in e])
    c = sol.location(roll.contact_point())
    diff = {"contact point": np.abs(c - P).max() / R,
            "centre": np.abs(sol.location(coin.point(0)) - G_ode).max() / R,
            "axis": np.abs(axis - np.array([f[1] for f in e])).max(),
            "lean": np.abs(th - y[0]).max(), "spin": np.abs(s - y[4]).max() / spin0}
    E = sol.body_energy() + sol.potential_energy()
    acc = sol.extra["accuracy"]
    checks = {"energy drift (relative)": np.ptp(E) / E[0],
              "position (touch)": np.abs(sol.eval(m.constraint("touch").equations(m.space)[0]))
              .max() / R,
              "velocity (touch)": acc["velocity"], "no slip (A qd + b)": acc["nonholonomic"],
              "slip speed / R spin": np.abs(sol.eval(roll.slip_velocity())).max() / (R * spin0)}
    return sol, t, (th, psi, y), c, P, diff, checks


def main() -> None:
    W, radius, dev, off, c_steady, centre = steady_turning()
    W_solved = turning_rate_from_guess(0.3, 15.0, guess=-1.0)
    print(f"(i) steady turning at lean 0.3 rad, spin 15 rad/s: turning rate W = {W:.6f} rad/s "
          f"(closed form), contact circle radius {radius:.6f} m")
    print(f"    solved from the guess -1 rad/s with mechsys's free acceleration: W = "
          f"{W_solved:.12f} rad/s ({abs(W_solved - W):.1e} from the closed form)")
    print(f"    over one turn: lean held to {dev[0]:.1e} rad, spin to {dev[1]:.1e} rad/s, heading "
          f"to {dev[2]:.1e} rad; contact off the circle by {off:.1e} m")
    sol, t, (th, psi, y), c, P, diff, checks = free_rolling()
    print("(ii) free rolling over 10 s against the minimal equations (SciPy):")
    for k, v in diff.items():
        print(f"    {k:14s} largest difference {v:.1e}" + (" (relative to R)" if k in (
            "contact point", "centre") else ""))
    print("(iii) over 10 s:")
    for k, v in checks.items():
        print(f"    {k:26s} {v:.1e}")
    assert max(dev) < 1e-8 and off < 1e-8 and abs(W_solved - W) < 1e-10
    assert max(diff.values()) < 1e-6, diff
    assert max(checks.values()) < 1e-8, checks
    print(f"    {sol.extra['compiled_steps']} of {sol.extra['steps']} steps compiled "
          f"({sol.extra['compiled_solver']}: the compiled stepper holds the rolling rows)")

    fig, ax = plt.subplots(1, 3, figsize=(13, 4.2))
    a = np.linspace(0, 2 * np.pi, 200)
    ax[0].plot(c_steady[:, 0], c_steady[:, 1], lw=2, label="contact (mechsys)")
    ax[0].plot(centre[0] + abs(radius) * np.cos(a), centre[1] + abs(radius) * np.sin(a), "k--",
               lw=0.8, label="closed-form circle")
    ax[0].set_title("(i) steady turning: one turn")
    ax[1].plot(c[:, 0], c[:, 1], lw=1.2, label="contact (mechsys)")
    ax[1].plot(P[::4, 0], P[::4, 1], ".", ms=2.5, label="minimal equations (SciPy)")
    ax[1].set_title("(ii) free rolling, 10 s")
    for k in (0, 1):
        ax[k].plot(0, 0, "k+")
        ax[k].set_aspect("equal")
        ax[k].set_xlabel("x [m]")
        ax[k].set_ylabel("y [m]")
        ax[k].legend(fontsize=8, loc="center")
    k = t <= 3.0
    ax[2].plot(t[k], th[k], lw=1, label="mechsys")
    ax[2].plot(t[k][::2], y[0][k][::2], ".", ms=3, label="SciPy")
    ax[2].set_xlabel("t [s]")
    ax[2].set_ylabel("lean [rad]")
    ax[2].set_title("(ii) free rolling: the lean wobbles (first 3 s)")
    ax[2].legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig("rolling_coin.png", dpi=80)


if __name__ == "__main__":
    main()
