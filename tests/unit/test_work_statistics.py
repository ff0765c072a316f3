"""Exact work statistics (analogue.theory.work_statistics) against closed forms, identities and
Monte Carlo; Ornstein-Uhlenbeck closed forms (analogue.theory.ornstein_uhlenbeck) against
independent routes."""
import math

import numpy as np
import pytest
from scipy import integrate

from analogue import Model
from analogue.theory import ornstein_uhlenbeck as ou
from analogue.theory import work_statistics as ws
from conftest import SLIP_A12

OU10 = Model(tau_m=1.0, delta=0.0, a=0.5, gamma=10.0)
OU100 = Model(tau_m=0.7, delta=0.0, a=-0.8, gamma=100.0, mass=2.0)
FIG8 = Model(tau_m=1.0, delta=1.0, a=0.5, gamma=10.0)       # paper's Fig. 8 parameters


# ----------------------------------------------------------------- OU closed forms
def test_ou_stationary_moments_match_quadrature_of_stationary_law():
    v = np.linspace(-5, 6, 20001)
    p = OU10.stationary_pdf(v)
    mean = integrate.trapezoid(v * p, v)
    var = integrate.trapezoid((v - mean) ** 2 * p, v)
    assert mean == pytest.approx(ou.stationary_mean(OU10), rel=1e-9)
    assert var == pytest.approx(ou.stationary_variance(OU10), rel=1e-9)


def test_ou_propagator_chapman_kolmogorov_and_stationary_limit():
    u = np.linspace(-4, 5, 6001)
    v = np.array([-0.3, 0.5, 1.1])
    mid = ou.propagator(OU10, u, 0.3, v0=1.5)
    two_step = integrate.trapezoid(ou.propagator(OU10, v[:, None], 0.5, u[None, :]) * mid, u, axis=1)
    np.testing.assert_allclose(two_step, ou.propagator(OU10, v, 0.8, 1.5), rtol=1e-8)
    np.testing.assert_allclose(ou.propagator(OU10, v, 60.0, 1.5), OU10.stationary_pdf(v), rtol=1e-9)


def test_ou_work_variance_is_double_integral_of_autocovariance():
    tau = 2.5
    # int_0^tau int_0^tau C(s - t) ds dt = 2 int_0^tau (tau - u) C(u) du
    val, _ = integrate.quad(lambda u: 2 * (tau - u) * float(ou.autocovariance(OU100, u)), 0, tau,
                            epsabs=0, epsrel=1e-13)
    assert ou.work_variance(OU100, tau) == pytest.approx(OU100.force**2 * val, rel=1e-10)
    # small-tau series branch joins the direct formula continuously
    assert ou.work_variance(OU100, 0.7e-3 * (1 - 1e-9)) == pytest.approx(
        ou.work_variance(OU100, 0.7e-3 * (1 + 1e-9)), rel=1e-6)


def test_ou_rate_function_is_paper_eq_Iw_and_legendre_of_scgf():
    w = np.linspace(-3, 2, 11)
    np.testing.assert_allclose(ou.rate_function(OU100, w), ws.paper_rate_function(OU100, w), rtol=1e-12)
    k = np.linspace(-400, 400, 400001)
    lam = ou.scgf(OU100, k)
    legendre = np.max(k[None, :] * w[:, None] - lam[None, :], axis=1) / OU100.gamma
    np.testing.assert_allclose(legendre, ou.rate_function(OU100, w), rtol=1e-6, atol=1e-9)


def test_ou_rejects_dry_friction_and_bad_tau():
    with pytest.raises(ValueError, match="delta == 0"):
        ou.scgf(FIG8, 1.0)
    with pytest.raises(ValueError, match="tau must be finite and > 0"):
        ou.work_variance(OU10, 0.0)


# ------------------------------------------------------------------- SCGF (Delta = 0)
@pytest.mark.parametrize("model", [OU10, OU100])
def test_scgf_and_derivative_equal_ou_closed_form(model):
    scale = model.gamma / (model.force**2 * model.tau_m**2)
    k = scale * np.array([-2.0, -0.3, 0.0, 0.05, 1.0, 3.0])
    # atol: the pointwise potential is not the exact ground-state transform (O(h^4) after Richardson)
    np.testing.assert_allclose(ws.scgf(model, k), ou.scgf(model, k), rtol=1e-7, atol=1e-8)
    exact_der = model.force * model.a * model.tau_m + 2 * k * model.force**2 * model.tau_m**2 / model.gamma
    np.testing.assert_allclose(ws.scgf_derivative(model, k), exact_der, rtol=1e-7, atol=1e-10)


@pytest.mark.parametrize("model", [OU10, OU100])
def test_rate_function_equals_ou_closed_form(model):
    mean = model.force * model.a * model.tau_m
    w = mean + abs(model.force) * np.array([-2.0, -0.5, -0.05, 0.0, 0.1, 1.0, 3.0])
    np.testing.assert_allclose(ws.rate_function(model, w), ou.rate_function(model, w), rtol=1e-5,
                               atol=1e-10)


# ------------------------------------------------------------- SCGF (Delta > 0)
@pytest.mark.parametrize("model", [FIG8, SLIP_A12])
def test_scgf_zero_slope_mean_and_convexity(model):
    assert float(ws.scgf(model, 0.0)) == pytest.approx(0.0, abs=1e-9)
    mean = ws.work_rate_mean(model)
    # <v> from quadrature of the exact stationary law (independent of the eigen-solver)
    assert float(ws.scgf_derivative(model, 0.0)) == pytest.approx(mean, rel=1e-6)
    k = np.linspace(-30, 30, 13)
    lam = ws.scgf(model, k)
    assert np.all(np.diff(lam, 2) > 0)
    der = ws.scgf_derivative(model, k)
    assert np.all(np.diff(der) > 0)
    # Hellmann-Feynman derivative agrees with a centred difference of the eigenvalue
    kk, d = 7.0, 1e-3
    fd = (ws.scgf(model, kk + d) - ws.scgf(model, kk - d)) / (2 * d)
    assert float(ws.scgf_derivative(model, kk)) == pytest.approx(float(fd), rel=1e-5)


def test_scgf_converged_in_grid_spacing():
    k = np.array([-20.0, 5.0, 40.0])
    h = ws.tilted_grid_spacing(FIG8)
    fine = ws.scgf(FIG8, k, h=h / 2)
    np.testing.assert_allclose(ws.scgf(FIG8, k), fine, rtol=1e-6, atol=1e-8)


@pytest.mark.slow
@pytest.mark.parametrize("model", [FIG8, SLIP_A12])
def test_rate_function_zero_at_mean_nonnegative_convex_and_legendre(model):
    mean = ws.work_rate_mean(model)
    assert float(ws.rate_function(model, mean)) == pytest.approx(0.0, abs=1e-12)
    w = np.linspace(-1.0, 1.6, 11)
    I = ws.rate_function(model, w)
    assert np.all(I >= 0)
    assert np.all(np.diff(I, 2) > -1e-9)
    # Legendre sandwich on a k grid: g(k) = k w - lambda(k) is concave, so
    # max_j g(k_j) <= gamma I(w) <= g(k_j) + g'(k_j) (k* - k_j) for the grid points k_j, k_j+1
    # bracketing the maximiser k* (|k* - k_j| <= step).
    k = np.linspace(-60, 60, 241)
    step = k[1] - k[0]
    lam, der = ws.scgf(model, k), ws.scgf_derivative(model, k)
    g = k[None, :] * w[:, None] - lam[None, :]
    gp = w[:, None] - der[None, :]
    lower = np.max(g, axis=1) / model.gamma
    assert np.all(lower <= I + 1e-9)
    checked = 0
    for i in range(w.size):
        j = np.flatnonzero((gp[i, :-1] >= 0) & (gp[i, 1:] <= 0))
        if j.size == 0:
            continue                     # maximiser outside the k grid
        j = j[0]
        upper = min(g[i, j] + gp[i, j] * step, g[i, j + 1] - gp[i, j + 1] * step) / model.gamma
        assert lower[i] - 1e-9 <= I[i] <= upper + 1e-9
        checked += 1
    assert checked >= 5


# ------------------------------------------------------------------ work density
@pytest.mark.slow
def test_work_pdf_equals_ou_density_deep_in_the_tails():
    tau = 2.0
    mean = OU10.force * OU10.a * OU10.tau_m
    sd = math.sqrt(ou.work_variance(OU10, tau)) / tau
    w = mean + sd * np.array([-6.0, -2.0, 0.0, 1.0, 4.0, 8.0])
    exact = ou.work_pdf(OU10, w, tau)
    assert exact.min() < 1e-8          # reaches far beyond the 1e-8 requirement
    np.testing.assert_allclose(ws.work_pdf(OU10, w, tau), exact, rtol=1e-4)


@pytest.fixture(scope="module")
def slip_density():
    """Work-rate density at tau = 4 on a trapezoid grid (spectrally accurate for an analytic
    density: step 0.15 against a standard deviation 0.2) from -4 to +5 standard deviations."""
    tau = 4.0
    mean = ws.work_rate_mean(SLIP_A12)
    w = np.linspace(mean - 0.75, mean + 1.05, 13)
    # 32 modes: at tau = 4 the higher modes are damped by exp(-4 * gap); convergence in modes is
    # tested separately (test_work_pdf_converged_in_modes)
    return tau, w, ws.work_pdf(SLIP_A12, w, tau, modes=32)


@pytest.mark.slow
def test_work_pdf_normalised_with_mean_F_v(slip_density):
    tau, w, p = slip_density
    assert p[0] < 1e-6 * p.max() and p[-1] < 1e-3 * p.max()
    # truncated tails hold < 2e-4 of the mass (the density falls faster than the Gaussian beyond)
    assert integrate.trapezoid(p, w) == pytest.approx(1.0, abs=5e-4)
    assert integrate.trapezoid(w * p, w) == pytest.approx(ws.work_rate_mean(SLIP_A12), abs=1e-3)


@pytest.mark.slow
def test_work_pdf_variance_matches_monte_carlo(slip_density):
    from analogue.montecarlo import simulate_sde
    tau, w, p = slip_density
    mean = integrate.trapezoid(w * p, w) / integrate.trapezoid(p, w)
    var = integrate.trapezoid((w - mean) ** 2 * p, w) / integrate.trapezoid(p, w)
    n = 4000
    ens = simulate_sde(SLIP_A12, v0="stationary", t_end=tau, replicas=n, seed=20261122, sample_dt=tau)
    wr = SLIP_A12.force * (ens.x[:, -1] - ens.x[:, 0]) / tau
    mc_var = np.var(wr, ddof=1)
    se_var = mc_var * math.sqrt(2.0 / (n - 1))
    assert abs(mc_var - var) < 4 * se_var
    assert abs(np.mean(wr) - ws.work_rate_mean(SLIP_A12)) < 4 * math.sqrt(mc_var / n)


def test_work_pdf_variance_matches_autocorrelation_route(slip_density):
    """Independent route: Var(w) = 2 F^2 int_0^tau (tau - s) C(s) ds / tau^2 with C the exact
    stationary velocity autocorrelation (analogue.theory.exact.autocorrelation)."""
    from analogue.theory.exact import autocorrelation
    tau, w, p = slip_density
    norm = integrate.trapezoid(p, w)
    mean = integrate.trapezoid(w * p, w) / norm
    var = integrate.trapezoid((w - mean) ** 2 * p, w) / norm
    s = np.linspace(0.0, tau, 81)
    C = autocorrelation(SLIP_A12, s)
    ref = 2 * SLIP_A12.force**2 * integrate.simpson((tau - s) * C, x=s) / tau**2
    # the density's truncated tails (< 2e-4 of the mass, 4-5 sd out) bias the variance low by
    # < 25 * 2e-4 relative; Simpson on 81 lags of a smooth C: < 1e-6
    assert var == pytest.approx(ref, rel=5e-3)


@pytest.mark.slow
def test_work_pdf_finite_and_unimodal_across_the_report_range():
    """The report evaluates work_pdf at every histogram bin with circuit data, far into the
    tails (w = 1.4 at tau = 2 used to raise 'contour integral not positive'): finite, positive,
    rising to one maximum and falling beyond it (a failing basis gave values like 1e100)."""
    w = np.array([-1.5, -0.5, 0.0, 0.3, 1.4, 2.5])
    p = ws.work_pdf(FIG8, w, 2.0)
    assert np.all(np.isfinite(p)) and np.all(p > 0)
    top = int(np.argmax(p))
    assert np.all(np.diff(p[:top + 1]) > 0) and np.all(np.diff(p[top:]) < 0)
    assert p[-1] < 1e-30 and p[0] < 1e-20          # far tails stay far tails
    p_slip = ws.work_pdf(SLIP_A12, np.array([-1.5, 0.5, 2.5]), 5.0)
    assert np.all(np.isfinite(p_slip)) and p_slip[1] > p_slip[0] and p_slip[1] > p_slip[2]


@pytest.mark.slow
def test_work_pdf_converged_in_modes():
    w = np.array([0.3])
    np.testing.assert_allclose(ws.work_pdf(FIG8, w, 2.0), ws.work_pdf(FIG8, w, 2.0, modes=80), rtol=2e-4)
    slip_w = np.array([ws.work_rate_mean(SLIP_A12) + 0.6])
    np.testing.assert_allclose(ws.work_pdf(SLIP_A12, slip_w, 4.0, modes=32), ws.work_pdf(SLIP_A12, slip_w, 4.0),
                               rtol=1e-4)


@pytest.mark.slow
def test_finite_tau_density_approaches_rate_function_with_log_correction():
    """-ln P_tau(w)/(tau gamma) = I(w) - ln(tau)/(2 tau gamma) + c/tau + o(1/tau)."""
    w = 0.3
    I = float(ws.rate_function(FIG8, w))
    taus = np.array([4.0, 8.0, 16.0])
    p = ws.work_pdf(FIG8, w, taus[0]), ws.work_pdf(FIG8, w, taus[1]), ws.work_pdf(FIG8, w, taus[2])
    D = -np.log(np.array(p, dtype=float).ravel()) / (taus * FIG8.gamma) - I
    assert abs(D[2]) < 0.01
    c = taus * D + np.log(taus) / (2 * FIG8.gamma)
    # with the log correction removed, tau*D converges (O(1/tau) steps, halving per doubling);
    # tau*D itself would keep drifting by -ln2/(2 gamma) = -0.035 per doubling
    assert abs(c[2] - c[1]) < 0.6 * abs(c[1] - c[0])
    assert abs(c[2] - c[1]) < 0.5 * math.log(2) / (2 * FIG8.gamma)


# --------------------------------------------------------------------- validation
@pytest.mark.parametrize("call,needle", [
    (lambda: ws.rate_function(Model(tau_m=1, delta=1, a=0.0, gamma=10), 0.1), "a must be != 0"),
    (lambda: ws.work_pdf(FIG8, 0.1, 0.0), "tau must be > 0"),
    (lambda: ws.work_pdf(FIG8, 0.1, 1.0, modes=2), "modes must be >= 4"),
    (lambda: ws.scgf(FIG8, float("nan")), "k must be finite"),
    (lambda: ws.scgf("model", 1.0), "model must be an analogue.Model"),
])
def test_bad_input_raises_value_error(call, needle):
    with pytest.raises(ValueError, match=needle):
        call()


def test_log_ground_state_resolves_tails_below_round_off():
    """The fallback's overlap needs ground-state tails far below 1e-16 of the peak: the ratio
    recursion must follow ln sqrt(pi) = -gamma U/2 + const (OU, continuum ground state of
    S_0) out to e^-100, and agree with the eigen-solver where that is accurate."""
    from scipy import linalg
    from analogue.theory.fokker_planck import Grid
    h = ws.tilted_grid_spacing(OU10)
    grid = Grid.span(-6.0, 7.0, h)
    d, e = ws.tilted_operator(OU10, grid, 0.0)
    n = grid.n
    lam, vec = linalg.eigh_tridiagonal(d, e, select="i", select_range=(n - 1, n - 1))
    lphi = ws._log_ground_state(d, e[0], lam[0], np.abs(vec[:, 0]))
    ref = -0.5 * OU10.gamma * OU10.potential(grid.v)
    j = int(np.argmax(ref))
    diff = (lphi - lphi[j]) - (ref - ref[j])
    assert np.min(ref - ref[j]) < -100
    # O((h/sigma)^2) = O(h^2 gamma/tau_m) = 2.5e-3 relative error of the exponent (measured 5e-3)
    assert np.all(np.abs(diff) <= 1e-2 * np.abs(ref - ref[j]) + 1e-6)
    big = np.abs(vec[:, 0]) > 1e-8 * np.abs(vec[:, 0]).max()
    np.testing.assert_allclose(lphi[big], np.log(np.abs(vec[big, 0])), atol=1e-6)
