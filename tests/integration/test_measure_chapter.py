"""The chapter "What experiments measure" in ``analogue report stick --quick`` (issue 23
item 5): the page's section with its figures, and the chapter's rows in metrics.json with
finite budgets, within them."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from analogue.report.measure_chapter import CHAPTER_TITLE
from analogue.study.metrics import validate_metrics

pytestmark = [pytest.mark.slow, pytest.mark.requires_ngspice]


def test_report_stick_quick_has_the_chapter(tmp_path):
    out = tmp_path / "out"
    exe = Path(sys.executable).with_name("analogue")
    env = dict(os.environ, ANALOGUE_STORE=str(tmp_path / "store"))
    p = subprocess.run([str(exe), "report", "stick", "--quick", "--out", str(out),
                        "--no-progress"], capture_output=True, text=True, timeout=900, env=env)
    assert p.returncode == 0, p.stderr[-3000:]
    metrics = json.loads((out / "metrics.json").read_text())
    validate_metrics(metrics)
    rows = [c for c in metrics["comparisons"]
            if c["observable"].startswith(("S(omega)", "first passage", "P(T<="))]
    assert len(rows) == 9 and {c["experiment"] for c in rows} == {"stick"}
    for c in rows:
        assert c["budget"]["total"] is not None and c["budget"]["total"] >= 0
        assert c["within_budget"], (c["observable"], c["z"])
    html = (out / "index.html").read_text()
    assert f">{CHAPTER_TITLE}</h2>" in html
    assert (out / "spectra_stick.png").is_file() and (out / "first_passage_stick.png").is_file()
    # the chapter's own phases are in the provenance
    phases = {p["phase"] for p in metrics["provenance"]["phases"]}
    assert any(ph.startswith(CHAPTER_TITLE) for ph in phases)
