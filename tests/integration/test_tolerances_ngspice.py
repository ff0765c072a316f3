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


def test_calibration_in_a_shared_pool_chooses_what_one_after_another_does(monkeypatch,
                                                                         tmp_path):
    """With the study's deck pool (a shared executor) the reference and the candidates run
    at once (tolerances.at_once), and the deck sizes too: every measured number and the
    choice are those of the runs one after another, each on its own store."""
    from analogue.circuit import deck_size as ds
    from analogue.circuit.deck_pool import DeckPool
    monkeypatch.setattr(tl, "CAL_HOLDS", 200)
    monkeypatch.setattr(ds, "CAL_HOLDS", 100)
    cands = (tl.Tolerances(1e-3, 20.0, "trap"), tl.Tolerances(1e-4, 7.0, "gear"))
    got = {}
    for name in ("one after another", "at once"):
        tl._MEMO.clear()
        ds._MEMO.clear()
        pool = DeckPool(2) if name == "at once" else None
        runner = analogue.Runner(store=tmp_path / name, workers=2,
                                 **({"executor": pool.view(0)} if pool else {}))
        assert tl.shared_pool(runner) == (pool is not None)
        try:
            choice = tl.choose_tolerances(STICK, CircuitSpec(), replicas=64, t_end=20.0,
                                          candidates=cands, runner=runner)
            spec = CircuitSpec().replace(**choice.tolerances.as_dict())
            deck = ds.choose_deck_size(STICK, spec, replicas=64, t_end=20.0, workers=2,
                                       runner=runner)
        finally:
            if pool is not None:
                pool.shutdown()
        got[name] = (choice.as_dict(), deck.as_dict())
    # (the choices' records hold measured counts and ratios, no times: equal, not close)
    assert got["at once"] == got["one after another"]
    assert got["at once"][1]["source"] == "measured"


def test_two_runs_needing_one_calibration_at_once_run_its_decks_once(monkeypatch, tmp_path):
    """An experiment whose stationary runs hold the noise as its transition runs do asks for
    the same calibration twice at once (tolerances.at_once): its decks run once, and the
    second call reads them from the store (tolerances.one_at_a_time)."""
    import concurrent.futures as cf
    import threading
    from analogue.circuit import deck_size as ds

    class Counting(cf.ThreadPoolExecutor):
        def __init__(self):
            super().__init__(2)
            self.decks = 0
            self.lock = threading.Lock()

        def submit(self, fn, /, *a, **k):
            with self.lock:
                self.decks += 1
            return super().submit(fn, *a, **k)
    monkeypatch.setattr(tl, "CAL_HOLDS", 100)
    monkeypatch.setattr(ds, "CAL_HOLDS", 50)
    cands = (tl.Tolerances(1e-3, 20.0, "trap"), tl.Tolerances(1e-4, 7.0, "gear"))

    def calibrate(runner):
        choice = tl.choose_tolerances(STICK, CircuitSpec(), replicas=64, t_end=20.0,
                                      candidates=cands, runner=runner)
        spec = CircuitSpec().replace(**choice.tolerances.as_dict())
        ds.choose_deck_size(STICK, spec, replicas=64, t_end=20.0, workers=2, runner=runner)
        return choice.as_dict()
    counts = {}
    for name, calls in (("once", 1), ("twice at once", 2)):
        tl._MEMO.clear()
        ds._MEMO.clear()
        ex = Counting()
        runner = analogue.Runner(store=tmp_path / name, workers=2, executor=ex)
        try:
            got = tl.at_once([lambda: calibrate(runner)] * calls, runner)
        finally:
            ex.shutdown()
        # the same choice; the second call's ratios come from the decks read back from the
        # store, which agree with the fresh ones to round-off (1e-14 relative)
        ratios = ("worst_ratio",)
        for g in got[1:]:
            assert {k: v for k, v in g.items() if k not in ("candidates", *ratios)} == \
                {k: v for k, v in got[0].items() if k not in ("candidates", *ratios)}
            assert g["worst_ratio"] == pytest.approx(got[0]["worst_ratio"], rel=1e-9)
            assert [c["points_per_replica_hold"] for c in g["candidates"]] == \
                [c["points_per_replica_hold"] for c in got[0]["candidates"]]
        counts[name] = ex.decks
    # reference and two candidates of 16 replicas in decks of 4, then three deck sizes
    assert counts["once"] == 3 * 4 + 3
    assert counts["twice at once"] == counts["once"]
