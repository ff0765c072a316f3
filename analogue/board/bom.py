"""``bom.csv``: reference, part, value, tolerance, dielectric or rating, quantity - from the
design's rounded values (one board, one replica channel)."""
from __future__ import annotations

import csv
from pathlib import Path

from .design import BoardDesign
from .schematic import eng

__all__ = ["HEADER", "bom_rows", "write_bom"]

HEADER = ("reference", "part", "value", "tolerance", "dielectric_or_rating", "quantity")


def bom_rows(design: BoardDesign, matched: tuple = ()) -> list[tuple]:
    """Rows of the bill of materials.  ``matched``: references whose tolerance the tolerance
    analysis says must be tightened (their row then asks for 0.1 % / a matched pair)."""
    v, s = design.values, design.spec
    amp = s.opamp.split("_")[0]

    advice = {"U1,U2": "offset trimmed, or an OPA2140-class integrator (|vos| < 120 uV)",
              "D1-D4": "matched quad (IS within 2 %)", "C1": "0.5 % (C0G) or measured",
              "VR1,VR2": "0.05 % references"}

    def tol(ref, default):
        if ref not in matched:
            return default
        return advice.get(ref, "0.1 % (matched pair / trimmed)")

    rows = [
        ("C1", "capacitor (mass)", eng(v["C"], "F"), tol("C1", "1 %"), "C0G/NP0 50 V or polypropylene film", 1),
        ("R1", "resistor (viscous friction)", eng(v["R"], "Ω"), tol("R1", "1 % E96, 50 ppm/K"), "metal film 0.25 W", 1),
        ("R2,R3", "resistor (current-source sense, top/bottom)", eng(v["R_S"], "Ω"),
         tol("R2,R3", "1 % E96, 50 ppm/K"), "metal film 0.25 W", 2),
        ("R4", "resistor (force input)", eng(v["R_F"], "Ω"), tol("R4", "1 % E96"), "metal film 0.25 W", 1),
        ("R5", "resistor (noise input)", eng(v["R_N"], "Ω"), tol("R5", "1 % E96"), "metal film 0.25 W", 1),
        ("R6,R7", "resistor (Bessel low-pass)", eng(v["R_B1"], "Ω"), "1 % E96", "metal film 0.25 W", 2),
        ("C2", "capacitor (Bessel, feedback)", eng(v["C_B1"], "F"), "5 %", "C0G/NP0 50 V", 1),
        ("C3", "capacitor (Bessel, to ground)", eng(v["C_B2"], "F"), "5 %", "C0G/NP0 50 V", 1),
        ("C4", "capacitor (AC coupling)", eng(v["C_AC"], "F"), "10 %", "polypropylene/PET film 50 V (not electrolytic: leakage)", 1),
        ("D1-D4", f"diode {s.diode} (bridge; a matched quad or one reel lot)", s.diode, tol("D1-D4", "IS within 10 %"),
         "100 V, 200 mA" if s.diode == "1N4148" else "30 V, 200 mA", 4),
        ("Q1", "P-MOSFET (sourcing current source), BSS84 class", "BSS84-class", "-", "-50 V, 130 mA", 1),
        ("Q2", "N-MOSFET (sinking current source), 2N7002 class", "2N7002-class", "-", "60 V, 300 mA", 1),
        ("U1,U2", f"dual op-amp {amp} (integrator + Bessel buffer; two current-source servos)", amp,
         tol("U1,U2", "offset as datasheet"), "+-15 V supply", 2),
        ("VR1,VR2", "2.5 V shunt reference (current-source set points), LM4040 class", f"{s.v_set:g} V",
         tol("VR1,VR2", "0.1 %"), "from the rails through 10 kΩ", 2),
        ("VR3", "force reference / force DAC channel", f"{s.v_force:g} V (calibration: ±10 V)", "0.1 %", "-", 1),
        ("U3", f"DAC {s.dac_bits} bit, ±{s.dac_range:g} V, {eng(1 / design.noise_ts, 'S/s')} (seeded Gaussian noise)",
         f"{s.dac_bits} bit", "INL 1 LSB", "bipolar output", 1),
        ("U4", "ADC, DC-coupled, simultaneous sampling, ±10 V, 16 bit", "16 bit",
         "INL 2 LSB", f"{eng(1 / design.noise_ts, 'S/s')} per channel", 1),
        ("C5-C8", "supply decoupling", "100 nF", "10 %", "X7R 50 V (decoupling only)", 4),
    ]
    return rows


def write_bom(design: BoardDesign, path, matched: tuple = ()) -> Path:
    path = Path(path)
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(HEADER)
        w.writerows(bom_rows(design, matched))
    return path
