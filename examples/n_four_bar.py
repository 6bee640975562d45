"""The IFToMM multibody benchmark's N-four-bar mechanism (problem A02), released under
gravity: a chain of N parallelogram loops whose links all become collinear twice per turn,
where the constraint Jacobian loses N ranks for an instant. Free motion passes through these
singular instants (see docs/robustness.md).

The exact motion has one degree of freedom: every crank turns by the same angle theta,
``a theta'' = -b g cos(theta)`` with ``a = (N + 1) / 3 + N`` and ``b = (N + 1) / 2 + N``
(energy of N + 1 cranks and N translating couplers). The script integrates both and prints
the largest difference of point B0's x and the energy error.

Run: python examples/n_four_bar.py [N] [t_end] [picture.png]
"""

from __future__ import annotations

import sys

import numpy as np
from scipy.integrate import solve_ivp

from mechsys import models

G = 9.81


def simulate(n_loops: int = 2, t_end: float = 3.0, points: int = 121):
    """The free motion from the benchmark's start (cranks vertical, B0 moving at 1 m/s along
    +x) at ``points`` times on ``[0, t_end]``."""
    m = models.n_four_bar(n_loops, G)
    m.solve(0.0)
    free = m.free(drop=["hold"])
    t = np.linspace(0.0, t_end, points)
    return free.simulate(t, initial_condition={"crank0.th_d": -1.0})


def one_dof(n_loops: int, t: np.ndarray) -> np.ndarray:
    """theta(t) of the one-degree-of-freedom equation."""
    a, b = (n_loops + 1) / 3 + n_loops, (n_loops + 1) / 2 + n_loops
    sol = solve_ivp(lambda _, y: [y[1], -b * G / a * np.cos(y[0])], (0.0, float(t[-1])),
                    [np.pi / 2, -1.0], t_eval=t, method="DOP853", rtol=1e-12, atol=1e-12)
    return sol.y[0]


def main(n_loops: int = 2, t_end: float = 3.0, picture: str | None = None) -> None:
    sol = simulate(n_loops, t_end)
    th = one_dof(n_loops, sol.t)
    err = np.abs(sol.coordinate("coupler0.x") - np.cos(th)).max()
    a, b = (n_loops + 1) / 3 + n_loops, (n_loops + 1) / 2 + n_loops
    w = sol.coordinate("crank0.th", 1)
    E = 0.5 * a * w**2 + b * G * np.sin(sol.coordinate("crank0.th"))
    crossings = int(np.sum(np.diff(np.floor(-th / np.pi)) != 0))
    print(f"N = {n_loops}: {crossings} singular instants in {t_end} s, "
          f"max |x_B0 - exact| = {err:.2e} m, "
          f"max |E - E0| / E0 = {np.abs(E - E[0]).max() / E[0]:.2e}")
    if picture:
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 3.2))
        ax.plot(sol.t, sol.coordinate("coupler0.x"), label="mechsys, free motion")
        ax.plot(sol.t, np.cos(th), "--", label="exact one-DOF motion")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("x of B0 [m]")
        ax.set_title(f"N-four-bar, N = {n_loops}: through {crossings} singular instants")
        ax.legend()
        fig.tight_layout()
        fig.savefig(picture, dpi=80)


if __name__ == "__main__":
    # arguments: [N [t_end]] [picture.png]
    numbers = [a for a in sys.argv[1:] if not a.endswith((".png", ".svg", ".pdf"))]
    pictures = [a for a in sys.argv[1:] if a.endswith((".png", ".svg", ".pdf"))]
    main(int(numbers[0]) if numbers else 2, float(numbers[1]) if len(numbers) > 1 else 3.0,
         pictures[0] if pictures else None)
