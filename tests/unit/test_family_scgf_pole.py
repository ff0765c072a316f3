"""The work SCGF of shot-noise members up to its pole, and the rate function beyond it.

With one-sided exponential kicks (mean mu) the SCGF is finite only for c mu < 1, c = k F tau_m
(:func:`analogue.theory.family.scgf_domain`), and diverges there like rate/(1 - c mu): the
rate function is finite for every w and asymptotically linear with slope k_pole.  References:
the Delta = 0 closed forms, the far-field form (near the pole the kick-transformed law lives
at large v, where f + v/tau_m = a - Delta), the direct tilted generator at moderate k, the
stationary mean (lambda'(0) = F <v>), and Monte Carlo of E exp(k W_T).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from analogue import Model, ShotNoise
from analogue.montecarlo import simulate_sde
from analogue.theory import family
from analogue.theory.kolmogorov_feller import default_spacing, shot_generator

INF = math.inf
SHOT = Model(1.0, 0.5, 0.2, INF, shot=ShotNoise(1.0, 0.5))  # circuits/shot.toml


def test_scgf_domain_and_infinity_beyond_the_pole():
    m = Model(1.0, 0.0, 0.5, INF, shot=ShotNoise(2.0, 0.3))
    lo, hi = family.scgf_domain(m)
    assert lo == -INF and hi == pytest.approx(1.0 / (m.force * m.tau_m * 0.3))
    neg = m.replace(a=-0.5)  # F < 0: the pole is at negative k
    assert family.scgf_domain(neg) == (pytest.approx(1.0 / (neg.force * 0.3)), INF)
    two = m.replace(shot=ShotNoise(2.0, 0.3, two_sided=True))
    assert family.scgf_domain(two) == (pytest.approx(-hi), pytest.approx(hi))
    assert family.scgf_domain(m.replace(cubic=0.2)) == (-INF, INF)
    assert family.scgf_domain(Model(1.0, 0.5, 0.2, 5.0)) == (-INF, INF)
    assert np.all(np.isinf(family.scgf(m, [hi, 1.5 * hi])))
    with pytest.raises(ValueError, match="one-sided shot noise"):
        family.rate_function_asymptote(two)


def test_ou_shot_scgf_and_rate_function_up_to_the_pole():
    """Delta = 0: lambda(k) = k F a tau + rate (1/(1 - c mu) - 1), c = k F tau, and its Legendre
    transform J(w) = (sqrt(B) - sqrt(rate))^2, B = (w - F a tau) k_pole (maximiser
    1 - c mu = sqrt(rate/B): w = 1000 puts it at 1 - c mu = 0.02)."""
    lam, mu, a = 2.0, 0.3, 0.5
    m = Model(1.0, 0.0, a, INF, shot=ShotNoise(lam, mu))
    F = m.force
    kp, rate = family.rate_function_asymptote(m)
    assert rate == lam and kp == pytest.approx(1.0 / (F * mu))
    ks = kp * np.array([0.5, 0.9, 0.99, 0.999])
    ref = ks * F * a + lam * (1.0 / (1.0 - ks * F * mu) - 1.0)
    assert np.allclose(family.scgf(m, ks), ref, rtol=1e-9, atol=0)
    w = np.array([0.45, 0.8, 10.0, 1000.0])
    B = (w - F * a) * kp
    got = family.rate_function(m, w)
    ref = (np.sqrt(B) - math.sqrt(lam)) ** 2
    # w < <w> = 0.55 (k < 0, the tilted generator's grid, first order + Richardson): measured
    # 2.2e-5; above (k > 0, the kick-transformed grid, exact for Delta = 0): 5e-12
    assert got[0] == pytest.approx(ref[0], rel=1e-4)
    assert np.allclose(got[1:], ref[1:], rtol=1e-9, atol=0)


def test_coulomb_shot_scgf_is_convex_and_tends_to_its_far_field_form():
    """lambda(k) - rate (1/u - 1), u = 1 - k/k_pole, is the principal eigenvalue of a generator
    plus the potential c (f + v/tau_m), bounded by c (a - Delta) (v > 0) and max(c (a + Delta),
    0) (v < 0, stuck); near the pole the transformed law lives at large v, so it tends to
    c (a - Delta).  lambda is convex up to k = 0.999 k_pole."""
    m = SHOT
    kp, rate = family.rate_function_asymptote(m)
    frac = np.r_[-1.0, -0.5, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99, 0.999]
    lam = family.scgf(m, frac * kp)
    k = frac * kp
    slopes = np.diff(lam) / np.diff(k)
    assert np.all(np.diff(slopes) > 0)
    c = k * m.force * m.tau_m
    rest = lam - rate * (1.0 / (1.0 - frac) - 1.0)
    pos = frac > 0
    assert np.all(rest[pos] >= c[pos] * (m.a - m.delta) - 1e-9)
    assert np.all(rest[pos] <= np.maximum(c[pos] * (m.a + m.delta), 0.0) + 1e-9)
    far = frac >= 0.9
    assert np.allclose(rest[far], c[far] * (m.a - m.delta), rtol=0, atol=1e-7)


def test_coulomb_shot_rate_function_far_branch_closed_form():
    """Where the Legendre maximiser lies in the far field (1 - c mu < 0.1), lambda =
    rate (1/u - 1) + c (a - Delta) exactly (previous test), so J is the Delta = 0 form with
    a -> a - Delta: (sqrt(B) - sqrt(rate))^2, B = (w - F tau (a - Delta)) k_pole; its slope tends
    to k_pole.  Below it, J is convex and 0 at the mean work rate."""
    m = SHOT
    kp, rate = family.rate_function_asymptote(m)
    F = m.force
    w = np.array([5.0, 20.0])
    B = (w - F * m.tau_m * (m.a - m.delta)) * kp
    assert np.allclose(family.rate_function(m, w), (np.sqrt(B) - math.sqrt(rate)) ** 2,
                       rtol=1e-8)
    mean = F * family.stationary_moments(m).mean
    ws = mean * np.array([0.5, 1.0, 2.0, 4.0, 8.0])
    J = family.rate_function(m, ws)
    assert J[1] == 0.0 and np.all(J[[0, 2, 3, 4]] > 0)
    assert np.all(np.diff(np.diff(J) / np.diff(ws)) > 0)


def test_coulomb_shot_scgf_kick_transform_agrees_with_the_direct_tilted_generator():
    """At moderate k both routes are valid: the transformed member's grid (used for k F > 0)
    and the tilted generator L + k F v on the member's own grid (measured 4.1e-5 apart at
    k = 0.3 k_pole).  lambda'(0) from the two sides (direct for k < 0, transformed for k > 0)
    is F <v> of stationary_moments (measured 8e-6 apart)."""
    m = SHOT
    kp, _ = family.rate_function_asymptote(m)
    k = 0.3 * kp
    h = default_spacing(m)
    direct = []
    for hh in (h, h / 2.0):
        g = shot_generator(m, hh)
        pot = k * m.force * g.v
        direct.append(family._principal(g, pot, float(pot.max()), 0.1))
    assert float(family.scgf(m, k)) == pytest.approx(2 * direct[1] - direct[0], rel=2e-4)
    d = 1e-2
    lp, lm = family.scgf(m, [d, -d])
    assert (lp - lm) / (2 * d) == pytest.approx(m.force * family.stationary_moments(m).mean,
                                                rel=1e-4)


@pytest.mark.slow
@pytest.mark.parametrize("frac", [0.2, -0.5])
def test_coulomb_shot_scgf_against_monte_carlo(frac):
    """(1/T) ln E exp(k W_T) from the stationary state, T = 10 and 20 (exact event-driven
    Monte Carlo), extrapolated linearly in 1/T to lambda(k); tolerance 4 standard errors
    (delta method).  k = 0.2 k_pole (the change of measure; 2k stays in the domain, finite
    variance) and k = -0.5 k_pole (the tilted generator with the transient states moved away);
    measured z = 1.6 and 0.9."""
    m = SHOT
    kp, _ = family.rate_function_asymptote(m)
    k = frac * kp
    est = []
    for T, seed in ((10.0, 1), (20.0, 2)):
        e = simulate_sde(m, v0="stationary", t_end=T, replicas=40000, seed=seed, sample_dt=T)
        y = np.exp(k * m.force * e.x[:, -1])
        est.append((math.log(y.mean()) / T, y.std() / y.mean() / math.sqrt(y.size) / T))
    ext = 2 * est[1][0] - est[0][0]
    se = math.hypot(2 * est[1][1], est[0][1])
    assert abs(ext - float(family.scgf(m, k))) < 4 * se


def test_scgf_far_below_zero_respects_the_metzler_bounds_and_the_closed_form():
    """k F -> -inf: the kicks' generating function -> 0, so lambda(k) -> k F v_edge - rate from
    above; for the sticking member v_edge = 0 and lambda decreases to -rate = -1 (the former
    shift gave lambda(-1000) = -11.4 and lambda(-1e4) = -1478).  Delta = 0 against the closed
    form at k F = -300."""
    m = SHOT
    lam = family.scgf(m, [-10.0, -100.0, -1000.0, -1e4])
    assert np.all(np.diff(lam) < 0) and np.all(lam > -1.0) and lam[-1] < -0.95
    ou = Model(1.0, 0.0, 0.5, INF, shot=ShotNoise(2.0, 0.3))
    k = -300.0 / ou.force
    ref = k * ou.force * 0.5 + 2.0 * (1.0 / (1.0 - k * ou.force * 0.3) - 1.0)
    assert float(family.scgf(ou, k)) == pytest.approx(ref, rel=1e-4)


def test_rate_function_at_and_beyond_the_lower_edge_of_the_work():
    """One-sided kicks: the recurrent velocities are >= v_edge (the highest attractor), so
    W/tau >= F v_edge, J(F v_edge) = rate (no kick at all) and +inf below.  Delta = 0: the
    closed form (sqrt(B) - sqrt(rate))^2 (B = (w - F a tau) k_pole) near the edge too."""
    m = SHOT
    assert family.work_edge(m) == 0.0
    J = family.rate_function(m, [-1e-3, 0.0, 1e-5, 1e-3])
    assert J[0] == INF and J[1] == 1.0 and 0.0 < J[3] < J[2] < 1.0
    ou = Model(1.0, 0.0, 0.5, INF, shot=ShotNoise(2.0, 0.3))
    kp, lam = family.rate_function_asymptote(ou)
    edge = family.work_edge(ou)
    assert edge == pytest.approx(ou.force * 0.5)
    w = edge + np.array([0.0, 1e-3, 1e-2])
    ref = (np.sqrt((w - edge) * kp) - math.sqrt(lam)) ** 2
    assert np.allclose(family.rate_function(ou, w), ref, rtol=2e-4)
    assert family.work_edge(Model(1.0, 0.5, 0.2, INF, shot=ShotNoise(1.0, 0.5, True))) is None
    assert family.work_edge(Model(1.0, 0.5, 0.2, 5.0, shot=ShotNoise(1.0, 0.5))) is None


@pytest.mark.parametrize("n,h", [(60, 0.05), (200, 0.01)])
def test_asymmetric_kicks_kernel_is_stochastic_and_its_banded_form_exact(n, h):
    """The two-sided transform needs kicks up and down with different weights and means."""
    from analogue.theory.kolmogorov_feller import (Kicks, banded_kicks_kernel, kicks_kernel,
                                                   kicks_premultiplier)
    for k in (Kicks(2.0, 0.3, 0.9, 0.7, 0.2), Kicks(1.0, 0.95, 0.05, 0.05, 3.0)):
        K = kicks_kernel(k, h, n).toarray()
        assert np.allclose(K.sum(axis=0), 1.0, atol=1e-14) and K.min() >= 0
        N = kicks_premultiplier(k, h, n)
        assert np.abs(banded_kicks_kernel(k, h, n).toarray() - N @ K).max() < 1e-13


@pytest.mark.slow
def test_two_sided_scgf_up_to_both_poles():
    """Two-sided kicks: M(c) = 1/(1 - c^2 mean^2), poles at c mean = +-1.  Delta = 0: the
    closed form k F a tau + rate (M - 1) (the direct tilted generator was 31 % off at
    -0.5 k_pole, 88-91 % at +-0.99; now <= 3e-8).  Delta > 0: near the pole c mean -> +-1 the
    transformed law lives at v -> +-inf, where f + v/tau_m = a -+ Delta (measured 5e-8);
    lambda'(0) = F <v> and lambda''(0) = 2 F^2 D_x of stationary_moments (5e-5, 1.3e-4)."""
    ou = Model(1.0, 0.0, 0.5, INF, shot=ShotNoise(2.0, 0.3, True))
    F = ou.force
    kp = 1.0 / (F * 0.3)
    assert family.scgf_domain(ou) == (pytest.approx(-kp), pytest.approx(kp))
    frac = np.array([-0.99, -0.9, -0.5, 0.5, 0.9, 0.99])
    c = frac * kp * F
    ref = c * 0.5 + 2.0 * (1.0 / (1.0 - (c * 0.3) ** 2) - 1.0)
    assert np.allclose(family.scgf(ou, frac * kp), ref, rtol=1e-7, atol=0)
    m = ou.replace(delta=0.5, a=0.2)
    F = m.force
    kp = 1.0 / (F * 0.3)
    frac = np.array([-0.99, -0.9, 0.9, 0.99])
    c = frac * kp * F
    lam = family.scgf(m, frac * kp)
    far = np.where(c > 0, c * (m.a - m.delta), c * (m.a + m.delta))
    assert np.allclose(lam - 2.0 * (1.0 / (1.0 - (c * 0.3) ** 2) - 1.0), far, rtol=0, atol=1e-6)
    s = family.stationary_moments(m)
    d = 0.02
    lp, lm = family.scgf(m, [d, -d])
    assert (lp - lm) / (2 * d) == pytest.approx(F * s.mean, rel=5e-4)
    assert (lp + lm) / d**2 == pytest.approx(2 * F**2 * s.diffusion, rel=1e-3)


@pytest.mark.parametrize("two_sided", [False, True])
def test_shot_plus_gaussian_scgf_closed_form_and_derivatives(two_sided):
    """Gaussian noise (gamma = 5) and kicks: the change of measure adds the drift 2c/gamma and
    the constant c^2/gamma.  Delta = 0: lambda = c a + c^2/gamma + rate (M(c) - 1) (the direct
    route did not converge at -0.9 k_pole; now <= 6e-8); Delta = 0.5: lambda'(0) = F <v>."""
    ou = Model(1.0, 0.0, 0.5, 5.0, shot=ShotNoise(2.0, 0.3, two_sided))
    F = ou.force
    kp = 1.0 / (F * 0.3)
    frac = np.array([-0.9, -0.5, 0.5, 0.9, 0.99])
    c = frac * kp * F
    M = 1.0 / (1.0 - (c * 0.3) ** 2) if two_sided else 1.0 / (1.0 - c * 0.3)
    ref = c * 0.5 + c * c / 5.0 + 2.0 * (M - 1.0)
    assert np.allclose(family.scgf(ou, frac * kp), ref, rtol=3e-7, atol=0)
    m = ou.replace(delta=0.5, a=0.2)
    d = 0.02
    lp, lm = family.scgf(m, [d, -d])
    assert (lp - lm) / (2 * d) == pytest.approx(m.force * family.stationary_moments(m).mean,
                                                rel=5e-4)
