"""The page's words that depend on the experiments it describes (issue 20 item 3).

Every number a page prints comes from the experiment it describes: the model sentence of a
section, the circuit paragraph (which sources and elements the decks have), the reduced
equation of the intro, the pointer to the stick board (the paper's report only).  A
description copied with its file keeps the original's numbers (a copy of ``shot.toml`` with
rate 2.5 and mean 0.35 read "rate 1 ... mean 0.5"): :func:`description_mismatches` finds the
``name = value`` statements of a description that disagree with the model, and the section
says so next to it.

Pure functions of the experiments (no files, no runs), so that a test can build the text of
any experiment and compare its numbers with the model.  What differs between the members of the
family (the friction law, the spring, the noise kind) is said by the variants themselves
(``describe``, ``stated_values``, ``page_phrases``: :mod:`analogue.variants.words`); this
module composes their words and tests no model feature except the paper's own model.
"""
from __future__ import annotations

import logging
import math
import re
from pathlib import Path
from ..study.experiments import PAPER_EXPERIMENTS, standard_circuit
from ..variants.words import CIRCUIT, EQUATION, REFERENCE, Phrase, merge, model_phrases, num

__all__ = ["is_paper_experiment", "is_paper_report", "main_part", "model_sentence", "description_mismatches",
           "experiment_paragraphs", "circuit_paragraph", "equation_text", "board_link",
           "component_rows", "theory_kinds_text", "budget_text"]

_log = logging.getLogger("analogue.report.prose")


def is_paper_experiment(exp) -> bool:
    """One of the paper's experiments, from the standard circuits (a user's
    ``./circuits/stick.toml`` is the user's, whatever its name)."""
    source = getattr(exp, "source", None)   # an experiment built in memory has none
    if exp.name not in PAPER_EXPERIMENTS or source is None:
        return False
    try:
        return Path(source).resolve() == standard_circuit(exp.name).resolve()
    except (OSError, ValueError):
        return False


def is_paper_report(experiments) -> bool:
    """The paper's own report: exactly the paper's experiments, from the standard circuits."""
    return (sorted(e.name for e in experiments) == sorted(PAPER_EXPERIMENTS)
            and all(is_paper_experiment(e) for e in experiments))


def main_part(experiments) -> str:
    """What the report's first part is called in its log and timing lines."""
    return "the paper's chapters" if is_paper_report(experiments) else "the experiments' sections"


# ------------------------------------------------------------------------- the model
def model_sentence(exp) -> str:
    """The experiment's parameters and what they imply, every number from ``exp``."""
    m = exp.model
    items = [f"tau_m = {num(m.tau_m)}", f"Delta = {num(m.delta)}", f"a = {num(m.a)}"]
    if m.mass != 1:
        items.append(f"mass = {num(m.mass)}")
    items += [*m.friction.describe(), *m.restoring.describe()]
    text = (f"Model (reduced units): {', '.join(items)}; "
            f"{'; '.join(m.noise_kind.describe())}.")
    if m.is_paper:
        if m.regime == "stick":
            t_a = ", ".join(f"t_a = {num(m.stick_time(v0))} from v0 = {num(v0)}"
                            for v0 in exp.v0)
            text += (f" Stick regime (|a| < Delta): without noise the motion stops at v = 0 "
                     f"({t_a}, eq. (31)).")
        else:
            text += (f" Slip regime (|a| > Delta): without noise the velocity relaxes to "
                     f"v_ss = (a - Delta sgn a) tau_m = {num(m.attractor)} (eq. (14)).")
    v0s = ", ".join(num(v) for v in exp.v0)
    diode = ("ideal diodes" if exp.spec.diode == "ideal" else f"{exp.spec.diode} diodes")
    element = (f"{exp.spec.coulomb} Coulomb element ({diode})" if m.delta > 0
               else "no Coulomb element (Delta = 0)")
    text += f" Circuit: {element}."
    if m.is_paper:
        # (no replica count: --quick runs fewer than the file's; the figures and the
        # provenance table give the counts each run had.  A member's runs have their own
        # lengths, given in its section.)
        text += (f" Transition runs from v0 = {v0s} to t = {num(exp.t_end)}, sampled every "
                 f"{num(exp.sample_dt)}.")
    return text


# a parameter named in a description, written "name = value": not after an operator or a
# closing bracket ("(a - Delta) tau_m = 0.5" is a product, "2 Delta/spring = 1" a quotient)
_ASSIGNED = re.compile(r"(?<![\w)*/+^.-])(?<![)*/+^-] )\b(tau_m|tau_c|Delta|delta|gamma|mass|cubic|spring|"
                       r"x0|delta_s|v_s|a)\s*=\s*(-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)(?![\w(])")
# shot-noise wording of the standard files: "at rate 1 per unit time", "with mean 0.5"
_SHOT_WORDS = re.compile(r"\b(rate|mean)\s+(\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)\b(?!\s*[*/^])")


def _model_values(m) -> dict:
    out = {"tau_m": m.tau_m, "delta": m.delta, "gamma": m.gamma, "mass": m.mass,
           "cubic": m.cubic, "spring": m.spring, "x0": m.x0, "a": m.a}
    return {**out, **m.friction.stated_values(), **m.noise_kind.stated_values()}


def description_mismatches(exp) -> list[str]:
    """``"a = 0.2 (the model has 0.3)"`` for every ``name = value`` of the description (and
    "rate R", "mean M" of a shot member) that disagrees with the experiment's model."""
    text = " ".join(exp.description.split())
    values = _model_values(exp.model)
    found = []
    for name, value in _ASSIGNED.findall(text):
        key = "delta" if name == "Delta" else name
        found.append((f"{name} = ", key, value))
    # (a model without shot noise has no "rate" or "mean" to disagree with: skipped below)
    found += [(f"{name} ", name, value) for name, value in _SHOT_WORDS.findall(text)]
    out = []
    for said, key, value in found:
        if key not in values:
            continue
        have = values[key]
        if not math.isclose(float(value), have, rel_tol=1e-3, abs_tol=1e-9):
            item = f"{said}{value} (the model has {num(have)})"
            if item not in out:
                out.append(item)
    return out


def experiment_paragraphs(exp) -> list[str]:
    """An experiment's section text: its description (the user's text, escaped by the page
    template), a note where its numbers disagree with the model, and the model sentence."""
    text = " ".join(exp.description.split())
    out = [text] if text else []
    bad = description_mismatches(exp)
    if bad:
        # also on the command line's progress log: a copied file's description misleads
        # whoever reads the page
        _log.info("%s: the description's numbers are not the model's: %s", exp.name,
                  "; ".join(bad))
        out.append("The description above was not written for these parameters: it says "
                   + "; ".join(bad) + ". The numbers of this section are the model's.")
    out.append(model_sentence(exp))
    return out


# --------------------------------------------------------------------- the circuit
def circuit_paragraph(experiments) -> str:
    """How the decks realise the model, naming only the sources and elements the report's
    experiments have (a shot member's deck has no trrandom source when gamma = inf)."""
    models = [e.model for e in experiments]
    specs = [e.spec for e in experiments]
    parts = ["Each replica is one node v (voltage = velocity, kappa volts per unit velocity: "
             "the component table gives kappa for each experiment): capacitor C to ground "
             "(mass), resistor R (viscous friction alpha), a DC current I_F into the node "
             "(the force)"]
    if any(m.delta > 0 and s.coulomb == "diode-bridge" for m, s in zip(models, specs)):
        parts.append("four diodes around a DC current source I_Delta (Coulomb friction: the "
                     "bridge passes I_Delta tanh(V/(2 N V_T)))")
    if any(m.delta > 0 and s.coulomb != "diode-bridge" for m, s in zip(models, specs)):
        parts.append("a behavioural source for the Coulomb friction (B-source)")
    parts += merge(model_phrases(models), CIRCUIT)
    parts.append("and an integrator node x (a VCCS into a capacitor) so that ngspice itself "
                 "integrates the position for the work W = F (x(t+tau) - x(t))")
    return (", ".join(parts) + ". Time is scaled by theta seconds per model time unit. "
            "`analogue netlist` writes each experiment's representative deck (netlists/ for "
            "the standard experiments, beside the TOML file for the others).")


def component_rows(mapping) -> list:
    """The component table of a circuit without the Gaussian source's rows when the deck has
    no Gaussian source (gamma = inf: no trrandom in the deck)."""
    rows = list(mapping.table())
    if not math.isfinite(mapping.model.gamma):
        rows = [r for r in rows if r[0] not in ("noise_stddev", "noise_TS", "noise_gain", "D_I")]
    return rows


def theory_kinds_text(experiments, members) -> str:
    """What 'exact' and 'weak-noise' mean in the summary, for the experiments it has:
    ``experiments`` on the paper's model, ``members`` of the family."""
    out = []
    if experiments:
        out.append("Theory 'exact' is the finite-noise Fokker-Planck solution of the ideal model "
                   "(sgn friction, white noise); 'weak-noise' is the paper's saddle-point result, "
                   "whose budget includes the finite-noise correction exact(gamma) - weak-noise.")
    if members:
        refs = merge(model_phrases(e.model for e in members), REFERENCE)
        out.append("For the family's members the reference is " + ", ".join(refs) + ".")
    return " ".join(out)


def budget_text(experiments) -> str:
    """The budget terms the report's comparisons can have (the bandwidth term needs held
    Gaussian noise; finite noise needs weak-noise rows, which only the paper's model has)."""
    models = [e.model for e in experiments]
    terms = ["smoothing = exact(epsilon) - exact(0) (the Coulomb element's tanh law)"]
    if any(math.isfinite(m.gamma) for m in models):
        terms.append("bandwidth = held-noise minus white-noise Monte Carlo driven by the same "
                     "Wiener increments (|difference| + 2 SE)")
    terms.append("integration = the circuit re-run with 100x tighter tolerances on the same "
                 "noise (|difference| + 2 SE; indicator observables through their smoothed "
                 "indicator, plus the kernel's Richardson bias estimate: docs/error-budget.md)")
    if any(not m.is_paper for m in models):
        terms.append("circuit element = the family's element terms (cubic network, inductor "
                     "resistance, shot pulses), where the member has that element")
    if any(m.is_paper and m.delta > 0 for m in models):
        terms.append("finite noise (weak-noise rows) = exact(gamma) - weak-noise")
    return ("Rows in red are deviations the budget does not explain. Budget terms (absolute, in "
            "the observable's units): " + "; ".join(terms) + ".")


def equation_text(experiments) -> str:
    """The reduced equation of the intro, with the terms the report's models have."""
    # the variants' terms between -v/tau_m (slot 0) and + a (slot 4): analogue.variants
    terms = merge([Phrase(0, "-v/tau_m"), Phrase(4, "+ a"),
                   *model_phrases(e.model for e in experiments)], EQUATION)
    return "dv/dt = " + " ".join(terms)


def board_link(out: Path, experiments):
    """The intro's pointer to the buildable board of the stick experiment (issue 13), in the
    paper's report (or wherever a board was written next to the page); None otherwise: the
    board realises the paper's stick parameters, not a user's."""
    from markupsafe import Markup
    if (Path(out) / "board" / "index.html").exists():
        return Markup('A board you can build for the stick experiment (op-amp realisation with '
                      'E-series parts, noise chain, tolerance Monte Carlo, calibration, schematic '
                      'and BOM): <a href="board/index.html">board/index.html</a>.')
    if not is_paper_report(experiments):
        return None
    return (f"A board you can build for the stick experiment: run `analogue board stick --out "
            f"{Path(out) / 'board'}` and it is linked here.")
