"""Issue 18, item 6: the exact stationary law with any friction law (analogue.theory.friction_law),
against the package's independent routes for the tanh law (half-line quadrature for the
moments, the Scharfetter-Gummel grid with Richardson extrapolation for D_x)."""
import math

import numpy as np
import pytest

from analogue import Model
from analogue.theory.exact import stationary_moments
from analogue.theory.friction_law import stationary_law_with_friction
from analogue.theory.stationary import stick_fraction_theory

MODELS = [Model(tau_m=2.0, delta=0.5, a=0.3, gamma=15.0, epsilon=0.0073),
          Model(tau_m=1.5, delta=0.6, a=0.9, gamma=40.0, epsilon=0.05)]


@pytest.mark.parametrize("model", MODELS)
def test_tanh_law_matches_exact(model):
    law = stationary_law_with_friction(model, lambda v: np.tanh(v / model.epsilon), model.epsilon)
    ex = stationary_moments(model)
    for key in ("mean", "variance", "p_positive", "mean_sign"):
        assert law.moments[key] == pytest.approx(ex[key], rel=1e-9, abs=1e-12), key
    assert law.moments.diffusion == pytest.approx(ex.diffusion, rel=1e-7)
    thr = 0.1 * model.velocity_scale
    assert law.mass(-thr, thr) == pytest.approx(stick_fraction_theory(model, thr), rel=1e-5)


def test_mirror_symmetry():
    """a -> -a with an odd law mirrors the stationary law: <v> -> -<v>, P(v>0) -> P(v<0)."""
    m = MODELS[0]
    law = lambda v: np.clip(v / m.epsilon, -1.0, 1.0)  # noqa: E731  (not a tanh: any odd law)
    p = stationary_law_with_friction(m, law, m.epsilon).moments
    q = stationary_law_with_friction(m.replace(a=-m.a), law, m.epsilon).moments
    assert q.mean == pytest.approx(-p.mean, rel=1e-10)
    assert q.p_positive == pytest.approx(p.p_negative, rel=1e-10)
    assert q.diffusion == pytest.approx(p.diffusion, rel=1e-8)


def test_refuses_family_members_and_bad_laws():
    with pytest.raises(ValueError, match="paper's model"):
        stationary_law_with_friction(Model(tau_m=1, delta=0.5, a=0.1, gamma=10, cubic=0.5),
                                     np.tanh, 0.01)
    with pytest.raises(ValueError, match="friction"):
        stationary_law_with_friction(MODELS[0], lambda v: np.full(3, 1.0), 0.01)
    with pytest.raises(ValueError, match="width"):
        stationary_law_with_friction(MODELS[0], np.tanh, -1.0)


@pytest.mark.parametrize("v0", [2.0, -3.0])
# -3.0: deep in the tail (gamma (U(v0) - U_min)/2 = 35), the contour route (was expm_multiply, 8 s)
def test_transition_tanh_law_matches_exact_propagator(v0):
    """Transition moments on the tanh law against analogue.theory.exact.propagator (its own
    grid and contour route) at the default spacings: mean to 1e-4 of the spread, variance to
    1e-3 (measured 1e-4 and 1e-3 at worst, t = 0.5)."""
    from analogue.theory.exact import propagator
    from analogue.theory.friction_law import transition_moments_with_friction
    m = MODELS[0]
    times = [0.5, 3.0]
    mine = transition_moments_with_friction(m, lambda v: np.tanh(v / m.epsilon), m.epsilon,
                                            v0, times)
    v = np.linspace(-5.0, 5.0, 100001)
    f = propagator(m, v, np.array(times), v0)
    for t, fi in zip(times, f):
        z = np.trapezoid(fi, v)
        mean = np.trapezoid(v * fi, v) / z
        var = np.trapezoid((v - mean) ** 2 * fi, v) / z
        neg = np.trapezoid(fi * (v < 0), v) / z
        got = mine[t]
        assert abs(got[0] - mean) < 1e-4 * math.sqrt(var)
        assert got[1] == pytest.approx(var, rel=1e-3)
        assert got[2] == pytest.approx(neg, abs=5e-4)


def test_transition_mirror_symmetry():
    """(v0, a) -> (-v0, -a) with an odd law: f(v, t | v0; a) = f(-v, t | -v0; -a)."""
    from analogue.theory.friction_law import transition_moments_with_friction
    m = MODELS[0]
    law = lambda v: np.clip(v / m.epsilon, -1.0, 1.0)  # noqa: E731
    p = transition_moments_with_friction(m, law, m.epsilon, 1.0, [0.7])[0.7]
    q = transition_moments_with_friction(m.replace(a=-m.a), law, m.epsilon, -1.0, [0.7])[0.7]
    assert q[0] == pytest.approx(-p[0], rel=1e-9)
    assert q[1] == pytest.approx(p[1], rel=1e-9)
    assert q[2] == pytest.approx(1.0 - p[2], abs=1e-9)


def test_deep_start_contour_matches_expm():
    """A start deep in the tail (v0 = -3: gamma (U(v0) - U_min)/2 = 35, beyond the spectral
    sum) goes the contour route; the expm_multiply route it replaced (Al-Mohy & Higham, an
    independent algorithm on the same generator) agrees to 1e-9 (measured 4.6e-12 per law and
    5e-13 on the element difference at t = 0.5; 1.8e-10 per law to t = 8 on the 1N4148 bridge,
    benchmarks/bench_friction_law.py), far inside the spectral sum's own 1e-6 of the mass."""
    from analogue.theory.friction_law import transition_moments_with_friction
    m = MODELS[0]
    c = lambda v: np.clip(v / m.epsilon, -1.0, 1.0)  # noqa: E731  (any odd law; tanh: above)
    times = [0.25, 0.5]
    new = transition_moments_with_friction(m, c, m.epsilon, -3.0, times)
    old = transition_moments_with_friction(m, c, m.epsilon, -3.0, times, method="expm")
    for t in times:
        assert new[t] == pytest.approx(old[t], rel=0, abs=1e-9), t
    # the start is really deep: the mass has not reached v = 0 yet, but has left v0
    assert new[0.5][2] > 0.999 and new[0.5][0] > -2.9


def test_transition_refuses_unknown_method():
    from analogue.theory.friction_law import transition_moments_with_friction
    m = MODELS[0]
    with pytest.raises(ValueError, match="method"):
        transition_moments_with_friction(m, np.tanh, m.epsilon, 1.0, [0.5], method="eigen")


def test_start_too_deep_for_the_contour_steps_first(monkeypatch):
    """v0 = -6 (gamma (U(v0) - U_min)/2 = 103: the contour would need 89 > CONTOUR_MAX_NODES
    nodes) goes by expm_multiply until the mass allows the contour (one step here), then the
    contour; against the expm_multiply route: 3e-10 measured, 1e-9 asserted."""
    from analogue.theory import friction_law
    m = MODELS[0]
    c = lambda v: np.clip(v / m.epsilon, -1.0, 1.0)  # noqa: E731
    calls = []
    expm = friction_law.expm_multiply
    monkeypatch.setattr(friction_law, "expm_multiply",
                        lambda *a, **k: calls.append(1) or expm(*a, **k))
    new = friction_law.transition_moments_with_friction(m, c, m.epsilon, -6.0, [0.3, 0.6])
    assert len(calls) == 1  # then the contour: the expm route would step twice
    old = friction_law.transition_moments_with_friction(m, c, m.epsilon, -6.0, [0.3, 0.6],
                                                        method="expm")
    for t in (0.3, 0.6):
        assert new[t] == pytest.approx(old[t], rel=0, abs=1e-9), t
