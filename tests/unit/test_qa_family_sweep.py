"""Seeded random sweep of the model family off the shipped parameters (issue 9 QA).

Independent routes only: the stationary law exp(-gamma U) of Gaussian members by a few-line
Simpson quadrature written here (not the package's), closed forms (Gamma law of one-sided
exponential kicks with linear friction, OU moments with shot + Gaussian noise), exact
symmetries, the propagator's normalisation and its t -> inf limit, the SCGF identities.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, special

from analogue import Model, ShotNoise
from analogue.theory import exact
from analogue.theory import family

INF = math.inf


# ------------------------------------------------------------------ independent reference
def _potential(v, tau, delta, a, cubic, stribeck):
    u = v * v / (2 * tau) + cubic * v**4 / 4 + delta * np.abs(v) - a * v
    if stribeck is not None:
        ds, vs = stribeck
        u = u + (ds - delta) * vs * (1.0 - np.exp(-np.abs(v) / vs))
    return u


def _quadrature_moments(tau, delta, a, gamma, cubic, stribeck):
    """mean, variance, P(v > 0) of exp(-gamma U)/Z by Simpson on each half line (kink at 0)."""
    reach = 2 * tau * abs(a) + math.sqrt(160 * tau / gamma) + 1.0
    halves = [np.linspace(0.0, reach, 200_001), np.linspace(-reach, 0.0, 200_001)]
    u0 = min(float(np.min(gamma * _potential(x, tau, delta, a, cubic, stribeck))) for x in halves)
    z, m1, m2 = [], 0.0, 0.0
    for x in halves:
        w = np.exp(-(gamma * _potential(x, tau, delta, a, cubic, stribeck) - u0))
        z.append(integrate.simpson(w, x=x))
        m1 += integrate.simpson(w * x, x=x)
        m2 += integrate.simpson(w * x * x, x=x)
    total = z[0] + z[1]
    mean = m1 / total
    return mean, m2 / total - mean * mean, z[0] / total


def _gaussian_sweep(n=18, seed=20261123):
    """Both signs of a, |a| < Delta and > Delta, Delta = 0, Stribeck weakening/strengthening
    with small and large v_s, cubic 0.01..10, gamma 1..100."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        tau = float(10 ** rng.uniform(-0.5, 0.5))
        delta = 0.0 if i % 3 == 0 else float(10 ** rng.uniform(-1, 0.5))
        ratio = (0.3, 0.8, 1.5, 3.0)[i % 4]
        mag = delta * ratio if delta else float(10 ** rng.uniform(-1, 0.3))
        a = mag * (1 if i % 2 else -1)
        gamma = float(10 ** rng.uniform(0, 2))
        cubic = (0.0, 0.01, 0.3, 10.0)[(i // 2) % 4]
        stribeck = None
        if i % 5 != 4:
            weak = (0.0, 0.4, 2.5, 4.0)[i % 4]  # < 1: strengthening, > 1: weakening
            ds = delta * weak if delta else float(rng.uniform(0.1, 1.0))
            stribeck = (ds, (0.01, 0.2, 5.0)[i % 3])
        if cubic == 0 and stribeck is None:
            cubic = 0.05
        out.append(dict(tau_m=tau, delta=delta, a=a, gamma=gamma, cubic=cubic,
                        stribeck=stribeck))
    return out


GAUSSIAN = _gaussian_sweep()


@pytest.mark.parametrize("p", GAUSSIAN, ids=[f"g{i}" for i in range(len(GAUSSIAN))])
def test_gaussian_member_matches_independent_quadrature(p):
    got = exact.stationary_moments(Model(**p))
    mean, var, pp = _quadrature_moments(p["tau_m"], p["delta"], p["a"], p["gamma"],
                                        p["cubic"], p["stribeck"])
    assert got.mean == pytest.approx(mean, abs=1e-8 * math.sqrt(var))
    assert got.variance == pytest.approx(var, rel=1e-7)
    assert got.p_positive == pytest.approx(pp, abs=1e-8)
    assert got.p_zero == 0.0
    assert got.p_positive + got.p_negative == pytest.approx(1.0, abs=1e-10)


# ------------------------------------------------------------------ closed forms
GAMMA_LAW = [(tau, a, lam, mu) for tau in (0.5, 2.0) for a in (-0.3, 0.0, 0.37)
             for lam, mu in ((0.5, 0.3), (0.2, 1.0), (5.0, 0.2), (2.0, 1.0))]


@pytest.mark.parametrize("tau,a,lam,mu", GAMMA_LAW)
def test_one_sided_kicks_linear_friction_is_a_shifted_gamma_law(tau, a, lam, mu):
    """Delta = 0, gamma = inf: v - a tau ~ Gamma(shape rate tau, scale mean).  rate tau < 1
    makes the density singular at the attractor a tau (regression: the attractor sat inside a
    cell and the mean was off by 1.3e-2 standard deviations)."""
    m = Model(tau_m=tau, delta=0.0, a=a, gamma=INF, shot=ShotNoise(lam, mu))
    got = exact.stationary_moments(m)
    mean, var = tau * (a + lam * mu), lam * tau * mu * mu
    pp = special.gammaincc(lam * tau, max(-a * tau, 0.0) / mu)
    # documented accuracy of the shot-noise moments: 2e-4
    assert got.mean == pytest.approx(mean, abs=2e-4 * math.sqrt(var))
    assert got.variance == pytest.approx(var, rel=2e-4)
    assert got.p_positive == pytest.approx(pp, abs=2e-4)
    assert got.p_zero == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("two_sided", [False, True])
@pytest.mark.parametrize("gamma", [1.0, 100.0])
@pytest.mark.parametrize("lam,mu", [(0.3, 0.5), (20.0, 0.05)])
def test_shot_plus_gaussian_linear_friction_ou_moments(two_sided, gamma, lam, mu):
    """Delta = 0: linear SDE, <v> = tau (a + rate <z>), Var v = tau (1/gamma + rate <z^2>/2)."""
    tau, a = 0.7, -0.4
    m = Model(tau_m=tau, delta=0.0, a=a, gamma=gamma, shot=ShotNoise(lam, mu, two_sided))
    got = exact.stationary_moments(m)
    mean = tau * (a + (0.0 if two_sided else lam * mu))
    var = tau * (1.0 / gamma + lam * mu * mu)
    assert got.mean == pytest.approx(mean, abs=2e-4 * math.sqrt(var))
    assert got.variance == pytest.approx(var, rel=2e-4)


# ------------------------------------------------------------------ symmetry
SYMMETRIC = [
    dict(tau_m=1.0, delta=0.5, a=0.2, gamma=30.0, cubic=0.05, shot=ShotNoise(4.0, 0.1, True)),
    dict(tau_m=1.0, delta=0.5, a=-0.8, gamma=INF, stribeck=(0.2, 2.0),
         shot=ShotNoise(4.0, 0.1, True)),
    dict(tau_m=0.8, delta=0.3, a=0.9, gamma=5.0, stribeck=(1.2, 0.1)),
    dict(tau_m=1.3, delta=0.0, a=-0.4, gamma=INF, cubic=2.0, shot=ShotNoise(0.3, 0.6, True)),
]


@pytest.mark.parametrize("p", SYMMETRIC, ids=[f"s{i}" for i in range(len(SYMMETRIC))])
def test_mirror_symmetry(p):
    """(v, v0, a) -> (-v, -v0, -a) maps the model onto itself for symmetric noise."""
    m = Model(**p)
    mirror = m.replace(a=-m.a)
    s, r = exact.stationary_moments(m), exact.stationary_moments(mirror)
    assert s.mean == pytest.approx(-r.mean, abs=1e-8)
    assert s.variance == pytest.approx(r.variance, rel=1e-8)
    assert s.p_positive == pytest.approx(r.p_negative, abs=1e-8)
    # v = 0 left out: with gamma = inf the density jumps there (the sgn law) and its value at
    # the jump is a convention (right limit), which the mirror turns into the left limit
    v = np.linspace(-2.0, 2.0, 40)
    f = exact.propagator(m, v, 0.7, v0=0.3)
    g = exact.propagator(mirror, -v, 0.7, v0=-0.3)
    assert np.max(np.abs(f - g)) < 1e-6 * np.max(f)


# ------------------------------------------------------------------ propagator
PROPAGATED = [
    dict(tau_m=1.0, delta=0.5, a=0.8, gamma=30.0, stribeck=(0.2, 0.05), shot=ShotNoise(4.0, 0.1)),
    dict(tau_m=1.0, delta=0.5, a=-0.2, gamma=INF, cubic=0.05, stribeck=(1.0, 2.0),
         shot=ShotNoise(4.0, 0.1)),
    dict(tau_m=1.0, delta=0.5, a=0.2, gamma=2.0, cubic=3.0, shot=ShotNoise(4.0, 0.1, True)),
    dict(tau_m=1.0, delta=0.0, a=0.2, gamma=INF, shot=ShotNoise(4.0, 0.1, True)),
    dict(tau_m=1.0, delta=0.7, a=0.3, gamma=3.0, cubic=0.5, stribeck=(1.5, 0.3)),
]


@pytest.mark.parametrize("p", PROPAGATED, ids=[f"p{i}" for i in range(len(PROPAGATED))])
def test_propagator_normalised_and_relaxes_to_stationary_law(p):
    m = Model(**p)
    v = np.linspace(-6.0, 6.0, 24_001)
    t = np.array([0.5, 25.0])
    f = exact.propagator(m, v, t, v0=0.3)
    atom = np.atleast_1d(exact.propagator_atom(m, t, v0=0.3))
    mass = integrate.trapezoid(f, v, axis=-1) + atom
    if m.shot is not None and not math.isfinite(m.gamma):
        vd, unkicked = family.unkicked(m, t, 0.3)
        mass = mass + np.where(vd == 0.0, 0.0, unkicked)  # the moving unkicked delta
    assert mass == pytest.approx(1.0, abs=2e-3)
    s = exact.stationary_moments(m)
    mean = integrate.trapezoid(f[1] * v, v)
    var = integrate.trapezoid(f[1] * v * v, v) - mean**2
    assert atom[1] == pytest.approx(s.p_zero, abs=2e-3)
    assert mean == pytest.approx(s.mean, abs=3e-3 * math.sqrt(s.variance))
    assert var == pytest.approx(s.variance, rel=5e-3)


# ------------------------------------------------------------------ SCGF
SCGF = [
    dict(tau_m=1.0, delta=0.5, a=0.2, gamma=2.0, cubic=3.0, shot=ShotNoise(4.0, 0.1, True)),
    dict(tau_m=1.0, delta=0.5, a=-0.8, gamma=2.0, stribeck=(1.0, 0.05),
         shot=ShotNoise(4.0, 0.1, True)),
    dict(tau_m=1.0, delta=0.5, a=-0.2, gamma=INF, cubic=0.05, stribeck=(1.0, 2.0),
         shot=ShotNoise(4.0, 0.1)),
    dict(tau_m=2.0, delta=0.4, a=1.0, gamma=10.0, cubic=0.3, stribeck=(0.9, 0.5)),
    dict(tau_m=0.5, delta=0.0, a=-0.3, gamma=INF, shot=ShotNoise(0.5, 0.3)),
]


@pytest.mark.parametrize("p", SCGF, ids=[f"k{i}" for i in range(len(SCGF))])
def test_scgf_vanishes_at_zero_and_its_slope_is_the_mean_power(p):
    m = Model(**p)
    s = exact.stationary_moments(m)
    k = 0.02
    lam = exact.scgf(m, np.array([-2 * k, -k, 0.0, k, 2 * k]))
    assert lam[2] == pytest.approx(0.0, abs=1e-6)
    # fourth-order central difference (the eigenvalues carry ~1e-7 absolute noise, so k is
    # not taken smaller)
    slope = (8 * (lam[3] - lam[1]) - (lam[4] - lam[0])) / (12 * k)
    assert slope == pytest.approx(m.mass * m.a * s.mean, abs=1e-3 * abs(m.a) * math.sqrt(s.variance))


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("kwargs,exc,name", [
    (dict(cubic="x"), TypeError, "cubic"),
    (dict(cubic=-0.1), ValueError, "cubic"),
    (dict(cubic=math.nan), ValueError, "cubic"),
    (dict(stribeck=1.0), TypeError, "stribeck"),
    (dict(stribeck=(1.0,)), TypeError, "stribeck"),
    (dict(stribeck="ab"), TypeError, "stribeck"),
    (dict(stribeck=(-1.0, 1.0)), ValueError, "delta_s"),
    (dict(stribeck=(1.0, 0.0)), ValueError, "v_s"),
    (dict(stribeck=(1.0, "x")), TypeError, "v_s"),
    (dict(spring=-1.0), ValueError, "spring"),
    (dict(spring=None), TypeError, "spring"),
    (dict(x0=math.inf), ValueError, "x0"),
    (dict(x0="0"), TypeError, "x0"),
    (dict(shot="poisson"), TypeError, "shot"),
    (dict(shot=3.0), TypeError, "shot"),
    (dict(gamma=0.0), ValueError, "gamma"),
    (dict(gamma=-math.inf), ValueError, "gamma"),
    (dict(gamma="inf"), TypeError, "gamma"),
])
def test_bad_family_field_names_itself(kwargs, exc, name):
    base = dict(tau_m=1.0, delta=0.5, a=0.2, gamma=10.0)
    base.update(kwargs)
    with pytest.raises(exc, match=name):
        Model(**base)


@pytest.mark.parametrize("kwargs,exc,name", [
    (dict(rate=0.0, mean=1.0), ValueError, "shot.rate"),
    (dict(rate=-1.0, mean=1.0), ValueError, "shot.rate"),
    (dict(rate="1", mean=1.0), TypeError, "shot.rate"),
    (dict(rate=1.0, mean=0.0), ValueError, "shot.mean"),
    (dict(rate=1.0, mean=math.inf), ValueError, "shot.mean"),
    (dict(rate=1.0, mean=None), TypeError, "shot.mean"),
    (dict(rate=1.0, mean=1.0, two_sided="yes"), TypeError, "two_sided"),
    (dict(rate=1.0, mean=1.0, two_sided=1), TypeError, "two_sided"),
])
def test_bad_shot_field_names_itself(kwargs, exc, name):
    with pytest.raises(exc, match=name):
        ShotNoise(**kwargs)
    with pytest.raises(exc, match=name):  # the mapping form goes through the same checks
        Model(tau_m=1.0, delta=0.5, a=0.2, gamma=INF, shot=kwargs)


def test_exact_theory_refuses_spring_and_noise_free_members_naming_the_field():
    with pytest.raises(ValueError, match="spring"):
        exact.stationary_moments(Model(tau_m=1.0, delta=0.5, a=0.2, gamma=10.0, spring=1.0))
    with pytest.raises(ValueError, match="gamma"):
        exact.stationary_moments(Model(tau_m=1.0, delta=0.5, a=0.2, gamma=INF, cubic=1.0))


# ------------------------------------------------------------------ Monte Carlo (slow)
# Members whose flow between kicks has a closed form (no cubic/Stribeck): the event-driven MC
# is then exact and fast (the other 1-D members use the tabulated flow, ~1e-9; RK4 between
# kicks, still used with a spring, took 21 s for 200 replicas over 10 tau_m).
MC = [
    # stick regime: the atom at 0; one-sided, small rate*mean
    dict(tau_m=1.0, delta=0.5, a=0.2, gamma=INF, shot=ShotNoise(0.8, 0.3)),
    # two-sided, slip regime a < -Delta
    dict(tau_m=1.0, delta=0.3, a=-0.6, gamma=INF, shot=ShotNoise(0.5, 0.4, True)),
    # one-sided against the force, large rate*mean, rate tau_m > 1
    dict(tau_m=0.5, delta=1.0, a=-0.5, gamma=INF, shot=ShotNoise(10.0, 0.4)),
    # two-sided in the stick regime, |a| < Delta
    dict(tau_m=2.0, delta=0.4, a=-0.3, gamma=INF, shot=ShotNoise(2.0, 0.5, True)),
    # shot + Gaussian (time-stepped, dt = 0.002 by default; ~9 s each with 20000 replicas)
    dict(tau_m=1.0, delta=0.5, a=0.2, gamma=10.0, shot=ShotNoise(0.8, 0.3)),
    dict(tau_m=1.0, delta=0.3, a=-0.6, gamma=3.0, shot=ShotNoise(2.0, 0.4, True)),
]


@pytest.mark.slow
@pytest.mark.parametrize("p", MC, ids=[f"mc{i}" for i in range(len(MC))])
def test_pure_shot_moments_against_event_driven_monte_carlo(p):
    """Replicas started at 0 and read after 15 tau_m (relaxation ~e^{-15}) are independent
    draws from the stationary law; tolerances 5 standard errors."""
    from analogue.montecarlo import simulate_sde
    m = Model(**p)
    s = exact.stationary_moments(m)
    t_end = 15.0 * m.tau_m
    replicas = 40_000 if math.isinf(m.gamma) else 20_000
    ens = simulate_sde(m, v0=0.0, t_end=t_end, replicas=replicas, seed=9, sample_dt=t_end)
    v = np.asarray(ens.v)[:, -1]
    n = v.size
    assert abs(v.mean() - s.mean) < 5 * math.sqrt(s.variance / n)
    mu4 = float(np.mean((v - v.mean()) ** 4))  # SE of the sample variance
    assert abs(v.var() - s.variance) < 5 * math.sqrt(max(mu4 - s.variance**2, 0.0) / n)
    for got, want in ((np.mean(v > 0), s.p_positive), (np.mean(v == 0), s.p_zero)):
        assert abs(got - want) < 5 * math.sqrt(max(want * (1 - want), 1.0 / n) / n)
