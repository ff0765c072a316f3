"""Exact stationary observables: closed forms vs quadrature, OU limits, identities, sampling."""
import math

import numpy as np
import pytest
from scipy import integrate, special, stats

from analogue import Model
from analogue.theory import exact
from analogue.theory.stationary import half_line_moments

PARAMS = [  # (a, eps, gamma): stick and slip, both friction laws, both signs of a
    (0.2, 0.0, 10.0), (1.2, 0.0, 10.0), (-0.4, 0.0, 3.0), (-1.5, 0.0, 30.0),
    (0.2, 0.05, 10.0), (1.2, 0.1, 10.0), (-0.4, 0.02, 50.0),
]


def _pdf(m):
    """model.stationary_pdf with its normaliser computed once (it is a quadrature for eps > 0)."""
    log_z = m.log_normaliser()
    return lambda v: math.exp(-m.gamma * float(m.potential(v)) - log_z)


def _direct_moments(m):
    """Mean, variance, P(v>0), <friction sign> by quad of model.stationary_pdf (independent of
    the package's half-line code: only the model's density is shared)."""
    c = m.potential_minimum()
    w = 30 * m.velocity_scale
    lo, hi = c - w, c + w
    pdf = _pdf(m)
    def q(f, a, b):
        if b <= a:
            return 0.0
        pts = [p for p in (0.0, m.epsilon, -m.epsilon) if a < p < b] or None
        return integrate.quad(lambda v: f(v) * pdf(v), a, b, points=pts,
                              limit=500, epsabs=0, epsrel=1e-11)[0]
    mean = q(lambda v: v, lo, hi)
    var = q(lambda v: (v - mean) ** 2, lo, hi)
    pp = q(lambda v: 1.0, max(lo, 0.0), hi)
    sign = q(lambda v: float(m.coulomb(v)) / m.delta, lo, hi)
    return mean, var, pp, sign


@pytest.mark.parametrize("a,eps,gamma", PARAMS)
def test_moments_match_direct_quadrature_of_model_pdf(a, eps, gamma):
    m = Model(1.0, 0.7, a, gamma, epsilon=eps)
    s = exact.stationary_moments(m)
    mean, var, pp, sign = _direct_moments(m)
    scale = m.velocity_scale
    assert s.mean == pytest.approx(mean, abs=1e-9 * scale)
    assert s.variance == pytest.approx(var, rel=1e-8)
    assert s.p_positive == pytest.approx(pp, abs=1e-9)
    assert s.mean_sign == pytest.approx(sign, abs=1e-9)
    assert s.p_positive + s.p_negative == pytest.approx(1.0, abs=1e-14)
    assert s.drift == s.mean


@pytest.mark.parametrize("a,eps,gamma", PARAMS + [(0.3, 0.0, 1e4), (1.5, 0.0, 1e4), (0.69, 0.0, 1e6),
                                                  (0.3, 1e-3, 1e4)])
def test_force_balance_identity(a, eps, gamma):
    """<U'(v)> = 0 in the stationary state (integrate p_s' = -gamma U' p_s), i.e.
    <v> = tau_m (a - Delta <sgn v>), with tanh for epsilon > 0."""
    m = Model(2.0, 0.7, a, gamma, epsilon=eps)
    s = exact.stationary_moments(m)
    rhs = m.tau_m * (m.a - m.delta * s.mean_sign)
    assert s.mean == pytest.approx(rhs, abs=1e-9 * m.velocity_scale * max(1.0, abs(s.mean) / m.velocity_scale))


@pytest.mark.parametrize("a,gamma", [(0.2, 10.0), (1.2, 10.0), (-0.4, 3.0), (0.3, 1e4), (1.5, 1e4),
                                     (0.2, 1e6), (-2.0, 1e5)])
def test_sgn_closed_forms_equal_half_line_quadrature(a, gamma):
    """Truncated-Gaussian closed forms (incl. the continued-fraction branch at large gamma) vs
    adaptive quadrature on each half line."""
    m = Model(1.0, 0.7, a, gamma)
    c = half_line_moments(m, "closed")
    q = half_line_moments(m, "quad")
    s2 = m.velocity_scale ** 2
    for side in ("p", "m"):
        lz_c, lz_q = getattr(c, "log_z" + side), getattr(q, "log_z" + side)
        if lz_c - c.log_z < -600:  # this half line carries no probability at all
            continue
        assert lz_c == pytest.approx(lz_q, abs=1e-9 * max(1.0, abs(lz_c)))
        assert getattr(c, "mean_" + side) == pytest.approx(getattr(q, "mean_" + side), abs=1e-9 * math.sqrt(s2), rel=1e-9)
        assert getattr(c, "var_" + side) == pytest.approx(getattr(q, "var_" + side), rel=1e-7)


def test_delta_zero_is_ornstein_uhlenbeck():
    tau, a, gamma = 1.5, 0.3, 8.0
    m = Model(tau, 0.0, a, gamma)
    s = exact.stationary_moments(m)
    sd = math.sqrt(tau / gamma)
    assert s.mean == pytest.approx(a * tau, rel=1e-12)
    assert s.variance == pytest.approx(tau / gamma, rel=1e-12)
    assert s.p_positive == pytest.approx(special.ndtr(a * tau / sd), rel=1e-12)
    assert s.mean_sign == pytest.approx(2 * special.ndtr(a * tau / sd) - 1, rel=1e-12)
    # C(t) = (tau/gamma) e^{-|t|/tau}  =>  D_x = int_0^inf C = tau^2/gamma
    assert s.diffusion == pytest.approx(tau ** 2 / gamma, rel=1e-6)
    lags = np.array([0.0, 0.2, 1.0, -1.0, 3.0])
    assert exact.autocorrelation(m, lags) == pytest.approx(tau / gamma * np.exp(-np.abs(lags) / tau), rel=1e-6)


def _green_kubo_quadrature(m, mean):
    """Independent route: D_x = gamma int G(v)^2 / p_s(v) dv, G(v) = int_{-inf}^v (u - <v>) p_s du
    (solution of the backward Poisson equation by two integrations)."""
    c = m.potential_minimum()
    w = 25 * m.velocity_scale
    pts = [p for p in (0.0, c) if c - w < p < c + w]
    pdf = _pdf(m)
    f = lambda u: (u - mean) * pdf(u)
    def G(v):  # integrate from the nearer end: G(-inf) = G(+inf) = 0
        if v < c:
            return integrate.quad(f, c - w, v, epsabs=0, epsrel=1e-11, limit=200,
                                  points=[p for p in pts if c - w < p < v] or None)[0]
        return -integrate.quad(f, v, c + w, epsabs=0, epsrel=1e-11, limit=200,
                               points=[p for p in pts if v < p < c + w] or None)[0]
    val, _ = integrate.quad(lambda v: G(v) ** 2 / pdf(v), c - w / 2, c + w / 2,
                            points=[p for p in pts if c - w / 2 < p < c + w / 2] or None,
                            epsabs=0, epsrel=1e-9, limit=200)
    return m.gamma * val


@pytest.mark.parametrize("a,eps", [(0.2, 0.0), (1.2, 0.0), (-0.5, 0.0), (0.2, 0.05)])
def test_diffusion_matches_green_kubo_quadrature(a, eps):
    m = Model(1.0, 0.7, a, 10.0, epsilon=eps)
    s = exact.stationary_moments(m)
    assert s.diffusion == pytest.approx(_green_kubo_quadrature(m, s.mean), rel=2e-6)


def test_diffusion_equals_integral_of_autocorrelation():
    """Spectral autocorrelation integrated in time vs the Poisson-equation route."""
    m = Model(1.0, 0.7, 0.3, 10.0)
    lags = np.linspace(0.0, 40.0, 8001)
    c = exact.autocorrelation(m, lags)
    assert integrate.simpson(c, x=lags) == pytest.approx(exact.stationary_moments(m).diffusion, rel=1e-5)


@pytest.mark.parametrize("a,eps,gamma", [(0.2, 0.0, 10.0), (1.2, 0.0, 10.0), (0.3, 0.0, 1e3), (0.2, 0.05, 10.0)])
def test_diffusion_grid_convergence(a, eps, gamma):
    """Docstring claim: halving h at the default spacing changes D_x by < 1e-5 relative."""
    from analogue.theory.exact_grid import resolved_grid
    m = Model(1.0, 0.7, a, gamma, epsilon=eps)
    h = resolved_grid(m).h
    d1 = exact.stationary_moments(m).diffusion
    d2 = exact.stationary_moments(m, h=h / 2).diffusion
    assert d2 == pytest.approx(d1, rel=1e-5)
    assert d1 > 0


@pytest.mark.parametrize("a,eps", [(0.2, 0.0), (1.2, 0.05)])
def test_autocorrelation_properties(a, eps):
    """C(0) = variance; C is even; for a reversible process C(t) = sum_k w_k e^{-mu_k t} with
    w_k >= 0, so C is positive and decreasing."""
    m = Model(1.0, 0.7, a, 10.0, epsilon=eps)
    lags = np.linspace(0.0, 6.0, 61)
    both = exact.autocorrelation(m, np.stack([lags, -lags]))
    assert both.shape == (2, 61)
    c = both[0]
    var = exact.stationary_moments(m).variance
    assert c[0] == pytest.approx(var, rel=2e-6)
    assert np.all(c > 0) and np.all(np.diff(c) < 0)
    assert both[1] == pytest.approx(c, rel=1e-12)


def test_large_gamma_is_finite_and_consistent():
    for a in (0.3, 0.69, 1.2, -1.2):
        m = Model(1.0, 0.7, a, 1e7)
        s = exact.stationary_moments(m)
        assert all(np.isfinite(list(s.values())))
        assert s.variance > 0 and 0 <= s.p_positive <= 1 and s.diffusion > 0
    # deep stick: mean of the v > 0 half ~ 1/(gamma (Delta - a)) (exponential law)
    m = Model(1.0, 0.7, 0.3, 1e7)
    h = half_line_moments(m)
    assert h.mean_p == pytest.approx(1 / (m.gamma * 0.4), rel=1e-4)


def test_mapping_interface():
    s = exact.stationary_moments(Model(1.0, 0.7, 0.2, 10.0))
    d = s.as_dict()
    assert set(d) == {"mean", "variance", "p_positive", "p_negative", "mean_sign", "diffusion", "drift",
                      "p_zero"}  # p_zero: the atom at v = 0 (family members; 0 here)
    assert d["p_zero"] == 0.0
    assert dict(s) == d and s["variance"] == s.variance and len(s) == 8
    with pytest.raises(KeyError):
        s["nope"]
    with pytest.raises(AttributeError):
        s.mean = 1.0  # frozen


@pytest.mark.parametrize("a,eps", [(0.2, 0.0), (1.2, 0.0), (-0.4, 0.05), (0.3, 0.02)])
def test_sample_stationary_moments_within_4_se(a, eps):
    m = Model(1.0, 0.7, a, 10.0, epsilon=eps)
    n = 200_000
    x = exact.sample_stationary(m, n, seed=11)
    s = exact.stationary_moments(m)
    se_mean = math.sqrt(s.variance / n)
    d2 = (x - s.mean) ** 2
    se_var = math.sqrt(np.var(d2) / n)
    se_p = math.sqrt(s.p_positive * s.p_negative / n)
    assert abs(x.mean() - s.mean) < 4 * se_mean
    assert abs(d2.mean() - s.variance) < 4 * se_var
    assert abs((x > 0).mean() - s.p_positive) < 4 * se_p


def test_sample_stationary_ks_against_exact_cdf():
    for m in (Model(1.0, 0.7, 0.2, 10.0), Model(1.0, 0.7, 1.0, 10.0, epsilon=0.05)):
        c = m.potential_minimum()
        grid = np.linspace(c - 30 * m.velocity_scale, c + 30 * m.velocity_scale, 200_001)
        if m.epsilon == 0:
            grid = np.union1d(grid, [0.0])
        cdf = integrate.cumulative_trapezoid(m.stationary_pdf(grid), grid, initial=0.0)
        x = exact.sample_stationary(m, 20_000, seed=5)
        res = stats.kstest(x, lambda q: np.interp(q, grid, cdf))
        assert res.pvalue > 1e-3


def test_sample_stationary_seeding_and_shape():
    m = Model(1.0, 0.7, 0.2, 10.0)
    assert np.array_equal(exact.sample_stationary(m, 10, seed=3), exact.sample_stationary(m, 10, seed=3))
    assert not np.array_equal(exact.sample_stationary(m, 10, seed=3), exact.sample_stationary(m, 10, seed=4))
    assert exact.sample_stationary(m, (4, 5), seed=np.random.default_rng(1)).shape == (4, 5)
    # extreme stick regime: samples finite, both signs, scale 1/(gamma (Delta -+ a))
    x = exact.sample_stationary(Model(1.0, 0.7, 0.3, 1e8), 1000, seed=1)
    assert np.all(np.isfinite(x)) and (x > 0).any() and (x < 0).any()


def test_bad_input_names_the_parameter():
    m = Model(1.0, 0.7, 0.2, 10.0)
    with pytest.raises(ValueError, match="model"):
        exact.stationary_moments({"tau_m": 1})
    with pytest.raises(ValueError, match="h must be"):
        exact.stationary_moments(m, h=-1.0)
    with pytest.raises(ValueError, match="lags"):
        exact.autocorrelation(m, [0.0, np.nan])
    with pytest.raises(ValueError, match="size"):
        exact.sample_stationary(m, -3)
    with pytest.raises(ValueError, match="method"):
        half_line_moments(m, "bogus")
    with pytest.raises(ValueError, match="epsilon"):
        half_line_moments(m.replace(epsilon=0.1), "closed")


def test_partial_spectrum_branch_matches_full(monkeypatch):
    """Large grids (small epsilon) use only the slowest modes plus a bounded remainder; on a
    normal grid, forcing that branch must reproduce the full spectral sum."""
    from analogue.theory import stationary
    from analogue.theory.exact_grid import resolved_grid
    m = Model(1.0, 0.7, 0.2, 10.0, epsilon=0.05)
    g = resolved_grid(m)
    lags = np.array([0.0, 0.05, 0.3, 1.0])
    full = stationary._autocorrelation_on_grid(m, g, lags)
    monkeypatch.setattr(stationary, "_FULL_SPECTRUM_NODES", 100)
    monkeypatch.setattr(stationary, "_PARTIAL_MODES", 150)
    part = stationary._autocorrelation_on_grid(m, g, lags)
    assert part == pytest.approx(full, rel=1e-9)
    monkeypatch.setattr(stationary, "_PARTIAL_MODES", 5)  # forces the expm fallback at small lags
    assert stationary._autocorrelation_on_grid(m, g, lags) == pytest.approx(full, rel=1e-8)
