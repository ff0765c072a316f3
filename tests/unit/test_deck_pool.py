"""The study's one pool of ngspice processes (analogue.circuit.deck_pool, issue 22: never
more processes than cores, the paper's decks first): plain functions as decks."""
import threading
import time

import pytest

from analogue import Runner
from analogue.circuit.deck_pool import DeckPool, WaitClock
from analogue.study.runs import _run_jobs


def test_never_more_at_once_than_workers_whoever_submits():
    pool = DeckPool(3)
    lock = threading.Lock()
    running, peak = [0], [0]

    def deck():
        with lock:
            running[0] += 1
            peak[0] = max(peak[0], running[0])
        time.sleep(0.01)
        with lock:
            running[0] -= 1
        return 1

    views = [pool.view(p) for p in (0, 1, 2)]
    submitters = [threading.Thread(target=lambda v=v: [v.submit(deck) for _ in range(20)])
                  for v in views]
    futs = []
    for t in submitters:
        t.start()
    for t in submitters:
        t.join()
    futs = [pool.submit(deck) for _ in range(10)]
    assert sum(f.result(timeout=10) for f in futs) == 10
    pool.shutdown(wait=True)
    assert peak[0] == 3


def test_lower_priority_first_then_fifo():
    pool = DeckPool(1)
    gate = threading.Event()
    order = []
    pool.submit(gate.wait)          # holds the one worker while the rest is queued
    futs = [pool.view(p).submit(order.append, (p, i))
            for i, p in enumerate([2, 1, 0, 1, 0, 2])]
    gate.set()
    for f in futs:
        f.result(timeout=10)
    pool.shutdown()
    assert order == [(0, 2), (0, 4), (1, 1), (1, 3), (2, 0), (2, 5)]


def test_exception_reaches_the_caller_and_the_worker_goes_on():
    pool = DeckPool(1)
    bad = pool.submit(lambda: 1 / 0)
    good = pool.submit(lambda: "ok")
    with pytest.raises(ZeroDivisionError):
        bad.result(timeout=10)
    assert good.result(timeout=10) == "ok"
    pool.shutdown()


def test_shutdown_cancels_queued_decks_and_refuses_new_ones():
    pool = DeckPool(1)
    gate, started = threading.Event(), threading.Event()
    first = pool.submit(lambda: started.set() or gate.wait(5))
    assert started.wait(10)         # under way: shutting down does not cancel it
    queued = [pool.view(1).submit(time.sleep, 0) for _ in range(5)]
    pool.shutdown(wait=False, cancel_futures=True)
    assert all(f.cancelled() for f in queued)
    gate.set()
    assert first.result(timeout=10) is True
    with pytest.raises(RuntimeError, match="shut down"):
        pool.view(0).submit(time.sleep, 0)
    # a view's shutdown leaves the owner's pool alone
    other = DeckPool(1)
    other.view(0).shutdown(cancel_futures=True)
    assert other.submit(lambda: 2).result(timeout=10) == 2
    other.shutdown()


@pytest.mark.parametrize("workers", [0, -1, 1.5, True])
def test_bad_worker_count_is_refused_by_name(workers):
    with pytest.raises(ValueError, match="workers must be an integer >= 1"):
        DeckPool(workers)


def test_an_experiments_jobs_on_the_study_pool_cancel_only_their_own_decks():
    """_run_jobs with the study's pool as the runner's executor: its decks go there (no pool
    of its own), and a failing job cancels this experiment's queued decks, not another
    user's."""
    pool = DeckPool(1)
    gate = threading.Event()
    pool.submit(gate.wait, 5)       # the one worker busy: everything below queues
    other = [pool.view(1).submit(lambda: "member deck") for _ in range(3)]
    names = []

    def failing(runner):
        f = runner.executor.submit(lambda: 1 / 0)
        names.append(threading.current_thread().name)
        gate.set()
        return f.result()

    def slow(runner):
        return [runner.executor.submit(time.sleep, 0.05).result() for _ in range(3)]

    runner = Runner(store=False, workers=1, progress=False, executor=pool.view(0))
    with pytest.raises(ZeroDivisionError):
        _run_jobs([("bad", failing), ("slow", slow)], runner)
    assert [f.result(timeout=10) for f in other] == ["member deck"] * 3
    pool.shutdown()


def test_wait_clock_counts_only_the_time_no_deck_of_its_caller_ran():
    """WaitClock.blocked_s: the seconds in which its caller's decks were all queued (the
    pool's one process busy with another caller's deck), not those in which one ran; a fake
    clock that moves only when the test moves it makes the sums exact."""
    now = [0.0]
    pool = DeckPool(1)
    try:
        gate, started = threading.Event(), threading.Event()
        other = pool.submit(lambda: (started.set(), gate.wait(10)))
        assert started.wait(10)
        clock = WaitClock(pool, clock=lambda: now[0])

        def deck():
            now[0] += 3.0            # running: not blocked
            return 7
        f = clock.submit(deck)       # queued at t = 0 behind the other caller's deck
        now[0] = 5.0
        gate.set()                   # the process is free at t = 5: blocked 5 s
        assert f.result(10) == 7 and other.result(10)
        assert clock.blocked_s == 5.0
        g = clock.submit(deck)       # a free process: never blocked
        assert g.result(10) == 7
        assert clock.blocked_s == 5.0
        # each deck ran 3 s (the fake clock): a stage's longest, then a new stage
        assert clock.stage_longest() == 3.0 and clock.stage_longest() == 0.0
        clock.shutdown()             # the pool is its owner's: still running
        assert pool.submit(lambda: 1).result(10) == 1
    finally:
        pool.shutdown()


def test_ahead_queues_before_the_same_and_the_next_priority():
    """A caller's calibrations (view.ahead()) run before every caller's bulk decks of its
    priority and the next, after those of a lower priority's calibrations."""
    pool = DeckPool(1)
    gate = threading.Event()
    order = []
    pool.submit(gate.wait)
    paper0, paper1, members = pool.view(0), pool.view(0.01), pool.view(1)
    futs = [paper0.submit(order.append, "bulk 0"), paper1.submit(order.append, "bulk 0.01"),
            members.submit(order.append, "member bulk"),
            members.ahead().submit(order.append, "member calibration"),
            paper1.ahead().submit(order.append, "calibration 0.01"),
            paper0.ahead().submit(order.append, "calibration 0")]
    gate.set()
    for f in futs:
        f.result(timeout=10)
    pool.shutdown()
    assert order == ["calibration 0", "calibration 0.01", "bulk 0", "bulk 0.01",
                     "member calibration", "member bulk"]


def test_the_papers_calibrations_run_ahead_of_the_bulk_decks(monkeypatch):
    """run_experiment_runs chooses tolerances and deck sizes with the runner's view moved
    ahead (its calibrations before any experiment's bulk decks), and runs its decks at the
    view's own priority."""
    from analogue.study import runs as R
    from analogue.study.experiments import load_experiment, standard_circuit
    from analogue.study.settings import RunOptions
    pool = DeckPool(1)
    seen = []

    def choose(model, spec, replicas, t_end, runner, check, observables, stages=None):
        seen.append(runner.executor.priority)
        raise RuntimeError("stop after the calibrations' runner")
    monkeypatch.setattr(R, "_choose", choose)
    opts = RunOptions(quick=True, progress=False, store=False, executor=pool.view(0.02))
    with pytest.raises(RuntimeError, match="stop"):
        R.run_experiment_runs(load_experiment(standard_circuit("slip")), opts)
    pool.shutdown()
    assert seen == [0.02 - 0.5] * 2        # the transition and the stationary runs', at once


def test_at_once_runs_calibrations_together_only_in_a_shared_pool():
    """tolerances.at_once: with a shared pool (the runner's executor) the calls run at once
    (each waits for the other here), their results in order; a runner that owns its
    processes runs them one after another (two at once would start twice its workers)."""
    from concurrent.futures import ThreadPoolExecutor
    from analogue.circuit.tolerances import at_once, shared_pool
    both = threading.Barrier(2, timeout=30)

    def call(x):
        both.wait()                       # raises BrokenBarrierError unless the other runs
        return x * 10
    with ThreadPoolExecutor(2) as ex:
        shared = Runner(executor=ex)
        assert shared_pool(shared)
        assert at_once([lambda: call(1), lambda: call(2)], shared) == [10, 20]
    order = []
    own = Runner(workers=2)
    assert not shared_pool(own)
    assert at_once([lambda: order.append(1) or 1, lambda: order.append(2) or 2], own) == [1, 2]
    assert order == [1, 2]
    with ThreadPoolExecutor(2) as ex:
        def bad():
            raise ValueError("calibration deck failed")
        with pytest.raises(ValueError, match="calibration deck failed"):
            at_once([lambda: 1, bad], Runner(executor=ex))


@pytest.mark.parametrize("name, at_once", [("slip", True), ("work", False)])
def test_an_experiments_two_calibrations_run_at_once_unless_they_share_decks(monkeypatch,
                                                                            name, at_once):
    """The transition and stationary runs' calibrations run at once in a shared pool, except
    where the stationary runs hold the noise as the transition runs do (work:
    stationary_hold_divisor 1): their calibrations are the same decks, which at once would
    both run (116 decks against 82), one after the other the second reads from the store."""
    from analogue.study import runs as R
    from analogue.study.experiments import load_experiment, standard_circuit
    from analogue.study.settings import RunOptions
    pool = DeckPool(1)
    threads = []

    def choose(model, spec, replicas, t_end, runner, check, observables, stages=None):
        threads.append(threading.get_ident())
        raise RuntimeError("stop after the calibrations' threads")
    monkeypatch.setattr(R, "_choose", choose)
    opts = RunOptions(quick=True, progress=False, store=False, executor=pool.view(0))
    exp = load_experiment(standard_circuit(name))
    assert (exp.report.stationary_hold_divisor == 1) is not at_once
    with pytest.raises(RuntimeError, match="stop"):
        R.run_experiment_runs(exp, opts)
    pool.shutdown()
    if at_once:       # both started, each in a calibration thread
        assert len(threads) == 2 and threading.get_ident() not in threads
    else:             # the first, in the caller's thread, stopped the run
        assert threads == [threading.get_ident()]
