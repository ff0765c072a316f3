"""The circuit runs behind one experiment's report (all through :func:`analogue.simulate`,
so they are seeded, stored and resumable).

- transition runs: ``replicas`` trajectories from each ``v0`` (f(v, t | v0), prehistory);
- a stationary run: replicas started from p_s (stationary law, work, stick, transport);
- a noise-free run against ``Model.deterministic`` (paper Fig. 1): the user's own circuit
  (same component values, same parts) with the noise source's amplitude set to zero
  (:meth:`~analogue.circuit.mapping.CircuitMapping.without_noise`), one replica per v0;
- integration checks: the first decks of the transition and stationary runs again with
  100x tighter tolerances than the ones chosen for them (:mod:`analogue.circuit.tolerances`,
  recorded with the deck size in each ensemble's ``meta``) and a quarter of the step,
  covering at least ``check_replicas`` replicas ([report]).  The held noise (``trrandom`` with
  ``.options seed``) is the same realisation, so the path-by-path difference measures the
  integration error directly, with no statistical noise.  The stationary check runs over a
  prefix window of the stationary run (:func:`stationary_check_plan`): ngspice draws the held
  noise in time order, so a deck re-run with a shorter ``t_end`` retraces exactly the first
  part of the nominal paths (measured: largest difference 0.0 over 32 replicas, t_end 5
  against 20), and :meth:`ExperimentRuns.check_pair` gives the nominal paths on the same
  rows and times.

All decks of one experiment (nominal runs and checks) go to one pool of ``workers`` ngspice
processes at once, the checks first (their decks are the longest), so every core stays busy
(issue 10: the work report's stationary check alone was one 56 s deck on one core of two).

Every circuit built here was validated when the experiment was loaded
(:meth:`~analogue.study.experiments.Experiment.planned_circuits`).
"""
from __future__ import annotations

import concurrent.futures as cf
import contextlib
import contextvars
import math
import threading
import time
from dataclasses import dataclass, field
from typing import Any
from collections.abc import Callable

import numpy as np

from .experiments import Experiment
from ..cores import usable_cpus
from ..circuit.deck_size import NOTIONAL_WORKERS
from ..circuit.simulate import DEFAULT_REPLICAS_PER_DECK, POLL_S
from ..circuit.tolerances import STATIONARY_OBSERVABLES
from ..circuit.store_index import indexing_runs
from ..ensemble import Ensemble
from ..model import Model
from .seeds import SeedPlan
from .settings import ReportSettings, RunOptions, stationary_noise_dt
from ..circuit.simulate import run_decks, time_grid, value_limits
from ..circuit.deck_size import choose_deck_size
from ..circuit.simulate import simulate
from ..circuit.tolerances import at_once, resolve_spec
from ..circuit.runner import Runner
from ..circuit import ngspice as _ng
from ..circuit.deck_pool import PoolView, WaitClock
from ..theory.exact import sample_stationary
from .theory_curves import stationary_taus

__all__ = ["ExperimentRuns", "run_experiment_runs", "first_deck_size", "check_plan",
           "stationary_check_plan", "head"]



def default_workers(runner: Runner | None = None) -> int:
    """Local ngspice processes at once: ``runner.workers`` when set, else the CPUs this
    process may use (:func:`analogue.cores.usable_cpus`: affinity mask and cgroup quota, not
    the machine's count; issue 22)."""
    return (runner.workers if runner is not None else None) or usable_cpus()


def first_deck_size(replicas: int, per_deck: int = DEFAULT_REPLICAS_PER_DECK) -> int:
    """Replicas in deck 0 when :func:`analogue.simulate` splits ``replicas`` evenly."""
    n_decks = -(-replicas // per_deck)
    return replicas // n_decks + (1 if replicas % n_decks else 0)


def check_plan(replicas: int, want: int, per_deck: int = DEFAULT_REPLICAS_PER_DECK) -> tuple[int, int]:
    """``(decks, size)``: the integration check re-runs the first ``decks`` decks of a nominal
    run of ``replicas`` replicas, each of ``size`` replicas, covering at least ``want`` replicas
    where the nominal run has that many equal-sized leading decks.

    :func:`analogue.simulate` splits ``replicas`` into ``n`` decks, the first ``replicas % n``
    one replica larger; deck ``b``'s noise depends on ``(seed, b)`` and on its size, so a
    re-run reproduces the nominal noise only deck for deck: ``simulate(replicas=decks * size,
    replicas_per_deck=size)`` builds exactly the first ``decks`` nominal decks."""
    n = -(-replicas // per_deck)
    q, r = divmod(replicas, n)
    size = q + (1 if r else 0)
    equal = r if r else n           # leading decks of that size
    return max(1, min(-(-want // size), equal)), size


def stationary_check_plan(replicas: int, want: int, per_deck: int, t_end: float, *,
                          burn_in: float, longest_window: float, sample_dt: float,
                          workers: int = 1) -> tuple[int, int, float]:
    """``(decks, size, window)``: the stationary integration check re-runs the first ``decks``
    decks (of ``size`` replicas) of a nominal run of ``replicas`` replicas of length ``t_end``,
    over the prefix window ``[0, window]``.

    The rule: the check covers at least the usable replica-time of ``want`` replicas over the
    whole run, ``decks * size * (window - lost) >= want * (t_end - lost)`` with ``lost =
    burn_in + longest_window`` (the stationary observables are time averages after the
    burn-in, the work rates over windows up to ``longest_window``: their integration
    difference, and so its standard error, depends on that replica-time; measured on the
    stick report, the term in units of the statistical error grows from 0.11 to 0.21 when the
    same 16 check replicas cover half the run), spread over at least ``workers`` decks (a whole
    number of rounds) where the nominal run has that many equal leading decks, so that the
    check, the longest job of the report at 5x the nominal cost per unit time, runs on every
    core.  The report passes :data:`~analogue.circuit.deck_size.NOTIONAL_WORKERS`, not the
    machine's count: the decks are the nominal run's, seeds included, and the numbers must
    not depend on the machine (issue 19).  The window is a whole number of ``sample_dt``, at most ``t_end``."""
    n_decks = -(-replicas // per_deck)
    q, r = divmod(replicas, n_decks)
    size = q + (1 if r else 0)
    equal = r if r else n_decks            # leading decks of that size
    decks = max(1, -(-want // size), workers)
    decks = -(-decks // workers) * workers  # a whole number of rounds on the workers
    decks = min(decks, equal)
    lost = min(burn_in + longest_window, t_end)
    window = lost + want * (t_end - lost) / (decks * size)
    steps = min(round(t_end / sample_dt), math.ceil(window / sample_dt - 1e-9))
    return decks, size, steps * sample_dt


def head(ens: Ensemble, t_end: float, replicas: int | None = None) -> Ensemble:
    """The first ``replicas`` paths of ``ens`` on its grid up to ``t_end`` (inclusive, within
    a hundredth of a sample step): the nominal counterpart of a check run."""
    k = int(np.searchsorted(ens.t, ens.t[0] + t_end + 1e-2 * ens.dt, side="right"))
    n = ens.replicas if replicas is None else replicas
    return Ensemble(ens.t[:k], ens.v[:n, :k], ens.x[:n, :k], ens.meta)


@dataclass
class ExperimentRuns:
    exp: Experiment
    settings: ReportSettings
    quick: bool
    transition: dict            # v0 -> Ensemble
    stationary: Ensemble
    noise_free: Ensemble        # one replica per v0: the same circuit with the noise off
    check_transition: Ensemble  # tight-tolerance re-run of deck 0 of transition[v0[0]]
    check_stationary: Ensemble  # ... and of the first decks of the stationary run, on a
                                # prefix window (stationary_check_plan)
    wall_time: float = 0.0
    seeds: dict = field(default_factory=dict)
    # seconds before the decks (tolerance and deck-size calibrations) and the longest deck
    # run here (0.0 when all came from the store): the runs' time with unlimited cores
    # (analogue.study.critical_path)
    timing: dict = field(default_factory=dict)

    def check_pair(self, kind: str) -> tuple[Ensemble, Ensemble]:
        """``(check, nominal)`` on the same rows and times, row i of both driven by the same
        noise: ``kind`` "transition" (the first v0's run) or "stationary" (its check covers
        a prefix window of the run).  The integration budget is their paired difference."""
        if kind == "transition":
            chk, nom = self.check_transition, self.transition[self.exp.v0[0]]
        elif kind == "stationary":
            chk, nom = self.check_stationary, self.stationary
        else:
            raise ValueError(f"kind must be 'transition' or 'stationary', got {kind!r}")
        return chk, head(nom, float(chk.t[-1] - chk.t[0]), chk.replicas)

    def by_role(self) -> dict[str, Ensemble]:
        """The runs named as :func:`analogue.load_runs` names them (:data:`analogue.export.
        ROLES`): ``transition_v0=<v0>`` per v0, ``stationary``, ``noise_free``,
        ``check_transition``, ``check_stationary``."""
        named = {f"transition_v0={v0:g}": ens for v0, ens in self.transition.items()}
        named.update(stationary=self.stationary, noise_free=self.noise_free,
                     check_transition=self.check_transition,
                     check_stationary=self.check_stationary)
        return named

    @property
    def model(self) -> Model:
        return self.exp.model

    @property
    def model_effective(self) -> Model:
        return Model(**self.stationary.meta["model_effective"])

    def provenance(self) -> dict:
        ens = {f"transition v0={v0:g}": e for v0, e in self.transition.items()}
        ens.update(stationary=self.stationary, noise_free=self.noise_free,
                   check_transition=self.check_transition, check_stationary=self.check_stationary)
        return {
            "experiment": self.exp.name,
            "parameters": self.exp.model.as_dict(),
            "model_effective": self.model_effective.as_dict(),
            "circuit_spec": self.exp.spec.as_dict(),
            # the spec's unset values as chosen from the model, and why (issue 20 item 5)
            "circuit_defaults": self.exp.mapping().chosen,
            # the stationary runs' finer hold (plan.stationary_noise_dt), model units
            "stationary_noise_dt": self.stationary.meta.get("noise_dt"),
            "quick": self.quick,
            "seeds": self.seeds,
            "ngspice_version": self.stationary.meta.get("ngspice_version"),
            "deck_hashes": {k: e.meta.get("deck_sha256") for k, e in ens.items()},
            "replicas": {k: e.replicas for k, e in ens.items()},
            # how each run's ngspice tolerances and deck size were chosen (issue 10)
            "tolerances": {k: e.meta.get("tolerances") for k, e in ens.items()},
            "deck_size": {k: e.meta.get("deck_size") for k, e in ens.items()},
            "wall_time_s": self.wall_time,
            "timing": self.timing,
        }


def _noise_free_run(exp: Experiment, seed: int, runner: Runner) -> Ensemble:
    """One replica per v0 on the user's circuit with the noise off (paper Fig. 1), its deck
    run with ``runner`` (its deck size unused: the deck is made here)."""
    deck = exp.noise_free_deck(seed=seed)
    times = time_grid(deck.t_end, exp.sample_dt)
    v0 = np.asarray(exp.v0, dtype=float)
    mapping = exp.noise_free_mapping()
    v, x, _, info = run_decks([deck], times, v0, limits=value_limits(mapping, v0, deck.t_end),
                              runner=runner)
    meta: dict[str, Any] = {"source": "circuit", "noise": "off", "model": exp.model.as_dict(),
            "model_effective": mapping.model_effective.as_dict(), "seed": seed,
            "deck_sha256": [deck.sha256], "t_end": deck.t_end, "sample_dt": exp.sample_dt,
            # nothing random to calibrate against: the spec's tolerances or the fixed ones
            "tolerances": {"reltol": mapping.reltol, "trtol": mapping.trtol,
                           "method": mapping.method,
                           "source": "user" if not exp.spec.unset_tolerances else "fixed"},
            **{k: info[k] for k in ("ngspice_version", "store_keys", "from_store", "wall_time",
                                    "ran_deck_wall_times")
               if k in info}}
    return Ensemble(times, v, x, meta)


# The report's integration terms must stay below 0.1 statistical errors (issue 10); the
# chooser's prediction comes from 16 calibration paths and the report's term is measured on
# other paths (the check): measured up to 1.4x the prediction (quick stick stationary run,
# trap 1e-4: predicted 0.069, the report's stick-fraction term 0.098, of which |mean d|
# 0.074), so the report asks the chooser for 0.06 (0.1 / 1.4 with a margin).
REPORT_FRACTION = 0.06


def _choose(model, spec, replicas: int, t_end: float, runner: Runner, check: int,
            observables, stages: list | None = None):
    """(spec with its tolerances set, replicas per deck, why) for one run of the report whose
    integration error is measured on about ``check`` of its paths, compared on
    ``observables`` (circuit.tolerances.STATIONARY_OBSERVABLES, or None: all).  The
    calibrations run with ``runner`` (its store, Dask scheduler and timeout: the run's
    --timeout holds for the calibrations too, issue 19, where a hung ngspice kept a --timeout
    3 run going for the calibrations' default hour per deck), on its workers or the usable
    CPUs, through :func:`analogue.circuit.decks.run_ensemble` (the same decks and store keys
    as through :func:`analogue.simulate`, which they called back before).  ``stages``: a
    list that gets the longest deck of each of its two stages (tolerances, then deck size;
    each stage's decks run at once: :func:`analogue.circuit.tolerances.at_once`), the
    calibrations' seconds with unlimited cores (0 for a stage whose runs were stored)."""
    workers = default_workers(runner)
    cal = runner.replace(workers=workers)
    clock = None
    if stages is not None and runner.executor is not None:
        clock = WaitClock(runner.executor)
        cal = cal.replace(executor=clock)
    spec, tol = resolve_spec(model, spec, replicas=replicas, t_end=t_end,
                             check_replicas=min(check, replicas), observables=observables,
                             fraction=REPORT_FRACTION, runner=cal)
    tol_stage = clock.stage_longest() if clock is not None else 0.0
    deck = choose_deck_size(model, spec, replicas=replicas, t_end=t_end, workers=workers,
                            runner=cal)
    if clock is not None and stages is not None:
        stages.append(tol_stage + clock.stage_longest())
    return spec, deck.replicas_per_deck, {"tolerances": tol.as_dict(),
                                          "deck_size": deck.as_dict()}


def _check_coupled(nominal: Ensemble, check: Ensemble, what: str) -> None:
    """The check run must retrace the nominal paths (same noise) on its rows and times (a
    prefix window of them for the stationary check); anything else is a bug in how the decks
    were matched, which would silently turn the integration estimate into noise."""
    nom = head(nominal, float(check.t[-1] - check.t[0]), check.replicas)
    if nom.v.shape != check.v.shape:
        raise RuntimeError(f"{what}: the tight-tolerance re-run has shape {check.v.shape}, "
                           f"the nominal paths it should retrace {nom.v.shape}")
    d = np.abs(check.v - nom.v)
    spread = float(np.std(nom.v))
    if not np.isfinite(d).all() or float(np.median(d)) > 0.1 * spread:
        raise RuntimeError(f"{what}: the tight-tolerance re-run does not retrace the nominal "
                           "paths (noise not reproduced?); integration budget unavailable")


class SharedPool(cf.Executor):
    """One job's view of the experiment's deck pool: submits go to the shared pool (which the
    caller owns and shuts down), and ``started`` is set at the job's first submit, so that the
    jobs' first decks queue in the order the jobs were started (a job's later decks may
    interleave with the next job's: the order is a schedule, the results do not depend on
    it).  :meth:`cancel_queued` cancels this job's decks not yet started (a sibling job
    failed), leaving other users of the pool alone."""

    def __init__(self, pool: cf.Executor):
        self.pool = pool
        self.started = threading.Event()
        self._futures: list = []
        self._lock = threading.Lock()

    def submit(self, fn, /, *args, **kwargs):
        fut = self.pool.submit(fn, *args, **kwargs)
        with self._lock:
            self._futures = [f for f in self._futures if not f.done()]
            self._futures.append(fut)
        self.started.set()
        return fut

    def cancel_queued(self) -> None:
        with self._lock:
            for f in self._futures:
                f.cancel()

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        pass  # the pool is the caller's


def _run_jobs(jobs: list[tuple[str, Callable[[Runner], Any]]], runner: Runner) -> dict:
    """Run ``jobs`` (name, fn(runner) -> result) with every deck on one pool of
    ``runner.workers`` ngspice processes (each job gets ``runner`` with the pool as its
    executor), queued in the order given (longest first), and return ``{name: result}``.  Each job runs in its own thread, which only waits for its decks, with
    a copy of the caller's context, so the run store's key collectors
    (:func:`analogue.circuit.store_index.collecting_keys`) see every deck.  The calling thread
    holds :func:`analogue.circuit.ngspice.interrupt_guard` meanwhile (a signal kills every
    ngspice process and raises there).  With a Dask scheduler address the jobs run one after
    another on it (each simulate call connects on its own) with ``runner`` as it is.  With an
    executor in ``runner`` (the study's one deck pool, :mod:`analogue.circuit.deck_pool`) the
    decks go there, beside the other experiments' and members' decks, and a failure cancels
    only this experiment's queued decks."""
    if runner.scheduler is not None:
        return {name: fn(runner) for name, fn in jobs}
    workers = default_workers(runner)
    out = {}
    own = runner.executor is None
    with _ng.interrupt_guard(), contextlib.ExitStack() as stack:
        pool = (stack.enter_context(cf.ThreadPoolExecutor(
            max_workers=workers, thread_name_prefix="analogue-deck")) if own else runner.executor)
        threads = stack.enter_context(cf.ThreadPoolExecutor(
            max_workers=len(jobs), thread_name_prefix="analogue-run"))
        futures = {}
        views: list[SharedPool] = []
        try:
            for name, fn in jobs:
                view = SharedPool(pool)
                views.append(view)
                fut = threads.submit(contextvars.copy_context().run, fn,
                                     runner.replace(executor=view))
                futures[name] = fut
                # the next job's decks queue behind this one's (all from the store: none)
                while not (view.started.wait(0.05) or fut.done()):
                    pass
            # the first failure stops the rest at once (not when the jobs before it are done);
            # polled, so that a signal the kernel gave another thread is handled here within
            # a poll (a wait without timeout is not woken by it)
            pending = set(futures.values())
            while pending:
                done, pending = cf.wait(pending, timeout=POLL_S, return_when=cf.FIRST_EXCEPTION)
                if any(not f.cancelled() and f.exception() is not None for f in done):
                    break
            for fut in futures.values():
                if fut.done() and fut.exception() is not None:
                    fut.result()
            for name, fut in futures.items():
                out[name] = fut.result()
        except BaseException:
            for fut in futures.values():
                fut.cancel()
            for v in views:
                v.cancel_queued()
            if own:
                pool.shutdown(wait=False, cancel_futures=True)
            raise
    return out


def _ran(e: Ensemble) -> list[float]:
    """Wall seconds of each deck of ``e`` run in this job (none: all from the store)."""
    return [float(w) for w in e.meta.get("ran_deck_wall_times") or () if w is not None]


@dataclass(frozen=True)
class StationaryRuns:
    """What an experiment's runs give as soon as its stationary run is in
    (``run_experiment_runs(on_stationary=)``): the experiment, its settings, the stationary
    run, and the transition runs' start velocities (``transition``: v0 -> None, the keys of
    :attr:`ExperimentRuns.transition`), which the theory curves read."""

    exp: Experiment
    settings: ReportSettings
    stationary: Ensemble

    @property
    def transition(self) -> dict:
        return dict.fromkeys(self.exp.v0)


@indexing_runs  # the store's index by experiment (analogue store ls): every entry used
def run_experiment_runs(exp: Experiment, opts: RunOptions,
                        settings: ReportSettings | None = None, *,
                        on_stationary: Callable[[StationaryRuns], Any] | None = None
                        ) -> ExperimentRuns:
    """Every circuit run of one experiment's report (transition runs from each v0, the
    stationary run, their integration checks, the noise-free run), stored and reused.
    ``on_stationary``: called with a :class:`StationaryRuns` as soon as the stationary run is
    in, while the other runs still run (the study starts the theory curves that need only
    it: :func:`analogue.study.theory_curves.figure_curves`)."""

    t_start = time.perf_counter()
    settings = (settings or exp.report).for_options(opts)
    runner = opts.runner()
    model, spec = exp.model, exp.spec
    model_eff = exp.mapping().model_effective
    replicas = opts.scaled(exp.replicas)
    # Each run gets its own seed, derived from the experiment's: distinct experiments (whose
    # seeds differ) never share a noise realisation, so their comparisons are independent.
    plan = SeedPlan(exp.seed)       # every seed of the report (analogue.study.seeds)
    # (the Monte Carlo pairs' seeds of study.comparisons are the plan's too: recorded here)
    seeds: dict = {"stationary": plan.stationary, "noise_free": plan.noise_free,
                   "mc_stationary": plan.mc_stationary, "mc_stationary_v0": plan.mc_stationary_v0,
                   **{f"mc_transition v0={v0:g}": plan.mc_transition(i)
                      for i, v0 in enumerate(exp.v0)},
                   "plan": plan.describe()}

    # Tolerances and deck sizes chosen here (not inside simulate) so that the integration
    # checks below integrate the very decks of the nominal runs 100x more tightly: each run
    # gets the tolerances its own size calls for (circuit.tolerances) and the deck size that
    # makes it fastest (circuit.deck_size); both are recorded in the ensembles' meta.  The
    # stationary check covers the replica-time of check_replicas whole paths (below), so the
    # tolerance chooser's model of the check's noise holds for it as for the transition check.
    n_stat = settings.stationary_replicas
    check = settings.check_replicas
    # transition runs are judged on every calibration observable, not only on the
    # instantaneous ones their rows read: those come from paths started in the stationary
    # state, and transitions from far-off v0 err more (measured: judged on v(T), v(T)^2,
    # 1[v(T)<0] alone, the quick stick and work transitions took trap 1e-4 and 1e-3 with
    # trtol 20, and their P(v<0) rows' integration terms reached 0.14 and 0.12 SE)
    # the calibrations' decks ahead of every experiment's bulk decks in the study's deck
    # pool: each experiment waits for its own calibrations, so with the experiments run at
    # once (many cores) its calibrations queued behind the longer experiments' hundreds of
    # decks (full paper on 16 cores: stick's and slip's 51-54 s before their first deck)
    cal_runner = (runner.replace(executor=runner.executor.ahead())
                  if isinstance(runner.executor, PoolView) else runner)
    # the stationary runs (and their check) hold the noise for a fraction of the circuit's
    # hold (plan.stationary_noise_dt): their indicator observables carry the largest
    # bandwidth bias; tolerances and deck size are chosen for that finer deck
    stat_base = spec.replace(noise_dt=stationary_noise_dt(exp.mapping().noise_dt, settings))
    # both runs' calibrations at once where the deck pool is shared (at_once: same choices,
    # their decks queue together); each records its two stages' longest decks.  Where the
    # stationary runs hold the noise as the transition runs do (stationary_hold_divisor 1:
    # the work experiment), the two calibrations run the same decks: one after the other,
    # the second reads them from the store (at once, both ran them: 116 decks against 82
    # for the quick work experiment)
    trans_stages: list = []
    stat_stages: list = []
    same_decks = settings.stationary_hold_divisor == 1
    calls = [lambda: _choose(model, spec, replicas, exp.t_end, cal_runner, check, None,
                             trans_stages),
             lambda: _choose(model, stat_base, n_stat, settings.stationary_t_end, cal_runner,
                             check, STATIONARY_OBSERVABLES, stat_stages)]
    (trans_spec, trans_deck, trans_why), (stat_spec, stat_deck, stat_why) = (
        [c() for c in calls] if same_decks else at_once(calls, cal_runner))
    calibration_unlimited = (
        (sum if same_decks else max)(trans_stages + stat_stages)
        if trans_stages and stat_stages else None)
    v0_stat = np.asarray(sample_stationary(model_eff, n_stat, seeds["stationary"]), dtype=float)
    for i, v0 in enumerate(exp.v0):
        seeds[f"transition v0={v0:g}"] = plan.transition(i)

    v00 = exp.v0[0]
    t_decks, t_size = check_plan(replicas, check, trans_deck)
    taus = stationary_taus(exp, settings)
    s_decks, s_size, s_window = stationary_check_plan(
        n_stat, check, stat_deck, settings.stationary_t_end,
        burn_in=settings.stationary_burn_in, longest_window=max(taus, default=0.0),
        sample_dt=exp.sample_dt, workers=NOTIONAL_WORKERS)
    n1 = s_decks * s_size

    def run(*, replicas_per_deck: int, **args):
        # a job's runner: the report's, with the deck pool as its executor (_run_jobs)
        return lambda job: simulate(model, sample_dt=exp.sample_dt, **args,
                                    runner=job.replace(replicas_per_deck=replicas_per_deck))

    stationary_run = run(v0=v0_stat, t_end=settings.stationary_t_end, replicas=n_stat,
                         seed=seeds["stationary"], circuit=stat_spec, replicas_per_deck=stat_deck)

    def stationary_job(job: Runner) -> Ensemble:
        ens = stationary_run(job)
        ens.meta.update(stat_why)
        if on_stationary is not None:
            on_stationary(StationaryRuns(exp, settings, ens))
        return ens

    # Longest first: the checks (5x the nominal cost per unit time), the stationary run, the
    # transition runs; the noise-free run (one short deck) last.
    jobs: list[tuple[str, Callable[[Runner], Any]]] = [
        ("check_stationary", run(v0=v0_stat[:n1], t_end=s_window, replicas=n1,
                                 seed=seeds["stationary"], circuit=exp.check_spec(stat_spec),
                                 replicas_per_deck=s_size)),
        ("check_transition", run(v0=v00, t_end=exp.t_end, replicas=t_decks * t_size,
                                 seed=plan.transition(0), circuit=exp.check_spec(trans_spec),
                                 replicas_per_deck=t_size)),
        ("stationary", stationary_job),
    ]
    jobs += [(f"transition {i}", run(v0=v0, t_end=exp.t_end, replicas=replicas,
                                     seed=plan.transition(i), circuit=trans_spec,
                                     replicas_per_deck=trans_deck))
             for i, v0 in enumerate(exp.v0)]
    jobs.append(("noise_free", lambda job: _noise_free_run(exp, seeds["noise_free"], job)))
    t_jobs = time.perf_counter()
    done = _run_jobs(jobs, runner)
    ran = [w for e in done.values() for w in _ran(e)]

    transition = {}
    for i, v0 in enumerate(exp.v0):
        transition[v0] = done[f"transition {i}"]
        transition[v0].meta.update(trans_why)  # simulate saw them as given: say why
    stationary = done["stationary"]   # (its meta has stat_why: stationary_job)
    check_transition, check_stationary = done["check_transition"], done["check_stationary"]
    check_stationary.meta["check_window"] = {
        "t_end": s_window, "decks": s_decks, "replicas": n1,
        "rule": "replica-time after burn-in and the longest work window >= check_replicas "
                "whole paths', over >= NOTIONAL_WORKERS decks (analogue.study.runs."
                "stationary_check_plan)"}
    _check_coupled(transition[v00], check_transition, "transition check")
    _check_coupled(stationary, check_stationary, "stationary check")
    return ExperimentRuns(exp=exp, settings=settings, quick=opts.quick, transition=transition,
                          stationary=stationary, noise_free=done["noise_free"],
                          check_transition=check_transition, check_stationary=check_stationary,
                          wall_time=time.perf_counter() - t_start, seeds=seeds,
                          timing={"before_decks_s": round(t_jobs - t_start, 3),
                                  # the calibrations with unlimited cores: the two runs'
                                  # at once, each its tolerance stage's longest deck then
                                  # its deck-size stage's (the work before the decks, less
                                  # the queueing a busy machine adds)
                                  **({"calibration_unlimited_s": round(
                                      calibration_unlimited, 3)}
                                     if calibration_unlimited is not None else {}),
                                  "longest_deck_s": round(max(ran, default=0.0), 3),
                                  "decks_run": len(ran),
                                  # the stationary run's own longest deck: what the theory
                                  # curves wait for (on_stationary)
                                  "stationary_longest_deck_s": round(max(
                                      _ran(stationary), default=0.0), 3)})

