r"""The on-disk cache of compiled LLVM kernels (``MECHSYS_CACHE``), safe against other users.

A kernel is machine code: whoever can put an entry where mechsys reads it runs code as the
user. So (docs/decisions/0037-safe-caches-and-files.md):

* **No pickle.** An entry is data: a fixed header, a JSON object of the numbers SymEngine
  needs to load the kernel (argument and output counts and shapes, checked field by field)
  and the object code SymEngine's LLVM backend produced. Loading parses the JSON and hands
  the bytes to SymEngine's loader; nothing in the file names a Python callable.
* **Authenticated.** Before its object code is loaded, an entry's HMAC-SHA256 tag is checked
  against a 32-byte secret of the user (``<cache>/secret.key``, mode 0600, made on first
  use), computed over the entry's *key* — a hash of the kernel's exact equations
  (:func:`fingerprint`), arguments, optimisation options, the versions of mechsys,
  SymEngine and NumPy and this machine's CPU — and over its contents. An entry written by
  anyone without the secret, or another model's genuine entry copied in place of this one
  (its tag was made for another key), fails the check: it is deleted and the kernel compiled
  again, never loaded.
* **Private.** The directory is created with mode 0700; the directory, the secret and every
  entry must be owned by the user and writable by nobody else, else
  :class:`~mechsys.CacheError` (nothing is read). See :mod:`mechsys._private`.
* **Bounded.** Entries unused for :data:`MAX_AGE_DAYS` days are deleted, then the oldest
  until the directory holds at most ``MECHSYS_CACHE_MAX_MB`` (default :data:`MAX_MB`)
  megabytes; checked when a process stores its first kernel. ``mechsys cache clear``
  empties it, ``mechsys cache info`` reports it.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import stat
import struct
import time
from pathlib import Path

from .._errors import CacheError
from .._private import check_private, my_uid, private_dir

#: bump when the layout of an entry changes (old entries are then never read, and pruned)
FORMAT = 2
MAGIC = b"MECHSYS-KERNEL\x00"
SUFFIX = ".kernel"
SECRET = "secret.key"
MAX_AGE_DAYS = 60
MAX_MB = 2048
#: an entry larger than this is not a kernel of ours (the largest measured: ~40 MB)
MAX_ENTRY_BYTES = 1 << 30

_HINT_ENV = ("Set MECHSYS_CACHE to a directory only you can write (it is created with mode "
             "0700 when missing, e.g. MECHSYS_CACHE=~/.cache/mechsys/kernels), or "
             "MECHSYS_CACHE=off to compile without a cache.")
_HINT_DEFAULT = ("Remove it (mechsys makes it again, private to you), or set MECHSYS_CACHE to "
                 "a directory only you can write, or MECHSYS_CACHE=off.")


def cache_dir() -> Path | None:
    """Where compiled LLVM kernels are kept between runs, or None when caching is off.

    ``MECHSYS_CACHE``: ``0``/``off`` disables the cache, a path chooses the directory;
    default ``$XDG_CACHE_HOME/mechsys/kernels`` (``~/.cache/mechsys/kernels``). The path is
    not checked here; :func:`open_dir` checks it before anything is read."""
    env = os.environ.get("MECHSYS_CACHE", "").strip()
    if env.lower() in ("0", "off", "false", "no"):
        return None
    if env and env.lower() not in ("1", "on", "true", "yes"):
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "mechsys" / "kernels"


def _hint() -> str:
    env = os.environ.get("MECHSYS_CACHE", "").strip()
    return _HINT_ENV if env and env.lower() not in ("1", "on", "true", "yes") else _HINT_DEFAULT


#: directory -> secret, once checked in this process
_opened: dict = {}


def open_dir() -> tuple[Path, bytes] | None:
    """``(directory, secret)`` of the kernel cache, created private when missing and checked
    (:class:`~mechsys.CacheError` when not private); None when caching is off or the
    directory cannot be created (an unwritable place costs compile time, nothing else)."""
    d = cache_dir()
    if d is None:
        return None
    try:
        private_dir(d, "the kernel cache directory", _hint())    # checked at every use
    except OSError:
        return None
    key = str(d)
    if key not in _opened:
        secret = _secret(d)
        if secret is None:
            return None
        _opened[key] = secret
    return d, _opened[key]


def _secret(d: Path) -> bytes | None:
    """The user's 32-byte key of ``d`` (made on first use, mode 0600)."""
    path = d / SECRET
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600)
    except FileExistsError:
        pass
    except OSError:
        return None
    else:
        with os.fdopen(fd, "wb") as fh:
            fh.write(os.urandom(32))
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError as exc:
        raise CacheError(f"the kernel cache's key {path} cannot be opened ({exc.strerror}); "
                         f"{_hint()}") from None
    with os.fdopen(fd, "rb") as fh:
        st = os.fstat(fh.fileno())
        _check_entry(path, st, "the kernel cache's key")
        if my_uid() is not None and st.st_mode & 0o077:
            raise CacheError(f"the kernel cache's key {path} is readable by others (mode "
                             f"{stat.S_IMODE(st.st_mode):o}); delete it (mechsys makes a new one, "
                             "mode 600) and the cache's entries with `mechsys cache clear`")
        secret = fh.read(33)
    if len(secret) != 32:
        raise CacheError(f"the kernel cache's key {path} is not 32 bytes; delete it and "
                         "`mechsys cache clear`")
    return secret


def _check_entry(path: Path, st, what: str) -> None:
    if not stat.S_ISREG(st.st_mode):
        raise CacheError(f"{what} {path} is not a regular file; mechsys reads nothing from it. "
                         f"{_hint()}")
    check_private(path, st, what, _hint())


def entry_key(parts) -> str:
    """The hex SHA-256 naming an entry: of ``parts`` (strings), with the cache format and the
    versions of mechsys, SymEngine and NumPy in front."""
    import sys

    import numpy
    import symengine

    __version__ = getattr(sys.modules.get("mechsys"), "__version__", "?")
    h = hashlib.sha256()
    for part in (f"format={FORMAT}", f"mechsys={__version__}", f"symengine={symengine.__version__}",
                 f"numpy={numpy.__version__}", *parts):
        h.update(part.encode("utf-8", "surrogatepass"))
        h.update(b"\0")
    return h.hexdigest()


def _tag(secret: bytes, key: str, header: bytes, blob: bytes) -> bytes:
    mac = hmac.new(secret, digestmod=hashlib.sha256)
    for part in (MAGIC, key.encode(), struct.pack("<QQ", len(header), len(blob)), header, blob):
        mac.update(part)
    return mac.digest()


# -- what an entry holds: SymEngine's LLVMDouble, as data ----------------------------------
def _to_data(f) -> tuple[bytes, bytes] | None:
    """``(header, object code)`` of a SymEngine LLVM ``Lambdify``; None if it is not one whose
    layout this module knows (then it is simply not cached)."""
    import numpy as np

    try:
        loader, args = f.__reduce__()[:2]
    except Exception:  # noqa: BLE001 - any failure: do not cache
        return None
    if getattr(loader, "__name__", "") != "llvm_loading_func" or len(args) != 9:
        return None
    n_in, n_out, shapes, real, n_exprs, order, sizes, dtype, blob = args
    if dtype is not np.float64 or not isinstance(blob, bytes):
        return None
    header = {"n_in": n_in, "n_out": n_out, "shapes": [list(s) for s in shapes], "real": real,
              "n_exprs": n_exprs, "order": order, "sizes": list(sizes)}
    return json.dumps(header, sort_keys=True).encode(), blob


def _ints(v, n: int | None = None) -> bool:
    return isinstance(v, list) and (n is None or len(v) == n) and all(
        type(i) is int and 0 <= i < (1 << 40) for i in v)


def _from_data(header: bytes, blob: bytes):
    """The kernel of an authenticated entry, or None when its header is not well formed."""
    import numpy as np
    from symengine.lib.symengine_wrapper import llvm_loading_func

    try:
        h = json.loads(header)
    except ValueError:
        return None
    if not isinstance(h, dict) or set(h) != {"n_in", "n_out", "shapes", "real", "n_exprs", "order",
                                             "sizes"}:
        return None
    if not (_ints([h["n_in"], h["n_out"], h["n_exprs"]]) and h["real"] is True
            and h["order"] in ("C", "F") and isinstance(h["shapes"], list)
            and all(_ints(s) for s in h["shapes"]) and _ints(h["sizes"])):
        return None
    return llvm_loading_func(h["n_in"], h["n_out"], [tuple(s) for s in h["shapes"]], True,
                             h["n_exprs"], h["order"], h["sizes"], np.float64, blob)


# -- load and store --------------------------------------------------------------------------
def load(key: str):
    """The kernel stored under ``key``, or None (no entry, or one that failed its checks and
    was deleted). :class:`~mechsys.CacheError` when the directory or the entry is not
    private to the user."""
    opened = open_dir()
    if opened is None:
        return None
    d, secret = opened
    path = d / (key + SUFFIX)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        return None
    except OSError:                       # a link (O_NOFOLLOW) or unreadable: not ours to read
        _discard(path)
        return None
    with os.fdopen(fd, "rb") as fh:
        st = os.fstat(fh.fileno())
        _check_entry(path, st, "the kernel cache entry")
        if st.st_size > MAX_ENTRY_BYTES:
            data = b""
        else:
            data = fh.read(MAX_ENTRY_BYTES + 1)
    parsed = _parse(data)
    if parsed is None or not hmac.compare_digest(parsed[0], _tag(secret, key, *parsed[1:])):
        # damaged, forged, or another kernel's entry copied here: compile again
        _discard(path)
        return None
    f = _from_data(*parsed[1:])
    if f is None:                                              # pragma: no cover - our own data
        _discard(path)
        return None
    try:
        os.utime(path)                    # used: the age bound counts from the last use
    except OSError:
        pass
    return f


def _parse(data: bytes):
    """``(tag, header, blob)`` of an entry's bytes, or None."""
    n = len(MAGIC)
    if len(data) < n + 32 + 16 or data[:n] != MAGIC:
        return None
    tag = data[n:n + 32]
    nh, nb = struct.unpack("<QQ", data[n + 32:n + 48])
    body = data[n + 48:]
    if nh + nb != len(body):
        return None
    return tag, body[:nh], body[nh:]


def _discard(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass


def store(key: str, f) -> None:
    """Keep kernel ``f`` under ``key`` (atomically: a parallel run never reads half a file).
    Failures to write cost compile time only."""
    opened = open_dir()
    if opened is None:
        return
    d, secret = opened
    data = _to_data(f)
    if data is None:
        return
    header, blob = data
    tag = _tag(secret, key, header, blob)
    tmp = d / f".{key}.{os.getpid()}.tmp"
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_NOFOLLOW", 0), 0o600)
        with os.fdopen(fd, "wb") as fh:
            fh.write(MAGIC + tag + struct.pack("<QQ", len(header), len(blob)) + header + blob)
        os.replace(tmp, d / (key + SUFFIX))
    except OSError:
        _discard(tmp)
        return
    if not _pruned.get(str(d)):
        _pruned[str(d)] = True
        prune(d)


_pruned: dict = {}


def max_bytes() -> int:
    """The size bound: ``MECHSYS_CACHE_MAX_MB`` megabytes (default :data:`MAX_MB`)."""
    try:
        mb = float(os.environ.get("MECHSYS_CACHE_MAX_MB", MAX_MB))
    except ValueError:
        mb = MAX_MB
    return int(max(mb, 0.0) * 1e6)


def _entries(d: Path) -> list[tuple[float, int, Path]]:
    out = []
    for e in os.scandir(d):
        if e.name == SECRET:
            continue
        try:
            st = e.stat(follow_symlinks=False)
        except OSError:
            continue
        out.append((st.st_mtime, st.st_size, Path(e.path)))
    return out


def prune(d: Path, now: float | None = None) -> int:
    """Delete from ``d`` what the bounds exclude: old-format files (pickles of earlier
    versions), stale temporary files, entries unused for :data:`MAX_AGE_DAYS` days, then the
    least recently used entries until the rest fit :func:`max_bytes`. Returns the count."""
    now = time.time() if now is None else now
    removed = 0
    try:
        entries = _entries(d)
    except OSError:
        return 0
    keep = []
    for mtime, size, path in entries:
        old = now - mtime > MAX_AGE_DAYS * 86400
        stale_tmp = path.suffix == ".tmp" and now - mtime > 3600
        foreign = path.suffix not in (SUFFIX, ".tmp")
        if old or stale_tmp or foreign:
            _discard(path)
            removed += 1
        elif path.suffix == SUFFIX:
            keep.append((mtime, size, path))
    keep.sort()
    total = sum(s for _, s, _ in keep)
    limit = max_bytes()
    for _, size, path in keep:
        if total <= limit:
            break
        _discard(path)
        total -= size
        removed += 1
    return removed


def clear() -> tuple[Path | None, int]:
    """Delete every entry of the kernel cache (its key too: entries made with it could not be
    read anyway). ``(directory, files deleted)``; the directory must pass the checks."""
    d = cache_dir()
    if d is None or not os.path.lexists(d):
        return d, 0
    private_dir(d, "the kernel cache directory", _hint())
    n = 0
    for _, _, path in _entries(d):
        _discard(path)
        n += 1
    _discard(d / SECRET)
    _opened.pop(str(d), None)
    return d, n


def info() -> dict:
    """The kernel cache's directory, entry count, size and bounds (``mechsys cache info``)."""
    d = cache_dir()
    out = {"directory": None if d is None else str(d), "enabled": d is not None, "entries": 0,
           "bytes": 0, "max_bytes": max_bytes(), "max_age_days": MAX_AGE_DAYS}
    if d is not None and os.path.lexists(d):
        private_dir(d, "the kernel cache directory", _hint())
        for _, size, path in _entries(d):
            if path.suffix == SUFFIX:
                out["entries"] += 1
                out["bytes"] += size
    numba = os.environ.get("NUMBA_CACHE_DIR")
    out["numba_cache_dir"] = numba or "beside the installed mechsys.solvers (__pycache__)"
    return out
