"""`analogue export` and `analogue.load_runs` read the report's own runs (issue 20 item 4).

After `report X --quick`, `export X --quick` runs no ngspice deck (counted by a logging
`ngspice` wrapper first on PATH), for the paper's model (a small copy of stick.toml) and for a
family member (a copy of circuits/shot.toml under another name); its files hold the runs the
report's provenance names (deck hashes and replicas, role by role) and its metrics.csv is the
report's metrics.json.  A full-size export says its size before it starts and does not pair
itself with the --quick report's metrics; `store ls` files the member's runs under its name.
"""
import csv
import json
import os
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import toml_text

import analogue
from analogue.cli import main
from analogue.circuit.store_index import usage

pytestmark = [pytest.mark.slow, pytest.mark.requires_ngspice]

ROOT = Path(__file__).resolve().parents[2]



def small_stick(tmp_path: Path, name: str, replicas: int = 32, stationary: int = 32) -> Path:
    """circuits/stick.toml under another name, at small sizes."""
    d = tomllib.loads((ROOT / "circuits" / "stick.toml").read_text())
    d["name"] = name
    d["experiment"].update(replicas=replicas, t_end=4.0, histogram_times=[0.5, 1.0, 4.0])
    d["report"] = {"stationary_replicas": stationary, "stationary_t_end": 20.0,
                   "stationary_burn_in": 2.0, "prehistory": [[2.0, 0.9, 1.0]],
                   "check_replicas": 8}
    path = tmp_path / f"{name}.toml"
    path.write_text(toml_text(d))
    return path


@pytest.fixture
def counted_ngspice(tmp_path, monkeypatch):
    """An `ngspice` first on PATH that logs each call, then runs the real one; returns a
    function giving the number of deck runs (`ngspice -b ...`) so far."""
    real = shutil.which("ngspice")
    assert real is not None
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    log = tmp_path / "ngspice-calls.log"
    wrapper = bin_dir / "ngspice"
    wrapper.write_text(f'#!/bin/sh\necho "$*" >> "{log}"\nexec "{real}" "$@"\n')
    wrapper.chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}{os.pathsep}{os.environ['PATH']}")

    def decks() -> int:
        if not log.exists():
            return 0
        return sum(1 for line in log.read_text().splitlines() if line.startswith("-b"))
    return decks


def _invoke(args):
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    return r


def _report_and_export(toml: Path, tmp_path: Path, decks):
    store, rep, out = tmp_path / "store", tmp_path / "rep", tmp_path / "out"
    common = ["--store", str(store), "--workers", "2", "--quick", "--no-progress"]
    _invoke(["report", str(toml), "--out", str(rep), *common])
    assert decks() > 0                      # the wrapper sees the report's decks
    before = decks()
    r = _invoke(["export", str(toml), "--out", str(out), "--report", str(rep), *common])
    assert decks() == before, "export --quick after report --quick ran new decks"
    assert "--quick size" in r.output
    return store, rep, out


def _check_same_runs(name: str, rep: Path, out: Path) -> dict:
    """The exported files are the report's runs: every deck the report's provenance names for
    ``name`` is among the files' decks, with the report's replica counts; metrics.csv holds
    the report's comparisons of ``name``, value for value."""
    metrics = json.loads((rep / "metrics.json").read_text())
    prov = metrics["provenance"]
    assert prov["quick"] is True
    files = {p.stem: analogue.open_ensemble(p) for p in out.glob("*.nc")}
    ours = {h for e in files.values() for h in e.meta["deck_sha256"]}
    theirs = {h for hs in prov["deck_hashes"][name].values() for h in hs}
    assert theirs and theirs <= ours
    for e in files.values():
        assert e.meta["experiment"] == name and e.meta["quick"] is True
        assert e.meta["from_store"] == len(e.meta["deck_sha256"])   # read, not run
    rows = list(csv.DictReader((out / "metrics.csv").open()))
    comps = [c for c in metrics["comparisons"] if c["experiment"] == name]
    assert [(r["observable"], float(r["circuit"]), float(r["theory"])) for r in rows] == \
        [(c["observable"], c["circuit"], c["theory"]) for c in comps]
    return files


def test_paper_model_export_reads_the_quick_reports_runs(tmp_path, counted_ngspice):
    toml = small_stick(tmp_path, "smallstick")
    store, rep, out = _report_and_export(toml, tmp_path, counted_ngspice)
    files = _check_same_runs("smallstick", rep, out)
    prov = json.loads((rep / "metrics.json").read_text())["provenance"]
    # role by role: the report's replicas and decks (its provenance names the roles
    # "transition v0=1", the files "transition_v0=1")
    for role, n in prov["replicas"]["smallstick"].items():
        ens = files[role.replace(" ", "_")]
        assert ens.replicas == n
        assert ens.meta["deck_sha256"] == prov["deck_hashes"]["smallstick"][role]

    # load_runs: the same runs as the files, from the store, no deck run
    before = counted_ngspice()
    runs = analogue.load_runs(toml, quick=True, store=store, workers=2)
    assert counted_ngspice() == before
    assert set(runs) == set(files)
    for role, ens in runs.items():
        np.testing.assert_array_equal(ens.v, files[role].v)
        np.testing.assert_array_equal(ens.x, files[role].x)

    # without --quick: one line naming the full size before anything runs, and the --quick
    # report's metrics are not paired with it (given explicitly: refused before any deck)
    r = CliRunner().invoke(main, ["export", str(toml), "--out", str(tmp_path / "full"),
                                  "--report", str(rep), "--store", str(store), "--no-progress"])
    assert r.exit_code == 2, r.output
    assert "full (no --quick) size" in r.output and "--quick report" in r.output
    assert counted_ngspice() == before and not (tmp_path / "full").exists()


def test_full_size_export_says_so_and_leaves_the_quick_metrics_out(tmp_path, monkeypatch,
                                                                  counted_ngspice):
    """Found in ./report/<name>/ (not given): the export runs, says its size first and that the
    report is left out."""
    monkeypatch.chdir(tmp_path)
    toml = small_stick(tmp_path, "tiny", replicas=4, stationary=16)
    rep = tmp_path / "report" / "tiny"
    rep.mkdir(parents=True)
    (rep / "metrics.json").write_text(json.dumps({
        "provenance": {"quick": True},
        "comparisons": [{"experiment": "tiny", "observable": "variance", "circuit": 0.1,
                         "theory": 0.1}]}))
    r = CliRunner().invoke(main, ["export", str(toml), "--store", str(tmp_path / "store"),
                                  "--workers", "2", "--no-progress"])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    assert lines[0].startswith("export tiny: the full (no --quick) size's runs (4 replicas per v0")
    assert any("metrics.csv not written" in ln and "--quick report" in ln for ln in lines)
    assert counted_ngspice() > 0
    assert not (tmp_path / "export" / "tiny" / "metrics.csv").exists()
    assert (tmp_path / "export" / "tiny" / "stationary.nc").is_file()


def test_member_export_reads_the_quick_reports_runs_and_is_indexed(tmp_path, counted_ngspice):
    toml = tmp_path / "myshot.toml"
    text = (ROOT / "circuits" / "shot.toml").read_text()
    toml.write_text("\n".join('name = "myshot"' if ln.startswith("name =") else ln
                              for ln in text.splitlines()) + "\n")
    store, rep, out = _report_and_export(toml, tmp_path, counted_ngspice)
    files = _check_same_runs("myshot", rep, out)
    assert set(files) == {"transition_v0=0", "stationary", "check_stationary"}
    assert files["stationary"].replicas == 32 and files["check_stationary"].replicas == 8
    # the check retraces the stationary run's first replicas (same noise), 100x tighter
    chk, stat = files["check_stationary"], files["stationary"]
    d = np.abs(chk.v - stat.v[:8, :chk.t.size])
    assert np.median(d) < 0.1 * np.std(stat.v)

    before = counted_ngspice()
    runs = analogue.load_runs(toml, quick=True, store=store)
    assert counted_ngspice() == before
    for role, ens in runs.items():
        np.testing.assert_array_equal(ens.v, files[role].v)

    # analogue store ls: the member's runs under its name and roles, nothing unindexed
    u = usage(store)
    assert u.unindexed_entries == 0, u
    assert {"quick/stationary", "quick/transition_v0=0",
            "quick/check_stationary"} <= set(u.experiments["myshot"]["runs"])
    r = _invoke(["store", "ls", "--store", str(store)])
    line = next(ln for ln in r.output.splitlines() if ln.startswith("myshot"))
    assert "quick/stationary" in line
    assert next(ln for ln in r.output.splitlines()
                if ln.startswith("(not indexed)")).split()[2] == "0"
