"""The report's background threads (theory, circuit) and per-group curve failures (no
ngspice)."""
from __future__ import annotations

import threading

import pytest

from analogue.study import schedule as S
from analogue.study.theory_curves import FigureCurves


def test_theory_thread_runs_in_order_off_the_main_thread_and_records_phases():
    phases = S.Phases()
    pool = S.Workers(phases, "theory", 1, blas_limit=True)
    try:
        names = []
        f1 = pool.submit("exact theory", "a", lambda: names.append(threading.current_thread().name) or 1)
        f2 = pool.submit("exact theory", "b", lambda: 1 / 0)
        assert f1.result(timeout=30) == 1
        with pytest.raises(ZeroDivisionError):
            f2.result(timeout=30)
    finally:
        pool.close()
    assert names == ["analogue-theory"]
    assert [(p["phase"], p["experiment"], p["thread"]) for p in phases.items] == [
        ("exact theory", "a", "theory"), ("exact theory", "b", "theory")]
    assert set(phases.totals()) == {"exact theory"}


def test_close_cancels_work_not_started():
    pool = S.Workers(S.Phases(), "theory", 1, blas_limit=True)
    gate, started = threading.Event(), threading.Event()
    first = pool.submit("x", None, lambda: started.set() or gate.wait(30))
    second = pool.submit("y", None, lambda: 2)
    assert started.wait(30)
    pool.close()
    gate.set()
    assert first.result(timeout=30) is True
    assert second.cancelled()


def test_circuit_threads_run_two_tasks_at_once_and_record_their_thread():
    """Two circuit threads: the second queued task starts while the first still runs (each
    waits for the other to have started), and each phase names the circuit thread."""
    phases = S.Phases()
    pool = S.Workers(phases, "circuit", 2)
    a, b = threading.Event(), threading.Event()
    try:
        fa = pool.submit("circuit runs", "a", lambda: a.set() or b.wait(30))
        fb = pool.submit("circuit runs", "b", lambda: b.set() or a.wait(30))
        assert fa.result(timeout=60) is True and fb.result(timeout=60) is True
    finally:
        pool.close()
    assert sorted((p["experiment"], p["thread"]) for p in phases.items) == [
        ("a", "circuit"), ("b", "circuit")]


def test_abort_cancels_queued_work_and_returns_while_a_task_runs(monkeypatch):
    """After an interrupt nothing new starts, the ngspice processes are killed (repeatedly)
    and abort returns within its wait even if a task (pure numerics) does not stop."""
    import analogue.circuit.ngspice as ng
    kills = []
    monkeypatch.setattr(ng, "terminate_all", lambda: kills.append(1) or 0)
    pool = S.Workers(S.Phases(), "circuit", 1)
    gate, started = threading.Event(), threading.Event()
    first = pool.submit("circuit runs", "a", lambda: started.set() or gate.wait(30))
    second = pool.submit("circuit runs", "b", lambda: 2)
    assert started.wait(30)
    pool.abort(wait=0.5)
    assert second.cancelled() and not first.done()
    assert len(kills) >= 2
    gate.set()
    assert first.result(timeout=30) is True


def test_a_failed_curve_group_fails_only_its_figure():
    c = FigureCurves()
    c.set("stationary law", (1, 2, 3))
    c.fail("rate function", ValueError("no work windows"))
    assert c.get("stationary law") == (1, 2, 3)
    assert c.get("work paths") is None
    with pytest.raises(ValueError, match="no work windows"):
        c.get("rate function")
