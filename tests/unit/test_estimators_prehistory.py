"""Prehistory: a synthetic ensemble built around a known path must give that path back."""
import numpy as np
import pytest
from scipy import stats

from analogue import Ensemble
from analogue.estimators import prehistory

DT = 0.01
T = np.arange(0, 2.0 + DT / 2, DT)


def _path(t):
    return 1.5 * np.sin(1.2 * t) * np.exp(-0.3 * t)


def _ensemble(seed, n_in=120, n_out=280, noise=0.05):
    rng = np.random.default_rng(seed)
    inside = _path(T)[None, :] + noise * rng.standard_normal((n_in, T.size))
    outside = -1.0 + noise * rng.standard_normal((n_out, T.size))
    v = np.vstack([inside, outside])
    order = rng.permutation(v.shape[0])
    v = v[order]
    x = np.concatenate([np.zeros((v.shape[0], 1)), np.cumsum(v[:, :-1], axis=1) * DT], axis=1)
    return Ensemble(T, v, x), np.sort(np.flatnonzero(order < n_in)), noise


def test_prehistory_recovers_the_path_it_was_built_around():
    ens, members, noise = _ensemble(31)
    target = float(_path(T[-1]))
    ph = prehistory(ens, v_target=target, t_target=2.0, window=0.5)  # 10 noise sd: all members
    assert ph.count == members.size == 120
    np.testing.assert_array_equal(ph.indices, members)
    assert ph.t_target == pytest.approx(2.0)
    assert ph.t.size == T.size and ph.lag[-1] == 0.0
    # mean path within its own errors at every time (Bonferroni over 201 times: 4.5 sigma)
    z = (ph.mean - _path(T)) / ph.mean_se
    assert np.max(np.abs(z)) < 4.5
    # the 10-90 % band of N(path, noise^2) is path +- 1.2816 noise
    half = stats.norm.ppf(0.9) * noise
    assert np.mean(ph.upper - _path(T)) == pytest.approx(half, rel=0.05)
    assert np.mean(_path(T) - ph.lower) == pytest.approx(half, rel=0.05)
    # each time column of the 2-D histogram is a density in v, centred on the path
    colmass = (ph.hist * np.diff(ph.hist_v_edges)).sum(axis=1)
    np.testing.assert_allclose(colmass, 1.0)
    vc = 0.5 * (ph.hist_v_edges[1:] + ph.hist_v_edges[:-1])
    col_mean = (ph.hist * np.diff(ph.hist_v_edges) * vc).sum(axis=1)
    assert np.max(np.abs(col_mean - _path(T))) < 2 * np.diff(ph.hist_v_edges)[0]


def test_prehistory_window_lookback_and_coarse_time_bins():
    ens, members, noise = _ensemble(32)
    target = float(_path(T[-1]))
    narrow = prehistory(ens, v_target=target, t_target=2.0, window=noise)
    # about P(|Z| < 1) of the members pass a +-1 sd window
    p = stats.norm.cdf(1) - stats.norm.cdf(-1)
    assert abs(narrow.count - p * 120) < 4 * np.sqrt(120 * p * (1 - p))
    assert set(narrow.indices) <= set(members)
    ph = prehistory(ens, target, 2.0, 0.5, lookback=0.5, time_bins=5, v_range=(-1, 2),
                    v_bins=30, quantiles=(0.25, 0.75))
    assert ph.t[0] == pytest.approx(1.5) and ph.t.size == 51
    assert ph.hist.shape == (5, 30)
    np.testing.assert_allclose((ph.hist * np.diff(ph.hist_v_edges)).sum(axis=1), 1.0)
    half = stats.norm.ppf(0.75) * noise
    assert np.mean(ph.upper - ph.lower) == pytest.approx(2 * half, rel=0.1)


def test_prehistory_bad_input():
    ens, _, _ = _ensemble(33, n_in=5, n_out=5)
    with pytest.raises(ValueError, match="window must be > 0"):
        prehistory(ens, 0.0, 1.0, 0.0)
    with pytest.raises(ValueError, match="t_target must be in"):
        prehistory(ens, 0.0, 5.0, 0.1)
    with pytest.raises(ValueError, match="no trajectory"):
        prehistory(ens, 10.0, 1.0, 0.1)
    with pytest.raises(ValueError, match="quantiles must be a pair"):
        prehistory(ens, -1.0, 1.0, 0.5, quantiles=(0.9, 0.1))
