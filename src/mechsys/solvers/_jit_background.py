r"""The background compile of the tiered execution (decision 0064): a process that compiles
specialisations of compiled loops into Numba's on-disk cache while the run that asked for
them continues on its Python path.

Started by ``_jit_modes._start`` as ``python -m mechsys.solvers._jit_background JOBFILE``
in its own session (it outlives the run that started it) with its output in
``mechsys-bg.log`` of the cache directory. ``JOBFILE`` is a pickle written by that run (in
the cache directory, private to the user like Numba's own pickled index files):
``{"sys_path": [...], "jobs": [(module, qualname, signature, lock, result), ...]}``, the
signature a tuple of Numba types (they pickle; a literal argument stays
``Literal[int](k)``). For each job it imports the dispatcher's module, calls
``dispatcher.compile(signature)`` (Numba compiles and writes the cache, or loads what
another process wrote meanwhile), writes ``result`` (JSON: CPU seconds of the compile and
of the process so far, success, the error's text) and removes ``lock``, whose presence told
other processes that the compile is under way. A failure of one job is recorded in its
result and does not stop the others; the asking run then compiles in its own process.

It runs at low priority (``os.nice(10)`` where the platform has it): the machine's other
core is meant, not the run's.

.. math:: t_{\mathrm{first\ result}} = t_{\mathrm{Python\ path}} + t_{\mathrm{spawn}},
          \qquad t_{\mathrm{compile}} \text{ on another core, once}

Example (what ``_jit_modes`` runs; not called by hand)::

    python -m mechsys.solvers._jit_background /path/to/cache/mechsys-bg-abc.job
"""

from __future__ import annotations

import importlib
import json
import os
import pickle
import sys
import time
import traceback


def _cpu() -> float:
    """CPU seconds (user + system) of this process so far."""
    try:
        import resource

        r = resource.getrusage(resource.RUSAGE_SELF)
        return r.ru_utime + r.ru_stime
    except ImportError:            # (no resource module: Windows)
        return time.process_time()


def _dispatcher(module: str, qualname: str):
    """The object ``module.qualname`` (a Numba dispatcher defined at a module's top level)."""
    obj = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


def _write(path: str, data: dict) -> None:
    """``data`` as JSON at ``path``, written whole (a temporary file renamed)."""
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "w") as fh:
        json.dump(data, fh)
    os.replace(tmp, path)


def run(jobfile: str) -> int:
    """Compile the jobs of ``jobfile`` into Numba's cache (see the module docstring); returns
    the number that failed."""
    with open(jobfile, "rb") as fh:
        spec = pickle.load(fh)
    try:
        os.unlink(jobfile)
    except OSError:
        pass
    for p in reversed(spec["sys_path"]):
        if p not in sys.path:
            sys.path.insert(0, p)
    for _, _, _, lock, _ in spec["jobs"]:
        try:                      # (the lock names the process compiling: this one now)
            with open(lock, "w") as fh:
                fh.write(f"{os.getpid()}\n")
        except OSError:
            pass
    failed = 0
    for module, qualname, sig, lock, result in spec["jobs"]:
        start, wall = _cpu(), time.time()
        out = {"function": f"{module}.{qualname}", "signature": str(sig), "ok": False,
               "error": None, "pid": os.getpid()}
        try:
            _dispatcher(module, qualname).compile(sig)
            out["ok"] = True
        except Exception as exc:  # (recorded for the asking run, which compiles itself)
            failed += 1
            out["error"] = f"{type(exc).__name__}: {exc}"[:2000]
            traceback.print_exc()
        out.update(cpu=_cpu() - start, process_cpu=_cpu(), wall=time.time() - wall)
        try:
            _write(result, out)
        except OSError:
            pass
        try:
            os.unlink(lock)
        except OSError:
            pass
    return failed


def main(argv: list[str] | None = None) -> int:
    """Entry point: ``python -m mechsys.solvers._jit_background JOBFILE``."""
    argv = sys.argv[1:] if argv is None else argv
    if hasattr(os, "nice"):
        try:
            os.nice(10)
        except OSError:
            pass
    return 1 if run(argv[0]) else 0


if __name__ == "__main__":
    raise SystemExit(main())
