"""Long hostile-input profile of model files (issue 39): the generator of
``tests/test_hostile_files.py`` run over many more cases, each timed.

Each case puts one hostile value (a huge power, ``exp(10**9*log(2))``, ``log(0)``, a lone
surrogate, a 160-factor product, a deep nesting, a foreign class name, a wrong type...) in one
place of a model file with every field in use, and loads it. Counted: cases that loaded,
cases refused with a MechError, anything else (must be none), and the slowest case.

Run: ``python benchmarks/hostile_long.py --cases 3000 [--seed 39] [--write
docs/model_files.md]`` (the summary goes between ``<!-- hostile-long:begin -->`` and
``<!-- hostile-long:end -->``).
"""

from __future__ import annotations

import argparse
import random
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "tests"))

import mechsys as ms  # noqa: E402
from mechsys.io import _files  # noqa: E402

BEGIN, END = "<!-- hostile-long:begin -->", "<!-- hostile-long:end -->"


def base() -> dict:
    from mechsys import models

    m = models.slider_crank_dynamic(piston_force=-10.0)
    m.parameter("k", 2.0)
    m.variable("s", 0.5)
    ms.draw.attach(m, ms.draw.Wheel(m.body("crank"), spokes=4))
    return ms.io.model_to_dict(m)


def main() -> int:
    from test_hostile_files import _HOSTILE_VALUES, _PRODUCT_160, _paths, _replace

    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cases", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=39)
    ap.add_argument("--write", type=Path, default=None)
    args = ap.parse_args()
    values = [*_HOSTILE_VALUES, {"expr": _PRODUCT_160}, {"expr": "+".join(["sin(cos(T))"] * 600)},
              {"expr": "((2*T)**1000)**1000"}, {"expr": "exp(T + 10**9*log(2))"}]
    data = base()
    paths = list(_paths(data))
    rng = random.Random(args.seed)
    counts = {"loaded": 0, "MechError": 0, "other": 0}
    slowest, others = (0.0, None), []
    start = time.perf_counter()
    for _ in range(args.cases):
        path, value = rng.choice(paths), rng.choice(values)
        case = _replace(data, path, value)
        t0 = time.perf_counter()
        try:
            _files.model_from_dict(case, "hostile.json")
            counts["loaded"] += 1
        except ms.MechError:
            counts["MechError"] += 1
        except Exception as exc:  # noqa: BLE001 - what the profile looks for
            counts["other"] += 1
            others.append((path, repr(value)[:60], f"{type(exc).__name__}: {exc}"[:160]))
        dt = time.perf_counter() - t0
        if dt > slowest[0]:
            slowest = (dt, (path, repr(value)[:60]))
    total = time.perf_counter() - start
    lines = [f"{args.cases} hostile cases (seed {args.seed}) in {total:.1f} s: "
             f"{counts['loaded']} loaded, {counts['MechError']} refused with a MechError, "
             f"{counts['other']} other exceptions; slowest case {slowest[0] * 1e3:.0f} ms "
             f"({slowest[1][1]} at {'/'.join(map(str, slowest[1][0]))})."]
    for o in others[:10]:
        lines.append(f"* {o}")
    text = "\n".join(lines)
    print(text)
    if args.write:
        page = args.write.read_text(encoding="utf-8")
        i, j = page.index(BEGIN) + len(BEGIN), page.index(END)
        args.write.write_text(page[:i] + "\n" + text + "\n" + page[j:], encoding="utf-8")
    return 1 if counts["other"] else 0


if __name__ == "__main__":
    raise SystemExit(main())
