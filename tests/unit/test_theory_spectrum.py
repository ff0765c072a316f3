"""Exact velocity power spectrum (theory.spectrum, issue 23 item 1) against independent routes:
the Ornstein-Uhlenbeck closed form at Delta = 0 (Gaussian and shot noise), the frequency
integral against the closed-form stationary variance, S(0) against the project's Green-Kubo
D_x, and the eigen (Lorentzian sum) route against the resolvent route."""
import math

import numpy as np
import pytest

from analogue import Model, ShotNoise
from analogue.theory import exact, spectrum


def _ou_spectrum(model: Model, w: np.ndarray, intensity: float) -> np.ndarray:
    """Two-sided S(omega) of dv = -(v - mu)/tau dt + noise of intensity ``intensity``:
    Var = tau intensity, C(t) = Var e^{-|t|/tau}, S = 2 Var tau / (1 + omega^2 tau^2)."""
    tau = model.tau_m
    return 2.0 * tau * tau * intensity / (1.0 + (w * tau) ** 2)


W = np.array([0.0, 0.05, 0.3, 1.0, 3.0, 10.0, 100.0])


@pytest.mark.parametrize("method", ["eigen", "resolvent"])
def test_delta_zero_is_the_ou_lorentzian(method):
    m = Model(tau_m=1.3, delta=0.0, a=0.3, gamma=10.0)
    got = spectrum.velocity_spectrum(m, W, method=method, h=0.02)  # 280 nodes: eigen is cheap
    np.testing.assert_allclose(got, _ou_spectrum(m, W, 1.0 / m.gamma), rtol=1e-7)


@pytest.mark.parametrize("gamma,rtol", [(20.0, 1e-7), (math.inf, 5e-4)])
def test_shot_noise_delta_zero_is_the_ou_lorentzian(gamma, rtol):
    """A linear drift with two-sided kicks: C(t) = Var e^{-t/tau} with the velocity-noise
    intensity 1/gamma + rate mean^2 (kicks of <z^2> = 2 mean^2).  Pure shot noise is first
    order (upwind), so its two-grid Richardson leaves ~2e-4 (measured 1.8e-4)."""
    shot = ShotNoise(rate=2.0, mean=0.3, two_sided=True)
    m = Model(tau_m=1.0, delta=0.0, a=0.3, gamma=gamma, shot=shot)
    w = W[:5]
    got = spectrum.velocity_spectrum(m, w)
    np.testing.assert_allclose(got, _ou_spectrum(m, w, 1.0 / gamma + shot.intensity), rtol=rtol)


def _integral(model: Model) -> float:
    """(1/pi) int_0^inf S d omega, trapezoid in ln omega over [1e-6, 1e9] (4001 points):
    the ends contribute < 1e-9 of the variance (S(0) omega_min and the 2/(gamma omega) tail)."""
    u = np.linspace(math.log(1e-6), math.log(1e9), 4001)
    om = np.exp(u)
    return float(np.trapezoid(spectrum.velocity_spectrum(model, om) * om, u)) / math.pi


@pytest.mark.parametrize("kw", [dict(delta=0.7, a=0.2), dict(delta=0.5, a=0.9),
                                dict(delta=0.7, a=-0.4, epsilon=0.05)])
def test_frequency_integral_is_the_stationary_variance(kw):
    m = Model(tau_m=1.0, gamma=10.0, **kw)
    assert _integral(m) == pytest.approx(exact.stationary_moments(m).variance, rel=1e-6)


def test_zero_frequency_is_twice_the_green_kubo_diffusion():
    """The Lorentzian sum at omega = 0 (eigenpairs) against the project's D_x (discrete
    Poisson equation, Richardson); the resolvent route is continuous into omega = 0."""
    m = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
    d_x = exact.stationary_moments(m).diffusion
    s0 = spectrum.velocity_spectrum(m, [0.0], method="eigen")[0]
    assert s0 == pytest.approx(2.0 * d_x, rel=1e-9)
    near = spectrum.velocity_spectrum(m, [1e-5], method="resolvent")[0]
    assert near == pytest.approx(2.0 * d_x, rel=1e-8)


def test_family_members_zero_frequency_and_integral():
    """Cubic friction (gradient member): the Lorentzian sum at 0 against the family's D_x
    (a sparse LU of the generator, an independent solve); a one-sided shot member: the
    resolvent near 0 against its Green-Kubo D_x."""
    cubic = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0, cubic=0.5)
    assert (spectrum.velocity_spectrum(cubic, [0.0], method="eigen")[0]
            == pytest.approx(2.0 * exact.stationary_moments(cubic).diffusion, rel=1e-8))
    assert _integral(cubic) == pytest.approx(exact.stationary_moments(cubic).variance, rel=1e-6)
    shot = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=math.inf, shot=ShotNoise(2.0, 0.3))
    near = spectrum.velocity_spectrum(shot, [1e-6])[0]
    assert near == pytest.approx(2.0 * exact.stationary_moments(shot).diffusion, rel=1e-6)


def test_eigen_and_resolvent_agree_and_mirror_symmetry():
    m = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
    a = spectrum.velocity_spectrum(m, W, method="eigen")
    b = spectrum.velocity_spectrum(m, W, method="resolvent")
    np.testing.assert_allclose(a, b, rtol=1e-9)
    # v -> -v maps the model with a onto the one with -a and leaves C(t), hence S, unchanged
    np.testing.assert_allclose(spectrum.velocity_spectrum(m.replace(a=-0.2), W), b, rtol=1e-10)
    # S is even and decreasing here (a sum of Lorentzians with positive weights)
    np.testing.assert_allclose(spectrum.velocity_spectrum(m, -W), b, rtol=0)
    assert np.all(np.diff(b) < 0)


def test_bad_input():
    m = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
    with pytest.raises(ValueError, match="omega"):
        spectrum.velocity_spectrum(m, [np.nan])
    with pytest.raises(ValueError, match="method"):
        spectrum.velocity_spectrum(m, [1.0], method="fft")
    with pytest.raises(ValueError, match="spring"):
        spectrum.velocity_spectrum(m.replace(spring=1.0), [1.0])
    with pytest.raises(ValueError, match="eigen"):
        spectrum.velocity_spectrum(m.replace(shot=ShotNoise(1.0, 0.2)), [1.0], method="eigen")


@pytest.mark.parametrize("model", [Model(10.0, 1.0, 0.0, 100.0), Model(100.0, 1.0, 0.3, 30.0)])
def test_half_power_point_near_the_sticking_rate(model):
    """Deep stick regime (sticking rate >> 1/tau_m): S falls to S(0)/2 within 25 % of the
    dry-friction sticking rate (measured 0.93 and 0.86 of it)."""
    from scipy.optimize import brentq
    inv_tau, rate = spectrum.crossover_frequencies(model)
    assert inv_tau == 1.0 / model.tau_m and rate > 30 * inv_tau
    s0 = spectrum.velocity_spectrum(model, [0.0])[0]
    half = brentq(lambda w: spectrum.velocity_spectrum(model, [w])[0] - 0.5 * s0,
                  0.1 * rate, 10 * rate, rtol=1e-4)
    assert half / rate == pytest.approx(0.9, abs=0.15)
    assert math.isnan(spectrum.crossover_frequencies(model.replace(a=1.5))[1])
