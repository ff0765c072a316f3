"""The certified shifted inverse iteration for the tilted generator's principal eigenpair
(work_statistics._top_eigenpair with a guess) against LAPACK's bisection (the route without a
guess), the OU closed form at Delta = 0, and the sweep against per-w LAPACK roots.
No timings are asserted (benchmarks/bench_theory.py, sections 1 and 8, measures them)."""
import numpy as np
import pytest

from analogue import Model
from analogue.theory import ornstein_uhlenbeck as ou
from analogue.theory import work_statistics as ws


def _operator(a, gamma, k):
    """The refined (h/2) operator of the report's mesh for this gamma, and its nodes."""
    m = Model(tau_m=1.0, delta=1.0, a=a, gamma=gamma)
    h = ws.tilted_grid_spacing(m)
    if ws._mesh_kind(m, h, "auto") == "graded":
        v = ws._refined(ws._graded_nodes(m, k, h))
        d, e = ws._mesh_operator(m, v, k, ws._kink_half_width(m, h / 2))
    else:
        g = ws._grid_for(m, k, h)
        g = ws.Grid(h / 2, 2 * g.i_min, 2 * g.i_max)
        d, e = ws.tilted_operator(m, g, k)
        v = g.v
    return d, e, v


@pytest.mark.parametrize("a", [0.5, 1.5])
@pytest.mark.parametrize("gamma", [10.0, 100.0, 1000.0])
def test_shifted_inverse_iteration_equals_lapack(a, gamma):
    """Eigenvalue within 2 eps ||T||_inf of LAPACK's (both are at the rounding of the matrix
    entries; measured <= 0.3 eps ||T||), <v> within 1e-9 (measured 1e-10), for guesses
    below, above and far from the eigenvalue."""
    rng = np.random.default_rng(7)
    for k in np.linspace(-2.0 * gamma, gamma, 4):
        d, e, v = _operator(a, gamma, k)
        lam, phi = ws._top_eigenpair(d, e)
        norm = float(np.max(np.abs(d)) + 2.0 * np.max(e))
        for guess in (lam - 1.0, lam + 0.3, lam * (1 + 1e-3 * rng.standard_normal()), lam - 50.0):
            out = ws._top_eigenpair_shifted(d, e, guess)
            assert out is not None
            lam2, x = out
            assert abs(lam2 - lam) <= 2 * np.finfo(float).eps * norm
            assert np.all(x > 0)                     # the Perron vector: the top state
            assert abs(float((x * x) @ v) - float((phi * phi) @ v)) < 1e-9


def test_shifted_inverse_iteration_falls_back_without_positive_coupling():
    d = np.array([1.0, 2.0, 3.0, 4.0])
    e = np.array([0.5, -0.5, 0.5])
    assert ws._top_eigenpair_shifted(d, e, 4.0) is None
    lam, x = ws._top_eigenpair(d, e, 4.0)           # LAPACK answers
    assert lam == pytest.approx(np.linalg.eigvalsh(np.diag(d) + np.diag(e, 1) + np.diag(e, -1))[-1])


def test_sweep_on_ou_equals_closed_form():
    """Delta = 0: every root of the sweep (shifted inverse iteration after k = 0) against the
    OU rate function in closed form, both signs of w (no fluctuation-relation shortcut)."""
    m = Model(tau_m=0.8, delta=0.0, a=0.5, gamma=10.0, mass=1.3)
    w = np.linspace(-1.5, 1.7, 17)
    np.testing.assert_allclose(ws.rate_function(m, w), ou.rate_function(m, w), atol=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("a, w", [(0.5, (-0.9, -0.3, 0.3, 0.9)), (1.5, (-1.6, 0.6, 1.6))])
def test_sweep_equals_per_w_lapack_roots_at_gamma_100(a, w):
    """The sweep (shared memo, shifted inverse iteration) against every w bracketed from k = 0
    with LAPACK eigenpairs on the same graded mesh: equal to 1e-9 off the stuck/slide
    crossing (measured 5e-10)."""
    m = Model(tau_m=1.0, delta=1.0, a=a, gamma=100.0)
    w = np.array(w)
    h = ws.tilted_grid_spacing(m)
    mean = float(ws._scgf_pair(m, 0.0, h, mesh="graded")[1])
    old = np.array([max(k * wi - lam, 0.0) / m.gamma for wi in w
                    for k, lam in [ws._legendre_root(m, float(wi), h, mean, "graded")]])
    np.testing.assert_allclose(ws.rate_function(m, w), old, atol=1e-9)
