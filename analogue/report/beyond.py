"""Beyond the paper: the chapter's page for the model family's members (issue 9).

What the chapter shows is computed in :mod:`analogue.study.members` (the circuits, the
references, the budgets: a :class:`~analogue.study.members.MemberAnalysis`); this module writes
its text, its table and its section, and draws its figures through
:mod:`analogue.report.family_figures`.  The analysis names are re-exported here, where they
were first.
"""
from __future__ import annotations

import math

import numpy as np
from pathlib import Path

from ..study.experiments import standard_circuit
from ..model import Model
from ..study.members import (CHAPTER_TITLE, CHECK_REPLICAS, MEMBERS, MemberAnalysis, MemberRuns,  # noqa: F401
                             MemberSizes, analyse_member, is_member_experiment, member_runs,
                             member_sizes, rate_function_data, stick_window, weak_noise_law,
                             work_tau)
from ..study import catalogue as C
from ..study.metrics import Comparison
from .html import Table
from . import family_figures as FF
from .html import Figure, Section
from .prose import experiment_paragraphs
from ..variants.words import ELEMENT_TERMS, merge, model_phrases, num

__all__ = [
    "CHAPTER_TITLE",
    "MEMBERS",
    "MemberAnalysis",
    "MemberRuns",
    "MemberSizes",
    "analyse_member",
    "chapter_intro",
    "is_member_experiment",
    "member_runs",
    "member_section",
    "member_sizes",
    "member_table",
    "member_text",
    "physics_text",
    "rate_function_data",
    "stick_window",
    "weak_noise_law",
    "weak_noise_text",
    "work_tau",
]



def _member_kind(m: Model) -> str:
    """Which extension a member's text describes (the spring first: a spring member has the
    spring's analysis, Monte Carlo reference and no exact P(v = 0), whatever its noise)."""
    return m.restoring.member_kind(m)   # analogue.variants: spring, noise, friction law


def physics_text(m: Model) -> str:
    """What the member's extension changes, with the member's own numbers and only the
    claims that hold for them (issue 20 item 3: a shot member with rate 2.5 and mean 0.35
    read the shipped file's "rate 1, mean 0.5"; an atom at v = 0 was claimed in the slip
    regime too)."""
    kind = _member_kind(m)
    stuck_free = abs(m.a) < m.static_friction
    if kind == "shot":
        assert m.shot is not None
        side = m.noise_kind.side_words()
        text = (f"Shot noise instead of vibrations: the plate kicks the object at random times "
                f"(Poisson, rate {num(m.shot.rate)} per unit time; exponentially distributed "
                f"velocity jumps of mean {num(m.shot.mean)}, {side}) and does nothing in "
                "between. Between kicks the object follows the deterministic dry-friction flow")
        if stuck_free:
            text += (f", which here (|a| = {num(abs(m.a))} < Delta(0) = "
                     f"{num(m.static_friction)}) reaches v = 0 in a finite time: the object "
                     "sticks until the next kick.")
            if not math.isfinite(m.gamma):
                text += (" The stationary law therefore has an atom at v = 0 - a finite "
                         "probability of being exactly at rest, which Gaussian noise (a density "
                         "everywhere) never gives.")
        else:
            text += (f", which here (|a| = {num(abs(m.a))} >= Delta(0) = "
                     f"{num(m.static_friction)}) does not stop at v = 0: the object slides "
                     "between kicks, and the stationary law has no atom at v = 0.")
        return text
    if kind == "coloured":
        return coloured_text(m)
    if kind == "spring":
        return (f"A linear spring (spring = {num(m.spring)}) on the object turns the steady "
                f"slide into stick-slip oscillations: released from x0 = {num(m.x0)} the object "
                f"swings back, Coulomb friction takes 2 Delta/spring = "
                f"{num(2 * m.delta / m.spring)} off the amplitude every half period, and it "
                "sticks once |spring x - a| < Delta; the noise unsticks it again. The state "
                "(x, v) is two-dimensional, so the reference is the Monte Carlo, and the "
                "stationary identities <v> = 0 and spring <x> = a - <Delta(v) sgn v> - cubic "
                "<v^3> are checked on the circuit.")
    if kind == "stribeck":
        assert m.stribeck is not None
        d_s, v_s = m.stribeck
        between = m.delta < abs(m.a) < d_s
        return (f"Velocity weakening (the Stribeck curve): the friction drops from its static "
                f"value delta_s = {num(d_s)} to the kinetic Delta = {num(m.delta)} over the "
                f"speed v_s = {num(v_s)}. For a force between Delta and delta_s both sticking "
                "and sliding can be stable without noise, and the stationary law exp(-gamma U) "
                f"can then have two peaks (a cusp at v = 0 and one at the sliding velocity); "
                f"here a = {num(m.a)} is {'between them' if between else 'not between them'}.")
    return (f"A cubic viscous term (cubic = {num(m.cubic)}: lubricated or hydrodynamic "
            "friction) confines fast velocities: the potential gains cubic v^4/4, the slide "
            "slows and the stationary law's fast tail is cut, so the variance shrinks against "
            "the paper's law at the same Delta.")


def coloured_text(m: Model) -> str:
    """Coloured noise (analogue.variants.coloured), with the member's tau_c, gamma, tau_m."""
    tau_c = m.noise_kind.tau_c  # type: ignore[attr-defined]
    text = (f"Coloured noise instead of white: the plate's force is white noise of intensity "
            f"1/gamma (gamma = {num(m.gamma)}) passed through a low-pass of correlation time "
            f"tau_c = {num(tau_c)} (an Ornstein-Uhlenbeck force, <eta(t) eta(t')> = "
            f"exp(-|t - t'|/tau_c)/(gamma tau_c), variance {num(1 / (m.gamma * tau_c))}; "
            f"tau_c/tau_m = {num(tau_c / m.tau_m)}). The state (v, eta) is two-dimensional "
            "and not a gradient system: exp(-gamma U) is not its stationary law and there is no "
            "exact theory here, so the reference is the Monte Carlo of the same model, started "
            "where the circuit starts. In the circuit the held Gaussian source feeds an RC "
            "low-pass (R_ou C_ou = tau_c) whose voltage drives the noise current.")
    cf = m.noise_kind.closed_form_variance(m)
    if cf is not None:
        text += (f" At Delta = 0 the model is linear and Var v = tau_m^2/(gamma (tau_m + "
                 f"tau_c)) = {num(cf)}, against tau_m/gamma = {num(m.tau_m / m.gamma)} for "
                 "white noise.")
    return text


def _fmt(c: Comparison) -> str:
    return (f"{c.observable}: circuit {c.circuit:.4g} +- {c.circuit_stderr:.2g}, "
            f"{'Monte Carlo' if 'Monte Carlo' in c.note else 'exact'} {c.theory:.4g}, "
            f"z = {c.z:.2f}, {'within' if c.within_budget else 'OUTSIDE'} budget")


def member_text(a: MemberAnalysis) -> list[str]:
    """Paragraphs of a member's section: what the extension changes, and its numbers."""
    m, f, _name = a.exp.model, a.facts, a.exp.name
    key = _member_kind(m)
    pure_shot = key == "shot" and not math.isfinite(m.gamma)
    text = [physics_text(m)]
    if key == "shot" and not pure_shot:
        text.append("With the Gaussian noise on as well (gamma finite) the diffusion spreads the "
                    "stuck state: the stationary law has a density and no atom at v = 0.")
    if pure_shot:
        text.append(f"Exact P(v = 0) = {f['p_zero']:.4f}; the circuit's stuck fraction "
                    f"(|v| < {stick_window(a.exp):.3g}, where the exact law has "
                    f"{next((c.theory for c in a.comparisons if c.observable == 'P(v=0)'), float('nan')):.4f}) "
                    f"is {f['p_zero_measured']:.4f}.")
    elif key == "coloured":
        text.append(f"Monte Carlo stationary mean {f['mc_mean']:.4f} and variance "
                    f"{f['mc_variance']:.4f} ({f['mc_replicas']} replicas), against the exact "
                    f"{f['white_mean']:.4f} and {f['white_variance']:.4f} for white noise of the "
                    "same gamma: the filter takes the noise's fast part away.")
    elif key == "spring":
        text.append(f"First swing after the release: half period {f['circuit_half_period']:.3f} "
                    f"(circuit) vs {f['mc_half_period']:.3f} (Monte Carlo), amplitude "
                    f"{f['circuit_amplitude']:.3f} vs {f['mc_amplitude']:.3f}; without damping "
                    f"the half period would be pi/sqrt(spring) = "
                    f"{f['omega_undamped_half_period']:.3f}.")
    elif "paper_mean" in f:
        text.append(f"Exact stationary mean {f['mean']:.4f} and variance {f['variance']:.4f}, "
                    f"against {f['paper_mean']:.4f} and {f['paper_variance']:.4f} for the "
                    "paper's model at the same Delta (no extension).")
    else:
        text.append(f"Exact stationary mean {f['mean']:.4f} and variance {f['variance']:.4f}.")
    if key in ("stribeck", "cubic") and "weak_noise_l1" in f:
        text.append(weak_noise_text(m, f))
    s = a.summary()
    text.append(f"{s['comparisons']} comparisons, {s['within_budget']} within budget, "
                f"{s['abs_z_below_3']} with |z| < 3 ({a.sizes.stationary_replicas} stationary "
                f"replicas of {a.sizes.stationary_t_end:g} time units, "
                f"{a.sizes.transition_replicas} transition replicas; {a.wall_time:.1f} s).")
    return text


def weak_noise_text(m: Model, f: dict) -> str:
    """What of the paper's weak-noise theory carries over to a 1-D Gaussian member
    (:mod:`analogue.theory.weak_noise_family`), with the member's quasi-potential numbers."""
    mins, um, tops = f["u_minima"], f["u_at_minima"], f["u_barrier_tops"]
    d0 = float(m.friction_magnitude(np.zeros(1))[0])  # the static friction
    out = ("Weak noise: the stationary law is exp(-gamma U) with the generalised potential U at "
           "every gamma, so the quasi-potential is U - U_min and the weak-noise law (dotted in "
           f"the figure) is the exact one (L1 distance {f['weak_noise_l1']:.1g} to the "
           "numerics). Of the paper's optimal paths, the kinds carry over (direct; indirect = "
           "relax, stick, leave, with action U(v) - U(0)), and so does the time-reversal "
           "identity A(v, t | v0) - A(v0, t | v) = U(v) - U(v0) of direct paths; sticking is "
           f"free iff |a| <= Delta(0) = {d0:g} (here a = {m.a:g}: "
           f"{'free' if abs(m.a) <= d0 else 'not free'}). The closed forms do not: U is no "
           "longer piecewise quadratic, so the basic solutions (eq. (16)), actions (eq. (20)) "
           "and gluing times are solved numerically, and the crossing paths are not "
           "implemented for the family.")
    if len(mins) > 1:
        j = int(np.argmin(um))
        wells = ", ".join(f"v = {x:.3g} (U - U_min = {u:.3g})" for x, u in zip(mins, um))
        out += (f" U is multi-welled here: minima at {wells}, barrier tops at "
                f"{', '.join(f'{t:.3g}' for t in tops)} above U_min; as gamma -> inf the law "
                f"concentrates at v = {mins[j]:.3g}, the other well is metastable (hops cost "
                "exp(-gamma barrier)), and the paper's closed-form work rate function "
                "(eq. (64)) does not apply.")
    elif len(mins) == 1:
        out += (f" U has a single minimum, at v = {mins[0]:.3g}: the weak-noise limit "
                "concentrates the law there.")
    return out


def member_table(a: MemberAnalysis):
    rows, classes = [], []
    for c in a.comparisons:
        b = c.budget
        rows.append([c.observable, c.circuit, c.circuit_stderr, c.theory, c.z, abs(b.smoothing),
                     abs(b.bandwidth), abs(b.integration), abs(b.element), abs(b.sampling),
                     c.within_budget, c.note])
        classes.append("ok" if c.within_budget else "fail")
    ref = "Monte Carlo" if C.reference_is_monte_carlo(a.exp.model) else "exact"
    return Table(f"{a.exp.name}: circuit against {ref}",
                 ["observable", "circuit", "SE", ref, "z", "smoothing", "bandwidth",
                  "integration", "circuit element", "sampling", "within budget", "note"], rows,
                 classes)


def member_section(a: MemberAnalysis, out: Path, attempt=None):
    """The section of one member (figures drawn from the analysis); ``attempt(what, fn)``
    runs a figure and returns (result, error) (the pipeline's failure recorder)."""
    attempt = attempt or (lambda what, fn: (fn(), None))
    figs, errs = [], []
    for what, fn in FF.member_figures(a):
        r, err = attempt(f"figure: {what}", lambda fn=fn: fn(a, Path(out)))
        if err is not None:
            errs.append(f"figure '{what}': {err}")
        elif r is not None:
            figs.append(Figure(*r))
    return Section(f"{CHAPTER_TITLE}: {a.exp.name}", member_text(a) + experiment_paragraphs(a.exp),
                   figures=figs, tables=[member_table(a)], error="; ".join(errs) or None)


def _is_paper_chapter(analyses: list) -> bool:
    """The paper report's chapter: the shipped members, from the standard circuits."""
    if sorted(a.exp.name for a in analyses) != sorted(MEMBERS):
        return False
    try:
        return all(a.exp.source is not None and Path(a.exp.source).resolve()
                   == standard_circuit(a.exp.name).resolve() for a in analyses)
    except (OSError, ValueError):
        return False


_KIND_WORDS = {"shot": "shot noise", "spring": "a spring",
               "coloured": "coloured (Ornstein-Uhlenbeck) noise", "stribeck": "velocity weakening "
               "(Stribeck) friction", "cubic": "cubic viscous friction"}


def chapter_intro(analyses: list, wall: float, quick: bool) -> list[str]:
    """The chapter's opening, naming only the members it has and their own sizes."""
    n = sum(len(a.comparisons) for a in analyses)
    ok = sum(c.within_budget for a in analyses for c in a.comparisons)
    kinds = [_member_kind(a.exp.model) for a in analyses]
    present = [k for k in ("shot", "spring", "stribeck", "cubic") if k in kinds]
    # an element term is booked wherever the member has that circuit element, whatever the
    # kind its text is filed under (a spring member with cubic friction has both)
    elements = merge(model_phrases(a.exp.model for a in analyses), ELEMENT_TERMS)
    if _is_paper_chapter(analyses):
        first = ("The paper's concluding section proposes extensions it does not treat: shot "
                 "noise instead of Gaussian vibrations, a spring on the object, a measured "
                 "(velocity weakening) friction law, and nonlinear viscous friction. Each is one "
                 "member of the model family, run on its own circuit (circuits/<member>.toml)")
    else:
        names = ", ".join(f"{a.exp.name} ({_KIND_WORDS[k]})" for a, k in zip(analyses, kinds))
        first = (f"Members of the model family in this report: {names}. Each runs on its own "
                 "circuit")
    refs = []
    if any(k not in ("spring", "coloured") for k in kinds):
        refs.append("the exact finite-noise numerics of its one-dimensional law (Fokker-Planck"
                    + (", or Kolmogorov-Feller for shot noise" if "shot" in kinds else "") + ")")
    if "spring" in kinds:
        refs.append("for the spring, the Monte Carlo")
    if "coloured" in kinds:
        refs.append("for coloured noise (no exact theory yet), the Monte Carlo")
    first += " and is held against " + " or, ".join(refs) + "."
    sizes = ("quick sizes: small replica counts, short runs" if quick else
             "full sizes: each member's own [experiment] replicas and [report] stationary "
             "length")
    second = (f"{n} comparisons, {ok} within their error budget (3 SE + smoothing + noise "
              f"bandwidth + integration (the first {CHECK_REPLICAS} replicas of the stationary "
              "run re-run 100x tighter on the same noise)"
              + (f" + the family's circuit-element terms: {', '.join(elements)}" if elements
                 else "")
              + f"). This chapter took {wall:.1f} s ({sizes}).")
    survive = []
    gauss_1d = [k for k in ("cubic", "stribeck") if k in present]
    if gauss_1d:
        survive.append("the stationary law is still exp(-gamma U) for every Gaussian "
                       f"one-dimensional member ({', '.join(gauss_1d)}) with U gaining "
                       + " or ".join({"cubic": "cubic v^4/4", "stribeck": "the Stribeck term"}[k]
                                     for k in gauss_1d)
                       + ", so the paper's weak-noise method carries over through U")
    if "shot" in present:
        survive.append("shot noise breaks it (no potential: a master equation"
                       + (", an atom at rest when the object sticks between kicks" if any(
                           k == "shot" and not math.isfinite(a.exp.model.gamma)
                           for a, k in zip(analyses, kinds)) else "") + ")")
    if "coloured" in kinds:
        survive.append("coloured noise breaks it too (the noise has a memory: the state "
                       "(v, eta) is two-dimensional; the Monte Carlo is the reference)")
    if "spring" in present:
        survive.append("the spring makes the state two-dimensional (no closed stationary law; "
                       "the Monte Carlo is the reference)")
    out = [first, second]
    if survive:
        out.append("What survives of the paper: " + "; ".join(survive) + ".")
    return out
