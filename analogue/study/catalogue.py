"""The catalogue of compared observables: one typed entry per kind, mapped to its estimator
(on circuit or Monte Carlo ensembles), its exact finite-noise theory and, where the paper has
one, its weak-noise theory.

Adding an observable is one :class:`Kind` in :data:`KINDS`: the report's estimates
(:func:`transition_values`, :func:`stationary_values`), its exact and weak-noise values
(:func:`transition_theory`, :func:`stationary_theory`) and its label all follow from it.
Each kind names the model classes it applies to (:func:`model_class`: the paper's model, a
one-dimensional family member with Gaussian noise, pure shot noise, the spring, a noise kind
without exact theory such as coloured noise), so the
chapter "Beyond the paper" (:mod:`analogue.report.beyond`) reads its observables
(:func:`member_observables`), their estimators, exact readings, Monte Carlo reference (the
spring, coloured noise) and circuit-element budget terms from the same table; adding a model class is one
class name on the kinds it shares.

Labels (the ``observable`` field of ``metrics.json``) are stable: ``"<kind> at t=<t> from
v0=<v0>"`` for the transition run, ``"<kind>"`` or ``"<kind> (tau=<tau>)"`` for the
stationary run (numbers formatted with ``:g``); ``tests/unit/test_study_catalogue.py``
holds them against the labels of a quick paper report.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from scipy import integrate

from ..ensemble import Ensemble
from ..estimators.smoothed_indicator import window
from ..estimators.variance_error import sample_variance_se
from ..model import Model
from ..theory.stationary import integrated_autocorrelation, stationary_moments
from ..estimators import transport
from ..estimators import work_rate_samples
from ..estimators.goodness_of_fit import histogram_chi2
from ..theory.stationary import stick_fraction_theory
from ..estimators.transport import diffusion_leave_group_out
from ..estimators.resampling import subset

__all__ = ["KINDS", "Kind", "Observable", "TRANSITION", "STATIONARY", "density_moments",
           "PAPER", "GAUSSIAN_MEMBER", "SHOT_MEMBER", "SPRING_MEMBER", "MONTE_CARLO_MEMBER", "member_stick_window",
           "LawMoments", "law_moments", "transition_laws", "StationarySample", "StationaryTheory", "first_swing",
           "model_class", "member_observables", "reference_of", "reference_is_monte_carlo", "stationary_sample",
           "transition_observables", "stationary_observables", "transition_values",
           "stationary_values", "StationaryValues", "transition_theory", "stationary_theory", "transition_label", "stationary_label",
           "kind_of", "find", "planned_comparisons", "estimate", "element_error", "no_exact",
           "transition_theory_se", "theory_se", "stationary_null_se", "stationary_mean_se",
           "stationary_exact_se", "record_span"]

TRANSITION = "transition"
STATIONARY = "stationary"

# model classes (:func:`model_class`): which kinds apply, and what the reference is
PAPER = "paper"                      # the paper's model: exact and weak-noise theory
GAUSSIAN_MEMBER = "gaussian member"  # 1-D family member with Gaussian noise (cubic, Stribeck)
SHOT_MEMBER = "shot member"          # 1-D, pure shot noise (gamma = inf): an atom at v = 0
SPRING_MEMBER = "spring member"      # state (x, v): the Monte Carlo is the reference
# 1-D, a noise kind with no exact solver (coloured noise, analogue.variants.coloured): the
# Monte Carlo of the same model is the reference
MONTE_CARLO_MEMBER = "monte carlo member"
_MEMBERS = frozenset({GAUSSIAN_MEMBER, SHOT_MEMBER})
_ALL_1D = frozenset({PAPER, GAUSSIAN_MEMBER, SHOT_MEMBER})
# the classes whose reference is the Monte Carlo (reference_of)
_MC_REFERENCE = frozenset({SPRING_MEMBER, MONTE_CARLO_MEMBER})

# the member's stick window holds the circuit's stuck state eps atanh(|a|/Delta(0)) with this
# margin (shot.toml: 4 x 0.0042 = 0.017, inside its 0.1 velocity-scale window 0.05)
STUCK_STATE_MARGIN = 4.0


def member_stick_window(model: Model, *, stick_threshold: float, epsilon: float = 0.0) -> float:
    """|v| below this counts as stuck on a family member (estimator and theory read the same
    window): ``stick_threshold`` (the experiment's ``[report] stick_threshold``, the paper
    experiments' threshold too) times the model's velocity scale
    (:attr:`analogue.Model.velocity_scale`, sqrt(tau_m/gamma) with the shot term in
    quadrature), widened where needed to hold the circuit's stuck state: the diode bridge of
    smoothing ``epsilon`` holds a stuck object at v = epsilon atanh(|a|/Delta(0)), never at 0
    (the theory counts the atom plus the continuous mass inside the window).

    Was the absolute 0.05 (issue 20): the same for a member whose velocities are 10x larger
    or smaller.  circuits/shot.toml keeps 0.05 (0.1 x 0.5); cubic.toml's window is 0.0316,
    stribeck.toml's 0.0447."""
    w = float(stick_threshold) * model.velocity_scale
    if not (w > 0 and math.isfinite(w)):
        raise ValueError(f"stick window {w!r}: stick_threshold ({stick_threshold!r}) times the "
                         f"velocity scale ({model.velocity_scale!r}) must be finite and > 0")
    d0 = model.static_friction
    if epsilon > 0 and abs(model.a) < d0:
        w = max(w, STUCK_STATE_MARGIN * epsilon * math.atanh(abs(model.a) / d0))
    return w


def model_class(model: Model) -> str:
    """The class of ``model`` that decides its observables and reference: ``PAPER``,
    ``SPRING_MEMBER`` (spring > 0), ``MONTE_CARLO_MEMBER`` (a noise kind without an exact
    solver: coloured noise), ``SHOT_MEMBER`` (shot noise without Gaussian noise) or
    ``GAUSSIAN_MEMBER`` (any other 1-D member)."""
    if not isinstance(model, Model):
        raise TypeError(f"model must be an analogue.Model, got {type(model).__name__}")
    if model.is_paper:
        return PAPER
    if model.dimension == 2:  # the spring's (x, v) (analogue.variants)
        return SPRING_MEMBER
    if model.noise_kind.exact_solver is None:
        return MONTE_CARLO_MEMBER
    if model.noise_kind.pure_kicks:
        return SHOT_MEMBER
    return GAUSSIAN_MEMBER


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
    computed once per window).  Spring members add the position of every replica over the
    whole path (``position``: the circuit's inductor read-back or the Monte Carlo's x0 + x),
    the nominal ``model`` and the friction law the data obey (``friction``: the circuit's
    tanh-smoothed law) for the stationary identities."""

    ens: Ensemble
    v: np.ndarray               # velocities after the burn-in (replicas x samples)
    burn_in: float
    threshold: float
    force: float
    position: np.ndarray | None = None
    model: Model | None = None
    friction: Model | None = None
    _work: dict = field(default_factory=dict, repr=False)

    def work(self, tau: float) -> np.ndarray:
        if tau not in self._work:
            self._work[tau] = _work_rates(self, tau)
        return self._work[tau]

    @property
    def x(self) -> np.ndarray:
        """Positions after the burn-in (spring members)."""
        if self.position is None:
            raise ValueError("this observable needs the position (a spring member's sample)")
        return self.position[:, self.ens.v.shape[1] - self.v.shape[1]:]


def stationary_sample(ens: Ensemble, *, burn_in: float, threshold: float, force: float,
                      position: np.ndarray | None = None, model: Model | None = None,
                      friction: Model | None = None) -> StationarySample:
    """The part of ``ens`` after ``burn_in`` (the first sample at t >= t0 + burn_in)."""
    i0 = int(np.searchsorted(ens.t, ens.t[0] + burn_in - 1e-12))
    return StationarySample(ens=ens, v=ens.v[:, i0:], burn_in=burn_in, threshold=threshold,
                            force=force, position=position, model=model, friction=friction)


def first_swing(t: np.ndarray, v: np.ndarray, x: np.ndarray,
                threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """Per replica: the time the first swing ends (v returns to 0 after leaving rest,
    |v| > ``threshold``: half a period of the damped oscillation) and |x| there (the first
    amplitude); the analysis passes the member's stick window
    (:func:`member_stick_window`; the absolute 0.05 never fired for a member 100x slower);
    NaN for a replica that never completes it.  The swing's direction is that of the first
    departure: backward when released from x0 > 0 at rest, forward from x0 < 0 (a release
    moving forward first had its second swing measured before)."""
    n = v.shape[0]
    t_half = np.full(n, np.nan)
    amp = np.full(n, np.nan)
    for r in range(n):
        moving = np.flatnonzero(np.abs(v[r]) > threshold)
        if moving.size == 0:
            continue
        j0 = moving[0]
        back = np.flatnonzero(np.sign(v[r, j0]) * v[r, j0:] <= 0.0)
        if back.size == 0:
            continue
        j = j0 + back[0]
        t_half[r], amp[r] = t[j], abs(x[r, j])
    return t_half, amp


def _half_period(s: StationarySample, tau=None) -> float:
    assert s.position is not None  # spring kinds: the sample carries the position
    return float(np.nanmean(first_swing(s.ens.t, s.ens.v, s.position, s.threshold)[0]))


def _amplitude(s: StationarySample, tau=None) -> float:
    assert s.position is not None
    return float(np.nanmean(first_swing(s.ens.t, s.ens.v, s.position, s.threshold)[1]))


def _kick_force(m: Model) -> float:
    """Mean acceleration of the kicks, rate <z> (0 without shot noise or with two-sided kicks)."""
    return m.noise_kind.mean_force


def _force_balance(s: StationarySample, tau=None) -> float:
    """spring <x> - a - rate <z> + <Delta(v) sgn v> + cubic <v^3>: the ensemble average of
    dv/dt, zero in the stationary state (<v> = 0 there, so the viscous term drops);
    <Delta(v) sgn v> with the friction law the data obey; rate <z> the kicks' mean force
    (one-sided shot noise; leaving it out gave a residual of 0.8 for rate 2, mean 0.4)."""
    m = s.model
    if m is None:
        raise ValueError("the force-balance identity needs the sample's model")
    law = s.friction if s.friction is not None else m
    return float(m.spring * s.x.mean() - m.a - _kick_force(m) + np.mean(law.coulomb(s.v))
                 + m.cubic * np.mean(s.v ** 3))


def _diffusion(s: StationarySample, tau=None) -> float:
    return float(transport(s.ens, burn_in=s.burn_in).diffusion)


def _work_rates(s: StationarySample, tau: float) -> np.ndarray:
    return work_rate_samples(s.ens, tau, s.force, burn_in=s.burn_in)


def _chi2_per_dof(samples, v, f) -> tuple[float, float]:
    chi2, dof = histogram_chi2(samples, v, f)
    return chi2 / dof, math.sqrt(2.0 / dof)


# ------------------------------------------------------------------------------- theory
def density_moments(v: np.ndarray, f: np.ndarray) -> tuple[float, float, float]:
    """Mean, variance and P(v <= 0) of a density ``f`` on the uniform grid ``v`` (trapezoid;
    the node at v = 0 counts half), normalised on the grid."""
    m = law_moments(v, f)
    return m.mean, m.variance, m.p_negative


class LawMoments(NamedTuple):
    """What the transition kinds read from a law f(v, t | v0) (+ an atom at v = 0)."""

    mean: float
    variance: float
    p_negative: float           # P(v < 0) (the atom excluded)
    p_stuck: float              # P(|v| < window), the atom included (law_moments)
    # central fourth moment: the standard error of a sample variance from n independent
    # draws, sqrt(mu4/n - sigma^4 (n - 3)/(n (n - 1)))
    fourth: float = math.nan


def law_moments(v: np.ndarray, f: np.ndarray, atom: float = 0.0, window: float = 0.0,
                point: tuple[float, float] | None = None) -> LawMoments:
    """Moments of the law ``f`` (continuous part, on the uniform grid ``v``; trapezoid) plus
    ``atom`` at v = 0 (shot noise: the object at rest) plus ``point = (v_p, mass)``, a delta
    at v_p (pure shot noise: the unkicked mass on the moving noise-free path,
    :func:`analogue.theory.family.unkicked`), normalised on the grid: total mass = integral
    of f + atom + mass.  Probabilities read the cumulative trapezoid integral, linearly
    interpolated at 0 and +-window (with v = 0 on a node, P(v < 0) is the trapezoid integral
    up to that node: the paper's convention, the node at 0 counting half).  ``window``: the
    stick window of ``p_stuck`` (:func:`member_stick_window`; 0: the atom alone)."""
    vp, mp = (0.0, 0.0) if point is None else (float(point[0]), float(point[1]))
    tot = integrate.trapezoid(f, v) + atom + mp
    f = f / tot
    a, mp = atom / tot, mp / tot
    mean = integrate.trapezoid(v * f, v) + mp * vp

    def central(k: int) -> float:
        return float(integrate.trapezoid((v - mean) ** k * f, v) + a * (-mean) ** k
                     + mp * (vp - mean) ** k)
    cdf = integrate.cumulative_trapezoid(f, v, initial=0.0)
    neg = np.interp(0.0, v, cdf) + (mp if vp < 0 else 0.0)
    stuck = a + np.interp(window, v, cdf) - np.interp(-window, v, cdf) + (
        mp if abs(vp) < window else 0.0)
    return LawMoments(float(mean), central(2), float(neg), float(stuck), central(4))


@dataclass(frozen=True, eq=False)
class StationaryTheory:
    """What the exact stationary values read.  ``law``: the grid's stationary law
    ``(v, density, atom)`` of a family member (:func:`analogue.theory.family.stationary_law`);
    window probabilities are then read from it (Riemann sum, plus the atom)."""

    model: Model
    moments: object             # analogue.theory.stationary.StationaryMoments
    threshold: float
    work_variance: dict         # tau -> exact Var(w)
    law: tuple | None = None


def _grid_mass(v: np.ndarray, dens: np.ndarray, lo: float, hi: float) -> float:
    """Mass of the grid density between lo and hi: the cumulative trapezoid, interpolated at
    the ends.  A Riemann sum over the nodes inside jumps with the grid (stribeck.toml's
    |v| < 0.05: 0.05191, 0.04941, 0.05058 at h, h/2, h/4; quadrature 0.05149) and misses the
    part of the window beyond the last cell when the window edge is not a cell edge (pure
    shot, slip regime: 0.0550 against the Monte Carlo 0.0574)."""
    c = integrate.cumulative_trapezoid(dens, v, initial=0.0)
    return float(np.interp(hi, v, c) - np.interp(lo, v, c))


def _window_mass(th: StationaryTheory) -> float:
    assert th.law is not None
    v, dens, atom = th.law
    return float(atom) + _grid_mass(v, dens, -th.threshold, th.threshold)


def _stick_theory(th: StationaryTheory, tau=None) -> float:
    if th.law is not None:
        return _window_mass(th)
    return float(stick_fraction_theory(th.model, th.threshold))


def _above_theory(th: StationaryTheory, tau=None) -> float:
    assert th.law is not None
    v, dens, _ = th.law
    return _grid_mass(v, dens, th.threshold, float(v[-1]))


def no_exact(*_args, **_kw) -> float:
    """The exact theory of a kind without one (the spring's state (x, v) has no exact
    stationary law here): the reference is the Monte Carlo (:func:`reference_of`)."""
    raise LookupError("this observable has no exact theory: its reference is the Monte Carlo")


# ----------------------------------------------------------------- circuit-element terms
# relative circuit-element errors of the family's circuits (analogue.circuit.mapping bias
# keys; each present only when its extension is on): a stationary observable of a 1-D member
# carries the cubic network's variance error and the shot pulses' width/edge/overlap terms
_ONE_D_TERMS = ("cubic_variance", "shot_pulse", "shot_edge", "shot_overlap")


def _relative(*keys: str) -> Callable:
    return lambda bias, model, ref: sum(bias.get(k, 0.0) for k in keys) * abs(ref)


def _leak_mean_x(bias, model, ref) -> float:
    # the leaky inductor's error of the spring's mean position (absolute; issue 18)
    return bias.get("spring_leak_mean_x", 0.0)


def _creep(bias, model, ref) -> float:
    # the leaky inductor lets a stuck object creep: a velocity bias (absolute)
    return bias.get("spring_creep", 0.0) * model.velocity_scale


def _creep_force(bias, model, ref) -> float:
    # the force balance of the leaky spring (the position its inductor reads back) misses the
    # viscous force of the creep, <v>/tau_m (absolute; issue 18)
    return _creep(bias, model, ref) / model.tau_m


# -------------------------------------------------------------------------------- kinds
@dataclass(frozen=True, eq=False)
class Kind:
    """One kind of observable.

    ``estimator``: transition kinds take the velocities at time t (one per replica);
    stationary kinds take a :class:`StationarySample` and the window ``tau`` (or None).
    ``exact``: transition kinds take the :class:`LawMoments` of the exact f(v, t | v0);
    stationary kinds a :class:`StationaryTheory` and ``tau``.  ``weak_noise``: the same
    reading of the paper's saddle-point propagator (eqs. (46)-(51)), compared in the report
    where ``compare_weak_noise``."""

    name: str
    run: str                    # TRANSITION or STATIONARY
    params: tuple               # ("t", "v0"), ("tau",) or ()
    estimator: Callable
    exact: Callable             # no_exact: the reference is the Monte Carlo (spring members)
    weak_noise: Callable | None = None
    compare_weak_noise: bool = False
    description: str = ""
    # a goodness-of-fit statistic: its estimator takes the samples and the exact density
    # (v grid, f), its "exact" value is its expectation under the theory
    fit_test: bool = False
    # a probability (estimated as a fraction of replicas: an estimate of 0 or 1 from n
    # replicas still has an error ~ 1/n)
    probability: bool = False
    # the model classes (model_class) the kind applies to, and a further condition
    classes: frozenset = frozenset({PAPER})
    applies: Callable[[Model], bool] | None = None
    # an identity: its value is exactly ``exact`` in the stationary state for every class
    # (the spring's references are otherwise the Monte Carlo)
    identity: bool = False
    # absolute circuit-element error: (mapping bias dict, model, reference value) -> float
    element: Callable | None = None
    # transition kinds: the standard error of the estimator on n independent draws from the
    # law (one velocity per replica), (LawMoments, n) -> float; the report's SE of the row is
    # the larger of it and the replica jackknife (transition_theory_se), because the jackknife
    # of a skewed or heavy-tailed sample that misses the tail is too small
    theory_se: Callable | None = None
    # indicator kinds, the fraction of samples with lo < v < hi: threshold -> (lo, hi).  Their
    # integration differences are taken on the smoothed indicator
    # (analogue.estimators.smoothed_indicator; ``smoothing`` of the value functions below)
    window: Callable[[float], tuple[float, float]] | None = None
    # a transition kind whose estimator also takes the stick window (estimator(v, threshold))
    thresholded: bool = False


# the stationary kind "moving forward" of shot members: v above the stick window (was
# "P(v>0.05)", the absolute window's value in the label)
ABOVE_WINDOW = "P(v>window)"

_ONE_D = _relative(*_ONE_D_TERMS)


def _mean_v_element(bias, model, ref) -> float:
    # the mean velocity of a spring member carries the inductor's creep (absolute), as the
    # identity <v> = 0 does: a reference near 0 makes the relative terms vanish (measured:
    # spring with one-sided kicks, circuit 0.0069 +- 0.0026 against the Monte Carlo's
    # -0.0016 with creep 0.0042 left out of its budget)
    return _ONE_D(bias, model, ref) + _creep(bias, model, ref)

KINDS: tuple[Kind, ...] = (
    # transition run: f(v, t | v0) (paper Fig. 6, eqs. (46)-(51)); in label order
    Kind("mean v", TRANSITION, ("t", "v0"), lambda v: float(np.mean(v)),
         exact=lambda m: m.mean, weak_noise=lambda m: m.mean, compare_weak_noise=True,
         theory_se=lambda m, n: math.sqrt(max(m.variance, 0.0) / n),
         description="mean velocity at t from v0; SE: the larger of the replica jackknife and "
                     "the exact law's sqrt(sigma^2/n)", classes=_ALL_1D | {MONTE_CARLO_MEMBER}),
    Kind("var v", TRANSITION, ("t", "v0"), lambda v: float(np.var(v, ddof=1)),
         exact=lambda m: m.variance, weak_noise=lambda m: m.variance,
         # (any law has mu4 >= sigma^4: the max only guards grid round-off)
         theory_se=lambda m, n: sample_variance_se(max(m.variance, 0.0),
                                                   max(m.fourth, m.variance ** 2), n),
         description="velocity variance at t from v0 (unbiased over replicas); SE: the larger "
                     "of the replica jackknife and the exact law's sqrt(Var s^2) = "
                     "sqrt(mu4/n - sigma^4 (n-3)/(n(n-1)))", classes=_ALL_1D | {MONTE_CARLO_MEMBER}),
    Kind("P(v<0)", TRANSITION, ("t", "v0"), lambda v: float(np.mean(v < 0)),
         exact=lambda m: m.p_negative, weak_noise=lambda m: m.p_negative, probability=True,
         description="probability of a negative velocity at t from v0",
         classes=frozenset({PAPER, GAUSSIAN_MEMBER, MONTE_CARLO_MEMBER}), window=lambda thr: (-math.inf, 0.0)),
    Kind("histogram chi2/dof", TRANSITION, ("t", "v0"), lambda v, grid, f: _chi2_per_dof(v, grid, f),
         exact=lambda m=None: 1.0, fit_test=True,
         description="Pearson chi^2 per degree of freedom of the circuit velocities at t "
                     "against the exact f(v, t | v0) at the circuit's epsilon, ~20 "
                     "equal-probability bins; (value, standard error sqrt(2/dof))"),
    Kind("P(v=0)", TRANSITION, ("t", "v0"),
         lambda v, threshold: float(np.mean(np.abs(v) < threshold)),
         exact=lambda m: m.p_stuck, probability=True, classes=frozenset({SHOT_MEMBER}),
         description="stuck at t from v0: |v| < the member's stick window "
                     "(study.catalogue.member_stick_window); theory: the atom plus the "
                     "continuous mass in the same window", thresholded=True,
         window=lambda thr: (-thr, thr)),
    # stationary run (eq. (6), eqs. (3), (52), Green-Kubo); in label order
    Kind("mean v", STATIONARY, (), lambda s, tau=None: float(s.v.mean()),
         exact=lambda th, tau=None: th.moments.mean, description="stationary mean velocity",
         classes=_ALL_1D | _MC_REFERENCE, element=_mean_v_element),
    Kind("var v", STATIONARY, (), lambda s, tau=None: float(s.v.var()),
         exact=lambda th, tau=None: th.moments.variance,
         description="stationary velocity variance", classes=_ALL_1D | _MC_REFERENCE,
         element=_relative(*_ONE_D_TERMS, "spring_leak_var_v")),
    Kind("P(v>0)", STATIONARY, (), lambda s, tau=None: float(np.mean(s.v > 0)),
         exact=lambda th, tau=None: th.moments.p_positive, probability=True,
         description="stationary probability of a positive velocity",
         classes=frozenset({PAPER, GAUSSIAN_MEMBER, MONTE_CARLO_MEMBER}), element=_ONE_D,
         window=lambda thr: (0.0, math.inf)),
    Kind("stick fraction", STATIONARY, (),
         lambda s, tau=None: float(np.mean(np.abs(s.v) < s.threshold)), exact=_stick_theory,
         probability=True,
         description="stationary P(|v| < threshold), threshold = report.stick_threshold "
                     "sqrt(tau_m/gamma) (family members: study.catalogue."
                     "member_stick_window)",
         classes=frozenset({PAPER, GAUSSIAN_MEMBER, MONTE_CARLO_MEMBER}), element=_ONE_D,
         window=lambda thr: (-thr, thr)),
    Kind("diffusion D_x", STATIONARY, (), _diffusion,
         exact=lambda th, tau=None: th.moments.diffusion,
         description="position diffusion coefficient (Green-Kubo); fixes the curvature of the "
                     "work rate function at <w>: I''(<w>) = 1/(2 gamma F^2 D_x)",
         classes=frozenset({PAPER, GAUSSIAN_MEMBER}), applies=lambda m: m.is_paper or m.a != 0,
         element=_ONE_D),
    Kind("mean w", STATIONARY, ("tau",), lambda s, tau: float(s.work(tau).mean()),
         exact=lambda th, tau: th.model.force * th.moments.mean,
         description="mean work rate over windows tau (eq. (3))"),
    Kind("var w", STATIONARY, ("tau",), lambda s, tau: float(s.work(tau).var()),
         exact=lambda th, tau: th.work_variance[tau],
         description="work-rate variance over windows tau (Green-Kubo route)"),
    # family members only (issue 9)
    Kind("P(v=0)", STATIONARY, (),
         lambda s, tau=None: float(np.mean(np.abs(s.v) < s.threshold)), exact=_stick_theory,
         probability=True, classes=frozenset({SHOT_MEMBER}), element=_ONE_D,
         description="stuck: |v| < the member's stick window (the bridge holds a stuck "
                     "object at epsilon atanh(a/Delta), not 0); theory: the atom P(v = 0) plus the "
                     "continuous mass in the window",
         window=lambda thr: (-thr, thr)),
    Kind(ABOVE_WINDOW, STATIONARY, (),
         lambda s, tau=None: float(np.mean(s.v >= s.threshold)), exact=_above_theory,
         probability=True, classes=frozenset({SHOT_MEMBER}), element=_ONE_D,
         description="moving forward: v above the member's stick window",
         window=lambda thr: (thr, math.inf)),
    Kind("mean x", STATIONARY, (), lambda s, tau=None: float(s.x.mean()), exact=no_exact,
         classes=frozenset({SPRING_MEMBER}), element=_leak_mean_x,
         description="stationary mean position"),
    Kind("var x", STATIONARY, (), lambda s, tau=None: float(s.x.var()), exact=no_exact,
         classes=frozenset({SPRING_MEMBER}), element=_relative("spring_leak_var_x"),
         description="stationary position variance"),
    Kind("half period (first swing)", STATIONARY, (), _half_period, exact=no_exact,
         classes=frozenset({SPRING_MEMBER}),
         description="time from release to the end of the first swing (v back to 0)"),
    Kind("amplitude (first swing)", STATIONARY, (), _amplitude, exact=no_exact,
         classes=frozenset({SPRING_MEMBER}), description="|x| where the first swing ends"),
    Kind("identity <v> = 0", STATIONARY, (), lambda s, tau=None: float(s.v.mean()),
         exact=lambda th=None, tau=None: 0.0, identity=True, classes=frozenset({SPRING_MEMBER}),
         element=_creep, description="stationary <v> = 0 (a bounded position)"),
    Kind("identity spring <x> - a + <Delta(v) sgn v> + cubic <v^3> = 0", STATIONARY, (),
         _force_balance, exact=lambda th=None, tau=None: 0.0, identity=True,
         classes=frozenset({SPRING_MEMBER}), element=_creep_force,
         applies=lambda m: _kick_force(m) == 0.0,
         description="the circuit's own friction law Delta(v) tanh(v/epsilon) in "
                     "<Delta(v) sgn v>; time averages after the burn-in (the identity holds "
                     "exactly in the stationary state)"),
    # one-sided kicks push with a mean force: the same identity with it (its own label, so
    # that the label says what is balanced)
    Kind("identity spring <x> - a - rate <z> + <Delta(v) sgn v> + cubic <v^3> = 0", STATIONARY,
         (), _force_balance, exact=lambda th=None, tau=None: 0.0, identity=True,
         classes=frozenset({SPRING_MEMBER}), element=_creep_force,
         applies=lambda m: _kick_force(m) != 0.0,
         description="rate <z>: the mean force of the one-sided kicks; the circuit's own "
                     "friction law Delta(v) tanh(v/epsilon) in <Delta(v) sgn v>; time "
                     "averages after the burn-in"),
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
            for t in times for k in KINDS
            if k.run == TRANSITION and k.fit_test == fit_tests and PAPER in k.classes]


def stationary_observables(taus=()) -> list[Observable]:
    """The stationary run's observables, in label order (windows last, by tau)."""
    paper = [k for k in KINDS if k.run == STATIONARY and PAPER in k.classes]
    plain = [Observable(k.name, STATIONARY) for k in paper if not k.params]
    windows = [Observable(k.name, STATIONARY, tau=float(tau)) for tau in taus
               for k in paper if k.params == ("tau",)]
    return plain + windows


def member_observables(model: Model, *, v0: float | None = None, times=()) -> list[Observable]:
    """A family member's observables, in label order: the stationary ones (those of its
    class, :func:`model_class`), then, with ``v0``, the transition ones at each time (spring
    members have none: their run is a release from x0, read by stationary kinds)."""
    cls = model_class(model)
    if cls == PAPER:
        raise ValueError("model is the paper's model: its observables are "
                         "transition_observables and stationary_observables")
    out = [Observable(k.name, STATIONARY) for k in KINDS
           if k.run == STATIONARY and cls in k.classes and not k.params
           and (k.applies is None or k.applies(model))]
    if v0 is not None and cls != SPRING_MEMBER:
        out += [Observable(k.name, TRANSITION, t=float(t), v0=float(v0)) for t in times
                for k in KINDS if k.run == TRANSITION and cls in k.classes and not k.fit_test]
    return out


def reference_is_monte_carlo(model: Model) -> bool:
    """Whether ``model``'s rows are held against the Monte Carlo (the spring; a noise kind
    without exact theory, coloured noise), not exact numerics."""
    return model_class(model) in _MC_REFERENCE


def reference_of(o: Observable, model: Model) -> str:
    """``"exact"`` (finite-noise numerics, or an identity's exact value) or ``"monte carlo"``
    (spring members: no exact law of the state (x, v); coloured noise: no exact theory yet)."""
    k = o.entry
    if k.identity or (not reference_is_monte_carlo(model) and k.exact is not no_exact):
        return "exact"
    return "monte carlo"


def estimate(o: Observable, ens: Ensemble, *, burn_in: float, threshold: float, force: float,
             position: np.ndarray | None = None, model: Model | None = None,
             friction: Model | None = None) -> float:
    """The kind's estimator of ``o`` on one ensemble (transition: the velocities at o.t;
    stationary: the part after ``burn_in``; see :func:`stationary_sample`)."""
    k = o.entry
    if o.run == TRANSITION:
        assert o.t is not None  # transition observables carry their time
        v = ens.at(o.t)
        return float(k.estimator(v, threshold) if k.thresholded else k.estimator(v))
    s = stationary_sample(ens, burn_in=burn_in, threshold=threshold, force=force,
                          position=position, model=model, friction=friction)
    return float(k.estimator(s, o.tau))


def element_error(o: Observable, bias: dict, model: Model, reference: float) -> float:
    """The kind's circuit-element error (absolute) for a circuit with mapping ``bias``."""
    k = o.entry
    return 0.0 if k.element is None else float(k.element(bias, model, reference))


# ------------------------------------------------------------------- values from the table
def transition_values(ens, v0: float, times, *, smoothing: float = 0.0) -> dict:
    """Every transition observable estimated on ``ens`` (velocities at each time):
    ``{label: value}``.  ``smoothing`` > 0: indicator kinds as the mean of their smoothed
    indicator of that width (the integration difference,
    :mod:`analogue.estimators.smoothed_indicator`)."""
    out = {}
    for t in times:
        v = ens.at(t)
        for o in transition_observables(v0, [t]):
            w = o.entry.window
            out[o.label] = (float(window(v, *w(0.0), smoothing).mean())
                            if smoothing > 0 and w is not None else o.entry.estimator(v))
    return out


def stationary_values(ens, *, burn_in: float, threshold: float, force: float, taus=(),
                      smoothing: float = 0.0) -> dict:
    """Every stationary observable: time-and-replica averages after ``burn_in``
    (``smoothing``: as in :func:`transition_values`)."""
    sample = stationary_sample(ens, burn_in=burn_in, threshold=threshold, force=force)
    out = {}
    for o in stationary_observables(taus):
        w = o.entry.window
        out[o.label] = (float(window(sample.v, *w(threshold), smoothing).mean())
                        if smoothing > 0 and w is not None else o.entry.estimator(sample, o.tau))
    return out


def _mean_var_left_out(a: np.ndarray, labels: np.ndarray, groups: int
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Mean and (population) variance of the rows of ``a`` (replicas x samples) with the
    rows of group j left out, for each j: from per-row means and centred sums of squares
    (the pooled-variance formula M2 = sum_r M2_r + m sum_r (mu_r - mu)^2, m samples a row:
    no cancellation, unlike sum a^2 - n mu^2)."""
    m = a.shape[1]
    mu = a.mean(axis=1)
    m2 = ((a - mu[:, None]) ** 2).sum(axis=1)
    means, variances = np.empty(groups), np.empty(groups)
    for j in range(groups):
        keep = labels != j
        mk = mu[keep]
        means[j] = mk.mean()
        variances[j] = (m2[keep].sum() + m * ((mk - means[j]) ** 2).sum()) / (m * mk.size)
    return means, variances


def _fraction_left_out(ind: np.ndarray, labels: np.ndarray, groups: int) -> np.ndarray:
    """Fraction of true entries of ``ind`` (replicas x samples) with group j left out
    (exact: integer counts over the same number of samples as np.mean)."""
    c = np.count_nonzero(ind, axis=1)
    return np.array([c[labels != j].sum() / (ind.shape[1] * np.count_nonzero(labels != j))
                     for j in range(groups)])


@dataclass(frozen=True)
class StationaryValues:
    """:func:`stationary_values` as an observable set for the replica jackknife
    (:class:`analogue.estimators.resampling.GroupObservables`): calling it gives the values
    of an ensemble; :meth:`leave_group_out` those of every delete-a-group subset from
    per-replica pieces computed once (sums, centred sums of squares, indicator counts, the
    work rates of each window, the position deviations of D_x), instead of one copy and
    one pass per group (the report's comparisons: 101 calls per experiment, most of their
    CPU; the values agree with the direct route to rounding, tested to 1e-12)."""

    burn_in: float
    threshold: float
    force: float
    taus: tuple[float, ...] = ()
    # > 0: indicator kinds smoothed (the integration difference; stationary_values)
    smoothing: float = 0.0

    def __call__(self, ens: Ensemble) -> dict:
        return stationary_values(ens, burn_in=self.burn_in, threshold=self.threshold,
                                 force=self.force, taus=self.taus, smoothing=self.smoothing)

    def leave_group_out(self, ens: Ensemble, labels: np.ndarray, groups: int) -> list[dict]:
        s = stationary_sample(ens, burn_in=self.burn_in, threshold=self.threshold,
                              force=self.force)
        cols: dict[str, np.ndarray] = {}
        mean_v, var_v = _mean_var_left_out(s.v, labels, groups)
        for o in stationary_observables(self.taus):
            name = o.kind
            w = o.entry.window
            if self.smoothing > 0 and w is not None:
                cols[o.label] = _mean_var_left_out(
                    window(s.v, *w(self.threshold), self.smoothing), labels, groups)[0]
            elif name in ("mean v", "identity <v> = 0"):
                cols[o.label] = mean_v
            elif name == "var v":
                cols[o.label] = var_v
            elif name == "P(v>0)":
                cols[o.label] = _fraction_left_out(s.v > 0, labels, groups)
            elif name in ("stick fraction", "P(v=0)"):
                cols[o.label] = _fraction_left_out(np.abs(s.v) < s.threshold, labels, groups)
            elif name == ABOVE_WINDOW:
                cols[o.label] = _fraction_left_out(s.v >= s.threshold, labels, groups)
            elif name == "diffusion D_x":
                cols[o.label] = diffusion_leave_group_out(ens, labels, groups,
                                                          burn_in=self.burn_in)
            elif name in ("mean w", "var w"):
                assert o.tau is not None  # window kinds carry their tau
                mw, vw = _mean_var_left_out(s.work(o.tau), labels, groups)
                cols[o.label] = mw if name == "mean w" else vw
            else:   # a kind without a per-replica form: the direct route
                return [self(subset(ens, labels != j)) for j in range(groups)]
        return [{k: float(c[j]) for k, c in cols.items()} for j in range(groups)]


def transition_laws(v: np.ndarray, f: np.ndarray, *, atom=None, point=None,
                    window: float = 0.0) -> list[LawMoments]:
    """:func:`law_moments` of each row of ``f`` (one per time), with ``atom[i]`` at v = 0,
    ``point = (v_p[i], mass[i])`` and the stick ``window`` (see :func:`law_moments`)."""
    return [law_moments(v, row, 0.0 if atom is None else float(atom[i]), window=window,
                        point=None if point is None else (point[0][i], point[1][i]))
            for i, row in enumerate(f)]


def transition_theory(v: np.ndarray, f: np.ndarray, v0: float, times, *,
                      weak_noise: bool = False, atom=None, observables=None,
                      point=None, window: float = 0.0) -> dict:
    """Exact (or, with ``weak_noise``, weak-noise) values of every transition observable
    from the densities ``f`` (rows: ``times``) on the grid ``v``, plus ``atom[i]`` at v = 0
    (shot noise) and the delta ``point`` (:func:`transition_laws`).  ``observables``: the
    transition observables to read (default: the paper's, :func:`transition_observables`)."""
    out = {}
    laws = transition_laws(v, f, atom=atom, point=point, window=window)
    for t, m in zip(times, laws):
        obs = (transition_observables(v0, [t]) if observables is None else
               [o for o in observables if o.run == TRANSITION and o.t == float(t)])
        for o in obs:
            fn = o.entry.weak_noise if weak_noise else o.entry.exact
            if fn is not None:
                out[o.label] = fn(m)
    return out


def transition_theory_se(v: np.ndarray, f: np.ndarray, v0: float, times, n: int, *,
                         atom=None, point=None, observables=None) -> dict:
    """``{label: theory-side SE}`` of the transition kinds that have one (``theory_se``), for
    estimates over ``n`` replicas drawn from the laws ``f`` (rows: ``times``; ``atom`` and
    ``point`` as in :func:`transition_laws`) on the grid ``v``."""
    out = {}
    for t, m in zip(times, transition_laws(v, f, atom=atom, point=point)):
        obs = (transition_observables(v0, [t]) if observables is None else
               [o for o in observables if o.run == TRANSITION and o.t == float(t)])
        for o in obs:
            if o.entry.theory_se is not None:
                out[o.label] = float(o.entry.theory_se(m, n))
    return out


def theory_se(o: Observable, law: LawMoments, n: int) -> float:
    """The kind's theory-side SE of ``o`` on ``n`` draws from ``law`` (0 if it has none)."""
    k = o.entry
    return 0.0 if k.theory_se is None else float(k.theory_se(law, n))


def stationary_null_se(entry: Kind, value: float, se: float, reference: float) -> float:
    """The standard error of a stationary (time-and-replica averaged) estimate under the null
    hypothesis that its value is ``reference``: the replica jackknife ``se``, measured at the
    estimate ``value``, rescaled to the reference, and never below ``se``.

    The jackknife of a time average is evaluated at the sample it is given, so a sample that
    happens to show fewer rare excursions (a probability near 0 or 1) or a narrower spread
    (a variance) also reports a smaller error, and the z-score of exactly those samples is
    inflated (measured: the quick cubic member, P(v>0) 0.99926 +- 0.00025 against 0.99819,
    z = 4.3, with P(v<0) at 0.4 of its reference).  Under the null the error scales like the
    variance of the averaged quantity: p (1 - p) for an indicator (the integrated
    autocovariance of a time-averaged indicator is p (1 - p) times a correlation time; for
    rare excursions their number is Poisson, variance ~ p), and sigma^4 for the variance of
    a Gaussian-like velocity (2 sigma^4 times a correlation time), so

        se_null = se sqrt(p0 (1 - p0) / (p (1 - p)))   (probability kinds)
        se_null = se sigma0^2 / sigma^2                (stationary var v)

    with the correlation time taken from the sample (an approximation: it assumes the
    correlation time itself is not what differs).  Other kinds: ``se``.  An estimate of
    exactly 0 or 1 is handled by the binomial floor of the report instead."""
    se = float(se)
    if entry.run != STATIONARY or not (np.isfinite(value) and np.isfinite(reference)):
        return se
    if entry.probability:
        num, den = reference * (1.0 - reference), value * (1.0 - value)
        if den <= 0.0 or num <= 0.0:
            return se
        return max(se, se * math.sqrt(num / den))
    if entry.name == "var v" and value > 0.0 and reference > 0.0:
        return max(se, se * reference / value)
    return se


def record_span(ens: Ensemble, burn_in: float) -> float:
    """The length of the record a stationary time average reads: from the first sample at
    ``t >= t0 + burn_in`` (:func:`stationary_sample`) to the last."""
    i0 = int(np.searchsorted(ens.t, ens.t[0] + burn_in - 1e-12))
    return float(ens.t[-1] - ens.t[min(i0, ens.t.size - 1)])


# the stationary kinds whose null spread has an exact route: f(v) of the time average
# (threshold: the stick window; mean: the law's exact mean)
def _averaged(name: str, threshold: float, mean: float):
    if name == "mean v":
        return lambda v: v
    if name == "var v":
        return lambda v: (v - mean) ** 2
    if name == "P(v>0)":
        return lambda v: (v > 0.0) + 0.5 * (v == 0.0)
    if name == "stick fraction":
        return lambda v: (np.abs(v) < threshold).astype(float)
    return None


def stationary_exact_se(model: Model, name: str, span: float, n: int, *,
                        threshold: float = 0.0) -> float:
    """The exact standard error, under the null that the replicas follow ``model``, of the
    stationary kind ``name`` estimated from ``n`` independent replicas started in p_s and
    each averaged over a record of length ``span``: with f the averaged function of v (v for
    the mean, (v - <v>)^2 for the variance to first order, the indicators of v > 0 and of
    |v| < ``threshold`` for P(v>0) and the stick fraction),

        se = sqrt(Var(int_0^T f(v(s)) ds) / n) / T,   Var = 2 int_0^T (T - s) C_f(s) ds

    (:func:`analogue.theory.stationary.integrated_autocorrelation`, exact at finite T; for T
    long against the correlation time, sqrt(2 D_f / (n T)), D_x for the mean).  The sample
    average of the report differs from the continuous one by O(sample_dt / T).  0 where no
    such route exists (other kinds, family members): the caller keeps its jackknife.

    Why (issue 18): the replica jackknife of the quick report's stationary run (32 replicas,
    16 groups of 2) has a relative spread of about 1/sqrt(2 x 15) = 18 %, and a sample with
    fewer far excursions reports a smaller error: a quick 1N4148 report at tau_m = 2, Delta =
    0.5, a = 0.3, gamma = 15 gave mean v 0.1028 +- 0.0032 (z = -4.6) where this spread is
    0.0051 (the 32 replicas' own means scatter as 0.0050; 5 seeds: z -2.9, +0.8, +0.1, -0.4,
    +1.3 on this SE)."""
    if not model.is_paper or span <= 0.0 or n < 1:
        return 0.0
    mean = stationary_moments(model).mean if name == "var v" else 0.0
    f = _averaged(name, threshold, mean)
    if f is None:
        return 0.0
    var = float(integrated_autocorrelation(model, [float(span)], observable=f)[0])
    return math.sqrt(max(var, 0.0) / n) / span


def stationary_mean_se(model: Model, span: float, n: int) -> float:
    """:func:`stationary_exact_se` of the stationary mean v."""
    return stationary_exact_se(model, "mean v", span, n)


def stationary_theory(model, moments, *, threshold: float, work_variance: dict,
                      law: tuple | None = None, observables=None) -> dict:
    """Exact values of every stationary observable (``work_variance``: {tau: Var(w)};
    ``law``: a family member's grid law, see :class:`StationaryTheory`; ``observables``:
    default the paper's, :func:`stationary_observables`)."""
    th = StationaryTheory(model=model, moments=moments, threshold=threshold,
                          work_variance=work_variance, law=law)
    obs = stationary_observables(list(work_variance)) if observables is None else [
        o for o in observables if o.run == STATIONARY]
    return {o.label: o.entry.exact(th, o.tau) for o in obs if o.entry.exact is not no_exact}


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
