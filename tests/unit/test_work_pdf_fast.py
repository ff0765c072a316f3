"""work_pdf's matrix-exponential route (propagator="expm", the default) against the
eigen-decomposition route it replaced (propagator="eig", kept callable), against the real-k
generating function from a symmetric eigen-decomposition, and against the Ornstein-Uhlenbeck
closed form at Delta = 0.  No timings are asserted (benchmarks/bench_theory.py measures them)."""
import math

import numpy as np
import pytest

from analogue import Model
from analogue.theory import ornstein_uhlenbeck as ou
from analogue.theory import work_statistics as ws
from analogue.theory.fokker_planck import Grid

FIG8 = Model(tau_m=1.0, delta=1.0, a=0.5, gamma=10.0)
OU = Model(tau_m=1.0, delta=0.0, a=0.5, gamma=10.0)


def _reduced(model, k0, modes, propagator):
    h = ws.tilted_grid_spacing(model)
    g1 = ws._grid_for(model, k0, h, extra=ws._tilt_centres(model, 0.0))
    grid = Grid(h / 2.0, 2 * g1.i_min, 2 * g1.i_max)
    return ws._Reduced(model, k0, grid, modes, propagator)


@pytest.mark.parametrize("tau, k0", [(1.0, 0.5), (1.0, -0.5), (5.0, 0.2)])
def test_reduced_generating_function_expm_equals_eig_and_real_axis(tau, k0):
    """G(k0 + iy)/G(k0) on 24 contour points (up to y = 300, where |G| has dropped to
    ~1e-4): the Pade exponential and the eigen-decomposition agree to 1e-11 (the eig route's
    round-off floor is ~1e-10 at the smallest values, measured 1e-13 typical); at y = 0 both
    equal the real-axis value from the symmetric eigen-decomposition (log_g_and_derivatives)."""
    # single-threaded BLAS as in work_pdf (threaded, small problems run 10-30x slower)
    with ws._single_threaded():
        red_x = _reduced(FIG8, k0, 96, "expm")
        red_e = _reduced(FIG8, k0, 96, "eig")
        K, _ = red_x.log_g_and_derivatives(k0, tau)
        y = np.concatenate([np.linspace(0.0, 20.0, 12), np.linspace(25.0, 300.0, 12)])
        # relative to exp(tau * shift) = G(k0): f = G(k0 + iy)/G(k0)
        fx = np.exp(red_x.log_g_complex(k0 + 1j * y, tau, K / tau))
        fe = np.exp(red_e.log_g_complex(k0 + 1j * y, tau, K / tau))
    np.testing.assert_allclose(fx, fe, rtol=0, atol=1e-11)
    assert abs(fx[0] - 1.0) < 1e-12
    assert np.all(np.abs(fx) <= 1.0 + 1e-12)  # |G(k + iy)| <= G(k): a moment generating function


def test_propagator_is_validated():
    with pytest.raises(ValueError, match="propagator"):
        ws.work_pdf(OU, [0.5], 2.0, propagator="krylov")


@pytest.mark.parametrize("tau, rtol", [(1.0, 2e-5), (2.0, 1e-6)])
def test_expm_route_equals_ou_closed_form(tau, rtol):
    """Delta = 0: the Gaussian closed form, +-3 sd.  Documented accuracy of work_pdf (old
    route, measured): 6e-6 at tau = 1, 2e-8 at tau >= 2; the tolerances leave a margin."""
    mean = OU.force * OU.tau_m * OU.a
    sd = math.sqrt(float(ou.work_variance(OU, tau))) / tau
    w = np.linspace(mean - 3 * sd, mean + 3 * sd, 7)
    np.testing.assert_allclose(ws.work_pdf(OU, w, tau), ou.work_pdf(OU, w, tau), rtol=rtol)


@pytest.mark.slow
def test_expm_route_equals_eig_route_in_the_stick_regime():
    """Fig. 8 model at tau = 1 (the report's costliest window, 96-mode bases), 7 w over
    +-4 sd: the two routes give the same densities to 1e-5 (measured on 30 w: 3.3e-6 at most,
    where the eig route's ill-conditioned eigenvectors leave ~1e-10 in G and the contour sum
    cancels; 1e-14 elsewhere)."""
    tau = 1.0
    mean = float(ws.scgf_derivative(FIG8, 0.0))
    sd = float(np.sqrt(ws.work_variance(FIG8, [tau])[0]))
    w = np.linspace(mean - 4 * sd, mean + 4 * sd, 7)
    new = ws.work_pdf(FIG8, w, tau)
    old = ws.work_pdf(FIG8, w, tau, propagator="eig")
    np.testing.assert_allclose(new, old, rtol=1e-5)


@pytest.mark.slow
def test_shared_group_with_undecayed_tail_retries_with_more_modes():
    """Fig. 8 model, tau = 1, W above the stick peak (the report's quick bins): with 48 modes a
    shared contour there levels off at |G| ~ 1e-6 (a basis artifact: 96 and 144 modes decay
    below 1e-9), so its group retries with 96 modes instead of sending every W off alone.
    Against the 96-mode per-W route to 1e-5 (measured <= 7.6e-7; the 48-mode per-W values
    that the shared route used to fall back to differ from it by up to 3.1e-5)."""
    w = np.array([0.115, 0.148, 0.181, 0.214])
    with ws.recorded_fallbacks() as fallbacks:
        shared = ws.work_pdf(FIG8, w, 1.0)
    reference = ws.work_pdf(FIG8, w, 1.0, modes=96, share=False)
    assert not fallbacks
    np.testing.assert_allclose(shared, reference, rtol=1e-5)
