"""Long fuzz profile: ``mechsys.testing._fuzz.check_mechanism`` on many random mechanisms.

Model ``k`` uses seed ``start + k`` and the constraint type ``case_names()[(start + k) %
len(case_names())]``, so every registered constraint type (joints, cams, gears, general
constraints; planar and spatial) comes round in turn; the seed draws the rest (extra pinned
bodies, geometry, masses, gravity, drivers). Every model is checked as in the short profile
of ``tests/test_fuzz.py``: only MechError escapes, Jacobian and gamma match finite
differences, solved points satisfy the constraints, ``m.dof()`` matches an independent rank,
the free acceleration satisfies ``Phi_q qdd = gamma``.

Run: ``python benchmarks/fuzz_long.py --models 10000`` (a few seconds a model: hours);
``--minutes 60`` stops after that long; ``--write docs/robustness_fuzz.md`` puts the summary
between ``<!-- fuzz-long:begin -->`` and ``<!-- fuzz-long:end -->``. Parallel runs
over adjacent seed ranges (``--start``, ``--json``) are summarised by
``--merge a.json b.json``. Failures are printed
with their seed: ``check_mechanism(seed, name=...)`` reproduces one.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import collections  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from mechsys.testing._fuzz import FuzzFailure, case_names, check_mechanism  # noqa: E402

BEGIN, END = "<!-- fuzz-long:begin -->", "<!-- fuzz-long:end -->"


def run(models: int, start: int, minutes: float | None, log=None) -> dict:
    names = case_names()
    outcomes = collections.Counter()
    per_type = collections.Counter()
    dims = collections.Counter()
    failures = []
    worst = {"jacobian_fd": 0.0, "gamma_fd": 0.0, "free_acceleration": 0.0}
    t0 = time.monotonic()
    cpu0 = time.process_time()
    done = 0
    for k in range(models):
        if minutes is not None and time.monotonic() - t0 > 60 * minutes:
            break
        seed = start + k
        name = names[seed % len(names)]
        try:
            r = check_mechanism(seed, name=name)
            for o in r["outcome"]:
                outcomes[o] += 1
            dims[r["dim"]] += 1
            for key in worst:
                worst[key] = max(worst[key], float(r.get(key, 0.0)))
        except FuzzFailure as err:
            failures.append({"seed": seed, "type": name, "what": err.what[:500]})
        except Exception as err:  # noqa: BLE001 - an error of the checker itself: report it
            failures.append({"seed": seed, "type": name,
                             "what": f"checker error {type(err).__name__}: {str(err)[:400]}"})
        if log is not None and len(failures) and failures[-1]["seed"] == seed:
            print(f"FAILURE {failures[-1]}", file=log, flush=True)
        per_type[name] += 1
        done += 1
        if log is not None and done % 25 == 0:
            print(f"{done} models, {len(failures)} failures, {time.monotonic() - t0:.0f} s",
                  file=log, flush=True)
    return {"models": done, "start": start, "types": len(per_type), "all_types": len(names),
            "dims": dict(dims), "outcomes": dict(outcomes), "failures": failures,
            "worst": worst, "wall_s": time.monotonic() - t0, "cpu_s": time.process_time() - cpu0}


def summary(r: dict) -> str:
    dims = {int(k): v for k, v in r["dims"].items()}  # (JSON turns the keys into strings)
    lines = [
        f"* models checked: **{r['models']:,}** (seeds {r['start']} to {r['start'] + r['models'] - 1}), "
        f"{r['types']} of {r['all_types']} constraint types; planar {dims.get(2, 0)}, "
        f"spatial {dims.get(3, 0)}",
        f"* failures: **{len(r['failures'])}**",
        f"* largest finite-difference mismatch (absolute; the checks allow 1e-6 for the Jacobian "
        f"and 1e-5 for gamma, times 1 + the largest entry): Jacobian "
        f"{r['worst']['jacobian_fd']:.1e}, gamma {r['worst']['gamma_fd']:.1e}; free acceleration "
        f"residual (scaled) {r['worst']['free_acceleration']:.1e}",
        "* outcomes (a model can have several): " + ", ".join(
            f"{k} {v}" for k, v in sorted(r["outcomes"].items())),
        f"* time: {r['wall_s'] / 60:.0f} min wall, {r['cpu_s'] / 60:.0f} min CPU "
        f"({r['cpu_s'] / max(r['models'], 1):.1f} s CPU a model)",
    ]
    for f in r["failures"]:
        lines.append(f"  * seed {f['seed']} ({f['type']}): {f['what']}")
    return "\n".join(lines)


def merged(parts: list[dict]) -> dict:
    """One summary of several runs (``--json`` files) over adjacent seed ranges, e.g. runs
    in parallel processes: counts add up, the worst mismatches are the largest, times add
    up (CPU) or are the longest (wall, parallel runs)."""
    parts = sorted(parts, key=lambda r: r["start"])
    for a, b in zip(parts, parts[1:]):
        if a["start"] + a["models"] != b["start"]:
            raise SystemExit(f"seed ranges not adjacent: {a['start']}+{a['models']} then "
                             f"{b['start']}")
    out = {"models": sum(r["models"] for r in parts), "start": parts[0]["start"],
           "types": max(r["types"] for r in parts), "all_types": parts[0]["all_types"],
           "dims": collections.Counter(), "outcomes": collections.Counter(), "failures": [],
           "worst": {k: max(r["worst"][k] for r in parts) for k in parts[0]["worst"]},
           "wall_s": max(r["wall_s"] for r in parts), "cpu_s": sum(r["cpu_s"] for r in parts)}
    for r in parts:
        out["dims"].update({int(k): v for k, v in r["dims"].items()})
        out["outcomes"].update(r["outcomes"])
        out["failures"] += r["failures"]
    out["dims"], out["outcomes"] = dict(out["dims"]), dict(out["outcomes"])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--models", type=int, default=10_000)
    ap.add_argument("--start", type=int, default=0)
    ap.add_argument("--minutes", type=float, default=None)
    ap.add_argument("--write", type=Path, default=None)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--merge", type=Path, nargs="+", default=None,
                    help="summarise these --json results (adjacent seed ranges) instead of running")
    a = ap.parse_args(argv)
    if a.merge:
        r = merged([json.loads(f.read_text()) for f in a.merge])
    else:
        r = run(a.models, a.start, a.minutes, log=sys.stderr)
    text = summary(r)
    print(text)
    if a.json:
        a.json.write_text(json.dumps(r, indent=1))
    if a.write:
        page = a.write.read_text()
        i, j = page.index(BEGIN) + len(BEGIN), page.index(END)
        a.write.write_text(page[:i] + "\n" + text + "\n" + page[j:])
    return 1 if r["failures"] else 0


if __name__ == "__main__":
    raise SystemExit(main())
