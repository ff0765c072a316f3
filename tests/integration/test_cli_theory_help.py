"""`analogue` help texts and `analogue theory`: whole command summaries, no word broken at a
hyphen, path points, --kind honoured or refused, unused options refused, strict JSON with
reasons, one --v value anywhere, aligned columns."""
import json
import math
import re

import numpy as np
import pytest

from analogue import Model
from analogue.cli import main
from analogue.theory import weak_noise
from analogue.theory.query import QUANTITIES

STICK = ["--tau-m", "1", "--delta", "0.7", "--a", "0.2", "--gamma", "10"]
SLIP = ["--tau-m", "1", "--delta", "0.7", "--a", "1.2", "--gamma", "10"]
WORK = ["--tau-m", "1", "--delta", "1", "--a", "0.5", "--gamma", "10"]


def _strict(text):
    def bad(const):
        raise ValueError(f"non-standard JSON constant {const}")
    return json.loads(text, parse_constant=bad)


@pytest.mark.parametrize("width", [50, 60, 80, 120])
def test_top_level_help_keeps_whole_summaries_and_words(cli, width):
    r = cli.invoke(main, ["--help"], terminal_width=width)
    assert r.exit_code == 0
    flat = " ".join(r.output.split())
    assert "Draw the paper's theory figures (Figs. 1-9, weak-noise curves) as PNG files." in flat
    assert "in one self-contained report." in flat
    commands = r.output.split("Commands:")[1]
    for line in r.output.splitlines():
        assert not re.search(r"\w-$", line), f"word broken at a hyphen: {line!r}"
    assert "..." not in commands      # click's truncation mark


@pytest.mark.parametrize("width", [50, 80])
def test_theory_help_lists_quantities_without_breaking_them(cli, width):
    r = cli.invoke(main, ["theory", "--help"], terminal_width=width)
    assert r.exit_code == 0
    lines = r.output.splitlines()
    assert lines[0].endswith(" theory [OPTIONS] QUANTITY [EXPERIMENT]")
    for name in QUANTITIES:
        assert any(line.split()[:1] == [name] for line in lines), name
    for line in lines:
        assert not re.search(r"\w-$", line), line


def test_path_prints_the_points_of_the_optimal_path(cli):
    r = cli.invoke(main, ["theory", "path", *STICK, "--v0", "2", "--t", "3", "--v", "0.2",
                          "--points", "10", "--json"])
    assert r.exit_code == 0, r.output
    rows = _strict(r.output)["rows"]
    assert len(rows) == 11
    s = np.array([row["s"] for row in rows])
    v = np.array([row["v*(s)"] for row in rows])
    assert s[0] == 0 and s[-1] == 3.0 and np.all(np.diff(s) > 0)
    assert v[0] == 2.0 and v[-1] == pytest.approx(0.2)
    assert {row["kind"] for row in rows} == {"indirect"}
    # an indirect path sticks: v* = 0 on (t_a, t_b) of the action table
    act = _strict(cli.invoke(main, ["theory", "action", *STICK, "--v0", "2", "--t", "3",
                                    "--v", "0.2", "--json"]).output)["rows"][0]
    inside = (s > act["t_a"] + 1e-9) & (s < act["t_b"] - 1e-9)
    assert inside.any() and np.all(v[inside] == 0)
    assert np.all(v[s < act["t_a"] - 1e-9] > 0)


@pytest.mark.parametrize("args, needle", [
    (["propagator", "--v0", "2", "--t", "1", "--v", "0", "--kind", "limit"], "--kind must be one of exact, weak-noise"),
    (["scgf", "--k", "1", "--kind", "weak-noise"], "--kind must be one of exact"),
    (["stationary", "--kind", "weak-noise"], "--kind must be one of exact"),
    (["action", "--v0", "2", "--t", "1", "--v", "0", "--kind", "exact"], "weak-noise"),
    (["deterministic", "--v0", "2", "--t", "1", "--kind", "exact"], "no choice of theory"),
    (["stationary", "--v", "1"], "--v: not used by stationary"),
    (["rate-function", "--w", "1", "--t", "2"], "--t: not used by rate-function"),
    (["boundaries", "--v0", "2", "--t", "1", "--v", "0.3", "--w", "1"], "--v, --w: not used"),
    (["action", "--v0", "2", "--t", "1", "--v", "0", "--points", "5"], "--points: not used"),
    (["propagator", "--v0", "2", "--t", "1"], "propagator needs --v"),
])
def test_kind_and_options_are_honoured_or_refused(cli, args, needle):
    r = cli.invoke(main, ["theory", args[0], *STICK, *args[1:]])
    assert r.exit_code == 2, r.output
    assert needle in r.output and "Traceback" not in r.output


def test_kind_labels_what_was_computed(cli):
    from analogue.theory.work_statistics import weak_noise_limit_rate_function
    r = cli.invoke(main, ["theory", "rate-function", *WORK, "--w", "-0.5,0.5", "--kind",
                          "limit", "--json"])
    data = _strict(r.output)
    assert data["kind"] == "limit" and data["columns"] == ["w", "I_limit"]
    ref = weak_noise_limit_rate_function(Model(1.0, 1.0, 0.5, 10.0), np.array([-0.5, 0.5]))
    assert [row["I_limit"] for row in data["rows"]] == pytest.approx(list(ref), rel=1e-12)


def test_boundaries_in_the_slip_regime_are_null_with_a_reason(cli):
    r = cli.invoke(main, ["theory", "boundaries", *SLIP, "--v0", "2", "--t", "1,2", "--json"])
    assert r.exit_code == 0, r.output
    assert "NaN" not in r.output
    for row in _strict(r.output)["rows"]:
        assert row["w"] is None and row["u"] is None
        assert "|a| > Delta" in row["null_reasons"]["w"]
    # v0 < 0 in the slip regime: w_cr exists (a number), w and u do not
    rows = _strict(cli.invoke(main, ["theory", "boundaries", *SLIP, "--v0", "-1", "--t", "2",
                                     "--json"]).output)["rows"]
    assert isinstance(rows[0]["w_cr"], float) and rows[0]["w"] is None
    txt = cli.invoke(main, ["theory", "boundaries", *SLIP, "--v0", "2", "--t", "1"]).output
    assert "nan" not in txt and "n/a" in txt and "slip regime" in txt


def test_action_json_is_strict(cli):
    r = cli.invoke(main, ["theory", "action", *STICK, "--v0", "2", "--t", "3",
                          "--v", "-0.5,0,1", "--json"])
    rows = _strict(r.output)["rows"]
    assert rows[2]["kind"] == "direct" and rows[2]["t_a"] is None
    assert "does not stick" in rows[2]["null_reasons"]["t_a"]
    assert rows[0]["t_a"] == pytest.approx(math.log(1 + 2 / 0.5))   # eq. (31), (Delta - a) = 0.5


def test_a_single_v_works_for_the_weak_noise_propagator(cli):
    def f(vs):
        out = cli.invoke(main, ["theory", "propagator", *STICK, "--v0", "2", "--t", "1",
                                "--v", vs, "--kind", "weak-noise", "--json"]).output
        return [row["f_weak-noise"] for row in _strict(out)["rows"]]
    one = f("0.5")
    assert len(one) == 1 and one[0] > 0
    assert f("0.3,0.5,0.7")[1] == pytest.approx(one[0], rel=1e-12)   # no grid dependence
    # independent route: the library's grid-normalised density on a wide fine grid
    grid = np.linspace(-3.0, 4.0, 70001)
    ref = weak_noise.propagator(Model(1.0, 0.7, 0.2, 10.0), grid, 1.0, 2.0)
    assert one[0] == pytest.approx(np.interp(0.5, grid, ref), rel=1e-4)


def test_columns_are_aligned(cli):
    r = cli.invoke(main, ["theory", "action", *STICK, "--v0", "2", "--t", "3",
                          "--v", "-0.5,0,0.5,1"])
    assert r.exit_code == 0, r.output
    table = [ln for ln in r.output.splitlines() if not ln.startswith("n/a ")]
    assert len(table) == 5 and len({len(ln) for ln in table}) == 1
    header = table[0]
    for name in ("action", "t_a", "t_2"):     # numeric columns end where their header ends
        end = header.index(name) + len(name)
        assert all(ln[end - 1] != " " and (end == len(ln) or ln[end] == " ") for ln in table)
