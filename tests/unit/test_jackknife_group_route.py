"""The stationary observables' fast delete-a-group route
(:meth:`analogue.study.catalogue.StationaryValues.leave_group_out`, used by the replica
jackknives) gives the values of the direct route (the observables computed on each subset
copy) to rounding, for every stationary observable: moments, indicator fractions, the work
windows and D_x."""
from __future__ import annotations

import numpy as np

from analogue.ensemble import Ensemble
from analogue.estimators.resampling import (GroupObservables, jackknife, jackknife_difference,
                                            subset)
from analogue.study import catalogue as C

TAUS = (0.5, 2.0)


def _ensemble(seed: int, replicas: int = 40, drift: float = 0.7) -> Ensemble:
    """An AR(1) velocity around ``drift`` (a drifting position stresses the centring of the
    D_x route), with velocities near 0 so the indicator kinds are neither 0 nor 1."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, 20.0 + 1e-9, 0.05)
    v = np.empty((replicas, t.size))
    v[:, 0] = drift + rng.normal(size=replicas)
    for i in range(1, t.size):
        v[:, i] = drift + 0.9 * (v[:, i - 1] - drift) + 0.45 * rng.normal(size=replicas)
    x = np.concatenate([np.zeros((replicas, 1)), np.cumsum(v[:, 1:] * 0.05, axis=1)], axis=1)
    return Ensemble(t, v, x + 3.0, {})


def _fn() -> C.StationaryValues:
    return C.StationaryValues(burn_in=2.0, threshold=0.3, force=1.5, taus=TAUS)


def _close(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-12 * max(abs(a), abs(b))


def test_leave_group_out_equals_the_observables_on_each_subset():
    ens, fn = _ensemble(1), _fn()
    assert isinstance(fn, GroupObservables)
    g = 16
    labels = np.arange(ens.replicas) % g
    fast = fn.leave_group_out(ens, labels, g)
    labels_seen = set()
    for j in range(g):
        direct = C.stationary_values(subset(ens, labels != j), burn_in=2.0, threshold=0.3,
                                     force=1.5, taus=TAUS)
        assert list(fast[j]) == list(direct)
        for k in direct:
            assert _close(fast[j][k], direct[k]), (j, k, fast[j][k], direct[k])
            labels_seen.add(k)
    # every stationary observable, windows and D_x included
    assert labels_seen == {o.label for o in C.stationary_observables(TAUS)}
    assert "diffusion D_x" in labels_seen and "var w (tau=2)" in labels_seen
    # the groups differ (the check is not of a constant)
    assert len({f["var v"] for f in fast}) == g


def test_jackknives_take_the_fast_route_with_the_direct_values():
    a, b = _ensemble(2), _ensemble(3, drift=0.6)
    fn = _fn()
    direct = lambda e: fn(e)   # a plain function: the jackknife copies the subsets
    for fast_out, direct_out in ((jackknife(fn, a), jackknife(direct, a)),
                                 (jackknife_difference(fn, a, b),
                                  jackknife_difference(direct, a, b))):
        assert list(fast_out) == list(direct_out)
        for k, (val, se) in direct_out.items():
            assert _close(fast_out[k][0], val) and _close(fast_out[k][1], se), k
            assert se > 0.0


def test_the_fast_route_is_the_direct_one_on_unequal_groups():
    """37 replicas in 32 groups: groups of 1 and 2 rows (and D_x's n - 1 with n = 35)."""
    ens, fn = _ensemble(4, replicas=37), _fn()
    out, ref = jackknife(fn, ens), jackknife(lambda e: fn(e), ens)
    for k, (val, se) in ref.items():
        assert _close(out[k][0], val) and _close(out[k][1], se), k


