"""Transport of the position x(t) = integral v (the integral in the work, paper eq. (3)):
drift velocity and diffusion coefficient."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import checks
from ..ensemble import Ensemble
from . import _checks

__all__ = ["TransportEstimate", "transport", "diffusion_leave_group_out"]


@dataclass(frozen=True, eq=False)
class TransportEstimate:
    """Drift velocity and position diffusion coefficient with replica-spread errors.

    ``t``, ``mean_x``, ``var_x`` are the curves the fits used (t from the burn-in, x re-zeroed
    there); ``fit_window`` is the time span of the linear fits.
    """

    drift: float
    drift_se: float
    diffusion: float
    diffusion_se: float
    fit_window: tuple[float, float]
    t: np.ndarray
    mean_x: np.ndarray
    var_x: np.ndarray
    n_replicas: int


def _fit(ens: Ensemble, burn_in: float, fit_from: float | None
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Times and re-zeroed positions after the burn-in, the fitted samples and the OLS
    slope weights ``a`` (slope of y = a @ y[sel])."""
    i0 = _checks.burn_in_index(ens, burn_in, min_samples=3)
    t = ens.t[i0:] - ens.t[i0]
    x = ens.x[:, i0:] - ens.x[:, i0:i0 + 1]
    if x.shape[0] < 2:
        raise ValueError("transport needs >= 2 independent replicas")
    if not np.all(np.isfinite(x)):
        raise ValueError("ensemble positions after burn_in must be finite")
    start = 0.5 * float(t[-1]) if fit_from is None else checks.nonnegative("fit_from", fit_from)
    sel = t >= start - 1e-9 * max(float(t[-1]), 1.0)
    if np.count_nonzero(sel) < 3:
        raise ValueError(f"fit_from must leave >= 3 samples to fit, got {start!r} with a record "
                         f"of {float(t[-1])!r} after burn_in")
    ts = t[sel]
    a = (ts - ts.mean()) / np.sum((ts - ts.mean()) ** 2)  # OLS slope = a @ y
    return t, x, sel, a


def diffusion_leave_group_out(ensemble: Ensemble, labels: np.ndarray, groups: int,
                              burn_in: float = 0.0, fit_from: float | None = None
                              ) -> np.ndarray:
    """``transport(subset(ensemble, labels != j), burn_in, fit_from).diffusion`` for
    j = 0 .. groups - 1 (the delete-a-group jackknife's values), from per-replica pieces
    computed once: with y_r = x_r - <x> (the full ensemble's mean) and the sum d_S of y_r
    over the kept replicas S (|S| = n), sum_S (x_r - <x>_S)^2 = sum_S y_r^2 - d_S^2 / n, so
    D_S = 0.5 (sum_S a @ y_r^2 - a @ d_S^2 / n) / (n - 1).  Centring on the full mean keeps
    the subtraction small (d_S / n is the mean's shift when a group is left out), so the
    values agree with the direct route to rounding (tested to 1e-12)."""
    ens = _checks.ensemble(ensemble)
    _, x, sel, a = _fit(ens, burn_in, fit_from)
    y = x[:, sel]
    y = y - y.mean(axis=0)
    q = (y ** 2) @ a                 # per replica
    total = y.sum(axis=0)
    out = np.empty(groups)
    for j in range(groups):
        drop = labels == j
        n = int(np.count_nonzero(~drop))
        d = total - y[drop].sum(axis=0)
        out[j] = 0.5 * (q[~drop].sum() - (d ** 2 / n) @ a) / (n - 1)
    return out


def transport(ensemble: Ensemble, burn_in: float = 0.0, fit_from: float | None = None
              ) -> TransportEstimate:
    """Drift ``<v> = d<x>/dt`` and diffusion ``D_x`` from ``Var x(t) ~ 2 D_x t + const``.

    After the burn-in the positions are re-zeroed; ``<x(t)>`` and ``Var x(t)`` over the
    replicas are fitted by straight lines (ordinary least squares, slope and offset) on
    ``t >= fit_from`` (time since the burn-in; default half of the remaining record).  The
    offset absorbs the velocity-correlation transient (for an Ornstein-Uhlenbeck velocity
    ``Var x = 2 D (t - tau_c (1 - e^{-t/tau_c}))``), so ``fit_from`` should exceed a few
    correlation times.  Errors: the drift slope is the replica average of per-replica
    slopes, and the variance slope is linear in per-replica squared deviations to first
    order; the spread of those per-replica contributions gives the standard errors.
    """
    ens = _checks.ensemble(ensemble)
    t, x, sel, a = _fit(ens, burn_in, fit_from)
    R = x.shape[0]
    ts = t[sel]
    slopes = x[:, sel] @ a
    mean_x = x.mean(axis=0)
    sq = (x - mean_x) ** 2
    var_x = sq.sum(axis=0) / (R - 1)
    d_contrib = 0.5 * (sq[:, sel] @ a) * R / (R - 1)  # mean over r equals 0.5 * slope(var_x)
    return TransportEstimate(
        drift=float(slopes.mean()), drift_se=float(slopes.std(ddof=1) / np.sqrt(R)),
        diffusion=float(d_contrib.mean()), diffusion_se=float(d_contrib.std(ddof=1) / np.sqrt(R)),
        fit_window=(float(ts[0]), float(ts[-1])), t=t, mean_x=mean_x, var_x=var_x, n_replicas=R)
