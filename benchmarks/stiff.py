"""Stiff free motion: the implicit method (``method="radau"``) against the explicit ones.

A slider on a spring and damper (mass 1, ``k``, ``c`` chosen so that the eigenvalues are
``-100`` and ``-k/100``: one slow and one fast decay) is released 1 mm from its free length
and run for 0.05 s, where the closed form is known; the stiffness ratio grows from 1e2 to
1e6. For each method: CPU time (``time.process_time``, best of 3 after a warm-up run that
compiles), accepted steps, evaluations of the free acceleration and the largest error
against the closed form. DOP853 is compiled; Radau runs in Python with SciPy's Radau IIA
(decision 0051).

``python benchmarks/stiff.py --write docs/free_motion.md`` replaces the section between
``<!-- stiff:begin -->`` and ``<!-- stiff:end -->`` in that page.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine  # noqa: E402

import mechsys as ms  # noqa: E402

BEGIN, END = "<!-- stiff:begin -->", "<!-- stiff:end -->"
T_END, X0 = 0.05, 1e-3


def slider(k: float, c: float):
    m = ms.Model2D()
    b = m.add_body("b", mass=1.0, inertia=0.1, guess=((1.0, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), b.axis((0, 0), (1, 0))))
    m.add_load(ms.Spring(m.ground.point((0, 0)), b.point(0), k, 1.0))
    m.add_load(ms.Damper(m.ground.point((0, 0)), b.point(0), c))
    return m.free(initial_guess={"b.x": 1.0 + X0}, initial_condition={"b.x_d": 0.0})


def run(ratio: float, method: str, rtol: float) -> dict:
    fast = 100.0 * ratio                  # eigenvalues -100 and -fast
    k, c = 100.0 * fast, 100.0 + fast
    free = slider(k, c)
    kw = dict(method=method, rtol=rtol, atol=rtol * 1e-3)
    free.simulate((0, T_END), **kw)       # compiles, fills the caches
    best, sol = np.inf, None
    for _ in range(3):
        t0 = time.process_time()
        sol = free.simulate((0, T_END), **kw)
        best = min(best, time.process_time() - t0)
    s1, s2 = -100.0, -fast
    a = np.linalg.solve([[1.0, 1.0], [s1, s2]], [X0, 0.0])
    exact = 1.0 + a[0] * np.exp(s1 * sol.t) + a[1] * np.exp(s2 * sol.t)
    return {"ratio": ratio, "method": method, "rtol": rtol, "cpu": best,
            "steps": sol.extra["steps"], "evaluations": sol.extra["evaluations"],
            "error": float(np.abs(sol["b.x"] - exact).max())}


def table(rows: list[dict]) -> str:
    out = [BEGIN, "",
           "<!-- Written by `python benchmarks/stiff.py --write docs/free_motion.md`; rerun "
           "it rather than editing. -->", "",
           f"Measured on: {machine()}.", "",
           "| stiffness ratio | method | rtol | CPU [s] | steps | evaluations | error [m] |",
           "| ---: | --- | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        out.append(f"| {r['ratio']:.0e} | {r['method']} | {r['rtol']:.0e} | {r['cpu']:.4f} | "
                   f"{r['steps']} | {r['evaluations']} | {r['error']:.1e} |")
    out += ["", END]
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", metavar="PATH", help="replace the marked section of PATH")
    args = ap.parse_args()
    rows = [run(ratio, method, 1e-8) for ratio in (1e2, 1e4, 1e6)
            for method in ("dop853", "radau")]
    text = table(rows)
    print(text)
    if args.write:
        page = Path(args.write)
        old = page.read_text()
        if BEGIN not in old:
            raise SystemExit(f"{page} has no {BEGIN} ... {END} section")
        page.write_text(re.sub(re.escape(BEGIN) + ".*?" + re.escape(END), lambda _: text, old,
                               flags=re.S))


if __name__ == "__main__":
    main()
