"""``analogue report <user TOML> --quick`` for family members off the shipped parameters (issue 9
QA): what an independent checker would try.  Each one once failed: pure two-sided shot noise
in the slip regime (var v at t = 0.5: z = -18.6, the unkicked mass was missing from the
theory), a spring with one-sided kicks (the report crashed on its text; the force balance
missed rate <z>), shot + Gaussian noise (text "the exact law has nan").

Quick sizes; measured on a loaded machine (load 8-11, --workers 1): 21 s, 53 s and 39 s."""
from __future__ import annotations

import json
import math
import re

import pytest
from click.testing import CliRunner

from analogue.cli import main
from analogue.report.metrics import validate_metrics
from conftest import toml_text

pytestmark = pytest.mark.slow

CIRCUIT = {"coulomb": "diode-bridge", "diode": "ideal", "smoothing": 0.02, "time_scale": 1e-3,
           "capacitance": 100e-9}

MEMBERS = {
    "shot_slip": (
        {"tau_m": 2.0, "delta": 0.3, "a": -0.5, "gamma": math.inf,
         "shot": {"rate": 1.5, "mean": 0.4, "two_sided": True}},
        CIRCUIT, [0.0], "var v at t=0.5 from v0=0"),
    "spring_kicks": (
        {"tau_m": 1.0, "delta": 0.5, "a": 0.3, "gamma": math.inf, "spring": 1.5, "x0": 0.5,
         "stribeck": [0.8, 0.3], "shot": {"rate": 2.0, "mean": 0.4}},
        {**CIRCUIT, "time_scale": 1e-4, "inductor_q": 300.0}, [0.0],
        "identity spring <x> - a - rate <z> + <Delta(v) sgn v> + cubic <v^3> = 0"),
    "shot_gauss": (
        {"tau_m": 1.0, "delta": 0.5, "a": -0.3, "gamma": 20.0,
         "shot": {"rate": 2.0, "mean": 0.3, "two_sided": True}},
        CIRCUIT, [0.5], "var v at t=0.5 from v0=0.5"),
}


@pytest.mark.parametrize("name", sorted(MEMBERS))
def test_user_member_report_is_within_budget(name, tmp_path):
    model, circuit, v0, label = MEMBERS[name]
    doc = {"name": name, "description": f"QA member {name}", "model": model, "circuit": circuit,
           "experiment": {"v0": v0, "replicas": 32, "t_end": 40.0, "sample_dt": 0.01, "seed": 8,
                          "burn_in": 10.0, "histogram_times": [0.5, 1.0, 3.0]}}
    path = tmp_path / f"{name}.toml"
    path.write_text(toml_text(doc))
    out = tmp_path / "rep"
    r = CliRunner().invoke(main, ["report", str(path), "--quick", "--out", str(out), "--store",
                                  str(tmp_path / "store"), "--no-progress", "--workers", "1"])
    assert r.exit_code == 0, r.output
    metrics = json.loads((out / "metrics.json").read_text())
    validate_metrics(metrics)
    assert metrics["failures"] == []
    rows = {c["observable"]: c for c in metrics["comparisons"]}
    assert label in rows, sorted(rows)
    for obs, c in rows.items():
        assert c["within_budget"], (obs, c)
    html = (out / "index.html").read_text()
    assert re.search(r"\bnan\b", html) is None  # no number left unset in the text or tables
    if name == "shot_gauss":
        assert "no atom at v = 0" in html
