"""From a study to a report directory: ``index.html`` (self-contained), PNGs, ``metrics.json``.

``build_paper_report`` is the main job (``analogue paper``): the paper's experiments
(:data:`analogue.study.experiments.PAPER_EXPERIMENTS`, the standard circuits shipped with
the package, never the user's files), the paper's Figs. 1-9 with circuit data, the paper's open
question settled by exact numerics, and every circuit-versus-theory comparison with its error
budget.  ``build_experiment_report`` (``analogue report``, :func:`analogue.report`) does the
same for one experiment of the user's.

What is computed (runs, theory, comparisons, budgets, the schedule) is the study's:
:func:`analogue.study.run.run_study` -> :class:`~analogue.study.run.StudyResult`.  This module
only draws the figures (while the study runs, through its hooks) and writes the page.

Every experiment is loaded (and so validated) before anything runs.  After that, a section
whose work fails (a circuit run, an analysis, a figure) never throws away the sections that
finished: it is written as a failed section with its error, ``metrics.json`` lists it under
``failures``, and :class:`ReportIncomplete` is raised once the page is written.
"""
from __future__ import annotations

import concurrent.futures as cf
import json
import time
from concurrent.futures import Future
from dataclasses import dataclass
from pathlib import Path

from markupsafe import Markup

from ..study.experiments import (FIG1_EXPERIMENTS, PAPER_EXPERIMENTS, PAPER_FIGURE_TAGS,
                                   Experiment, standard_circuit)
from ..circuit.mapping import map_model
from ..files import write_text
from ..paper import references_html
from ..plots.open_question import CASES, draw_open_question, open_question_data
from ..study import members as beyond_analysis
from ..study.budget import terms_above_se_text
from ..study.comparisons import ExperimentAnalysis
from ..study.critical_path import FIGURES_COMPARED, MEMBER_FIGURES, critical_path_text
from ..study.members import CHAPTER_TITLE, MEMBERS, MemberRuns
# run_experiment (``analogue run``) runs circuits only: the study's; importable from here as before
from ..study.run import (MemberRunSummary, RunSummary, StudyHooks, StudyResult, load as _load,  # noqa: F401
                         run_experiment, run_study)
from ..circuit.simulate import POLL_S
from ..study.runs import ExperimentRuns
from ..study.schedule import SWEEP_DECKS, Failures, result_of, say as _log
from ..study.settings import RunOptions
from . import beyond, figures, measure_chapter, prose
from .html import Figure, Section, Table, write_page

__all__ = ["RunOptions", "run_experiment", "build_experiment_report", "build_paper_report",
           "build_report", "report", "RunSummary", "ReportIncomplete", "experiment_section_text"]


class ReportIncomplete(RuntimeError):
    """The report was written, but some of its sections failed (each is in the page with its
    error, and in metrics.json under ``failures``)."""

    def __init__(self, index: Path, failures: list, result: StudyResult | None = None):
        self.index, self.failures, self.result = index, failures, result
        what = "; ".join(f"{f['section']}: {f['error']}" for f in failures)
        super().__init__(f"report written to {index} with {len(failures)} failed "
                         f"section(s): {what}")


def build_experiment_report(name, out, opts: RunOptions) -> Path:
    """The report of one experiment (a name or a TOML path: the user's): :func:`report`'s
    page; raises :class:`ReportIncomplete` when a section failed."""
    result = report(name, out, opts=opts, raise_incomplete=True)
    assert result.page is not None
    return result.page


def report(experiment, out=None, *, quick: bool = False, opts: RunOptions | None = None,
           runner=None, raise_incomplete: bool = False) -> StudyResult:
    """Run, analyse and write the report of one experiment: what ``analogue report`` does,
    from Python (``analogue.report(...)``).

    ``experiment``: a name (``./circuits/<name>.toml``, else a standard experiment), a TOML
    path or an :class:`~analogue.study.experiments.Experiment`; ``out``: the report
    directory (default ``report/<name>``); ``quick``: the quick sizes (ignored when ``opts``,
    a :class:`~analogue.study.settings.RunOptions`, is given: its own ``quick`` counts);
    ``runner``: how the decks run, an :class:`analogue.Runner` (its store, workers, scheduler,
    timeout, progress: :meth:`~analogue.study.settings.RunOptions.from_runner`).

    Returns the :class:`~analogue.study.run.StudyResult`: its ``comparisons``, ``figures``
    (experiment -> PNG paths), ``page`` (``index.html``), ``failures``, the runs
    (``by_role(name)``).  A section that failed is in ``failures`` (and on the page); with
    ``raise_incomplete`` it raises :class:`ReportIncomplete` instead, as the command line
    does."""
    if runner is not None and opts is not None:
        raise TypeError("pass either runner= (an analogue.Runner) or opts=, not both")
    if runner is not None:
        opts = RunOptions.from_runner(runner, quick=quick)
    exp = _load(experiment)  # validated before anything runs
    out = Path(out) if out is not None else Path("report") / exp.name
    opts = opts if opts is not None else RunOptions(quick=quick, progress=False)
    try:
        return _report([exp], out, opts, title=f"analogue report: experiment {exp.name}")
    except ReportIncomplete as exc:
        if raise_incomplete:
            raise
        assert exc.result is not None
        return exc.result


def _board_link(out: Path, experiments=()):
    """The intro's pointer to the buildable board of the stick experiment (issue 13), in the
    paper's report: :func:`analogue.report.prose.board_link`."""
    return prose.board_link(out, experiments)


def build_paper_report(out, opts: RunOptions) -> Path:
    """The paper's experiments (:data:`PAPER_EXPERIMENTS`, standard circuits), then the
    chapter "Beyond the paper" (one experiment per extension, :mod:`.beyond`, quick sizes)."""
    return build_report([standard_circuit(n) for n in PAPER_EXPERIMENTS], Path(out), opts,
                        title="Stick-slip friction with noise: the paper on an analogue circuit",
                        chapter=[standard_circuit(n) for n in MEMBERS])


def experiment_section_text(exp: Experiment) -> list[str]:
    """Paragraphs of an experiment's section: its description (the user's text, escaped by
    the page template like every other text), a note where the description's numbers are not
    the model's, and the model's parameters (:func:`analogue.report.prose.experiment_paragraphs`)."""
    return prose.experiment_paragraphs(exp)


# ------------------------------------------------------------------------------ sections
def _mapping_table(runs) -> Table:
    m = map_model(runs.exp.model, runs.exp.spec)  # runs: ExperimentRuns or MemberAnalysis
    rows = [[name, float(value), unit, meaning]
            for name, value, unit, meaning in prose.component_rows(m)]
    element = (f"{runs.exp.spec.coulomb}, diode {runs.exp.spec.diode}"
               if m.coulomb_element is not None else "no Coulomb element (Delta = 0)")
    return Table(f"{runs.exp.name}: component values ({element})",
                 ["quantity", "value", "unit", "meaning"], rows, collapsed=True)


def _comparison_table(comps, caption) -> Table:
    rows, classes = [], []
    for c in comps:
        b = c.budget
        rows.append([c.experiment, c.observable, c.theory_kind, c.circuit, c.circuit_stderr,
                     c.theory, c.z, abs(b.smoothing), abs(b.bandwidth), abs(b.integration),
                     abs(b.sampling), abs(b.finite_noise), c.within_budget,
                     c.as_dict()["budget"]["dominant"]])
        classes.append("ok" if c.within_budget else "fail")
    return Table(caption, ["experiment", "observable", "theory", "circuit", "SE", "theory value",
                           "z", "smoothing", "bandwidth", "integration", "sampling",
                           "finite noise",
                           "within budget", "dominant error"], rows, classes)


def _explain(comps) -> list[str]:
    """Say, for each comparison outside |z| < 3, whether the budget explains it."""
    lines = []
    for c in comps:
        if abs(c.z) < 3:
            continue
        if c.within_budget:
            lines.append(f"{c.experiment} / {c.observable} ({c.theory_kind}): z = {c.z:.1f}, "
                         f"explained by the budget (dominant: {c.as_dict()['budget']['dominant']}).")
        else:
            lines.append(f"{c.experiment} / {c.observable} ({c.theory_kind}): z = {c.z:.1f}, "
                         "NOT explained by the budget: |circuit - theory| = "
                         f"{abs(c.circuit - c.theory):.3g} > 3 SE + systematics = "
                         f"{3 * c.circuit_stderr + c.budget.total():.3g}.")
    return lines

#: the experiment figures that draw theory curves (``analysis.curves``: the work-rate bins,
#: the histogram's range); the others need the comparisons alone and are drawn as soon as
#: they are in, while the curves are computed (issue 22: figures drawn as their data arrive)
CURVE_FIGURES = frozenset({"prehistory", "stationary law", "work paths", "rate function"})


def _figure_calls(runs: ExperimentRuns, a: ExperimentAnalysis, out: Path) -> list:
    """``(what, function)`` for each of the experiment's figures, in the page's order."""
    # the paper's figure number only for the paper's own experiment (a user's file named
    # "stick" is not paper Fig. 2)
    tag = (PAPER_FIGURE_TAGS.get(runs.exp.name, "paths") if prose.is_paper_experiment(runs.exp)
           else "paths")
    return [("prehistory", lambda: figures.fig_prehistory(a, out, tag)),
            ("boundaries", lambda: figures.fig_boundaries(runs, out)),
            ("propagator", lambda: figures.fig_propagator(a, out)),
            ("propagator", lambda: figures.fig_propagator(a, out, runs.exp.v0[-1])
             if len(runs.exp.v0) > 1 else None),
            ("stationary law", lambda: figures.fig_stationary(a, out)),
            ("work paths", lambda: figures.fig_work_paths(a, out)),
            ("rate function", lambda: figures.fig_rate_function(a, out)),
            ("error budget", lambda: figures.fig_budget(a, out))]


def _draw_figures(runs: ExperimentRuns, analysis: ExperimentAnalysis, out: Path,
                  fails: Failures, section: str, curves: bool | None = None) -> dict:
    """Draw the experiment's figures: those of :data:`CURVE_FIGURES` (``curves`` True), the
    others (False) or all (None).  Returns ``{position: (Figure or None, error or None)}``,
    the position in the page's order; one that fails is recorded and the others are kept."""
    drawn: dict = {}
    for k, (what, fn) in enumerate(_figure_calls(runs, analysis, out)):
        if curves is not None and (what in CURVE_FIGURES) != curves:
            continue
        _log(f"{runs.exp.name}: figure: {what}")
        r, err = fails.attempt(section, f"figure: {what}", fn, runs.exp.name)
        drawn[k] = (None if err is not None or r is None else Figure(*r),
                    None if err is None else f"figure '{what}': {err}")
    return drawn


def _in_order(drawn: dict) -> tuple[list, list]:
    """(figures, errors) of :func:`_draw_figures`'s parts, in the page's order."""
    items = [drawn[k][0] for k in sorted(drawn) if drawn[k][0] is not None]
    errors = [drawn[k][1] for k in sorted(drawn) if drawn[k][1] is not None]
    return items, errors


def _figures_for(runs: ExperimentRuns, analysis: ExperimentAnalysis, out: Path,
                 fails: Failures, section: str) -> tuple[list, list]:
    """The experiment's figures; one that fails is recorded and the others are kept.
    They only draw: every theory curve is in ``analysis`` (computed once).
    Returns (figures, errors)."""
    return _in_order(_draw_figures(runs, analysis, out, fails, section))


def _open_question_gammas(opts: RunOptions) -> tuple:
    return (10.0, 100.0) if opts.quick else (10.0, 100.0, 1000.0)


def _open_question_data(opts: RunOptions) -> dict:
    """The exact curves of the open question (no circuit data: computed while ngspice runs)."""
    return {(a, half): open_question_data(a, half, gammas=_open_question_gammas(opts))
            for a, half in CASES}


def _open_question_section(out: Path, opts: RunOptions, data=None) -> Section:
    """``data``: the exact curves (:func:`_open_question_data`), or a Future of them (computed
    while ngspice ran), or None (computed here)."""
    gammas = _open_question_gammas(opts)
    if isinstance(data, Future):
        data = result_of(data)
    paths = draw_open_question(out, gammas=gammas, data=data)
    text = [
        "The paper finds a jump of the rate function I(w) at w = 0 (eq. (64)) and cannot tell "
        "whether it is real. The exact rate function at finite noise, I_gamma(w) = "
        "sup_k [k w - lambda(k)] / gamma with lambda the principal eigenvalue of the tilted "
        "Fokker-Planck generator, answers it: I_gamma is convex and continuous for every gamma, "
        "and as gamma grows it converges to the lower convex envelope of the cost of holding a "
        "constant velocity w/(m a) - where holding v = 0 costs max(|a| - Delta, 0)^2/4, i.e. "
        "nothing when the object can stick. Near w = 0 the optimal histories share their time "
        "between sticking and sliding, which makes the limit linear there: the jump is an "
        "artefact of restricting the paths to one constant velocity, and the fluctuation "
        "relation of eq. (68) has no jump either. The tests check the convergence "
        "(tests/unit/test_open_question.py)."]
    gs = ", ".join(f"{g:g}" for g in gammas)
    caps = [f"Exact I_gamma(w) for gamma = {gs} against the paper's I(w) (eq. (64)) and the "
            "gamma -> infinity limit (convex envelope).",
            f"The fluctuation relation I(-w) - I(w): exact at gamma = {gs}, the paper's eq. (67) "
            "with its jump 2 a Delta, and the limit."]
    return Section("The paper's open question: is the jump of I(w) at w = 0 real?", text,
                   figures=[Figure(p, caps[i] if i < len(caps) else "") for i, p in enumerate(paths)])




def _wants_open_question(experiments) -> bool:
    """The paper's open question (its own parameters) belongs to reports of the paper's
    experiments, not to a report of the user's own files (issue 20 item 3)."""
    return any(prose.is_paper_experiment(e) for e in experiments)


def _experiment_title(exp) -> str:
    return f"Experiment '{exp.name}': {exp.model.regime} regime"


FIG1_TITLE = "Paper Fig. 1: deterministic motion"
OPEN_QUESTION_TITLE = "The paper's open question: is the jump of I(w) at w = 0 real?"


class _Drawer(StudyHooks):
    """The report's figures, drawn while the study runs (:class:`~analogue.study.run.
    StudyHooks`): each experiment's as soon as its theory curves are in, the open question's
    when its exact curves are, Fig. 1 once every experiment is compared."""

    def __init__(self, out: Path, opts: RunOptions, experiments: list):
        self.out, self.opts, self.experiments = out, opts, experiments
        self.figs: dict = {}            # experiment -> (figures, errors)
        self.drawn: dict = {}           # experiment -> its figures drawn before its curves
        self.member_sections: dict = {}  # family member -> its section, drawn when it completed
        self.oq_section: list = []      # the open question's section, once drawn
        self.fig1_section: Section | None = None
        self.measure_f: dict = {}        # experiment -> future of its measure theory
        self.measured = measure_chapter.ChapterResult()
        self.sweep_f: dict = {}          # sweep name -> future of its dataset

    def circuit_background(self, result: StudyResult) -> dict:
        # the chapter's sweep curves (--sweeps), with the circuit work (issue 22: they waited
        # for the paper's chapters and ran point after point, 93 s of the quick paper's 95 s
        # critical path): both sweeps' points at once, every deck in the study's one deck
        # pool after the paper's and the members' (with a Dask scheduler, on the cluster)
        exp = measure_chapter.sweep_experiment(self.experiments, self.opts)
        if exp is None:
            return {}
        return measure_chapter.sweep_tasks(exp, result.options_for(self.opts, SWEEP_DECKS),
                                           phases=result.phases)

    def background(self) -> dict:
        # the chapter "What experiments measure" (stick, slip): exact theory and Monte Carlo
        # pairs, no circuit data; the chapter reads the experiments' runs (no deck of its own)
        tasks = measure_chapter.theory_tasks(self.experiments, self.opts, progress=_log)
        if _wants_open_question(self.experiments):
            tasks["open question (exact rate functions)"] = lambda: _open_question_data(self.opts)
        return tasks

    def experiment_compared(self, result: StudyResult, runs, analysis) -> None:
        # the figures that need no theory curve, while the curves are computed
        with result.phases(FIGURES_COMPARED, runs.exp.name):
            self.drawn[runs.exp.name] = _draw_figures(
                runs, analysis, self.out, result.failures, _experiment_title(runs.exp),
                curves=False)

    def experiment_ready(self, result: StudyResult, runs, analysis) -> None:
        drawn = self.drawn.pop(runs.exp.name, None)
        with result.phases("figures", runs.exp.name):
            rest = _draw_figures(runs, analysis, self.out, result.failures,
                                 _experiment_title(runs.exp),
                                 curves=None if drawn is None else True)
        self.figs[runs.exp.name] = _in_order({**(drawn or {}), **rest})
        result.figures[runs.exp.name] = [f.path for f in self.figs[runs.exp.name][0]]

    def member_ready(self, result: StudyResult, exp, analysis) -> None:
        # a member's section, drawn as soon as it is analysed (the others still run); before,
        # every member's figures were drawn with the page, at the very end
        with result.phases(MEMBER_FIGURES, exp.name):
            self.member_sections[exp.name] = _member_section(result, exp, analysis, self.out)

    def background_ready(self, result: StudyResult, phase: str, future: Future) -> None:
        if phase.startswith(measure_chapter.SWEEP_PHASE):
            self.sweep_f[phase.rpartition(": ")[2]] = future
            return
        if phase.startswith(measure_chapter.THEORY_PHASE):
            self.measure_f[phase.rpartition(": ")[2]] = future
            return
        _log("the paper's open question: exact rate functions at several gamma")
        with result.phases("figures: open question"):
            sec, err = result.failures.attempt(
                OPEN_QUESTION_TITLE, "exact rate functions",
                lambda: _open_question_section(self.out, self.opts, future))
        self.oq_section.append(sec if sec is not None else Section(OPEN_QUESTION_TITLE, error=err))
        result.figures["open question"] = [f.path for f in self.oq_section[0].figures]

    def main_complete(self, result: StudyResult) -> None:
        all_runs = list(result.runs.values())
        if all_runs:
            paper = [r for r in all_runs if r.exp.name in FIG1_EXPERIMENTS
                     and prose.is_paper_experiment(r.exp)]
            fig1_runs = paper or all_runs
            # the paper's figure number only over the paper's own experiments (issue 20
            # item 3: a user's report read "Paper Fig. 1" over its own runs)
            title = FIG1_TITLE if paper else "Deterministic motion (noise off)"
            with result.phases("figures: Fig. 1"):
                fig, err = result.failures.attempt(
                    title, "figure",
                    lambda: Figure(*figures.fig_deterministic(fig1_runs, self.out)))
            self.fig1_section = Section(title, figures=[fig] if fig is not None else [],
                                        error=err)
            if fig is not None:
                result.figures["Fig. 1"] = [fig.path]
        _log(f"{prose.main_part(result.experiments)} are complete "
             f"({time.perf_counter() - result.t0:.0f} s)")
        if self.measure_f:
            self._measure_chapter(result)

    def _measure_chapter(self, result: StudyResult) -> None:
        """The chapter "What experiments measure": its own part, then (waiting for them, a
        phase that is no work) the sweep curves started with the circuit work."""
        mc, all_runs = measure_chapter, list(result.runs.values())
        attempt = result.failures.attempt
        with result.phases(f"{mc.CHAPTER_TITLE} (comparisons, figures)"):
            res = mc.measure_part(
                all_runs, self.measure_f, self.out, attempt,
                paper_comps=[c for a in result.analyses.values() for c in a.comparisons])
        if mc.wants_sweeps(res, all_runs, self.opts):
            if self.sweep_f:
                with result.phases("waiting for the sweep curves"):
                    futures = list(self.sweep_f.values())
                    while cf.wait(futures, timeout=POLL_S).not_done:
                        pass  # (polled: see result_of)
            with result.phases(f"{mc.CHAPTER_TITLE} (sweep curves)"):
                mc.add_sweeps(res, all_runs, self.opts, self.out, attempt,
                              futures=self.sweep_f or None)
        self.measured = mc.finish(res)
        result.measured = {a.experiment: a for a in self.measured.analyses}


def build_report(names, out: Path, opts: RunOptions, title: str, chapter=()) -> Path:
    """Run and analyse the experiments ``names`` (names, TOML paths or Experiment objects) and
    write the report into ``out``.  Family members among them (and the experiments of
    ``chapter``, written as the chapter "Beyond the paper" after the paper's sections) are
    analysed by :mod:`analogue.study.members`.  Raises :class:`ReportIncomplete` after writing
    the page when some section failed."""
    return _report(names, Path(out), opts, title, chapter).page  # type: ignore[return-value]


def _report(names, out: Path, opts: RunOptions, title: str, chapter=()) -> StudyResult:
    """:func:`build_report`, returning the study (its ``page`` set); raises as it does."""
    given = [_load(n) for n in names]   # validated before anything runs or is written
    chapter = [_load(n) for n in chapter]
    out.mkdir(parents=True, exist_ok=True)
    drawer = _Drawer(out, opts, [e for e in given
                                 if not beyond_analysis.is_member_experiment(e)])
    result = run_study(given, members=chapter, opts=opts, hooks=drawer)
    write_report(result, drawer, out, title, opts)
    if result.failures.items:
        raise ReportIncomplete(result.page, result.failures.items, result)  # type: ignore[arg-type]
    return result


def write_report(result: StudyResult, drawer: _Drawer, out: Path, title: str,
                 opts: RunOptions) -> Path:
    """The page and metrics.json of a study whose figures ``drawer`` drew."""
    experiments, members = result.experiments, result.members
    _log("drawing figures")
    draw0 = time.perf_counter()
    sections = [_summary_section(result, drawer), _circuit_section(result)]
    if drawer.fig1_section is not None:
        sections.append(drawer.fig1_section)
    for exp in experiments:
        if exp.name in result.failed:
            sections.append(_failed_section(exp, result.failed[exp.name]))
            continue
        figs, errs = drawer.figs[exp.name]
        sections.append(Section(_experiment_title(exp), experiment_section_text(exp),
                                figures=figs, error="; ".join(errs) if errs else None))
    sections.extend(drawer.oq_section)
    sections.extend(drawer.measured.sections)
    if members:
        sections.extend(_chapter_sections(result, out, opts, drawer.member_sections))
    sections.append(Section("All comparisons and their error budgets", [
        prose.budget_text([*experiments, *members])],
        tables=[_comparison_table(result.comparisons, "Comparisons")]))

    result.phases.items.append({"phase": "figures and page", "experiment": None,
                                "thread": "main", "start_s": round(draw0 - result.t0, 3),
                                "seconds": round(time.perf_counter() - draw0, 3)})
    wall = time.perf_counter() - result.t0
    provenance = result.provenance(wall)
    sections.extend(_provenance_sections(provenance, wall))
    metrics = result.metrics(provenance)
    result.record = metrics
    # (ensure_ascii=False: a path under a non-UTF-8 locale is written as its own UTF-8 bytes,
    # not as escaped lone surrogates; files.write_text)
    write_text(out / "metrics.json", json.dumps(metrics, indent=2, default=str,
                                                ensure_ascii=False))
    index = write_page(out / "index.html", title, _intro(result, provenance, wall, out, opts),
                       sections)
    result.page = index
    _log(f"report written: {index}")
    return index


def _summary_section(result: StudyResult, drawer: _Drawer) -> Section:
    comps, fails = result.comparisons, result.failures
    counts = result.summary()
    summary_rows = []
    for a in result.all_analyses:
        s = a.summary()
        ex = [c for c in a.comparisons if c.theory_kind == "exact"]
        summary_rows.append([a.exp.name if hasattr(a, "exp") else a.runs.exp.name,
                             s["comparisons"], s["abs_z_below_3"], s["within_budget"],
                             sum(abs(c.z) < 3 for c in ex), len(ex)])
    summary_rows += measure_chapter.summary_rows(drawer.measured)
    failed_names = [f["experiment"] for f in fails.items if f["experiment"]]
    summary_text = [
        f"{len(comps)} comparisons of circuit estimates with theory: {counts['abs_z_below_3']} "
        f"have |z| < 3 and {counts['within_budget']} lie within their error budget (3 standard "
        "errors plus the independently estimated systematic errors). "
        + prose.theory_kinds_text(result.experiments, result.members)]
    if failed_names:
        summary_text.append("Failed (see their sections): " + ", ".join(failed_names) + ".")
    return Section("Summary", summary_text + _explain(comps) + terms_above_se_text(comps),
                   tables=[Table("Per experiment", ["experiment", "comparisons", "|z| < 3",
                                                    "within budget", "exact: |z| < 3",
                                                    "exact: total"], summary_rows)])


def _circuit_section(result: StudyResult) -> Section:
    circuit_par = [prose.circuit_paragraph([*result.experiments, *result.members])]
    tables = []
    circuits: list = [*result.runs.values(), *result.member_analyses.values()]
    for r in circuits:
        t, _ = result.failures.attempt("The circuit and its component values",
                                       "component table", lambda r=r: _mapping_table(r),
                                       r.exp.name)
        if t is not None:
            tables.append(t)
    return Section("The circuit and its component values", circuit_par, tables=tables)


def _member_section(result: StudyResult, exp, analysis, out: Path) -> Section:
    """One member's section of the chapter "Beyond the paper" (its figures drawn here)."""
    title_ = f"{CHAPTER_TITLE}: {exp.name}"
    return beyond.member_section(
        analysis, out, lambda what, fn, t=title_, n=exp.name: result.failures.attempt(t, what,
                                                                                      fn, n))


def _chapter_sections(result: StudyResult, out: Path, opts: RunOptions,
                      drawn: dict | None = None) -> list[Section]:
    """The chapter "Beyond the paper": its opening, then one section per member (their
    figures drawn as each completed, ``drawn``: member -> section, or here; their time added
    to the chapter's)."""
    drawn = drawn or {}
    t_fig = time.perf_counter()
    chapter_sections = []
    for exp in result.members:
        if exp.name in result.failed:
            chapter_sections.append(_failed_section(exp, result.failed[exp.name]))
            continue
        sec = drawn.get(exp.name)
        if sec is None:
            sec = _member_section(result, exp, result.member_analyses[exp.name], out)
        chapter_sections.append(sec)
        result.figures[exp.name] = [f.path for f in sec.figures]
    result.member_wall += time.perf_counter() - t_fig + sum(
        p["seconds"] for p in result.phases.items if p["phase"] == MEMBER_FIGURES)
    intro = beyond.chapter_intro(list(result.member_analyses.values()), result.member_wall,
                                 opts.quick)
    return [Section(CHAPTER_TITLE, intro), *chapter_sections]


def _provenance_sections(provenance: dict, wall: float) -> list[Section]:
    prov_rows = [[k, json.dumps(v, default=str)[:400]] for k, v in provenance.items()
                 if k not in ("deck_hashes", "phases", "critical_path")]
    crit = {"critical_path_s": provenance["critical_path_s"],
            "chain": provenance["critical_path"]}
    prov_rows.insert(next((i + 1 for i, r in enumerate(prov_rows) if r[0] == "critical_path_s"),
                          len(prov_rows)),
                     ["critical path (unlimited cores)", critical_path_text(crit, wall)])
    return [
        Section("Provenance", [
            "Everything needed to reproduce this report: model parameters, seeds, ngspice "
            "version, the sha256 of every deck (full list in metrics.json), software versions, "
            "wall time."],
            tables=[Table("run provenance", ["item", "value"], prov_rows)]),
        Section("References", [
            "Equations and figures are cited by their numbers in Baule, Touchette & Cohen "
            "(2011); docs/equations.md maps the paper's LaTeX labels to them."]
            # references_html() escapes every text itself and adds only the DOI/arXiv links
            + [Markup(p) for p in references_html()])]


def _intro(result: StudyResult, provenance: dict, wall: float, out: Path,
           opts: RunOptions) -> list:
    experiments, members = result.experiments, result.members
    timing = (f"{wall:.0f} s in all; {prose.main_part(experiments)} were complete after "
              f"{result.paper_wall:.0f} s, and the chapter '{CHAPTER_TITLE}' took "
              f"{result.member_wall:.0f} s of its own threads' time" if members and experiments
              else f"{wall:.0f} s")
    software = provenance["software"]
    intro = [f"Generated {provenance['created']} by analogue {software['analogue']} "
             f"with ngspice {provenance['ngspice_version']} ({'quick' if opts.quick else 'full'} "
             f"run, {timing}). Model units throughout: velocity, time and work rate of the "
             f"reduced equation {prose.equation_text([*experiments, *members])} (Baule, "
             "Touchette & Cohen).",
             "Every figure is also a PNG file in this directory; every number is in metrics.json."]
    if result.failures.items:
        intro.append(f"{len(result.failures.items)} section(s) failed; they are marked below "
                     "with their errors, and listed in metrics.json under 'failures'.")
    board = _board_link(out, experiments)
    if board is not None:
        intro.append(board)
    return intro


def _failed_section(exp: Experiment, err: str) -> Section:
    title = (f"{CHAPTER_TITLE}: {exp.name}" if beyond_analysis.is_member_experiment(exp)
             else f"Experiment '{exp.name}'")
    return Section(f"{title}: failed", experiment_section_text(exp), error=err)
