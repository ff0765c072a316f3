"""``simulate(..., runner=Runner(...))`` gives the very arrays of the run keywords it replaces
(issue 20: the Runner changes how decks run, never a number), and a run whose tolerances and
deck size are chosen gives the same arrays as the same run with the chosen values set."""
from __future__ import annotations

import numpy as np
import pytest

import analogue
from analogue import Runner
from analogue.circuit import deck_size as ds
from conftest import STICK_A02

pytestmark = pytest.mark.requires_ngspice

# the keys that time the call or name where it ran, not what it computed
TIMING = {"wall_time", "deck_wall_times", "ran_deck_wall_times", "from_store", "ran", "store"}


def _same(a, b) -> None:
    assert np.array_equal(a.t, b.t) and np.array_equal(a.v, b.v) and np.array_equal(a.x, b.x)
    assert (a.noise is None) == (b.noise is None)
    if a.noise is not None:
        assert np.array_equal(a.noise, b.noise)
    assert {k: v for k, v in a.meta.items() if k not in TIMING} == \
        {k: v for k, v in b.meta.items() if k not in TIMING}


def test_runner_gives_the_arrays_of_the_keywords(tmp_path) -> None:
    run = dict(v0="stationary", t_end=0.5, replicas=5, seed=11)
    old = analogue.simulate(STICK_A02, workers=2, replicas_per_deck=2, store=False,
                            progress=False, timeout=60.0, **run)
    new = analogue.simulate(STICK_A02, runner=Runner(workers=2, replicas_per_deck=2,
                                                     store=False, progress=False,
                                                     timeout=60.0), **run)
    _same(old, new)
    # one process or two, stored or not: the same numbers
    stored = analogue.simulate(STICK_A02, runner=Runner(workers=1, replicas_per_deck=2,
                                                        store=tmp_path, progress=False), **run)
    _same(old, stored)
    assert stored.meta["ran"] == 3
    again = analogue.simulate(STICK_A02, runner=Runner(workers=1, replicas_per_deck=2,
                                                       store=tmp_path, progress=False), **run)
    _same(old, again)
    assert again.meta["from_store"] == 3 and again.meta["ran"] == 0


def test_a_chosen_deck_size_runs_as_if_it_were_given(monkeypatch, tmp_path) -> None:
    """The deck-size calibration runs through decks.run_ensemble (not simulate); the run
    then equals the same run with that deck size given."""
    monkeypatch.setattr(ds, "CAL_HOLDS", 20)   # a short calibration
    ds._MEMO.clear()
    spec = {"reltol": 1e-3, "trtol": 7.0, "method": "gear"}
    run = dict(v0=0.2, t_end=0.3, replicas=6, seed=3, circuit=spec)
    try:
        chosen = analogue.simulate(STICK_A02, runner=Runner(workers=2, store=tmp_path,
                                                            progress=False), **run)
        # (a run this small gets the default size without calibrating; force the choice)
        measured = ds.choose_deck_size(STICK_A02, analogue.circuit.CircuitSpec(**spec),
                                       replicas=6, t_end=0.3, workers=2,
                                       runner=Runner(store=tmp_path, workers=2))
    finally:
        ds._MEMO.clear()
    assert chosen.meta["deck_size"]["source"] == "default"
    assert measured.source == "measured" and set(measured.points_per_hold) == set(ds.CAL_SIZES)
    given = analogue.simulate(STICK_A02, runner=Runner(workers=1, store=False, progress=False,
                                                       replicas_per_deck=16), **run)
    assert np.array_equal(chosen.v, given.v) and np.array_equal(chosen.x, given.x)
