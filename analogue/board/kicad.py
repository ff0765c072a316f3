"""``board.net``: the board channel as a KiCad netlist (S-expression, export version "E", as
KiCad 7/8 write and Pcbnew's "Import Netlist" reads), from the same design object as the BOM
and the schematic (:func:`analogue.board.components.board_components`): designators, values,
footprints, the part numbers as fields, and every net with its (designator, pin) nodes.
Bench instruments (off board) are left out; so are pins marked not connected."""
from __future__ import annotations

import datetime as _dt
from pathlib import Path

from .components import Part, board_components, nets
from .design import BoardDesign

__all__ = ["kicad_netlist", "write_kicad_netlist"]

_LIB = {"R": ("Device", "R"), "C": ("Device", "C"), "D": ("Device", "D"), "Q": ("Device", "Q_MOS"),
        "U": ("analogue_board", "IC"), "J": ("Connector", "Conn"), "TP": ("Connector", "TestPoint")}


def _q(text) -> str:
    """A KiCad string: double-quoted, backslash and quote escaped."""
    return '"' + str(text).replace("\\", "\\\\").replace('"', '\\"') + '"'


def _comp(p: Part) -> str:
    lib, part = _LIB.get(p.kind, ("analogue_board", p.kind))
    fields = "".join(f"\n        (field (name {_q(k)}) {_q(v)})" for k, v in
                     (("MPN", p.mpn), ("Manufacturer", p.manufacturer),
                      ("Second source", p.second_source), ("Tolerance", p.tolerance),
                      ("Rating", p.rating)))
    return (f"    (comp (ref {_q(p.ref)})\n      (value {_q(p.value)})\n"
            f"      (footprint {_q(p.footprint)})\n      (fields{fields})\n"
            f"      (libsource (lib {_q(lib)}) (part {_q(part)}) (description {_q(p.description)})))")


def kicad_netlist(design: BoardDesign, matched: tuple = (), date: str | None = None) -> str:
    """The netlist text (see module docstring)."""
    parts = [p for p in board_components(design, matched) if not p.off_board]
    names = {p.ref: {num: name for num, name, _ in p.pins} for p in parts}
    date = date or _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M:%S")
    comps = "\n".join(_comp(p) for p in parts)
    net_text = []
    for code, (net, nodes) in enumerate(nets(parts).items(), 1):
        body = "".join(f"\n      (node (ref {_q(r)}) (pin {_q(n)}) (pinfunction {_q(names[r][n])}))"
                       for r, n in nodes)
        net_text.append(f"    (net (code {_q(code)}) (name {_q(net)}){body})")
    return ("(export (version \"E\")\n"
            f"  (design\n    (source \"analogue board\")\n    (date {_q(date)})\n"
            "    (tool \"analogue.board.kicad\"))\n"
            f"  (components\n{comps})\n"
            "  (nets\n" + "\n".join(net_text) + "))\n")


def write_kicad_netlist(design: BoardDesign, path, matched: tuple = ()) -> Path:
    path = Path(path)
    path.write_text(kicad_netlist(design, matched), encoding="utf-8")
    return path
