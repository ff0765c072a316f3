"""Worker processes for a study's interpreter-bound theory (issue 22, item 1).

The exact finite-tau work densities of an experiment's theory curves
(:func:`analogue.theory.exact.work_pdf`, one call per window tau) are many small dense
matrix exponentials driven from Python: they hold the interpreter lock (GIL) for most of
their time, so threads do not run them side by side (measured, quick work experiment on an
idle 2-core machine: tau = 1 and 2 in two threads 4.34 s against 3.43 + 0.74 s one after
the other).  In processes they do, and each call sends only a model, a few bin centres and a
window in, one density array out.  They are on the report's critical path: the work
experiment's stationary run -> its theory curves (5.2 s of work_pdf, 3.5 s of it tau = 1)
-> its rate-function figures -> the page.

:class:`TheoryProcesses` is a small pool started once per study, from a ``forkserver``
(safe in a process that runs threads, unlike ``fork``; the server imports the theory once,
then each worker is a fork of it, not a fresh interpreter as with ``spawn``).  It starts in
the background when the study does, so it is ready by the time the first stationary run is
in.  The numbers are the same as in-process, bit for bit (the same function on the same
arguments, with BLAS at one thread as in the study).  A pool that breaks (a worker killed)
is not trusted again: :meth:`TheoryProcesses.run` then computes in the calling thread.
"""
from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time
import warnings
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from collections.abc import Callable
from typing import Any

__all__ = ["Started", "TheoryProcesses", "THEORY_PROCESSES", "quiet_call"]

#: the most worker processes of a study's :class:`TheoryProcesses` (the quick and the full
#: paper compare 4 work windows, the longest of which takes most of the time)
THEORY_PROCESSES = 4

#: what the forkserver imports once for every worker (the theory a worker runs)
_PRELOAD = ["analogue.theory.work_statistics", "analogue.theory.exact"]


def _worker_init() -> None:
    """A worker runs one computation at a time beside ngspice and the study's threads: BLAS
    at one thread (as the study sets in its own process), and no Ctrl-C of its own (the
    terminal sends SIGINT to the whole process group; the study ends its workers itself)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        from threadpoolctl import threadpool_limits
        threadpool_limits(limits=1)
    except Exception:       # threadpoolctl is a dependency; a broken BLAS probe is no reason
        pass                # to lose the worker


def quiet_call(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)`` with RuntimeWarnings silenced (a worker's warnings would be
    lost anyway; the callers that use this silence them in-process too)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return fn(*args, **kwargs)


def _noop() -> int:
    return os.getpid()


def _timed(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[Any, float]:
    """``(fn(*args, **kwargs), CPU seconds of this worker process for it)``."""
    c0 = time.process_time()
    out = fn(*args, **kwargs)
    return out, time.process_time() - c0


class TheoryProcesses:
    """A pool of ``workers`` theory processes (see the module docstring).

    ``submit(fn, *args, **kwargs)`` returns a :class:`~concurrent.futures.Future` (``fn``
    and its arguments must pickle: module-level functions, models, arrays); :meth:`run`
    waits for it, falling back to the calling thread if the pool is broken; :meth:`close`
    cancels what has not started and ends the workers (the study's interrupt path too)."""

    def __init__(self, workers: int):
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
        self.workers = workers
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(_PRELOAD)
        self._pool: ProcessPoolExecutor | None = ProcessPoolExecutor(
            max_workers=workers, mp_context=ctx, initializer=_worker_init)
        self.broken = False
        # start the server and the workers now, in the background (starting the forkserver
        # takes ~0.4 s of this thread), so that the first real task finds them up
        threading.Thread(target=self._warm, name="analogue-theory-processes",
                         daemon=True).start()

    def _warm(self) -> None:
        try:
            for _ in range(self.workers):
                self.submit(_noop)
        except BrokenProcessPool:   # closed before it started, or could not start
            pass

    def submit(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Future:
        if self._pool is None or self.broken:
            raise BrokenProcessPool("the study's theory processes are closed or broken")
        try:
            return self._pool.submit(fn, *args, **kwargs)
        except (BrokenProcessPool, RuntimeError, OSError) as exc:
            # RuntimeError: shut down; OSError: a worker could not be started (a process
            # limit, no fork in a sandbox): the computations run in the calling thread
            self.broken = True
            raise BrokenProcessPool(f"{type(exc).__name__}: {exc}") from exc

    def start(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Started:
        """``fn(*args, **kwargs)`` started in a worker; its :meth:`Started.result` computes
        it in the calling thread instead when the pool is closed, broken, or breaks before
        the result is in."""
        try:
            fut: Future | None = self.submit(_timed, fn, *args, **kwargs)
        except BrokenProcessPool:
            fut = None
        return Started(self, fut, fn, args, kwargs)

    def run(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        """``fn(*args, **kwargs)`` in a worker, or here when the pool is broken or closed."""
        return self.start(fn, *args, **kwargs).result()

    def close(self) -> None:
        """Cancel the queued tasks and end the workers (a running computation is killed:
        nothing waits for it any more)."""
        pool, self._pool = self._pool, None
        if pool is None:
            return
        # the workers: terminated, not waited for (an interrupted study ends at once)
        procs = list(getattr(pool, "_processes", None) or {})   # pids
        pool.shutdown(wait=False, cancel_futures=True)
        for pid in procs:
            try:
                os.kill(pid, signal.SIGTERM)
            except (ProcessLookupError, PermissionError):
                pass

    def __enter__(self) -> TheoryProcesses:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class Started:
    """A computation :meth:`TheoryProcesses.start` started (the future of a worker), with
    the fallback of computing it here.  After :meth:`result`: ``cpu_s``, the CPU seconds of
    the computation (in its worker, or here), and ``waited_s``, the seconds the caller was
    blocked waiting for the worker (the report's critical path counts the first instead of
    the second: with unlimited cores a worker has a core of its own)."""

    def __init__(self, pool: TheoryProcesses, future: Future | None, fn: Callable[..., Any],
                 args: tuple, kwargs: dict):
        self._pool, self._future = pool, future
        self._call = (fn, args, kwargs)
        self.cpu_s = 0.0
        self.waited_s = 0.0

    def result(self) -> Any:
        fn, args, kwargs = self._call
        if self._future is not None:
            t0 = time.perf_counter()
            try:
                out, self.cpu_s = self._future.result()
                self.waited_s = time.perf_counter() - t0
                return out
            except BrokenProcessPool:       # a worker died: not trusted again
                self._pool.broken = True
        c0 = time.thread_time()
        out = fn(*args, **kwargs)
        self.cpu_s = time.thread_time() - c0
        return out
