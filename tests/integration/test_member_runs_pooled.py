"""A family member's circuit runs share one deck pool (issue 22, item 1:
``members._member_circuits``): each run is still exactly the run :func:`analogue.simulate`
makes with the same arguments (its calibrations, store keys, decks and ``meta``), and the
runs' timing is recorded for the report's critical path."""
from __future__ import annotations

import time

import numpy as np

import pytest

from analogue import Runner, simulate
from analogue.study import members as M
from analogue.study.experiments import load_experiment, standard_circuit

pytestmark = [pytest.mark.slow, pytest.mark.requires_ngspice]


def test_pooled_member_runs_are_simulate_s_runs(tmp_path):
    exp = load_experiment(standard_circuit("cubic"))
    sizes = M.member_sizes(exp, quick=True)
    runner = Runner(store=tmp_path / "store", progress=False, workers=2)
    # a check (tolerances given, deck size given), a nominal run (tolerances calibrated,
    # deck size given) and a run with both calibrated, as the members' runs are
    runs = [M._Run("check", np.array([0.1, -0.2]), 2.0, 2, 7, exp.check_spec(), 2),
            M._Run("nominal", np.array([0.1, -0.2, 0.3, 0.0]), 2.0, 4, 7, per_deck=2),
            M._Run("free", 0.2, 1.0, 3, 9)]
    done, timing = M._member_circuits(exp, sizes, runner, runs, time.perf_counter())
    assert set(done) == {"check", "nominal", "free"}
    assert timing["decks_run"] == sum(len(e.meta["deck_sha256"]) for e in done.values())
    assert timing["longest_deck_s"] > 0 and timing["before_decks_s"] >= 0
    per_run = timing["runs"]
    assert set(per_run) == set(done)
    assert max(r["longest_deck_s"] for r in per_run.values()) == timing["longest_deck_s"]
    assert all(r["calibration_s"] >= 0 for r in per_run.values())
    for r in runs:
        run = runner if r.per_deck is None else runner.replace(replicas_per_deck=r.per_deck)
        ref = simulate(exp.model, v0=r.v0, t_end=r.t_end, replicas=r.replicas, seed=r.seed,
                       sample_dt=sizes.sample_dt, circuit=exp.spec if r.spec is None else r.spec,
                       runner=run)
        got = done[r.name]
        # the same store keys: simulate ran none of the decks again
        assert not [w for w in ref.meta["ran_deck_wall_times"] if w is not None], r.name
        assert np.array_equal(got.v, ref.v) and np.array_equal(got.x, ref.x), r.name
        for k in ("deck_sha256", "tolerances", "deck_size", "replicas_per_deck", "seed"):
            assert got.meta[k] == ref.meta[k], (r.name, k)
