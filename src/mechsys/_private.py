"""Directories and files only their user may have written: the checks every on-disk cache of
mechsys makes before it reads anything (docs/decisions/0037-safe-caches-and-files.md).

A cache read back by the library is code in waiting (compiled kernels, Numba's pickled
indexes): a directory another user created first, or may write to, would let that user
run code as everyone who uses mechsys after them. So a cache directory is created private
(mode 0700) and, before anything in it is read, it and every file read from it must be
owned by the user running mechsys and writable by nobody else; otherwise
:class:`~mechsys.CacheError` names the path, never reads it. On systems without POSIX
owners (Windows) the checks are skipped: the per-user profile directory protects the cache.

This module imports nothing of mechsys but its errors, so that the compiled solvers (the
ground layer) can use it too.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ._errors import CacheError


def my_uid() -> int | None:
    """The effective user id of this process (None where the OS has no owners)."""
    return os.geteuid() if hasattr(os, "geteuid") else None


def _owner_name(uid: int) -> str:
    try:
        import pwd

        return f"{pwd.getpwuid(uid).pw_name!r} (uid {uid})"
    except (ImportError, KeyError):
        return f"uid {uid}"


def private_group(st: os.stat_result) -> bool:
    """The group of ``st`` is its owner's private group (named like the owner, no other
    members): group write is then no one else's write (the umask 002 of systems with user
    private groups makes such directories)."""
    try:
        import grp
        import pwd

        g = grp.getgrgid(st.st_gid)
        return not g.gr_mem and g.gr_name == pwd.getpwuid(st.st_uid).pw_name
    except (ImportError, KeyError):
        return False


def check_private(path: Path, st: os.stat_result, what: str, hint: str) -> None:
    """Raise :class:`~mechsys.CacheError` unless ``st`` (of ``path``) is owned by this user and
    writable by nobody else (no other write bit; no group write bit unless the group is the
    user's private group, :func:`private_group`). ``what`` names the object in the
    message, ``hint`` says what to do."""
    uid = my_uid()
    if uid is None:
        return
    if st.st_uid != uid:
        raise CacheError(f"{what} {path} is owned by {_owner_name(st.st_uid)}, not by you "
                         f"({_owner_name(uid)}); mechsys reads nothing from it. {hint}")
    if st.st_mode & stat.S_IWOTH or (st.st_mode & stat.S_IWGRP and not private_group(st)):
        raise CacheError(f"{what} {path} is writable by others (mode {stat.S_IMODE(st.st_mode):o}); "
                         f"mechsys reads nothing from it. {hint}")


def private_dir(path: Path, what: str, hint: str) -> Path:
    """``path`` as a directory private to this user: created with mode 0700 when missing
    (its missing parents too), then checked by :func:`check_private` (it must be a real
    directory, not a symbolic link). ``OSError`` when it cannot be created."""
    path = Path(path)
    if not os.path.lexists(path):
        # parents as private as the leaf: a cache under a new ~/.cache is nobody else's
        for parent in reversed(path.parents):
            if not os.path.lexists(parent):
                os.mkdir(parent, 0o700)
        try:
            os.mkdir(path, 0o700)
        except FileExistsError:      # another process of ours made it meanwhile
            pass
    st = os.lstat(path)
    if stat.S_ISLNK(st.st_mode):
        # a link may point anywhere: the directory it names must pass the checks, and so
        # must the link itself (whoever owns it decides where it points)
        uid = my_uid()
        if uid is not None and st.st_uid != uid:
            raise CacheError(f"{what} {path} is a symbolic link owned by "
                             f"{_owner_name(st.st_uid)}, not by you; mechsys reads nothing "
                             f"from it. {hint}")
        st = os.stat(path)
    if not stat.S_ISDIR(st.st_mode):
        raise CacheError(f"{what} {path} is not a directory. {hint}")
    check_private(path, st, what, hint)
    return path
