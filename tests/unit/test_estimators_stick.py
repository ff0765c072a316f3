"""Stick statistics: exact stationary stick fraction, and estimators on samples with known
answers (iid samples from p_s drawn by rejection, hand-made episode patterns)."""
import math

import numpy as np
import pytest
from scipy import integrate

from analogue import Ensemble, Model
from analogue.estimators import stick_fraction_theory, stick_statistics

MODELS = [Model(tau_m=1.0, delta=0.7, a=0.3, gamma=10.0),   # stick regime
          Model(tau_m=1.0, delta=0.7, a=1.2, gamma=10.0),   # slip regime
          Model(tau_m=2.0, delta=1.0, a=-0.4, gamma=3.0),
          Model(tau_m=1.0, delta=0.0, a=0.5, gamma=2.0)]    # OU: Delta = 0


def _sample_stationary(model, size, rng):
    """Exact iid draws from p_s ~ exp(-gamma U) (sgn law) by rejection: propose from
    N(a tau_m, tau_m/gamma) and accept with probability exp(-gamma Delta |v|) <= 1."""
    out = np.empty(0)
    while out.size < size:
        v = rng.normal(model.a * model.tau_m, math.sqrt(model.tau_m / model.gamma), 4 * size)
        keep = rng.random(v.size) < np.exp(-model.gamma * model.delta * np.abs(v))
        out = np.concatenate([out, v[keep]])
    return out[:size]


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("threshold", [0.05, 0.3, 2.0])
def test_stick_fraction_theory_equals_integral_of_stationary_pdf(model, threshold):
    val, _ = integrate.quad(model.stationary_pdf, -threshold, threshold, points=[0.0],
                            epsabs=0, epsrel=1e-12, limit=200)
    assert stick_fraction_theory(model, threshold) == pytest.approx(val, rel=1e-8)


def test_stick_fraction_theory_limits_and_smooth_law():
    m = MODELS[0]
    assert stick_fraction_theory(m, math.inf) == 1.0
    assert stick_fraction_theory(m, 50.0) == pytest.approx(1.0, abs=1e-12)
    # small threshold: P ~ 2 th p_s(0)
    th = 1e-6
    assert stick_fraction_theory(m, th) == pytest.approx(2 * th * float(m.stationary_pdf(0.0)), rel=1e-4)
    # a smooth law much narrower than the threshold barely changes the fraction
    smooth = m.replace(epsilon=1e-4)
    assert stick_fraction_theory(smooth, 0.3) == pytest.approx(stick_fraction_theory(m, 0.3), rel=1e-3)
    with pytest.raises(ValueError, match="threshold must be > 0"):
        stick_fraction_theory(m, 0.0)
    with pytest.raises(ValueError, match="model must be an analogue.Model"):
        stick_fraction_theory({"a": 1}, 0.1)


def test_stick_statistics_of_iid_stationary_samples():
    model = MODELS[0]
    rng = np.random.default_rng(21)
    R, n, dt, th = 50, 2000, 0.01, 0.1
    v = _sample_stationary(model, R * n, rng).reshape(R, n)
    ens = Ensemble(dt * np.arange(n), v, np.cumsum(v, axis=1) * dt)
    st = stick_statistics(ens, th)
    p = stick_fraction_theory(model, th)
    assert abs(st.fraction.value - p) < 4 * st.fraction.stderr
    # iid: tau_int ~ 1 and the error is the binomial one
    assert st.fraction.stderr == pytest.approx(math.sqrt(p * (1 - p) / (R * n)), rel=0.1)
    # runs of an iid Bernoulli(p) sequence are geometric: mean length 1/(1 - p) samples
    assert abs(st.mean_duration - dt / (1 - p)) < 4 * st.mean_duration_se
    assert st.n_episodes > 1000
    assert np.all(st.durations > 0)


def test_stick_episodes_on_a_hand_made_pattern():
    v = np.array([[0.0, 5, 0, 0, 5, 0, 0, 0],     # leading and trailing runs are censored
                  [5.0, 0, 5, 0, 0, 0, 5, 5],
                  [5.0, 5, 5, 5, 5, 5, 5, 5]])
    dt = 0.5
    ens = Ensemble(dt * np.arange(8), v, np.zeros_like(v))
    st = stick_statistics(ens, threshold=1.0)
    np.testing.assert_allclose(st.durations, [2 * dt, 1 * dt, 3 * dt])
    assert st.censored == 2 and st.n_episodes == 3
    assert st.mean_duration == pytest.approx(2 * dt)
    assert st.fraction.value == pytest.approx(10 / 24)
    # burn_in = 1.0 drops samples 0 and 1: row 0's run [2, 3] now starts the record
    # (censored) and row 1's single-sample run is gone
    late = stick_statistics(ens, threshold=1.0, burn_in=1.0)
    np.testing.assert_allclose(late.durations, [3 * dt])
    assert late.censored == 2


def test_stick_statistics_bad_input():
    ens = Ensemble(np.arange(5.0), np.zeros((2, 5)), np.zeros((2, 5)))
    with pytest.raises(ValueError, match="threshold must be > 0"):
        stick_statistics(ens, -0.1)
    with pytest.raises(ValueError, match="burn_in must be >= 0"):
        stick_statistics(ens, 0.1, burn_in=-2)
    bad = Ensemble(np.array([0.0, 1.0, 3.0]), np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="time grid must be uniform"):
        stick_statistics(bad, 0.1)
