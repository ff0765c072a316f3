"""Resampling errors over independent replicas: the delete-a-group jackknife of any scalar
observables of an ensemble, alone or as the difference of two paired ensembles (row i of both
driven by the same noise).

Replicas are independent, so these errors hold however correlated the samples along one path
are; the observables are plain functions ``fn(ensemble) -> {name: value}`` (the report's come
from :mod:`analogue.study.catalogue`).
"""
from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike

from ..ensemble import Ensemble

# an observable set: ensemble -> {name: value}
Observables = Callable[[Ensemble], Mapping[str, float]]

__all__ = ["jackknife", "jackknife_difference", "subset"]


def subset(ens: Ensemble, rows: np.ndarray) -> Ensemble:
    return Ensemble(ens.t, ens.v[rows], ens.x[rows], ens.meta)


def _groups(n: int, groups: int) -> tuple[int, np.ndarray]:
    g = max(2, min(groups, n // 2))
    return g, np.arange(n) % g


def _jk_se(reps: ArrayLike, g: int) -> float:
    d = np.asarray(reps, dtype=float)
    return float(np.sqrt((g - 1) / g * np.sum((d - d.mean()) ** 2)))


def jackknife(fn: Observables, ens: Ensemble, groups: int = 32
              ) -> dict[str, tuple[float, float]]:
    """``fn(ens)`` with delete-a-group jackknife errors over replicas (which are independent,
    so the errors hold however correlated the samples along one path are);
    returns ``{name: (value, se)}``."""
    g, labels = _groups(ens.replicas, groups)
    full = fn(ens)
    reps = [fn(subset(ens, labels != j)) for j in range(g)]
    return {k: (float(full[k]), _jk_se([r[k] for r in reps], g)) for k in full}


def jackknife_difference(fn: Observables, a: Ensemble, b: Ensemble, groups: int = 16
                         ) -> dict[str, tuple[float, float]]:
    """``fn(a) - fn(b)`` for paired ensembles (row i of a and b share their noise), with
    delete-a-group jackknife standard errors; returns ``{name: (diff, se)}``."""
    if b.replicas != a.replicas:
        raise ValueError("paired ensembles need the same number of replicas")
    g, labels = _groups(a.replicas, groups)
    full_a, full_b = fn(a), fn(b)
    reps = []
    for j in range(g):
        keep = labels != j
        fa, fb = fn(subset(a, keep)), fn(subset(b, keep))
        reps.append({k: fa[k] - fb[k] for k in full_a})
    return {k: (float(full_a[k] - full_b[k]), _jk_se([r[k] for r in reps], g)) for k in full_a}
