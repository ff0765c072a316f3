"""Coloured noise in the circuit (analogue.variants.coloured: the white trrandom source through
an RC low-pass of time constant tau_c): the circuit's stationary mean and variance agree with
the Monte Carlo of the same model within standard errors (tiny size: 48 replicas, t = 12), at
Delta = 0 also with the closed form ``Var v = tau_m^2/(gamma (tau_m + tau_c))``, and a noise
hold that the filter cannot follow is refused naming noise_dt."""
from __future__ import annotations

import math

import pytest
from conftest import stationary_stats

import analogue
from analogue import Model
from analogue.montecarlo import simulate_sde
from analogue.variants import OrnsteinUhlenbeck
from analogue.variants.coloured import stationary_velocity_variance

pytestmark = pytest.mark.requires_ngspice


_stationary = stationary_stats  # (mean, se, variance, se), se from the replicas


def _circuit(model, seed):
    return analogue.simulate(model, v0=0.0, t_end=12.0, replicas=48, seed=seed, sample_dt=0.1,
                             circuit={"noise_dt": 0.01}, store=False, workers=1)


@pytest.mark.parametrize("delta, a, tau_c", [(0.0, 0.3, 0.5), (0.5, 0.2, 0.2)])
def test_circuit_agrees_with_monte_carlo_within_standard_errors(delta, a, tau_c):
    model = Model(1.0, delta, a, 10.0, noise=OrnsteinUhlenbeck(tau_c))
    e = _circuit(model, seed=11)
    # the Monte Carlo of the model the circuit realises (its tanh smoothing included)
    effective = Model(**e.meta["model_effective"])
    assert effective.noise == model.noise
    mc = simulate_sde(effective, v0=0.0, t_end=12.0, replicas=400, seed=12, sample_dt=0.1)
    c_mean, c_se_m, c_var, c_se_v = _stationary(e, 4.0, 10)
    m_mean, m_se_m, m_var, m_se_v = _stationary(mc, 4.0, 10)
    assert abs(c_mean - m_mean) < 4 * math.hypot(c_se_m, m_se_m)
    assert abs(c_var - m_var) < 4 * math.hypot(c_se_v, m_se_v)
    if delta == 0:
        exact = stationary_velocity_variance(1.0, 10.0, tau_c)
        assert abs(c_var - exact) < 4 * c_se_v
        assert abs(c_mean - a) < 4 * c_se_m


def test_a_noise_hold_too_long_for_the_filter_is_refused():
    model = Model(1.0, 0.5, 0.2, 10.0, noise=OrnsteinUhlenbeck(0.05))
    with pytest.raises(ValueError, match="noise_dt"):
        analogue.simulate(model, v0=0.0, t_end=1.0, replicas=2, seed=1,
                          circuit={"noise_dt": 0.01}, store=False, workers=1)
