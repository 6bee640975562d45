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
from types import SimpleNamespace

import numpy as np
import sympy as sp

from .._errors import ConvergenceError, MechError, ModelError, choice
from ..geometry._units import is_quantity

#: analysis names that mean ``model.solve(t, solution=name)``
SOLVE_KINDS = ("location", "velocity", "acceleration", "static", "kinematic", "dynamic")

# worker cache: (payload hash, process id, thread id) -> (model, analysis, outputs)
_CACHE: dict = {}
_CACHE_SIZE = 8
# compiling in several threads of one process at once is not worth the risk: one at a time
_BUILD_LOCK = threading.Lock()


#: the time at which a model's guesses describe its assembly (as ``Model.dof`` takes them)
T_ASSEMBLY = 0.0
#: substeps of the parameter continuation of a row that does not assemble on the branch of
#: the model's assembly directly
ROW_STEPS = 8
#: the message of a row that could not be kept on the branch (the sweep's warning finds them)
OFF_BRANCH = "sweep row left the assembly branch"


class _Solve:
    """The analysis ``model.solve(t, solution=kind)`` (picklable, unlike a lambda), each row
    kept on the branch of the model's assembly (decision 0035):

    1. ``prepare`` (once per worker, at the model's own parameters): the assembly ``q_a`` at
       ``T_ASSEMBLY`` from the model's guesses, and the sign of ``det Phi_q(q_a)`` — it changes
       only through a singular configuration, so two assemblies of opposite sign lie on
       different branches (the two closures of a four-bar loop are mirror images with
       opposite signs).
    2. Each row: the position at ``T_ASSEMBLY`` at the row's parameters, Newton from ``q_a``;
       when it turns a rotational coordinate by more than ``STEP_CHECK`` from ``q_a`` or its
       determinant has the other sign, by continuation in ``ROW_STEPS`` substeps of the
       parameters from the model's values to the row's, each from the one before. A row still
       of the other sign is not solved: a :class:`ConvergenceError` (``on_error``: raised, or
       NaN outputs and the reason).
    3. Then a kinematic sweep from ``T_ASSEMBLY`` to the row's first time (its coarse steps
       are continued in substeps, :func:`~mechsys.solvers._kinematics.sweep`): the row's
       point on the branch. The asked solution from the model's guesses is returned when its
       first point is that point (to 1e-6: the numbers of a sweep without the check), else
       the solution started from it.

    Without an assembly at the model's parameters (guesses that do not assemble at
    ``T_ASSEMBLY``) or with a non-square Jacobian the rows are solved from the guesses as
    before, and the sweep says so in a warning."""

    def __init__(self, kind: str, t):
        self.kind, self.t = kind, t
        self.ref = None

    def prepare(self, model):
        """The model's assembly at its own parameters (see the class): ``ref``."""
        self.ref = None
        if getattr(model, "_switches", lambda: ())():
            return        # (stage switches: the stage at t = 0 need not be the row's)
        try:
            q = np.ravel(model.solve(T_ASSEMBLY, solution="location").q)
            sign = _det_sign(model, q) if q.size == model.compile().n else 0
        except MechError:
            return
        if sign:
            self.ref = (dict(model._params), q, sign)

    def __call__(self, model):
        if self.ref is None:
            return model.solve(self.t, solution=self.kind)
        from ..solvers._kinematics import _same_point
        from ..solvers._linalg import rotation_indices

        q0 = _on_branch(model, *self.ref)
        t0 = float(np.atleast_1d(np.asarray(self.t, dtype=float))[0])
        if t0 != T_ASSEMBLY:
            q0 = model.solve([T_ASSEMBLY, t0], solution="location", guess=q0).q[-1]
        try:
            # the solve from the guesses, as without the check, when it is on the branch: a
            # right answer keeps its numbers to the last bit
            sol = model.solve(self.t, solution=self.kind)
            system = model.compile()
            scale = SimpleNamespace(length=max(1.0, float(np.abs(q0).max(initial=0.0))))
            if sol.q.shape[-1] == q0.size and _same_point(
                    np.atleast_2d(sol.q)[0], q0, rotation_indices(system), scale):
                return sol
        except MechError:
            pass
        return model.solve(self.t, solution=self.kind, guess=q0)

    def __repr__(self) -> str:
        return f"solve(t={self.t!r}, solution={self.kind!r})"


def _det_sign(model, q) -> int:
    """The sign of ``det Phi_q`` at ``(T_ASSEMBLY, q)`` (0: singular or not square)."""
    system = model.compile()
    J = system.jacobian(T_ASSEMBLY, q, model._p())
    J = J.toarray() if hasattr(J, "toarray") else np.asarray(J)
    if J.shape[0] != J.shape[1]:
        return 0
    return int(np.linalg.slogdet(J)[0])


def _on_branch(model, base: dict, q_a, sign: int):
    """The row's position at ``T_ASSEMBLY`` on the branch of the assembly ``q_a`` (at the
    parameters ``base``), or a :class:`ConvergenceError` (see :class:`_Solve`)."""
    from ..solvers._kinematics import STEP_CHECK
    from ..solvers._linalg import rotation_indices

    rot = rotation_indices(model.compile())
    row = dict(model._params)

    def turned(q):
        return float(np.abs(q[rot] - q_a[rot]).max()) if rot.size else 0.0

    try:
        q = np.ravel(model.solve(T_ASSEMBLY, solution="location", guess=q_a).q)
        if _det_sign(model, q) == sign and turned(q) <= STEP_CHECK:
            return q
    except MechError:
        pass
    q = q_a
    try:
        for s in np.arange(1, ROW_STEPS + 1) / ROW_STEPS:
            model._params.update({k: base[k] + s * (row[k] - base[k]) for k in row
                                  if row[k] != base[k]})
            q = np.ravel(model.solve(T_ASSEMBLY, solution="location", guess=q).q)
            if _det_sign(model, q) != sign:
                break
    except MechError as exc:
        why = (f"the mechanism does not assemble at t = {T_ASSEMBLY:g} at (or on the way to) "
               "these parameters, so the branch cannot be followed from the model's assembly "
               f"to them ({type(exc).__name__}: {str(exc)[:200]})")
    else:
        if _det_sign(model, q) == sign:
            return q
        why = ("its configuration crosses a singular (toggle) position on the way from the "
               "model's parameters, where the assembly branch ends")
    finally:
        model._params.update(row)
    changed = ", ".join(f"{getattr(k, 'name', k)}={row[k]!r}" for k in row if row[k] != base[k])
    raise ConvergenceError(
        f"{OFF_BRANCH}: at {changed} the row cannot be put on the branch of the model's "
        f"assembly at t = {T_ASSEMBLY:g} (the configuration where det Phi_q has the assembly's "
        f"sign): {why}. "
        "Rows past a toggle position belong to another assembly mode; sweep them from a model "
        "whose guesses describe that mode, or narrow the parameter range.")


class _UserCall:
    """A user's analysis or output function (executor layer): an exception of its own that
    is not a mechsys error becomes a :class:`~mechsys.MechError` naming the function, so that
    it is the failure of its row (``on_error="nan"``: NaN and the message) instead of the end
    of the sweep. Picklable when the function is."""

    def __init__(self, what: str, fn):
        self.what, self.fn = what, fn

    def __call__(self, *args):
        try:
            return self.fn(*args)
        except MechError:
            raise
        except Exception as exc:  # noqa: BLE001 - any failure of user code is this row's
            raise MechError(f"{self.what} raised {type(exc).__name__}: {exc}") from exc

    def __repr__(self) -> str:
        return repr(self.fn)


#: how many more times the points of tasks lost with their worker (a process that died, a
#: Dask KilledWorker) are tried, one point a task, before they are reported lost
MAX_RETRIES = 2
#: how long a Dask retry waits for the cluster to have a worker again
DASK_WAIT_SECONDS = 60.0
#: the worker id of rows reported lost (no worker finished them)
_NO_WORKER = ("lost",)


def _lost_rows(points, attempts: int, on_error: str, why: str) -> list:
    """The rows of ``points`` whose worker died ``attempts`` times: NaN and the reason
    (``on_error="nan"``), or a :class:`~mechsys.MechError` naming them (``"raise"``)."""
    if on_error == "raise":
        which = ", ".join(f"{i} ({', '.join(f'{k}={v!r}' for k, v in pt.items())})"
                          for i, pt in points[:5])
        more = f" and {len(points) - 5} more" if len(points) > 5 else ""
        raise MechError(f"sweep: the worker computing point(s) {which}{more} died {attempts} "
                        f"times ({why}); on_error='nan' keeps the finished points and reports "
                        "these as failed")
    return [(i, {"error": f"WorkerLost: the worker died computing this point, {attempts} "
                          f"times ({why})"}) for i, _ in points]


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
        if is_quantity(v):
            # an array quantity: one quantity per point (each converted to the model's units
            # where it is set), never its magnitudes with the unit stripped
            v = [v[i] for i in range(len(v))] if np.ndim(v.magnitude) else [v]
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
        if hasattr(analysis, "prepare"):       # the model's own assembly (_Solve)
            analysis.prepare(model)
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
    choice(on_error, ("raise", "nan"), "sweep: on_error")
    if isinstance(analysis, str):
        choice(analysis, SOLVE_KINDS, "sweep: analysis", "or a callable f(model)")
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
    if not isinstance(analysis, _Solve):
        analysis = _UserCall("sweep: the analysis function", analysis)
    if outputs is not None:
        outputs = {k: (_UserCall(f"sweep: output {k!r}", v)
                       if callable(v) and not isinstance(v, (sp.Basic, sp.MatrixBase)) else v)
                   for k, v in outputs.items()}
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
            choice(executor, ("serial", "processes"), "sweep: executor",
                   "or a dask.distributed.Client")
        else:
            results, kind = _on_dask(executor, payload, names, indexed, on_error, chunks, tick)
        rows = [r for _, _, part in results for r in part]
        used = len({w for w, _, _ in results if w != _NO_WORKER})
        builds = sum(b for _, b, _ in results)
    bar.close()
    rows.sort(key=lambda r: r[0])
    table = [{**pts[i], **row} for i, row in rows]
    df = pd.DataFrame(table)
    if on_error == "nan" and "error" in df:
        df = df[[c for c in df.columns if c != "error"] + ["error"]]
    df.attrs.update(executor=kind, workers=used, builds=builds,
                    seconds=time.monotonic() - start)
    if isinstance(analysis, _Solve):
        _warn_branches(df, analysis, kind == "serial")
    return df


def _warn_branches(df, analysis, serial: bool) -> None:
    """A warning naming the rows not kept on the assembly branch (``on_error="nan"``), or
    saying that the rows could not be checked (no assembly of the model to check against)."""
    import warnings

    if "error" in df:
        bad = [i for i, e in enumerate(df["error"]) if isinstance(e, str) and OFF_BRANCH in e]
        if bad:
            warnings.warn(
                f"sweep: {len(bad)} row(s) could not be kept on the branch of the model's "
                f"assembly and have NaN outputs: rows {bad[:20]}{' ...' if len(bad) > 20 else ''}"
                " (the error column says why)", stacklevel=3)
    if analysis.ref is None and serial:      # (workers prepare their own copies)
        warnings.warn(
            f"sweep: the model does not assemble at t = {T_ASSEMBLY:g} from its guesses at its "
            "own parameters (or its Jacobian is singular or not square there, or it has stage "
            "switches), so the rows were solved from the guesses without checking that they "
            "stay on one assembly branch",
            stacklevel=3)


def _check_count(value, what):
    if value is not None and (isinstance(value, bool) or not isinstance(value, Integral)
                              or value < 1):
        raise ModelError(f"sweep: {what} must be a positive integer, got {value!r}")


def _on_pool(payload, names, indexed, on_error, workers, chunks, tick):
    """The points on a local process pool. A worker process that dies (killed, out of
    memory, ``os._exit`` in user code) breaks the whole pool: the finished tasks are kept,
    the lost ones run again in a new pool, one point a task (so a point that kills its
    worker takes only itself and the points running beside it), and on the last of the
    :data:`MAX_RETRIES` tries each in a pool of its own (so that only the point that kills
    its worker is lost); then they are reported lost (:func:`_lost_rows`)."""
    _check_count(workers, "workers")
    _check_count(chunks, "chunks")
    workers = workers or os.cpu_count() or 1
    parts = _chunks(indexed, chunks or 4 * workers)
    results: list = []
    attempt = 0
    while parts:
        if attempt < MAX_RETRIES:
            lost, why = _pool_round(payload, names, parts, on_error, workers, results, tick)
        else:  # the last try: each point alone in a pool of its own, so that a point that
            # kills its worker takes no other with it (beside it, an innocent one is lost too)
            lost, why = [], ""
            for part in parts:
                more, reason = _pool_round(payload, names, [part], on_error, 1, results, tick)
                lost, why = lost + more, reason or why
        if not lost:
            break
        attempt += 1
        points = _retry_or_report(lost, attempt, on_error, why, results, tick)
        if points is None:
            break
        parts = [[p] for p in points]
    return results, "processes"


def _retry_or_report(lost, attempt: int, on_error: str, why: str, results: list, tick):
    """The points of the ``lost`` parts to try again, or None once ``attempt`` is past
    :data:`MAX_RETRIES`: then they are reported lost (:func:`_lost_rows`) into ``results``."""
    points = [p for part in lost for p in part]
    if attempt <= MAX_RETRIES:
        return points
    rows = _lost_rows(points, attempt, on_error, why)
    results.append((_NO_WORKER, 0, rows))
    tick(len(rows))
    return None


def _pool_round(payload, names, parts, on_error, workers, results, tick):
    """One pool over ``parts``; appends the finished tasks' results to ``results`` and
    returns ``(lost parts, why)``."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed
    from concurrent.futures.process import BrokenProcessPool

    lost, why = [], ""
    # spawn, not fork: forking a process that runs threads (a Dask client, BLAS) can deadlock
    with ProcessPoolExecutor(max_workers=min(workers, len(parts)),
                             mp_context=mp.get_context("spawn")) as pool:
        futs = {pool.submit(_run_chunk, payload, names, part, on_error): k
                for k, part in enumerate(parts)}
        for f in as_completed(futs):
            try:
                res = f.result()
            except BrokenProcessPool as exc:
                lost.append(parts[futs[f]])
                why = f"{type(exc).__name__}: a worker process ended abruptly"
                continue
            results.append(res)
            tick(len(res[2]))
    return lost, why


def _on_dask(client, payload, names, indexed, on_error, chunks, tick):
    try:
        from distributed import Client
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
    results: list = []
    attempt = 0
    while parts:
        lost, why = _dask_round(client, data, names, parts, on_error, results, tick)
        if not lost:
            break
        attempt += 1
        points = _retry_or_report(lost, attempt, on_error, why, results, tick)
        if points is None:
            break
        try:
            # the cluster may have no workers left (their nannies did not restart them): a
            # retry would then wait forever, so it waits a bounded time for one
            client.wait_for_workers(1, timeout=DASK_WAIT_SECONDS)
        except Exception:  # noqa: BLE001 - distributed raises TimeoutError (several kinds)
            rows = _lost_rows(points, attempt, on_error, why + "; no worker left to retry on")
            results.append((_NO_WORKER, 0, rows))
            tick(len(rows))
            break
        parts = [[p] for p in points]       # one point a task, as on the process pool
        # the scattered payload dies with the workers that held it ("lost dependencies"):
        # the retries carry it in their tasks, which the scheduler keeps
        data = payload
    return results, "dask"


def _dask_round(client, data, names, parts, on_error, results, tick):
    """One map of ``parts`` on the cluster; a task Dask gave up on after its own retries
    (``KilledWorker``: its workers died) or cancelled is lost, not the end of the sweep.
    Returns ``(lost parts, why)``; finished results are appended to ``results``."""
    from concurrent.futures import CancelledError

    from distributed import KilledWorker, as_completed

    futs = client.map(_run_chunk, [data] * len(parts), [names] * len(parts), parts,
                      [on_error] * len(parts), pure=False)
    index = {f.key: k for k, f in enumerate(futs)}
    lost, why = [], ""
    for f in as_completed(futs):
        try:
            res = f.result()
        except (KilledWorker, CancelledError) as exc:
            lost.append(parts[index[f.key]])
            why = f"{type(exc).__name__}: {str(exc)[:200]}"
            continue
        results.append(res)
        tick(len(res[2]))
    return lost, why
