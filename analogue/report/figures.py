"""The paper's figures with circuit data on them (and the figures only a circuit can add).

Each function takes the analysis of one experiment (:class:`~analogue.study.comparisons.
ExperimentAnalysis`), draws the theory curves computed once with it
(:mod:`analogue.study.theory_curves`: no theory is computed here), overlays circuit estimates
with their error bands, and writes one PNG; it returns ``(path, caption)``.  The paper's
I(w) is drawn with one convention at w = 0 everywhere: the Filippov value
``max(|a| - Delta, 0)^2/4`` (:func:`analogue.theory.weak_noise.rate_function`).
"""
from __future__ import annotations

import itertools
import logging
import math
from pathlib import Path

import numpy as np

from ..estimators import (empirical_rate_function, fluctuation_ratio, prehistory,
                          prehistory_count, transition_density)
from ..model import Model
from ..plots.paper_theory import FIG5_EXAMPLE_TAUS
from ..plots.style import KIND_COLOURS, TIME, VELOCITY, new_figure, save
from ..study.comparisons import ExperimentAnalysis
from ..study.runs import ExperimentRuns
from ..study.theory_curves import ExperimentTheory, FigureCurves, propagator_times
from ..plots.paper_theory import fig5_boundaries, fig5_layout
from ..study.catalogue import find

__all__ = ["fig_deterministic", "fig_prehistory", "fig_propagator", "fig_stationary",
           "fig_work_paths", "fig_rate_function", "fig_budget",
           "fig_boundaries"]

# the report's progress logger's family: the command line shows it on stderr (analogue.cli)
_log = logging.getLogger("analogue.report.figures")

CIRCUIT = "tab:red"
EXACT = "k"
WEAK = "tab:blue"


def _title(runs: ExperimentRuns) -> str:
    m = runs.exp.model
    return (f"{runs.exp.name}: $\\tau_m$={m.tau_m:g}, $\\Delta$={m.delta:g}, a={m.a:g}, "
            f"$\\gamma$={m.gamma:g}")


# ------------------------------------------------------------------------------ Fig. 1
def fig_deterministic(all_runs: list, out: Path):
    """Paper Fig. 1: noise-free motion, the circuit with its noise off vs eq. (13)."""
    fig, axes = new_figure(1, len(all_runs), squeeze=False)
    for ax, runs in zip(axes.ravel(), all_runs):
        ens = runs.noise_free
        m = runs.exp.model
        t = np.linspace(0, ens.t[-1], 600)
        for i, v0 in enumerate(runs.exp.v0):
            ax.plot(t, m.deterministic(v0, t), color=EXACT, lw=1.5,
                    label="eq. (13) (sgn law)" if i == 0 else None)
            ax.plot(ens.t[::8], ens.v[i, ::8], "o", ms=3, color=CIRCUIT, mfc="none",
                    label="circuit, noise off" if i == 0 else None)
            ts = m.stick_time(v0)
            if math.isfinite(ts) and m.regime == "stick":
                ax.axvline(ts, color="0.6", ls=":", lw=1)
        if m.attractor:
            ax.axhline(m.attractor, color="0.4", ls="--", lw=0.8, label="$v_{ss}$ (eq. (14))")
        ax.axhline(0, color="0.7", lw=0.7)
        ax.set_title(f"Fig. 1 ({runs.exp.name}): $\\Delta$={m.delta:g}, a={m.a:g}", fontsize=10)
        ax.set_xlabel(TIME)
        ax.set_ylabel(VELOCITY)
        ax.legend(fontsize=8)
    path = save(fig, out / "fig1_deterministic.png")
    dev = max(float(np.max(np.abs(r.noise_free.v - np.array(
        [Model(**r.noise_free.meta["model_effective"]).deterministic(v0, r.noise_free.t)
         for v0 in r.exp.v0])))) for r in all_runs)
    return path, ("Noise-free motion (paper Fig. 1). Lines: eq. (13) with the exact sgn law "
                  "(dotted: stick time t_a, eq. (31)). Circles: the same circuit (its own "
                  f"components and parts) with the noise source off. Largest deviation from the circuit's own smoothed "
                  f"law: {dev:.1e} (model units).")


def _curves(analysis: ExperimentAnalysis) -> FigureCurves:
    """The figures' theory curves (computed by :func:`analogue.study.comparisons.analyse`)."""
    if analysis.curves is None:
        raise ValueError(f"{analysis.runs.exp.name}: no theory curves (analyse() was not run)")
    return analysis.curves


def _theory(analysis: ExperimentAnalysis) -> ExperimentTheory:
    if analysis.theory is None:
        raise ValueError(f"{analysis.runs.exp.name}: no theory (analyse() was not run)")
    return analysis.theory


# ------------------------------------------------------------------------- Figs. 2-5
def fig_prehistory(analysis: ExperimentAnalysis, out: Path, tag: str):
    """Optimal paths (eqs. (16) ... (36)) against the circuit's prehistory: the paths of
    the transition run from v0 that end in a window around (v, t).  Every target is named in
    the caption and the log with the number of circuit paths found, 0 included (an empty
    panel used to be left out of the caption without a word, issue 20 item 2)."""
    runs = analysis.runs
    paths = _curves(analysis).get("prehistory")
    if not paths:
        return None
    window = runs.settings.prehistory_window
    n = len(paths)
    ncols = 2 if n == 4 else min(n, 3)
    nrows = -(-n // ncols)
    fig, axes = new_figure(nrows, ncols, squeeze=False)
    lines, empty = [], []
    for ax, ((v0, v, t), p) in zip(axes.ravel(), paths):
        ens = runs.transition[v0]
        colour = KIND_COLOURS.get(p.kind, "k")
        count = prehistory_count(ens, v, t, window)
        what = (f"v0={v0:g} to (v={v:g}, t={t:g}): {p.kind}, {count} of {ens.replicas} "
                "circuit paths")
        lines.append(what)
        _log.info("%s: prehistory %s", runs.exp.name, what)
        if count:
            ph = prehistory(ens, v, t, window, v_bins=60, lookback=t)
            ext = [ph.hist_t_edges[0], ph.hist_t_edges[-1], ph.hist_v_edges[0], ph.hist_v_edges[-1]]
            ax.imshow(np.nan_to_num(ph.hist).T, origin="lower", aspect="auto", extent=ext,
                      cmap="Greys", alpha=0.6)
            # grey, so that the optimal path keeps its kind's colour (one of which is red)
            ax.fill_between(ph.t, ph.lower, ph.upper, color="0.55", alpha=0.25,
                            label="circuit 10-90 %")
            ax.plot(ph.t, ph.mean, color="0.15", lw=1.3, label=f"circuit mean ({ph.count} paths)")
        else:
            empty.append(f"v={v:g}, t={t:g}")
            ax.annotate(f"no circuit path ends within ±{window:g}\nof v={v:g} at t={t:g} "
                        f"(of {ens.replicas})", (0.5, 0.9), xycoords="axes fraction",
                        ha="center", va="top", fontsize=8, color="0.3")
        ax.plot(p.s, p.v, color=colour, lw=2.2, label=f"optimal path: {p.kind}")
        ax.plot([t], [v], "s", color=colour, ms=5)
        ax.axhline(0, color="0.6", lw=0.7)
        ax.set_title(f"to v={v:g} at t={t:g} from $v_0$={v0:g}", fontsize=9)
        ax.set_xlabel(TIME)
        ax.set_ylabel(VELOCITY)
        ax.legend(fontsize=7)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    fig.suptitle(f"Optimal paths and circuit prehistory — {_title(runs)}", fontsize=10)
    path = save(fig, out / f"fig_{tag}_prehistory_{runs.exp.name}.png")
    caption = ("Optimal paths (paper Figs. 2-4: direct, crossing, indirect and twice-crossing "
               "kinds from eqs. (22)-(36)) against the prehistory of the circuit (Dykman et al. "
               "1992): all circuit paths from v0 that end within "
               f"±{window:g} of the target; dark grey: their mean, "
               "light grey: 10-90 % band. At this finite noise the prehistory is broad; "
               "the optimal path is its gamma -> infinity limit. " + "; ".join(lines) + ".")
    if empty:
        caption += (f" No circuit path reached {' or '.join(empty)}: the target lies where "
                    "f(v, t | v0) is too small for this run's replicas; widen "
                    "report.prehistory_window, run more experiment.replicas, or choose a "
                    "target nearer the bulk of the transition density (Fig. 6).")
    return path, caption


def fig_boundaries(runs: ExperimentRuns, out: Path):
    """Paper Fig. 5: boundary lines w, u (eqs. (41), (45)) and one optimal path of each kind
    around them (theory only).  Every time and range comes from the experiment's model and
    v0 (:func:`analogue.plots.paper_theory.fig5_layout`); the stick regime only."""
    m = runs.exp.model
    if m.regime != "stick":
        return None
    fig, axes = new_figure(1, 2, squeeze=False)
    v0s = tuple(v for v in runs.exp.v0[:2])
    if len(v0s) < 2:
        v0s = (v0s[0], -v0s[0])
    fig5_boundaries(axes.ravel(), tau_m=m.tau_m, delta=m.delta, a=m.a, v0s=v0s)
    fig.suptitle(f"Fig. 5: boundaries between path kinds — {_title(runs)}", fontsize=10)
    path = save(fig, out / f"fig5_boundaries_{runs.exp.name}.png")
    lays = [fig5_layout(m, v0) for v0 in v0s]
    when = "; ".join(f"v0 = {v0:g}: t_a = {lay['t_a']:.3g}, example paths end at t = "
                     f"{lay['t_example']:.3g}" for v0, lay in zip(v0s, lays))
    return path, ("Boundary lines between direct and indirect optimal paths (paper Fig. 5, "
                  "eqs. (41) and (45), upper sign for v0 > 0), from the stick time t_a on; "
                  f"example paths {FIG5_EXAMPLE_TAUS:g} tau_m after t_a ({when}). Each boundary "
                  "is checked in the tests by the continuity of the minimal action across it.")


# ------------------------------------------------------------------------------ Fig. 6
def fig_propagator(analysis: ExperimentAnalysis, out: Path, v0: float | None = None):
    """Paper Fig. 6: f(v, t | v0) at four times: weak-noise, exact, circuit histogram.  The
    exact and weak-noise densities are those the comparisons used (one computation)."""
    runs = analysis.runs
    m = runs.exp.model
    v0 = runs.exp.v0[0] if v0 is None else v0
    ens = runs.transition[v0]
    th = _theory(analysis).transition[v0]
    times = propagator_times(th.times)
    if not times:   # no experiment.histogram_times: nothing to draw
        return None
    rows = [th.times.index(t) for t in times]
    v = th.v
    f_exact = th.f_exact[rows]
    fig, axes = new_figure(2, len(times), squeeze=False, width=4.0, height=3.2)
    for j, t in enumerate(times):
        sample = ens.at(t)
        pad = 0.5 * m.velocity_scale
        lo, hi = float(sample.min()) - pad, float(sample.max()) + pad
        d = transition_density(ens, t, bins=30, range=(lo, hi))
        occupied = d.counts > 0
        f_weak = th.f_weak[rows[j]] if th.f_weak is not None else None
        for row, log in enumerate((False, True)):
            ax = axes[row, j]
            band_lo = np.where(occupied | (row == 0), d.lower, np.nan)
            band_hi = np.where(occupied | (row == 0), d.upper, np.nan)
            ax.fill_between(d.centres, band_lo, band_hi, step="mid", color=CIRCUIT, alpha=0.25)
            ax.step(d.centres, np.where(occupied | (row == 0), d.density, np.nan), where="mid",
                    color=CIRCUIT, lw=1.2, label=f"circuit ({ens.replicas} paths, 95 % band)")
            ax.plot(v, f_exact[j], color=EXACT, lw=1.4, label="exact (Fokker-Planck)")
            if f_weak is not None:
                ax.plot(v, f_weak, color=WEAK, lw=1.2, ls="--", label="weak noise (eqs. (46)-(51))")
            ax.set_xlim(lo - pad, hi + pad)
            if row == 0:
                ax.set_title(f"t = {t:g}", fontsize=10)
                ax.set_ylim(bottom=0)
            else:
                ax.set_yscale("log")
                top = max(float(np.max(f_exact[j])), float(np.max(d.density)))
                ax.set_ylim(top * 1e-4, top * 3)
            ax.set_xlabel(VELOCITY)
            ax.axvline(0, color="0.7", lw=0.7)
        axes[0, j].set_ylabel("f(v, t | v0)")
        axes[1, j].set_ylabel("f (log scale)")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"Fig. 6: transition probability from $v_0$={v0:g} — {_title(runs)}", fontsize=10)
    path = save(fig, out / f"fig6_propagator_{runs.exp.name}_v0_{v0:g}.png")
    return path, (f"Transition probability f(v, t | v0 = {v0:g}) (paper Fig. 6) at t = "
                  f"{', '.join(f'{t:g}' for t in times)}, linear (top) and logarithmic (bottom). Black: exact finite-noise Fokker-Planck "
                  "solution; blue dashed: the paper's weak-noise saddle point normalised on the "
                  "grid (no Jacobian or fluctuation factor); red: circuit histogram with 95 % "
                  "Wilson band.")


def fig_stationary(analysis: ExperimentAnalysis, out: Path):
    runs = analysis.runs
    d, v, p_s = _curves(analysis).get("stationary law")
    fig, axes = new_figure(1, 2, squeeze=False)
    for ax, log in zip(axes.ravel(), (False, True)):
        ax.fill_between(d.centres, d.lower, d.upper, step="mid", color=CIRCUIT, alpha=0.25)
        ax.step(d.centres, d.density, where="mid", color=CIRCUIT, label="circuit (95 % band)")
        ax.plot(v, p_s, color=EXACT, label="$p_s \\propto e^{-\\gamma U}$ (eq. (6))")
        if log:
            ax.set_yscale("log")
        ax.set_xlabel(VELOCITY)
        ax.set_ylabel("stationary density")
        ax.legend(fontsize=8)
    fig.suptitle(f"Stationary law — {_title(runs)}", fontsize=10)
    path = save(fig, out / f"stationary_{runs.exp.name}.png")
    return path, ("Stationary velocity density: circuit (after burn-in, errors from the spread "
                  "across independent replicas) against the exact p_s (eq. (6)), which holds "
                  "at every gamma.")


# ------------------------------------------------------------------------------ Fig. 7
def fig_work_paths(analysis: ExperimentAnalysis, out: Path):
    """Paper Fig. 7: work-optimal paths against circuit windows of the same work rate."""
    runs = analysis.runs
    items = _curves(analysis).get("work paths")
    if not items:
        return None
    m = runs.exp.model
    fig, axes = new_figure(1, len(items), squeeze=False)
    notes = []
    for ax, ((w, tau), s, seg, p) in zip(axes.ravel(), items):
        if seg.shape[0] >= 5:
            lo, hi = np.quantile(seg, [0.1, 0.9], axis=0)
            ax.fill_between(s, lo, hi, color=CIRCUIT, alpha=0.2, label="circuit 10-90 %")
            ax.plot(s, seg.mean(axis=0), color=CIRCUIT, lw=1.5,
                    label=f"circuit mean ({seg.shape[0]} windows)")
        ax.plot(p.s, p.v, color=EXACT, lw=2, label="work-optimal path (eq. (60))")
        ax.axhline(w / m.force, color="0.3", ls="--", lw=1, label="$\\tilde v_w$ = w/(m a) (eq. (63))")
        ax.axhline(0, color="0.7", lw=0.7)
        ax.set_title(f"w = {w:g}, $\\tau$ = {tau:g}", fontsize=10)
        ax.set_xlabel("time within the window (units of tau_m)")
        ax.set_ylabel(VELOCITY)
        ax.legend(fontsize=7)
        notes.append(f"w={w:g}, tau={tau:g}: {seg.shape[0]} circuit windows")
    fig.suptitle(f"Fig. 7: paths of given work rate — {_title(runs)}", fontsize=10)
    path = save(fig, out / f"fig7_work_paths_{runs.exp.name}.png")
    return path, ("Paths with a prescribed work rate (paper Fig. 7). Black: minimiser of "
                  "K = A - beta W (eqs. (57)-(60)) between the median end points of the circuit "
                  "windows; red: circuit windows of the stationary run whose work rate lies within "
                  "10 % of w (first such window of each replica). Near w = 0 the optimal path "
                  "shares its time between sticking at v = 0 and sliding (the time-sharing that "
                  "makes the true rate function the convex envelope of eq. (64)); in the circuit "
                  "the switching instant varies from window to window, so the mean smears the "
                  "stuck and sliding stretches. " + "; ".join(notes))


# ------------------------------------------------------------------------------ Figs. 8-9
def _lookup(table, w):
    return np.array([table.get(x, np.nan) for x in np.round(np.asarray(w), 12)])


def fig_rate_function(analysis: ExperimentAnalysis, out: Path):
    """Paper Fig. 8 with circuit data: I(w) of eq. (64), the exact I_gamma(w), the weak-noise
    limit, the finite-tau exact -ln P_tau(w)/(tau gamma) and the circuit's estimate."""
    runs = analysis.runs
    rc = _curves(analysis).get("rate function")
    if rc is None:
        return None
    m = runs.exp.model
    w, paper, dists, finite = rc.w, rc.paper, rc.dists, rc.finite
    fig, axes = new_figure(1, 2, squeeze=False, width=5.5)
    ax = axes[0, 0]
    ax.plot(w[w < 0], paper[w < 0], color=WEAK, ls="--", lw=1.5, label="paper I(w) (eq. (64))")
    ax.plot(w[w > 0], paper[w > 0], color=WEAK, ls="--", lw=1.5)
    ax.plot(w, rc.limit, color="tab:purple", lw=1.2, ls="-.",
            label="$\\gamma\\to\\infty$ limit (convex hull)")
    ax.plot(w, rc.exact, color=EXACT, lw=1.8,
            label=f"exact $I_\\gamma$ ($\\tau\\to\\infty$, $\\gamma$={m.gamma:g})")
    # one colour per work window, cycled: zip() with five colours dropped a sixth
    # experiment.work_taus entry from the figure without a word
    colours = list(itertools.islice(itertools.cycle(
        ["tab:red", "tab:orange", "tab:green", "tab:brown", "tab:pink"]), len(dists)))
    for (tau, d), c in zip(dists.items(), colours):
        r = empirical_rate_function(d, tau, m.gamma)
        ax.errorbar(r.w, r.rate, yerr=r.stderr, fmt="o", ms=3, color=c, capsize=2,
                    label=f"circuit, $\\tau$={tau:g}")
        rate_fin = -np.log(_lookup(finite[tau], r.w)) / (tau * m.gamma)
        ax.plot(r.w, rate_fin - np.nanmin(rate_fin), color=c, lw=1, alpha=0.8)
    ax.set_xlabel("work rate w (model units)")
    ax.set_ylabel("rate function I(w)")
    # 2 % of the exact curve's height below 0 (was -0.02 in absolute units: the paper's
    # I(w) spans ~0.6; a model with a 100x smaller I(w) was squeezed to its bottom)
    ax.set_ylim(bottom=-0.02 * max(float(np.nanmax(rc.exact)), 1e-12))
    ax.set_title("Fig. 8: rate function (thin: exact finite-$\\tau$)", fontsize=10)
    ax.legend(fontsize=7)
    ax = axes[0, 1]
    wp = w[w > 0]
    ax.plot(wp, rc.paper_fr, color=WEAK, ls="--",
            label="paper (eq. (67))")
    ax.plot(wp, rc.exact_fr, color=EXACT, label="exact $I_\\gamma(-w)-I_\\gamma(w)$")
    for (tau, d), c in zip(dists.items(), colours):
        fr = fluctuation_ratio(d, tau, m.gamma)
        ax.errorbar(fr.w, fr.ratio, yerr=fr.stderr, fmt="o", ms=3, color=c, capsize=2,
                    label=f"circuit, $\\tau$={tau:g}")
        ratio = _lookup(finite[tau], fr.w) / _lookup(finite[tau], -fr.w)
        ax.plot(fr.w, np.log(ratio) / (tau * m.gamma), color=c, lw=1, alpha=0.8)
    ax.set_xlabel("work rate w > 0 (model units)")
    ax.set_ylabel("ln[P(w)/P(-w)] / ($\\tau\\gamma$)")
    ax.set_title("Fig. 9: fluctuation relation (thin: exact finite-$\\tau$)", fontsize=10)
    ax.legend(fontsize=7)
    fig.suptitle(f"Work fluctuations — {_title(runs)}", fontsize=10)
    path = save(fig, out / f"fig8_9_work_{runs.exp.name}.png")
    return path, ("Rate function and fluctuation relation of the work rate (paper Figs. 8 and 9). "
                  "Blue dashed: the paper's weak-noise formulas (eqs. (64), (67)) with the jump "
                  "at w = 0 (where eq. (64) is ambiguous, this report uses the Filippov value "
                  "I(0) = max(|a| - Delta, 0)^2/4, the cheapest way of holding v = 0); purple: the gamma -> infinity limit of the exact rate function "
                  "(the convex hull, continuous at w = 0); black: exact I_gamma at this gamma "
                  "(tilted generator, Legendre transform); thin coloured lines: exact finite-tau "
                  "densities (-ln P_tau(w)/(tau gamma), shifted); points: circuit, errors from the "
                  "spread across independent replicas.")


# ------------------------------------------------------------------------- error budget
# (label, |term| of a comparison, colour): the stacked bars of every budget figure
BUDGET_TERMS = (
    ("statistical (3 SE)", lambda c: 3 * c.circuit_stderr, "0.75"),
    ("smoothing", lambda c: abs(c.budget.smoothing), "tab:blue"),
    ("bandwidth", lambda c: abs(c.budget.bandwidth), "tab:green"),
    ("integration", lambda c: abs(c.budget.integration), "tab:purple"),
    ("circuit element", lambda c: abs(c.budget.element), "tab:red"),
    ("sampling", lambda c: abs(c.budget.sampling), "tab:brown"),
)


def budget_axes(comps, reference: str):
    """One horizontal stacked bar per comparison (the allowed deviation, term by term; terms
    that are zero for every row are left out of the legend) and a diamond at the actual
    |circuit - reference|.  Shared by the paper's and the Beyond chapter's budget figures."""
    names = [c.observable for c in comps]
    y = np.arange(len(comps))
    fig, axes = new_figure(1, 1, squeeze=False, width=9.0, height=0.28 * len(comps) + 1.5)
    ax = axes[0, 0]
    left = np.zeros(len(comps))
    for label, fn, colour in BUDGET_TERMS:
        vals = np.array([fn(c) for c in comps])
        if label != "statistical (3 SE)" and not np.any(vals > 0):
            continue
        ax.barh(y, vals, left=left, color=colour, label=label, height=0.6)
        left += vals
    dev = np.array([abs(c.circuit - c.theory) for c in comps])
    ax.plot(dev, y, "D", color="k", ms=4, label=f"|circuit - {reference}|")
    ax.set_yticks(y, names, fontsize=7)
    pos = left[left > 0]
    ax.set_xscale("symlog", linthresh=max(1e-5, float(pos.min()) if pos.size else 1e-5))
    ax.invert_yaxis()
    ax.set_xlabel("absolute error (observable's units)")
    return fig, ax


def fig_budget(analysis: ExperimentAnalysis, out: Path):
    comps = [c for c in analysis.comparisons
             if c.theory_kind == "exact"
             and not ((o := find(c.observable)) is not None and o.entry.fit_test)]
    if not comps:
        return None
    fig, ax = budget_axes(comps, "exact")
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title(f"Error budget — {analysis.runs.exp.name}", fontsize=10)
    path = save(fig, out / f"budget_{analysis.runs.exp.name}.png")
    return path, ("Error budget per observable (histogram chi-square tests are in the table): stacked bars are the allowed deviation "
                  "(3 standard errors + smoothing + noise bandwidth + integration, each estimated "
                  "independently); diamonds are the actual |circuit - exact|. A diamond inside "
                  "its bar is explained by the budget.")
