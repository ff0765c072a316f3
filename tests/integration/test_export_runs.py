"""`analogue export` and `analogue.load_runs` on a tiny experiment: one netCDF file per run role,
identical to the runs in Python, metrics.csv from a report's metrics.json."""
import csv
import json
import shutil

import numpy as np
import pytest
from click.testing import CliRunner

import analogue
from analogue.cli import main

pytestmark = pytest.mark.slow

TINY = """
name = "tiny"
description = "a tiny experiment for the export tests"
[model]
tau_m = 1.0
delta = 0.7
a = 0.2
gamma = 10.0
[experiment]
v0 = [1.0, -1.5]
replicas = 2
t_end = 0.5
sample_dt = 0.01
seed = 3
[report]
stationary_replicas = 8
stationary_t_end = 0.5
stationary_burn_in = 0.1
check_replicas = 4
"""

ROLES = {"transition_v0=1", "transition_v0=-1.5", "stationary", "noise_free",
         "check_transition", "check_stationary"}


@pytest.fixture
def tiny(tmp_path):
    if shutil.which("ngspice") is None:
        pytest.skip("ngspice not installed")
    p = tmp_path / "tiny.toml"
    p.write_text(TINY)
    return p


def _comparison(exp, obs, z):
    return {"experiment": exp, "observable": obs, "circuit": 0.5, "circuit_stderr": 0.01,
            "theory": 0.49, "theory_kind": "exact", "z": z, "within_budget": True, "note": "",
            "budget": {"smoothing": 0.001, "bandwidth": 0.0, "integration": 0.0,
                       "sampling": 0.0, "finite_noise": 0.0, "total": 0.001,
                       "statistical": 0.03, "dominant": "statistical"}}


def test_export_writes_every_run_and_metrics_csv(tiny, tmp_path):
    store = tmp_path / "store"
    report = tmp_path / "rep"
    report.mkdir()
    (report / "metrics.json").write_text(json.dumps({"comparisons": [
        _comparison("tiny", "variance", 1.0), _comparison("other", "mean", None)]}))
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["export", str(tiny), "--out", str(out), "--store", str(store),
                                  "--workers", "1", "--report", str(report), "--no-progress"])
    assert r.exit_code == 0, r.output
    assert {p.stem for p in out.glob("*.nc")} == ROLES
    assert sorted(p.name for p in out.iterdir() if not p.name.endswith(".nc")) == ["metrics.csv"]

    runs = analogue.load_runs(tiny, store=store, workers=1)   # from the store now
    assert set(runs) == ROLES
    for role, ens in runs.items():
        back = analogue.open_ensemble(out / f"{role}.nc")
        np.testing.assert_array_equal(back.v, ens.v)
        np.testing.assert_array_equal(back.x, ens.x)
        np.testing.assert_array_equal(back.t, ens.t)
        assert back.meta["role"] == role and back.meta["experiment"] == "tiny"
        assert ens.meta["from_store"] == len(ens.meta["deck_sha256"])
    # the roles are what they say
    assert np.all(runs["transition_v0=1"].v[:, 0] == 1.0)
    assert np.all(runs["transition_v0=-1.5"].v[:, 0] == -1.5)
    assert runs["transition_v0=1"].replicas == 2 and runs["stationary"].replicas == 8
    nf = runs["noise_free"]      # noise off: the deterministic motion, eq. (13)
    model = analogue.Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
    for row in nf.v:
        np.testing.assert_allclose(row, model.deterministic(row[0], nf.t), atol=0.05)
    np.testing.assert_array_equal(np.sort(runs["noise_free"].v[:, 0]), [-1.5, 1.0])

    # the runs are indexed under the experiment's name (analogue store ls)
    from analogue.circuit.store_index import usage
    # (the named runs and whatever else they needed: the tolerance calibration)
    keys = {k for ens in runs.values() for k in ens.meta["store_keys"]}
    u = usage(store)
    assert u.unindexed_entries == 0, u
    assert u.experiments["tiny"]["entries"] == u.total_entries >= len(keys)

    rows = list(csv.DictReader((out / "metrics.csv").open()))
    assert len(rows) == 1 and rows[0]["experiment"] == "tiny"
    assert rows[0]["observable"] == "variance" and float(rows[0]["budget_smoothing"]) == 0.001
    assert rows[0]["budget_dominant"] == "statistical"


def test_export_without_report_and_with_a_foreign_report(tiny, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)       # no report/ here: no metrics.csv
    store = tmp_path / "store"
    r = CliRunner().invoke(main, ["export", str(tiny), "--store", str(store), "--workers", "1"])
    assert r.exit_code == 0, r.output
    out = tmp_path / "export" / "tiny"
    assert {p.name for p in out.iterdir()} == {f"{role}.nc" for role in ROLES}

    foreign = tmp_path / "foreign.json"
    foreign.write_text(json.dumps({"comparisons": [_comparison("other", "mean", 0.1)]}))
    r = CliRunner().invoke(main, ["export", str(tiny), "--out", str(tmp_path / "o2"),
                                  "--store", str(store), "--report", str(foreign)])
    assert r.exit_code == 2 and "no comparisons of experiment 'tiny'" in r.output
    assert not (tmp_path / "o2").exists()
