"""Content-addressed store of circuit runs: one ``.npz`` file per deck (batch of replicas).

The key of a batch is the sha256 of everything that determines its numbers: the deck text
(which carries the seed, the initial conditions and every component value), the resample grid,
the ngspice version and :data:`SCHEMA_VERSION` of this code (bump it whenever the way arrays are
derived from a raw file, or the entry format, changes).  Looking a key up therefore either
returns exactly what a fresh run would return, or nothing.  A repeated ``simulate`` call costs
only file reads, and an interrupted one resumes: batches that finished were written as they
finished.

Layout and format (``SCHEMA_VERSION`` 2)::

    <root>/<key[:2]>/<key>.npz       one entry: arrays, "__meta__" (JSON provenance) and
                                     "__integrity__" (JSON: format, key, sha256 of the content)
    <root>/quarantine/<key>.<UTC time>.npz (+ .json: why)   damaged entries, moved aside
    <root>/<key[:2]>/.<key[:12]>.<host>.<pid>.<random>.tmp  a write in progress

Integrity: every entry is verified when it is read (:meth:`RunStore.get`): it must parse
within its own size (no allocation beyond the file), record the key it is filed under, match
its sha256 checksum, hold only finite numbers, and pass the caller's own check (the runner
checks that the recorded deck is the requested one, the grid, the shapes and the arrays it
needs).  A bad entry is reported in one warning line (logger ``analogue.circuit.store``), moved
to ``quarantine/`` (never deleted) and treated as missing, so the caller recomputes it.

Writes are atomic (a temporary file in the same directory, then ``os.replace``): a crash never
leaves a partial file under a key.  Temporary files of writers that died (same host and a pid
that no longer exists, or older than :data:`TMP_MAX_AGE`) are removed by
:meth:`RunStore.clean_tmp`.  Entries are readable by the group (files ``0o664 & ~umask``, at
least ``0o640``; directories ``0o2775 & ~umask``, at least ``0o2750``, setgid so that entries
keep the store's group), so that a lab can share one store.

Location: the ``store=`` argument (a path, or False to disable), else the environment variable
``ANALOGUE_STORE``, else ``~/.cache/analogue/runs``.
"""
from __future__ import annotations

import hashlib
import io
import errno
import json
import logging
import math
import os
import re
import socket
import tempfile
import time
import zipfile
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..checks import ArgumentTypeError

__all__ = ["SCHEMA_VERSION", "TMP_MAX_AGE", "RunStore", "StoreEntry", "batch_key",
           "default_store_path", "open_store"]

log = logging.getLogger(__name__)

#: Version of the raw-file -> arrays derivation and of the entry format; part of every key.
#: 2: entries carry "__integrity__" (key + sha256) and are verified on read.
SCHEMA_VERSION = 2
#: seconds after which a temporary file is stale whatever its writer (a write takes seconds).
TMP_MAX_AGE = 6 * 3600.0
QUARANTINE = "quarantine"
_FORMAT = 2


def default_store_path() -> Path:
    """``$ANALOGUE_STORE`` if set, else ``~/.cache/analogue/runs``."""
    env = os.environ.get("ANALOGUE_STORE")
    if env:
        return Path(env).expanduser()
    return Path.home() / ".cache" / "analogue" / "runs"


def batch_key(deck_text: str, times, ngspice_version: str, schema: int = SCHEMA_VERSION) -> str:
    """sha256 (hex) identifying one batch: deck text + resample grid + ngspice version + schema."""
    if not isinstance(deck_text, str):
        raise ValueError("deck_text must be a string")
    times = np.ascontiguousarray(np.asarray(times, dtype="<f8"))
    h = hashlib.sha256()
    for part in (b"analogue-run", str(int(schema)).encode(), str(ngspice_version).encode(),
                 deck_text.encode(), str(times.size).encode(), times.tobytes()):
        h.update(len(part).to_bytes(8, "little"))  # length-prefixed: no ambiguous concatenation
        h.update(part)
    return h.hexdigest()


def _is_key(key: str) -> bool:
    return isinstance(key, str) and len(key) == 64 and all(c in "0123456789abcdef" for c in key)


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9_-]", "_", socket.gethostname())[:40] or "host"


def _umask() -> int:
    """The process umask, read without changing it (os.umask would race with other threads)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    old = os.umask(0o022)
    os.umask(old)
    return old


def _modes() -> tuple[int, int]:
    """(file mode, directory mode): the umask's choice, but always group-readable."""
    um = _umask()
    return (0o664 & ~um) | 0o040, (0o2775 & ~um) | 0o2050


def _content_sha256(key: str, arrays: dict, meta_json: str) -> str:
    h = hashlib.sha256()
    for part in (b"analogue-entry", key.encode()):
        h.update(len(part).to_bytes(8, "little"))
        h.update(part)
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        for part in (name.encode(), a.dtype.str.encode(), repr(a.shape).encode(), a.tobytes()):
            h.update(len(part).to_bytes(8, "little"))
            h.update(part)
    part = meta_json.encode()
    h.update(len(part).to_bytes(8, "little"))
    h.update(part)
    return h.hexdigest()


def _one_line(text: object, limit: int = 300) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


class _Bad(Exception):
    """An entry that cannot be used (the message says why, in one line)."""


class _NoAccess(_Bad):
    """An entry this user may not read (another user's, written private): not damaged, so
    not quarantined; it is recomputed and, where the directory allows, replaced."""


def _read_npz(path: Path) -> dict:
    """Arrays of an uncompressed ``.npz`` written by :meth:`RunStore.put`, parsed within the
    file's own size: a damaged header can neither allocate beyond it nor load objects."""
    size = path.stat().st_size
    if size == 0:
        raise _Bad("empty file")
    out = {}
    with zipfile.ZipFile(path) as zf:
        for info in zf.infolist():
            if info.compress_type != zipfile.ZIP_STORED or info.file_size > size:
                raise _Bad(f"member {info.filename!r} is not a stored array of a plausible size")
            if not info.filename.endswith(".npy"):
                raise _Bad(f"unexpected member {info.filename!r}")
            data = zf.read(info)  # checks the member's CRC-32
            bio = io.BytesIO(data)
            version = np.lib.format.read_magic(bio)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(bio)
            else:
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(bio)
            if dtype.hasobject:
                raise _Bad(f"array {info.filename!r} holds Python objects")
            count = math.prod(shape)
            if count * dtype.itemsize != len(data) - bio.tell():
                raise _Bad(f"array {info.filename!r} declares {shape} {dtype} but holds "
                           f"{len(data) - bio.tell()} bytes")
            arr = np.frombuffer(data, dtype=dtype, count=count, offset=bio.tell())
            out[info.filename[:-4]] = arr.reshape(shape, order="F" if fortran else "C").copy()
    return out


class StoreEntry(NamedTuple):
    """One complete entry of a store: its key, file, size in bytes and modification time."""

    key: str
    path: Path
    size: int
    mtime: float


class RunStore:
    """A directory of ``<key[:2]>/<key>.npz`` files, each holding named arrays, a JSON meta and
    an integrity record; see the module docstring for the layout and the guarantees.

    Reading: :meth:`get` (verified; a bad entry is quarantined), :meth:`problem` (verify only),
    :meth:`keys`, :meth:`entries`, :meth:`size_bytes`, :meth:`quarantined`.  Writing:
    :meth:`put` (atomic), :meth:`remove`, :meth:`quarantine`, :meth:`clean_tmp`.
    """

    def __init__(self, root):
        self.root = Path(root).expanduser()

    def __repr__(self) -> str:
        return f"RunStore({str(self.root)!r})"

    @property
    def quarantine_dir(self) -> Path:
        return self.root / QUARANTINE

    def path(self, key: str) -> Path:
        if not _is_key(key):
            raise ValueError(f"key must be a 64-character lower-case hex sha256, got {key!r}")
        return self.root / key[:2] / f"{key}.npz"

    def __contains__(self, key: str) -> bool:
        return self.path(key).is_file()

    # ------------------------------------------------------------------------- reading
    def _load(self, key: str, check=None):
        """(arrays, meta) of a verified entry, None if absent; _Bad if it is damaged."""
        p = self.path(key)
        if not os.path.lexists(p):
            return None
        if p.is_symlink() or not p.is_file():
            raise _Bad("not a regular file")
        if not os.access(p, os.R_OK):
            raise _NoAccess(f"not readable by this user (mode {p.stat().st_mode & 0o777:o})")
        try:
            arrays = _read_npz(p)
        except _Bad:
            raise
        except Exception as exc:  # noqa: BLE001 - BadZipFile, EOFError, OSError, MemoryError...
            raise _Bad(f"unreadable ({type(exc).__name__}: {_one_line(exc, 160)})") from None
        try:
            integrity = json.loads(str(arrays.pop("__integrity__")[()]))
            meta_json = str(arrays.pop("__meta__")[()])
            meta = json.loads(meta_json)
        except KeyError as exc:
            raise _Bad(f"no {exc.args[0]} record") from None
        except (ValueError, TypeError) as exc:
            raise _Bad(f"unreadable record ({_one_line(exc, 120)})") from None
        if not isinstance(integrity, dict) or integrity.get("format") != _FORMAT:
            raise _Bad("unknown entry format")
        if integrity.get("key") != key:
            other = str(integrity.get("key"))[:12]
            raise _Bad(f"it is the entry of another key ({other}...), filed under this one")
        if integrity.get("sha256") != _content_sha256(key, arrays, meta_json):
            raise _Bad("content checksum mismatch")
        for name, a in arrays.items():
            if a.dtype.kind in "fc" and not np.all(np.isfinite(a)):
                raise _Bad(f"array {name!r} holds NaN or infinite values")
        if check is not None:
            reason = check(arrays, meta)
            if reason:
                raise _Bad(_one_line(reason))
        return arrays, meta

    def problem(self, key: str, check=None) -> str | None:
        """Why the entry under ``key`` cannot be used (one line), or None if it is fine or
        absent.  Only looks: nothing is moved.  ``check(arrays, meta)`` -> reason or None is
        the caller's own test of the content."""
        try:
            self._load(key, check)
        except _Bad as exc:
            return str(exc)
        return None

    def get(self, key: str, check=None):
        """``(arrays, meta)`` stored under ``key``, verified (see the module docstring), or
        None if there is no usable entry.  A damaged entry (or one failing ``check(arrays,
        meta)`` -> reason or None) is reported in one warning line and moved to the
        quarantine directory; None is returned so that the caller recomputes it."""
        try:
            return self._load(key, check)
        except _NoAccess as exc:
            log.warning("analogue: run store: entry %s... is %s; it will be recomputed",
                        key[:12], exc)
            return None
        except _Bad as exc:
            self._quarantine_and_warn(key, str(exc))
            return None

    def _quarantine_and_warn(self, key: str, reason: str) -> None:
        try:
            dest = self.quarantine(key, reason)
            where = f"moved to {dest}"
        except OSError as exc:
            where = f"could not be moved to {self.quarantine_dir} ({_one_line(exc, 120)})"
        log.warning("analogue: run store: entry %s... is damaged (%s); %s; "
                    "it will be recomputed", key[:12], reason, where)

    def keys(self) -> list[str]:
        """Keys of all complete entries (not verified: see :meth:`problem`)."""
        return [e.key for e in self.entries()]

    def entries(self) -> list[StoreEntry]:
        """Every complete entry (key order) with its file, size and modification time; junk
        files and temporary files are not listed."""
        if not self.root.is_dir():
            return []
        out = []
        for p in self.root.glob("??/*.npz"):
            if _is_key(p.stem) and p.parent.name == p.stem[:2]:
                try:
                    st = p.stat()
                except OSError:
                    continue
                out.append(StoreEntry(p.stem, p, st.st_size, st.st_mtime))
        return sorted(out)

    def size_bytes(self) -> int:
        """Total size of the complete entries (bytes)."""
        return sum(e.size for e in self.entries())

    def quarantined(self) -> list[Path]:
        """Quarantined entries (files or directories ``<key>.<time>.npz``), oldest first; each
        has a ``.json`` beside it saying why."""
        q = self.quarantine_dir
        if not q.is_dir():
            return []
        return sorted(q.glob("*.npz"))

    # ------------------------------------------------------------------------- writing
    def _mkdir(self, d: Path) -> None:
        if d.is_dir():
            return
        missing = [d] + [p for p in d.parents if not p.exists()]
        d.mkdir(parents=True, exist_ok=True)
        _, dmode = _modes()
        for p in missing:
            if p == d or p == self.root or self.root in p.parents:
                try:
                    os.chmod(p, dmode)
                except OSError:
                    pass

    def put(self, key: str, arrays: dict, meta: dict) -> Path:
        """Write ``arrays`` (name -> ndarray) and ``meta`` (JSON-serialisable) under ``key``,
        atomically: readers see either no file or the complete one.  Raises OSError if the
        store cannot be written (read-only, disk full); nothing partial is left behind."""
        p = self.path(key)
        for reserved in ("__meta__", "__integrity__"):
            if reserved in arrays:
                raise ValueError(f"array name {reserved!r} is reserved")
        arrays = {k: np.asarray(v) for k, v in arrays.items()}
        for name, a in arrays.items():
            if a.dtype.hasobject:
                raise ValueError(f"array {name!r} holds Python objects; the store keeps numbers")
        meta_json = json.dumps(meta, sort_keys=True, default=_jsonable)
        integrity = json.dumps({"format": _FORMAT, "key": key,
                                "sha256": _content_sha256(key, arrays, meta_json)})
        if os.path.lexists(p) and (p.is_symlink() or not p.is_file()):
            self._quarantine_and_warn(key, "not a regular file")
        self._mkdir(p.parent)
        fmode, _ = _modes()
        fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f".{key[:12]}.{_host()}.{os.getpid()}.",
                                   suffix=".tmp")
        try:
            os.fchmod(fd, fmode)
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, __meta__=np.array(meta_json), __integrity__=np.array(integrity),
                         **arrays)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, p)
        except BaseException:
            # Interrupted or failed: never leave the temporary file behind.
            try:
                os.unlink(tmp)
            except OSError:
                pass
            raise
        return p

    def quarantine(self, key: str, reason: str) -> Path:
        """Move the entry filed under ``key`` (file or whatever is there) to the quarantine
        directory as ``<key>.<UTC time>.npz`` with a ``.json`` saying why; returns its path."""
        p = self.path(key)
        self._mkdir(self.quarantine_dir)
        stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
        for n in range(1000):
            dest = self.quarantine_dir / f"{key}.{stamp}{'' if n == 0 else f'-{n}'}.npz"
            if not os.path.lexists(dest):
                break
        os.replace(p, dest)
        try:
            dest.with_suffix(".json").write_text(json.dumps(
                {"key": key, "reason": reason, "from": str(p),
                 "time": stamp}, indent=1) + "\n")
        except OSError:
            pass
        return dest

    def remove(self, key: str) -> bool:
        """Delete the entry under ``key``; True if there was one."""
        try:
            self.path(key).unlink()
            return True
        except FileNotFoundError:
            return False

    def clean_tmp(self, max_age: float = TMP_MAX_AGE) -> int:
        """Remove temporary files left by writers that died: written on this host by a process
        that no longer exists, or older than ``max_age`` seconds.  Returns how many."""
        if not self.root.is_dir():
            return 0
        host, now, removed = _host(), time.time(), 0
        for f in self.root.glob("??/.*.tmp"):
            parts = f.name.split(".")  # "", key12, host, pid, random, "tmp"
            stale = False
            if len(parts) == 6 and parts[2] == host and parts[3].isdigit():
                pid = int(parts[3])
                if pid != os.getpid():
                    try:
                        os.kill(pid, 0)
                    except ProcessLookupError:
                        stale = True
                    except (PermissionError, OverflowError):
                        pass
            try:
                stale = stale or now - f.lstat().st_mtime > max_age
                if stale:
                    f.unlink()
                    removed += 1
            except OSError:
                pass
        return removed


def _jsonable(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    return repr(obj)


def root_problem(root) -> str | None:
    """Why ``root`` can never be a run store (one line), or None: it, or the nearest of its
    parents that exists, is a symbolic link that is dangling or loops.  (Such a store took
    every run and stored none of them, with one "not writable" warning per deck.)"""
    p = Path(root).expanduser().absolute()
    for q in (p, *p.parents):
        if not os.path.lexists(q):
            continue
        if not q.is_symlink():
            return None
        try:
            os.stat(q)
            return None
        except OSError as exc:
            if exc.errno == errno.ELOOP:
                what = "a symbolic link that loops"
            else:
                what = f"a symbolic link to {os.readlink(q)!r}, which does not exist"
        where = "is" if q == p else f"lies below {str(q)!r}, which is"
        return f"run store {str(p)!r} {where} {what}; point it at a directory"
    return None


def _checked(root) -> RunStore:
    problem = root_problem(root)
    if problem is not None:
        raise ValueError(problem)
    return RunStore(root)


def open_store(store=None):
    """Resolve the ``store=`` argument: None -> default location, False -> None (disabled),
    a path -> that directory, a RunStore -> itself."""
    if store is False:
        return None
    if store is None or store is True:
        return _checked(default_store_path())
    if isinstance(store, RunStore):
        return store
    if isinstance(store, (str, os.PathLike)):
        if not str(store).strip():
            raise ValueError("store must be a directory path, not an empty string")
        return _checked(store)
    raise ArgumentTypeError(f"store must be a directory path, a RunStore, None (default "
                            f"location) or False (disabled), got {store!r}")
