"""Exact finite-noise propagator f(v, t | v0, t0): closed forms, limits, identities, grid
convergence, and agreement with the SDE Monte Carlo."""
import math

import numpy as np
import pytest
from scipy import integrate, linalg

from analogue import Model
from analogue.montecarlo import simulate_sde, standard_noise
from analogue.theory import exact
from analogue.theory.exact_grid import propagator_grid, resolved_grid
from analogue.theory.fokker_planck import Grid, generator, symmetric_generator
from analogue.theory.propagation import (CONTOUR_MAX_NODES, CONTOUR_MIN_NODES, amplification,
                                        contour_nodes, initial_delta, propagate)

TIMES = np.array([0.1, 0.5, 1.0, 3.0])


def ou_density(v, t, v0, tau, a, gamma):
    """Delta = 0: Gaussian, mean v0 e^{-t/tau} + a tau (1 - e^{-t/tau}),
    variance (tau/gamma)(1 - e^{-2t/tau})."""
    t = np.asarray(t, dtype=float)[:, None]
    mu = v0 * np.exp(-t / tau) + a * tau * (1 - np.exp(-t / tau))
    var = tau / gamma * (1 - np.exp(-2 * t / tau))
    return np.exp(-(v - mu) ** 2 / (2 * var)) / np.sqrt(2 * np.pi * var)


@pytest.mark.parametrize("v0", [2.0, -1.303])  # -1.303 is off-node: split initial delta
def test_delta_zero_equals_ou_closed_form(v0):
    """Docstring accuracy claim: max error below 1e-3 of the peak at the default grid (the
    earliest of the times sets the grid)."""
    tau, a, gamma = 1.0, 0.3, 10.0
    m = Model(tau, 0.0, a, gamma)
    v = np.linspace(-3.0, 4.0, 3001)
    f = exact.propagator(m, v, TIMES, v0)
    ref = ou_density(v, TIMES, v0, tau, a, gamma)
    err = np.abs(f - ref).max(axis=1) / ref.max(axis=1)
    assert np.all(err < 1e-3)


@pytest.mark.parametrize("a,eps", [(0.2, 0.0), (1.2, 0.0), (-0.5, 0.05), (0.3, 0.1)])
def test_long_time_limit_is_stationary_pdf(a, eps):
    m = Model(1.0, 0.7, a, 10.0, epsilon=eps)
    v = np.linspace(-2.0, 2.5, 901)
    f = exact.propagator(m, v, 40.0, 1.7)
    ps = m.stationary_pdf(v)
    assert np.abs(f - ps).max() < 1e-9 * ps.max()


@pytest.mark.parametrize("a,eps", [(0.2, 0.0), (1.2, 0.0), (0.3, 0.05)])
def test_fp_stationary_state_is_model_stationary_pdf(a, eps):
    """The null vector of the discrete generator is p_s at the nodes (up to the O(h^2)
    normalisation of a node sum), for both friction laws."""
    m = Model(1.0, 0.7, a, 10.0, epsilon=eps)
    grid = resolved_grid(m)
    diag, off, _ = symmetric_generator(m, grid)
    lam, q = linalg.eigh_tridiagonal(diag, off, select="i", select_range=(grid.n - 1, grid.n - 1))
    assert abs(lam[0]) < 1e-9 * abs(diag).max()
    ps = m.stationary_pdf(grid.v)
    null = q[:, 0] ** 2  # Pi^{1/2} q0 with q0 ~ Pi^{1/2}
    null *= ps.sum() / null.sum()
    assert np.abs(null - ps).max() < 1e-9 * ps.max()
    assert np.abs(generator(m, grid) @ ps).max() < 1e-9 * ps.max() / (m.gamma * grid.h ** 2)


@pytest.mark.parametrize("a,v0,eps", [(0.3, 1.0, 0.0), (0.3, -1.0, 0.0), (1.2, -1.0, 0.0),
                                      (1.2, 1.0, 0.05)])
@pytest.mark.slow  # > 5 s (make test-fast skips it)
def test_normalised_positive_and_grid_converged(a, v0, eps):
    """Docstring claims: halving h changes the density by < 7.5e-4 of its peak; every time
    slice integrates to 1 within 1e-4 (Simpson on the grid refined 8x)."""
    m = Model(1.0, 0.7, a, 10.0, epsilon=eps)
    g = propagator_grid(m, v0, TIMES[0])
    v = np.linspace(g.v[0], g.v[-1], 8 * (g.n - 1) + 1)
    f1 = exact.propagator(m, v, TIMES, v0)
    f2 = exact.propagator(m, v, TIMES, v0, h=g.h / 2)
    assert np.all(f1 >= 0)
    assert integrate.simpson(f1, x=v, axis=1) == pytest.approx(np.ones(TIMES.size), abs=1e-4)
    change = np.abs(f1 - f2).max(axis=1) / f2.max(axis=1)
    assert np.all(change < 7.5e-4)
    # node probabilities themselves sum to 1 to round-off
    p = propagate(m, g, initial_delta(g, v0), TIMES)
    assert p.sum(axis=1) == pytest.approx(np.ones(TIMES.size), abs=1e-10)


@pytest.mark.slow  # > 5 s (make test-fast skips it)
def test_routes_agree():
    """eigen, expm_multiply, hybrid and contour propagation of the same grid problem."""
    m = Model(1.0, 0.7, 0.3, 10.0)
    g = resolved_grid(m, extra=[1.9], t_min=0.2)
    p0 = initial_delta(g, 1.9)
    t = np.array([0.2, 1.0, 2.5])
    pe = propagate(m, g, p0, t, method="eigen")
    px = propagate(m, g, p0, t, method="expm")
    ph = propagate(m, g, p0, t, method="hybrid")
    pc = propagate(m, g, p0, t, method="contour")
    assert np.abs(pe - px).max() < 1e-8 * px.max()
    assert np.abs(ph - px).max() < 1e-10 * px.max()
    assert np.abs(pc - px).max() < 1e-10 * px.max()
    # unsorted times give the same rows
    order = [2, 0, 1]
    for method in ("eigen", "expm", "hybrid", "contour"):
        shuffled = propagate(m, g, p0, t[order], method=method)
        assert np.abs(shuffled - pe[order]).max() < 1e-8 * px.max()


def test_reflection_symmetry_and_shapes():
    """f(v, t | v0; a) = f(-v, t | -v0; -a); mass does not enter; t0 shifts time; shapes."""
    m = Model(1.0, 0.7, 0.4, 10.0)
    mirror = m.replace(a=-0.4)
    v = np.linspace(-2.0, 2.0, 401)
    f = exact.propagator(m, v, [0.3, 1.2], 1.1)
    g = exact.propagator(mirror, -v, [0.3, 1.2], -1.1)
    assert np.abs(f - g).max() < 1e-10 * f.max()
    heavy = exact.propagator(m.replace(mass=5.0), v, 1.2, 1.1)
    assert heavy.shape == v.shape
    assert heavy == pytest.approx(f[1], rel=1e-12, abs=1e-300)
    shifted = exact.propagator(m, v[:400].reshape(20, 20), 2.2, 1.1, t0=1.0)
    assert shifted.shape == (20, 20)
    # 2.2 - 1.0 != 1.2 in floating point; below ~1e-11 of the peak the contour route's
    # round-off floor (propagation.contour_nodes) differs between the two
    assert shifted.ravel() == pytest.approx(f[1][:400], rel=1e-9, abs=1e-10 * f.max())
    assert exact.propagator(m, 0.0, [0.5, 1.0], 0.2).shape == (2,)


@pytest.mark.slow  # > 5 s (make test-fast skips it)
def test_large_gamma_tail_start_is_accurate():
    """Start deep in the tail (eigen route would lose digits): hybrid route, vs expm."""
    m = Model(1.0, 0.7, 0.2, 100.0)
    v = np.linspace(-0.5, 2.5, 601)
    f = exact.propagator(m, v, [0.5, 1.5, 12.0], 2.0)
    fx = exact.propagator(m, v, [0.5, 1.5], 2.0, method="expm")
    assert np.abs(f[:2] - fx).max() < 1e-9 * fx.max()
    assert f[-1] == pytest.approx(m.stationary_pdf(v), rel=1e-6, abs=1e-9 * f[-1].max())


def test_contour_nodes_grow_with_the_amplification():
    """The contour route's node count: the minimum for a start at the mode, growing with the
    start's amplification (its quadrature error is multiplied by e^amp), None beyond the
    round-off limit (auto then takes the hybrid route)."""
    assert contour_nodes(0.0) == CONTOUR_MIN_NODES
    counts = [contour_nodes(a) for a in (0.0, 10.0, 20.0, 30.0, 60.0)]
    assert counts == sorted(counts) and all(c % 2 == 0 for c in counts)
    assert contour_nodes(1000.0) is None
    assert contour_nodes(1.53 * CONTOUR_MAX_NODES - 32.0) == CONTOUR_MAX_NODES


def test_contour_tail_start_matches_expm_and_stays_normalised():
    """Start in the tail (amplification e^15 at gamma = 30): the contour route (auto) against
    expm_multiply to 1e-10 of the peak; a start at the mode against the eigen route."""
    m = Model(1.0, 0.7, 0.2, 30.0)
    g = resolved_grid(m, extra=[1.6], t_min=0.3)
    _, _, log_pi = symmetric_generator(m, g)
    p0 = initial_delta(g, 1.6)
    assert amplification(log_pi, p0) > 9.0          # the eigen route would not be trusted
    t = np.array([0.3, 1.0])
    pc = propagate(m, g, p0, t)
    px = propagate(m, g, p0, t, method="expm")
    assert np.abs(pc - px).max() < 1e-10 * px.max()
    assert np.abs(pc.sum(axis=1) - 1.0).max() < 1e-9
    mode = initial_delta(g, 0.0)
    pe = propagate(m, g, mode, t, method="eigen")
    assert np.abs(propagate(m, g, mode, t) - pe).max() < 1e-10 * pe.max()


def _exact_stats(m, v0, times):
    g = resolved_grid(m, extra=[v0], t_min=min(times))
    v = np.union1d(np.linspace(g.v[0], g.v[-1], 20001), [0.0])
    f = exact.propagator(m, v, times, v0)
    mean = integrate.trapezoid(f * v, v, axis=1)
    var = integrate.trapezoid(f * (v - mean[:, None]) ** 2, v, axis=1)
    neg = v <= 0
    p_neg = integrate.trapezoid(f[:, neg], v[neg], axis=1)
    return mean, var, p_neg


@pytest.mark.slow
@pytest.mark.parametrize("a,v0", [(0.3, 1.0), (0.3, -0.6), (1.2, 1.0), (1.2, -1.0)])
def test_propagator_matches_monte_carlo(a, v0):
    """Mean, variance and P(v < 0) at t = 0.3 and 1.0 within 4 MC standard errors, for
    a < Delta and a > Delta, v0 of both signs.

    The MC time-step bias is measured, not assumed: the same Wiener paths integrated with
    dt and 2 dt (weak order 1: bias(dt) ~ est(dt) - est(2 dt)) must differ by less than one
    standard error of the main comparison, so the standard error dominates.
    """
    m = Model(1.0, 0.7, a, 10.0)
    times = (0.3, 1.0)
    dt, n = 1e-3, 40_000
    e = simulate_sde(m, v0=v0, t_end=1.0, replicas=n, seed=31, dt=dt, sample_dt=0.1)
    mean, var, p_neg = _exact_stats(m, v0, times)
    ses = []
    for k, t in enumerate(times):
        x = e.at(t)
        d2 = (x - mean[k]) ** 2
        se = (math.sqrt(var[k] / n), math.sqrt(np.var(d2) / n), math.sqrt(p_neg[k] * (1 - p_neg[k]) / n))
        ses.append(se)
        assert abs(x.mean() - mean[k]) < 4 * se[0]
        assert abs(d2.mean() - var[k]) < 4 * se[1]
        assert abs((x < 0).mean() - p_neg[k]) < 4 * se[2]

    n_b = 4000
    noise = standard_noise(5, n_b, 1000)
    fine = simulate_sde(m, v0=v0, t_end=1.0, replicas=n_b, seed=5, dt=dt, sample_dt=0.1, noise=noise)
    coarse = simulate_sde(m, v0=v0, t_end=1.0, replicas=n_b, seed=5, dt=2 * dt, sample_dt=0.1,
                          noise=(noise[:, 0::2] + noise[:, 1::2]) / math.sqrt(2.0))
    for k, t in enumerate(times):
        xf, xc = fine.at(t), coarse.at(t)
        assert abs(xf.mean() - xc.mean()) < ses[k][0]
        assert abs(xf.var() - xc.var()) < ses[k][1]
        assert abs((xf < 0).mean() - (xc < 0).mean()) < ses[k][2]


def test_bad_input_names_the_parameter():
    m = Model(1.0, 0.7, 0.2, 10.0)
    v = np.linspace(-1, 1, 11)
    with pytest.raises(ValueError, match="t must be finite and > t0"):
        exact.propagator(m, v, 0.0, 0.5)
    with pytest.raises(ValueError, match="t must be finite and > t0"):
        exact.propagator(m, v, [1.0, 0.5], 0.5, t0=0.7)
    with pytest.raises(ValueError, match="1-D"):
        exact.propagator(m, v, np.ones((2, 2)), 0.5)
    with pytest.raises(ValueError, match="v0"):
        exact.propagator(m, v, 1.0, float("nan"))
    with pytest.raises(ValueError, match="v must be finite"):
        exact.propagator(m, [0.0, np.inf], 1.0, 0.5)
    with pytest.raises(ValueError, match="model"):
        exact.propagator("model", v, 1.0, 0.5)
    with pytest.raises(ValueError, match="either grid or h"):
        exact.propagator(m, v, 1.0, 0.5, grid=Grid(0.01, -100, 100), h=0.01)
    with pytest.raises(ValueError, match="v0=.*outside the grid"):
        exact.propagator(m, v, 1.0, 5.0, grid=Grid(0.01, -100, 100))
    with pytest.raises(ValueError, match="method"):
        exact.propagator(m, v, 1.0, 0.5, method="magic")
    with pytest.raises(ValueError, match="h must be"):
        exact.propagator(m, v, 1.0, 0.5, h=-0.1)
