"""The cost of ``free.linearize`` once the model is built (issue 36 asks for under 50 ms).

Models: the double pendulum of docs/vibration.md (absolute coordinates, 6 coordinates, 4
constraint equations), the inverted pendulum on a cart with a force input and two outputs,
the sleeping top (3D, expression coordinates, a steady spin) and a chain of 10 pendulums
(30 coordinates, 20 equations), and the Whipple bicycle of examples/whipple_bicycle.py (4
bodies, 28 coordinates, 21 equations, 4 rolling rows; lean and steer, the others cyclic, at
5 m/s: decision 0054). ``first`` is the first call on a freshly built model (it
derives and compiles the exact derivatives: wall time), ``median`` and ``min`` the following
calls (wall time, 30 of them).

Run: ``.venv/bin/python benchmarks/linearize.py`` prints the table (about a minute).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import time  # noqa: E402

import numpy as np  # noqa: E402
import sympy as sp  # noqa: E402
from _machine import machine  # noqa: E402  (sibling module)

import mechsys as ms  # noqa: E402

G = 9.81


def chain(k: int):
    m = ms.Model2D()
    prev = m.ground.point((0, 0))
    for i in range(k):
        b = m.add_body(f"l{i}", points={"tip": (1.0, 0)}, mass=1.0, centroid=(0.5, 0),
                       inertia=0.1, guess=((0.0, -float(i)), -np.pi / 2))
        m.add(ms.Revolute2(prev, b.point(0)))
        prev = b.point("tip")
    m.add_load(ms.Gravity((0, -1), G))
    eq = m.free(solution="static").solve()
    return m.free(), (eq,), {}


def double_pendulum():
    free, args, kw = chain(2)
    return free, args, kw


def cart_pole():
    m = ms.Model2D()
    F = m.parameter("F", 0.0)
    cart = m.add_body("cart", mass=1.0, inertia=0.05)
    pole = m.add_body("pole", mass=0.3, centroid=(0.5, 0), inertia=0.01,
                      guess=((0, 0), np.pi / 2))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), cart.axis((0, 0), (1, 0))))
    m.add(ms.Revolute2(cart.point(0), pole.point(0)))
    m.add_load(ms.Gravity((0, -1), G))
    m.add_load(ms.Force(cart.point(0), (1, 0), F))
    return m.free(), (), dict(coordinates=["cart.x", "pole.th"], inputs=["F"],
                              outputs=["cart.x", "pole.th"])


def sleeping_top():
    m = ms.Model3D()
    top = m.add_body("top", mass=1.2, centroid=(0, 0, 0.1), inertia=(6e-3, 6e-3, 4e-3, 0, 0, 0))
    m.add(ms.Spherical3(m.ground.point((0, 0, 0)), top.point(0)))
    m.add_load(ms.Gravity((0, 0, -1), G))
    e0, _, _, e3 = top.q[3:]
    axis = top.point((0, 0, 1)).location()
    coords = [("tilt_x", axis[0]), ("tilt_y", axis[1]), ("spin", 2 * sp.atan2(e3, e0))]
    return m.free(), ({"top.e3_d": 60.0},), dict(coordinates=coords, cyclic=["spin"])


def bicycle():
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "whipple_bicycle", Path(__file__).resolve().parents[1] / "examples" / "whipple_bicycle.py")
    wb = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(wb)
    m, coords = wb.build()
    return m.free(), (wb.upright(5.0),), dict(coordinates=coords, cyclic=wb.CYCLIC,
                                              speeds=wb.SPEEDS)


def measure(build, repeat: int = 30):
    free, args, kw = build()
    t0 = time.perf_counter()
    lin = free.linearize(*args, **kw)
    first = time.perf_counter() - t0
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        free.linearize(*args, **kw)
        ts.append(time.perf_counter() - t0)
    return lin, first, float(np.median(ts)), float(np.min(ts))


def main() -> None:
    print(machine())
    print("| model | n | m | states | first [ms] | median [ms] | min [ms] |")
    print("|---|---|---|---|---|---|---|")
    for name, build in (("double pendulum", double_pendulum), ("cart-pole (1 input, 2 outputs)",
                        cart_pole), ("sleeping top (3D, steady spin)", sleeping_top),
                        ("chain of 10 pendulums", lambda: chain(10)),
                        ("Whipple bicycle (rolling, 5 m/s)", bicycle)):
        lin, first, med, low = measure(build)
        s = lin.model.free().system
        print(f"| {name} | {s.n} | {s.m} | {len(lin.states)} | {first * 1e3:.0f} | "
              f"{med * 1e3:.2f} | {low * 1e3:.2f} |")


if __name__ == "__main__":
    main()
