"""The catalogue of compared observables: one typed entry per kind, mapped to its estimator
(on circuit or Monte Carlo ensembles), its exact finite-noise theory and, where the paper has
one, its weak-noise theory.

Adding an observable is one :class:`Kind` in :data:`KINDS`: the report's estimates
(:func:`transition_values`, :func:`stationary_values`), its exact and weak-noise values
(:func:`transition_theory`, :func:`stationary_theory`) and its label all follow from it.

Labels (the ``observable`` field of ``metrics.json``) are stable: ``"<kind> at t=<t> from
v0=<v0>"`` for the transition run, ``"<kind>"`` or ``"<kind> (tau=<tau>)"`` for the
stationary run (numbers formatted with ``:g``); ``tests/unit/test_study_catalogue.py``
holds them against the labels of a quick paper report.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy import integrate

from ..ensemble import Ensemble
from ..model import Model

__all__ = ["KINDS", "Kind", "Observable", "TRANSITION", "STATIONARY", "density_moments",
           "transition_observables", "stationary_observables", "transition_values",
           "stationary_values", "transition_theory", "stationary_theory", "transition_label", "stationary_label",
           "kind_of", "find", "planned_comparisons"]

TRANSITION = "transition"
STATIONARY = "stationary"


def transition_label(kind: str, t: float, v0: float) -> str:
    """Label of a transition-run observable."""
    return f"{kind} at t={t:g} from v0={v0:g}"


def stationary_label(kind: str, tau: float | None = None) -> str:
    """Label of a stationary-run observable (``tau``: the work window)."""
    return kind if tau is None else f"{kind} (tau={tau:g})"


# --------------------------------------------------------------------------- estimators
@dataclass(frozen=True, eq=False)
class StationarySample:
    """What the stationary estimators read: one ensemble after its burn-in (work rates
    computed once per window)."""

    ens: Ensemble
    v: np.ndarray               # velocities after the burn-in (replicas x samples)
    burn_in: float
    threshold: float
    force: float
    _work: dict = field(default_factory=dict, repr=False)

    def work(self, tau: float) -> np.ndarray:
        if tau not in self._work:
            self._work[tau] = _work_rates(self, tau)
        return self._work[tau]


def _diffusion(s: StationarySample, tau=None) -> float:
    from ..estimators import transport
    return float(transport(s.ens, burn_in=s.burn_in).diffusion)


def _work_rates(s: StationarySample, tau: float) -> np.ndarray:
    from ..estimators import work_rate_samples
    return work_rate_samples(s.ens, tau, s.force, burn_in=s.burn_in)


def _chi2_per_dof(samples, v, f) -> tuple[float, float]:
    from ..estimators.goodness_of_fit import histogram_chi2
    chi2, dof = histogram_chi2(samples, v, f)
    return chi2 / dof, math.sqrt(2.0 / dof)


# ------------------------------------------------------------------------------- theory
def density_moments(v: np.ndarray, f: np.ndarray) -> tuple[float, float, float]:
    """Mean, variance and P(v <= 0) of a density ``f`` on the uniform grid ``v`` (trapezoid;
    the node at v = 0 counts half), normalised on the grid."""
    norm = integrate.trapezoid(f, v)
    f = f / norm
    mean = integrate.trapezoid(v * f, v)
    var = integrate.trapezoid((v - mean) ** 2 * f, v)
    neg = (integrate.trapezoid(np.where(v <= 0, f, 0.0), v)
           - 0.5 * f[np.argmin(np.abs(v))] * (v[1] - v[0]))
    return mean, var, neg


@dataclass(frozen=True, eq=False)
class StationaryTheory:
    """What the exact stationary values read."""

    model: Model
    moments: object             # analogue.theory.stationary.StationaryMoments
    threshold: float
    work_variance: dict         # tau -> exact Var(w)


def _stick_theory(th: StationaryTheory, tau=None) -> float:
    from ..estimators import stick_fraction_theory
    return float(stick_fraction_theory(th.model, th.threshold))


# -------------------------------------------------------------------------------- kinds
@dataclass(frozen=True, eq=False)
class Kind:
    """One kind of observable.

    ``estimator``: transition kinds take the velocities at time t (one per replica);
    stationary kinds take a :class:`StationarySample` and the window ``tau`` (or None).
    ``exact``: transition kinds take ``density_moments`` of the exact f(v, t | v0);
    stationary kinds a :class:`StationaryTheory` and ``tau``.  ``weak_noise``: the same
    reading of the paper's saddle-point propagator (eqs. (46)-(51)), compared in the report
    where ``compare_weak_noise``."""

    name: str
    run: str                    # TRANSITION or STATIONARY
    params: tuple               # ("t", "v0"), ("tau",) or ()
    estimator: Callable
    exact: Callable
    weak_noise: Callable | None = None
    compare_weak_noise: bool = False
    description: str = ""
    # a goodness-of-fit statistic: its estimator takes the samples and the exact density
    # (v grid, f), its "exact" value is its expectation under the theory
    fit_test: bool = False
    # a probability (estimated as a fraction of replicas: an estimate of 0 or 1 from n
    # replicas still has an error ~ 1/n)
    probability: bool = False


KINDS: tuple[Kind, ...] = (
    # transition run: f(v, t | v0) (paper Fig. 6, eqs. (46)-(51)); in label order
    Kind("mean v", TRANSITION, ("t", "v0"), lambda v: float(np.mean(v)),
         exact=lambda m: m[0], weak_noise=lambda m: m[0], compare_weak_noise=True,
         description="mean velocity at t from v0"),
    Kind("var v", TRANSITION, ("t", "v0"), lambda v: float(np.var(v, ddof=1)),
         exact=lambda m: m[1], weak_noise=lambda m: m[1],
         description="velocity variance at t from v0 (unbiased over replicas)"),
    Kind("P(v<0)", TRANSITION, ("t", "v0"), lambda v: float(np.mean(v < 0)),
         exact=lambda m: m[2], weak_noise=lambda m: m[2], probability=True,
         description="probability of a negative velocity at t from v0"),
    Kind("histogram chi2/dof", TRANSITION, ("t", "v0"), lambda v, grid, f: _chi2_per_dof(v, grid, f),
         exact=lambda m=None: 1.0, fit_test=True,
         description="Pearson chi^2 per degree of freedom of the circuit velocities at t "
                     "against the exact f(v, t | v0) at the circuit's epsilon, ~20 "
                     "equal-probability bins; (value, standard error sqrt(2/dof))"),
    # stationary run (eq. (6), eqs. (3), (52), Green-Kubo); in label order
    Kind("mean v", STATIONARY, (), lambda s, tau=None: float(s.v.mean()),
         exact=lambda th, tau=None: th.moments.mean, description="stationary mean velocity"),
    Kind("var v", STATIONARY, (), lambda s, tau=None: float(s.v.var()),
         exact=lambda th, tau=None: th.moments.variance,
         description="stationary velocity variance"),
    Kind("P(v>0)", STATIONARY, (), lambda s, tau=None: float(np.mean(s.v > 0)),
         exact=lambda th, tau=None: th.moments.p_positive, probability=True,
         description="stationary probability of a positive velocity"),
    Kind("stick fraction", STATIONARY, (),
         lambda s, tau=None: float(np.mean(np.abs(s.v) < s.threshold)), exact=_stick_theory,
         description="stationary P(|v| < threshold), threshold = report.stick_threshold "
                     "sqrt(tau_m/gamma)"),
    Kind("diffusion D_x", STATIONARY, (), _diffusion,
         exact=lambda th, tau=None: th.moments.diffusion,
         description="position diffusion coefficient (Green-Kubo)"),
    Kind("mean w", STATIONARY, ("tau",), lambda s, tau: float(s.work(tau).mean()),
         exact=lambda th, tau: th.model.force * th.moments.mean,
         description="mean work rate over windows tau (eq. (3))"),
    Kind("var w", STATIONARY, ("tau",), lambda s, tau: float(s.work(tau).var()),
         exact=lambda th, tau: th.work_variance[tau],
         description="work-rate variance over windows tau (Green-Kubo route)"),
)


def kind_of(run: str, name: str) -> Kind:
    """The catalogue entry of ``name`` in the ``run`` ("transition" or "stationary")."""
    for k in KINDS:
        if k.run == run and k.name == name:
            return k
    raise KeyError(f"no observable kind {name!r} for the {run} run (known: "
                   f"{', '.join(k.name for k in KINDS if k.run == run)})")


@dataclass(frozen=True)
class Observable:
    """One compared observable: a kind and its parameters."""

    kind: str
    run: str
    t: float | None = None
    v0: float | None = None
    tau: float | None = None

    @property
    def label(self) -> str:
        if self.run == TRANSITION:
            assert self.t is not None and self.v0 is not None  # transition rows have both
            return transition_label(self.kind, self.t, self.v0)
        return stationary_label(self.kind, self.tau)

    @property
    def entry(self) -> Kind:
        return kind_of(self.run, self.kind)


def find(label: str) -> Observable | None:
    """The catalogue observable with this label (None if the label is not the catalogue's)."""
    import re
    m = re.fullmatch(r"(.+) at t=(\S+) from v0=(\S+)", label)
    if m:
        try:
            kind_of(TRANSITION, m.group(1))
        except KeyError:
            return None
        return Observable(m.group(1), TRANSITION, t=float(m.group(2)), v0=float(m.group(3)))
    m = re.fullmatch(r"(.+) \(tau=(\S+)\)", label)
    name, tau = (m.group(1), float(m.group(2))) if m else (label, None)
    try:
        k = kind_of(STATIONARY, name)
    except KeyError:
        return None
    if (tau is None) != (k.params == ()):
        return None
    return Observable(name, STATIONARY, tau=tau)


def transition_observables(v0: float, times, *, fit_tests: bool = False) -> list[Observable]:
    """The transition run's observables from ``v0``, in label order (time, then kind);
    with ``fit_tests``, the goodness-of-fit statistics instead."""
    return [Observable(k.name, TRANSITION, t=float(t), v0=float(v0))
            for t in times for k in KINDS if k.run == TRANSITION and k.fit_test == fit_tests]


def stationary_observables(taus=()) -> list[Observable]:
    """The stationary run's observables, in label order (windows last, by tau)."""
    plain = [Observable(k.name, STATIONARY) for k in KINDS if k.run == STATIONARY and not k.params]
    windows = [Observable(k.name, STATIONARY, tau=float(tau)) for tau in taus
               for k in KINDS if k.run == STATIONARY and k.params == ("tau",)]
    return plain + windows


# ------------------------------------------------------------------- values from the table
def transition_values(ens, v0: float, times) -> dict:
    """Every transition observable estimated on ``ens`` (velocities at each time):
    ``{label: value}``."""
    out = {}
    for t in times:
        v = ens.at(t)
        for o in transition_observables(v0, [t]):
            out[o.label] = o.entry.estimator(v)
    return out


def stationary_values(ens, *, burn_in: float, threshold: float, force: float, taus=()) -> dict:
    """Every stationary observable: time-and-replica averages after ``burn_in``."""
    i0 = int(np.searchsorted(ens.t, ens.t[0] + burn_in - 1e-12))
    sample = StationarySample(ens=ens, v=ens.v[:, i0:], burn_in=burn_in, threshold=threshold,
                              force=force)
    return {o.label: o.entry.estimator(sample, o.tau) for o in stationary_observables(taus)}


def transition_theory(v: np.ndarray, f: np.ndarray, v0: float, times, *,
                      weak_noise: bool = False) -> dict:
    """Exact (or, with ``weak_noise``, weak-noise) values of every transition observable
    from the densities ``f`` (rows: ``times``) on the grid ``v``."""
    out = {}
    for t, row in zip(times, f):
        m = density_moments(v, row)
        for o in transition_observables(v0, [t]):
            fn = o.entry.weak_noise if weak_noise else o.entry.exact
            if fn is not None:
                out[o.label] = fn(m)
    return out


def stationary_theory(model, moments, *, threshold: float, work_variance: dict) -> dict:
    """Exact values of every stationary observable (``work_variance``: {tau: Var(w)})."""
    th = StationaryTheory(model=model, moments=moments, threshold=threshold,
                          work_variance=work_variance)
    return {o.label: o.entry.exact(th, o.tau)
            for o in stationary_observables(list(work_variance))}


def planned_comparisons(v0s, times, taus, *, weak_noise: bool) -> list[tuple[str, str]]:
    """``(label, theory kind)`` of every comparison of one experiment, in the report's order:
    per v0 the transition observables (each exact, then weak-noise where the kind is compared
    with it and ``weak_noise``, i.e. Delta > 0), then the goodness-of-fit statistics; then the
    stationary observables."""
    out = []
    for v0 in v0s:
        for o in transition_observables(v0, times):
            out.append((o.label, "exact"))
            if weak_noise and o.entry.compare_weak_noise and o.entry.weak_noise is not None:
                out.append((o.label, "weak-noise"))
        out += [(o.label, "exact") for o in transition_observables(v0, times, fit_tests=True)]
    out += [(o.label, "exact") for o in stationary_observables(taus)]
    return out
