"""Drift and diffusion under a bias (theory.bias_transport, issue 23 item 3): the pure
dry-friction closed forms against the exact numerics at large tau_m (they converge as
1/tau_m), the mobility identity d<v>/da = gamma Var v against finite differences of the
exact mean, and the Einstein-like ratio in its two limits."""
import math

import numpy as np
import pytest

from analogue import Model, ShotNoise
from analogue.theory import bias_transport as bt
from analogue.theory import exact


def test_closed_forms_are_consistent():
    """<v> = 2 a D/(Delta^2 - a^2) with D = 1/gamma; mobility 2 D/Delta^2 at a -> 0 and the
    a-derivative of the closed-form mean; D_x = 5 D^3/Delta^4 and the 5/4 factor at a = 0."""
    d, g = 0.8, 12.0
    D = 1.0 / g
    for a in (-0.5, 0.0, 0.3, 0.7):
        c = bt.pure_dry_friction(d, a, g)
        assert c.mean == pytest.approx(2 * a * D / (d * d - a * a), rel=1e-14, abs=1e-16)
        assert c.variance == pytest.approx(c.second_moment - c.mean**2, rel=1e-12)
        e = 1e-6
        fd = (bt.pure_dry_friction(d, a + e, g).mean - bt.pure_dry_friction(d, a - e, g).mean) / (2 * e)
        assert c.mobility == pytest.approx(fd, rel=1e-7)
    c0 = bt.pure_dry_friction(d, 0.0, g)
    assert c0.mobility == pytest.approx(2 * D / d**2, rel=1e-14)
    assert c0.diffusion == pytest.approx(5 * D**3 / d**4, rel=1e-14)
    assert c0.einstein_factor == pytest.approx(1.25, rel=1e-14)
    assert c0.einstein_ratio == pytest.approx(2.5 * D**2 / d**2, rel=1e-14)
    # mirror symmetry a -> -a: the mean changes sign, the rest is even
    p, m = bt.pure_dry_friction(d, 0.3, g), bt.pure_dry_friction(d, -0.3, g)
    assert p.mean == pytest.approx(-m.mean) and p.diffusion == pytest.approx(m.diffusion, rel=1e-14)


@pytest.mark.parametrize("a", [0.0, 0.3, -0.6])
def test_exact_numerics_tend_to_the_dry_friction_closed_forms(a):
    """Relative deviations of <v>, Var v, D_x at tau_m = 2e3 and 4e3 are first order in
    1/tau_m, ``-c D/((Delta - |a|)^2 tau_m)`` with c = 2.4 .. 13.8 (measured; a = 0: Var
    exactly 5, D_x 12): below 15 D/((Delta - |a|)^2 tau_m), halving when tau_m doubles, and
    the extrapolation 2 f(4e3) - f(2e3) agrees with the closed form to 2e-5 (measured <=
    9e-6: the O(1/tau_m^2) rest).  h = 0.005: the default grid's D_x error at a = 0 (6e-5,
    measured) would hide the 1/tau_m^2 rest."""
    delta, gamma = 1.0, 10.0
    c = bt.pure_dry_friction(delta, a, gamma)
    got = {}
    for tau in (2e3, 4e3):
        mom = exact.stationary_moments(Model(tau, delta, a, gamma), h=0.005)
        got[tau] = np.array([mom.mean, mom.variance, mom.diffusion])
    ref = np.array([c.mean, c.variance, c.diffusion])
    keep = ref != 0
    for tau, val in got.items():
        dev = np.abs(val[keep] / ref[keep] - 1)
        assert np.all(dev < 15.0 / (gamma * (delta - abs(a)) ** 2 * tau))
    if a == 0:
        assert abs(got[4e3][0]) < 1e-12
    extrap = 2.0 * got[4e3] - got[2e3]
    np.testing.assert_allclose(extrap[keep], ref[keep], rtol=2e-5)
    ratio = (got[2e3][keep] / ref[keep] - 1) / (got[4e3][keep] / ref[keep] - 1)
    np.testing.assert_allclose(ratio, 2.0, rtol=0.02)


@pytest.mark.parametrize("model", [Model(1.0, 1.0, 0.3, 10.0), Model(1.0, 0.5, 0.9, 4.0),
                                   Model(1.0, 1.0, 0.3, 10.0, stribeck=(1.3, 0.2)),
                                   Model(1.0, 0.6, 0.2, 10.0, epsilon=0.05)])
def test_mobility_is_gamma_times_the_variance(model):
    """d<v>/da by central differences of the exact (quadrature) mean, step 1e-4."""
    e = 1e-4
    fd = (exact.stationary_moments(model.replace(a=model.a + e)).mean
          - exact.stationary_moments(model.replace(a=model.a - e)).mean) / (2 * e)
    assert bt.mobility(model) == pytest.approx(fd, rel=1e-7)


def test_einstein_ratio_and_noise_exponent_limits():
    """Delta = 0: D_x/mu = tau_m/gamma = Var v and D_x ~ D (exponent 1); large tau_m: the dry
    friction ratio 5 D^2/(2 Delta^2) (within 3/tau_m) and D_x ~ D^3; the exponent falls from
    3 towards 1 as the noise grows at tau_m = 1."""
    ou = Model(1.0, 0.0, 0.3, 10.0)
    assert bt.einstein_ratio(ou) == pytest.approx(ou.tau_m / ou.gamma, rel=1e-8)
    assert bt.diffusion_exponent(ou) == pytest.approx(1.0, abs=1e-8)
    dry = Model(4e3, 1.0, 0.0, 10.0)
    ref = bt.pure_dry_friction(1.0, 0.0, 10.0)
    assert bt.einstein_ratio(dry) == pytest.approx(ref.einstein_ratio, rel=3.0 / 4e3)
    assert bt.diffusion_exponent(dry) == pytest.approx(3.0, abs=3e-3)
    ex = [bt.diffusion_exponent(Model(1.0, 1.0, 0.3, g)) for g in (1.0, 10.0, 100.0, 1000.0)]
    assert 1.0 < ex[0] and np.all(np.diff(ex) > 0) and ex[-1] < 3.0


def test_bad_input():
    with pytest.raises(ValueError, match="delta"):
        bt.pure_dry_friction(0.5, 0.5, 10.0)
    with pytest.raises(ValueError, match="gamma"):
        bt.pure_dry_friction(0.5, 0.1, -1.0)
    with pytest.raises(ValueError, match="shot"):
        bt.mobility(Model(1.0, 0.5, 0.1, math.inf, shot=ShotNoise(1.0, 0.2)))
    with pytest.raises(ValueError, match="rel_step"):
        bt.diffusion_exponent(Model(1.0, 0.5, 0.1, 10.0), rel_step=0.0)
