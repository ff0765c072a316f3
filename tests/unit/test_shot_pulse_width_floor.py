"""The automatic shot pulse width has a floor tied to the solver's largest step (issue 9 QA).

Found with a user TOML (pure one-sided shot noise with cubic = 0.5: tau_m 1, Delta 0.5, a -0.2,
rate 1.5, mean 0.4): the automatic width 1e-3 mean/max|drift| was 3.3e-7 (max|drift| ~ 1200
from cubic v^3 at the rating range's edge v ~ 13) = 3.3e-5 of the largest step noise_dt, and
ngspice's velocity then relaxed 4-20 % too slowly between kicks (circuit dv/dt -0.797 against
the model's -0.829 at v ~ 0.1, -3.26 against -3.88 at v ~ 1.5), so the stationary rows failed
(mean v: circuit 0.492 +- 0.011, exact 0.190, z = 27).  Measured on the same kicks: width
1e-6 (1e-4 of the step) -1.4 %; 4e-6 (4e-4) and 5e-5 within 0.3 % (the sampled-secant noise).
"""
from __future__ import annotations

import math

import pytest

from analogue import Model, ShotNoise
from analogue.circuit.mapping import SHOT_MIN_WIDTH, SHOT_PULSE_TARGET, CircuitSpec, map_model

CUBIC_SHOT = Model(1.0, 0.5, -0.2, math.inf, cubic=0.5, shot=ShotNoise(1.5, 0.4))
SPEC = dict(coulomb="diode-bridge", diode="ideal", smoothing=0.02, time_scale=1e-3,
            capacitance=100e-9)


def test_automatic_width_is_not_below_the_floor():
    m = map_model(CUBIC_SHOT, CircuitSpec(**SPEC))
    assert m.shot_width >= SHOT_MIN_WIDTH * m.noise_dt * (1 - 1e-12)
    # and the kick error estimate of that width stays within the default tolerance
    assert m.bias["shot_pulse"] <= 0.05


def test_floor_follows_an_explicit_max_step():
    m = map_model(CUBIC_SHOT, CircuitSpec(**SPEC, max_step=0.002))
    assert m.shot_width >= SHOT_MIN_WIDTH * 0.002 * (1 - 1e-12)
    assert m.shot_width < SHOT_MIN_WIDTH * m.noise_dt


def test_explicit_width_below_the_floor_is_refused_naming_it():
    with pytest.raises(ValueError, match="shot_width"):
        map_model(CUBIC_SHOT, CircuitSpec(**SPEC, shot_width=3e-7))


def test_shipped_shot_width_unchanged():
    """shot.toml's automatic width (2.9e-3 of noise_dt) is above the floor: the rule still
    picks the width whose kick error estimate is the target."""
    m = map_model(Model(1.0, 0.5, 0.2, math.inf, shot=ShotNoise(1.0, 0.5)), CircuitSpec(**SPEC))
    assert m.bias["shot_pulse"] == pytest.approx(SHOT_PULSE_TARGET, rel=1e-12)
    assert m.shot_width > SHOT_MIN_WIDTH * m.noise_dt


def test_refusal_of_a_wide_floor_names_max_step():
    """cubic = 5 with shot noise: the floored width (1e-3 noise_dt) gives a kick error above
    the tolerance; lowering shot_width alone would be refused by the floor, so the message
    names max_step too, and following it gives a valid mapping."""
    m = Model(1.0, 0.5, -0.2, math.inf, cubic=5.0, shot=ShotNoise(1.5, 0.4))
    with pytest.raises(ValueError, match="max_step") as err:
        map_model(m, CircuitSpec(**SPEC))
    import re
    w = float(re.search(r"shot_width below (\S+)", str(err.value)).group(1).rstrip(","))
    step = float(re.search(r"max_step below (\S+)", str(err.value)).group(1).rstrip(","))
    ok = map_model(m, CircuitSpec(**SPEC, max_step=step, shot_width=w))
    assert ok.bias["shot_pulse"] <= 0.05 * (1 + 1e-2)
