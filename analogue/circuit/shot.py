"""Poissonian shot noise as a seeded pulse source (issue 9, "Shot noise").

A kick is a velocity jump ``z``: the charge ``Q = C kappa z`` delivered to the mass capacitor.
The kicks of replica ``i`` of a deck with ngspice seed ``s`` are drawn in numpy from
``SeedSequence(s, spawn_key=(2, i))``: Poisson event times of rate ``rate`` on ``[0, t_end)``
(exponential gaps), jump sizes exponential with mean ``mean`` (sign +-1 with equal probability
if ``two_sided``).  Each kick becomes a flat-topped (trapezoidal) current pulse of width ``w`` (model
time; edges 1e-3 w) and area ``Q`` starting at the event time, written into the deck as a ``pwl(...)`` current
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
against the exact event-driven values mean 0.3126, variance 0.2148, P(|v| < 0.05) 0.4336;
machine under load): flat-topped PWL 15.5 s (144k time points), z = -1.77, -0.41, +1.94;
trrandom compound source with TS = 0.01 7.9 s (63k points), z = +0.19, +0.30, +0.21; with
TS = 0.001 47.6 s.  So the held trrandom source is as good for these stationary averages and
about 2x faster at 32 replicas per deck (the PWL corners of every replica shorten the shared
time steps of all), but its kicks sit on the hold grid, last TS (a kick error ~ max|drift|
TS/mean = 3 % per kick here, 30x the PWL's) and can only be recovered from saved held nodes;
the PWL route keeps exact kick times and sizes for a Monte Carlo driven by the same
realisation, which is what the project needs.  Delivered jumps (bare capacitor): within
5e-5 of the mean jump of the recorded ones (triangular pulses gave +1 %, see pulse_pwl).

Budget (the mapping's ``bias``): ``shot_edge``: EDGE/2, the edges' share of the charge
that the first-order steps after breakpoints may misintegrate; ``shot_pulse``: ``max|drift| w / mean``, the velocity error
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
EDGE = 1e-3       # rise and fall time of a pulse, as a fraction of its width (see pulse_pwl)


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


def pulse_pwl(starts, charges, width, edge: float = EDGE) -> tuple[np.ndarray, np.ndarray]:
    """(times, currents) of the PWL source: per kick a trapezoid of area ``charge`` on
    ``[start, start + width]`` with edges of ``edge * width``, summed (circuit units: s, C, A).
    Starts with (0, 0).  Corners closer than 1e-6 width are merged (the sum is continuous).

    Why flat-topped: ngspice restarts at every breakpoint with a first-order step, and its
    implicit integrators err on a current *ramp* (backward Euler takes the ramp's end value):
    measured on a bare capacitor, triangular pulses delivered +1.0 % too much charge with gear
    (+0.45 % with trap) at the default step limit, while a constant current is integrated
    exactly by any of them; the edges then contribute at most ~edge/2 of the charge."""
    starts = np.asarray(starts, dtype=float)
    charges = np.asarray(charges, dtype=float)
    rise = edge * width
    peak = charges / (width - rise)
    corners = np.concatenate([[0.0], starts, starts + rise, starts + width - rise, starts + width])
    corners = np.unique(corners)
    keep = np.concatenate([[True], np.diff(corners) > 1e-6 * width])
    corners = corners[keep]
    # sum of trapezoids evaluated at every corner (vectorised over kicks in chunks)
    current = np.zeros_like(corners)
    for lo in range(0, starts.size, 256):
        s = starts[lo:lo + 256, None]
        p = peak[lo:lo + 256, None]
        u = corners[None, :] - s  # time into each pulse
        shape = np.clip(np.minimum(u, width - u) / rise, 0.0, 1.0)
        current += np.sum(p * shape, axis=0)
    return corners, current
