"""``schematic.svg`` drawn with schemdraw from a :class:`BoardDesign` (values from the design,
never hand-edited).  Two sheets in one drawing: the signal overview (the integrator with C1,
R1 and the diode bridge in its feedback, the two current sources, the force and noise inputs
into the virtual ground, the noise chain, enable and reset) and the parts sheet, on which
every on-board part of :func:`analogue.board.components.board_components` is drawn with its
pins connected by net labels (the nets of ``board.net``): the same designators as the BOM and
the KiCad netlist."""
from __future__ import annotations

from pathlib import Path

from .components import board_components, eng
from .design import BoardDesign

__all__ = ["build_schematic", "draw_schematic", "eng"]


def _parts_sheet(d, design: BoardDesign, origin: tuple) -> None:
    """Every on-board part with its pins on net labels, below the overview: two-pin parts in
    rows of four, then the multi-pin parts (pin number, function and net on each pin)."""
    import schemdraw.elements as elm

    parts = [p for p in board_components(design) if not p.off_board]
    x0, y = origin
    d.add(elm.Label().at((x0, y)).label("Parts sheet: every part, pins on net labels "
                                        "(the nets of board.net)", halign="left", fontsize=13))
    y -= 2.0
    sym = {"R": elm.Resistor, "C": elm.Capacitor, "D": elm.Diode}
    two = [p for p in parts if p.kind in sym and len(p.pins) == 2]
    for i, p in enumerate(two):
        col, row = i % 4, i // 4
        x, yy = x0 + 11.0 * col, y - 3.0 * row
        a, b = p.pins
        if p.kind == "D":     # pins are (K, A): draw anode on the left
            a, b = b, a
        d.add(elm.Line().at((x, yy)).right(0.6).label(a[2], loc="left", fontsize=9))
        d.add(sym[p.kind]().right(3.0).label(f"{p.ref} {p.value}", loc="top", fontsize=10))
        d.add(elm.Line().right(0.6).label(b[2], loc="right", fontsize=9))
    y -= 3.0 * (len(two) // 4 + 1) + 1.0
    multi = [p for p in parts if p not in two]
    col_x = [x0 + 11.0 * c for c in range(4)]
    col_y = [y] * 4
    for p in multi:
        c = col_y.index(max(col_y))
        n = len(p.pins)
        left = [q for k, q in enumerate(p.pins) if k < (n + 1) // 2]
        right = [q for k, q in enumerate(p.pins) if k >= (n + 1) // 2]
        # schemdraw stacks a side's pins from the bottom: pin 1 at the top left, the last pin
        # at the top right (the package's own order)
        pins = [elm.IcPin(name=f"{q[1]} {q[2] or 'NC'}", pin=str(q[0]), side="L") for q in left[::-1]]
        pins += [elm.IcPin(name=f"{q[2] or 'NC'} {q[1]}", pin=str(q[0]), side="R") for q in right]
        h = max(1.5, 0.7 * max(len(left), len(right)) + 0.6)
        d.add(elm.Ic(pins=pins, size=(6.0, h), pinspacing=0.7, edgepadW=0.5, lsize=9, plblsize=8)
              .at((col_x[c] + 4.0, col_y[c] - 0.8 - h / 2)).anchor("center")
              .label(f"{p.ref} {p.value}", loc="top", fontsize=10))
        col_y[c] -= h + 2.6


def build_schematic(design: BoardDesign):
    """The placed drawing (a ``schemdraw.Drawing``, nothing rendered yet): the overview and
    the parts sheet.  Rendering is left to :func:`draw_schematic`, so that a test can render
    the same elements on a matplotlib canvas and measure where the text lands."""
    import schemdraw
    import schemdraw.elements as elm
    v = design.values
    spec = design.spec
    d = schemdraw.Drawing(show=False)
    d.config(fontsize=11, unit=2.5, margin=2.0)
    # integrator; the feedback network spans sj .. xr, one unit right of the op-amp output, so
    # that the bridge has room for the designators and the current sources between its rows
    op = d.add(elm.Opamp(leads=True).anchor("in1").label("U1A\n" + spec.opamp, loc="center",
                                                        ofst=(-0.4, 0)))
    d.add(elm.Line().at(op.in2).left(0.5))
    d.add(elm.Ground())
    sj = op.in1
    xr = op.out[0] + 1.0
    width = xr - sj[0]
    d.add(elm.Dot().at(sj))
    d.add(elm.Line().at(op.out).right(1.0))
    out = d.here
    # feedback: C, R, bridge stacked above
    d.add(elm.Line().at(sj).up(1.5))
    top1 = d.here
    d.add(elm.Capacitor().right(width).label(f"C1 {eng(v['C'], 'F')}\nC0G 1 %"))
    d.add(elm.Line().down(1.5 + sj[1] - out[1]))
    d.add(elm.Line().at(top1).up(2.0))
    top2 = d.here
    d.add(elm.Resistor().right(width).label(f"R1 {eng(v['R'], 'Ω')} 1 %"))
    d.add(elm.Line().down(2.0))
    # bridge, bottom pair: D3 sj -> bot, D4 out -> bot, I_bot from bot to the -rail (drawn
    # up into the gap between the rows; its rail is in the note on the right)
    d.add(elm.Line().at(top2).up(2.5))
    row3 = d.here
    d.add(elm.Diode().right(width / 2).label("D3", loc="bottom"))
    bot = d.here
    d.add(elm.Diode().right(width / 2).reverse().label("D4", loc="bottom"))
    d.add(elm.Line().down(2.5))
    d.add(elm.SourceI().at(bot).up(1.6).label("I_bot", loc="bottom"))
    # bridge, top pair: D1 top -> sj, D2 top -> out, I_top from the +rail into top
    d.add(elm.Line().at(row3).up(3.0))
    d.add(elm.Diode().right(width / 2).reverse().label("D1", loc="bottom"))
    mid = d.here
    d.add(elm.Diode().right(width / 2).label("D2", loc="bottom"))
    d.add(elm.Line().down(3.0))
    d.add(elm.SourceI().at(mid).up(1.6).reverse().label("I_top", loc="bottom"))
    notes = (f"bridge D1-D4: 4 × {spec.diode}\n"
             f"I_top = {spec.v_set:g} V / R_S: Q1 + U2A + VR1,\n"
             f"    R2 {eng(v['R_S'], 'Ω')} to +{spec.rails:g} V, via U3 (enable)\n"
             f"I_bot: Q2 + U2B + VR2, R3 {eng(v['R_S'], 'Ω')}\n"
             f"    to -{spec.rails:g} V, via U3 (enable)")
    d.add(elm.Label().at((xr + 1.0, row3[1] + 1.5)).label(notes, halign="left"))
    d.add(elm.Dot().at(out))
    d.add(elm.Line().at(out).right(1.0))
    d.add(elm.Dot(open=True).label(f"OUT = -{design.kappa:.3g} V × v  (J4, DAQ AI0)\n"
                                   "reset: U4 closes R10 across C1, R11 from J3 (IC)",
                                   loc="right"))
    # force input, at a node far enough left of sj for the sj label above the wire
    d.add(elm.Line().at(sj).left(4.0))
    node = d.here
    d.add(elm.Label().at((sj[0] - 2.0, sj[1] + 0.35)).label("sj (virtual ground)"))
    d.add(elm.Resistor().at(node).up(2.0).label(f"R4 {eng(v['R_F'], 'Ω')}", loc="top"))
    d.add(elm.Dot(open=True).label(f"V_F = {design.force_sign * spec.v_force:+g} V (J2, DAQ AO1)",
                                   loc="top"))
    # noise chain
    d.add(elm.Resistor().at(node).left(2.5).label(f"R5 {eng(v['R_N'], 'Ω')}"))
    if "C_AC" in v:       # the AC coupling, only where BoardSpec.ac_corner asks for it
        d.add(elm.Capacitor().left(2.5).label(f"C4 {eng(v['C_AC'], 'F')}\nfilm"))
    else:
        d.add(elm.Line().left(2.5))
    d.add(elm.Line().left(1.0))
    d.add(elm.RBox().left(2.5).label(f"Bessel (U1B, R6, R7, C2, C3)\nf_c {eng(spec.bessel_fc / design.noise_ts, 'Hz')}\n"
                                      f"R {eng(v['R_B1'], 'Ω')}, C {eng(v['C_B1'], 'F')}/{eng(v['C_B2'], 'F')}",
                                      loc="top"))
    d.add(elm.Line().left(1.5))
    d.add(elm.SourceSin().down(2.0).label(
        f"J1: DAQ AO0 {spec.dac_bits} bit\n{eng(1.0 / design.noise_ts, 'S/s')}\n{spec.dac_rms:g} V rms\n"
        "seeded Gaussian", loc="top", ofst=(-1.6, 0)))
    d.add(elm.Ground())
    _parts_sheet(d, design, origin=(-14.0, -9.0))
    return d


def draw_schematic(design: BoardDesign, path, fmt: str = "svg") -> Path:
    """Write the schematic as SVG (schemdraw's own backend) or PNG (matplotlib backend)."""
    if fmt not in ("svg", "png"):
        raise ValueError(f"fmt must be 'svg' or 'png', got {fmt!r}")
    path = Path(path)
    d = build_schematic(design)
    if fmt == "png":
        import matplotlib
        matplotlib.use("Agg")
    d.draw(show=False, canvas="matplotlib" if fmt == "png" else "svg")
    data = d.get_imagedata(fmt)
    path.write_bytes(data if isinstance(data, bytes) else data.encode())
    if fmt == "png":
        import matplotlib.pyplot as plt
        plt.close(d.fig.fig)
    return path
