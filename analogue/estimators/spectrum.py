"""Velocity power spectrum of an ensemble (circuit or Monte Carlo): Welch averaging over
segments and replicas, with error bars (issue 23 item 1).

Convention: the two-sided, angular-frequency ``S(omega)`` of
:mod:`analogue.theory.spectrum` (``S(0) = 2 D_x``, ``(1/2 pi) int S d omega = Var v``).

Estimator.  After the burn-in, the grand mean (all replicas and times) is subtracted (not
each segment's mean, which would empty the omega = 0 bin); each replica's record is cut into
segments of ``nperseg`` samples overlapping by half, each multiplied by the periodic Hann
window ``w``; with ``dt`` the sample interval

    P(omega_k) = (dt / sum_j w_j^2) |sum_j w_j dv_j e^{-i omega_k j dt}|^2,
    omega_k = 2 pi k / (nperseg dt),  k = 0 .. nperseg/2,

averaged over the segments of a replica, then over the replicas.

What it estimates (exactly, for a stationary record; :func:`welch_expectation`):

    E P(omega) = dt [C(0) + 2 sum_{n=1}^{nperseg-1} C(n dt) r_w(n) cos(omega n dt)],
    r_w(n) = sum_j w_j w_{j+n} / sum_j w_j^2,

i.e. the spectrum of the *sampled* process (aliasing: ``sum_m S(omega + 2 pi m/dt)``)
smoothed by the window's kernel (leakage, width ~ 4 pi/(nperseg dt)).  Give it the exact
autocorrelation (:func:`analogue.theory.exact.autocorrelation` at the lags ``n dt``) to get
the exact expected estimate, the reference a test or a budget compares with.  A circuit's
noise delivered as a hold of length T adds the factor of
:func:`analogue.theory.spectrum.noise_hold_factor` to S before sampling (exact for a linear
response, Delta = 0; a first-order statement otherwise).

Errors.  ``stderr``: the spread of the per-replica averages over the replicas (replicas are
independent; distribution-free; needs >= 2 replicas).  ``lower``/``upper``: the chi-square
band ``[nu P / chi2_{nu, 1 - alpha/2}, nu P / chi2_{nu, alpha/2}]`` with the equivalent degrees
of freedom of Welch's overlapped segments (Percival & Walden, Spectral Analysis for Physical
Applications, 1993, eq. 292b): per replica ``nu = 2 K / (1 + 2 sum_{m=1}^{K-1} (1 - m/K)
c_m^2)``, ``c_m = sum_j w_j w_{j + m D} / sum_j w_j^2`` for K segments at shift D, times the
number of replicas (half of it at omega = 0 and at the Nyquist frequency, where the
periodogram is a chi-square with 1 degree of freedom).  Hann at 50 % overlap: ``c_1^2 =
0.0278``, so ``nu ~ 1.9 K``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import signal, stats

from .. import checks
from ..ensemble import Ensemble
from . import _checks

__all__ = ["SpectrumEstimate", "velocity_spectrum", "welch_expectation", "welch_frequencies"]


@dataclass(frozen=True, eq=False)
class SpectrumEstimate:
    """Welch estimate of ``S(omega)`` (module docstring) at the angular frequencies ``omega``.

    ``value`` the replica average, ``stderr`` its standard error from the spread across
    replicas (NaN with one replica), ``lower``/``upper`` the chi-square band at
    ``confidence`` with ``dof`` equivalent degrees of freedom (interior frequencies; half at
    omega = 0 and Nyquist).  ``n_segments`` per replica; ``per_replica`` (replicas,
    frequencies) the replicas' own Welch averages (for ratios of two ensembles driven by
    common noise, whose errors are the spread of per-replica differences)."""

    omega: np.ndarray
    value: np.ndarray
    stderr: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    dof: float
    confidence: float
    n_replicas: int
    n_segments: int
    nperseg: int
    sample_dt: float
    per_replica: np.ndarray
    method: str = "welch, periodic Hann, 50% overlap, grand mean removed"


def _window(nperseg: int) -> np.ndarray:
    return np.asarray(signal.get_window("hann", nperseg), dtype=float)


def welch_frequencies(nperseg: int, sample_dt: float) -> np.ndarray:
    """Angular frequencies ``2 pi k/(nperseg dt)``, ``k = 0 .. nperseg/2``, of the estimate."""
    n = checks.integer("nperseg", nperseg, minimum=4)
    dt = checks.positive("sample_dt", sample_dt)
    return 2.0 * np.pi * np.fft.rfftfreq(n, dt)


def _lag_weights(w: np.ndarray) -> np.ndarray:
    """``r_w(n) = sum_j w_j w_{j+n} / sum w^2`` for n = 0 .. len(w) - 1."""
    full = np.correlate(w, w, mode="full")[w.size - 1:]
    out: np.ndarray = full / float(w @ w)
    return out


def welch_expectation(autocorrelation: ArrayLike, sample_dt: float) -> np.ndarray:
    """Exact expectation of :func:`velocity_spectrum`'s estimate at
    :func:`welch_frequencies` for a stationary process with connected autocorrelation
    ``autocorrelation[n] = C(n sample_dt)``, ``n = 0 .. nperseg - 1`` (module docstring):
    aliasing and the window's leakage included."""
    c = checks.finite_array("autocorrelation", autocorrelation)
    if c.ndim != 1 or c.size < 4:
        raise ValueError("autocorrelation must be 1-D with nperseg >= 4 lags C(0), C(dt), ...")
    dt = checks.positive("sample_dt", sample_dt)
    n = c.size
    r = _lag_weights(_window(n))
    omega = welch_frequencies(n, dt)
    lags = np.arange(1, n)
    terms = c[1:] * r[1:]
    out: np.ndarray = dt * (c[0] + 2.0 * np.cos(np.outer(omega, lags) * dt) @ terms)
    return out


def _dof(nperseg: int, step: int, k: int) -> float:
    """Equivalent degrees of freedom of one replica's average of k overlapped segments."""
    w = _window(nperseg)
    r = _lag_weights(w)
    m = np.arange(1, k)
    shifts = m * step
    cm = np.where(shifts < nperseg, r[np.minimum(shifts, nperseg - 1)], 0.0)
    return float(2.0 * k / (1.0 + 2.0 * np.sum((1.0 - m / k) * cm**2)))


def velocity_spectrum(ensemble: Ensemble, *, burn_in: float = 0.0, nperseg: int = 256,
                      confidence: float = 0.95) -> SpectrumEstimate:
    """Welch estimate of the stationary velocity spectrum ``S(omega)`` (module docstring)
    from the samples after ``burn_in`` (a duration), segments of ``nperseg`` samples."""
    ens = _checks.ensemble(ensemble)
    dt = _checks.uniform_dt(ens)
    n = checks.integer("nperseg", nperseg, minimum=4)
    conf = checks.in_range("confidence", confidence, 0.0, 1.0, closed=False)
    i0 = _checks.burn_in_index(ens, burn_in, min_samples=n)
    v = ens.v[:, i0:]
    if not np.all(np.isfinite(v)):
        raise ValueError("ensemble velocities after burn_in must be finite")
    step = n // 2
    k = 1 + (v.shape[1] - n) // step
    w = _window(n)
    scale = dt / float(w @ w)
    dv = v - v.mean()
    per_replica = np.zeros((v.shape[0], n // 2 + 1))
    for s in range(k):
        seg = dv[:, s * step:s * step + n] * w
        f = np.fft.rfft(seg, axis=1)
        per_replica += f.real**2 + f.imag**2
    per_replica *= scale / k
    value = per_replica.mean(axis=0)
    reps = v.shape[0]
    stderr = (per_replica.std(axis=0, ddof=1) / np.sqrt(reps) if reps >= 2
              else np.full(value.shape, np.nan))
    nu = reps * _dof(n, step, k)
    dof = np.full(value.shape, nu)
    dof[0] *= 0.5
    if n % 2 == 0:
        dof[-1] *= 0.5
    alpha = 1.0 - conf
    lower = dof * value / stats.chi2.ppf(1.0 - alpha / 2.0, dof)
    upper = dof * value / stats.chi2.ppf(alpha / 2.0, dof)
    return SpectrumEstimate(omega=welch_frequencies(n, dt), value=value, stderr=stderr,
                            lower=lower, upper=upper, dof=nu, confidence=conf,
                            n_replicas=reps, n_segments=k, nperseg=n, sample_dt=dt,
                            per_replica=per_replica)
