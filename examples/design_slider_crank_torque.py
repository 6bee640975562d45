"""Slider-crank design: minimise the peak driving torque over a cycle at a given stroke, with
exact gradients of the inverse-dynamic torque from sensitivities (docs/design_optimisation.md).

Design variables: crank radius ``r``, rod length ``L`` and slider offset ``e``. The piston
works against a constant 300 N; the rod's mass and inertia grow with its length (a steel bar:
mass proportional to L, inertia to L^3), so a long rod lowers the kinematic torque but adds
inertia torque: the optimum is inside. The stroke of an offset slider-crank,

    s = sqrt((L + r)^2 - e^2) - sqrt((L - r)^2 - e^2),

is held at 0.1 m. The peak is minimised in epigraph form (SLSQP): minimise ``z`` subject to
``z >= tau_k`` and ``z >= -tau_k`` at every sampled crank angle ``k``, and ``s = 0.1``.
The script runs the same optimisation with finite-difference gradients and prints the table of
the tutorial page.
"""

import time

import numpy as np
from scipy.optimize import minimize

import mechsys as ms
from mechsys import T

OMEGA = 2 * np.pi * 5.0                      # 300 rpm
TIMES = np.linspace(0, 0.2, 25)[:-1]         # one revolution, every 15 degrees
STROKE = 0.1
NAMES = ["r", "L", "e"]
START = np.array([0.06, 0.30, 0.02])


def slider_crank():
    m = ms.Model2D()
    r, L, e = (m.parameter(k, v) for k, v in zip(NAMES, START))
    rho = 4.0 / 0.15                         # rod mass per length, kg/m
    crank = m.add_body("crank", points={"pin": (r, 0)}, mass=2.0, inertia=0.002)
    rod = m.add_body("rod", points={"b": (L, 0)}, mass=rho * L, centroid=(L / 2, 0),
                     inertia=rho * L**3 / 12, guess=((0.06, 0.02), -0.1))
    piston = m.add_body("piston", mass=1.0, guess=((0.35, 0.02), 0))
    m.add(ms.Revolute2((0, 0), crank.point(0)), name="main bearing")
    m.add(ms.Revolute2(crank.point("pin"), rod.point(0)), name="crank pin")
    m.add(ms.Revolute2(rod.point("b"), piston.point(0)), name="wrist pin")
    m.add(ms.Translate2(m.ground.axis((0, e), (1, 0)), piston.axis((0, 0), (1, 0))),
          name="slider")
    m.add(ms.RotationLock1(crank, OMEGA * T), name="drive")
    m.add_load(ms.Force(piston.point(0), (1, 0), -300.0))
    return m


def stroke(x):
    r, L, e = x[:3]
    return np.sqrt((L + r) ** 2 - e**2) - np.sqrt((L - r) ** 2 - e**2)


def stroke_gradient(x):
    r, L, e = x[:3]
    a, b = np.sqrt((L + r) ** 2 - e**2), np.sqrt((L - r) ** 2 - e**2)
    return np.array([(L + r) / a + (L - r) / b, (L + r) / a - (L - r) / b, -e / a + e / b, 0.0])


def optimise(exact: bool):
    m = slider_crank()
    sens = m.sensitivity(NAMES)
    count = {"solves": 0, "gradients": 0}
    memo: dict = {}

    def solve(x):
        key = tuple(x[:3])
        if key not in memo:                  # objective and constraints share one solve
            m.set_parameters(dict(zip(NAMES, x[:3])))
            memo.clear()
            memo[key] = m.solve(TIMES, solution="dynamic")
            count["solves"] += 1
        return memo[key]

    def torque(x):
        return solve(x).reaction("drive", "crank")[1]

    def torque_gradient(x):
        count["gradients"] += 1
        s = sens.of(solve(x))
        return np.column_stack([s[p].reaction("drive", "crank")[1] for p in NAMES])

    def peak_constraint(x):                  # z - tau >= 0 and z + tau >= 0
        tau = torque(x)
        return np.concatenate((x[3] - tau, x[3] + tau))

    def peak_jacobian(x):
        G = torque_gradient(x)
        ones = np.ones((len(TIMES), 1))
        return np.vstack((np.hstack((-G, ones)), np.hstack((G, ones))))

    cons = [{"type": "ineq", "fun": peak_constraint},
            {"type": "eq", "fun": lambda x: stroke(x) - STROKE}]
    if exact:
        cons[0]["jac"] = peak_jacobian
        cons[1]["jac"] = stroke_gradient
    x0 = np.concatenate((START, [np.abs(torque(np.concatenate((START, [0])))).max()]))
    bounds = [(0.02, 0.1), (0.12, 0.6), (-0.05, 0.05), (0, None)]
    start = time.perf_counter()
    res = minimize(lambda x: x[3], x0, jac=(lambda x: np.array([0, 0, 0, 1.0])) if exact else None,
                   method="SLSQP", bounds=bounds, constraints=cons,
                   options={"ftol": 1e-10, "maxiter": 200})
    seconds = time.perf_counter() - start
    peak = np.abs(torque(res.x)).max()
    return res, peak, count, seconds, np.abs(torque(np.concatenate((START, [0])))).max()


def main():
    rows = []
    results = []
    for exact in (True, False):
        res, peak, count, seconds, peak0 = optimise(exact)
        assert res.success, res.message
        assert abs(stroke(res.x) - STROKE) < 1e-8
        results.append(res.x)
        rows.append((("exact (sensitivity)" if exact else "finite differences"), res.nit,
                     count["solves"], count["gradients"], seconds, peak0, peak, res.x))
    # both reach the same design
    assert np.allclose(results[0][:3], results[1][:3], rtol=1e-4, atol=1e-6), results
    print("| gradients | SLSQP iterations | model solves | sensitivity solves | time (s) | "
          "start peak (N m) | optimal peak (N m) | r, L, e (m) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for name, nit, solves, grads, sec, p0, peak, x in rows:
        print(f"| {name} | {nit} | {solves} | {grads} | {sec:.2f} | {p0:.3f} | {peak:.4f} | "
              f"{x[0]:.4f}, {x[1]:.4f}, {x[2]:.4f} |")


if __name__ == "__main__":
    main()
