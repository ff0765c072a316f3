"""Confidence intervals for binomial proportions and for means of independent units."""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats

__all__ = ["wilson_interval", "clopper_pearson_interval", "student_interval"]


def wilson_interval(k: ArrayLike, n: ArrayLike, confidence: float = 0.95
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval for a binomial proportion with ``k`` successes in ``n`` trials.

    Its coverage stays close to nominal down to a few counts (unlike the Wald interval,
    which collapses to zero width at k = 0).
    """
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    z = stats.norm.ppf(0.5 + 0.5 * confidence)
    p = k / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return np.clip(centre - half, 0.0, 1.0), np.clip(centre + half, 0.0, 1.0)


def clopper_pearson_interval(k: ArrayLike, n: ArrayLike, confidence: float = 0.95
                             ) -> tuple[np.ndarray, np.ndarray]:
    """Exact (conservative) Clopper-Pearson interval from beta quantiles."""
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    alpha = 1.0 - confidence
    with np.errstate(invalid="ignore"):
        lo = np.where(k > 0, stats.beta.ppf(alpha / 2, k, n - k + 1), 0.0)
        hi = np.where(k < n, stats.beta.ppf(1 - alpha / 2, k + 1, n - k), 1.0)
    return lo, hi


def student_interval(mean: ArrayLike, stderr: ArrayLike, units: int, confidence: float = 0.95
                     ) -> tuple[np.ndarray, np.ndarray]:
    """``mean +- t_{units-1} * stderr``: band for a mean over ``units`` independent units
    (replicas or batches) whose spread gave ``stderr``."""
    q = stats.t.ppf(0.5 + 0.5 * confidence, units - 1)
    mean = np.asarray(mean, dtype=float)
    return mean - q * stderr, mean + q * stderr
