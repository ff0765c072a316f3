"""Ensemble.concatenate pools replicas without touching its inputs (issue 12)."""
from __future__ import annotations

import numpy as np

from analogue import Ensemble


def _ensemble(value: float, tag: str) -> Ensemble:
    t = np.linspace(0.0, 1.0, 5)
    v = np.full((2, t.size), value)
    return Ensemble(t, v, np.zeros_like(v), {"tag": tag})


def test_concatenate_leaves_its_inputs_meta_alone() -> None:
    a, b = _ensemble(1.0, "a"), _ensemble(2.0, "b")
    ab = a.concatenate(b)
    abb = ab.concatenate(b)
    # The bug: a shallow copy of meta shared the "pooled" list, so pooling ab again grew it.
    assert len(ab.meta["pooled"]) == 1
    assert len(abb.meta["pooled"]) == 2
    assert "pooled" not in a.meta and "pooled" not in b.meta
    assert [m["tag"] for m in abb.meta["pooled"]] == ["b", "b"]
    assert abb.replicas == 6
    np.testing.assert_array_equal(abb.v[:, 0], [1, 1, 2, 2, 2, 2])


def test_concatenate_keeps_noise_when_both_have_it() -> None:
    a, b = _ensemble(1.0, "a"), _ensemble(2.0, "b")
    za, zb = np.ones((2, 3)), -np.ones((2, 3))
    a = Ensemble(a.t, a.v, a.x, a.meta, za)
    b = Ensemble(b.t, b.v, b.x, b.meta, zb)
    np.testing.assert_array_equal(a.concatenate(b).noise, np.vstack([za, zb]))
