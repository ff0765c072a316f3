"""The files a builder takes (issue 21): bom.csv with part numbers and footprints on every
line, board.net a KiCad netlist that parses back to the same parts and nets, and the same
values as the SPICE deck, all from one design object."""
import csv
import math
import re

import pytest

from analogue import Model
from analogue.board.bom import HEADER, bom_rows, write_bom
from analogue.board.components import board_components, nets
from analogue.board.design import design_board
from analogue.board.kicad import kicad_netlist
from analogue.board.netlist import build_board_deck, nominal_instance

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
DESIGN = design_board(STICK, v0=[2.0, -2.0])


def parse_sexpr(text: str):
    """A small S-expression reader: lists, bare atoms and double-quoted strings (with \\
    escapes); raises ValueError on unbalanced parentheses or trailing text."""
    tokens = re.findall(r'\(|\)|"(?:[^"\\]|\\.)*"|[^\s()"]+', text)
    pos = 0

    def read():
        nonlocal pos
        if pos >= len(tokens):
            raise ValueError("unexpected end")
        tok = tokens[pos]
        pos += 1
        if tok == "(":
            out = []
            while pos < len(tokens) and tokens[pos] != ")":
                out.append(read())
            if pos >= len(tokens):
                raise ValueError("unbalanced (")
            pos += 1
            return out
        if tok == ")":
            raise ValueError("unbalanced )")
        if tok.startswith('"'):
            return re.sub(r"\\(.)", r"\1", tok[1:-1])
        return tok

    tree = read()
    if pos != len(tokens):
        raise ValueError("text after the top-level expression")
    return tree


def _find(node, head):
    return [x for x in node if isinstance(x, list) and x and x[0] == head]


def test_parser_refuses_broken_text():
    with pytest.raises(ValueError):
        parse_sexpr('(export (version "E")')
    with pytest.raises(ValueError):
        parse_sexpr('(a) (b)')
    assert parse_sexpr('(a "b \\" c" (d))') == ["a", 'b " c', ["d"]]


def test_kicad_netlist_parses_back_to_the_design():
    tree = parse_sexpr(kicad_netlist(DESIGN, date="2026-01-01"))
    assert tree[0] == "export" and _find(tree, "version")[0][1] == "E"
    comps = _find(_find(tree, "components")[0], "comp")
    parts = {p.ref: p for p in board_components(DESIGN) if not p.off_board}
    got = {}
    for c in comps:
        ref = _find(c, "ref")[0][1]
        got[ref] = (_find(c, "value")[0][1], _find(c, "footprint")[0][1],
                    {f[1][1]: f[2] for f in _find(_find(c, "fields")[0], "field")})
    assert set(got) == set(parts)
    for ref, (value, fp, fields) in got.items():
        assert value == parts[ref].value and fp == parts[ref].footprint and fp
        assert fields["MPN"] == parts[ref].mpn and fields["MPN"]
    net_nodes = {}
    for n in _find(_find(tree, "nets")[0], "net"):
        name = _find(n, "name")[0][1]
        net_nodes[name] = sorted((_find(x, "ref")[0][1], int(_find(x, "pin")[0][1]))
                                 for x in _find(n, "node"))
    assert net_nodes == {k: sorted(v) for k, v in nets(list(parts.values())).items()}
    # the circuit's topology: the bridge between the virtual ground and the output
    assert ("D1", 1) in net_nodes["SJ"] and ("D2", 1) in net_nodes["OUT"]
    assert ("U1", 2) in net_nodes["SJ"] and ("U1", 1) in net_nodes["OUT"]
    # every net joins at least two pins (no dangling labels), every part pin is on a net or NC
    for name, nodes in net_nodes.items():
        assert len(nodes) >= 2, name


def test_bom_has_an_orderable_line_for_every_part(tmp_path):
    path = write_bom(DESIGN, tmp_path / "bom.csv")
    with path.open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0].keys()) == HEADER
    for r in rows:
        for col in ("mpn", "manufacturer", "second_source", "footprint", "value"):
            assert r[col].strip() and r[col] != "-", (r["references"], col)
        assert "class" not in r["mpn"].lower() and "class" not in r["value"].lower()
    refs = [x for r in rows for x in r["references"].split(",")]
    assert len(refs) == len(set(refs)) == sum(int(r["quantity"]) for r in rows)
    assert set(refs) == {p.ref for p in board_components(DESIGN)}
    # what a bench needs is on it: enable and reset switches, references, decoupling, power
    # entry, connectors, the DAQ that plays the seeded sequence
    desc = " ".join(r["description"] for r in rows).lower()
    for word in ("enable", "reset", "shunt reference", "decoupling", "power entry", "daq",
                 "test point", "supply"):
        assert word in desc, word


def test_kicad_values_are_the_spice_deck_values(tmp_path):
    deck = build_board_deck(DESIGN, nominal_instance(DESIGN), v0=[1.0], t_end=0.1,
                            sample_dt=0.01, seed=1, noise_dir=tmp_path, start="reset")
    elements = {}
    for line in deck.text.splitlines():
        f = line.split()
        if f and f[0][0] in "RC" and len(f) == 4:
            elements[f[0]] = float(f[3])
    checked = 0
    for p in board_components(DESIGN):
        if p.spice and p.kind in ("R", "C"):
            assert elements[p.spice] == pytest.approx(p.numeric, rel=1e-12), p.ref
            checked += 1
    assert checked >= 12
    assert not math.isnan(board_components(DESIGN)[0].numeric)


def test_schematic_shows_every_bom_designator(tmp_path):
    from analogue.board.schematic import draw_schematic
    svg = draw_schematic(DESIGN, tmp_path / "schematic.svg").read_text(encoding="utf-8")
    texts = " ".join(re.findall(r">([^<>]+)</tspan>", svg))
    words = set(re.findall(r"\b[A-Z]+[0-9]+\b", texts))
    on_board = {p.ref for p in board_components(DESIGN) if not p.off_board}
    assert on_board <= words, sorted(on_board - words)


def test_board_readme_quotes_the_design():
    from pathlib import Path
    text = Path(__file__).resolve().parents[2].joinpath("docs", "board", "README.md").read_text()
    para = text.split("## Scaling for the stick experiment")[1].split("The noise default")[0]
    para = " ".join(para.split())
    v = DESIGN.values
    expect = [f"theta = {DESIGN.theta * 1e3:g} ms", f"kappa = {DESIGN.kappa:.4g} V",
              f"C1 = {v['C'] * 1e9:g} nF", f"R1 = {v['R'] / 1e3:g} kOhm",
              f"R2 = R3 = {v['R_S'] / 1e3:g} kOhm", f"(I_0 = {DESIGN.i_delta * 1e6:.3g} uA)",
              f"R4 = {v['R_F'] / 1e3:g} kOhm", f"R5 = {v['R_N'] / 1e3:g} kOhm",
              f"DAC at {1e-3 / DESIGN.noise_ts:g} kS/s",
              f"({DESIGN.noise_dt ** -1:g} samples per tau_m)",
              f"corner at {DESIGN.spec.bessel_fc / DESIGN.noise_ts / 1e3:g} kHz",
              f"width {DESIGN.eps_volts * 1e3:.4g} mV", f"epsilon = {DESIGN.realised.epsilon:.3g}"]
    missing = [e for e in expect if e not in para]
    assert not missing, missing


@pytest.mark.slow
def test_matching_advice_and_bom_are_the_same_in_quick_and_full_runs(tmp_path):
    # issue 21: the BOM asked for 0.1 % parts in one run and not in another; the advice now
    # depends only on the design, the seeds and the full job's statistical error
    from analogue.board import budget, tolerance
    from analogue.board.job import FULL, QUICK, recommend_matching, reference_stderr, theory_observables
    assert QUICK.sens_boards == FULL.sens_boards
    thr = 0.1 * STICK.velocity_scale
    fn = budget.observables_fn(STICK, burn_in=2.0, threshold=thr, taus=(1.0,))
    _, grads = tolerance.gradients(DESIGN, lambda m, off: theory_observables(m, off, thr))
    sens = tolerance.sensitivities(DESIGN, tolerance.Tolerances(), boards=QUICK.sens_boards,
                                   seed=11, grads=grads)
    se = reference_stderr(DESIGN, fn, seed=5)
    assert reference_stderr(DESIGN, fn, seed=5) == se
    advice = recommend_matching(sens, se)
    # a class is flagged exactly when its spread exceeds half the full job's standard error
    for k, rows in advice["dominant"].items():
        for r in rows:
            if se.get(k):
                assert (r["std"] > 0.5 * se[k]) <= (r["class"] in advice["must_trim_or_match"])
    a = write_bom(DESIGN, tmp_path / "a.csv", matched=tuple(advice["bom_refs"])).read_text()
    b = write_bom(DESIGN, tmp_path / "b.csv", matched=tuple(advice["bom_refs"])).read_text()
    assert a == b


def test_a_matched_resistor_is_ordered_as_a_tight_part():
    rows = {r[0]: r for r in bom_rows(DESIGN, matched=("R1",))}
    assert rows["R1"][5].startswith("TNPW0805") and rows["R1"][8].startswith("0.1 %")
    assert rows["R2,R3"][5].startswith("RT0805FRE07") and rows["R2,R3"][8].startswith("1 %")
