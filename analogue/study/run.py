"""Run a study: every experiment's circuit runs, its circuit-free theory, its comparisons with
their error budgets, and the family members' analyses, scheduled on background threads
(:mod:`analogue.study.schedule`) -> a :class:`StudyResult`.

:func:`run_study` is the analysis half of what ``analogue report`` and ``analogue paper`` do;
the page half (:mod:`analogue.report.pipeline`) draws figures and writes the page from the
:class:`StudyResult`.  The page can draw while the study runs (figures overlap the next
experiment's circuit runs: measured, the figures and page took 17 s after everything else
had finished when they waited): :class:`StudyHooks` are called in the calling thread as
results come in.

Every experiment is loaded (and so validated) before anything runs.  After that, a piece of
work that fails (a circuit run, an analysis) is recorded in :attr:`StudyResult.failures` and
never throws away the experiments that finished.
"""
from __future__ import annotations

import json
import os
import platform
import time
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, wait
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from .experiments import Experiment, load_experiment
from ..circuit.deck_pool import DeckPool
from ..circuit.ngspice import interrupt_guard
from ..circuit.simulate import POLL_S
from ..ensemble import Ensemble
from .comparisons import BandwidthTerms, ExperimentAnalysis, analyse, bandwidth_terms
from .critical_path import report_critical_path
from .members import (CHAPTER_TITLE, MemberAnalysis, MemberRuns, analyse_member,
                      is_member_experiment, member_runs)
from .metrics import Comparison, validate_metrics
from .runs import ExperimentRuns, run_experiment_runs
from .schedule import (CIRCUIT_THREADS, MEMBER_DECKS, MEMBER_THREADS, NOW, PAPER_DECKS,
                       PAPER_RANK_STEP, SCHEDULER_CIRCUIT_THREADS, Failures, Phases, Workers, circuit_cost,
                       experiments_at_once, member_cost, monte_carlo_pool, theory_process_count,
                       theory_processes,
                       result_of, say)
from .settings import RunOptions
from .theory_curves import (CURVE_GROUPS, ExperimentTheory, FigureCurves, experiment_theory,
                            figure_curves)
from .. import __version__
from ..cores import usable_cpus
from .processes import TheoryProcesses

__all__ = ["StudyResult", "StudyHooks", "run_study", "load", "experiment_section_title",
           "run_experiment", "RunSummary", "MemberRunSummary", "PAGE_CIRCUIT_THREADS"]

#: Threads of the hooks' circuit work (:meth:`StudyHooks.circuit_background`): the report's
#: two sweep curves at once.  Each thread only waits for its sweep's point threads, whose
#: decks go to the study's one deck pool (analogue.circuit.deck_pool).
PAGE_CIRCUIT_THREADS = 2


def load(name_or_exp) -> Experiment:
    """An experiment from a name, a TOML path or an Experiment (validated when loaded)."""
    return name_or_exp if isinstance(name_or_exp, Experiment) else load_experiment(name_or_exp)


def experiment_section_title(exp: Experiment) -> str:
    """The name under which an experiment's failures are recorded (its page section)."""
    if is_member_experiment(exp):
        return f"{CHAPTER_TITLE}: {exp.name}"
    return f"Experiment '{exp.name}'"


class StudyHooks:
    """What a page does while a study runs, in the thread that called :func:`run_study`
    (:class:`analogue.report.pipeline` draws its figures here).  Every method is optional."""

    def background(self) -> dict[str, Callable[[], Any]]:
        """Circuit-free tasks (phase name -> function) queued on the theory thread after the
        experiments' theory; each future is handed to :meth:`background_ready`."""
        return {}

    def experiment_ready(self, result: StudyResult, runs: ExperimentRuns,
                         analysis: ExperimentAnalysis) -> None:
        """An experiment is compared and its theory curves are in (``analysis.curves``)."""

    def experiment_compared(self, result: StudyResult, runs: ExperimentRuns,
                            analysis: ExperimentAnalysis) -> None:
        """An experiment is compared; its theory curves may still be computing
        (``analysis.curves`` None until :meth:`experiment_ready`): what needs the comparisons
        alone can be drawn now (issue 22: figures drawn as their data arrive)."""

    def background_ready(self, result: StudyResult, phase: str, future: Future) -> None:
        """A task of :meth:`background` is done (or, at the end, waited for)."""

    def main_complete(self, result: StudyResult) -> None:
        """Every experiment on the paper's model is compared and drawn (the family members'
        circuit work started when the paper's circuit runs were done)."""

    def member_ready(self, result: StudyResult, exp: Experiment,
                     analysis: MemberAnalysis) -> None:
        """A family member is analysed (called as each completes, after
        :meth:`main_complete`); a failed member is not handed here."""

    def circuit_background(self, result: StudyResult) -> dict[str, Callable[[], Any]]:
        """Circuit work of the page's own (phase name -> function; the measurement chapter's
        sweep curves), queued like the family members (on a few cores once the paper's
        circuit runs are done), each on its own thread (:data:`PAGE_CIRCUIT_THREADS`), its
        decks in the study's deck pool (``result.options_for(opts, SWEEP_DECKS)``);
        each future is handed to :meth:`background_ready` when it is done, and at the latest
        before :meth:`main_complete` (then perhaps still running: wait for it there)."""
        return {}


@dataclass
class StudyResult:
    """What a study computed.  Experiments on the paper's model and family members are kept
    apart (their analyses differ); each dict is in the order the experiments were given."""

    experiments: list[Experiment]          # on the paper's model
    members: list[Experiment]              # family members
    quick: bool
    phases: Phases
    failures: Failures
    t0: float
    load0: tuple
    runs: dict[str, ExperimentRuns] = field(default_factory=dict)
    analyses: dict[str, ExperimentAnalysis] = field(default_factory=dict)
    member_analyses: dict[str, MemberAnalysis] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)   # experiment -> the error that ended it
    # the chapter "What experiments measure" (study.measure), filled by the page's hooks:
    # experiment -> MeasureAnalysis; its comparisons are the study's too
    measured: dict = field(default_factory=dict)
    # experiment -> how its bandwidth terms' Monte Carlo chunks ran (BandwidthTerms.timing)
    bandwidth_timing: dict = field(default_factory=dict)
    # experiment -> how its theory curves' worker processes ran (FigureCurves.timing)
    curves_timing: dict = field(default_factory=dict)
    paper_wall: float = 0.0       # seconds from the start until main_complete
    member_wall: float = 0.0      # the members' threads' time (the page adds its drawing)
    # filled by the page: experiment (or figure group) -> PNG paths; the page itself
    figures: dict[str, list[Path]] = field(default_factory=dict)
    page: Path | None = None
    # what the page recorded (metrics.json's content: comparisons, provenance with the wall
    # time and the critical path, summary, failures); None until a page is written
    record: dict | None = None
    # the study's one pool of local ngspice processes (analogue.circuit.deck_pool; None with
    # a Dask scheduler): circuit work the hooks start (the sweeps) queues there too, at
    # SWEEP_DECKS, through options_for()
    deck_pool: DeckPool | None = field(default=None, repr=False)

    def options_for(self, opts: RunOptions, priority: float) -> RunOptions:
        """``opts`` with this study's deck pool at ``priority`` (:data:`analogue.study.
        schedule.PAPER_DECKS` ...); ``opts`` itself without a pool (a Dask scheduler)."""
        if self.deck_pool is None or opts.scheduler:
            return opts
        return replace(opts, executor=self.deck_pool.view(priority))

    def __repr__(self) -> str:
        s = self.summary()
        return (f"StudyResult({len(self.experiments) + len(self.members)} experiments, "
                f"{s['comparisons']} comparisons, {s['within_budget']} within budget, "
                f"{len(self.failures.items)} failures, page={self.page})")

    @property
    def wall_time_s(self) -> float | None:
        """Seconds from the start of the study to its page (None before the page)."""
        return None if self.record is None else self.record["provenance"]["wall_time_s"]

    @property
    def critical_path_s(self) -> float | None:
        """The study's wall time with unlimited cores (:mod:`analogue.study.critical_path`;
        None before the page)."""
        return None if self.record is None else self.record["provenance"]["critical_path_s"]

    @property
    def all_analyses(self) -> list:
        """Analyses of the paper-model experiments, then of the members."""
        return [*self.analyses.values(), *self.member_analyses.values()]

    @property
    def comparisons(self) -> list[Comparison]:
        return ([c for a in self.all_analyses for c in a.comparisons]
                + [c for m in self.measured.values() for c in m.comparisons])

    def by_role(self, experiment: str) -> dict[str, Ensemble]:
        """An experiment's circuit runs by role (:data:`analogue.export.ROLES` names)."""
        if experiment in self.runs:
            return self.runs[experiment].by_role()
        if experiment in self.member_analyses:
            runs = self.member_analyses[experiment].runs
            if runs is not None:
                return runs.by_role()
        raise KeyError(f"experiment {experiment!r} has no runs in this study (has: "
                       f"{sorted([*self.runs, *self.member_analyses])})")

    def summary(self) -> dict:
        comps = self.comparisons
        return {"comparisons": len(comps), "abs_z_below_3": sum(abs(c.z) < 3 for c in comps),
                "within_budget": sum(c.within_budget for c in comps),
                "failed_sections": len(self.failures.items)}

    def provenance(self, wall: float) -> dict:
        """Everything needed to reproduce the study (metrics.json's ``provenance``)."""
        provs = {name: r.provenance() for name, r in self.runs.items()}
        provs.update({name: a.provenance for name, a in self.member_analyses.items()})
        software = _software()
        circuit_timing = {k: p.get("timing") for k, p in provs.items() if p.get("timing")}
        crit = report_critical_path(self.phases.items, circuit_timing, self.bandwidth_timing,
                                    self.curves_timing)
        return {
            "parameters": {k: p["parameters"] for k, p in provs.items()},
            "model_effective": {k: p["model_effective"] for k, p in provs.items()},
            "circuit_spec": {k: p["circuit_spec"] for k, p in provs.items()},
            "circuit_defaults": {k: p.get("circuit_defaults", {}) for k, p in provs.items()},
            "seeds": {k: p["seeds"] for k, p in provs.items()},
            "replicas": {k: p["replicas"] for k, p in provs.items()},
            "ngspice_version": next(iter(provs.values()))["ngspice_version"] if provs else None,
            "deck_hashes": {k: p["deck_hashes"] for k, p in provs.items()},
            # how each run's ngspice tolerances and deck size were chosen (circuit.tolerances)
            "tolerances": {k: p.get("tolerances") for k, p in provs.items()},
            "deck_size": {k: p.get("deck_size") for k, p in provs.items()},
            "wall_time_s": wall,
            # the wall time with unlimited cores: the longest chain of dependent phases, each
            # circuit run counted as its calibrations plus its longest deck (issue 22, item 1;
            # analogue.study.critical_path), and that chain
            "critical_path_s": crit["critical_path_s"],
            "critical_path": crit["chain"],
            "circuit_timing": circuit_timing,
            # the bandwidth terms' Monte Carlo chunks: noise draw and jackknives in the theory
            # thread, chunk count, total and longest CPU seconds (comparisons.bandwidth_terms)
            "bandwidth_timing": self.bandwidth_timing,
            # the theory curves' work densities in worker processes: seconds waited for them,
            # CPU seconds of the longest (theory_curves.FigureCurves.timing)
            "curves_timing": self.curves_timing,
            # when the paper's chapters (its experiments, Fig. 1, the open question) were
            # complete, from the start; the chapter "Beyond the paper" runs after their circuit
            # runs, beside their comparisons and figures
            "paper_wall_time_s": round(self.paper_wall, 3),
            "beyond_wall_time_s": self.member_wall if self.members else None,
            "quick": self.quick,
            "created": datetime.now(UTC).isoformat(timespec="seconds"),
            "software": software,
            # wall time per phase (the theory thread's phases overlap the circuit runs) and the
            # machine's load average (1, 5, 15 min) at the start and the end: times on a shared
            # machine mean little without it
            "phases": self.phases.items,
            "phase_totals_s": self.phases.totals(),
            "load_average": {"start": [round(x, 2) for x in self.load0],
                             "end": [round(x, 2) for x in os.getloadavg()]},
        }

    def metrics(self, provenance: dict) -> dict:
        """metrics.json's content (validated: :func:`analogue.study.metrics.validate_metrics`)."""
        metrics = {"comparisons": [c.as_dict() for c in self.comparisons],
                   "provenance": provenance, "summary": self.summary(),
                   "failures": self.failures.items}
        validate_metrics(json.loads(json.dumps(metrics, default=str)))
        return metrics


def _software() -> dict:
    import matplotlib  # its version only (the study draws nothing); loaded by the page anyway
    import scipy
    return {"analogue": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "matplotlib": matplotlib.__version__,
            "platform": platform.platform()}


def _curves_of(f: Future) -> FigureCurves:
    """An experiment's theory curves from the theory thread."""
    try:
        return result_of(f)
    except Exception as exc:  # figure_curves keeps its failures; this is a safety net
        curves = FigureCurves()
        for g in CURVE_GROUPS:
            curves.fail(g, exc)
        return curves


def member_task(exp: Experiment, opts: RunOptions) -> MemberAnalysis:
    say(f"{exp.name}: family member: circuit against theory")
    return analyse_member(exp, opts, progress=say)


def runs_task(exp: Experiment, opts: RunOptions, on_stationary=None) -> ExperimentRuns:
    say(f"{exp.name}: circuit runs ({'quick' if opts.quick else 'full'} size; stored runs are "
        "reused)")
    return run_experiment_runs(exp, opts, on_stationary=on_stationary)


def run_study(experiments: Iterable, *, members: Iterable = (), opts: RunOptions | None = None,
              quick: bool | None = None, runner=None, hooks: StudyHooks | None = None
              ) -> StudyResult:
    """Run and analyse ``experiments`` (names, TOML paths or Experiment objects; family
    members among them are analysed as members, and so are those of ``members``).

    ``opts`` says how the circuits run (:class:`~analogue.study.settings.RunOptions`; default:
    local, quick when ``quick``); ``quick`` overrides ``opts.quick``.  ``runner``: how the
    decks run, an :class:`analogue.Runner` (:meth:`RunOptions.from_runner`) in place of
    ``opts``.
    ``hooks`` (:class:`StudyHooks`): what the caller does while the study runs.  Failures of
    single experiments are recorded in the result, never raised; an interrupt is raised after
    every ngspice process was killed."""
    if runner is not None:
        if opts is not None:
            raise TypeError("pass either runner= (an analogue.Runner) or opts=, not both")
        opts = RunOptions.from_runner(runner, quick=bool(quick))
    opts = opts or RunOptions(quick=bool(quick))
    if quick is not None and quick != opts.quick:
        opts = replace(opts, quick=quick)
    t0 = time.perf_counter()
    load0 = os.getloadavg()
    # every experiment is validated before anything runs (bad input: nothing started yet)
    given = [load(n) for n in experiments]
    # (and the environment's process count, before anything starts)
    n_procs = theory_process_count([e for e in given if not is_member_experiment(e)])
    result = StudyResult(experiments=[e for e in given if not is_member_experiment(e)],
                         members=[e for e in given if is_member_experiment(e)]
                         + [load(n) for n in members],
                         quick=opts.quick, phases=Phases(origin=t0), failures=Failures(),
                         t0=t0, load0=load0)
    # Locally, every deck of the study (the paper's runs and calibrations, the members', the
    # sweeps') runs in one pool of `workers` ngspice processes, the paper's first (issue 22:
    # never more processes than cores; before, each member's run started `workers` of its
    # own beside the others', 2-3x the cores).  With a Dask scheduler the cluster is the pool.
    decks = None
    if not opts.scheduler and opts.executor is None:
        decks = DeckPool(opts.workers or usable_cpus())
        result.deck_pool = decks
    # ngspice runs in the circuit threads: this (main) thread's guard turns SIGINT/SIGTERM/
    # SIGHUP into RunInterrupted here (killing every ngspice group), whoever called us.
    # BLAS/LAPACK at one thread for the whole study (threadpoolctl, process-wide): the study
    # runs its own threads (theory, members, Monte Carlo chunks, comparisons) beside ngspice,
    # and a BLAS call in each would start one thread per core.  Measured on an idle 16-core
    # Xeon: the quick paper took 416 CPU-s (Python 178) against 154 (57) on 2 cores; the
    # theory thread's limit alone was restored whenever one of its tasks ended.
    with interrupt_guard(), threadpool_limits(limits=1):
        pool = Workers(result.phases, "theory", 1, blas_limit=True)
        circuit = Workers(result.phases, "circuit",
                          SCHEDULER_CIRCUIT_THREADS if opts.scheduler else
                          max(1, len(result.experiments)) if experiments_at_once(opts)
                          and decks is not None
                          else CIRCUIT_THREADS)
        family = Workers(result.phases, "members",
                         MEMBER_THREADS)
        page = Workers(result.phases, "page circuit", PAGE_CIRCUIT_THREADS)
        # the theory curves on a thread of their own: an experiment's curves start when its
        # stationary run is in, not when the theory thread is done with what it was doing
        # (the quick paper: work's curves waited 18 s behind two bandwidth terms); their
        # heavy part waits on the theory processes
        curves = Workers(result.phases, "curves", 1)
        mc = monte_carlo_pool()
        procs = theory_processes(result.experiments, n_procs)
        try:
            _schedule(result, opts, hooks or StudyHooks(), pool, circuit, family, mc, page=page,
                      processes=procs, curves=curves)
            return result
        except BaseException:
            # an interrupt (failures are caught in _schedule): nothing new starts in either
            # pool, then every ngspice process is killed until their threads end
            if procs is not None:
                procs.close()
            family.close()
            page.close()
            curves.close()
            mc.shutdown(wait=False, cancel_futures=True)
            if decks is not None:
                decks.shutdown(wait=False, cancel_futures=True)
            circuit.abort()
            family.abort()
            page.abort()
            raise
        finally:
            circuit.close()
            family.close()
            page.close()
            pool.close()
            curves.close()
            mc.shutdown(wait=False, cancel_futures=True)
            if procs is not None:
                procs.close()
            if decks is not None:
                decks.shutdown(wait=False, cancel_futures=True)


def _schedule(result: StudyResult, opts: RunOptions, hooks: StudyHooks, pool: Workers,
              circuit: Workers, family: Workers, mc=None, page: Workers | None = None,
              processes: TheoryProcesses | None = None,
              curves: Workers | None = None) -> None:
    """The schedule (issue 10: the paper's chapters first, every core busy):

    - circuit runs longest first: the longest experiment's runs finish early, and its long
      analysis (comparisons, the work densities of its theory curves) overlaps the other
      experiments' runs instead of trailing after them (measured on the quick paper: work's
      runs queued behind slip ended at 73 s, its comparisons and curves at 90 s);
    - the theory thread takes the experiments in the same order: each experiment's exact
      theory, then its bandwidth term (held/white Monte Carlo pairs: no circuit data), so
      that both are ready when its runs are; the hooks' background tasks last; the
      bandwidth terms' Monte Carlo chunks run on the threads of ``mc`` (every core);
    - the family members' circuit work starts once the paper's circuit runs are done (the
      cores ngspice used are free), beside the paper's last comparisons and figures, and so
      does the page's own (the hooks' :meth:`~StudyHooks.circuit_background`: the sweep
      curves, which waited for the paper's chapters before, 93 s on the critical path of
      the quick paper).

    Its phases, in the order they start, are the methods of :class:`_Schedule`."""
    plan = _Schedule(result, opts, hooks, pool, circuit, family, processes, curves)
    plan.submit_theory(mc)
    plan.submit_runs()
    plan.submit_members()
    if page is not None:
        plan.submit_page_circuit(page)
    plan.compare_as_runs_complete()
    plan.complete_paper()
    plan.collect_members()


class _Schedule:
    """One study's schedule (:func:`_schedule`): what was submitted to which pool, and the
    phases that submit and collect it."""

    def __init__(self, result: StudyResult, opts: RunOptions, hooks: StudyHooks,
                 pool: Workers, circuit: Workers, family: Workers,
                 processes: TheoryProcesses | None = None, curves: Workers | None = None):
        self.result, self.opts, self.hooks = result, opts, hooks
        self.pool, self.circuit, self.family = pool, circuit, family
        # where the theory curves run (their own thread; without one, the theory thread)
        self.curves = curves if curves is not None else pool
        # worker processes for the theory curves' work densities (None: in the theory thread)
        self.processes = processes
        self.experiments = result.experiments
        self.order = sorted(range(len(self.experiments)),
                            key=lambda i: -circuit_cost(self.experiments[i], opts))
        self.theory_f: dict = {}
        self.band_f: dict = {}
        self.background: dict = {}
        self.runs_f: dict = {}
        # experiment -> future of its theory curves, started once its stationary run was in
        # (curves_early; set in its circuit thread before its runs' future is done)
        self.curves_f: dict = {}
        self.members_f: list = [None] * len(result.members)
        # (runs, analysis, future of its theory curves), in the order the runs completed:
        # drawn by the hooks in this thread as soon as their theory curves are in, while the
        # circuit threads run the next experiments
        self.undrawn: list = []

    def submit_theory(self, mc) -> None:
        """The theory thread, longest experiment first: each one's exact theory, then its
        bandwidth term (Monte Carlo chunks on ``mc``); the hooks' background tasks last."""
        for i in self.order:
            exp = self.experiments[i]
            settings = exp.report.for_options(self.opts)
            self.theory_f[i] = self.pool.submit(
                "exact theory", exp.name,
                lambda exp=exp, s=settings: experiment_theory(exp, s, progress=say))
            self.band_f[i] = self.pool.submit(
                "bandwidth term (held/white Monte Carlo)", exp.name,
                lambda exp=exp, s=settings: bandwidth_terms(exp, s, progress=say, executor=mc))
        self.background = {phase: self.pool.submit(phase, None, fn)
                           for phase, fn in self.hooks.background().items()}

    def submit_runs(self) -> None:
        """The paper-model experiments' circuit runs, longest first."""
        # each experiment's decks at its own priority in the study's deck pool, in this
        # order: with a thread per experiment (many cores) the longest one's decks still go
        # first and the others' fill the cores its calibrations and last decks leave idle
        self.runs_f = {}
        for rank, i in enumerate(self.order):
            opts = self.result.options_for(self.opts, PAPER_DECKS + rank * PAPER_RANK_STEP)
            self.runs_f[i] = self.circuit.submit("circuit runs", self.experiments[i].name,
                                                 lambda exp=self.experiments[i], opts=opts, i=i:
                                                 runs_task(exp, opts, self.curves_early(i)))

    def curves_early(self, i: int):
        """Experiment ``i``'s callback for its stationary run (``run_experiment_runs(
        on_stationary=)``): its theory curves need only that run, so they start in the curves
        thread while its other runs (the integration checks, whose decks are the longest: the
        quick work experiment's stationary check 6.4 s, its stationary decks at most 2.7 s)
        still run."""
        def start(partial) -> None:
            self.curves_f[i] = self.curves.submit(
                "theory curves", partial.exp.name,
                lambda: figure_curves(partial, progress=say, processes=self.processes),
                priority=NOW)
        return start

    def submit_members(self) -> None:
        """The members, longest first, once the paper's circuit runs are done, when ngspice
        leaves the cores (issue 22: more cores, less waiting).  Before, they waited for the
        paper's chapters (figures and Fig. 1 drawn): on 2 cores that kept the paper's chapters
        8.5 s shorter (two members' ngspice made the last experiment's figures take 6.3 s of
        wall for ~2.4 CPU-s) but left the cores to the main thread alone for those seconds,
        and on a larger machine all but one idle."""
        members = self.result.members
        opts = self.result.options_for(self.opts, MEMBER_DECKS)
        # after the paper's circuit runs on every machine (schedule.EXPERIMENTS_AT_ONCE_CORES
        # says why not at once on many cores: their Python work takes turns on the GIL)
        after = [*self.runs_f.values()]
        for j in sorted(range(len(members)), key=lambda j: -member_cost(members[j])):
            self.members_f[j] = self.family.submit_after(
                after, "family member (circuit and theory)",
                members[j].name, lambda exp=members[j]: member_task(exp, opts))

    def submit_page_circuit(self, page: Workers) -> None:
        """The hooks' circuit work (:meth:`StudyHooks.circuit_background`), queued on
        ``page`` like the members (its decks in the study's deck pool at
        :data:`~analogue.study.schedule.SWEEP_DECKS`: the hook asks
        :meth:`StudyResult.options_for`); its futures join
        the background tasks handed to :meth:`StudyHooks.background_ready`."""
        # (as the members: once the paper's circuit runs are done)
        after = [*self.runs_f.values()]
        for phase, fn in self.hooks.circuit_background(self.result).items():
            self.background[phase] = page.submit_after(after, phase, None, fn)

    def draw_ready(self, block: bool) -> None:
        """Hand the hooks every experiment whose theory curves are in (all: ``block``), in
        order, and every finished background task."""
        phases, undrawn, background = self.result.phases, self.undrawn, self.background
        while undrawn and (block or undrawn[0][2].done()):
            runs, a, f = undrawn.pop(0)
            with phases("waiting for theory curves", runs.exp.name):
                a.curves = _curves_of(f)
            if a.curves.timing:
                self.result.curves_timing[runs.exp.name] = a.curves.timing
            self.hooks.experiment_ready(self.result, runs, a)
        for phase, f in list(background.items()):
            if block or f.done():
                del background[phase]
                self.hooks.background_ready(self.result, phase, f)

    def next_done(self) -> int:
        """The next experiment whose runs are done (the runs' order among those done at
        once), drawing what is ready while none is."""
        runs_f = self.runs_f
        while True:
            done = [i for i in self.order if i in runs_f and runs_f[i].done()]
            if done:
                return done[0]
            self.draw_ready(block=False)
            waits = list(runs_f.values())
            if self.undrawn:
                waits.append(self.undrawn[0][2])
            waits.extend(self.background.values())
            with self.result.phases("waiting for circuit runs"):
                while not wait(waits, timeout=POLL_S, return_when=FIRST_COMPLETED).done:
                    pass  # (polled: see result_of)

    def compare_as_runs_complete(self) -> None:
        """Each experiment compared with theory in the order its runs complete (the result
        keeps the given order); a failed run or comparison is recorded, never raised."""
        runs_by_index: dict = {}
        analyses_by_index: dict = {}
        while self.runs_f:
            i = self.next_done()
            got = self.compare(i)
            if got is not None:
                runs_by_index[i], analyses_by_index[i] = got
        for i in sorted(runs_by_index):
            self.result.runs[self.experiments[i].name] = runs_by_index[i]
            self.result.analyses[self.experiments[i].name] = analyses_by_index[i]

    def compare(self, i: int) -> tuple[ExperimentRuns, ExperimentAnalysis] | None:
        """Experiment ``i``'s runs (done) against its theory; its data-dependent theory
        curves (work densities on the circuit's bins...) start in the background meanwhile,
        beside the next experiment's circuit runs.  None when its runs or its comparison
        failed (recorded)."""
        result, phases, fails = self.result, self.result.phases, self.result.failures
        exp, run_f = self.experiments[i], self.runs_f.pop(i)
        th_f, bw_f = self.theory_f[i], self.band_f[i]
        section = experiment_section_title(exp)
        runs, err = fails.attempt(section, "circuit runs", lambda f=run_f: result_of(f), exp.name)
        early = self.curves_f.pop(i, None)
        if runs is None:
            th_f.cancel()
            bw_f.cancel()
            if early is not None:
                early.cancel()
            result.failed[exp.name] = err
            return None
        # its curves, unless they started with its stationary run (curves_early)
        cf = early if early is not None else self.curves.submit(
            "theory curves", exp.name, lambda runs=runs: figure_curves(runs, progress=say,
                                                     processes=self.processes),
            priority=NOW)
        say(f"{exp.name}: comparing with theory")

        def compare_(runs=runs, th_f=th_f, bw_f=bw_f):
            with phases("waiting for theory", runs.exp.name):
                theory: ExperimentTheory = result_of(th_f)
                bandwidth: BandwidthTerms = result_of(bw_f)
            result.bandwidth_timing[runs.exp.name] = bandwidth.timing
            with phases("comparisons", runs.exp.name):
                return analyse(runs, theory=theory, bandwidth=bandwidth, progress=say)
        analysis, err = fails.attempt(section, "comparison with theory", compare_, exp.name)
        if analysis is None:
            cf.cancel()
            result.failed[exp.name] = err
            return None
        self.undrawn.append((runs, analysis, cf))
        self.hooks.experiment_compared(result, runs, analysis)
        return runs, analysis

    def complete_paper(self) -> None:
        """The paper's chapters are complete once their figures are drawn."""
        self.draw_ready(block=True)
        self.hooks.main_complete(self.result)
        self.result.paper_wall = time.perf_counter() - self.result.t0

    def collect_members(self) -> None:
        """The members' analyses, in the given order (a failure recorded), and their own
        time: their analyses (in a circuit thread, beside the paper's comparisons); the page
        adds its figures.  Each member is handed to :meth:`StudyHooks.member_ready` as it
        completes (its figures drawn while the others run, not all at the end)."""
        result, phases, fails = self.result, self.result.phases, self.result.failures
        pending = {j: f for j, f in enumerate(self.members_f) if f is not None}
        while pending:
            first = min(pending)
            with phases("waiting for family members", result.members[first].name):
                while not wait(list(pending.values()), timeout=POLL_S,
                               return_when=FIRST_COMPLETED).done:
                    pass  # (polled: see result_of)
            for j in sorted(j for j, f in pending.items() if f.done()):
                f = pending.pop(j)
                if not f.cancelled() and f.exception() is None:
                    self.hooks.member_ready(result, result.members[j], f.result())
        for exp, ma_f in zip(result.members, self.members_f):
            ma, err = fails.attempt(experiment_section_title(exp), "member analysis",
                                    ma_f.result, exp.name)
            if ma is None:
                result.failed[exp.name] = err
            else:
                result.member_analyses[exp.name] = ma
        result.member_wall = sum(p["seconds"] for p in phases.items
                                 if p["phase"] == "family member (circuit and theory)")


# ------------------------------------------------------------------------ runs alone
@dataclass
class RunSummary:
    runs: ExperimentRuns

    def summary(self) -> str:
        p = self.runs.provenance()
        reps = ", ".join(f"{k}: {v}" for k, v in p["replicas"].items())
        return (f"{p['experiment']}: runs stored ({reps}); ngspice {p['ngspice_version']}; "
                f"{p['wall_time_s']:.1f} s")


@dataclass
class MemberRunSummary:
    """The circuit runs of a family member (:func:`analogue.study.members.member_runs`): the
    very runs ``analogue report`` reads for it (same decks and seeds, from the store)."""

    runs: MemberRuns
    wall_time: float

    def summary(self) -> str:
        runs = self.runs.by_role()
        reps = ", ".join(f"{role}: {e.replicas} x {float(e.t[-1] - e.t[0]):g}"
                         for role, e in runs.items())
        version = next(iter(runs.values())).meta.get("ngspice_version")
        name, quick = self.runs.exp.name, self.runs.quick
        return (f"{name}: runs stored ({reps}; the {'quick' if quick else 'full'} size of "
                f"'analogue report {name}'); ngspice {version}; {self.wall_time:.1f} s")


def run_experiment(name, opts: RunOptions) -> RunSummary | MemberRunSummary:
    """Run (or load from the store) every circuit run of one experiment: a paper-model
    experiment's runs (:func:`analogue.study.runs.run_experiment_runs`), or a family
    member's (:func:`analogue.study.members.member_runs`: the runs its report reads)."""
    exp = load(name)
    say(f"{exp.name}: running the circuit (stored runs are reused)")
    if is_member_experiment(exp):
        t0 = time.perf_counter()
        runs = member_runs(exp, opts, progress=say)
        return MemberRunSummary(runs, time.perf_counter() - t0)
    return RunSummary(run_experiment_runs(exp, opts))
