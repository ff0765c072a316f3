"""The bandwidth pair (held against white Gaussian noise) of a member with shot noise on as
well (issue 9 QA): the report of a shot + Gaussian member failed with "simulate_sde_held_pair
needs Gaussian noise only" since the pair was fused into one loop (81c60ae); before that the
two runs drew their kicks from unseeded streams, so the pair's difference held kick noise too.
"""
from __future__ import annotations

import numpy as np

from analogue import Model, ShotNoise
from analogue.study.budget import held_noise_pair


def test_pair_runs_and_shares_the_kicks():
    # weak Gaussian noise (gamma = 1e3, std 0.03): held and white then differ only by its
    # hold, so the paths stay close when both runs see the same kicks (rate 2, mean 0.3: ~10
    # kicks each); with independent kicks they differ by ~0.3
    m = Model(1.0, 0.5, -0.3, 1e3, shot=ShotNoise(2.0, 0.3, two_sided=True))
    held, white = held_noise_pair(m, v0=0.2, t_end=5.0, replicas=8, seed=5, noise_dt=0.01,
                                  sample_dt=0.02)
    assert held.v.shape == white.v.shape == (8, 251)
    jumps = np.abs(np.diff(white.v, axis=1)).max()
    assert jumps > 0.1                        # kicks happened
    assert np.max(np.abs(held.v - white.v)) < 0.05 * jumps


def test_pair_with_kicks_differs_by_the_hold_only():
    """gamma = 20: the pair's difference is the hold's effect, of the order of the Gaussian
    part, not the kicks' (mean 0.3)."""
    m = Model(1.0, 0.5, -0.3, 20.0, shot=ShotNoise(2.0, 0.3, two_sided=True))
    held, white = held_noise_pair(m, v0=0.0, t_end=10.0, replicas=16, seed=6, noise_dt=0.01,
                                  sample_dt=0.02)
    d = held.v - white.v
    assert np.sqrt(np.mean(d**2)) < 0.05 * np.sqrt(np.mean(white.v**2))
