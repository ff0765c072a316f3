"""One seed plan for a report (analogue.study.seeds): every seed is a named child of one
``numpy.random.SeedSequence(experiment seed)``, in ngspice's range, distinct within and across
experiments, and what cannot be a seed is refused."""
from __future__ import annotations

import numpy as np
import pytest

from analogue.circuit.experiments import PAPER_EXPERIMENTS, load_experiment, standard_circuit
from analogue.circuit.netlist import build_deck
from analogue.study.seeds import SEED_MAX, STREAMS, SeedPlan


def _via_spawn(seed: int, key: int, index: int) -> int:
    """The same seed through numpy's spawn tree (an independent route to the named keys):
    child ``key`` of the root, then its child ``index``."""
    child = np.random.SeedSequence(seed).spawn(key + 1)[key].spawn(index + 1)[index]
    return int(child.generate_state(1, np.uint32)[0]) % (2**31 - 1) + 1


def test_seeds_are_children_of_one_seed_sequence():
    for seed in (0, 7, 13, 2**31 - 1):
        plan = SeedPlan(seed)
        assert plan.stationary == _via_spawn(seed, STREAMS["stationary"], 0)
        assert plan.transition(2) == _via_spawn(seed, STREAMS["transition"], 2)
        assert plan.member_band == _via_spawn(seed, STREAMS["member_band"], 0)


def test_seeds_fit_ngspice_and_are_accepted_by_the_deck_builder():
    """ngspice reads `.options seed` as a C int: 1 .. 2**31 - 1 (build_deck refuses more)."""
    seeds = [v for s in range(50) for v in SeedPlan(s).all(4).values()]
    assert SEED_MAX == 2**31 - 1
    assert min(seeds) >= 1 and max(seeds) <= 2**31 - 1
    exp = load_experiment(standard_circuit("stick"))
    deck = build_deck(exp.mapping(), replicas=1, v0=[0.0], t_end=0.1, sample_dt=0.01,
                      seed=max(seeds))
    assert f".options seed={max(seeds)} " in deck.text
    with pytest.raises(ValueError, match="seed"):
        build_deck(exp.mapping(), replicas=1, v0=[0.0], t_end=0.1, sample_dt=0.01,
                   seed=2**31)


def test_every_seed_of_an_experiment_is_distinct_and_experiments_do_not_share_seeds():
    plans = [SeedPlan(s).all(4) for s in range(200)]
    for p in plans:
        assert len(set(p.values())) == len(p)
    every = [v for p in plans for v in p.values()]
    assert len(set(every)) == len(every)
    # the standard experiments' seeds differ, so their reports share no realisation
    assert len({load_experiment(standard_circuit(n)).seed for n in PAPER_EXPERIMENTS}) == len(PAPER_EXPERIMENTS)


def test_the_plan_is_recorded_for_the_provenance():
    d = SeedPlan(5).describe()
    assert d["entropy"] == 5 and d["streams"] == STREAMS
    assert len(set(STREAMS.values())) == len(STREAMS)
    assert min(STREAMS.values()) >= 100        # clear of simulate's, budget's, board's keys


@pytest.mark.parametrize("bad", [-1, 1.5, True, "3"])
def test_bad_seeds_are_refused(bad):
    with pytest.raises(ValueError, match="seed must be an integer"):
        SeedPlan(bad)


def test_bad_streams_and_indices_are_refused():
    with pytest.raises(ValueError, match="v0 index"):
        SeedPlan(1).transition(100)
    with pytest.raises(ValueError, match="v0 index"):
        SeedPlan(1).transition(True)
    with pytest.raises(ValueError, match="seed stream must be one of"):
        SeedPlan(1).stream("nope")
    with pytest.raises(ValueError, match="has one seed"):
        SeedPlan(1).stream("stationary", 1)
    with pytest.raises(AttributeError):
        _ = SeedPlan(1).member  # the old offset name is gone
