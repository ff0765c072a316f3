"""Exact finite-noise theory of the stick-slip model (the numerical reference, not in the paper).

Public functions
----------------
propagator(model, v, t, v0, t0=0.0, *, grid=None, h=None, method="auto")
    Transition density ``f(v, t | v0, t0)`` (the paper's eqs. (46)/(47)/(51) at finite gamma).
stationary_moments(model, h=None) -> StationaryMoments
    Mean, variance, P(v > 0), P(v < 0), mean friction sign, Green-Kubo diffusion, drift.
autocorrelation(model, lags, h=None)
    Connected stationary velocity autocorrelation.
sample_stationary(model, size, seed=None)
    Draws from ``p_s`` (eq. (6)).
scgf, rate_function, work_pdf
    Work statistics (re-exported from :mod:`analogue.theory.work_statistics`).

Methods: Scharfetter-Gummel Fokker-Planck generator (exact discrete stationary state), its
eigen-decomposition or ``expm_multiply`` (:mod:`.propagation`), closed forms and half-line
quadrature for stationary moments (:mod:`.stationary`).  The reduced dynamics does not depend
on the mass.
"""
from __future__ import annotations

import math

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .. import checks
from ..model import Model
from .exact_grid import propagator_grid
from .fokker_planck import Grid
from .propagation import initial_delta, propagate
from .stationary import StationaryMoments, autocorrelation, sample_stationary
from .stationary import stationary_moments as _stationary_moments

from . import family as _family
from .work_statistics import rate_function as _paper_rate_function, scgf as _paper_scgf
from .work_statistics import work_pdf as _paper_work_pdf

__all__ = ["propagator", "propagator_atom", "stationary_moments", "StationaryMoments", "autocorrelation",
           "sample_stationary", "scgf", "rate_function", "work_pdf"]


def _check_model(model: object) -> None:
    checks.instance("model", model, Model, description="an analogue.Model")


class _Paper:
    """The paper's model (:attr:`analogue.Model.is_paper`): closed forms, half-line
    quadrature and the Scharfetter-Gummel Fokker-Planck of :mod:`.stationary`,
    :mod:`.work_statistics` and this module."""

    @staticmethod
    def stationary_moments(model: Model, h: float | None) -> StationaryMoments:
        return _stationary_moments(model, h=h)

    @staticmethod
    def scgf(model: Model, k: ArrayLike, h: float | None) -> np.ndarray:
        out: np.ndarray = _paper_scgf(model, k, h=h)
        return out

    @staticmethod
    def rate_function(model: Model, w: ArrayLike, h: float | None) -> np.ndarray:
        out: np.ndarray = _paper_rate_function(model, w, h=h)
        return out

    @staticmethod
    def work_pdf(model: Model, w: ArrayLike, tau: float, **kwargs: Any) -> np.ndarray:
        out: np.ndarray = _paper_work_pdf(model, w, tau, **kwargs)
        return out

    @staticmethod
    def propagator_atom(model: Model, t: ArrayLike, v0: float, t0: float,
                        h: float | None) -> float | np.ndarray:
        t_arr = np.asarray(t, dtype=float)   # Gaussian noise: no atom
        return 0.0 if t_arr.ndim == 0 else np.zeros(t_arr.shape)

    @staticmethod
    def propagator(model: Model, v: ArrayLike, t: ArrayLike, v0: float, t0: float,
                   grid: Grid | None, h: float | None, method: str) -> np.ndarray:
        return _paper_propagator(model, v, t, v0, t0, grid=grid, h=h, method=method)


class _Family:
    """Every other one-dimensional member: :mod:`.family`, whose solver the noise variant
    names (``model.noise.exact_solver``: Fokker-Planck, Kolmogorov-Feller; a noise without
    one, coloured noise, is refused there naming the Monte Carlo)."""

    @staticmethod
    def stationary_moments(model: Model, h: float | None) -> StationaryMoments:
        moments: StationaryMoments = _family.stationary_moments(model, h=h)
        return moments

    @staticmethod
    def scgf(model: Model, k: ArrayLike, h: float | None) -> np.ndarray:
        out: np.ndarray = _family.scgf(model, k, h=h)
        return out

    @staticmethod
    def rate_function(model: Model, w: ArrayLike, h: float | None) -> np.ndarray:
        out: np.ndarray = _family.rate_function(model, w, h=h)
        return out

    @staticmethod
    def work_pdf(model: Model, w: ArrayLike, tau: float, **kwargs: Any) -> np.ndarray:
        raise ValueError("work_pdf is implemented for the paper's model only; for the family use "
                         "exact.scgf / exact.rate_function")

    @staticmethod
    def propagator_atom(model: Model, t: ArrayLike, v0: float, t0: float,
                        h: float | None) -> float | np.ndarray:
        atom: float | np.ndarray = _family.propagator_atom(model, t, v0, t0, h=h)
        return atom

    @staticmethod
    def propagator(model: Model, v: ArrayLike, t: ArrayLike, v0: float, t0: float,
                   grid: Grid | None, h: float | None, method: str) -> np.ndarray:
        if grid is not None or method != "auto":
            raise ValueError("grid and method apply to the paper's model only")
        density: np.ndarray = _family.propagator(model, v, t, v0, t0, h=h)
        return density


def _route(model: Model) -> type[_Paper] | type[_Family]:
    """The exact route of ``model``, chosen here once: the paper's numerics or the family's."""
    _check_model(model)
    return _Paper if model.is_paper else _Family


def stationary_moments(model: Model, h: float | None = None) -> StationaryMoments:
    """Exact stationary moments; the paper's model by :mod:`.stationary`, every other 1-D
    member of the family by :mod:`.family` (with ``p_zero``, the atom at v = 0)."""
    return _route(model).stationary_moments(model, h)


def scgf(model: Model, k: ArrayLike, *, h: float | None = None) -> np.ndarray:
    """Work SCGF (:func:`.work_statistics.scgf`; family members: :func:`.family.scgf`)."""
    return _route(model).scgf(model, k, h)


def rate_function(model: Model, w: ArrayLike, *, h: float | None = None) -> np.ndarray:
    """Work rate function (:func:`.work_statistics.rate_function`; family members:
    :func:`.family.rate_function`, whose scaling with gamma = inf is documented there)."""
    return _route(model).rate_function(model, w, h)


def work_pdf(model: Model, w: ArrayLike, tau: float, **kwargs: Any) -> np.ndarray:
    """Finite-time work density (:func:`.work_statistics.work_pdf`); the paper's model only
    (for family members the SCGF and rate function are available)."""
    return _route(model).work_pdf(model, w, tau, **kwargs)


def propagator_atom(model: Model, t: ArrayLike, v0: float, t0: float = 0.0, *,
                    h: float | None = None) -> float | np.ndarray:
    """``P(v(t) = 0 | v0)``: the atom of the transition law (pure shot noise, stick regime);
    0 for the paper's model."""
    return _route(model).propagator_atom(model, t, v0, t0, h)


def propagator(model: Model, v: ArrayLike, t: ArrayLike, v0: float, t0: float = 0.0, *,
               grid: Grid | None = None,
               h: float | None = None, method: str = "auto") -> np.ndarray:
    """Transition density ``f(v, t | v0, t0)`` of eq. (4) at finite gamma.

    Parameters
    ----------
    v : array_like
        Velocities at which the density is returned (any shape).  The density is computed on an
        internal grid (:func:`analogue.theory.exact_grid.propagator_grid`) covering the
        stationary law (where ``gamma (U - U_min) < 40``) and the reach of ``v0`` (within
        ``sqrt(80 tau_m/gamma)`` of it and where ``gamma (U - U(v0)) < 40``) and interpolated;
        outside that range it is returned as 0 (the true density there is below ``e^{-40}`` of
        a transition density's peak).  Between nodes, ``f/p_s`` is interpolated log-linearly
        (see :func:`_interpolate`).
    t : float or 1-D array
        Final time(s), each > t0.  An array is computed in one go on the grid of its earliest
        time and gives shape ``(len(t),) + v.shape``.
    v0, t0 : float
        Initial velocity and initial time.  The default grid puts ``v0`` on a node; on a grid
        that does not, the unit mass is split linearly between the two neighbouring nodes.
    grid : Grid, optional
        Use this grid instead of the automatic one (must contain v0).
    h : float, optional
        Spacing of the automatic grid (default: from the local scales, see
        :func:`~analogue.theory.exact_grid.propagator_grid`: drift per cell ``gamma |U'| h <=
        0.08`` wherever the mass travels, which resolves the kink length
        ``1/(gamma (Delta + |a|))``; ``h <= sqrt(2 (t - t0)/gamma)/16``; ``h <= epsilon/8``).
    method : "auto" | "eigen" | "expm" | "hybrid" | "contour"
        Propagation route (:mod:`analogue.theory.propagation`; "auto": the Talbot contour,
        O(n) per time, absolute error ~1e-11 of the peak, the hybrid route for starts too deep
        in the tail for it).

    Accuracy: exact in time; O(h^2) in space.  At the default grid the maximum error is below
    1e-3 of the peak at every ``t - t0`` (the grid adapts to the earliest time), measured in
    every regime tried (stick, slip, a = Delta, gamma = 1 - 1000, tau_m = 1 - 1e5,
    t - t0 = 0.01 - 2 tau_m, and 0.01 - 30 dry relaxation times 1/(gamma Delta^2) at
    tau_m = 1e5): against the Delta = 0 closed form <= 8.2e-4, against the pure dry-friction
    closed form (Caughey-Dienes; Touchette, Van der Straeten & Just 2010) <= 8.9e-4, elsewhere
    against h/8 <= 8.2e-4; the largest errors are at the earliest times, where the lattice
    kernel's excess kurtosis ``h^2/(2 (t - t0)/gamma)`` dominates, and fall to ~1e-4 by
    0.5 tau_m.  Not for starts deeper than ``gamma (U(v0) - U_min) = 180`` in the tail
    (:data:`~analogue.theory.exact_grid.DEEP_START`): the contour route cannot take them and
    the expm route would cost minutes on that grid, so they keep the previous spacing, with
    errors up to 1e-2 - 6e-2 of the peak at gamma = 1000 (pass ``h`` for more).  Error estimate: halving h changes the density by less than 7.5e-4 of its
    peak, and the changes fall by ~4 per halving, so the error of the default is ~4/3 of that
    change (the tests check both).  Every time slice integrates to 1 within 1e-4 (measured
    <= 2e-10): it is normalised by the integral of its own interpolant.  The t -> inf limit
    is the exact ``p_s`` (eq. (6)) to ~1e-11 of its peak (the contour route's round-off
    floor; measured 4e-12 - 5e-11 at t - t0 = 40 tau_m, gamma = 10; the eigen route gave
    ~1e-12).  Cost: O(n) per time; the grid has 900 - 14000 nodes in the cases above (see
    ``benchmarks/bench_propagator_grid.py`` for the cost against the previous grid).
    """
    return _route(model).propagator(model, v, t, v0, t0, grid, h, method)


def _paper_propagator(model: Model, v: ArrayLike, t: ArrayLike, v0: float, t0: float, *,
                      grid: Grid | None, h: float | None, method: str) -> np.ndarray:
    """:func:`propagator` of the paper's model (Scharfetter-Gummel grid, :mod:`.propagation`)."""
    v = np.asarray(v, dtype=float)
    if not np.all(np.isfinite(v)):
        raise ValueError("v must be finite")
    t_arr = np.asarray(t, dtype=float)
    if t_arr.ndim > 1:
        raise ValueError(f"t must be a number or a 1-D array, got shape {t_arr.shape}")
    try:
        v0 = float(v0)
        t0 = float(t0)
    except (TypeError, ValueError):
        raise ValueError("v0 and t0 must be real numbers") from None
    if not (math.isfinite(v0) and math.isfinite(t0)):
        raise ValueError("v0 and t0 must be finite")
    elapsed = np.atleast_1d(t_arr) - t0
    if elapsed.size == 0:
        raise ValueError("t must not be empty")
    if not np.all(np.isfinite(elapsed)) or np.any(elapsed <= 0):
        raise ValueError("t must be finite and > t0 (at t = t0 the density is a delta)")
    if grid is None:
        grid = propagator_grid(model, v0, float(elapsed.min()), h=h)
    elif h is not None:
        raise ValueError("pass either grid or h, not both")
    if not grid.v[0] <= v0 <= grid.v[-1]:
        raise ValueError(f"v0={v0} lies outside the grid [{grid.v[0]}, {grid.v[-1]}]")
    probs = propagate(model, grid, initial_delta(grid, v0), elapsed, method=method)
    return _interpolate(model, grid, probs / grid.h, v, t_arr.ndim == 0)


#: Gauss-Legendre points per cell for the mass of the interpolant (its log is a quadratic in
#: the cell for the sgn law, smooth on the scale epsilon >= 8 h for tanh: error < 1e-12).
_GAUSS_POINTS = 4
_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(_GAUSS_POINTS)


def _log_interpolant(model: Model, grid: Grid, log_ratio: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``ln f(x)`` for ``x`` inside the grid: ``ln(f e^{gamma U})`` (``log_ratio`` at the nodes,
    shape (times, n)) interpolated linearly, minus ``gamma U(x)``."""
    pos = (x - grid.v[0]) / grid.h
    i = np.clip(np.floor(pos).astype(int), 0, grid.n - 2)
    theta = pos - i
    out: np.ndarray = ((1.0 - theta) * log_ratio[:, i] + theta * log_ratio[:, i + 1]
                       - model.gamma * model.potential(x))
    return out


def _exp_above(x: np.ndarray, floor: float = -700.0) -> np.ndarray:
    """``exp(x)``, and exactly 0 where ``x < floor`` (no subnormal arithmetic)."""
    out: np.ndarray = np.exp(np.maximum(x, floor))
    out[x < floor] = 0.0
    return out


def _interpolate(model: Model, grid: Grid, dens: np.ndarray, v: np.ndarray, scalar: bool
                ) -> np.ndarray:
    """Interpolate node densities to ``v``: ``ln(f/p_s)`` linearly, times the exact
    ``p_s(v) ~ exp(-gamma U(v))``, normalised so that every time slice integrates to 1.

    For the sgn law ``f`` and ``p_s`` have the same jump of the log-derivative at the node
    v = 0 (it comes from the jump of the drift), so ``f/p_s`` is smooth there; the interpolant
    is exact for the stationary law and for the exponential (Laplace-like) profiles either
    side of the kink, and elsewhere its *relative* error is O(h^2) uniformly, also far in the
    tails (what log-density comparisons need).

    Normalisation: the node probabilities sum to 1, but ``sum_i f(v_i) h`` is only a quadrature
    of ``integral f``; at the kink it is ``(x/2) coth(x/2) = 1 + x^2/12`` of it (``x`` the drift
    per cell), so scaling every slice by the stationary factor ``h sum_i p_s(v_i)`` (exact only
    as t -> inf) over-normalised transients away from the kink by up to 0.8 %.  Each slice is
    instead divided by the integral of its own interpolant (Gauss-Legendre per cell), which is
    1 for the stationary law: the t -> inf limit stays the exact ``p_s``."""
    nodes = grid.v
    flat = v.ravel()
    inside = (flat >= nodes[0]) & (flat <= nodes[-1])
    gu_nodes = model.gamma * model.potential(nodes)
    with np.errstate(divide="ignore"):
        # log 0 -> -1e300 (not -inf, so that 0 * log 0 = 0 at theta = 0 or 1)
        log_ratio = np.maximum(np.log(dens), -1e300) + gu_nodes
    # shift by the largest value so that neither the tails nor the mass overflow
    log_ratio -= np.max(log_ratio - gu_nodes, axis=1, keepdims=True)
    cells = nodes[:-1, None] + 0.5 * grid.h * (1.0 + _GAUSS_X[None, :])
    log_cells = _log_interpolant(model, grid, log_ratio, cells.ravel())
    top = log_cells.max(axis=1, keepdims=True)
    weights = np.tile(0.5 * grid.h * _GAUSS_W, grid.n - 1)
    # below e^-700 of the top: 0 (exp would return subnormals, ~10x slower on x86, for
    # nothing: the mass is needed to 1e-16 of the total)
    log_mass = np.log(_exp_above(log_cells - top) @ weights) + top[:, 0]
    log_out = _log_interpolant(model, grid, log_ratio, flat[inside]) - log_mass[:, None]
    out: np.ndarray = np.zeros((dens.shape[0], flat.size))
    out[:, inside] = _exp_above(log_out)
    out = out.reshape((dens.shape[0],) + v.shape)
    return out[0] if scalar else out
