"""``index.html`` of the board job, through the project's jinja2 page writer (autoescape on:
every text here is escaped; only the link to schematic.svg is markup we write ourselves)."""
from __future__ import annotations

import csv
from pathlib import Path

from markupsafe import Markup

from ..report.html import Figure, Section, Table, write_page
from .calibration import ADC_SPEC
from .netlist import R_IC, RESET_TIME
from .schematic import draw_schematic

__all__ = ["write_report"]


def _offset_paragraph(lim) -> str:
    """The integrator op-amp's offset requirement (:func:`analogue.board.tolerance.offset_limit`)."""
    if not lim:
        return ""
    per = ", ".join(f"{k} {v * 1e6:.0f} uV" for k, v in lim["per_observable_V"].items())
    return (f"Offset of U1 (integrator and Bessel buffer, one part): with both halves at their "
            f"guaranteed offset and opposite signs, the force offset and the read-out shift move "
            f"every observable by less than {lim['fraction_of_se']:g} standard error if the offset "
            f"stays below {lim['limit_V'] * 1e6:.0f} uV (set by {lim['binding']}; per observable: "
            f"{per}). The {lim['part']} guarantees {lim['guaranteed_V'] * 1e6:.0f} uV (offset plus "
            f"drift at the warmest bench temperature): "
            + ("inside the limit." if lim["meets"] else "outside it: use a precision part or the "
               "calibrated force."))


def _schematic_png(design, out: Path) -> Path | None:
    """The same drawing rasterised (the page embeds PNG); the SVG is the deliverable."""
    try:
        return draw_schematic(design, out / "schematic.png", fmt="png")
    except Exception:  # noqa: BLE001 - a missing matplotlib backend must not lose the report
        return None


def _trajectory_text(tc) -> str:
    if not tc:
        return ""
    return (f"Trajectory by trajectory: the first {tc['replicas']} replicas of the board against the "
            "realised equations (tanh friction) driven by the same seeded DAC sequences through the "
            "exact numpy model of the DAC hold and Bessel filter "
            f"(analogue.board.trajectory): rms path difference {tc['rms']:.2g} (stationary spread "
            f"{tc['stationary_std']:.2g}), largest {tc['max']:.2g}, time averages {tc['board_mean']:.4g} "
            f"(board) and {tc['reference_mean']:.4g} (equations). A built board fed the same "
            "sequence is checked the same way: where the board's mean departs from theory by more "
            "than the budget's systematic terms, the equations on the same noise show whether it "
            "is the noise realisation or the circuit.")


def _pm(s: dict) -> str:
    if s.get("std") is None:
        return f"{s['mean']:.4g}"
    return f"{s['mean']:+.4g} ± {s['std']:.3g}"


def write_report(out: Path, exp, design, metrics: dict) -> Path:
    out = Path(out)
    prov = metrics["provenance"]
    st = prov["settings"]
    quick = prov["quick"]
    sections = []

    # ------------------------------------------------------------------ design
    comp = Table("Component values: ideal (from the mapping), rounded (E-series), relative error "
                 "(enters the budget as 'rounding')", ["part", "ideal", "on the board", "rel. error", "role"],
                 [list(r) for r in metrics["board"]["components"]])
    sections.append(Section("Design choices and reasons", paragraphs=[
        *metrics["board"]["notes"],
        ("Friction element: the diode bridge sits in the integrator's feedback between the virtual "
        "ground and the output; its two nodes are fed by rail-referenced current sources (op-amp "
        "servo + MOSFET + sense resistor), so no source floats and each has volts of compliance. "
        "A floating two-terminal regulator cannot do this (it would have to deliver power near "
        "v = 0): with 1.5 V of headroom friction collapses into a dead zone "
        "(tests/integration/test_board_nominal.py reproduces it)."),
        ("Force and noise enter as voltages through resistors into the virtual ground, where they "
        "are exact currents; the position is integrated digitally from the sampled velocity."),
        (f"Rails ±{design.spec.rails:g} V, machine unit {design.spec.machine_unit:g} V; every node "
        "of the deck is checked to stay within the rails (test_every_node_stays_within_the_rails)."),
        ("Op-amps are our own macromodels (gain, GBW, slew rate, offset, bias current, output "
        "swing against load, short-circuit current, input common-mode range with the TL07x's "
        "phase reversal) with typical and worst-case sets for TL072-, OPA2140- and "
        f"OPA2197-class parts (U1 is an {design.spec.opamp}: see the tolerance section for the "
        "offset limit the observables set); no vendor model is shipped (analogue.board.opamp.vendor_model_path "
        "validates a file the user downloads and refuses .control/.exec/shell/.include lines). "
        f"The current sources' servos are {design.spec.servo_opamp}-class (rail-to-rail input): "
        f"their inputs sit {design.spec.v_set:g} V from a rail, outside a TL072's guaranteed "
        "+-11 V."),
        ("Friction enable: each source's drain goes through an SPDT switch (U3, DG413) to the "
         "bridge or to ground; the sources stay in regulation and the bridge floats, whatever "
         "the MOSFET threshold. Reset: U4 (DG412) closes R10 across C1 and feeds the IC voltage "
         "through R11 while the enable is low and the noise DAC at mid-scale."),
    ], tables=[comp]))

    # ------------------------------------------------------------------ schematic + BOM
    with (out / "bom.csv").open(encoding="utf-8") as fh:
        bom = list(csv.reader(fh))
    figs = []
    png = _schematic_png(design, out)
    if png is not None:
        figs.append(Figure(png, "Schematic drawn from the design (schemdraw); vector version "
                                "schematic.svg."))
    sections.append(Section("Schematic and bill of materials", paragraphs=[
        Markup('Vector schematic (overview and a parts sheet with every designator): '
               '<a href="schematic.svg">schematic.svg</a>; KiCad netlist (Pcbnew: File, Import, '
               'Netlist): <a href="board.net">board.net</a>; KiCad schematic (every part on net '
               'labels): <a href="board.kicad_sch">board.kicad_sch</a>; SPICE deck: '
               '<a href="board.cir">board.cir</a>; BOM: <a href="bom.csv">bom.csv</a>.')],
        figures=figs, tables=[Table("Bill of materials (one channel)", bom[0], bom[1:])]))

    # ------------------------------------------------------------------ nominal
    rows, classes = [], []
    for c in metrics["comparisons"]:
        b = c["budget"]
        rows.append([c["observable"], c["circuit"], c["circuit_stderr"], c["theory"],
                     c["z"] if c["z"] is not None else float("nan"), b["rounding"], b["smoothing"],
                     b["bandwidth"], b["integration"], b["statistical"], b["dominant"],
                     c["within_budget"]])
        classes.append("ok" if c["within_budget"] else "fail")
    dens = out / "density.png"
    sections.append(Section("Nominal board against exact theory", figures=[Figure(
        dens, "Stationary velocity histogram of the nominal board against exact p_s: the requested "
              "model (sgn friction, cusp at v = 0) and the realised board (E-series values, the "
              "bridge's tanh width).")] if dens.exists() else [], paragraphs=[
        (f"{st['replicas']} replicas × {st['t_end']} tau_m (burn-in {st['burn_in']}), started from "
        "the stationary law of the realised model; theory: exact finite-noise values of the "
        "requested ideal model (sgn friction, white noise). Budget terms: rounding (E-series "
        "model minus requested, exact theory), smoothing (bridge tanh width, exact theory), "
        f"bandwidth (SDE pair coloured minus white, {st['pair_replicas']} replicas, |d| + 2 se), "
        f"integration (reltol 1e-3 against 1e-4 on the same noise, {st['integ_replicas']} "
        "replicas), statistical = 3 standard errors: "
        + (metrics["comparisons"][0].get("stderr_method", "jackknife over replicas")
           if metrics["comparisons"] else "jackknife over replicas") + "."),
        _trajectory_text(metrics.get("trajectory_check"))],
        tables=[Table("Nominal board vs exact theory", ["observable", "board", "stderr", "theory",
                                                        "z", "rounding", "smoothing", "bandwidth",
                                                        "integration", "3 se", "dominant", "within budget"],
                      rows, row_classes=classes)]))

    study = metrics.get("bandwidth_study") or []
    if study:
        keys = ("mean v", "var v", "P(v>0)", "stick fraction")
        sections[-1].tables.append(Table(
            "Noise-chain design study: bias of the coloured noise (DAC hold + Bessel) "
            "against white noise, SDE pair with common increments (difference ± se). The stick "
            "fraction is the sensitive one: near v = 0 the bridge relaxes in epsilon/Delta, a few "
            "DAC samples at tau_m/100; a 4x faster DAC and a Bessel corner at half the DAC rate (the "
            "default since issue 21) cut "
            "its bias about 5x, at about 4x the simulation cost",
            ["DAC samples per tau_m", "Bessel corner / DAC rate", *keys],
            [[r["dac_rate_per_tau"], r["bessel_fc"]] + [f"{r[k][0]:+.4f} ± {r[k][1]:.4f}" for k in keys]
             for r in study]))

    # ------------------------------------------------------------------ Monte Carlo
    mc = metrics["monte_carlo"]
    rows = [[k, v["theory_requested"], v["nominal_board"], _pm(v["before"]), _pm(v["vs_nominal_board"]),
             _pm(v["predicted"]), _pm(v["after"])] for k, v in mc.items()]
    n_boards = st["boards"]
    sections.append(Section(f"Tolerance Monte Carlo ({n_boards} boards)", paragraphs=[
        f"{n_boards} boards drawn with a seeded generator (seed {prov['seeds']['monte_carlo']}; same seed, "
        f"same boards), each simulated in ngspice for {st['mc_replicas']} replicas × {st['mc_t_end']} "
        "tau_m with the same DAC sequences as the nominal reference (common random numbers: the "
        "board-to-board spread is the tolerances', not sampling noise)."
        + (" This is the --quick run: fewer boards and shorter runs than the full job (20 boards)."
           if quick else ""),
        ("Before calibration: board minus exact theory of the requested model (bias ± spread "
        "across boards; the bias includes the common statistical error of the short runs). "
        "Board minus nominal board on the same noise: the tolerance effect alone, before "
        "calibration. Predicted: exact theory at each board's first-order effective model "
        "(analogue.board.tolerance.effective_model) minus exact theory of the nominal board, an "
        "independent route to the same number. After calibration: the tolerance effect that "
        "remains once theory is evaluated at the parameters the calibration procedure measured "
        "on each board, (board - nominal board) - (theory(calibrated) - theory(nominal)).")],
        tables=[Table("Observables across boards", ["observable", "theory (requested)",
                                                    "nominal board (MC runs)", "before calibration",
                                                    "board - nominal board", "predicted (effective model)",
                                                    "left after calibration"], rows)]))

    rf = metrics.get("monte_carlo_rate_function") or {}
    if rf:
        sections[-1].tables.append(Table(
            "Work rate-function points I(w) across the same boards (exact-theory gradients at each "
            "board's effective parameters; after calibration: the part the calibrated parameters do "
            "not capture, i.e. the calibration errors and the uncalibrated ADC offset)",
            ["point", "before calibration", "after calibration"],
            [[k, _pm(v["before"]), _pm(v["after"])] for k, v in rf.items()]))

    # ------------------------------------------------------------------ sensitivities
    sens = metrics["sensitivities"]
    obs_names = [k for k in sens["all"] if not k.startswith("_")]
    classes_ = [c for c in sens if c != "all"] + ["all"]
    rows = [[c] + [sens[c][k]["std"] for k in obs_names] for c in classes_]
    prow = [[c] + [sens[c]["_params_std"][p] for p in ("tau_m", "delta", "a", "gamma", "epsilon", "offset")]
            for c in classes_]
    contrib = sens["all"]["_param_contrib"]
    params = ("tau_m", "delta", "a", "gamma", "epsilon", "offset")
    stat = {c["observable"]: c["circuit_stderr"] for c in metrics["comparisons"]}
    crow = [[k] + [contrib[k][p] for p in params] + [sens["all"][k]["std"],
            sens["all"][k]["std"] / stat[k] if stat.get(k) else float("nan")] for k in obs_names]
    must = metrics["matching"]["must_trim_or_match"]
    sections.append(Section("Which tolerances must be trimmed or matched", paragraphs=[
        (f"Standard deviation of each observable (work rate-function points I(w) included) caused "
        f"by each tolerance class alone, over {st['sens_boards']} drawn boards, propagated through "
        "the gradients of exact theory with respect to (tau_m, Delta, a, gamma, epsilon, ADC "
        "offset)."),
        (f"Matching is asked for only where a class's spread exceeds "
         f"{metrics['matching']['fraction_of_se']:g} of the full job's statistical standard "
         "error of some compared observable (from a seeded SDE ensemble of the realised model "
         "at the full job's size, the same in --quick and full runs, so the BOM is too): "
         + (", ".join(must) if must else "none") + ". The BOM marks their parts."),
        _offset_paragraph(metrics["matching"].get("offset_limit"))],
        tables=[Table("Spread per tolerance class", ["class"] + obs_names, rows),
                Table("Spread per model parameter (all tolerances): which part to trim - tau_m: R "
                      "and C; Delta: the sense resistors R_S and references; a: R_F, the force "
                      "reference, the integrator offset and the current-source mismatch; gamma: "
                      "R_N, C and the DAC level; offset: the integrator op-amp's offset at the ADC. "
                      "Last column: total spread / standard error of the nominal board's estimate "
                      "(below 1: the tolerances are not resolved at this statistical error).",
                      ["observable", "tau_m", "Delta", "a", "gamma", "epsilon", "ADC offset",
                       "total", "total / nominal se"], crow),
                Table("Parameter spread per tolerance class (absolute)", ["class", "tau_m", "Delta",
                      "a", "gamma", "epsilon", "ADC offset"], prow, collapsed=True)]))

    # ------------------------------------------------------------------ calibration
    ce = metrics["calibration_errors"]
    rows = [[p, _pm(ce[p]["rel"]), ce[p]["max_abs_rel"]] for p in ("tau_m", "delta", "a", "gamma", "epsilon")
            if p in ce]
    rows.append(["gamma (OU variance route)", _pm(ce["gamma_variance_route"]["rel"]),
                 ce["gamma_variance_route"]["se_rel"]])
    sections.append(Section("Acquisition and calibration", paragraphs=[
        "ADC: " + "; ".join(f"{k}: {v}" for k, v in ADC_SPEC.items()),
        ("Procedure (analogue.board.calibration): tau_m from friction-off step responses at ±10 V "
        "force; Delta from the terminal velocities with friction on at ±10 V; a from the drift "
        "(offset force of the step responses plus the friction asymmetry); epsilon (the bridge "
        "width) from the stuck velocities at a force of ±Delta/2; D (gamma) by regressing "
        "the friction-off Ornstein-Uhlenbeck response on the known DAC sequence, and by the OU "
        "variance (shown for comparison, with its standard error)."),
        ("Errors: calibrated minus the board's first-order effective parameters (from its drawn "
        "parts), relative, mean ± spread over the Monte Carlo boards.")],
        tables=[Table("Calibration errors", ["parameter", "relative error", "max |rel| (or se)"], rows)]))

    # ------------------------------------------------------------------ bench
    sections.append(_bench_section(design, metrics))

    sections.append(Section("Provenance", paragraphs=[
        (f"Seeds: {prov['seeds']}; ngspice {prov['ngspice_version']}; wall time {prov['wall_time_s']:.0f} s "
        f"({', '.join(f'{k} {v:.0f}' for k, v in prov['timings_s'].items())}); settings {st}.")]))

    intro = [(f"Board for experiment {exp.name}: tau_m = {exp.model.tau_m:g}, Delta = {exp.model.delta:g}, "
             f"a = {exp.model.a:g}, gamma = {exp.model.gamma:g}."),
             "Everything on this page was produced by `analogue board`; metrics.json holds the numbers."]
    return write_page(out / "index.html", f"A board you can build: {exp.name}", intro, sections)


def _bench_section(design, metrics) -> Section:
    """The bench procedure with named instruments, and the bench checks of this run."""
    s = design.spec
    rate = 1.0 / design.noise_ts
    b = metrics["bench"]
    cm = b["common_mode"]["instances"]
    rows = [[inst, r["part"], r["role"], f"[{r['range'][0]:g}, {r['range'][1]:g}]", r["min"], r["max"],
             min(r["margin_low"], r["margin_high"])] for inst, r in cm.items()]
    rf = b["residual_friction"]
    rs = b["reset_start"]
    steps = [
        "Instruments: a dual bench supply (Keysight E36313A or Rigol DP832: +-15 V, current "
        "limit 100 mA per rail) into J6; a synchronous DAQ (NI USB-6363: AO0 noise into J1, AO1 "
        "force into J2, AO2 IC voltage into J3, AI0 from J4, port-0 lines EN and RESET on J5, all "
        f"on one sample clock at {rate / 1e3:g} kS/s); a 4.5-digit DMM for the DC checks. A "
        "function generator and a scope cannot do it: the noise must be the seeded sequence "
        "(analogue.board.noise_chain.dac_sequence), replayed sample by sample and recorded on "
        "the same clock.",
        "0. Order: the DAQ's outputs at 0 V (or its task stopped) until the supply is on. "
        "Should it drive an unpowered board anyway, R11 (J3), R12/R13 (J5) and R6 + R7 (J1) "
        "hold every pin's current inside its rating (table below); R14/R15 hold EN and RESET "
        "low (friction off, switches open) while the DAQ's lines float.",
        "1. Power: supply at +-15 V with the limit set; DMM on TP5/TP6: +15 V - "
        f"{s.v_set:g} V and -15 V + {s.v_set:g} V within 5 mV (references and servos working).",
        "2. Enable low (EN = 0), RESET = 1, AO0 = 0 V: DMM on TP2 (OUT) follows -AO2 (the IC "
        "network); TP3/TP4 float (friction off).",
        "3. Calibration (analogue.board.calibration, about 50 tau_m of records): friction-off step "
        "responses with EN = 0 at AO1 = +-10 V (tau_m, force gain and offset); terminal "
        "velocities with EN = 1 at +-10 V (Delta and its asymmetry); stuck velocities with EN = 1 "
        "at a force of +-Delta/2 (the bridge width epsilon); an OU record with EN = 0, "
        "AO1 = 0 and the noise sequence playing (gamma by regression on the known sequence). "
        "Enter the fitted parameters in the comparison.",
        f"4. A transient run: RESET = 1 with AO2 = ic_voltage(v0) for {RESET_TIME * 1e3:g} ms "
        f"(R10 = R11 = {R_IC / 1e3:g} kOhm, time constant {R_IC * design.values['C'] * 1e6:g} us), "
        "then on one clock edge RESET = 0, EN = 1 and the noise sequence starts; record AI0 for "
        "the run length. Repeat with the next seed for every replica.",
        f"5. Record lengths: at theta = {design.theta * 1e3:g} ms one tau_m is "
        f"{design.theta * design.model.tau_m * 1e3:g} ms, so the full job's 32 replicas x 40 tau_m "
        f"are {32 * 40 * design.theta * design.model.tau_m:.2g} s of data and a 10^4 tau_m "
        f"stationary record {1e4 * design.theta * design.model.tau_m:.3g} s (16-bit samples at "
        f"{rate / 1e3:g} kS/s: {2 * rate * 1e4 * design.theta / 1e6:.3g} MB).",
    ]
    checks = [
        f"Common mode: every op-amp input stayed inside its part's guaranteed range over a 1 tau_m "
        f"transient from v0 = +-2; smallest margin {b['common_mode']['min_margin']:.2f} V.",
        f"Friction off: with EN = 0, the MOSFET threshold at {rf['mosfet_vto']:g} V (datasheet "
        f"minimum) and the servos at their guaranteed swing ({rf['servo']}), the largest friction "
        f"current over the settled +-10 V calibration steps was {rf['max_A'] * 1e9:.3g} nA = "
        f"{rf['relative_to_I0']:.2g} I_0 (the bridge diodes' own saturation current and leakage); "
        f"while the output slews, the switches' 9 pF at the floating bridge nodes carry up to "
        f"{rf['capacitive_peak_A'] * 1e9:.3g} nA of C dV/dt (0.2 % of C1, part of the measured tau_m).",
        f"Reset start: released after {rs['reset_time_s'] * 1e3:g} ms the board starts at "
        f"v = {rs['initial'][0]:.5f} / {rs['initial'][1]:.5f} (target +-2) and follows the .ic start "
        f"on the same noise to {rs['rms_vs_ic_start']:.2g} rms over 1 tau_m.",
        "Over-range: an output at its rail (power-up, an overdriven input) does not latch: the "
        "bridge's top node sits a diode drop above the lower of V(sj) and V(out) and its bottom "
        "node a drop below the higher, so with the virtual ground held both sources stay in "
        "regulation and friction stays two-sided; from +-14.8 V the board is back inside the "
        "machine unit within one tau_m (test_an_output_at_its_rail_does_not_latch). Every run "
        "still starts with step 4's reset, which sets v0.",
    ]
    tables = [Table("Op-amp inputs against their guaranteed common-mode range (V)",
                    ["instance", "part", "role", "guaranteed range", "min", "max", "margin"], rows)]
    if "stresses" in b:
        st = b["stresses"]
        checks.append(
            "Ratings: over the bench modes simulated here (" + "; ".join(st["modes"]) + ") "
            + ("every part stayed inside its absolute maximum ratings" if st["all_ok"]
               else "SOME PART LEFT ITS ABSOLUTE MAXIMUM RATINGS") + " (worst case per part "
            "below; an output at its rail is checked in test_board_ratings.py).")
        tables.append(Table("Worst stress per part over the bench modes, against its absolute "
                            "maximum rating", ["part", "quantity", "worst", "limit", "unit",
                                               "mode", "inside"],
                            [[r["part"], r["quantity"], r["worst"], r["limit"], r["unit"],
                              r["mode"], "yes" if r["ok"] else "NO"] for r in st["rows"]]))
    if "unpowered_inputs" in b:
        tables.append(Table("DAQ outputs into an unpowered board: the first IC pin each reaches, "
                            "the series resistance on the board and the current into that pin "
                            "(a diode drop from its unpowered rails)",
                            ["connector", "pin", "net", "DAQ V", "first IC pin", "series ohm",
                             "current A", "pin limit A", "inside"],
                            [[r["connector"], r["pin"], r["net"], r["volts"], r["first_pin"],
                              r["series_ohm"], r["current_A"], r["limit_A"],
                              "yes" if r["ok"] else "NO"] for r in b["unpowered_inputs"]]))
    return Section("Bench procedure and bench checks", paragraphs=steps + checks, tables=tables)
