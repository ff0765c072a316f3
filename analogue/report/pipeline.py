"""From experiments to a report directory: ``index.html`` (self-contained), PNGs, ``metrics.json``.

``build_paper_report`` is the main job (``analogue paper``): the paper's experiments
(:data:`analogue.circuit.experiments.PAPER_EXPERIMENTS`, the standard circuits shipped with
the package, never the user's files), the paper's Figs. 1-9 with circuit data, the paper's open
question settled by exact numerics, and every circuit-versus-theory comparison with its error
budget.  ``build_experiment_report`` (``analogue report``) does the same for one experiment of
the user's.

Every experiment is loaded (and so validated) before anything runs.  After that, a section
whose work fails (a circuit run, an analysis, a figure) never throws away the sections that
finished: it is written as a failed section with its error, ``metrics.json`` lists it under
``failures``, and :class:`ReportIncomplete` is raised once the page is written.
"""
from __future__ import annotations

import json
import logging
import os
import platform
import threading
import time
import traceback
from concurrent.futures import FIRST_COMPLETED, Future, wait
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..files import write_text
from ..circuit.experiments import (FIG1_EXPERIMENTS,
                                   PAPER_EXPERIMENTS, PAPER_FIGURE_TAGS, Experiment,
                                   load_experiment, standard_circuit)
from . import figures, prose
from ..study.budget import terms_above_se_text
from ..study.critical_path import critical_path_text, report_critical_path
from ..study.comparisons import BandwidthTerms, ExperimentAnalysis, analyse, bandwidth_terms
from ..study.theory_curves import ExperimentTheory, experiment_theory, figure_curves
from .html import Figure, Section, Table, write_page
from ..study.metrics import validate_metrics
from .plan import RunOptions
from ..study.runs import ExperimentRuns, run_experiment_runs
from ..circuit.simulate import POLL_S

if TYPE_CHECKING:   # beyond is imported where it is used (start-up time)
    from .beyond import MemberRuns

__all__ = ["RunOptions", "run_experiment", "build_experiment_report", "build_paper_report",
           "build_report", "RunSummary", "ReportIncomplete", "experiment_section_text"]


class ReportIncomplete(RuntimeError):
    """The report was written, but some of its sections failed (each is in the page with its
    error, and in metrics.json under ``failures``)."""

    def __init__(self, index: Path, failures: list):
        self.index, self.failures = index, failures
        what = "; ".join(f"{f['section']}: {f['error']}" for f in failures)
        super().__init__(f"report written to {index} with {len(failures)} failed "
                         f"section(s): {what}")


def _error_text(exc: BaseException) -> str:
    msg = " | ".join(ln.strip() for ln in str(exc).splitlines() if ln.strip())
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


class _Failures:
    """Runs one piece of a report; a failure is recorded (section, stage, error), not raised."""

    def __init__(self):
        self.items: list[dict] = []

    def attempt(self, section: str, stage: str, fn, experiment: str | None = None):
        try:
            return fn(), None
        except (KeyboardInterrupt, SystemExit):
            raise
        except Exception as exc:  # any failure of one section is reported
            if os.environ.get("ANALOGUE_DEBUG"):
                traceback.print_exc()
            err = _error_text(exc)
            self.items.append({"section": section, "experiment": experiment, "stage": stage,
                               "error": err})
            _log(f"{section}: FAILED ({stage}): {err}")
            return None, err


log = logging.getLogger(__name__)


def _result(f: Future):
    """``f.result()``, waited for in polls of ``POLL_S``: a wait without a timeout is not
    woken by a signal the kernel delivered to another thread, so the main thread's handler
    (RunInterrupted) would wait for the task (issue 19: under load a SIGTERM to ``analogue
    run`` once went unanswered for more than 10 s)."""
    while True:
        try:
            return f.result(timeout=POLL_S)
        except TimeoutError:
            if f.done():
                raise  # the task's own TimeoutError


def _log(msg: str) -> None:
    """Progress of the report job, on the ``analogue.report.pipeline`` logger (the command line
    shows it on stderr with the time since the command started: see analogue.cli).  A task
    still running in a background thread after its report ended (a daemon thread finishing
    its numerics) says nothing more: in one process, the next command's output (an
    in-process ``analogue theory --json`` after a failed report) got its progress lines."""
    if getattr(threading.current_thread(), "analogue_report_closed", False):
        return
    log.info(msg)


class _Phases:
    """Wall time per phase of a report (logged, and recorded in the provenance).  Phases in
    the theory thread overlap with the circuit runs, so the phases sum to more than the wall
    time when the overlap works."""

    def __init__(self, origin: float | None = None):
        self.items: list[dict] = []
        self.origin = time.perf_counter() if origin is None else origin

    @contextmanager
    def __call__(self, phase: str, experiment: str | None = None, thread: str = "main"):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            dt = time.perf_counter() - t0
            self.items.append({"phase": phase, "experiment": experiment, "thread": thread,
                               "start_s": round(t0 - self.origin, 3), "seconds": round(dt, 3)})
            _log(f"phase done: {phase}{f' ({experiment})' if experiment else ''} "
                 f"[{thread}]: {dt:.1f} s")

    def totals(self) -> dict:
        out: dict = {}
        for it in self.items:
            out[it["phase"]] = round(out.get(it["phase"], 0.0) + it["seconds"], 3)
        return out


@dataclass
class RunSummary:
    runs: ExperimentRuns

    def summary(self) -> str:
        p = self.runs.provenance()
        reps = ", ".join(f"{k}: {v}" for k, v in p["replicas"].items())
        return (f"{p['experiment']}: runs stored ({reps}); ngspice {p['ngspice_version']}; "
                f"{p['wall_time_s']:.1f} s")


def _load(name_or_exp) -> Experiment:
    return name_or_exp if isinstance(name_or_exp, Experiment) else load_experiment(name_or_exp)


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
    from . import beyond
    exp = _load(name)
    _log(f"{exp.name}: running the circuit (stored runs are reused)")
    if beyond.is_member_experiment(exp):
        t0 = time.perf_counter()
        runs = beyond.member_runs(exp, opts, progress=_log)
        return MemberRunSummary(runs, time.perf_counter() - t0)
    return RunSummary(run_experiment_runs(exp, opts))


def build_experiment_report(name, out, opts: RunOptions) -> Path:
    """The report of one experiment (a name or a TOML path: the user's)."""
    exp = _load(name)
    return build_report([exp], Path(out), opts, title=f"analogue report: experiment {exp.name}")


def _board_link(out: Path, experiments=()):
    """The intro's pointer to the buildable board of the stick experiment (issue 13), in the
    paper's report: :func:`analogue.report.prose.board_link`."""
    return prose.board_link(out, experiments)


def build_paper_report(out, opts: RunOptions) -> Path:
    """The paper's experiments (:data:`PAPER_EXPERIMENTS`, standard circuits), then the
    chapter "Beyond the paper" (one experiment per extension, :mod:`.beyond`, quick sizes)."""
    from .beyond import MEMBERS
    return build_report([standard_circuit(n) for n in PAPER_EXPERIMENTS], Path(out), opts,
                        title="Stick-slip friction with noise: the paper on an analogue circuit",
                        chapter=[standard_circuit(n) for n in MEMBERS])


def experiment_section_text(exp: Experiment) -> list[str]:
    """Paragraphs of an experiment's section: its description (the user's text, escaped by
    the page template like every other text), a note where the description's numbers are not
    the model's, and the model's parameters (:func:`analogue.report.prose.experiment_paragraphs`)."""
    return prose.experiment_paragraphs(exp)


# ------------------------------------------------------------------------------ sections
def _mapping_table(runs) -> Table:
    from ..circuit.mapping import map_model
    m = map_model(runs.exp.model, runs.exp.spec)  # runs: ExperimentRuns or MemberAnalysis
    rows = [[name, float(value), unit, meaning]
            for name, value, unit, meaning in prose.component_rows(m)]
    element = (f"{runs.exp.spec.coulomb}, diode {runs.exp.spec.diode}"
               if m.coulomb_element is not None else "no Coulomb element (Delta = 0)")
    return Table(f"{runs.exp.name}: component values ({element})",
                 ["quantity", "value", "unit", "meaning"], rows, collapsed=True)


def _comparison_table(comps, caption) -> Table:
    rows, classes = [], []
    for c in comps:
        b = c.budget
        rows.append([c.experiment, c.observable, c.theory_kind, c.circuit, c.circuit_stderr,
                     c.theory, c.z, abs(b.smoothing), abs(b.bandwidth), abs(b.integration),
                     abs(b.finite_noise), c.within_budget,
                     c.as_dict()["budget"]["dominant"]])
        classes.append("ok" if c.within_budget else "fail")
    return Table(caption, ["experiment", "observable", "theory", "circuit", "SE", "theory value",
                           "z", "smoothing", "bandwidth", "integration", "finite noise",
                           "within budget", "dominant error"], rows, classes)


def _explain(comps) -> list[str]:
    """Say, for each comparison outside |z| < 3, whether the budget explains it."""
    lines = []
    for c in comps:
        if abs(c.z) < 3:
            continue
        if c.within_budget:
            lines.append(f"{c.experiment} / {c.observable} ({c.theory_kind}): z = {c.z:.1f}, "
                         f"explained by the budget (dominant: {c.as_dict()['budget']['dominant']}).")
        else:
            lines.append(f"{c.experiment} / {c.observable} ({c.theory_kind}): z = {c.z:.1f}, "
                         "NOT explained by the budget: |circuit - theory| = "
                         f"{abs(c.circuit - c.theory):.3g} > 3 SE + systematics = "
                         f"{3 * c.circuit_stderr + c.budget.total():.3g}.")
    return lines


def _software() -> dict:
    import matplotlib
    import scipy
    from .. import __version__
    return {"analogue": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "matplotlib": matplotlib.__version__,
            "platform": platform.platform()}


def _figures_for(runs: ExperimentRuns, analysis: ExperimentAnalysis, out: Path,
                 fails: _Failures, section: str) -> tuple[list, list]:
    """The experiment's figures; one that fails is recorded and the others are kept.
    They only draw: every theory curve is in ``analysis`` (computed once).
    Returns (figures, errors)."""
    items, errors = [], []
    a = analysis
    # the paper's figure number only for the paper's own experiment (a user's file named
    # "stick" is not paper Fig. 2)
    tag = (PAPER_FIGURE_TAGS.get(runs.exp.name, "paths") if prose.is_paper_experiment(runs.exp)
           else "paths")
    for what, fn in (
            ("prehistory", lambda: figures.fig_prehistory(a, out, tag)),
            ("boundaries", lambda: figures.fig_boundaries(runs, out)),
            ("propagator", lambda: figures.fig_propagator(a, out)),
            ("propagator", lambda: figures.fig_propagator(a, out, runs.exp.v0[-1])
             if len(runs.exp.v0) > 1 else None),
            ("stationary law", lambda: figures.fig_stationary(a, out)),
            ("work paths", lambda: figures.fig_work_paths(a, out)),
            ("rate function", lambda: figures.fig_rate_function(a, out)),
            ("error budget", lambda: figures.fig_budget(a, out))):
        _log(f"{runs.exp.name}: figure: {what}")
        r, err = fails.attempt(section, f"figure: {what}", fn, runs.exp.name)
        if err is not None:
            errors.append(f"figure '{what}': {err}")
        elif r is not None:
            items.append(Figure(*r))
    return items, errors


def _open_question_gammas(opts: RunOptions) -> tuple:
    return (10.0, 100.0) if opts.quick else (10.0, 100.0, 1000.0)


def _open_question_data(opts: RunOptions) -> dict:
    """The exact curves of the open question (no circuit data: computed while ngspice runs)."""
    from ..plots.open_question import CASES, open_question_data
    return {(a, half): open_question_data(a, half, gammas=_open_question_gammas(opts))
            for a, half in CASES}


def _open_question_section(out: Path, opts: RunOptions, data=None) -> Section:
    """``data``: the exact curves (:func:`_open_question_data`), or a Future of them (computed
    while ngspice ran), or None (computed here)."""
    from ..plots.open_question import draw_open_question
    gammas = _open_question_gammas(opts)
    if isinstance(data, Future):
        data = _result(data)
    paths = draw_open_question(out, gammas=gammas, data=data)
    text = [
        "The paper finds a jump of the rate function I(w) at w = 0 (eq. (64)) and cannot tell "
        "whether it is real. The exact rate function at finite noise, I_gamma(w) = "
        "sup_k [k w - lambda(k)] / gamma with lambda the principal eigenvalue of the tilted "
        "Fokker-Planck generator, answers it: I_gamma is convex and continuous for every gamma, "
        "and as gamma grows it converges to the lower convex envelope of the cost of holding a "
        "constant velocity w/(m a) - where holding v = 0 costs max(|a| - Delta, 0)^2/4, i.e. "
        "nothing when the object can stick. Near w = 0 the optimal histories share their time "
        "between sticking and sliding, which makes the limit linear there: the jump is an "
        "artefact of restricting the paths to one constant velocity, and the fluctuation "
        "relation of eq. (68) has no jump either. The tests check the convergence "
        "(tests/unit/test_open_question.py)."]
    gs = ", ".join(f"{g:g}" for g in gammas)
    caps = [f"Exact I_gamma(w) for gamma = {gs} against the paper's I(w) (eq. (64)) and the "
            "gamma -> infinity limit (convex envelope).",
            f"The fluctuation relation I(-w) - I(w): exact at gamma = {gs}, the paper's eq. (67) "
            "with its jump 2 a Delta, and the limit."]
    return Section("The paper's open question: is the jump of I(w) at w = 0 real?", text,
                   figures=[Figure(p, caps[i] if i < len(caps) else "") for i, p in enumerate(paths)])


class _Workers:
    """Background threads that run tasks in submission order, each as a phase of the report
    (issue 10, item 4: keep every core busy from start to end).

    - the **theory** thread (one): the theory needs no circuit data, so it runs while ngspice
      runs; BLAS/LAPACK are limited to one thread while a task runs (threadpoolctl), so it adds
      one runnable thread, not one per core;
    - the **circuit** thread (one): every experiment's circuit runs, queued from the start
      (longest first), so that ngspice never waits for the main thread's comparisons of the
      previous experiment.  One thread: an experiment's runs keep ``workers`` ngspice
      processes busy on their own (one deck pool for all its runs, study.runs), and the
      theory thread fills the last deck's idle core.  With two threads the experiments
      shared the cores, so the longest one (work, queued first) ended last anyway, at 108 s
      of the quick paper, and its theory curves trailed after it;
    - the **members** threads: the family members' analyses (circuit and theory), queued
      once the paper's chapters are complete (:meth:`submit_after`).  Two threads: a member's runs are
      few decks, which alone leave a core idle.

    The threads are daemons: an interrupt does not wait for a task under way (see
    :meth:`abort`)."""

    def __init__(self, phases: _Phases, name: str, threads: int = 1, blas_limit: bool = False):
        import queue
        self.phases, self.name, self.blas_limit = phases, name, blas_limit
        self.queue: queue.Queue = queue.Queue()
        self._lock = threading.Lock()
        self._closed = False
        self.threads = [threading.Thread(target=self._run, daemon=True,
                                         name=f"analogue-{name}" + (f"-{i}" if threads > 1 else ""))
                        for i in range(threads)]
        for t in self.threads:
            t.start()

    def _run(self):
        from contextlib import nullcontext

        from threadpoolctl import threadpool_limits
        while True:
            item = self.queue.get()
            if item is None:
                return
            fut, phase, experiment, fn = item
            if not fut.set_running_or_notify_cancel():
                continue
            try:
                # the limit is process-wide (OpenBLAS has one pool): held only while a theory
                # task runs, so the main thread's own theory (the family chapter) gets both
                # cores once the background work is done
                with (threadpool_limits(1) if self.blas_limit else nullcontext()), \
                        self.phases(phase, experiment, thread=self.name):
                    fut.set_result(fn())
            except BaseException as exc:  # handed to whoever waits for the result
                fut.set_exception(exc)

    def submit(self, phase: str, experiment: str | None, fn) -> Future:
        fut: Future = Future()
        self._put((fut, phase, experiment, fn))
        return fut

    def _put(self, item) -> None:
        with self._lock:   # nothing is queued behind close()'s end markers: cancelled instead
            if self._closed:
                item[0].cancel()
            else:
                self.queue.put(item)

    def submit_after(self, after: list, phase: str, experiment: str | None, fn) -> Future:
        """Like :meth:`submit`, but queued only once every future in ``after`` is done
        (a result, an error or cancelled): the family members' circuit work waits for the
        paper's circuit runs, so that they never share the cores with them."""
        fut: Future = Future()
        left = [len(after)]
        lock = threading.Lock()

        def one_done(_f) -> None:
            with lock:
                left[0] -= 1
                go = left[0] == 0
            if go:
                self._put((fut, phase, experiment, fn))
        if not after:
            self._put((fut, phase, experiment, fn))
        for f in after:
            f.add_done_callback(one_done)
        return fut

    def _cancel_pending(self) -> None:
        import queue
        while True:               # whatever has not started is cancelled
            try:
                item = self.queue.get_nowait()
            except queue.Empty:
                break
            if item is not None:
                item[0].cancel()

    def close(self) -> None:
        for t in self.threads:
            t.analogue_report_closed = True  # type: ignore[attr-defined]  # read by _log
        with self._lock:
            self._closed = True
            self._cancel_pending()
            for _ in self.threads:
                self.queue.put(None)

    def abort(self, wait: float = 10.0) -> None:
        """After an interrupt: nothing new starts, and the ngspice processes of the tasks under
        way are killed (again and again: a task whose deck was killed may start its next one)
        until their threads end or ``wait`` seconds have passed; a task in pure numerics is
        left to the daemon thread.  Its temporary directories are removed as it unwinds."""
        from ..circuit.ngspice import terminate_all
        self.close()
        deadline = time.monotonic() + wait
        while any(t.is_alive() for t in self.threads) and time.monotonic() < deadline:
            terminate_all()
            for t in self.threads:
                t.join(0.05)
        terminate_all()


# the threads of the paper's circuit runs and of the family members' analyses (see
# _Workers): each simulate call runs up to `workers` ngspice processes.  With a Dask
# scheduler an experiment's runs go to the cluster one after another (study.runs._run_jobs)
# and the local cores are not the limit: two experiments at once keep more of it busy.
CIRCUIT_THREADS = 1
SCHEDULER_CIRCUIT_THREADS = 2
MEMBER_THREADS = 2


def _wants_open_question(experiments) -> bool:
    """The paper's open question (its own parameters) belongs to reports of the paper's
    experiments, not to a report of the user's own files (issue 20 item 3)."""
    return any(prose.is_paper_experiment(e) for e in experiments)


def build_report(names, out: Path, opts: RunOptions, title: str, chapter=()) -> Path:
    """Run and analyse the experiments ``names`` (names, TOML paths or Experiment objects) and
    write the report into ``out``.  Family members among them (and the experiments of
    ``chapter``, written as the chapter "Beyond the paper" after the paper's sections) are
    analysed by :mod:`.beyond`.  Raises :class:`ReportIncomplete` after writing the page
    when some section failed."""
    from . import beyond
    t0 = time.perf_counter()
    load0 = os.getloadavg()
    out = Path(out)
    # every experiment is validated before anything runs (bad input: nothing started yet)
    experiments = [_load(n) for n in names]
    members = [e for e in experiments if beyond.is_member_experiment(e)] + [_load(n) for n in chapter]
    experiments = [e for e in experiments if not beyond.is_member_experiment(e)]
    out.mkdir(parents=True, exist_ok=True)
    fails = _Failures()
    phases = _Phases(origin=t0)
    # ngspice runs in the circuit threads: this (main) thread's guard turns SIGINT/SIGTERM/
    # SIGHUP into RunInterrupted here (killing every ngspice group), whoever called us
    from ..circuit.ngspice import interrupt_guard
    with interrupt_guard():
        pool = _Workers(phases, "theory", 1, blas_limit=True)
        circuit = _Workers(phases, "circuit",
                           SCHEDULER_CIRCUIT_THREADS if opts.scheduler else CIRCUIT_THREADS)
        family = _Workers(phases, "members", MEMBER_THREADS)
        try:
            return _build(experiments, members, out, opts, title, fails, phases, pool, circuit,
                          family, t0, load0)
        except BaseException:
            # an interrupt (sections' failures are caught in _build): nothing new starts in
            # either pool, then every ngspice process is killed until their threads end
            family.close()
            circuit.abort()
            family.abort()
            raise
        finally:
            circuit.close()
            family.close()
            pool.close()


def _experiment_title(exp) -> str:
    return f"Experiment '{exp.name}': {exp.model.regime} regime"


def _curves_of(f: Future):
    """An experiment's theory curves from the theory thread."""
    try:
        return _result(f)
    except Exception as exc:  # figure_curves keeps its failures; this is a safety net
        from ..study.theory_curves import CURVE_GROUPS, FigureCurves
        curves = FigureCurves()
        for g in CURVE_GROUPS:
            curves.fail(g, exc)
        return curves


def _member_task(exp, opts):
    from . import beyond
    _log(f"{exp.name}: family member: circuit against theory")
    return beyond.analyse_member(exp, opts, progress=_log)


def _runs_task(exp, opts):
    _log(f"{exp.name}: circuit runs ({'quick' if opts.quick else 'full'} size; stored runs are "
         "reused)")
    return run_experiment_runs(exp, opts)


def _circuit_cost(exp: Experiment, opts: RunOptions) -> float:
    """A proxy for an experiment's ngspice time: its replica-time (replicas x model time of
    the transition and stationary runs; the integration checks scale with them).  Only its
    order matters: the paper's work experiment (7600 replica-time units at --quick, against
    5600 for stick and slip) took 58 s of circuit runs, stick 30 s, slip 15 s."""
    settings = exp.report.for_options(opts)
    return (len(exp.v0) * opts.scaled(exp.replicas) * exp.t_end
            + settings.stationary_replicas * settings.stationary_t_end)


def _build(experiments, members, out, opts, title, fails, phases, pool, circuit, family, t0,
           load0) -> Path:
    from . import beyond
    # The schedule (issue 10: the paper's chapters first, every core busy):
    # - circuit runs longest first: the longest experiment's runs finish early, and its long
    #   analysis (comparisons, the work densities of its theory curves) overlaps the other
    #   experiments' runs instead of trailing after them (measured on the quick paper: work's
    #   runs queued behind slip ended at 73 s, its comparisons and curves at 90 s);
    # - the theory thread takes the experiments in the same order: each experiment's exact
    #   theory, then its bandwidth term (held/white Monte Carlo pairs: no circuit data), so
    #   that both are ready when its runs are; the open question last (only drawn);
    # - the family members' circuit work waits until the paper's chapters are complete
    #   (every paper run compared, every figure drawn), then has both cores.
    order = sorted(range(len(experiments)), key=lambda i: -_circuit_cost(experiments[i], opts))
    theory_f: dict = {}
    band_f: dict = {}
    for i in order:
        exp = experiments[i]
        settings = exp.report.for_options(opts)
        theory_f[i] = pool.submit("exact theory", exp.name,
                                  lambda exp=exp, s=settings: experiment_theory(exp, s,
                                                                                progress=_log))
        band_f[i] = pool.submit("bandwidth term (held/white Monte Carlo)", exp.name,
                                lambda exp=exp, s=settings: bandwidth_terms(exp, s,
                                                                            progress=_log))
    oq_f = (pool.submit("open question (exact rate functions)", None,
                        lambda: _open_question_data(opts))
            if _wants_open_question(experiments) else None)
    runs_f = {i: circuit.submit("circuit runs", experiments[i].name,
                                lambda exp=experiments[i]: _runs_task(exp, opts))
              for i in order}
    # the members start once the paper's chapters are complete (runs compared, figures and
    # Fig. 1 drawn), not when the paper's runs are: measured on the quick paper, two members'
    # ngspice beside the last experiment's figures made those take 6.3 s of wall time for
    # ~2.4 CPU-s, and the paper's chapters ended 8.5 s after its last run
    paper_done: Future = Future()
    members_f = [family.submit_after([*runs_f.values(), paper_done],
                                      "family member (circuit and theory)", exp.name,
                                      lambda exp=exp: _member_task(exp, opts))
                 for exp in members]
    runs_by_index: dict = {}
    analyses_by_index: dict = {}
    exp_sections: dict = {}
    # Figures are drawn in this thread as soon as an experiment's theory curves are in, while
    # the circuit threads run the next experiments (measured: the figures and page took 17 s
    # after everything else had finished)
    figs_by_name: dict = {}     # experiment -> (figures, errors)
    undrawn: list = []          # (runs, analysis, future of its theory curves), in order
    oq_section: list = []       # the open question's section, once drawn

    def draw_ready(block: bool) -> None:
        while undrawn and (block or undrawn[0][2].done()):
            runs, a, f = undrawn.pop(0)
            with phases("waiting for theory curves", runs.exp.name):
                a.curves = _curves_of(f)
            with phases("figures", runs.exp.name):
                figs_by_name[runs.exp.name] = _figures_for(
                    runs, a, out, fails, _experiment_title(runs.exp))
        if oq_f is not None and not oq_section and (block or oq_f.done()):
            _log("the paper's open question: exact rate functions at several gamma")
            title_ = "The paper's open question: is the jump of I(w) at w = 0 real?"
            with phases("figures: open question"):
                sec, err = fails.attempt(title_, "exact rate functions",
                                         lambda: _open_question_section(out, opts, oq_f))
            oq_section.append(sec if sec is not None else Section(title_, error=err))

    def next_done() -> int:
        """The next experiment whose runs are done (the runs' order among those done at
        once), drawing the figures whose curves are in while none is."""
        while True:
            done = [i for i in order if i in runs_f and runs_f[i].done()]
            if done:
                return done[0]
            draw_ready(block=False)
            waits = list(runs_f.values())
            if undrawn:
                waits.append(undrawn[0][2])
            if oq_f is not None and not oq_section:
                waits.append(oq_f)
            with phases("waiting for circuit runs"):
                while not wait(waits, timeout=POLL_S, return_when=FIRST_COMPLETED).done:
                    pass  # (polled: see _result)

    # the experiments are compared in the order their runs complete (the page keeps the
    # paper's order)
    while runs_f:
        i = next_done()
        exp, run_f, th_f, bw_f = experiments[i], runs_f.pop(i), theory_f[i], band_f[i]
        section = f"Experiment '{exp.name}'"
        runs, err = fails.attempt(section, "circuit runs", lambda f=run_f: _result(f), exp.name)
        if runs is None:
            th_f.cancel()
            bw_f.cancel()
            exp_sections[exp.name] = Section(f"{section}: failed", experiment_section_text(exp),
                                             error=err)
            continue
        # the data-dependent theory curves (work densities on the circuit's bins...) run in the
        # background while this experiment's comparisons and the next one's circuit run
        cf = pool.submit("theory curves", exp.name,
                         lambda runs=runs: figure_curves(runs, progress=_log))
        _log(f"{exp.name}: comparing with theory")

        def compare_(runs=runs, th_f=th_f, bw_f=bw_f):
            with phases("waiting for theory", runs.exp.name):
                theory: ExperimentTheory = _result(th_f)
                bandwidth: BandwidthTerms = _result(bw_f)
            with phases("comparisons", runs.exp.name):
                return analyse(runs, theory=theory, bandwidth=bandwidth, progress=_log)
        analysis, err = fails.attempt(section, "comparison with theory", compare_, exp.name)
        if analysis is None:
            cf.cancel()
            exp_sections[exp.name] = Section(f"{section}: failed", experiment_section_text(exp),
                                             error=err)
            continue
        runs_by_index[i] = runs
        analyses_by_index[i] = analysis
        undrawn.append((runs, analysis, cf))
    all_runs = [runs_by_index[i] for i in sorted(runs_by_index)]
    analyses = [analyses_by_index[i] for i in sorted(analyses_by_index)]

    # the paper's chapters are complete once their figures (and Fig. 1) are drawn
    draw_ready(block=True)
    fig1_section = None
    if all_runs:
        fig1_runs = [r for r in all_runs if r.exp.name in FIG1_EXPERIMENTS
                     and prose.is_paper_experiment(r.exp)] or all_runs
        with phases("figures: Fig. 1"):
            fig, err = fails.attempt("Paper Fig. 1: deterministic motion", "figure",
                                     lambda: Figure(*figures.fig_deterministic(fig1_runs, out)))
        fig1_section = Section("Paper Fig. 1: deterministic motion",
                               figures=[fig] if fig is not None else [], error=err)
    paper_wall = time.perf_counter() - t0
    _log(f"{prose.main_part(experiments)} are complete ({paper_wall:.0f} s)")
    paper_done.set_result(None)

    member_analyses = []
    for exp, ma_f in zip(members, members_f):
        section = f"{beyond.CHAPTER_TITLE}: {exp.name}"
        with phases("waiting for family members", exp.name):
            ma, err = fails.attempt(section, "member analysis", ma_f.result, exp.name)
        if ma is None:
            exp_sections[exp.name] = Section(f"{section}: failed", experiment_section_text(exp),
                                             error=err)
        else:
            member_analyses.append(ma)
    # the chapter's own time: its members' analyses (in a circuit thread, beside the paper's
    # comparisons) and, below, its figures
    member_wall = sum(p["seconds"] for p in phases.items
                      if p["phase"] == "family member (circuit and theory)")

    _log("drawing figures")
    draw0 = time.perf_counter()
    sections = []
    comps = [c for a in analyses + member_analyses for c in a.comparisons]
    n_ok = sum(c.within_budget for c in comps)
    n_z = sum(abs(c.z) < 3 for c in comps)
    summary_rows = []
    for a in analyses + member_analyses:
        s = a.summary()
        ex = [c for c in a.comparisons if c.theory_kind == "exact"]
        summary_rows.append([a.exp.name if hasattr(a, "exp") else a.runs.exp.name, s["comparisons"], s["abs_z_below_3"], s["within_budget"],
                             sum(abs(c.z) < 3 for c in ex), len(ex)])
    failed_names = [f["experiment"] for f in fails.items if f["experiment"]]
    summary_text = [
        f"{len(comps)} comparisons of circuit estimates with theory: {n_z} have |z| < 3 and "
        f"{n_ok} lie within their error budget (3 standard errors plus the independently "
        "estimated systematic errors). " + prose.theory_kinds_text(experiments, members)]
    if failed_names:
        summary_text.append("Failed (see their sections): " + ", ".join(failed_names) + ".")
    sections.append(Section("Summary", summary_text + _explain(comps)
                            + terms_above_se_text(comps),
        tables=[Table("Per experiment", ["experiment", "comparisons", "|z| < 3", "within budget",
                                         "exact: |z| < 3", "exact: total"], summary_rows)]))

    circuit_par = [prose.circuit_paragraph([*experiments, *members])]
    tables = []
    for r in all_runs + member_analyses:
        t, _ = fails.attempt("The circuit and its component values", "component table",
                             lambda r=r: _mapping_table(r), r.exp.name)
        if t is not None:
            tables.append(t)
    sections.append(Section("The circuit and its component values", circuit_par, tables=tables))

    if fig1_section is not None:
        sections.append(fig1_section)
    for exp in experiments:
        if exp.name in exp_sections:
            sections.append(exp_sections[exp.name])
            continue
        figs, errs = figs_by_name[exp.name]
        sections.append(Section(_experiment_title(exp), experiment_section_text(exp),
                                figures=figs, error="; ".join(errs) if errs else None))

    sections.extend(oq_section)

    if members:
        t_fig = time.perf_counter()
        chapter_sections = []
        for exp in members:
            if exp.name in exp_sections:
                chapter_sections.append(exp_sections[exp.name])
                continue
            ma = next(a for a in member_analyses if a.exp.name == exp.name)
            title_ = f"{beyond.CHAPTER_TITLE}: {exp.name}"
            chapter_sections.append(beyond.member_section(
                ma, out, lambda what, fn, t=title_, n=exp.name: fails.attempt(t, what, fn, n)))
        member_wall += time.perf_counter() - t_fig
        sections.append(Section(beyond.CHAPTER_TITLE,
                                beyond.chapter_intro(member_analyses, member_wall, opts.quick)))
        sections.extend(chapter_sections)

    sections.append(Section("All comparisons and their error budgets", [
        prose.budget_text([*experiments, *members])],
        tables=[_comparison_table(comps, "Comparisons")]))

    phases.items.append({"phase": "figures and page", "experiment": None, "thread": "main",
                         "start_s": round(draw0 - t0, 3),
                         "seconds": round(time.perf_counter() - draw0, 3)})
    wall = time.perf_counter() - t0
    provs = {r.exp.name: r.provenance() for r in all_runs}
    provs.update({a.exp.name: a.provenance for a in member_analyses})
    software = _software()
    circuit_timing = {k: p.get("timing") for k, p in provs.items() if p.get("timing")}
    crit = report_critical_path(phases.items, circuit_timing)
    provenance: dict = {
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
        # when the paper's chapters (its experiments, Fig. 1, the open question) were
        # complete, from the start; the chapter "Beyond the paper" runs after their circuit
        # runs, beside their comparisons and figures
        "paper_wall_time_s": round(paper_wall, 3),
        "beyond_wall_time_s": member_wall if members else None,
        "quick": opts.quick,
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "software": software,
        # wall time per phase (the theory thread's phases overlap the circuit runs) and the
        # machine's load average (1, 5, 15 min) at the start and the end: times on a shared
        # machine mean little without it
        "phases": phases.items,
        "phase_totals_s": phases.totals(),
        "load_average": {"start": [round(x, 2) for x in load0],
                         "end": [round(x, 2) for x in os.getloadavg()]},
    }
    prov_rows = [[k, json.dumps(v, default=str)[:400]] for k, v in provenance.items()
                 if k not in ("deck_hashes", "phases", "critical_path")]
    prov_rows.insert(next((i + 1 for i, r in enumerate(prov_rows) if r[0] == "critical_path_s"),
                          len(prov_rows)),
                     ["critical path (unlimited cores)", critical_path_text(crit, wall)])
    sections.append(Section("Provenance", [
        "Everything needed to reproduce this report: model parameters, seeds, ngspice version, "
        "the sha256 of every deck (full list in metrics.json), software versions, wall time."],
        tables=[Table("run provenance", ["item", "value"], prov_rows)]))
    from markupsafe import Markup

    from ..paper import references_html
    sections.append(Section("References", [
        "Equations and figures are cited by their numbers in Baule, Touchette & Cohen "
        "(2011); docs/equations.md maps the paper's LaTeX labels to them."]
        # references_html() escapes every text itself and adds only the DOI/arXiv links
        + [Markup(p) for p in references_html()]))

    metrics = {"comparisons": [c.as_dict() for c in comps], "provenance": provenance,
               "summary": {"comparisons": len(comps), "abs_z_below_3": n_z, "within_budget": n_ok,
                           "failed_sections": len(fails.items)},
               "failures": fails.items}
    validate_metrics(json.loads(json.dumps(metrics, default=str)))
    # (ensure_ascii=False: a path under a non-UTF-8 locale is written as its own UTF-8 bytes,
    # not as escaped lone surrogates; files.write_text)
    write_text(out / "metrics.json", json.dumps(metrics, indent=2, default=str,
                                                ensure_ascii=False))

    timing = (f"{wall:.0f} s in all; {prose.main_part(experiments)} were complete after "
              f"{paper_wall:.0f} s, and the chapter '{beyond.CHAPTER_TITLE}' took "
              f"{member_wall:.0f} s of its own threads' time" if members and experiments
              else f"{wall:.0f} s")
    intro = [f"Generated {provenance['created']} by analogue {software['analogue']} "
             f"with ngspice {provenance['ngspice_version']} ({'quick' if opts.quick else 'full'} run, "
             f"{timing}). Model units throughout: velocity, time and work rate of the "
             f"reduced equation {prose.equation_text([*experiments, *members])} (Baule, "
             "Touchette & Cohen).",
             "Every figure is also a PNG file in this directory; every number is in metrics.json."]
    if fails.items:
        intro.append(f"{len(fails.items)} section(s) failed; they are marked below with their "
                     "errors, and listed in metrics.json under 'failures'.")
    board = _board_link(out, experiments)
    if board is not None:
        intro.append(board)
    index = write_page(out / "index.html", title, intro, sections)
    _log(f"report written: {index}")
    if fails.items:
        raise ReportIncomplete(index, fails.items)
    return index
