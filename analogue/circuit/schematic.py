"""A schematic of one replica of the circuit, drawn from a :class:`CircuitMapping` (schemdraw).

The drawing follows the deck of :mod:`analogue.circuit.netlist` element by element, with the
component values of the mapping in SI units:

- node ``v`` (voltage = kappa x velocity): mass capacitor ``Cm``, viscous resistor ``Rvisc``,
  force current source ``Iforce`` (into the node), the noise current ``Gnoise`` (a VCCS driven by
  the held Gaussian ``trrandom`` voltage on node ``nz``) and the Coulomb element between ``v``
  and ground: four diodes around the current source ``Idelta`` (terminal current
  ``I_Delta tanh(V/(2 N V_T))``), or a behavioural source;
- node ``x``: the position integrator, a VCCS ``g_x V(v)`` into ``Cx``.

``analogue schematic stick docs/schematic.svg`` redraws the committed ``docs/schematic.svg``
(the command line reads the experiment, a layer above this one; this module only draws a
mapping).
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

from .mapping import CircuitMapping

__all__ = ["draw", "si"]

_PREFIXES = {-15: "f", -12: "p", -9: "n", -6: "µ", -3: "m", 0: "", 3: "k", 6: "M", 9: "G"}


def si(value: float, unit: str, digits: int = 4) -> str:
    """``si(1e-7, "F") -> "100 nF"``: a value with an SI prefix and ``digits`` significant
    digits."""
    if not math.isfinite(value):
        return f"{value} {unit}"
    if value == 0:
        return f"0 {unit}"
    exp3 = int(math.floor(math.log10(abs(value)) / 3) * 3)
    exp3 = max(-15, min(9, exp3))
    scaled = value / 10.0**exp3
    return f"{scaled:.{digits}g} {_PREFIXES[exp3]}{unit}"


def draw(mapping: CircuitMapping, path=None, *, title: str | None = None):
    """Draw one replica of the circuit of ``mapping``; write it to ``path`` (SVG or PNG, by the
    suffix) when given.  Returns the ``schemdraw.Drawing``."""
    import matplotlib
    import schemdraw
    import schemdraw.elements as elm

    if not isinstance(mapping, CircuitMapping):
        raise TypeError(f"mapping must be a CircuitMapping (analogue.circuit.mapping.map_model), "
                        f"got {type(mapping).__name__}")
    m = mapping
    matplotlib.use("Agg", force=False)
    schemdraw.use("svg" if path is not None and str(path).endswith(".svg") else "matplotlib")
    d = schemdraw.Drawing(show=False)
    d.config(fontsize=11, unit=2.5)
    if title:
        d += elm.Label().label(title, fontsize=13).at((0, 3.2))

    # node v: a top rail, branches down to ground
    d += (top := elm.Dot().label("v", loc="top"))
    spacing = 3.2
    x = 0.0

    def branch(element, label):
        nonlocal x
        d.add(elm.Line().at((x, 0)).to((x + spacing, 0)))
        x += spacing
        d.add(elm.Dot().at((x, 0)))
        d.add(element.at((x, 0)).down().label(label, loc="bottom", ofst=0.3))
        d.add(elm.Ground())

    d += elm.Capacitor().at((0, 0)).down().label(f"Cm\n{si(m.capacitance, 'F')}", loc="bottom",
                                                  ofst=0.3)
    d += elm.Ground()
    branch(elm.Resistor(), f"Rvisc\n{si(m.resistance, 'Ω')}")
    branch(elm.SourceI().reverse(), f"Iforce\n{si(m.i_force, 'A')}")
    branch(elm.SourceControlledI().reverse(),
           f"Gnoise\n{si(m.noise_gain, 'S')} × V(nz)")

    if m.coulomb_element == "diode-bridge":
        # the bridge: t (top) = v, bottom = ground, p right, n left; Idelta from p to n
        d += elm.Line().at((x, 0)).to((x + spacing + 1.2, 0))
        x += spacing + 1.2
        t = (x, 0)
        p, n, g = (x + 1.8, -2.2), (x - 1.8, -2.2), (x, -4.4)
        d += elm.Diode().endpoints(t, p).label("D1", loc="top")
        d += elm.Diode().endpoints(g, p).label("D2", loc="bottom")
        d += elm.Diode().endpoints(n, t).label("D3", loc="top")
        d += elm.Diode().endpoints(n, g).label("D4", loc="bottom")
        d += elm.SourceI().endpoints(n, p).reverse()
        d += elm.Ground().at(g)
        part = m.part.name if m.part is not None else "diode"
        d += elm.Label().at((x - 3, -5.6)).label(
            f"Coulomb bridge: {part} diodes, N = {m.emission:.4g}; Idelta = {si(m.i_delta, 'A')}; "
            f"terminal current {si(m.i_delta_total, 'A')} × tanh(V / {si(m.eps_volts, 'V')})",
            fontsize=10)
    elif m.coulomb_element is not None:
        law = "sgn(V)" if m.coulomb_element == "behavioural-sgn" else \
            f"tanh(V / {si(m.eps_volts, 'V')})"
        branch(elm.SourceControlledI(), f"B: {si(m.i_delta_total, 'A')}\n× {law}")

    # the noise voltage source (node nz) and the position integrator (node x), to the left
    d += elm.SourceV().at((-4.5, -2.5)).up().label(
        f"Vnoise: trrandom\nσ = {si(m.noise_stddev, 'V')}\nhold {si(m.noise_ts, 's')}",
        loc="bottom", ofst=0.3)
    d += elm.Dot().label("nz", loc="top")
    d += elm.Ground().at((-4.5, -2.5))
    d += elm.Dot().at((-9, 0)).label("x", loc="top")
    d += elm.SourceControlledI().at((-9, 0)).down().reverse().label(
        f"Gx\n{si(m.g_x, 'S')} × V(v)", loc="bottom", ofst=0.3)
    d += elm.Ground()
    d += elm.Line().at((-9, 0)).to((-12, 0))
    d += elm.Capacitor().down().label(f"Cx\n{si(m.cap_x, 'F')}", loc="bottom", ofst=0.3)
    d += elm.Ground()
    d += elm.Label().at((-1, -6.8)).label(
        f"one replica; theta = {si(m.theta, 's')} per model time unit, "
        f"kappa = {si(m.kappa, 'V')} per unit velocity", fontsize=10)
    del top
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        d.save(str(path))
    return d


if __name__ == "__main__":  # pragma: no cover
    # the entry that was here read an experiment (the study layer's) from the circuit layer
    print("python -m analogue.circuit.schematic is now `analogue schematic EXPERIMENT OUT.svg`",
          file=sys.stderr)
    sys.exit(2)
