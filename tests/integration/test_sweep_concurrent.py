"""A sweep's points run at once (issue 22: more cores, less waiting, never more processes than
cores): the numbers are those of the points one after another, bit for bit; every deck of
every point goes to one pool of ``workers`` processes; each point is its own phase; a failing
point stops the others and nothing is written.

Cost: a tiny user experiment (8 replicas of 2 time units, 8 x 8 stationary, quick size:
2 replicas a run) at three values of a, run twice into separate stores (~2 s in all)."""
import threading

import numpy as np
import pytest

import analogue
import analogue.circuit.decks as decks_mod
from analogue.study import sweep as sweep_mod
from analogue.study.schedule import Phases

pytestmark = [pytest.mark.requires_ngspice]

# (test_sweep's tiny experiment, started from rest and from v0 = 0.3: the first passage runs)
TOML = """
name = "rest"
[model]
tau_m = 1.0
delta = 0.7
a = 0.2
gamma = 10.0
[circuit]
time_scale = 1e-3
capacitance = 100e-9
[experiment]
v0 = [0.0, 0.3]
replicas = 8
t_end = 2.0
sample_dt = 0.01
[report]
stationary_replicas = 8
stationary_t_end = 8.0
stationary_burn_in = 1.0
check_replicas = 4
"""
GRID = {"a": [0.0, 0.2, 0.4]}


@pytest.fixture
def toml(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(TOML)
    return p


class _Counter:
    """Wraps ``run_batch``: the most decks running at once, and the decks run."""

    def __init__(self, inner):
        self.inner, self.lock = inner, threading.Lock()
        self.now = self.most = self.calls = 0

    def __call__(self, task):
        with self.lock:
            self.now += 1
            self.calls += 1
            self.most = max(self.most, self.now)
        try:
            return self.inner(task)
        finally:
            with self.lock:
                self.now -= 1


def _same(a, b) -> list[str]:
    """Names of the data variables (timings aside) that differ in any bit (NaN equal to NaN)."""
    out = []
    for name in a.data_vars:
        if name.startswith("time_"):
            continue
        x, y = a[name].values, b[name].values
        if x.dtype != y.dtype or x.shape != y.shape or not (
                np.array_equal(x, y, equal_nan=x.dtype.kind == "f")):
            out.append(name)
    return out


def test_concurrent_points_match_the_sequential_sweep_bit_for_bit(toml, tmp_path, monkeypatch):
    seq = analogue.sweep(toml, GRID, quick=True, store=tmp_path / "s1", progress=False,
                         max_concurrent_points=1)
    counter = _Counter(decks_mod.run_batch)
    monkeypatch.setattr(decks_mod, "run_batch", counter)
    phases = Phases()
    conc = analogue.sweep(toml, GRID, quick=True, store=tmp_path / "s2", progress=False,
                          workers=2, phases=phases)
    assert _same(seq, conc) == []
    assert np.isfinite(conc["first_passage_mean"].values).all()
    assert {k: v for k, v in seq.attrs.items() if k not in ("date", "wall_time_s")} == {
        k: v for k, v in conc.attrs.items() if k not in ("date", "wall_time_s")}
    # every deck ran (none from the other store), never more than `workers` at once
    assert counter.calls > 0 and 1 <= counter.most <= 2
    # one phase per point, in the sweep's threads, and the points ran at once
    points = [p for p in phases.items if p["phase"] == "sweep point"]
    assert sorted(p["experiment"] for p in points) == ["rest a=0", "rest a=0.2", "rest a=0.4"]
    assert {p["thread"] for p in points} == {"sweep"}
    # its seconds with unlimited cores: its decks' batches counted as their longest deck
    assert all(0 < p["unlimited_s"] <= p["seconds"] for p in points)
    first_end = min(p["start_s"] + p["seconds"] for p in points)
    assert sum(p["start_s"] < first_end for p in points) >= 2


def test_one_worker_runs_one_deck_at_a_time(toml, tmp_path, monkeypatch):
    counter = _Counter(decks_mod.run_batch)
    monkeypatch.setattr(decks_mod, "run_batch", counter)
    analogue.sweep(toml, GRID, quick=True, store=tmp_path / "s", progress=False, workers=1)
    assert counter.calls > 0 and counter.most == 1


def test_a_failing_point_stops_the_sweep_and_writes_nothing(toml, tmp_path, monkeypatch):
    inner = sweep_mod._point

    def point(plan, i, runner, stop=None):
        if i == 1:
            raise RuntimeError("point 1 broke")
        return inner(plan, i, runner, stop)
    monkeypatch.setattr(sweep_mod, "_point", point)
    with pytest.raises(RuntimeError, match="point 1 broke"):
        analogue.sweep(toml, GRID, quick=True, store=tmp_path / "s", progress=False,
                       workers=2, out=tmp_path / "out")
    assert not (tmp_path / "out" / "sweep.nc").exists()
    assert [t.name for t in threading.enumerate() if "analogue-sweep" in t.name] == []


def test_max_concurrent_points_is_checked(toml):
    with pytest.raises(ValueError, match="max_concurrent_points"):
        analogue.sweep(toml, GRID, quick=True, max_concurrent_points=0)
