"""Spline cam profiles inside constraint equations: compile and sweep cost of the candidate
representations of docs/decisions/0008-curves.md, on a cam sweep of 1,000 points.

Model: a disk cam (body ``cam``, pinned at the origin, driven at one revolution per second)
whose profile is the body point ``r(a) (cos a, sin a)`` with ``r`` a closed cubic spline
through ``N`` samples of ``2 + 0.3 sin(3a)``; a radial translating point follower
(``follower``, sliding along the global x axis) touches the profile, ``a`` being a new
variable (the general ``Constraint``: 2 equations, 1 variable). The follower's lift, velocity
and acceleration are checked against the spline's own derivatives.

Representations:

* ``piecewise`` -- what mechsys does: ``Piecewise`` of cubics nested as a binary search,
  derived in SymEngine and compiled with LLVM;
* ``piecewise-flat`` -- the same pieces in one flat ``Piecewise`` (linear search);
* ``piecewise/sympy`` -- the nested ``Piecewise`` through SymPy derivation and SymPy
  ``lambdify`` (what mechsys did before SymEngine was allowed ``Piecewise``); not run at 361
  knots, where its compile had not finished after 150 s;
* ``function`` -- option (a): a SymPy ``Function`` per component with ``fdiff`` returning
  the derivative spline and a NumPy implementation (``_imp_``) for ``lambdify``; SymEngine
  cannot compile it, so derivation and compile go through SymPy.

Also printed: the slider-crank sweep per point (the issue's speed target), and the accuracy
of the truncated-power form ``p(u) + sum c_k (u - u_k)_+^3`` (option (c)'s piecewise-free
rewriting) against the local form.

Run: ``PYTHONPATH=src .venv/bin/python benchmarks/curves.py [--quick]``. Times are CPU time
(``time.process_time``), best of 3 sweeps.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import sympy as sp  # noqa: E402
from _machine import machine  # noqa: E402

import mechsys as ms  # noqa: E402
from mechsys import T, models  # noqa: E402
from mechsys.compile import _derive  # noqa: E402
from mechsys.geometry._curves import SplineFunction  # noqa: E402

clock = time.process_time


class _FlatSpline(SplineFunction):
    def _bisect(self, w, lo, hi, j):
        pieces = []
        for k in range(lo, hi):
            a0, a1, a2, a3 = (sp.Float(float(c)) for c in self.coefficients[:, k, j])
            h = w - sp.Float(float(self.knots[k]))
            cond = w < sp.Float(float(self.knots[k + 1])) if k < hi - 1 else True
            pieces.append((a0 + h * (a1 + h * (a2 + h * a3)), cond))
        return sp.Piecewise(*pieces)


def _function_form(spline: SplineFunction):
    """Option (a): callable giving SymPy Function objects with exact ``fdiff``."""
    classes: dict = {}

    def make(order: int):
        if order not in classes:
            def imp(u, _o=order):
                return spline.derivative(np.asarray(u, dtype=float), _o)

            def fdiff(self, argindex=1, _o=order):
                return make(_o + 1)(self.args[0])

            classes[order] = type(f"spline_d{order}", (sp.Function,),
                                  {"fdiff": fdiff, "_imp_": staticmethod(imp)})
        return classes[order]

    return lambda u: make(0)(u)


def _profile(n_knots: int, kind: str):
    a = np.linspace(0, 2 * np.pi, n_knots)
    rad = 2 + 0.3 * np.sin(3 * a)
    cls = _FlatSpline if kind == "piecewise-flat" else SplineFunction
    spline = cls(rad, "closed", knots=a)
    form = _function_form(spline) if kind == "function" else spline
    return spline, form


def cam_model(form):
    m = ms.Model2D()
    g = m.ground
    cam = m.add_body("cam", guess=((0, 0), 0))
    fol = m.add_body("follower", guess=((2.0, 0), 0))
    a = sp.Symbol("a")
    r = form(a)
    prof = cam.point((r * sp.cos(a), r * sp.sin(a)))
    m.add(ms.Revolute2(g.point((0, 0)), cam.point(0)), name="cam pin")
    m.add(ms.RotationLock1(cam, 2 * sp.pi * T), name="drive")
    m.add(ms.Translate2(g.axis((0, 0), (1, 0)), fol.axis((0, 0), (1, 0))), name="slide")
    loc = m.location(prof)
    x, y, _ = fol.q
    m.add(ms.Constraint([x - loc[0], y - loc[1]], {a: 0.0}), name="contact")
    return m


def run(kind: str, n_knots: int, points: int) -> dict:
    spline, form = _profile(n_knots, kind)
    saved = _derive.se
    if kind in ("piecewise/sympy", "function"):
        os.environ["MECHSYS_BACKEND"] = "sympy"
        _derive.se = None                      # SymPy derivation, as before this change
    try:
        m = cam_model(form)
        t0 = clock()
        system = m.compile()
        _ = (system.f_position, system.f_velocity, system.f_gamma)
        t1 = clock()
        t = np.linspace(0, 1, points)
        best = np.inf
        for _ in range(3):
            s0 = clock()
            sol = m.solve(t)
            best = min(best, clock() - s0)
    finally:
        _derive.se = saved
        os.environ.pop("MECHSYS_BACKEND", None)
    # follower at x = r(-theta) = r(2 pi - 2 pi t): velocity -2 pi r', acceleration 4 pi^2 r''
    u = 2 * np.pi - 2 * np.pi * t
    err = max(np.max(np.abs(sol.coordinate("follower.x", k) - c * spline.derivative(u, k)))
              / max(1.0, np.max(np.abs(c * spline.derivative(u, k))))
              for k, c in ((0, 1.0), (1, -2 * np.pi), (2, 4 * np.pi**2)))
    return {"kind": kind, "knots": n_knots, "backend": system.f_position.backend,
            "compile_s": t1 - t0, "per_point_us": best / points * 1e6, "rel_error": err}


def slider_crank(points: int) -> float:
    m = models.slider_crank()
    system = m.compile()
    _ = (system.f_position, system.f_velocity, system.f_gamma)
    t = np.linspace(0, 1, points)
    best = np.inf
    for _ in range(3):
        s0 = clock()
        m.solve(t)
        best = min(best, clock() - s0)
    return best / points * 1e6


def truncated_power_error(n_knots: int) -> float:
    """Max error of ``p(u) + sum_k c_k (u - u_k)_+^3`` (the spline written without pieces,
    c_k = jump of s''' / 6) against the local form, relative to max |s|, on a natural spline
    through smooth data."""
    u = np.linspace(0, 2 * np.pi, n_knots)
    s = SplineFunction(2 + 0.3 * np.sin(3 * u), "natural", knots=u)
    c = s.coefficients[:, :, 0]
    jumps = np.diff(6 * c[3]) / 6               # change of a3 at the interior knots
    uu = np.linspace(0, 2 * np.pi, 2001)
    p = c[0, 0] + (uu - u[0]) * (c[1, 0] + (uu - u[0]) * (c[2, 0] + (uu - u[0]) * c[3, 0]))
    tp = p + sum(j * np.maximum(uu - uk, 0) ** 3 for j, uk in zip(jumps, u[1:-1]))
    return float(np.max(np.abs(tp - s(uu))) / np.max(np.abs(s(uu))))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    points = 200 if args.quick else 1000
    print(machine())
    print(f"\nslider-crank sweep: {slider_crank(points):.0f} µs per point ({points} points)\n")
    print("| profile form | knots | backend | compile [s] | per point [µs] | max rel. error |")
    print("| --- | ---: | --- | ---: | ---: | ---: |")
    kinds = ("piecewise", "piecewise-flat", "piecewise/sympy", "function")
    for n in ((37,) if args.quick else (37, 361)):
        for kind in kinds:
            if kind == "piecewise/sympy" and n > 100:
                print(f"| {kind} | {n} | sympy | > 150 (stopped) | | |")
                continue
            r = run(kind, n, points)
            print(f"| {r['kind']} | {r['knots']} | {r['backend']} | {r['compile_s']:.2f} | "
                  f"{r['per_point_us']:.0f} | {r['rel_error']:.1e} |")
    print("\ntruncated-power form, max error relative to max |s| (float64):")
    for n in (37, 361, 3601):
        print(f"  {n} knots: {truncated_power_error(n):.1e}")


if __name__ == "__main__":
    main()
