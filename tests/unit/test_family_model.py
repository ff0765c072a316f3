"""The model family's fields on analogue.Model: defaults, validation, the force law, U."""
import math

import numpy as np
import pytest
from scipy import integrate

from analogue import Model, ShotNoise

BASE = dict(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)


def test_defaults_are_the_papers_model():
    m = Model(**BASE)
    assert (m.cubic, m.stribeck, m.spring, m.x0, m.shot) == (0.0, None, 0.0, 0.0, None)
    assert m.is_paper and m.is_gradient and m.dimension == 1 and m.is_noisy
    assert m.as_dict() == {**BASE, "mass": 1.0, "epsilon": 0.0}


def test_extension_fields_are_keyword_only():
    with pytest.raises(TypeError):
        Model(1.0, 0.7, 0.2, 10.0, 1.0, 0.0, 0.5)


@pytest.mark.parametrize("kw", [dict(cubic=0.3), dict(stribeck=(1.0, 0.2)), dict(spring=2.0, x0=0.5),
                                dict(shot=ShotNoise(2.0, 0.3, two_sided=True), gamma=math.inf),
                                dict(stribeck=[1.0, 0.2], shot={"rate": 1.0, "mean": 0.5})])
def test_round_trip_replace_hash_equality(kw):
    m = Model(**{**BASE, **kw})
    back = Model(**m.as_dict())
    assert back == m and hash(back) == hash(m) and repr(back) == repr(m)
    assert isinstance(m.shot, (ShotNoise, type(None)))
    assert m.replace() == m and m.replace(cubic=0.1) != m
    assert not m.is_paper


@pytest.mark.parametrize("kw,exc,needle", [
    (dict(tau_m="1"), TypeError, "tau_m must be a real number"),
    (dict(gamma=True), TypeError, "gamma must be a real number"),
    (dict(cubic=False), TypeError, "cubic must be a real number"),
    (dict(cubic=-1.0), ValueError, "cubic must be >= 0"),
    (dict(spring=-1.0), ValueError, "spring must be >= 0"),
    (dict(stribeck=(1.0, 0.0)), ValueError, "stribeck v_s must be > 0"),
    (dict(stribeck=(-1.0, 0.2)), ValueError, "stribeck delta_s must be >= 0"),
    (dict(stribeck=1.0), TypeError, "stribeck must be None or a pair"),
    (dict(shot=(1.0, 2.0)), TypeError, "shot must be None or analogue.ShotNoise"),
    (dict(shot={"rate": -1.0, "mean": 1.0}), ValueError, "shot.rate must be > 0"),
    (dict(gamma=1e300), ValueError, "gamma must be within"),
    (dict(tau_m=1e-300), ValueError, "tau_m must be within"),
    (dict(gamma=1e-20, tau_m=1e12), ValueError, "gamma=1e-20 is too small for tau_m"),
    (dict(a=1e8, tau_m=1e8), ValueError, "reduce a or tau_m"),
    (dict(shot={"rate": 1.0, "mean": 1e20}), ValueError, "reduce shot.mean"),
    (dict(gamma=-math.inf), ValueError, "gamma must be finite"),
])
def test_bad_values_name_the_parameter(kw, exc, needle):
    with pytest.raises(exc, match=needle):
        Model(**{**BASE, **kw})


def test_shot_noise_validation():
    with pytest.raises(TypeError, match="two_sided must be True or False"):
        ShotNoise(1.0, 1.0, two_sided="yes")
    with pytest.raises(ValueError, match="shot.mean must be > 0"):
        ShotNoise(1.0, 0.0)
    s = ShotNoise(2.0, 0.5)
    assert s.mean_force == 1.0 and ShotNoise(2.0, 0.5, True).mean_force == 0.0


def test_gamma_inf_is_noise_free_unless_shot():
    m = Model(**{**BASE, "gamma": math.inf})
    assert not m.is_noisy and m.noise_intensity == 0.0
    with pytest.raises(ValueError, match="gamma must be finite"):
        m.stationary_pdf(0.0)
    assert m.replace(shot=ShotNoise(1.0, 0.1)).is_noisy


def test_stribeck_friction_magnitude_and_flags():
    m = Model(**BASE, stribeck=(1.2, 0.3))
    assert float(m.friction_magnitude(0.0)) == pytest.approx(1.2)
    assert float(m.friction_magnitude(100.0)) == pytest.approx(0.7)
    assert float(m.friction_magnitude(-0.3)) == pytest.approx(0.7 + 0.5 / math.e)
    assert m.static_friction == 1.2 and m.regime == "stick"
    assert m.replace(a=1.0).regime == "stick" and m.replace(a=1.3).regime == "slip"
    sp = Model(**BASE, spring=1.0)
    assert sp.dimension == 2 and not sp.is_gradient
    assert float(sp.drift(0.5, x=2.0)) == pytest.approx(-0.5 - 0.7 - 2.0 + 0.2)


@pytest.mark.parametrize("kw", [dict(cubic=0.4), dict(stribeck=(1.1, 0.25)),
                                dict(stribeck=(0.3, 0.5), cubic=0.2, epsilon=0.02),
                                dict(stribeck=(1.1, 0.25), epsilon=1e-3)])
@pytest.mark.parametrize("a", [0.2, 0.9, -1.4])
def test_potential_is_minus_the_integral_of_the_drift(kw, a):
    """U' = -drift (independent route: numerical differentiation), U(0) = 0."""
    m = Model(**{**BASE, "a": a, **kw})
    v = np.array([-2.3, -0.7, -0.11, 0.13, 0.6, 1.9])
    h = 1e-6
    du = (m.potential(v + h) - m.potential(v - h)) / (2 * h)
    assert np.max(np.abs(du + m.drift(v))) < 1e-7
    assert float(m.potential(0.0)) == 0.0
    # and against a quadrature of the drift
    for vv in v:
        val, _ = integrate.quad(lambda u: -float(m.drift(u)), 0.0, vv, points=[0.0] if vv else None,
                                epsabs=1e-13, epsrel=1e-12, limit=200)
        assert float(m.potential(vv)) == pytest.approx(val, rel=1e-9, abs=1e-11)


@pytest.mark.parametrize("kw", [dict(cubic=0.4), dict(stribeck=(1.1, 0.25)), dict(cubic=1.0, stribeck=(0.2, 1.0))])
@pytest.mark.parametrize("a", [0.3, 1.3, -1.6])
def test_family_stationary_pdf_normalised_and_attractor_is_a_drift_zero(kw, a):
    m = Model(**{**BASE, "a": a, **kw})
    total, _ = integrate.quad(m.stationary_pdf, -15, 15, points=[0.0], limit=400, epsrel=1e-11)
    assert total == pytest.approx(1.0, rel=1e-8)
    v = m.attractor
    if m.regime == "slip":
        assert abs(float(m.drift(v))) < 1e-12 and v * a > 0
        # nothing nearer to 0 on that side: the drift points outward between 0 and v
        u = np.linspace(0, abs(v), 200)[1:-1] * np.sign(v)
        assert np.all(np.sign(m.drift(u)) == np.sign(a))
    else:
        assert v == 0.0
    vm = m.potential_minimum()
    grid = np.linspace(-5, 5, 20001)
    assert float(m.potential(vm)) <= float(np.min(m.potential(grid))) + 1e-12


def test_deterministic_family_against_closed_form_limits():
    """cubic = 0 and Stribeck with delta_s = Delta reduce to the paper's closed form."""
    t = np.linspace(0, 4, 41)
    for a in (0.2, 1.3, -1.5):
        m = Model(**{**BASE, "a": a})
        ref = m.deterministic(1.0, t)
        fam = m.replace(stribeck=(0.7, 0.3)).deterministic(1.0, t)
        assert np.max(np.abs(fam - ref)) < 1e-9
        assert m.replace(stribeck=(0.7, 0.3)).stick_time(1.0) == pytest.approx(m.stick_time(1.0), rel=1e-9)


def test_spring_deterministic_ends_at_rest_within_the_static_band():
    m = Model(**BASE, spring=1.0, x0=0.0)
    from analogue.theory.deterministic import flow
    t = np.linspace(0, 30, 301)
    v, x = flow(m, 2.0, 0.0, t)
    assert v[-1] == 0.0 and abs(m.a - m.spring * x[-1]) <= m.static_friction
    # x is the integral of v (independent route: trapezoid on a fine grid)
    tf = np.linspace(0, 30, 30001)
    vf, xf = flow(m, 2.0, 0.0, tf)
    assert xf[-1] == pytest.approx(integrate.trapezoid(vf, tf), abs=1e-5)
