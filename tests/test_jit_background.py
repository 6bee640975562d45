"""The background tier of the compiled loops (decision 0064): a specialisation missing from the
process and from Numba's cache is compiled by another process while the caller takes its
Python path; afterwards it is loaded from the cache. A tiny dispatcher of the test's own,
with a literal argument like the loops' modes, in a private Numba cache directory, keeps it
cheap (the loops themselves: ``benchmarks/cold_start.py``)."""

from __future__ import annotations

import json
import logging
import sys
import uuid

import numpy as np
import pytest

from mechsys import ModelError

pytest.importorskip("numba")

_SOURCE = '''
import numba as nb


@nb.njit(cache=True)
def scaled(x, k):
    out = np.empty_like(x)
    for i in range(x.size):
        out[i] = 2.0 * x[i] + k
    return out


def _make():
    @nb.njit(cache=True)
    def hidden(x, k):          # (qualname _make.<locals>.hidden: no process can import it)
        return x.sum() * k
    return hidden


hidden = _make()
'''


@pytest.fixture
def probe(tmp_path, monkeypatch):
    """A fresh module of two cached dispatchers whose cache lives in a new private
    ``NUMBA_CACHE_DIR`` (this process's Numba and the child's), the background policy, and
    this process's background state reset."""
    import numba

    from mechsys.solvers import _jit_modes

    cache = tmp_path / "numba-cache"
    cache.mkdir(mode=0o700)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(cache))
    monkeypatch.setenv("MECHSYS_COMPILE", "background")
    name = f"mechsys_bg_probe_{uuid.uuid4().hex[:12]}"
    (tmp_path / f"{name}.py").write_text("import numpy as np\n" + _SOURCE)
    monkeypatch.syspath_prepend(str(tmp_path))
    import importlib

    mod = importlib.import_module(name)
    for attr, value in (("_WAITING", {}), ("_JOBS", {}),
                        ("_CHILD", {"proc": None, "jobs": [], "queue": [], "exit_hook": True})):
        monkeypatch.setattr(_jit_modes, attr, value)
    yield mod, cache
    assert _jit_modes.wait_background(timeout=300)     # (a safety net: no child left behind)
    sys.modules.pop(name, None)


def test_background_compile_then_load(probe):
    """First request: None, one child compiling into the cache, the caller's Python answer;
    after the child (waited for here only as a safety net): the machine code loaded from
    the cache (not compiled in this process), the same answer; the child reaped."""
    from mechsys.solvers import _jit_modes

    mod, cache = probe
    x = np.linspace(0.0, 1.0, 7)
    args = (x, 3)
    said = []
    assert _jit_modes.entry(mod.scaled, args, literal=(1,), say=said.append) is None
    assert said == ["background"]
    python = 2.0 * x + 3                               # the caller's Python path
    proc = _jit_modes._CHILD["proc"]
    assert proc is not None
    # asked again while it compiles: still None, no second child, nothing compiled here
    if proc.poll() is None:
        assert _jit_modes.entry(mod.scaled, args, literal=(1,), say=said.append) is None
    assert _jit_modes.wait_background(timeout=300)
    assert proc.returncode == 0                        # reaped: no zombie
    assert not mod.scaled.overloads                    # this process compiled nothing
    fn = _jit_modes.entry(mod.scaled, args, literal=(1,), say=said.append)
    assert fn is not None and said == ["background"]
    assert mod.scaled._cache_hits and not mod.scaled._cache_misses    # loaded, not compiled
    np.testing.assert_array_equal(fn(*args), python)
    (result,) = cache.rglob("mechsys-bg-*.json")
    got = json.loads(result.read_text())
    assert got["ok"] and "Literal[int](3)" in got["signature"] and got["cpu"] > 0
    assert not list(cache.rglob("mechsys-bg-*.lock"))


def test_failed_or_impossible_background_compiles_here(probe, monkeypatch, caplog, tmp_path):
    """A child that cannot compile (a dispatcher no process can import) is logged once and
    the request compiled in this process; a cache directory where no lock can be written
    compiles in this process at once. The answers are the Python ones."""
    from mechsys.solvers import _jit_modes

    mod, _ = probe
    x = np.arange(4.0)
    said = []
    assert _jit_modes.entry(mod.hidden, (x, 2), literal=(1,), say=said.append) is None
    assert _jit_modes.wait_background(timeout=300)
    with caplog.at_level(logging.WARNING, logger="mechsys"):
        fn = _jit_modes.entry(mod.hidden, (x, 2), literal=(1,), say=said.append)
        assert fn is not None
    assert fn(x, 2) == x.sum() * 2
    assert said == ["background", "wait"]
    warned = [r for r in caplog.records if "did not fill" in r.getMessage()]
    assert len(warned) == 1 and "hidden" in warned[0].getMessage()

    # a lock that cannot be written (the cache "directory" below a file): compiled here
    blocker = tmp_path / "not-a-directory"
    blocker.write_text("")
    monkeypatch.setattr(_jit_modes, "_cache_dir", lambda d: blocker / "cache")
    said.clear()
    fn = _jit_modes.entry(mod.scaled, (x, 5), literal=(1,), say=said.append)
    assert fn is not None and said == ["wait"] and _jit_modes._CHILD["proc"] is None
    np.testing.assert_array_equal(fn(x, 5), 2.0 * x + 5)


def test_compile_policy_is_validated(monkeypatch):
    """``MECHSYS_COMPILE``: background (default) or wait; a misspelling names the variable
    and the allowed values."""
    from mechsys.solvers._jit_runtime import compile_policy

    monkeypatch.delenv("MECHSYS_COMPILE", raising=False)
    assert compile_policy() == "background"
    monkeypatch.setenv("MECHSYS_COMPILE", " Wait ")
    assert compile_policy() == "wait"
    monkeypatch.setenv("MECHSYS_COMPILE", "later")
    with pytest.raises(ModelError, match=r"MECHSYS_COMPILE='later'.*background.*wait"):
        compile_policy()


def test_a_compile_under_way_elsewhere_is_waited_for(probe, caplog):
    """A lock held by another live process (here pid 1): no child is started, the caller
    takes its Python path; once the lock is gone without filling the cache (that process
    failed), the request compiles here, with a warning, and answers right. A lock whose
    process is gone is stale (:func:`_alive`)."""
    from mechsys.solvers import _jit_modes

    mod, _ = probe
    x = np.arange(3.0)
    sig = _jit_modes.signature((x, 7), (1,))
    lock = _jit_modes._lock_path(_jit_modes._cache_dir(mod.scaled), mod.scaled, sig)
    lock.write_text("1\n")
    assert _jit_modes._alive(lock)
    assert _jit_modes.entry(mod.scaled, (x, 7), literal=(1,)) is None
    assert _jit_modes._CHILD["proc"] is None and not _jit_modes._CHILD["queue"]
    assert _jit_modes.entry(mod.scaled, (x, 7), literal=(1,)) is None     # still held
    lock.unlink()
    with caplog.at_level(logging.WARNING, logger="mechsys"):
        fn = _jit_modes.entry(mod.scaled, (x, 7), literal=(1,))
    assert fn is not None and any("did not fill" in r.getMessage() for r in caplog.records)
    np.testing.assert_array_equal(fn(x, 7), 2.0 * x + 7)
    # a stale lock: a process that has ended
    import subprocess

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    lock.write_text(f"{gone.pid}\n")
    assert not _jit_modes._alive(lock)


_HOLDER = '''
import os, sys, time
lock, where, name, what = sys.argv[1:]
fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
os.write(fd, f"{os.getpid()}\\n".encode())
os.close(fd)
print("locked", flush=True)
time.sleep(0.5)                # (the other process is surely waiting by now)
if what == "compile":          # (writes the cache, as a compiling worker does)
    sys.path.insert(0, where)
    import importlib
    import numpy as np
    from mechsys.solvers import _jit_modes
    importlib.import_module(name).scaled.compile(_jit_modes.signature((np.arange(3.0), 7), (1,)))
os.unlink(lock)
'''


@pytest.mark.parametrize("holder", ["compile", "give up"])
def test_wait_policy_waits_for_another_process_compile(probe, monkeypatch, caplog, tmp_path,
                                                       holder):
    """``MECHSYS_COMPILE=wait`` (decision 0071): a specialisation another live process is
    compiling (its lock held) is waited for, then loaded from the cache (a cache hit, nothing
    compiled here); if that process lets go without filling the cache, it is compiled here.
    Either way the answer is the Python one, and no lock is left."""
    import subprocess

    from mechsys.solvers import _jit_modes

    mod, cache = probe
    monkeypatch.setenv("MECHSYS_COMPILE", "wait")
    x = np.arange(3.0)
    lock = _jit_modes._lock_path(_jit_modes._cache_dir(mod.scaled), mod.scaled,
                                 _jit_modes.signature((x, 7), (1,)))
    proc = subprocess.Popen([sys.executable, "-c", _HOLDER, str(lock), str(tmp_path),
                             mod.__name__, holder], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "locked"
        said = []
        with caplog.at_level(logging.INFO, logger="mechsys"):
            fn = _jit_modes.entry(mod.scaled, (x, 7), literal=(1,), say=said.append)
    finally:
        proc.wait(timeout=300)
    assert proc.returncode == 0
    assert said == ["wait"]
    assert any(f"waiting for process {proc.pid}" in r.getMessage() for r in caplog.records)
    np.testing.assert_array_equal(fn(x, 7), 2.0 * x + 7)
    if holder == "compile":
        assert mod.scaled._cache_hits and not mod.scaled._cache_misses   # loaded, not compiled
    else:
        assert mod.scaled._cache_misses                                   # compiled here
    assert not list(cache.rglob("mechsys-bg-*.lock"))


def test_wait_policy_holds_the_lock_while_it_compiles(probe, monkeypatch):
    """The process that compiles under ``wait`` holds the lock with its pid meanwhile (others
    wait for it) and removes it after; an empty lock (its creator has not written its pid
    yet) counts as held for a few seconds, then as stale."""
    import os
    import time

    from mechsys.solvers import _jit_modes

    mod, cache = probe
    monkeypatch.setenv("MECHSYS_COMPILE", "wait")
    x = np.arange(5.0)
    sig = _jit_modes.signature((x, 2), (1,))
    lock = _jit_modes._lock_path(_jit_modes._cache_dir(mod.scaled), mod.scaled, sig)
    seen = []

    def say(how):
        seen.append((how, lock.read_text().split()))

    fn = _jit_modes.entry(mod.scaled, (x, 2), literal=(1,), say=say)
    assert seen == [("wait", [str(os.getpid())])]
    assert not lock.exists() and mod.scaled._cache_misses
    np.testing.assert_array_equal(fn(x, 2), 2.0 * x + 2)
    lock.write_text("")
    assert _jit_modes._alive(lock)
    old = time.time() - 2 * _jit_modes._UNWRITTEN_SECONDS
    os.utime(lock, (old, old))
    assert not _jit_modes._alive(lock)
