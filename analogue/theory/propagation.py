"""Time evolution of node probabilities under the Scharfetter-Gummel Fokker-Planck generator.

Two routes compute ``p(t) = exp(L t) p0`` for the tridiagonal generator ``L`` of
:mod:`analogue.theory.fokker_planck` (exact in time; the only error is the O(h^2) space
discretisation):

* **eigen**: ``L = Pi^{1/2} S Pi^{-1/2}`` with ``S`` symmetric tridiagonal (detailed balance), so
  ``exp(L t) = Pi^{1/2} Q exp(Lambda t) Q^T Pi^{-1/2}``.  One decomposition serves every time;
  O(n^2) memory.  Its round-off is amplified by ``sqrt(pi_max / pi(v0))``: starting far in the
  tail of the stationary law it loses digits, so it is only used while that factor is below
  ``exp(EIGEN_MAX_HALF_LOG_RANGE)``.
* **expm**: ``scipy.sparse.linalg.expm_multiply`` (Al-Mohy & Higham), stepping through the
  sorted times; positive and accurate from any start, slower for long times on fine grids.

* **hybrid**: expm while the mass is deep in the tail, eigen from then on (the "auto" choice
  for starts in the tail).

The facade :func:`analogue.theory.exact.propagator` picks the route (``method="auto"``).
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import eigh_tridiagonal
from scipy.special import logsumexp
from scipy.sparse.linalg import expm_multiply

from ..model import Model
from .fokker_planck import Grid, generator, symmetric_generator

__all__ = ["EIGEN_MAX_HALF_LOG_RANGE", "EIGEN_MAX_NODES", "initial_delta", "propagate",
           "propagate_eigen", "propagate_expm", "propagate_hybrid", "choose_method", "amplification"]

#: The eigen route multiplies round-off (~1e-16 of the peak) by at most ``e^this`` (~1e4).
EIGEN_MAX_HALF_LOG_RANGE = 9.0
#: Largest grid for the dense eigenvector matrix (n^2 doubles).
EIGEN_MAX_NODES = 6000


def initial_delta(grid: Grid, v0: float) -> np.ndarray:
    """Node probabilities of a unit mass at ``v0``, split linearly between the two nodes
    around it (matches the first two moments of the delta: second-order accurate)."""
    pos = (v0 - grid.i_min * grid.h) / grid.h
    if not (0.0 <= pos <= grid.n - 1):
        raise ValueError(f"v0={v0!r} lies outside the grid [{grid.v[0]}, {grid.v[-1]}]")
    j = min(int(math.floor(pos)), grid.n - 2)
    theta = pos - j
    p0 = np.zeros(grid.n)
    p0[j] = 1.0 - theta
    p0[j + 1] = theta
    return p0


def amplification(log_pi: np.ndarray, p: np.ndarray) -> float:
    """``ln`` of the factor by which the eigen route multiplies round-off when started from
    ``p``: ``sum_j p_j sqrt(pi_max/pi_j)`` (1 for a start at the mode)."""
    support = p > 0
    lp = log_pi[support] - log_pi.max()
    w = p[support] / np.sum(p[support])
    return float(logsumexp(-0.5 * lp, b=w))


def choose_method(log_pi: np.ndarray, p0: np.ndarray) -> str:
    """``"eigen"`` when the grid is small enough and the start is not too deep in the tail of
    the stationary law (see module docstring), else ``"expm"``."""
    if log_pi.size > EIGEN_MAX_NODES:
        return "expm"
    return "eigen" if amplification(log_pi, p0) <= EIGEN_MAX_HALF_LOG_RANGE else "expm"


def propagate_eigen(model: Model, grid: Grid, p0: np.ndarray, times: np.ndarray) -> np.ndarray:
    """``exp(L t) p0`` for every t in ``times`` (shape (len(times), n)) by eigen-decomposition
    of the symmetrised generator."""
    diag, off, log_pi = symmetric_generator(model, grid)
    lam, q = eigh_tridiagonal(diag, off)
    lam = np.minimum(lam, 0.0)  # L is a generator: round-off must not create growth
    lp = log_pi - log_pi.max()
    root = np.exp(0.5 * lp)
    support = p0 > 0
    # Pi^{-1/2} p0 only involves the (two) start nodes, so no overflow outside the support.
    y = np.zeros_like(p0)
    y[support] = p0[support] * np.exp(-0.5 * lp[support])
    c = q.T @ y
    out = (np.exp(np.outer(times, lam)) * c) @ q.T
    out *= root
    return np.asarray(out)


def propagate_expm(model: Model, grid: Grid, p0: np.ndarray, times: np.ndarray) -> np.ndarray:
    """``exp(L t) p0`` for every t in ``times`` by ``expm_multiply``, stepping through the sorted
    times (each step starts from the previous result)."""
    gen = generator(model, grid).tocsc()
    order = np.argsort(times, kind="stable")
    out = np.empty((times.size, grid.n))
    p, t_prev = p0.astype(float), 0.0
    for k in order:
        dt = float(times[k]) - t_prev
        if dt > 0:
            p = expm_multiply(gen * dt, p, traceA=float(gen.diagonal().sum()) * dt)
            t_prev = float(times[k])
        out[k] = p
    return out


def propagate_hybrid(model: Model, grid: Grid, p0: np.ndarray, times: np.ndarray) -> np.ndarray:
    """``expm_multiply`` while the mass sits deep in the tail of the stationary law, in steps
    of at most tau_m/4, then the eigen route from the first checkpoint where that is accurate
    (:func:`amplification` <= :data:`EIGEN_MAX_HALF_LOG_RANGE`) for all later times.  Same
    accuracy as the expm route at a fraction of its cost for long times."""
    _, _, log_pi = symmetric_generator(model, grid)
    if grid.n > EIGEN_MAX_NODES:
        return propagate_expm(model, grid, p0, times)
    gen = generator(model, grid).tocsc()
    trace = float(gen.diagonal().sum())
    order = np.argsort(times, kind="stable")
    out = np.empty((times.size, grid.n))
    p, t_now = p0.astype(float), 0.0
    step = model.tau_m / 4.0
    for pos, k in enumerate(order):
        target = float(times[k])
        while t_now < target:
            if amplification(log_pi, np.clip(p, 0.0, None)) <= EIGEN_MAX_HALF_LOG_RANGE:
                rest = order[pos:]
                out[rest] = propagate_eigen(model, grid, p, times[rest] - t_now)
                return out
            dt = min(step, target - t_now)
            p = expm_multiply(gen * dt, p, traceA=trace * dt)
            t_now += dt
        out[k] = p
    return out


def propagate(model: Model, grid: Grid, p0: np.ndarray, times: ArrayLike,
              method: str = "auto") -> np.ndarray:
    """Node probabilities at each of ``times`` (>= 0) from ``p0``; rows sum to 1.

    ``method``: "eigen", "expm", or "auto" (eigen if the start is benign, else
    :func:`propagate_hybrid`).  Round-off negatives (|p| ~ 1e-16 relative) are clipped to 0:
    the exact evolution of a probability vector under a generator is non-negative.
    """
    times = np.atleast_1d(np.asarray(times, dtype=float))
    if method == "auto":
        _, _, log_pi = symmetric_generator(model, grid)
        method = choose_method(log_pi, p0)
        if method == "expm":
            method = "hybrid"
    if method == "eigen":
        out = propagate_eigen(model, grid, p0, times)
    elif method == "expm":
        out = propagate_expm(model, grid, p0, times)
    elif method == "hybrid":
        out = propagate_hybrid(model, grid, p0, times)
    else:
        raise ValueError(f"method must be 'auto', 'eigen', 'expm' or 'hybrid', got {method!r}")
    return np.asarray(np.clip(out, 0.0, None))
