"""The deck-size chooser (analogue.circuit.deck_size) with given step counts (no ngspice)."""
import pytest

from analogue import Model
from analogue.circuit import deck_size as ds
from analogue.circuit.mapping import CircuitSpec

STICK = Model(1.0, 0.7, 0.2, 10.0)
SPEC = CircuitSpec(reltol=1e-4, trtol=7.0, method="gear")
FLAT = {4: 10.0, 16: 10.0, 64: 10.0}
STEEP = {4: 5.0, 16: 40.0, 64: 160.0}   # points per hold growing like r: small decks win


@pytest.mark.parametrize("bounds", [(1, 64), (4, 16), (8, 8), (16, 64), (5, 7)])
@pytest.mark.parametrize("measured", [FLAT, STEEP])
def test_choice_within_bounds(bounds, measured):
    c = ds.choose_deck_size(STICK, SPEC, replicas=500, t_end=10.0, workers=2, bounds=bounds,
                            measured=measured)
    assert bounds[0] <= c.replicas_per_deck <= bounds[1]


def test_flat_step_counts_fill_both_workers():
    # p(r) constant: per-replica cost falls with r (start-up and per-point overhead shared),
    # but 64 replicas in one deck leave the second worker idle: two decks of 32 are faster.
    c = ds.choose_deck_size(STICK, SPEC, replicas=64, t_end=10.0, workers=2, measured=FLAT)
    assert c.replicas_per_deck == 32


def test_steep_step_counts_prefer_small_decks():
    c = ds.choose_deck_size(STICK, SPEC, replicas=512, t_end=10.0, workers=2, measured=STEEP)
    assert c.replicas_per_deck == 4


def test_small_runs_default_without_calibration(monkeypatch):
    monkeypatch.setattr(ds, "_calibrate", lambda *a, **k: (_ for _ in ()).throw(AssertionError))
    c = ds.choose_deck_size(STICK, SPEC, replicas=40, t_end=1.0, workers=2,
                            min_replica_holds=10**6)
    assert c.source == "default" and c.replicas_per_deck == ds.DEFAULT_REPLICAS_PER_DECK
    c = ds.choose_deck_size(STICK, SPEC, replicas=40, t_end=1.0, workers=2, bounds=(1, 8),
                            min_replica_holds=10**6)
    assert c.replicas_per_deck == 8


@pytest.mark.parametrize("bounds", [(0, 4), (8, 4), (1.5, 4), "x"])
def test_bad_bounds(bounds):
    with pytest.raises(ValueError, match="bounds"):
        ds.choose_deck_size(STICK, SPEC, replicas=40, t_end=1.0, workers=2, bounds=bounds,
                            measured=FLAT)


@pytest.mark.parametrize("measured", [FLAT, STEEP])
@pytest.mark.parametrize("replicas", [32, 64, 500])
def test_choice_does_not_depend_on_the_machines_workers(measured, replicas):
    """The split sets the deck seeds: the same on every machine (issue 19, item 4).  Before,
    FLAT with 64 replicas chose 64 on one worker and 32 on two."""
    chosen = {ds.choose_deck_size(STICK, SPEC, replicas=replicas, t_end=10.0, workers=w,
                                  measured=measured).replicas_per_deck for w in (1, 2, 3, 16)}
    assert len(chosen) == 1


def test_the_calibration_runs_through_a_given_run():
    """A simulate-like ``run`` handed in (the way calibrations ran before the Runner; without
    one they run through decks.run_ensemble: tests/unit/test_runner.py) runs every
    calibration size, and one that is not callable is refused by name."""
    import numpy as np

    from analogue import Ensemble
    ds._MEMO.clear()
    with pytest.raises(TypeError, match="run must be callable"):
        ds.choose_deck_size(STICK, SPEC, replicas=500, t_end=10.0, workers=2, run="ngspice")
    calls = []

    def run(model, *, circuit, replicas, replicas_per_deck, **kw):
        calls.append((circuit, replicas, replicas_per_deck))
        t = np.linspace(0.0, 1.0, 3)
        # points growing like r per hold (STEEP): small decks must win
        pts = 5.0 * replicas * ds.CAL_HOLDS / 4
        return Ensemble(t, np.zeros((replicas, 3)), np.zeros((replicas, 3)),
                        {"deck_raw_points": [pts]})
    try:
        with pytest.deprecated_call(match=r"choose_deck_size\(run=\.\.\.\) is deprecated"):
            c = ds.choose_deck_size(STICK, SPEC, replicas=512, t_end=10.0, workers=2, run=run)
    finally:
        ds._MEMO.clear()
    assert [(r, d) for _, r, d in calls] == [(r, r) for r in ds.CAL_SIZES]
    assert all(spec == SPEC for spec, _, _ in calls)
    assert c.source == "measured" and c.replicas_per_deck == 4
