"""Every circuit-versus-theory comparison of one experiment, with its error budget.

Theory values are those of the *ideal* model (sgn friction, white noise); the circuit's
departures from it are budgeted term by term (:mod:`analogue.study.budget`), so a reader can
see which one dominates.  Circuit standard errors come from a jackknife over replicas, which
are independent (errors hold however correlated the samples along one path are).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .experiments import Experiment
from ..circuit.mapping import map_model
from ..ensemble import Ensemble
from ..theory.exact import sample_stationary
from .budget import (SE_MULTIPLIER, held_noise_pair_chunks, integration_term,
                     real_diode_element, real_diode_transition_element)
from .metrics import Budget, compare
from ..estimators.resampling import jackknife, jackknife_difference
from ..estimators.smoothed_indicator import kernel_width
from .seeds import SeedPlan
from .catalogue import (Kind, StationaryValues, record_span, stationary_exact_se,
                               stationary_null_se, stationary_observables, transition_observables,
                               transition_theory_se, transition_values)
from .settings import ReportSettings, stationary_noise_dt
from .runs import ExperimentRuns
from .theory_curves import ExperimentTheory, FigureCurves, experiment_theory, stationary_taus

__all__ = ["ExperimentAnalysis", "analyse", "MC_REPLICAS", "MC_STATIONARY_REPLICAS",
           "BandwidthTerms", "bandwidth_terms"]

# Held/white Monte Carlo pairs are cheap (numpy); enough replicas that the bandwidth estimate
# is not dominated by its own noise (threshold observables change by whole paths).  At 1024
# transition replicas the paper's P(v<0) terms were up to 1.27 statistical errors of the
# full-size circuit, of which 2 SE(d) = 0.76 was the pair's own noise; at 4096 every
# transition term is at most 0.81 (slip, v0 = -1, t = 1; the others <= 0.43), for 10 s of
# CPU for the three experiments' pairs and 1.7 GB peak (benchmarks/README.md).
MC_REPLICAS = 4096
MC_STATIONARY_REPLICAS = 256


@dataclass
class ExperimentAnalysis:
    runs: ExperimentRuns
    comparisons: list = field(default_factory=list)
    budgets: dict = field(default_factory=dict)   # observable -> Budget
    circuit: dict = field(default_factory=dict)   # observable -> (value, se)
    exact: dict = field(default_factory=dict)     # observable -> exact value (ideal model)
    exact_eff: dict = field(default_factory=dict)  # ... at the circuit's epsilon
    # every theory value and curve, computed once (study.theory_curves): the figures draw them
    theory: ExperimentTheory | None = None
    curves: FigureCurves | None = None

    def summary(self) -> dict:
        n = len(self.comparisons)
        ok = sum(c.within_budget for c in self.comparisons)
        z_ok = sum(abs(c.z) < 3 for c in self.comparisons if math.isfinite(c.z))
        return {"comparisons": n, "within_budget": ok, "abs_z_below_3": z_ok}


_NULL_SE_NOTE = ("SE: the replica jackknife rescaled to the theory's value (p(1-p) or sigma^4), "
                 "as the estimate's spread under the null (study.catalogue.stationary_null_se)")
_EXACT_SE_NOTE = ("SE: the larger of the replica jackknife and the exact spread of the "
                  "replicas' time averages under the null, sqrt(2 int_0^T (T - s) C_f(s) ds / n) "
                  "/ T (study.catalogue.stationary_exact_se)")
_THEORY_SE_NOTE = ("SE: the larger of the replica jackknife and that of n draws from the "
                   "exact law (sigma/sqrt(n) for the mean, sqrt(mu4/n - sigma^4 (n-3)/(n(n-1))) "
                   "for the variance)")


def _element_note(mapping) -> str:
    return (f"element: the {mapping.part.name} bridge's DC law (exact numerics on it minus "
            f"exact numerics on tanh(v/epsilon))")


def _prob_floor(kind: Kind, value: float, se: float, n: int) -> float:
    """A probability estimated as 0 or 1 from n samples still has an error ~ 1/n."""
    if kind.probability and n > 0:
        p = (value * n + 1) / (n + 2)
        return max(se, math.sqrt(p * (1 - p) / n))
    return se


def _bias(pair_diffs: dict, name: str) -> float:
    d, se = pair_diffs.get(name, (0.0, 0.0))
    return abs(d) + SE_MULTIPLIER * se


# ------------------------------------------------------------------- bandwidth term
@dataclass(frozen=True, eq=False)
class BandwidthTerms:
    """The bandwidth term of every comparison of one experiment: the held-noise minus
    white-noise Monte Carlo difference ``{label: (difference, se)}`` (paired jackknife),
    per transition ``v0`` and for the stationary run.  It needs no circuit data (the
    effective model, the seeds, the settings, the hold and sampling steps), so the report
    computes it while ngspice runs; ``threshold`` and ``taus`` are those of the stationary
    observables it was computed for (checked against the theory's by :func:`analyse`)."""

    threshold: float
    taus: tuple
    transition: dict                   # v0 -> {label: (difference, se)}
    stationary: dict                   # label -> (difference, se)
    wall_time_s: float = 0.0
    # how the Monte Carlo chunks ran (study.budget.held_noise_pair_chunks), for the report's
    # critical path: seconds drawing the noise and computing the jackknives in the calling
    # thread, and the CPU seconds of the longest chunk
    timing: dict = field(default_factory=dict)


def _at_times(ens: Ensemble, times) -> Ensemble:
    """``ens`` on the grid points nearest ``times`` alone (:meth:`Ensemble.at`'s choice, so
    that ``at`` picks the same column and the transition observables are bit for bit those
    on ``ens``), without its noise: the jackknife copies its ensembles once per group (32
    copies of the quick work experiment's 4096 x 1201 paths per transition pair, for the
    velocities at four times)."""
    idx = sorted({int(np.argmin(np.abs(ens.t - t))) for t in times})
    return Ensemble(ens.t[idx], ens.v[:, idx], ens.x[:, idx], ens.meta)


def bandwidth_terms(exp: Experiment, settings: ReportSettings, *,
                    progress=None, executor=None) -> BandwidthTerms:
    """Held/white Monte Carlo pairs (:func:`~analogue.study.budget.held_noise_pair`) of one
    experiment, on the seeds of its :class:`~analogue.study.seeds.SeedPlan`, and their paired
    jackknife differences: the budget's bandwidth term, bit for bit what :func:`analyse`
    computes when not given it.  ``settings``: the report settings the runs use
    (``exp.report.for_options(opts)``).  ``executor``: where the pairs' chunks of replicas
    run (:func:`~analogue.study.budget.held_noise_pair_chunks`; the report passes a thread
    pool of the usable cores), each pair's chunks queued before the previous pair is waited
    for; the numbers do not depend on it (bit for bit the same with any executor or none).
    ``timing`` of the result: seconds drawing the noise and computing the jackknives in this
    thread, the chunks' count, total and longest CPU seconds (the report's critical path)."""
    import time
    t0 = time.perf_counter()
    tick = progress or (lambda *_: None)
    model = exp.model
    mapping = map_model(model, exp.spec)
    model_eff, noise_dt = mapping.model_effective, mapping.noise_dt
    seeds = SeedPlan(exp.seed)
    times = list(exp.histogram_times)
    thr = settings.stick_threshold * model.velocity_scale
    taus = stationary_taus(exp, settings)
    stationary_fn = StationaryValues(burn_in=settings.stationary_burn_in, threshold=thr,
                                     force=model.force, taus=tuple(taus))
    chunks: list = []
    common = dict(sample_dt=exp.sample_dt, executor=executor, timing=chunks, keep_noise=False)

    def transition_pair(i, v0):
        tick(f"{exp.name}: held-noise Monte Carlo pair from v0={v0:g}")
        return held_noise_pair_chunks(model_eff, v0=v0, t_end=max(times), replicas=MC_REPLICAS,
                                      seed=seeds.mc_transition(i), noise_dt=noise_dt, **common)

    def stationary_pair():
        v0_mc = sample_stationary(model_eff, MC_STATIONARY_REPLICAS, seeds.mc_stationary_v0)
        tick(f"{exp.name}: held-noise Monte Carlo pair (stationary)")
        # the stationary runs' own (finer) hold: plan.stationary_noise_dt
        return held_noise_pair_chunks(model_eff, v0=v0_mc, t_end=settings.stationary_t_end,
                                      replicas=v0_mc.size, seed=seeds.mc_stationary,
                                      noise_dt=stationary_noise_dt(noise_dt, settings),
                                      **common)

    jobs: list = [(v0, lambda i=i, v0=v0: transition_pair(i, v0)) for i, v0 in enumerate(exp.v0)]
    jobs.append((None, stationary_pair))
    values: dict = {v0: (lambda e, v0=v0: transition_values(e, v0, times)) for v0 in exp.v0}
    values[None] = stationary_fn
    # each pair's chunks are queued before the previous pair is waited for (one pair ahead:
    # the noise of two pairs in memory at most, 1.3 GB for the quick work experiment's
    # 4096 x 19 200 transition pairs, instead of every pair's at once)
    out: dict = {}
    after = 0.0
    queued: list = []
    for key, start in [*jobs, (None, None)]:
        if start is not None:
            queued.append((key, start()))
        if len(queued) == 2 or (start is None and queued):
            k, collect = queued.pop(0)
            held, white = collect()
            c0 = time.thread_time()
            if k is not None:
                held, white = _at_times(held, times), _at_times(white, times)
            out[k] = jackknife_difference(values[k], held, white)
            after += time.thread_time() - c0
            del held, white
    stationary = out.pop(None)
    transition = {v0: out[v0] for v0 in exp.v0}
    timing = {"draw_s": round(sum(c[0] for c in chunks), 3), "jackknife_s": round(after, 3),
              "chunks": sum(len(c[1]) for c in chunks),
              "longest_chunk_s": round(max((x for c in chunks for x in c[1]), default=0.0), 3),
              "chunks_cpu_s": round(sum(x for c in chunks for x in c[1]), 3)}
    return BandwidthTerms(threshold=thr, taus=tuple(taus), transition=transition,
                          stationary=stationary, wall_time_s=time.perf_counter() - t0,
                          timing=timing)


def analyse(runs: ExperimentRuns, *, theory: ExperimentTheory | None = None,
            bandwidth: BandwidthTerms | None = None, progress=None,
            cache=None) -> ExperimentAnalysis:
    """Every comparison of one experiment.  ``theory``: its circuit-free theory
    (:func:`~analogue.study.theory_curves.experiment_theory`, computed here if not given;
    the pipeline computes it while ngspice runs).  ``bandwidth``: its bandwidth terms
    (:func:`bandwidth_terms`, likewise: computed here if not given)."""
    exp, settings = runs.exp, runs.settings
    model = exp.model
    model_eff = map_model(model, exp.spec).model_effective
    tick = progress or (lambda *_: None)
    if theory is None:
        theory = experiment_theory(exp, settings, cache=cache, progress=progress)
    if bandwidth is None:
        bandwidth = bandwidth_terms(exp, settings, progress=progress)
    if (bandwidth.threshold != theory.threshold or bandwidth.taus != tuple(theory.taus)
            or list(bandwidth.transition) != list(runs.transition)):
        raise ValueError(f"{exp.name}: bandwidth terms computed for other settings (threshold "
                         f"{bandwidth.threshold:g}, work windows {bandwidth.taus}, v0 "
                         f"{list(bandwidth.transition)}) than the analysis (threshold "
                         f"{theory.threshold:g}, work windows {tuple(theory.taus)}, v0 "
                         f"{list(runs.transition)})")
    res = ExperimentAnalysis(runs, theory=theory)
    # kernel width of the smoothed indicators in the integration differences
    h = kernel_width(theory.threshold, model_eff.epsilon)
    # a real bridge's own DC law against the tanh the smoothing term assumes (issue 18)
    mapping = map_model(model, exp.spec)

    # ---------------------------------------------------------------- transition runs
    times = [t for t in exp.histogram_times]
    for i, (v0, ens) in enumerate(runs.transition.items()):
        tick(f"{exp.name}: transition from v0={v0:g}")
        fn = lambda e, v0=v0: transition_values(e, v0, times)
        circ = jackknife(fn, ens)
        n = ens.replicas
        th = theory.transition[v0]
        entries = {o.label: o.entry for o in transition_observables(v0, times)}
        circ = {k: (v, _prob_floor(entries[k], v, se, n)) for k, (v, se) in circ.items()}
        # kinds with a theory-side SE (mean, variance: n draws from the exact law; the
        # jackknife of few replicas of a skewed law that miss its tail is too small) use the
        # larger of the two, from the exact law at the circuit's epsilon (the replicas' law)
        se_theory = transition_theory_se(th.v_eff, th.f_exact_eff, v0, times, n)
        circ = {k: (v, max(se, se_theory.get(k, 0.0))) for k, (v, se) in circ.items()}
        ex, ex_eff, weak = th.exact, th.exact_eff, th.weak
        band = bandwidth.transition[v0]
        integ = {}
        if i == 0:
            integ = integration_term(
                lambda s, v0=v0: (lambda e: transition_values(e, v0, times, smoothing=s)),
                *runs.check_pair("transition"), h)
        element = real_diode_transition_element(mapping, v0, times)
        for k, (val, se) in circ.items():
            b = Budget(smoothing=ex_eff[k] - ex[k], bandwidth=_bias(band, k),
                       integration=integ[k][0] if integ else 0.0, element=element.get(k, 0.0))
            res.budgets[k] = b
            res.circuit[k], res.exact[k], res.exact_eff[k] = (val, se), ex[k], ex_eff[k]
            note = "" if integ else "integration checked on the first v0 only"
            if k in se_theory:
                note = "; ".join(x for x in (note, _THEORY_SE_NOTE) if x)
            if k in element:
                note = "; ".join(x for x in (note, _element_note(mapping)) if x)
            res.comparisons.append(compare(exp.name, k, val, se, ex[k], "exact", b, note))
            if k in weak and entries[k].compare_weak_noise:
                bw = Budget(smoothing=b.smoothing, bandwidth=b.bandwidth, integration=b.integration,
                            finite_noise=ex[k] - weak[k], element=b.element)
                res.comparisons.append(compare(
                    exp.name, k, val, se, weak[k], "weak-noise", bw,
                    "saddle-point propagator (eqs. (46)-(51)) normalised on a grid; "
                    "finite_noise = exact(gamma) - weak-noise"))

        for o, f in zip(transition_observables(v0, times, fit_tests=True), th.f_exact_eff):
            value, se = o.entry.estimator(ens.at(o.t), th.v_eff, f)
            dof = round(2.0 / se ** 2)
            res.comparisons.append(compare(
                exp.name, o.label, value, se, o.entry.exact(), "exact", Budget(),
                f"Pearson chi^2 of the {ens.replicas} circuit velocities against the exact "
                f"f(v, t | v0) at the circuit's epsilon, {dof + 1} equal-probability bins"))

    # ---------------------------------------------------------------- stationary run
    tick(f"{exp.name}: stationary observables")
    ens = runs.stationary
    thr = theory.threshold
    taus = list(theory.taus)
    # the jackknives take their leave-a-group-out values from per-replica pieces
    # (StationaryValues.leave_group_out): the same numbers to rounding, measured below
    stationary_fn = StationaryValues(burn_in=settings.stationary_burn_in, threshold=thr,
                                     force=model.force, taus=tuple(taus))
    circ = jackknife(stationary_fn, ens)
    ex, ex_eff = theory.stationary, theory.stationary_eff
    band = bandwidth.stationary
    # the check covers a prefix window of the run: compared on the same rows and times
    integ = integration_term(lambda s: replace(stationary_fn, smoothing=s),
                             *runs.check_pair("stationary"), h)
    stat_entries = {o.label: o.entry for o in stationary_observables(taus)}
    element = real_diode_element(mapping, threshold=thr, taus=taus, stationary_eff=ex_eff)
    # the spread under the null of the time averages is known exactly (the replica jackknife
    # of 32 quick replicas in 16 groups scatters by ~18 %: mean v 0.0032 where it is 0.0051,
    # z -4.6); 0.4 s a kind
    span = record_span(ens, settings.stationary_burn_in)
    for k, (val, se) in circ.items():
        b = Budget(smoothing=ex_eff[k] - ex[k], bandwidth=_bias(band, k),
                   integration=integ[k][0], element=element.get(k, 0.0))
        se_null = stationary_null_se(stat_entries[k], val, se, ex_eff[k])
        note = _NULL_SE_NOTE if se_null > se else ""
        se_exact = stationary_exact_se(model_eff, stat_entries[k].name, span, ens.replicas,
                                       threshold=thr)
        if se_exact > se_null:
            se_null, note = se_exact, _EXACT_SE_NOTE
        if k in element:
            note = "; ".join(x for x in (note, _element_note(mapping)) if x)
        se = se_null
        res.budgets[k] = b
        res.circuit[k], res.exact[k], res.exact_eff[k] = (val, se), ex[k], ex_eff[k]
        res.comparisons.append(compare(exp.name, k, val, se, ex[k], "exact", b, note))
    return res
