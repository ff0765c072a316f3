"""The integration difference of indicator observables by smoothed perturbation analysis
(:mod:`analogue.estimators.smoothed_indicator`, :func:`analogue.study.budget.integration_term`):
the smoothed difference estimates the indicator's mean change under a small path-wise
perturbation (checked against the closed form of a Gaussian law), with far less noise than
counting flips, and its Richardson term measures the kernel's bias."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ndtr

from analogue.ensemble import Ensemble
from analogue.estimators.resampling import jackknife_difference, subset
from analogue.estimators.smoothed_indicator import kernel_width, window
from analogue.study.budget import SE_MULTIPLIER, integration_term
from analogue.study import catalogue as C


def test_window_without_smoothing_is_the_indicator():
    v = np.array([-1.0, -0.3, -0.1, 0.0, 0.1, 0.3, 2.0])
    assert np.array_equal(window(v, -0.3, 0.3), (np.abs(v) < 0.3).astype(float))
    assert np.array_equal(window(v, 0.0, math.inf), (v > 0).astype(float))
    assert np.array_equal(window(v, -math.inf, 0.0), (v < 0).astype(float))


def test_window_smoothing_is_a_gaussian_convolution_of_the_indicator():
    v = np.linspace(-1, 1, 41)
    h = 0.05
    w = window(v, -0.3, 0.3, h)
    assert np.all((w >= 0) & (w <= 1))
    # far from the edges it is the indicator; at an edge it is 1/2
    far = np.abs(np.abs(v) - 0.3) > 8 * h
    assert np.allclose(w[far], (np.abs(v[far]) < 0.3), atol=1e-12)
    assert window(np.array([0.3]), -0.3, 0.3, h)[0] == pytest.approx(0.5, abs=1e-12)
    # independent route: quadrature of the indicator against the Gaussian kernel
    u = np.linspace(-8, 8, 4001)
    kern = np.exp(-u**2 / 2) / math.sqrt(2 * math.pi)
    for x in (-0.33, -0.1, 0.28, 0.31, 0.5):
        q = np.trapezoid(kern * (np.abs(x + h * u) < 0.3), u)
        assert window(np.array([x]), -0.3, 0.3, h)[0] == pytest.approx(q, abs=2e-3)


def test_kernel_width():
    assert kernel_width(0.03, 0.006) == pytest.approx(0.25 * 0.006)
    assert kernel_width(0.03, 0.0) == pytest.approx(0.25 * 0.03)
    assert kernel_width(0.0, 0.0) == 0.0


def _perturbed(seed: int, n: int, m: int, shift, h: float | None = None):
    """Paths of a stationary Gaussian AR(1) law N(0.2, 0.3^2) (rows: replicas) and the same
    paths moved by ``shift(v)``: the nominal run and its 'check'."""
    rng = np.random.default_rng(seed)
    v = np.empty((n, m))
    v[:, 0] = rng.normal(0.2, 0.3, n)
    for i in range(1, m):
        v[:, i] = 0.2 + 0.8 * (v[:, i - 1] - 0.2) + 0.3 * math.sqrt(1 - 0.64) * rng.normal(size=n)
    t = np.arange(m) * 0.01
    x = np.zeros_like(v)
    return Ensemble(t, v + shift(v), x, {}), Ensemble(t, v, x, {})


def test_smoothed_difference_estimates_the_indicators_change_with_less_noise():
    """delta(v) = 1e-3 (1 + v): the mean change of P(|v| < 0.1) is known in closed form
    (to first order in delta, exact here to 1e-9).  The flip count and the smoothed
    difference both estimate it; the smoothed one with >= 5x less spread over paths, and
    within its booked term (|d| + 2 SE + Richardson) of the truth."""
    shift = lambda v: 1e-3 * (1.0 + v)
    thr, mu, sd = 0.1, 0.2, 0.3
    # P(|v + delta(v)| < thr), v ~ N(mu, sd^2): v + 1e-3 (1 + v) = (1.001) v + 1e-3 is monotone
    lo, hi = (-thr - 1e-3) / 1.001, (thr - 1e-3) / 1.001
    truth = (ndtr((hi - mu) / sd) - ndtr((lo - mu) / sd)) - (ndtr((thr - mu) / sd)
                                                             - ndtr((-thr - mu) / sd))
    check, nominal = _perturbed(5, 64, 2000, shift)
    values = lambda s: (lambda e: {"stick": float(window(e.v, -thr, thr, s).mean())})
    per_path = lambda s: (window(check.v, -thr, thr, s).mean(1)
                          - window(nominal.v, -thr, thr, s).mean(1))
    flips, smooth = per_path(0.0), per_path(0.01)
    assert smooth.std() < 0.2 * flips.std()
    term, d, se, kernel = integration_term(values, check, nominal, 0.01)["stick"]
    assert term == pytest.approx(abs(d) + SE_MULTIPLIER * se + kernel)
    assert abs(d - truth) <= term - abs(d) + 1e-12 or abs(d - truth) <= 3 * se + kernel
    # and the flip count agrees with the truth within its own (larger) error
    assert abs(flips.mean() - truth) <= 3 * flips.std() / math.sqrt(flips.size)


def test_richardson_term_covers_the_kernel_bias():
    """The same law and perturbation, kernels from wide (h = 0.16, wider than the window's
    half-width 0.1: d_h is 25 % off) to narrow: each smoothed difference lies within 3 SE
    plus its Richardson term of the closed-form change, and the Richardson term shrinks like
    h^2 until the estimates' noise is all that is left.
    (A perturbation that jumps exactly at an edge is not covered: then d_h tends to
    -delta p(edge)/2, not 0, as h -> 0; the module docstring says why the circuit's is
    smooth there.)"""
    c, thr, mu, sd = 2e-3, 0.1, 0.2, 0.3
    shift = lambda v: c * (1.0 + v)
    lo, hi = (-thr - c) / (1 + c), (thr - c) / (1 + c)
    truth = (ndtr((hi - mu) / sd) - ndtr((lo - mu) / sd)) - (ndtr((thr - mu) / sd)
                                                             - ndtr((-thr - mu) / sd))
    check, nominal = _perturbed(6, 64, 2000, shift)
    values = lambda s: (lambda e: {"stick": float(window(e.v, -thr, thr, s).mean())})
    kernels = []
    for h in (0.16, 0.08, 0.04, 0.01):
        term, d, se, kernel = integration_term(values, check, nominal, h)["stick"]
        assert abs(d - truth) <= 3 * se + kernel, (h, d, truth, se, kernel)
        kernels.append(kernel)
    assert kernels[0] > 2 * kernels[1] > 4 * kernels[2]
    assert kernels[0] > 0.15 * abs(truth)       # a wide kernel's bias is reported


def test_integration_term_leaves_smooth_observables_alone():
    check, nominal = _perturbed(7, 16, 500, lambda v: 1e-3 * v)
    fn = C.StationaryValues(burn_in=0.5, threshold=0.1, force=1.0, taus=(0.5,))
    from dataclasses import replace
    out = integration_term(lambda s: replace(fn, smoothing=s), check, nominal, 0.01)
    plain = jackknife_difference(fn, check, nominal)
    for k in ("mean v", "var v", "mean w (tau=0.5)", "var w (tau=0.5)"):
        term, d, se, kernel = out[k]
        assert kernel == 0.0
        assert d == pytest.approx(plain[k][0], rel=1e-12, abs=1e-15)
        assert se == pytest.approx(plain[k][1], rel=1e-9, abs=1e-15)
    # the indicator kinds are smoothed: their differences are not the flip counts
    assert out["stick fraction"][1] != plain["stick fraction"][0]


def test_smoothed_values_leave_group_out_equals_direct_route():
    check, _ = _perturbed(8, 24, 400, lambda v: 0.0 * v)
    fn = C.StationaryValues(burn_in=0.5, threshold=0.1, force=1.0, smoothing=0.01)
    g = 8
    labels = np.arange(check.replicas) % g
    fast = fn.leave_group_out(check, labels, g)
    for j in range(g):
        direct = fn(subset(check, labels != j))
        for k, val in direct.items():
            assert fast[j][k] == pytest.approx(val, rel=1e-12, abs=1e-15), k


def test_transition_values_smooth_only_the_indicator():
    check, _ = _perturbed(9, 40, 50, lambda v: 0.0 * v)
    plain = C.transition_values(check, 0.0, [0.2])
    smooth = C.transition_values(check, 0.0, [0.2], smoothing=0.05)
    v = check.at(0.2)
    for k in plain:
        if k.startswith("P(v<0)"):
            assert smooth[k] == pytest.approx(float(window(v, -math.inf, 0.0, 0.05).mean()))
            assert smooth[k] != plain[k]
        else:
            assert smooth[k] == plain[k]


def test_documented_limit_a_perturbation_that_jumps_at_an_edge():
    """delta = 2e-4 only where v > 0.1 moves no path across the window's edge (the
    indicator's change is 0), but the smoothed difference tends to -delta p(0.1)/2 for any
    h >> delta: the limit the module docstring states (the circuit's error has no such
    jump)."""
    shift = lambda v: np.where(v > 0.1, 2e-4, 0.0)
    check, nominal = _perturbed(6, 64, 2000, shift)
    values = lambda s: (lambda e: {"stick": float(window(e.v, -0.1, 0.1, s).mean())})
    p_edge = math.exp(-0.5 * ((0.1 - 0.2) / 0.3) ** 2) / (0.3 * math.sqrt(2 * math.pi))
    for h in (0.01, 0.004):
        d = integration_term(values, check, nominal, h)["stick"][1]
        assert d == pytest.approx(-2e-4 * p_edge / 2, rel=0.15)
    assert integration_term(values, check, nominal, 0.0)["stick"][1] == 0.0
