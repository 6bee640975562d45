"""Keeps Numba's on-disk cache of the compiled loops consistent with their sources.

Numba keys a cached function on the timestamp of its own source file only. The loops call,
inline or link code from other modules (``_jit_lapack``, ``_jit_borrow``, ``_tree``) and bake
in constants from others (``RCOND_MIN``, ``ZONE``), so an edit there leaves a loop compiled
from the old code in the cache, and it would be loaded as if current: a silent wrong
answer. At the first import of a loop module, :func:`check` hashes the sources of the
``solvers`` package; when the hash differs from the one stored beside the cache, the cached
loops are deleted and compile again on first use (about two minutes for all of them).

Only the cache beside the sources (``solvers/__pycache__``, where Numba writes it for a
checkout or a writable install) is managed; an installed copy's files change their
timestamps when reinstalled, which Numba's own check sees.
"""

from __future__ import annotations

import hashlib
import logging
import os
import sys
from pathlib import Path

_HERE = Path(__file__).resolve().parent
_STAMP = "mechsys-jit-sources.sha256"
_done: dict = {}
_said: set = set()
_LOG = logging.getLogger("mechsys")


def sources_digest(directory: Path) -> str:
    """SHA-256 over the names and contents of the ``*.py`` files of ``directory``."""
    h = hashlib.sha256()
    for path in sorted(directory.glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def sync(directory: Path) -> bool:
    """Delete the cached Numba functions (``*.nbi``, ``*.nbc``) of ``directory/__pycache__``
    unless they were made from the current sources (the stored digest); returns True when
    it deleted. A directory that cannot be written is left alone (Numba then caches
    elsewhere)."""
    cache = directory / "__pycache__"
    digest = sources_digest(directory)
    stamp = cache / _STAMP
    try:
        if stamp.is_file() and stamp.read_text().strip() == digest:
            return False
        stale = list(cache.glob("*.nb[ic]")) if cache.is_dir() else []
        for p in stale:
            p.unlink(missing_ok=True)
        cache.mkdir(exist_ok=True)
        stamp.write_text(digest + "\n")
        return bool(stale)
    except OSError:
        return False


def check_safe(directory: Path) -> None:
    """Refuse (:class:`~mechsys.CacheError`) a Numba cache that someone else could have
    written: Numba reads its index files (``*.nbi``) with ``pickle``, so whoever can write
    them runs code as the user. ``NUMBA_CACHE_DIR``, when set, must be a directory private to
    the user (created 0700 when missing); the cache beside the sources
    (``directory/__pycache__``) must be writable by nobody but its owner, and owned by the
    user or by the owner of the sources (whoever installed mechsys)."""
    import os
    import stat

    from .._errors import CacheError
    from .._private import my_uid, private_dir, private_group

    hint = ("Point NUMBA_CACHE_DIR at a directory only you can write (or unset it), or "
            "MECHSYS_JIT=0 to run without compiled loops.")
    env = os.environ.get("NUMBA_CACHE_DIR", "").strip()
    if env:
        try:
            private_dir(Path(env).expanduser(), "Numba's cache directory (NUMBA_CACHE_DIR)", hint)
        except OSError:
            pass                     # cannot be made: Numba caches nothing there
    cache = directory / "__pycache__"
    uid = my_uid()
    try:
        st = os.stat(cache)
        owner = os.stat(directory).st_uid
    except OSError:
        return
    if uid is None:
        return
    if st.st_uid not in (uid, owner) or st.st_mode & stat.S_IWOTH or (
            st.st_mode & stat.S_IWGRP and not private_group(st)):
        raise CacheError(f"Numba's cache of mechsys's compiled loops, {cache}, is owned by uid "
                         f"{st.st_uid} (mode {stat.S_IMODE(st.st_mode):o}): it must be owned by you "
                         "or by the owner of the installed package and writable by nobody else; "
                         f"mechsys reads nothing from it. Remove it (it is made again) and {hint[0].lower()}"
                         f"{hint[1:]}")


def check() -> None:
    """:func:`check_safe` and :func:`sync` of the ``solvers`` package, once per process (before
    any loop compiles)."""
    if not _done:
        check_safe(_HERE)
        _done["deleted"] = sync(_HERE)


def compile_policy() -> str:
    """``"background"`` or ``"wait"`` from ``MECHSYS_COMPILE``: what a run does when the
    compiled loop it needs is neither in the process nor in Numba's on-disk cache (decision
    0064). ``background`` (unset: the default): one low-priority process compiles it into the
    cache while this run takes the Python path, and switches to the compiled loop once the
    compile is done; ``wait``: compile it in this process first (the run waits for it).
    Anything else raises :class:`ModelError`, like ``MECHSYS_JIT``."""
    v = os.environ.get("MECHSYS_COMPILE", "").strip().lower()
    if v in ("", "background"):
        return "background"
    if v == "wait":
        return "wait"
    from .._errors import ModelError

    raise ModelError(f"MECHSYS_COMPILE={os.environ['MECHSYS_COMPILE']!r}: use background "
                     "(unset: the default; compile in another process, this run continues "
                     "without the compiled loop) or wait (compile in this process first)")


def cached(module: str, function: str) -> bool:
    """Whether Numba's on-disk cache holds the compiled ``module.function`` of this package
    (its index file ``module.function-LINE.pyXY.nbi``, beside the sources or under
    ``NUMBA_CACHE_DIR``)."""
    pattern = f"{module}.{function}-*.nbi"
    try:
        if any((_HERE / "__pycache__").glob(pattern)):
            return True
        root = os.environ.get("NUMBA_CACHE_DIR")
        return bool(root) and any(Path(root).rglob(pattern))
    except OSError:
        return False


def notice(what: str, seconds: float | None, *functions: tuple, background: bool = False) -> bool:
    """Say once per process that ``what`` is being compiled, when one of ``functions``
    (``(module, function)`` pairs) is not in Numba's cache: the compile takes about
    ``seconds`` of CPU (measured by ``benchmarks/cold_start.py``; None: not measured on its
    own, the message gives no figure), and a silent wait of that long looks like a hang.
    With no ``functions`` the caller has found the compile needed (``_jit_modes.entry``: a
    specialisation missing from the cache). ``background``: the compile runs in another
    process (decision 0064) and this run continues without it. The message goes to the
    ``mechsys`` logger
    (INFO); when logging is not configured and stderr is a terminal it is also printed
    there. Returns whether it was said."""
    key = (what, background) + tuple(functions)
    if key in _said:
        return False
    _said.add(key)
    if functions and all(cached(m, f) for m, f in functions):
        return False
    if background:
        cost = "" if seconds is None else f" (about {seconds:.0f} s of CPU on another core)"
        msg = (f"mechsys: compiling {what} in the background{cost}; this run continues "
               "without it, later runs use it")
    else:
        cost = "" if seconds is None else f", about {seconds:.0f} s of CPU"
        msg = f"mechsys: compiling {what} (first run{cost}; cached for later runs)"
    _LOG.info(msg)
    isatty = getattr(sys.stderr, "isatty", lambda: False)
    if not _LOG.hasHandlers() and isatty():
        print(msg, file=sys.stderr, flush=True)
    return True


__all__ = ["cached", "check", "check_safe", "compile_policy", "notice", "sources_digest", "sync"]
