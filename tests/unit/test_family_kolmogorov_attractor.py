"""The Kolmogorov-Feller grid and a velocity-weakening member's second (sliding) attractor.

Stribeck friction (tau_m = 5, Delta = 0.3, delta_s = 1, v_s = 0.2, a = 0.6) sticks from rest
(a < delta_s) but has a stable sliding zero v* of the drift; with one-sided kicks the kicked
object ends up above the unstable zero and never sticks again, so [v*, inf) is the recurrent
class.  The grid must put v* on a cell edge (as it puts v = 0), and the stationary solve must
anchor a recurrent state.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from analogue import Model, ShotNoise
from analogue.theory import family
from analogue.theory.kolmogorov_feller import default_spacing, shot_generator, stable_zeros

INF = math.inf
BISTABLE = Model(5.0, 0.3, 0.6, INF, stribeck=(1.0, 0.2), shot=ShotNoise(0.5, 0.3))


def test_stable_zeros_are_the_sliding_attractors():
    m = BISTABLE
    (z,) = stable_zeros(m)
    assert m.attractor == 0.0  # stuck from rest
    assert abs(float(m.drift(z))) < 1e-12
    assert float(m.drift(z - 1e-6)) > 0 > float(m.drift(z + 1e-6))
    # the paper's law: no sliding zero in the stick regime, (a - Delta) tau_m in the slip one
    assert stable_zeros(Model(1.0, 0.5, 0.2, INF, shot=ShotNoise(1.0, 0.5))).size == 0
    slip = Model(2.0, 0.5, 0.8, INF, shot=ShotNoise(1.0, 0.5))
    assert stable_zeros(slip) == pytest.approx([0.6], rel=1e-12)


@pytest.mark.parametrize("refine", [1.0, 0.5, 1.0 / 3.0])
def test_stribeck_sliding_attractor_is_a_cell_edge(refine):
    m = BISTABLE
    (z,) = stable_zeros(m)
    h = default_spacing(m) * refine
    ratio = z / h
    assert abs(ratio - round(ratio)) < 1e-9
    g = shot_generator(m, h)
    edges = np.r_[g.v[:-1] - 0.5 * h, g.v[-2] + 0.5 * h]  # cells (the last state is S)
    assert np.min(np.abs(edges - z)) < 1e-9 * z


def test_bistable_one_sided_member_stationary_law():
    """The stuck state is transient (p_zero = 0), the solve anchors above v* at every spacing
    (anchored at S it gave weights of -2e12 on h/6), and the stationary identity
    <v>/tau_m = a + rate mean - <Delta(v) sgn v> holds between the grid law and the
    Richardson mean (measured 4e-8)."""
    m = BISTABLE
    h = default_spacing(m)
    means = []
    for hh in (h, h / 3.0):
        s = family.stationary_moments(m, h=hh)
        assert s.p_zero == pytest.approx(0.0, abs=1e-12)
        assert s.p_positive == pytest.approx(1.0, abs=1e-12)
        means.append(s.mean)
    assert means[1] == pytest.approx(means[0], rel=1e-6)
    v, dens, atom = family.stationary_law(m, h=h)
    w = dens * h
    assert w.sum() + atom == pytest.approx(1.0, abs=1e-12)
    friction = float(np.sum(w * m.friction_magnitude(v) * np.sign(v)))
    assert means[0] == pytest.approx(m.tau_m * (m.a + 0.5 * 0.3 - friction), rel=1e-6)
