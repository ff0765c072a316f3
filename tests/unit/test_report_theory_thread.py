"""The report's background theory thread and per-group curve failures (no ngspice)."""
from __future__ import annotations

import threading

import pytest

from analogue.report import pipeline as P
from analogue.report.theory_curves import FigureCurves


def test_theory_thread_runs_in_order_off_the_main_thread_and_records_phases():
    phases = P._Phases()
    pool = P._TheoryThread(phases)
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
    pool = P._TheoryThread(P._Phases())
    gate, started = threading.Event(), threading.Event()
    first = pool.submit("x", None, lambda: started.set() or gate.wait(30))
    second = pool.submit("y", None, lambda: 2)
    assert started.wait(30)
    pool.close()
    gate.set()
    assert first.result(timeout=30) is True
    assert second.cancelled()


def test_a_failed_curve_group_fails_only_its_figure():
    c = FigureCurves()
    c.set("stationary law", (1, 2, 3))
    c.fail("rate function", ValueError("no work windows"))
    assert c.get("stationary law") == (1, 2, 3)
    assert c.get("work paths") is None
    with pytest.raises(ValueError, match="no work windows"):
        c.get("rate function")
