"""Content-addressed store of circuit runs: one ``.npz`` file per deck (batch of replicas).

The key of a batch is the sha256 of everything that determines its numbers: the deck text
(which carries the seed, the initial conditions and every component value), the resample grid,
the ngspice version and :data:`SCHEMA_VERSION` of this code (bump it whenever the way arrays are
derived from a raw file changes).  Looking a key up therefore either returns exactly what a
fresh run would return, or nothing.  A repeated ``simulate`` call costs only file reads, and an
interrupted one resumes: batches that finished were written as they finished.

Files are written atomically (a temporary file in the same directory, then ``os.replace``), so a
crash never leaves a partial file under a key; provenance is stored with the arrays as JSON.

Location: the ``store=`` argument (a path, or False to disable), else the environment variable
``ANALOGUE_STORE``, else ``~/.cache/analogue/runs``.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["SCHEMA_VERSION", "RunStore", "batch_key", "open_store", "default_store_path"]

#: Version of the raw-file -> arrays derivation; part of every key.
SCHEMA_VERSION = 1


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


class RunStore:
    """A directory of ``<key[:2]>/<key>.npz`` files, each holding named arrays and a JSON meta."""

    def __init__(self, root):
        self.root = Path(root).expanduser()

    def __repr__(self) -> str:
        return f"RunStore({str(self.root)!r})"

    def path(self, key: str) -> Path:
        if not _is_key(key):
            raise ValueError(f"key must be a 64-character lower-case hex sha256, got {key!r}")
        return self.root / key[:2] / f"{key}.npz"

    def __contains__(self, key: str) -> bool:
        return self.path(key).is_file()

    def get(self, key: str):
        """``(arrays, meta)`` stored under ``key``, or None.  An unreadable file (e.g. written
        by an incompatible numpy) counts as missing and is overwritten by the next put."""
        p = self.path(key)
        if not p.is_file():
            return None
        try:
            with np.load(p, allow_pickle=False) as f:
                arrays = {k: np.array(f[k]) for k in f.files if k != "__meta__"}
                meta = json.loads(str(f["__meta__"]))
        except (OSError, ValueError, KeyError, json.JSONDecodeError):
            return None
        return arrays, meta

    def put(self, key: str, arrays: dict, meta: dict) -> Path:
        """Write ``arrays`` (name -> ndarray) and ``meta`` (JSON-serialisable) under ``key``,
        atomically: readers see either no file or the complete one."""
        p = self.path(key)
        if "__meta__" in arrays:
            raise ValueError("array name '__meta__' is reserved")
        meta_json = json.dumps(meta, sort_keys=True, default=_jsonable)
        p.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f".{key[:12]}-", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, __meta__=np.array(meta_json), **arrays)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, p)
        except BaseException:
            # Interrupted or failed: never leave the temporary file behind.
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
            raise
        return p

    def keys(self) -> list[str]:
        """Keys of all complete entries."""
        if not self.root.is_dir():
            return []
        return sorted(p.stem for p in self.root.glob("??/*.npz") if _is_key(p.stem))


def _jsonable(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    return repr(obj)


def open_store(store=None):
    """Resolve the ``store=`` argument: None -> default location, False -> None (disabled),
    a path -> that directory, a RunStore -> itself."""
    if store is False:
        return None
    if store is None or store is True:
        return RunStore(default_store_path())
    if isinstance(store, RunStore):
        return store
    if isinstance(store, (str, os.PathLike)):
        return RunStore(store)
    raise ValueError(f"store must be a directory path, a RunStore, None (default location) or "
                     f"False (disabled), got {store!r}")
