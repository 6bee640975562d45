"""Compile only what a run uses: the compiled loops specialised on their mode (decision 0044).

The free-motion loops (``_jit_free_loop.runge_kutta``, ``adams``, ``derivative``) and the
kinematic sweep hold every solver kind in one function (``blocks``: dense augmented, block,
Gen tree, path, Newton, sparse; the sweep: dense or sparse LU), chosen at run time. Numba
types, and so compiles, every function a loop can call, whichever kind a run takes: the
double pendulum paid for the sparse LU, the Newton with its banded pattern and the block
path it never runs (about two thirds of the first run's CPU, decision 0044).

Two pieces make the kind a compile-time constant without a second copy of any algorithm:

* :func:`entry`: the loop compiled for the argument types of a call with the mode argument
  typed as its value (Numba's ``Literal[int](k)``), and the machine code of that
  specialisation, called directly afterwards. A literal argument reaches every function the
  loop passes it to (Numba compiles the callee for the literal type too), so the mode is
  known wherever it is tested. Numba caches each specialisation under its own signature.
* :func:`within` at each call of a mode's solver: ``within(mode, lo, hi, fn, *args)`` is
  ``fn(*args)``, except that where ``mode`` is a literal outside ``[lo, hi]`` it is
  ``False`` and ``fn`` is never typed, hence never compiled. Called with a mode that is not a
  literal (a caller of the loop from Python through the plain dispatcher) it is always the
  call: the loop then holds every kind, as before.

The run-time tests (``if blocks == BLOCK``) stay where they were: the code between them is
the one implementation of each kind, and the specialised loop takes the same branches with
the same numbers as the general one (the tests compare both bit for bit).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import sys
import time
from pathlib import Path

import numba as nb
import numba.core.options  # noqa: F401  (_LEAF_OPTIONS reads it)
from numba._dispatcher import compute_fingerprint as _compute_fingerprint
from numba.extending import overload


def within(mode, lo, hi, fn, *args):
    r"""``fn(*args)`` when ``lo <= mode <= hi``, else ``False``, for a solver ``fn`` returning
    a bool (False: hand over). In compiled code :func:`_within_impl` decides from the types:
    a literal ``mode`` outside the range compiles to ``False`` without typing ``fn``; any
    other mode compiles to the call (the caller's own test of ``mode`` guards it at run time).

    .. math:: \mathrm{within}(k, l, h, f, a) = \begin{cases} f(a) & l \le k \le h \\
              \mathrm{False} & \text{otherwise} \end{cases}

    Example (in a compiled loop whose ``blocks`` is a literal)::

        if blocks == BLOCK:
            ok = within(blocks, BLOCK, BLOCK, _accel_blocks, kp, x, ...)
    """
    return fn(*args) if lo <= mode <= hi else False


#: compiled as the loops' leaf functions (``_jit_lapack.leaf``): no reference counting of the
#: arrays it hands on (each call would otherwise count every one of them up and down)
_LEAF_OPTIONS = {"error_model": "numpy", **(
    {"_nrt": False} if hasattr(getattr(nb.core.options, "DefaultOptions", None), "_nrt") else {})}


@overload(within, prefer_literal=True, jit_options=_LEAF_OPTIONS)
def _within_impl(mode, lo, hi, fn, *args):
    k = getattr(mode, "literal_value", None)
    if isinstance(k, int) and not lo.literal_value <= k <= hi.literal_value:
        def skip(mode, lo, hi, fn, *args):
            return False
        return skip

    def call(mode, lo, hi, fn, *args):
        return fn(*args)
    return call


def signature(args, literal=()) -> tuple:
    """The Numba argument types of ``args`` (as the dispatcher types a call from Python),
    with the arguments at the positions ``literal`` typed as their values."""
    return tuple(nb.types.literal(a) if i in literal else nb.typeof(a)
                 for i, a in enumerate(args))


def in_cache(dispatcher, sig) -> bool:
    """Whether ``dispatcher`` holds ``sig`` compiled in this process or in Numba's on-disk
    cache (its index file lists the signatures it holds)."""
    if sig in dispatcher.overloads:
        return True
    try:
        index = dispatcher._cache._cache_file._load_index()
    except Exception:      # (an unreadable or foreign index: Numba compiles, so do we say)
        return False
    return any(key[0] == sig for key in index)


#: the entries found: ``(dispatcher, literal values, argument fingerprints) -> machine code``
_ENTRIES: dict = {}


def _fingerprint(a):
    """Numba's own key of the type of ``a`` (its C dispatcher's: dtype, dimensions, layout,
    for arrays and tuples of them), about 1 µs an argument; ``numba.typeof`` took about 100
    µs an argument (measured on the loaded 2-core machine), milliseconds for a loop's 40."""
    try:
        return _compute_fingerprint(a)
    except (TypeError, ValueError, NotImplementedError):   # (a type it does not key)
        return nb.typeof(a)


def entry(dispatcher, args, literal=(), say=None):
    """The machine code of ``dispatcher`` specialised for ``args`` with the arguments at the
    positions ``literal`` typed as their values (see the module docstring), or None while it
    is being compiled in the background (decision 0064; the caller takes its Python path and
    may ask again later). Found in the process, or loaded from Numba's on-disk cache, on the
    first request; afterwards found by the arguments' type fingerprints. When neither holds
    it, ``MECHSYS_COMPILE`` (:func:`~mechsys.solvers._jit_runtime.compile_policy`) decides:
    ``background`` (the default) hands the compile to one low-priority process
    (:mod:`._jit_background`), which writes it into the cache, and returns None until that
    process is done; ``wait`` compiles here. ``say(how)`` is called first when it starts a
    compile (``how``: ``"background"`` or ``"wait"``; the caller's notice). Call it with the
    same arguments: ``entry(...)(*args)``. Example::

        fn = entry(runge_kutta, args, literal=(14,))
        if fn is not None:
            status, steps, *rest = fn(*args)
    """
    try:
        # (the C function over all arguments at once: a Python frame per argument cost as
        # much as the fingerprints themselves, some 70 of them per simulate)
        prints = tuple(map(_compute_fingerprint, args))
    except (TypeError, ValueError, NotImplementedError):
        prints = tuple(map(_fingerprint, args))
    key = (dispatcher, tuple(args[i] for i in literal), prints)
    got = _ENTRIES.get(key)
    if got is not None:
        return got
    job = _WAITING.get(key)
    if job is not None:
        # asked again while its compile runs elsewhere: the cheap checks only (no typing of
        # the arguments, no reading of the cache's index)
        if not job.finished():
            return None
        del _WAITING[key]
        sig = job.sig
    else:
        sig = signature(args, literal)
    cres = dispatcher.overloads.get(sig)
    if cres is not None:
        fn = cres.entry_point
    elif in_cache(dispatcher, sig):
        fn = dispatcher.compile(sig)          # (loads the machine code: well under a second)
        if job is not None:
            _LOG.info("mechsys: %s compiled in the background; from here on it runs compiled",
                      _name(dispatcher))
    else:
        job = job if job is not None else _background(dispatcher, sig, say)
        if job is not None and not job.failed:
            _WAITING[key] = job
            return None
        fn = _compile_here(dispatcher, sig, say)
    _ENTRIES[key] = fn
    return fn


#: how often a process waiting for another's compile looks at its lock (seconds)
_POLL_SECONDS = 0.2


def _compile_here(dispatcher, sig, say):
    """``dispatcher.compile(sig)`` in this process (the ``wait`` policy, or a background
    compile that could not be had), holding the same lock file as the background tier
    (:func:`_lock_path`), so that two processes needing the same missing specialisation at
    once compile it once (decision 0071): while another live process holds the lock (its
    own compile, or a background child's), wait for it and then load its result from the
    cache. A stale lock is taken over; a cache directory where no lock can be written, a
    lock this process holds, or a holder that ended without filling the cache: compile
    here. ``say("wait")`` is called once, before the wait or the compile (the caller's
    notice: the run waits either way). Example::

        fn = _compile_here(runge_kutta, signature(args, (14,)), None)
    """
    said = False
    where = _cache_dir(dispatcher)
    lock = None if where is None else _lock_path(where, dispatcher, sig)
    while lock is not None:
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
        except FileExistsError:
            if not _alive(lock):
                try:
                    lock.unlink()         # (stale: its process is gone; take it over)
                except FileNotFoundError:
                    pass
                except OSError:
                    lock = None
                continue
            if _holder(lock) == os.getpid():
                lock = None               # (held by this process: nothing to wait for)
                break
            if not said and say is not None:
                say("wait")
            said = True
            _LOG.info("mechsys: waiting for process %s, which compiles %s", _holder(lock),
                      _name(dispatcher))
            while lock.exists() and _alive(lock):
                time.sleep(_POLL_SECONDS)
            if in_cache(dispatcher, sig):
                return dispatcher.compile(sig)    # (loads the other process's machine code)
            continue                      # (it failed or was killed: compile it here)
        except OSError:                   # (an unwritable cache directory: no lock)
            lock = None
            break
        with os.fdopen(fd, "w") as fh:
            fh.write(f"{os.getpid()}\n")
        try:
            if not said and say is not None:
                say("wait")
            return dispatcher.compile(sig)
        finally:
            try:
                lock.unlink()
            except OSError:
                pass
    if not said and say is not None:
        say("wait")
    return dispatcher.compile(sig)


# --- the background tier (decision 0064) --------------------------------------------------

_LOG = logging.getLogger("mechsys")

#: the requests whose compile is under way elsewhere: entry key -> :class:`_Job`
_WAITING: dict = {}
#: every background compile this process asked for: (dispatcher, signature) -> :class:`_Job`
_JOBS: dict = {}
#: this process's child (at most one at a time while it lives) and the jobs waiting for it
_CHILD: dict = {"proc": None, "jobs": [], "queue": [], "exit_hook": False}

#: a lock older than this is taken for abandoned whoever holds it (a compile takes minutes)
_STALE_SECONDS = 3 * 3600.0
#: an empty lock (its creator has not written its pid yet) is taken as held this long
_UNWRITTEN_SECONDS = 10.0


class _Job:
    """One specialisation compiled by a background process: its lock file in the cache
    directory (held while the compile runs, by this process's child or another process's),
    its result file (the child's JSON: CPU seconds, success, error), and its state."""

    def __init__(self, dispatcher, sig, lock: Path, mine: bool):
        self.dispatcher, self.sig, self.lock, self.mine = dispatcher, sig, lock, mine
        self.result = lock.with_suffix(".json")
        self.done = False       # the compile is over (its outcome is in the cache or not)
        self.failed = False     # it did not fill the cache: compile in this process instead

    def finished(self) -> bool:
        """Whether the compile is over (a finished child is reaped here; a job waiting for
        this process's child starts it when the child before it is done)."""
        if not self.done:
            _pump()
            if not self.mine and not self.lock.exists():
                self.done = True          # (another process's compile: its lock is gone)
        if self.done and not self.failed and not in_cache(self.dispatcher, self.sig):
            self._fail()
        return self.done

    def _fail(self) -> None:
        self.failed = True
        why = ""
        try:
            why = json.loads(self.result.read_text()).get("error") or ""
        except (OSError, ValueError, AttributeError):
            pass
        _LOG.warning("mechsys: the background compile of %s for %s did not fill Numba's "
                     "cache%s; compiling it in this process", _name(self.dispatcher),
                     self.sig, f" ({why})" if why else "")


def _name(dispatcher) -> str:
    f = dispatcher.py_func
    return f"{f.__module__}.{f.__qualname__}"


def _cache_dir(dispatcher) -> Path | None:
    """The directory of ``dispatcher``'s on-disk cache (Numba's choice: beside the sources or
    under ``NUMBA_CACHE_DIR``), created if missing; None when it caches nothing or the
    directory cannot be made."""
    path = getattr(getattr(dispatcher, "_cache", None), "_cache_path", None)
    if not path:
        return None
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return None
    return Path(path)


def _lock_path(where: Path, dispatcher, sig) -> Path:
    """The lock file of the compile of ``sig`` of ``dispatcher`` in the cache directory
    ``where`` (keyed by the function, the signature, Python's and Numba's versions)."""
    digest = hashlib.sha256(f"{_name(dispatcher)}|{sig!r}|{sys.version}|{nb.__version__}"
                            .encode()).hexdigest()[:20]
    return where / f"mechsys-bg-{digest}.lock"


def _alive(lock: Path) -> bool:
    """Whether the process named in ``lock`` may still be compiling (its process exists and
    the lock is younger than :data:`_STALE_SECONDS`)."""
    try:
        age = time.time() - lock.stat().st_mtime
        if age > _STALE_SECONDS:
            return False
        text = lock.read_text()
    except OSError:
        return False
    try:
        pid = int(text.split()[0])
    except (ValueError, IndexError):
        # (created but its pid not yet written: its creator writes it next; a lock left
        # empty by a process that died at that instant is stale a few seconds later)
        return age < _UNWRITTEN_SECONDS
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True           # (someone else's process, or no way to ask: assume alive)
    return True


def _holder(lock: Path) -> int | None:
    """The pid written in ``lock`` (None when it cannot be read)."""
    try:
        return int(lock.read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def _background(dispatcher, sig, say):
    """The :class:`_Job` compiling ``sig`` of ``dispatcher`` in the background: started (or
    queued behind this process's child) when no process holds its lock, else waiting for the
    process that does. None when it cannot be done (the policy is ``wait``; the dispatcher
    has no on-disk cache; its directory cannot be written): the caller compiles here."""
    from ._jit_cache import compile_policy

    if compile_policy() != "background":
        return None
    got = _JOBS.get((dispatcher, sig))
    if got is not None:
        return got
    where = _cache_dir(dispatcher)
    if where is None:
        return None
    lock = _lock_path(where, dispatcher, sig)
    mine = False
    for _ in range(2):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
        except FileExistsError:
            if _alive(lock):
                break                     # another process compiles it: wait for its lock
            try:
                lock.unlink()
            except OSError:
                return None
            continue
        except OSError:                   # (an unwritable cache: compile here)
            return None
        with os.fdopen(fd, "w") as fh:
            fh.write(f"{os.getpid()}\n")
        mine = True
        break
    else:
        return None
    job = _JOBS[(dispatcher, sig)] = _Job(dispatcher, sig, lock, mine)
    if mine:
        try:
            job.result.unlink(missing_ok=True)
        except OSError:
            pass
        _CHILD["queue"].append(job)
        _pump()
        if job.failed:                    # (the child could not be started)
            return job
    if say is not None:
        say("background")
    return job


def _pump() -> None:
    """Reap this process's finished child and start the next one for the queued jobs (at
    most one child at a time while this process lives: the machine's other core)."""
    if _CHILD.get("pid", os.getpid()) != os.getpid():
        # a forked copy of the process that started the child (a worker of a parallel
        # sweep): the child and the queue are the parent's; here the jobs wait for their locks
        for job in _CHILD["jobs"] + _CHILD["queue"]:
            job.mine = False
        _CHILD.update(proc=None, jobs=[], queue=[])
    _CHILD["pid"] = os.getpid()
    proc = _CHILD["proc"]
    if proc is not None:
        if proc.poll() is None:
            return
        for job in _CHILD["jobs"]:
            job.done = True
            try:                          # (a child that died early left it)
                job.lock.unlink(missing_ok=True)
            except OSError:
                pass
        _CHILD["proc"], _CHILD["jobs"] = None, []
    if _CHILD["queue"]:
        jobs, _CHILD["queue"] = _CHILD["queue"], []
        _start(jobs)


def _start(jobs) -> None:
    """Start one detached low-priority process compiling ``jobs`` into Numba's cache; a job
    it cannot start for is marked failed (its caller compiles in process)."""
    import pickle
    import subprocess
    import tempfile
    import threading

    where = jobs[0].lock.parent
    try:
        fd, name = tempfile.mkstemp(prefix="mechsys-bg-", suffix=".job", dir=where)
        with os.fdopen(fd, "wb") as fh:
            pickle.dump({"sys_path": list(sys.path), "jobs": [
                (j.dispatcher.py_func.__module__, j.dispatcher.py_func.__qualname__, j.sig,
                 str(j.lock), str(j.result)) for j in jobs]}, fh)
        root = str(Path(__file__).resolve().parents[2])     # (the directory holding mechsys)
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join([root] + [p for p in env.get(
            "PYTHONPATH", "").split(os.pathsep) if p])
        log = open(where / "mechsys-bg.log", "ab")          # noqa: SIM115 (the child's)
        try:
            proc = subprocess.Popen(
                [sys.executable, "-m", "mechsys.solvers._jit_background", name],
                stdin=subprocess.DEVNULL, stdout=log, stderr=log, env=env,
                start_new_session=True, close_fds=True)
        finally:
            log.close()
    except (OSError, pickle.PicklingError, TypeError, AttributeError) as exc:
        _LOG.warning("mechsys: could not start the background compile (%s); compiling in "
                     "this process", exc)
        for j in jobs:
            j.done = j.failed = True
            try:
                j.lock.unlink()
            except OSError:
                pass
        return
    _CHILD["proc"], _CHILD["jobs"] = proc, jobs
    # reaped as soon as it ends (no zombie while this process lives, whether or not it asks
    # again); the child outlives this process (its own session) and fills the cache anyway
    try:
        threading.Thread(target=proc.wait, name="mechsys-compile-reaper", daemon=True).start()
    except RuntimeError:        # (at interpreter shutdown, Python 3.12+: no reaping needed)
        pass
    if not _CHILD["exit_hook"]:
        import atexit

        atexit.register(_at_exit)
        _CHILD["exit_hook"] = True


def _at_exit() -> None:
    """At exit, start a child for the jobs still queued behind the running one (the cache is
    filled for the next session)."""
    if _CHILD.get("pid", os.getpid()) != os.getpid():
        return                    # (a forked copy: the queue is its parent's)
    queue, _CHILD["queue"] = _CHILD["queue"], []
    if queue:
        _start(queue)


def wait_background(timeout: float | None = None) -> bool:
    """Wait until this process's background compiles are over (at most ``timeout`` seconds);
    returns whether they are. For tests and benchmarks: a run never needs to wait."""
    deadline = None if timeout is None else time.monotonic() + timeout
    while True:
        _pump()
        proc = _CHILD["proc"]
        if proc is None and not _CHILD["queue"]:
            return True
        left = None if deadline is None else deadline - time.monotonic()
        if left is not None and left <= 0:
            return False
        try:
            proc.wait(timeout=left)
        except Exception:       # (subprocess.TimeoutExpired)
            return False


__all__ = ["entry", "in_cache", "signature", "wait_background", "within"]
