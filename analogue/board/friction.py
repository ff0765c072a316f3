"""The Coulomb-friction element of the board, and an alternative.

**Diode bridge with rail-referenced current sources** (the default).  The bridge sits between
the virtual ground ``sj`` and the integrator output ``out``.  Its top node is fed by a sourcing
current source (P-MOSFET, sense resistor ``R_S`` to +15 V, op-amp holding ``v_set`` across
``R_S``) and its bottom node drained by a sinking one (N-MOSFET to -15 V).  Neither source
floats: each has volts of compliance (its node sits a diode drop from the lower/upper terminal,
within +-0.7 V of ground when ``sj`` is the virtual ground), which is what the passive bridge
around a floating regulator lacks (:func:`floating_bridge_deck`).

With ``u = V(sj) - V(out)`` the bridge carries ``I_bot`` out of ``sj`` for ``u >> w`` and
``I_top`` into it for ``u << -w``: a mismatch is the friction ``Delta = (I_top + I_bot)/2`` plus a
constant force ``(I_top - I_bot)/2`` (sliding limits), i.e. a friction asymmetry that the drift
calibration absorbs.  Each source delivers ``(v_set - vos)/R_S``: op-amp offset and sense
resistor tolerance set the mismatch.

**OTA** (LM13700-class, :func:`ota_lines`, behavioural): output current ``I_abc tanh(k
V(out)/(2 V_T))`` into ``sj`` through an input divider ``k``.  Not offered for the board
(issue 21): at k = 1 the output's +-10 V would sit across an input rated for about +-5 V, and
a divider that fits (k <= 0.5) makes its width 2 V_T/k >= 103 mV, no narrower than the
bridge's 98.6 mV, with the input offset divided by k on top.  The element stays for studies.

A comparator driving an analogue switch (sharp sgn, then ``I_0`` switched between the two
sources) is the third option: it removes the tanh width, but each switching event injects
the switch's charge (pC) into ``sj`` - at ``C kappa = 48 nC`` per unit velocity a 5 pC
injection is a velocity kick of 1e-4 per crossing, and in the stick regime the comparator
chatters around v = 0 (hundreds of crossings per tau_m), so the kicks add an uncontrolled
noise term exactly where the stick statistics are measured.  It is described, not built.
"""
from __future__ import annotations

from .. import checks
from ..circuit.parts import DiodePart, get_part, thermal_voltage

_n = checks.spice_number  # a deck number: _n(name, value)

__all__ = ["MOSFET_VTO", "SWITCH_MODELS", "bridge_lines", "floating_bridge_deck", "mosfet_models",
           "ota_lines"]

# Our own level-1 small-signal MOSFETs (BSS84/2N7002 class); their gates draw no current,
# so the source current is exactly the sense-resistor current.  Threshold 1.8 V (typical);
# the datasheets allow 0.8-2.5 V (2N7002) and 0.8-2.0 V (BSS84): :func:`mosfet_models`.
MOSFET_VTO = 1.8


def mosfet_models(vto: float = MOSFET_VTO) -> tuple[str, str]:
    """The P and N models with threshold magnitude ``vto`` (V)."""
    vto = checks.positive("mosfet vto", vto)
    return (f".model pmosx PMOS(LEVEL=1 VTO={_n('vto', -vto)} KP=0.05 LAMBDA=0.01)",
            f".model nmosx NMOS(LEVEL=1 VTO={_n('vto', vto)} KP=0.05 LAMBDA=0.01)")


# Analogue switches (DG413 / DG412 class at +-15 V, TTL control 0/5 V): on-resistance 35 Ohm
# (datasheet maximum at 25 C), off leakage 0.25 nA at 15 V (maximum at 25 C) -> 6e10 Ohm.
# ``swno`` closes for a control voltage above 2.5 V, ``swnc`` (control pins swapped) below.
SWITCH_RON = 35.0
SWITCH_ROFF = 6e10
SWITCH_C = 9e-12      # source/drain capacitance of a switch channel (DG413: 9 pF typical)
SWITCH_MODELS = (f".model swno SW(VT=2.5 VH=0.2 RON={SWITCH_RON:g} ROFF={SWITCH_ROFF:g})",
                 f".model swnc SW(VT=-2.5 VH=0.2 RON={SWITCH_RON:g} ROFF={SWITCH_ROFF:g})")


def diode_model_line(name: str, part: DiodePart, is_scale: float = 1.0, temp_shift: float = 0.0) -> str:
    params = dict(part.model)
    params["IS"] = params.get("IS", 1e-14) * is_scale
    text = " ".join(f"{k}={_n(k, v)}" for k, v in params.items())
    return f".model {checks.identifier('diode model name', name)} D({text})"


def bridge_lines(prefix: str, a: str, b: str, *, part: DiodePart, diode_models, r_s_top: float,
                 r_s_bot: float, v_set_top: float, v_set_bot: float, opamp_top: str,
                 opamp_bot: str, enable: str | bool = "en") -> list[str]:
    """Element lines of one bridge between nodes ``a`` (virtual ground) and ``b`` (output),
    with its two current sources (op-amp subcircuits ``opamp_top``/``opamp_bot``, supplies
    ``vcc``/``vee``).  ``diode_models``: four model names (D1 top->a, D2 top->b, D3 a->bot,
    D4 b->bot), so that each diode can carry its own mismatch.

    Enable (issue 21): each MOSFET's drain goes through an SPDT analogue switch (controlled by
    node ``enable``, 0/5 V) to the bridge (enabled) or to ground (disabled).  The sources keep
    running and their servos stay in regulation whatever the MOSFET threshold or the servo's
    output swing; with the enable low the bridge floats and only the switch's off leakage
    and the diodes' saturation currents reach it.  ``V{p}ia`` (0 V) in series with the bridge
    at ``a`` measures the friction current into the virtual ground.  ``enable`` a bool: the
    switches are static for the whole run and are written as their on/off resistances (the
    same circuit; ngspice's operating point with switch elements in several replicas needed
    gmin stepping and then missed the ``.ic`` values)."""
    p = checks.identifier("prefix", prefix)
    top, bot, ia = f"{p}top", f"{p}bot", f"{p}ia"
    d1, d2, d3, d4 = diode_models
    lines = [f"V{p}ia {ia} {a} dc 0",
             f"D{p}1 {top} {ia} {d1}", f"D{p}2 {top} {b} {d2}",
             f"D{p}3 {ia} {bot} {d3}", f"D{p}4 {b} {bot} {d4}"]
    # the switch channels' capacitance to ground at the bridge's nodes: with the enable low
    # these nodes float between reverse-biased diodes and a 60 GOhm off switch, and without it
    # ngspice stopped on "timestep too small" there (calibration OU run, measured)
    lines += [f"C{p}ct {top} 0 {_n('c_sw', SWITCH_C)}", f"C{p}cb {bot} 0 {_n('c_sw', SWITCH_C)}"]
    if isinstance(enable, bool):
        on, off = _n("ron", SWITCH_RON), _n("roff", SWITCH_ROFF)
        r_no, r_nc = (on, off) if enable else (off, on)
        lines += [f"R{p}et {p}dt {top} {r_no}", f"R{p}dt {p}dt 0 {r_nc}",
                  f"R{p}eb {p}db {bot} {r_no}", f"R{p}db {p}db 0 {r_nc}"]
    else:
        en = checks.identifier("enable node", enable)
        lines += [f"S{p}et {p}dt {top} {en} 0 swno", f"S{p}dt {p}dt 0 0 {en} swnc",
                  f"S{p}eb {p}db {bot} {en} 0 swno", f"S{p}db {p}db 0 0 {en} swnc"]
    if part.rp:
        for i, (x, y) in enumerate(((top, ia), (top, b), (ia, bot), (b, bot)), 1):
            lines.append(f"R{p}p{i} {x} {y} {_n('rp', part.rp)}")
    lines += [
        # sourcing: V(ref) = Vcc - v_set, op-amp forces V(s) = V(ref): I = v_set/R_S
        f"V{p}rt vcc {p}rt dc {_n('v_set', v_set_top)}",
        f"R{p}st vcc {p}st {_n('R_S', r_s_top)}",
        f"X{p}ut {p}rt {p}st vcc vee {p}gt {opamp_top}",
        f"M{p}t {p}dt {p}gt {p}st {p}st pmosx",
        # sinking: V(ref) = Vee + v_set
        f"V{p}rb {p}rb vee dc {_n('v_set', v_set_bot)}",
        f"R{p}sb {p}sb vee {_n('R_S', r_s_bot)}",
        f"X{p}ub {p}rb {p}sb vcc vee {p}gb {opamp_bot}",
        f"M{p}b {p}db {p}gb {p}sb {p}sb nmosx",
    ]
    return lines


def ota_lines(prefix: str, sj: str, out: str, *, i_abc: float, k: float, vos: float,
              asymmetry: float, temperature_k: float) -> list[str]:
    """An LM13700-class OTA as the friction element: current ``I_abc (1 + asym sgn) tanh((k
    V(out) + vos)/(2 V_T))`` into ``sj`` (behavioural; ``asymmetry`` is the relative mismatch
    of the output mirrors).  Bipolar input pair: width 2 V_T at the OTA input."""
    p = checks.identifier("prefix", prefix)
    vt2 = 2.0 * thermal_voltage(temperature_k)
    arg = f"({_n('k', k)}*v({out})+{_n('vos', vos)})/{_n('vt2', vt2)}"
    return [(f"B{p}ota 0 {sj} i={_n('i_abc', i_abc)}*(1+{_n('asymmetry', asymmetry)}*"
            f"tanh(1e3*{arg}))*tanh({arg})")]


def floating_bridge_deck(*, i_delta: float, i_force: float, r: float, c: float, headroom: float,
                         v0: float, t_end: float, regulator: bool) -> str:
    """The passive circuit of :mod:`analogue.circuit` (bridge around a *floating* DC source,
    1N4148 diodes), relaxing from ``V(v) = v0`` under the force current ``i_force`` without noise.  ``regulator=False``: ideal
    current source; ``True``: a two-terminal regulator with finite compliance - it delivers
    ``i_delta`` only while the voltage across it exceeds ``headroom`` and can never deliver
    power (a current-regulator diode / LM334-class part), modelled as
    ``I = i_delta * clip(V_across/headroom, 0, 1)`` from ``p`` to ``n``."""
    part = get_part("1N4148")
    model = " ".join(f"{k}={_n(k, v)}" for k, v in part.model)
    # orientation of analogue.circuit.netlist: D1 v->p, D2 0->p, D3 n->v, D4 n->0 and the
    # source driving current from p to n; it absorbs power only while V(p) > V(n).
    if regulator:
        src = f"Breg p n i={_n('i_delta', i_delta)}*min(max((v(p)-v(n))/{_n('headroom', headroom)},0),1)"
    else:
        src = f"Ireg p n dc {_n('i_delta', i_delta)}"
    return "\n".join([
        "floating bridge", f".model d4148 D({model})",
        f"C1 v 0 {_n('c', c)}", f"R1 v 0 {_n('r', r)}", f"IF 0 v dc {_n('i_force', i_force)}",
        "D1 v p d4148", "D2 0 p d4148", "D3 n v d4148", "D4 n 0 d4148", src,
        f".ic v(v)={_n('v0', v0)}",
        ".options reltol=1e-4",
        f".tran {_n('tstep', t_end / 2000)} {_n('t_end', t_end)} 0 {_n('tmax', t_end / 2000)}",
        ".save v(v) v(p) v(n)", ".end", ""])
