"""What experiments measure (issue 23, items 1-3 and 5): the observables a tribometer or a
granular probe records, for a paper-model experiment's circuit runs, against the exact theory,
each with the terms of its error budget.

* **Velocity power spectrum** (Gnoli, Puglisi & Touchette, EPL 2013, against Touchette,
  Prellberg & Just, J. Phys. A 45, 395002 (2012)): the Welch estimate of the stationary runs
  (:func:`analogue.estimators.spectrum.velocity_spectrum`, segments of :data:`NPERSEG`
  samples) averaged over frequency bands (:data:`BANDS`, in units of ``1/tau_m``), against
  the band average of the exact ``S(omega)`` (:func:`analogue.theory.spectrum.
  velocity_spectrum`) of the ideal model.  Budget:

  - *sampling*: the exact expectation of the estimator (aliasing of the sampled record and
    the window's leakage, :func:`~analogue.estimators.spectrum.welch_expectation` of the
    exact autocorrelation) minus S, band-averaged: signed and exact;
  - *bandwidth*: the noise hold.  Its linear part is ``sinc^2(omega T/2)``
    (:func:`~analogue.theory.spectrum.noise_hold_factor`), but in the stick regime the hold
    also lowers the variance itself (measured: 1 % below ``sinc^2`` at T = tau_m/100 on the
    stick model), so the term is *measured*: a held/white Monte Carlo pair on common Wiener
    increments (the report's recipe for every other observable), at the stationary runs'
    own hold, on the circuit's effective model; ``|held - white| + 2 SE``;
  - *smoothing*: the relative change of S from the bridge's tanh width (exact S at
    epsilon against epsilon = 0 at the band's geometric centre; measured < 1e-3 relative on
    the paper's experiments), times the band's expectation;
  - *integration*: the circuit's tight-tolerance re-run of the first stationary decks
    against the same rows and times of the nominal run (paired).

  The statistical error is the larger of the replica jackknife and the spread of one
  replica's band average in the held run of that pair (the circuit's law) over
  ``sqrt(replicas)``.  The low-frequency power of the stick regime is intermittent (a
  replica's band average at omega ~ 1 scatters by 40-60 %, far beyond the chi-square law of
  a Gaussian process): a quick run of 32 replicas that misses the upper tail has a small
  jackknife error too (measured on the circuit: band [0.5, 1.5) at 0.81 of the exact value,
  z = -3.6 on the jackknife alone, -1.9 with this floor; at another seed 1.04).

* **First passage to rest** (Chen & Just, Phys. Rev. E 89, 022103 (2014)): the time for a
  path started at ``v0`` to first reach ``v = 0``, by first sign change per replica
  (:mod:`analogue.estimators.first_passage`) of the transition runs, against the exact
  absorbing Fokker-Planck law (:mod:`analogue.theory.first_passage`).  Rows per ``v0``: the
  mean (where the record outlasts every path: exact survival at the record's end below
  :data:`CENSORED_LIMIT`) and ``P(T <= t)`` at the deterministic stick time ``t_a``
  (eq. (31); at the record's end where the noise-free path never stops).  Budget:

  - *sampling*: the first crossing observed every ``dt`` comes late by at most
    :func:`~analogue.estimators.first_passage.sampling_bias_bound` (``beta sigma sqrt(dt)
    T'(0+) + dt``) on average; for ``P(T <= t)`` that delay times the exact density ``f(t)``
    (first order).  Where the drift pushes away from rest on both sides (slip from v0 = 2:
    ``T'(0+) = 26``, bound 0.69) the mean delay is made of rare long excursions and the term
    overstates the change of ``P`` (0.043 there, 1.4 standard errors at quick size): a
    conservative allowance, not a correction;
  - *bandwidth*: held/white Monte Carlo pair from ``v0`` on the effective model, both
    observed at the circuit's sampling interval (what the hold changes in what the estimator
    sees: with tanh friction and held noise a path that comes to rest sits at a small
    velocity of its own sign until a hold's force turns it);
  - *smoothing*: exact at the circuit's epsilon minus exact at 0;
  - *integration*: the first ``v0``'s tight-tolerance re-run (paired), as the report's rows.

* **Transport under a bias** (Goohpattader, Mettu & Chaudhury, Langmuir 25, 9969 (2009);
  Goohpattader & Chaudhury, J. Chem. Phys. 133, 024702 (2010)): the drift ``<v>`` and ``D_x``
  of the stationary runs are rows of every report already (``mean v``, ``diffusion D_x``);
  the chapter sets them beside the exact mobility ``mu = d<v>/da = gamma Var v`` (exact for
  every 1-D gradient model, :func:`analogue.theory.bias_transport.mobility`) and the
  Einstein-like ratio ``D_x / mu`` (:func:`~analogue.theory.bias_transport.einstein_ratio`).
  A circuit row for that ratio was tried and left out: on Monte Carlo runs of the quick
  size (32 replicas x 48 tau_m) its replica jackknife understated the spread (z rms 1.5
  over 6 seeds), D_x's fit being the noisy part; the curves over ``a`` and over the noise
  strength are the sweep's (:mod:`analogue.study.sweep`).

Everything here is numbers (:class:`Row`, :class:`MeasureTheory`, :class:`MeasureAnalysis`,
whose ``comparisons`` are the rows with their budgets, in :attr:`analogue.study.run.
StudyResult.measured`); the report writes the chapter (:mod:`analogue.report.measure_chapter`)
and the plots draw the curves (:mod:`analogue.plots.measure`).  :func:`measure_theory` needs
no circuit data (the report runs it while ngspice runs); :func:`analyse_measure` reads the
report's own runs (stationary and transition), so the chapter adds no ngspice time.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..ensemble import Ensemble
from ..estimators import first_passage as efp
from ..estimators import spectrum as esp
from ..estimators.resampling import jackknife, jackknife_difference
from ..model import Model
from ..theory import exact
from ..theory import first_passage as tfp
from ..theory import spectrum as tsp
from ..theory.bias_transport import einstein_ratio, mobility
from .budget import SE_MULTIPLIER, held_noise_pair
from .metrics import Budget, Comparison, compare
from .seeds import SeedPlan
from .settings import ReportSettings, stationary_noise_dt

__all__ = ["NPERSEG", "BANDS", "CENSORED_LIMIT", "PAIR_REPLICAS", "STATIONARY_PAIR_REPLICAS",
           "Row", "SpectrumTheory", "FirstPassageTheory", "MeasureTheory", "MeasureAnalysis",
           "SpectrumBands", "FirstPassageValues", "measure_theory", "analyse_measure",
           "band_label", "applies"]

#: Welch segment length (samples).  At the paper's ``sample_dt = 0.01`` the resolution is
#: 0.61/tau_m, and the quick stationary run (32 replicas x 48 after the burn-in) gives 8
#: segments per replica (nu ~ 490 interior degrees of freedom).
NPERSEG = 1024
#: Band edges in units of ``1/tau_m``: around and above the two crossovers (1/tau_m and the
#: sticking rate, 1.3/tau_m on the stick experiment) up to where S has fallen ~1e3-fold.
BANDS = (0.5, 1.5, 4.0, 10.0, 30.0, 100.0)
#: A mean first-passage row needs the exact survival at the record's end below this (the
#: few censored paths are then counted at the record's end: a bias below this times the
#: record, far below the errors).
CENSORED_LIMIT = 1e-4
#: Held/white Monte Carlo pairs.  Their loop costs per step more than per replica (the
#: report's 256-replica stationary pair takes 2.3 s), so the stationary pair has as many as
#: the report's (:data:`analogue.study.comparisons.MC_STATIONARY_REPLICAS`); the
#: first-passage pairs 1024, paired differences with SE ~0.002 on a mean of ~1.5.
PAIR_REPLICAS = 1024
STATIONARY_PAIR_REPLICAS = 256


def applies(model: Model) -> bool:
    """Whether this chapter's theory covers the model: the paper's 1-D model (finite gamma,
    no spring, no kicks), whose spectra and first passage the exact numerics give."""
    return bool(model.is_paper and math.isfinite(model.gamma))


# ------------------------------------------------------------------------------ rows
@dataclass(frozen=True)
class Row:
    """One comparison, as numbers: the circuit estimate and its statistical error, the exact
    value of the ideal model, and the budget's terms (absolute; signed where the sign is
    known), each with what it is in ``note``.  ``bandwidth`` and ``integration`` are measured
    differences ``(d, se)``; the report books ``|d| + SE_MULTIPLIER se``."""

    label: str
    circuit: float
    stderr: float
    theory: float
    smoothing: float = 0.0
    sampling: float = 0.0
    bandwidth: tuple = (0.0, 0.0)
    integration: tuple = (0.0, 0.0)
    note: str = ""
    group: str = ""            # "spectrum" or "first passage"


def band_label(lo: float, hi: float) -> str:
    return f"S(omega) band [{lo:.3g}, {hi:.3g})"


def _bands(tau_m: float, omega: np.ndarray) -> list[tuple[float, float, np.ndarray]]:
    out = []
    for lo, hi in zip(BANDS[:-1], BANDS[1:]):
        lo, hi = lo / tau_m, hi / tau_m
        sel = (omega >= lo) & (omega < hi)
        if sel.any():
            out.append((lo, hi, sel))
    return out


@dataclass(frozen=True)
class SpectrumBands:
    """The band averages of an ensemble's Welch estimate, ``{label: value}``: the value
    function of the jackknives."""

    burn_in: float
    tau_m: float
    nperseg: int = NPERSEG

    def __call__(self, ens: Ensemble) -> dict:
        est = esp.velocity_spectrum(ens, burn_in=self.burn_in, nperseg=self.nperseg)
        return {band_label(lo, hi): float(est.value[sel].mean())
                for lo, hi, sel in _bands(self.tau_m, est.omega)}


def _fp_labels(v0: float, t_a: float, record: float, with_mean: bool) -> tuple[str | None, str, float]:
    t = t_a if math.isfinite(t_a) and t_a < record else record
    mean = f"first passage mean from v0={v0:g}" if with_mean else None
    return mean, f"P(T<={t:.3g}) from v0={v0:g}", t


@dataclass(frozen=True)
class FirstPassageValues:
    """First-passage observables of a transition ensemble from ``v0``: the mean (censored
    paths counted at the record's end) and ``P(T <= t_prob)``."""

    mean_label: str | None
    prob_label: str
    t_prob: float

    def __call__(self, ens: Ensemble) -> dict:
        t = efp.first_passage_times(ens)
        end = float(ens.t[-1] - ens.t[0])
        out = {self.prob_label: float(np.mean(np.nan_to_num(t, nan=np.inf) <= self.t_prob))}
        if self.mean_label is not None:
            out[self.mean_label] = float(np.mean(np.nan_to_num(t, nan=end)))
        return out


# ---------------------------------------------------------------------------- theory
@dataclass(frozen=True, eq=False)
class SpectrumTheory:
    """Exact spectrum pieces at the Welch frequencies ``omega`` of the stationary runs:
    ``exact`` (S of the ideal model), ``expected`` (E of the Welch estimate, ideal model:
    aliasing and leakage), ``smoothing`` ``{band label: relative change of S at the circuit's
    epsilon}``, the hold's Monte Carlo differences ``hold`` ``{label: (d, se)}`` (bands and
    dense curves for the figure, and the crossovers."""

    omega: np.ndarray
    exact: np.ndarray
    expected: np.ndarray
    smoothing: dict
    hold: dict
    curve_omega: np.ndarray
    curve: np.ndarray
    replica_sd: dict          # band label -> spread of one replica's band average (held run)
    crossovers: tuple
    sample_dt: float
    hold_dt: float
    mobility: float           # d<v>/da = gamma Var v, exact (for the chapter's text)
    einstein: float           # D_x / mobility, exact


@dataclass(frozen=True, eq=False)
class FirstPassageTheory:
    """Exact first passage from ``v0`` (ideal model and at the circuit's epsilon), the rows'
    labels and exact values, the density on ``t`` for the figure, and the hold's Monte Carlo
    differences ``{label: (d, se)}``."""

    v0: float
    t_a: float
    mean: float
    variance: float
    record: float
    survival_end: float
    values: FirstPassageValues
    exact: dict
    exact_eff: dict
    density_at: dict          # label -> exact density at the row's time (P rows)
    t: np.ndarray
    density: np.ndarray
    hold: dict
    sampling_bound: float


@dataclass(frozen=True, eq=False)
class MeasureTheory:
    experiment: str
    model: Model
    model_effective: Model
    burn_in: float
    spectrum: SpectrumTheory
    first_passage: dict       # v0 -> FirstPassageTheory
    wall_time_s: float = 0.0


def _spectrum_theory(exp, settings: ReportSettings, model_eff: Model, noise_dt: float,
                     plan: SeedPlan, tick) -> SpectrumTheory:
    model = exp.model
    dt = float(exp.sample_dt)
    omega = esp.welch_frequencies(NPERSEG, dt)
    tick(f"{exp.name}: exact velocity spectrum")
    c = exact.autocorrelation(model, np.arange(NPERSEG) * dt)
    expected = esp.welch_expectation(c, dt)
    s = tsp.velocity_spectrum(model, omega)
    bands = _bands(model.tau_m, omega)
    centres = np.array([math.sqrt(lo * hi) for lo, hi, _ in bands])
    rel = tsp.velocity_spectrum(model_eff, centres) / tsp.velocity_spectrum(model, centres) - 1.0
    smoothing = {band_label(lo, hi): float(r) for (lo, hi, _), r in zip(bands, rel)}
    hold_dt = stationary_noise_dt(noise_dt, settings)
    tick(f"{exp.name}: held/white Monte Carlo pair for the spectrum")
    v0 = exact.sample_stationary(model_eff, STATIONARY_PAIR_REPLICAS,
                                 plan.stream("measure_spectrum_pair_v0"))
    held, white = held_noise_pair(model_eff, v0=v0, t_end=settings.stationary_t_end,
                                  replicas=STATIONARY_PAIR_REPLICAS,
                                  seed=plan.stream("measure_spectrum_pair"), noise_dt=hold_dt,
                                  sample_dt=dt)
    fn = SpectrumBands(settings.stationary_burn_in, model.tau_m)
    hold = jackknife_difference(fn, held, white)
    per = esp.velocity_spectrum(held, burn_in=settings.stationary_burn_in,
                                nperseg=NPERSEG).per_replica
    replica_sd = {band_label(lo, hi): float(per[:, sel].mean(axis=1).std(ddof=1))
                  for lo, hi, sel in bands}
    w_curve = np.geomspace(0.05 / model.tau_m, math.pi / dt, 240)
    curve = tsp.velocity_spectrum(model, w_curve)
    return SpectrumTheory(omega=omega, exact=s, expected=expected, smoothing=smoothing,
                          hold=hold, curve_omega=w_curve, curve=curve,
                          replica_sd=replica_sd,
                          crossovers=tsp.crossover_frequencies(model), sample_dt=dt,
                          hold_dt=hold_dt, mobility=mobility(model),
                          einstein=einstein_ratio(model))


def _first_passage_theory(exp, i: int, v0: float, model_eff: Model, noise_dt: float,
                          plan: SeedPlan, tick) -> FirstPassageTheory:
    model = exp.model
    record = float(exp.t_end)
    dt = float(exp.sample_dt)
    tick(f"{exp.name}: exact first passage from v0={v0:g}")
    mean, var = tfp.first_passage_moments(model, v0)
    mean_eff, _ = tfp.first_passage_moments(model_eff, v0)
    t_a = model.stick_time(v0)
    s_end = float(tfp.first_passage_survival(model, v0, [record])[0])
    mean_label, prob_label, t_prob = _fp_labels(v0, t_a, record, s_end < CENSORED_LIMIT)
    values = FirstPassageValues(mean_label, prob_label, t_prob)
    s_eff = float(tfp.first_passage_survival(model_eff, v0, [t_prob])[0])
    s_id = float(tfp.first_passage_survival(model, v0, [t_prob])[0])
    ex, ex_eff = {prob_label: 1.0 - s_id}, {prob_label: 1.0 - s_eff}
    if mean_label is not None:
        ex[mean_label], ex_eff[mean_label] = mean, mean_eff
    t = np.linspace(0.0, min(record, max(4.0 * mean, 2.0 * t_a if math.isfinite(t_a) else 0.0,
                                         1.0)), 161)[1:]
    density = tfp.first_passage_density(model, v0, t)
    f_at = float(tfp.first_passage_density(model, v0, [t_prob])[0])
    tick(f"{exp.name}: held/white Monte Carlo pair for first passage from v0={v0:g}")
    held, white = held_noise_pair(model_eff, v0=v0, t_end=record, replicas=PAIR_REPLICAS,
                                  seed=plan.stream("measure_first_passage_pair", i),
                                  noise_dt=noise_dt, sample_dt=dt)
    hold = jackknife_difference(values, held, white)
    return FirstPassageTheory(v0=v0, t_a=t_a, mean=mean, variance=var, record=record,
                              survival_end=s_end, values=values, exact=ex, exact_eff=ex_eff,
                              density_at={prob_label: f_at}, t=t, density=density, hold=hold,
                              sampling_bound=efp.sampling_bias_bound(model, v0, dt))


def measure_theory(exp, settings: ReportSettings, *, progress=None) -> MeasureTheory:
    """Everything the chapter compares with that needs no circuit data (exact spectra and
    first-passage laws, the held/white Monte Carlo pairs) for the experiment ``exp`` (an
    :class:`analogue.study.experiments.Experiment` of the paper's model) with the report
    settings its runs use (``exp.report.for_options(opts)``)."""
    t0 = time.perf_counter()
    if not applies(exp.model):
        raise ValueError(f"{exp.name}: 'what experiments measure' needs the paper's 1-D model "
                         "with finite gamma")
    tick = progress or (lambda *_: None)
    mapping = exp.mapping()
    model_eff, noise_dt = mapping.model_effective, mapping.noise_dt
    plan = SeedPlan(exp.seed)
    spectrum = _spectrum_theory(exp, settings, model_eff, noise_dt, plan, tick)
    fp = {float(v0): _first_passage_theory(exp, i, float(v0), model_eff, noise_dt, plan, tick)
          for i, v0 in enumerate(exp.v0)}
    return MeasureTheory(experiment=exp.name, model=exp.model, model_effective=model_eff,
                         burn_in=settings.stationary_burn_in, spectrum=spectrum,
                         first_passage=fp, wall_time_s=time.perf_counter() - t0)


# --------------------------------------------------------------------------- analysis
@dataclass(eq=False)
class MeasureAnalysis:
    """The chapter's numbers for one experiment: rows, the circuit's spectrum estimate and
    first-passage times (for the figures) and the theory they were compared with."""

    experiment: str
    theory: MeasureTheory
    spectrum: esp.SpectrumEstimate
    first_passage: dict                 # v0 -> FirstPassageEstimate
    rows: list = field(default_factory=list)
    wall_time_s: float = 0.0
    # comparisons made elsewhere for this experiment's chapter (the sweep points the report
    # adds when asked: analogue.report.measure_chapter.run_sweeps)
    extra: list = field(default_factory=list)

    @property
    def comparisons(self) -> list[Comparison]:
        """The rows as comparisons: smoothing and sampling as computed (signed), the measured
        bandwidth and integration differences as ``|d| + SE_MULTIPLIER SE`` (as every other
        row of the report); then :attr:`extra`."""
        return [*self._row_comparisons(), *self.extra]

    def _row_comparisons(self) -> list[Comparison]:
        return [compare(self.experiment, r.label, r.circuit, r.stderr, r.theory, "exact",
                        Budget(smoothing=r.smoothing, sampling=r.sampling,
                               bandwidth=_term(r.bandwidth), integration=_term(r.integration)),
                        r.note) for r in self.rows]


def _term(d_se: tuple) -> float:
    d, se = d_se
    return abs(float(d)) + SE_MULTIPLIER * float(se)


def _integration(fn, runs, kind: str) -> dict:
    chk, nom = runs.check_pair(kind)
    return jackknife_difference(fn, chk, nom)


def analyse_measure(runs, theory: MeasureTheory) -> MeasureAnalysis:
    """The chapter's rows for one experiment from the report's own runs (``runs``: an
    :class:`analogue.study.runs.ExperimentRuns`; its stationary and transition ensembles and
    their integration checks)."""
    t0 = time.perf_counter()
    exp = runs.exp
    if theory.experiment != exp.name:
        raise ValueError(f"theory of {theory.experiment!r} given for experiment {exp.name!r}")
    sp = theory.spectrum
    model = exp.model
    rows: list[Row] = []

    # ------------------------------------------------------------------------- spectrum
    ens = runs.stationary
    if not math.isclose(ens.dt, sp.sample_dt, rel_tol=1e-9):
        raise ValueError(f"{exp.name}: stationary runs sampled every {ens.dt!r}, the theory "
                         f"every {sp.sample_dt!r}")
    fn = SpectrumBands(theory.burn_in, model.tau_m)
    est = esp.velocity_spectrum(ens, burn_in=theory.burn_in, nperseg=NPERSEG)
    circ = jackknife(fn, ens)
    chk, _ = runs.check_pair("stationary")
    long_check = float(chk.t[-1] - chk.t[0]) >= theory.burn_in + NPERSEG * ens.dt
    integ = _integration(fn, runs, "stationary") if long_check else {}
    hold_note = (f"bandwidth: held (T = {sp.hold_dt:.3g}) minus white noise, Monte Carlo pair "
                 f"of {STATIONARY_PAIR_REPLICAS} replicas on common increments")
    for lo, hi, sel in _bands(model.tau_m, sp.omega):
        k = band_label(lo, hi)
        val, se = circ[k]
        expct = sp.expected[sel]
        se = max(se, sp.replica_sd[k] / math.sqrt(ens.replicas))
        theory_val = float(sp.exact[sel].mean())
        rows.append(Row(k, val, se, theory_val,
                        smoothing=sp.smoothing[k] * float(expct.mean()),
                        sampling=float(expct.mean()) - theory_val,
                        bandwidth=sp.hold[k], integration=integ.get(k, (0.0, 0.0)),
                        note=(f"Welch band average over {int(sel.sum())} bins (nperseg "
                              f"{NPERSEG}, dt {ens.dt:g}); theory: exact S of the ideal model; "
                              "sampling: E[Welch] - S (aliasing, leakage; exact); "
                              f"{hold_note}; SE: max(replica jackknife, the held Monte Carlo run's replica spread / sqrt(n))"),
                        group="spectrum"))

    # -------------------------------------------------------------------- first passage
    fps = {}
    for i, (v0, ens) in enumerate(runs.transition.items()):
        th = theory.first_passage[float(v0)]
        fps[v0] = efp.first_passage(ens)
        circ = jackknife(th.values, ens)
        n = ens.replicas
        integ = _integration(th.values, runs, "transition") if i == 0 else {}
        for k, (val, se) in circ.items():
            ex = th.exact[k]
            if k == th.values.mean_label:
                se = max(se, math.sqrt(th.variance / n))
                sampling = th.sampling_bound
                what = (f"mean of the first sign change (linear interpolation) of {n} paths; "
                        f"deterministic stick time t_a = {th.t_a:.4g}")
            else:
                p = min(max(ex, 1.0 / n), 1.0 - 1.0 / n)
                se = max(se, math.sqrt(p * (1.0 - p) / n))
                sampling = th.sampling_bound * th.density_at[k]
                what = (f"fraction of {n} paths at rest by t = {th.values.t_prob:.4g} "
                        + ("(t_a, eq. (31))" if th.values.t_prob == th.t_a
                           else "(the record's end; the noise-free path never stops)"))
            rows.append(Row(k, val, se, ex, smoothing=th.exact_eff[k] - ex, sampling=sampling,
                            bandwidth=th.hold[k], integration=integ.get(k, (0.0, 0.0)),
                            note=(f"{what}; theory: absorbing Fokker-Planck (theory."
                                  "first_passage); sampling: the late observed crossing, "
                                  f"<= {th.sampling_bound:.3g} in time (estimators."
                                  "first_passage.sampling_bias_bound); bandwidth: held minus "
                                  f"white Monte Carlo pair, {PAIR_REPLICAS} replicas"
                                  + ("" if integ else "; integration checked on the first v0 "
                                     "only")),
                            group="first passage"))
    return MeasureAnalysis(experiment=exp.name, theory=theory, spectrum=est, first_passage=fps,
                           rows=rows, wall_time_s=time.perf_counter() - t0)
