"""The shot pulses of the circuit are the kicks' own (analogue.variants.noise.Shot.pulses,
issue 20): the chosen width makes the pulse budget term its target, is never below the floor
of the solver step, a given width below the floor is refused naming shot_width; noises
without kicks have no pulses; a spring adds its force over the position's reach."""
import math

import pytest

from analogue import Model, ShotNoise
from analogue.variants import Free, Gaussian, Shot, Spring


def test_width_from_the_target_floor_and_refusal():
    shot = Shot(ShotNoise(2.0, 0.4))
    charge, w, bias = shot.pulses(3.0, lambda jump: 5.0 * jump, 0.01, None,
                                  min_width=1e-3, target=1e-3, edge=0.02)
    assert charge == 3.0
    assert bias["shot_pulse"] == pytest.approx(1e-3)      # drift_max w/mean = the target
    assert bias["shot_overlap"] == pytest.approx(2.0 * w) and bias["shot_edge"] == 0.01
    # a tiny drift would give a wide pulse; a huge one is held at the floor 1e-3 x step
    _, w_floor, _ = shot.pulses(3.0, lambda jump: 1e9, 0.01, None, min_width=1e-3,
                                target=1e-3, edge=0.02)
    assert w_floor == pytest.approx(1e-5)
    with pytest.raises(ValueError, match="shot_width"):
        shot.pulses(3.0, lambda jump: 1.0, 0.01, 1e-7, min_width=1e-3, target=1e-3, edge=0.0)
    assert Gaussian(10.0).pulses(3.0, lambda jump: 1 / 0, 0.01, None, min_width=1e-3,
                                 target=1e-3, edge=0.02) == (0.0, 0.0, {})


def test_spring_reach():
    assert Free(0.0).kick_drift(None, 0.5, 0.4, 1.0) == 0.0
    s = Spring(2.0, -1.5)
    assert s.kick_drift(None, 0.5, 0.4, 1.0) == pytest.approx(2.0 * (1.5 + 0.25 + 3.2 + 1.0))
    m = Model(1.0, 0.5, 0.2, math.inf, shot=ShotNoise(1.0, 0.4), spring=2.0, x0=-1.5)
    assert isinstance(m.restoring, Spring) and isinstance(m.noise_kind, Shot)
