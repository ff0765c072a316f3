"""Fault injection: absurd sizes (issue 8, section 5).

A request that cannot fit is refused before anything is allocated or any ngspice starts, with
one line naming the parameters and the limit: replicas x time points against the memory
limit (half the available memory, or ``ANALOGUE_MEMORY_LIMIT``), the bytes to be stored against
the store limit (free space on the store's disk, or ``ANALOGUE_STORE_LIMIT``).  Requests under
the limits still run.
"""
from __future__ import annotations

import time
import tracemalloc

import numpy as np
import pytest

import analogue
from analogue.circuit import limits
from analogue.circuit import ngspice as ng
from analogue.circuit import simulate as sim
from conftest import STICK_A02

BASE = {"v0": 0.4, "seed": 1, "progress": False, "workers": 1}


@pytest.fixture
def no_ngspice(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("ngspice must not start for a refused request")
    monkeypatch.setattr(ng, "run_deck", refuse)


def _refused(match_all, **kw):
    tracemalloc.start()
    t0 = time.monotonic()
    try:
        with pytest.raises(ValueError) as exc:
            analogue.simulate(STICK_A02, **{**BASE, **kw})
        elapsed = time.monotonic() - t0
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    msg = str(exc.value)
    assert "\n" not in msg, msg
    for part in match_all:
        assert part in msg, (part, msg)
    assert elapsed < 5.0 and peak < 50e6, (elapsed, peak)  # refused before allocating
    return msg


@pytest.mark.parametrize("kw,parts", [
    ({"t_end": 1e9, "sample_dt": 1e-9, "replicas": 8}, ["t_end=1e+09", "sample_dt=1e-09", "limit"]),
    ({"t_end": 1e9, "replicas": 8}, ["t_end=1e+09", "sample_dt", "default", "limit"]),
    ({"t_end": 1.0, "replicas": 10**12}, ["replicas=1000000000000", "limit"]),
    ({"t_end": 1e308, "replicas": 1}, ["t_end=1e+308"]),
    ({"t_end": 1e300, "sample_dt": 1e-300, "replicas": 1}, ["t_end=1e+300", "sample_dt=1e-300"]),
])
def test_absurd_requests_are_refused_in_one_line(no_ngspice, tmp_path, kw, parts):
    _refused(parts, store=tmp_path, **kw)


def test_time_grid_refuses_before_allocating():
    for t_end, dt in ((1e9, 1e-9), (1e300, 1e-300), (1e308, 1e-10)):
        with pytest.raises(ValueError, match="time points"):
            sim.time_grid(t_end, dt)


def test_memory_limit_from_environment(no_ngspice, monkeypatch, tmp_path):
    monkeypatch.setenv("ANALOGUE_MEMORY_LIMIT", "200000")
    # 64 replicas x 1001 points x (v, x) x 8 bytes = 1.0 MB > 0.2 MB
    msg = _refused(["replicas=64", "limit of 2e+05 bytes", "ANALOGUE_MEMORY_LIMIT"],
                   t_end=10.0, replicas=64, store=tmp_path)
    assert "t_end=10" in msg


def test_store_limit_from_environment(no_ngspice, monkeypatch, tmp_path):
    monkeypatch.setenv("ANALOGUE_STORE_LIMIT", "100k")
    msg = _refused([str(tmp_path / "st"), "limit of 1.02e+05 bytes", "ANALOGUE_STORE_LIMIT",
                    "store=False"], t_end=10.0, replicas=16, store=tmp_path / "st")
    assert "replicas=16" in msg
    assert not (tmp_path / "st").exists()  # nothing was created


@pytest.mark.parametrize("value", ["lots", "-5", "0", "1e400", "12Q"])
def test_bad_limit_settings_are_named(monkeypatch, value, tmp_path):
    monkeypatch.setenv("ANALOGUE_MEMORY_LIMIT", value)
    with pytest.raises(ValueError, match="ANALOGUE_MEMORY_LIMIT"):
        analogue.simulate(STICK_A02, t_end=1.0, replicas=1, store=tmp_path, **BASE)


def test_within_the_limits_it_runs(monkeypatch, tmp_path):
    """Same tight settings, a request that fits: it runs and is stored (the limits are not
    refusing everything)."""
    monkeypatch.setenv("ANALOGUE_MEMORY_LIMIT", "200000")
    monkeypatch.setenv("ANALOGUE_STORE_LIMIT", "100k")
    e = analogue.simulate(STICK_A02, t_end=1.0, replicas=2, store=tmp_path, **BASE)
    assert e.v.shape == (2, 101) and np.all(np.isfinite(e.v)) and e.meta["ran"] == 1
    # without a store only memory counts: the store limit does not refuse this one
    monkeypatch.delenv("ANALOGUE_MEMORY_LIMIT")
    e2 = analogue.simulate(STICK_A02, t_end=10.0, replicas=4, store=False, **BASE)
    assert e2.v.shape == (4, 1001)


def test_limits_are_reported():
    mem, why = limits.memory_limit()
    assert mem > 0 and "memory" in why


# ------------------------------------------------------------- wrong types, odd values
@pytest.mark.parametrize("change,name", [
    ({"replicas": 2.0}, "replicas"), ({"replicas": True}, "replicas"),
    ({"replicas": "2"}, "replicas"), ({"seed": 1.5}, "seed"), ({"seed": False}, "seed"),
    ({"t_end": "1"}, "t_end"), ({"t_end": True}, "t_end"), ({"sample_dt": "0.1"}, "sample_dt"),
    ({"workers": 1.0}, "workers"), ({"replicas_per_deck": "4"}, "replicas_per_deck"),
    ({"timeout": "10"}, "timeout"), ({"timeout": True}, "timeout"),
    ({"progress": 1}, "progress"), ({"return_noise": "yes"}, "return_noise"),
    ({"store": 3.5}, "store"), ({"circuit": 3}, "circuit"), ({"scheduler": 8786}, "scheduler"),
])
def test_wrong_types_are_type_errors(no_ngspice, change, name):
    kw = {**BASE, "t_end": 1.0, "replicas": 2, "store": False, **change}
    with pytest.raises(TypeError, match=name) as exc:
        analogue.simulate(STICK_A02, **kw)
    assert isinstance(exc.value, ValueError)  # what these raised before: callers keep working
    with pytest.raises(TypeError, match="model"):
        analogue.simulate({"tau_m": 1.0}, **{**BASE, "t_end": 1.0, "replicas": 2})


@pytest.mark.parametrize("change,name", [
    ({"t_end": 10**400}, "t_end"), ({"t_end": float("inf")}, "t_end"),
    ({"timeout": float("nan")}, "timeout"), ({"sample_dt": 10**400}, "sample_dt"),
    ({"scheduler": "tcp://host:notaport"}, "scheduler"),
    ({"scheduler": "tcp://h:99999"}, "scheduler"), ({"scheduler": "ucx://host:8786"}, "scheduler"),
    ({"scheduler": "http://host:8786"}, "scheduler"),
    ({"store": ""}, "store"),
])
def test_odd_values_are_value_errors(no_ngspice, change, name):
    kw = {**BASE, "t_end": 1.0, "replicas": 2, "store": False, **change}
    with pytest.raises(ValueError, match=name) as exc:
        analogue.simulate(STICK_A02, **kw)
    assert not isinstance(exc.value, TypeError)
    assert "\n" not in str(exc.value)
