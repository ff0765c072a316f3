"""Tolerance and deck-size choices with ngspice: a deliberately coarse candidate is rejected
by the measured error, user values are used as given, and every choice is in ``meta``."""
import pytest

import analogue
from analogue import Model
from analogue.circuit import tolerances as tl
from analogue.circuit.mapping import CircuitSpec

pytestmark = pytest.mark.slow

STICK = Model(1.0, 0.7, 0.2, 10.0)


def test_coarse_tolerance_rejected_by_measurement(monkeypatch, tmp_path):
    # 200 holds of 16 replicas keep this short; reltol 0.05 with trtol 100 lets ngspice take
    # steps across whole noise holds' relaxations: its paths must miss the reference by more
    # than 0.1 statistical errors, while reltol 1e-4 must not.
    monkeypatch.setattr(tl, "CAL_HOLDS", 200)
    coarse = tl.Tolerances(0.05, 100.0, "gear")
    fine = tl.Tolerances(1e-4, 7.0, "gear")
    c = tl.choose_tolerances(STICK, CircuitSpec(), replicas=16, t_end=2.0,
                             candidates=(coarse, fine),
                             runner=analogue.Runner(store=tmp_path, workers=2))
    d = c.as_dict()
    by = {(x["reltol"], x["method"]): x for x in d["candidates"]}
    assert not by[(0.05, "gear")]["accepted"]
    assert by[(0.05, "gear")]["worst_ratio"] > 0.1
    # the coarse deck really is cheaper: it would have been chosen had it been accurate
    assert (by[(0.05, "gear")]["points_per_replica_hold"]
            < by[(1e-4, "gear")]["points_per_replica_hold"])
    assert c.tolerances == fine and c.source == "measured"


def test_choices_recorded_in_meta(tmp_path):
    kw = {"v0": 0.3, "t_end": 1.0, "replicas": 4, "seed": 3, "store": tmp_path, "progress": False}
    user = analogue.simulate(STICK, circuit=CircuitSpec(reltol=3e-4, trtol=10.0, method="trap"),
                             replicas_per_deck=2, **kw)
    t = user.meta["tolerances"]
    assert (t["reltol"], t["trtol"], t["method"], t["source"]) == (3e-4, 10.0, "trap", "user")
    assert user.meta["deck_size"] == {"replicas_per_deck": 2, "source": "user"}
    assert user.meta["deck_replicas"] == [2, 2]
    assert user.meta["circuit_spec"]["reltol"] == 3e-4
    # a small run: no calibration, today's fixed values, recorded as such
    small = analogue.simulate(STICK, **kw)
    assert small.meta["tolerances"]["source"] == "fixed"
    assert small.meta["tolerances"]["reltol"] == 1e-4
    assert small.meta["deck_size"]["source"] in ("default", "measured")
