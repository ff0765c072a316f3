"""First passage to rest (theory.first_passage, issue 23 item 2): the absorbing Fokker-Planck
moments and law against the quadrature formula, the erfcx closed form against nested
quadrature, and the weak-noise limit t_a."""
import math

import numpy as np
import pytest

from analogue import Model, ShotNoise
from analogue.theory import first_passage as fp

M = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)


@pytest.mark.parametrize("model,v0", [(M, 1.0), (M, -1.0), (M, 0.3), (M.replace(gamma=60.0), 1.0),
                                      (M.replace(a=0.9), 0.5),             # slip regime
                                      (M.replace(a=1.2), -1.0),  # the slip experiment's crossing start
                                      (M.replace(epsilon=0.05), 0.8),      # tanh law
                                      (Model(1.0, 0.7, 0.2, 10.0, cubic=0.5), -0.6)])
def test_grid_mean_equals_the_quadrature_formula(model, v0):
    mean, var = fp.first_passage_moments(model, v0)
    assert mean == pytest.approx(fp.first_passage_mean(model, v0), rel=1e-6)
    assert var > 0


def test_closed_form_equals_nested_quadrature():
    """A Stribeck member with delta_s = Delta has the sgn law's U but takes the nested route."""
    same = Model(1.0, 0.7, 0.2, 10.0, stribeck=(0.7, 0.3))
    for v0 in (1.0, -0.4):
        assert fp.first_passage_mean(same, v0) == pytest.approx(fp.first_passage_mean(M, v0),
                                                                rel=1e-9)


def test_law_integrates_to_the_moments():
    """int f dt = 1, int S dt = E T, int t^2 f dt = E T^2 (trapezoid in ln t over
    [1e-4, 60]: S(60) < 1e-12 here, and the first 1e-4 adds 1e-4 to int S)."""
    ts = np.exp(np.linspace(math.log(1e-4), math.log(60.0), 600))
    surv = fp.first_passage_survival(M, 1.0, ts)
    dens = fp.first_passage_density(M, 1.0, ts)
    mean, var = fp.first_passage_moments(M, 1.0)
    lt = np.log(ts)
    assert surv[0] == pytest.approx(1.0, abs=1e-12) and surv[-1] < 1e-12
    assert np.all(np.diff(surv) <= 1e-12) and np.all(dens >= 0)
    assert np.trapezoid(dens * ts, lt) == pytest.approx(1.0, abs=1e-6)
    assert np.trapezoid(surv * ts, lt) + 1e-4 == pytest.approx(mean, rel=1e-6)
    assert np.trapezoid(dens * ts**3, lt) == pytest.approx(var + mean**2, rel=1e-5)
    # f = -dS/dt: 1 - S(t) is the integral of f up to t, at every t
    from scipy.integrate import cumulative_simpson
    np.testing.assert_allclose(cumulative_simpson(dens * ts, x=lt, initial=0.0), 1.0 - surv,
                               atol=2e-5)


def test_weak_noise_limit_is_the_stick_time():
    """T(gamma) -> t_a = tau_m ln(1 + v0/((Delta - a) tau_m)) with an O(1/gamma) correction."""
    t_a = M.stick_time(1.0)
    gaps = [abs(fp.first_passage_mean(M.replace(gamma=g), 1.0) - t_a) for g in (1e2, 1e3, 1e4)]
    assert gaps[-1] < 3e-4 * t_a
    assert gaps[0] / gaps[1] == pytest.approx(10.0, rel=0.1)
    assert gaps[1] / gaps[2] == pytest.approx(10.0, rel=0.05)
    # the slope at rest tends to 1/(Delta - a) on the stick side
    assert fp.mean_slope_at_rest(M.replace(gamma=1e4), 1.0) == pytest.approx(2.0, rel=1e-3)


def test_bad_input():
    with pytest.raises(ValueError, match="v0"):
        fp.first_passage_mean(M, 0.0)
    with pytest.raises(ValueError, match="shot"):
        fp.first_passage_moments(M.replace(shot=ShotNoise(1.0, 0.2)), 1.0)
    with pytest.raises(ValueError, match="t must"):
        fp.first_passage_survival(M, 1.0, [-1.0])
