"""Histogram densities: binomial bands for independent replicas (Wilson, Clopper-Pearson)."""
import numpy as np
import pytest
from scipy import stats

from analogue import Ensemble
from analogue.estimators import (clopper_pearson_interval, stationary_density,
                                 transition_density, wilson_interval)


def test_intervals_match_textbook_values():
    # Published 95 % intervals (e.g. Brown, Cai & DasGupta 2001; Newcombe 1998): 0/10 and 5/10.
    lo, hi = wilson_interval([0, 5], 10, 0.95)
    np.testing.assert_allclose(lo, [0.0, 0.2366], atol=1e-4)
    np.testing.assert_allclose(hi, [0.2775, 0.7634], atol=1e-4)
    lo, hi = clopper_pearson_interval([0, 5], 10, 0.95)
    np.testing.assert_allclose(lo, [0.0, 0.1871], atol=1e-4)
    np.testing.assert_allclose(hi, [0.3085, 0.8129], atol=1e-4)


def _iid_normal_ensemble(replicas, times, seed):
    rng = np.random.default_rng(seed)
    v = rng.standard_normal((replicas, times))
    return Ensemble(np.arange(times, dtype=float), v, np.zeros_like(v))


def _exact_coverage(p, n, interval, confidence):
    """P(p in interval(K, n)) for K ~ Binomial(n, p), summed exactly."""
    k = np.arange(n + 1)
    lo, hi = interval(k, n, confidence)
    pmf = stats.binom.pmf(k[None, :], n, np.asarray(p)[:, None])
    hit = (lo[None, :] <= np.asarray(p)[:, None]) & (np.asarray(p)[:, None] <= hi[None, :])
    return (pmf * hit).sum(axis=1)


@pytest.mark.parametrize("method,interval", [("wilson", wilson_interval),
                                             ("clopper-pearson", clopper_pearson_interval)])
def test_band_coverage_over_many_bins_is_nominal(method, interval):
    n, reps = 300, 200
    ens = _iid_normal_ensemble(n, reps, seed=11)
    edges = np.linspace(-2.5, 2.5, 21)
    p_true = np.diff(stats.norm.cdf(edges))
    hits = []
    for j in range(reps):
        d = transition_density(ens, float(j), bins=edges, method=method)
        truth = p_true / d.widths
        hits.append((d.lower <= truth) & (truth <= d.upper))
    hits = np.array(hits)
    expected = _exact_coverage(p_true, n, interval, 0.95)
    # the band's exact coverage is near nominal (Wilson) or above it (Clopper-Pearson) ...
    if method == "wilson":
        assert 0.935 < expected.mean() < 0.965
    else:
        assert np.all(expected >= 0.95)
    # ... and the observed coverage agrees with it within 4 sigma (bins ~ independent)
    se = np.sqrt(np.sum(expected * (1 - expected)) * reps) / hits.size
    assert abs(hits.mean() - expected.mean()) < 4 * se


def test_transition_density_recovers_iid_normal_within_its_errors():
    ens = _iid_normal_ensemble(20000, 3, seed=12)
    d = transition_density(ens, 1.2, bins=30, range=(-3, 3))
    assert d.time == 1.0 and d.n_samples == 20000 and d.n_effective == 20000
    np.testing.assert_array_equal(d.counts, np.histogram(ens.v[:, 1], bins=d.edges)[0])
    exact = np.diff(stats.norm.cdf(d.edges)) / d.widths
    assert np.max(np.abs(d.density - exact) / d.stderr) < 4
    # density normalises over ALL samples: its integral is the fraction inside the range
    inside = np.mean(np.abs(ens.v[:, 1]) <= 3)
    assert np.sum(d.density * d.widths) == pytest.approx(inside, rel=1e-12)
    assert np.all(d.lower <= d.density) and np.all(d.density <= d.upper)


def test_stationary_density_of_iid_samples_agrees_with_binomial():
    # for independent samples, the batch-means error matches the binomial one
    ens = _iid_normal_ensemble(200, 500, seed=13)
    d = stationary_density(ens, bins=np.linspace(-2, 2, 11))
    p = d.density * d.widths
    binom_se = np.sqrt(p * (1 - p) / d.n_samples) / d.widths
    ratio = np.sqrt(np.mean(d.stderr**2) / np.mean(binom_se**2))
    assert 0.9 < ratio < 1.1  # chi^2 with 199 dof per bin, averaged over 10 bins
    exact = np.diff(stats.norm.cdf(d.edges)) / d.widths
    assert np.max(np.abs(d.density - exact) / d.stderr) < 4
    assert d.n_effective == pytest.approx(d.n_samples, rel=0.15)


def test_density_bad_input():
    ens = _iid_normal_ensemble(50, 10, seed=14)
    with pytest.raises(ValueError, match=r"t must be in \[0.0, 9.0\]"):
        transition_density(ens, 12.0)
    with pytest.raises(ValueError, match=r"confidence must be in \(0, 1\)"):
        transition_density(ens, 1.0, confidence=1.5)
    with pytest.raises(ValueError, match="bins must be an integer >= 1"):
        transition_density(ens, 1.0, bins=0)
    with pytest.raises(ValueError, match="range must have low < high"):
        transition_density(ens, 1.0, range=(1.0, -1.0))
    with pytest.raises(ValueError, match="method must be"):
        transition_density(ens, 1.0, method="wald")
    with pytest.raises(ValueError, match="ensemble must be an analogue.Ensemble"):
        transition_density(ens.v, 1.0)
    with pytest.raises(ValueError, match="burn_in must leave"):
        stationary_density(ens, burn_in=100.0)
    one = Ensemble(ens.t, ens.v[:1], ens.x[:1])
    with pytest.raises(ValueError, match=">= 2 independent units"):
        stationary_density(one)
    assert stationary_density(one, batches_per_replica=2).units == 2
