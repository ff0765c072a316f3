"""The catalogue of theory quantities that ``analogue theory`` answers (:data:`QUANTITIES`):
for each, the options it uses, the theories (``kind``) it offers and what it returns.

Its own module, apart from :mod:`analogue.theory.query` which computes them, so that the CLI's
``--help`` lists the quantities without loading the theories (and scipy with them).
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["KINDS", "OPTION_NAMES", "QUANTITIES", "Quantity"]

KINDS = ("exact", "weak-noise", "limit")


@dataclass(frozen=True)
class Quantity:
    name: str
    options: tuple[str, ...]   # the options it needs, e.g. ("t", "v", "v0")
    kinds: tuple[str, ...]     # the theories it offers (first = default); () = no choice
    summary: str
    optional: tuple[str, ...] = ()    # options it may use

    def default_kind(self) -> str | None:
        return self.kinds[0] if self.kinds else None


QUANTITIES: dict[str, Quantity] = {q.name: q for q in (
    Quantity("stationary", (), ("exact",), "moments of the stationary law p_s, eq. (6)"),
    Quantity("deterministic", ("t", "v0"), (), "noise-free velocity v(t) from v0, eq. (13)"),
    Quantity("action", ("t", "v", "v0"), ("weak-noise",),
             "least action to (v, t), kind of path, switching times"),
    Quantity("path", ("t", "v", "v0"), ("weak-noise",),
             "points (s, v*(s)) of the optimal path to (v, t)", optional=("points",)),
    Quantity("boundaries", ("t", "v0"), ("weak-noise",),
             "w, u, w_cr between path kinds, eqs. (41), (45), (49)"),
    Quantity("propagator", ("t", "v", "v0"), ("exact", "weak-noise"),
             "transition density f(v, t | v0), eqs. (46)-(51)"),
    Quantity("rate-function", ("w",), ("exact", "weak-noise", "limit"),
             "work rate function I(w), eq. (64)"),
    Quantity("fluctuation-relation", ("w",), ("exact", "weak-noise", "limit"),
             "I(-w) - I(w), eq. (67)"),
    Quantity("scgf", ("k",), ("exact",), "scaled cumulant generating function lambda(k)"),
    Quantity("work-pdf", ("w", "tau"), ("exact",), "density of w = W_tau/tau at finite tau"),
)}

OPTION_NAMES = {"t": "--t", "v": "--v", "v0": "--v0", "w": "--w", "k": "--k", "tau": "--tau",
                 "points": "--points"}
