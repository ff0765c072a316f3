"""Poissonian shot noise as a seeded pulse source (issue 9, "Shot noise").

A kick is a velocity jump ``z``: the charge ``Q = C kappa z`` delivered to the mass capacitor.
The kicks of replica ``i`` of a deck with ngspice seed ``s`` are drawn in numpy from
``SeedSequence(s, spawn_key=(2, i))``: Poisson event times of rate ``rate`` on ``[0, t_end)``
(exponential gaps), jump sizes exponential with mean ``mean`` (sign +-1 with equal probability
if ``two_sided``).  Each kick becomes a triangular current pulse of width ``w`` (model time)
and area ``Q`` starting at the event time, written into the deck as a ``pwl(...)`` current
source into the velocity node; overlapping pulses add (the PWL is evaluated on the union of
all corners, which is exact because a sum of PWL functions is PWL on the union of their
corners).  ngspice puts a breakpoint at every PWL corner, so the pulses are integrated without
stepping over them; between kicks the source costs nothing.

Why PWL and not ngspice's ``trrandom`` types 3 (exponential) and 4 (Poisson): those are
*held* random values, redrawn every ``TS``; a compound Poisson process built from them
(``count x size / TS`` per hold) puts every kick at a hold boundary (time discretisation
``TS``), merges the kicks of one hold into ``N x E`` instead of a sum of N exponentials
(wrong jump law with probability ~ rate TS / 2), and forces a breakpoint every TS on every
replica even when nothing happens (at rate 1 and TS = tau_m/100 that is 100 breakpoints per
kick).  The PWL source has exact event times and jump sizes and ~3 corners per kick, the
kicks are known in numpy (so a Monte Carlo can be driven by the very same realisation:
:func:`deck_kicks`), and it is reproducible by construction.  Its cost grows with the number
of corners in the source text (the theory notes measured 32 s for 4000 points x 50 replicas
of inline PWL noise), which at ~3 corners per kick keeps small for rates ~ 1/tau_m.

Measured (benchmarks/bench_family_circuit.py; tau_m = 1, Delta = 0.5, a = 0.2, rate 1,
mean 0.5, gamma = inf; 32 replicas in one deck, t = 100, stationary averages after t = 5
against the exact event-driven values mean 0.3126, variance 0.2148, P(|v| < 0.05) 0.4336):
PWL 3.5 s (83k time points), z = -1.43, -0.13, +1.75; trrandom compound source with
TS = 0.01 2.6 s (63k points), z = +0.19, +0.30, +0.21; with TS = 0.001 21 s.  So the held
trrandom source is as good for these stationary averages and 1.4x faster at 32 replicas per
deck (the PWL corners of every replica shorten the shared time steps of all), but its kicks
sit on the hold grid, last TS (a kick error ~ max|drift| TS/mean = 3 % per kick here, 30x
the PWL's) and can only be recovered from saved held nodes; the PWL route keeps exact kick
times and sizes for a Monte Carlo driven by the same realisation, which is what the project
needs.

Budget (the mapping's ``bias``): ``shot_pulse``: ``max|drift| w / mean``, the velocity error
of one kick relative to the mean jump, because the drift acts during the pulse's width and
the friction kink may be crossed inside it (for a linear drift the pulse is equivalent to an
instantaneous kick at its centre ``t_k + w/2``; the recorded kick times are these centres);
``shot_overlap``: ``rate w``, the fraction of kicks whose pulse overlaps another's (harmless
for the velocity, reported for completeness).  The event times are exact (no time grid).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["KICK_STREAM", "deck_kicks", "pulse_pwl", "replica_kicks"]

KICK_STREAM = 2  # SeedSequence spawn_key prefix of the kick streams (0: v0 draws, 1: decks)


def replica_kicks(rate: float, mean: float, two_sided: bool, t_end: float, seed: int,
                  index: int) -> tuple[np.ndarray, np.ndarray]:
    """Kick (start times, signed jump sizes) of replica ``index`` of the deck with seed ``seed``,
    in model units, on ``[0, t_end)``."""
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(KICK_STREAM, int(index))))
    n_guess = int(rate * t_end + 10.0 * math.sqrt(rate * t_end + 1.0) + 10)
    times = np.cumsum(rng.exponential(1.0 / rate, n_guess))
    while times[-1] < t_end:  # (only if the guess was short: extend the same stream)
        times = np.concatenate([times, times[-1] + np.cumsum(rng.exponential(1.0 / rate, n_guess))])
    times = times[times < t_end]
    sizes = rng.exponential(mean, times.size)
    if two_sided:
        sizes = sizes * np.where(rng.random(times.size) < 0.5, -1.0, 1.0)
    return times, sizes


def deck_kicks(model, t_end: float, seed: int, replicas: int):
    """Kicks of every replica of one deck: a list of (start times, sizes); the effective
    (centre) time of a kick with pulse width w is ``start + w/2``."""
    shot = model.shot
    return [replica_kicks(shot.rate, shot.mean, shot.two_sided, t_end, seed, i)
            for i in range(replicas)]


def pulse_pwl(starts, charges, width) -> tuple[np.ndarray, np.ndarray]:
    """(times, currents) of the PWL source: a triangle of area ``charge`` on
    ``[start, start + width]`` per kick, summed (all in circuit units: s, C, A).  Starts with
    (0, 0).  Corners closer than 1e-6 width are merged (the sum is continuous there)."""
    starts = np.asarray(starts, dtype=float)
    charges = np.asarray(charges, dtype=float)
    peak = 2.0 * charges / width
    corners = np.concatenate([[0.0], starts, starts + 0.5 * width, starts + width])
    corners = np.unique(corners)
    keep = np.concatenate([[True], np.diff(corners) > 1e-6 * width])
    corners = corners[keep]
    # sum of triangles evaluated at every corner (vectorised over kicks in chunks)
    current = np.zeros_like(corners)
    for lo in range(0, starts.size, 256):
        s = starts[lo:lo + 256, None]
        p = peak[lo:lo + 256, None]
        u = (corners[None, :] - s) / width  # position within each pulse, 0..1
        tri = np.where((u > 0) & (u < 1), 1.0 - np.abs(2.0 * u - 1.0), 0.0)
        current += np.sum(p * tri, axis=0)
    return corners, current
