"""Writing result files (pages, metrics, figures, exports): atomically, as UTF-8 whatever the
locale, and with a failure that names the file and its cause and leaves nothing half-written
(issue 19, items 5 and 6).

- Atomic: the data goes to a hidden temporary file next to the target, then ``os.replace``;
  on any failure the temporary file is removed, so a reader sees the old file or the new one.
- UTF-8: under a non-UTF-8 locale (``LC_ALL=C`` without Python's UTF-8 mode) a non-ASCII path
  reaches Python as lone surrogates (PEP 383); text naming it is written back as the path's
  own bytes (``surrogateescape``), which :func:`check_path` has checked are UTF-8, so every
  file is valid UTF-8 and names the path as it is on disk.
- A failed write raises OSError naming the path and the cause (``No space left on device``);
  a writer that hides the cause (netCDF's "NetCDF: HDF error") is diagnosed by the space left
  on the file system.
"""
from __future__ import annotations

import errno
import os
import shutil
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["atomic_path", "check_path", "utf8", "write_bytes", "write_text"]

# Below this many free bytes, a writer's unexplained failure is taken for a full disk (a
# netCDF file is written in chunks of up to 4 MiB; a figure needs ~0.2 MB).
LOW_SPACE_BYTES = 4 * 1024 * 1024


def utf8(text: str) -> bytes:
    """``text`` as UTF-8 bytes; lone surrogates from an undecodable path (PEP 383) go back to
    the path's own bytes."""
    return text.encode("utf-8", "surrogateescape")


def check_path(path, what: str) -> Path:
    """``path`` as a Path if its name can be used and written into UTF-8 files: it must be
    encodable in the file-system encoding and its bytes must be UTF-8; else ValueError naming
    ``what`` (the option or argument) and the locale, before any work starts."""
    p = Path(path)
    try:
        raw = os.fsencode(p)
    except UnicodeEncodeError as exc:
        raise ValueError(f"{what}: the path {str(p)!r} cannot be written in this locale's "
                         f"file-name encoding ({exc.encoding}); set a UTF-8 locale (e.g. "
                         f"LC_ALL=C.UTF-8) or use an ASCII path") from None
    try:
        raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{what}: the path {raw!r} is not valid UTF-8, so the reports and "
                         f"metrics that name it could not; rename it or use another "
                         f"path") from None
    return p


def _cause(exc: BaseException, where: Path) -> tuple[int, str]:
    """(errno, text) of a failed write: the OSError's own, else a full file system when
    little space is left, else the writer's message."""
    if isinstance(exc, OSError) and exc.errno is not None:
        return exc.errno, exc.strerror or os.strerror(exc.errno)
    try:
        free = shutil.disk_usage(where).free
    except OSError:
        free = None
    msg = " ".join(str(exc).split()) or type(exc).__name__
    if free is not None and free < LOW_SPACE_BYTES:
        return errno.ENOSPC, f"{os.strerror(errno.ENOSPC)} ({free} bytes free; the writer " \
                             f"said: {msg})"
    return errno.EIO, msg


@contextmanager
def atomic_path(path) -> Iterator[Path]:
    """A temporary path next to ``path`` for a writer to fill; moved onto ``path`` when the
    block ends, removed if it fails.  A failure raises OSError ``could not write <path>:
    <cause>``, the writer's exception chained."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    try:
        yield tmp
        os.replace(tmp, path)
    except Exception as exc:
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        code, why = _cause(exc, path.parent)
        raise OSError(code, f"could not write {path}: {why}; nothing was left "
                            f"half-written") from exc
    except BaseException:  # an interrupt: no half-written file either
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        raise


def write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (:func:`atomic_path`); returns the path."""
    path = Path(path)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())   # a full disk can fail only here (delayed allocation)
    return path


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` as UTF-8 (:func:`utf8`), atomically; returns the path."""
    return write_bytes(path, utf8(text))
