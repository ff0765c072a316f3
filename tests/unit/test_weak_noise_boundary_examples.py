"""weak_noise.boundary_examples (the paper's Fig. 5 example paths): at each returned final
velocity the optimal path (weak_noise.optimal_path, the minimum over all kinds) has the kind
the key names, on both sides of v0, for the figure's and other stick-regime parameters."""
import math

import pytest

from analogue import Model
from analogue.theory import weak_noise as wn


@pytest.mark.parametrize("a,delta", [(0.2, 0.7), (-0.3, 0.5), (0.0, 1.0)])
@pytest.mark.parametrize("v0", [2.0, -2.0, 0.8])
def test_boundary_examples_have_the_kinds_they_name(a, delta, v0):
    m = Model(1.0, delta, a, 10.0)
    t = m.stick_time(v0) + 1.5
    ex = wn.boundary_examples(m, t, v0)
    assert set(ex) == {"direct", "direct-crossing", "indirect-crossing"}
    for kind, v in ex.items():
        assert wn.optimal_path(m, v, t, v0).kind == kind


def test_boundary_examples_refuse_slip_regime_and_early_times():
    with pytest.raises(ValueError, match="stick regime"):
        wn.boundary_examples(Model(1.0, 0.5, 0.9, 10.0), 3.0, 2.0)
    m = Model(1.0, 0.7, 0.2, 10.0)
    with pytest.raises(ValueError, match="t_a"):
        wn.boundary_examples(m, 0.5 * m.stick_time(2.0), 2.0)
    assert math.isfinite(wn.boundary_examples(m, 3.0, 2.0)["direct"])
