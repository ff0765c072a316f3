"""Exact power spectrum of the stationary velocity (not in the paper; issue 23 item 1).

Convention (one throughout the project): **two-sided, angular frequency**,

    S(omega) = int_{-inf}^{inf} C(t) e^{-i omega t} dt = 2 int_0^inf C(t) cos(omega t) dt,

with ``C(t) = <v(0) v(t)> - <v>^2`` the connected stationary autocorrelation of
:func:`analogue.theory.exact.autocorrelation`.  S is even in omega, and

* ``(1/2 pi) int_{-inf}^{inf} S(omega) d omega = C(0) = Var v`` (the stationary variance);
* ``S(0) = 2 int_0^inf C dt = 2 D_x`` with ``D_x`` the Green-Kubo diffusion coefficient of
  :class:`analogue.theory.stationary.StationaryMoments` (``Var x(t) ~ 2 D_x t``, as
  :func:`analogue.estimators.transport.transport` fits it).

The one-sided density in cycles per unit time that ``scipy.signal.welch(..., scaling=
"density")`` returns is ``G(f) = 2 S(2 pi f)`` (``int_0^inf G df = Var v``).  With Delta = 0
(Ornstein-Uhlenbeck) ``S(omega) = 2 tau_m^2 / (gamma (1 + omega^2 tau_m^2))``.

Method: the generator's resolvent.  With ``dv = v - <v>``,

    S(omega) = 2 Re <dv, (i omega - L)^{-1} (dv p_s)>.

* Gaussian-noise members (the paper's model and every 1-D gradient member): L is the
  Scharfetter-Gummel generator of :mod:`analogue.theory.fokker_planck`, similar to the
  symmetric tridiagonal ``S_L = Pi^{-1/2} L Pi^{1/2}``; with ``y = dv sqrt(pi)``,
  ``S(omega) = 2 Re y^T (i omega - S_L)^{-1} y = sum_k w_k 2 r_k / (omega^2 + r_k^2)``
  (``r_k = -lambda_k > 0``, ``w_k = (q_k . y)^2 >= 0``: a sum of Lorentzians with positive
  weights).  ``method="resolvent"`` (the default) does one complex tridiagonal solve per
  omega (LAPACK gtsv, O(n): 1 ms for 6 frequencies on 1127 nodes), and at omega = 0 the
  discrete Poisson equation of :mod:`analogue.theory.stationary`; ``"eigen"`` sums the
  Lorentzians of the full eigen-decomposition (1.4-2.7 s for the same grid here: the
  independent route the tests use, and the modes a plot of the relaxation rates needs).  The null mode
  ``sqrt(pi)`` (weight ~1e-32) is left out of the eigen sum; in the resolvent it would only
  add an imaginary part.  Grids h and h/2 are Richardson-combined ``(4 S_{h/2} - S_h)/3``
  like :func:`analogue.theory.stationary.autocorrelation` (the same grids, so S(0) is twice
  the same discrete D_x).
* Shot-noise members: the Kolmogorov-Feller generator of
  :mod:`analogue.theory.kolmogorov_feller` (not symmetrisable: jumps), one sparse complex LU
  of ``N (i omega - L)`` per omega on its banded form ``N L``; omega = 0 is the Green-Kubo
  solve of :mod:`analogue.theory.family`.  Richardson as the family's autocorrelation
  (weight 4 with Gaussian noise, 2 for pure shot noise, whose upwind drift is first order).

Accuracy (tests/unit/test_theory_spectrum.py; measured): Delta = 0 against the OU closed
form 1.6e-9 relative (Gaussian noise; 1.8e-8 with shot + Gaussian, 1.8e-4 for pure shot
noise, first order); the frequency integral equals the closed-form variance to 1.8e-7 -
5.2e-7 relative (stick, slip, tanh law); the Lorentzian sum at omega = 0 equals 2 D_x of
:func:`analogue.theory.exact.stationary_moments` to 5e-13 (paper's model; the family's
sparse Green-Kubo solve for a cubic member to < 1e-8); the two routes agree to 1e-9.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy import sparse
from scipy.linalg import eigh_tridiagonal, lapack
from scipy.sparse.linalg import splu

from .. import checks
from ..model import Model
from . import family
from .bias_transport import pure_dry_friction
from .fokker_planck import Grid
from .kolmogorov_feller import _grid_range, default_spacing, shot_generator
from .stationary import _grid_pieces, _poisson_solution, _refined_grids

__all__ = ["velocity_spectrum", "spectrum_grid_pieces", "noise_hold_factor",
           "crossover_frequencies", "METHODS", "HOLD_KINDS"]

METHODS = ("auto", "eigen", "resolvent")
HOLD_KINDS = ("hold", "linear")


def _omega(omega: ArrayLike) -> np.ndarray:
    return checks.finite_array("omega", omega)


def noise_hold_factor(omega: ArrayLike, hold: float, kind: str = "hold") -> np.ndarray:
    """Factor by which a noise delivered in samples of length ``hold`` (T) multiplies the
    white-noise spectrum ``2/gamma`` of the velocity noise, hence S(omega) for a linear
    response (exact at Delta = 0):

    * ``"hold"`` (zero-order hold: the circuit's held DAC/``trrandom`` noise and
      :func:`analogue.montecarlo.simulate_sde` with ``noise_hold``): independent values
      ``xi_k`` of variance ``2/(gamma T)`` held for T; phase-averaged spectrum
      ``(1/T) Var xi |T sinc(omega T/2)|^2 = (2/gamma) sinc^2(omega T/2)``;
    * ``"linear"`` (``trnoise``: samples linearly interpolated): the triangle kernel of
      half-width T has the transform ``T sinc^2(omega T/2)``, so ``sinc^4(omega T/2)``.

    ``sinc(x) = sin(x)/x``.  ``1 - (omega T)^2/12`` (hold) at small omega T: the hold loses
    1 % of the noise power at ``omega T = 0.35``.  T = 0 gives 1 (white noise).  The sampling
    of the *output* (aliasing) is a separate effect, in
    :func:`analogue.estimators.spectrum.welch_expectation`.

    Dry friction is not linear, and there the hold does more than this factor.  Measured with
    held and white noise from common Wiener increments (:func:`analogue.montecarlo.
    simulate_sde_held_pair`; tau_m = 1, Delta = 0.7, a = 0.2, gamma = 10, 32 replicas x 95
    time units, omega < 12): the held spectrum lies below ``sinc^2 x`` the white one by
    1.0 % (T = 0.01 = tau_m/100, the circuit's usual hold), 5.7 % (T = 0.05) and 25 %
    (T = 0.2), nearly flat in omega, i.e. about ``T/(4 t_kink)`` with the kink time
    ``t_kink = 2/(gamma (Delta + |a|)^2) = 0.25``: the hold lowers the variance itself in
    the stick regime.  At Delta = 0 the same test agrees with this factor within its
    standard errors (1-4 %).  A budget for the circuit's spectrum in the stick regime must
    therefore take the hold's term from such a held/white pair, as the report does for the
    other observables; this factor is the linear (Delta = 0) part of it.
    """
    w = _omega(omega)
    t = checks.nonnegative("hold", hold)
    if kind not in HOLD_KINDS:
        raise ValueError(f"kind must be one of {HOLD_KINDS}, got {kind!r}")
    x = 0.5 * w * t
    sinc2 = np.sinc(x / np.pi) ** 2  # numpy's sinc is sin(pi x)/(pi x)
    out: np.ndarray = sinc2 if kind == "hold" else sinc2 * sinc2
    return out


def spectrum_grid_pieces(model: Model, grid: Grid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(diag, off, y)``: the symmetrised generator on ``grid`` and ``y = (v - <v>) sqrt(pi)``
    (pi the grid's normalised stationary weights); any 1-D Gaussian-noise member."""
    diag, off, _, pi = _grid_pieces(model, grid)
    y = (grid.v - float(np.dot(grid.v, pi))) * np.sqrt(pi)
    return diag, off, y


def _eigen(diag: np.ndarray, off: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
    lam, q = eigh_tridiagonal(diag, off)
    # ascending: the last eigenvalue is the null mode (stationary state), weight ~ 0
    rate = -lam[:-1]
    weight = (q[:, :-1].T @ y) ** 2
    out = np.empty(w.size)
    for start in range(0, w.size, 256):  # (frequencies x modes) blocks of at most 256 rows
        ww = w[start:start + 256, None]
        out[start:start + 256] = (2.0 * weight * rate / (ww * ww + rate * rate)).sum(axis=1)
    return out


def _resolvent(model: Model, grid: Grid, diag: np.ndarray, off: np.ndarray, y: np.ndarray,
               w: np.ndarray) -> np.ndarray:
    out = np.empty(w.size)
    sub = (-off).astype(complex)
    yc = y.astype(complex)
    for k, om in enumerate(w):
        if om == 0.0:
            _, _, yy, u = _poisson_solution(model, grid)
            out[k] = -2.0 * float(yy @ u)  # S u = y, D_x = -y.u
            continue
        _, _, _, x, info = lapack.zgtsv(sub, 1j * om - diag, sub, yc)
        if info != 0:  # pragma: no cover - i omega is off the real spectrum
            raise np.linalg.LinAlgError(f"resolvent solve failed (info={info})")
        out[k] = 2.0 * float((y @ x).real)
    return out


def _gradient_grids(model: Model, h: float | None) -> tuple[Grid, Grid]:
    """The two grids (h, h/2) of the project's D_x for this member: those of
    :func:`analogue.theory.stationary.diffusion_coefficient` (paper's model) or of
    :func:`analogue.theory.family.stationary_moments` (other gradient members)."""
    if model.is_paper:
        return _refined_grids(model, h)
    hh = default_spacing(model) if h is None else h
    lo, hi = _grid_range(model)
    return Grid.span(lo, hi, hh), Grid.span(lo, hi, hh / 2.0)


def _gradient_spectrum(model: Model, w: np.ndarray, h: float | None, method: str,
                       richardson: bool) -> np.ndarray:
    coarse, fine = _gradient_grids(model, h)
    vals = []
    for grid in ((coarse, fine) if richardson else (fine,)):
        diag, off, y = spectrum_grid_pieces(model, grid)
        vals.append(_eigen(diag, off, y, w) if method == "eigen"
                    else _resolvent(model, grid, diag, off, y, w))
    if not richardson:
        return vals[0]
    out: np.ndarray = (4.0 * vals[1] - vals[0]) / 3.0
    return out


def _complex_solve(M: sparse.spmatrix, b: np.ndarray) -> np.ndarray:
    """``M^{-1} b`` for the banded-form resolvent ``N (i omega - L)``: as
    :func:`analogue.theory.family._factor`, the few dense rows (folds of the jump kernel) are
    moved last and the LU keeps diagonal pivots (``i omega N`` only strengthens the diagonal of
    the M-matrix-like ``-N L``).  Default COLAMD with partial pivoting filled in 11e6 entries
    and took 2.4 s per omega on 15089 states; this takes 0.3 s (two-sided shot, gamma = 20)."""
    M = sparse.csr_matrix(M)
    n = M.shape[0]
    dense = np.flatnonzero(np.diff(M.indptr) > 24)
    perm = np.r_[np.setdiff1d(np.arange(n), dense), dense]
    lu = splu(M[perm][:, perm].tocsc(), permc_spec="NATURAL" if dense.size else "MMD_AT_PLUS_A",
              diag_pivot_thresh=0.0)
    x = np.empty(n, dtype=complex)
    x[perm] = lu.solve(b[perm])
    return x


def _shot_spectrum(model: Model, w: np.ndarray, h: float | None) -> np.ndarray:
    hh = default_spacing(model) if h is None else h
    vals = []
    for step in (hh, hh / 2.0):
        g = shot_generator(model, step)
        p = family._solve_stationary(g, model)
        dv = g.v - float(np.dot(g.v, p))
        NL = g.banded_L().tocsc()
        N = g.premultiplier
        N = sparse.identity(g.n, format="csc") if N is None else N
        rhs = np.asarray(N @ (dv * p), dtype=complex)
        out = np.empty(w.size)
        for k, om in enumerate(w):
            if om == 0.0:
                out[k] = 2.0 * family._green_kubo(model, g, p)
                continue
            out[k] = 2.0 * float((dv @ _complex_solve(1j * om * N - NL, rhs)).real)
        vals.append(out)
    r = 4.0 if math.isfinite(model.gamma) else 2.0
    return (r * vals[1] - vals[0]) / (r - 1.0)


def velocity_spectrum(model: Model, omega: ArrayLike, *, h: float | None = None,
                      method: str = "auto", richardson: bool = True) -> np.ndarray:
    """Exact two-sided velocity power spectrum ``S(omega)`` (angular frequency; module
    docstring for the convention, ``S(0) = 2 D_x``, ``(1/2 pi) int S = Var v``) at ``|omega|``,
    for every one-dimensional member of the model family.

    Parameters
    ----------
    omega : array_like
        Angular frequencies (any shape; S is even, so the sign is ignored).
    h : float, optional
        Coarse grid spacing (default: the grid of the project's D_x for this member).
    method : "auto" | "eigen" | "resolvent"
        Gaussian-noise members only: the Lorentzian sum of the eigen-decomposition, or one
        tridiagonal resolvent solve per omega ("auto": the resolvent).  Shot-noise members
        always use the sparse resolvent.
    richardson : bool
        Combine the grids h and h/2 (default); False gives the fine grid alone (Gaussian-noise
        members).
    """
    checks.instance("model", model, Model, description="an analogue.Model")
    family.check_one_dimensional(model)
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if h is not None:
        checks.positive("h", h)
    w = _omega(omega)
    flat = np.abs(w.ravel())
    if model.shot is None:
        out = _gradient_spectrum(model, flat, h, method, bool(richardson))
    else:
        if method == "eigen":
            raise ValueError("method='eigen' needs Gaussian noise only (shot-noise generators "
                             "are not symmetrisable); use 'auto' or 'resolvent'")
        out = _shot_spectrum(model, flat, h)
    return out.reshape(w.shape)


def crossover_frequencies(model: Model) -> tuple[float, float]:
    """``(1/tau_m, sticking_rate)``: the two angular frequencies where S(omega) bends over to
    its ``omega^-2`` tail, the viscous one and the dry-friction one.  ``sticking_rate`` is the
    inverse correlation time ``Var v / D_x`` of pure dry friction
    (:func:`analogue.theory.bias_transport.pure_dry_friction`; ``2 gamma Delta^2/5`` at
    a = 0), NaN in the slip regime (|a| >= Delta), where the velocity rarely visits 0.  In the
    stick regime the spectrum has one visible corner, at the sticking rate when it exceeds
    1/tau_m: half-power points measured at 37.2 (tau_m = 10, Delta = 1, a = 0, gamma = 100;
    sticking rate 40) and 6.6 (tau_m = 100, Delta = 1, a = 0.3, gamma = 30; 7.7)."""
    checks.instance("model", model, Model, description="an analogue.Model")
    if not abs(model.a) < model.delta or not math.isfinite(model.gamma):
        return 1.0 / model.tau_m, math.nan
    dry = pure_dry_friction(model.delta, model.a, model.gamma)
    return 1.0 / model.tau_m, 1.0 / dry.correlation_time

