"""Independent cross-check: Monte Carlo (simulate_sde) vs the exact finite-noise theory on
parameter sets nobody tuned for (a < 0, a > Delta, a < Delta, mass != 1, a = 0).

Each comparison allows 4 standard errors of the Monte Carlo estimate plus the measured
time-step bias: the same Wiener path is integrated with dt and with 2 dt (common random
numbers, ``xi_2dt = (xi_1 + xi_2)/sqrt 2``); the bias is ~linear in dt, so the change from dt
to 2 dt bounds the remaining bias at dt.  Fixed seeds.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from analogue import Model
from analogue.montecarlo import default_dt, simulate_sde
from analogue.theory import exact

Z = 4.0

CASES = {
    "slip_neg_heavy": dict(tau_m=0.3, delta=0.2, a=-1.1, gamma=5.0, mass=2.5),
    "stick_pos": dict(tau_m=2.5, delta=1.5, a=0.4, gamma=3.0),
    "zero_force": dict(tau_m=1.0, delta=0.6, a=0.0, gamma=4.0),
}


def _pair(model, v0, t_end, replicas, seed, sample_dt):
    """Ensembles at dt and 2 dt driven by the same Wiener increments."""
    dt = default_dt(model) * 2.0
    n2 = int(round(sample_dt / (2 * dt)))
    dt = sample_dt / (2 * n2)                  # fine dt divides sample_dt, 2 dt too
    n_fine = int(round(t_end / dt))
    rng = np.random.default_rng(seed)
    xi = rng.standard_normal((replicas, n_fine))
    coarse = (xi[:, 0::2] + xi[:, 1::2]) / math.sqrt(2.0)
    fine = simulate_sde(model, v0=v0, t_end=t_end, replicas=replicas, dt=dt,
                        sample_dt=sample_dt, noise=xi)
    crude = simulate_sde(model, v0=v0, t_end=t_end, replicas=replicas, dt=2 * dt,
                         sample_dt=sample_dt, noise=coarse)
    return fine, crude


def _density_moments(model, t, v0):
    """Mean and variance of the exact propagator by quadrature on a fine v grid."""
    c = model.attractor
    r = 12.0 * model.velocity_scale
    lo, hi = min(v0, c, 0.0) - r, max(v0, c, 0.0) + r
    v = np.linspace(lo, hi, 6001)
    f = exact.propagator(model, v, t, v0)
    norm = integrate.simpson(f, x=v)
    mean = integrate.simpson(v * f, x=v) / norm
    var = integrate.simpson((v - mean[..., None]) ** 2 * f, x=v) / norm
    return norm, mean, var


def _var_se(x):
    n = x.size
    m2 = np.var(x)
    m4 = np.mean((x - x.mean()) ** 4)
    return math.sqrt(max(m4 - m2 * m2, 0.0) / n)


@pytest.mark.slow
@pytest.mark.parametrize("name,v0", [("slip_neg_heavy", 0.4), ("stick_pos", -1.0),
                                     ("zero_force", 0.0)])
def test_propagator_moments_match_monte_carlo(name, v0):
    model = Model(**CASES[name])
    t_end = 1.5 * model.tau_m
    fine, crude = _pair(model, v0, t_end, replicas=6000, seed=11, sample_dt=t_end / 3)
    times = fine.t[1:]
    norm, mean, var = _density_moments(model, times, v0)
    assert np.allclose(norm, 1.0, atol=2e-3)
    for j, t in enumerate(times, start=1):
        x, y = fine.v[:, j], crude.v[:, j]
        se_m = x.std(ddof=1) / math.sqrt(x.size)
        bias_m = abs(x.mean() - y.mean())
        assert abs(x.mean() - mean[j - 1]) < Z * se_m + bias_m, (t, x.mean(), mean[j - 1], se_m)
        bias_v = abs(x.var() - y.var())
        assert abs(x.var() - var[j - 1]) < Z * _var_se(x) + bias_v, (t, x.var(), var[j - 1])


@pytest.mark.slow
@pytest.mark.parametrize("name", ["slip_neg_heavy", "stick_pos"])
def test_work_variance_and_mean_match_autocorrelation(name):
    """Stationary start: E W = F <v> tau and Var W = 2 F^2 int_0^tau (tau - s) C(s) ds."""
    model = Model(**CASES[name])
    tau = model.tau_m
    fine, crude = _pair(model, "stationary", tau, replicas=6000, seed=23, sample_dt=tau)
    F = model.force
    W, Wc = F * fine.x[:, -1], F * crude.x[:, -1]
    mom = exact.stationary_moments(model)
    s = np.linspace(0.0, tau, 401)
    C = exact.autocorrelation(model, s)
    var_w = 2.0 * F * F * integrate.simpson((tau - s) * C, x=s)
    mean_w = F * mom.mean * tau
    se_m = W.std(ddof=1) / math.sqrt(W.size)
    assert abs(W.mean() - mean_w) < Z * se_m + abs(W.mean() - Wc.mean())
    assert abs(W.var() - var_w) < Z * _var_se(W) + abs(W.var() - Wc.var()), (W.var(), var_w)
    # stationary law itself at the end of the run
    v = fine.v[:, -1]
    assert abs(v.mean() - mom.mean) < Z * v.std() / math.sqrt(v.size) + abs(v.mean() - crude.v[:, -1].mean())
    assert abs(v.var() - mom.variance) < Z * _var_se(v) + abs(v.var() - crude.v[:, -1].var())


@pytest.mark.slow
@pytest.mark.parametrize("name", ["slip_neg_heavy"])
def test_work_density_matches_histogram(name):
    """exact.work_pdf (density of w = W/tau) vs a histogram of simulated work rates: each bin
    probability within 4 binomial SE (+ dt bias from the 2 dt run)."""
    model = Model(**CASES[name])
    tau = model.tau_m
    fine, crude = _pair(model, "stationary", tau, replicas=6000, seed=37, sample_dt=tau)
    w, wc = model.force * fine.x[:, -1] / tau, model.force * crude.x[:, -1] / tau
    lo, hi = np.quantile(w, [0.03, 0.97])
    edges = np.linspace(lo, hi, 6)
    n = w.size
    counts = np.histogram(w, edges)[0]
    counts_c = np.histogram(wc, edges)[0]
    # bin probabilities from the exact density (Gauss-Legendre, 3 nodes per bin; the density
    # is smooth on the scale of a bin here).  Default modes (see the stick-regime test below
    # for why fewer modes are not safe).
    xg, wg = np.polynomial.legendre.leggauss(3)
    mids, halfs = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.diff(edges)
    nodes = (mids[:, None] + halfs[:, None] * xg).ravel()
    dens = exact.work_pdf(model, nodes, tau).reshape(mids.size, xg.size)
    assert np.all(dens >= 0)
    prob = (dens * wg).sum(axis=1) * halfs
    p_hat = counts / n
    se = np.sqrt(prob * (1 - prob) / n)
    bias = np.abs(counts - counts_c) / n
    assert np.all(np.abs(p_hat - prob) < Z * se + bias), (p_hat, prob, se)


@pytest.mark.slow
def test_work_pdf_stick_regime_converged_in_modes():
    """QA finding: in the stick regime (tau_m = 2.5, Delta = 1.5, a = 0.4, gamma = 3, tau = 2.5)
    work_pdf with modes=32 is silently wrong at w < 0 (0.085 vs 1.28 with the default 48 at
    w = -0.047, the 3% quantile of a 6000-replica Monte Carlo, whose box estimate there is
    1.48 +- 0.08).  A density that depends on the truncation by a factor 15 is not converged;
    the function should either converge (the two agree within 5%) or refuse/warn.  Until then
    the 2-bin histogram check for this case is left out (it costs ~100 s at 48 modes)."""
    model = Model(**CASES["stick_pos"])
    w = np.array([-0.047, -0.019])
    p32 = exact.work_pdf(model, w, model.tau_m, modes=32)
    p48 = exact.work_pdf(model, w, model.tau_m)
    assert np.allclose(p32, p48, rtol=0.05), (p32, p48)
