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


def simulate_both(monkeypatch, free, t, **options):
    """``free.simulate(t, **options)`` with ``MECHSYS_JIT=0`` (the Python stepper), then
    ``1`` (the compiled loop): ``(python, compiled)``."""
    out = {}
    for mode in ("0", "1"):
        monkeypatch.setenv("MECHSYS_JIT", mode)
        out[mode] = free.simulate(t, **options)
    return out["0"], out["1"]
