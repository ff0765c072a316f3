"""One seed plan for a report (analogue.study.seeds): it must keep the seeds the stored runs
were made with (read from the provenance of a quick paper report on main before the plan
existed, commit fb15674), and refuse what cannot be a seed."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from analogue.circuit.experiments import PAPER_EXPERIMENTS, load_experiment, standard_circuit
from analogue.study.seeds import SeedPlan

RECORDED = Path(__file__).with_name("data") / "quick_paper_seeds.json"


def test_circuit_seeds_are_those_recorded_before_the_plan():
    recorded = json.loads(RECORDED.read_text())
    for name in PAPER_EXPERIMENTS:
        exp = load_experiment(standard_circuit(name))
        plan = SeedPlan(exp.seed)
        want = recorded[name]
        assert plan.stationary == want["stationary"]
        assert plan.noise_free == want["noise_free"]
        for i, v0 in enumerate(exp.v0):
            assert plan.transition(i) == want[f"transition v0={v0:g}"]


def test_every_seed_of_an_experiment_is_distinct_and_experiments_do_not_share_seeds():
    a, b = SeedPlan(1).all(3), SeedPlan(2).all(3)
    assert len(set(a.values())) == len(a)
    assert not set(a.values()) & set(b.values())


@pytest.mark.parametrize("bad", [-1, 1.5, True, "3"])
def test_bad_seeds_are_refused(bad):
    with pytest.raises(ValueError, match="seed must be an integer"):
        SeedPlan(bad)


def test_v0_index_out_of_range_is_refused():
    with pytest.raises(ValueError, match="v0 index"):
        SeedPlan(1).transition(100)
