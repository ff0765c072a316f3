"""Histogram estimates of the transition density f(v, t | v0) and of the stationary density
p_s(v) (paper, eq. (6)), each with a confidence band that is honest for how the samples
were drawn."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .. import checks
from ..ensemble import Ensemble
from . import _checks
from .intervals import clopper_pearson_interval, student_interval, wilson_interval

__all__ = ["DensityEstimate", "transition_density", "stationary_density"]


@dataclass(frozen=True, eq=False)
class DensityEstimate:
    """A histogram density with its uncertainty.

    ``density = (fraction of ALL samples in the bin) / width``, so samples outside the bins
    count in the normalisation and the density integrates to the fraction inside the range.

    Attributes
    ----------
    centres, edges : bin centres (nb,) and edges (nb + 1,)
    density : estimate (nb,)
    lower, upper : confidence band (nb,) at level ``confidence``
    stderr : standard error of ``density`` (nb,)
    counts : pooled counts per bin (nb,)
    n_samples : number of samples that went into the normalisation
    n_effective : median over occupied bins of ``p (1 - p) / SE(p)^2``: the number of
        independent samples that would give the same error (equals ``n_samples`` for iid data)
    units : number of independent units the errors come from (samples, or replicas x batches)
    confidence, method : band level and how it was built
    time : grid time of a transition density (None for a stationary density)
    """

    centres: np.ndarray
    edges: np.ndarray
    density: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    stderr: np.ndarray
    counts: np.ndarray
    n_samples: int
    n_effective: float
    units: int
    confidence: float
    method: str
    time: float | None = None

    @property
    def widths(self) -> np.ndarray:
        return np.diff(self.edges)


def transition_density(ensemble: Ensemble, t: float, bins: int | ArrayLike = 50,
                       range: tuple[float, float] | None = None, confidence: float = 0.95,
                       method: str = "wilson") -> DensityEstimate:
    """Histogram of the transition density ``f(v, t | v0)`` (paper, eqs. (46)-(51)) from the
    velocities of all replicas at the grid time nearest ``t``.

    Replicas are independent, so each bin count is binomial(n, p): the band is the Wilson
    score interval (``method="wilson"``) or the exact Clopper-Pearson interval
    (``method="clopper-pearson"``) on p, divided by the bin width; ``stderr`` is the
    binomial ``sqrt(p (1 - p) / n) / width``.
    """
    ens = _checks.ensemble(ensemble)
    c = checks.in_range("confidence", confidence, 0, 1, closed=False)
    if method not in ("wilson", "clopper-pearson"):
        raise ValueError(f"method must be 'wilson' or 'clopper-pearson', got {method!r}")
    i = _checks.time_index(ens, "t", t)
    samples = ens.v[:, i]
    e = _checks.edges(bins, range, samples)
    counts = _checks.binned_counts(samples[None, :], e)[0]
    n = samples.size
    width = np.diff(e)
    p = counts / n
    interval = wilson_interval if method == "wilson" else clopper_pearson_interval
    lo, hi = interval(counts, n, c)
    return DensityEstimate(
        centres=0.5 * (e[1:] + e[:-1]), edges=e, density=p / width,
        lower=lo / width, upper=hi / width, stderr=np.sqrt(p * (1 - p) / n) / width,
        counts=counts, n_samples=n, n_effective=float(n), units=n, confidence=c,
        method=method, time=float(ens.t[i]))


def stationary_density(ensemble: Ensemble, burn_in: float = 0.0, bins: int | ArrayLike = 50,
                       range: tuple[float, float] | None = None, confidence: float = 0.95,
                       batches_per_replica: int = 1) -> DensityEstimate:
    """Histogram of the stationary density ``p_s(v)`` (paper, eq. (6)) pooling every sample
    after ``burn_in`` (a duration from the first time) across all replicas.

    Pooled samples along one trajectory are correlated, so binomial errors would be far too
    small.  Instead each replica's record is cut into ``batches_per_replica`` contiguous
    batches (default 1: whole replicas); the fraction of samples in each bin is computed per
    batch and the error is the spread of these fractions across the ``units = replicas *
    batches`` batches (batch means).  Replicas are independent; batches of one replica are
    nearly so only if each is much longer than the velocity correlation time.  The band is
    Student-t with ``units - 1`` degrees of freedom, clipped at 0.  Samples beyond the last
    full batch are dropped.
    """
    ens = _checks.ensemble(ensemble)
    c = checks.in_range("confidence", confidence, 0, 1, closed=False)
    nbatch = checks.integer("batches_per_replica", batches_per_replica, minimum=1)
    i0 = _checks.burn_in_index(ens, burn_in)
    data = ens.v[:, i0:]
    length = data.shape[1] // nbatch
    if length < 1:
        raise ValueError(f"batches_per_replica must be <= the {data.shape[1]} samples after burn-in, "
                         f"got {nbatch}")
    units = data[:, : length * nbatch].reshape(-1, length)
    if units.shape[0] < 2:
        raise ValueError("stationary_density needs >= 2 independent units: use >= 2 replicas or "
                         "batches_per_replica >= 2")
    e = _checks.edges(bins, range, units)
    width = np.diff(e)
    per_unit = _checks.binned_counts(units, e)
    frac = per_unit / length
    p = frac.mean(axis=0)
    se = frac.std(axis=0, ddof=1) / np.sqrt(units.shape[0])
    lo, hi = student_interval(p, se, units.shape[0], c)
    return DensityEstimate(
        centres=0.5 * (e[1:] + e[:-1]), edges=e, density=p / width,
        lower=np.clip(lo, 0.0, None) / width, upper=hi / width, stderr=se / width,
        counts=per_unit.sum(axis=0), n_samples=units.size,
        n_effective=_effective_n(p, se), units=units.shape[0], confidence=c,
        method="batch-means")


def _effective_n(p: np.ndarray, se: np.ndarray) -> float:
    ok = (p > 0) & (p < 1) & (se > 0)
    if not np.any(ok):
        return float("nan")
    return float(np.median(p[ok] * (1 - p[ok]) / se[ok] ** 2))
