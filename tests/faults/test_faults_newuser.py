"""Faults found by trying the tool as a new user would, off the happy path (issue 8): each
test failed on main before its fix.  No ngspice here: every case fails or answers before a
deck runs."""
import json
from pathlib import Path

import pytest

from analogue.cli import main
from analogue.report.plan import ReportSettings, RunOptions

ROOT = Path(__file__).resolve().parents[2]
SHOT = ROOT / "circuits" / "shot.toml"


def one_error_line(r) -> str:
    text = r.stderr if r.stderr else r.output
    lines = [ln for ln in text.splitlines() if ln.strip()]
    assert len(lines) == 1, text
    assert "Traceback" not in text
    return lines[0]


def _strict(s: str):
    def refuse(c):
        raise AssertionError(f"not strict JSON: {c}")
    return json.loads(s, parse_constant=refuse)


# --- theory --json on a model with gamma = inf (pure shot noise) -----------------------
# Before: "analogue: error: Out of range float values are not JSON compliant: inf", exit 2,
# although the same query without --json printed its values.
@pytest.mark.parametrize("args", [["stationary"], ["deterministic", "--t", "1", "--v0", "1"],
                                  ["scgf", "--k", "0.1"]])
def test_theory_json_with_infinite_gamma_is_strict_json(cli, args):
    r = cli.invoke(main, ["theory", args[0], str(SHOT), *args[1:], "--json"])
    assert r.exit_code == 0, r.output
    data = _strict(r.stdout)
    assert data["model"]["gamma"] is None
    assert "gamma" in data["model_null_reasons"]
    assert data["model"]["tau_m"] == 1.0  # finite values unchanged
    assert data["rows"]


# --- --quick never enlarges what the file asks for ----------------------------------------
# Before: replicas = 8 in the file ran 32 replicas with --quick ("small ensembles"), four times
# what the run without --quick does.
@pytest.mark.parametrize("n", [1, 8, 31, 32])
def test_quick_never_runs_more_replicas_than_the_file(n):
    assert RunOptions(quick=True).scaled(n) <= n
    assert RunOptions(quick=False).scaled(n) == n


def test_quick_scales_large_counts_by_four():
    assert RunOptions(quick=True).scaled(1000) == 250
    assert RunOptions(quick=True).scaled(64) == 32


def test_quick_stationary_replicas_not_enlarged():
    s = ReportSettings(stationary_replicas=16).for_options(RunOptions(quick=True))
    assert s.stationary_replicas <= 16


# --- store subcommands and board refuse --store '' ----------------------------------------
# Before: `analogue store ls --store ''` listed (and prune would have pruned) the current
# directory; run/report/export already refused the empty string.
@pytest.mark.parametrize("args", [["store", "ls"], ["store", "du"],
                                  ["store", "prune", "--max-size", "0", "--dry-run"],
                                  ["board", "stick", "--out", "OUT", "--quick"]])
def test_empty_store_is_refused_everywhere(cli, tmp_path, monkeypatch, args):
    monkeypatch.chdir(tmp_path)
    r = cli.invoke(main, [*args, "--store", ""])
    assert r.exit_code == 2, r.output
    line = one_error_line(r)
    assert "--store" in line and "empty" in line
    assert not (tmp_path / "OUT").exists()


# --- theory rate-function at the edge of the work's support ------------------------------
# Before: `analogue theory rate-function circuits/shot.toml --w 0` (one-sided kicks: w >= 0,
# the maximiser of k w - lambda(k) runs to k -> -inf) ran for minutes and then printed a
# number from the grid's unresolved lambda at |k| ~ 1e12.  Now: n/a (NaN) within seconds.
@pytest.mark.timeout(120)
def test_shot_rate_function_at_the_support_edge_answers_quickly():
    """Pure one-sided shot noise in the stick regime (circuits/shot.toml): the work rate
    cannot be negative, and w = 0 is the edge of its support, reached by the histories with
    no kick at all (the object stays stuck): J(0) = rate (P(no kick in T) = e^{-rate T}),
    J = +inf below.  (It once hung, then answered nan; theory.family.work_edge.)"""
    import math
    from analogue.circuit.experiments import load_experiment
    from analogue.theory import exact
    m = load_experiment(SHOT).model
    got = exact.rate_function(m, [0.0, -0.1])
    assert got[0] == pytest.approx(m.shot.rate, rel=1e-9)
    assert math.isinf(got[1]) and got[1] > 0


@pytest.mark.timeout(120)
def test_shot_rate_function_cli_answers_at_and_below_the_edge(cli):
    r = cli.invoke(main, ["theory", "rate-function", str(SHOT), "--w", "0", "--w", "-0.1",
                          "--json"])
    assert r.exit_code == 0, r.output
    at, below = _strict(r.stdout)["rows"]
    assert at["I_exact"] == pytest.approx(1.0, rel=1e-9)           # the kick rate of shot.toml
    assert below["I_exact"] is None and "cannot be reached" in below["null_reasons"]["I_exact"]


# --- theory: huge numbers are refused naming the option, sizes are bounded ----------------
# Before: --v 1e308 printed RuntimeWarnings (overflow) and "no admissible optimal path found
# (please report ...)" with exit 1; --points 100000000 ran past a minute.
@pytest.mark.parametrize("opt", ["--v", "--v0", "--t"])
def test_theory_huge_numbers_are_one_line_bad_input(cli, opt):
    args = {"--t": "1", "--v": "0.1", "--v0": "1", opt: "1e308"}
    r = cli.invoke(main, ["theory", "action", "stick", *[x for kv in args.items() for x in kv]])
    assert r.exit_code == 2, r.output
    line = one_error_line(r)
    assert opt in line and "1e+12" in line


@pytest.mark.timeout(60)
def test_theory_path_points_is_bounded(cli):
    r = cli.invoke(main, ["theory", "path", "stick", "--t", "2", "--v", "0.1", "--v0", "1",
                          "--points", "100000000"])
    assert r.exit_code == 2, r.output
    assert "--points" in one_error_line(r)


# --- a store below a file ---------------------------------------------------------------
# Before: `run --store FILE/sub` warned once per deck (29 lines for a quick run) and stored
# nothing; `store ls --store FILE/sub` listed an empty store with exit 0.
@pytest.mark.parametrize("args", [["run", "stick", "--quick"], ["store", "ls"],
                                  ["store", "prune", "--max-size", "0"]])
def test_store_below_a_file_is_refused(cli, tmp_path, args):
    f = tmp_path / "f.toml"
    f.write_text("x = 1\n")
    r = cli.invoke(main, [*args, "--store", str(f / "sub")])
    assert r.exit_code == 2, r.output
    line = one_error_line(r)
    assert "--store" in line and "not a directory" in line


# --- --out below a file -------------------------------------------------------------------
# Before: report/export/board ran and then failed with "[Errno 20] Not a directory", exit 1.
@pytest.mark.parametrize("cmd", ["report", "export", "board", "figures", "paper"])
def test_out_below_a_file_is_bad_input(cli, tmp_path, cmd):
    f = tmp_path / "f.toml"
    f.write_text("x = 1\n")
    args = [cmd] + (["stick"] if cmd in ("report", "export", "board") else [])
    r = cli.invoke(main, [*args, "--out", str(f / "sub")])
    assert r.exit_code == 2, r.output
    line = one_error_line(r)
    assert "--out" in line and "not a directory" in line
