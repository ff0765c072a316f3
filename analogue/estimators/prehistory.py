"""Prehistory of fluctuations (Dykman et al., PRL 68, 2718 (1992)): the paths that end in a
velocity window, averaged.  In the weak-noise limit their distribution concentrates on the
optimal path of the paper (eqs. (15a)/(15b), (16)), which is how analogue experiments
measure optimal paths.

Two selections: :func:`prehistory` (all replicas at one time ``t_target``, the transient
problem f(v, t | v0) of the paper) and :func:`stationary_prehistory` (every arrival into the
window along long stationary records, Dykman's experimental protocol).
"""
from __future__ import annotations

from dataclasses import dataclass

from collections.abc import Iterable
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from .. import checks
from ..ensemble import Ensemble
from . import _checks

__all__ = ["Prehistory", "prehistory", "prehistory_count", "stationary_prehistory"]

_MAX_SEGMENT_VALUES = 50_000_000  # path samples gathered at once (400 MB of float64)


@dataclass(frozen=True, eq=False)
class Prehistory:
    """Paths that end in ``|v - v_target| < window``.

    ``t`` is the time grid of the paths, ending at ``t_target`` (``lag = t - t_target <= 0``;
    for a stationary prehistory ``t`` is the lag itself and ``t_target = 0``).  ``mean``,
    ``mean_se`` (NaN if it cannot be estimated), ``median`` and the quantile band
    ``lower``/``upper`` at ``quantiles`` are per time.  ``hist[i, j]`` is the density in v of
    the selected paths in time bin i (``hist_t_edges``) and velocity bin j
    (``hist_v_edges``): each time column integrates to 1 over v (minus paths outside the v
    range).  ``indices`` are the replicas of the selected paths (repeated for several arrivals
    in one replica) and ``arrival_times`` the grid times at which they end.
    """

    t: np.ndarray
    count: int
    n_replicas: int
    mean: np.ndarray
    mean_se: np.ndarray
    median: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    quantiles: tuple[float, float]
    hist: np.ndarray
    hist_t_edges: np.ndarray
    hist_v_edges: np.ndarray
    indices: np.ndarray
    arrival_times: np.ndarray
    v_target: float
    t_target: float
    window: float

    @property
    def lag(self) -> np.ndarray:
        return self.t - self.t_target


def _quantile_pair(quantiles: ArrayLike) -> tuple[float, float]:
    try:
        q = tuple(float(x) for x in cast("Iterable[float]", quantiles))  # else TypeError
    except (TypeError, ValueError):
        raise ValueError(f"quantiles must be a pair (low, high) in [0, 1], got {quantiles!r}") from None
    if len(q) != 2 or not 0 <= q[0] < q[1] <= 1:
        raise ValueError(f"quantiles must be a pair (low, high) with 0 <= low < high <= 1, "
                         f"got {quantiles!r}")
    return q


def _summarise(paths: np.ndarray, t: np.ndarray, dt: float, q: tuple[float, float],
               v_bins: int | ArrayLike, v_range: tuple[float, float] | None,
               time_bins: int | ArrayLike | None) -> dict[str, Any]:
    """Pointwise mean, median, quantile band and per-time density histogram of paths."""
    mean = paths.mean(axis=0)
    median, lower, upper = np.quantile(paths, [0.5, q[0], q[1]], axis=0)
    if time_bins is None:
        t_edges = np.concatenate([t - 0.5 * dt, [t[-1] + 0.5 * dt]])
    else:
        t_edges = _checks.edges(time_bins, (float(t[0]), float(t[-1]) + 1e-12 * max(dt, 1.0)), t)
    v_edges = _checks.edges(v_bins, v_range, paths)
    tt = np.broadcast_to(t, paths.shape).ravel()
    hist, _, _ = np.histogram2d(tt, paths.ravel(), bins=[t_edges, v_edges])
    per_column = np.histogram(t, bins=t_edges)[0] * paths.shape[0]  # samples per time bin
    with np.errstate(invalid="ignore", divide="ignore"):
        hist = hist / (per_column[:, None] * np.diff(v_edges)[None, :])
    return dict(mean=mean, median=median, lower=lower, upper=upper, hist=hist,
                hist_t_edges=t_edges, hist_v_edges=v_edges)


def prehistory_count(ensemble: Ensemble, v_target: float, t_target: float,
                     window: float) -> int:
    """How many replicas have ``|v(t_target) - v_target| < window`` (``t_target`` snapped to
    the nearest grid time): the paths :func:`prehistory` summarises, 0 included (where
    :func:`prehistory` raises), so that a report can say what it found for every target."""
    ens = _checks.ensemble(ensemble)
    vt = checks.finite("v_target", v_target)
    win = checks.positive("window", window)
    i = _checks.time_index(ens, "t_target", t_target)
    return int(np.count_nonzero(np.abs(ens.v[:, i] - vt) < win))


def prehistory(ensemble: Ensemble, v_target: float, t_target: float, window: float,
               quantiles: ArrayLike = (0.1, 0.9), lookback: float | None = None,
               v_bins: int | ArrayLike = 40, v_range: tuple[float, float] | None = None,
               time_bins: int | ArrayLike | None = None) -> Prehistory:
    """Select the replicas with ``|v(t_target) - v_target| < window`` (``t_target`` snapped to
    the nearest grid time) and summarise their paths on ``[t_target - lookback, t_target]``
    (default: from the start).  Replicas are independent, so ``mean_se`` is the plain
    standard error over the selected paths.  ``time_bins`` coarse-grains the 2-D histogram
    in time (default: one column per grid time).  Compare ``mean``/``median`` with
    ``analogue.theory.weak_noise.optimal_path``.
    """
    ens = _checks.ensemble(ensemble)
    vt = checks.finite("v_target", v_target)
    win = checks.positive("window", window)
    i = _checks.time_index(ens, "t_target", t_target)
    q = _quantile_pair(quantiles)
    if lookback is None:
        j0 = 0
    else:
        lb = checks.nonnegative("lookback", lookback)
        j0 = int(np.searchsorted(ens.t, ens.t[i] - lb - 1e-9 * max(lb, 1.0), side="left"))
    sel = np.flatnonzero(np.abs(ens.v[:, i] - vt) < win)
    if sel.size == 0:
        raise ValueError(f"no trajectory has |v(t_target) - v_target| < window={win!r} at "
                         f"t_target={float(ens.t[i])!r}: widen window or use more replicas")
    paths = ens.v[sel, j0:i + 1]
    t = ens.t[j0:i + 1]
    count = sel.size
    if count >= 2:
        mean_se = paths.std(axis=0, ddof=1) / np.sqrt(count)
    else:
        mean_se = np.full(t.size, np.nan)
    dt = ens.dt if ens.t.size > 1 else 1.0
    return Prehistory(t=t, count=count, n_replicas=ens.replicas, mean_se=mean_se,
                      quantiles=q, indices=sel, arrival_times=np.full(count, float(ens.t[i])),
                      v_target=vt, t_target=float(ens.t[i]), window=win,
                      **_summarise(paths, t, dt, q, v_bins, v_range, time_bins))


def stationary_prehistory(ensemble: Ensemble, v_target: float, window: float, lookback: float,
                          burn_in: float = 0.0, entries_only: bool = True,
                          quantiles: ArrayLike = (0.1, 0.9), v_bins: int | ArrayLike = 40,
                          v_range: tuple[float, float] | None = None,
                          time_bins: int | ArrayLike | None = None,
                          cluster_time: float | None = None) -> Prehistory:
    """Prehistory of stationary fluctuations: every path segment of length ``lookback`` that
    ends inside ``|v - v_target| < window`` at any time after ``burn_in + lookback``.

    ``entries_only=True`` keeps only arrivals (the previous sample is outside the window), so
    one long visit counts once, as in Dykman's measurements; ``False`` keeps every sample in
    the window (then the conditional mean is exactly ``E[v(t - s) | v(t) in window]``).  The
    time axis ``t`` is the lag (<= 0).

    Segments of one record overlap and correlate, so ``mean_se`` treats arrivals as clusters:
    each replica is cut into blocks of ``cluster_time`` (default ``10 * lookback``) and the
    error is the ratio-estimator spread over the blocks, honest when a block is much longer
    than the velocity correlation time.
    """
    ens = _checks.ensemble(ensemble)
    vt = checks.finite("v_target", v_target)
    win = checks.positive("window", window)
    q = _quantile_pair(quantiles)
    dt = _checks.uniform_dt(ens)
    k = int(round(checks.positive("lookback", lookback) / dt))
    if k < 1:
        raise ValueError(f"lookback must be >= the sample interval dt={dt!r}, got {lookback!r}")
    block_time = 10 * k * dt if cluster_time is None else checks.positive("cluster_time", cluster_time)
    block = max(1, int(round(block_time / dt)))
    i0 = _checks.burn_in_index(ens, burn_in, min_samples=k + 2)
    inside = np.abs(ens.v - vt) < win
    arrive = inside.copy()
    if entries_only:
        arrive[:, 1:] &= ~inside[:, :-1]
    arrive[:, : i0 + k] = False  # the whole segment must lie after the burn-in
    rows, cols = np.nonzero(arrive)
    if rows.size == 0:
        raise ValueError(f"no path reaches |v - v_target| < window={win!r} after burn_in: "
                         "widen window or use longer records")
    if rows.size * (k + 1) > _MAX_SEGMENT_VALUES:
        raise ValueError(f"{rows.size} arrivals x {k + 1} samples exceed the memory budget: use "
                         "entries_only=True, a narrower window or a shorter lookback")
    paths = ens.v[rows[:, None], cols[:, None] + np.arange(-k, 1)[None, :]]
    lags = dt * np.arange(-k, 1)
    # cluster-robust (ratio estimator) standard error of the pointwise mean
    cluster = rows * (ens.t.size // block + 1) + cols // block
    _, cid = np.unique(cluster, return_inverse=True)
    n_cl = int(cid.max()) + 1
    count = rows.size
    mean = paths.mean(axis=0)
    if n_cl >= 2:
        sums = np.zeros((n_cl, k + 1))
        np.add.at(sums, cid, paths)
        sizes = np.bincount(cid, minlength=n_cl)
        z = sums - sizes[:, None] * mean[None, :]
        mean_se = np.sqrt(n_cl / (n_cl - 1) * np.sum(z * z, axis=0)) / count
    else:
        mean_se = np.full(k + 1, np.nan)
    return Prehistory(t=lags, count=count, n_replicas=ens.replicas, mean_se=mean_se,
                      quantiles=q, indices=rows, arrival_times=ens.t[cols], v_target=vt,
                      t_target=0.0, window=win,
                      **_summarise(paths, lags, dt, q, v_bins, v_range, time_bins))
