"""A study's theory processes (issue 22): the same numbers as in-process, a broken pool
falls back to the calling thread, the policy that starts them."""
import math
import os
import time
import types

import numpy as np
import pytest

from analogue import Model
from analogue.study import schedule as SCH
from analogue.study.processes import TheoryProcesses
from analogue.study.theory_curves import _finite_tau_pdfs


def test_work_densities_in_processes_are_bit_for_bit_the_in_process_ones():
    m = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
    centres = np.round(np.linspace(-0.4, 0.8, 7), 12)
    dists = {tau: types.SimpleNamespace(centres=centres, contributing=np.full(7, 50))
             for tau in (2.0, 5.0)}
    dists[5.0].contributing[0] = 3          # below min_replicas: not evaluated
    timing_here: dict = {}
    here = _finite_tau_pdfs(m, dists, cache=False, timing=timing_here)
    assert timing_here == {}                      # no workers, nothing to record
    timing: dict = {}
    with TheoryProcesses(2) as procs:
        there = _finite_tau_pdfs(m, dists, cache=False, processes=procs, timing=timing)
        assert not procs.broken
    # the critical path's record: the waits for the workers and their longest CPU seconds
    assert timing["longest_process_s"] > 0 and timing["process_wait_s"] >= 0
    assert list(there) == list(here) == [2.0, 5.0]
    assert len(there[5.0]) == 6
    for tau in here:
        assert list(there[tau]) == list(here[tau])
        np.testing.assert_array_equal(np.array(list(there[tau].values())),
                                      np.array(list(here[tau].values())))
        assert all(v > 0 for v in here[tau].values())


def test_a_killed_worker_breaks_the_pool_and_the_work_is_done_here():
    procs = TheoryProcesses(1)
    try:
        assert procs.run(math.sqrt, 16.0) == 4.0
        spin = procs.start(sum, range(3_000_000))
        assert spin.result() == sum(range(3_000_000))
        assert spin.cpu_s > 0 and spin.waited_s >= 0   # measured in the worker
        started = procs.start(time.sleep, 1.0)
        deadline = time.time() + 30
        while not started._future.running() and time.time() < deadline:
            time.sleep(0.02)
        for pid in list(procs._pool._processes):
            os.kill(pid, 9)
        assert started.result() is None        # time.sleep(1.0), run here instead
        assert procs.broken and started.waited_s == 0.0
        assert procs.run(math.sqrt, 9.0) == 3.0   # here, not in a broken pool
    finally:
        procs.close()
    with pytest.raises(Exception, match="closed or broken"):
        procs.submit(math.sqrt, 1.0)
    assert procs.run(math.sqrt, 25.0) == 5.0    # closed: computed here


def test_close_ends_the_workers_and_drops_the_queue():
    procs = TheoryProcesses(1)
    first = procs.start(time.sleep, 30.0)
    queued = procs.submit(math.sqrt, 4.0)
    deadline = time.time() + 30
    while not first._future.running() and time.time() < deadline:
        time.sleep(0.02)
    pids = list(procs._pool._processes)
    assert pids
    t0 = time.perf_counter()
    procs.close()
    # (a task already handed to the workers' queue cannot be cancelled: it fails instead)
    assert queued.cancelled() or queued.exception(timeout=20) is not None
    for pid in pids:                         # terminated, not left to finish its 30 s
        deadline = time.time() + 10
        while time.time() < deadline:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                break
            time.sleep(0.05)
        else:
            pytest.fail(f"theory worker {pid} still alive 10 s after close")
    assert time.perf_counter() - t0 < 25     # (a hang detector, not a timing)


def _exp(name, a, taus):
    return types.SimpleNamespace(name=name, model=types.SimpleNamespace(a=a), work_taus=taus)


def test_the_policy_one_process_per_work_window_within_the_cores(monkeypatch):
    made = []
    monkeypatch.setattr(SCH, "TheoryProcesses", lambda n: made.append(n) or n)
    monkeypatch.delenv(SCH.THEORY_PROCESSES_ENV, raising=False)
    work = _exp("work", 0.5, (1.0, 2.0, 5.0, 10.0))
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 2)
    assert SCH.theory_processes([work]) == 2
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 16)
    assert SCH.theory_processes([work]) == 4
    assert SCH.theory_processes([_exp("w2", 0.5, (1.0, 2.0))]) == 2
    assert SCH.theory_processes([_exp("a0", 0.0, (1.0, 2.0))]) is None      # no work
    assert SCH.theory_processes([_exp("none", 0.5, ())]) is None
    monkeypatch.setattr(SCH, "usable_cpus", lambda: 1)
    assert SCH.theory_processes([work]) is None                              # one core
    monkeypatch.setenv(SCH.THEORY_PROCESSES_ENV, "3")
    assert SCH.theory_processes([work]) == 3                                 # the user's
    monkeypatch.setenv(SCH.THEORY_PROCESSES_ENV, "0")
    assert SCH.theory_processes([work]) is None
    for bad in ("two", "-1"):
        monkeypatch.setenv(SCH.THEORY_PROCESSES_ENV, bad)
        with pytest.raises(ValueError, match=SCH.THEORY_PROCESSES_ENV):
            SCH.theory_processes([work])
    assert made == [2, 4, 2, 3]


def test_workers_that_cannot_start_leave_the_work_to_the_calling_thread(monkeypatch):
    """A process limit or a sandbox without fork: submitting raises OSError; the pool is
    marked broken and every computation runs in the calling thread instead of failing the
    figure that needs it."""
    procs = TheoryProcesses(1)
    try:
        def no_fork(*a, **k):
            raise OSError(11, "Resource temporarily unavailable")
        monkeypatch.setattr(procs._pool, "submit", no_fork)
        started = procs.start(math.sqrt, 49.0)
        assert procs.broken and started.result() == 7.0
        assert procs.run(math.sqrt, 4.0) == 2.0
    finally:
        monkeypatch.undo()
        procs.close()


def test_a_bad_process_count_is_refused_before_the_study_starts(monkeypatch):
    """ANALOGUE_THEORY_PROCESSES is checked with the experiments, before any pool, thread
    or process is started: the error names the variable, and no thread is left behind."""
    import threading

    from analogue.study import run as S
    from analogue.study.experiments import load_experiment, standard_circuit
    from analogue.study.settings import RunOptions
    monkeypatch.setenv(SCH.THEORY_PROCESSES_ENV, "lots")
    before = set(threading.enumerate())
    with pytest.raises(ValueError, match="ANALOGUE_THEORY_PROCESSES must be a whole number"):
        S.run_study([load_experiment(standard_circuit("work"))],
                    opts=RunOptions(quick=True, progress=False))
    assert set(threading.enumerate()) <= before
