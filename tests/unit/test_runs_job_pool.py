"""The report's deck pool (analogue.study.runs._run_jobs): every job's decks on one pool, queued
in the jobs' order, the caller's context (store-key collectors) seen by every job, and a failing
job raising in the caller without hanging the others (no ngspice: plain functions as decks)."""
import threading
import time

import pytest

from analogue import Runner
from analogue.circuit.store_index import collecting_keys, note_keys
from analogue.study.runs import _run_jobs


def _job(name, log, n=2, sleep=0.01, fail=False):
    def fn(runner):
        executor = runner.executor

        def deck(i):
            log.append((name, i, threading.current_thread().name))
            time.sleep(sleep)
            if fail:
                raise RuntimeError(f"{name} failed")
            return i
        futs = [executor.submit(deck, i) for i in range(n)]
        note_keys([f"{name}-key"])
        return [f.result() for f in futs]
    return fn


def _runner(workers):
    return Runner(store=False, workers=workers, progress=False)


def test_each_job_gets_the_callers_runner_with_the_pool_as_executor():
    """No dict of run options between the layers (issue 20): a job's runner is the caller's,
    its executor the shared pool."""
    base = Runner(store=False, workers=2, timeout=7.0, progress=False, label="x")
    out = _run_jobs([("a", lambda r: r), ("b", lambda r: r)], base)
    for r in out.values():
        assert r.executor is not None and r.replace(executor=None) == base
    assert out["a"].executor is not out["b"].executor


def test_jobs_share_one_pool_in_order():
    log = []
    out = _run_jobs([(f"j{k}", _job(f"j{k}", log)) for k in range(4)], _runner(1))
    assert out == {f"j{k}": [0, 1] for k in range(4)}
    # one worker: the decks ran one at a time in queue order; each job's first deck queued
    # after the previous job's first (its later decks may interleave with the next job's)
    first = list(dict.fromkeys(n for n, _, _ in log))
    assert first == [f"j{k}" for k in range(4)]
    assert sorted((n, i) for n, i, _ in log) == [(f"j{k}", i) for k in range(4) for i in range(2)]
    assert {t for *_, t in log} == {log[0][2]} and log[0][2].startswith("analogue-deck")


def test_jobs_see_the_callers_key_collector():
    log = []
    with collecting_keys() as bag:
        _run_jobs([("a", _job("a", log)), ("b", _job("b", log))], _runner(2))
    assert {"a-key", "b-key"} <= bag


def test_a_failing_job_raises_in_the_caller():
    log = []
    jobs = [("first", _job("first", log, n=1, sleep=0.3)), ("bad", _job("bad", log, fail=True)),
            ("slow", _job("slow", log, n=40, sleep=0.05))]
    t0 = time.perf_counter()
    with pytest.raises(RuntimeError, match="bad failed"):
        _run_jobs(jobs, _runner(2))
    # the failure stopped the rest: the slow job's queued decks were cancelled (all 40 would
    # take 1 s on the two workers)
    assert time.perf_counter() - t0 < 1.5
    assert sum(n == "slow" for n, _, _ in log) < 40


def test_a_job_without_decks_does_not_block_the_next():
    out = _run_jobs([("none", lambda r: "stored"), ("one", lambda r: r.executor.submit(
        lambda: 1).result())], _runner(2))
    assert out == {"none": "stored", "one": 1}
