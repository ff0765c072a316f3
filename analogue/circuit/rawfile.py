"""Reader for ngspice binary raw files (``ngspice -b -r out.raw deck.cir``).

The format is an ASCII header (``Title:``, ``Plotname:``, ``Flags:``, ``No. Variables:``,
``No. Points:``, a ``Variables:`` table) followed by ``Binary:`` and the points, each point
being one little-endian float64 per variable (complex plots: two).  A file may hold several
plots one after another.  This reader maps the data with numpy in one call per plot; it is
cross-checked against spicelib's ``RawRead(path, dialect='ngspice')`` in the tests.

When a run is aborted ngspice may leave the header's point count larger than the data that
was written; the count is therefore clipped to what the file really holds, and the caller
decides (from the last time point) whether the run is complete.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["RawPlot", "read_raw"]


@dataclass(frozen=True)
class RawPlot:
    """One plot of a raw file: ``plot[name]`` is the (n_points,) array of vector ``name``
    (names lower-case, exactly as ngspice writes them, e.g. ``"time"``, ``"v(v0)"``)."""

    title: str
    plotname: str
    flags: str
    names: tuple
    values: np.ndarray = field(repr=False)  # (n_points, n_variables)

    @property
    def n_points(self) -> int:
        return self.values.shape[0]

    def index(self, name: str) -> int:
        try:
            return self.names.index(name.lower())
        except ValueError:
            raise KeyError(f"vector {name!r} not in raw file plot {self.plotname!r}; "
                           f"available: {', '.join(self.names)}") from None

    def __getitem__(self, name: str) -> np.ndarray:
        return self.values[:, self.index(name)]

    def columns(self, names) -> np.ndarray:
        """The vectors ``names`` stacked as a (len(names), n_points) array."""
        return self.values[:, [self.index(n) for n in names]].T


# A raw file written by ngspice for this project has a few hundred vectors; 10**6 is far beyond
# any real deck and keeps a damaged header from making the reader loop or allocate for ever.
MAX_VARIABLES = 1_000_000
_HEADER_MAX = 64 * 1024 * 1024  # bytes of ASCII header we are willing to scan for one plot


def _count(fields: dict, key: str, label: str, lo: int, hi: int | None = None) -> int:
    """A header count as an int in [lo, hi], else ValueError naming the field."""
    raw = fields.get(key)
    if raw is None:
        raise ValueError(f"raw file header has no '{label}:' line")
    try:
        n = int(raw)
    except ValueError:
        raise ValueError(f"raw file header: '{label}: {raw[:40]}' is not an integer") from None
    if n < lo or (hi is not None and n > hi):
        top = hi if hi is not None else "inf"
        raise ValueError(f"raw file header: '{label}: {n}' is outside [{lo}, {top}]")
    return n


def _parse_header(buf: bytes, pos: int):
    """Parse one ASCII header starting at ``pos``; return (fields, names, data_start).
    Every count is checked before use and every step moves forward in ``buf``."""
    fields: dict[str, str] = {}
    names: list[str] = []
    limit = min(len(buf), pos + _HEADER_MAX)
    while True:
        end = buf.find(b"\n", pos, limit)
        if end < 0:
            raise ValueError("raw file header is truncated (no 'Binary:' line)")
        line = buf[pos:end].decode("ascii", errors="replace").rstrip("\r")
        pos = end + 1
        key, _, value = line.partition(":")
        key = key.strip().lower()
        if key == "binary":
            if not names:
                raise ValueError("raw file header has no 'Variables:' table")
            return fields, names, pos
        if key == "values":
            raise ValueError("ASCII raw files are not supported; run ngspice with -r "
                             "(binary is its default for batch output)")
        if key == "variables":
            # each table line is at least "\t0\tt\tt\n": 4 bytes; more lines than the file
            # can hold is a damaged header
            n = _count(fields, "no. variables", "No. Variables", 1,
                       min(MAX_VARIABLES, (len(buf) - pos) // 4))
            for _ in range(n):
                end = buf.find(b"\n", pos, limit)
                if end < 0:
                    raise ValueError("raw file variable table is truncated")
                parts = buf[pos:end].decode("ascii", errors="replace").split()
                pos = end + 1
                if len(parts) < 2 or parts[1].lower() in ("binary:", "values:"):
                    raise ValueError(f"malformed variable line in raw file (declared {n} "
                                     f"variables): {' '.join(parts)[:60]!r}")
                names.append(parts[1].lower())
            continue
        fields[key] = value.strip()


def read_raw(path) -> list[RawPlot]:
    """All plots of an ngspice binary raw file (real or complex data).

    The header is validated against the file: counts must be integers in range (a negative or
    absurd ``No. Points`` / ``No. Variables`` raises ValueError naming the field), the variable
    table must list as many vectors as declared, and the data read is clipped to what the file
    holds (an aborted run), so the reader never loops or allocates beyond the file's size.
    """
    buf = Path(path).read_bytes()
    plots = []
    pos = 0
    while pos < len(buf) and buf[pos:pos + 4096].strip():
        fields, names, start = _parse_header(buf, pos)
        nvar = len(names)
        flags = fields.get("flags", "real").lower()
        width = 2 if "complex" in flags else 1
        declared = _count(fields, "no. points", "No. Points", 0)
        point_bytes = 8 * nvar * width
        available = (len(buf) - start) // point_bytes
        npts = min(declared, available)
        block = np.frombuffer(buf, dtype="<f8", count=npts * nvar * width, offset=start)
        block = block.reshape(npts, nvar * width)
        if width == 2:
            block = block[:, 0::2] + 1j * block[:, 1::2]
        plots.append(RawPlot(title=fields.get("title", ""), plotname=fields.get("plotname", ""),
                             flags=flags, names=tuple(names), values=np.array(block)))
        new_pos = start + npts * point_bytes
        if npts < declared or new_pos <= pos:
            break  # truncated file (nothing sensible follows), or no progress
        pos = new_pos
    return plots
