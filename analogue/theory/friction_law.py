"""Exact stationary law of the paper's model with any odd friction law (not only tanh or sgn).

A real circuit element realises ``Delta c(v)`` with its own normalised law ``c`` (a diode
bridge: its DC I-V, :func:`analogue.circuit.mapping.CircuitMapping.friction_law`).  The model
stays one-dimensional with additive noise, so its stationary law is still exactly
``p_s = exp(-gamma U)/Z`` (eq. (6)), with

    U(v) = v^2/(2 tau_m) + Delta int_0^v c(u) du - a v,

and the position diffusion coefficient (Green-Kubo) is the quadrature
``D_x = gamma int G(v)^2 / p_s(v) dv``, ``G(v) = int_{-inf}^v (u - <v>) p_s(u) du`` (the
continuum form of :mod:`analogue.theory.stationary`'s grid sum).  Everything here is a
quadrature on one uniform grid that resolves the law's width: ``U`` by cumulative Simpson of
``U'``, the moments by Simpson, ``G`` by cumulative Simpson.  With ``c = tanh(v/epsilon)`` the
values agree with :func:`analogue.theory.exact.stationary_moments` at that epsilon to 3e-12
(moments, relative) and 1.5e-9 (D_x) at the two models of tests/unit/test_friction_law.py
(which asserts 1e-9 and 1e-7).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import integrate

from .. import checks
from ..model import Model
from .stationary import StationaryMoments

__all__ = ["FrictionLaw", "stationary_law_with_friction"]


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
