"""The IFToMM multibody benchmark's N-four-bar mechanism (problem A02), released under
gravity: a chain of N parallelogram loops whose links all become collinear twice per turn,
where the constraint Jacobian loses N ranks for an instant. Free motion passes through these
singular instants (see docs/robustness.md).

The exact motion has one degree of freedom: every crank turns by the same angle theta,
``a theta'' = -b g cos(theta)`` with ``a = (N + 1) / 3 + N`` and ``b = (N + 1) / 2 + N``
(energy of N + 1 cranks and N translating couplers). The script integrates both and prints
the largest difference of point B0's x and the energy error.

Run: python examples/n_four_bar.py [N] [t_end]
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


def main(n_loops: int = 2, t_end: float = 3.0) -> None:
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


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2,
         float(sys.argv[2]) if len(sys.argv) > 2 else 3.0)
