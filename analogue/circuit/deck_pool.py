"""One pool of ngspice processes for everything a job runs, with priorities (issue 22: "more
cores, less waiting, and never more processes than cores").

A study runs several kinds of circuit work at once: the paper's experiments, the family
members, the sweep points, each through :func:`analogue.simulate` with ``workers`` ngspice
processes of its own.  Run side by side, each with its own pool, they started ``workers``
processes apiece (two members and a sweep: 3 x 16 on a 16-core machine).  A
:class:`DeckPool` holds ``workers`` threads, each running one deck (one ngspice process) at
a time, shared by all of them: whatever runs beside what, at most ``workers`` ngspice
processes run.  Each caller gets a :meth:`DeckPool.view` with a priority: a free thread takes
the queued deck of the lowest priority first (then the earliest), so the paper's decks run
before the members' and the members' before the sweeps', whatever order they were queued
in.  The order is a schedule: no result depends on it (every deck's seed and split are fixed
before it is queued).

A view is a :class:`concurrent.futures.Executor` the caller owns (``Runner(executor=view)``):
:func:`analogue.circuit.decks.run_decks` never shuts it down.  Shutting the pool down with
``cancel_futures=True`` cancels every queued deck (an interrupt: the decks under way are
killed by :func:`analogue.circuit.ngspice.interrupt_guard`).
"""
from __future__ import annotations

import concurrent.futures as cf
import itertools
import queue
import threading
import time
from typing import Any

__all__ = ["CALIBRATION_AHEAD", "DeckPool", "PoolView", "WaitClock"]


#: how far ahead of its caller's decks :meth:`PoolView.ahead` queues (less than a step between
#: the study's tiers, analogue.study.schedule.PAPER_DECKS ...)
CALIBRATION_AHEAD = 0.5


class DeckPool(cf.Executor):
    """``workers`` threads running submitted callables, lowest priority first, FIFO within a
    priority.  Threads are daemons: an interrupt never waits for a deck under way."""

    def __init__(self, workers: int, *, name: str = "analogue-deck"):
        if not isinstance(workers, int) or isinstance(workers, bool) or workers < 1:
            raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
        self.workers = workers
        self._queue: queue.PriorityQueue = queue.PriorityQueue()
        self._seq = itertools.count()
        self._lock = threading.Lock()
        self._closed = False
        self._threads = [threading.Thread(target=self._run, name=f"{name}-{i}", daemon=True)
                         for i in range(workers)]
        for t in self._threads:
            t.start()

    def _run(self) -> None:
        while True:
            _, _, item = self._queue.get()
            if item is None:
                return
            fut, fn, args, kwargs = item
            if not fut.set_running_or_notify_cancel():
                continue
            try:
                fut.set_result(fn(*args, **kwargs))
            except BaseException as exc:  # handed to the waiting caller, as cf's pools do
                fut.set_exception(exc)

    def submit_at(self, priority: float, fn, /, *args, **kwargs) -> cf.Future:
        """Queue ``fn(*args, **kwargs)`` at ``priority`` (lower runs first)."""
        fut: cf.Future = cf.Future()
        with self._lock:
            if self._closed:
                raise RuntimeError("cannot schedule new decks after the pool was shut down")
            self._queue.put((priority, next(self._seq), (fut, fn, args, kwargs)))
        return fut

    def submit(self, fn, /, *args, **kwargs) -> cf.Future:
        return self.submit_at(0, fn, *args, **kwargs)

    def view(self, priority: float) -> PoolView:
        """An executor whose decks queue at ``priority`` in this pool."""
        return PoolView(self, priority)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
            if cancel_futures:
                while True:
                    try:
                        _, _, item = self._queue.get_nowait()
                    except queue.Empty:
                        break
                    if item is not None:
                        item[0].cancel()
            # after every queued deck (or at once, when they were cancelled)
            for _ in self._threads:
                self._queue.put((float("inf"), next(self._seq), None))
        if wait:
            for t in self._threads:
                t.join()


class PoolView(cf.Executor):
    """A :class:`DeckPool` seen at one priority; the pool's owner shuts the pool down, so
    :meth:`shutdown` here does nothing (as for any executor a caller passes in)."""

    def __init__(self, pool: DeckPool, priority: float):
        self.pool, self.priority = pool, priority

    @property
    def workers(self) -> int:
        return self.pool.workers

    def submit(self, fn, /, *args: Any, **kwargs: Any) -> cf.Future:
        return self.pool.submit_at(self.priority, fn, *args, **kwargs)

    def ahead(self) -> PoolView:
        """A view of the same pool half a priority step ahead: work that everything else of
        this caller waits for (its calibrations) before other callers' bulk decks of the
        same or the next priority."""
        return PoolView(self.pool, self.priority - CALIBRATION_AHEAD)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        pass  # the pool is its owner's

    def __repr__(self) -> str:
        return f"PoolView(priority={self.priority}, workers={self.pool.workers})"


class WaitClock(cf.Executor):
    """An executor in front of another that measures how long its caller only waited for a
    free process: ``blocked_s``, the seconds in which at least one of the decks submitted
    through it was queued and none was running (the report's critical path takes the work
    of a calibration, whose decks queue in a shared pool behind other runs' decks, as its
    seconds less these: with unlimited cores a deck never waits).  Submits pass through;
    :meth:`shutdown` does nothing (the executor is its owner's)."""

    def __init__(self, executor: cf.Executor, clock=time.perf_counter):
        self.executor, self.clock = executor, clock
        self.blocked_s = 0.0
        # seconds each deck ran (from its start in a pool thread to its end), since the last
        # stage_longest(): the decks of one stage of a calibration run at once
        self._ran: list[float] = []
        self._queued = self._running = 0
        self._since: float | None = None     # start of the current blocked interval
        self._lock = threading.Lock()

    def _update(self, queued: int, running: int) -> None:
        with self._lock:
            self._queued += queued
            self._running += running
            now = self.clock()
            blocked = self._queued > 0 and self._running == 0
            if blocked and self._since is None:
                self._since = now
            elif not blocked and self._since is not None:
                self.blocked_s += now - self._since
                self._since = None

    def stage_longest(self) -> float:
        """The longest run of a deck submitted through this executor since the previous call
        (0 if none ran: every run came from the store), and a new stage begins: with
        unlimited cores the decks of a stage run at once, so the stage takes its longest."""
        with self._lock:
            ran, self._ran = self._ran, []
        return max(ran, default=0.0)

    def submit(self, fn, /, *args: Any, **kwargs: Any) -> cf.Future:
        def timed():
            self._update(-1, +1)
            t0 = self.clock()
            try:
                return fn(*args, **kwargs)
            finally:
                with self._lock:
                    self._ran.append(self.clock() - t0)
                self._update(0, -1)
        self._update(+1, 0)
        try:
            return self.executor.submit(timed)
        except BaseException:
            self._update(-1, 0)
            raise

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        pass  # the executor is its owner's
