"""The board's inputs with the board unpowered (issue 21): the DAQ is on and driving while the
bench supply is off (power-up order, a supply tripped), so every IC pin an input reaches sits
a diode drop from its unpowered rails and the current into it is set by the series resistance
on the board alone (never by the instrument's current limit).  Checked on the netlist the
BOM, board.net and the schematic are written from (DC: capacitors open, diodes shorted)."""
import math

from analogue import Model
from analogue.board.components import board_components
from analogue.board.design import design_board
from analogue.board.ratings import DAQ_INPUTS, unpowered_inputs

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
DESIGN = design_board(STICK, v0=[2.0, -2.0])


def test_every_input_reaches_its_ic_pins_through_a_resistor_that_limits_the_current():
    rows = unpowered_inputs(board_components(DESIGN))
    # every DAQ output the board takes: noise, force, IC voltage, the two logic lines
    assert {(r["connector"], r["pin"]) for r in rows} == {
        (ref, pin) for ref, pins in DAQ_INPUTS.items() for pin in pins}
    for r in rows:
        assert r["series_ohm"] >= 1e3, r
        assert r["current_A"] <= r["limit_A"], r
        # and the page's number is Ohm's law on that path: a diode drop at the pin
        assert math.isclose(r["current_A"], (r["volts"] - 0.7) / r["series_ohm"])


def test_the_ic_voltage_no_longer_meets_the_switch_pin_directly():
    # the previous board put J3 on U4's pin 15 and the logic lines on the switches' IN pins:
    # 10 V (5 V) into an unpowered DG41x limited only by the DAQ (abs max: a diode drop
    # beyond the rails or 30 mA)
    rows = {(r["connector"], r["pin"]): r for r in unpowered_inputs(board_components(DESIGN))}
    ic, en, reset = rows[("J3", 1)], rows[("J5", 1)], rows[("J5", 2)]
    assert ic["first_pin"].startswith("U4 ")
    assert en["first_pin"].startswith("U3 ") and reset["first_pin"].startswith("U4 ")
    assert ic["current_A"] < 1e-3                # 10 kOhm: 0.93 mA
    assert en["current_A"] < 5e-3 and reset["current_A"] < 5e-3      # 1 kOhm: 4.3 mA


def test_the_board_page_quotes_these_currents():
    # docs/board/README.md quotes the unpowered currents: they must be today's (issue 21 item 12)
    from pathlib import Path
    rows = {(r["connector"], r["pin"]): r for r in unpowered_inputs(board_components(DESIGN))}
    text = " ".join((Path(__file__).parents[2] / "docs" / "board" / "README.md").read_text().split())
    ma = {k: f"{r['current_A'] * 1e3:.2g} mA" for k, r in rows.items()}
    for quoted in (f"({ma[('J3', 1)]} at 10 V, DG412 30 mA)", f"({rows[('J5', 1)]['series_ohm'] / 1e3:g} "
                   f"kOhm: {ma[('J5', 1)]} at 5 V)", f"({ma[('J1', 1)]} into U1B, 10 mA)"):
        assert quoted in text, quoted


def test_each_rail_has_a_clamp_that_stops_it_going_the_wrong_way():
    # reverse-biased Schottkys from ground to +15 V and from -15 V to ground: a rail pulled
    # past ground (supply outputs switched on one after the other, leads swapped at J6) is
    # held a Schottky drop from it
    parts = {p.ref: p for p in board_components(DESIGN)}
    clamps = {}
    for p in parts.values():
        if p.kind == "D" and p.mpn == parts["D5"].mpn:
            pins = {name: net for _num, name, net in p.pins}
            clamps[(pins["A"], pins["K"])] = p.ref
    assert set(clamps) == {("GND", "+15V"), ("-15V", "GND")}
