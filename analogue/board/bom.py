"""``bom.csv``: one line per orderable item of one board channel, from
:func:`analogue.board.components.board_components` (the design object the KiCad netlist and
the schematic are written from): designators, quantity, value, manufacturer and part number,
a second source, footprint, tolerance and rating.  Identical parts share a line."""
from __future__ import annotations

import csv
from pathlib import Path

from .components import Part, board_components
from .design import BoardDesign

__all__ = ["HEADER", "bom_rows", "write_bom"]

HEADER = ("references", "quantity", "value", "description", "manufacturer", "mpn",
          "second_source", "footprint", "tolerance", "rating")


def _ref_key(ref: str) -> tuple:
    head = ref.rstrip("0123456789")
    return head, int(ref[len(head):] or 0)


def bom_rows(design: BoardDesign, matched: tuple = ()) -> list[tuple]:
    """Rows of the bill of materials (without the header).  ``matched``: designators whose
    tolerance the tolerance analysis asks to tighten."""
    groups: dict[tuple, list[Part]] = {}
    for p in board_components(design, matched):
        key = (p.value, p.manufacturer, p.mpn, p.footprint, p.tolerance, p.rating)
        groups.setdefault(key, []).append(p)
    rows = []
    for (value, manu, mpn, fp, tol, rating), ps in groups.items():
        refs = sorted((p.ref for p in ps), key=_ref_key)
        desc = ps[0].description if len(ps) == 1 else "; ".join(dict.fromkeys(p.description for p in ps))
        rows.append((",".join(refs), len(ps), value, desc, manu, mpn, ps[0].second_source, fp, tol,
                     rating))
    return sorted(rows, key=lambda r: _ref_key(r[0].split(",")[0]))


def write_bom(design: BoardDesign, path, matched: tuple = ()) -> Path:
    path = Path(path)
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(HEADER)
        w.writerows(bom_rows(design, matched))
    return path
