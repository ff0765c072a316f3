"""Ensemble-record helpers shared by the estimators: the record itself, its burn-in and time
indices, bin edges and counts (no physics here; the argument checks are analogue.checks)."""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import checks
from ..ensemble import Ensemble


def ensemble(obj: object) -> Ensemble:
    return checks.instance("ensemble", obj, Ensemble, description="an analogue.Ensemble")


def uniform_dt(ens: Ensemble) -> float:
    """Sample interval; the estimators that convert lags to times need a uniform grid."""
    if ens.t.size < 2:
        raise ValueError("ensemble must have at least 2 time points")
    steps = np.diff(ens.t)
    dt = float(steps.mean())
    if np.max(np.abs(steps - dt)) > 1e-6 * dt:
        raise ValueError("ensemble time grid must be uniform (steps differ by more than 1e-6 dt)")
    return dt


def burn_in_index(ens: Ensemble, burn_in: float, min_samples: int = 2) -> int:
    """Index of the first sample with ``t >= t[0] + burn_in`` (burn_in is a duration)."""
    b = checks.nonnegative("burn_in", burn_in)
    duration = float(ens.t[-1] - ens.t[0])
    i0 = int(np.searchsorted(ens.t, ens.t[0] + b - 1e-9 * max(duration, 1.0), side="left"))
    if ens.t.size - i0 < min_samples:
        raise ValueError(f"burn_in must leave at least {min_samples} samples: got burn_in={b!r} "
                         f"for a record of duration {duration!r}")
    return i0


def time_index(ens: Ensemble, name: str, time: float) -> int:
    """Grid index nearest ``time``; the time must lie on the record (within half a step)."""
    tt = checks.finite(name, time)
    half = 0.5 * (ens.dt if ens.t.size > 1 else 0.0)
    if not ens.t[0] - half <= tt <= ens.t[-1] + half:
        raise ValueError(f"{name} must be in [{float(ens.t[0])!r}, {float(ens.t[-1])!r}], "
                         f"got {tt!r}")
    return int(np.argmin(np.abs(ens.t - tt)))


def edges(bins: int | ArrayLike, value_range: tuple[float, float] | None,
          data: ArrayLike) -> np.ndarray:
    """Bin edges from an int (with ``value_range`` or the data's finite extent) or from an
    explicit increasing array of edges."""
    if np.ndim(bins) == 1:
        e = np.asarray(bins, dtype=float)
        if e.size < 2 or not np.all(np.isfinite(e)) or not np.all(np.diff(e) > 0):
            raise ValueError("bins given as edges must be >= 2 finite, strictly increasing values")
        return e
    nb = checks.integer("bins", bins, minimum=1)
    if value_range is None:
        d = np.asarray(data, dtype=float)
        d = d[np.isfinite(d)]
        if d.size == 0:
            raise ValueError("no finite samples to bin")
        lo, hi = float(d.min()), float(d.max())
    else:
        try:
            lo, hi = (checks.finite("range[0]", value_range[0]), checks.finite("range[1]", value_range[1]))
        except (TypeError, IndexError):
            raise ValueError(f"range must be a pair (low, high), got {value_range!r}") from None
        if not lo < hi:
            raise ValueError(f"range must have low < high, got {value_range!r}")
    if lo == hi:
        lo, hi = lo - 0.5, hi + 0.5
    return np.linspace(lo, hi, nb + 1)


def binned_counts(samples: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Counts per row of a 2-D array of samples: (rows, bins).  Same convention as
    ``np.histogram`` (half-open bins, the last one closed); samples outside are dropped."""
    s = np.atleast_2d(np.asarray(samples, dtype=float))
    rows, nb = s.shape[0], e.size - 1
    idx = np.searchsorted(e, s, side="right") - 1
    idx = np.where(s == e[-1], nb - 1, idx)
    inside = (idx >= 0) & (idx < nb) & np.isfinite(s)
    flat = (np.arange(rows)[:, None] * nb + idx)[inside]
    return np.bincount(flat, minlength=rows * nb).reshape(rows, nb)
