"""Trajectory sensitivities of a rolling disk (3D, holonomic contact plus two no-slip rows)
against central differences of whole runs (decision 0055).

The disk of ``tests/test_free_nonholonomic.py`` (radius ``R = 0.3``, unit mass, lean 0.3
rad), started leaning, spinning at 5 rad/s, turning at -1 rad/s and with a lean rate of 0.5
rad/s, 1 s at rtol 1e-11; the sensitivities to the radius ``R`` (in the contact's
holonomic part and in the no-slip rows) and to gravity ``g`` (the loads). The finite
differences rerun the motion at ``p +- 1e-5 p`` (rtol 1e-12) from the same start state: a
start on the constraints at the nominal values, given as a state (nothing held), so that the
start projection of each run moves it by the same smallest change the sensitivities' start
takes. (With the angular velocity held instead, each run would keep that angular velocity
on the attitude its radius gives: a start the sensitivities, which hold nothing, do not
describe.)

This is not a unit test: the 3D tangent kernels take 8 to 17 s to compile on a loaded
two-core machine. The unit test is the sleigh's (tests/test_free_nonholonomic.py), against
its closed form and finite differences.

Run: ``PYTHONPATH=src .venv/bin/python benchmarks/nonholonomic_sensitivity.py`` (about 30 s).
"""

from __future__ import annotations

import time

import numpy as np

import mechsys as ms

BETA, SIGMA = 0.3, 5.0


def disk(R0: float = 0.3, g0: float = 9.81):
    m = ms.Model3D()
    R, g = m.parameter("R", R0), m.parameter("g", g0)
    sb, cb = np.sin(BETA), np.cos(BETA)
    d = m.add_body("disk", guess=((0, -R0 * sb, R0 * cb), (np.cos(BETA / 2), np.sin(BETA / 2),
                                                           0, 0)),
                   mass=1.0, inertia=(0.3**2 / 4, 0.3**2 / 2, 0.3**2 / 4))
    roll = ms.RollingDisk2(m.ground.axis((0, 0, 0), (0, 0, 1)), d.axis(0, (0, 1, 0)), R)
    m.add(roll.holonomic(), name="touch")
    m.add(roll, name="roll")
    m.add_load(ms.Gravity((0, 0, -1), g))
    return m


def main() -> None:
    m = disk()
    axis = np.array([0, np.cos(BETA), np.sin(BETA)])
    w = -1.0 * np.array([0, 0, 1.0]) + SIGMA * axis + 0.5 * np.array([1.0, 0, 0])
    start = m.free().solve(0.0, initial_condition={("omega", "disk"): w})
    t = np.linspace(0, 1.0, 11)
    t0 = time.perf_counter()
    S = m.sensitivity(["R", "g"], free=m.free()).simulate(t, initial_condition=start,
                                                          rtol=1e-11, atol=1e-13)
    print(f"sensitivity run (with the kernels' compilation): {time.perf_counter() - t0:.1f} s")
    for j, (name, v0) in enumerate((("R", 0.3), ("g", 9.81))):
        h = 1e-5 * v0
        runs = []
        for v in (v0 + h, v0 - h):
            m.set_parameters({name: v})
            runs.append(m.free().simulate(t, initial_condition=start, rtol=1e-12, atol=1e-14))
        m.set_parameters({name: v0})
        for what, got, fd in (("q", S.dq[:, j], runs[0].q - runs[1].q),
                              ("qd", S.dqd[:, j], runs[0].qd - runs[1].qd),
                              ("lambda, mu", S.dlam[:, j], runs[0].lam - runs[1].lam)):
            fd = fd / (2 * h)
            print(f"d/d{name:2s} {what:11s} largest difference {np.abs(got - fd).max():.1e} "
                  f"(largest value {np.abs(fd).max():.3g})")


if __name__ == "__main__":
    main()
