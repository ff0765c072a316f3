"""A coloured-noise experiment end to end (issue 20): a user's TOML in another directory, a
copy of circuits/cubic.toml with ``noise = {kind = "ornstein-uhlenbeck", tau_c = ...}`` and no
cubic term.  ``report --quick`` runs to the end (before: "noise kind 'ornstein-uhlenbeck' has
no exact solver here", a failed section); its rows are held against the Monte Carlo of the same
model (no exact theory yet), every budget is finite, the page's prose quotes the experiment's
own tau_c and gamma; ``export --quick`` afterwards runs no new deck."""
import json
import math
import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import toml_text
from integration.test_export_is_the_reports_data import counted_ngspice  # noqa: F401 (fixture)

from analogue.cli import main

pytestmark = [pytest.mark.slow, pytest.mark.requires_ngspice]

ROOT = Path(__file__).resolve().parents[2]


def _my_coloured(tmp_path: Path) -> Path:
    d = tomllib.loads((ROOT / "circuits" / "cubic.toml").read_text())
    d["name"] = "mycoloured"
    d["description"] = "My own stick-slip with coloured noise."
    d["model"] = {"tau_m": 1.0, "delta": 0.5, "a": 0.3, "gamma": 12.0,
                  "noise": {"kind": "ornstein-uhlenbeck", "tau_c": 0.25}}
    d["circuit"] = {"coulomb": "diode-bridge", "diode": "ideal", "time_scale": 1e-3,
                    "capacitance": 100e-9}
    d["experiment"].update(histogram_times=[0.5, 1.0])
    where = tmp_path / "elsewhere"
    where.mkdir()
    path = where / "mycoloured.toml"
    path.write_text(toml_text(d))
    return path


def _invoke(args):
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    return r


def test_coloured_report_runs_against_the_monte_carlo_and_export_reads_its_runs(
        tmp_path, counted_ngspice):  # noqa: F811 (the imported fixture)
    toml = _my_coloured(tmp_path)
    store, rep, out = tmp_path / "store", tmp_path / "rep", tmp_path / "out"
    common = ["--store", str(store), "--workers", "2", "--quick", "--no-progress"]
    _invoke(["report", str(toml), "--out", str(rep), *common])
    metrics = json.loads((rep / "metrics.json").read_text())
    rows = [c for c in metrics["comparisons"] if c["experiment"] == "mycoloured"]
    names = {(c["observable"]) for c in rows}
    assert {"mean v", "var v", "P(v>0)", "stick fraction"} <= names
    assert any(n.startswith("var v at t=") for n in names)
    for c in rows:
        assert "Monte Carlo" in c["note"], c
        b = c["budget"]
        assert all(math.isfinite(x) for x in b.values() if not isinstance(x, str)), c
        assert math.isfinite(c["theory"]) and math.isfinite(c["circuit"])
        assert c["circuit_stderr"] > 0
    page = (rep / "index.html").read_text()
    assert "tau_c = 0.25" in page and "gamma = 12" in page
    assert "FAILED" not in page

    before = counted_ngspice()
    r = _invoke(["export", str(toml), "--out", str(out), "--report", str(rep), *common])
    assert counted_ngspice() == before, "export --quick after report --quick ran new decks"
    assert "--quick size" in r.output
    assert {p.stem for p in out.glob("*.nc")} == {"transition_v0=0", "stationary",
                                                 "check_stationary"}
