"""Local exponent of a sweep on log-log axes (estimators.scaling)."""
import numpy as np
import pytest

from analogue import Model
from analogue.estimators.scaling import local_exponent
from analogue.theory import bias_transport as bt
from analogue.theory import exact


def test_power_law_and_error_propagation():
    x = np.array([0.1, 0.2, 0.4, 0.8])
    mid, e, se = local_exponent(x, 3.0 * x**1.74, 0.01 * 3.0 * x**1.74)
    np.testing.assert_allclose(e, 1.74, rtol=1e-12)
    np.testing.assert_allclose(mid, np.sqrt(x[1:] * x[:-1]))
    np.testing.assert_allclose(se, np.sqrt(2) * 0.01 / np.log(2.0), rtol=1e-12)
    # decreasing x gives the same slopes
    np.testing.assert_allclose(local_exponent(x[::-1], (x**1.74)[::-1])[1], 1.74, rtol=1e-12)


def test_chords_of_the_exact_diffusion_match_the_exact_exponent():
    """D_x against D = 1/gamma on a fine sweep (ratio 1.1): each chord slope equals the exact
    local exponent at its midpoint to O(step^2) (< 2e-3 here)."""
    gammas = np.array([5.0, 5.5, 6.05])
    d_x = [exact.stationary_moments(Model(1.0, 1.0, 0.3, g)).diffusion for g in gammas]
    mid, e, _ = local_exponent(1.0 / gammas, d_x)
    for m, ei in zip(mid, e):
        assert ei == pytest.approx(bt.diffusion_exponent(Model(1.0, 1.0, 0.3, 1.0 / m)), abs=2e-3)


def test_bad_input():
    with pytest.raises(ValueError, match="monotone"):
        local_exponent([1.0, 2.0, 1.5], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="> 0"):
        local_exponent([1.0, 2.0], [1.0, -2.0])
    with pytest.raises(ValueError, match="y_se"):
        local_exponent([1.0, 2.0], [1.0, 2.0], [0.1])
