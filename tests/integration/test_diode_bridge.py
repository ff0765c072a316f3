"""The Coulomb element in ngspice: DC sweeps of the bridge (and B-sources) against closed forms."""
import subprocess

import numpy as np
import pytest

from analogue.circuit import CircuitSpec, map_model
from analogue.circuit.netlist import bridge_dc_deck
from analogue.circuit.parts import bridge_current, bridge_node_voltages, thermal_voltage
from analogue.circuit.rawfile import read_raw
from conftest import STICK_A02

pytestmark = pytest.mark.requires_ngspice


def sweep(mapping, v_max, tmp_path, points=201):
    deck = tmp_path / "dc.cir"
    deck.write_text(bridge_dc_deck(mapping, v_max, points))
    run = subprocess.run(["ngspice", "-b", "-r", "dc.raw", "dc.cir"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr
    plot = read_raw(tmp_path / "dc.raw")[0]
    return plot["v(t)"], -plot["i(vs)"], plot  # the source supplies what the element sinks


def test_ideal_bridge_is_tanh(tmp_path):
    """Ideal diodes (RS = 0, CJO = 0): I = I_Delta tanh(V/(2 N V_T)), to 1e-5 of I_Delta."""
    m = map_model(STICK_A02)
    v, i, _ = sweep(m, 6 * m.eps_volts, tmp_path)
    assert v.size == 201 and v[0] == pytest.approx(-6 * m.eps_volts)
    law = m.i_delta_total * np.tanh(v / (2 * m.emission * thermal_voltage()))
    assert np.max(np.abs(i - law)) < 1e-5 * m.i_delta_total
    # the emission coefficient realises the requested smoothing width in volts
    assert 2 * m.emission * thermal_voltage() == pytest.approx(m.smoothing * STICK_A02.velocity_scale * m.kappa)


@pytest.mark.parametrize("emission", [0.05, 1.0, 3.0])
def test_ideal_bridge_other_widths(tmp_path, emission):
    spec = CircuitSpec(volts_per_velocity=emission * 2 * thermal_voltage() / (0.02 * STICK_A02.velocity_scale))
    m = map_model(STICK_A02, spec)
    assert m.emission == pytest.approx(emission)
    v, i, _ = sweep(m, 5 * m.eps_volts, tmp_path, points=101)
    law = m.i_delta_total * np.tanh(v / m.eps_volts)
    assert np.max(np.abs(i - law)) < 1e-5 * m.i_delta_total


@pytest.mark.parametrize("diode", ["1N4148", "BAT54"])
def test_real_bridge_follows_series_resistance_law(tmp_path, diode):
    """Vendor models: the sweep follows V = 2 N V_T atanh(I/(I0 + 2 IS)) + RS I up to the
    vendor's parallel resistors (four of rp: at most 2|V|/rp extra current), and its slope at 0
    is the mapping's smoothing width."""
    m = map_model(STICK_A02, CircuitSpec(diode=diode))
    v_max = 6 * m.eps_volts
    v, i, plot = sweep(m, v_max, tmp_path)
    law = bridge_current(m.part, m.i_delta, v)
    tol = 2 * v_max / m.part.rp + 1e-6 * m.i_delta_total
    assert np.max(np.abs(i - law)) < tol
    # slope at V = 0 from the central difference of the two points around 0
    mid = v.size // 2
    assert v[mid] == pytest.approx(0.0, abs=1e-12)
    slope = (i[mid + 1] - i[mid - 1]) / (v[mid + 1] - v[mid - 1])
    assert slope == pytest.approx(m.i_delta_total / m.eps_volts, rel=2e-3)
    # the inner nodes match the .ic values the transient decks use (DC solution)
    vp, vn = bridge_node_voltages(m.part, m.i_delta, v)
    assert np.max(np.abs(plot["v(xcoulomb.p)"] - vp)) < 1e-3 * m.eps_volts + tol * m.part.RS + 1e-4
    assert np.max(np.abs(plot["v(xcoulomb.n)"] - vn)) < 1e-3 * m.eps_volts + tol * m.part.RS + 1e-4
    # the real law departs from the slope-matched tanh; record how much (not a pass criterion
    # beyond being small against the amplitude)
    dev = np.max(np.abs(i - m.i_delta_total * np.tanh(v / m.eps_volts))) / m.i_delta_total
    assert dev < 0.01


def test_behavioural_sources(tmp_path):
    m = map_model(STICK_A02, CircuitSpec(coulomb="behavioural"))
    v, i, _ = sweep(m, 5 * m.eps_volts, tmp_path, points=101)
    assert np.max(np.abs(i - m.i_delta * np.tanh(v / m.eps_volts))) < 1e-9 * m.i_delta
    m = map_model(STICK_A02, CircuitSpec(coulomb="behavioural-sgn"))
    v, i, _ = sweep(m, 1.0, tmp_path, points=101)
    np.testing.assert_allclose(i, m.i_delta * np.sign(v), rtol=1e-9, atol=1e-15)
