"""Every seed of one experiment's report, derived from the experiment's seed in one place.

Each run of a report (circuit runs, the held/white-noise Monte Carlo pairs of the bandwidth
budget, the stationary starting velocities) gets its own integer seed, a fixed offset from
``1000 * experiment.seed``; :func:`analogue.simulate` and :mod:`analogue.montecarlo` turn it
into a ``numpy.random.SeedSequence``.  Experiments with different seeds never share a
realisation (offsets stay below 1000).

These are exactly the integers the report used before this module existed (scattered over
``report/runs.py`` and ``report/comparisons.py``), so stored runs and every number of the
report are unchanged.  Deriving them instead with ``SeedSequence(seed).spawn`` would be a
change of this module alone, but it changes every noise realisation and so every number: it
needs a re-run of the report and a check that every comparison stays within its budget.
"""
from __future__ import annotations

from dataclasses import dataclass

from .. import checks

__all__ = ["SeedPlan"]

_STRIDE = 1000
_OFFSETS = {"stationary": 500, "noise_free": 900, "mc_stationary": 700,
            "mc_stationary_v0": 701,
            # the family members' chapter (report.beyond): its runs use member + 0..5
            "member": 800}
_MC_TRANSITION = 600          # + index of v0
_MAX_V0 = 100                 # transition runs use offsets 0..99, their Monte Carlo 600..699


@dataclass(frozen=True)
class SeedPlan:
    """The seeds of one experiment (``seed``: the experiment's ``[experiment] seed``)."""

    seed: int

    def __post_init__(self):
        object.__setattr__(self, "seed", checks.integer("seed", self.seed, minimum=0))

    @property
    def base(self) -> int:
        return _STRIDE * self.seed

    def _index(self, i: int) -> int:
        if not 0 <= i < _MAX_V0:
            raise ValueError(f"v0 index must be in [0, {_MAX_V0}), got {i!r}")
        return i

    def transition(self, i: int) -> int:
        """Circuit transition run from the i-th v0 (its integration check reuses it)."""
        return self.base + self._index(i)

    def mc_transition(self, i: int) -> int:
        """Held/white-noise Monte Carlo pair of the i-th transition run (bandwidth budget)."""
        return self.base + _MC_TRANSITION + self._index(i)

    def __getattr__(self, name: str) -> int:
        # stationary, noise_free, mc_stationary, mc_stationary_v0, member
        if name in _OFFSETS:
            return self.base + _OFFSETS[name]
        raise AttributeError(name)

    def all(self, n_v0: int) -> dict:
        """Every seed by name (for the provenance)."""
        out = {f"transition {i}": self.transition(i) for i in range(n_v0)}
        out.update({f"mc_transition {i}": self.mc_transition(i) for i in range(n_v0)})
        out.update({k: self.base + v for k, v in _OFFSETS.items()})
        return out
