"""``board.kicad_sch``: the board channel as a KiCad schematic (KiCad 7 format, version
20230121; KiCad 8 opens it), from the same design object as the BOM, ``board.net`` and
``schematic.svg`` (:func:`analogue.board.components.board_components`).

Every on-board part is one placed symbol (Reference, Value, Footprint, MPN, manufacturer,
second source) from a symbol library embedded in the file (two-pin parts drawn vertically,
pin 1 on top; multi-pin parts as a box, pins down the left side and back up the right, in the
package's order); every pin ends on a local net label with its net's name (labels of the same
name are one net in KiCad), an unconnected pin on a no-connect flag.  Parts sit in a grid,
every coordinate on KiCad's 1.27 mm connection grid; the UUIDs are derived from the
designators, so the same design writes the same file.  Signal flow is drawn in
``schematic.svg``; this file is for capture and layout.  It was checked by parsing it back
(``tests/integration/test_board_kicad_sch.py``), not by opening it in KiCad (none on the
machine it was written on)."""
from __future__ import annotations

import re
import uuid
from pathlib import Path

from .components import Part, board_components
from .design import BoardDesign

__all__ = ["kicad_schematic", "pin_points", "write_kicad_schematic"]

G = 1.27                       # KiCad's connection grid (mm)
PIN_LEN = 2.54
PITCH = 2.54                   # pin spacing on a box
BOX_W = 10.16                  # box width (between the pin roots)
CELL_W = 50.8                  # grid cell of one part
PAGE = ("A1", 841.0, 594.0)
_NS = uuid.UUID("6f1d2b8e-3c4a-5d6e-8f90-a1b2c3d4e5f6")


def _uid(*key) -> str:
    return str(uuid.uuid5(_NS, "/".join(map(str, key))))


def _q(text) -> str:
    return '"' + str(text).replace("\\", "\\\\").replace('"', '\\"') + '"'


def _f(x: float) -> str:
    """A coordinate on the 1.27 mm grid, written without float noise."""
    return f"{round(x / G) * G:.4f}".rstrip("0").rstrip(".")


def _font(hide: bool = False, justify: str = "") -> str:
    j = f" (justify {justify})" if justify else ""
    return f"(effects (font (size 1.27 1.27)){j}{' hide' if hide else ''})"


def _symbol_name(p: Part) -> str:
    if p.kind in ("R", "C", "D") and len(p.pins) == 2:
        return p.kind
    return re.sub(r"[^A-Za-z0-9_+-]", "_", p.value) + f"_{len(p.pins)}"


def _pin_layout(p: Part) -> list[tuple[int, str, float, float, int]]:
    """(number, name, x, y, angle) of each pin's connection point in symbol coordinates (y up;
    the angle points from the connection point into the body)."""
    n = len(p.pins)
    if p.kind in ("R", "C", "D") and n == 2:
        (a, na, _), (b, nb, _) = p.pins
        return [(a, na, 0.0, 3.81, 270), (b, nb, 0.0, -3.81, 90)]
    left = (n + 1) // 2
    top = (left - 1) * PITCH / 2.0
    top = round(top / G) * G
    out = []
    for k, (num, name, _net) in enumerate(p.pins):
        if k < left:                           # down the left side
            out.append((num, name, -BOX_W / 2 - PIN_LEN, top - k * PITCH, 0))
        else:                                  # back up the right side
            j = n - 1 - k
            out.append((num, name, BOX_W / 2 + PIN_LEN, top - j * PITCH, 180))
    return out


def _lib_symbol(p: Part) -> str:
    name = _symbol_name(p)
    pins = _pin_layout(p)
    two = p.kind in ("R", "C", "D") and len(p.pins) == 2
    if two:
        body = ("(rectangle (start -1.016 2.54) (end 1.016 -2.54) (stroke (width 0.254) "
                "(type default)) (fill (type none)))")
    else:
        ys = [y for *_, y, _a in pins]
        h = max(ys) - min(ys) + 2 * G
        body = (f"(rectangle (start {_f(-BOX_W / 2)} {_f(max(ys) + G)}) (end {_f(BOX_W / 2)} "
                f"{_f(max(ys) + G - h)}) (stroke (width 0.254) (type default)) "
                "(fill (type background)))")
    pin_text = " ".join(
        f"(pin passive line (at {_f(x)} {_f(y)} {a}) (length {PIN_LEN:g}) "
        f"(name {_q('~' if two and p.kind != 'D' else nm)} {_font()}) "
        f"(number {_q(num)} {_font()}))"
        for num, nm, x, y, a in pins)
    props = " ".join(f"(property {_q(k)} {_q(v)} (id {i}) (at 0 0 0) {_font(hide=i > 1)})"
                     for i, (k, v) in enumerate((("Reference", p.ref.rstrip("0123456789")),
                                                 ("Value", name), ("Footprint", ""),
                                                 ("Datasheet", ""))))
    return (f"    (symbol {_q('analogue_board:' + name)} (in_bom yes) (on_board yes) {props}\n"
            f"      (symbol {_q(name + '_0_1')} {body})\n"
            f"      (symbol {_q(name + '_1_1')} {pin_text}))")


def _size(p: Part) -> float:
    """Height (mm) of the part's cell."""
    if p.kind in ("R", "C", "D") and len(p.pins) == 2:
        return 15.24
    return ((len(p.pins) + 1) // 2) * PITCH + 10.16


def _placements(parts: list[Part]) -> dict[str, tuple[float, float]]:
    """Part -> (x, y) of its origin on the sheet (y down), in columns filled top to bottom."""
    x0, y0, y_max = 25.4, 25.4, PAGE[2] - 25.4
    out, x, y = {}, x0, y0
    for p in parts:
        h = _size(p)
        if y + h > y_max:
            x, y = x + CELL_W, y0
        out[p.ref] = (round((x + CELL_W / 2) / G) * G, round((y + h / 2) / G) * G)
        y += h
    return out


def pin_points(design: BoardDesign, matched: tuple = ()) -> dict[tuple[str, int], tuple[float, float]]:
    """(designator, pin number) -> sheet coordinates (mm, y down) of the pin's end, where its
    label sits (what a test compares with the parsed file)."""
    parts = [p for p in board_components(design, matched) if not p.off_board]
    where = _placements(parts)
    out = {}
    for p in parts:
        sx, sy = where[p.ref]
        for num, _nm, x, y, _a in _pin_layout(p):
            out[(p.ref, num)] = (round((sx + x) / G) * G, round((sy - y) / G) * G)
    return out


def kicad_schematic(design: BoardDesign, matched: tuple = ()) -> str:
    """The schematic text (see module docstring)."""
    parts = [p for p in board_components(design, matched) if not p.off_board]
    root = _uid("root")
    libs, seen = [], set()
    for p in parts:
        name = _symbol_name(p)
        if name not in seen:
            seen.add(name)
            libs.append(_lib_symbol(p))
    where = _placements(parts)
    body = []
    for p in parts:
        x, y = where[p.ref]
        fields = (("Reference", p.ref, False), ("Value", p.value, False),
                  ("Footprint", p.footprint, True), ("Datasheet", "", True),
                  ("MPN", p.mpn, True), ("Manufacturer", p.manufacturer, True),
                  ("Second source", p.second_source, True), ("Description", p.description, True))
        if p.kind in ("R", "C", "D") and len(p.pins) == 2:
            # beside the body, between the two pins' labels
            spots = [(x + 2.54, y - 1.27), (x + 2.54, y + 1.27)]
        else:
            # above and below the box, clear of the labels at its sides
            ys = [py for *_, py, _a in _pin_layout(p)]
            spots = [(x - BOX_W / 2, y - max(ys) - 2.54), (x - BOX_W / 2, y - min(ys) + 3.81)]
        props = "\n".join(
            f"      (property {_q(k)} {_q(v)} (id {i}) (at {_f(spots[min(i, 1)][0])} "
            f"{_f(spots[min(i, 1)][1])} 0) {_font(hide=hide, justify='left')})"
            for i, (k, v, hide) in enumerate(fields))
        pins = " ".join(f"(pin {_q(num)} (uuid {_uid(p.ref, 'pin', num)}))" for num, _n, _net in p.pins)
        body.append(
            f"  (symbol (lib_id {_q('analogue_board:' + _symbol_name(p))}) (at {_f(x)} {_f(y)} 0) "
            f"(unit 1)\n    (in_bom yes) (on_board yes) (dnp no) (uuid {_uid(p.ref)})\n{props}\n"
            f"    {pins}\n"
            f"    (instances (project \"board\" (path {_q('/' + root)} (reference {_q(p.ref)}) "
            "(unit 1)))))")
        nets_of = {num: net for num, _n, net in p.pins}
        for num, _nm, px, py, ang in _pin_layout(p):
            ax, ay = x + px, y - py
            net = nets_of[num]
            if not net:
                body.append(f"  (no_connect (at {_f(ax)} {_f(ay)}) (uuid {_uid(p.ref, 'nc', num)}))")
                continue
            # the label reads away from the body: left pins to the left, right pins to the right
            angle, just = {0: (180, "right bottom"), 180: (0, "left bottom"),
                           270: (90, "left bottom"), 90: (270, "right bottom")}[ang]
            body.append(f"  (label {_q(net)} (at {_f(ax)} {_f(ay)} {angle}) (fields_autoplaced) "
                        f"{_font(justify=just)} (uuid {_uid(p.ref, 'label', num)}))")
    return ("(kicad_sch (version 20230121) (generator analogue_board)\n"
            f"  (uuid {root})\n  (paper {_q(PAGE[0])})\n"
            "  (title_block (title \"analogue board: one channel\") "
            "(comment 1 \"generated by analogue.board.kicad_sch from the design object\"))\n"
            "  (lib_symbols\n" + "\n".join(libs) + ")\n"
            + "\n".join(body) + "\n"
            "  (sheet_instances (path \"/\" (page \"1\"))))\n")


def write_kicad_schematic(design: BoardDesign, path, matched: tuple = ()) -> Path:
    path = Path(path)
    path.write_text(kicad_schematic(design, matched), encoding="utf-8")
    return path
