"""The report's chapter "What experiments measure" (issue 23 item 5): for the paper's stick and
slip experiments, the velocity power spectra, the time to come to rest and transport under a
bias, each circuit-versus-theory comparison a row of ``metrics.json`` with its budget.

The numbers are :mod:`analogue.study.measure`'s (this module books them as
:class:`~analogue.study.metrics.Comparison` rows are the study's) and writes the text; the figures
are :mod:`analogue.plots.measure`'s.  The pipeline's hooks queue :func:`theory_tasks` with the study's
background tasks (the chapter's theory and Monte Carlo pairs run in the theory thread while
ngspice runs) and call :func:`chapter` once the paper's chapters are complete; the chapter
reads the runs the experiments' sections made and runs no deck of its own.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from markupsafe import Markup, escape

from ..plots.measure import draw_first_passage, draw_spectra
from ..plots.sweep import diffusion_figure, mobility_figure
from ..study import measure
from ..theory.bias_transport import diffusion_exponent
from .html import Figure, Section, Table
from ..study.metrics import Budget, Comparison, compare
from ..study.schedule import result_of
from ..study.sweep import BUDGET_TERMS, sweep
from .prose import is_paper_experiment

__all__ = ["CHAPTER_TITLE", "MEASURE_EXPERIMENTS", "THEORY_PHASE", "SWEEP_PHASE", "wants",
           "theory_tasks", "sweep_experiment", "sweep_tasks", "chapter", "measure_part",
           "wants_sweeps", "add_sweeps", "finish", "ChapterResult", "summary_rows"]

CHAPTER_TITLE = "What experiments measure"
#: The paper's experiments the chapter measures (the work experiment repeats the stick
#: regime at other parameters).
MEASURE_EXPERIMENTS = ("stick", "slip")


def wants(exp) -> bool:
    """Whether the chapter measures this experiment: the paper's own stick and slip
    experiments (standard circuits), not a user's file of the same name."""
    return (exp.name in MEASURE_EXPERIMENTS and is_paper_experiment(exp)
            and measure.applies(exp.model))


def theory_tasks(experiments, opts, progress=None) -> dict:
    """``{phase: function}``: each wanted experiment's :func:`~analogue.study.measure.
    measure_theory` (no circuit data), for the study's background tasks (the theory thread,
    while ngspice runs)."""
    out = {}
    for exp in experiments:
        if wants(exp):
            settings = exp.report.for_options(opts)
            out[f"{THEORY_PHASE}: {exp.name}"] = (
                lambda exp=exp, s=settings: measure.measure_theory(exp, s, progress=progress))
    return out


THEORY_PHASE = f"{CHAPTER_TITLE} (exact theory, Monte Carlo pairs)"


@dataclass
class ChapterResult:
    analyses: list = field(default_factory=list)      # MeasureAnalysis
    comparisons: list = field(default_factory=list)   # Comparison
    sections: list = field(default_factory=list)      # Section
    # figures, paragraphs and error of the section until it is written (finish)
    draft: dict | None = None


def _table(comps: list[Comparison]) -> Table:
    rows, classes = [], []
    for c in comps:
        b = c.budget
        rows.append([c.experiment, c.observable, c.circuit, c.circuit_stderr, c.theory, c.z,
                     abs(b.sampling), abs(b.bandwidth), abs(b.smoothing), abs(b.integration),
                     c.within_budget, c.as_dict()["budget"]["dominant"]])
        classes.append("ok" if c.within_budget else "fail")
    return Table(f"{CHAPTER_TITLE}: comparisons", ["experiment", "observable", "circuit", "SE",
                                                   "exact", "z", "sampling", "bandwidth (hold)",
                                                   "smoothing", "integration", "within budget",
                                                   "dominant error"], rows, classes)


def _intro(comps: list[Comparison], sweep_note: str) -> list:
    n_ok = sum(c.within_budget for c in comps)
    zmax = max((abs(c.z) for c in comps if math.isfinite(c.z)), default=math.nan)
    worst = max(comps, key=lambda c: abs(c.z) if math.isfinite(c.z) else -1.0, default=None)
    text = [
        Markup(
            "The paper computes transition densities, stationary laws and work fluctuations. "
            "Experiments on dry friction with noise measure other things: the velocity's power "
            "spectrum (Gnoli, Puglisi &amp; Touchette, EPL 102, 14002 (2013), on a granular "
            "probe, against the exact spectra of Touchette, Prellberg &amp; Just, J. Phys. A "
            "45, 395002 (2012)), the time an object takes to come to rest (Chen &amp; Just, "
            "Phys. Rev. E 89, 022103 (2014)), and the drift and diffusion of an object pushed "
            "by a bias through a noisy contact (Goohpattader, Mettu &amp; Chaudhury, Langmuir "
            "25, 9969 (2009): diffusivity against noise power with exponent 1.61 measured and "
            "1.74 from a Coulomb-friction Langevin analysis; Goohpattader &amp; Chaudhury, "
            "J. Chem. Phys. 133, 024702 (2010)). This chapter measures them on the circuit runs "
            "of the experiments' sections above (no deck of its own) and holds them against "
            "the exact theory, each with its error budget."),
        f"{len(comps)} comparisons: {n_ok} lie within their budget (3 standard errors plus "
        f"the systematic terms); the largest |z| is {zmax:.2f}"
        + (f" ({worst.experiment} / {worst.observable})." if worst is not None else "."),
    ]
    if sweep_note:
        text.append(sweep_note)
    return text


def _spectrum_text(a: measure.MeasureAnalysis, comps: list[Comparison]) -> str:
    sp, m = a.theory.spectrum, a.theory.model
    w1, w2 = sp.crossovers
    rows = [c for c in comps if c.observable.startswith("S(omega)")]
    ok = sum(c.within_budget for c in rows)
    hold = max((abs(r.bandwidth[0]) / r.theory for r in a.rows if r.group == "spectrum"),
               default=0.0)
    samp = max((abs(r.sampling) / r.theory for r in a.rows if r.group == "spectrum"),
               default=0.0)
    corner = (f"the sticking rate {w2:.3g} (the inverse correlation time Var v / D_x of pure "
              f"dry friction at this a and gamma)" if math.isfinite(w2)
              else "no sticking corner (slip regime: the velocity seldom visits 0)")
    est = a.spectrum
    return (f"{a.experiment} ({m.regime} regime): the Welch estimate of {est.n_replicas} "
            f"stationary runs ({est.n_segments} Hann segments of {est.nperseg} samples each, "
            f"{est.dof:.0f} degrees of freedom per frequency) against the exact S(omega), "
            f"whose plateau S(0) = 2 D_x = {sp.exact[0]:.4g} bends over at 1/tau_m = {w1:.3g} "
            f"and {corner}. Averaged over {len(rows)} frequency bands, {ok} of {len(rows)} lie "
            f"within budget. The noise hold (T = {sp.hold_dt:.3g}) moves the spectrum by at "
            f"most {100 * hold:.2g} % of S in any band, measured by a held/white Monte Carlo "
            f"pair (in the stick regime the hold also lowers the variance itself, beyond the "
            f"sinc^2 factor of a linear response, so no closed form is used); sampling every "
            f"{sp.sample_dt:g} (aliasing) and the window's leakage move the estimator's "
            f"expectation by at most {100 * samp:.2g} % of S, computed exactly from the "
            f"autocorrelation.")


def _fp_text(a: measure.MeasureAnalysis, comps: list[Comparison]) -> str:
    parts = []
    by = {c.observable: c for c in comps}
    for v0, th in a.theory.first_passage.items():
        est = a.first_passage[v0]
        bits = [f"from v0 = {v0:g}"]
        if math.isfinite(th.t_a):
            bits.append(f"the noise-free path stops at t_a = {th.t_a:.3g}")
        else:
            bits.append("the noise-free path never stops")
        if th.values.mean_label is not None:
            c = by[th.values.mean_label]
            bits.append(f"the exact mean time to rest is {th.mean:.3g} (circuit {c.circuit:.3g} "
                        f"+- {c.circuit_stderr:.2g}, z = {c.z:.2f}; sampling the path every "
                        f"{a.theory.spectrum.sample_dt:g} delays the observed crossing by up to "
                        f"{th.sampling_bound:.2g})")
        else:
            bits.append(f"{100 * th.survival_end:.0f} % of the paths are still moving at the "
                        f"record's end ({th.record:g}; circuit: {est.n_censored} of "
                        f"{est.times.size})")
        c = by[th.values.prob_label]
        bits.append(f"P(T <= {th.values.t_prob:.3g}) = {c.theory:.3f} exact, {c.circuit:.3f} "
                    f"+- {c.circuit_stderr:.3f} circuit")
        parts.append(", ".join(bits))
    ratios = [th.mean / th.t_a for th in a.theory.first_passage.values()
              if th.values.mean_label is not None and math.isfinite(th.t_a)]
    stays = [th for th in a.theory.first_passage.values() if not math.isfinite(th.t_a)]
    why = []
    if ratios:
        why.append("with noise the mean time to rest is "
                   + " and ".join(f"{r:.2f}" for r in ratios)
                   + " of the noise-free stick time")
    if stays:
        why.append("where the noise-free path slides on to v_ss, only the noise brings the "
                   "object to rest")
    parts.append("; ".join(why))
    return f"{a.experiment}: " + "; ".join(p for p in parts if p) + "."


def _transport_text(a: measure.MeasureAnalysis, paper_comps: list[Comparison]) -> str:
    sp, m = a.theory.spectrum, a.theory.model
    by = {c.observable: c for c in paper_comps if c.experiment == a.experiment
          and c.theory_kind == "exact"}
    expo = diffusion_exponent(m)
    out = (f"{a.experiment}: exact mobility mu = d<v>/da = gamma Var v = {sp.mobility:.4g} "
           f"and Einstein-like ratio D_x / mu = {sp.einstein:.4g} (= Var v for viscous friction "
           f"alone; {sp.einstein / (sp.mobility / m.gamma):.3g} x Var v here); the exact local "
           f"exponent d ln D_x / d ln D of the diffusion against the noise intensity D = "
           f"1/gamma is {expo:.3g} at these parameters (1 for viscous friction, 3 for pure dry "
           f"friction; Goohpattader et al. measured 1.61).")
    rows = [by[k] for k in ("mean v", "diffusion D_x") if k in by]
    if rows:
        out += " The circuit's drift and D_x are rows of the experiment's section: " + "; ".join(
            f"{c.observable} {c.circuit:.4g} +- {c.circuit_stderr:.2g} against {c.theory:.4g} "
            f"(z = {c.z:.2f})" for c in rows) + "."
    return out


#: The chapter's two sweep curves (issue 23 item 2), on the paper's stick experiment at quick
#: size (:func:`analogue.study.sweep.sweep`): ``name -> (vary, observable, figure)``.  Four
#: points each: the drift across the stick-slip threshold a = Delta = 0.7, and D_x over a
#: factor 8 of noise strength.
SWEEPS: dict[str, tuple[dict, str, Callable]] = {
    "mobility": ({"a": (0.0, 1.2, 4)}, "mean_v", mobility_figure),
    "diffusion": ({"gamma": (5.0, 40.0, 4, "log")}, "D_x", diffusion_figure),
}
SWEEP_EXPERIMENT = "stick"
_SWEEP_LABEL = {"mean_v": "drift <v>", "D_x": "diffusion D_x"}


def sweep_comparisons(ds, obs: str, experiment: str) -> list[Comparison]:
    """One comparison per point of a one-dimensional sweep dataset (:func:`analogue.study.
    sweep.sweep`): its circuit value, stderr, exact value and budget terms, as in the
    dataset (the same criterion as every row: :func:`analogue.study.metrics.compare`)."""
    (axis,) = [d for d in ds[obs].dims]
    out = []
    for i, x in enumerate(ds[axis].values):
        terms = {t: float(v) for t, v in zip(BUDGET_TERMS, ds[f"{obs}_budget_terms"].values[i])}
        value, se = float(ds[obs].values[i]), float(ds[f"{obs}_stderr"].values[i])
        theory = float(ds[f"{obs}_theory"].values[i])
        if not (math.isfinite(value) and math.isfinite(se) and math.isfinite(theory)):
            continue
        out.append(compare(experiment, f"sweep: {_SWEEP_LABEL[obs]} at {axis}={x:.4g}", value,
                           se, theory, "exact", Budget(**terms),
                           "analogue.study.sweep at quick size: its own stationary run at this "
                           "point (budget as the dataset's: smoothing, held/white bandwidth, "
                           "the tolerance chooser's integration estimate)"))
    return out


#: The phase of a sweep's own thread in the report (``f"{SWEEP_PHASE}: {name}"``): it waits
#: for its points' threads (each point its own phase, "sweep point"), then puts their
#: results and the theory curves into the dataset.
SWEEP_PHASE = "waiting for sweep points"


def sweep_experiment(experiments, opts):
    """The experiment the sweep curves are drawn for (the paper's stick experiment, when
    the chapter measures it and ``opts.sweeps`` asks for them), or None."""
    if opts is None or not getattr(opts, "sweeps", False):
        return None
    return next((e for e in experiments if e.name == SWEEP_EXPERIMENT and wants(e)), None)


def sweep_tasks(exp, opts, *, phases=None) -> dict[str, Callable]:
    """``{phase: function}``: the chapter's sweeps of ``exp`` (:data:`SWEEPS`), for the
    study's circuit work (:meth:`analogue.study.run.StudyHooks.circuit_background`: they start
    with the circuit work, not after the paper's chapters).  Each runs its points at once
    (:func:`analogue.study.sweep.sweep`), every deck where ``opts`` says (the study's one deck
    pool, ``opts.executor``: never more ngspice processes than ``workers`` in all), each
    point recorded in ``phases``."""
    runner = opts.runner(progress=False)
    return {f"{SWEEP_PHASE}: {name}": (
        lambda vary=vary: sweep(exp, vary, quick=True, runner=runner, phases=phases))
        for name, (vary, _obs, _figure) in SWEEPS.items()}


def run_sweeps(exp, opts, out: Path, attempt, futures: dict | None = None
               ) -> tuple[list, list, list[str]]:
    """The two sweep curves of the chapter for ``exp`` (the paper's stick experiment):
    ``(comparisons, figures, errors)``; each sweep's circuit runs go through the run store
    like every other, with the report's runner (``opts.runner()``: store, workers, scheduler,
    timeout), silent.  ``futures`` (``{name: Future}`` of :func:`sweep_tasks`, started
    earlier): their datasets instead of running the sweeps here."""
    comps, figs, errors = [], [], []
    runner = opts.runner(progress=False)
    for name, (vary, obs, figure) in SWEEPS.items():
        fut = (futures or {}).get(name)
        if fut is not None:
            ds, err = attempt(CHAPTER_TITLE, f"sweep: {name}",
                              lambda fut=fut: result_of(fut), exp.name)
        else:
            ds, err = attempt(CHAPTER_TITLE, f"sweep: {name}", lambda vary=vary: sweep(
                exp, vary, quick=True, runner=runner), exp.name)
        if ds is None:
            errors.append(f"sweep {name}: {err}")
            continue
        comps += sweep_comparisons(ds, obs, exp.name)
        paths, err = attempt(CHAPTER_TITLE, f"figure: {name}",
                             lambda ds=ds, figure=figure: figure(ds, out), exp.name)
        if paths is None:
            errors.append(f"figure {name}: {err}")
            continue
        png = next(p for p in paths if str(p).endswith(".png"))
        n_ok = sum(c.within_budget for c in comps if c.observable.startswith(
            f"sweep: {_SWEEP_LABEL[obs]}"))
        axis = next(iter(vary))
        caption = (f"{exp.name}: {_SWEEP_LABEL[obs]} against {axis} at {ds.sizes[axis]} points "
                   f"(circuit, quick size; {n_ok} within budget) and the exact theory"
                   + (", with the local exponent d ln D_x / d ln D below (Goohpattader, Mettu "
                      "& Chaudhury measured 1.61)" if obs == "D_x" else
                      "; the stick-slip threshold is a = Delta"))
        figs.append(Figure(png, caption))
    return comps, figs, errors


SWEEP_NOTE = ("The issue's curves over a parameter (the mobility: drift against the force a; "
              "D_x against the noise strength on log-log axes with its local exponent) are the "
              "sweep's (analogue.study.sweep): each point is its own circuit run, so they are "
              "drawn here only when asked for (analogue report/paper --sweeps: 8 points of "
              "the stick experiment at quick size, run at once: 70 s more wall and 129 CPU-s more "
              "for the quick paper on an idle 2-core machine); "
              "at the experiments' own parameters the exact values are below.")


def chapter(all_runs, futures: dict, out: Path, attempt, *, paper_comps=(),
            opts=None, sweeps: dict | None = None) -> ChapterResult:
    """The chapter from the report's runs (``all_runs``: ExperimentRuns) and the futures of
    :func:`theory_tasks` (``{experiment: Future}``).  ``attempt(section, stage, fn, experiment)`` runs a
    piece and records its failure (the pipeline's ``_Failures.attempt``).  ``paper_comps``:
    the experiments' own comparisons (the drift and D_x rows the text quotes).  ``opts``
    (RunOptions): where the sweep curves' runs go, when ``opts.sweeps``; ``sweeps``: their
    futures when they were started earlier (:func:`sweep_tasks`).  The pipeline calls its
    three parts itself (:func:`measure_part`, :func:`add_sweeps`, :func:`finish`), to wait
    for the sweeps between them."""
    res = measure_part(all_runs, futures, out, attempt, paper_comps=paper_comps)
    if wants_sweeps(res, all_runs, opts):
        add_sweeps(res, all_runs, opts, out, attempt, futures=sweeps)
    return finish(res)


def measure_part(all_runs, futures: dict, out: Path, attempt, *,
                 paper_comps=()) -> ChapterResult:
    """The chapter without its sweep curves: analyses, comparisons, figures and text, kept
    in ``res.draft`` until :func:`finish` writes the section."""
    res = ChapterResult()
    if not futures:
        return res
    for runs in all_runs:
        f = futures.get(runs.exp.name)
        if f is None:
            continue
        title = f"{CHAPTER_TITLE}: {runs.exp.name}"
        a, err = attempt(title, "analysis", lambda f=f, runs=runs: measure.analyse_measure(
            runs, f.result()), runs.exp.name)
        if a is None:
            res.sections.append(Section(title, error=err))
            continue
        res.analyses.append(a)
        res.comparisons.extend(a.comparisons)
    if not res.analyses:
        return res
    comps = res.comparisons
    figs = []
    fig, err = attempt(CHAPTER_TITLE, "figure: spectra",
                       lambda: Figure(*draw_spectra(res.analyses, out)), None)
    if fig is not None:
        figs.append(fig)
    paragraphs = [Markup("<b>Power spectra.</b> ") + escape(" ".join(
        _spectrum_text(a, [c for c in comps if c.experiment == a.experiment])
        for a in res.analyses))]
    fp_figs = []
    for a in res.analyses:
        fig, err2 = attempt(CHAPTER_TITLE, "figure: first passage",
                            lambda a=a: Figure(*draw_first_passage(a, out)), a.experiment)
        if fig is not None:
            fp_figs.append(fig)
        err = err or err2
    paragraphs.append(Markup("<b>Time to come to rest.</b> ") + escape(" ".join(
        _fp_text(a, [c for c in comps if c.experiment == a.experiment]) for a in res.analyses)))
    paragraphs.append(Markup("<b>Drift and diffusion under a bias.</b> ") + escape(" ".join(
        _transport_text(a, list(paper_comps)) for a in res.analyses)))
    res.draft = {"figures": figs + fp_figs, "paragraphs": paragraphs, "error": err,
                 "sweep_figures": []}
    return res


def _sweep_pair(res: ChapterResult, all_runs):
    a0 = next((a for a in res.analyses if a.experiment == SWEEP_EXPERIMENT), None)
    runs0 = next((r for r in all_runs if a0 is not None and r.exp.name == a0.experiment), None)
    return a0, runs0


def wants_sweeps(res: ChapterResult, all_runs, opts) -> bool:
    """Whether the chapter draws the sweep curves: asked for (``opts.sweeps``) and the
    stick experiment measured."""
    a0, runs0 = _sweep_pair(res, all_runs)
    return (res.draft is not None and opts is not None and getattr(opts, "sweeps", False)
            and a0 is not None and runs0 is not None)


def add_sweeps(res: ChapterResult, all_runs, opts, out: Path, attempt,
               futures: dict | None = None) -> None:
    """The sweep curves' comparisons, figures and text into the chapter (``futures``: the
    sweeps started earlier, :func:`sweep_tasks`; else they run here)."""
    a0, runs0 = _sweep_pair(res, all_runs)
    assert a0 is not None and runs0 is not None and res.draft is not None
    sweep_comps, sweep_figs, errs = run_sweeps(runs0.exp, opts, out, attempt, futures)
    a0.extra = sweep_comps   # the experiment's chapter rows (and so metrics.json's)
    res.comparisons.extend(sweep_comps)
    d = res.draft
    d["error"] = "; ".join(x for x in [d["error"], *errs] if x) or None
    d["paragraphs"].append(Markup("<b>Curves over a parameter.</b> ") + escape(
        _sweep_text(sweep_comps)))
    d["sweep_figures"] = sweep_figs


def finish(res: ChapterResult) -> ChapterResult:
    """The chapter's section from its draft (:func:`measure_part`, :func:`add_sweeps`)."""
    d = res.draft
    if d is None:
        return res
    comps = res.comparisons
    res.sections.insert(0, Section(CHAPTER_TITLE, _intro(comps, "" if d["sweep_figures"]
                                                         else SWEEP_NOTE)
                                   + d["paragraphs"],
                                   figures=d["figures"] + d["sweep_figures"],
                                   tables=[_table(comps)], error=d["error"]))
    res.draft = None
    return res


def _sweep_text(comps: list[Comparison]) -> str:
    if not comps:
        return "The sweeps failed (see the error below)."
    ok = sum(c.within_budget for c in comps)
    zmax = max(abs(c.z) for c in comps)
    return (f"The mobility curve (drift against the force a, across the stick-slip threshold) "
            f"and D_x against the noise strength 1/gamma (log-log, with its local exponent) of "
            f"the stick experiment, each point its own circuit run at quick size "
            f"(analogue.study.sweep): {ok} of {len(comps)} points within budget, largest "
            f"|z| {zmax:.2f}.")


def summary_rows(res: ChapterResult) -> list:
    """The report summary's per-experiment rows of the chapter (experiment, comparisons,
    |z| < 3, within budget, exact: |z| < 3, exact: total); every row is an exact one."""
    out = []
    for a in res.analyses:
        comps = [c for c in res.comparisons if c.experiment == a.experiment]
        n3 = sum(abs(c.z) < 3 for c in comps)
        out.append([f"{a.experiment}: {CHAPTER_TITLE.lower()}", len(comps), n3,
                    sum(c.within_budget for c in comps), n3, len(comps)])
    return out
