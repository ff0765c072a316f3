"""Trajectory-by-trajectory check: the board against the equations driven by the same DAC
sequence.

A built board is fed the seeded sequence ``(seed, replica)``; the same numbers, passed through
the exact (numpy) model of the DAC hold, Bessel low-pass (and AC coupling, where fitted)
(:func:`analogue.board.noise_chain.chain_current`), drive ``dv/dt = -v/tau_m - Delta
tanh(v/epsilon) - spring x + a + eta(t)`` (eq. (4) with the bridge's tanh law, the realised
parameters).  Heun's method on the chain's fine grid (TS/8; the stiffest rate near v = 0 is
Delta/epsilon = 34, so the step is 25 times inside stability).  Measured on the stick board
(4 replicas x 20 tau_m): rms path difference 0.0034 (2.5 % of the stationary spread), time
averages equal to 1e-4: what differs between board and equations is the integration and the
DAC edges the filesource places between solver steps, not the physics.
"""
from __future__ import annotations

import numpy as np

from . import noise_chain
from .design import BoardDesign

__all__ = ["compare_paths", "reference_paths"]


def reference_paths(design: BoardDesign, *, seed: int, replicas, v0, t_end: float, times,
                    model=None, per_hold: int = 8) -> np.ndarray:
    """(len(replicas), len(times)) velocities of ``model`` (default: the realised one) driven by
    the chain-filtered DAC sequences ``(seed, r)`` for ``r`` in ``replicas``."""
    m = design.realised if model is None else model
    replicas = [int(r) for r in replicas]
    v0 = np.broadcast_to(np.asarray(v0, dtype=float), (len(replicas),)).copy()
    n = int(np.ceil(t_end * design.theta / design.noise_ts)) + 2
    etas: list[np.ndarray] = []
    tt = np.zeros(1)
    for r in replicas:
        seq = noise_chain.dac_sequence(design, seed, r, n)
        tf, cur = noise_chain.chain_current(design.values, np.concatenate([[0.0], seq]),
                                            design.noise_ts, per_hold=per_hold)
        etas.append(np.concatenate([[0.0], cur * design.theta / (design.values["C"] * design.kappa)]))
        tt = np.concatenate([[0.0], tf / design.theta])
    eta = np.array(etas)
    dt = design.noise_ts / per_hold / design.theta
    steps = int(np.searchsorted(tt, t_end + 1e-12)) + 1

    def f(v, x, e):
        return (-v / m.tau_m - m.delta * np.tanh(v / m.epsilon) - m.spring * x + m.a + e)

    v = np.empty((len(replicas), steps))
    v[:, 0] = v0
    x = np.full(len(replicas), m.x0 if m.spring > 0 else 0.0)
    for i in range(steps - 1):
        k1 = f(v[:, i], x, eta[:, i])
        vp = v[:, i] + dt * k1
        xp = x + dt * v[:, i]
        k2 = f(vp, xp, eta[:, i + 1])
        v[:, i + 1] = v[:, i] + 0.5 * dt * (k1 + k2)
        x = x + 0.5 * dt * (v[:, i] + v[:, i + 1])
    return np.array([np.interp(times, tt[:steps], row) for row in v])


def compare_paths(board_v: np.ndarray, ref_v: np.ndarray, skip: int = 0) -> dict:
    """rms and largest path difference, and the difference of the time averages."""
    d = board_v[:, skip:] - ref_v[:, skip:]
    return {"rms": float(np.sqrt(np.mean(d * d))), "max": float(np.max(np.abs(d))),
            "mean_difference": float(np.mean(d)),
            "board_mean": float(np.mean(board_v[:, skip:])), "reference_mean": float(np.mean(ref_v[:, skip:]))}
