"""The on-disk cache of compiled kernels (compile/_backends.py): a second build of the same
equations compiles nothing and gives the same numbers; a change anywhere in the equations,
down to the last bit of a length, gets its own kernel; a broken or unwritable cache costs
compile time, never a wrong answer."""

from __future__ import annotations

import numpy as np
import pytest

from mechsys import models
from mechsys.compile import _backends

pytest.importorskip("symengine")
pytestmark = pytest.mark.skipif(_backends.default_backend() != "symengine", reason="LLVM kernels only")

T = np.linspace(0.0, 1.0, 21)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    d = tmp_path / "kernels"
    monkeypatch.setenv("MECHSYS_CACHE", str(d))
    return d


def _no_compiler(monkeypatch):
    def refuse(*a, **k):
        raise AssertionError("compiled although cached")

    monkeypatch.setattr(_backends._se, "Lambdify", refuse)


def test_second_build_compiles_nothing_and_agrees(cache, monkeypatch):
    first = models.slider_crank().solve(T)
    files = sorted(cache.glob("*.kernel"))
    assert len(files) == 3                      # position, velocity, gamma kernels
    _no_compiler(monkeypatch)
    second = models.slider_crank().solve(T)
    np.testing.assert_array_equal(second.q, first.q)
    np.testing.assert_array_equal(second.qdd, first.qdd)


def test_last_bit_of_a_length_makes_a_new_kernel(cache):
    """Printed SymEngine expressions round doubles to 15 digits: the key must not."""
    rod = 6.0
    rod2 = rod + 2e-15
    assert str(_backends._se.sympify(rod)) == str(_backends._se.sympify(rod2))   # same print
    a = models.slider_crank(rod=rod).compile()
    x = a.pack(0.3, a.guess)
    fa = a.f_position(x)
    n_files = len(list(cache.glob("*.kernel")))
    b = models.slider_crank(rod=rod2).compile()
    fb = b.f_position(x)
    assert len(list(cache.glob("*.kernel"))) > n_files
    # the kernel of the second model holds its own rod length, to the last bit
    assert np.abs(fb - fa).max() > 0


def test_corrupt_entry_is_replaced(cache):
    good = models.slider_crank().solve(T)
    for f in cache.glob("*.kernel"):
        f.write_bytes(b"not a kernel")
    again = models.slider_crank().solve(T)
    np.testing.assert_array_equal(again.q, good.q)
    for f in cache.glob("*.kernel"):
        assert f.read_bytes() != b"not a kernel"


def test_cache_off_and_unwritable(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHSYS_CACHE", "0")
    assert _backends.cache_dir() is None
    ref = models.slider_crank().solve(T)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    monkeypatch.setenv("MECHSYS_CACHE", str(blocker / "sub"))    # cannot be created
    sol = models.slider_crank().solve(T)
    np.testing.assert_array_equal(sol.q, ref.q)
    assert not list(tmp_path.glob("**/*.tmp"))


# -- tampering (issue 39): nothing foreign is ever loaded -------------------------------------
import os  # noqa: E402
import pickle  # noqa: E402
import shutil  # noqa: E402
import time  # noqa: E402

import mechsys as ms  # noqa: E402
from mechsys import _private  # noqa: E402
from mechsys.compile import _cache  # noqa: E402


def _never_read(monkeypatch):
    """Fail the test if an entry's contents reach the loader."""
    def refuse(*a, **k):
        raise AssertionError("an entry was read")

    monkeypatch.setattr(_cache, "_from_data", refuse)


def test_entries_are_data_not_pickles(cache, monkeypatch):
    """The cached second build unpickles nothing (an entry is JSON and object code)."""
    first = models.slider_crank().solve(T)
    for f in cache.glob("*.kernel"):
        assert f.read_bytes().startswith(_cache.MAGIC)
        assert oct(f.stat().st_mode & 0o777) == oct(0o600)
    assert oct(cache.stat().st_mode & 0o777) == oct(0o700)
    assert oct((cache / _cache.SECRET).stat().st_mode & 0o777) == oct(0o600)

    def refuse(*a, **k):
        raise AssertionError("unpickled")

    monkeypatch.setattr(pickle, "load", refuse)
    monkeypatch.setattr(pickle, "loads", refuse)
    _no_compiler(monkeypatch)
    second = models.slider_crank().solve(T)
    np.testing.assert_array_equal(second.qdd, first.qdd)


def test_directory_writable_by_others_is_refused(cache, monkeypatch):
    models.slider_crank().solve(T)
    os.chmod(cache, 0o777)
    _never_read(monkeypatch)
    with pytest.raises(ms.CacheError) as err:
        models.slider_crank().solve(T)
    msg = str(err.value)
    assert str(cache) in msg and "writable by others" in msg and "MECHSYS_CACHE" in msg


def test_world_writable_directory_made_by_someone_else_is_refused(tmp_path, monkeypatch):
    """The guide's old example: a shared temporary directory someone else created first."""
    d = tmp_path / "shared"
    d.mkdir()
    os.chmod(d, 0o1777)
    monkeypatch.setenv("MECHSYS_CACHE", str(d))
    with pytest.raises(ms.CacheError, match="writable by others"):
        models.slider_crank().solve(T)
    assert not (d / _cache.SECRET).exists()       # nothing written there either


def test_directory_owned_by_someone_else_is_refused(cache, monkeypatch):
    models.slider_crank().solve(T)
    uid = os.geteuid()
    monkeypatch.setattr(_private, "my_uid", lambda: uid + 1)   # as if another user ran it
    _never_read(monkeypatch)
    with pytest.raises(ms.CacheError) as err:
        models.slider_crank().solve(T)
    assert "owned by" in str(err.value) and str(cache) in str(err.value)


def test_entry_owned_by_someone_else_is_refused(cache, monkeypatch):
    models.slider_crank().solve(T)
    uid = os.geteuid()
    real = os.fstat

    def fstat(fd):      # the directory is ours, the entries are someone else's
        st = real(fd)
        return os.stat_result((st.st_mode, st.st_ino, st.st_dev, st.st_nlink, uid + 1,
                               *tuple(st)[5:10]))

    monkeypatch.setattr(_cache.os, "fstat", fstat)
    _never_read(monkeypatch)
    with pytest.raises(ms.CacheError, match="kernel cache entry .* is owned by"):
        models.slider_crank().solve(T)


def test_entry_writable_by_others_is_refused(cache, monkeypatch):
    models.slider_crank().solve(T)
    for f in cache.glob("*.kernel"):
        os.chmod(f, 0o666)
    _never_read(monkeypatch)
    with pytest.raises(ms.CacheError, match="writable by others"):
        models.slider_crank().solve(T)


def test_key_readable_by_others_is_refused(cache):
    models.slider_crank().solve(T)
    os.chmod(cache / _cache.SECRET, 0o644)
    _cache._opened.clear()
    with pytest.raises(ms.CacheError, match="readable by others"):
        models.slider_crank().solve(T)


def test_swapped_entry_is_rebuilt_not_used(cache):
    """Another model's genuine entry copied in place of this one's: detected (its tag was
    made for the other key), deleted and compiled again; the numbers are this model's."""
    models.slider_crank(rod=6.0).solve(T)
    a = {f.name for f in cache.glob("*.kernel")}
    ref = models.slider_crank(rod=7.0).solve(T)
    b = sorted(f for f in cache.glob("*.kernel") if f.name not in a)
    assert len(b) == 3
    donor = cache / sorted(a)[0]
    for f in b:
        shutil.copyfile(donor, f)
    again = models.slider_crank(rod=7.0).solve(T)
    np.testing.assert_array_equal(again.q, ref.q)
    np.testing.assert_array_equal(again.qdd, ref.qdd)
    for f in b:   # replaced by this model's kernels
        assert f.read_bytes() != donor.read_bytes()


def test_entry_forged_without_the_key_is_rebuilt(cache, monkeypatch):
    """An entry of the right layout signed with another secret (an attacker's) is not used."""
    ref = models.slider_crank().solve(T)
    files = sorted(cache.glob("*.kernel"))
    originals = [f.read_bytes() for f in files]
    real = _cache._opened[str(cache)]
    _cache._opened[str(cache)] = os.urandom(32)
    for f in files:
        f.unlink()
    models.slider_crank().solve(T)              # entries signed with the wrong key
    forged = [f.read_bytes() for f in files]
    assert forged != originals
    _cache._opened[str(cache)] = real
    calls = []
    monkeypatch.setattr(_cache, "_from_data", lambda *a: calls.append(a))
    again = models.slider_crank().solve(T)
    np.testing.assert_array_equal(again.q, ref.q)
    assert calls == []                          # no forged entry reached the loader


def test_old_entries_and_pickles_are_pruned(cache):
    models.slider_crank().solve(T)
    files = sorted(cache.glob("*.kernel"))
    old = time.time() - (_cache.MAX_AGE_DAYS + 1) * 86400
    os.utime(files[0], (old, old))
    (cache / "0123.pkl").write_bytes(b"an old pickle")
    assert _cache.prune(cache) == 2
    assert not files[0].exists() and files[1].exists() and not (cache / "0123.pkl").exists()


def test_size_bound(cache, monkeypatch):
    models.slider_crank().solve(T)
    files = sorted(cache.glob("*.kernel"), key=lambda f: f.stat().st_size)
    for i, f in enumerate(files):        # the first is the least recently used
        os.utime(f, (1e9 + i, 1e9 + i + time.time() - 1e9 - 10))
    keep = files[-1].stat().st_size + files[-2].stat().st_size
    monkeypatch.setenv("MECHSYS_CACHE_MAX_MB", str(keep / 1e6))
    assert _cache.prune(cache) == 1
    assert not files[0].exists() and files[1].exists() and files[2].exists()


def test_cli_cache_info_and_clear(cache, capsys):
    from mechsys.cli import main

    models.slider_crank().solve(T)
    assert main(["cache", "info"]) == 0
    out = capsys.readouterr().out
    assert str(cache) in out and "entries: 3" in out
    assert main(["cache", "clear"]) == 0
    assert "deleted 3 files" in capsys.readouterr().out
    assert not list(cache.glob("*.kernel"))
    os.chmod(cache, 0o777)
    assert main(["cache", "clear"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "writable by others" in err


def test_numba_cache_dir_must_be_private(tmp_path, monkeypatch):
    from mechsys.solvers import _jit_cache

    d = tmp_path / "numba"
    d.mkdir()
    os.chmod(d, 0o777)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(d))
    with pytest.raises(ms.CacheError, match="NUMBA_CACHE_DIR"):
        _jit_cache.check_safe(tmp_path)
    os.chmod(d, 0o700)
    _jit_cache.check_safe(tmp_path)
    pyc = tmp_path / "__pycache__"
    pyc.mkdir()
    os.chmod(pyc, 0o777)
    with pytest.raises(ms.CacheError, match="__pycache__"):
        _jit_cache.check_safe(tmp_path)


def test_group_write_refused_unless_the_users_private_group(cache, monkeypatch):
    """umask 002 (user private groups) makes 775 directories: group write is then the
    user's own; any other group's write is refused."""
    models.slider_crank().solve(T)
    os.chmod(cache, 0o770)
    monkeypatch.setattr(_private, "private_group", lambda st: False)
    with pytest.raises(ms.CacheError, match="writable by others"):
        models.slider_crank().solve(T)
    monkeypatch.setattr(_private, "private_group", lambda st: True)
    _no_compiler(monkeypatch)
    models.slider_crank().solve(T)
