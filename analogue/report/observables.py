"""Scalar observables of an ensemble, and the same observables predicted by theory.

The budget terms need the *same* observable evaluated on several ensembles (the circuit, its
tight-tolerance re-run, the held-noise and white-noise Monte Carlo runs), so each observable is
a plain function of an :class:`~analogue.Ensemble`; names are the keys of the returned dicts.
"""
from __future__ import annotations

import numpy as np
from scipy import integrate

from ..ensemble import Ensemble
from ..estimators import transport, work_rate_samples
from ..model import Model

__all__ = ["transition_values", "stationary_values", "jackknife", "subset", "jackknife_difference",
           "exact_transition", "weak_noise_transition", "exact_stationary", "velocity_grid",
           "work_variance_exact", "tname", "sname"]


def tname(kind: str, t: float, v0: float) -> str:
    return f"{kind} at t={t:g} from v0={v0:g}"


def sname(kind: str, tau: float | None = None) -> str:
    return kind if tau is None else f"{kind} (tau={tau:g})"


def subset(ens: Ensemble, rows) -> Ensemble:
    return Ensemble(ens.t, ens.v[rows], ens.x[rows], ens.meta)


# ----------------------------------------------------------------------------- ensembles
def transition_values(ens: Ensemble, v0: float, times) -> dict:
    """Mean, variance and P(v < 0) of v(t) over the replicas, at each time."""
    out = {}
    for t in times:
        v = ens.at(t)
        out[tname("mean v", t, v0)] = float(np.mean(v))
        out[tname("var v", t, v0)] = float(np.var(v, ddof=1))
        out[tname("P(v<0)", t, v0)] = float(np.mean(v < 0))
    return out


def stationary_values(ens: Ensemble, *, burn_in: float, threshold: float, force: float,
                           taus=()) -> dict:
    """Time-and-replica averages after ``burn_in``: moments, stick fraction, transport, and the
    mean and variance of the work rate over windows ``tau`` (paper eqs. (3), (52))."""
    i0 = int(np.searchsorted(ens.t, ens.t[0] + burn_in - 1e-12))
    v = ens.v[:, i0:]
    out = {
        sname("mean v"): float(v.mean()),
        sname("var v"): float(v.var()),
        sname("P(v>0)"): float(np.mean(v > 0)),
        sname("stick fraction"): float(np.mean(np.abs(v) < threshold)),
    }
    tr = transport(ens, burn_in=burn_in)
    out[sname("diffusion D_x")] = float(tr.diffusion)
    for tau in taus:
        w = work_rate_samples(ens, tau, force, burn_in=burn_in)
        out[sname("mean w", tau)] = float(w.mean())
        out[sname("var w", tau)] = float(w.var())
    return out


def _groups(n: int, groups: int):
    g = max(2, min(groups, n // 2))
    return g, np.arange(n) % g


def _jk_se(reps, g: int) -> float:
    d = np.asarray(reps, dtype=float)
    return float(np.sqrt((g - 1) / g * np.sum((d - d.mean()) ** 2)))


def jackknife(fn, ens: Ensemble, groups: int = 32):
    """``fn(ens)`` with delete-a-group jackknife errors over replicas (which are independent,
    so the errors hold however correlated the samples along one path are);
    returns ``{name: (value, se)}``."""
    g, labels = _groups(ens.replicas, groups)
    full = fn(ens)
    reps = [fn(subset(ens, labels != j)) for j in range(g)]
    return {k: (float(full[k]), _jk_se([r[k] for r in reps], g)) for k in full}


def jackknife_difference(fn, a: Ensemble, b: Ensemble, groups: int = 16):
    """``fn(a) - fn(b)`` for paired ensembles (row i of a and b share their noise), with
    delete-a-group jackknife standard errors; returns ``{name: (diff, se)}``."""
    if b.replicas != a.replicas:
        raise ValueError("paired ensembles need the same number of replicas")
    g, labels = _groups(a.replicas, groups)
    full_a, full_b = fn(a), fn(b)
    reps = []
    for j in range(g):
        keep = labels != j
        fa, fb = fn(subset(a, keep)), fn(subset(b, keep))
        reps.append({k: fa[k] - fb[k] for k in full_a})
    return {k: (float(full_a[k] - full_b[k]), _jk_se([r[k] for r in reps], g)) for k in full_a}


# -------------------------------------------------------------------------------- theory
def velocity_grid(model: Model, v0s=(), n: int = 4001, widths: float = 12.0) -> np.ndarray:
    """A fine uniform grid with v = 0 on a node, covering p_s and the initial velocities."""
    c = model.potential_minimum()
    s = model.velocity_scale
    lo = min([c] + list(v0s)) - widths * s
    hi = max([c] + list(v0s)) + widths * s
    h = (hi - lo) / (n - 1)
    return h * np.arange(int(np.floor(lo / h)), int(np.ceil(hi / h)) + 1)


def _moments(v, f):
    norm = integrate.trapezoid(f, v)
    f = f / norm
    mean = integrate.trapezoid(v * f, v)
    var = integrate.trapezoid((v - mean) ** 2 * f, v)
    neg = integrate.trapezoid(np.where(v <= 0, f, 0.0), v) - 0.5 * f[np.argmin(np.abs(v))] * (v[1] - v[0])
    return mean, var, neg


def exact_transition(model: Model, v0: float, times, h: float | None = None,
                     densities: dict | None = None) -> dict:
    """Exact finite-noise mean, variance and P(v<0) of f(v, t | v0) (Fokker-Planck).

    ``h`` fixes the Fokker-Planck grid spacing: a difference between two models (the smoothing
    bias) is computed on one common grid so that discretisation errors cancel.  If
    ``densities`` is a dict, the grid and densities are stored in it ("v", "f")."""
    from ..theory import exact
    v = velocity_grid(model, [v0])
    f = np.atleast_2d(exact.propagator(model, v, np.asarray(times, dtype=float), v0, h=h))
    if densities is not None:
        densities.update(v=v, f=f)
    out = {}
    for t, row in zip(times, f):
        m, var, neg = _moments(v, row)
        out[tname("mean v", t, v0)] = m
        out[tname("var v", t, v0)] = var
        out[tname("P(v<0)", t, v0)] = neg
    return out


def histogram_chi2(samples, v, f, min_expected: float = 5.0):
    """Pearson chi^2 of iid ``samples`` against the density ``f`` on the grid ``v``.

    Bins are equal-probability under the theory (about ``n/20`` expected counts each, at
    least ``min_expected``), so every bin is well populated and the statistic is close to its
    chi^2 law; returns ``(chi2, dof)``."""
    samples = np.asarray(samples, dtype=float)
    n = samples.size
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(v))])
    cdf /= cdf[-1]
    k = int(max(2, min(20, n // min_expected)))
    qs = np.linspace(0, 1, k + 1)[1:-1]
    edges = np.interp(qs, cdf, v)
    counts = np.bincount(np.searchsorted(edges, samples), minlength=k)
    expected = n / k
    return float(np.sum((counts - expected) ** 2) / expected), k - 1


def weak_noise_transition(model: Model, v0: float, times) -> dict:
    """The same moments of the paper's saddle-point propagator (eqs. (46)-(51))."""
    from ..theory import weak_noise
    v = velocity_grid(model, [v0])
    out = {}
    for t in times:
        m, var, neg = _moments(v, np.asarray(weak_noise.propagator(model, v, t, v0)))
        out[tname("mean v", t, v0)] = m
        out[tname("var v", t, v0)] = var
        out[tname("P(v<0)", t, v0)] = neg
    return out


def work_variance_exact(model: Model, tau: float, n: int = 801, h: float | None = None) -> float:
    """Var(w) = (F/tau)^2 * 2 int_0^tau (tau - s) C(s) ds from the exact autocorrelation C
    (Green-Kubo route, independent of the work density)."""
    from ..theory import exact
    s = np.linspace(0.0, tau, n)
    c = np.asarray(exact.autocorrelation(model, s, h=h), dtype=float)
    var_int = 2.0 * integrate.simpson((tau - s) * c, x=s)
    return float((model.force / tau) ** 2 * var_int)


def exact_stationary(model: Model, *, threshold: float, taus=(), h: float | None = None) -> dict:
    from ..estimators import stick_fraction_theory
    from ..theory import exact
    m = exact.stationary_moments(model)
    out = {
        sname("mean v"): m.mean,
        sname("var v"): m.variance,
        sname("P(v>0)"): m.p_positive,
        sname("stick fraction"): float(stick_fraction_theory(model, threshold)),
        sname("diffusion D_x"): m.diffusion,
    }
    for tau in taus:
        out[sname("mean w", tau)] = model.force * m.mean
        out[sname("var w", tau)] = work_variance_exact(model, tau, h=h)
    return out
