"""Every part of one board channel, with its pins and nets: the one design object from which
``bom.csv``, ``board.net`` (KiCad) and ``schematic.svg`` are written (issue 21).

:func:`board_components` turns a :class:`~analogue.board.design.BoardDesign` into
:class:`Part` rows (designator, value, manufacturer part number and a second source, KiCad
footprint, pins -> nets).  The values are the design's E-series values, the same numbers
:func:`analogue.board.netlist.build_board_deck` writes into the SPICE deck; ``spice`` names
the deck element of replica 0 that each passive part is, so a test can compare the two files
part by part.

Part numbers follow the manufacturers' ordering codes (E96 value codes for the resistors,
EIA capacitance codes); they were written without a distributor at hand, so check stock and
the exact suffix (reel, lead finish) when ordering.  Where a second source is not
pin-compatible the row says so.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .design import BoardDesign
from .netlist import R_IC

__all__ = ["Part", "board_components", "nets"]

R0805 = "Resistor_SMD:R_0805_2012Metric"
C0805 = "Capacitor_SMD:C_0805_2012Metric"
C1206 = "Capacitor_SMD:C_1206_3216Metric"
C1210 = "Capacitor_SMD:C_1210_3225Metric"
SOIC8 = "Package_SO:SOIC-8_3.9x4.9mm_P1.27mm"
SOIC16 = "Package_SO:SOIC-16_3.9x9.9mm_P1.27mm"
SOT23 = "Package_TO_SOT_SMD:SOT-23"
SOT89 = "Package_TO_SOT_SMD:SOT-89-3"
SOD123 = "Diode_SMD:D_SOD-123"
SOD123F = "Diode_SMD:D_SOD-123F"
BNC = "Connector_Coaxial:BNC_TEConnectivity_1478204_Vertical"
HDR3 = "Connector_PinHeader_2.54mm:PinHeader_1x03_P2.54mm_Vertical"
TB3 = "TerminalBlock_Phoenix:TerminalBlock_Phoenix_MKDS-1,5-3-5.08_1x03_P5.08mm_Horizontal"
TP = "TestPoint:TestPoint_Keystone_5000-5004_Miniature"
FILM = "Capacitor_THT:C_Rect_L31.5mm_W17.0mm_P27.50mm_MKS4"

# dual op-amp, SOIC-8 (the industry pin-out): 1 OUTA 2 INA- 3 INA+ 4 V- 5 INB+ 6 INB- 7 OUTB 8 V+
# DG412/DG413, SOIC-16: 1 IN1 2 D1 3 S1 4 V- 5 GND 6 S4 7 D4 8 IN4 9 IN3 10 D3 11 S3 12 VL 13 V+
# 14 S2 15 D2 16 IN2 (DG413: switches 1 and 4 close on logic 1, 2 and 3 on logic 0)
DG41X_PINS = ("IN1", "D1", "S1", "V-", "GND", "S4", "D4", "IN4", "IN3", "D3", "S3", "VL", "V+",
              "S2", "D2", "IN2")


# what "tighten" means per kind of part, when the tolerance analysis flags its class
MATCH_ADVICE = {"R": "0.1 %, 25 ppm/K",
                "C": "0.5 % C0G, or measured and entered in the calibration",
                "U": "guaranteed offset below the limit on the board page (precision part, or trimmed)",
                "VR": "0.05 % (LM4040A25 is 0.1 %: select or use an ADR4525)",
                "D": "matched quad (IS within 2 %)"}


@dataclass(frozen=True)
class Part:
    """One designator: ``pins`` is ((number, name, net), ...); ``off_board`` parts (the bench
    instruments) are in the BOM but not in the KiCad netlist."""

    ref: str
    value: str
    description: str
    manufacturer: str
    mpn: str
    second_source: str
    footprint: str
    pins: tuple
    tolerance: str = "-"
    rating: str = "-"
    spice: str = ""
    numeric: float = math.nan
    kind: str = "device"          # R, C, D, Q, U, J, TP, instrument
    off_board: bool = False


def _rkm(x: float, digits: int) -> str:
    """Resistance code with the multiplier as decimal point: 9310 -> '9K31', 402e3 -> '402K'."""
    for mult, letter in ((1e6, "M"), (1e3, "K"), (1.0, "R")):
        if x >= mult * 0.9999:
            v = x / mult
            s = f"{v:.{digits}g}"
            if "." in s:
                a, b = s.split(".")
            else:
                a, b = s, ""
            if digits == 4:                 # Vishay TNPW: four characters, zero-padded
                b = (b + "000")[: max(0, 3 - len(a))]
            return f"{a}{letter}{b}"
    raise ValueError(f"resistance {x} out of range")


def eng(x: float, unit: str) -> str:
    """Engineering notation: 4.42e3 -> '4.42 k' + unit (the schematic's labels; here, below
    :mod:`.schematic`, which imports this module, so that the two do not import each other)."""
    if x == 0:
        return f"0 {unit}"
    prefixes = [(1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"),
                (1e-9, "n"), (1e-12, "p")]
    for scale, p in prefixes:
        if abs(x) >= scale * 0.999:
            return f"{x / scale:.3g} {p}{unit}"
    return f"{x:.3g} {unit}"


def _eng(x: float, unit: str) -> str:
    return eng(x, unit).replace(" ", "")


def _cap_code(x: float) -> str:
    """EIA code in pF: 270e-12 -> '271', 10e-9 -> '103'."""
    pf = x * 1e12
    exp = int(math.floor(math.log10(pf))) - 1
    return f"{round(pf / 10 ** exp):02d}{exp}"


def _era_code(x: float) -> str:
    """Panasonic four-digit resistance code: 3320 -> '3321', 100e3 -> '1003'."""
    exp = int(math.floor(math.log10(x))) - 2
    return f"{round(x / 10 ** exp):03d}{exp}"


def _resistor(ref, value, net1, net2, desc, spice="", tol="1 %, 50 ppm/K") -> Part:
    if tol.startswith("0.1 %"):      # flagged for matching: a 0.1 % part, not a 1 % one
        return Part(ref, _eng(value, "Ω"), desc, "Vishay", f"TNPW0805{_rkm(value, 4)}BEEA",
                    f"Panasonic ERA-6AEB{_era_code(value)}V (0.1 %, 25 ppm/K)", R0805,
                    ((1, "1", net1), (2, "2", net2)), tol, "thin film 0805, 0.125 W", spice,
                    value, "R")
    return Part(ref, _eng(value, "Ω"), desc, "Yageo", f"RT0805FRE07{_rkm(value, 3)}L",
                f"Vishay TNPW0805{_rkm(value, 4)}BEEA (0.1 %, 25 ppm/K)", R0805,
                ((1, "1", net1), (2, "2", net2)), tol, "thin film 0805, 0.125 W", spice, value, "R")


def _c0g(ref, value, net1, net2, desc, spice="", tol="5 %") -> Part:
    code = _cap_code(value)
    return Part(ref, _eng(value, "F"), desc, "KEMET", f"C0805C{code}J5GACTU",
                f"Murata GRM2165C1H{code}JA01D", C0805, ((1, "1", net1), (2, "2", net2)), tol,
                "C0G/NP0 50 V", spice, value, "C")


def _decoupling(ref, net, ic) -> Part:
    return Part(ref, "100nF", f"decoupling of {ic} ({net} pin)", "KEMET", "C0805C104K5RACTU",
                "Murata GRM21BR71H104KA01L", C0805, ((1, "1", net), (2, "2", "GND")), "10 %",
                "X7R 50 V", "", 100e-9, "C")


def board_components(design: BoardDesign, matched: tuple = ()) -> list[Part]:
    """All parts of one channel (see module docstring).  ``matched``: designators whose
    tolerance the tolerance analysis asks to tighten (:func:`analogue.board.job.recommend_matching`)."""
    v, s = design.values, design.spec
    amp = s.opamp.split("_")[0]
    servo = s.servo_opamp.split("_")[0]
    def tol(ref, default):
        if ref not in matched:
            return default
        return MATCH_ADVICE.get(ref.rstrip("0123456789"), "0.1 %")

    rate = 1.0 / design.noise_ts
    ac = "C_AC" in v      # AC coupling only where BoardSpec.ac_corner asks for it
    parts = [
        # ---------------------------------------------------------------- integrator
        Part("C1", _eng(v["C"], "F"), "mass capacitor (integrator feedback)", "TDK",
             f"C3216C0G1H{_cap_code(v['C'])}F160AA", f"KEMET C1206C{_cap_code(v['C'])}F5GACTU",
             C1206, ((1, "1", "SJ"), (2, "2", "OUT")), tol("C1", "1 %"), "C0G/NP0 50 V",
             "C0m", v["C"], "C"),
        _resistor("R1", v["R"], "SJ", "OUT", "viscous resistor (integrator feedback)", "R0v",
                  tol("R1", "1 %, 50 ppm/K")),
        Part("U1", amp, f"dual op-amp: A integrator, B Bessel buffer ({amp})", "Texas Instruments",
             {"TL072": "TL072CDR", "OPA2140": "OPA2140AIDR", "OPA2197": "OPA2197IDR"}[amp],
             {"TL072": "STMicroelectronics TL072CDT", "OPA2140": "Analog Devices ADA4610-2ARZ",
              "OPA2197": "Analog Devices ADA4084-2ARZ"}[amp], SOIC8,
             ((1, "OUTA", "OUT"), (2, "INA-", "SJ"), (3, "INA+", "GND"), (4, "V-", "-15V"),
              (5, "INB+", "B2"), (6, "INB-", "BO"), (7, "OUTB", "BO"), (8, "V+", "+15V")),
             tol("U1", "offset as datasheet"), "+-15 V", "", math.nan, "U"),
        # ---------------------------------------------------------------- bridge
        *[Part(f"D{i}", s.diode, f"bridge diode {i}", "Diodes Inc.", "1N4148W-7-F",
               "Vishay 1N4148W-E3-08", SOD123, ((1, "K", k), (2, "A", a)),
               "one reel lot (IS within 10 %)", "100 V, 150 mA", "", math.nan, "D")
          for i, (a, k) in enumerate((("BR_TOP", "SJ"), ("BR_TOP", "OUT"), ("SJ", "BR_BOT"),
                                      ("OUT", "BR_BOT")), 1)],
        # ---------------------------------------------------------------- current sources
        Part("U2", servo, f"dual op-amp: current-source servos A top, B bottom ({servo}, "
             "rail-to-rail input: its inputs sit v_set from a rail)", "Texas Instruments",
             "OPA2197IDR", "Analog Devices ADA4084-2ARZ", SOIC8,
             ((1, "OUTA", "GATE_T"), (2, "INA-", "SNS_T"), (3, "INA+", "REF_T"), (4, "V-", "-15V"),
              (5, "INB+", "REF_B"), (6, "INB-", "SNS_B"), (7, "OUTB", "GATE_B"), (8, "V+", "+15V")),
             "offset as datasheet", "+-15 V (36 V max)", "", math.nan, "U"),
        _resistor("R2", v["R_S"], "+15V", "SNS_T", "sense resistor, sourcing source (I_0 = v_set/R_S)",
                  "Rb0st", tol("R2", "1 %, 50 ppm/K")),
        _resistor("R3", v["R_S"], "SNS_B", "-15V", "sense resistor, sinking source", "Rb0sb",
                  tol("R3", "1 %, 50 ppm/K")),
        Part("Q1", "BSS84", "P-MOSFET, sourcing current source", "Nexperia", "BSS84,215",
             "onsemi BSS84LT1G", SOT23, ((1, "G", "GATE_T"), (2, "S", "SNS_T"), (3, "D", "DRAIN_T")),
             "-", "-50 V, 130 mA, VGS(th) -0.8 to -2.0 V", "", math.nan, "Q"),
        Part("Q2", "2N7002", "N-MOSFET, sinking current source", "Nexperia", "2N7002,215",
             "onsemi 2N7002LT1G", SOT23, ((1, "G", "GATE_B"), (2, "S", "SNS_B"), (3, "D", "DRAIN_B")),
             "-", "60 V, 300 mA, VGS(th) 0.8 to 2.5 V (simulated at 0.8)", "", math.nan, "Q"),
        Part("VR1", f"{s.v_set:g}V", "shunt reference: REF_T = +15 V - v_set", "Texas Instruments",
             "LM4040AIM3-2.5/NOPB", "Analog Devices LM4040AIM3-2.5+T", SOT23,
             ((1, "K", "+15V"), (2, "A", "REF_T"), (3, "NC", "")), tol("VR1", "0.1 %"),
             "60 uA-15 mA", "", math.nan, "U"),
        Part("VR2", f"{s.v_set:g}V", "shunt reference: REF_B = -15 V + v_set", "Texas Instruments",
             "LM4040AIM3-2.5/NOPB", "Analog Devices LM4040AIM3-2.5+T", SOT23,
             ((1, "K", "REF_B"), (2, "A", "-15V"), (3, "NC", "")), tol("VR2", "0.1 %"),
             "60 uA-15 mA", "", math.nan, "U"),
        _resistor("R8", 12.4e3, "REF_T", "GND", "bias of VR1 (1.0 mA)", tol="1 %"),
        _resistor("R9", 12.4e3, "GND", "REF_B", "bias of VR2 (1.0 mA)", tol="1 %"),
        # ---------------------------------------------------------------- enable and reset
        Part("U3", "DG413", "friction enable: SPDT per source, drain to bridge (EN high) or to "
             "ground (EN low)", "Vishay", "DG413DY-E3", "Analog Devices DG413DY+", SOIC16,
             tuple((i, n, net) for i, (n, net) in enumerate(zip(DG41X_PINS, (
                 "EN", "DRAIN_T", "BR_TOP", "-15V", "GND", "BR_BOT", "DRAIN_B", "EN", "EN",
                 "DRAIN_B", "GND", "+5V", "+15V", "GND", "DRAIN_T", "EN")), 1)),
             "-", "+-15 V, R_on 35 ohm max, 0.25 nA off leakage", "Sb0et", math.nan, "U"),
        Part("U4", "DG412", "reset switch across C (SW1, with R10) and IC switch (SW2, with R11); "
             "SW3/SW4 spare, inputs grounded", "Vishay", "DG412DY-E3", "Analog Devices DG412DY+",
             SOIC16, tuple((i, n, net) for i, (n, net) in enumerate(zip(DG41X_PINS, (
                 "RESET", "OUT", "RST_R", "-15V", "GND", "", "", "GND", "GND", "", "", "+5V",
                 "+15V", "SJ", "IC_R", "RESET")), 1)),
             "-", "+-15 V, R_on 35 ohm max, 5 pC charge injection", "S0r", math.nan, "U"),
        _resistor("R10", R_IC, "RST_R", "SJ", "reset resistor R_IC across C (through U4 SW1)", "R0r"),
        # R11 on the connector's side of SW2: with the bench supply off it limits what the
        # DAQ's +-10 V pushes into U4's pin to 0.93 mA (issue 21; abs max 30 mA)
        _resistor("R11", R_IC, "IC_IN", "IC_R", "IC input resistor R_IC (J3 to U4 SW2)", "R0i"),
        # logic lines: series resistors limit a 5 V line into an unpowered DG41x to 4.3 mA;
        # pull-downs hold EN and RESET low (friction off, switches open) while the DAQ's lines
        # float at power-up (the logic high still reaches 4.95 V, VINH 2.4 V)
        _resistor("R12", 1e3, "EN_IN", "EN", "series resistor of the enable line (J5 pin 1)",
                  tol="1 %, 50 ppm/K"),
        _resistor("R13", 1e3, "RESET_IN", "RESET", "series resistor of the reset line (J5 pin 2)",
                  tol="1 %, 50 ppm/K"),
        _resistor("R14", 100e3, "EN", "GND", "pull-down of EN (friction off at power-up)",
                  tol="1 %, 50 ppm/K"),
        _resistor("R15", 100e3, "RESET", "GND", "pull-down of RESET (switches open at power-up)",
                  tol="1 %, 50 ppm/K"),
        # ---------------------------------------------------------------- force and noise
        _resistor("R4", v["R_F"], "FORCE_IN", "SJ", "force resistor, I_F = V_F/R_F", "R0f",
                  tol("R4", "1 %, 50 ppm/K")),
        _resistor("R5", v["R_N"], "AC" if ac else "BO", "SJ", "noise resistor, I_n = V_n/R_N", "R0n",
                  tol("R5", "1 %, 50 ppm/K")),
        _resistor("R6", v["R_B1"], "NOISE_IN", "B1", "Bessel low-pass resistor", "Rn0b1"),
        _resistor("R7", v["R_B2"], "B1", "B2", "Bessel low-pass resistor", "Rn0b2"),
        _c0g("C2", v["C_B1"], "B1", "BO", "Bessel low-pass feedback capacitor", "Cn0b1"),
        _c0g("C3", v["C_B2"], "B2", "GND", "Bessel low-pass capacitor to ground", "Cn0b2"),
        *([Part("C4", _eng(v["C_AC"], "F"), "AC-coupling capacitor of the noise chain", "WIMA",
                f"MKS4 {_eng(v['C_AC'], 'F')} 63 V (MKS4D series)", "KEMET R60 series, same value",
                FILM, ((1, "1", "BO"), (2, "2", "AC")), "10 %", "polyester film 63 V (not "
                "electrolytic: leakage)", "C0ac", v["C_AC"], "C")] if ac else []),
        # ---------------------------------------------------------------- power
        Part("U5", "78L05", "+5 V for the switches' logic supply (VL)", "STMicroelectronics",
             "L78L05ABUTR", "onsemi MC78L05ACHT1G", SOT89,
             ((1, "OUT", "+5V"), (2, "GND", "GND"), (3, "IN", "+15V")), "5 %", "30 V in, 100 mA",
             "", math.nan, "U"),
        Part("C17", "10uF", "bulk decoupling, +15 V entry", "Murata", "GRM32ER71H106KA12L",
             "TDK C3225X7R1H106K250AC", C1210, ((1, "1", "+15V"), (2, "2", "GND")), "10 %",
             "X7R 50 V", "", 10e-6, "C"),
        Part("C18", "10uF", "bulk decoupling, -15 V entry", "Murata", "GRM32ER71H106KA12L",
             "TDK C3225X7R1H106K250AC", C1210, ((1, "1", "GND"), (2, "2", "-15V")), "10 %",
             "X7R 50 V", "", 10e-6, "C"),
        # rail clamps at the power entry: reverse-biased in use; a rail pulled the wrong way
        # (one output of the supply on before the other, the ICs' quiescent current from V+
        # to V- lifting the idle rail; leads swapped at J6) stops a Schottky drop past
        # ground, inside the ICs' supply ratings, and a swapped supply runs into its 100 mA
        # limit through them
        *[Part(ref, "MBR140", f"rail clamp: Schottky from {a} to {k}", "onsemi", "MBR140SFT1G",
               "Nexperia PMEG4010CEH (40 V, 1 A, SOD-123F)", SOD123F, ((1, "K", k), (2, "A", a)),
               "-", "40 V, 1 A", "", math.nan, "D")
          for ref, a, k in (("D5", "GND", "+15V"), ("D6", "-15V", "GND"))],
        Part("C16", "330nF", "input capacitor of U5", "KEMET", "C0805C334K5RACTU",
             "Murata GRM21BR71H334KA01L", C0805, ((1, "1", "+15V"), (2, "2", "GND")), "10 %",
             "X7R 50 V", "", 330e-9, "C"),
    ]
    dec = [("C5", "+15V", "U1"), ("C6", "-15V", "U1"), ("C7", "+15V", "U2"), ("C8", "-15V", "U2"),
           ("C9", "+15V", "U3"), ("C10", "-15V", "U3"), ("C11", "+15V", "U4"), ("C12", "-15V", "U4"),
           ("C13", "+5V", "U3"), ("C14", "+5V", "U4"), ("C15", "+5V", "U5 output")]
    parts += [_decoupling(r, n, ic) for r, n, ic in dec]
    # ---------------------------------------------------------------- connectors, test points
    bnc = [("J1", "NOISE_IN", f"noise input from DAQ AO0 ({rate / 1e3:g} kS/s seeded sequence)"),
           ("J2", "FORCE_IN", "force input from DAQ AO1 (V_F; +-10 V in calibration)"),
           ("J3", "IC_IN", "IC voltage from DAQ AO2 (held during reset)"),
           ("J4", "OUT", "velocity output -kappa v to DAQ AI0 (16 bit, same clock)")]
    parts += [Part(r, "BNC", d, "TE Connectivity", "1-1478204-0", "Amphenol RF 031-5431", BNC,
                   ((1, "SIG", n), (2, "SHIELD", "GND")), "-", "50 ohm", "", math.nan, "J")
              for r, n, d in bnc]
    parts += [
        Part("J5", "1x3 header", "logic from DAQ digital lines (hardware-timed): EN, RESET, GND",
             "Würth Elektronik", "61300311121", "Samtec TSW-103-07-G-S", HDR3,
             ((1, "1", "EN_IN"), (2, "2", "RESET_IN"), (3, "3", "GND")), "-", "2.54 mm", "",
             math.nan, "J"),
        Part("J6", "3-pole terminal", "power entry from the bench supply: +15 V, GND, -15 V",
             "Phoenix Contact", "1935174", "Würth Elektronik 691137710003", TB3,
             ((1, "1", "+15V"), (2, "2", "GND"), (3, "3", "-15V")), "-", "5.08 mm, 13.5 A", "",
             math.nan, "J"),
    ]
    tps = [("TP1", "SJ"), ("TP2", "OUT"), ("TP3", "BR_TOP"), ("TP4", "BR_BOT"), ("TP5", "SNS_T"),
           ("TP6", "SNS_B"), ("TP7", "BO"), ("TP8", "GND")]
    parts += [Part(r, "test point", f"test point {n}", "Keystone", "5000" if n != "GND" else "5001",
                   "Harwin S2751-46R", TP, ((1, "1", n),), "-", "-", "", math.nan, "TP")
              for r, n in tps]
    # ---------------------------------------------------------------- bench instruments
    parts += [
        Part("INST1", "USB-6363", "synchronous DAQ (off board): AO0 noise, AO1 force, AO2 IC "
             "voltage (16 bit, +-10 V), AI0 velocity (16 bit), DO EN/RESET, one sample clock; "
             "the PC streams the seeded sequence (analogue.board.noise_chain.dac_sequence)",
             "NI", "USB-6363 (BNC)", "NI PCIe-6363 (same X-series API)",
             "off board: bench instrument, cables to J1-J5", (), "-", "2 MS/s AI, 2.86 MS/s AO",
             "", math.nan, "instrument", True),
        Part("INST2", "+-15 V supply", "dual bench supply (off board), current limit 100 mA per "
             "rail", "Keysight", "E36313A", "Rigol DP832", "off board: bench instrument, to J6",
             (), "-", "2 x 0-30 V/2 A", "", math.nan, "instrument", True),
    ]
    return parts


def nets(parts: list[Part]) -> dict:
    """Net name -> [(ref, pin number)] over the on-board parts (unconnected pins left out)."""
    out: dict[str, list] = {}
    for p in parts:
        if p.off_board:
            continue
        for num, _name, net in p.pins:
            if net:
                out.setdefault(net, []).append((p.ref, num))
    return dict(sorted(out.items()))
