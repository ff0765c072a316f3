"""Independent cross-checks: weak-noise theory (paper) vs exact finite-noise numerics, on
parameter sets well away from the paper's (tau_m in {0.3, 2.5}, Delta in {0.2, 1.5},
a of both signs, a < Delta and a > Delta, mass != 1, v0 of both signs and 0).

1. ``-(1/gamma) ln f_exact(v, t | v0) -> A*(v, t | v0) + c(t)`` (eq. (12)): the spread
   over v of ``-(1/gamma) ln f - A*`` is the prefactor's ``O(ln gamma / gamma)``; it must fall
   by a clear factor when gamma grows 16-fold and be small at the largest gamma.  Only points
   with ``gamma (A* - A*_min) <= 20`` are used, where the exact density is far above rounding.
2. ``I_gamma(w) -> weak_noise_limit_rate_function(w)`` (convex envelope) roughly like 1/gamma.
3. SCGF identities: ``lambda(0) = 0``, ``lambda'(0) = F <v>`` (mean by independent quadrature of
   ``exp(-gamma U)``), convexity, and the Delta = 0 closed form
   ``lambda(k) = k F a tau_m + k^2 F^2 tau_m^2 / gamma`` (derived below).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from analogue import Model
from analogue.theory import exact
from analogue.theory import weak_noise as wn
from analogue.theory.work_statistics import weak_noise_limit_rate_function

# (parameters, v0, t, probe velocities): each set covers several optimal-path kinds.
PROPAGATOR_CASES = [
    # stick regime, a > 0, v0 > 0: direct, indirect (on v <= 0 side), direct-crossing
    (dict(tau_m=2.5, delta=1.5, a=0.4), 1.0, 0.8, [0.02, 0.1, 0.2, -0.02, -0.04]),
    # slip regime a > Delta, v0 < 0: direct-crossing, twice-crossing, direct
    (dict(tau_m=0.3, delta=0.2, a=2.0), -0.3, 0.2, [0.135, 0.05, 0.25, 0.1, -0.005]),
    # stick regime, a < 0, v0 > 0 after sticking: indirect and indirect-crossing
    (dict(tau_m=2.5, delta=1.5, a=-1.1), 0.5, 1.0, [0.004, 0.012, -0.03, -0.06, -0.1]),
    # stick regime, a < 0, v0 < 0, mass != 1
    (dict(tau_m=0.3, delta=1.5, a=-0.3, mass=2.5), -0.2, 0.4, [-0.02, -0.04, 0.01, 0.03]),
    # v0 = 0 in the stick regime (paths start on both half planes)
    (dict(tau_m=1.0, delta=0.6, a=0.3), 0.0, 0.5, [0.0, 0.03, 0.06, -0.02, -0.04]),
]
GAMMAS = (16.0, 64.0, 256.0)


def _spread(params, v0, t, pts, gamma):
    m = Model(gamma=gamma, **params)
    A = wn.action(m, pts, t, v0)
    f = exact.propagator(m, pts, t, v0)
    assert np.all(f > 0), "exact density vanished at a probe point inside its grid"
    resid = -np.log(f) / gamma - A
    return float(np.ptp(resid))


@pytest.mark.slow
@pytest.mark.parametrize("params,v0,t,pts", PROPAGATOR_CASES)
def test_exact_log_propagator_converges_to_action(params, v0, t, pts):
    pts = np.asarray(pts, float)
    A = wn.action(Model(gamma=1.0, **params), pts, t, v0)
    # gamma_max (A - A_min) <= 20: the probes sit where the exact density is well resolved
    assert GAMMAS[-1] * (A.max() - A.min()) <= 20.0
    spreads = [_spread(params, v0, t, pts, g) for g in GAMMAS]
    # prefactor differences are O(ln gamma / gamma): 16x gamma -> factor ~ 16/ln(16)/... >= 3;
    # ask for a factor 2.5 and an absolute level at gamma = 256.
    assert spreads[-1] < spreads[0] / 2.5, spreads
    assert spreads[-1] < 12.0 / GAMMAS[-1], spreads


@pytest.mark.parametrize("params,v0,t,pts", PROPAGATOR_CASES)
def test_probe_points_cover_several_path_kinds(params, v0, t, pts):
    m = Model(gamma=1.0, **params)
    kinds = {wn.optimal_path(m, x, t, v0).kind for x in pts}
    assert len(kinds) >= 2 or kinds == {"indirect"} or kinds == {"indirect", "indirect-crossing"}


# ------------------------------------------------------------------- rate function limit
RATE_CASES = [
    dict(tau_m=0.3, delta=1.5, a=0.4),              # |a| < Delta
    dict(tau_m=1.0, delta=0.6, a=-0.3),             # a < 0, stick
    dict(tau_m=0.3, delta=0.2, a=2.0, mass=2.5),    # a > Delta, mass != 1
]


@pytest.mark.slow
@pytest.mark.parametrize("params", RATE_CASES)
def test_exact_rate_function_tends_to_convex_envelope(params):
    m1 = Model(gamma=1.0, **params)
    scale = max(1.0, abs(m1.attractor))
    w = m1.force * scale * np.array([-0.5, 0.3, 1.0])
    limit = weak_noise_limit_rate_function(m1, w)
    err = [np.max(np.abs(exact.rate_function(Model(gamma=g, **params), w) - limit))
           for g in (8.0, 32.0)]
    # Measured (QA): ~1/gamma on the parabolas, but only ~gamma^(-1/3) in the time-sharing
    # region near w = 0 (e.g. a = 2, Delta = 0.2: gap 0.156, 0.096, 0.046 at gamma = 40, 160,
    # 640).  Require a clear decrease (factor 0.75 for 4x gamma, gamma^(-1/3) gives 0.63) and
    # a gap below 10% of the largest limit value.
    assert err[1] < 0.75 * err[0], err
    assert err[1] < 0.1 * max(1.0, limit.max()), err


# ------------------------------------------------------------------------- SCGF identities
SCGF_CASES = [
    dict(tau_m=0.3, delta=1.5, a=-1.1, gamma=5.0),
    dict(tau_m=2.5, delta=0.2, a=0.4, gamma=3.0, mass=2.5),
    dict(tau_m=1.0, delta=1.5, a=2.0, gamma=8.0),
]


def _mean_velocity(m: Model) -> float:
    """<v> by adaptive quadrature of exp(-gamma U) (no library normaliser involved)."""
    c = m.attractor
    r = 12.0 * m.velocity_scale + 1.0 / m.gamma
    pts = sorted({0.0, c})
    lo, hi = c - r - 1.0, c + r + 1.0
    pts = [p for p in pts if lo < p < hi]
    u0 = float(m.potential(c))
    wgt = lambda v: math.exp(-m.gamma * (float(m.potential(v)) - u0))
    z, _ = integrate.quad(wgt, lo, hi, points=pts, limit=500, epsabs=0, epsrel=1e-11)
    s, _ = integrate.quad(lambda v: v * wgt(v), lo, hi, points=pts, limit=500, epsabs=0,
                          epsrel=1e-11)
    return s / z


@pytest.mark.parametrize("params", SCGF_CASES)
def test_scgf_zero_slope_and_convexity(params):
    m = Model(**params)
    F = m.force
    scale = m.gamma / (F * F * m.tau_m)   # natural tilt scale
    assert abs(float(exact.scgf(m, 0.0))) < 1e-7
    dk = 1e-3 * scale
    lp, lm = exact.scgf(m, np.array([dk, -dk]))
    slope = (lp - lm) / (2 * dk)
    mean = F * _mean_velocity(m)
    # central difference error ~ lambda''' dk^2; lambda'' ~ F^2 Var-type scale
    assert slope == pytest.approx(mean, abs=1e-4 * (abs(mean) + abs(F) * m.velocity_scale))
    k = np.linspace(-2.0, 2.0, 9) * scale
    lam = exact.scgf(m, k)
    second = lam[2:] - 2 * lam[1:-1] + lam[:-2]
    assert np.all(second > 0), second


@pytest.mark.parametrize("tau_m,a,gamma,mass", [(0.3, -1.1, 2.0, 1.0), (2.5, 0.4, 7.0, 2.5)])
def test_scgf_ou_closed_form(tau_m, a, gamma, mass):
    """Delta = 0: v is OU with mean a tau_m, stationary variance tau_m/gamma, correlation time
    tau_m, so int v over tau is Gaussian with asymptotic variance 2 (tau_m/gamma) tau_m tau;
    lambda(k) = k F a tau_m + (1/2) k^2 F^2 * 2 tau_m^2/gamma = k F a tau_m + k^2 F^2 tau_m^2/gamma."""
    m = Model(tau_m=tau_m, delta=0.0, a=a, gamma=gamma, mass=mass)
    F = m.force
    k = np.array([-1.0, -0.3, 0.2, 0.7]) * gamma / (F * F * tau_m)
    expected = k * F * a * tau_m + k**2 * F**2 * tau_m**2 / gamma
    got = exact.scgf(m, k)
    assert np.allclose(got, expected, rtol=2e-4, atol=1e-6 * np.abs(expected).max())
