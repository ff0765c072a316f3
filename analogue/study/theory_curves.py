"""Every theory number and curve of one experiment's report, computed once.

Two stages, because only part of the theory depends on the circuit's data:

- :func:`experiment_theory` needs the experiment alone (model, circuit spec, settings): the
  exact finite-noise transition densities and their moments for the ideal model and for the
  circuit's smoothed model (one common grid, so their difference is the smoothing bias), the
  weak-noise propagator and its moments, and the exact stationary observables.  It can run
  while ngspice runs (issue 10, item 4).
- :func:`figure_curves` needs the circuit's estimates where a curve is drawn on their grid or
  between their end points: the work-rate bins of Figs. 8-9 (the exact finite-tau densities and
  the exact I_gamma(w) on a symmetric grid spanning them), the end points of Fig. 7's
  work-optimal paths, the range of the stationary histogram.  Each figure's curves are
  computed independently and a failure is kept with the figure it belongs to (the figure
  then fails, not the experiment).

The figures (:mod:`analogue.report.figures`) only draw what is here; the comparisons
(:mod:`analogue.study.comparisons`) read their theory values from here, so the exact
propagator of a comparison is the one drawn in Fig. 6.  Exact results (propagators,
stationary moments, work variances, work densities, rate functions) go through the on-disk
theory cache (:mod:`analogue.theory.cache`): a repeated report recomputes nothing.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from .experiments import Experiment
from ..model import Model
from ..theory.cache import cached_call, cached_later
from .processes import quiet_call
from .observables import exact_stationary, exact_transition, weak_noise_transition
from .settings import ReportSettings
from ..theory import weak_noise
from ..estimators import stationary_density
from ..theory.weak_noise_work import work_optimal_path
from ..estimators import work_distribution
from ..theory import exact
from ..theory.work_statistics import rate_function_curve
from ..theory.work_statistics import weak_noise_limit_rate_function

__all__ = ["TransitionTheory", "ExperimentTheory", "FigureCurves", "experiment_theory",
           "figure_curves", "stationary_taus", "propagator_times", "CURVE_GROUPS"]


@dataclass(frozen=True, eq=False)
class TransitionTheory:
    """Theory of the transition run from one ``v0``: values keyed by observable label, and
    the densities on the grid ``v`` (rows: ``times``)."""

    v0: float
    times: tuple
    v: np.ndarray                      # grid of the exact (and weak-noise) densities
    exact: dict                        # label -> exact value, ideal model
    exact_eff: dict                    # label -> exact value at the circuit's epsilon
    f_exact: np.ndarray                # (len(times), v.size), ideal model
    v_eff: np.ndarray
    f_exact_eff: np.ndarray            # at the circuit's epsilon (histogram chi-square)
    weak: dict = field(default_factory=dict)   # label -> weak-noise value (Delta > 0)
    f_weak: np.ndarray | None = None           # weak-noise propagator on v (Delta > 0)


@dataclass(frozen=True, eq=False)
class ExperimentTheory:
    """The circuit-free theory of one experiment (see the module docstring)."""

    model: Model
    model_effective: Model
    h: float | None                    # common Fokker-Planck spacing (ideal and smoothed)
    transition: dict                   # v0 -> TransitionTheory
    stationary: dict                   # label -> exact value, ideal model
    stationary_eff: dict               # ... at the circuit's epsilon
    threshold: float                   # stick threshold (velocity units)
    taus: tuple                        # work windows compared
    wall_time_s: float = 0.0


def stationary_taus(exp: Experiment, settings: ReportSettings) -> tuple:
    """The work windows that fit in one stationary path after its burn-in."""
    return tuple(tau for tau in exp.work_taus
                 if tau <= settings.stationary_t_end - settings.stationary_burn_in - 1e-9)


def propagator_times(times) -> list:
    """At most four of the histogram times for Fig. 6 (first, two inner, last)."""
    times = list(times)
    if len(times) > 4:
        times = [times[0], times[len(times) // 3], times[2 * len(times) // 3], times[-1]]
    return times


def experiment_theory(exp: Experiment, settings: ReportSettings, *, cache=None,
                      progress=None) -> ExperimentTheory:
    """Everything the comparisons and Fig. 6 need from theory, without circuit data.

    ``settings``: the report settings the runs use (``--quick`` changes the stationary
    length and so the work windows).  ``cache``: the theory cache (None: default location,
    False: off)."""
    import time
    t0 = time.perf_counter()
    tick = progress or (lambda *_: None)
    model = exp.model
    model_eff = exp.mapping().model_effective
    # one Fokker-Planck spacing for the ideal and the smoothed model: their difference (the
    # smoothing bias) is then free of the discretisation error, which cancels
    h = model_eff.epsilon / 2 if model_eff.epsilon > 0 else None
    times = list(exp.histogram_times)
    transition = {}
    for v0 in exp.v0:
        tick(f"{exp.name}: exact transition theory from v0={v0:g}")
        dens: dict = {}
        dens_eff: dict = {}
        dens_weak: dict = {}
        ex = exact_transition(model, v0, times, h=h, densities=dens, cache=cache)
        ex_eff = exact_transition(model_eff, v0, times, h=h, densities=dens_eff, cache=cache)
        weak = (weak_noise_transition(model, v0, times, densities=dens_weak)
                if model.delta > 0 else {})
        transition[v0] = TransitionTheory(
            v0=v0, times=tuple(times), v=dens["v"], exact=ex, exact_eff=ex_eff, f_exact=dens["f"],
            v_eff=dens_eff["v"], f_exact_eff=dens_eff["f"], weak=weak, f_weak=dens_weak.get("f"))
    tick(f"{exp.name}: exact stationary theory")
    thr = settings.stick_threshold * model.velocity_scale
    taus = stationary_taus(exp, settings)
    stat = exact_stationary(model, threshold=thr, taus=taus, h=h, cache=cache)
    stat_eff = exact_stationary(model_eff, threshold=thr, taus=taus, h=h, cache=cache)
    return ExperimentTheory(model=model, model_effective=model_eff, h=h, transition=transition,
                            stationary=stat, stationary_eff=stat_eff, threshold=thr, taus=taus,
                            wall_time_s=time.perf_counter() - t0)


# --------------------------------------------------------------------- figure curves
CURVE_GROUPS = ("prehistory", "stationary law", "work paths", "rate function")


class FigureCurves:
    """The data-dependent theory curves of one experiment's figures, by group
    (:data:`CURVE_GROUPS`).  A group whose computation failed keeps its exception, which
    :meth:`get` raises, so that the figure drawing it fails alone."""

    def __init__(self):
        self._values: dict = {}
        self._errors: dict = {}
        self.wall_time_s = 0.0
        # with worker processes: the seconds waited for them and their longest computation's
        # CPU seconds (analogue.study.critical_path.curves_unlimited_s)
        self.timing: dict = {}

    def set(self, group: str, value) -> None:
        self._values[group] = value

    def fail(self, group: str, exc: BaseException) -> None:
        self._errors[group] = exc

    def get(self, group: str):
        if group in self._errors:
            raise self._errors[group]
        return self._values.get(group)


def _prehistory_curves(runs):
    targets = [p if len(p) == 3 else (runs.exp.v0[0],) + tuple(p)
               for p in runs.settings.prehistory]
    out = []
    for v0, v, t in targets:
        if v0 not in runs.transition:
            raise ValueError(f"{runs.exp.name}: report.prehistory starts at v0={v0:g}, which is "
                             f"not one of experiment.v0 = {list(runs.transition)}")
        out.append(((v0, v, t), weak_noise.optimal_path(runs.exp.model, v, t, v0, n=600)))
    return out


def _stationary_curves(runs):
    m = runs.exp.model
    d = stationary_density(runs.stationary, burn_in=runs.settings.stationary_burn_in, bins=50)
    v = np.unique(np.concatenate([np.linspace(d.edges[0], d.edges[-1], 800), [0.0]]))
    v = v[(v >= d.edges[0]) & (v <= d.edges[-1])]
    return d, v, np.asarray(m.stationary_pdf(v))


def _windows_with_rate(ens, tau, force, w_target, half_width, burn_in):
    """Velocity segments of the windows [s, s + tau] whose work rate is within half_width of
    w_target (one segment per replica at most, the first, so the segments are independent)."""
    dt = ens.dt
    k = int(round(tau / dt))
    i0 = int(round(burn_in / dt))
    starts = np.arange(i0, ens.t.size - k)
    w = force * (ens.x[:, starts + k] - ens.x[:, starts]) / (k * dt)
    hit = np.abs(w - w_target) < half_width
    rows = np.flatnonzero(hit.any(axis=1))
    first = starts[np.argmax(hit[rows], axis=1)]
    idx = first[:, None] + np.arange(k + 1)[None, :]
    return np.arange(k + 1) * dt, ens.v[rows[:, None], idx]


def _work_path_curves(runs):
    """Per (w, tau): circuit windows of that work rate and the work-optimal path between
    their median end points (eq. (60))."""
    m = runs.exp.model
    out = []
    for w, tau in runs.settings.work_paths:
        half = 0.1 * max(abs(w), m.force * m.velocity_scale)
        s, seg = _windows_with_rate(runs.stationary, tau, m.force, w, half,
                                    runs.settings.stationary_burn_in)
        if seg.shape[0] >= 5:
            v0, v1 = float(np.median(seg[:, 0])), float(np.median(seg[:, -1]))
        else:
            v0 = v1 = w / m.force
        out.append(((w, tau), s, seg, work_optimal_path(m, w, tau, v0, v1, n=600)))
    return out


def work_distributions(runs) -> dict:
    """The circuit's work-rate histograms, one per window that fits (Figs. 8-9)."""
    m = runs.exp.model
    settings = runs.settings
    out = {}
    for tau in runs.exp.work_taus:
        if tau > settings.stationary_t_end - settings.stationary_burn_in - 1e-9:
            continue
        out[tau] = work_distribution(runs.stationary, tau, m.force, bins=41,
                                     burn_in=settings.stationary_burn_in)
    return out


def _finite_tau_pdfs(model, dists, min_replicas=10, cache=None, processes=None,
                     timing=None):
    """Exact finite-tau work densities on the bin centres the circuit estimates use, one call
    per tau: {tau: {w: density}}.  The fluctuation ratio pairs bins that both have data, so
    its -w are among these centres too (the bins are symmetric about 0).  ``processes``: a
    :class:`~analogue.study.processes.TheoryProcesses` that computes the windows side by side
    (each call holds the interpreter lock most of its time; same numbers); ``timing``: a
    dict that gets the workers' record (:class:`FigureCurves` ``timing``)."""
    started: list = []

    def submit(fn, *a, **k):
        s = processes.start(quiet_call, fn, *a, **k)
        started.append(s)
        return s
    pending = {}
    for tau, d in dists.items():
        w = d.centres[d.contributing >= min_replicas]
        # every window started before the first is waited for
        pending[tau] = (w, cached_later(exact.work_pdf, model, w, tau, cache=cache,
                                        submit=None if processes is None else submit))
    out = {}
    for tau, (w, density) in pending.items():
        with warnings.catch_warnings():
            # work_pdf warns where it falls back to the large-deviation form (far tails, ln p
            # right to O(1)); only bins the circuit reaches are evaluated here
            warnings.simplefilter("ignore", RuntimeWarning)
            p = np.asarray(density())
        out[tau] = dict(zip(np.round(w, 12), p))
    if timing is not None and started:
        # the critical path's record: the seconds this thread waited for the workers, and
        # the longest computation's CPU seconds (what it takes with a core of its own)
        timing["process_wait_s"] = round(sum(s.waited_s for s in started), 3)
        timing["longest_process_s"] = round(max(s.cpu_s for s in started), 3)
    return out


@dataclass(frozen=True, eq=False)
class RateFunctionCurves:
    """Figs. 8-9 on the symmetric grid ``w``: the paper's I(w) (eq. (64), the Filippov value
    at w = 0, :func:`analogue.theory.weak_noise.rate_function`), its fluctuation relation
    (eq. (67)), the gamma -> infinity limit, the exact I_gamma(w) and I_gamma(-w) -
    I_gamma(w), the circuit's histograms and the exact finite-tau densities on their bins."""

    w: np.ndarray
    paper: np.ndarray
    paper_fr: np.ndarray               # on w > 0
    limit: np.ndarray
    exact: np.ndarray
    exact_fr: np.ndarray               # on w > 0
    dists: dict                        # tau -> circuit WorkDistribution
    finite: dict                       # tau -> {w: exact finite-tau density}


def exact_rate_curve(model: Model, w: np.ndarray, cache=None):
    """``(w, I(w), I(-w) - I(w))`` on the symmetric grid w, every point computed once
    (:func:`analogue.theory.work_statistics.rate_function_curve` for the paper's model; family
    members through :func:`analogue.theory.exact.rate_function`, I(-w) read off the reversed
    grid)."""
    if model.is_paper:
        w, rate, fr = cached_call(rate_function_curve, model, w, cache=cache)
        return np.asarray(w), np.asarray(rate), np.asarray(fr)
    rate = np.asarray(cached_call(exact.rate_function, model, w, cache=cache))
    return w, rate, rate[::-1] - rate


def _rate_function_curves(runs, cache=None, processes=None, timing=None):
    m = runs.exp.model
    dists = work_distributions(runs)
    if not dists or m.a == 0:
        return None
    finite = _finite_tau_pdfs(m, dists, cache=cache, processes=processes, timing=timing)
    w_all = np.concatenate([d.centres for d in dists.values()])
    wmax = float(np.max(np.abs(w_all)))
    # one symmetric grid: I(-w) is I reversed, so Fig. 9 needs no second computation
    w, rate, fr = exact_rate_curve(m, np.linspace(-wmax, wmax, 61), cache=cache)
    pos = w > 0
    return RateFunctionCurves(
        w=w, paper=np.asarray(weak_noise.rate_function(m, w)),
        paper_fr=np.asarray(weak_noise.fluctuation_relation(m, w[pos])),
        limit=np.asarray(weak_noise_limit_rate_function(m, w)), exact=rate, exact_fr=fr[pos],
        dists=dists, finite=finite)


def figure_curves(runs, *, cache=None, progress=None, processes=None) -> FigureCurves:
    """The data-dependent curves of every figure of one experiment (failures kept per group).
    ``processes``: a study's :class:`~analogue.study.processes.TheoryProcesses` for the work
    densities of the rate-function figures (None: all in this thread)."""
    import time
    t0 = time.perf_counter()
    tick = progress or (lambda *_: None)
    curves = FigureCurves()
    for group, fn in (("prehistory", lambda: _prehistory_curves(runs)),
                      ("stationary law", lambda: _stationary_curves(runs)),
                      ("work paths", lambda: _work_path_curves(runs)),
                      ("rate function", lambda: _rate_function_curves(
                          runs, cache=cache, processes=processes, timing=curves.timing))):
        tick(f"{runs.exp.name}: theory curves: {group}")
        try:
            curves.set(group, fn())
        except (KeyboardInterrupt, SystemExit):
            raise
        except Exception as exc:  # the figure drawing this group reports it
            curves.fail(group, exc)
    curves.wall_time_s = time.perf_counter() - t0
    return curves
