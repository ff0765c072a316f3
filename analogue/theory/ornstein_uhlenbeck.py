"""Closed forms for the model without dry friction (Delta = 0): an Ornstein-Uhlenbeck process.

With ``Delta = 0`` the reduced equation (paper, eqs. (4) and (5)) is linear,

    dv = -(v - mu)/tau_m dt + sqrt(2/gamma) dW,      mu = a tau_m,

so everything is Gaussian.  Derivations (``s^2 = tau_m/gamma``, ``r = exp(-t/tau_m)``):

* Propagator: ``v(t) = mu + (v0 - mu) r + sqrt(2/gamma) int_0^t e^{-(t-s)/tau_m} dW_s``, a
  Gaussian of mean ``mu + (v0 - mu) r`` and variance ``(2/gamma)(tau_m/2)(1 - r^2) = s^2 (1 - r^2)``.
* Stationary law (t -> inf): mean ``mu``, variance ``s^2`` (eq. (6) with U quadratic).
* Stationary autocovariance: ``C(t) = <dv(0) dv(t)> = s^2 exp(-|t|/tau_m)`` (from the propagator
  mean, linear in v0).
* Work ``W_tau = F int_0^tau v ds`` (eq. (3)), ``F = m a``, in the stationary state: a linear
  functional of a Gaussian process, hence Gaussian at every tau, with
  ``<W> = F mu tau`` and
  ``Var W = F^2 int_0^tau int_0^tau C(s - s') ds ds' = 2 F^2 s^2 tau_m [tau - tau_m (1 - e^{-tau/tau_m})]``.
* Finite-tau cumulant generating function ``ln E e^{k W} = k <W> + k^2 Var W / 2`` (Gaussian).
* Scaled CGF ``lambda(k) = lim (1/tau) ln E e^{kW} = k F mu + k^2 F^2 s^2 tau_m``
  (``Var W / tau -> 2 F^2 s^2 tau_m``, the Green-Kubo integral of C).
* Rate function in the paper's scaling ``P_tau(w) ~ exp(-tau gamma I(w))`` (eq. (54)):
  ``gamma I(w) = sup_k [k w - lambda(k)] = (w - F mu)^2 / (4 F^2 s^2 tau_m)``, i.e.
  ``I(w) = (w - F a tau_m)^2 / (4 F^2 tau_m^2) = (1/4)(w/(m a tau_m) - a)^2`` -- the paper's
  eq. (64) with Delta = 0.  Here the weak-noise formula is exact at every gamma.

All functions take an :class:`analogue.Model` with ``delta == 0`` (``epsilon`` is then irrelevant).
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .. import checks
from ..model import Model

__all__ = [
    "stationary_mean", "stationary_variance", "autocovariance", "propagator",
    "work_mean", "work_variance", "work_pdf", "scgf", "rate_function",
]


def _check(model: Model) -> Model:
    checks.instance("model", model, Model, description="an analogue.Model")
    if model.delta != 0:
        raise ValueError(f"Ornstein-Uhlenbeck closed forms need delta == 0, got delta={model.delta!r}")
    return model


def _tau(tau: ArrayLike) -> np.ndarray:
    out = np.asarray(tau, dtype=float)
    if not np.all(np.isfinite(out)) or np.any(out <= 0):
        raise ValueError("tau must be finite and > 0")
    return out


def _force(model: Model) -> float:
    if model.force == 0:
        raise ValueError("the work distribution is degenerate (W = 0) for a == 0; need a != 0")
    return model.force


def stationary_mean(model: Model) -> float:
    """Stationary mean velocity ``mu = a tau_m``."""
    return _check(model).a * model.tau_m


def stationary_variance(model: Model) -> float:
    """Stationary velocity variance ``s^2 = tau_m/gamma`` (eq. (6), U quadratic)."""
    return _check(model).tau_m / model.gamma


def autocovariance(model: Model, t: ArrayLike) -> np.ndarray:
    """Stationary autocovariance ``<dv(0) dv(t)> = s^2 exp(-|t|/tau_m)``."""
    lag = np.asarray(t, dtype=float)
    return np.asarray(stationary_variance(model) * np.exp(-np.abs(lag) / model.tau_m))


def propagator(model: Model, v: ArrayLike, t: ArrayLike, v0: float) -> np.ndarray:
    """Transition density ``f(v, t | v0, 0)``: Gaussian, mean ``mu + (v0 - mu) e^{-t/tau_m}``,
    variance ``s^2 (1 - e^{-2t/tau_m})``.  Requires t > 0."""
    t = _tau(t)
    mu, s2 = stationary_mean(model), stationary_variance(model)
    r = np.exp(-t / model.tau_m)
    mean = mu + (np.asarray(v0, dtype=float) - mu) * r
    var = s2 * -np.expm1(-2.0 * t / model.tau_m)
    v = np.asarray(v, dtype=float)
    return np.exp(-(v - mean) ** 2 / (2.0 * var)) / np.sqrt(2.0 * math.pi * var)


def work_mean(model: Model, tau: ArrayLike) -> np.ndarray:
    """Stationary ``<W_tau> = F a tau_m tau`` (eq. (3))."""
    return model.force * stationary_mean(model) * _tau(tau)


def work_variance(model: Model, tau: ArrayLike) -> np.ndarray:
    """Stationary ``Var W_tau = 2 F^2 s^2 tau_m [tau - tau_m (1 - e^{-tau/tau_m})]``."""
    _check(model)
    tau = _tau(tau)
    tm = model.tau_m
    # tau - tm (1 - e^{-x}) = tm (x - 1 + e^{-x}); the bracket suffers cancellation for small x.
    x = tau / tm
    bracket = np.where(x < 1e-3, x * x / 2 - x**3 / 6 + x**4 / 24, x + np.expm1(-x))
    return 2.0 * model.force**2 * stationary_variance(model) * tm * tm * bracket


def work_pdf(model: Model, w: ArrayLike, tau: ArrayLike) -> np.ndarray:
    """Exact density of the work rate ``w = W_tau/tau`` at finite tau (Gaussian)."""
    _force(model)
    tau = _tau(tau)
    mean = model.force * stationary_mean(model)
    var = work_variance(model, tau) / tau**2
    w = np.asarray(w, dtype=float)
    return np.asarray(np.exp(-(w - mean) ** 2 / (2.0 * var)) / np.sqrt(2.0 * math.pi * var))


def scgf(model: Model, k: ArrayLike) -> np.ndarray:
    """``lambda(k) = k F a tau_m + k^2 F^2 tau_m^2 / gamma``."""
    k = np.asarray(k, dtype=float)
    F = model.force
    return np.asarray(k * F * stationary_mean(model)
                      + k * k * F * F * stationary_variance(model) * model.tau_m)


def rate_function(model: Model, w: ArrayLike) -> np.ndarray:
    """``I(w) = (w - F a tau_m)^2 / (4 F^2 tau_m^2)`` in the scaling ``P ~ exp(-tau gamma I)``
    (eq. (64) with Delta = 0; exact for every gamma)."""
    F = _force(model)
    w = np.asarray(w, dtype=float)
    tm = model.tau_m
    return (w - F * stationary_mean(model)) ** 2 / (4.0 * F * F * tm * tm)
