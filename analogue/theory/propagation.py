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

* **hybrid**: expm while the mass is deep in the tail, eigen from then on.
* **contour** (the "auto" choice): the Bromwich integral on a Talbot contour, a few dozen
  complex tridiagonal solves per time, O(n) whatever the stiffness; absolute error ~1e-11 of
  the peak (:func:`contour_nodes`).  Starts too deep in the tail for it go the hybrid way.

The facade :func:`analogue.theory.exact.propagator` picks the route (``method="auto"``).
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import eigh_tridiagonal, lapack
from scipy.special import logsumexp
from scipy.sparse.linalg import expm_multiply

from ..model import Model
from .fokker_planck import Grid, generator, symmetric_generator

__all__ = ["EIGEN_MAX_HALF_LOG_RANGE", "EIGEN_MAX_NODES", "CONTOUR_MIN_NODES", "CONTOUR_MAX_NODES",
           "initial_delta", "propagate", "propagate_eigen", "propagate_expm", "propagate_hybrid",
           "propagate_contour", "contour_tridiagonal", "contour_nodes", "choose_method", "amplification"]

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
    (:func:`amplification` <= :data:`EIGEN_MAX_HALF_LOG_RANGE`) for all later times; on grids
    too large for the eigen route, the contour route from the first checkpoint where
    :func:`contour_nodes` allows it.  Same accuracy as the expm route at a fraction of its
    cost for long times."""
    _, _, log_pi = symmetric_generator(model, grid)
    gen = generator(model, grid).tocsc()
    trace = float(gen.diagonal().sum())
    order = np.argsort(times, kind="stable")
    out = np.empty((times.size, grid.n))
    p, t_now = p0.astype(float), 0.0
    step = model.tau_m / 4.0
    for pos, k in enumerate(order):
        target = float(times[k])
        while t_now < target:
            amp = amplification(log_pi, np.clip(p, 0.0, None))
            nodes = contour_nodes(amp)
            if nodes is not None and grid.n > EIGEN_MAX_NODES:
                # fine grids: the contour route as soon as the mass allows it (O(n) per time;
                # the eigen route is out of reach and expm_multiply costs O(n / h^2) per unit time)
                rest = order[pos:]
                out[rest] = propagate_contour(model, grid, np.clip(p, 0.0, None), times[rest] - t_now, nodes)
                return out
            if amp <= EIGEN_MAX_HALF_LOG_RANGE and grid.n <= EIGEN_MAX_NODES:
                rest = order[pos:]
                out[rest] = propagate_eigen(model, grid, p, times[rest] - t_now)
                return out
            dt = min(step, target - t_now)
            p = expm_multiply(gen * dt, p, traceA=trace * dt)
            t_now += dt
        out[k] = p
    return out


#: Fewest trapezoid nodes of the contour route (max |error| of e^lambda on lambda <= 0: 2.4e-14).
CONTOUR_MIN_NODES = 24
#: Most nodes: beyond, the contour's round-off (~1e-16 e^{0.17 N} of the peak) would exceed 1e-10.
CONTOUR_MAX_NODES = 80


def _talbot(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes ``z_j`` and weights ``c_j`` (upper half of the contour only) with
    ``e^lambda ~ 2 Re sum_j c_j / (z_j - lambda)`` for every real ``lambda <= 0``: the
    trapezoid rule with ``n`` points on the optimised cotangent ("improved Talbot") contour
    ``z(theta) = n (0.5017 theta cot(0.6407 theta) - 0.6122 + 0.2645 i theta)`` of
    Trefethen, Weideman & Schmelzer, BIT 46, 653 (2006) (error ~3.89^-n; measured max over
    lambda in [-1e7, 0]: 3.5e-12 at n = 20, 2.4e-14 at n = 24, 9e-15 at n = 28)."""
    th = -math.pi + (np.arange(1, n + 1) - 0.5) * 2.0 * math.pi / n
    th = th[th > 0]
    a, b, c, d = 0.5017, 0.6407, 0.6122, 0.2645
    z = n * (a * th / np.tan(b * th) - c + 1j * d * th)
    dz = n * (a / np.tan(b * th) - a * b * th / np.sin(b * th) ** 2 + 1j * d)
    return z, np.exp(z) * dz / (1j * n)


def contour_nodes(amp: float) -> int | None:
    """Trapezoid nodes for a start of amplification ``e^amp`` (:func:`amplification`), or None
    when more than :data:`CONTOUR_MAX_NODES` would be needed.

    The contour's quadrature error is a function ``eps(lambda)`` of the generator, bounded by
    ~3.89^-N on the spectrum; applied to a start in the tail it is multiplied by ``e^amp``, as
    round-off is in the eigen route.  Its round-off is not (the resolvent solves are done in
    the original, well-conditioned basis) but grows like ``1e-16 e^{0.17 N}`` with the size
    of ``e^z`` on the contour.  N balances the two: ``e^amp 3.89^-N <= 1e-14 e^{0.17 N}``, i.e.
    ``N >= (amp + 32)/1.53`` (at least :data:`CONTOUR_MIN_NODES`, even).  Measured against
    the hybrid route on the report's tail starts (stick v0 = +-2: amp 15 / 19, work v0 = 3:
    amp 30): 24 nodes leave 4e-9 / 1e-7 / 3e-5 of the peak, 32-40 nodes 1e-11."""
    n = max(CONTOUR_MIN_NODES, math.ceil((amp + 32.0) / 1.53))
    n += n % 2
    return n if n <= CONTOUR_MAX_NODES else None


def propagate_contour(model: Model, grid: Grid, p0: np.ndarray, times: np.ndarray,
                      nodes: int | None = None) -> np.ndarray:
    """``exp(L t) p0`` for every t by the contour integral ``(1/2 pi i) int e^z (z - t L)^-1
    p0 dz`` on a Talbot contour (:func:`_talbot`), ``nodes`` points (default
    :func:`contour_nodes` of the start): ``nodes/2`` complex tridiagonal solves per time
    (L is real, so the lower half of the contour is the conjugate), O(n) each whatever the
    stiffness of L.  Valid because the spectrum of L is real and <= 0 (L is similar to a
    symmetric negative semi-definite matrix).  Measured on the report's propagators (n ~
    2000 nodes, 4-5 times): 0.01 s per start against 0.3-3 s for the eigen/hybrid routes."""
    if nodes is None:
        _, _, log_pi = symmetric_generator(model, grid)
        nodes = contour_nodes(amplification(log_pi, p0))
        if nodes is None:
            raise ValueError("the start lies too deep in the tail for the contour route; "
                             "use method='hybrid'")
    gen = generator(model, grid)
    return contour_tridiagonal(gen.diagonal(-1), gen.diagonal(0), gen.diagonal(1), p0, times,
                               int(nodes))


def contour_tridiagonal(sub: np.ndarray, dia: np.ndarray, sup: np.ndarray, p0: np.ndarray,
                        times: np.ndarray, nodes: int) -> np.ndarray:
    """The contour route (:func:`propagate_contour`) for any tridiagonal generator given by its
    sub-, main and super-diagonals (spectrum real and <= 0, e.g. a Scharfetter-Gummel generator
    in detailed balance), ``nodes`` from :func:`contour_nodes`: shape (len(times), n)."""
    sub = np.asarray(sub).astype(complex)
    sup = np.asarray(sup).astype(complex)
    dia = np.asarray(dia).astype(complex)
    z, c = _talbot(int(nodes))
    b = p0.astype(complex)
    out = np.empty((times.size, dia.size))
    for k, t in enumerate(times):
        if t == 0:
            out[k] = p0
            continue
        acc = np.zeros(dia.size, dtype=complex)
        for zj, cj in zip(z, c):
            # (z_j - t L) x = p0, LU with partial pivoting (LAPACK gtsv)
            _, _, _, x, info = lapack.zgtsv(-t * sub, zj - t * dia, -t * sup, b)
            if info != 0:  # pragma: no cover - z_j is off the spectrum: never singular
                raise np.linalg.LinAlgError(f"contour solve failed (info={info})")
            acc += cj * x
        out[k] = 2.0 * acc.real
    return out


def propagate(model: Model, grid: Grid, p0: np.ndarray, times: ArrayLike,
              method: str = "auto") -> np.ndarray:
    """Node probabilities at each of ``times`` (>= 0) from ``p0``; rows sum to 1.

    ``method``: "eigen", "expm", "hybrid", "contour", or "auto" (:func:`propagate_contour`
    unless the start lies so deep in the tail that it would need more than
    :data:`CONTOUR_MAX_NODES` nodes, then :func:`propagate_hybrid`).  Round-off negatives
    (|p| ~ 1e-16 of the peak, ~1e-13 for the contour route) are clipped to 0: the exact
    evolution of a probability vector under a generator is non-negative.
    """
    times = np.atleast_1d(np.asarray(times, dtype=float))
    nodes = None
    if method == "auto":
        _, _, log_pi = symmetric_generator(model, grid)
        nodes = contour_nodes(amplification(log_pi, p0))
        method = "contour" if nodes is not None else "hybrid"
    if method == "eigen":
        out = propagate_eigen(model, grid, p0, times)
    elif method == "expm":
        out = propagate_expm(model, grid, p0, times)
    elif method == "hybrid":
        out = propagate_hybrid(model, grid, p0, times)
    elif method == "contour":
        out = propagate_contour(model, grid, p0, times, nodes)
    else:
        raise ValueError("method must be 'auto', 'eigen', 'expm', 'hybrid' or 'contour', "
                         f"got {method!r}")
    return np.asarray(np.clip(out, 0.0, None))
