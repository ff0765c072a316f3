"""Seeded board draws, the effective model, the noise chain's transfer function."""
import math

import numpy as np
import pytest

from analogue import Model
from analogue.board import noise_chain
from analogue.board.design import design_board
from analogue.board.netlist import nominal_instance
from analogue.board.tolerance import (
    CLASSES,
    Tolerances,
    draw_board,
    effective_model,
    readout_offset,
)

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
DESIGN = design_board(STICK, v0=[2.0, -2.0])


def test_same_seed_same_board_and_other_seed_other_board():
    a = draw_board(DESIGN, Tolerances(), 5, 3)
    b = draw_board(DESIGN, Tolerances(), 5, 3)
    c = draw_board(DESIGN, Tolerances(), 6, 3)
    assert a.values == b.values and a.draws == b.draws and a.opamps == b.opamps
    assert a.values != c.values


def test_switching_a_class_off_keeps_the_other_draws():
    full = draw_board(DESIGN, Tolerances(), 1, 0)
    only_r = draw_board(DESIGN, Tolerances().only("resistors"), 1, 0)
    for k in ("R", "R_S_top", "R_F", "R_N"):
        # same uniform number, without the temperature coefficient
        tempco = 1 + 50e-6 * (full.temperature - 27.0)
        assert 1 + only_r.draws[k] == pytest.approx((1 + full.draws[k]) / tempco, rel=1e-12)
    assert only_r.opamps["int"].vos == 0.0 and only_r.temperature == 27.0


def test_resistor_draws_stay_within_tolerance():
    tol = Tolerances().only("resistors")
    for i in range(50):
        b = draw_board(DESIGN, tol, 2, i)
        for k in ("R", "R_S_top", "R_S_bot", "R_F", "R_N"):
            assert abs(b.draws[k]) <= 0.01 + 1e-12


def test_effective_model_of_the_nominal_board_is_the_realised_model():
    b = draw_board(DESIGN, Tolerances(enabled=()), 0, 0)
    eff = effective_model(DESIGN, b)
    for name in ("tau_m", "delta", "a", "gamma", "epsilon"):
        # epsilon: RS I differs by RS 2 IS (1e-6 relative)
        assert getattr(eff, name) == pytest.approx(getattr(DESIGN.realised, name), rel=1e-5)
    assert readout_offset(DESIGN, b) == 0.0


def test_current_source_mismatch_is_a_force_and_its_mean_the_friction():
    nom = nominal_instance(DESIGN)
    b = nom.replace(v_set_top=nom.v_set_top * 1.01)
    eff = effective_model(DESIGN, b)
    real = DESIGN.realised
    i0 = DESIGN.spec.v_set / DESIGN.values["R_S"]
    unit = DESIGN.theta / (DESIGN.values["C"] * DESIGN.kappa)
    assert eff.delta - real.delta == pytest.approx(0.005 * i0 * unit, rel=1e-6)
    assert eff.a - real.a == pytest.approx(0.005 * i0 * unit, rel=1e-6)


def test_bad_tolerance_input():
    with pytest.raises(ValueError, match="enabled"):
        Tolerances(enabled=("gremlins",))
    with pytest.raises(ValueError, match="seed"):
        draw_board(DESIGN, Tolerances(), -1, 0)
    with pytest.raises(TypeError):
        draw_board(DESIGN, {"r_tol": 0.01}, 0, 0)
    assert set(CLASSES) >= {"resistors", "temperature"}


def test_chain_has_unit_low_frequency_gain_and_bessel_q():
    h = noise_chain.chain_transfer(DESIGN.values)
    w_mid = 2 * math.pi * 2e3   # well inside the pass band (AC corner ~0.16 Hz... Bessel 25 kHz)
    _, resp = h.freqresp([w_mid])
    assert abs(resp[0]) == pytest.approx(1.0, abs=0.01)
    # intensity delivered: the integrated held noise over many samples has variance 2 D t
    seq = noise_chain.dac_sequence(DESIGN, 5, 0, 100_000)
    assert np.std(seq) == pytest.approx(DESIGN.spec.dac_rms, rel=0.01)
    lsb = 2 * DESIGN.spec.dac_range / 2 ** DESIGN.spec.dac_bits
    assert np.allclose(seq / lsb, np.round(seq / lsb))


def test_dac_sequence_is_seeded_per_replica():
    a = noise_chain.dac_sequence(DESIGN, 5, 0, 100)
    assert np.array_equal(a, noise_chain.dac_sequence(DESIGN, 5, 0, 100))
    assert not np.array_equal(a, noise_chain.dac_sequence(DESIGN, 5, 1, 100))
    assert np.array_equal(a[:50], noise_chain.dac_sequence(DESIGN, 5, 0, 50))
