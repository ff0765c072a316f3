"""The stationary rows' SE under the null (study.catalogue.stationary_null_se): the replica
jackknife rescaled to the theory's value, never below it."""
import math

import numpy as np
import pytest
from scipy.stats import norm, t as student_t

from analogue.study.catalogue import KINDS, STATIONARY, TRANSITION, stationary_null_se


def _kind(name, run=STATIONARY):
    return next(k for k in KINDS if k.name == name and k.run == run)


def test_probability_rescaled_by_p_one_minus_p_and_never_below_the_jackknife():
    k = _kind("P(v>0)")
    # the sample saw fewer negative excursions than the theory: its own SE is too small
    assert stationary_null_se(k, 0.999, 1e-4, 0.998) == pytest.approx(
        1e-4 * math.sqrt(0.998 * 0.002 / (0.999 * 0.001)))
    # a sample with more excursions than the theory keeps its (larger) jackknife SE
    assert stationary_null_se(k, 0.997, 1e-4, 0.998) == 1e-4
    # 0 or 1: left to the report's binomial floor
    assert stationary_null_se(k, 1.0, 0.0, 0.998) == 0.0


def test_variance_rescaled_by_sigma_squared_other_kinds_unchanged():
    assert stationary_null_se(_kind("var v"), 0.04, 1e-3, 0.05) == pytest.approx(1.25e-3)
    assert stationary_null_se(_kind("var v"), 0.05, 1e-3, 0.04) == 1e-3
    assert stationary_null_se(_kind("mean v"), 0.1, 1e-3, 0.5) == 1e-3
    # transition rows have their own theory-side SE (theory_se), not this one
    assert stationary_null_se(_kind("P(v<0)", TRANSITION), 0.01, 1e-3, 0.1) == 1e-3
    assert stationary_null_se(_kind("var v"), float("nan"), 1e-3, 0.05) == 1e-3


def test_rare_indicator_coverage_of_a_correlated_series():
    """Time averages of the indicator 1[x > c] over n replicas of a stationary Gaussian AR(1)
    series (p0 = P(x > 2.3) = 0.0107, correlation time ~ 19 steps): the plug-in jackknife
    interval |p - p0| < 3 se misses several times more often than a t-distribution with n - 1
    degrees of freedom allows, because samples with few excursions report small errors; the
    null-rescaled SE brings the miss rate to that level.  Fixed seed; the bounds are the
    t-distribution's miss rate and its binomial error over the ensembles."""
    rng = np.random.default_rng(20261123)
    ensembles, n, steps, phi, c = 2000, 16, 400, 0.9, 2.3
    p0 = float(norm.sf(c))
    x = rng.standard_normal((ensembles, n))
    count = np.zeros((ensembles, n))
    s = math.sqrt(1 - phi ** 2)
    for _ in range(steps):
        count += x > c
        x = phi * x + s * rng.standard_normal((ensembles, n))
    per_replica = count / steps
    p = per_replica.mean(axis=1)
    se = per_replica.std(axis=1, ddof=1) / math.sqrt(n)
    k = _kind("stick fraction")
    se_null = np.array([stationary_null_se(k, pi, si, p0) for pi, si in zip(p, se)])
    with np.errstate(divide="ignore"):
        miss_plugin = float(np.mean(np.abs(p - p0) > 3 * se))
        miss_null = float(np.mean(np.abs(p - p0) > 3 * se_null))
    t_miss = 2 * float(student_t.sf(3.0, n - 1))          # 0.0089 for n = 16
    binom = 3 * math.sqrt(t_miss / ensembles)
    assert miss_null <= t_miss + binom
    assert miss_plugin > t_miss + binom                      # the fault it fixes is real
