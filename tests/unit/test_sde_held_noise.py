"""simulate_sde's held noise (noise_hold) and the held/white pair integrated in one loop:
both must reproduce, bit for bit, the plain runs they replace (a repeated noise array, two
separate simulate_sde calls), since the report's bandwidth budget term is their difference."""
from __future__ import annotations

import numpy as np
import pytest

from analogue import Model
from analogue.montecarlo import simulate_sde, simulate_sde_held_pair

SMOOTH = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0, epsilon=0.01)   # tanh law
SGN = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
STRIBECK = Model(tau_m=1.0, delta=0.5, a=0.2, gamma=10.0, stribeck=(0.8, 0.3))


@pytest.mark.parametrize("model", [SMOOTH, SGN, STRIBECK])
def test_noise_hold_equals_the_repeated_array(model):
    rng = np.random.default_rng(3)
    reps, hold, n_hold, dt = 37, 4, 500, 1e-3
    m = rng.standard_normal((reps, n_hold))
    v0 = rng.normal(0, 0.3, reps)
    kw = dict(v0=v0, t_end=n_hold * hold * dt, replicas=reps, dt=dt, sample_dt=20 * dt)
    a = simulate_sde(model, noise=m, noise_hold=hold, **kw)
    b = simulate_sde(model, noise=np.repeat(m, hold, axis=1), **kw)
    assert np.array_equal(a.v, b.v) and np.array_equal(a.x, b.x)
    assert a.meta["noise_dt"] == pytest.approx(hold * dt)


@pytest.mark.parametrize("model", [SMOOTH, SGN, STRIBECK])
def test_held_pair_equals_two_separate_runs(model):
    rng = np.random.default_rng(4)
    reps, hold, n_hold, dt = 29, 8, 300, 1e-3
    z = rng.standard_normal((reps, n_hold * hold))
    kw = dict(v0=0.4, t_end=n_hold * hold * dt, replicas=reps, dt=dt, sample_dt=40 * dt)
    held, white = simulate_sde_held_pair(model, noise=z, noise_hold=hold, **kw)
    means = z.reshape(reps, n_hold, hold).mean(axis=2)
    h = simulate_sde(model, noise=np.repeat(means, hold, axis=1), **kw)
    w = simulate_sde(model, noise=z, **kw)
    assert np.array_equal(held.v, h.v) and np.array_equal(held.x, h.x)
    assert np.array_equal(white.v, w.v) and np.array_equal(white.x, w.x)
    assert not np.array_equal(held.v, white.v)   # the pair differs: held vs white noise


def test_noise_hold_bad_values_name_the_parameter():
    kw = dict(v0=0.0, t_end=0.1, replicas=2, dt=1e-3, sample_dt=1e-2)
    with pytest.raises(ValueError, match="noise_hold"):
        simulate_sde(SGN, noise=np.zeros((2, 100)), noise_hold=0, **kw)
    with pytest.raises(ValueError, match="noise_hold"):
        simulate_sde(SGN, noise=np.zeros((2, 34)), noise_hold=3, **kw)   # 3 does not divide 100
    with pytest.raises(ValueError, match="noise_hold"):
        simulate_sde(SGN, noise_hold=2, seed=1, **kw)                    # nothing to hold
    with pytest.raises(ValueError, match="shape"):
        simulate_sde(SGN, noise=np.zeros((2, 100)), noise_hold=2, **kw)
    with pytest.raises(ValueError, match="noise_hold"):
        simulate_sde_held_pair(SGN, noise=np.zeros((2, 100)), noise_hold=3, **kw)
