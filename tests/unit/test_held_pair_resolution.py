"""The held/white pair of the bandwidth budget resolves every hold (issue 18 item 7): its
"white" run is noise held over one fine step, so the pair measures b(hold) - b(fine step).
The fine step was the model's default_dt alone: a circuit hold at or below it gave one fine
step per hold, a "white" run identical to the held one and a bandwidth term of exactly 0."""
from __future__ import annotations

import numpy as np

from analogue import Model
from analogue.montecarlo import default_dt
from analogue.study.budget import MIN_STEPS_PER_HOLD, held_noise_pair

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0, epsilon=0.02 * np.sqrt(0.1))


def test_fine_hold_is_resolved():
    hold = 0.0005                     # below default_dt (0.1 epsilon/Delta = 9e-4)
    assert default_dt(STICK) > hold    # main: one fine step per hold, held == white
    held, white = held_noise_pair(STICK, v0=0.0, t_end=1.0, replicas=8, seed=3, noise_dt=hold,
                                  sample_dt=0.01)
    assert held.meta["dt"] * MIN_STEPS_PER_HOLD <= hold * (1 + 1e-12)
    # the runs differ (the hold's effect), by little against the spread
    d = np.abs(held.v - white.v)
    assert float(d.max()) > 0.0
    assert float(np.sqrt(np.mean(d ** 2))) < 0.1 * float(np.std(white.v))


def test_coarse_hold_keeps_the_model_step():
    """A coarse hold still uses at most default_dt (the kink's own resolution)."""
    held, _ = held_noise_pair(STICK, v0=0.0, t_end=1.0, replicas=4, seed=3, noise_dt=0.05,
                              sample_dt=0.05)
    assert held.meta["dt"] <= default_dt(STICK) * (1 + 1e-12)
    assert held.meta["dt"] * MIN_STEPS_PER_HOLD <= 0.05 * (1 + 1e-12)
