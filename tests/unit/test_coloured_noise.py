"""Coloured noise, the Ornstein-Uhlenbeck force (analogue.variants.coloured; issue 20's new
member): the model takes it, round-trips it and refuses what it cannot take; its Monte Carlo
meets the closed form of the linear 2-D OU at Delta = 0,

    Var v = tau_m^2 / (gamma (tau_m + tau_c)),

(derived in the module docstring), and recovers white noise as tau_c -> 0 (also with dry
friction, against the exact white-noise stationary law exp(-gamma U)).  Tolerances: 4 standard
errors of each estimate (replicas are independent)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import stationary_stats

from analogue import Model, ShotNoise
from analogue.montecarlo import default_dt, simulate_sde
from analogue.variants import NOISE_KINDS, Gaussian, OrnsteinUhlenbeck
from analogue.variants.coloured import stationary_velocity_variance


def _ou(tau_c, **kw):
    p = {"tau_m": 1.0, "delta": 0.0, "a": 0.3, "gamma": 10.0} | kw
    return Model(**p, noise=OrnsteinUhlenbeck(tau_c))


def test_model_binds_round_trips_and_refuses():
    m = _ou(0.5)
    assert m.noise == OrnsteinUhlenbeck(0.5, 10.0)
    assert not m.is_paper and not m.is_gradient and m.is_noisy
    assert m.as_dict()["noise"] == {"kind": "ornstein-uhlenbeck", "tau_c": 0.5}
    assert Model(**m.as_dict()) == m
    assert NOISE_KINDS["ornstein-uhlenbeck"] is OrnsteinUhlenbeck
    # a new gamma re-binds the kind; dropping it gives the paper's noise again
    assert m.replace(gamma=20.0).noise == OrnsteinUhlenbeck(0.5, 20.0)
    assert Model(1.0, 0.0, 0.3, 10.0).noise == Gaussian(10.0)
    with pytest.raises(ValueError, match="gamma"):
        _ou(0.5, gamma=math.inf)
    with pytest.raises(ValueError, match="shot"):
        Model(1.0, 0.5, 0.2, 10.0, shot=ShotNoise(1.0, 0.5), noise=OrnsteinUhlenbeck(0.5))
    with pytest.raises(ValueError, match="tau_c"):
        OrnsteinUhlenbeck(-1.0)
    with pytest.raises(ValueError, match="noise kind"):
        Model(1.0, 0.5, 0.2, 10.0, noise={"kind": "pink", "tau_c": 1.0})
    with pytest.raises(TypeError, match="noise"):
        Model(1.0, 0.5, 0.2, 10.0, noise="ou")
    with pytest.raises(ValueError, match="exp\\(-gamma U\\)"):
        m.stationary_pdf(0.0)
    assert default_dt(m) <= 0.5 / 50


# pooled over output times one unit apart (about the correlation time), se from the replicas
_stationary = stationary_stats


@pytest.mark.parametrize("tau_c", [0.2, 1.0, 3.0])
def test_stationary_variance_at_zero_friction_is_the_closed_form(tau_c):
    # At Delta = 0 the scheme is exact for any dt (module docstring): dt = 0.05.
    m = _ou(tau_c)
    e = simulate_sde(m, v0=0.3, t_end=10.0 + 5.0 * tau_c, replicas=1500, seed=7, dt=0.05,
                     sample_dt=1.0)
    mean, se_mean, var, se_var = _stationary(e, 5.0 + 5.0 * tau_c)
    expected = stationary_velocity_variance(1.0, 10.0, tau_c)
    assert abs(mean - 0.3) < 4 * se_mean
    assert abs(var - expected) < 4 * se_var
    # and it is not the white-noise value tau_m/gamma = 0.1 (the test can tell them apart)
    assert abs(var - 0.1) > 4 * se_var


def test_given_noise_holds_the_filters_input_and_meets_the_closed_form_at_zero_friction():
    """Given increments (the held-noise pair of the report's bandwidth term) drive the
    filter's input, held over each step: at Delta = 0, dt = 0.02 its stationary variance is the
    closed form tau_m^2/(gamma (tau_m + tau_c)) (relative bias dt^2/(12 tau_m tau_c) = 2e-4,
    far below the 4 SE tolerance of ~6 %); held over 5 steps the same increments give another
    path (a different force), and a wrong shape is refused."""
    tau_c = 0.4
    m = _ou(tau_c)
    n = 1500
    t_end, dt = 9.0, 0.02
    z = np.random.default_rng(3).standard_normal((n, round(t_end / dt)))
    e = simulate_sde(m, v0=0.3, t_end=t_end, replicas=n, dt=dt, sample_dt=1.0, noise=z)
    mean, se_mean, var, se_var = _stationary(e, 5.0)
    assert abs(mean - 0.3) < 4 * se_mean
    assert abs(var - stationary_velocity_variance(1.0, 10.0, tau_c)) < 4 * se_var
    held = z.reshape(n, -1, 5).mean(axis=2)
    h = simulate_sde(m, v0=0.3, t_end=t_end, replicas=n, dt=dt, sample_dt=1.0, noise=held,
                     noise_hold=5)
    assert not np.array_equal(h.v[:, 1:], e.v[:, 1:])
    assert np.corrcoef(h.v[:, -1], e.v[:, -1])[0, 1] > 0.9   # common increments
    with pytest.raises(ValueError, match="noise must have shape"):
        simulate_sde(m, v0=0.0, t_end=1.0, replicas=2, dt=0.01, noise=np.zeros((2, 99)))


def test_short_correlation_time_recovers_white_noise_at_zero_friction():
    e = simulate_sde(_ou(1e-3), v0=0.3, t_end=12.0, replicas=1500, seed=8, dt=0.05,
                     sample_dt=1.0)
    mean, se_mean, var, se_var = _stationary(e, 5.0)
    # white noise: Var v = tau_m/gamma; the OU value differs by tau_c/(tau_m + tau_c) = 1e-3
    assert abs(var - 0.1) < 4 * se_var and abs(mean - 0.3) < 4 * se_mean
    assert se_var < 0.01 * 0.1 * 4  # the comparison is sharp (a few per cent)


@pytest.mark.slow
def test_short_correlation_time_recovers_the_white_stationary_law_with_dry_friction():
    """Stick regime (Delta = 0.7, a = 0.2, gamma = 10): with tau_c = 2e-3, far below the
    stick peak's relaxation time 1/(gamma Delta^2) = 0.2, the stationary mean and variance
    are those of exp(-gamma U) (eq. (6)), computed by quadrature of the white model's law."""
    white = Model(1.0, 0.7, 0.2, 10.0)
    v = np.linspace(-3.0, 3.0, 60001)
    p = white.stationary_pdf(v)
    dv = v[1] - v[0]
    m1 = float(np.sum(v * p) * dv)
    var_white = float(np.sum((v - m1) ** 2 * p) * dv)
    m = Model(1.0, 0.7, 0.2, 10.0, noise=OrnsteinUhlenbeck(2e-3))
    e = simulate_sde(m, v0=0.0, t_end=3.0, replicas=1000, seed=9, dt=1e-4, sample_dt=0.5)
    mean, se_mean, var, se_var = _stationary(e, 1.5)
    assert abs(mean - m1) < 4 * se_mean
    assert abs(var - var_white) < 4 * se_var


def test_exact_theory_refuses_coloured_noise_instead_of_answering_for_white_noise():
    """The family's exact solvers (Fokker-Planck, Kolmogorov-Feller) have no OU force: before
    the guard, stationary_law and sample_stationary silently returned the white-noise law."""
    from analogue.theory import exact, family, stationary
    m = Model(1.0, 0.7, 0.2, 10.0, noise=OrnsteinUhlenbeck(0.2))
    for call in (lambda: family.stationary_law(m), lambda: family.stationary_moments(m),
                 lambda: stationary.sample_stationary(m, 3, seed=1),
                 lambda: exact.stationary_moments(m), lambda: family.scgf(m, [0.1])):
        with pytest.raises(ValueError, match="ornstein-uhlenbeck"):
            call()


def test_an_experiment_file_takes_the_noise_kind_as_a_table(tmp_path):
    from pathlib import Path

    from analogue.circuit.experiments import load_experiment
    stick = (Path(__file__).resolve().parents[2] / "circuits" / "stick.toml").read_text()
    text = stick.replace('name = "stick"', 'name = "colour"').replace(
        "mass = 1.0\n", 'mass = 1.0\nnoise = {kind = "ornstein-uhlenbeck", tau_c = 0.2}\n', 1)
    path = tmp_path / "colour.toml"
    path.write_text(text)
    assert load_experiment(path).model.noise == OrnsteinUhlenbeck(0.2, 10.0)
    for bad, error, words in (("tau_c = -1", ValueError, "model.noise: noise.tau_c"),
                              ("tau_c = 0.2, colour = 1", TypeError, "model.noise.*colour")):
        path.write_text(text.replace("tau_c = 0.2", bad))
        with pytest.raises(error, match=words):
            load_experiment(path)
    path.write_text(text.replace('"ornstein-uhlenbeck"', '"pink"'))
    with pytest.raises(ValueError, match="noise kind must be one of"):
        load_experiment(path)


def test_weak_noise_theories_refuse_coloured_noise():
    """The weak-noise theories are those of white Gaussian noise (optimal paths of a gradient
    system): before the guard, analogue.theory.weak_noise.action accepted a coloured-noise
    model (it tested only cubic, stribeck, spring and shot)."""
    from analogue.theory import weak_noise, weak_noise_family
    m = Model(1.0, 0.7, 0.2, 10.0, noise=OrnsteinUhlenbeck(0.2))
    with pytest.raises(ValueError, match="noise=None"):
        weak_noise.action(m, 0.5, 1.0, 1.0)
    with pytest.raises(ValueError, match="noise = None"):
        weak_noise_family.quasi_potential(m, 0.5)
