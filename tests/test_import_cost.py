"""``import mechsys`` stays light (decision 0061).

A user who builds a model and solves kinematics or inverse dynamics never steps an ODE or
finds a root, so ``import mechsys`` must not pay for scipy.integrate (~0.3 s with the
scipy.optimize and scipy.special it pulls in), scipy.optimize, matplotlib or numba: those load
in the functions that use them. One fresh interpreter per test (this process has them all
loaded already), no timing: only which modules ``sys.modules`` holds.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

HEAVY = ("scipy.integrate", "scipy.optimize", "scipy.signal", "scipy.interpolate",
         "matplotlib", "numba", "pandas")


def test_import_mechsys_does_not_load_the_heavy_optional_modules():
    code = textwrap.dedent(f"""
        import sys
        import mechsys
        print(sorted(n for n in {HEAVY!r} if n in sys.modules))
        # The deferred import still resolves: the Runge-Kutta stepper class comes from
        # scipy.integrate at call time, the same class as before.
        from mechsys.solvers._integrators import stepper_class
        import scipy.integrate
        assert stepper_class("rk45") is scipy.integrate.RK45
        assert stepper_class("dop853") is scipy.integrate.DOP853
        print("ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    loaded, ok = out.stdout.strip().splitlines()
    assert loaded == "[]", f"import mechsys loaded {loaded}; import them where they are used"
    assert ok == "ok"
