"""Issue 18, item 6: the exact stationary law with any friction law (analogue.theory.friction_law),
against the package's independent routes for the tanh law (half-line quadrature for the
moments, the Scharfetter-Gummel grid with Richardson extrapolation for D_x)."""
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
