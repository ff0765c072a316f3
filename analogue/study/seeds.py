"""Every seed of one experiment's report, derived from one ``numpy.random.SeedSequence`` plan.

The plan is the seed sequence of the experiment's ``[experiment] seed``.  Each stream of a
report (circuit runs, the noise-free run, the held/white-noise Monte Carlo pairs of the
bandwidth budget, the stationary starting velocities, the family members' runs and Monte
Carlo references, the board job's noise, pairs, sensitivities and Monte Carlo boards) has a fixed name and spawn key: stream ``k``, index ``i`` is the
grandchild ``SeedSequence(seed, spawn_key=(k, i))``, i.e. ``SeedSequence(seed).spawn(k + 1)[k]
.spawn(i + 1)[i]`` in numpy's spawn tree, so streams are statistically independent and a new
stream (a new key) leaves every other seed unchanged.  Its first 32-bit word, reduced to
``1 .. 2**31 - 1``, is the integer handed to :func:`analogue.simulate`, the Monte Carlo or
``build_deck`` (ngspice parses ``.options seed=`` as a C int: ``build_deck`` refuses seeds
above ``2**31 - 1``).

Stream keys start at 100, clear of the spawn keys that :mod:`analogue.circuit.simulate`
(0, 1, 2), :mod:`analogue.study.budget` (7) and the board (13, 17) apply to the seeds they
are given.  The plan replaced fixed offsets from ``1000 * seed`` (which :func:`SeedPlan.all`
no longer produces): every noise realisation of the report changed with it, and the quick
reports were re-run and checked against their budgets (commit message).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import checks

__all__ = ["SeedPlan", "STREAMS", "SEED_MAX"]

SEED_MAX = 2**31 - 1          # ngspice's `.options seed` is a C int

# stream name -> spawn key (never renumber: stored runs are keyed by the seeds)
STREAMS = {
    # the paper's experiments (study.runs, study.comparisons)
    "transition": 100,          # circuit transition run from the i-th v0 (+ its check)
    "mc_transition": 101,       # held/white Monte Carlo pair of the i-th transition run
    "stationary": 102,          # stationary circuit run (+ its starting velocities, check)
    "noise_free": 103,          # the noise-free deck
    "mc_stationary": 104,       # held/white Monte Carlo pair of the stationary run
    "mc_stationary_v0": 105,    # its starting velocities
    # the family members (report.beyond)
    "member_circuit": 110,      # 1-D: stationary run (+ check); spring: the release run
    "member_monte_carlo": 111,  # spring: the Monte Carlo reference (ideal and smoothed)
    "member_stationary_v0": 112,  # 1-D: starting velocities of the stationary run
    "member_transition": 113,   # 1-D: transition run
    "member_band_v0": 114,      # 1-D: starting velocities of the held/white pair
    "member_band": 115,         # 1-D: the held/white Monte Carlo pair
    # the board job (board.job): its noise (ngspice DAC sequence, references, calibration)
    "board_noise": 120,
    "board_stationary_v0": 121,   # starting velocities of the nominal board
    "board_pair_v0": 122,         # ... of the coloured/white SDE pair
    "board_pair": 123,            # the coloured/white SDE pair and the bandwidth study
    "board_sensitivities": 124,   # tolerance sensitivities
    "board_monte_carlo": 125,     # Monte Carlo boards (component draws)
    # "what experiments measure" (study.measure): held/white Monte Carlo pairs
    "measure_spectrum_pair": 130,      # the stationary pair (spectrum bands, Einstein ratio)
    "measure_spectrum_pair_v0": 131,   # its starting velocities
    "measure_first_passage_pair": 132,  # first passage from the i-th v0
    # parameter sweeps (study.sweep): per grid point, keyed by the point's model
    # (study.sweep.point_seed), not by an index
    "sweep_stationary": 140,      # the point's stationary circuit run (+ its starting velocities)
    "sweep_first_passage": 141,   # the point's first-passage circuit run
    "sweep_band": 142,            # the point's held/white Monte Carlo pairs
}
_INDEXED = {"transition", "mc_transition", "measure_first_passage_pair"}
# streams whose seeds depend on more than (seed, index): not in SeedPlan.all
_POINTWISE = {"sweep_stationary", "sweep_first_passage", "sweep_band"}
_MAX_INDEX = 100


def _derive(seed: int, key: int, index: int) -> int:
    word = np.random.SeedSequence(seed, spawn_key=(key, index)).generate_state(1, np.uint32)[0]
    return int(word) % SEED_MAX + 1


@dataclass(frozen=True)
class SeedPlan:
    """The seeds of one experiment (``seed``: the experiment's ``[experiment] seed``)."""

    seed: int

    def __post_init__(self):
        object.__setattr__(self, "seed", checks.integer("seed", self.seed, minimum=0))

    def stream(self, name: str, index: int = 0) -> int:
        """The seed of stream ``name`` (a key of :data:`STREAMS`), ``index`` for the
        per-v0 streams; an int in ``1 .. 2**31 - 1``."""
        if name not in STREAMS or name in _POINTWISE:
            raise ValueError(f"seed stream must be one of "
                             f"{', '.join(k for k in STREAMS if k not in _POINTWISE)}; got "
                             f"{name!r} (the sweep streams' seeds: analogue.study.sweep."
                             f"point_seed)")
        index = checks.integer("v0 index", index, minimum=0, maximum=_MAX_INDEX - 1)
        if index and name not in _INDEXED:
            raise ValueError(f"seed stream {name!r} has one seed (index 0), got index {index!r}")
        return _derive(self.seed, STREAMS[name], index)

    def transition(self, i: int) -> int:
        """Circuit transition run from the i-th v0 (its integration check reuses it)."""
        return self.stream("transition", i)

    def mc_transition(self, i: int) -> int:
        """Held/white-noise Monte Carlo pair of the i-th transition run (bandwidth budget)."""
        return self.stream("mc_transition", i)

    def __getattr__(self, name: str) -> int:
        # stationary, noise_free, mc_stationary, mc_stationary_v0, member_*
        if name in STREAMS and name not in _INDEXED and name not in _POINTWISE:
            return self.stream(name)
        raise AttributeError(name)

    def all(self, n_v0: int) -> dict:
        """Every seed by name (for the provenance)."""
        out = {f"transition {i}": self.transition(i) for i in range(n_v0)}
        out.update({f"mc_transition {i}": self.mc_transition(i) for i in range(n_v0)})
        out.update({k: self.stream(k) for k in STREAMS
                    if k not in _INDEXED and k not in _POINTWISE})
        return out

    def describe(self) -> dict:
        """The plan itself, for the provenance: how every seed above was derived."""
        return {"entropy": int(self.seed),
                "rule": "SeedSequence(entropy, spawn_key=(stream key, index))"
                        ".generate_state(1, uint32)[0] % (2**31 - 1) + 1",
                "streams": dict(STREAMS)}
