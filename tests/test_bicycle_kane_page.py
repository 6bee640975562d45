"""The bicycle-against-SymPy block of docs/performance.md (benchmarks/bicycle_kane.py): the
page holds the block the script writes, and the block states the agreement of the two
formulations that makes its times comparable (issue 36, item 6). The benchmark itself (a
minute of SymPy derivation) is not run here."""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
_spec = importlib.util.spec_from_file_location("bicycle_kane",
                                               ROOT / "benchmarks" / "bicycle_kane.py")
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)


def _block() -> str:
    page = (ROOT / "docs" / "performance.md").read_text(encoding="utf-8")
    assert page.count(bench.BEGIN) == 1 and page.count(bench.END) == 1, (
        "docs/performance.md lacks the bicycle_kane block: run "
        "`python benchmarks/bicycle_kane.py --write docs/performance.md`")
    return page.split(bench.BEGIN, 1)[1].split(bench.END, 1)[0]


def test_block_has_both_sides_and_their_agreement():
    block = _block()
    rows = [line for line in block.splitlines() if line.startswith("| mechsys")
            or line.startswith("| SymPy")]
    assert len(rows) == 2
    lean, steer = (float(x) for x in re.findall(
        r"(?:lean|steer) within ([0-9.e+-]+) rad", block))
    # the same physical model integrated at rtol 1e-8: the times compare like with like only
    # when the motions agree near the tolerance
    assert 0 < lean < 1e-7 and 0 < steer < 1e-7


def test_block_renders_from_a_result():
    # the table function the script writes with (the keys measure() returns)
    r = {"cold": 1.5, "warm": 0.9, "cold_all": [1.4, 1.6], "warm_all": [0.8, 1.0],
         "first": 2.5, "first_all": [2.3, 2.7], "first_compiled_steps": [0, 0],
         "background": 50.0, "background_all": [48.0, 52.0],
         "kernels": 4, "sympy_build": 23.0,
         "sympy_phases": {"derivation": 10.0, "lambdify": 13.0},
         "run": {"mechsys": 0.5, "sympy": 0.35, "python": 0.9},
         "steps": {"mechsys": 217, "sympy": 75, "python": 217, "compiled": 217},
         "sympy_steps_with_wheels": 124, "evaluations": {"mechsys": 3564, "sympy": 1208},
         "lean": 1.3e-9, "steer": 4.8e-9, "lean_peak": 0.116, "steer_peak": 0.134,
         "lean_end": 2e-3}
    text = bench.table(r)
    assert ("| mechsys | 56 | 2.5 s (+ 50.0 s on the other core, once) | 1.5 s | 900 ms | "
            "500 ms | 217 | 3564 | 140 µs |") in text
    # SymPy has no cache: its first build and run is its build plus its run
    assert "| SymPy `KanesMethod` + SciPy | 10 | 23.4 s | 23.0 s | (no cache) |" in text
    # the first run's path is stated from what it measured, not assumed
    assert "(0 compiled steps)" in text and "2.30-2.70 s) does not wait" in text
    assert "lean within 1.3e-09 rad" in text and "124 steps instead of 75" in text
    assert ("interpreted (`MECHSYS_JIT=0`, the stepper's own code, the same numbers): 900 ms "
            "(217 steps)") in text
