"""``solvers._jit_cache``: cached compiled loops are dropped when any solver source changes
(Numba alone would only notice a change of the loop's own file)."""

from mechsys.solvers import _jit_cache


def _tree(tmp_path):
    (tmp_path / "_jit_loop.py").write_text("X = 1\n")
    (tmp_path / "_linalg.py").write_text("RCOND_MIN = 1e-12\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    files = [cache / "_jit_loop.sweep-10.py311.nbi", cache / "_jit_loop.sweep-10.py311.1.nbc",
             cache / "_tree._fill-12.py311.1.nbc"]
    for f in files:
        f.write_bytes(b"machine code")
    other = cache / "_linalg.cpython-311.pyc"
    other.write_bytes(b"bytecode")
    return files, other


def test_stale_loops_are_deleted_when_a_dependency_changes(tmp_path):
    files, other = _tree(tmp_path)
    # no stamp yet: the cache's sources are unknown, so it goes
    assert _jit_cache.sync(tmp_path) is True
    assert not any(f.exists() for f in files) and other.exists()
    # compiled again from these sources: kept while they do not change
    for f in files:
        f.write_bytes(b"machine code")
    assert _jit_cache.sync(tmp_path) is False
    assert all(f.exists() for f in files)
    # a constant the loop bakes in changes in another module: the loops go
    (tmp_path / "_linalg.py").write_text("RCOND_MIN = 1e-10\n")
    assert _jit_cache.sync(tmp_path) is True
    assert not any(f.exists() for f in files) and other.exists()


def test_digest_covers_names_and_contents(tmp_path):
    (tmp_path / "a.py").write_text("1")
    d1 = _jit_cache.sources_digest(tmp_path)
    (tmp_path / "a.py").write_text("2")
    d2 = _jit_cache.sources_digest(tmp_path)
    (tmp_path / "a.py").rename(tmp_path / "b.py")
    (tmp_path / "b.py").write_text("2")
    assert len({d1, d2, _jit_cache.sources_digest(tmp_path)}) == 3


def test_the_package_cache_is_stamped_with_its_sources():
    import mechsys.solvers._jit_lapack  # noqa: F401  (runs the check)

    stamp = _jit_cache._HERE / "__pycache__" / _jit_cache._STAMP
    if stamp.parent.is_dir() and stamp.exists():      # a read-only install stamps nothing
        assert stamp.read_text().strip() == _jit_cache.sources_digest(_jit_cache._HERE)
