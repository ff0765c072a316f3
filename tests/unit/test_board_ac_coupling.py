"""Issue 21 item 6: the AC-coupling capacitor (R_N C_AC = 156 tau_m) never settled in a run.
It is dropped by default: absent from all four outputs built from the design object (BOM,
schematic, KiCad netlist, SPICE deck); the offsets it blocked are a constant force that the
tolerance model carries and ngspice shows settled within a step response; the option
``ac_corner`` still builds a consistent board with it."""
import re

import pytest

from analogue import Model
from analogue.board import tolerance
from analogue.board.bom import bom_rows
from analogue.board.components import board_components
from analogue.board.design import BoardSpec, design_board
from analogue.board.kicad import kicad_netlist
from analogue.board.netlist import build_board_deck, nominal_instance
from analogue.board.noise_chain import ou_variance_factor

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
DESIGN = design_board(STICK, v0=[2.0, -2.0])
WITH_AC = design_board(STICK, v0=[2.0, -2.0], spec=BoardSpec(ac_corner=0.001))


def _outputs(design, tmp_path):
    from analogue.board.schematic import draw_schematic
    bom = " ".join(" ".join(map(str, r)) for r in bom_rows(design))
    svg = draw_schematic(design, tmp_path / "s.svg").read_text(encoding="utf-8")
    svg = " ".join(re.findall(r">([^<>]+)</tspan>", svg))
    net = kicad_netlist(design, date="2026-01-01")
    deck = build_board_deck(design, nominal_instance(design), v0=[0.0], t_end=0.05,
                            sample_dt=0.01, seed=1, noise_dir=tmp_path).text
    return bom, svg, net, deck


def test_no_coupling_capacitor_in_any_output(tmp_path):
    assert "C_AC" not in DESIGN.values
    assert "C4" not in {p.ref for p in board_components(DESIGN)}
    bom, svg, net, deck = _outputs(DESIGN, tmp_path)
    assert not re.search(r"\bC4\b", bom) and not re.search(r"\bC4\b", svg)
    assert '(ref "C4")' not in net and "(ref C4)" not in net
    assert not re.search(r"^C0ac ", deck, re.M)
    # R_N driven by the Bessel buffer's output directly, in the deck and on the board
    assert re.search(r"^R0n bo0 \S+ ", deck, re.M)
    r5 = next(p for p in board_components(DESIGN) if p.ref == "R5")
    assert {q[2] for q in r5.pins} == {"BO", "SJ"}


def test_the_option_keeps_all_four_outputs_consistent(tmp_path):
    c = WITH_AC.values["C_AC"]
    assert 0.9 < c * WITH_AC.values["R_N"] / WITH_AC.theta / 156.0 < 1.1   # tau_m/(2 pi 0.001), rounded to E12
    bom, svg, net, deck = _outputs(WITH_AC, tmp_path)
    assert re.search(r"\bC4\b", bom) and re.search(r"\bC4\b", svg) and "C4" in net
    assert re.search(r"^C0ac bo0 ac0 ", deck, re.M) and re.search(r"^R0n ac0 ", deck, re.M)


def test_what_a_settling_capacitor_would_cost():
    # sized to settle in the burn-in (5 R_N C_AC = 2 tau_m) it removes most of the noise the
    # velocity sees; without it the chain loses only the DAC hold's and Bessel's share
    v = dict(DESIGN.values)
    lam = 1.0 / DESIGN.theta
    plain = ou_variance_factor(v, DESIGN.noise_ts, lam)
    settling = ou_variance_factor({**v, "C_AC": 0.4 * DESIGN.theta / v["R_N"]}, DESIGN.noise_ts, lam)
    assert plain > 0.999 and settling < 0.3
    assert ou_variance_factor(WITH_AC.values, DESIGN.noise_ts, lam) < plain - 0.005


def test_effective_model_carries_the_offsets_across_r_n():
    b = nominal_instance(DESIGN)
    amps = dict(b.opamps)
    base = tolerance.effective_model(DESIGN, b).a
    amps["bf"] = amps["bf"].replace(vos=3e-3)
    da = tolerance.effective_model(DESIGN, b.replace(opamps=amps)).a - base
    # (vos_int - vos_bf)/R_N in units of the force scale C kappa / theta, computed here
    expect = -3e-3 / DESIGN.values["R_N"] * DESIGN.theta / (DESIGN.values["C"] * DESIGN.kappa)
    assert da == pytest.approx(expect, rel=1e-9) and abs(da) > 0.01
    # with the capacitor the DC path is blocked
    bw = nominal_instance(WITH_AC)
    aw = dict(bw.opamps)
    aw["bf"] = aw["bf"].replace(vos=3e-3)
    assert tolerance.effective_model(WITH_AC, bw.replace(opamps=aw)).a == \
        tolerance.effective_model(WITH_AC, bw).a


@pytest.mark.requires_ngspice
def test_dc_offset_response_settles_within_the_burn_in(tmp_path):
    """ngspice, friction off, noise DAC at mid-scale, no force: a 5 mV offset on the Bessel
    buffer gives the constant force the effective model predicts, settled (the OU step,
    time constant tau_m) before the burn-in of 2 tau_m ends to e^-2 of it, and flat after."""
    from analogue.board.calibration import _run
    b = nominal_instance(DESIGN).replace(enable=False, v_force=0.0)
    amps = dict(b.opamps)
    amps["bf"] = amps["bf"].replace(vos=5e-3)
    b = b.replace(opamps=amps)
    eff = tolerance.effective_model(DESIGN, b)
    t, v = _run(DESIGN, b, t_end=8.0, noise=False, seed=1, noise_dir=tmp_path)
    v_inf = eff.tau_m * eff.a
    assert abs(v_inf) > 0.02
    late = v[t > 6.0]
    assert late.mean() == pytest.approx(v_inf, rel=0.02)
    assert abs(late[-1] - late[0]) < 0.01 * abs(v_inf)     # no slow tail (no 156 tau_m mode)
    at2 = v[t.searchsorted(2.0)]
    assert abs(at2 - v_inf) < 0.2 * abs(v_inf)
