"""Prehistory of fluctuations (Dykman et al., PRL 68, 2718 (1992)): the paths that end in a
velocity window, averaged.  In the weak-noise limit their distribution concentrates on the
optimal path of the paper (eqs. EL1/EL2, sol_basic), which is how analogue experiments
measure optimal paths."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _checks

__all__ = ["Prehistory", "prehistory"]


@dataclass(frozen=True, eq=False)
class Prehistory:
    """Paths that pass through ``|v(t_target) - v_target| < window``.

    ``t`` is the time grid up to the target (``lag = t - t_target <= 0``); ``mean``,
    ``mean_se`` (NaN below 2 paths), ``median``, and the quantile band ``lower``/``upper`` at
    ``quantiles`` are per time.  ``hist[i, j]`` is the density in v of the selected paths at
    time bin i (``hist_t_edges``), velocity bin j (``hist_v_edges``): each time column
    integrates to 1 over v (paths outside the v range excepted).  ``indices`` are the selected
    replicas.
    """

    t: np.ndarray
    count: int
    n_replicas: int
    mean: np.ndarray
    mean_se: np.ndarray
    median: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    quantiles: tuple
    hist: np.ndarray
    hist_t_edges: np.ndarray
    hist_v_edges: np.ndarray
    indices: np.ndarray
    v_target: float
    t_target: float
    window: float

    @property
    def lag(self) -> np.ndarray:
        return self.t - self.t_target


def prehistory(ensemble, v_target, t_target, window, quantiles=(0.1, 0.9), lookback=None,
               v_bins=40, v_range=None, time_bins=None) -> Prehistory:
    """Select the replicas with ``|v(t_target) - v_target| < window`` (``t_target`` snapped to
    the nearest grid time) and summarise their paths on ``[t_target - lookback, t_target]``
    (default: from the start).  ``time_bins`` coarse-grains the 2-D histogram in time
    (default: one column per grid time).  Compare ``mean``/``median`` with
    ``analogue.theory.weak_noise.optimal_path``.
    """
    ens = _checks.ensemble(ensemble)
    vt = _checks.finite("v_target", v_target)
    win = _checks.positive("window", window)
    i = _checks.time_index(ens, "t_target", t_target)
    try:
        q = tuple(float(x) for x in quantiles)
    except TypeError:
        raise ValueError(f"quantiles must be a pair (low, high) in [0, 1], got {quantiles!r}") from None
    if len(q) != 2 or not 0 <= q[0] < q[1] <= 1:
        raise ValueError(f"quantiles must be a pair (low, high) with 0 <= low < high <= 1, got {quantiles!r}")
    if lookback is None:
        j0 = 0
    else:
        lb = _checks.nonnegative("lookback", lookback)
        j0 = int(np.searchsorted(ens.t, ens.t[i] - lb - 1e-9 * max(lb, 1.0), side="left"))
    sel = np.flatnonzero(np.abs(ens.v[:, i] - vt) < win)
    if sel.size == 0:
        raise ValueError(f"no trajectory has |v(t_target) - v_target| < window={win!r} at "
                         f"t_target={float(ens.t[i])!r}: widen window or use more replicas")
    paths = ens.v[sel, j0:i + 1]
    t = ens.t[j0:i + 1]
    count = sel.size
    mean = paths.mean(axis=0)
    mean_se = paths.std(axis=0, ddof=1) / np.sqrt(count) if count >= 2 else np.full_like(mean, np.nan)
    median, lower, upper = np.quantile(paths, [0.5, q[0], q[1]], axis=0)

    if time_bins is None:
        dt = ens.dt if t.size > 1 else 1.0
        t_edges = np.concatenate([t - 0.5 * dt, [t[-1] + 0.5 * dt]])
    else:
        t_edges = _checks.edges(time_bins, (float(t[0]), float(t[-1]) + 1e-12), t)
    v_edges = _checks.edges(v_bins, v_range, paths)
    tt = np.broadcast_to(t, paths.shape).ravel()
    hist, _, _ = np.histogram2d(tt, paths.ravel(), bins=[t_edges, v_edges])
    per_column = np.histogram(t, bins=t_edges)[0] * count  # samples per time bin
    with np.errstate(invalid="ignore", divide="ignore"):
        hist = hist / (per_column[:, None] * np.diff(v_edges)[None, :])
    return Prehistory(t=t, count=count, n_replicas=ens.replicas, mean=mean, mean_se=mean_se,
                      median=median, lower=lower, upper=upper, quantiles=q, hist=hist,
                      hist_t_edges=t_edges, hist_v_edges=v_edges, indices=sel, v_target=vt,
                      t_target=float(ens.t[i]), window=win)
