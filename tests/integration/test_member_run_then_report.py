"""``analogue run <member>`` runs the family member's circuit runs (issue 20): exactly those
``analogue report <member>`` reads (same decks, seeds and sizes), so that the report after it
runs no new deck.  Before, ``run spring`` stopped with "spring > 0: the state (x, v) is
two-dimensional and has no exact solver here" (the paper experiments' runs: sample_stationary
from the exact law) and a 1-D member ran the paper's run set, which its report never reads."""
from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner

from analogue.cli import main
from conftest import toml_text

pytestmark = [pytest.mark.slow, pytest.mark.requires_ngspice]

ROOT = Path(__file__).resolve().parents[2]


def _files(store: Path) -> set:
    return {p.relative_to(store) for p in store.rglob("*") if p.is_file()}


@pytest.mark.parametrize("member,changes", [
    # a user's spring: tau_m 1 instead of 3 (quick run 40 tau_m: the cheapest spring deck)
    ("spring", {"tau_m": 1.0, "delta": 0.4}),
    # a user's shot member: faster kicks, no transition times (stationary rows only)
    ("shot", {"shot": {"rate": 2.0, "mean": 0.4, "two_sided": False}}),
])
def test_run_then_report_runs_no_new_deck(member, changes, tmp_path):
    d = tomllib.loads((ROOT / "circuits" / f"{member}.toml").read_text())
    d["name"] = f"my{member}"
    d["model"].update(changes)
    if member == "shot":
        d["experiment"].pop("histogram_times")
    path = tmp_path / f"my{member}.toml"
    path.write_text(toml_text(d))
    store = tmp_path / "store"
    common = ["--quick", "--store", str(store), "--no-progress"]
    r = CliRunner().invoke(main, ["run", str(path), *common])
    assert r.exit_code == 0, r.output
    assert f"my{member}: runs stored" in r.output and "check_" in r.output, r.output
    after_run = _files(store)
    assert after_run
    out = tmp_path / "rep"
    r = CliRunner().invoke(main, ["report", str(path), *common, "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert _files(store) == after_run      # every deck the report needed was stored by run
    assert "Beyond the paper" in (out / "index.html").read_text()
