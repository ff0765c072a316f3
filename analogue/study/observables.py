"""Scalar observables of an ensemble, and the same observables predicted by theory.

The budget terms need the *same* observable evaluated on several ensembles (the circuit, its
tight-tolerance re-run, the held-noise and white-noise Monte Carlo runs), so each observable is
a plain function of an :class:`~analogue.Ensemble`; names are the keys of the returned dicts.
Which observables there are, and how each is estimated and predicted, is the catalogue's
(:mod:`analogue.study.catalogue`); this module applies it (jackknife errors, theory grids).
"""
from __future__ import annotations

import numpy as np
from scipy import integrate

from ..estimators.goodness_of_fit import histogram_chi2
from ..estimators.resampling import jackknife, jackknife_difference, subset
from ..model import Model
from .catalogue import (stationary_label, stationary_theory, stationary_values, transition_label,
                               transition_theory, transition_values)
from ..theory import exact
from ..theory.cache import cached_call
from ..theory import weak_noise
from ..theory.work_statistics import work_variance

__all__ = ["histogram_chi2", "transition_values", "stationary_values", "jackknife", "subset", "jackknife_difference",
           "exact_transition", "weak_noise_transition", "exact_stationary", "velocity_grid",
           "work_variance_exact", "transition_label", "stationary_label"]


# -------------------------------------------------------------------------------- theory
def velocity_grid(model: Model, v0s=(), n: int = 4001, widths: float = 12.0) -> np.ndarray:
    """A fine uniform grid with v = 0 on a node, covering p_s and the initial velocities."""
    c = model.potential_minimum()
    s = model.velocity_scale
    lo = min([c] + list(v0s)) - widths * s
    hi = max([c] + list(v0s)) + widths * s
    h = (hi - lo) / (n - 1)
    return h * np.arange(int(np.floor(lo / h)), int(np.ceil(hi / h)) + 1)


def exact_transition(model: Model, v0: float, times, h: float | None = None,
                     densities: dict | None = None, cache=None) -> dict:
    """Exact finite-noise mean, variance and P(v<0) of f(v, t | v0) (Fokker-Planck).

    ``h`` fixes the Fokker-Planck grid spacing: a difference between two models (the smoothing
    bias) is computed on one common grid so that discretisation errors cancel.  If
    ``densities`` is a dict, the grid and densities are stored in it ("v", "f").  ``cache``:
    the theory cache (:func:`analogue.theory.cache.open_cache`; False: compute afresh)."""
    v = velocity_grid(model, [v0])
    f = np.atleast_2d(cached_call(exact.propagator, model, v, np.asarray(times, dtype=float),
                                  float(v0), h=h, cache=cache))
    if densities is not None:
        densities.update(v=v, f=f)
    return transition_theory(v, f, v0, times)


def weak_noise_transition(model: Model, v0: float, times, densities: dict | None = None) -> dict:
    """The same moments of the paper's saddle-point propagator (eqs. (46)-(51)).  If
    ``densities`` is a dict, the grid and densities are stored in it ("v", "f")."""
    v = velocity_grid(model, [v0])
    f = np.array([np.asarray(weak_noise.propagator(model, v, t, v0)) for t in times])
    if densities is not None:
        densities.update(v=v, f=f)
    return transition_theory(v, f, v0, times, weak_noise=True)


def work_variance_exact(model: Model, tau: float, n: int = 801, h: float | None = None) -> float:
    """Var(w) = (F/tau)^2 * 2 int_0^tau (tau - s) C(s) ds from the exact autocorrelation C
    (Green-Kubo route, independent of the work density)."""
    s = np.linspace(0.0, tau, n)
    c = np.asarray(exact.autocorrelation(model, s, h=h), dtype=float)
    var_int = 2.0 * integrate.simpson((tau - s) * c, x=s)
    return float((model.force / tau) ** 2 * var_int)


def exact_stationary(model: Model, *, threshold: float, taus=(), h: float | None = None,
                     cache=None) -> dict:
    """Exact stationary observables (the labels of :func:`stationary_values`); the work
    variances of all windows from one autocorrelation
    (:func:`analogue.theory.work_statistics.work_variance`, the same numbers as
    :func:`work_variance_exact`)."""
    m = cached_call(exact.stationary_moments, model, cache=cache)
    taus = [float(t) for t in taus]
    var_w = (np.asarray(cached_call(work_variance, model, np.asarray(taus), h=h, cache=cache))
             if taus else np.zeros(0))
    return stationary_theory(model, m, threshold=threshold,
                             work_variance={tau: float(v) for tau, v in zip(taus, var_w)})
