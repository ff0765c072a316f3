"""Weak-noise theory of the family (analogue.theory.weak_noise_family)."""
import math

import numpy as np
import pytest

from analogue import Model, ShotNoise
from analogue.theory import weak_noise as wn
from analogue.theory import weak_noise_family as wf


@pytest.mark.parametrize("v,t,v0", [(0.5, 1.0, 1.0), (1.5, 1.0, 0.5), (-0.8, 2.0, -0.3), (-0.2, 0.7, -1.1)])
@pytest.mark.parametrize("a", [0.2, 1.3])
def test_direct_path_bvp_reproduces_the_papers_closed_form(v, t, v0, a):
    """Paper's model: the numerical EL solution equals the basic-solution action eq. (20)."""
    m = Model(1.0, 0.7, a, 10.0)
    got = wf.direct_action(m, v, t, v0)
    if math.isnan(got):  # left the half line: then the paper's direct candidate is not admissible
        assert wn.action(m, v, t, v0) <= wn.Lambda(math.copysign(1, v0), v, t, v0, 0.0, m) + 1e-12
        return
    assert got == pytest.approx(float(wn.Lambda(math.copysign(1, v0), v, t, v0, 0.0, m)), rel=1e-9)


@pytest.mark.parametrize("v,t,v0", [(0.5, 1.0, 1.0), (-0.8, 2.0, -0.3), (0.9, 3.0, 0.2), (1.5, 4.0, 0.5)])
def test_family_action_equals_papers_minimum_where_no_crossing_is_involved(v, t, v0):
    m = Model(1.0, 0.7, 0.2, 10.0)
    assert wf.action(m, v, t, v0) == pytest.approx(float(wn.action(m, v, t, v0)), rel=1e-9)


@pytest.mark.parametrize("kw", [dict(stribeck=(1.0, 0.2)), dict(cubic=0.5), dict(cubic=0.2, stribeck=(0.4, 0.5))])
def test_time_reversal_identity_of_direct_paths(kw):
    """Gradient system: A(v, t | v0) - A(v0, t | v) = U(v) - U(v0)."""
    m = Model(1.0, 0.7, 0.9, 10.0, **kw)
    for v, v0, t in ((1.2, 0.4, 2.0), (0.3, 1.5, 0.8)):
        diff = wf.direct_action(m, v, t, v0) - wf.direct_action(m, v0, t, v)
        assert diff == pytest.approx(float(m.potential(v) - m.potential(v0)), abs=1e-9)


@pytest.mark.parametrize("kw", [dict(stribeck=(1.0, 0.3)), dict(cubic=0.5)])
def test_long_uphill_paths_cost_the_quasi_potential(kw):
    """From the slip attractor (a smooth minimum of U), A(v, t) -> U(v) - U(v*) as t -> inf,
    from above and monotonically (closed-form U, independent of the BVP)."""
    m = Model(1.0, 0.7, 1.4, 10.0, **kw)
    vs = m.attractor
    target = vs + 0.6
    q = float(wf.quasi_potential(m, target)) - float(wf.quasi_potential(m, vs))
    acts = [wf.direct_action(m, target, t, vs) for t in (2.0, 4.0, 8.0)]
    assert acts[0] > acts[1] > acts[2] > q
    assert acts[2] == pytest.approx(q, rel=1e-4)


def test_quasi_potential_is_the_log_of_the_stationary_law():
    m = Model(1.0, 0.7, 0.9, 25.0, stribeck=(1.0, 0.2))
    v = np.array([-0.5, 0.0, 0.3, 0.8])
    lhs = -np.log(m.stationary_pdf(v)) / m.gamma
    q = wf.quasi_potential(m, v)
    assert np.allclose(lhs - lhs.min(), q - q[np.argmin(lhs)], atol=1e-12)


def test_shot_noise_and_spring_have_no_gaussian_weak_noise_theory():
    with pytest.raises(ValueError, match="one-dimensional members with Gaussian"):
        wf.action(Model(1.0, 0.7, 0.2, 10.0, spring=1.0), 0.5, 1.0, 0.2)
    with pytest.raises(ValueError, match="one-dimensional members with Gaussian"):
        wf.quasi_potential(Model(1.0, 0.7, 0.2, math.inf, shot=ShotNoise(1.0, 0.2)), 0.5)
