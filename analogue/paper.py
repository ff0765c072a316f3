"""The paper's published equation and figure numbers, and the references the project cites.

Baule, Touchette & Cohen, "Stick-slip motion of solids with dry friction subject to random
vibrations and an external field", Nonlinearity 24, 351 (2011), arXiv:1008.3531 (:data:`REFERENCES`
holds it and the other works the project uses, with DOIs).  The code and the report cite
its equations by number, "eq. (12)", never by LaTeX label: :func:`eq` and :func:`fig` turn a
label of the LaTeX source into that number, and :data:`LABELS` is the whole table (also in
``docs/equations.md``).

The numbers follow LaTeX's own rules applied to the order of the source
(:func:`number_labels`): each row of an ``eqnarray``/``align`` and each ``equation`` gets the
next number unless it is starred or carries ``\\nonumber``/``\\notag``; rows are separated by
``\\\\`` outside inner ``array``/``cases`` environments; a ``subequations`` block takes one
number and its rows get letters (13a, 13b); figures are numbered in the order of their
``figure`` environments.  ``tests/unit/test_paper_numbers.py`` re-derives the table from the
source when it is available.
"""
from __future__ import annotations

import re
import string
from dataclasses import dataclass

__all__ = [
    "EQUATIONS",
    "FIGURES",
    "LABELS",
    "REFERENCES",
    "Reference",
    "cite",
    "eq",
    "eqs",
    "equations_markdown",
    "fig",
    "label_citations",
    "number_labels",
    "references_html",
    "references_text",
]

# label -> ("eq" | "fig", number), derived by number_labels() from the arXiv source of the paper
# (arXiv:1008.3531; the project keeps it at /work/shared/paper/baule-touchette-cohen-stick-slip.tex).
LABELS: dict[str, tuple[str, str]] = {
    "model": ("eq", "1"), "noise_corr": ("eq", "2"), "work": ("eq", "3"), "bm": ("eq", "4"),
    "U_pot": ("eq", "5"), "p_stat": ("eq", "6"), "path_int": ("eq", "7"), "action": ("eq", "8"),
    "lagrangian": ("eq", "9"), "jacobian": ("eq", "10"), "ELform": ("eq", "11"),
    "sp_approx": ("eq", "12"), "det_eq": ("eq", "13"), "v_st": ("eq", "14"), "EL": ("eq", "15"),
    "EL1": ("eq", "15a"), "EL2": ("eq", "15b"), "sol_basic": ("eq", "16"), "B+": ("eq", "18"),
    "C+": ("eq", "19"), "lambda": ("eq", "20"), "dir_par": ("eq", "21"), "Adir": ("eq", "22"),
    "dirx_par": ("eq", "23"), "Adirx": ("eq", "24"), "tbar_eq": ("eq", "25"),
    "id_par": ("eq", "26"), "idx_par": ("eq", "27"), "Aind": ("eq", "28"), "ineq": ("eq", "30"),
    "tbar1": ("eq", "31"), "tbar2": ("eq", "32"), "Aind2": ("eq", "33"), "Aind2b": ("eq", "34"),
    "dc_par": ("eq", "35"), "Adc": ("eq", "36"), "cond1": ("eq", "37"), "cond1b": ("eq", "38"),
    "dpm": ("eq", "41"), "cond2": ("eq", "42"), "vc_b": ("eq", "45"), "sol1": ("eq", "46"),
    "sol2": ("eq", "47"), "cond3": ("eq", "49"), "sol3": ("eq", "51"), "work_power": ("eq", "52"),
    "eqpi1": ("eq", "53"), "largeDev": ("eq", "54"), "eqi1": ("eq", "55"),
    "rate_func": ("eq", "56"), "Keq": ("eq", "57"), "modLag": ("eq", "58"),
    "eqelk1": ("eq", "60"), "vw": ("eq", "61"), "wF": ("eq", "63"), "Iw": ("eq", "64"),
    "conventional": ("eq", "65"), "ftexp": ("eq", "67"), "dryft": ("eq", "68"),
    "fluc_fac": ("eq", "72"), "Fig_traj_F": ("fig", "1"), "Fig_smallF": ("fig", "2"),
    "Fig_largeF": ("fig", "3"), "Fig_dc": ("fig", "4"), "Fig_bound1": ("fig", "5"),
    "Fig_dist": ("fig", "6"), "Fig_workpath": ("fig", "7"), "Fig_ratef": ("fig", "8"),
    "Fig_dryft": ("fig", "9"),
}
EQUATIONS = {k: n for k, (kind, n) in LABELS.items() if kind == "eq"}
FIGURES = {k: n for k, (kind, n) in LABELS.items() if kind == "fig"}


def number_labels(tex: str) -> dict[str, tuple[str, str]]:
    """``{label: ("eq" | "fig", number)}`` for a LaTeX source, by LaTeX's numbering rules (see
    the module docstring).  Labels of sections and of unnumbered rows are left out."""
    tex = re.sub(r"(?<!\\)%.*", "", tex)                         # comments
    macros = dict(re.findall(r"\\newcommand\{\\(\w+)\}\{(\\(?:begin|end)\{[\w*]+\})\}", tex))
    tex = re.sub(r"\\newcommand\{\\\w+\}\{[^\n]*\}\n", "\n", tex)
    math_envs = {"equation", "eqnarray", "align", "gather", "multline", "flalign", "alignat"}
    inner_envs = {"array", "cases", "matrix", "pmatrix", "bmatrix", "split", "aligned",
                  "gathered", "tabular", "smallmatrix"}
    token = re.compile(r"\\(begin|end)\{([\w*]+)\}|\\label\{([^}]*)\}|\\(nonumber|notag)\b"
                       r"|\\\\|\\([A-Za-z]+)")
    out: dict[str, tuple[str, str]] = {}
    eq_no = fig_no = 0
    stack: list[str] = []
    row_labels: list[str] = []
    row_numbered = True
    sub_parent: int | None = None
    sub_count = 0
    sub_labels: list[str] = []

    def math_top() -> str | None:
        for env in reversed(stack):
            if env in inner_envs:
                return None
            if env.rstrip("*") in math_envs:
                return env
        return None

    def end_row() -> None:
        nonlocal eq_no, sub_count, row_labels, row_numbered
        env = math_top()
        if env is not None and not env.endswith("*") and row_numbered:
            if sub_parent is not None:
                number = f"{sub_parent}{string.ascii_lowercase[sub_count]}"
                sub_count += 1
            else:
                eq_no += 1
                number = str(eq_no)
            for lab in row_labels:
                out[lab] = ("eq", number)
            row_labels = []
        # A label in an unnumbered row stays pending: LaTeX's eqnarray steps the counter only
        # after a numbered row, so such a label names the next numbered row (eq. "lambda").
        row_numbered = True

    for m in token.finditer(tex):
        kind, env, label, nonum, macro = m.groups()
        if macro is not None:
            if macro not in macros:
                continue
            spec = re.fullmatch(r"\\(begin|end)\{([\w*]+)\}", macros[macro])
            if spec is None:
                continue
            kind, env = spec.groups()
        if kind == "begin":
            if env == "subequations":
                eq_no += 1
                sub_parent, sub_count, sub_labels = eq_no, 0, []
            elif env.rstrip("*") == "figure":
                fig_no += 1
            stack.append(env)
            if env.rstrip("*") in math_envs and math_top() == env:
                row_labels, row_numbered = [], True
        elif kind == "end":
            if env.rstrip("*") in math_envs and math_top() == env:
                end_row()
                row_labels = []
            if env == "subequations":
                for lab in sub_labels:
                    out[lab] = ("eq", str(sub_parent))
                sub_parent = None
            if stack and stack[-1] == env:
                stack.pop()
        elif label is not None:
            if math_top() is not None:
                row_labels.append(label)
            elif stack and stack[-1] == "subequations":
                sub_labels.append(label)
            elif any(e.rstrip("*") == "figure" for e in stack):
                out[label] = ("fig", str(fig_no))
        elif nonum is not None:
            if math_top() is not None:
                row_numbered = False
        else:  # "\\"
            env = math_top()
            if env is not None and env.rstrip("*") != "equation":
                end_row()
    return out


# ------------------------------------------------------------------------------ citations
def _lookup(label: str, kind: str) -> str:
    if not isinstance(label, str):
        raise TypeError(f"label must be a str, got {type(label).__name__}")
    table = EQUATIONS if kind == "eq" else FIGURES
    if label not in table:
        import difflib
        close = difflib.get_close_matches(label, list(table), n=3)
        hint = f" (did you mean {', '.join(close)}?)" if close else ""
        raise ValueError(f"{label!r} is not a{'n equation' if kind == 'eq' else ' figure'} "
                         f"label of the paper{hint}; see analogue.paper.LABELS")
    return table[label]


def eq(label: str) -> str:
    """``eq("det_eq") -> "eq. (13)"``: the paper's published number of an equation label."""
    return f"eq. ({_lookup(label, 'eq')})"


def eqs(*labels: str, span: bool = False) -> str:
    """Several equations: ``eqs("sol1", "sol2") -> "eqs. (46) and (47)"``;
    ``eqs("sol1", "sol3", span=True) -> "eqs. (46)-(51)"``."""
    if not labels:
        raise ValueError("eqs needs at least one label")
    nums = [f"({_lookup(lab, 'eq')})" for lab in labels]
    if span:
        if len(nums) != 2:
            raise ValueError("eqs(..., span=True) takes exactly two labels (first, last)")
        return f"eqs. {nums[0]}-{nums[1]}"
    if len(nums) == 1:
        return f"eq. {nums[0]}"
    return f"eqs. {', '.join(nums[:-1])} and {nums[-1]}"


def fig(label: str) -> str:
    """``fig("Fig_dist") -> "Fig. 6"``."""
    return f"Fig. {_lookup(label, 'fig')}"


# ----------------------------------------------------------------------------- references
@dataclass(frozen=True)
class Reference:
    """One bibliography entry; ``doi`` without the ``https://doi.org/`` prefix."""

    key: str
    authors: str
    title: str
    journal: str
    year: int
    doi: str
    arxiv: str = ""
    used_for: str = ""

    @property
    def url(self) -> str:
        return f"https://doi.org/{self.doi}"

    def text(self) -> str:
        """A one-line citation: authors, "title", journal (year), doi:..."""
        extra = f", arXiv:{self.arxiv}" if self.arxiv else ""
        return f'{self.authors}, "{self.title}", {self.journal} ({self.year}), doi:{self.doi}{extra}'


REFERENCES: tuple[Reference, ...] = (
    Reference("BTC2011", "A. Baule, H. Touchette and E. G. D. Cohen",
              "Stick-slip motion of solids with dry friction subject to random vibrations and "
              "an external field", "Nonlinearity 24, 351", 2011,
              "10.1088/0951-7715/24/2/001", arxiv="1008.3531",
              used_for="the model, the weak-noise theory and the figures reproduced here"),
    Reference("BCT2010", "A. Baule, E. G. D. Cohen and H. Touchette",
              "A path integral approach to random motion with nonlinear friction",
              "J. Phys. A 43, 025003", 2010, "10.1088/1751-8113/43/2/025003",
              used_for="the path-integral method (the a = 0 case)"),
    Reference("TVJ2010", "H. Touchette, E. Van der Straeten and W. Just",
              "Brownian motion with dry friction: Fokker-Planck approach",
              "J. Phys. A 43, 445002", 2010, "10.1088/1751-8113/43/44/445002",
              used_for="exact propagator of pure dry friction (checks of the exact numerics)"),
    Reference("TPJ2012", "H. Touchette, T. Prellberg and W. Just",
              "Exact power spectra of Brownian motion with solid friction",
              "J. Phys. A 45, 395002", 2012, "10.1088/1751-8113/45/39/395002",
              used_for="Laplace-transform solution with viscous friction and force; spectra"),
    Reference("CBTJ2013", "Y. Chen, A. Baule, H. Touchette and W. Just",
              "Weak-noise limit of a piecewise-smooth stochastic differential equation",
              "Phys. Rev. E 88, 052103", 2013, "10.1103/PhysRevE.88.052103",
              used_for="the weak-noise limit of this model (finite-noise corrections)"),
    Reference("HKS2019", "V. Holubec, K. Kroy and S. Steffenoni",
              "Physically consistent numerical solver for time-dependent Fokker-Planck equations",
              "Phys. Rev. E 99, 032117", 2019, "10.1103/PhysRevE.99.032117",
              used_for="the symmetrised finite-volume Fokker-Planck generator of the exact numerics"),
    Reference("Dykman1992", "M. I. Dykman, P. V. E. McClintock, V. N. Smelyanski, N. D. Stein "
              "and N. G. Stocks", "Optimal paths and the prehistory problem for large "
              "fluctuations in noise-driven systems", "Phys. Rev. Lett. 68, 2718", 1992,
              "10.1103/PhysRevLett.68.2718",
              used_for="prehistory: measuring optimal paths in an analogue circuit"),
    Reference("Luchinsky1998", "D. G. Luchinsky, P. V. E. McClintock and M. I. Dykman",
              "Analogue studies of nonlinear systems", "Rep. Prog. Phys. 61, 889", 1998,
              "10.1088/0034-4885/61/8/001",
              used_for="analogue electronic circuits as stochastic-dynamics experiments"),
    Reference("vanZon2004", "R. van Zon, S. Ciliberto and E. G. D. Cohen",
              "Power and heat fluctuation theorems for electric circuits",
              "Phys. Rev. Lett. 92, 130601", 2004, "10.1103/PhysRevLett.92.130601",
              used_for="fluctuation theorems measured in an RC circuit"),
    Reference("Garnier2005", "N. Garnier and S. Ciliberto", "Nonequilibrium fluctuations in a "
              "resistor", "Phys. Rev. E 71, 060101(R)", 2005, "10.1103/PhysRevE.71.060101",
              used_for="work and heat fluctuations of a driven RC circuit"),
    Reference("GPT2013", "A. Gnoli, A. Puglisi and H. Touchette", "Granular Brownian motion "
              "with dry friction", "EPL 102, 14002", 2013, "10.1209/0295-5075/102/14002",
              used_for="velocity power spectra of a granular probe with dry friction, measured "
                       "(the chapter 'What experiments measure')"),
    Reference("CJ2014", "Y. Chen and W. Just", "First-passage time of Brownian motion with dry "
              "friction", "Phys. Rev. E 89, 022103", 2014, "10.1103/PhysRevE.89.022103",
              arxiv="1312.0581",
              used_for="first passage to rest (the chapter 'What experiments measure')"),
    Reference("GMC2009", "P. S. Goohpattader, S. Mettu and M. K. Chaudhury",
              "Experimental investigation of the drift and diffusion of small objects on a "
              "surface subjected to a bias and an external white noise: roles of Coulombic "
              "friction and hysteresis", "Langmuir 25, 9969", 2009, "10.1021/la901012m",
              used_for="drift and diffusion under a bias against the noise power, measured"),
    Reference("GC2010", "P. S. Goohpattader and M. K. Chaudhury", "Diffusive motion with "
              "nonlinear friction: apparently Brownian", "J. Chem. Phys. 133, 024702", 2010,
              "10.1063/1.3460530",
              used_for="mobility and an Einstein-like relation under dry friction, measured"),
)
_BY_KEY = {r.key: r for r in REFERENCES}


def cite(key: str) -> Reference:
    """The :class:`Reference` with this key (``"BTC2011"`` is the paper)."""
    if key not in _BY_KEY:
        raise ValueError(f"unknown reference key {key!r}; known: {', '.join(_BY_KEY)}")
    return _BY_KEY[key]


def references_text() -> list[str]:
    """The bibliography as plain text lines, ``[key] citation``."""
    return [f"[{r.key}] {r.text()}" for r in REFERENCES]


def equations_markdown() -> str:
    """``docs/equations.md``: the label -> number table and the references (regenerate with
    ``python -c "import analogue.paper as p; print(p.equations_markdown(), end='')" >
    docs/equations.md``; a test keeps the file in step)."""
    lines = ["# The paper's equation and figure numbers", "",
             ("Baule, Touchette & Cohen (2011) are cited throughout analogue by their published "
              "numbers, \"eq. (13)\", \"Fig. 6\". The numbers follow from the order of the LaTeX "
              "source (arXiv:1008.3531) by LaTeX's own rules (`analogue.paper.number_labels`): "
              "every row of an `eqnarray`/`align` and every `equation` is numbered unless "
              "starred or `\\nonumber`; a label in an unnumbered row names the next numbered "
              "row; a `subequations` block takes one number and lettered rows; figures count "
              "in order. Unlabelled equations are counted too, hence the gaps."), "",
             ("In Python: `analogue.paper.eq(\"det_eq\")` -> `eq. (13)`, "
              "`analogue.paper.fig(\"Fig_dist\")` -> `Fig. 6`."), "",
             "| LaTeX label | number |", "|---|---|"]
    for label, (kind, number) in LABELS.items():
        shown = f"eq. ({number})" if kind == "eq" else f"Fig. {number}"
        lines.append(f"| `{label}` | {shown} |")
    lines += ["", "## References", ""]
    for r in REFERENCES:
        arxiv = f", [arXiv:{r.arxiv}](https://arxiv.org/abs/{r.arxiv})" if r.arxiv else ""
        lines.append(f"- **[{r.key}]** {r.authors}, \"{r.title}\", *{r.journal}* ({r.year}), "
                     f"[doi:{r.doi}]({r.url}){arxiv}. {r.used_for[:1].upper() + r.used_for[1:]}.")
    return "\n".join(lines) + "\n"


def references_html() -> list[str]:
    """The bibliography as HTML paragraphs for the report (text escaped, DOI and arXiv links)."""
    import html
    out = []
    for r in REFERENCES:
        arxiv = (f', <a href="https://arxiv.org/abs/{html.escape(r.arxiv)}">arXiv:'
                 f'{html.escape(r.arxiv)}</a>') if r.arxiv else ""
        out.append(f"[{html.escape(r.key)}] {html.escape(r.authors)}, "
                   f"&ldquo;{html.escape(r.title)}&rdquo;, <i>{html.escape(r.journal)}</i> "
                   f"({r.year}), <a href=\"{html.escape(r.url)}\">doi:{html.escape(r.doi)}</a>"
                   f"{arxiv}. {html.escape(r.used_for[:1].upper() + r.used_for[1:])}.")
    return out


_LABEL_RE = ("(?:" + "|".join(re.escape(x) for x in sorted(LABELS, key=len, reverse=True))
             + r")(?![\w+])")
# a citation head followed (possibly after "(", across a line break) by a label
_CITATION = re.compile(r"\b(?:[Ee]qs?\.|[Ee]quations?|[Ff]igs?\.|[Ff]igures?)\s*\(?\s*"
                       + _LABEL_RE)
# labels that cannot be ordinary words (underscores or digits), wherever they stand
_DISTINCT = re.compile(r"(?<![\w.\"'`])(?:" + "|".join(
    re.escape(x) for x in sorted(LABELS, key=len, reverse=True)
    if re.search(r"[_\d]", x) and x not in ("EL1", "EL2")) + r")(?![\w+])")


def label_citations(text: str) -> list[str]:
    """LaTeX labels of the paper cited in ``text`` ("eq. det_eq", "Fig. Fig_dist", a bare
    "p_stat"): what a reader could not look up.  Empty when ``text`` cites numbers only."""
    return ([m.group(0) for m in _CITATION.finditer(text)]
            + [m.group(0) for m in _DISTINCT.finditer(text)])
