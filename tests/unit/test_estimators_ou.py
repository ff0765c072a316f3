"""Estimators on exact Ornstein-Uhlenbeck ensembles (Delta = 0), whose answers are known in
closed form: stationary N(a tau_m, tau_m/gamma) velocity, Gaussian work rate with
Var(integral_0^tau v) = 2 s^2 tau_m^2 (tau/tau_m - 1 + e^{-tau/tau_m}).

Paths come from the exact joint (v, x) update of the OU process (no discretisation error),
started in the stationary law, so every 'known answer' below holds exactly on the grid.
"""
import dataclasses
import math

import numpy as np
import pytest
from scipy import signal, stats

from analogue import Ensemble
from analogue.estimators import (empirical_rate_function, fluctuation_ratio,
                                 integrated_autocorrelation_time, stationary_density,
                                 stationary_observables, stationary_prehistory, transport,
                                 work_distribution,
                                 work_rate_samples)

TAU_M, GAMMA, A, MASS = 1.0, 2.0, 0.4, 1.0
F = MASS * A
MU = A * TAU_M                      # stationary mean velocity (Delta = 0)
S2 = TAU_M / GAMMA                  # stationary velocity variance
DT = 0.05


def exact_ou(replicas, n_t, seed, dt=DT, tau=TAU_M, gamma=GAMMA, mu=MU):
    """Exact OU paths (v, x) on a uniform grid, stationary start, x(0) = 0."""
    rng = np.random.default_rng(seed)
    E = math.exp(-dt / tau)
    sig2 = 2.0 / gamma
    s2 = sig2 * tau / 2
    var1 = s2 * (1 - E * E)
    var2 = sig2 * tau**2 * (dt - 2 * tau * (1 - E) + 0.5 * tau * (1 - E * E))
    cov = 0.5 * sig2 * tau**2 * (1 - E) ** 2
    L = np.linalg.cholesky(np.array([[var1, cov], [cov, var2]]))
    z = rng.standard_normal((2, replicas, n_t - 1))
    xi1 = L[0, 0] * z[0]
    xi2 = L[1, 0] * z[0] + L[1, 1] * z[1]
    drive = np.empty((replicas, n_t))
    drive[:, 0] = math.sqrt(s2) * rng.standard_normal(replicas)
    drive[:, 1:] = xi1
    y = signal.lfilter([1.0], [1.0, -E], drive, axis=1)  # y = v - mu, AR(1) exactly
    steps = mu * dt + y[:, :-1] * tau * (1 - E) + xi2
    x = np.zeros((replicas, n_t))
    x[:, 1:] = np.cumsum(steps, axis=1)
    t = dt * np.arange(n_t)
    return Ensemble(t, mu + y, x, {"source": "exact-ou", "seed": seed})


def var_integral(t, tau=TAU_M, s2=S2):
    """Var of integral_0^t v for the stationary OU velocity."""
    return 2 * s2 * tau**2 * (t / tau - 1 + np.exp(-t / tau))


def test_integrated_autocorrelation_time_of_ar1():
    # AR(1) with coefficient phi has rho(k) = phi^k, tau_int = (1 + phi)/(1 - phi) = 9.
    phi = 0.8
    rng = np.random.default_rng(1)
    drive = rng.standard_normal((100, 2000))
    drive[:, 0] /= math.sqrt(1 - phi**2)
    y = signal.lfilter([1.0], [1.0, -phi], drive, axis=1)
    ac = integrated_autocorrelation_time(y)
    assert ac.converged
    # Sokal's variance of the windowed estimator: var(tau)/tau^2 ~ 2 (2M + 1)/N.
    rel_se = math.sqrt(2 * (2 * ac.window + 1) / y.size)
    assert abs(ac.tau_int / 9.0 - 1) < 4 * rel_se
    iid = integrated_autocorrelation_time(rng.standard_normal(20000))
    assert abs(iid.tau_int - 1) < 4 * math.sqrt(2 * (2 * iid.window + 1) / 20000)


def test_stationary_observables_recover_ou_moments():
    ens = exact_ou(100, 2000, seed=2)
    obs = stationary_observables(ens, burn_in=0.0)
    truth = {"mean": MU, "variance": S2,
             "p_positive": stats.norm.cdf(MU / math.sqrt(S2))}
    for name, value in truth.items():
        est = getattr(obs, name)
        assert abs(est.value - value) < 4 * est.stderr, name
        # the tau_int error and the independent replica-spread error agree
        assert 0.7 < est.stderr / est.stderr_replicas < 1.4, name
    # mean's tau_int is that of the AR(1) with phi = exp(-dt/tau_m)
    phi = math.exp(-DT / TAU_M)
    assert obs.mean.tau_int == pytest.approx((1 + phi) / (1 - phi), rel=0.15)
    assert obs.mean.n_effective < obs.mean.n_samples / 10


def test_work_rate_samples_mean_and_variance():
    ens = exact_ou(200, 1200, seed=3)
    tau = 2.0
    w = work_rate_samples(ens, tau, F, burn_in=1.0, overlap=False)
    assert w.shape[0] == 200
    # back-to-back windows: window j spans samples [20 + 40 j, 20 + 40 (j + 1)]
    assert w.shape[1] == len(range(20, 1200 - 40, 40))
    np.testing.assert_allclose(w[:, 0], F * (ens.x[:, 60] - ens.x[:, 20]) / tau)
    per_rep_mean = w.mean(axis=1)
    se_mean = per_rep_mean.std(ddof=1) / math.sqrt(200)
    assert abs(per_rep_mean.mean() - F * MU) < 4 * se_mean
    var_exact = F**2 * var_integral(tau) / tau**2
    per_rep_var = ((w - F * MU) ** 2).mean(axis=1)
    se_var = per_rep_var.std(ddof=1) / math.sqrt(200)
    assert abs(per_rep_var.mean() - var_exact) < 4 * se_var
    wo = work_rate_samples(ens, tau, F, burn_in=1.0, overlap=True, stride=5)
    assert wo.shape[1] == len(range(20, 1200 - 40, 5))


def _gauss_bins(edges, mean, sd):
    return np.diff(stats.norm.cdf(edges, mean, sd))


@pytest.fixture(scope="module")
def long_ou():
    return exact_ou(200, 4000, seed=4)


@pytest.fixture(scope="module")
def work_dist(long_ou):
    return work_distribution(long_ou, 2.0, F, bins=41, overlap=True, stride=2)


def test_work_distribution_matches_exact_gaussian(work_dist):
    tau = 2.0
    sd = F * math.sqrt(var_integral(tau)) / tau
    exact = _gauss_bins(work_dist.edges, F * MU, sd) / work_dist.widths
    ok = work_dist.contributing >= 50   # replica-spread errors need many replicas per bin
    assert np.count_nonzero(ok) >= 20
    z = (work_dist.density[ok] - exact[ok]) / work_dist.stderr[ok]
    assert np.max(np.abs(z)) < 4
    assert abs(work_dist.mean - F * MU) < 4 * work_dist.mean_se
    # 95 % Student bands should cover most well-populated bins
    inside = (work_dist.lower[ok] <= exact[ok]) & (exact[ok] <= work_dist.upper[ok])
    assert inside.mean() > 0.8


def test_fluctuation_ratio_of_gaussian_work_is_linear(work_dist):
    tau = 2.0
    mean_w, var_w = F * MU, F**2 * var_integral(tau) / tau**2
    fr = fluctuation_ratio(work_dist, tau, GAMMA)
    assert fr.w.size >= 6 and np.all(fr.w > 0)
    # exact bin-level ratio from the Gaussian's bin probabilities
    p = _gauss_bins(work_dist.edges, mean_w, math.sqrt(var_w))
    nb = p.size
    idx = np.searchsorted(work_dist.centres, fr.w)
    exact = np.log(p[idx] / p[nb - 1 - idx]) / (tau * GAMMA)
    z = (fr.ratio - exact) / fr.stderr
    assert np.max(np.abs(z)) < 4
    # pointwise Gaussian fluctuation relation: ln P(w)/P(-w) = 2 <w> w / Var(w)
    slope_true = 2 * mean_w / var_w / (tau * GAMMA)
    fit = fr.fit_line()
    fit_exact_bins = dataclasses.replace(fr, ratio=exact).fit_line()
    assert fit_exact_bins.slope == pytest.approx(slope_true, rel=0.02)   # binning is harmless
    assert abs(fit_exact_bins.intercept) < 0.02 * slope_true * fr.w.max()
    assert abs(fit.slope - fit_exact_bins.slope) < 4 * fit.slope_se
    assert abs(fit.intercept - fit_exact_bins.intercept) < 4 * fit.intercept_se
    assert fit.slope_se < 0.2 * slope_true  # the test has power


def test_empirical_rate_function_of_gaussian_work(work_dist):
    tau = 2.0
    mean_w, var_w = F * MU, F**2 * var_integral(tau) / tau**2
    rf = empirical_rate_function(work_dist, tau, GAMMA, min_replicas=50)
    assert rf.rate.min() == 0.0
    p = _gauss_bins(work_dist.edges, mean_w, math.sqrt(var_w)) / work_dist.widths
    idx = np.searchsorted(work_dist.centres, rf.w)
    raw = -np.log(p[idx]) / (tau * GAMMA)
    j = int(np.argmin(rf.rate))
    exact = raw - raw[j]
    ok = rf.stderr > 0
    z = (rf.rate[ok] - exact[ok]) / rf.stderr[ok]
    assert np.max(np.abs(z)) < 4
    # and the exact bin values follow the parabola (w - <w>)^2 / (2 Var tau gamma)
    parab = (rf.w - mean_w) ** 2 / (2 * var_w * tau * GAMMA)
    assert np.allclose(exact - exact.min(), parab - parab[np.argmin(exact)],
                       atol=0.05 * parab.max())


def test_transport_drift_and_diffusion(long_ou):
    tr = transport(long_ou, burn_in=0.0, fit_from=50.0)
    assert abs(tr.drift - MU) < 4 * tr.drift_se
    # the same OLS on the exact variance curve (offset absorbs the transient)
    sel = tr.t >= 50.0 - 1e-9
    ts = tr.t[sel]
    expected = 0.5 * np.polyfit(ts, var_integral(ts), 1)[0]
    assert expected == pytest.approx(S2 * TAU_M, rel=1e-6)  # D_x = tau_m^2 / gamma
    assert abs(tr.diffusion - expected) < 4 * tr.diffusion_se
    assert tr.fit_window[0] == pytest.approx(50.0)
    np.testing.assert_allclose(tr.var_x[1:], long_ou.x[:, 1:].var(axis=0, ddof=1), rtol=1e-10)


def _spread_ratio(estimates, stated):
    """sqrt(mean stated^2) / empirical std across independent seeds, pooled over columns."""
    return math.sqrt(np.mean(stated**2) / np.mean(np.var(estimates, axis=0, ddof=1)))


def test_overlapping_window_errors_are_honest():
    seeds, reps, n_t, tau = 60, 30, 800, 2.0
    big = exact_ou(seeds * reps, n_t, seed=5)
    dens, se, means, mean_se, naive = [], [], [], [], []
    edges = np.linspace(-0.3, 0.6, 19)
    for k in range(seeds):
        sl = slice(k * reps, (k + 1) * reps)
        ens = Ensemble(big.t, big.v[sl], big.x[sl])
        d = work_distribution(ens, tau, F, bins=edges, overlap=True)
        dens.append(d.density)
        se.append(d.stderr)
        means.append(d.mean)
        mean_se.append(d.mean_se)
        n = d.n_replicas * d.windows_per_replica
        p = d.density * d.widths
        naive.append(np.sqrt(p * (1 - p) / n) / d.widths)
    dens, se, naive = map(np.array, (dens, se, naive))
    ok = dens.mean(axis=0) * np.diff(edges) > 0.02
    assert 0.7 < _spread_ratio(dens[:, ok], se[:, ok]) < 1.4
    assert 0.7 < _spread_ratio(np.array(means)[:, None], np.array(mean_se)) < 1.4
    # binomial errors that pretend the overlapping windows are independent are far too small
    assert _spread_ratio(dens[:, ok], naive[:, ok]) < 0.4


def test_stationary_density_errors_are_honest_for_correlated_samples():
    seeds, reps, n_t = 50, 20, 1000
    big = exact_ou(seeds * reps, n_t, seed=6)
    edges = np.linspace(MU - 3 * math.sqrt(S2), MU + 3 * math.sqrt(S2), 25)
    exact = _gauss_bins(edges, MU, math.sqrt(S2)) / np.diff(edges)
    dens, se, naive = [], [], []
    for k in range(seeds):
        sl = slice(k * reps, (k + 1) * reps)
        d = stationary_density(Ensemble(big.t, big.v[sl], big.x[sl]), bins=edges)
        dens.append(d.density)
        se.append(d.stderr)
        p = d.density * d.widths
        naive.append(np.sqrt(p * (1 - p) / d.n_samples) / d.widths)
        assert d.n_effective < d.n_samples / 2  # correlation is recognised
    dens, se, naive = np.array(dens), np.array(se), np.array(naive)
    assert 0.7 < _spread_ratio(dens, se) < 1.4
    # binomial errors on the pooled correlated samples would be far too small
    assert _spread_ratio(dens, naive) < 0.6
    pooled = dens.mean(axis=0)
    pooled_se = np.sqrt((se**2).mean(axis=0) / seeds)
    assert np.max(np.abs(pooled - exact) / pooled_se) < 4
    # batch means within replicas give a consistent error when batches >> correlation time
    one = Ensemble(big.t, big.v[:4], big.x[:4])
    bm = stationary_density(one, bins=edges, batches_per_replica=10)
    assert bm.units == 40


def test_work_and_transport_reject_bad_input(long_ou):
    with pytest.raises(ValueError, match="tau must be a positive multiple"):
        work_rate_samples(long_ou, 0.123, F)
    with pytest.raises(ValueError, match="tau must be > 0"):
        work_rate_samples(long_ou, -1.0, F)
    with pytest.raises(ValueError, match="force must be finite"):
        work_rate_samples(long_ou, 1.0, float("nan"))
    with pytest.raises(ValueError, match="burn_in must be >= 0"):
        work_rate_samples(long_ou, 1.0, F, burn_in=-1)
    with pytest.raises(ValueError, match="tau=.* must be shorter"):
        work_rate_samples(long_ou, 199.0, F, burn_in=100.0)
    with pytest.raises(ValueError, match="stride must be an integer >= 1"):
        work_rate_samples(long_ou, 1.0, F, stride=0)
    one = Ensemble(long_ou.t, long_ou.v[:1], long_ou.x[:1])
    with pytest.raises(ValueError, match=">= 2 independent replicas"):
        work_distribution(one, 1.0, F)
    with pytest.raises(ValueError, match=">= 2 independent replicas"):
        transport(one)
    asym = work_distribution(long_ou, 2.0, F, bins=10, range=(-0.2, 0.5))
    with pytest.raises(ValueError, match="symmetric about w = 0"):
        fluctuation_ratio(asym, 2.0, GAMMA)
    with pytest.raises(ValueError, match="gamma must be > 0"):
        fluctuation_ratio(asym, 2.0, 0.0)
    with pytest.raises(ValueError, match="tau must match"):
        empirical_rate_function(asym, 3.0, GAMMA)
    with pytest.raises(ValueError, match="fit_from must leave"):
        transport(long_ou, fit_from=1e6)


def test_autocorrelation_blocking_does_not_change_the_result(monkeypatch):
    import analogue.estimators.stationary as st
    y = exact_ou(37, 500, seed=7).v
    full = st.integrated_autocorrelation_time(y)
    monkeypatch.setattr(st, "_FFT_BLOCK", 3 * 1024)  # 3 replicas per FFT batch
    blocked = st.integrated_autocorrelation_time(y)
    assert blocked.window == full.window
    assert blocked.tau_int == pytest.approx(full.tau_int, rel=1e-12)
    # a direct lag-by-lag sum to the same window agrees with the FFT autocovariance route
    yc = y - y.mean()
    rho = [np.sum(yc[:, : yc.shape[1] - k] * yc[:, k:]) / np.sum(yc * yc)
           for k in range(1, full.window + 1)]
    assert full.tau_int == pytest.approx(1 + 2 * np.sum(rho), rel=1e-10)


def _truncated_mean(centre, half):
    """E[v | |v - centre| < half] for the stationary N(MU, S2)."""
    s = math.sqrt(S2)
    a, b = (centre - half - MU) / s, (centre + half - MU) / s
    return MU + s * (stats.norm.pdf(a) - stats.norm.pdf(b)) / (stats.norm.cdf(b) - stats.norm.cdf(a))


def test_stationary_prehistory_is_the_gaussian_conditional_mean(long_ou):
    # OU is Gaussian and reversible: E[v(t - s) | v(t)] = MU + e^{-s/tau_m} (v(t) - MU), so
    # conditioning on v(t) in the window gives MU + e^{-s/tau_m} (E[v | window] - MU) exactly.
    target, half = MU + 2 * math.sqrt(S2), 0.1
    ph = stationary_prehistory(long_ou, target, half, lookback=3.0, entries_only=False)
    assert ph.t[0] == pytest.approx(-3.0) and ph.t[-1] == 0.0 and ph.t_target == 0.0
    assert ph.count > 5000
    expected = MU + np.exp(ph.t / TAU_M) * (_truncated_mean(target, half) - MU)
    z = (ph.mean - expected) / ph.mean_se
    assert np.max(np.abs(z)) < 4.5   # 61 correlated lags
    assert np.all(np.abs(long_ou.v[ph.indices, np.searchsorted(long_ou.t, ph.arrival_times)]
                         - target) < half)


@pytest.mark.slow  # > 5 s (make test-fast skips it)
def test_stationary_prehistory_entries_and_honest_errors():
    seeds, reps, n_t = 60, 20, 2000
    big = exact_ou(seeds * reps, n_t, seed=8)
    target, half = MU + 1.5 * math.sqrt(S2), 0.1
    means, ses = [], []
    for k in range(seeds):
        sl = slice(k * reps, (k + 1) * reps)
        ens = Ensemble(big.t, big.v[sl], big.x[sl])
        ph = stationary_prehistory(ens, target, half, lookback=2.0, burn_in=1.0)
        means.append(ph.mean[::10])
        ses.append(ph.mean_se[::10])
    ratio = _spread_ratio(np.array(means), np.array(ses))
    assert 0.7 < ratio < 1.4
    # entries: in the window now, outside one sample before, counted by hand
    inside = np.abs(ens.v - target) < half
    entries = inside[:, 1:] & ~inside[:, :-1]
    entries[:, : 20 + 40 - 1] = False   # segment must start after the burn-in (index 20)
    assert ph.count == np.count_nonzero(entries)
    cols = np.searchsorted(ens.t, ph.arrival_times)
    assert np.all(inside[ph.indices, cols]) and not np.any(inside[ph.indices, cols - 1])
    with pytest.raises(ValueError, match="lookback must be > 0"):
        stationary_prehistory(ens, target, half, lookback=0.0)
    with pytest.raises(ValueError, match="no path reaches"):
        stationary_prehistory(ens, 50.0, half, lookback=1.0)
