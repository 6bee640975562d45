r"""Parameter studies: one analysis evaluated over a grid or a sample of parameter values.

``mechsys.sweep(model_or_builder, params, analysis, outputs)`` returns a pandas DataFrame with
one row per parameter point: the parameter values, then the outputs. It runs serially, on a
local process pool (``executor="processes"``) or on a Dask cluster (``executor=client``, a
``dask.distributed.Client``). See ``docs/sweeps.md``.

**Every point starts from the same model.** Before each point the sweep sets the point's
parameter values and clears ``model.last_solution`` (which couples and free systems read as
their default guesses), so a point's result does not depend on which points ran before it
on the same worker: serial, pool and Dask sweeps give identical numbers.

**Models on workers.** The model (or a builder function ``builder() -> Model``), the analysis
and the outputs are serialised together once (with cloudpickle when it is installed, which
Dask installs, else pickle; one payload keeps body handles captured by the analysis pointing
at the same model copy). Each worker process or thread unpickles the payload and builds the
model once, compiles it once, caches it under the payload's hash and reuses it for every
point it is given (``set_parameters`` needs no recompilation). A Model is picklable; a
builder function is the better choice when the model is large (the payload stays small) or
holds something that does not pickle. Lambdas and local functions need cloudpickle.
"""

from __future__ import annotations

import hashlib
import itertools
import os
import pickle
import threading
import time
from collections.abc import Mapping, Sequence
from numbers import Integral

import numpy as np
import sympy as sp

from .._errors import MechError, ModelError

#: analysis names that mean ``model.solve(t, solution=name)``
SOLVE_KINDS = ("location", "velocity", "acceleration", "static", "kinematic", "dynamic")

# worker cache: (payload hash, process id, thread id) -> (model, analysis, outputs)
_CACHE: dict = {}
_CACHE_SIZE = 8
# compiling in several threads of one process at once is not worth the risk: one at a time
_BUILD_LOCK = threading.Lock()


class _Solve:
    """The analysis ``model.solve(t, solution=kind)`` (picklable, unlike a lambda)."""

    def __init__(self, kind: str, t):
        self.kind, self.t = kind, t

    def __call__(self, model):
        return model.solve(self.t, solution=self.kind)

    def __repr__(self) -> str:
        return f"solve(t={self.t!r}, solution={self.kind!r})"


def _dumps(obj) -> bytes:
    try:
        import cloudpickle
    except ImportError:  # pragma: no cover - cloudpickle comes with dask
        return pickle.dumps(obj)
    return cloudpickle.dumps(obj)


def _points(params) -> tuple[list[str], list[dict]]:
    """Parameter names and the list of points ``{name: value}``."""
    try:
        import pandas as pd
    except ImportError:  # pragma: no cover - checked by sweep()
        pd = None
    if pd is not None and isinstance(params, pd.DataFrame):
        names = [str(c) for c in params.columns]
        return names, [dict(zip(names, map(float, row))) for row in params.itertuples(index=False)]
    if isinstance(params, Mapping):
        raise AssertionError("mappings are expanded by sweep()")  # pragma: no cover
    if isinstance(params, Sequence) and params and all(isinstance(p, Mapping) for p in params):
        names = [str(k) for k in params[0]]
        for i, p in enumerate(params):
            if sorted(map(str, p)) != sorted(names):
                raise ModelError(f"sweep: sample {i} sets {sorted(map(str, p))}, sample 0 sets "
                                 f"{sorted(names)}; every sample must set the same parameters")
        return names, [{str(k): v for k, v in p.items()} for p in params]
    raise ModelError("sweep: params must be a mapping {name: values} (a grid, or samples with "
                     "grid=False), a list of mappings {name: value} or a pandas DataFrame")


def _expand(params: Mapping, grid: bool) -> tuple[list[str], list[dict]]:
    names = [p.name if isinstance(p, sp.Symbol) else str(p) for p in params]
    values = []
    for name, v in zip(names, params.values()):
        arr = np.atleast_1d(np.asarray(v, dtype=object))
        if arr.ndim != 1 or arr.size == 0:
            raise ModelError(f"sweep: the values of parameter {name!r} must be a non-empty 1-D "
                             f"sequence, got {v!r}")
        values.append(list(arr))
    if grid:
        pts = [dict(zip(names, combo)) for combo in itertools.product(*values)]
    else:
        sizes = {len(v) for v in values}
        if len(sizes) != 1:
            raise ModelError("sweep(grid=False): the parameters are zipped into samples, so "
                             "they need equally many values; got "
                             + ", ".join(f"{n}: {len(v)}" for n, v in zip(names, values)))
        pts = [dict(zip(names, combo)) for combo in zip(*values)]
    return names, pts


def _columns(name: str, value) -> dict:
    """One column for a scalar output, ``name[i]`` columns for a 1-D output."""
    arr = np.ravel(np.asarray(value, dtype=float))
    if arr.size == 1:
        return {name: float(arr[0])}
    return {f"{name}[{i}]": float(v) for i, v in enumerate(arr)}


def _collect(result, outputs) -> dict:
    """The output columns of one point."""
    from ._couple import CoupleSolution

    if outputs is None:
        if isinstance(result, CoupleSolution):
            row = dict(result.unknowns)
            if any(result.couple._free):
                row.update(_columns("T", result.times))
            return row
        if getattr(result, "scalar", False) and hasattr(result, "names"):
            return {n: float(v) for n, v in zip(result.names, np.ravel(result.q))}
        raise ModelError("sweep: give outputs={column: callable or SymPy expression}; without "
                         "them only a couple (its unknowns) or a single-time solution (its "
                         f"coordinates) can be tabulated, and the analysis returned {result!r}")
    row = {}
    for name, out in outputs.items():
        if callable(out):
            value = out(result)
        elif isinstance(out, (sp.Basic, sp.MatrixBase)):
            value = result.eval(out)
        else:
            raise ModelError(f"sweep: output {name!r} must be a callable of the analysis result "
                             f"or a SymPy expression, got {out!r}")
        try:
            row.update(_columns(str(name), value))
        except (TypeError, ValueError):
            raise ModelError(f"sweep: output {name!r} gave {value!r}, which is not a number or a "
                             "1-D array of numbers") from None
    return row


def _run_points(model, analysis, outputs, names, points, on_error, report=None) -> list:
    """Evaluate ``points`` (``(index, {name: value})``) on one model; the model's parameter
    values and last solution are restored afterwards."""
    saved_p, saved_last = dict(model._params), model.last_solution
    rows = []
    try:
        for idx, pt in points:
            try:
                model.set_parameters(pt)
                model.last_solution = None
                row = _collect(analysis(model), outputs)
                if on_error == "nan":
                    row["error"] = ""
            except MechError as exc:
                if on_error == "raise":
                    msg = (f"sweep point {idx} ({', '.join(f'{k}={v!r}' for k, v in pt.items())}): "
                           f"{exc}")
                    try:
                        new = type(exc)(msg)
                    except TypeError:  # pragma: no cover - every mechsys error takes a message
                        new = MechError(msg)
                    raise new from exc
                row = {"error": f"{type(exc).__name__}: {exc}"}
            rows.append((idx, row))
            if report is not None:
                report()
    finally:
        model._params.update(saved_p)
        model.last_solution = saved_last
    return rows


def _run_chunk(payload: bytes, names, points, on_error):
    """Worker entry (process pool and Dask): the model of ``payload`` built and compiled once
    per worker process/thread, then the points. Returns ``(worker id, built now, rows)``."""
    key = (hashlib.sha1(payload).hexdigest(), os.getpid(), threading.get_ident())
    entry = _CACHE.get(key)
    built = entry is None
    if built:
        with _BUILD_LOCK:
            model_or_builder, analysis, outputs = pickle.loads(payload)
            model = _as_model(model_or_builder)
            model.compile()
        entry = (model, analysis, outputs)
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = entry
    model, analysis, outputs = entry
    return key[1:], built, _run_points(model, analysis, outputs, names, points, on_error)


def _is_model(obj) -> bool:
    """A Model2D/Model3D (by its interface: analyses do not import ``model``, which imports
    them)."""
    return all(hasattr(obj, a) for a in ("set_parameters", "compile", "solve", "_params"))


def _as_model(model_or_builder):
    if _is_model(model_or_builder):
        return model_or_builder
    model = model_or_builder()
    if not _is_model(model):
        raise ModelError(f"sweep: the builder {model_or_builder!r} must return a Model2D or "
                         f"Model3D, got {model!r}")
    return model


def _chunks(points, k):
    k = max(1, min(k, len(points)))
    size = -(-len(points) // k)
    return [points[i: i + size] for i in range(0, len(points), size)]


def sweep(model, params, analysis="acceleration", outputs=None, *, t=0.0, grid: bool = True,
          executor="serial", workers: int | None = None, chunks: int | None = None,
          progress: bool | None = None, on_error: str = "raise"):
    r"""Evaluate ``analysis`` at every point of a parameter grid or sample; a DataFrame.

    ``model``: a :class:`~mechsys.Model2D`/``Model3D`` or a builder function (no arguments)
    that returns one. ``params``: ``{name: values}`` — the Cartesian grid of the values
    (``grid=True``, the first name varying slowest) or, with ``grid=False``, samples zipped
    from equally long sequences; or a list of ``{name: value}`` samples, or a DataFrame of
    samples (one column per parameter).

    ``analysis``: ``"location"``, ``"velocity"``, ``"acceleration"`` (default),
    ``"static"``, ``"kinematic"`` or ``"dynamic"`` — ``model.solve(t, solution=...)`` — or
    any callable ``f(model) -> result`` (a couple: ``lambda m: m.couple(...).solve()``).
    ``outputs``: ``{column: output}``, each a callable ``g(result)`` or a SymPy expression
    (``result.eval(expr)``); a scalar gives one column, a 1-D array ``column[i]`` columns.
    Without outputs a couple gives its unknowns, a single-time solution its coordinates.

    ``executor``: ``"serial"`` (default), ``"processes"`` (a local process pool of ``workers``
    processes, default ``os.cpu_count()``, started with ``spawn``) or a
    ``dask.distributed.Client`` (optional extra ``mechsys[dask]``). The points are split
    into ``chunks`` tasks (default four per worker); each worker builds and compiles the model
    once and reuses it for all its points. ``progress``: a tqdm bar (stderr; a widget in
    Jupyter; ``None``: only on a terminal for 60 points or more). ``on_error``: ``"raise"``
    (default: the first failing point raises its mechsys error, prefixed with the point) or ``"nan"`` (failed
    points get NaN outputs and the message in an ``error`` column).

    Returns a pandas DataFrame, rows in the order of the points; ``df.attrs`` holds
    ``executor``, ``workers`` (distinct workers used), ``builds`` (model builds: one per
    worker) and ``seconds``.

    Example::

        df = ms.sweep(build, {"L": [5, 6, 7], "r": [1.5, 2]}, "acceleration", t=0.25,
                      outputs={"x": piston_x, "v": piston_v})
    """
    try:
        import pandas as pd
    except ImportError:
        raise MechError("sweep returns a pandas DataFrame: pip install pandas (or "
                        "mechsys[sweep])") from None
    if on_error not in ("raise", "nan"):
        raise ModelError(f"sweep: on_error must be 'raise' or 'nan', got {on_error!r}")
    if isinstance(analysis, str):
        if analysis not in SOLVE_KINDS:
            raise ModelError(f"sweep: analysis must be a callable f(model) or one of "
                             f"{list(SOLVE_KINDS)}, got {analysis!r}")
        analysis = _Solve(analysis, t)
    elif not callable(analysis):
        raise ModelError(f"sweep: analysis must be a callable f(model) or one of "
                         f"{list(SOLVE_KINDS)}, got {analysis!r}")
    if outputs is not None and not isinstance(outputs, Mapping):
        raise ModelError("sweep: outputs must be a mapping {column name: callable or SymPy "
                         f"expression}}, got {outputs!r}")
    if not _is_model(model) and not callable(model):
        raise ModelError(f"sweep: give a Model or a builder function returning one, got {model!r}")
    names, pts = _expand(params, grid) if isinstance(params, Mapping) else _points(params)
    if not pts:
        raise ModelError("sweep: no parameter points")
    for n in names:
        if n in ("error",):
            raise ModelError(f"sweep: {n!r} is reserved for the error column")
    indexed = list(enumerate(pts))
    start = time.monotonic()
    from .._progress import Progress

    bar = Progress(len(pts), "sweep", progress, unit="points")
    done = [0]

    def tick(k=1):
        done[0] += k
        bar.update(done[0])

    if isinstance(executor, str) and executor == "serial":
        m = _as_model(model)
        rows = _run_points(m, analysis, outputs, names, indexed, on_error, tick)
        kind, used, builds = "serial", 1, 1
    else:
        payload = _dumps((model, analysis, outputs))
        if isinstance(executor, str) and executor == "processes":
            results, kind = _on_pool(payload, names, indexed, on_error, workers, chunks, tick)
        elif isinstance(executor, str):
            raise ModelError(f"sweep: executor must be 'serial', 'processes' or a "
                             f"dask.distributed.Client, got {executor!r}")
        else:
            results, kind = _on_dask(executor, payload, names, indexed, on_error, chunks, tick)
        rows = [r for _, _, part in results for r in part]
        used = len({w for w, _, _ in results})
        builds = sum(b for _, b, _ in results)
    bar.close()
    rows.sort(key=lambda r: r[0])
    table = [{**pts[i], **row} for i, row in rows]
    df = pd.DataFrame(table)
    if on_error == "nan" and "error" in df:
        df = df[[c for c in df.columns if c != "error"] + ["error"]]
    df.attrs.update(executor=kind, workers=used, builds=builds,
                    seconds=time.monotonic() - start)
    return df


def _check_count(value, what):
    if value is not None and (isinstance(value, bool) or not isinstance(value, Integral)
                              or value < 1):
        raise ModelError(f"sweep: {what} must be a positive integer, got {value!r}")


def _on_pool(payload, names, indexed, on_error, workers, chunks, tick):
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed

    _check_count(workers, "workers")
    _check_count(chunks, "chunks")
    workers = workers or os.cpu_count() or 1
    parts = _chunks(indexed, chunks or 4 * workers)
    results = []
    # spawn, not fork: forking a process that runs threads (a Dask client, BLAS) can deadlock
    with ProcessPoolExecutor(max_workers=min(workers, len(parts)),
                             mp_context=mp.get_context("spawn")) as pool:
        futs = [pool.submit(_run_chunk, payload, names, part, on_error) for part in parts]
        for f in as_completed(futs):
            results.append(f.result())
            tick(len(results[-1][2]))
    return results, "processes"


def _on_dask(client, payload, names, indexed, on_error, chunks, tick):
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise MechError("sweep on a Dask cluster needs dask.distributed: pip install "
                        "'mechsys[dask]'") from None
    if not isinstance(client, Client):
        raise ModelError(f"sweep: executor must be 'serial', 'processes' or a "
                         f"dask.distributed.Client, got {client!r}")
    _check_count(chunks, "chunks")
    threads = sum(client.nthreads().values()) or 1
    parts = _chunks(indexed, chunks or 4 * threads)
    data = client.scatter(payload, broadcast=True)
    futs = client.map(_run_chunk, [data] * len(parts), [names] * len(parts), parts,
                      [on_error] * len(parts), pure=False)
    results = []
    for f in as_completed(futs):
        results.append(f.result())
        tick(len(results[-1][2]))
    return results, "dask"

