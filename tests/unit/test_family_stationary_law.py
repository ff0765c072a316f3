"""The stationary law of the 1-D family members (analogue.theory.family.stationary_law, issue
18 item 5): one law, as accurate as stationary_moments.  Checked against the moments (the
same two grids), the closed form of the ODE reduction, exact (event-driven) Monte Carlo and,
for Gaussian-only members, exp(-gamma U)/Z with U written out here."""
import math

import numpy as np
import pytest
from scipy import integrate

from analogue import Model, ShotNoise
from analogue.montecarlo import simulate_sde
from analogue.theory import family

INF = math.inf
SHOT = Model(1.0, 0.5, 0.2, INF, shot=ShotNoise(1.0, 0.5))  # circuits/shot.toml


def _law_moments(v, dens, atom):
    """Mean, variance, P(v>0), P(v<0), total mass of the cell law (uniform in each cell)."""
    h = v[1] - v[0]
    mass = dens * h
    mean = float(np.dot(v, mass))
    second = float(np.dot(v * v + h * h / 12.0, mass))
    return mean, second - mean * mean, mass[v > 0].sum(), mass[v < 0].sum(), mass.sum() + atom


@pytest.mark.parametrize("m", [SHOT,
                               Model(1.0, 0.7, 0.2, INF, shot=ShotNoise(2.0, 0.3, two_sided=True)),
                               Model(1.0, 0.7, 1.3, INF, shot=ShotNoise(1.0, 1.0), stribeck=(1.0, 0.3)),
                               Model(1.0, 0.5, -0.2, INF, cubic=0.5, shot=ShotNoise(1.5, 0.4))],
                         ids=["shot", "two-sided", "stribeck-slip", "cubic"])
def test_pure_shot_law_carries_the_moments(m):
    """Atom and sign probabilities are the same sums as the moments'; mean and variance (each
    cell read as uniform) agree to O(h^2) (measured <= 1.6e-4 of the variance, two-sided).
    Single-grid law before issue 18: atom 0.36970 against p_zero 0.37497 (shot.toml)."""
    s = family.stationary_moments(m)
    v, dens, atom = family.stationary_law(m)
    mean, var, pp, pm, total = _law_moments(v, dens, atom)
    assert atom == pytest.approx(s.p_zero, abs=1e-14)
    assert pp == pytest.approx(s.p_positive, abs=1e-12)
    assert pm == pytest.approx(s.p_negative, abs=1e-12)
    assert total == pytest.approx(1.0, abs=1e-12)
    assert mean == pytest.approx(s.mean, abs=1e-4 * math.sqrt(s.variance))
    assert var == pytest.approx(s.variance, rel=2.5e-4)


def test_pure_shot_law_against_the_ode_reduction():
    """One-sided kicks, |a| < Delta: p(v) = C e^{-v/mu} (1 + v/(b tau))^{rate tau - 1} on v > 0,
    rate P0 = b C (tests/unit/test_family_exact.py).  Measured: atom 3.0e-5 off (single grid
    4.9e-3), cell averages within 6.9e-5 of the peak, the cell next to v = 0 included (single
    grid 7.1e-3)."""
    a, lam, mu, tau, d = 0.2, 2.0, 0.3, 1.0, 0.7
    b = d - a
    m = Model(tau, d, a, INF, shot=ShotNoise(lam, mu))
    shape = lambda x: math.exp(-x / mu) * (1 + x / (b * tau)) ** (lam * tau - 1)  # noqa: E731
    i0, _ = integrate.quad(shape, 0, np.inf, epsabs=0, epsrel=1e-13)
    p0 = 1.0 / (1.0 + lam / b * i0)
    c = lam * p0 / b
    v, dens, atom = family.stationary_law(m)
    h = v[1] - v[0]
    assert atom == pytest.approx(p0, abs=1e-4)
    assert np.all(dens[v < 0] == 0.0)
    sel = np.flatnonzero((v > 0) & (v < 2.5))
    ref = np.array([integrate.quad(shape, v[i] - h / 2, v[i] + h / 2, epsabs=0,
                                   epsrel=1e-12)[0] for i in sel]) * c / h
    err = np.abs(dens[sel] - ref) / c
    assert err.max() < 2e-4


def test_pure_shot_law_against_event_driven_monte_carlo():
    """shot.toml from rest, read at 15 tau_m (the unkicked stuck mass e^{-15}): P(v = 0) and
    the masses of bins of v > 0 within 4 binomial standard errors (10^6 replicas: SE of the
    atom 4.8e-4; the single-grid law was 11 SE off, its bins up to 7.6 SE)."""
    m = SHOT
    v, dens, atom = family.stationary_law(m)
    h = v[1] - v[0]
    e = simulate_sde(m, v0=0.0, t_end=15.0, replicas=1_000_000, seed=3, sample_dt=15.0)
    assert e.meta["shot_scheme"].startswith("event-driven")
    x = np.asarray(e.v)[:, -1]
    n = x.size
    p = float(np.mean(x == 0.0))
    assert abs(p - atom) < 4 * math.sqrt(atom * (1 - atom) / n)
    edges = np.array([0.0, 0.05, 0.1, 0.2, 0.4, 0.8, 1.6, 10.0])
    cdf = np.r_[0.0, np.cumsum(dens * h)]
    theory = np.diff(np.interp(edges, np.r_[v - h / 2, v[-1] + h / 2], cdf))
    got = np.histogram(x[x > 0], edges)[0] / n
    z = (got - theory) / np.sqrt(theory * (1 - theory) / n)
    assert np.all(np.abs(z) < 4), z


def _stribeck_u(v, tau, delta, a, ds, vs, eps=0.0):
    """U written out (theory.md): v^2/(2 tau) + Delta |v| (or Delta eps ln cosh(v/eps)) +
    (delta_s - Delta) v_s (1 - e^{-|v|/v_s}) - a v."""
    av = np.abs(v)
    dry = delta * eps * (np.logaddexp(v / eps, -v / eps) - math.log(2.0)) if eps else delta * av
    return v * v / (2 * tau) + dry + (ds - delta) * vs * (1 - np.exp(-av / vs)) - a * v


@pytest.mark.parametrize("args", [(1.0, 0.5, 0.3, 0.9, 0.3, 0.0), (2.0, 0.3, 0.7, 1.0, 0.2, 0.0),
                                  (1.0, 0.7, 0.2, 0.7, 1.0, 0.02)],
                         ids=["stick-cusp", "stribeck.toml", "smooth"])
def test_gaussian_law_is_exp_minus_gamma_u_at_gamma_200(args):
    """Gamma = 200: exp(-gamma U)/Z, U and Z computed here (quad, split at 0).  Measured
    2e-15 of the peak (sgn law), 4e-10 (epsilon > 0, spline of ln p); the Scharfetter-Gummel grid's
    Riemann normalisation was 7.4e-3 of the peak off at the stick cusp."""
    tau, delta, a, ds, vs, eps = args
    gamma = 200.0
    m = Model(tau, delta, a, gamma, stribeck=(ds, vs) if ds != delta else None, epsilon=eps)
    v, dens, atom = family.stationary_law(m)
    assert atom == 0.0

    def w(x):
        return np.exp(-gamma * _stribeck_u(np.asarray(x, float), tau, delta, a, ds, vs, eps))
    z = sum(integrate.quad(w, lo, hi, epsabs=0, epsrel=1e-13, limit=500)[0]
            for lo, hi in ((-20.0, 0.0), (0.0, 20.0)))
    ref = w(v) / z
    assert np.max(np.abs(dens - ref)) < 1e-6 * ref.max()
