"""The theory-side standard error of a sample variance (analogue.estimators.variance_error):
the closed form for a Gaussian law, the spread of s^2 over Monte Carlo ensembles of a skewed
law, and the coverage it gives where the replica jackknife falls short."""
from __future__ import annotations

import math

import numpy as np
import pytest

from analogue.checks import ArgumentTypeError
from analogue.estimators.variance_error import sample_variance_se

# exponential law of rate 1: variance 1, fourth central moment 9 (skewness 2)
EXP_VAR, EXP_MU4 = 1.0, 9.0
N, ENSEMBLES, GROUPS = 50, 4000, 16


def test_gaussian_closed_form():
    """mu4 = 3 sigma^4: Var(s^2) = 2 sigma^4/(n - 1) (the chi-square law of (n-1) s^2/sigma^2)."""
    for sigma2, n in ((1.0, 2), (0.3, 10), (4.0, 1000)):
        assert sample_variance_se(sigma2, 3 * sigma2 ** 2, n) == pytest.approx(
            math.sqrt(2 * sigma2 ** 2 / (n - 1)), rel=1e-12)


@pytest.fixture(scope="module")
def ensembles():
    rng = np.random.default_rng(20261123)
    x = rng.exponential(1.0, (ENSEMBLES, N))
    s2 = x.var(axis=1, ddof=1)
    labels = np.arange(N) % GROUPS           # the report's delete-a-group jackknife
    reps = np.stack([x[:, labels != j].var(axis=1, ddof=1) for j in range(GROUPS)], axis=1)
    jk = np.sqrt((GROUPS - 1) / GROUPS * ((reps - reps.mean(1, keepdims=True)) ** 2).sum(1))
    return s2, jk


def test_matches_the_spread_of_s2_over_ensembles_of_a_skewed_law(ensembles):
    s2, _ = ensembles
    se = sample_variance_se(EXP_VAR, EXP_MU4, N)
    sd = s2.std(ddof=1)
    # standard error of a sample SD: sd sqrt((kurtosis - 1)/(4 M)), kurtosis of s2 measured
    z = (s2 - s2.mean()) / sd
    kurt = float(np.mean(z ** 4))
    assert abs(sd - se) < 4 * sd * math.sqrt((kurt - 1) / (4 * ENSEMBLES))
    assert s2.mean() == pytest.approx(EXP_VAR, abs=4 * sd / math.sqrt(ENSEMBLES))


def test_coverage_of_the_larger_se_where_the_jackknife_falls_short(ensembles):
    """|s^2 - sigma^2| < 3 SE: the jackknife alone misses far more often than a 3-SE band
    should (measured 90 %); the larger of it and the theory-side SE covers (measured 100 %)."""
    s2, jk = ensembles
    th = sample_variance_se(EXP_VAR, EXP_MU4, N)
    cover_jk = float(np.mean(np.abs(s2 - EXP_VAR) < 3 * jk))
    cover_max = float(np.mean(np.abs(s2 - EXP_VAR) < 3 * np.maximum(jk, th)))
    cover_th = float(np.mean(np.abs(s2 - EXP_VAR) < 3 * th))
    binom = math.sqrt(0.01 * 0.99 / ENSEMBLES)        # SE of a coverage near 99 %
    assert cover_max >= 0.99 - 3 * binom
    assert cover_th >= 0.98 - 3 * binom               # Chebyshev-free: a skewed s^2 law
    assert cover_max - cover_jk > 10 * binom          # the gap the report's change closes


@pytest.mark.parametrize("kw, exc, match", [
    ({"variance": 1.0, "mu4": 0.5, "n": 10}, ValueError, "mu4 must be >= variance"),
    ({"variance": -1.0, "mu4": 1.0, "n": 10}, ValueError, "variance"),
    ({"variance": 1.0, "mu4": 3.0, "n": 1}, ValueError, "n"),
    ({"variance": 1.0, "mu4": 3.0, "n": 2.5}, ArgumentTypeError, "n"),
])
def test_bad_arguments_are_refused(kw, exc, match):
    with pytest.raises(exc, match=match):
        sample_variance_se(**kw)
