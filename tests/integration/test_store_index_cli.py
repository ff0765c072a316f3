"""The store index by experiment and `analogue store ls | du | prune`, on a store filled
directly (no ngspice): sizes and counts, pruning by experiment, unindexed, age and size."""
import json
import os
import time

import numpy as np
import pytest
from click.testing import CliRunner

from analogue import Ensemble
from analogue.circuit.store import RunStore
from analogue.circuit.store_index import parse_size, prune, record_runs, usage
from analogue.cli import main


def _key(i: int) -> str:
    return f"{i:064x}"


@pytest.fixture
def store(tmp_path):
    st = RunStore(tmp_path / "store")
    for i in range(6):
        st.put(_key(i), {"v": np.full((2, 50 * (i + 1)), float(i))}, {"i": i})
    ens = lambda keys: Ensemble(np.arange(3.0), np.zeros((1, 3)), np.zeros((1, 3)),
                                {"store": str(st.root), "store_keys": keys})
    record_runs("alpha", {"stationary": ens([_key(0), _key(1)]), "noise_free": ens([_key(2)])},
                quick=False)
    record_runs("beta", {"stationary": ens([_key(2), _key(3)])}, quick=True)
    return st     # entries 4, 5 belong to no experiment


def test_usage_by_experiment(store):
    u = usage(store.root)
    sizes = {e.key: e.size for e in store.entries()}
    assert u.total_entries == 6 and u.total_bytes == sum(sizes.values())
    assert u.experiments["alpha"]["entries"] == 3
    assert u.experiments["alpha"]["bytes"] == sizes[_key(0)] + sizes[_key(1)] + sizes[_key(2)]
    assert u.experiments["beta"]["runs"] == ["quick/stationary"]
    assert u.unindexed_entries == 2 and u.unindexed_bytes == sizes[_key(4)] + sizes[_key(5)]


def test_ls_and_du(store):
    r = CliRunner().invoke(main, ["store", "ls", "--store", str(store.root)])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    alpha = next(ln for ln in lines if ln.startswith("alpha"))
    assert alpha.split()[1] == "3" and "full/noise_free, full/stationary" in alpha
    assert next(ln for ln in lines if ln.startswith("(not indexed)")).split()[2] == "2"
    r = CliRunner().invoke(main, ["store", "du", "--store", str(store.root)])
    assert r.exit_code == 0 and "6 entries  total" in r.output and "(quarantine)" in r.output


def test_prune_by_experiment_keeps_shared_and_other_entries(store):
    r = CliRunner().invoke(main, ["store", "prune", "--store", str(store.root),
                                  "--experiment", "beta", "--dry-run"])
    assert r.exit_code == 0 and r.output.startswith("would delete 2 entries")
    assert len(store.entries()) == 6
    r = CliRunner().invoke(main, ["store", "prune", "--store", str(store.root),
                                  "--experiment", "beta"])
    assert r.exit_code == 0, r.output
    assert store.keys() == [_key(i) for i in (0, 1, 4, 5)]
    assert "beta" not in usage(store.root).experiments
    # alpha's index still names key 2, now missing: it simply counts what is there
    assert usage(store.root).experiments["alpha"]["entries"] == 2


def test_prune_unindexed_age_and_size(store):
    assert prune(store.root, unindexed=True)["entries"] == 2
    assert store.keys() == [_key(i) for i in range(4)]
    old = time.time() - 40 * 86400
    for e in store.entries():
        if e.key in (_key(3),):
            os.utime(e.path, (old, old))
    idx = store.root / "index" / "beta.json"           # beta's run is old as well
    data = json.loads(idx.read_text())
    data["runs"]["quick/stationary"]["updated"] = old
    idx.write_text(json.dumps(data))
    r = prune(store.root, older_than_days=30)
    assert r["keys"] == [_key(3)]
    sizes = {e.key: e.size for e in store.entries()}
    budget = sizes[_key(1)] + sizes[_key(2)] + 10
    for k, age in ((_key(0), 3), (_key(1), 2), (_key(2), 1)):   # key 0 least recently used
        t = time.time() - age * 86400
        os.utime(store.path(k), (t, t))
    r = prune(store.root, max_bytes=budget)
    assert r["keys"] == [_key(0)] and store.size_bytes() <= budget


def test_prune_quarantine_and_bad_input(store):
    store.quarantine(_key(5), "test")
    assert usage(store.root).quarantined == 1
    assert prune(store.root, quarantine=True)["quarantined"] == 1
    assert usage(store.root).quarantined == 0
    r = CliRunner().invoke(main, ["store", "prune", "--store", str(store.root)])
    assert r.exit_code == 2 and "needs a criterion" in r.output
    r = CliRunner().invoke(main, ["store", "prune", "--store", str(store.root),
                                  "--experiment", "gamma"])
    assert r.exit_code == 2 and "no index for experiment(s) gamma" in r.output
    with pytest.raises(ValueError, match="size"):
        parse_size("lots")
    assert parse_size("1.5G") == 1_500_000_000 and parse_size("200") == 200
