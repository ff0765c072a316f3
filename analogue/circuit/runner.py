"""How circuit decks run: :class:`Runner` (store, workers, deck size, executor, timeout,
progress, label), and the progress a run shows.

A :class:`Runner` is a small frozen value, validated once when it is made; every layer that
runs decks takes one (``analogue.simulate(..., runner=)``, the tolerance and deck-size
calibrations, the board), so no dict of run options travels between layers.  It says nothing
about *what* runs (model, seed, circuit): two runs with the same arguments give the same
arrays under any runner (the deck seeds depend only on the run; issue 19), except through
``replicas_per_deck``, which sets the deck split and with it the seeds, as
:func:`analogue.simulate` documents.

Progress (issue 20 item 6): with progress on, a run shows the decks done of the total and an
estimate of the time left (:func:`eta_seconds`, a pure function of the finished decks' wall
times); on a terminal in a tqdm bar, otherwise as plain lines on stderr
(:class:`DeckProgress`).
"""
from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import importlib.util
import math
import re
import sys
import time as _time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .. import checks
from ..checks import ArgumentTypeError
from .store import open_store

if TYPE_CHECKING:
    from os import PathLike

__all__ = [
    "DEFAULT_TIMEOUT",
    "PROGRESS_EVERY_S",
    "DeckProgress",
    "Runner",
    "check_executor",
    "check_scheduler",
    "eta_seconds",
    "format_duration",
    "is_client",
    "progress_line",
    "progress_mode",
]

#: seconds per deck before its ngspice process group is killed
DEFAULT_TIMEOUT = 3600.0
#: plain progress lines (stderr not a terminal) come at most this often, so that a log of a
#: long run stays short: a 200-deck report run of ~10 min writes ~20 lines, not 200
PROGRESS_EVERY_S = 30.0

_ADDRESS = re.compile(r"(tcp|tls|ws|wss|ucx)://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+)"
                      r"(?::(\d{1,5}))?/?")


def is_client(obj: object) -> bool:
    """A ``distributed.Client`` (checked by type when Dask is importable)."""
    try:
        from distributed import Client
    except ImportError:
        return False
    return isinstance(obj, Client)


def check_executor(executor: object) -> None:
    """None, a ``concurrent.futures.Executor`` or a ``distributed.Client``."""
    if executor is None or isinstance(executor, cf.Executor) or is_client(executor):
        return
    raise ArgumentTypeError(f"executor must be a concurrent.futures.Executor or a "
                            f"distributed.Client, got {type(executor).__name__}")


def check_scheduler(scheduler: object) -> None:
    """None or a well-formed Dask scheduler address: tcp/tls/ws/wss://host[:port] (port
    1-65535), inproc://..., ucx:// only when a UCX backend is installed.  (A
    ``distributed.Client`` is accepted too, as before ``executor=`` existed.)"""
    if scheduler is None or is_client(scheduler):
        return
    if not isinstance(scheduler, str):
        raise ArgumentTypeError(f"scheduler must be a Dask scheduler address such as "
                                f"'tcp://host:8786' (an executor object goes to executor=), "
                                f"got {scheduler!r}")
    if re.fullmatch(r"inproc://\S+", scheduler):
        return
    m = _ADDRESS.fullmatch(scheduler)
    port_ok = m is not None and (m.group(3) is None or 0 < int(m.group(3)) < 65536)
    if m is None or not port_ok:
        raise ValueError(f"scheduler must be a Dask scheduler address such as 'tcp://host:8786' "
                         f"(host, then a port 1-65535), got {scheduler!r}")
    if m.group(1) == "ucx":
        if not any(importlib.util.find_spec(n) for n in ("distributed_ucxx", "ucp")):
            raise ValueError(f"scheduler {scheduler!r}: ucx:// needs a UCX backend "
                             f"(distributed-ucxx), which is not installed; use tcp://host:port")


def check_label(label: object) -> str | None:
    """None or a printable str of at most 100 characters (it names a run on its bar/line)."""
    if label is None:
        return None
    if not isinstance(label, str):
        raise ArgumentTypeError(f"label must be a printable str of at most 100 characters, "
                                f"got {label!r}")
    if not label.isprintable() or len(label) > 100:
        raise ValueError(f"label must be a printable str of at most 100 characters, got "
                         f"{label!r}")
    return label


@dataclass(frozen=True)
class Runner:
    """How decks run (not what runs): validated when made, immutable, shared by every layer.

    Parameters
    ----------
    store : path, True, False or None
        Run-store directory; False disables it (results in memory only); None or True:
        $ANALOGUE_STORE or ~/.cache/analogue/runs.
    workers : int >= 1, optional
        ngspice processes run at once locally; None: the CPUs this process may use
        (:func:`analogue.cores.usable_cpus`).
    replicas_per_deck : int >= 1, optional
        Replicas per ngspice deck; None: chosen per model (:mod:`analogue.circuit.deck_size`).
        It sets the deck split, hence the deck seeds: a different value gives different
        (equally valid) numbers, like a different seed.
    scheduler : str, optional
        A Dask scheduler address ("tcp://host:port", port 1-65535); exclusive with
        ``executor``.
    executor : concurrent.futures.Executor or distributed.Client, optional
        An executor the caller owns (never shut down here).
    timeout : float > 0
        Seconds per deck (default 3600) before its ngspice process group is killed.
    progress : bool or None
        None: a bar when stderr is a terminal and several decks run; True: the bar on a
        terminal, else plain lines on stderr; False: silent.
    label : str, optional
        Names the run on its bar or lines (printable, at most 100 characters).
    """

    store: str | PathLike[str] | bool | None = None
    workers: int | None = None
    replicas_per_deck: int | None = None
    scheduler: Any = None
    executor: Any = None
    timeout: float = DEFAULT_TIMEOUT
    progress: bool | None = None
    label: str | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        if self.store is not True:
            open_store(self.store)  # refuses a bad store argument, by name
        if self.workers is not None:
            set_(self, "workers", checks.integer("workers", self.workers, minimum=1))
        if self.replicas_per_deck is not None:
            set_(self, "replicas_per_deck",
                 checks.integer("replicas_per_deck", self.replicas_per_deck, minimum=1))
        check_scheduler(self.scheduler)
        check_executor(self.executor)
        if self.executor is not None and self.scheduler is not None:
            raise ValueError("pass either scheduler= (a Dask address) or executor=, not both")
        set_(self, "timeout", checks.positive("timeout", self.timeout))
        set_(self, "progress", checks.optional_flag("progress", self.progress,
                                                    none_means="auto"))
        set_(self, "label", check_label(self.label))

    def replace(self, **changes: Any) -> Runner:
        """A copy with ``changes`` (validated like the constructor's arguments)."""
        return dataclasses.replace(self, **changes)

    def for_calibration(self) -> Runner:
        """The runner a calibration uses: the same store, processes, executor and per-deck
        time limit (a run's --timeout holds for its calibrations too: issue 19), silent, with
        the calibration's own deck split."""
        return dataclasses.replace(self, progress=False, label=None, replicas_per_deck=None)


# --------------------------------------------------------------------------- progress
def eta_seconds(deck_times: Sequence[float | None], total: int, workers: int) -> float | None:
    """Estimated seconds until ``total`` decks are done, from the wall times of those done
    so far (``deck_times``, one per finished deck, None where not known) run ``workers`` at a time: the decks left
    times their mean time, shared by at most ``workers`` processes (fewer when fewer decks
    are left).  None while no deck has finished (nothing to estimate from); 0 when all are
    done.  The decks running now count as not started, so the estimate errs long by up to a
    deck's time."""
    total = checks.integer("total", total, minimum=0)
    workers = checks.integer("workers", workers, minimum=1)
    done = len(deck_times)
    if done > total:
        raise ValueError(f"deck_times has {done} entries, more than total = {total}")
    left = total - done
    if left == 0:
        return 0.0
    times = [float(t) for t in deck_times if t is not None and math.isfinite(float(t))]
    if not times:
        return None
    return left * (sum(times) / len(times)) / min(workers, left)


def format_duration(seconds: float) -> str:
    """``42 s``, ``3 min 20 s``, ``2 h 05 min`` (rounded; for progress lines)."""
    s = max(0, round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {(s % 3600) // 60:02d} min"


def progress_line(label: str, done: int, total: int, elapsed: float,
                  eta: float | None) -> str:
    """One plain progress line: ``label: 12/40 decks done, 1 min 05 s, about 2 min 10 s
    left`` (the estimate left out until one deck has finished)."""
    left = "" if eta is None else f", about {format_duration(eta)} left"
    return f"{label}: {done}/{total} decks done, {format_duration(elapsed)}{left}"


def progress_mode(progress: bool | None, n_run: int) -> str | None:
    """"bar" (tqdm, only on a terminal), "line" (plain lines when progress was asked for but
    stderr is a file or pipe: logs stay readable) or None."""
    if progress is None:
        return "bar" if n_run > 1 and sys.stderr.isatty() else None
    if not checks.flag("progress", progress):
        return None
    return "bar" if sys.stderr.isatty() else "line"


class DeckProgress:
    """The progress of one run's ``total`` decks (those not from the store): a tqdm bar with
    the time left as its postfix, or plain lines on stderr at most every
    :data:`PROGRESS_EVERY_S` (the run's summary line comes from the caller at the end), or
    nothing."""

    def __init__(self, mode: str | None, label: str, total: int, workers: int):
        self.mode, self.label, self.total, self.workers = mode, label, total, workers
        self.times: list[float | None] = []
        self.t0 = self.last = _time.perf_counter()
        self.bar = None
        if mode == "bar":
            from tqdm.auto import tqdm
            self.bar = tqdm(total=total, desc=label, unit="deck")

    def update(self, deck_wall_time: float | None) -> None:
        """One more deck done, which took ``deck_wall_time`` seconds (None: not known)."""
        self.times.append(deck_wall_time)
        done = len(self.times)
        eta = eta_seconds(self.times, self.total, self.workers)
        if self.bar is not None:
            self.bar.update(1)
            if eta is not None and done < self.total:
                self.bar.set_postfix_str(f"about {format_duration(eta)} left", refresh=False)
            return
        now = _time.perf_counter()
        if self.mode == "line" and done < self.total and now - self.last >= PROGRESS_EVERY_S:
            self.last = now
            print(progress_line(self.label, done, self.total, now - self.t0, eta),
                  file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
