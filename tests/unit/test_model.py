"""analogue.Model: validation, unit conversions, potential, stationary law, deterministic motion."""
import math

import numpy as np
import pytest
from scipy import integrate

from analogue import Model


@pytest.mark.parametrize("name,value,needle", [
    ("tau_m", 0.0, "tau_m must be > 0"),
    ("tau_m", -1.0, "tau_m must be > 0"),
    ("delta", -0.1, "delta must be >= 0"),
    ("gamma", 0.0, "gamma must be > 0"),
    ("mass", -2.0, "mass must be > 0"),
    ("epsilon", -1e-3, "epsilon must be >= 0"),
    ("a", float("nan"), "a must be finite"),
    ("gamma", float("-inf"), "gamma must be finite"),
])
def test_invalid_parameters_name_the_parameter(name, value, needle):
    kw = dict(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
    kw[name] = value
    with pytest.raises(ValueError, match=needle):
        Model(**kw)


@pytest.mark.parametrize("name,value", [("delta", "abc"), ("tau_m", "1"), ("gamma", True),
                                        ("a", None), ("mass", [1.0])])
def test_wrong_types_raise_type_error_naming_the_parameter(name, value):
    kw = dict(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
    kw[name] = value
    with pytest.raises(TypeError, match=f"{name} must be a real number"):
        Model(**kw)


def test_mechanical_round_trip():
    m = Model.from_mechanical(mass=2.0, alpha=0.5, delta_F=1.4, F=-0.6, D=0.8)
    assert m.tau_m == pytest.approx(4.0)
    assert m.delta == pytest.approx(0.7)
    assert m.a == pytest.approx(-0.3)
    assert m.gamma == pytest.approx(5.0)
    back = m.mechanical()
    assert back == pytest.approx((2.0, 0.5, 1.4, -0.6, 0.8))
    assert Model.from_mechanical(*back) == m
    with pytest.raises(ValueError, match="alpha must be > 0"):
        Model.from_mechanical(1.0, 0.0, 1.0, 0.0, 1.0)


@pytest.mark.parametrize("a", [0.2, 1.2, -0.4, -1.5])
@pytest.mark.parametrize("eps", [0.0, 0.05])
@pytest.mark.parametrize("gamma", [1.0, 10.0, 1000.0])
def test_stationary_pdf_is_normalised(a, eps, gamma):
    m = Model(1.0, 0.7, a, gamma, epsilon=eps)
    c = m.potential_minimum()
    w = 30 * m.velocity_scale
    total, _ = integrate.quad(m.stationary_pdf, c - w, c + w, points=[0.0] if abs(c) < w else None,
                              limit=500, epsabs=0, epsrel=1e-10)
    assert total == pytest.approx(1.0, rel=1e-7)


def test_potential_smooth_law_tends_to_sgn_law():
    v = np.linspace(-3, 3, 61)
    m = Model(1.0, 0.7, 0.2, 10.0)
    assert np.allclose(m.replace(epsilon=1e-6).potential(v), m.potential(v), atol=1e-6)
    # U' of the smooth law is the tanh friction (numerical derivative)
    ms = m.replace(epsilon=0.1)
    h = 1e-6
    du = (ms.potential(v + h) - ms.potential(v - h)) / (2 * h)
    assert np.allclose(-du, ms.drift(v), atol=1e-6)


def test_stick_time_and_vss_match_paper():
    # Paper Fig. 5 caption: tau_m = 1, Delta = 0.7, a = 0.2, v0 = 2 gives t_a+ = 1.6
    m = Model(1.0, 0.7, 0.2, 10.0)
    t_st = m.stick_time(2.0)
    assert t_st == pytest.approx(math.log(1 + 2.0 / 0.5))
    assert round(t_st, 1) == 1.6
    t = np.array([0.0, 0.5 * t_st, t_st * (1 - 1e-9), t_st, 5.0])
    v = m.deterministic(2.0, t)
    assert v[0] == 2.0 and v[1] > 0 and v[3] == 0 and v[4] == 0
    assert abs(v[2]) < 1e-8
    # Negative start: eq. (31) with the lower sign
    assert m.stick_time(-1.0) == pytest.approx(math.log(1 + 1.0 / 0.9))
    assert m.deterministic(-1.0, [10.0])[0] == 0.0
    # Slip: v_ss = (a - Delta) tau_m (eq. (14)), crossing from below with a kink
    s = Model(1.0, 0.7, 1.2, 10.0)
    assert s.attractor == pytest.approx(0.5)
    assert s.deterministic(-1.0, [60.0])[0] == pytest.approx(0.5, abs=1e-12)
    t_x = math.log(1 + 1.0 / 1.9)
    v = s.deterministic(-1.0, [t_x - 1e-7, t_x + 1e-7])
    assert abs(v[0]) < 1e-6 and abs(v[1]) < 1e-6
    # slopes either side of the crossing: -U'(0-) = Delta + a, -U'(0+) = a - Delta
    dv = s.deterministic(-1.0, [t_x - 1e-4, t_x, t_x + 1e-4])
    assert (dv[1] - dv[0]) / 1e-4 == pytest.approx(1.9, rel=1e-3)
    assert (dv[2] - dv[1]) / 1e-4 == pytest.approx(0.5, rel=1e-3)


def test_deterministic_symmetry_and_smooth_limit():
    t = np.linspace(0, 4, 41)
    for a in (0.2, 1.2, -1.3):
        m = Model(1.0, 0.7, a, 10.0)
        mirror = m.replace(a=-a)
        for v0 in (1.5, -0.8, 0.0):
            assert np.allclose(m.deterministic(v0, t), -mirror.deterministic(-v0, t), atol=1e-13)
        # epsilon -> 0: the smooth ODE approaches the closed form (stuck value O(epsilon))
        eps = 1e-4
        smooth = m.replace(epsilon=eps).deterministic(1.5, t)
        assert np.allclose(smooth, m.deterministic(1.5, t), atol=20 * eps)


def test_deterministic_rejects_negative_time():
    with pytest.raises(ValueError, match="t must be"):
        Model(1.0, 0.7, 0.2, 10.0).deterministic(1.0, [-1.0])
