"""What a report measures: the runs of one experiment and the settings of its analysis.

The ``[report]`` table of ``circuits/<name>.toml`` (all keys optional)::

    [report]
    stationary_replicas = 128      # replicas started from p_s (eq. (6))
    stationary_t_end = 100.0       # their length (model time)
    stationary_burn_in = 2.0       # discarded at the start of each
    stick_threshold = 0.1          # |v| below this many sqrt(tau_m/gamma) counts as stuck
    prehistory = [[2.0, 0.5, 3.0]] # (v0, v, t): paths from v0 (one of experiment.v0) reaching
                                   # (v, t); a pair (v, t) means v0 = experiment.v0[0] (refused
                                   # when v is itself one of experiment.v0: ambiguous)
    prehistory_window = 0.15       # half-width of the target window (velocity units)
    work_paths = [[1.0, 5.0]]      # (w, tau): circuit windows of work rate ~ w vs eq. (60)
    check_replicas = 64            # replicas re-run with tight tolerances (integration check)
    stationary_hold_divisor = 1    # the stationary runs hold the noise for noise_dt / this

``stationary_hold_divisor`` (an integer 1..64, default 1) refines the noise hold of the
stationary runs (and of their integration check) only: the held noise biases the stationary
indicator observables (the stick fraction) most, about linearly in the hold, while a finer
hold costs ngspice less than in proportion (measured on the paper's stationary decks: half
the hold costs 1.43-1.71x their ngspice CPU and cuts the stick fraction's bandwidth term
1.9-2.6x; the full work report 1.54x, 159 -> 244 s; see :func:`stationary_noise_dt` and
``benchmarks/bench_bandwidth_frontier.py``).  An integer keeps every run length and the
sampling step whole numbers of holds.

``--quick`` divides replica counts by four (at least 32; the integration check: at least 8;
never more than the file's count) and halves the stationary length.

The table is parsed with the rest of the file, by
:func:`analogue.study.experiments.experiment_from_dict`, and travels with the experiment
(``Experiment.report``); its cross-references to ``[experiment]`` (prehistory starting
velocities and times, work windows) are checked there, before anything runs.

This module is the study layer's (below the experiment that holds the settings and the report
that reads them); :mod:`analogue.report.plan` re-exports every name, where they were first.
"""
from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from .. import checks
from ..circuit.runner import DEFAULT_TIMEOUT, Runner

__all__ = ["RunOptions", "ReportSettings", "report_settings_from_dict",
           "QUICK_DIVISOR", "MIN_STATIONARY_REPLICAS", "MIN_CHECK_REPLICAS",
           "MAX_HOLD_DIVISOR", "stationary_noise_dt"]

QUICK_DIVISOR = 4
MIN_QUICK_REPLICAS = 32
MIN_QUICK_CHECK_REPLICAS = 8
# The stationary estimators' errors are delete-a-group jackknives over replicas with
# g = min(32, n // 2) groups (study.observables): at least 4 groups.
MIN_STATIONARY_REPLICAS = 8
# The integration check's paired jackknife needs at least 2 groups of 2.
MIN_CHECK_REPLICAS = 4
# A finer stationary hold costs ngspice about divisor^0.6 (measured 1.43-1.71x at 2, 2.2-3.2x
# at 4 on the paper's stationary decks); 64 bounds a typo, not a design choice.
MAX_HOLD_DIVISOR = 64


@dataclass(frozen=True)
class RunOptions:
    """How to run: where (workers / Dask scheduler), the run store, size, progress."""

    workers: int | None = None
    scheduler: str | None = None
    store: Path | None = None
    quick: bool = False
    progress: bool = True
    timeout: float | None = None  # seconds per deck; None: simulate's default
    # the report's chapter "What experiments measure" also runs its two sweep curves (8
    # circuit points of the stick experiment at quick size: analogue.report.measure_chapter)
    sweeps: bool = False
    # where the decks run locally: an executor the caller owns (the study's one pool of
    # ngspice processes, analogue.circuit.deck_pool, seen at a priority); None: each run
    # starts `workers` processes of its own.  Set by run_study, not by a user.
    executor: Any = None

    def runner(self, **changes: Any) -> Runner:
        """These options as the :class:`analogue.Runner` every deck of the study runs with
        (store, workers, Dask scheduler, per-deck timeout, progress), with ``changes`` (a
        deck size, a label, an executor: :meth:`Runner.replace`'s keywords), validated by the
        Runner.  The one way run options travel from the study to what runs decks (issue 20:
        no dict of run options between layers)."""
        return Runner(store=self.store, workers=self.workers, scheduler=self.scheduler or None,
                      executor=None if self.scheduler else self.executor,
                      timeout=DEFAULT_TIMEOUT if self.timeout is None else self.timeout,
                      progress=self.progress).replace(**changes)

    def simulate_kwargs(self) -> dict:
        """Deprecated (DeprecationWarning): use :meth:`runner` and pass ``runner=``."""
        warnings.warn("RunOptions.simulate_kwargs() is deprecated: pass "
                      "runner=RunOptions.runner() instead", DeprecationWarning, stacklevel=2)
        kw: dict = {"workers": self.workers, "progress": self.progress}
        if self.scheduler:
            kw["scheduler"] = self.scheduler
        if self.store is not None:
            kw["store"] = self.store
        if self.timeout is not None:
            kw["timeout"] = self.timeout
        return kw

    @classmethod
    def from_runner(cls, runner: Runner, *, quick: bool = False) -> RunOptions:
        """The report's options from an :class:`analogue.Runner`: its store, workers, Dask
        scheduler, timeout and progress.  The report sizes its decks, names its runs and pools
        its decks itself, so a runner's ``replicas_per_deck``, ``label`` or ``executor`` is
        refused (ValueError naming it) rather than silently dropped."""
        if not isinstance(runner, Runner):
            raise TypeError(f"runner must be an analogue.Runner, got {type(runner).__name__}")
        for name in ("replicas_per_deck", "label", "executor"):
            if getattr(runner, name) is not None:
                raise ValueError(f"runner.{name}={getattr(runner, name)!r}: a report chooses "
                                 f"its runs' {name.replace('_', ' ')} itself; leave it None")
        store = runner.store
        return cls(workers=runner.workers, scheduler=runner.scheduler,
                   store=None if store is None or store is True else
                   (store if store is False else Path(store)),  # type: ignore[arg-type]
                   quick=quick, progress=bool(runner.progress), timeout=runner.timeout)

    def scaled(self, replicas: int) -> int:
        if not self.quick:
            return int(replicas)
        # never more than the file asks for (replicas = 8 used to run 32 with --quick)
        return min(int(replicas), max(MIN_QUICK_REPLICAS, int(replicas) // QUICK_DIVISOR))


# what the numbers of a list entry mean (in the message that refuses a malformed one)
_MEANING = {"prehistory": "[v0, v, t]: paths from v0 (one of experiment.v0) reaching v at t; "
                          "[v, t]: from experiment.v0[0]",
            "work_paths": "[w, tau]: work rate w over windows tau"}


@dataclass(frozen=True)
class ReportSettings:
    stationary_replicas: int = 128
    stationary_t_end: float = 100.0
    stationary_burn_in: float = 2.0
    stick_threshold: float = 0.1
    prehistory: tuple = ()
    prehistory_window: float = 0.15
    work_paths: tuple = ()
    check_replicas: int = 64
    stationary_hold_divisor: int = 1

    def __post_init__(self):
        for name, lo in (("stationary_replicas", MIN_STATIONARY_REPLICAS),
                         ("check_replicas", MIN_CHECK_REPLICAS)):
            object.__setattr__(self, name, checks.integer(f"report.{name}", getattr(self, name),
                                                          minimum=lo, maximum=100_000))
        object.__setattr__(self, "stationary_hold_divisor", checks.integer(
            "report.stationary_hold_divisor", self.stationary_hold_divisor, minimum=1,
            maximum=MAX_HOLD_DIVISOR))
        for name in ("stationary_t_end", "stick_threshold", "prehistory_window"):
            object.__setattr__(self, name, checks.positive(f"report.{name}", getattr(self, name)))
        b = checks.finite("report.stationary_burn_in", self.stationary_burn_in)
        # --quick halves the stationary length: the burn-in must leave data in both sizes
        if not 0 <= b < self.stationary_t_end / 2:
            raise ValueError(f"report.stationary_burn_in must be in [0, stationary_t_end/2) = "
                             f"[0, {self.stationary_t_end / 2:g}) (--quick halves "
                             f"stationary_t_end), got {b!r}")
        object.__setattr__(self, "stationary_burn_in", b)
        for name, sizes in (("prehistory", (2, 3)), ("work_paths", (2,))):
            items = getattr(self, name)

            def well_formed(p, sizes=sizes) -> bool:
                return isinstance(p, (list, tuple)) and len(p) in sizes and all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                    for x in p)
            listed = isinstance(items, (list, tuple))
            if not (listed and all(well_formed(p) for p in items)):
                bad = next(p for p in items if not well_formed(p)) if listed else items
                shape = " or ".join(f"[{', '.join(['number'] * k)}]" for k in sizes)
                raise ValueError(f"report.{name} must be a list of {shape} entries "
                                 f"({_MEANING[name]}), got {bad!r}")
            object.__setattr__(self, name, tuple(tuple(float(x) for x in p) for p in items))
        for p in self.prehistory:
            if p[-1] <= 0:
                raise ValueError(f"report.prehistory times must be > 0, got {p[-1]}")
        for _w, tau in self.work_paths:
            if tau <= 0:
                raise ValueError(f"report.work_paths tau must be > 0, got {tau}")

    def for_options(self, opts: RunOptions) -> ReportSettings:
        if not opts.quick:
            return self
        # the check costs 100x tighter tolerances: a quarter of it, like the replicas
        return replace(self, stationary_replicas=opts.scaled(self.stationary_replicas),
                       stationary_t_end=self.stationary_t_end / 2,
                       check_replicas=min(self.check_replicas, max(
                           MIN_QUICK_CHECK_REPLICAS, self.check_replicas // QUICK_DIVISOR)))

    def variants(self) -> tuple[ReportSettings, ReportSettings]:
        """The full and the ``--quick`` settings (both are checked when a file is loaded)."""
        return self, self.for_options(RunOptions(quick=True))


_KEYS = set(ReportSettings.__dataclass_fields__)


def report_settings_from_dict(data, where: str = "experiment") -> ReportSettings:
    """Validate a ``[report]`` table (defaults for absent keys; unknown keys are errors)."""
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ValueError(f"{where}: [report] must be a table, got {type(data).__name__}")
    unknown = sorted(set(data) - _KEYS)
    if unknown:
        key = unknown[0] if re.fullmatch(r"[A-Za-z0-9_-]{1,64}", unknown[0]) else repr(unknown[0])
        raise ValueError(f"{where}: unknown key report.{key} (allowed: "
                         f"{', '.join(sorted(_KEYS))})")
    try:
        return ReportSettings(**data)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None


def stationary_noise_dt(noise_dt: float, settings: ReportSettings) -> float:
    """The noise hold (model units) of the report's stationary runs and of their integration
    check and bandwidth pair: the circuit's hold ``noise_dt`` divided by
    ``settings.stationary_hold_divisor``."""
    return noise_dt / settings.stationary_hold_divisor
