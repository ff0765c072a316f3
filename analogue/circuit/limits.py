"""Size limits of a circuit run: what ``simulate`` may hold in memory and write to the store.

A request is checked before anything is allocated or any ngspice starts (issue 8: ``t_end =
1e9`` used to reach numpy's MemoryError or the kernel's OOM killer).  The limits:

* memory: ``ANALOGUE_MEMORY_LIMIT`` (bytes; suffixes K, M, G, T = powers of 1024), else half
  of the memory the kernel reports as available (``MemAvailable``), else 4 GiB;
* store: ``ANALOGUE_STORE_LIMIT`` (same syntax), else 90 % of the free space on the store's disk.

The estimates (:func:`estimate`) are lower bounds of what a run really needs, so a refused
request could never have fitted: the arrays returned (v, x: replicas x time points; the held
noise: replicas x hold intervals; float64), held twice at the end of a run (per-deck results
and the stacked arrays), plus one raw file per running ngspice (at least ``t_end / max_step``
simulator points of 1 + 3 x replicas-per-deck vectors, read and copied once; measured: the
stick decks write ~16 times more points than this bound), plus the deck texts (~700 bytes +
~140 bytes per replica, measured on the default circuit).
"""
from __future__ import annotations

import math
import os
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Estimate", "estimate", "format_bytes", "format_count", "memory_limit", "parse_bytes",
           "store_limit"]

_FALLBACK_MEMORY = 4 * 1024**3
_UNITS = {"": 1, "K": 1024, "M": 1024**2, "G": 1024**3, "T": 1024**4}


def parse_bytes(text: str, name: str) -> float:
    """``"4e9"``, ``"512M"``, ``"2GiB"`` -> bytes; ValueError naming ``name`` otherwise."""
    m = re.fullmatch(r"\s*([0-9.eE+-]+)\s*([KMGT]?)(?:i?B)?\s*", str(text), re.IGNORECASE)
    try:
        if m is None:
            raise ValueError
        value = float(m.group(1)) * _UNITS[m.group(2).upper()]
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a number of bytes > 0 (suffixes K, M, G, T allowed, "
                         f"e.g. 8G), got {text!r}")
    return value


def format_count(n: float) -> str:
    """A count as digits up to 1e12 (``1001``), beyond as ``3e+18``."""
    return f"{n:.0f}" if math.isfinite(n) and abs(n) < 1e12 else f"{n:.3g}"


def format_bytes(n: float) -> str:
    """``2e+05 bytes (195 KiB)``: the exact order of magnitude and a readable size."""
    if not math.isfinite(n):
        return "inf bytes"
    size, unit = float(n), "bytes"
    for u in ("KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if size < 1024:
            break
        size, unit = size / 1024, u
    return f"{n:.3g} bytes" + (f" ({size:.3g} {unit})" if unit != "bytes" else "")


def _available_memory() -> float | None:
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def memory_limit() -> tuple[float, str]:
    """(bytes, where the number comes from)."""
    env = os.environ.get("ANALOGUE_MEMORY_LIMIT")
    if env:
        return parse_bytes(env, "ANALOGUE_MEMORY_LIMIT"), "set by ANALOGUE_MEMORY_LIMIT"
    avail = _available_memory()
    if avail is None:
        return float(_FALLBACK_MEMORY), ("4 GiB: the available memory is unknown; "
                                         "ANALOGUE_MEMORY_LIMIT=BYTES overrides it")
    return avail / 2, "half the available memory; ANALOGUE_MEMORY_LIMIT=BYTES overrides it"


def store_limit(root) -> tuple[float, str]:
    """(bytes, where the number comes from) for a store at ``root``."""
    env = os.environ.get("ANALOGUE_STORE_LIMIT")
    if env:
        return parse_bytes(env, "ANALOGUE_STORE_LIMIT"), "set by ANALOGUE_STORE_LIMIT"
    p = Path(root).expanduser()
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        free = shutil.disk_usage(p).free
    except OSError:
        return math.inf, "free space unknown"
    return 0.9 * free, "90% of the free space on its disk; ANALOGUE_STORE_LIMIT=BYTES overrides it"


@dataclass(frozen=True)
class Estimate:
    """Lower bounds of the bytes a run holds in memory at its peak and writes to the store."""

    arrays: float
    memory: float
    stored: float


def estimate(*, replicas: int, n_times: float, n_hold: float, per_deck: int, workers: int,
             raw_points: float, n_decks: int) -> Estimate:
    """See the module docstring; all arguments are counts (floats allowed: no overflow)."""
    n_replicas, deck = float(replicas), float(min(per_deck, replicas))
    arrays = n_replicas * (2.0 * n_times + n_hold) * 8.0
    raw = 2.0 * raw_points * (1.0 + 3.0 * deck) * 8.0
    decks_text = float(n_decks) * 700.0 + n_replicas * 140.0
    memory = 2.0 * arrays + float(min(workers, n_decks)) * raw + decks_text
    stored = arrays + float(n_decks) * (n_times * 8.0 + 2048.0) + decks_text
    return Estimate(arrays=arrays, memory=memory, stored=stored)
