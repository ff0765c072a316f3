"""Injection into the HTML report: every user text is escaped (jinja2 autoescape); a failing
section is written as a failed section, finished sections are kept, metrics.json records it."""
import json
import tomllib
from pathlib import Path

import pytest

from analogue.report.html import Figure, Section, Table, write_page

ROOT = Path(__file__).resolve().parents[2]
PAYLOADS = ['<script>alert(1)</script>', '"><img src=x onerror=alert(1)>',
            "</table><script>x()</script>", "<!--", "&lt;script&gt;", "{{ 7*7 }}{% raw %}"]


def _png(tmp_path):
    from analogue.plots.style import new_figure, save
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1])
    return save(fig, tmp_path / "a.png")


def _no_live_markup(html: str):
    assert "<script" not in html.lower()
    assert "<img src=x" not in html and "<!--" not in html


@pytest.mark.parametrize("payload", PAYLOADS)
def test_every_text_field_of_the_page_is_escaped(tmp_path, payload):
    png = _png(tmp_path)
    page = write_page(tmp_path / "index.html", f"T {payload}", [f"intro {payload}"],
                      [Section(f"S {payload}", [f"p {payload}"], [Figure(png, f"cap {payload}")],
                               [Table(f"t {payload}", [f"h {payload}", "n"],
                                      [[f"c {payload}", 1.5]], collapsed=True)])])
    html = page.read_text()
    _no_live_markup(html)
    from markupsafe import escape
    for where in ("T", "intro", "S", "p", "cap", "t", "h", "c"):
        assert f"{where} {escape(payload)}" in html, where


def test_trusted_markup_is_explicit(tmp_path):
    from markupsafe import Markup
    page = write_page(tmp_path / "index.html", "T", [Markup("<b>kept</b>")],
                      [Section("S", ["<b>escaped</b>"])])
    html = page.read_text()
    assert "<b>kept</b>" in html and "&lt;b&gt;escaped&lt;/b&gt;" in html


def test_failed_section_shows_its_error_escaped(tmp_path):
    page = write_page(tmp_path / "index.html", "T", [],
                      [Section("Experiment 'x'", error="RuntimeError: <script>boom</script>")])
    html = page.read_text()
    assert "failed" in html.lower() and "&lt;script&gt;boom" in html and "<script" not in html


def test_description_payload_is_escaped_in_the_experiment_section(tmp_path):
    from analogue.report.pipeline import experiment_section_text
    from analogue.circuit.experiments import experiment_from_dict
    d = tomllib.loads((ROOT / "circuits" / "stick.toml").read_text())
    d["description"] = "<script>alert('desc')</script>\nsecond line & more"
    exp = experiment_from_dict(d)
    page = write_page(tmp_path / "index.html", "T", [],
                      [Section("E", experiment_section_text(exp))])
    html = page.read_text()
    assert "<script" not in html and "&lt;script&gt;alert(" in html


def test_failing_experiments_keep_finished_work_and_are_recorded(tmp_path, monkeypatch):
    """Every experiment fails: the page and metrics.json are still written, each failure is a
    section with its error, and the exit status reflects it."""
    import analogue.report.pipeline as P
    from analogue.report.plan import RunOptions

    def boom(exp, opts, settings=None, on_stationary=None):
        raise RuntimeError(f"ngspice failed for {exp.name} <b>")
    import analogue.study.run as S
    monkeypatch.setattr(S, "run_experiment_runs", boom)
    monkeypatch.setattr(P, "_open_question_section",
                        lambda out, opts, data=None: Section("The paper's open question", ["kept"]))
    with pytest.raises(P.ReportIncomplete) as exc:
        P.build_report(["stick", "slip"], tmp_path, RunOptions(quick=True, progress=False),
                       title="t")
    assert "stick" in str(exc.value) and "slip" in str(exc.value)
    html = (tmp_path / "index.html").read_text()
    assert html.count("failed") >= 2 and "ngspice failed for stick &lt;b&gt;" in html
    assert "kept" in html  # the section that finished is there
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    failed = {f["section"]: f for f in metrics["failures"]}
    assert any("stick" in k for k in failed) and any("slip" in k for k in failed)
    assert all("ngspice failed" in f["error"] for f in failed.values())
    from analogue.study.metrics import validate_metrics
    validate_metrics(metrics)
    # the job's critical path (issue 22 item 1) is recorded for a failed report too: a chain
    # of its recorded phases (here all of them about 0 s), no longer than the job
    prov = metrics["provenance"]
    assert 0 <= prov["critical_path_s"] <= prov["wall_time_s"]
    assert prov["critical_path"] and prov["circuit_timing"] == {}
    assert prov["critical_path_s"] == pytest.approx(
        sum(c["seconds"] for c in prov["critical_path"]), abs=1e-2)
    assert "critical path (unlimited cores)" in html


def test_a_failing_figure_keeps_the_other_figures(tmp_path, monkeypatch):
    import types
    import analogue.report.pipeline as P
    png = _png(tmp_path)
    names = ["fig_prehistory", "fig_boundaries", "fig_propagator", "fig_stationary",
             "fig_work_paths", "fig_rate_function", "fig_budget"]
    for n in names:
        monkeypatch.setattr(P.figures, n, lambda *a, n=n, **k: (png, f"caption of {n}"))

    def broken(*a, **k):
        raise ValueError("no circuit window of work rate 0.2 <here>")
    monkeypatch.setattr(P.figures, "fig_work_paths", broken)
    runs = types.SimpleNamespace(exp=types.SimpleNamespace(name="work", v0=(0.0,)))
    from analogue.study.schedule import Failures
    fails = Failures()
    figs, errors = P._figures_for(runs, None, tmp_path, fails, "Experiment 'work'")
    assert len(figs) == 6 and not any("work_paths" in f.caption for f in figs)
    assert errors == ["figure 'work paths': ValueError: no circuit window of work rate 0.2 <here>"]
    assert fails.items == [{"section": "Experiment 'work'", "experiment": "work",
                            "stage": "figure: work paths",
                            "error": "ValueError: no circuit window of work rate 0.2 <here>"}]
    page = write_page(tmp_path / "index.html", "T", [],
                      [Section("Experiment 'work'", figures=figs, error="; ".join(errors))])
    html = page.read_text()
    assert html.count("<figure>") == 6 and "&lt;here&gt;" in html
