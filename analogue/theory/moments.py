"""The stationary observables' record, :class:`StationaryMoments`, returned by every exact route:
:mod:`analogue.theory.stationary` (the paper's model) and :mod:`analogue.theory.family` (the
members).  It lives here, below both, so that neither imports the other for it."""
from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import asdict, dataclass, fields

__all__ = ["StationaryMoments"]


@dataclass(frozen=True)
class StationaryMoments(Mapping[str, float]):
    """Stationary observables (exact at the given gamma).  Also a read-only mapping.

    mean, drift : <v> (drift is the same number: the mean sliding velocity, dx/dt on average)
    variance    : <v^2> - <v>^2
    p_positive  : P(v > 0);  p_negative: P(v < 0) (each computed directly, not as 1 - other)
    mean_sign   : <sgn v> (epsilon = 0) or <tanh(v/epsilon)>
    diffusion   : Green-Kubo D_x = int_0^inf <dv(0) dv(t)> dt; Var x(t) ~ 2 D_x t
    p_zero      : P(v = 0), the atom of the law (probability of being stuck): 0 except for
                  pure shot noise in the stick regime (:mod:`analogue.theory.family`)
    """

    mean: float
    variance: float
    p_positive: float
    p_negative: float
    mean_sign: float
    diffusion: float
    drift: float
    p_zero: float = 0.0

    def as_dict(self) -> dict[str, float]:
        return asdict(self)

    def __getitem__(self, key: str) -> float:
        if key not in self._names():
            raise KeyError(key)
        return float(getattr(self, key))

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())

    def __len__(self) -> int:
        return len(self._names())

    @classmethod
    def _names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))
