"""Machine and library versions printed with every benchmark table (shared by the
benchmark scripts)."""

from __future__ import annotations

import datetime as _dt
import os
import platform
from pathlib import Path


def machine() -> str:
    import numpy
    import scipy
    import sympy

    try:
        import symengine

        se = symengine.__version__
    except ImportError:  # pragma: no cover
        se = "not installed"
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{_dt.date.today().isoformat()}; {cpu}, {os.cpu_count()} cores "
            f"(shared with other jobs); {platform.system()} {platform.release()}; "
            f"Python {platform.python_version()}, NumPy {numpy.__version__}, "
            f"SciPy {scipy.__version__}, SymPy {sympy.__version__}, SymEngine {se}")


PAGE = """\
# Performance

<!-- Written by `python benchmarks/kinematic_sweep.py --write docs/performance.md`; rerun it
rather than editing the tables. -->

Measured on: {machine}. Times are CPU time of the benchmark process (the machine is shared;
see the script's docstring).

Command: `{command}`.

## Kinematic sweeps

Position (damped Newton, continued from a Taylor predictor of the previous point), velocity
and acceleration at every point. "compile" is `m.compile()`: the symbolic derivation of the
Jacobian, `Phi_t` and `gamma` plus compiling the three numeric functions. "per point" is the
whole sweep (best of three runs) divided by the number of points. "function calls" counts
evaluations of the compiled functions.

{sweeps}

Growth of the time per point with the number of coordinates `n` (chain):
{growth}.

## One evaluation of the equations

One compiled function returning `Phi`, the Jacobian's nonzero values and `gamma`, called at a
solved state: the inner-loop cost that decides the backend
([decision 0002](decisions/0002-numeric-backend.md)). "compile" is only the numeric compile
of that function (no symbolic derivation).

{evals}

## Reading the numbers

* A sweep needs about one Newton iteration per point: the predictor
  `q + qd dt + qdd dt^2/2` from the previous point lands close to the solution. Each point
  then costs four calls of compiled functions (residual and Jacobian twice, velocity, gamma).
* For small models the time per point is Python overhead in the solver (assembling,
  factorising and solving with NumPy/SciPy), not equation evaluation, which is a few µs of it;
  the two backends are then equally fast.
* Above 150 coordinates the solver switches to sparse LU (SuperLU); the cost per point grows
  more slowly than `n` over the sizes measured (exponents above). There the evaluation cost
  shows: SymPy's per-call time grows linearly with the number of outputs, SymEngine's LLVM
  code hardly at all.
* Compiling happens once per model change (`m.compile()` is cached), and changing parameter
  values does not recompile. For large models most of it is the numeric compile of the
  solver's three functions rather than the symbolic derivation.
"""
