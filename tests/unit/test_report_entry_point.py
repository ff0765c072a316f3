"""``analogue.report(experiment, out=..., quick=...)``: the Python entry point of what
``analogue report`` does (issue 20 item 6), returning the StudyResult; the name is also the
package of the page's modules, and both uses work in one process, in either order.

No ngspice: the circuit runs are SDE ensembles of the circuit's effective model
(``test_report_schedule._fake_runs``); everything after them (theory, comparisons, figures,
page) is the report's own."""
from __future__ import annotations

import json
import math
import re
import subprocess
import sys

import pytest

import analogue
from analogue.report.pipeline import ReportIncomplete
from analogue.study import run as S
from analogue.study.run import StudyResult
from test_report_schedule import _exp, _fake_runs


@pytest.mark.parametrize("first", ["call", "submodule"])
def test_report_is_callable_and_a_package_in_one_process(first):
    """In a fresh interpreter: ``analogue.report`` resolves to the callable package, and
    importing its submodules neither replaces it nor stops them importing."""
    steps = {"call": "assert callable(analogue.report), type(analogue.report)",
             "submodule": "from analogue.report import figures; import analogue.report.html"}
    code = "\n".join([
        "import sys, analogue",
        steps[first],
        steps["submodule" if first == "call" else "call"],
        "from analogue import report",
        "assert report is sys.modules['analogue.report'] and callable(report)",
        "from analogue.report import figures",
        "assert figures.__name__ == 'analogue.report.figures'",
        "assert 'report' in dir(analogue) and 'report' in analogue.__all__",
    ])
    subprocess.run([sys.executable, "-c", code], check=True)


def _runs(exp, opts, settings=None, on_stationary=None):
    """The schedule test's SDE runs, with the noise-free run as the report has it: one
    replica per v0 (Fig. 1 draws each against Model.deterministic)."""
    import dataclasses

    import numpy as np

    from analogue.montecarlo import simulate_sde
    r = _fake_runs(exp, opts)
    m = exp.mapping().model_effective
    nf = simulate_sde(m, v0=np.asarray(exp.v0, float), t_end=exp.t_end, replicas=len(exp.v0),
                      seed=1, sample_dt=exp.sample_dt)
    nf.meta["model_effective"] = m.as_dict()
    return dataclasses.replace(r, noise_free=nf)


def _fake(monkeypatch):
    monkeypatch.setattr(S, "run_experiment_runs", _runs)


def test_report_returns_the_study(tmp_path, monkeypatch):
    monkeypatch.setenv("ANALOGUE_THEORY_CACHE", str(tmp_path / "theory"))
    _fake(monkeypatch)
    exp = _exp("mine", 6.0, 5)
    res = analogue.report(exp, out=tmp_path / "r", quick=True)
    assert isinstance(res, StudyResult)
    assert res.page == tmp_path / "r" / "index.html" and res.page.exists()
    metrics = json.loads((tmp_path / "r" / "metrics.json").read_text())
    # the result is what the page and metrics.json say
    assert [c.as_dict() for c in res.comparisons] == metrics["comparisons"]
    assert json.loads(json.dumps(res.record, default=str)) == metrics
    assert 0 < res.critical_path_s <= res.wall_time_s == metrics["provenance"]["wall_time_s"]
    assert res.comparisons and all(math.isfinite(c.budget.total()) for c in res.comparisons)
    assert res.figures["mine"] and all(p.exists() for p in res.figures["mine"])
    assert set(res.by_role("mine")) >= {"stationary", "noise_free", "check_transition",
                                        "check_stationary"}
    assert not res.failures.items and "comparisons" in repr(res)
    # a user's report claims no section of the paper's (issue 20 item 3: it read "Paper Fig. 1:
    # deterministic motion" over the user's own noise-free runs)
    titles = re.findall(r"<h2[^>]*>(.*?)</h2>", res.page.read_text())
    assert "Deterministic motion (noise off)" in titles
    assert not [t for t in titles if "paper" in t.lower()], titles
    with pytest.raises(KeyError, match="no runs"):
        res.by_role("other")


def test_report_hands_back_failures_or_raises_them(tmp_path, monkeypatch):
    def boom(exp, opts, settings=None, on_stationary=None):
        raise RuntimeError("ngspice failed")
    monkeypatch.setattr(S, "run_experiment_runs", boom)
    monkeypatch.setattr(S, "analyse", lambda *a, **k: pytest.fail("nothing to compare"))
    exp = _exp("mine", 6.0, 5)
    res = analogue.report(exp, out=tmp_path / "a", quick=True)
    assert res.failed == {"mine": "RuntimeError: ngspice failed"}
    assert res.page is not None and "ngspice failed" in res.page.read_text()
    with pytest.raises(ReportIncomplete) as exc:
        analogue.report(exp, out=tmp_path / "b", quick=True, raise_incomplete=True)
    assert exc.value.result is not None and exc.value.result.failed == res.failed


def test_the_command_line_uses_the_same_function(tmp_path, monkeypatch):
    from click.testing import CliRunner

    import analogue.report.pipeline as P
    from analogue.cli import main
    seen = {}

    def report(experiment, out=None, **kw):
        seen.update(experiment=experiment, out=out, **kw)
        res = S.StudyResult([], [], True, S.Phases(), S.Failures(), 0.0, (0, 0, 0))
        res.page = out / "index.html"
        return res
    monkeypatch.setattr(P, "report", report)
    r = CliRunner().invoke(main, ["report", "stick", "--quick", "--out", str(tmp_path / "o")])
    assert r.exit_code == 0, r.output
    assert seen["experiment"].name == "stick" and seen["opts"].quick
    assert seen["raise_incomplete"] is True
    assert f"report: {tmp_path / 'o' / 'index.html'}" in r.output


def test_a_runner_says_how_the_report_runs(tmp_path, monkeypatch):
    """analogue.report(..., runner=analogue.Runner(...)): its store, workers, timeout and
    progress reach every circuit run of the study; what the report chooses itself (deck size,
    labels, its own deck pool) is refused by name, before anything runs."""
    seen = []

    def runs(exp, opts, settings=None, on_stationary=None):
        seen.append(opts)
        raise RuntimeError("stop")
    monkeypatch.setattr(S, "run_experiment_runs", runs)
    runner = analogue.Runner(store=tmp_path / "store", workers=3, timeout=99.0, progress=False)
    res = analogue.report(_exp("mine", 6.0, 5), out=tmp_path / "r", quick=True, runner=runner)
    assert res.failed == {"mine": "RuntimeError: stop"}
    (opts,) = seen
    assert (opts.store, opts.workers, opts.timeout, opts.progress, opts.quick) == \
        (tmp_path / "store", 3, 99.0, False, True)
    # the options give the decks back the very runner the report was handed (issue 20), with
    # the study's one deck pool of its 3 workers as the executor (issue 22)
    assert opts.runner().replace(executor=None) == runner
    assert opts.runner().executor.workers == 3
    with pytest.deprecated_call():
        assert opts.simulate_kwargs()["store"] == tmp_path / "store"
    for bad in (dict(replicas_per_deck=8), dict(label="x")):
        with pytest.raises(ValueError, match=f"runner.{next(iter(bad))}"):
            analogue.report("stick", out=tmp_path / "n", runner=analogue.Runner(**bad))
    with pytest.raises(TypeError, match="either runner"):
        S.run_study([], runner=runner, opts=S.RunOptions())
    with pytest.raises(TypeError, match="analogue.Runner"):
        analogue.report("stick", out=tmp_path / "n", runner=object())
    assert not (tmp_path / "n").exists()
