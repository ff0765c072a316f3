"""The generated report cites the paper's equation and figure numbers, never its LaTeX labels:
in the HTML text, the figure captions and every text drawn in the figures (titles, axis
labels, legends); and it ends with the references, with DOIs.  A tiny experiment (16 replicas)
keeps it to about a minute and a half on the shared machine."""
import re
import shutil
from pathlib import Path

import matplotlib.figure
import matplotlib.text
import pytest

from analogue.paper import REFERENCES
from analogue.paper import label_citations as find_labels

pytestmark = pytest.mark.slow

TINY = """
name = "tinyrep"
description = "a tiny experiment for the report-text test"
[model]
tau_m = 1.0
delta = 0.7
a = 0.2
gamma = 10.0
[experiment]
v0 = [2.0]
replicas = 16
t_end = 2.0
sample_dt = 0.02
seed = 3
histogram_times = [1.0]
work_taus = [1.0]
[report]
stationary_replicas = 16
stationary_t_end = 10.0
stationary_burn_in = 1.0
check_replicas = 4
prehistory = [[2.0, 0.2, 1.5]]
work_paths = [[0.1, 1.0]]
"""


def test_report_text_and_figures_cite_numbers(tmp_path, monkeypatch):
    if shutil.which("ngspice") is None:
        pytest.skip("ngspice not installed")
    from analogue.report.pipeline import RunOptions, build_report
    texts = []
    real = matplotlib.figure.Figure.savefig

    def savefig(self, *args, **kwargs):
        texts.extend(t.get_text() for t in self.findobj(matplotlib.text.Text))
        return real(self, *args, **kwargs)
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", savefig)
    toml = tmp_path / "tinyrep.toml"
    toml.write_text(TINY)
    index = build_report([str(toml)], tmp_path / "report",
                         RunOptions(workers=2, store=tmp_path / "store", progress=False),
                         title="label test")
    html = Path(index).read_text()
    text = re.sub(r"<img[^>]*>", "", html)            # base64 images are not text
    assert len(texts) > 50                            # the figures were drawn and seen
    assert find_labels(text) == []
    assert [t for t in texts if find_labels(t)] == []
    assert "eq. (" in text                            # numbers are cited
    paper = REFERENCES[0]
    assert f'href="https://doi.org/{paper.doi}"' in html and ">References<" in html
