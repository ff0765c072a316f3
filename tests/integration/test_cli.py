"""The command line: help on every subcommand, theory queries, netlist check, one-line errors."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

from analogue import Model
from analogue.cli import main
from analogue.theory import exact, weak_noise

ROOT = Path(__file__).resolve().parents[2]
COMMANDS = ["netlist", "schematic", "run", "report", "paper", "sweep", "theory", "figures"]


@pytest.mark.parametrize("cmd", COMMANDS)
def test_every_subcommand_has_help(cli, cmd):
    r = cli.invoke(main, [cmd, "--help"])
    assert r.exit_code == 0, r.output
    assert "Usage:" in r.output and "--help" in r.output


def test_run_commands_offer_workers_scheduler_quick(cli):
    for cmd in ("run", "report", "paper", "sweep"):
        out = cli.invoke(main, [cmd, "--help"]).output
        for opt in ("--workers", "--scheduler", "--quick", "--store"):
            assert opt in out, (cmd, opt)


def test_theory_action_json_matches_library(cli):
    r = cli.invoke(main, ["theory", "action", "--tau-m", "1", "--delta", "0.7", "--a", "0.2",
                          "--gamma", "10", "--v0", "2", "--t", "3", "--v", "-0.5,0.5,2.5", "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    m = Model(1.0, 0.7, 0.2, 10.0)
    assert [row["v"] for row in data["rows"]] == [-0.5, 0.5, 2.5]
    for row in data["rows"]:
        p = weak_noise.optimal_path(m, row["v"], 3.0, 2.0)
        assert row["action"] == pytest.approx(p.action, rel=1e-12)
        assert row["kind"] == p.kind


def test_theory_stationary_from_experiment(cli):
    r = cli.invoke(main, ["theory", "stationary", "--experiment", "stick", "--json"])
    assert r.exit_code == 0, r.output
    rows = {row["quantity"]: row["value"] for row in json.loads(r.stdout)["rows"]}
    ref = exact.stationary_moments(Model(1.0, 0.7, 0.2, 10.0))
    assert rows["mean"] == pytest.approx(ref.mean, rel=1e-12)
    assert rows["p_positive"] == pytest.approx(ref.p_positive, rel=1e-12)


def test_theory_table_output_is_readable(cli):
    r = cli.invoke(main, ["theory", "rate-function", "--kind", "weak-noise", "--tau-m", "1",
                          "--delta", "1", "--a", "0.5", "--gamma", "10", "--w", "-1,1"])
    assert r.exit_code == 0, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 3 and "w" in lines[0]
    # eq. (64): I(1) = (1/4)(1/(m a tau_m) + Delta - a)^2 = (1/4)(2.5)^2
    assert float(lines[2].split()[-1]) == pytest.approx(0.25 * 2.5**2)


@pytest.mark.parametrize("args,needle", [
    (["theory", "action", "--tau-m", "-1", "--delta", "0.7", "--a", "0.2", "--gamma", "10",
      "--v0", "1", "--t", "1", "--v", "0"], "tau_m must be > 0"),
    (["theory", "action", "--delta", "0.7", "--a", "0.2", "--gamma", "10"], "--tau-m"),
    (["theory", "action", "--tau-m", "1", "--delta", "0.7", "--a", "0.2", "--gamma", "10",
      "--v0", "1", "--t", "1", "--v", "x"], "comma-separated numbers"),
    (["theory", "stationary", "--experiment", "no_such_experiment"], "no_such_experiment"),
    (["report", "bad;name", "--quick"], "bad;name"),
])
def test_errors_are_one_clear_line_with_nonzero_exit(cli, args, needle):
    r = cli.invoke(main, args)
    assert r.exit_code != 0
    assert needle in r.output
    assert "Traceback" not in r.output


@pytest.mark.slow  # > 5 s (make test-fast skips it)
def test_console_script_exit_code_and_no_traceback():
    exe = Path(sys.executable).with_name("analogue")
    assert exe.exists(), "the analogue console script is installed with the package"
    p = subprocess.run([str(exe), "theory", "stationary", "--tau-m", "1", "--delta", "-1",
                        "--a", "0", "--gamma", "1"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2
    assert p.stderr.strip().count("\n") == 0 and "delta must be >= 0" in p.stderr
    assert "Traceback" not in p.stderr


def test_netlist_check_passes_on_committed_decks(cli):
    r = cli.invoke(main, ["netlist", "--check"])
    assert r.exit_code == 0, r.output
    assert "up to date" in r.output


def test_repeated_options_and_comma_lists_are_the_same(cli):
    base = ["theory", "rate-function", "--kind", "weak-noise", "--tau-m", "1", "--delta", "1",
            "--a", "0.5", "--gamma", "10", "--json"]
    a = json.loads(cli.invoke(main, base + ["--w", "-1,1"]).output)
    b = json.loads(cli.invoke(main, base + ["--w", "-1", "--w", "1"]).output)
    assert a["rows"] == b["rows"] and len(a["rows"]) == 2
