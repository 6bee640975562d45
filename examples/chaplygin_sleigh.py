r"""The Chaplygin sleigh: a body on a knife edge in free motion, against its closed form.

A planar body (mass ``MASS``, moment of inertia ``INERTIA`` about its centroid ``G``) slides on
a knife edge at the point ``P``, a distance ``a = OFFSET`` behind ``G`` on the body's ``x``
axis: ``P`` may not move across the body (``Orthogonal1`` of ``m.velocity(P)`` and the body's
``y`` direction, a velocity constraint kept by ``m.free()``: decision 0053). It is pushed into
a spin ``w0`` and left alone.

With the forward speed ``u`` of ``P`` along the body and the angular velocity ``w``, Newton's
law along and across the body (the edge's force is across it) gives ``u' = a w^2`` and
``(I + m a^2) w' = -m a u w``. The energy ``E = m u^2 / 2 + J w^2 / 2``, ``J = I + m a^2``, is
conserved, so from ``u(0) = 0``::

    u(t) = U tanh(k t),   w(t) = w0 sech(k t),   U = |w0| sqrt(J / m),   k = a |w0| sqrt(m / J)

(Neimark and Fufaev, *Dynamics of Nonholonomic Systems*, ch. III; Bloch, *Nonholonomic
Mechanics and Control*, sec. 1.7; docs/nonholonomic.md). The heading integrates to
``theta(t) = theta0 + (w0 / k) gd(k t)`` (``gd`` the Gudermannian, ``2 atan(tanh(x / 2))``):
the sleigh turns through ``(pi / 2) w0 / k = (pi / 2) sqrt(J / m) / a`` in all and runs off in
a straight line at the speed ``U``. The edge's path is the integral of ``u (cos theta, sin
theta)`` (a quadrature of the closed form, here with SciPy). The edge's lateral force (the
multiplier ``mu``) is Newton's ``m (u w + a w')`` across the body.

Run: python examples/chaplygin_sleigh.py
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mechsys as ms

MASS, INERTIA, OFFSET, W0 = 2.0, 0.3, 0.4, 2.0
START = ((0.1, -0.2), 0.3)                      # the centroid and heading at the start


def sleigh():
    """The sleigh model and its body (``tests/test_free_nonholonomic.py`` uses it too)."""
    m = ms.Model2D()
    b = m.add_body("sleigh", points={"P": (-OFFSET, 0.0)}, guess=START, mass=MASS,
                   inertia=INERTIA)
    # the knife edge at P: no velocity across the body's x axis
    m.add(ms.Orthogonal1(m.velocity(b.point("P")), b.vector((0, 1))), name="knife")
    return m, b


def closed_form(t):
    """``(u, w, theta, P)`` of the closed form at the times ``t`` (``P`` by quadrature)."""
    J = INERTIA + MASS * OFFSET**2
    U, k = W0 * np.sqrt(J / MASS), OFFSET * W0 * np.sqrt(MASS / J)
    theta = START[1] + (W0 / k) * 2 * np.arctan(np.tanh(k * t / 2))
    P0 = np.array(START[0]) - OFFSET * np.array([np.cos(START[1]), np.sin(START[1])])

    def along(s, _):
        th = START[1] + (W0 / k) * 2 * np.arctan(np.tanh(k * s / 2))
        return U * np.tanh(k * s) * np.array([np.cos(th), np.sin(th)])

    P = solve_ivp(along, (t[0], t[-1]), P0, t_eval=t, rtol=1e-12, atol=1e-14).y.T
    return U * np.tanh(k * t), W0 / np.cosh(k * t), theta, P


def main() -> None:
    m, b = sleigh()
    free = m.free()
    print(free)
    t = np.linspace(0, 5, 101)
    sol = free.simulate(t, initial_condition={"th2_d": W0}, rtol=1e-10, atol=1e-12)
    u_cf, w_cf, th_cf, P_cf = closed_form(t)
    th, w = sol["sleigh.th"], sol.omega(b)
    vP = sol.velocity(b.point("P"))
    u = vP[:, 0] * np.cos(th) + vP[:, 1] * np.sin(th)
    P = sol.location(b.point("P"))
    F = MASS * (u * w + OFFSET * sol.qdd[:, 2])          # Newton across the body
    mu = sol.extra["mu"][:, 0]
    E = 0.5 * MASS * (sol.qd[:, 0]**2 + sol.qd[:, 1]**2) + 0.5 * INERTIA * w**2
    d = {"spin w": np.abs(w - w_cf).max(), "speed u": np.abs(u - u_cf).max(),
         "heading": np.abs(th - th_cf).max(), "edge path": np.abs(P - P_cf).max(),
         "lateral force": np.abs(-mu - F).max() / np.abs(F).max(),
         "energy (relative)": np.ptp(E) / E[0]}
    J = INERTIA + MASS * OFFSET**2
    turn = np.pi / 2 * np.sqrt(J / MASS) / OFFSET
    print(f"turns through {th[-1] - th[0]:.6f} rad in 5 s; in all (pi/2) sqrt(J/m)/a = "
          f"{turn:.6f} rad")
    for k, v in d.items():
        print(f"largest difference from the closed form, {k:18s}: {v:.1e}")
    print(f"no-slip residual (relative): {sol.extra['accuracy']['nonholonomic']:.1e}")
    assert max(d.values()) < 1e-8, d

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    ax[0].plot(P[:, 0], P[:, 1], lw=2, label="knife edge P (mechsys)")
    ax[0].plot(P_cf[::4, 0], P_cf[::4, 1], "k.", ms=3, label="closed form")
    G = sol.location(b.point(0))
    ax[0].plot(G[:, 0], G[:, 1], lw=1, label="centroid G")
    for i in range(0, len(t), 10):                   # the sleigh: a wedge from P to the nose
        c, s = np.cos(th[i]), np.sin(th[i])
        pts = np.array([[-OFFSET, -0.12], [0.35, 0.0], [-OFFSET, 0.12], [-OFFSET, -0.12]])
        xy = G[i] + pts @ np.array([[c, s], [-s, c]])
        ax[0].fill(xy[:, 0], xy[:, 1], alpha=0.3, color="C3")
    ax[0].set_aspect("equal")
    ax[0].set_xlabel("x [m]")
    ax[0].set_ylabel("y [m]")
    ax[0].set_title("the sleigh's path (every 0.5 s)")
    ax[0].legend(fontsize=8)
    ax[1].plot(t, w, label="spin w [rad/s]")
    ax[1].plot(t, u, label="forward speed u [m/s]")
    ax[1].plot(t[::4], w_cf[::4], "k.", ms=3, label="closed form")
    ax[1].plot(t[::4], u_cf[::4], "k.", ms=3)
    ax[1].set_xlabel("t [s]")
    ax[1].set_title("w0 sech(k t) and U tanh(k t)")
    ax[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig("chaplygin_sleigh.png", dpi=80)


if __name__ == "__main__":
    main()
