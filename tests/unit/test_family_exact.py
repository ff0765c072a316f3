"""Exact numerics of the model family (analogue.theory.family / kolmogorov_feller) against
closed forms and identities that do not use the code under test."""
import math

import numpy as np
import pytest
from scipy import integrate, special

from analogue import Model, ShotNoise
from analogue.theory import exact, family
from analogue.theory.kolmogorov_feller import banded_jump_kernel, jump_kernel, premultiplier

INF = math.inf


@pytest.mark.parametrize("two_sided", [False, True])
@pytest.mark.parametrize("n,r", [(40, 0.3), (200, 0.05)])
def test_jump_kernel_is_stochastic_and_banded_form_is_exact(two_sided, n, r):
    h, mean = r, 1.0
    K = jump_kernel(mean, h, n, two_sided)
    assert np.allclose(np.asarray(K.sum(axis=0)).ravel(), 1.0, atol=1e-13)
    assert K.min() >= 0.0
    N = premultiplier(mean, h, n, two_sided)
    assert abs(banded_jump_kernel(mean, h, n, two_sided) - N @ K).max() < 1e-12


def test_jump_kernel_cell_average_matches_quadrature():
    """P(v + z in cell d) for v uniform in cell 0, z ~ Exp(mean): independent double integral."""
    h, mean = 0.2, 0.5
    K = jump_kernel(mean, h, 30, False).toarray()
    for d in (0, 1, 4):
        val, _ = integrate.dblquad(lambda z, v: math.exp(-z / mean) / mean / h, 0.0, h,
                                   lambda v: max(d * h - v, 0.0), lambda v: (d + 1) * h - v)
        assert K[d, 0] == pytest.approx(val, rel=1e-9)


@pytest.mark.parametrize("a", [0.0, 0.4])
def test_shot_ou_stationary_law_is_a_gamma_law(a):
    """Delta = 0, one-sided exponential kicks: v - a tau_m ~ Gamma(rate tau_m, mean)."""
    lam, mu, tau = 2.0, 0.3, 1.0
    m = Model(tau, 0.0, a, INF, shot=ShotNoise(lam, mu))
    s = exact.stationary_moments(m)
    assert s.mean == pytest.approx(a * tau + lam * tau * mu, abs=2e-4)
    assert s.variance == pytest.approx(lam * tau * mu**2, rel=5e-4)  # measured 2.1e-4 (O(h^2) left)
    assert s.p_zero == pytest.approx(0.0, abs=1e-9)
    assert s.p_positive == pytest.approx(1.0, abs=1e-9)
    # Green-Kubo: C(t) = var e^{-t/tau} for this linear process, so D_x = var tau
    assert s.diffusion == pytest.approx(lam * tau * mu**2 * tau, rel=5e-4)
    # the cells carry averages: compare with the Gamma law's cell averages (CDF differences).
    # The upwind scheme is first order (single grid: 3.9 %, 2.2 %, 1.2 % of the peak at
    # h = mean/25, /50, /100); the law is Richardson-extrapolated over (h, h/2) (measured
    # 0.22 %, 0.076 %, 0.025 % (a = 0), largest next to the lower edge of the support)
    cdf = lambda x: special.gammainc(lam * tau, np.clip(x - a * tau, 0, None) / mu)  # noqa: E731
    errs = []
    for h in (mu / 25, mu / 100):
        v, dens, atom = family.stationary_law(m, h)
        ref = (cdf(v + h / 2) - cdf(v - h / 2)) / h
        errs.append(np.max(np.abs(dens - ref)) / ref.max())
        assert atom == pytest.approx(0.0, abs=1e-12)
    assert errs[0] < 5e-3 and errs[1] < 0.25 * errs[0]  # two halvings: measured 0.11, 0.13


def test_two_sided_shot_ou_variance():
    """Delta = 0, two-sided: cumulant generating function -(rate tau/2) ln(1 + mu^2 k^2) gives
    mean a tau and variance rate tau mu^2."""
    m = Model(1.0, 0.0, 0.25, INF, shot=ShotNoise(3.0, 0.2, two_sided=True))
    s = exact.stationary_moments(m)
    assert s.mean == pytest.approx(0.25, abs=2e-4)
    assert s.variance == pytest.approx(3.0 * 0.04, rel=3e-4)


@pytest.mark.parametrize("a,lam,mu", [(0.2, 2.0, 0.3), (-0.3, 0.7, 0.5)])
def test_stick_atom_and_mean_from_the_ode_reduction(a, lam, mu):
    """One-sided exponential kicks, |a| < Delta: applying (1 + mu d/dv) to the stationary
    Kolmogorov-Feller equation on v > 0 gives p(v) = C e^{-v/mu} (1 + v/(b tau))^{lam tau - 1},
    b = Delta - a, and the balance of the stuck state gives rate P0 = b C."""
    tau, d = 1.0, 0.7
    b = d - a
    m = Model(tau, d, a, INF, shot=ShotNoise(lam, mu))
    shape = lambda v: math.exp(-v / mu) * (1 + v / (b * tau)) ** (lam * tau - 1)  # noqa: E731
    i0, _ = integrate.quad(shape, 0, np.inf, epsabs=0, epsrel=1e-12)
    i1, _ = integrate.quad(lambda v: v * shape(v), 0, np.inf, epsabs=0, epsrel=1e-12)
    i2, _ = integrate.quad(lambda v: v * v * shape(v), 0, np.inf, epsabs=0, epsrel=1e-12)
    p0 = 1.0 / (1.0 + lam / b * i0)
    c = lam * p0 / b
    s = exact.stationary_moments(m)
    assert s.p_zero == pytest.approx(p0, abs=1e-4)
    assert s.mean == pytest.approx(c * i1, abs=1e-4)
    assert s.variance == pytest.approx(c * i2 - (c * i1) ** 2, abs=2e-4)
    assert s.p_negative == pytest.approx(0.0, abs=1e-9)
    assert s.p_positive + s.p_zero == pytest.approx(1.0, abs=1e-12)


def test_gaussian_members_grid_moments_agree_with_quadrature():
    """Two routes for the Gaussian members: quadrature of exp(-gamma U) and the stationary
    vector of the Scharfetter-Gummel grid (Richardson over h, h/2)."""
    for m in (Model(1.0, 0.7, 0.9, 10.0, stribeck=(1.0, 0.2)), Model(1.0, 0.5, 0.2, 5.0, cubic=0.8)):
        h = 0.01
        c, f = family._grid_moments(m, h), family._grid_moments(m, h / 2)
        grid = (4 * f - c) / 3
        quad = family._gradient_quadrature(m)
        assert grid[0] == pytest.approx(quad[0], abs=2e-5)
        assert grid[1] - grid[0] ** 2 == pytest.approx(quad[1] - quad[0] ** 2, rel=2e-4)
        assert grid[2] == pytest.approx(quad[2], abs=2e-4)


def test_shot_ou_propagator_moments():
    """Delta = 0: v(t) = v0 e^{-t/tau} + kicks filtered by e^{-(t-s)/tau}:
    mean v0 e^{-t} + rate mu tau (1 - e^{-t}), variance rate mu^2 tau (1 - e^{-2t}) (tau = 1),
    the law = continuous part + the unkicked atom e^{-rate t} at v0 e^{-t}."""
    m = Model(1.0, 0.0, 0.0, INF, shot=ShotNoise(2.0, 0.3))
    ts = np.array([0.3, 1.0, 3.0])
    v = np.linspace(-0.5, 6.0, 6501)
    f = exact.propagator(m, v, ts, 0.5)
    vd, mass = family.unkicked(m, ts, 0.5)
    dv = v[1] - v[0]
    for i, t in enumerate(ts):
        total = f[i].sum() * dv + mass[i]
        mean = ((v * f[i]).sum() * dv + mass[i] * vd[i]) / total
        var = (((v - mean) ** 2 * f[i]).sum() * dv + mass[i] * (vd[i] - mean) ** 2) / total
        assert total == pytest.approx(1.0, abs=2e-3)
        assert mean == pytest.approx(0.5 * math.exp(-t) + 0.6 * (1 - math.exp(-t)), abs=1e-3)
        assert var == pytest.approx(0.18 * (1 - math.exp(-2 * t)), abs=1e-3)


def test_atom_of_the_propagator_tends_to_p_zero_and_starts_at_zero():
    m = Model(1.0, 0.7, 0.2, INF, shot=ShotNoise(2.0, 0.3))
    atom = exact.propagator_atom(m, [0.05, 20.0], 0.5)
    assert atom[0] == pytest.approx(0.0, abs=1e-3)
    assert atom[1] == pytest.approx(exact.stationary_moments(m).p_zero, abs=1e-3)
    # from rest, the unkicked mass stays stuck: P(v(t) = 0) >= e^{-rate t}
    assert exact.propagator_atom(m, 0.2, 0.0) >= math.exp(-0.4) - 1e-3


def test_gaussian_member_propagator_relaxes_to_exp_minus_gamma_u():
    m = Model(1.0, 0.7, 0.9, 10.0, stribeck=(1.0, 0.2))
    v = np.linspace(-1.0, 2.0, 301)
    f = exact.propagator(m, v, 15.0, 1.0)
    ps = m.stationary_pdf(v)
    assert np.max(np.abs(f - ps)) < 2e-3 * ps.max()


def test_spring_and_noise_free_are_refused_by_the_exact_solvers():
    with pytest.raises(ValueError, match="spring > 0"):
        exact.stationary_moments(Model(1.0, 0.7, 0.2, 10.0, spring=1.0))
    with pytest.raises(ValueError, match="noise-free"):
        exact.stationary_moments(Model(1.0, 0.7, 0.2, INF))


def test_family_sample_stationary_matches_moments():
    m = Model(1.0, 0.7, 0.2, INF, shot=ShotNoise(2.0, 0.3))
    x = exact.sample_stationary(m, 40000, seed=3)
    s = exact.stationary_moments(m)
    z_atom = ((x == 0).mean() - s.p_zero) / math.sqrt(s.p_zero * (1 - s.p_zero) / x.size)
    z_mean = (x.mean() - s.mean) / math.sqrt(s.variance / x.size)
    assert abs(z_atom) < 4 and abs(z_mean) < 4


def test_shot_ou_scgf_and_rate_function_closed_form():
    """Delta = 0, one-sided kicks: each kick z adds z tau_m to int v, so
    lambda(k) = k F a tau + rate (1/(1 - k F tau mu) - 1); J(w) its Legendre transform."""
    lam, mu, a = 2.0, 0.3, 0.5
    m = Model(1.0, 0.0, a, INF, shot=ShotNoise(lam, mu))
    F = m.force
    ks = np.array([-0.5, 0.5, 2.0])
    ref = ks * F * a + lam * (1.0 / (1.0 - ks * F * mu) - 1.0)
    got = exact.scgf(m, ks)
    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-4  # measured 4.2e-5 at k = 2, 5e-6 below
    assert float(exact.scgf(m, 0.0)) == pytest.approx(0.0, abs=1e-10)
    from scipy import optimize
    for w in (0.45, 0.8):
        res = optimize.minimize_scalar(
            lambda k: -(k * w - (k * F * a + lam * (1 / (1 - k * F * mu) - 1))),
            bounds=(-60.0, 1 / (F * mu) - 1e-9), method="bounded", options={"xatol": 1e-12})
        assert float(exact.rate_function(m, w)) == pytest.approx(-res.fun, rel=1e-3)


def test_gaussian_member_scgf_derivatives_are_mean_and_green_kubo():
    """lambda'(0) = F <v> (quadrature of exp(-gamma U)) and lambda''(0) = 2 F^2 D_x
    (Green-Kubo from the Poisson equation): independent routes to the same numbers."""
    m = Model(1.0, 0.7, 1.2, 10.0, cubic=0.3)
    s = exact.stationary_moments(m)
    F, d = m.force, 1e-3
    lp, l0, lm = exact.scgf(m, [d, 0.0, -d])
    assert l0 == pytest.approx(0.0, abs=1e-9)
    assert (lp - lm) / (2 * d) == pytest.approx(F * s.mean, rel=1e-5)
    assert (lp - 2 * l0 + lm) / d**2 == pytest.approx(2 * F**2 * s.diffusion, rel=1e-3)


def test_family_autocorrelation_ou_shot_and_green_kubo():
    """Delta = 0: C(t) = rate mu^2 tau e^{-t/tau}; for a Stribeck member the integral of C is the
    Green-Kubo D_x of stationary_moments (Poisson equation: an independent route)."""
    m = Model(1.0, 0.0, 0.3, INF, shot=ShotNoise(2.0, 0.3))
    lags = np.array([0.0, 0.5, 2.0])
    assert np.allclose(exact.autocorrelation(m, lags), 0.18 * np.exp(-lags), atol=3e-4)
    ms = Model(1.0, 0.7, 0.9, 10.0, stribeck=(1.0, 0.2))
    t = np.linspace(0, 12, 241)
    c = exact.autocorrelation(ms, t)
    assert c[0] == pytest.approx(exact.stationary_moments(ms).variance, rel=1e-3)
    assert np.trapezoid(c, t) == pytest.approx(exact.stationary_moments(ms).diffusion, rel=2e-3)


def test_paper_only_functions_refuse_family_members():
    from analogue.theory import weak_noise
    m = Model(1.0, 0.7, 0.2, 10.0, cubic=0.5)
    with pytest.raises(ValueError, match="weak_noise_family"):
        weak_noise.action(m, 0.5, 1.0, 0.2)
    with pytest.raises(ValueError, match="paper's model only"):
        exact.work_pdf(m, 0.1, 1.0)


def test_smooth_law_moments_two_routes():
    """epsilon > 0: Simpson on the cumulative drift against quadrature of the closed-form
    (Gauss-Legendre) potential."""
    m = Model(2.0, 0.3, 0.7, 10.0, stribeck=(1.0, 0.2), epsilon=0.02)
    a = family._gradient_smooth_moments(m)
    b = family._gradient_quadrature(m)
    assert np.allclose(a[:4], b[:4], rtol=1e-7, atol=1e-9)
