"""Board scaling, E-series rounding, op-amp macromodel text and vendor-file checks."""
import math

import pytest

from analogue import Model
from analogue.board import opamp
from analogue.board.design import BoardSpec, design_board, round_to_series
from analogue.circuit.mapping import stationary_std

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)


def test_scaling_fits_machine_unit_and_sigma():
    d = design_board(STICK, v0=[2.0, -2.0])
    assert d.kappa * d.v_max <= 10.0 + 1e-9
    assert d.kappa * 2.0 <= 10.0 + 1e-9
    assert d.kappa * stationary_std(STICK) <= 1.0 + 1e-9


def test_rounded_values_are_series_values_within_tolerance():
    d = design_board(STICK)
    for key, err in d.rounding.items():
        if key.startswith("R") and math.isfinite(d.ideal[key]):
            assert abs(err) <= 0.0102, key   # E96: neighbours ~2 % apart
    assert round_to_series(4.47e3, "E96") == pytest.approx(4.42e3)


def test_realised_model_follows_the_rounded_values():
    d = design_board(STICK)
    real = d.realised
    # independent route: the circuit equation with the rounded values
    ck = d.values["C"] * d.kappa
    assert real.tau_m == pytest.approx(d.values["R"] * d.values["C"] / d.theta, rel=2e-3)
    i0 = d.spec.v_set / d.values["R_S"]
    assert real.delta == pytest.approx(d.theta * i0 / ck, rel=2e-3)
    assert real.a == pytest.approx(d.theta * d.spec.v_force / d.values["R_F"] / ck, rel=1e-9)
    for name in ("tau_m", "delta", "a"):
        assert getattr(real, name) == pytest.approx(getattr(STICK, name), rel=0.012)
    # gamma goes as R_N^2: twice the E96 half-step (at the 800-per-tau_m default R_N rounds
    # by -1 %, gamma by +2 %)
    assert real.gamma == pytest.approx(STICK.gamma, rel=0.021)


def test_bad_spec_values_name_the_parameter():
    with pytest.raises(ValueError, match="machine_unit"):
        BoardSpec(machine_unit=20.0)
    with pytest.raises(ValueError, match="op-amp"):
        BoardSpec(opamp="LM741")
    with pytest.raises(ValueError, match="dac_bits"):
        BoardSpec(dac_bits=4)
    with pytest.raises(TypeError):
        design_board("stick")


def test_opamp_subcircuit_parameters():
    p = opamp.get_opamp("TL072")
    assert p.gm / (2 * math.pi * p.c1) == pytest.approx(3e6)
    assert p.i_max / p.c1 == pytest.approx(13e6)
    text = opamp.subcircuit(p, "u1")
    assert text.startswith(".subckt u1 inp inn vcc vee out") and text.endswith(".ends u1")
    assert not opamp.forbidden_deck_lines(text)
    hot = p.at_temperature(35.0)
    assert hot.ib == pytest.approx(2 * p.ib)
    with pytest.raises(ValueError):
        opamp.get_opamp("nonsense")


def test_vendor_model_path_refuses_control_blocks(tmp_path):
    good = tmp_path / "amp.lib"
    good.write_text("* vendor\n.subckt VAMP 1 2 3 4 5\nR1 1 2 1k\n.ends\n")
    assert opamp.vendor_model_path(good, "VAMP") == good.resolve()
    bad = tmp_path / "evil.lib"
    bad.write_text(".subckt VAMP 1 2 3 4 5\n.ends\n.control\nshell rm -rf /\n.endc\n")
    with pytest.raises(ValueError, match="forbidden"):
        opamp.vendor_model_path(bad, "VAMP")
    with pytest.raises(ValueError, match="pins"):
        four = tmp_path / "four.lib"
        four.write_text(".subckt VAMP 1 2 3 4\n.ends\n")
        opamp.vendor_model_path(four, "VAMP")
    with pytest.raises(ValueError, match="letters"):
        odd = tmp_path / "a b.lib"
        odd.write_text(".subckt VAMP 1 2 3 4 5\n.ends\n")
        opamp.vendor_model_path(odd, "VAMP")


def test_spring_design_and_refused_members():
    spring = Model(tau_m=3.0, delta=0.5, a=0.0, gamma=20.0, spring=1.0, x0=2.0)
    d = design_board(spring)
    ck = d.values["C"] * d.kappa
    # independent route: spring force -V(x)/R_K with V(x) = kappa theta x/(R_X C_X)
    k = d.theta * (d.x_volts / d.values["R_K"]) / ck
    assert d.realised.spring == pytest.approx(k, rel=1e-12)
    assert d.realised.spring == pytest.approx(1.0, rel=0.02)
    assert d.kappa * (2.0 * math.sqrt(1.0)) <= 10.0
    with pytest.raises(ValueError, match="cubic"):
        design_board(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0, cubic=0.5))
