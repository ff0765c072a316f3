"""Exact stationary law of the paper's model with any odd friction law (not only tanh or sgn).

A real circuit element realises ``Delta c(v)`` with its own normalised law ``c`` (a diode
bridge: its DC I-V, :func:`analogue.circuit.mapping.CircuitMapping.friction_law`).  The model
stays one-dimensional with additive noise, so its stationary law is still exactly
``p_s = exp(-gamma U)/Z`` (eq. (6)), with

    U(v) = v^2/(2 tau_m) + Delta int_0^v c(u) du - a v,

and the position diffusion coefficient (Green-Kubo) is the quadrature
``D_x = gamma int G(v)^2 / p_s(v) dv``, ``G(v) = int_{-inf}^v (u - <v>) p_s(u) du`` (the
continuum form of :mod:`analogue.theory.stationary`'s grid sum).  Transition moments
(:func:`transition_moments_with_friction`) propagate the Scharfetter-Gummel master equation of
:mod:`analogue.theory.fokker_planck` built on that U (detailed balance with exp(-gamma U) is
exact at the nodes for any law) by its spectral sum, or by the contour route of
:mod:`analogue.theory.propagation` for a start deep in the tail.  Everything here is a
quadrature on one uniform grid that resolves the law's width: ``U`` by cumulative Simpson of
``U'``, the moments by Simpson, ``G`` by cumulative Simpson.  With ``c = tanh(v/epsilon)`` the
values agree with :func:`analogue.theory.exact.stationary_moments` at that epsilon to 3e-12
(moments, relative) and 1.5e-9 (D_x) at the two models of tests/unit/test_friction_law.py
(which asserts 1e-9 and 1e-7).
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
from scipy import integrate, linalg, sparse
from scipy.sparse.linalg import expm_multiply

from .. import checks
from ..model import Model
from .fokker_planck import bernoulli
from .propagation import amplification, contour_nodes, contour_tridiagonal
from .stationary import StationaryMoments

# spectral route: modes kept while exp(lambda t_min) > e^-_MODES; starts where gamma (U - U_min)/2
# exceeds _DEEP use the contour route (the spectral sum's rounding error is about
# exp(gamma (U(v0) - U_min)/2) 1e-16 of the mass: 1e-6 at _DEEP).  They went by expm_multiply,
# O(n / h^2) per unit time: 28-66 s per law to t = 8 from v0 = -3 on the 1N4148 grid at tau_m =
# 2 (n = 3282), against 0.3-0.6 s by the contour route, which agrees to 1.8e-10
# (benchmarks/bench_friction_law.py)
_MODES = 40.0
_DEEP = 23.0

__all__ = ["FrictionLaw", "stationary_law_with_friction", "transition_moments_with_friction"]


@dataclass(frozen=True, eq=False)
class FrictionLaw:
    """The stationary law on a grid and its moments, for one friction law ``c``."""

    v: np.ndarray          # uniform grid (v = 0 a node)
    density: np.ndarray    # p_s(v), normalised on the grid (Simpson)
    moments: StationaryMoments

    def mass(self, lo: float, hi: float) -> float:
        """P(lo < v < hi) by the cumulative Simpson integral, interpolated at the ends."""
        c = integrate.cumulative_simpson(self.density, x=self.v, initial=0.0)
        return float(np.interp(hi, self.v, c) - np.interp(lo, self.v, c))


def _range(model: Model, width: float) -> tuple[float, float]:
    """Where gamma (U - U_min) < 50 for every friction law |c| <= 1: U'' >= 1/tau_m bounds the
    law by Gaussians of variance tau_m/gamma about the extreme attractors (a +- Delta) tau_m."""
    reach = 10.0 * math.sqrt(model.tau_m / model.gamma) + 10.0 * width
    return (min(0.0, (model.a - model.delta) * model.tau_m) - reach,
            max(0.0, (model.a + model.delta) * model.tau_m) + reach)


def stationary_law_with_friction(model: Model, friction: Callable[[np.ndarray], np.ndarray],
                                 width: float, points_per_width: int = 40,
                                 max_points: int = 2_000_001) -> FrictionLaw:
    """Stationary law of ``dv = (-v/tau_m - Delta c(v) + a) dt + sqrt(2/gamma) dW`` (the paper's
    model, eq. (4), with its sgn replaced by ``c = friction``, vectorised, odd, |c| <= 1) and its
    moments (``mean_sign`` is ``<c(v)>``, ``diffusion`` the Green-Kubo D_x, ``p_zero`` 0).

    ``width``: the smallest velocity scale of ``c`` (e.g. the tanh width epsilon); the grid
    resolves it with ``points_per_width`` points and ``sqrt(tau_m/gamma)`` with 400.
    ``model.epsilon`` is not used (the law is ``friction``)."""
    checks.instance("model", model, Model, description="an analogue.Model")
    if not model.is_paper:
        raise ValueError("stationary_law_with_friction is for the paper's model (no cubic, "
                         "Stribeck, spring or shot noise)")
    width = checks.positive("width", width)
    h = min(width / points_per_width, model.velocity_scale / 400.0)
    lo, hi = _range(model, width)
    n_lo = max(2, 2 * math.ceil(-lo / (2 * h)))
    n_hi = max(2, 2 * math.ceil(hi / (2 * h)))
    if n_lo + n_hi + 1 > max_points:
        raise ValueError(f"width={width:g} needs {n_lo + n_hi + 1} grid points over the law "
                         f"(more than {max_points}); the law is too narrow against "
                         f"sqrt(tau_m/gamma)={model.velocity_scale:g}")
    v = np.concatenate([np.linspace(lo, 0.0, n_lo + 1), np.linspace(0.0, hi, n_hi + 1)[1:]])
    i0 = n_lo
    c = np.asarray(friction(v), dtype=float)
    if c.shape != v.shape or not np.all(np.isfinite(c)):
        raise ValueError("friction must map a velocity array to finite values of the same shape")
    du = v / model.tau_m + model.delta * c - model.a
    # cumulative Simpson from v = 0 in both directions (v = 0 a node: U(0) = 0 exactly)
    up = integrate.cumulative_simpson(du[i0:], x=v[i0:], initial=0.0)
    down = -integrate.cumulative_simpson(du[:i0 + 1][::-1], x=-v[:i0 + 1][::-1], initial=0.0)[::-1]
    u = np.concatenate([down[:-1], up])
    gu = model.gamma * (u - u.min())
    w = np.exp(-gu)
    w /= integrate.simpson(w, x=v)
    mean = float(integrate.simpson(w * v, x=v))
    var = float(integrate.simpson(w * (v - mean) ** 2, x=v))
    pp = float(integrate.simpson(w[i0:], x=v[i0:]))
    sign = float(integrate.simpson(w * c, x=v))
    # G from the nearer end (left of the mean from the left, right of it from the right), so
    # that in each tail it is a sum of tail terms, not a difference of O(1) numbers
    f = (v - mean) * w
    left = integrate.cumulative_simpson(f, x=v, initial=0.0)
    right = integrate.cumulative_simpson(f[::-1], x=-v[::-1], initial=0.0)[::-1]
    g = np.where(v < mean, left, right)
    live = gu < 200.0  # beyond, G^2/p_s ~ p_s (v - <v>)^2 tau_m^2 < e^-200: nothing
    ratio = np.where(live, g * g / np.where(live, w, 1.0), 0.0)
    diff = model.gamma * float(integrate.simpson(ratio, x=v))
    moments = StationaryMoments(mean=mean, variance=var, p_positive=pp, p_negative=1.0 - pp,
                                mean_sign=sign, diffusion=diff, drift=mean, p_zero=0.0)
    return FrictionLaw(v, w, moments)


def _deep_start(sub: np.ndarray, dia: np.ndarray, sup: np.ndarray, p0: np.ndarray,
                times: np.ndarray, half: np.ndarray, step: float) -> list[np.ndarray]:
    """``exp(L t) p0`` at the sorted ``times`` for a start deep in the tail: the contour route
    (:func:`analogue.theory.propagation.contour_tridiagonal`, O(n) per time whatever t) with the
    nodes :func:`~analogue.theory.propagation.contour_nodes` asks for this start's
    amplification ``ln sum p_j e^{half_j}``; a start too deep even for it (more than
    CONTOUR_MAX_NODES) goes by ``expm_multiply`` in steps of at most ``step`` until the
    mass allows it (as :func:`~analogue.theory.propagation.propagate_hybrid`)."""
    log_pi = -2.0 * half
    gen = None
    probs: list[np.ndarray] = []
    now, p = 0.0, p0
    for pos, t in enumerate(times):
        while True:
            q = np.clip(p, 0.0, None)
            nodes = contour_nodes(amplification(log_pi, q))
            if nodes is not None:
                return probs + list(contour_tridiagonal(sub, dia, sup, q, times[pos:] - now, nodes))
            if now >= t:
                break
            if gen is None:
                gen = sparse.diags([sup, dia, sub], [1, 0, -1], format="csr")
            dt = min(step, float(t) - now)
            p = expm_multiply(gen * dt, p)
            now += dt
        probs.append(p)
    return probs


def _potential_on(v: np.ndarray, i0: int, du: np.ndarray) -> np.ndarray:
    """U on the grid ``v`` (node i0 is v = 0) from U' = du, by cumulative Simpson from 0."""
    up = integrate.cumulative_simpson(du[i0:], x=v[i0:], initial=0.0)
    down = -integrate.cumulative_simpson(du[:i0 + 1][::-1], x=-v[:i0 + 1][::-1], initial=0.0)[::-1]
    return np.concatenate([down[:-1], up])


def transition_moments_with_friction(model: Model, friction: Callable[[np.ndarray], np.ndarray],
                                     width: float, v0: float, times: Iterable[float],
                                     h: float | None = None, method: str = "auto"
                                     ) -> dict[float, tuple[float, float, float]]:
    """Mean, variance and P(v < 0) of ``f(v, t | v0)`` for the paper's model with its sgn
    replaced by ``c = friction`` (as :func:`stationary_law_with_friction`), at each of
    ``times`` (> 0): ``{t: (mean, variance, p_negative)}``.

    Scharfetter-Gummel rates ``B(+-gamma dU)/(gamma h^2)`` on a uniform grid of spacing ``h``
    (default ``width/2``, at most sqrt(tau_m/gamma)/40) with v = 0 a node, the start split
    linearly between the two nodes around v0; in time the spectral sum of the symmetrised
    generator over the modes that survive the earliest time (for a start deep in the tail,
    where that sum would cancel, the contour route
    :func:`analogue.theory.propagation.contour_tridiagonal`: O(n) per time whatever t, 1e-11
    of the peak; ``method="expm"`` forces ``expm_multiply`` through the sorted times, the
    former deep route, 100-200x slower to t = 8 and equal to 2e-10); P(v < 0) counts half of
    the node v = 0.  O(h^2) in space: two laws on the same grid share the leading error, so
    their difference (the element term) is far more accurate than either (with the tanh law,
    against :func:`analogue.theory.exact.propagator`'s moments: 1e-4 of the spread at the
    default h, tests/unit/test_friction_law.py)."""
    checks.instance("model", model, Model, description="an analogue.Model")
    if not model.is_paper:
        raise ValueError("transition_moments_with_friction is for the paper's model")
    width = checks.positive("width", width)
    v0 = checks.finite("v0", v0)
    times = [checks.positive("t", float(t)) for t in times]
    if method not in ("auto", "expm"):
        raise ValueError(f"method must be 'auto' or 'expm', got {method!r}")
    if h is None:
        h = min(width / 2.0, model.velocity_scale / 40.0)
    h = checks.positive("h", h)
    lo, hi = _range(model, width)
    reach = 10.0 * math.sqrt(model.tau_m / model.gamma)
    lo, hi = min(lo, v0 - reach), max(hi, v0 + reach)
    n_lo, n_hi = math.ceil(-lo / h), math.ceil(hi / h)
    v = h * np.arange(-n_lo, n_hi + 1, dtype=float)
    i0 = n_lo
    c = np.asarray(friction(v), dtype=float)
    if c.shape != v.shape or not np.all(np.isfinite(c)):
        raise ValueError("friction must map a velocity array to finite values of the same shape")
    u = model.gamma * _potential_on(v, i0, v / model.tau_m + model.delta * c - model.a)
    du = np.diff(u)
    k = 1.0 / (model.gamma * h * h)
    up, down = k * bernoulli(du), k * bernoulli(-du)
    diag = np.zeros(v.size)
    diag[:-1] -= up
    diag[1:] -= down
    p0 = np.zeros(v.size)
    j = int(math.floor((v0 - v[0]) / h))
    w = (v0 - v[j]) / h
    p0[j] += 1.0 - w
    p0[j + 1] += w
    grid_t = np.sort(np.array(times))
    half = 0.5 * (u - u.min())  # -ln sqrt(pi), up to a constant
    if method == "auto" and half[j] + half[j + 1] < 2.0 * _DEEP:
        # spectral route: S = Pi^-1/2 L Pi^1/2 symmetric tridiagonal; only the modes that
        # survive the earliest time (exp(lambda t_min) > e^-_MODES) are needed
        lam, q = linalg.eigh_tridiagonal(diag, np.sqrt(up * down), select="v",
                                         select_range=(-_MODES / grid_t[0], 1.0))
        b = q.T @ (p0 * np.exp(half))
        probs = [np.exp(-half) * (q @ (np.exp(lam * t) * b)) for t in grid_t]
    elif method == "expm":
        # expm_multiply through the sorted times (the deep route before the contour; kept to
        # check it: O(n / h^2) per unit time, 28 s per law to t = 8 from v0 = -3 on the
        # 1N4148 tau_m = 2 grid, benchmarks/bench_friction_law.py)
        gen = sparse.diags([down, diag, up], [1, 0, -1], format="csr")
        probs, prev, p = [], 0.0, p0
        for t in grid_t:
            p = expm_multiply(gen * (t - prev), p)
            prev = t
            probs.append(p)
    else:
        # a start deep in the tail: the spectral sum would cancel; the contour route
        probs = _deep_start(up, diag, down, p0, grid_t, half, model.tau_m / 4.0)
    out = {}
    for t, p in zip(grid_t, probs):
        q = np.clip(p, 0.0, None)
        q = q / q.sum()
        mean = float(np.dot(v, q))
        var = float(np.dot((v - mean) ** 2, q))
        neg = float(q[:i0].sum() + 0.5 * q[i0])
        out[float(t)] = (mean, var, neg)
    return out
