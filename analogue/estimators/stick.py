"""Stick statistics: how much of the time the velocity sits near zero, and for how long.

With the exact sgn law the stationary law still has no atom at v = 0 (noise unsticks the
object at once), so "stuck" means ``|v| < threshold``; its exact stationary probability is
the integral of p_s (paper, eq. (6)) over ``(-threshold, threshold)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import checks
from ..ensemble import Ensemble
from . import _checks
from ..theory.stationary import stick_fraction_theory  # physics: lives in theory, re-exported
from .stationary import Estimate, mean_estimate

__all__ = ["StickStatistics", "stick_statistics", "stick_fraction_theory"]


@dataclass(frozen=True, eq=False)
class StickStatistics:
    """Fraction of time with ``|v| < threshold`` (an :class:`Estimate`, autocorrelation-aware)
    and the stick episodes: maximal runs of consecutive stuck samples, duration = samples x dt.

    Episodes that touch the start or the end of the analysed record are censored (their true
    length is unknown) and left out of ``durations``; ``censored`` counts them.  Leaving them
    out biases ``mean_duration`` slightly low (long episodes are more likely to be cut) unless
    the record is much longer than an episode.  ``mean_duration_se`` treats each replica as
    a cluster (ratio estimator over replicas), since episodes of one replica may correlate.
    """

    fraction: Estimate
    durations: np.ndarray
    mean_duration: float
    mean_duration_se: float
    n_episodes: int
    censored: int
    threshold: float
    dt: float


def stick_statistics(ensemble: Ensemble, threshold: float, burn_in: float = 0.0) -> StickStatistics:
    """Stick fraction and episode durations after ``burn_in`` (a duration from t[0])."""
    ens = _checks.ensemble(ensemble)
    th = checks.positive("threshold", threshold)
    dt = _checks.uniform_dt(ens)
    i0 = _checks.burn_in_index(ens, burn_in)
    stuck = np.abs(ens.v[:, i0:]) < th
    R, n = stuck.shape
    fraction = mean_estimate(stuck.astype(float))

    padded = np.zeros((R, n + 2), dtype=np.int8)
    padded[:, 1:-1] = stuck
    edges = np.diff(padded, axis=1)
    rs, starts = np.nonzero(edges == 1)   # row-major order pairs each start with its end
    _, ends = np.nonzero(edges == -1)
    complete = (starts > 0) & (ends < n)
    lengths = (ends - starts)[complete]
    rows = rs[complete]
    durations = lengths * dt
    N = durations.size
    if N == 0:
        mean, se = float("nan"), float("nan")
    else:
        mean = float(durations.mean())
        if R >= 2:
            S = np.bincount(rows, weights=durations, minlength=R)
            cnt = np.bincount(rows, minlength=R)
            z = S - mean * cnt
            se = float(np.sqrt(R / (R - 1) * np.sum(z * z)) / N)
        else:
            se = float(durations.std(ddof=1) / np.sqrt(N)) if N >= 2 else float("nan")
    return StickStatistics(fraction=fraction, durations=durations, mean_duration=mean,
                           mean_duration_se=se, n_episodes=N,
                           censored=int(np.count_nonzero(~complete)), threshold=th, dt=dt)
