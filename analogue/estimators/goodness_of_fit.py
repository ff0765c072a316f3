"""Goodness of fit of independent samples against a theoretical density."""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["histogram_chi2"]


def histogram_chi2(samples: ArrayLike, v: np.ndarray, f: np.ndarray,
                   min_expected: float = 5.0) -> tuple[float, int]:
    """Pearson chi^2 of iid ``samples`` against the density ``f`` on the grid ``v``.

    Bins are equal-probability under the theory (about ``n/20`` expected counts each, at
    least ``min_expected``), so every bin is well populated and the statistic is close to its
    chi^2 law; returns ``(chi2, dof)``."""
    samples = np.asarray(samples, dtype=float)
    n = samples.size
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(v))])
    cdf /= cdf[-1]
    k = int(max(2, min(20, n // min_expected)))
    qs = np.linspace(0, 1, k + 1)[1:-1]
    edges = np.interp(qs, cdf, v)
    counts = np.bincount(np.searchsorted(edges, samples), minlength=k)
    expected = n / k
    return float(np.sum((counts - expected) ** 2) / expected), k - 1
