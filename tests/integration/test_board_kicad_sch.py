"""``board.kicad_sch`` (issue 21 item 10, the optional KiCad schematic): written from the
design object, it parses back to the same parts (designator, value, footprint, part number)
and, through the labels at the pins' ends, to the same nets as ``board.net`` and the BOM.
Not opened in KiCad (none on this machine): the checks are the file's own consistency."""
import math
from collections import defaultdict

from analogue import Model
from analogue.board.components import board_components, nets
from analogue.board.design import design_board
from analogue.board.kicad_sch import kicad_schematic, pin_points
from unit.test_board_files import parse_sexpr

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
DESIGN = design_board(STICK, v0=[2.0, -2.0])


def _all(node, head):
    return [x for x in node if isinstance(x, list) and x and x[0] == head]


def _prop(sym, name):
    return next(p[2] for p in _all(sym, "property") if p[1] == name)


def test_the_schematic_parses_back_to_the_boards_parts_and_nets():
    text = kicad_schematic(DESIGN)
    assert text == kicad_schematic(DESIGN)                  # reproducible (UUIDs from designators)
    tree = parse_sexpr(text)
    assert tree[0] == "kicad_sch" and _all(tree, "version")[0][1] == "20230121"
    libs = {s[1]: s for s in _all(_all(tree, "lib_symbols")[0], "symbol")}
    placed = {_prop(s, "Reference"): s for s in _all(tree, "symbol")}
    parts = [p for p in board_components(DESIGN) if not p.off_board]
    assert set(placed) == {p.ref for p in parts}
    for p in parts:
        s = placed[p.ref]
        assert _prop(s, "Value") == p.value and _prop(s, "Footprint") == p.footprint
        assert _prop(s, "MPN") == p.mpn
        lib_id = _all(s, "lib_id")[0][1]
        assert lib_id in libs
        # the pins of the placed symbol are the library symbol's, and the part's
        lib_pins = {q[_all_index(q, "number")][1] for sub in _all(libs[lib_id], "symbol")
                    for q in _all(sub, "pin")}
        assert lib_pins == {str(n) for n, _nm, _net in p.pins} == {q[1] for q in _all(s, "pin")}
    # every label sits on the grid and on a pin end; the labels rebuild board.net's nets
    ends = {pt: key for key, pt in pin_points(DESIGN).items()}
    assert len(ends) == len(pin_points(DESIGN))              # no two pins share an end
    rebuilt = defaultdict(set)
    for lab in _all(tree, "label"):
        x, y = float(lab[2][1]), float(lab[2][2])
        assert math.isclose(x / 1.27, round(x / 1.27), abs_tol=1e-6)
        key = ends[(round(x / 1.27) * 1.27, round(y / 1.27) * 1.27)]
        rebuilt[lab[1]].add(key)
    want = {net: {(r, n) for r, n in nodes} for net, nodes in nets(parts).items()}
    assert dict(rebuilt) == want
    # unconnected pins carry a no-connect flag
    unconnected = sum(1 for p in parts for _n, _nm, net in p.pins if not net)
    assert unconnected > 0 and len(_all(tree, "no_connect")) == unconnected


def _all_index(node, head):
    return next(i for i, x in enumerate(node) if isinstance(x, list) and x and x[0] == head)
