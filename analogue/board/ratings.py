"""Parts inside their datasheet limits, read off a simulated board (issue 21).

:func:`opamp_instances` lists every op-amp of a board deck (instance, non-inverting and
inverting input nodes, role); :func:`common_mode_margins` measures, over a transient saved
with every node (``build_board_deck(..., save_all=True)``), how far each op-amp's inputs stay
inside the *guaranteed* input common-mode range of its part (the ``_worst`` set): a negative
margin is a part outside its datasheet range, where a TL07x inverts its output.
:func:`part_stresses` reads every other absolute maximum rating a simulated run can reach
(MOSFET voltages and dissipation, resistor power, diode reverse voltage, switch channels
inside their supplies, op-amp output current), :func:`worst_stresses` merges the bench modes,
and :func:`unpowered_inputs` checks, on the parts list, that every DAQ input reaches its first
IC pin through enough resistance to keep that pin inside its rating with the supply off.
"""
from __future__ import annotations

import heapq
import math
import re

import numpy as np

from .design import BoardDesign
from .netlist import BoardInstance, role_part
from .opamp import get_opamp

__all__ = ["DAQ_INPUTS", "PIN_CURRENT_LIMIT", "common_mode_margins", "opamp_instances",
           "part_stresses", "unpowered_inputs", "worst_stresses"]

# The inputs the bench drives (connector -> pin -> largest |V| the DAQ puts there): the
# USB-6363's analogue outputs (+-10 V) on the noise, force and IC connectors, its 5 V digital
# lines on the enable and reset header.
DAQ_INPUTS = {"J1": {1: 10.0}, "J2": {1: 10.0}, "J3": {1: 10.0}, "J5": {1: 5.0, 2: 5.0}}
# Largest current into a signal pin beyond its rails (absolute maximum ratings): DG412/DG413
# analogue and logic pins "(V-) - 2 V to (V+) + 2 V or 30 mA, whichever occurs first"; the
# op-amps' inputs 10 mA (input clamp diodes to the supplies).
PIN_CURRENT_LIMIT = {"DG412": 30e-3, "DG413": 30e-3, "OPA2140": 10e-3, "OPA2197": 10e-3,
                     "TL072": 10e-3}
_SUPPLY_PINS = {"V+", "V-", "GND", "VL"}
DIODE_DROP = 0.7

_X = re.compile(r"^(X\S+)\s+(\S+)\s+(\S+)\s+vcc\s+vee\s+\S+\s+opa_(\w+)\s*$", re.MULTILINE)


def opamp_instances(deck_text: str) -> list[tuple[str, str, str, str]]:
    """(instance, in+ node, in- node, role) of every op-amp in a board deck."""
    return [(m.group(1), m.group(2), m.group(3), m.group(4)) for m in _X.finditer(deck_text)]


def _node(plot, node: str) -> np.ndarray | None:
    if node == "0":
        return np.zeros(len(plot["time"]))
    name = f"v({node.lower()})"
    return plot[name] if name in plot.names else None


def common_mode_margins(design: BoardDesign, board: BoardInstance, deck_text: str, plot) -> dict:
    """Per op-amp instance: the part, its guaranteed common-mode range at the board's rails,
    the extreme input voltages over the transient, and the margins (V) to the lower and upper
    limits (positive: inside).  ``plot`` must hold every node (``save_all``)."""
    out = {}
    for inst, inp, inn, role in opamp_instances(deck_text):
        part = get_opamp(role_part(design, role))
        lo, hi = part.guaranteed.common_mode_range(board.rails)
        volts = [v for v in (_node(plot, inp), _node(plot, inn)) if v is not None]
        if not volts:
            raise ValueError(f"the plot holds neither input of {inst}; build the deck with save_all=True")
        vmin = float(min(np.min(v) for v in volts))
        vmax = float(max(np.max(v) for v in volts))
        out[inst] = {"part": part.name, "role": role, "range": [lo, hi], "min": vmin,
                     "max": vmax, "margin_low": vmin - lo, "margin_high": hi - vmax}
    return out


def unpowered_inputs(parts) -> list[dict]:
    """Each DAQ-driven input (:data:`DAQ_INPUTS`) with the bench supply off: the
    lowest-resistance DC path from the connector pin to a signal pin of an op-amp or switch
    (resistors add, diodes count as shorts, capacitors as open; Dijkstra over the nets of
    ``parts``), and the current ``(V - 0.7)/R`` it lets into that pin when the pin sits a
    diode drop from its unpowered rails, against the pin's absolute maximum
    (:data:`PIN_CURRENT_LIMIT`).  A pin on the connector's own net has R = 0 and an unbounded
    current (limited only by the instrument, which a design must not rely on)."""
    edges: dict[str, list] = {}
    pins_on: dict[str, list] = {}
    for p in parts:
        if p.off_board:
            continue
        if p.kind in ("R", "D") and len(p.pins) == 2:
            a, b = p.pins[0][2], p.pins[1][2]
            r = p.numeric if p.kind == "R" else 0.0
            edges.setdefault(a, []).append((b, r))
            edges.setdefault(b, []).append((a, r))
        if p.value in PIN_CURRENT_LIMIT:
            for num, name, net in p.pins:
                if net and name not in _SUPPLY_PINS:
                    pins_on.setdefault(net, []).append((p, num, name))
    by_ref = {p.ref: p for p in parts}
    rows = []
    for ref, pins in DAQ_INPUTS.items():
        for num, volts in pins.items():
            net = next(n for k, _name, n in by_ref[ref].pins if k == num)
            dist, heap, hit = {net: 0.0}, [(0.0, net)], None
            while heap:
                d, n = heapq.heappop(heap)
                if d > dist.get(n, math.inf):
                    continue
                if n in pins_on:
                    hit = (d, n)
                    break
                for m, r in edges.get(n, ()):
                    if d + r < dist.get(m, math.inf):
                        dist[m] = d + r
                        heapq.heappush(heap, (d + r, m))
            if hit is None:
                raise ValueError(f"{ref} pin {num} ({net}) reaches no op-amp or switch pin")
            r, n = hit
            part, pin, name = pins_on[n][0]
            limit = min(PIN_CURRENT_LIMIT[q.value] for q, _k, _m in pins_on[n])
            current = (volts - DIODE_DROP) / r if r > 0 else math.inf
            rows.append({"connector": ref, "pin": num, "net": net, "volts": volts,
                         "first_pin": f"{part.ref} pin {pin} ({name})", "series_ohm": r,
                         "current_A": current, "limit_A": limit, "ok": current <= limit})
    return rows


# Absolute maximum ratings of the board's parts (datasheets, 25 C) that a simulated run can
# reach: MOSFETs |V_GS|, |V_DS| and dissipation (BSS84: 20 V, 50 V, 250 mW; 2N7002: 20 V,
# 60 V, 300 mW), 0805 thin-film resistors 0.125 W, the bridge diodes' continuous reverse
# voltage (1N4148W: 75 V), the op-amps' and switches' total supply (36 V; DG41x 44 V).
MOSFET_LIMITS = {"pmosx": ("Q1 BSS84", 20.0, 50.0, 0.25), "nmosx": ("Q2 2N7002", 20.0, 60.0, 0.30)}
RESISTOR_POWER = 0.125
DIODE_REVERSE = 75.0
OPAMP_SUPPLY = 36.0
SWITCH_SUPPLY = 44.0
_ROLE_REF = {"int": "U1A", "bf": "U1B", "st": "U2A", "sb": "U2B"}
_M = re.compile(r"^M(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+\S+\s+(pmosx|nmosx)\s*$", re.MULTILINE)
_R = re.compile(r"^(R\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s*$", re.MULTILINE)
_D = re.compile(r"^(D\S+)\s+(\S+)\s+(\S+)\s+dbr\d\s*$", re.MULTILINE)
_S = re.compile(r"^(S\S+)\s+(\S+)\s+(\S+)\s+\S+\s+\S+\s+sw\w+\s*$", re.MULTILINE)
# switch channels written as their on/off resistances when the enable is static
_SWITCH_R = re.compile(r"^R\w+(et|dt|eb|db)$")


def _top_level(deck_text: str) -> str:
    """The deck without its ``.subckt`` blocks (their element lines are the macromodels')."""
    return re.sub(r"^\.subckt.*?^\.ends.*?$", "", deck_text, flags=re.MULTILINE | re.DOTALL)


def part_stresses(design: BoardDesign, board: BoardInstance, deck_text: str, plot) -> list[dict]:
    """The largest stress on every kind of part over one simulated run (``plot`` saved with
    every node), against its absolute maximum rating: rows (part, quantity, worst, limit, unit,
    ok).  MOSFETs: |V_GS|, |V_DS| and V_DS I_D (I_D the sense-resistor current: the gates draw
    none); resistors: V^2/R; bridge diodes: reverse voltage; analogue switches: every channel
    pin inside the supplies (the DG41x's analogue range); op-amps: output current against the
    guaranteed short-circuit current and the total supply."""
    top = _top_level(deck_text)

    def v(node: str) -> np.ndarray:
        got = _node(plot, node)
        if got is None:
            raise ValueError(f"the plot holds no v({node}); build the deck with save_all=True")
        return got

    vcc, vee = v("vcc"), v("vee")
    rows = []

    def row(part, what, worst, limit, unit):
        rows.append({"part": part, "quantity": what, "worst": float(worst), "limit": float(limit),
                     "unit": unit, "ok": bool(abs(worst) <= limit + 1e-9)})

    for m in _M.finditer(top):
        _name, d, g, s, kind = m.groups()
        part, vgs_max, vds_max, p_max = MOSFET_LIMITS[kind]
        top_side = kind == "pmosx"
        r_s = board.values["R_S_top" if top_side else "R_S_bot"]
        i_d = np.abs((vcc - v(s)) if top_side else (v(s) - vee)) / r_s
        vds = np.abs(v(d) - v(s))
        row(part, "|V_GS|", np.max(np.abs(v(g) - v(s))), vgs_max, "V")
        row(part, "|V_DS|", np.max(vds), vds_max, "V")
        row(part, "dissipation", np.max(vds * i_d), p_max, "W")
    worst_r, which = 0.0, ""
    for m in _R.finditer(top):
        name, a, b, value = m.groups()
        if _SWITCH_R.match(name) or _node(plot, a) is None or _node(plot, b) is None:
            continue
        p = float(np.max((v(a) - v(b)) ** 2)) / float(value)
        if p >= worst_r:
            worst_r, which = p, name
    row(f"resistors (largest: {which})", "V^2/R", worst_r, RESISTOR_POWER, "W")
    rev = max(float(np.max(v(k) - v(a))) for _n, a, k in _D.findall(top))
    row("D1-D4 1N4148W", "reverse voltage", max(rev, 0.0), DIODE_REVERSE, "V")
    nodes = {x for s_ in _S.findall(top) for x in s_[1:3]}
    nodes |= {x for m in _R.finditer(top) if _SWITCH_R.match(m.group(1)) for x in m.group(2, 3)}
    if nodes:
        beyond = max(float(np.max(np.maximum(v(x) - vcc, vee - v(x)))) for x in nodes)
        row("U3/U4 DG413/DG412", "channel pin beyond the supplies", max(beyond, 0.0), 0.0, "V")
    for inst, _inp, _inn, role in opamp_instances(deck_text):
        amp = get_opamp(role_part(design, role)).guaranteed
        key = f"i(e.{inst.lower()}.ebuf)"
        if key in plot.names:   # every replica's op-amp of one role is one row
            row(f"{_ROLE_REF[role]} {amp.name}", "output current",
                np.max(np.abs(plot[key])), amp.i_sc, "A")
    row("op-amps", "total supply", float(np.max(vcc - vee)), OPAMP_SUPPLY, "V")
    row("U3/U4 DG413/DG412", "total supply", float(np.max(vcc - vee)), SWITCH_SUPPLY, "V")
    return rows


def worst_stresses(modes: dict) -> dict:
    """Per (part, quantity), the worst row over the bench modes ``{mode: part_stresses rows}``,
    with the mode it came from; ``all_ok`` when every part stayed inside its ratings."""
    worst: dict = {}
    for mode, rows_ in modes.items():
        for r in rows_:
            key = (r["part"].split(" (largest")[0], r["quantity"])
            if key not in worst or abs(r["worst"]) > abs(worst[key]["worst"]):
                worst[key] = {**r, "mode": mode}
    rows = list(worst.values())
    return {"rows": rows, "all_ok": all(r["ok"] for r in rows)}
