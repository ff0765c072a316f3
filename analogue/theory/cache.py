"""On-disk cache of exact theory results, content-addressed like the run store.

The theory functions stay pure; this module is a thin wrapper used at the edges (the report,
the figures, the CLI).  The key of an entry is the sha256 of everything that determines its
numbers:

* the function's qualified name,
* the model's parameters (``float.hex``: bit-exact),
* every argument (arrays by dtype, shape and bytes; scalars by ``repr``/``float.hex``),
* the **code version**: a sha256 of the source of every module of :mod:`analogue.theory` and of
  :mod:`analogue.model` (so any change of the numerics invalidates the cache by itself), and
  the numpy and scipy versions (LAPACK round-off differs between builds).

So a lookup returns exactly what a fresh call would return, or nothing.

Files are ``<root>/<key[:2]>/<key>.npz`` holding the result arrays and a JSON ``__meta__``
with the provenance (function, model, arguments, versions) and a sha256 of the result arrays.
Writes are atomic (temporary file in the same directory, then ``os.replace``); reads verify the
checksum and the stored key, and a bad entry (truncated, corrupted, foreign) is ignored,
recomputed and overwritten.

Location: the ``cache=`` argument (a path, a :class:`TheoryCache`, or False to disable), else
``$ANALOGUE_THEORY_CACHE`` (``off``/``0``/``false`` disables it), else ``theory/`` inside the
run store root (``$ANALOGUE_STORE``, default ``~/.cache/analogue``): ``~/.cache/analogue/theory``.
"""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
import os
import tempfile
import zipfile
from pathlib import Path
from typing import Any
from collections.abc import Callable

import numpy as np

from ..model import Model

__all__ = ["TheoryCache", "cached", "cached_call", "cached_later", "code_version",
           "default_cache_path", "open_cache", "theory_key"]

_DISABLED = {"0", "off", "false", "no", "none"}


def default_cache_path() -> Path:
    """``$ANALOGUE_THEORY_CACHE`` if set, else ``$ANALOGUE_STORE/theory`` if that is set, else
    ``~/.cache/analogue/theory``."""
    env = os.environ.get("ANALOGUE_THEORY_CACHE")
    if env and env.strip().lower() not in _DISABLED:
        return Path(env).expanduser()
    store = os.environ.get("ANALOGUE_STORE")
    if store:
        return Path(store).expanduser() / "theory"
    return Path.home() / ".cache" / "analogue" / "theory"


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """sha256 of the theory sources (every ``analogue/theory/*.py``, ``analogue/model.py``,
    ``analogue/checks.py``) and the numpy/scipy versions."""
    import scipy
    here = Path(__file__).resolve().parent
    files = sorted(here.glob("*.py")) + [here.parent / "model.py", here.parent / "checks.py"]
    h = hashlib.sha256()
    for f in files:
        if f.name == "cache.py":      # the cache's own plumbing does not change any number
            continue
        h.update(f.name.encode())
        h.update(f.read_bytes())
    h.update(f"numpy {np.__version__} scipy {scipy.__version__}".encode())
    return h.hexdigest()


def _encode(obj: Any) -> bytes:
    """Unambiguous bytes for a key part (bit-exact for floats and arrays)."""
    if isinstance(obj, Model):
        return b"Model" + _encode(obj.as_dict())
    if isinstance(obj, dict):
        return b"dict" + b"".join(_frame(str(k).encode()) + _frame(_encode(v))
                                  for k, v in sorted(obj.items()))
    if isinstance(obj, (list, tuple)):
        return b"seq" + b"".join(_frame(_encode(v)) for v in obj)
    if obj is None or isinstance(obj, (bool, str)):
        return repr(obj).encode()
    if isinstance(obj, (int, np.integer)) and not isinstance(obj, bool):
        return b"int" + str(int(obj)).encode()
    if isinstance(obj, (float, np.floating)):
        return b"float" + float(obj).hex().encode()
    if isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        if a.dtype == object:
            raise TypeError("object arrays cannot be part of a theory-cache key")
        return b"array" + a.dtype.str.encode() + str(a.shape).encode() + a.tobytes()
    if hasattr(obj, "__dataclass_fields__"):          # e.g. a Grid
        return type(obj).__name__.encode() + _encode(dataclasses.asdict(obj))
    raise TypeError(f"cannot build a theory-cache key from {type(obj).__name__}")


def _frame(b: bytes) -> bytes:
    return len(b).to_bytes(8, "little") + b


def theory_key(name: str, args: tuple[Any, ...] | list[Any] = (),
               kwargs: dict[str, Any] | None = None) -> str:
    """sha256 (hex) of function name, arguments and :func:`code_version`."""
    h = hashlib.sha256()
    for part in (b"analogue-theory", code_version().encode(), name.encode(),
                 _encode(tuple(args)), _encode(dict(kwargs or {}))):
        h.update(_frame(part))
    return h.hexdigest()


def _checksum(arrays: dict[str, Any]) -> str:
    h = hashlib.sha256()
    for k in sorted(arrays):
        h.update(_frame(k.encode()))
        h.update(_frame(_encode(np.asarray(arrays[k]))))
    return h.hexdigest()


def _is_key(key: object) -> bool:
    return isinstance(key, str) and len(key) == 64 and all(c in "0123456789abcdef" for c in key)


def _describe(obj: Any) -> Any:
    """JSON-friendly provenance of an argument (arrays summarised, not stored)."""
    if isinstance(obj, Model):
        return obj.as_dict()
    if isinstance(obj, np.ndarray):
        return {"shape": list(obj.shape), "dtype": obj.dtype.str,
                "min": float(np.min(obj)) if obj.size and obj.dtype.kind in "fiu" else None,
                "max": float(np.max(obj)) if obj.size and obj.dtype.kind in "fiu" else None}
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else repr(f)
    if isinstance(obj, (int, np.integer, str, bool)) or obj is None:
        return obj.item() if isinstance(obj, np.generic) else obj
    if isinstance(obj, (list, tuple)):
        return [_describe(v) for v in obj]
    return repr(obj)


class TheoryCache:
    """A directory of ``<key[:2]>/<key>.npz`` entries (result arrays + JSON meta)."""

    def __init__(self, root: str | os.PathLike[str]) -> None:
        self.root = Path(root).expanduser()
        self.hits = 0
        self.misses = 0

    def __repr__(self) -> str:
        return f"TheoryCache({str(self.root)!r})"

    def path(self, key: str) -> Path:
        if not _is_key(key):
            raise ValueError(f"key must be a 64-character lower-case hex sha256, got {key!r}")
        return self.root / key[:2] / f"{key}.npz"

    def get(self, key: str) -> tuple[dict[str, np.ndarray], dict[str, Any]] | None:
        """``(arrays, meta)`` under ``key``, or None if absent or bad (unreadable, checksum or
        key mismatch): a bad entry is treated as missing and overwritten by the next put."""
        p = self.path(key)
        if not p.is_file():
            return None
        try:
            with np.load(p, allow_pickle=False) as f:
                arrays = {k: np.array(f[k]) for k in f.files if k != "__meta__"}
                meta = json.loads(str(f["__meta__"]))
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile,
                json.JSONDecodeError):
            return None          # unreadable (truncated, not a zip, foreign numpy...)
        if (not isinstance(meta, dict) or meta.get("key") != key
                or meta.get("checksum") != _checksum(arrays)):
            return None
        return arrays, meta

    def put(self, key: str, arrays: dict[str, Any], meta: dict[str, Any]) -> Path:
        """Write atomically: readers see no file or the complete one."""
        p = self.path(key)
        if "__meta__" in arrays:
            raise ValueError("array name '__meta__' is reserved")
        arrays = {k: np.asarray(v) for k, v in arrays.items()}
        meta = dict(meta, key=key, checksum=_checksum(arrays))
        meta_json = json.dumps(meta, sort_keys=True, default=repr)
        p.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f".{key[:12]}-", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, __meta__=np.array(meta_json), **arrays)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, p)
        except BaseException:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
            raise
        return p


def open_cache(cache: Any = None) -> TheoryCache | None:
    """Resolve ``cache=``: None -> the default location (or None if
    ``$ANALOGUE_THEORY_CACHE`` disables it), False -> None, a path -> that directory, a
    TheoryCache -> itself."""
    if cache is False:
        return None
    if cache is None or cache is True:
        env = os.environ.get("ANALOGUE_THEORY_CACHE")
        if env is not None and env.strip().lower() in _DISABLED:
            return None
        return TheoryCache(default_cache_path())
    if isinstance(cache, TheoryCache):
        return cache
    if isinstance(cache, (str, os.PathLike)):
        return TheoryCache(cache)
    raise TypeError(f"cache must be a directory path, a TheoryCache, None (default location) or "
                    f"False (disabled), got {type(cache).__name__}")


def _normalise(obj: Any) -> Any:
    """Array-likes as float arrays (so [1, 2] and np.array([1., 2.]) share an entry)."""
    if isinstance(obj, (list, tuple)) and all(isinstance(v, (int, float, np.number)) for v in obj):
        return np.asarray(obj, dtype=float)
    return obj


def _import(path: str) -> Any:
    import importlib
    module, _, qualname = path.partition(":")
    obj = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return obj


def _scalar(a: np.ndarray) -> Any:
    """0-d arrays back to Python scalars (a NamedTuple of floats stays one)."""
    return a.item() if a.ndim == 0 else a


_MISS = object()


def _lookup(store: TheoryCache, key: str) -> Any:
    """The cached value of ``key`` with its type restored, or ``_MISS``."""
    hit = store.get(key)
    if hit is None:
        store.misses += 1
        return _MISS
    arrays, meta = hit
    store.hits += 1
    kind = meta.get("kind")
    if kind == "tuple":
        return tuple(arrays[f"r{i}"] for i in range(int(meta["n"])))
    if kind == "namedtuple":
        cls = _import(meta["type"])
        return cls(*(_scalar(arrays[f"r{i}"]) for i in range(int(meta["n"]))))
    if kind == "dataclass":
        cls = _import(meta["type"])
        return cls(**{name: _scalar(arrays[f"r{i}"]) for i, name in enumerate(meta["fields"])})
    if kind == "float":
        return float(arrays["r0"])
    return arrays["r0"]


def _put(store: TheoryCache, key: str, name: str, args: tuple[Any, ...],
         kwargs: dict[str, Any], out: Any) -> None:
    """Store ``out`` (the result of ``name(*args, **kwargs)``) under ``key``."""
    extra = {}
    if dataclasses.is_dataclass(out) and not isinstance(out, type):
        names = [f.name for f in dataclasses.fields(out)]
        arrays = {f"r{i}": np.asarray(getattr(out, n)) for i, n in enumerate(names)}
        kind = "dataclass"
        extra = {"type": f"{type(out).__module__}:{type(out).__qualname__}", "fields": names}
    elif isinstance(out, tuple) and hasattr(out, "_fields"):    # a NamedTuple comes back as one
        arrays, kind = {f"r{i}": np.asarray(o) for i, o in enumerate(out)}, "namedtuple"
        extra = {"type": f"{type(out).__module__}:{type(out).__qualname__}"}
    elif isinstance(out, tuple):
        arrays, kind = {f"r{i}": np.asarray(o) for i, o in enumerate(out)}, "tuple"
    elif isinstance(out, float):
        arrays, kind = {"r0": np.asarray(out)}, "float"
    else:
        arrays, kind = {"r0": np.asarray(out)}, "array"
    if all(a.dtype != object for a in arrays.values()):
        meta = {"function": name, "kind": kind, "n": len(arrays), "code_version": code_version(),
                **extra,
                "args": [_describe(a) for a in args],
                "kwargs": {k: _describe(v) for k, v in kwargs.items()}}
        try:
            store.put(key, arrays, meta)
        except OSError:          # a read-only or full disk must not fail the computation
            pass


def cached_call(fn: Callable[..., Any], *args: Any, cache: Any = None, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)`` through the cache.  ``fn`` must be pure and return an ndarray
    (or a float, a tuple of ndarrays, or a NamedTuple or dataclass of floats/arrays such as
    ``StationaryMoments``); the result comes back with the same type and values.
    ``cache``: see :func:`open_cache` (False: call ``fn`` directly)."""
    return cached_later(fn, *args, cache=cache, **kwargs)()


def cached_later(fn: Callable[..., Any], *args: Any, cache: Any = None,
                 submit: Callable[..., Any] | None = None, **kwargs: Any) -> Callable[[], Any]:
    """:func:`cached_call` in two steps: the cache is read now and, on a miss, the
    computation started with ``submit(fn, *args, **kwargs)`` (an executor's ``submit``, e.g.
    a worker process: :class:`analogue.study.processes.TheoryProcesses`; it returns a
    future: anything with ``result()``); the function returned waits for it, stores it in the
    cache (here, in this process) and returns it.  ``submit`` None: computed when the
    function returned is called, in the calling thread."""
    store = open_cache(cache)
    if store is None:
        if submit is None:
            return lambda: fn(*args, **kwargs)
        started = submit(fn, *args, **kwargs)
        return lambda: started.result()
    name = f"{fn.__module__}.{fn.__qualname__}"
    args = tuple(_normalise(a) for a in args)
    kwargs = {k: _normalise(v) for k, v in kwargs.items()}
    key = theory_key(name, args, kwargs)
    hit = _lookup(store, key)
    if hit is not _MISS:
        return lambda: hit
    started = None if submit is None else submit(fn, *args, **kwargs)

    def finish() -> Any:
        out = fn(*args, **kwargs) if started is None else started.result()
        _put(store, key, name, args, kwargs, out)
        return out
    return finish


def cached(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator: the same function with an extra keyword ``cache=`` (see :func:`cached_call`).
    The wrapped function stays available as ``.uncached``."""
    @functools.wraps(fn)
    def wrapper(*args: Any, cache: Any = None, **kwargs: Any) -> Any:
        return cached_call(fn, *args, cache=cache, **kwargs)
    wrapper.uncached = fn  # type: ignore[attr-defined]
    return wrapper
