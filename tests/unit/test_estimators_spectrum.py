"""Welch spectrum of an ensemble (estimators.spectrum, issue 23 item 1) on Monte Carlo paths
against the exact theory: the estimate against the exact expectation of the estimator
(aliasing and leakage from the exact autocorrelation) within replica standard errors, the
chi-square bands' coverage, and the noise hold's sinc^2 factor at Delta = 0."""
import math

import numpy as np
import pytest

from analogue import Ensemble, Model
from analogue.estimators import spectrum as esp
from analogue.montecarlo import simulate_sde, simulate_sde_held_pair
from analogue.theory import exact
from analogue.theory import spectrum as tsp

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)


@pytest.fixture(scope="module")
def stick_estimate():
    ens = simulate_sde(STICK, v0="stationary", t_end=100.0, replicas=64, seed=1, sample_dt=0.05)
    return esp.velocity_spectrum(ens, nperseg=128)


def test_estimate_matches_the_exact_expectation(stick_estimate):
    """65 frequencies, 64 replicas x 30 segments: every |z| < 4 (z from the replica
    standard error; measured max 2.5), z^2 averages to 1 within its chi-square spread, and
    the 95 % chi-square bands cover the expectation at >= 85 % of the frequencies (95 %)."""
    est = stick_estimate
    c = exact.autocorrelation(STICK, np.arange(est.nperseg) * est.sample_dt)
    expected = esp.welch_expectation(c, est.sample_dt)
    z = (est.value - expected) / est.stderr
    assert np.max(np.abs(z)) < 4.0
    assert np.mean(z**2) < 1.0 + 4.0 * math.sqrt(2.0 / z.size)
    covered = (expected >= est.lower) & (expected <= est.upper)
    assert covered.mean() >= 0.85
    # the expectation differs from S(omega) itself (leakage at low, aliasing at high
    # frequencies): here by -2 % at omega = 0 and +8 % at omega = 20 -- larger than the
    # standard errors (3 %), so a comparison must use the expectation, not S
    s = tsp.velocity_spectrum(STICK, est.omega)
    assert expected[0] / s[0] - 1 == pytest.approx(-0.021, abs=0.003)
    assert s[0] == pytest.approx(2.0 * exact.stationary_moments(STICK).diffusion, rel=1e-6)


def test_expectation_identities():
    """White samples: flat dt sigma^2.  OU samples with a long window: the DTFT of the
    sampled exponential, dt Var (1 - q^2)/(1 - 2 q cos(omega dt) + q^2), q = e^{-dt/tau}."""
    flat = esp.welch_expectation(np.r_[2.0, np.zeros(63)], 0.1)
    np.testing.assert_allclose(flat, 0.2, rtol=1e-12)
    tau, var, dt, n = 1.0, 0.1, 0.05, 2048
    c = var * np.exp(-np.arange(n) * dt / tau)
    got = esp.welch_expectation(c, dt)
    om = esp.welch_frequencies(n, dt)
    q = math.exp(-dt / tau)
    ref = dt * var * (1 - q * q) / (1 - 2 * q * np.cos(om * dt) + q * q)
    np.testing.assert_allclose(got[5:], ref[5:], rtol=2e-3)   # leakage only near omega = 0


def test_hold_factor_at_delta_zero():
    """Ornstein-Uhlenbeck driven by held noise (T = 0.2) and by the white noise it is the
    mean of (common increments): the ratio of the two spectra is sinc^2(omega T/2) within the
    standard error of per-replica differences, for 0 < omega < 12 (z measured within 2.2)."""
    m = Model(1.0, 0.0, 0.2, 10.0)
    reps, dt, t_end, hold = 32, 0.002, 100.0, 100
    noise = np.random.default_rng(3).standard_normal((reps, int(round(t_end / dt))))
    held, white = simulate_sde_held_pair(m, v0=0.2, t_end=t_end, replicas=reps, noise=noise,
                                         noise_hold=hold, dt=dt, sample_dt=0.01)
    eh = esp.velocity_spectrum(held, burn_in=5.0, nperseg=1024)
    ew = esp.velocity_spectrum(white, burn_in=5.0, nperseg=1024)
    sel = (eh.omega > 0) & (eh.omega < 12.0)
    h, w = eh.per_replica[:, sel], ew.per_replica[:, sel]
    ratio = h.mean(axis=0) / w.mean(axis=0)
    se = ((h - ratio * w) / w.mean(axis=0)).std(axis=0, ddof=1) / math.sqrt(reps)
    factor = tsp.noise_hold_factor(eh.omega[sel], hold * dt)
    assert np.max(np.abs((ratio - factor) / se)) < 4.0
    assert factor[-1] < 0.65  # the factor is far from 1 over the band tested
    np.testing.assert_allclose(tsp.noise_hold_factor([0.0, 1.0], 0.3, "linear"),
                               [1.0, (math.sin(0.15) / 0.15) ** 4], rtol=1e-14)


def test_degrees_of_freedom():
    """One segment: 2 (1 at omega = 0); Hann at 50 % overlap: ~1.89 per segment."""
    assert esp._dof(64, 32, 1) == pytest.approx(2.0)
    assert esp._dof(256, 128, 200) / 200 == pytest.approx(2.0 / (1 + 2 * 0.0278), rel=0.01)


def test_bad_input():
    t = np.arange(100) * 0.1
    ens = Ensemble(t, np.zeros((2, 100)), np.zeros((2, 100)))
    with pytest.raises(ValueError, match="burn_in"):
        esp.velocity_spectrum(ens, nperseg=128)
    with pytest.raises(ValueError, match="confidence"):
        esp.velocity_spectrum(ens, nperseg=32, confidence=1.0)
    with pytest.raises(ValueError, match="autocorrelation"):
        esp.welch_expectation([1.0, 0.5], 0.1)
    with pytest.raises(ValueError, match="kind"):
        tsp.noise_hold_factor([1.0], 0.1, "cubic")


def test_pure_shot_noise_member_matches_its_exact_expectation():
    """A family member without Gaussian noise (stick regime, one-sided kicks; exact
    event-driven Monte Carlo): the Welch estimate against the expectation from the
    Kolmogorov-Feller autocorrelation, max |z| < 4.5 over 65 frequencies (measured 3.6),
    and the theory's S(0) = 2 D_x lies above the low-frequency expectation by the leakage."""
    from analogue import ShotNoise
    m = Model(1.0, 0.7, 0.2, math.inf, shot=ShotNoise(2.0, 0.3))
    ens = simulate_sde(m, v0="stationary", t_end=100.0, replicas=64, seed=2, sample_dt=0.05)
    est = esp.velocity_spectrum(ens, nperseg=128)
    expected = esp.welch_expectation(exact.autocorrelation(m, np.arange(128) * 0.05), 0.05)
    z = (est.value - expected) / est.stderr
    assert np.max(np.abs(z)) < 4.5
    assert np.mean(z**2) < 1.0 + 4.0 * math.sqrt(2.0 / z.size)
    assert tsp.velocity_spectrum(m, [0.0])[0] > expected[0]
