"""Stationary averages with autocorrelation-aware errors.

Samples along one trajectory are correlated; the variance of a time average of ``N`` samples
is ``var(f) * tau_int / N`` with the integrated autocorrelation time (in samples)

    tau_int = 1 + 2 sum_{k >= 1} rho(k),

so ``N / tau_int`` is the effective number of independent samples.  ``rho`` is estimated
from the replica-averaged autocovariance (FFT, the usual biased 1/n normalisation) and the
sum is cut at Sokal's self-consistent window: the smallest ``M`` with ``M >= c tau_int(M)``
(c = 5 by default), which balances the bias of truncating against the noise of the tail.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .. import checks
from ..ensemble import Ensemble
from . import _checks

__all__ = ["AutocorrelationTime", "Estimate", "StationaryObservables",
           "integrated_autocorrelation_time", "mean_estimate", "stationary_observables"]


@dataclass(frozen=True)
class AutocorrelationTime:
    """``tau_int`` in samples, the window ``M`` it was summed to, and whether Sokal's window
    condition was met inside the record (if not, ``tau_int`` is a lower bound)."""

    tau_int: float
    window: int
    converged: bool


@dataclass(frozen=True)
class Estimate:
    """A scalar estimate with its standard error.

    ``stderr`` uses the integrated autocorrelation time ``tau_int`` (samples);
    ``stderr_replicas`` is the independent cross-check from the spread of per-replica
    averages (NaN with fewer than 2 replicas).  ``n_effective = n_samples / tau_int``.
    """

    value: float
    stderr: float
    tau_int: float
    n_samples: int
    n_effective: float
    stderr_replicas: float

    def __float__(self) -> float:
        return float(self.value)


@dataclass(frozen=True)
class StationaryObservables:
    """Stationary mean, variance and P(v > 0) of the velocity (each an :class:`Estimate`);
    ``dt`` converts ``tau_int`` to time units."""

    mean: Estimate
    variance: Estimate
    p_positive: Estimate
    burn_in: float
    dt: float
    n_replicas: int
    n_times: int


_FFT_BLOCK = 1 << 22  # complex values per FFT batch (~64 MB)


def integrated_autocorrelation_time(series: ArrayLike, c: float = 5.0) -> AutocorrelationTime:
    """Integrated autocorrelation time (in samples) of a stationary series, 1-D ``(n,)`` or
    several independent replicas ``(replicas, n)`` pooled (see module docstring)."""
    c = checks.positive("c", c)
    y = np.atleast_2d(np.asarray(series, dtype=float))
    if y.ndim != 2 or y.shape[1] < 2:
        raise ValueError("series must be (n,) or (replicas, n) with n >= 2")
    if not np.all(np.isfinite(y)):
        raise ValueError("series must be finite")
    n = y.shape[1]
    mean = y.mean()
    size = 1 << int(np.ceil(np.log2(2 * n)))
    acov = np.zeros(n)
    block = max(1, _FFT_BLOCK // size)  # bound the FFT workspace for long circuit records
    for r0 in range(0, y.shape[0], block):
        f = np.fft.rfft(y[r0:r0 + block] - mean, size, axis=1)
        acov += np.fft.irfft(f.real**2 + f.imag**2, size, axis=1)[:, :n].sum(axis=0)
    acov /= y.shape[0] * n
    if acov[0] <= 0:
        return AutocorrelationTime(1.0, 0, True)
    rho = acov / acov[0]
    tau_m = 1.0 + 2.0 * np.cumsum(rho[1:])  # tau_m[M-1] = tau_int summed to window M
    windows = np.arange(1, n)
    ok = windows >= c * tau_m
    if np.any(ok):
        m = int(np.argmax(ok))
        return AutocorrelationTime(float(max(tau_m[m], 1e-12)), int(windows[m]), True)
    return AutocorrelationTime(float(max(tau_m[-1], 1e-12)), n - 1, False)


def mean_estimate(samples: ArrayLike, c: float = 5.0) -> Estimate:
    """Mean of ``samples`` (replicas, n) with the ``tau_int`` error (and the replica-spread
    error as a cross-check)."""
    y = np.atleast_2d(np.asarray(samples, dtype=float))
    n_total = y.size
    value = float(y.mean())
    var = float(np.mean((y - value) ** 2))
    ac = integrated_autocorrelation_time(y, c)
    tau = ac.tau_int if var > 0 else 1.0
    if y.shape[0] >= 2:
        se_rep = float(y.mean(axis=1).std(ddof=1) / np.sqrt(y.shape[0]))
    else:
        se_rep = float("nan")
    return Estimate(value=value, stderr=float(np.sqrt(var * tau / n_total)), tau_int=tau,
                    n_samples=n_total, n_effective=n_total / tau, stderr_replicas=se_rep)


def stationary_observables(ensemble: Ensemble, burn_in: float = 0.0) -> StationaryObservables:
    """Stationary mean and variance of v and P(v > 0), pooled over replicas and all times
    after ``burn_in`` (a duration from the first time); compare with moments of p_s
    (paper, eq. (6)).

    The variance is the mean of ``(v - mean)^2``; its error treats that as an average of a
    correlated series with its own ``tau_int`` (the mean's uncertainty enters only at second
    order), and its 1/N bias is negligible against that error.
    """
    ens = _checks.ensemble(ensemble)
    i0 = _checks.burn_in_index(ens, burn_in)
    v = ens.v[:, i0:]
    if not np.all(np.isfinite(v)):
        raise ValueError("ensemble velocities after burn_in must be finite")
    mean = mean_estimate(v)
    variance = mean_estimate((v - mean.value) ** 2)
    p_pos = mean_estimate((v > 0).astype(float))
    return StationaryObservables(mean=mean, variance=variance, p_positive=p_pos,
                                 burn_in=float(burn_in), dt=_checks.uniform_dt(ens),
                                 n_replicas=v.shape[0], n_times=v.shape[1])
