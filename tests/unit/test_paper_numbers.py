"""The paper's equation/figure numbers: LaTeX's numbering rules on small hand-numbered sources,
the committed table against the paper's source, and the citation helpers."""
from pathlib import Path

import pytest

from analogue import paper as P

PAPER_TEX = Path("/work/shared/paper/baule-touchette-cohen-stick-slip.tex")

SNIPPET = r"""
\newcommand{\be}{\begin{eqnarray}}
\newcommand{\ee}{\end{eqnarray}}
\begin{equation}\label{one} a = b \end{equation}       % (1)
\begin{equation*} c \end{equation*}                     % unnumbered
\be \label{two} x &=& 1 \\ \label{three} y &=& 2 \ee   % (2), (3)
\be \label{four} z &=& 1 \nonumber \\ &=& 2 \ee         % label in a \nonumber row -> (4)
\begin{figure}\caption{\label{F_a} first}\end{figure}
\be \label{cases} f &=& \left\{\begin{array}{ll} 1 & x \\ 2 & y \end{array}\right. \ee  % (5)
\begin{subequations}\label{pair}
\begin{align} p &= 1 \label{pa}\\ q &= 2 \label{pb} \end{align}
\end{subequations}                                       % (6), (6a), (6b)
\section{S}\label{sec}
\beta \bf % macros that start like \be must not open an eqnarray
\begin{align} r &= 1 \notag \\ s &= 2 \label{seven} \end{align}   % (7)
\begin{figure*}\caption{\label{F_b} second}\end{figure*}
% \begin{equation}\label{commented}\end{equation}
"""


def test_numbering_rules_on_a_hand_numbered_snippet():
    got = P.number_labels(SNIPPET)
    assert got == {"one": ("eq", "1"), "two": ("eq", "2"), "three": ("eq", "3"),
                   "four": ("eq", "4"), "F_a": ("fig", "1"), "cases": ("eq", "5"),
                   "pair": ("eq", "6"), "pa": ("eq", "6a"), "pb": ("eq", "6b"),
                   "seven": ("eq", "7"), "F_b": ("fig", "2")}


@pytest.mark.skipif(not PAPER_TEX.is_file(), reason="the paper's LaTeX source is not here")
def test_table_matches_the_paper_source():
    tex = PAPER_TEX.read_text()
    assert P.number_labels(tex) == P.LABELS
    # figure count and the last equation agree with an independent count of the source
    assert len(P.FIGURES) == tex.count(r"\begin{figure}") == 9
    assert P.FIGURES["Fig_dryft"] == "9"


def test_known_numbers_and_formatting():
    # published numbers quoted in the project's README/issue text: Figs. 1-9, eq. (13) det_eq
    assert P.eq("det_eq") == "eq. (13)" and P.eq("model") == "eq. (1)"
    assert P.fig("Fig_dist") == "Fig. 6" and P.fig("Fig_traj_F") == "Fig. 1"
    assert P.eqs("sol1", "sol3", span=True) == "eqs. (46)-(51)"
    assert P.eqs("sol1", "sol2") == "eqs. (46) and (47)"
    assert P.eqs("bm", "U_pot", "p_stat") == "eqs. (4), (5) and (6)"
    assert P.eqs("EL1") == "eq. (15a)"
    with pytest.raises(ValueError, match="det_eq"):
        P.eq("det_eqq")
    with pytest.raises(ValueError, match="figure label"):
        P.fig("det_eq")
    with pytest.raises(TypeError):
        P.eq(13)
    with pytest.raises(ValueError, match="exactly two"):
        P.eqs("sol1", span=True)


def test_references_have_dois_and_the_required_works():
    keys = {r.key for r in P.REFERENCES}
    assert {"BTC2011", "Dykman1992", "Luchinsky1998", "vanZon2004"} <= keys
    for r in P.REFERENCES:
        assert r.doi.startswith("10.") and "/" in r.doi, r.key
        assert r.url == f"https://doi.org/{r.doi}"
        assert str(r.year) in r.text() and r.doi in r.text()
    assert len(keys) == len(P.REFERENCES)
    assert P.cite("BTC2011").arxiv == "1008.3531"
    with pytest.raises(ValueError, match="unknown reference"):
        P.cite("nope")


def test_docs_table_is_up_to_date():
    doc = Path(__file__).resolve().parents[2] / "docs" / "equations.md"
    assert doc.read_text() == P.equations_markdown(), "regenerate docs/equations.md (see paper.py)"


def test_references_html_is_escaped_and_linked():
    items = P.references_html()
    assert len(items) == len(P.REFERENCES)
    for r, h in zip(P.REFERENCES, items):
        assert f'href="https://doi.org/{r.doi}"' in h
        assert "<script" not in h and "&" not in r.title or "&amp;" in h
