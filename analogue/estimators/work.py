"""Work-rate statistics: samples of ``w = W_tau / tau`` (paper, eqs. (3) and (52)),
their distribution ``P_tau(w)``, the fluctuation ratio (eqs. (67), (68)) and the empirical
rate function (eq. (54)).

Windows taken along one trajectory (especially overlapping ones) are strongly correlated,
so every error here comes from the spread across the INDEPENDENT replicas: each replica
gives its own histogram fraction per bin, and nonlinear functions (logs, ratios, the shift
to the minimum) are propagated by linearising them replica by replica (the delta method
applied to the replica averages), which keeps the covariance between bins.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .. import checks
from ..ensemble import Ensemble
from . import _checks
from .intervals import student_interval
from .density import _effective_n

__all__ = ["WorkDistribution", "FluctuationRatio", "RateFunctionEstimate", "LineFit",
           "work_rate_samples", "work_distribution", "fluctuation_ratio",
           "empirical_rate_function"]


def _lag(ens: Ensemble, tau: float) -> tuple[int, float]:
    tau = checks.positive("tau", tau)
    dt = _checks.uniform_dt(ens)
    k = int(round(tau / dt))
    if k < 1 or abs(k * dt - tau) > 1e-6 * max(tau, dt):
        raise ValueError(f"tau must be a positive multiple of the sample interval dt={dt!r}, "
                         f"got {tau!r}")
    return k, dt


def work_rate_samples(ensemble: Ensemble, tau: float, force: float, burn_in: float = 0.0,
                      overlap: bool = True, stride: int | None = None) -> np.ndarray:
    """Work rates ``w = F (x(s + tau) - x(s)) / tau`` (paper, eqs. (3), (52)) for
    windows starting at ``s >= t[0] + burn_in``.

    ``overlap=True`` starts a window every ``stride`` samples (default 1); ``overlap=False``
    uses back-to-back windows (stride = tau / dt).  ``tau`` must be a multiple of the sample
    interval.  Returns an array (replicas, windows): keep the replica axis, it is what makes
    honest errors possible.
    """
    ens = _checks.ensemble(ensemble)
    force = checks.finite("force", force)
    k, dt = _lag(ens, tau)
    i0 = _checks.burn_in_index(ens, burn_in)
    if overlap:
        step = 1 if stride is None else checks.integer("stride", stride, minimum=1)
    else:
        if stride is not None:
            raise ValueError("stride must be None when overlap=False (windows are back to back)")
        step = k
    starts = np.arange(i0, ens.t.size - k, step)
    if starts.size == 0:
        raise ValueError(f"tau={tau!r} must be shorter than the record after burn_in "
                         f"({float(ens.t[-1] - ens.t[i0])!r})")
    # strided slices, not fancy indexing (starts + k): the same numbers without gathering
    # two copies of x first (the report's jackknife calls this ~400 times; measured 12 s ->
    # 3 s).  Computed on x.T so that the result keeps the layout fancy indexing gave (column
    # major): reductions over it (mean, var) then add in the same order, to the last bit.
    n, i1 = starts.size, int(starts[0])
    end = i1 + step * (n - 1) + 1
    xt = ens.x.T
    dx = np.subtract(xt[i1 + k:end + k:step], xt[i1:end:step], order="C").T
    return np.asarray(force * dx / (k * dt))


@dataclass(frozen=True, eq=False)
class WorkDistribution:
    """Histogram of ``P_tau(w)`` with replica-spread errors.

    ``replica_fractions[r, j]`` is the fraction of replica r's windows falling in bin j; the
    density is their replica mean over the bin width.  ``mean`` and ``mean_se`` are the mean
    work rate and its replica-spread error.

    The replica-spread error is only as good as the number of replicas that actually reach a
    bin (``contributing``): in the tails one rare excursion fills many overlapping windows, so
    a bin with 30 counts may rest on 5 replicas, and its (skewed, zero-inflated) spread gives
    heavy-tailed z-scores.  Trust the errors where ``contributing`` is a few tens or more.
    """

    centres: np.ndarray
    edges: np.ndarray
    density: np.ndarray
    stderr: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    counts: np.ndarray
    replica_fractions: np.ndarray
    tau: float
    force: float
    n_replicas: int
    windows_per_replica: int
    stride: int
    n_effective: float
    confidence: float
    mean: float
    mean_se: float

    @property
    def widths(self) -> np.ndarray:
        return np.diff(self.edges)

    @property
    def contributing(self) -> np.ndarray:
        """Number of replicas with at least one window in each bin."""
        return np.asarray(np.count_nonzero(self.replica_fractions > 0, axis=0))


def work_distribution(ensemble: Ensemble, tau: float, force: float, bins: int | ArrayLike = 41,
                      burn_in: float = 0.0, overlap: bool = True,
                      range: tuple[float, float] | None = None, stride: int | None = None,
                      confidence: float = 0.95) -> WorkDistribution:
    """Distribution ``P_tau(w)`` of the work rate (paper, eqs. (53), (54)).

    Without ``range`` the bins are symmetric about 0, ``(-max|w|, max|w|)``, so that
    :func:`fluctuation_ratio` can pair ``w`` with ``-w``.  Errors are the spread of the
    per-replica histogram fractions across replicas (>= 2 needed), which is honest however
    much the windows overlap; the band is Student-t with ``replicas - 1`` degrees of freedom.
    """
    ens = _checks.ensemble(ensemble)
    c = checks.in_range("confidence", confidence, 0, 1, closed=False)
    w = work_rate_samples(ens, tau, force, burn_in=burn_in, overlap=overlap, stride=stride)
    R, nw = w.shape
    if R < 2:
        raise ValueError("work_distribution needs >= 2 independent replicas for its errors")
    if range is None and np.ndim(bins) == 0:
        finite_w = w[np.isfinite(w)]
        m = float(np.max(np.abs(finite_w))) if finite_w.size else 0.0
        m = m * (1 + 1e-9) if m > 0 else 1.0
        range = (-m, m)
    e = _checks.edges(bins, range, w)
    counts = _checks.binned_counts(w, e)
    frac = counts / nw
    p = frac.mean(axis=0)
    se = frac.std(axis=0, ddof=1) / np.sqrt(R)
    lo, hi = student_interval(p, se, R, c)
    width = np.diff(e)
    k, dt = _lag(ens, tau)
    per_rep_mean = w.mean(axis=1)
    return WorkDistribution(
        centres=0.5 * (e[1:] + e[:-1]), edges=e, density=p / width, stderr=se / width,
        lower=np.clip(lo, 0.0, None) / width, upper=hi / width, counts=counts.sum(axis=0),
        replica_fractions=frac, tau=k * dt, force=float(force), n_replicas=R,
        windows_per_replica=nw, stride=(k if not overlap else (1 if stride is None else int(stride))),
        n_effective=_effective_n(p, se), confidence=c, mean=float(per_rep_mean.mean()),
        mean_se=float(per_rep_mean.std(ddof=1) / np.sqrt(R)))


@dataclass(frozen=True)
class LineFit:
    """Weighted least-squares line ``y = slope * w + intercept`` with replica-spread errors."""

    slope: float
    slope_se: float
    intercept: float
    intercept_se: float


@dataclass(frozen=True, eq=False)
class FluctuationRatio:
    """``ln[P(w)/P(-w)] / (tau gamma)`` on the positive bin centres ``w`` (paper, eqs. (67),
    (68) predict ``w/(m tau_m) + a Delta`` for large tau and gamma).

    ``influence[r, j]`` is replica r's linearised contribution to ``ratio[j]`` (mean zero);
    ``stderr = influence.std(ddof=1) / sqrt(R)``, and correlated fits use it too.
    """

    w: np.ndarray
    ratio: np.ndarray
    stderr: np.ndarray
    counts_positive: np.ndarray
    counts_negative: np.ndarray
    influence: np.ndarray
    tau: float
    gamma: float

    def fit_line(self, through_origin: bool = False) -> LineFit:
        """Fit ``ratio = slope * w (+ intercept)`` with weights 1/stderr^2; the errors come
        from the replica influences, so the correlation between bins is accounted for.  The
        intercept estimates the paper's jump ``a Delta`` (eq. (67))."""
        need = 1 if through_origin else 2
        ok = self.stderr > 0
        if np.count_nonzero(ok) < need:
            raise ValueError(f"fit_line needs >= {need} bins with a nonzero error")
        w, y, wt = self.w[ok], self.ratio[ok], 1.0 / self.stderr[ok] ** 2
        X = w[:, None] if through_origin else np.column_stack([w, np.ones_like(w)])
        A = np.linalg.solve(X.T @ (wt[:, None] * X), (X * wt[:, None]).T)  # (p, nbins)
        beta = A @ y
        infl = self.influence[:, ok] @ A.T  # (R, p)
        se = infl.std(axis=0, ddof=1) / np.sqrt(infl.shape[0])
        if through_origin:
            return LineFit(float(beta[0]), float(se[0]), 0.0, 0.0)
        return LineFit(float(beta[0]), float(se[0]), float(beta[1]), float(se[1]))


def _tau_gamma(dist: object, tau: float, gamma: float) -> tuple[float, float]:
    if not isinstance(dist, WorkDistribution):
        raise ValueError(f"dist must be a WorkDistribution, got {type(dist).__name__}")
    g = checks.positive("gamma", gamma)
    if tau is None:
        return dist.tau, g
    t = checks.positive("tau", tau)
    if abs(t - dist.tau) > 1e-6 * dist.tau:
        raise ValueError(f"tau must match the distribution's tau={dist.tau!r}, got {t!r}")
    return t, g


def fluctuation_ratio(dist: WorkDistribution, tau: float, gamma: float,
                      min_replicas: int = 10) -> FluctuationRatio:
    """``ln[P_tau(w)/P_tau(-w)] / (tau gamma)`` (paper, eqs. (67), (68)) from a
    :func:`work_distribution` whose bins are symmetric about 0.

    Only pairs of bins ``(w, -w)`` with ``w > 0`` where both sides are reached by at least
    ``min_replicas`` replicas are used: the delta-method error of a log rests on the
    replicas that contribute, and is poor with only a few.  ``tau`` must equal the
    distribution's (pass None to take it from ``dist``).
    """
    tau, gamma = _tau_gamma(dist, tau, gamma)
    mc = checks.integer("min_replicas", min_replicas, minimum=1)
    e = dist.edges
    scale = float(np.max(np.abs(e)))
    if not np.allclose(e, -e[::-1], rtol=0, atol=1e-9 * scale):
        raise ValueError("dist must have bins symmetric about w = 0 (use range=(-m, m))")
    nb = dist.centres.size
    pos = np.flatnonzero(dist.centres > 1e-9 * scale)
    neg = nb - 1 - pos
    n_rep = dist.contributing
    ok = (n_rep[pos] >= mc) & (n_rep[neg] >= mc)
    pos, neg = pos[ok], neg[ok]
    P = dist.replica_fractions.mean(axis=0)
    f = dist.replica_fractions
    tg = tau * gamma
    ratio = (np.log(P[pos]) - np.log(P[neg])) / tg
    influence = (f[:, pos] / P[pos] - f[:, neg] / P[neg]) / tg
    se = influence.std(axis=0, ddof=1) / np.sqrt(f.shape[0])
    return FluctuationRatio(w=dist.centres[pos], ratio=ratio, stderr=se,
                            counts_positive=dist.counts[pos], counts_negative=dist.counts[neg],
                            influence=influence, tau=tau, gamma=gamma)


@dataclass(frozen=True, eq=False)
class RateFunctionEstimate:
    """Empirical rate function ``-ln P_tau(w) / (tau gamma)`` shifted to zero at its minimum
    (paper, eq. (54)); ``shift`` is the unshifted value at the minimum.  At finite tau it
    still contains the O(1/tau) prefactor corrections, which vanish as tau grows."""

    w: np.ndarray
    rate: np.ndarray
    stderr: np.ndarray
    counts: np.ndarray
    shift: float
    tau: float
    gamma: float


def empirical_rate_function(dist: WorkDistribution, tau: float, gamma: float,
                            min_replicas: int = 10) -> RateFunctionEstimate:
    """``I_tau(w) = -ln P_tau(w) / (tau gamma)`` minus its minimum, on bins reached by at
    least ``min_replicas`` replicas.  Errors propagate ``ln P`` and the shift replica by replica
    (so the error at the minimum bin is 0 and the others include its uncertainty).  ``tau``
    must equal the distribution's (None takes it from ``dist``)."""
    tau, gamma = _tau_gamma(dist, tau, gamma)
    mc = checks.integer("min_replicas", min_replicas, minimum=1)
    keep = np.flatnonzero(dist.contributing >= mc)
    if keep.size == 0:
        raise ValueError(f"no bin is reached by >= min_replicas={mc} replicas")
    f = dist.replica_fractions[:, keep]
    P = f.mean(axis=0)
    tg = tau * gamma
    raw = -np.log(P / np.diff(dist.edges)[keep]) / tg  # density, not fraction: bins may differ
    j = int(np.argmin(raw))
    influence = -(f / P - (f[:, j] / P[j])[:, None]) / tg
    se = influence.std(axis=0, ddof=1) / np.sqrt(f.shape[0])
    return RateFunctionEstimate(w=dist.centres[keep], rate=raw - raw[j], stderr=se,
                                counts=dist.counts[keep], shift=float(raw[j]), tau=tau,
                                gamma=gamma)
