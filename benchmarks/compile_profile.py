"""Where the cold start's time goes: the Numba compile time of each function, in a fresh
process with empty caches (issue 35, item 2; decision 0044).

Runs one task of ``cold_start.py`` in a fresh process whose ``NUMBA_CACHE_DIR`` and
``MECHSYS_CACHE`` are new empty directories, with a listener on Numba's ``numba:compile``
events (``numba.core.event``). A function's compile includes the compiles of the functions
it calls for the first time (they are typed inside it); the table gives both the inclusive
time and the exclusive one (inclusive less its nested compiles), largest exclusive first.
Times are wall-clock seconds of the compiling process (``time.perf_counter``), so a loaded
machine inflates them; the total CPU time of the process is printed beside.

Run from the repository root::

    PYTHONPATH=src python benchmarks/compile_profile.py simulate
    PYTHONPATH=src python benchmarks/compile_profile.py sweep adams --top 25
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from cold_start import _PRELUDE, TASKS  # noqa: E402

_LISTEN = """
import time as _time
from numba.core import event as _ev
_rows, _stack = [], []
class _L(_ev.Listener):
    def on_start(self, e):
        d = e.data["dispatcher"]
        name = getattr(d, "py_func", d).__module__.rsplit(".", 1)[-1] + "." + d.__name__
        _stack.append([name, _time.perf_counter(), 0.0])
    def on_end(self, e):
        name, t0, inner = _stack.pop()
        dt = _time.perf_counter() - t0
        if _stack:
            _stack[-1][2] += dt
        _rows.append((name, dt, dt - inner))
_ev.register("numba:compile", _L())
"""


def profile(key: str) -> dict:
    """Compile events of ``TASKS[key]`` in a fresh process with empty caches:
    ``{"cpu": s, "rows": [(function, inclusive s, exclusive s), ...]}``."""
    code = (_LISTEN + _PRELUDE + TASKS[key][1]
            + "\nprint(json.dumps({'cpu': cpu(), 'rows': _rows}))\n")
    with tempfile.TemporaryDirectory() as nb, tempfile.TemporaryDirectory() as mc:
        # (compiled in the process: the compile is what is profiled; decision 0064)
        env = dict(os.environ, NUMBA_CACHE_DIR=nb, MECHSYS_CACHE=mc, MECHSYS_COMPILE="wait")
        env.pop("MECHSYS_JIT", None)
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                             text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tasks", nargs="*", default=list(TASKS), help=", ".join(TASKS))
    ap.add_argument("--top", type=int, default=20)
    args = ap.parse_args(argv)
    for key in args.tasks:
        res = profile(key)
        rows = {}
        for name, inc, exc in res["rows"]:     # a function compiled for two signatures: summed
            a = rows.setdefault(name, [0.0, 0.0, 0])
            a[0] += inc
            a[1] += exc
            a[2] += 1
        total = sum(a[1] for a in rows.values())
        print(f"\n{key}: process CPU {res['cpu']:.1f} s; compiles {total:.1f} s wall "
              f"({len(res['rows'])} compiles of {len(rows)} functions)")
        print(f"{'function':48s} {'n':>3s} {'inclusive':>10s} {'exclusive':>10s}")
        for name, (inc, exc, n) in sorted(rows.items(), key=lambda kv: -kv[1][1])[:args.top]:
            print(f"{name:48s} {n:3d} {inc:10.2f} {exc:10.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
