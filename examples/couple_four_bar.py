"""Four-bar design with couples (Mech's SetCouple/SolveCouple), checked against Freudenstein.

Ground pivots O2 = (0, 0) and O4 = (d, 0); crank a = 1 driven at th2 = T, coupler b, rocker
c. Freudenstein's equation

    K1 cos(th4) - K2 cos(th2) + K3 = cos(th2 - th4),
    K1 = d / a,  K2 = d / c,  K3 = (a^2 - b^2 + c^2 + d^2) / (2 a c),

is linear in K2 and K3, so the coupler and rocker lengths that put the rocker at th4_i for
crank angles th2_i (two precision positions) come from a 2x2 linear solve. We find them with
a two-configuration couple, then a one-parameter couple, a velocity couple and the time at
which the rocker reaches an angle, and tabulate the rocker length over target angles with
mechsys.sweep.

Run: ``python examples/couple_four_bar.py``
"""

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T

a, d = 1.0, 4.0


def four_bar():
    m = ms.Model2D()
    b = m.parameter("b", 4.0)
    c = m.parameter("c", 3.0)
    m.parameter("target", 1.7)
    crank = m.add_body("crank", points={"A": (a, 0)})
    coupler = m.add_body("coupler", points={"A": (0, 0), "B": (b, 0)}, guess=((a, 0), 0.9))
    rocker = m.add_body("rocker", points={"B": (c, 0)}, guess=((d, 0), 1.8))
    m.add(ms.Revolute2((0, 0), crank.point(0)), name="O2")
    m.add(ms.Revolute2(crank.point("A"), coupler.point("A")), name="A")
    m.add(ms.Revolute2(coupler.point("B"), rocker.point("B")), name="B")
    m.add(ms.Revolute2((d, 0), rocker.point(0)), name="O4")
    m.add(ms.RotationLock1(crank, T), name="drive")
    return m


def rocker_length(m):
    """The rocker length that puts the rocker at the parameter ``target`` at th2 = 0.8."""
    return m.couple(unknowns=["c"], conditions=sp.Eq(m.angle("rocker"), sp.Symbol("target")),
                    t=0.8).solve()


def freudenstein_residual(th2, th4, b, c):
    K1, K2, K3 = d / a, d / c, (a**2 - b**2 + c**2 + d**2) / (2 * a * c)
    return K1 * np.cos(th4) - K2 * np.cos(th2) + K3 - np.cos(th2 - th4)


if __name__ == "__main__":
    m = four_bar()
    rocker, coupler = m.body("rocker"), m.body("coupler")

    # two precision positions: (th2, th4) = (0.5, 1.80), (1.5, 1.89)
    th2s, th4s = np.array([0.5, 1.5]), np.array([1.80, 1.89])
    cm = m.couple(unknowns=["b", "c"], configurations=[
        ms.Configuration(sp.Eq(m.angle(rocker), th4s[k]), t=th2s[k]) for k in range(2)])
    res = cm.solve()
    K2, K3 = np.linalg.solve(np.column_stack((-np.cos(th2s), np.ones(2))),
                             np.cos(th2s - th4s) - d / a * np.cos(th4s))
    c_lin = d / K2
    b_lin = np.sqrt(a**2 + c_lin**2 + d**2 - 2 * a * c_lin * K3)
    print(f"two positions: b = {res['b']:.12f} (linear solve {b_lin:.12f}), "
          f"c = {res['c']:.12f} (linear solve {c_lin:.12f}); {res.iterations} iterations")
    assert abs(res["b"] - b_lin) < 1e-10 and abs(res["c"] - c_lin) < 1e-10

    # one parameter: the rocker reaches 1.7 rad at th2 = 0.8
    one = rocker_length(m)
    print(f"rocker at 1.7 rad for th2 = 0.8: c = {one['c']:.12f}, Freudenstein residual "
          f"{freudenstein_residual(0.8, 1.7, 4.0, one['c']):+.1e}")
    assert abs(freudenstein_residual(0.8, 1.7, 4.0, one["c"])) < 1e-12

    # velocity couple: the rocker turns at 0.3 rad/s there (crank at 1 rad/s)
    vel = m.couple(unknowns=["c"], conditions=sp.Eq(m.omega(rocker), 0.3), t=0.8).solve()
    print(f"rocker speed 0.3 rad/s at th2 = 0.8: c = {vel['c']:.9f}, "
          f"omega4 = {vel.configurations[0].omega(rocker):.12f}")

    # time as an unknown (Mech's Time -> Free)
    when = m.couple(unknowns=[], conditions=sp.Eq(m.angle(rocker), 1.7), t=ms.Free(0.8)).solve()
    print(f"with c = 3 the rocker is at 1.7 rad at T = th2 = {when['T']:.12f}, Freudenstein "
          f"residual {freudenstein_residual(when['T'], 1.7, 4.0, 3.0):+.1e}")

    # a sweep: the rocker length over target angles (serial; executor= a process pool or Dask)
    try:
        df = ms.sweep(four_bar, {"target": [1.6, 1.7, 1.8, 1.9]}, rocker_length)
    except ms.MechError as err:      # pandas missing
        print(f"sweep skipped: {err}")
    else:
        print(df.to_string(index=False))
        for th4, c in zip(df["target"], df["c"]):
            assert abs(freudenstein_residual(0.8, th4, 4.0, c)) < 1e-10
