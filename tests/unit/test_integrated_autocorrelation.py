"""Closed-form 2 int_0^tau (tau - s) C(s) ds (stationary.integrated_autocorrelation, the default
route of work_statistics.work_variance) against the OU closed form, the quadrature route it
replaces, and its small- and large-tau limits."""
import numpy as np
import pytest

from analogue import Model
from analogue.theory import ornstein_uhlenbeck as ou
from analogue.theory import stationary as st
from analogue.theory import work_statistics as ws


def test_delta_zero_equals_ou_closed_form():
    """Delta = 0: Var(W_tau)/F^2 of the OU process, from tau = 0.01 (where the closed form's
    three terms nearly cancel) to tau = 20."""
    m = Model(tau_m=1.0, delta=0.0, a=0.5, gamma=10.0)
    taus = np.array([0.01, 0.3, 1.0, 5.0, 20.0])
    ref = np.asarray(ou.work_variance(m, taus)) / m.force**2
    np.testing.assert_allclose(st.integrated_autocorrelation(m, taus), ref, rtol=1e-7)


@pytest.mark.parametrize("a,gamma", [(0.5, 10.0), (1.5, 10.0), (0.2, 30.0)])
def test_matches_converged_quadrature_of_the_autocorrelation(a, gamma):
    """Against Simpson's rule on the spectral autocorrelation with 3201 lags per window (its
    quadrature error at these windows is below 1e-8 relative: it shrinks ~n^-3, measured)."""
    m = Model(tau_m=1.0, delta=1.0, a=a, gamma=gamma)
    taus = np.array([0.5, 1.0, 2.0])
    quad = ws.work_variance(m, taus, n=3201)
    np.testing.assert_allclose(ws.work_variance(m, taus), quad, rtol=1e-8)


def test_limits_variance_and_diffusion():
    """tau -> 0: tau^2 C(0) = tau^2 Var(v); tau -> inf: slope 2 D (Green-Kubo diffusion)."""
    m = Model(tau_m=1.0, delta=0.7, a=0.3, gamma=10.0)
    var = st.stationary_moments(m).variance
    small = st.integrated_autocorrelation(m, [1e-3])[0]
    assert small / 1e-6 == pytest.approx(var, rel=2e-3)      # C(s) = C(0) (1 - O(s))
    big = st.integrated_autocorrelation(m, [60.0, 80.0])
    assert (big[1] - big[0]) / 20.0 == pytest.approx(2.0 * st.diffusion_coefficient(m), rel=1e-8)


def test_bad_input():
    with pytest.raises(ValueError, match="taus"):
        st.integrated_autocorrelation(Model(1.0, 0.5, 0.2, 10.0), [np.inf])
    with pytest.raises(ValueError, match="paper's model"):
        st.integrated_autocorrelation(Model(1.0, 0.5, 0.2, 10.0, cubic=0.1), [1.0])
