"""The members' propagator figure shows where the law lives, not the whole theory grid."""
import numpy as np

from analogue.report.family_figures import _propagator_range


def test_range_holds_the_mass_not_the_grid_tail():
    v = np.linspace(0.0, 28.0, 2801)
    f = np.vstack([np.exp(-v / m) / m for m in (0.5, 0.8)])    # exponential laws, means 0.5, 0.8
    rng = np.random.default_rng(3)
    samples = [rng.exponential(0.5, 200), rng.exponential(0.8, 200)]
    lo, hi = _propagator_range({"v": v, "density": f, "samples": samples})
    assert lo == 0.0
    # 99.95 % of the wider law: 0.8 ln(2000) = 6.1; the grid runs to 28
    assert 0.8 * np.log(2000) <= hi < 8.0


def test_range_covers_samples_beyond_the_theory_mass():
    v = np.linspace(-5.0, 5.0, 1001)
    f = np.exp(-v ** 2 / 0.02)[None, :]
    lo, hi = _propagator_range({"v": v, "density": f, "samples": [np.array([-1.0, 0.0, 2.0])]})
    assert lo <= -1.0 and hi >= 2.0
