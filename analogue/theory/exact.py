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
from scipy.special import logsumexp

from .. import checks
from ..model import Model
from .exact_grid import resolved_grid
from .fokker_planck import Grid
from .propagation import initial_delta, propagate
from .stationary import (StationaryMoments, autocorrelation, half_line_moments, sample_stationary)
from .stationary import stationary_moments as _stationary_moments

from . import family as _family
from .work_statistics import rate_function as _paper_rate_function, scgf as _paper_scgf
from .work_statistics import work_pdf as _paper_work_pdf

__all__ = ["propagator", "propagator_atom", "stationary_moments", "StationaryMoments", "autocorrelation",
           "sample_stationary", "scgf", "rate_function", "work_pdf"]


def _check_model(model: object) -> None:
    checks.instance("model", model, Model, description="an analogue.Model")


def stationary_moments(model: Model, h: float | None = None) -> StationaryMoments:
    """Exact stationary moments; the paper's model by :mod:`.stationary`, every other 1-D
    member of the family by :mod:`.family` (with ``p_zero``, the atom at v = 0)."""
    _check_model(model)
    if not model.is_paper:
        moments: StationaryMoments = _family.stationary_moments(model, h=h)
        return moments
    return _stationary_moments(model, h=h)


def scgf(model: Model, k: ArrayLike, *, h: float | None = None) -> np.ndarray:
    """Work SCGF (:func:`.work_statistics.scgf`; family members: :func:`.family.scgf`)."""
    _check_model(model)
    if not model.is_paper:
        out: np.ndarray = _family.scgf(model, k, h=h)
    else:
        out = _paper_scgf(model, k, h=h)
    return out


def rate_function(model: Model, w: ArrayLike, *, h: float | None = None) -> np.ndarray:
    """Work rate function (:func:`.work_statistics.rate_function`; family members:
    :func:`.family.rate_function`, whose scaling with gamma = inf is documented there)."""
    _check_model(model)
    if not model.is_paper:
        out: np.ndarray = _family.rate_function(model, w, h=h)
    else:
        out = _paper_rate_function(model, w, h=h)
    return out


def work_pdf(model: Model, w: ArrayLike, tau: float, **kwargs: Any) -> np.ndarray:
    """Finite-time work density (:func:`.work_statistics.work_pdf`); the paper's model only
    (for family members the SCGF and rate function are available)."""
    _check_model(model)
    if not model.is_paper:
        raise ValueError("work_pdf is implemented for the paper's model only; for the family use "
                         "exact.scgf / exact.rate_function")
    out: np.ndarray = _paper_work_pdf(model, w, tau, **kwargs)
    return out


def propagator_atom(model: Model, t: ArrayLike, v0: float, t0: float = 0.0, *,
                    h: float | None = None) -> float | np.ndarray:
    """``P(v(t) = 0 | v0)``: the atom of the transition law (pure shot noise, stick regime);
    0 for the paper's model."""
    _check_model(model)
    if model.is_paper:
        t_arr = np.asarray(t, dtype=float)
        return 0.0 if t_arr.ndim == 0 else np.zeros(t_arr.shape)
    atom: float | np.ndarray = _family.propagator_atom(model, t, v0, t0, h=h)
    return atom


def propagator(model: Model, v: ArrayLike, t: ArrayLike, v0: float, t0: float = 0.0, *,
               grid: Grid | None = None,
               h: float | None = None, method: str = "auto") -> np.ndarray:
    """Transition density ``f(v, t | v0, t0)`` of eq. (4) at finite gamma.

    Parameters
    ----------
    v : array_like
        Velocities at which the density is returned (any shape).  The density is computed on an
        internal grid covering the stationary law and ``v0`` (where ``gamma (U - U_min) < 40``,
        and ``v0 +- sqrt(80 tau_m/gamma)``) and linearly interpolated; outside that range it is
        returned as 0 (the true density there is below ``e^{-40}`` of its peak).  Between
        nodes, ``f/p_s`` is interpolated linearly (see :func:`_interpolate`).
    t : float or 1-D array
        Final time(s), each > t0.  An array is computed in one go (one eigen-decomposition, or
        one sweep of ``expm_multiply``) and gives shape ``(len(t),) + v.shape``.
    v0, t0 : float
        Initial velocity (may lie between nodes: the unit mass is split linearly between the
        two neighbouring nodes) and initial time.
    grid : Grid, optional
        Use this grid instead of the automatic one (must contain v0).
    h : float, optional
        Spacing of the automatic grid (default: resolves sqrt(tau_m/gamma)/40, epsilon/8, the
        kink length 1/(gamma (Delta + |a|)) / 5 and sqrt(2 (t - t0)/gamma)/10).
    method : "auto" | "eigen" | "expm" | "hybrid" | "contour"
        Propagation route (:mod:`analogue.theory.propagation`; "auto": the Talbot contour,
        O(n) per time, absolute error ~1e-11 of the peak, the hybrid route for starts too deep
        in the tail for it).

    Accuracy: exact in time; O(h^2) in space.  At the default spacing the maximum error
    relative to the peak is below 2e-3 for t - t0 >= 0.1 tau_m and below 1e-3 for
    t - t0 >= 0.5 tau_m (measured against the Delta = 0 closed form: 1.3e-3 and 5e-4; the
    tests check the stated bounds); halving h changes the density by less than 3e-3 of its
    peak (measured <= 2.3e-3, at t - t0 = 0.1 tau_m); ``integral f dv = 1`` within 1e-3
    (measured 2e-4); the t -> inf limit is the exact ``p_s`` (eq. (6)) to ~1e-11 of its
    peak (the contour route's round-off floor; measured 4e-12 - 5e-11 at t - t0 = 40 tau_m,
    gamma = 10; the eigen route gave ~1e-12).
    """
    _check_model(model)
    if not model.is_paper:
        if grid is not None or method != "auto":
            raise ValueError("grid and method apply to the paper's model only")
        density: np.ndarray = _family.propagator(model, v, t, v0, t0, h=h)
        return density
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
        grid = resolved_grid(model, extra=(v0,), h=h, t_min=float(elapsed.min()))
    elif h is not None:
        raise ValueError("pass either grid or h, not both")
    if not grid.v[0] <= v0 <= grid.v[-1]:
        raise ValueError(f"v0={v0} lies outside the grid [{grid.v[0]}, {grid.v[-1]}]")
    probs = propagate(model, grid, initial_delta(grid, v0), elapsed, method=method)
    return _interpolate(model, grid, probs / grid.h, v, t_arr.ndim == 0)


def _interpolate(model: Model, grid: Grid, dens: np.ndarray, v: np.ndarray, scalar: bool
                ) -> np.ndarray:
    """Interpolate node densities to ``v``: ``ln(f/p_s)`` linearly, times the exact
    ``p_s(v) ~ exp(-gamma U(v))``.  For the sgn law ``f`` and ``p_s`` have the same jump of the
    log-derivative at the node v = 0 (it comes from the jump of the drift), so ``f/p_s`` is
    smooth there; the interpolant is exact for the stationary law and for the exponential
    (Laplace-like) profiles either side of the kink, and elsewhere its *relative* error is
    O(h^2) uniformly, also far in the tails (what log-density comparisons need)."""
    nodes = grid.v
    flat = v.ravel()
    inside = (flat >= nodes[0]) & (flat <= nodes[-1])
    pos = (flat[inside] - nodes[0]) / grid.h
    i = np.minimum(np.floor(pos).astype(int), grid.n - 2)
    theta = pos - i
    gu_v = model.gamma * model.potential(flat[inside])
    gu_nodes = model.gamma * model.potential(nodes)
    with np.errstate(divide="ignore"):
        # log 0 -> -1e300 (not -inf, so that 0 * log 0 = 0 at theta = 0 or 1)
        log_dens = np.maximum(np.log(dens), -1e300)
    # The grid's node weights sum to 1 while sum_i p_s(v_i) h = 1 + O(h^2) (kink at 0): scale
    # by that sum so that the t -> inf limit is the exact p_s, not only up to O(h^2).
    log_z = half_line_moments(model).log_z
    log_dens = log_dens + float(logsumexp(-gu_nodes)) + math.log(grid.h) - log_z
    # ln f(v) = interpolated ln(f e^{gamma U}) - gamma U(v); the U terms stay O(gamma |U'| h).
    shift = (1.0 - theta) * gu_nodes[i] + theta * gu_nodes[i + 1] - gu_v
    log_out = (1.0 - theta) * log_dens[:, i] + theta * log_dens[:, i + 1] + shift
    out: np.ndarray = np.zeros((dens.shape[0], flat.size))
    out[:, inside] = np.exp(log_out)
    out = out.reshape((dens.shape[0],) + v.shape)
    return out[0] if scalar else out
