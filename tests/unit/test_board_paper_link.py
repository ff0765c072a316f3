"""The paper report points at the buildable board (issue 13)."""
from analogue.circuit.experiments import PAPER_EXPERIMENTS, load_experiment, standard_circuit
from analogue.report.html import render_page
from analogue.report.pipeline import _board_link

# the board realises the paper's stick experiment: the paper's report points at it (a user's
# report does not: tests/unit/test_prose_from_the_model.py)
PAPER = [load_experiment(standard_circuit(n)) for n in PAPER_EXPERIMENTS]


def test_paper_intro_links_the_board_when_it_exists(tmp_path):
    text = render_page("t", [_board_link(tmp_path, PAPER)], [])
    assert "analogue board stick --out" in text and 'href="board/index.html"' not in text
    (tmp_path / "board").mkdir()
    (tmp_path / "board" / "index.html").write_text("<html></html>")
    assert '<a href="board/index.html">board/index.html</a>' in render_page("t", [_board_link(tmp_path, PAPER)], [])


def test_a_hostile_output_path_is_escaped(tmp_path):
    odd = tmp_path / "<script>x"
    odd.mkdir()
    assert "<script>" not in render_page("t", [_board_link(odd, PAPER)], []).split("<body>")[1]
