"""From experiments to a report directory: ``index.html`` (self-contained), PNGs, ``metrics.json``.

``build_paper_report`` is the main job (``analogue paper``): every standard experiment in
``circuits/``, the paper's Figs. 1-9 with circuit data, the paper's open question settled by
exact numerics, and every circuit-versus-theory comparison with its error budget.
"""
from __future__ import annotations

import json
import platform
import sys
import time
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from ..circuit.experiments import experiment_names, load_experiment
from . import figures as F
from .comparisons import ExperimentAnalysis, analyse
from .html import Figure, Section, Table, write_page
from .metrics import validate_metrics
from .plan import RunOptions, report_settings
from .runs import ExperimentRuns, run_experiment_runs

__all__ = ["RunOptions", "run_experiment", "build_experiment_report", "build_paper_report",
           "build_report", "RunSummary"]


_T0 = time.perf_counter()


def _log(msg: str) -> None:
    print(f"analogue [{time.perf_counter() - _T0:6.1f} s]: {msg}", file=sys.stderr, flush=True)


@dataclass
class RunSummary:
    runs: ExperimentRuns

    def summary(self) -> str:
        p = self.runs.provenance()
        reps = ", ".join(f"{k}: {v}" for k, v in p["replicas"].items())
        return (f"{p['experiment']}: runs stored ({reps}); ngspice {p['ngspice_version']}; "
                f"{p['wall_time_s']:.1f} s")


def run_experiment(name, opts: RunOptions) -> RunSummary:
    """Run (or load from the store) every circuit run of one experiment."""
    exp = load_experiment(name)
    _log(f"{exp.name}: running the circuit (stored runs are reused)")
    return RunSummary(run_experiment_runs(exp, opts))


def build_experiment_report(name, out, opts: RunOptions) -> Path:
    return build_report([name], Path(out), opts, title=f"analogue report: experiment {name}")


# the paper's order: stick (Figs. 2, 5, 6), slip (Figs. 3, 4), work (Figs. 7-9), then the rest
PAPER_ORDER = ("stick", "slip", "work")


def build_paper_report(out, opts: RunOptions) -> Path:
    names = experiment_names()
    # The model-family experiments (issue 9: cubic, stribeck, spring, shot) join the paper once
    # the report supports them ("Beyond the paper" chapter); until then the paper keeps the
    # paper's own models only.
    names = [n for n in names if load_experiment(n).model.is_paper]
    names = [n for n in PAPER_ORDER if n in names] + [n for n in names if n not in PAPER_ORDER]
    return build_report(names, Path(out), opts,
                        title="Stick-slip friction with noise: the paper on an analogue circuit")


# ------------------------------------------------------------------------------ sections
def _mapping_table(runs: ExperimentRuns) -> Table:
    from ..circuit.mapping import map_model
    m = map_model(runs.exp.model, runs.exp.spec)
    rows = [[name, float(value), unit, meaning] for name, value, unit, meaning in m.table()]
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
                     abs(b.finite_noise), c.within_budget,
                     c.as_dict()["budget"]["dominant"]])
        classes.append("ok" if c.within_budget else "fail")
    return Table(caption, ["experiment", "observable", "theory", "circuit", "SE", "theory value",
                           "z", "smoothing", "bandwidth", "integration", "finite noise",
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


def _software() -> dict:
    import matplotlib
    import scipy
    from .. import __version__
    return {"analogue": __version__, "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "matplotlib": matplotlib.__version__,
            "platform": platform.platform()}


def _figures_for(runs: ExperimentRuns, analysis: ExperimentAnalysis, out: Path) -> list:
    items = []
    tag = {"stick": "2", "slip": "3-4"}.get(runs.exp.name, "paths")
    for what, fn in (
            ("prehistory", lambda: F.fig_prehistory(runs, out, tag)),
            ("boundaries", lambda: F.fig_boundaries(runs, out)),
            ("propagator", lambda: F.fig_propagator(runs, out)),
            ("propagator", lambda: F.fig_propagator(runs, out, runs.exp.v0[-1])
             if len(runs.exp.v0) > 1 else None),
            ("stationary law", lambda: F.fig_stationary(runs, out)),
            ("work paths", lambda: F.fig_work_paths(runs, out)),
            ("rate function", lambda: F.fig_rate_function(runs, out)),
            ("error budget", lambda: F.fig_budget(analysis, out))):
        _log(f"{runs.exp.name}: figure: {what}")
        r = fn()
        if r is not None:
            items.append(Figure(*r))
    return items


def _open_question_section(out: Path, opts: RunOptions) -> Section:
    from ..plots.open_question import draw_open_question
    gammas = (10.0, 100.0) if opts.quick else (10.0, 100.0, 1000.0)
    paths = draw_open_question(out, gammas=gammas)
    text = [
        "The paper finds a jump of the rate function I(w) at w = 0 (eq. Iw) and cannot tell "
        "whether it is real. The exact rate function at finite noise, I_gamma(w) = "
        "sup_k [k w - lambda(k)] / gamma with lambda the principal eigenvalue of the tilted "
        "Fokker-Planck generator, answers it: I_gamma is convex and continuous for every gamma, "
        "and as gamma grows it converges to the lower convex envelope of the cost of holding a "
        "constant velocity w/(m a) - where holding v = 0 costs max(|a| - Delta, 0)^2/4, i.e. "
        "nothing when the object can stick. Near w = 0 the optimal histories share their time "
        "between sticking and sliding, which makes the limit linear there: the jump is an "
        "artefact of restricting the paths to one constant velocity, and the fluctuation "
        "relation of eq. dryft has no jump either. The tests check the convergence "
        "(tests/test_open_question.py)."]
    gs = ", ".join(f"{g:g}" for g in gammas)
    caps = [f"Exact I_gamma(w) for gamma = {gs} against the paper's I(w) (eq. Iw) and the "
            "gamma -> infinity limit (convex envelope).",
            "The fluctuation relation I(-w) - I(w): exact at three gammas, the paper's eq. ftexp "
            "with its jump 2 a Delta, and the limit."]
    return Section("The paper's open question: is the jump of I(w) at w = 0 real?", text,
                   figures=[Figure(p, caps[i] if i < len(caps) else "") for i, p in enumerate(paths)])


def build_report(names, out: Path, opts: RunOptions, title: str) -> Path:
    """Run and analyse the experiments ``names`` and write the report into ``out``."""
    t0 = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    all_runs, analyses = [], []
    for name in names:
        exp = load_experiment(name)
        _log(f"{exp.name}: circuit runs ({'quick' if opts.quick else 'full'} size; stored runs are reused)")
        runs = run_experiment_runs(exp, opts, report_settings(exp))
        _log(f"{exp.name}: comparing with theory")
        analyses.append(analyse(runs, progress=_log))
        all_runs.append(runs)

    _log("drawing figures")
    sections = []
    comps = [c for a in analyses for c in a.comparisons]
    n_ok = sum(c.within_budget for c in comps)
    n_z = sum(abs(c.z) < 3 for c in comps)
    summary_rows = []
    for a in analyses:
        s = a.summary()
        ex = [c for c in a.comparisons if c.theory_kind == "exact"]
        summary_rows.append([a.runs.exp.name, s["comparisons"], s["abs_z_below_3"], s["within_budget"],
                             sum(abs(c.z) < 3 for c in ex), len(ex)])
    sections.append(Section("Summary", [
        f"{len(comps)} comparisons of circuit estimates with theory: {n_z} have |z| &lt; 3 and "
        f"{n_ok} lie within their error budget (3 standard errors plus the independently "
        "estimated systematic errors). Theory 'exact' is the finite-noise Fokker-Planck solution "
        "of the ideal model (sgn friction, white noise); 'weak-noise' is the paper's saddle-point "
        "result, whose budget includes the finite-noise correction exact(gamma) - weak-noise."]
        + _explain(comps),
        tables=[Table("Per experiment", ["experiment", "comparisons", "|z| < 3", "within budget",
                                         "exact: |z| < 3", "exact: total"], summary_rows)]))

    circuit_par = [
        "Each replica is one node v (voltage = velocity, 1 V per unit velocity for the ideal "
        "bridge): capacitor C to ground (mass), resistor R (viscous friction alpha), a DC current "
        "I_F into the node (the force), four diodes around a DC current source I_Delta (Coulomb "
        "friction: the bridge passes I_Delta tanh(V/(2 N V_T))), a held Gaussian noise current "
        "(ngspice trrandom, reproducible with .options seed; the vibrating plate), and an "
        "integrator node x (a VCCS into a capacitor) so that ngspice itself integrates the "
        "position for the work W = F (x(t+tau) - x(t)). Time is scaled by theta seconds per "
        "model time unit. The decks are in netlists/ (regenerate with `analogue netlist`)."]
    sections.append(Section("The circuit and its component values", circuit_par,
                            tables=[_mapping_table(r) for r in all_runs]))

    figs = []
    fig1_runs = [r for r in all_runs if r.exp.name in ("stick", "slip")] or all_runs
    figs.append(Figure(*F.fig_deterministic(fig1_runs, out)))
    sections.append(Section("Paper Fig. 1: deterministic motion", figures=figs))
    for runs, a in zip(all_runs, analyses):
        sections.append(Section(f"Experiment '{runs.exp.name}': {runs.exp.model.regime} regime",
                                [runs.exp.description.replace("\n", " ")],
                                figures=_figures_for(runs, a, out)))

    if any(r.exp.name == "work" for r in all_runs) or len(names) > 1:
        _log("the paper's open question: exact rate functions at several gamma")
        sections.append(_open_question_section(out, opts))

    sections.append(Section("All comparisons and their error budgets", [
        "Rows in red are deviations the budget does not explain. Budget terms (absolute, in "
        "the observable's units): smoothing = exact(epsilon) - exact(0) (the diode bridge's "
        "tanh law); bandwidth = held-noise minus white-noise Monte Carlo driven by the same "
        "Wiener increments (|difference| + 2 SE); integration = the circuit re-run with 100x "
        "tighter tolerances on the same noise (|difference| + 2 SE); finite noise (weak-noise "
        "rows) = exact(gamma) - weak-noise."], tables=[_comparison_table(comps, "Comparisons")]))

    wall = time.perf_counter() - t0
    provs = {r.exp.name: r.provenance() for r in all_runs}
    provenance = {
        "parameters": {k: p["parameters"] for k, p in provs.items()},
        "model_effective": {k: p["model_effective"] for k, p in provs.items()},
        "circuit_spec": {k: p["circuit_spec"] for k, p in provs.items()},
        "seeds": {k: p["seeds"] for k, p in provs.items()},
        "replicas": {k: p["replicas"] for k, p in provs.items()},
        "ngspice_version": next(iter(provs.values()))["ngspice_version"],
        "deck_hashes": {k: p["deck_hashes"] for k, p in provs.items()},
        "wall_time_s": wall,
        "quick": opts.quick,
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "software": _software(),
    }
    prov_rows = [[k, json.dumps(v, default=str)[:400]] for k, v in provenance.items()
                 if k not in ("deck_hashes",)]
    sections.append(Section("Provenance", [
        "Everything needed to reproduce this report: model parameters, seeds, ngspice version, "
        "the sha256 of every deck (full list in metrics.json), software versions, wall time."],
        tables=[Table("run provenance", ["item", "value"], prov_rows)]))

    metrics = {"comparisons": [c.as_dict() for c in comps], "provenance": provenance,
               "summary": {"comparisons": len(comps), "abs_z_below_3": n_z, "within_budget": n_ok}}
    validate_metrics(json.loads(json.dumps(metrics, default=str)))
    tmp = out / "metrics.json.tmp"
    tmp.write_text(json.dumps(metrics, indent=2, default=str))
    tmp.replace(out / "metrics.json")

    intro = [f"Generated {provenance['created']} by analogue {provenance['software']['analogue']} "
             f"with ngspice {provenance['ngspice_version']} ({'quick' if opts.quick else 'full'} run, "
             f"{wall:.0f} s). Model units throughout: velocity, time and work rate of the "
             "reduced equation dv/dt = -v/tau_m - Delta sgn(v) + a + xi/m (Baule, Touchette & "
             "Cohen).",
             "Every figure is also a PNG file in this directory; every number is in metrics.json."]
    index = write_page(out / "index.html", title, intro, sections)
    _log(f"report written: {index}")
    return index
