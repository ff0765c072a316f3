"""No LaTeX label of the paper is cited anywhere a reader sees it (docstrings, captions, figure
text, TOML descriptions, README, notebook): "eq. det_eq" must read "eq. (13)"
(analogue.paper.eq).  A fast source scan; the generated report is checked in
tests/integration/test_report_no_latex_labels.py."""
from pathlib import Path

from analogue.paper import label_citations as find_labels

ROOT = Path(__file__).resolve().parents[2]
SKIP = {"analogue/paper.py", "docs/equations.md", "tests/unit/test_paper_numbers.py",
        "tests/unit/test_no_latex_labels.py", "tests/integration/test_report_no_latex_labels.py"}


def _files():
    for pattern in ("analogue/**/*.py", "circuits/*.toml", "README.md", "docs/*.md",
                    "examples/*.ipynb", "benchmarks/*.py", "benchmarks/*.md"):
        for p in ROOT.glob(pattern):
            if str(p.relative_to(ROOT)) not in SKIP:
                yield p


def test_the_detector_finds_what_it_should():
    assert find_labels("see eq. det_eq and eqs.\n    sol1-sol3, Fig. Fig_dist") == [
        "eq. det_eq", "eqs.\n    sol1", "Fig. Fig_dist", "det_eq", "sol1", "sol3", "Fig_dist"]
    assert find_labels("eq. (13), eqs. (46)-(51), Fig. 6, the model, p_s, work") == []


def test_sources_cite_numbers_not_labels():
    bad = {}
    for p in _files():
        found = find_labels(p.read_text(errors="ignore"))
        if found:
            bad[str(p.relative_to(ROOT))] = found[:5]
    assert not bad, f"LaTeX labels cited (use analogue.paper.eq/fig numbers): {bad}"
