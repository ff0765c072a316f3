"""The time-stepped Monte Carlo loop (analogue.montecarlo._stepped) against the plain loop it
replaced (_stepped_reference: one numpy expression per term and step), bit for bit.

The fast loop reorders the work (the noise scaled per block, the force in preallocated
buffers, the position's trapezoid increments per block and added per step) but must keep
every floating-point operation and its order: the report's bandwidth term and its
reproducibility from seeds rely on it.  The cases cover each branch of the force (tanh, sgn,
Stribeck, cubic, Gaussian + shot kicks), both schemes, seeded and given noise (held, and the
held/white pair's two parts), a single row, output intervals that do not divide the hold,
and several blocks with a short last one and output intervals straddling them.
"""
from __future__ import annotations

import numpy as np
import pytest

from analogue import Model, ShotNoise
from analogue import montecarlo as mc

SMOOTH = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0, epsilon=0.01)
SGN = Model(tau_m=1.0, delta=0.7, a=1.2, gamma=10.0)
STRIBECK = Model(tau_m=1.0, delta=0.5, a=0.2, gamma=10.0, stribeck=(0.8, 0.3))
CUBIC = Model(tau_m=1.0, delta=0.5, a=1.5, gamma=10.0, cubic=1.0, epsilon=0.02)
KICKS = Model(tau_m=1.0, delta=0.5, a=-0.3, gamma=20.0, shot=ShotNoise(2.0, 0.3, two_sided=True))
MODELS = {"tanh": SMOOTH, "sgn": SGN, "stribeck": STRIBECK, "cubic": CUBIC, "kicks": KICKS}


def _both(model, rows, n_steps, per, scheme, parts, seed=7, dt=1e-3):
    """(fast, reference) outputs for the same inputs and fresh, equally seeded streams."""
    v0 = np.random.default_rng(1).normal(0.0, 0.5, rows)
    out = []
    for loop in (mc._stepped, mc._stepped_reference):
        _, noise_rng, kick_rng = mc._streams(seed)
        out.append(loop(model, v0.copy(), n_steps, per, dt, scheme, parts, noise_rng, kick_rng))
    return out


def _identical(fast, ref):
    assert np.array_equal(fast[0], ref[0])
    assert np.array_equal(fast[1], ref[1])
    assert fast[2] == ref[2]
    assert np.all(np.isfinite(fast[0])) and np.all(np.ptp(fast[0], axis=1) > 0)   # paths moved


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("scheme", mc.SCHEMES)
def test_seeded_loop_is_the_reference_bit_for_bit(name, scheme, monkeypatch):
    # small blocks: 3 of 120 steps and a last one of 40, and (per = 7) output intervals
    # that straddle blocks
    monkeypatch.setattr(mc, "_BLOCK_NUMBERS", 120 * 13)
    fast, ref = _both(MODELS[name], 13, 400, 8, scheme, None)
    _identical(fast, ref)
    _identical(*_both(MODELS[name], 13, 399, 7, scheme, None))
    if name == "kicks":
        assert fast[2] > 0


@pytest.mark.parametrize("name", ["tanh", "sgn", "stribeck", "kicks"])
@pytest.mark.parametrize("rows, per, hold", [(1, 5, 1), (7, 3, 4), (29, 8, 8), (4, 12, 6)])
def test_given_held_pair_is_the_reference_bit_for_bit(name, rows, per, hold, monkeypatch):
    """Two parts as in simulate_sde_held_pair (hold means, then the white normals) and the
    single held part of simulate_sde(noise=, noise_hold=)."""
    monkeypatch.setattr(mc, "_BLOCK_NUMBERS", 46 * 2 * rows)   # blocks not whole intervals
    n_steps = 24 * 25          # a whole number of every hold and interval above
    z = np.random.default_rng(2).standard_normal((rows, n_steps))
    means = z.reshape(rows, n_steps // hold, hold).mean(axis=2)
    fast, ref = _both(MODELS[name], 2 * rows, n_steps, per, "exponential",
                      ((means, hold), (z, 1)))
    _identical(fast, ref)
    fast, ref = _both(MODELS[name], rows, n_steps, per, "euler", ((means, hold),))
    _identical(fast, ref)


def test_block_size_does_not_change_a_seeded_run(monkeypatch):
    """The seeded normals are drawn block by block: the run must not depend on the block."""
    kw = dict(v0=0.3, t_end=0.6, replicas=9, seed=11, dt=1e-3, sample_dt=0.01)
    a = mc.simulate_sde(SMOOTH, **kw)
    monkeypatch.setattr(mc, "_BLOCK_NUMBERS", 9 * 30)
    b = mc.simulate_sde(SMOOTH, **kw)
    assert np.array_equal(a.v, b.v) and np.array_equal(a.x, b.x)


def test_seeded_run_is_driven_by_standard_noise():
    """simulate_sde(seed=s) equals simulate_sde(noise=standard_noise(s, ...)) (the seeded loop
    fills its block buffer in place; the given-noise loop scales the given array)."""
    kw = dict(v0=0.3, t_end=0.5, replicas=6, dt=1e-3, sample_dt=0.01)
    a = mc.simulate_sde(SGN, seed=4, **kw)
    b = mc.simulate_sde(SGN, noise=mc.standard_noise(4, 6, 500), **kw)
    assert np.array_equal(a.v, b.v) and np.array_equal(a.x, b.x)


def test_spring_member_takes_the_reference_loop():
    spring = Model(tau_m=1.0, delta=0.5, a=0.2, gamma=10.0, spring=4.0)
    fast, ref = _both(spring, 5, 300, 10, "exponential", None)
    _identical(fast, ref)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf, "inf and -inf"])
def test_non_finite_noise_is_refused(bad):
    """The finiteness check goes through sums (an inf or nan term makes a sum non-finite):
    every kind of non-finite value is still refused, by both entry points."""
    z = np.random.default_rng(5).standard_normal((3, 100))
    if bad == "inf and -inf":          # their sum is nan, within one hold of 4
        z[1, 40], z[1, 41] = np.inf, -np.inf
    else:
        z[2, 77] = bad
    kw = dict(v0=0.0, t_end=0.1, replicas=3, dt=1e-3, sample_dt=1e-2)
    with pytest.raises(ValueError, match="noise must be finite"):
        mc.simulate_sde(SGN, noise=z, **kw)
    with pytest.raises(ValueError, match="noise must be finite"):
        mc.simulate_sde_held_pair(SGN, noise=z, noise_hold=4, **kw)


def test_finite_noise_whose_sums_overflow_is_accepted():
    """Finite values whose sums overflow to inf are not refused (the elementwise fallback)."""
    z = np.full((2, 100), 1e308)
    kw = dict(v0=0.0, t_end=0.1, replicas=2, dt=1e-3, sample_dt=1e-2)
    with np.errstate(over="ignore", invalid="ignore"):
        mc.simulate_sde(SGN, noise=z, **kw)
        mc.simulate_sde_held_pair(SGN, noise=z, noise_hold=4, **kw)
