"""The held/white pair in chunks of replicas (issue 22: the bandwidth term's Monte Carlo on
every core): bit for bit one loop over all replicas on the noise drawn in one piece, whatever
the executor, so the report's numbers never depend on the core count."""
from __future__ import annotations

import multiprocessing
import math
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

from analogue import Model
from analogue.cores import limit_worker_threads
from analogue.montecarlo import default_dt, simulate_sde_held_pair
from analogue.study import budget
from analogue.study.budget import MIN_STEPS_PER_HOLD, held_noise_pair, held_noise_pair_chunks

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0, epsilon=0.05)
KW = dict(t_end=0.5, seed=21, noise_dt=0.01, sample_dt=0.05)


def _one_loop(v0, replicas):
    """The pair as held_noise_pair computed it before the chunks: the noise of every row in one
    draw, one loop over all rows."""
    per_hold = max(MIN_STEPS_PER_HOLD, math.ceil(0.01 / default_dt(STICK) - 1e-9))
    rng = np.random.default_rng(np.random.SeedSequence(KW["seed"], spawn_key=(7,)))
    z = rng.standard_normal((replicas, 50 * per_hold))
    return simulate_sde_held_pair(STICK, v0=v0, t_end=KW["t_end"], replicas=replicas, noise=z,
                                  noise_hold=per_hold, dt=0.01 / per_hold, sample_dt=0.05)


def _same(a, b):
    for name in ("t", "v", "x", "noise"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.meta == b.meta


@pytest.mark.parametrize("v0", [0.5, "array"])
def test_chunks_are_one_loop_bit_for_bit(monkeypatch, v0):
    replicas = 11
    v0 = np.linspace(-1.0, 1.0, replicas) if v0 == "array" else v0
    monkeypatch.setattr(budget, "PAIR_CHUNK", 4)          # 3 chunks: 4 + 4 + 3 rows
    want = _one_loop(v0, replicas)
    timing: list = []
    with ThreadPoolExecutor(2) as ex:
        got = held_noise_pair_chunks(STICK, v0=v0, replicas=replicas, executor=ex,
                                     timing=timing, **KW)()
    for g, w in zip(got, want):
        _same(g, w)
    assert len(timing) == 1 and len(timing[0][1]) == 3
    for g, w in zip(held_noise_pair(STICK, v0=v0, replicas=replicas, **KW), want):
        _same(g, w)


def test_chunks_in_worker_processes(monkeypatch):
    """Processes (a Dask-like executor) work too: spawned, one BLAS thread each."""
    monkeypatch.setattr(budget, "PAIR_CHUNK", 3)
    want = _one_loop(0.2, 7)
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(2, mp_context=ctx, initializer=limit_worker_threads) as ex:
        got = held_noise_pair(STICK, v0=0.2, replicas=7, executor=ex, **KW)
    for g, w in zip(got, want):
        _same(g, w)


def test_without_noise_the_paths_are_the_same(monkeypatch):
    """keep_noise=False (the report's bandwidth terms, which read only the paths): the same
    paths bit for bit, and no noise stacked (one chunk or several)."""
    for chunk in (4, 64):
        monkeypatch.setattr(budget, "PAIR_CHUNK", chunk)
        want = _one_loop(0.5, 11)
        with ThreadPoolExecutor(2) as ex:
            got = held_noise_pair_chunks(STICK, v0=0.5, replicas=11, executor=ex,
                                         keep_noise=False, **KW)()
        for g, w in zip(got, want):
            assert g.noise is None
            for name in ("t", "v", "x"):
                assert np.array_equal(getattr(g, name), getattr(w, name)), name
            assert g.meta == w.meta
