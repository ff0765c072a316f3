"""Stationary observables of the stick-slip model at finite noise (exact, not weak-noise).

The stationary law ``p_s = exp(-gamma U)/Z`` (eq. (6)) has a kink at ``v = 0`` for the sgn
law, so every integral is split at 0 ("half lines"):

* ``epsilon = 0``: on ``v > 0``, ``exp(-gamma U)`` is the Gaussian ``N(mu_+, s^2)`` with
  ``mu_+ = (a - Delta) tau_m``, ``s^2 = tau_m/gamma`` truncated to ``v > 0``; on ``v < 0`` it is
  ``N(mu_-, s^2)``, ``mu_- = (a + Delta) tau_m``, truncated to ``v < 0``.  Weights, means and
  variances are closed forms in ``log_ndtr`` and the inverse Mills ratio; deep truncations
  (``mu/s < -5``, large gamma) use Laplace's continued fraction so nothing cancels.
* ``epsilon > 0``: adaptive quadrature (``quad_vec``) on each half line, about the most
  probable point of that half line, with the Boltzmann factor scaled there.

Dynamics (autocorrelation, Green-Kubo diffusion) use the Scharfetter-Gummel grid of
:mod:`analogue.theory.fokker_planck`, whose discrete stationary state is exactly
``exp(-gamma U)`` at the nodes:

* ``diffusion``: ``D_x = int_0^inf C(t) dt = sum_i dv_i g_i`` with ``L g = -(v - <v>) p_s``
  (the Poisson equation).  For a nearest-neighbour chain with detailed balance it is solved
  exactly by one cumulative sum: the flux through link ``i -> i+1`` is
  ``J_i = F_i = sum_{k <= i} dv_k pi_k`` and ``J_i = k_{i->i+1} pi_i (psi_i - psi_{i+1})`` with
  ``psi = g/pi``, so ``D_x = sum_i F_i^2 / (k_{i->i+1} pi_i)`` -- the discrete form of
  ``gamma int G(v)^2 / p_s(v) dv``, ``G(v) = int_{-inf}^v (u - <v>) p_s(u) du``.  The grid error
  is O(h^2); two grids (h, h/2) and Richardson extrapolation remove its leading term.
* ``autocorrelation``: spectral sum ``C(t) = sum_k w_k exp(lambda_k t)`` with
  ``w_k = (q_k . (dv sqrt(pi)))^2`` from the symmetrised generator (all weights >= 0, so no
  cancellation), also Richardson-extrapolated over (h, h/2).
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import integrate, special
from scipy.linalg import eigh_tridiagonal
from scipy.sparse.linalg import expm_multiply

from .. import checks
from ..model import Model
from . import family
from .exact_grid import resolved_grid
from .fokker_planck import Grid, generator, symmetric_generator
from .propagation import CONTOUR_MIN_NODES, _talbot
# StationaryMoments lives below this module and the family's (both return it); re-exported here,
# where it has always been imported from.
from .moments import StationaryMoments

__all__ = ["StationaryMoments", "stationary_moments", "half_line_moments", "diffusion_coefficient",
           "autocorrelation", "sample_stationary", "stationary_std", "central_bin_bias",
           "CENTRAL_BIN", "stick_fraction_theory", "integrated_autocorrelation"]

_SQRT_2PI = math.sqrt(2.0 * math.pi)
# Beyond this depth of truncation (mu/s < -_CF_SWITCH) the truncated-Gaussian formulas cancel;
# the continued fraction (which converges fast there) takes over.
_CF_SWITCH = 5.0
_CF_TERMS = 400


def _check_model(model: object) -> None:
    checks.instance("model", model, Model, description="an analogue.Model")


def _check_h(h: object) -> None:
    if h is not None:
        checks.positive("h", h)


# ---------------------------------------------------------------- truncated Gaussians (eps = 0)
def _upper_truncated_standard(z: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Mean and variance of ``Y = X | X > 0`` for ``X ~ N(z, 1)`` (vectorised in z).

    Direct: ``E = z + l``, ``Var = 1 - l (z + l)`` with ``l = phi(z)/Phi(z)``.  For ``z < -5``,
    with ``x = -z`` and Laplace's continued fraction ``f_k = k/(x + f_{k+1})``, the identities
    ``E = f_1`` and ``Var = f_1^2 f_2 (x + 2 f_2 - f_3)/2`` avoid the cancellation.
    """
    z = np.asarray(z, dtype=float)
    mean = np.empty_like(z)
    var = np.empty_like(z)
    direct = z >= -_CF_SWITCH
    zd = z[direct]
    lam = np.exp(-0.5 * zd * zd - math.log(_SQRT_2PI) - special.log_ndtr(zd))
    mean[direct] = zd + lam
    var[direct] = 1.0 - lam * (zd + lam)
    x = -z[~direct]
    f = np.zeros_like(x)
    f2 = f3 = f
    for k in range(_CF_TERMS, 0, -1):
        f, f2, f3 = k / (x + f), f, f2
    mean[~direct] = f
    var[~direct] = f * f * f2 * (x + 2.0 * f2 - f3) / 2.0
    return mean, var


@dataclass(frozen=True)
class _Halves:
    """Per-half-line pieces: log weights (of exp(-gamma U)), conditional means and variances,
    conditional <friction sign>, for v > 0 ('p') and v < 0 ('m')."""

    log_zp: float
    log_zm: float
    mean_p: float
    mean_m: float
    var_p: float
    var_m: float
    sign_p: float
    sign_m: float

    @property
    def p_positive(self) -> float:
        return float(special.expit(self.log_zp - self.log_zm))

    @property
    def p_negative(self) -> float:
        return float(special.expit(self.log_zm - self.log_zp))

    @property
    def log_z(self) -> float:
        return float(np.logaddexp(self.log_zp, self.log_zm))


def _half_log_gauss(z: float) -> float:
    """``z^2/2 + ln Phi(z)`` without the cancellation of two huge terms when z << 0."""
    if z < 0:
        return math.log(0.5 * float(special.erfcx(-z / math.sqrt(2.0))))
    return 0.5 * z * z + float(special.log_ndtr(z))


def _halves_sgn(model: Model) -> _Halves:
    s = model.velocity_scale
    mu_p = (model.a - model.delta) * model.tau_m
    mu_m = (model.a + model.delta) * model.tau_m
    (ep, em), (vp, vm) = _upper_truncated_standard(np.array([mu_p / s, -mu_m / s]))
    log_zp = math.log(s * _SQRT_2PI) + _half_log_gauss(mu_p / s)
    log_zm = math.log(s * _SQRT_2PI) + _half_log_gauss(-mu_m / s)
    return _Halves(log_zp, log_zm, s * ep, -s * em, s * s * vp, s * s * vm, 1.0, -1.0)


def _halves_quad(model: Model) -> _Halves:
    """Quadrature on each half line; valid for both laws (used for epsilon > 0, and as an
    independent check of the closed forms for epsilon = 0)."""
    g, eps = model.gamma, model.epsilon
    width = model.velocity_scale
    c = model.potential_minimum()
    out = {}
    for side, sgn in (("p", 1.0), ("m", -1.0)):
        # Most probable point of this half line: the mode if it lies there, else v = 0.
        r = c if sgn * c > 0 else 0.0
        # one-sided |U'(0)| on this half line (the sgn law has a kink there)
        slope = abs((sgn * model.delta if eps == 0 else 0.0) - model.a) if r == 0.0 else 0.0
        scales = [width] + ([eps] if eps > 0 else []) + ([1.0 / (g * slope)] if slope > 0 else [])
        small = min(scales)
        # U'' >= 1/tau_m and r minimises U on the half line => integrand <= exp(-(v-r)^2/(2 s^2)).
        if sgn > 0:
            lo, hi = max(0.0, r - 40.0 * width), r + 40.0 * width
        else:
            lo, hi = r - 40.0 * width, min(0.0, r + 40.0 * width)
        pts = {r}
        for k in (1.0, 10.0, 100.0):
            pts.update((r + k * small, r - k * small))
        if eps > 0:
            pts.update((eps, -eps, 10 * eps, -10 * eps))
        breaks = sorted(p for p in pts if lo < p < hi)
        ur = float(model.potential(r))

        def integrand(v: float, r: float = r, ur: float = ur) -> np.ndarray:
            w = math.exp(-g * (float(model.potential(v)) - ur))
            d = v - r
            fr = math.tanh(v / eps) if eps > 0 else math.copysign(1.0, v) if v != 0 else 0.0
            return np.array([w, w * d, w * d * d, w * fr])

        val, _ = integrate.quad_vec(integrand, lo, hi, points=breaks or None, epsabs=0.0,
                                    epsrel=1e-12, limit=2000)
        z, m1, m2, fs = val
        m1, m2 = m1 / z, m2 / z
        out[side] = (math.log(z) - g * ur, r + m1, m2 - m1 * m1, fs / z)
    (lzp, ep, vp, sp), (lzm, em, vm, sm) = out["p"], out["m"]
    return _Halves(lzp, lzm, ep, em, vp, vm, sp, sm)


def half_line_moments(model: Model, method: str = "auto") -> _Halves:
    """Per-half-line weights and conditional moments; ``method`` is "closed" (sgn law only),
    "quad", or "auto" (closed for epsilon = 0, quad otherwise).  The paper's model only (the
    half-line Gaussians and the convexity of U are used); family members: :mod:`.family`."""
    _check_model(model)
    if not model.is_paper:
        raise ValueError("half_line_moments is for the paper's model; use "
                         "analogue.theory.family.stationary_moments for the family")
    if method == "auto":
        method = "closed" if model.epsilon == 0 else "quad"
    if method == "closed":
        if model.epsilon != 0:
            raise ValueError("method='closed' needs epsilon == 0 (the sgn law)")
        return _halves_sgn(model)
    if method == "quad":
        return _halves_quad(model)
    raise ValueError(f"method must be 'auto', 'closed' or 'quad', got {method!r}")


# -------------------------------------------------------------------------- grid dynamics
def _grid_pieces(model: Model, grid: Grid
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    diag, off, log_pi = symmetric_generator(model, grid)
    lp = log_pi - log_pi.max()
    lp -= math.log(np.sum(np.exp(lp)))
    with np.errstate(under="ignore"):
        pi = np.exp(lp)
    return diag, off, lp, pi


def _cumulative_flux(v: np.ndarray, pi: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """``(dv, F, mode)``: ``dv = v - <v>``, the cumulative flux ``F_i = sum_{j <= i} dv_j
    pi_j`` between nodes i and i + 1, summed from whichever end is nearer (left of the mode
    from the left, right of it from the right, where F_i = -sum_{j > i}), so the tails are
    not differences of O(1) numbers; and the mode's index."""
    dv = v - np.sum(v * pi)  # pairwise sum: no BLAS thread-count rounding
    f = dv * pi
    left = np.cumsum(f)[:-1]
    right = -np.cumsum(f[::-1])[::-1][1:]
    mode = int(np.argmax(pi))
    return dv, np.where(np.arange(v.size - 1) < mode, left, right), mode


def _diffusion_on_grid(model: Model, grid: Grid) -> float:
    """Exact solution of the discrete Poisson equation (see module docstring)."""
    _, off, lp, pi = _grid_pieces(model, grid)
    _, flux, _ = _cumulative_flux(grid.v, pi)
    # k_{i->i+1} pi_i = sqrt(k_up k_down) sqrt(pi_i pi_{i+1}) by detailed balance.
    # Summed in log space: far in the tails both F^2 and the conductance underflow.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        log_cond = np.log(off) + 0.5 * (lp[:-1] + lp[1:])
        terms = np.exp(2.0 * np.log(np.abs(flux)) - log_cond)
    return float(np.sum(terms[flux != 0.0]))


def _refined_grids(model: Model, h: float | None, extra: Iterable[float] = ()
                   ) -> tuple[Grid, Grid]:
    coarse = resolved_grid(model, extra=extra, h=h)
    fine = Grid(coarse.h / 2.0, 2 * coarse.i_min, 2 * coarse.i_max)
    return coarse, fine


def diffusion_coefficient(model: Model, h: float | None = None, richardson: bool = True) -> float:
    """Green-Kubo ``D_x = int_0^inf C(t) dt`` from the grid Poisson equation (module docstring);
    with ``richardson`` the results on h and h/2 are combined as ``(4 D_{h/2} - D_h)/3``."""
    _check_model(model)
    _check_h(h)
    if not model.is_paper:
        return float(family.stationary_moments(model, h=h).diffusion)
    coarse, fine = _refined_grids(model, h)
    d_fine = _diffusion_on_grid(model, fine)
    if not richardson:
        return d_fine
    return (4.0 * d_fine - _diffusion_on_grid(model, coarse)) / 3.0


_FULL_SPECTRUM_NODES = 6000
_PARTIAL_MODES = 300


def _autocorrelation_on_grid(model: Model, grid: Grid, lags: np.ndarray) -> np.ndarray:
    diag, off, lp, pi = _grid_pieces(model, grid)
    v = grid.v
    y = (v - np.dot(v, pi)) * np.sqrt(pi)
    total = float(y @ y)  # C(0): the grid variance
    if grid.n <= _FULL_SPECTRUM_NODES:
        lam, q = eigh_tridiagonal(diag, off)
        lam = np.minimum(lam, 0.0)
        w = (q.T @ y) ** 2
        return np.asarray(np.exp(np.outer(lags, lam)) @ w)
    # Large grids (small epsilon): only the slowest modes.  The weights are >= 0 and sum to
    # C(0), so the omitted modes contribute between 0 and rest * e^{lambda_cut t}; take the
    # midpoint, and fall back to expm_multiply where that bound is not negligible.
    k = min(grid.n, _PARTIAL_MODES)
    lam, q = eigh_tridiagonal(diag, off, select="i", select_range=(grid.n - k, grid.n - 1),
                              lapack_driver="stemr")
    lam = np.minimum(lam, 0.0)
    w = (q.T @ y) ** 2
    rest = max(total - float(w.sum()), 0.0)
    half_bound = 0.5 * rest * np.exp(lam.min() * lags)
    out = np.exp(np.outer(lags, lam)) @ w + half_bound
    out[lags == 0] = total
    todo = np.flatnonzero((half_bound > 1e-9 * total) & (lags > 0))
    if todo.size:
        gen = generator(model, grid).tocsc()
        dv = v - np.dot(v, pi)
        for i in todo:
            out[i] = float(dv @ expm_multiply(gen * lags[i], dv * pi))
    return np.asarray(out)


def autocorrelation(model: Model, lags: ArrayLike, h: float | None = None,
                    richardson: bool = True) -> np.ndarray:
    """Connected stationary velocity autocorrelation ``C(t) = <v(0) v(t)> - <v>^2`` at ``|lags|``
    (C is even in the lag; C(0) is the variance).  Spectral sum on the FP grid, Richardson
    extrapolated over (h, h/2) unless ``richardson=False``.  Accuracy at the default grid:
    ~1e-9 relative for Delta = 0 (OU closed form), C(0) equals the quadrature variance to
    < 2e-6 relative (tests).  For grids over 6000 nodes (small epsilon) only the 300 slowest
    modes are computed; the rest of the spectral weight (known: the weights sum to C(0)) is
    bounded and, for lags where that bound exceeds 1e-9 C(0), ``expm_multiply`` is used."""
    _check_model(model)
    _check_h(h)
    if not model.is_paper:
        return family.autocorrelation(model, lags, h=h)
    try:
        lags = np.asarray(lags, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("lags must be an array of real numbers") from None
    if not np.all(np.isfinite(lags)):
        raise ValueError("lags must be finite")
    flat = np.abs(lags.ravel())
    coarse, fine = _refined_grids(model, h)
    c_fine = _autocorrelation_on_grid(model, fine, flat)
    if richardson:
        c_fine = (4.0 * c_fine - _autocorrelation_on_grid(model, coarse, flat)) / 3.0
    return c_fine.reshape(lags.shape)


def _poisson_solution(model: Model, grid: Grid, observable: Callable[[np.ndarray], np.ndarray]
                      | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(diag, off, y, u)``: the symmetrised generator S (tridiagonal), ``y = (v - <v>)
    sqrt(pi)`` and a solution of ``S u = y`` (S is singular; y is orthogonal to its null
    vector sqrt(pi), and any solution serves :func:`_integrated_on_grid`).  With ``u =
    sqrt(pi) g`` the equation is the discrete Poisson equation of :func:`_diffusion_on_grid`:
    ``g_{i+1} - g_i = F_i / (k_{i->i+1} pi_i)`` with F_i the cumulative flux, summed outwards
    from the mode (no differences of O(1) numbers in the tails).  ``observable``: f(v) in
    place of v (``y = (f - <f>) sqrt(pi)``)."""
    diag, off, lp, pi = _grid_pieces(model, grid)
    values = grid.v if observable is None else _observable_on(observable, grid.v)
    dv, flux, mode = _cumulative_flux(values, pi)
    step = flux / (off * np.exp(0.5 * (lp[:-1] + lp[1:])))
    g = np.empty(grid.n)
    g[mode] = 0.0
    g[mode + 1:] = np.cumsum(step[mode:])
    g[:mode] = -np.cumsum(step[:mode][::-1])[::-1]
    root = np.sqrt(pi)
    return diag, off, dv * root, g * root


def _observable_on(observable: Callable[[np.ndarray], np.ndarray], v: np.ndarray) -> np.ndarray:
    f = np.asarray(observable(v), dtype=float)
    if f.shape != v.shape or not np.all(np.isfinite(f)):
        raise ValueError("observable must map a velocity array to finite values of the same "
                         "shape")
    return f


def _integrated_on_grid(model: Model, grid: Grid, taus: np.ndarray,
                        observable: Callable[[np.ndarray], np.ndarray] | None = None
                        ) -> np.ndarray:
    """``2 int_0^tau (tau - s) C(s) ds`` on one grid, for every tau (see
    :func:`integrated_autocorrelation`)."""
    from scipy.linalg import lapack
    diag, off, y, u = _poisson_solution(model, grid, observable)
    # Dot products by numpy's pairwise sum, not BLAS: a threaded OpenBLAS ddot rounds
    # differently with the thread count, and the report computes these both in its
    # one-BLAS-thread theory thread and in the main thread (the stationary rows' exact SE):
    # the same comparison must not differ in the last bit with where it was computed.
    d_x = -float(np.sum(y * u))            # Green-Kubo D = -y^T S^+ y
    uu = float(np.sum(u * u))
    z, c = _talbot(CONTOUR_MIN_NODES)
    uc = u.astype(complex)
    out = np.empty(taus.size)
    for k, tau in enumerate(taus):
        if tau == 0:
            out[k] = 0.0
            continue
        # u^T exp(tau S) u = 2 Re sum_j c_j u^T (z_j - tau S)^-1 u (S symmetric, spectrum <= 0)
        quad = 0.0 + 0.0j
        sub = (-tau * off).astype(complex)
        for zj, cj in zip(z, c):
            _, _, _, x, info = lapack.zgtsv(sub, zj - tau * diag, sub, uc)
            if info != 0:  # pragma: no cover - z_j is off the real spectrum
                raise np.linalg.LinAlgError(f"contour solve failed (info={info})")
            quad += cj * np.sum(u * x)
        out[k] = 2.0 * (2.0 * quad.real - uu + tau * d_x)
    return out


def integrated_autocorrelation(model: Model, taus: ArrayLike, h: float | None = None,
                               richardson: bool = True,
                               observable: Callable[[np.ndarray], np.ndarray] | None = None
                               ) -> np.ndarray:
    """``2 int_0^tau (tau - s) C(s) ds = Var(int_0^tau v ds)`` for every tau (C the connected
    stationary autocorrelation, :func:`autocorrelation`), in closed form on the FP grid:
    with ``y = (v - <v>) sqrt(pi)``, ``S u = y`` and ``D = -y^T u`` (Green-Kubo),

        2 int_0^tau (tau - s) y^T e^{s S} y ds = 2 [u^T e^{tau S} u - u^T u + tau D],

    (mode by mode ``(e^{tau lambda} - 1 - tau lambda)/lambda^2``), the one matrix function
    by the Talbot contour of :mod:`analogue.theory.propagation` (12 complex tridiagonal
    solves per tau, error <= 2.4e-14 u^T u), u by the discrete Poisson equation: O(n) per
    tau, no eigen-decomposition, no quadrature over lags.  Richardson extrapolated over
    (h, h/2) as :func:`autocorrelation`.  Paper's model only.

    ``observable``: a function f (vectorised) in place of v: ``Var(int_0^tau f(v(s)) ds)``,
    e.g. an indicator for the variance of a time-averaged probability (issue 18: the
    report's stationary SEs under the null, :func:`analogue.study.catalogue.stationary_exact_se`).
    An indicator whose edge falls between nodes converges at first order only: for the stick
    window |v| < 0.1 sqrt(tau_m/gamma) at tau_m = 2, Delta = 0.5, a = 0.3, gamma = 15 the
    single grid and the extrapolation differ by 0.3 %; against 400 Monte Carlo time averages
    over 12 tau the variance ratio is 0.98 (v), 0.95 ((v - <v>)^2), 1.07 (1[v > 0]) and 1.11
    (the stick window), each +- 0.07 (tests/unit/test_stationary_mean_se.py)."""
    _check_model(model)
    _check_h(h)
    if not model.is_paper:
        raise ValueError("integrated_autocorrelation: the paper's model only (family members: "
                         "integrate analogue.theory.family.autocorrelation)")
    ta = np.abs(np.asarray(taus, dtype=float))
    if not np.all(np.isfinite(ta)):
        raise ValueError("taus must be finite")
    flat = ta.ravel()
    coarse, fine = _refined_grids(model, h)
    out = _integrated_on_grid(model, fine, flat, observable)
    if richardson:
        out = (4.0 * out - _integrated_on_grid(model, coarse, flat, observable)) / 3.0
    return out.reshape(ta.shape)


# ---------------------------------------------------------------------------- public moments
def stationary_moments(model: Model, h: float | None = None) -> StationaryMoments:
    """Exact stationary mean, variance, P(v > 0), P(v < 0), mean friction sign and Green-Kubo
    diffusion coefficient (see the module docstring for the methods).

    ``h`` overrides the FP grid spacing used for ``diffusion`` only.  Accuracy: the moments are
    at round-off level (closed forms) or ~1e-11 relative (quadrature); ``diffusion`` is
    Richardson-extrapolated and changes by < 1e-5 relative when h is halved at the default
    spacing (tests check this).
    """
    _check_model(model)
    _check_h(h)
    halves = half_line_moments(model)
    pp, pm = halves.p_positive, halves.p_negative
    mean = pp * halves.mean_p + pm * halves.mean_m
    var = pp * halves.var_p + pm * halves.var_m + pp * pm * (halves.mean_p - halves.mean_m) ** 2
    sign = pp * halves.sign_p + pm * halves.sign_m
    d = diffusion_coefficient(model, h=h)
    return StationaryMoments(mean=float(mean), variance=float(var), p_positive=pp, p_negative=pm,
                             mean_sign=float(sign), diffusion=d, drift=float(mean))


# ------------------------------------------------------------------------------- sampling
def sample_stationary(model: Model, size: int | tuple[int, ...],
                      seed: int | np.random.SeedSequence | np.random.Generator | None = None
                      ) -> np.ndarray:
    """Independent draws from ``p_s = exp(-gamma U)/Z`` (eq. (6)).

    ``epsilon = 0``: choose the half line with probability P(v > 0), then invert the truncated
    Gaussian's survival function in log space (``ndtri_exp``: exact, stable far in the tails).
    ``epsilon > 0``: inverse of the CDF tabulated by the trapezoid rule on a grid of spacing
    ``min(sqrt(tau_m/gamma)/400, epsilon/20)`` over the mode +- 40 widths (CDF error O(h^2)).
    ``seed``: None, an int, a SeedSequence or a numpy Generator.  Other members of the model
    family: :func:`analogue.theory.family.sample_stationary`.
    """
    _check_model(model)
    if not model.is_paper:
        return family.sample_stationary(model, size, seed)
    sizes = np.atleast_1d(np.asarray(size, dtype=object))
    if not all(isinstance(s, (int, np.integer)) and not isinstance(s, bool) for s in sizes):
        raise ValueError(f"size must be an int or a tuple of ints, got {size!r}")
    shape = tuple(int(s) for s in sizes)
    if any(s < 0 for s in shape):
        raise ValueError(f"size must be >= 0, got {size!r}")
    if np.ndim(size) == 0:
        shape = shape[:1]  # a plain int: one dimension
    rng = np.random.default_rng(seed)
    if model.epsilon == 0:
        halves = _halves_sgn(model)
        s = model.velocity_scale
        upper = rng.random(shape) < halves.p_positive
        u = rng.random(shape)
        log_u = np.log1p(-u)  # log of a uniform on (0, 1]
        z = np.where(upper, (model.a - model.delta) * model.tau_m / s,
                     -(model.a + model.delta) * model.tau_m / s)
        # Y = X | X > 0 with X ~ N(z, 1):  P(Y > y) = Phi(z - y)/Phi(z)
        y = z - special.ndtri_exp(log_u + special.log_ndtr(z))
        y = np.maximum(y, 0.0)
        return np.asarray(s * np.where(upper, y, -y))
    c = model.potential_minimum()
    width = model.velocity_scale
    h = min(width / 400.0, model.epsilon / 20.0)
    n = int(math.ceil(80.0 * width / h))
    if n > 2_000_000:
        raise ValueError("epsilon is too small against sqrt(tau_m/gamma) for the tabulated "
                         "inverse CDF (more than 2e6 nodes)")
    v = np.linspace(c - 40.0 * width, c + 40.0 * width, n + 1)
    dens = np.exp(-model.gamma * (model.potential(v) - model.potential(c)))
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]))])
    cdf /= cdf[-1]
    return np.interp(rng.random(shape), cdf, v)


# ------------------------------------------------- closed forms used by the circuit mapping
# (moved from analogue.circuit.mapping: one home for the stationary law's closed forms)
CENTRAL_BIN = 0.1  # width of the reference histogram bin, in stationary standard deviations


def _positive_part_moments(mu: float, s: float) -> tuple[float, float]:
    """Mean and variance of N(mu, s^2) conditioned on > 0.  With alpha = -mu/s and the Mills
    ratio lam = phi(alpha)/Phi(-alpha): mean = mu + s lam, var = s^2 (1 + alpha lam - lam^2);
    for alpha > 40 that difference loses more than 6 digits and the asymptotic series
    lam - alpha = 1/alpha - 2/alpha^3 + 10/alpha^5, var/s^2 = 1/alpha^2 - 6/alpha^4 + 50/alpha^6
    is used instead (relative error < 2e-7)."""
    alpha = -mu / s
    if alpha > 40.0:
        a2 = alpha * alpha
        excess = (1.0 - 2.0 / a2 + 10.0 / a2**2) / alpha
        return s * excess, s * s * (1.0 - 6.0 / a2 + 50.0 / a2**2) / a2
    lam = math.sqrt(2.0 / math.pi) / float(special.erfcx(alpha / math.sqrt(2.0)))
    return mu + s * lam, s * s * (1.0 + alpha * lam - lam * lam)


def stationary_std(model: Model) -> float:
    """Standard deviation of the exact (sgn-law) stationary law p_s ~ exp(-gamma U) (eq.
    (6)), in closed form: on each half line p_s is a truncated Gaussian of variance
    tau_m/gamma centred at (a - Delta) tau_m (v > 0) or (a + Delta) tau_m (v < 0).  In the stick
    regime at weak noise it is ~ 1/(gamma (Delta - |a|)), far below sqrt(tau_m/gamma): the
    scale the smoothing must be small against."""
    tau, g, s = model.tau_m, model.gamma, model.velocity_scale
    means, variances, logw = [], [], []
    for sign, centre in ((1.0, (model.a - model.delta) * tau), (-1.0, (model.a + model.delta) * tau)):
        mu = sign * centre  # the piece in y = sign * v > 0 is N(mu, s^2) truncated to y > 0
        m, v = _positive_part_moments(mu, s)
        means.append(sign * float(m))
        variances.append(float(v))
        logw.append(g * mu * mu / (2 * tau) + float(special.log_ndtr(mu / s)))
    w = np.exp(np.array(logw) - max(logw))
    w /= w.sum()
    mean = float(np.dot(w, means))
    second = float(np.dot(w, np.array(variances) + np.array(means) ** 2))
    return math.sqrt(max(second - mean * mean, 0.0))


def central_bin_bias(model: Model, epsilon: float, std: float | None = None) -> float:
    """``|P_eps(B) / P_0(B) - 1|`` for the central bin ``B = {|v| < b/2}``, ``b = 0.1``
    stationary standard deviations, under the stationary law p_s ~ exp(-gamma U) (eq. (6))
    with the smoothed (width ``epsilon``) and the exact sgn friction law: the bias of a
    histogram at the finest resolution the experiments use, at v = 0 where smoothing acts.

    ``U_eps - U_0 = Delta eps (ln(1 + e^{-2|v|/eps}) - ln 2)``: a constant (absorbed by the
    normaliser) beyond ~20 eps, so only integrals over |v| < 20 eps are needed."""
    if epsilon == 0 or model.delta == 0:
        return 0.0
    std = stationary_std(model) if std is None else std
    exact = model.replace(epsilon=0.0)
    gde = model.gamma * model.delta * epsilon

    def h(v: np.ndarray) -> np.ndarray:  # exp(-gamma (U_eps - U_0) - gamma Delta eps ln 2)
        return np.asarray(np.exp(-gde * np.log1p(np.exp(-2.0 * np.abs(v) / epsilon))))

    # Normaliser ratio Z_eps/(Z_0 e^{gamma Delta eps ln2}) = 1 + R, R = E_0[h - 1]
    span = 20.0 * epsilon
    v = np.linspace(-span, span, 8001)
    p0 = np.exp(-model.gamma * exact.potential(v) - exact.log_normaliser())
    R = float(np.trapezoid(p0 * (h(v) - 1.0), v))
    half = 0.5 * CENTRAL_BIN * std
    v = np.linspace(-half, half, 4001)  # v = 0 is a node, so the kink of p_0 is on the grid
    u0 = exact.potential(v)
    # shifted by the bin's lowest U: in the slip regime at weak noise gamma U_0 is far below 0
    # on the bin and exp(-gamma U_0) overflows; the ratio of integrals is unchanged.
    g0 = np.exp(-model.gamma * (u0 - u0.min()))
    ratio = float(np.trapezoid(g0 * h(v), v) / np.trapezoid(g0, v)) / (1.0 + R)
    return abs(ratio - 1.0)


def _log_phi_diff(u1: float, u2: float) -> float:
    """ln(Phi(u2) - Phi(u1)) for u1 < u2, accurate in both tails."""
    if u1 > 0:  # upper tail: Phi(u2) - Phi(u1) = Phi(-u1) - Phi(-u2)
        a, b = special.log_ndtr(-u1), special.log_ndtr(-u2)
    else:
        a, b = special.log_ndtr(u2), special.log_ndtr(u1)
    return float(a + np.log1p(-np.exp(b - a)))


def stick_fraction_theory(model: Model, threshold: float) -> float:
    """Exact stationary ``P(|v| < threshold) = integral_{-th}^{th} p_s(v) dv`` (eq. (6)).

    For the sgn law each half line is a Gaussian piece: on v > 0,
    ``exp(-gamma U) = exp(gamma b^2 tau_m / 2) exp(-(v + b tau_m)^2 / (2 s^2))`` with
    ``b = Delta - a`` and ``s^2 = tau_m/gamma`` (mirror with ``b = Delta + a`` on v < 0), so
    the integral is a difference of normal CDFs.  With epsilon > 0 it is integrated
    numerically.
    """
    checks.instance("model", model, Model, description="an analogue.Model")
    th = checks.positive("threshold", threshold, allow_inf=True)
    if math.isinf(th):
        return 1.0
    g, tau = model.gamma, model.tau_m
    if model.epsilon == 0:
        s = math.sqrt(tau / g)
        def half(b: float) -> float:
            return (math.log(s * math.sqrt(2 * math.pi)) + 0.5 * g * b * b * tau
                    + _log_phi_diff(b * tau / s, (th + b * tau) / s))
        log_mass = np.logaddexp(half(model.delta - model.a), half(model.delta + model.a))
        return float(min(1.0, math.exp(log_mass - model.log_normaliser())))
    val, _ = integrate.quad(lambda v: float(model.stationary_pdf(v)), -th, th, points=[0.0],
                            limit=400, epsabs=0, epsrel=1e-11)
    return float(min(1.0, val))
