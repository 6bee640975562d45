"""Shared test helpers."""

import importlib.util
import os
import pathlib

# The tests compile a missing loop in their own process and wait for it (decision 0064): the
# tests asserting ``compiled_steps`` / ``compiled_points`` keep their meaning. The background
# tier has its own tests (tests/test_jit_background.py). Set before mechsys is imported.
os.environ.setdefault("MECHSYS_COMPILE", "wait")

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


def load_example(name: str):
    """Import ``examples/<name>.py`` as a module (its builders are reused by the tests)."""
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def same_bits(a, b, keys=("t", "q", "qd", "qdd", "lam")) -> None:
    """Two solutions equal bit for bit (NaN where the other has NaN)."""
    import numpy as np

    for key in keys:
        x, y = np.asarray(getattr(a, key)), np.asarray(getattr(b, key))
        assert x.shape == y.shape and np.array_equal(x, y, equal_nan=True), key


def simulate_both(monkeypatch, free, t, **options):
    """``free.simulate(t, **options)`` with ``MECHSYS_JIT=0`` (the loop's own code
    interpreted, never compiled: decision 0082), then ``1`` (the compiled loop):
    ``(interpreted, compiled)``, checked equal bit for bit (the same code: ``t``, ``q``,
    ``qd``, ``qdd``, ``lam``) with every step of the first the interpreted loop's or the
    Python path's hand-overs. Being one code, the two are no reference for each other: each
    test checks the motion against an independent one (a minimal-coordinate ODE, a closed
    form, a conservation law)."""
    out = {}
    for mode in ("0", "1"):
        monkeypatch.setenv("MECHSYS_JIT", mode)
        out[mode] = free.simulate(t, **options)
    slow, fast = out["0"], out["1"]
    assert slow.extra["compiled_steps"] == 0
    assert slow.extra["interpreted_steps"] == fast.extra["compiled_steps"]
    same_bits(slow, fast)
    return slow, fast


def python_path(monkeypatch) -> None:
    """Every free-motion and path run of the test takes the Python path whole: no stepper is
    planned (``FreeStepper.plan`` and ``plan_path`` answer None), as for the cases the loop
    does not take at all (decision 0082; since decision 0084 SymPy kernels and switched
    stages with velocity rows run in the loop). ``MECHSYS_JIT=0`` no longer selects it: the
    loop runs interpreted then."""
    from mechsys.solvers._jit_free import FreeStepper

    monkeypatch.setattr(FreeStepper, "plan", classmethod(lambda cls, *a, **k: None))
    monkeypatch.setattr(FreeStepper, "plan_path", classmethod(lambda cls, *a, **k: None))
