"""Reports: metrics schema, the self-contained page, and the quick paper run end to end
(including the page loading in headless Chromium, with a screenshot kept as a test artefact)."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from scipy import stats

from analogue.report.html import Figure, Section, Table, write_page
from analogue.study.metrics import Budget, compare, validate_metrics
from analogue.report.plan import ReportSettings, RunOptions
from conftest import chromium

ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = ROOT / "test-artifacts"


# ----------------------------------------------------------------------------- metrics
def test_compare_z_and_budget():
    c = compare("e", "mean v", 1.10, 0.02, 1.0, "exact", Budget(smoothing=0.01, bandwidth=-0.02))
    assert c.z == pytest.approx(5.0)
    # |diff| = 0.1 > 3 SE + 0.03 = 0.09: not explained
    assert not c.within_budget
    c2 = compare("e", "mean v", 1.08, 0.02, 1.0, "exact", Budget(smoothing=0.01, bandwidth=-0.02))
    assert c2.within_budget  # 0.08 <= 0.09
    d = c.as_dict()
    assert d["budget"]["total"] == pytest.approx(0.03)
    assert d["budget"]["dominant"] == "statistical"
    with pytest.raises(ValueError, match="theory_kind"):
        compare("e", "x", 1.0, 0.1, 1.0, "guess")


def test_validate_metrics_rejects_bad_documents():
    good = {"comparisons": [compare("e", "x", 1.0, 0.1, 1.0).as_dict()],
            "provenance": {"parameters": {}, "seeds": {}, "ngspice_version": "x",
                           "deck_hashes": {}, "wall_time_s": 1.0}}
    validate_metrics(json.loads(json.dumps(good)))
    for mutate, needle in [
        (lambda d: d.pop("provenance"), "provenance"),
        (lambda d: d["comparisons"][0].pop("z"), "'z'"),
        (lambda d: d["comparisons"][0].update(theory_kind="guess"), "theory_kind"),
        (lambda d: d["comparisons"][0].update(within_budget="yes"), "within_budget"),
        (lambda d: d["provenance"].pop("deck_hashes"), "deck_hashes"),
    ]:
        bad = json.loads(json.dumps(good))
        mutate(bad)
        with pytest.raises(ValueError, match=needle):
            validate_metrics(bad)


def test_page_is_self_contained(tmp_path):
    from analogue.plots.style import new_figure, save
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1])
    png = save(fig, tmp_path / "a.png")
    page = write_page(tmp_path / "index.html", "T <&>", ["intro"],
                      [Section("S", ["p"], [Figure(png, "cap")], [Table("t", ["a", "b"], [["x", 1.5]])])])
    html = page.read_text()
    assert "T &lt;&amp;&gt;" in html
    assert re.search(r'src="data:image/png;base64,[A-Za-z0-9+/=]{100,}"', html)
    assert "http://" not in html and "https://" not in html and "<script" not in html


def test_report_settings_validation():
    assert ReportSettings(prehistory=[[1.0, 2.0], [2.0, 0.5, 1.0]]).prehistory[1] == (2.0, 0.5, 1.0)
    with pytest.raises(ValueError, match="report.prehistory"):
        ReportSettings(prehistory=[[1.0]])
    with pytest.raises(ValueError, match="report.stationary_replicas"):
        ReportSettings(stationary_replicas=1)
    with pytest.raises(ValueError, match="report.stationary_burn_in"):
        ReportSettings(stationary_burn_in=200.0)
    q = ReportSettings().for_options(RunOptions(quick=True))
    assert q.stationary_replicas == 32 and q.stationary_t_end == 50.0


# --------------------------------------------------------------------- quick paper run
@pytest.fixture(scope="module")
def paper_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    store = tmp_path_factory.mktemp("store")
    exe = Path(sys.executable).with_name("analogue")
    env = dict(os.environ, ANALOGUE_STORE=str(store))
    p = subprocess.run([str(exe), "paper", "--quick", "--out", str(out), "--no-progress"],
                       capture_output=True, text=True, timeout=1500, env=env)
    assert p.returncode == 0, p.stderr[-3000:]
    return out, p


@pytest.mark.slow
@pytest.mark.xdist_group("paper")
def test_quick_paper_writes_valid_report(paper_report):
    out, proc = paper_report
    metrics = json.loads((out / "metrics.json").read_text())
    validate_metrics(metrics)
    names = {c["experiment"] for c in metrics["comparisons"]}
    from analogue.circuit.experiments import PAPER_EXPERIMENTS
    from analogue.report.beyond import MEMBERS
    # the paper's experiments, then the chapter "Beyond the paper" (one per family member)
    assert names == set(PAPER_EXPERIMENTS) | set(MEMBERS)
    phases = metrics["provenance"]["phases"]
    assert {p["phase"] for p in phases} >= {"circuit runs", "exact theory", "comparisons"}
    # the circuit-free theory ran in the background thread
    assert all(p["thread"] == "theory" for p in phases if p["phase"] == "exact theory")
    kinds = {c["theory_kind"] for c in metrics["comparisons"]}
    assert kinds == {"exact", "weak-noise"}
    prov = metrics["provenance"]
    # the wall time with unlimited cores (issue 22 item 1): a chain of the job's own phases,
    # no longer than the job; every experiment's circuit runs timed (calibrations, longest
    # deck, which ran on an empty store)
    assert 0 < prov["critical_path_s"] <= prov["wall_time_s"]
    assert prov["critical_path"] and prov["critical_path"][-1]["phase"] == "figures and page"
    assert sum(c["seconds"] for c in prov["critical_path"]) == pytest.approx(
        prov["critical_path_s"], abs=1e-2)
    # the family members' too (by their parts: each run's calibrations and longest deck,
    # the Monte Carlo reference and the estimates)
    assert set(prov["circuit_timing"]) == set(PAPER_EXPERIMENTS) | set(MEMBERS)
    assert all(t["longest_deck_s"] > 0 and t["decks_run"] > 0
               for t in prov["circuit_timing"].values())
    assert all({"runs", "reference_s", "analysis_s"} <= set(prov["circuit_timing"][m])
               for m in MEMBERS)
    assert "critical path (unlimited cores)" in (out / "index.html").read_text()
    assert re.fullmatch(r"\d+(\.\d+)*", str(prov["ngspice_version"]))
    # every run lists the sha256 of each of its decks
    runs = [h for per_exp in prov["deck_hashes"].values() for h in per_exp.values()]
    assert runs and all(isinstance(h, list) and h for h in runs)
    assert all(re.fullmatch(r"[0-9a-f]{64}", x) for h in runs for x in h)
    pngs = sorted(p.name for p in out.glob("*.png"))
    for needed in ("fig1_deterministic.png", "fig5_boundaries_stick.png",
                   "fig6_propagator_stick_v0_2.png", "fig7_work_paths_work.png",
                   "fig8_9_work_work.png", "open_question_rate.png"):
        assert needed in pngs
    html = (out / "index.html").read_text()
    assert html.count("data:image/png;base64,") >= len(pngs)
    assert "report written" in proc.stderr


@pytest.mark.slow
@pytest.mark.xdist_group("paper")
def test_quick_paper_comparisons_are_within_budget_or_flagged(paper_report):
    """Circuit vs exact: |z| < 3 or explained by the budget; what is neither must be named in
    the report.  With n comparisons a 3-sigma rule flags ~0.27 % by chance: allow at most the
    99.9 % binomial quantile of such flukes."""
    out, _ = paper_report
    metrics = json.loads((out / "metrics.json").read_text())
    exact = [c for c in metrics["comparisons"] if c["theory_kind"] == "exact"]
    bad = [c for c in exact if not c["within_budget"]]
    allowed = int(stats.binom.ppf(0.999, len(exact), 2 * stats.norm.sf(3.0)))
    assert len(bad) <= allowed, [(c["experiment"], c["observable"], c["z"]) for c in bad]
    html = (out / "index.html").read_text()
    from markupsafe import escape  # the page escapes every text (observables hold < and >)
    for c in bad:
        assert str(escape(f"{c['experiment']} / {c['observable']}")) in html
    for c in exact:
        assert c["within_budget"] == (abs(c["circuit"] - c["theory"])
                                      <= 3 * c["circuit_stderr"] + c["budget"]["total"] + 1e-15)
    # every circuit bias term of at least one SE is named in the summary with its reason
    # (issue 18; study.budget.terms_above_se_text)
    from analogue.study.budget import CIRCUIT_BIAS_TERMS
    for c in exact:
        for name in CIRCUIT_BIAS_TERMS:
            if c["circuit_stderr"] and abs(c["budget"][name]) >= c["circuit_stderr"]:
                assert str(escape(f"{c['observable']} ({name} ")) in html, (c["observable"], name)


@pytest.mark.slow
@pytest.mark.xdist_group("paper")
def test_quick_paper_has_the_chapter_what_experiments_measure(paper_report):
    """Issue 23 item 5: stick and slip each give 5 spectrum bands and their first-passage rows
    (stick: mean and P(T <= t_a) from both v0; slip: P(T <= 8) from v0 = 2, mean and
    P(T <= t_a) from v0 = -1), every one with a finite budget and within it at quick size; the
    page has the chapter, its spectra and first-passage figures, and cites the experiments."""
    from analogue.report.measure_chapter import CHAPTER_TITLE
    from analogue.study.measure import BANDS, band_label
    out, _ = paper_report
    metrics = json.loads((out / "metrics.json").read_text())
    bands = [band_label(lo, hi) for lo, hi in zip(BANDS[:-1], BANDS[1:])]
    want = {"stick": bands + ["P(T<=1.61) from v0=2", "first passage mean from v0=2",
                              "P(T<=1.17) from v0=-2", "first passage mean from v0=-2"],
            "slip": bands + ["P(T<=8) from v0=2", "P(T<=0.423) from v0=-1",
                             "first passage mean from v0=-1"]}
    for name, labels in want.items():
        rows = {c["observable"]: c for c in metrics["comparisons"] if c["experiment"] == name}
        for label in labels:
            c = rows[label]
            assert c["budget"]["total"] is not None and c["budget"]["total"] >= 0, label
            assert c["circuit_stderr"] > 0 and c["within_budget"], (name, label, c["z"])
    html = (out / "index.html").read_text()
    assert f">{CHAPTER_TITLE}</h2>" in html
    for png in ("spectra_stick_slip.png", "first_passage_stick.png", "first_passage_slip.png"):
        assert (out / png).is_file()
    for cited in ("Gnoli", "Chen &amp; Just", "Goohpattader", "Touchette, Prellberg"):
        assert cited in html


def _chromium():
    path = chromium()
    assert path is not None  # requires_chromium skips the test otherwise
    return path


@pytest.mark.slow
@pytest.mark.requires_chromium
@pytest.mark.requires_ngspice
@pytest.mark.xdist_group("paper")
def test_report_loads_in_headless_chromium(paper_report, tmp_path):
    out, _ = paper_report
    ARTIFACTS.mkdir(exist_ok=True)
    shot = ARTIFACTS / "report.png"
    if shot.exists():
        shot.unlink()
    cmd = [_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}", "--window-size=1280,2400",
           "--enable-logging=stderr", "--v=0", f"--screenshot={shot}",
           (out / "index.html").as_uri()]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
    assert p.returncode == 0, p.stderr[-2000:]
    assert shot.exists() and shot.stat().st_size > 20_000
    # no failed loads and no console errors from the page itself
    assert "Failed to load resource" not in p.stderr
    assert "CONSOLE" not in p.stderr
    from matplotlib.image import imread
    img = imread(shot)
    assert img.std() > 0.05, "the screenshot is blank"
