"""The circuit schematic drawn from the mapping: SI values, every element, each Coulomb option;
axis labels that do not read like seconds."""
from pathlib import Path

import pytest

from analogue import Model
from analogue.circuit.experiments import load_experiment
from analogue.circuit.mapping import CircuitSpec, map_model
from analogue.circuit.schematic import draw, si

ROOT = Path(__file__).resolve().parents[2]
pytest.importorskip("schemdraw")


def test_si_prefixes():
    assert si(1e-7, "F") == "100 nF"
    assert si(10_000.0, "Ω") == "10 kΩ"
    assert si(2e-5, "A") == "20 µA"
    assert si(0.0, "A") == "0 A"
    assert si(4.47213595499958, "V") == "4.472 V"
    assert si(-3.3e-3, "s") == "-3.3 ms"


def _texts(svg: str) -> str:
    return svg.replace("&#181;", "µ").replace("&#937;", "Ω")


def test_stick_schematic_shows_every_component_in_si(tmp_path):
    m = load_experiment("stick").mapping()
    out = tmp_path / "s.svg"
    draw(m, out, title="stick")
    svg = _texts(out.read_text())
    for name in ("Cm", "Rvisc", "Iforce", "Gnoise", "D1", "D2", "D3", "D4", "Vnoise", "Gx", "Cx"):
        assert name in svg, name
    # values from the component table, formatted independently of the drawing code
    table = {name: (value, unit) for name, value, unit, _ in m.table()}
    assert f"{table['C'][0] * 1e9:.4g} nF" in svg
    assert f"{table['R'][0] / 1e3:.4g} kΩ" in svg
    assert f"{table['I_F'][0] * 1e6:.4g} µA" in svg
    assert f"{table['I_Delta'][0] * 1e6:.4g} µA" in svg


def test_committed_schematic_is_the_stick_circuit():
    svg = _texts((ROOT / "docs" / "schematic.svg").read_text())
    m = load_experiment("stick").mapping()
    assert si(m.capacitance, "F") in svg and si(m.resistance, "Ω") in svg
    assert si(m.i_delta, "A") in svg and si(m.noise_ts, "s") in svg


@pytest.mark.parametrize("delta, coulomb", [(0.0, "diode-bridge"), (0.7, "behavioural"),
                                            (0.7, "behavioural-sgn")])
def test_other_coulomb_elements(tmp_path, delta, coulomb):
    model = Model(tau_m=1.0, delta=delta, a=0.2, gamma=10.0)
    m = map_model(model, CircuitSpec(coulomb=coulomb, allow_bias=True))
    draw(m, tmp_path / "x.svg")
    svg = (tmp_path / "x.svg").read_text()
    assert ("D1" in svg) is False
    if delta == 0:
        assert "B:" not in svg
    else:
        assert ("sgn" in svg) == (coulomb == "behavioural-sgn")


def test_draw_refuses_a_model():
    with pytest.raises(TypeError, match="CircuitMapping"):
        draw(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0))


def test_time_axis_label_is_not_seconds():
    from analogue.plots.style import TIME
    assert TIME == "time t (units of tau_m)"
    for p in (ROOT / "analogue").rglob("*.py"):
        assert "time s (model units)" not in p.read_text(), p


def test_cli_schematic_draws_the_experiments_mapping(tmp_path):
    # `analogue schematic` replaced `python -m analogue.circuit.schematic` (whose main() read an
    # experiment from the circuit layer, an import up into the study layer): the same drawing
    from click.testing import CliRunner

    from analogue.cli import main
    out = tmp_path / "cli.svg"
    r = CliRunner().invoke(main, ["schematic", "stick", str(out)])
    assert r.exit_code == 0, r.output
    assert f"wrote {out}" in r.output
    direct = tmp_path / "direct.svg"
    exp = load_experiment("stick")
    draw(exp.mapping(), direct, title=f"{exp.name}: {exp.model.regime} regime")
    assert out.read_text() == direct.read_text()


def test_cli_schematic_names_an_unknown_experiment(tmp_path):
    from click.testing import CliRunner

    from analogue.cli import main
    r = CliRunner().invoke(main, ["schematic", "no-such-experiment", str(tmp_path / "x.svg")])
    assert r.exit_code != 0
    assert "no-such-experiment" in r.output
    assert not (tmp_path / "x.svg").exists()
