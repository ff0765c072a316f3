"""``schematic.svg`` drawn with schemdraw from a :class:`BoardDesign` (values from the design,
never hand-edited): the integrator with C, R and the diode bridge in its feedback, the two
current sources, the force and noise inputs into the virtual ground, and the noise chain."""
from __future__ import annotations

from pathlib import Path

from .design import BoardDesign

__all__ = ["draw_schematic", "eng"]


def eng(x: float, unit: str) -> str:
    """Engineering notation: 4.42e3 -> '4.42 k' + unit."""
    if x == 0:
        return f"0 {unit}"
    prefixes = [(1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "µ"),
                (1e-9, "n"), (1e-12, "p")]
    for scale, p in prefixes:
        if abs(x) >= scale * 0.999:
            return f"{x / scale:.3g} {p}{unit}"
    return f"{x:.3g} {unit}"


def draw_schematic(design: BoardDesign, path, fmt: str = "svg") -> Path:
    """Write the schematic as SVG (schemdraw's own backend) or PNG (matplotlib backend)."""
    import schemdraw
    import schemdraw.elements as elm
    if fmt not in ("svg", "png"):
        raise ValueError(f"fmt must be 'svg' or 'png', got {fmt!r}")
    if fmt == "png":
        import matplotlib
        matplotlib.use("Agg")
        schemdraw.use("matplotlib")
    else:
        schemdraw.use("svg")
    v = design.values
    spec = design.spec
    path = Path(path)
    with schemdraw.Drawing(show=False) as d:
        d.config(fontsize=11, unit=2.5, margin=2.0)
        # integrator
        op = d.add(elm.Opamp(leads=True).anchor("in1").label("U1\n" + spec.opamp, loc="center",
                                                            ofst=(-0.4, 0)))
        d.add(elm.Line().at(op.in2).left(0.5))
        d.add(elm.Ground())
        sj = op.in1
        d.add(elm.Dot().at(sj))
        d.add(elm.Label().at(sj).label("sj (virtual ground)", loc="bottom", ofst=(0.0, -0.6)))
        # feedback: C, R, bridge stacked above
        d.add(elm.Line().at(sj).up(1.5))
        top1 = d.here
        d.add(elm.Capacitor().right(op.out[0] - sj[0]).label(f"C {eng(v['C'], 'F')}\nC0G 1 %"))
        d.add(elm.Line().down(1.5).to(op.out))
        d.add(elm.Line().at(top1).up(2.0))
        top2 = d.here
        d.add(elm.Resistor().right(op.out[0] - sj[0]).label(f"R {eng(v['R'], 'Ω')} 1 %"))
        d.add(elm.Line().down(2.0))
        width = op.out[0] - sj[0]
        # bridge, bottom pair: D3 sj -> bot, D4 out -> bot, I_bot from bot to the -rail
        d.add(elm.Line().at(top2).up(2.5))
        row3 = d.here
        d.add(elm.Diode().right(width / 2).label("D3"))
        bot = d.here
        d.add(elm.Diode().right(width / 2).reverse().label("D4"))
        d.add(elm.Line().down(2.5))
        d.add(elm.SourceI().at(bot).up(1.6).label(
            f"I_bot: NMOS + U3,\nR_S {eng(v['R_S'], 'Ω')} to -{spec.rails:g} V", loc="bottom"))
        # bridge, top pair: D1 top -> sj, D2 top -> out, I_top from the +rail into top
        d.add(elm.Line().at(row3).up(3.0))
        d.add(elm.Diode().right(width / 2).reverse().label("D1"))
        mid = d.here
        d.add(elm.Diode().right(width / 2).label("D2"))
        d.add(elm.Line().down(3.0))
        d.add(elm.SourceI().at(mid).up(1.6).reverse().label(
            f"I_top = {spec.v_set:g} V / R_S: PMOS + U2,\nR_S {eng(v['R_S'], 'Ω')} to +{spec.rails:g} V",
            loc="top"))
        d.add(elm.Label().at((mid[0], mid[1] - 1.2)).label(f"bridge: 4 × {spec.diode} (matched quad)"))
        d.add(elm.Dot().at(op.out))
        d.add(elm.Line().at(op.out).right(1.0))
        d.add(elm.Dot(open=True).label(f"out = -{design.kappa:.3g} V × v  (ADC)", loc="right"))
        # force input
        d.add(elm.Line().at(sj).left(1.0))
        node = d.here
        d.add(elm.Resistor().up(2.0).label(f"R_F {eng(v['R_F'], 'Ω')}", loc="bottom"))
        d.add(elm.Dot(open=True).label(f"V_F = {design.force_sign * spec.v_force:+g} V (ref.)",
                                       loc="left"))
        # noise chain
        d.add(elm.Resistor().at(node).left(2.5).label(f"R_N {eng(v['R_N'], 'Ω')}"))
        d.add(elm.Capacitor().left(2.5).label(f"C_AC {eng(v['C_AC'], 'F')}\nfilm"))
        d.add(elm.Line().left(0.5))
        d.add(elm.RBox().left(2.5).label(f"Bessel 2nd order\nf_c {eng(spec.bessel_fc / design.noise_ts, 'Hz')}\n"
                                          f"R {eng(v['R_B1'], 'Ω')}, C {eng(v['C_B1'], 'F')}/{eng(v['C_B2'], 'F')}",
                                          loc="top"))
        d.add(elm.Line().left(0.5))
        d.add(elm.SourceSin().down(2.0).label(
            f"DAC {spec.dac_bits} bit\n{eng(1.0 / design.noise_ts, 'S/s')}\n{spec.dac_rms:g} V rms\n"
            "seeded Gaussian", loc="top", ofst=(-1.6, 0)))
        d.add(elm.Ground())
    data = d.get_imagedata(fmt)
    path.write_bytes(data if isinstance(data, bytes) else data.encode())
    if fmt == "png":
        import matplotlib.pyplot as plt
        plt.close("all")
        schemdraw.use("svg")
    return path
