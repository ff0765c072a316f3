"""How a study's work is scheduled: background threads, phases and recorded failures
(issue 10: every core busy from start to end; issue 20: the schedule belongs to the study, not
to the page).

- :class:`Workers`: threads that run tasks in submission order, each as a phase;
- :class:`Phases`: the wall time per phase (the report's provenance and critical path,
  :mod:`analogue.study.critical_path`);
- :class:`Failures`: a piece of work that fails is recorded (section, stage, error), not raised;
- :func:`result_of`: a future's result, waited for in polls (signals reach the main thread).

Progress goes to the ``analogue.report.pipeline`` logger, where the command line has always
shown the report job's progress (analogue.cli).
"""
from __future__ import annotations

import itertools
import logging
import math
import os
import queue
import threading
import time
import traceback
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import contextmanager, nullcontext

from threadpoolctl import threadpool_limits

from .experiments import Experiment
from ..circuit import ngspice
from ..circuit.simulate import POLL_S
from ..cores import usable_cpus
from .processes import THEORY_PROCESSES, TheoryProcesses
from .settings import RunOptions

__all__ = ["Failures", "Phases", "Workers", "NOW", "LATER", "result_of", "say", "error_text",
           "circuit_cost", "CIRCUIT_THREADS", "SCHEDULER_CIRCUIT_THREADS", "MEMBER_THREADS", "monte_carlo_pool",
           "member_cost", "MEMBER_SECONDS"]

log = logging.getLogger("analogue.report.pipeline")

def error_text(exc: BaseException) -> str:
    msg = " | ".join(ln.strip() for ln in str(exc).splitlines() if ln.strip())
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


class Failures:
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
            err = error_text(exc)
            self.items.append({"section": section, "experiment": experiment, "stage": stage,
                               "error": err})
            say(f"{section}: FAILED ({stage}): {err}")
            return None, err


def result_of(f: Future):
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


def say(msg: str) -> None:
    """Progress of the report job, on the ``analogue.report.pipeline`` logger (the command line
    shows it on stderr with the time since the command started: see analogue.cli).  A task
    still running in a background thread after its report ended (a daemon thread finishing
    its numerics) says nothing more: in one process, the next command's output (an
    in-process ``analogue theory --json`` after a failed report) got its progress lines."""
    if getattr(threading.current_thread(), "analogue_report_closed", False):
        return
    log.info(msg)


class Phases:
    """Wall time per phase of a report (logged, and recorded in the provenance).  Phases in
    the theory thread overlap with the circuit runs, so the phases sum to more than the wall
    time when the overlap works."""

    def __init__(self, origin: float | None = None):
        self.items: list[dict] = []
        self.origin = time.perf_counter() if origin is None else origin

    @contextmanager
    def __call__(self, phase: str, experiment: str | None = None, thread: str = "main"):
        t0, c0 = time.perf_counter(), time.thread_time()
        try:
            yield
        finally:
            dt = time.perf_counter() - t0
            # cpu_s: this thread's CPU seconds in the phase (not its ngspice processes', nor
            # the Monte Carlo chunks' threads': provenance's bandwidth_timing), the job's CPU
            # by item (issue 22, item 4: the quick job on 2 cores is bound by its CPU)
            self.items.append({"phase": phase, "experiment": experiment, "thread": thread,
                               "start_s": round(t0 - self.origin, 3), "seconds": round(dt, 3),
                               "cpu_s": round(time.thread_time() - c0, 3)})
            say(f"phase done: {phase}{f' ({experiment})' if experiment else ''} "
                f"[{thread}]: {dt:.1f} s")

    def totals(self) -> dict:
        out: dict = {}
        for it in self.items:
            out[it["phase"]] = round(out.get(it["phase"], 0.0) + it["seconds"], 3)
        return out


#: Workers priorities: ``NOW`` for work whose data are in and whose result is waited for,
#: ``LATER`` (the default) for work queued ahead of its need
NOW, LATER = 0, 1


class Workers:
    """Background threads that run tasks in submission order within a priority (``submit(...,
    priority=)``: lower first; default :data:`LATER`), each as a phase of the report (issue
    10, item 4: keep every core busy from start to end).

    - the **theory** thread (one): the theory needs no circuit data, so it runs while ngspice
      runs; BLAS/LAPACK are limited to one thread while a task runs (threadpoolctl), so it adds
      one runnable thread, not one per core.  An experiment's data-dependent theory curves
      are queued :data:`NOW` (issue 22): its runs are in and its figures wait for them,
      while the circuit-free tasks queued from the start are needed only when later runs
      arrive (measured on the quick paper at load ~10: the work experiment's curves waited
      107 s behind the other experiments' bandwidth terms and the measurement chapter's
      theory, and the paper's chapters ended 41 s after them);
    - the **circuit** thread (one): every experiment's circuit runs, queued from the start
      (longest first), so that ngspice never waits for the main thread's comparisons of the
      previous experiment.  One thread: an experiment's runs keep ``workers`` ngspice
      processes busy on their own (one deck pool for all its runs, study.runs), and the
      theory thread fills the last deck's idle core.  With two threads the experiments
      shared the cores, so the longest one (work, queued first) ended last anyway, at 108 s
      of the quick paper, and its theory curves trailed after it;
    - the **members** threads: the family members' analyses (circuit and theory), queued
      once the paper's circuit runs are done (:meth:`submit_after`).  Two threads: a member's runs are
      few decks, which alone leave a core idle.

    The threads are daemons: an interrupt does not wait for a task under way (see
    :meth:`abort`)."""

    def __init__(self, phases: Phases, name: str, threads: int = 1, blas_limit: bool = False):
        self.phases, self.name, self.blas_limit = phases, name, blas_limit
        self.queue: queue.PriorityQueue = queue.PriorityQueue()
        self._seq = itertools.count()     # submission order within a priority
        self._lock = threading.Lock()
        self._closed = False
        self.threads = [threading.Thread(target=self._run, daemon=True,
                                         name=f"analogue-{name}" + (f"-{i}" if threads > 1 else ""))
                        for i in range(threads)]
        for t in self.threads:
            t.start()

    def _run(self):
        while True:
            _, _, item = self.queue.get()
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

    def submit(self, phase: str, experiment: str | None, fn, priority: int | None = None
               ) -> Future:
        fut: Future = Future()
        self._put((fut, phase, experiment, fn), LATER if priority is None else priority)
        return fut

    def _put(self, item, priority: int = 1) -> None:
        with self._lock:   # nothing is queued behind close()'s end markers: cancelled instead
            if self._closed:
                item[0].cancel()
            else:
                self.queue.put((priority, next(self._seq), item))

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
        while True:               # whatever has not started is cancelled
            try:
                _, _, item = self.queue.get_nowait()
            except queue.Empty:
                break
            if item is not None:
                item[0].cancel()

    def close(self) -> None:
        for t in self.threads:
            t.analogue_report_closed = True  # type: ignore[attr-defined]  # read by say
        with self._lock:
            self._closed = True
            self._cancel_pending()
            for _ in self.threads:
                self.queue.put((math.inf, next(self._seq), None))

    def abort(self, wait: float = 10.0) -> None:
        """After an interrupt: nothing new starts, and the ngspice processes of the tasks under
        way are killed (again and again: a task whose deck was killed may start its next one)
        until their threads end or ``wait`` seconds have passed; a task in pure numerics is
        left to the daemon thread.  Its temporary directories are removed as it unwinds."""
        self.close()
        deadline = time.monotonic() + wait
        while any(t.is_alive() for t in self.threads) and time.monotonic() < deadline:
            ngspice.terminate_all()
            for t in self.threads:
                t.join(0.05)
        ngspice.terminate_all()


# The standard members' analyses (circuit runs and their references), seconds measured on the
# quick paper (2-core machine, load 1.7-3.3, two member threads).  Only their order is used:
# the members are queued longest first.  In the order of MEMBERS (cubic, stribeck, spring,
# shot) the spring started third and ran alone on one thread for its last 11 s (the job's
# members took 33 s; longest first would make it about 29 s).  The spring's cost is its
# integration check, one deck of 8 replicas over its whole release run (40 tau_m = 120, 100x
# tighter: 13.4 s of its 23.1 s at load ~4, its Monte Carlo reference 3.2 s beside it), which
# circuit_cost (replica-time) does not weigh, so it does not order the members.
MEMBER_SECONDS = {"spring": 22.7, "cubic": 15.2, "stribeck": 10.5, "shot": 6.7}


def member_cost(exp) -> float:
    """The queueing key of a family member (:data:`MEMBER_SECONDS`; 0 for one not measured:
    queued after those)."""
    return MEMBER_SECONDS.get(exp.name, 0.0)


def monte_carlo_pool():
    """The threads that run the bandwidth terms' Monte Carlo chunks
    (:func:`analogue.study.comparisons.bandwidth_terms`, issue 22): one per usable core, at most
    :data:`MC_THREADS`.
    Threads, not processes: a chunk's loop is numpy arithmetic on 2048-row arrays, which runs
    outside the GIL, and its noise (160 MB per chunk of the quick work experiment's transition
    pairs) stays in this process.  Measured on the shared 2-core machine (load ~10), the
    quick work experiment's terms: a spawned process pool pickled ~2.5 GB of noise through
    pipes (system CPU of the whole quick paper 17.6 -> 34.0 s); two threads took the same
    CPU as one loop (9.8 against 9.1-11.3 s), bit for bit the same numbers.

    At most :data:`MC_THREADS` threads: the loop's numpy calls on 1024-row chunks are a few
    microseconds each, so the threads take turns on the GIL more than they run beside each
    other.  Measured on an idle 16-core Xeon (quick paper, one thread per core): the work
    experiment's chunks took 29.0 CPU-s against 3.3 on 2 cores (2.5x per core slower there),
    its longest chunk 3.3 s against 0.75, and the threads starved the rest of the job (a
    member's Monte Carlo reference: 41 s against 1.9); with 4 threads 24.2 CPU-s.  Two threads
    took the same CPU as one loop on 2 cores (above), so two it is.  The chunks are fixed in
    size, so the numbers do not depend on the thread count."""
    return ThreadPoolExecutor(max_workers=min(usable_cpus(), MC_THREADS),
                              thread_name_prefix="analogue-mc")


#: the most threads of :func:`monte_carlo_pool` (its docstring)
MC_THREADS = 2

#: environment variable: how many theory processes a study starts (0: none, the theory
#: curves in the theory thread as before; default: :func:`theory_processes`)
THEORY_PROCESSES_ENV = "ANALOGUE_THEORY_PROCESSES"


def theory_process_count(experiments) -> int:
    """How many theory processes a study of ``experiments`` starts
    (:func:`theory_processes`): one per work window of the experiment with the most, at
    most :data:`~analogue.study.processes.THEORY_PROCESSES` and the usable cores; 0 when no
    experiment has a work window to compute (a = 0, or none fits) or on one core;
    :data:`THEORY_PROCESSES_ENV` overrides it (0: none).  Raises ValueError, naming the
    variable, for a value that is not a whole number >= 0 (checked before the study starts
    anything)."""
    windows = max((len(e.work_taus) for e in experiments if e.model.a != 0), default=0)
    env = os.environ.get(THEORY_PROCESSES_ENV, "").strip()
    if env:
        try:
            n = int(env)
        except ValueError:
            raise ValueError(f"{THEORY_PROCESSES_ENV} must be a whole number of processes "
                             f"(0: none), got {env!r}") from None
        if n < 0:
            raise ValueError(f"{THEORY_PROCESSES_ENV} must be >= 0, got {env!r}")
        return min(windows, n)
    n = min(windows, THEORY_PROCESSES, usable_cpus())
    return n if n >= 2 else 0


def theory_processes(experiments, n: int | None = None) -> TheoryProcesses | None:
    """The study's worker processes for its theory curves' work densities
    (:mod:`analogue.study.processes`), ``n`` of them (default
    :func:`theory_process_count`); None for 0, and when the pool cannot start (the curves
    then run in their thread, as before)."""
    n = theory_process_count(experiments) if n is None else n
    if n < 1:
        return None
    try:
        return TheoryProcesses(n)
    except OSError:
        return None


# the threads of the paper's circuit runs and of the family members' analyses (see
# Workers): each simulate call runs up to `workers` ngspice processes.  With a Dask
# scheduler an experiment's runs go to the cluster one after another (study.runs._run_jobs)
# and the local cores are not the limit: two experiments at once keep more of it busy.
CIRCUIT_THREADS = 1
SCHEDULER_CIRCUIT_THREADS = 2
MEMBER_THREADS = 2

# The priorities of the study's one deck pool (analogue.circuit.deck_pool: at most `workers`
# ngspice processes, whoever queued the decks): a free process takes the paper's decks first,
# then the members', then the sweep points'.
PAPER_DECKS, MEMBER_DECKS, SWEEP_DECKS = 0, 1, 2
# the paper's experiments, longest first, at PAPER_DECKS + rank x this (all below the members')
PAPER_RANK_STEP = 0.01

# From this many usable cores on, the paper's experiments run their circuit work at once (a
# circuit thread each): an experiment is a few dozen decks with serial calibrations before
# them, which leave most of a large machine idle, and the deck pool keeps the longest
# experiment's decks before the others'.  Those threads mostly wait for ngspice.
#
# The family members (and the sweeps) still start only once the paper's circuit runs are
# done, on MEMBER_THREADS threads, on every machine: their work beside the decks is Python
# (theory, Monte Carlo references and held/white pairs on arrays of a few thousand rows),
# which takes turns on the GIL rather than running beside the rest.  Measured on an idle
# 16-core Xeon (quick paper, the members started with the paper's runs, one thread each):
# the members' Monte Carlo references took 23-36 s of wall against 2-5 s on 2 cores, and the
# job's Python CPU was 152-178 s against 57 s (sys 37-44 s: the threads' GIL hand-offs).
EXPERIMENTS_AT_ONCE_CORES = 8


def experiments_at_once(opts) -> bool:
    """Whether the paper's experiments run their circuit work at once
    (:data:`EXPERIMENTS_AT_ONCE_CORES` local workers or more; never with a Dask scheduler,
    which has its own :data:`SCHEDULER_CIRCUIT_THREADS`)."""
    return not opts.scheduler and (opts.workers or usable_cpus()) >= EXPERIMENTS_AT_ONCE_CORES


def circuit_cost(exp: Experiment, opts: RunOptions) -> float:
    """A proxy for an experiment's ngspice time: its replica-time (replicas x model time of
    the transition and stationary runs; the integration checks scale with them).  Only its
    order matters: the paper's work experiment (7600 replica-time units at --quick, against
    5600 for stick and slip) took 58 s of circuit runs, stick 30 s, slip 15 s."""
    settings = exp.report.for_options(opts)
    return (len(exp.v0) * opts.scaled(exp.replicas) * exp.t_end
            + settings.stationary_replicas * settings.stationary_t_end)

