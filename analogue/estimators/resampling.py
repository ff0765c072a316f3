"""Resampling errors over independent replicas: the delete-a-group jackknife of any scalar
observables of an ensemble, alone or as the difference of two paired ensembles (row i of both
driven by the same noise).

Replicas are independent, so these errors hold however correlated the samples along one path
are; the observables are plain functions ``fn(ensemble) -> {name: value}`` (the report's come
from :mod:`analogue.study.catalogue`).  An ``fn`` that also has a method
``leave_group_out(ensemble, labels, groups) -> [fn(subset(ensemble, labels != j)) for j]``
(:class:`GroupObservables`) gives the jackknife its values from per-replica pieces computed
once instead of ``groups`` copies of the ensemble (the report's stationary observables:
measured 101 calls on 64 x 10^4 samples per experiment).
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from ..ensemble import Ensemble

# an observable set: ensemble -> {name: value}
Observables = Callable[[Ensemble], Mapping[str, float]]

__all__ = ["GroupObservables", "jackknife", "jackknife_difference", "subset"]


@runtime_checkable
class GroupObservables(Protocol):
    """An observable set with a fast route to its delete-a-group values."""

    def __call__(self, ens: Ensemble, /) -> Mapping[str, float]: ...

    def leave_group_out(self, ens: Ensemble, labels: np.ndarray, groups: int
                        ) -> Sequence[Mapping[str, float]]: ...


def subset(ens: Ensemble, rows: np.ndarray) -> Ensemble:
    return Ensemble(ens.t, ens.v[rows], ens.x[rows], ens.meta)


def _groups(n: int, groups: int) -> tuple[int, np.ndarray]:
    g = max(2, min(groups, n // 2))
    return g, np.arange(n) % g


def _left_out(fn: Observables, ens: Ensemble, labels: np.ndarray, g: int
              ) -> Sequence[Mapping[str, float]]:
    """``[fn(subset(ens, labels != j)) for j in range(g)]``, by ``fn.leave_group_out`` when
    it has one."""
    if isinstance(fn, GroupObservables):
        return fn.leave_group_out(ens, labels, g)
    return [fn(subset(ens, labels != j)) for j in range(g)]


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
    reps = _left_out(fn, ens, labels, g)
    return {k: (float(full[k]), _jk_se([r[k] for r in reps], g)) for k in full}


def jackknife_difference(fn: Observables, a: Ensemble, b: Ensemble, groups: int = 16
                         ) -> dict[str, tuple[float, float]]:
    """``fn(a) - fn(b)`` for paired ensembles (row i of a and b share their noise), with
    delete-a-group jackknife standard errors; returns ``{name: (diff, se)}``."""
    if b.replicas != a.replicas:
        raise ValueError("paired ensembles need the same number of replicas")
    g, labels = _groups(a.replicas, groups)
    full_a, full_b = fn(a), fn(b)
    reps = [{k: fa[k] - fb[k] for k in full_a}
            for fa, fb in zip(_left_out(fn, a, labels, g), _left_out(fn, b, labels, g))]
    return {k: (float(full_a[k] - full_b[k]), _jk_se([r[k] for r in reps], g)) for k in full_a}
