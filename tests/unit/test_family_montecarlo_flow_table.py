"""The tabulated noise-free flow (analogue.theory.flow_table) used by the event-driven
pure-shot Monte Carlo: against the DOP853 solver of theory.deterministic (rtol 1e-11), the
paper's closed form, the RK4 route with the same kicks, and the exact Kolmogorov-Feller law."""
import math

import numpy as np
import pytest

from analogue import Model, ShotNoise
from analogue.montecarlo import _event_driven, _flow_exact, default_dt, simulate_sde
from analogue.theory import family
from analogue.theory.deterministic import flow
from analogue.theory.flow_table import flow_table

INF = math.inf
KICKS = ShotNoise(1.0, 1.0)
MEMBERS = [
    Model(1.0, 0.7, 0.2, INF, shot=KICKS, cubic=0.5),                   # sticks
    Model(1.0, 0.7, 0.2, INF, shot=KICKS, stribeck=(1.0, 0.3)),         # sticks
    Model(5.0, 0.3, 0.6, INF, shot=KICKS, stribeck=(1.0, 0.2)),         # sticks + sliding v*
    Model(1.0, 0.7, 1.3, INF, shot=KICKS, stribeck=(1.0, 0.3)),         # slips: crosses 0
    Model(1.0, 0.7, -1.3, INF, shot=KICKS, cubic=0.3),                  # slips the other way
    Model(1.0, 0.7, 0.2, INF, shot=KICKS, epsilon=0.05),                # smooth law
]


@pytest.mark.parametrize("m", MEMBERS, ids=["cubic", "stribeck", "bistable", "slip", "slip-",
                                            "tanh"])
def test_flow_table_matches_the_ode_solver(m):
    """Measured: |dv| <= 1e-9, |dx| <= 9e-9 (scale: velocities up to 5, times up to 6)."""
    rng = np.random.default_rng(0)
    tab = flow_table(m, -6.0, 6.0)
    v0 = np.r_[rng.uniform(-5, 5, 30), 0.0, 1e-3, -1e-3]
    s = np.r_[rng.uniform(0, 6, 30), 0.5, 0.5, 3.0]
    v, x = tab.flow(v0, s)
    ref = np.array([[float(u) for u in flow(m, a, 0.0, d)] for a, d in zip(v0, s)])
    assert np.max(np.abs(v - ref[:, 0])) < 1e-8
    assert np.max(np.abs(x - ref[:, 1])) < 5e-8
    assert np.all(tab.flow(v0, np.zeros_like(s))[0] == v0)


@pytest.mark.parametrize("a", [0.2, 1.5, -1.5])
def test_flow_table_matches_the_papers_closed_form(a):
    m = Model(1.0, 0.7, a, INF, shot=KICKS)
    rng = np.random.default_rng(1)
    v0, s = rng.uniform(-4, 4, 200), rng.uniform(0, 5, 200)
    v, x = flow_table(m, -5.0, 5.0).flow(v0, s)
    ve, xe = _flow_exact(m, v0, s)
    assert np.max(np.abs(v - ve)) < 1e-10 and np.max(np.abs(x - xe)) < 1e-10


@pytest.mark.parametrize("m", [Model(2.0, 0.3, 0.7, INF, stribeck=(1.0, 0.2), shot=ShotNoise(1.0, 0.5)),
                               Model(1.0, 0.5, 1.5, INF, cubic=1.0, shot=ShotNoise(1.0, 0.5))],
                         ids=["stribeck", "cubic"])
def test_tabulated_and_rk4_event_driven_routes_agree_with_the_same_kicks(m):
    """The kick stream does not depend on the flow, so both routes see the same kicks:
    measured max |dv| 2.8e-9 (Stribeck), 2.2e-7 (cubic, RK4's error), |dx| <= 3.3e-8."""
    dt = default_dt(m)
    out = [_event_driven(m, np.zeros(100), 201, 5.0 * m.tau_m / 200, dt,
                         np.random.default_rng(5), tabulate=tab) for tab in (False, True)]
    (v_rk, x_rk, k_rk), (v_tb, x_tb, k_tb) = out
    assert k_rk == k_tb
    assert np.array_equal(v_rk == 0, v_tb == 0)
    assert np.max(np.abs(v_rk - v_tb)) < 1e-5
    assert np.max(np.abs(x_rk - x_tb)) < 1e-6


@pytest.mark.parametrize("m", [Model(1.0, 0.7, 0.2, INF, shot=ShotNoise(2.0, 0.3), stribeck=(1.0, 0.3)),
                               Model(5.0, 0.3, 0.6, INF, stribeck=(1.0, 0.2), shot=ShotNoise(0.5, 0.3))],
                         ids=["stick", "bistable"])
def test_tabulated_event_driven_stationary_law_matches_kolmogorov_feller(m):
    """Replicas from rest read after 15 tau_m (the bistable member's stuck state empties at
    rate 0.5: e^{-37}): mean, variance, P(v = 0) within 5 standard errors."""
    s = family.stationary_moments(m)
    t_end = 15.0 * m.tau_m
    e = simulate_sde(m, v0=0.0, t_end=t_end, replicas=20_000, seed=9, sample_dt=t_end)
    assert e.meta["shot_scheme"] == "event-driven, tabulated flow between kicks"
    v = np.asarray(e.v)[:, -1]
    n = v.size
    assert abs(v.mean() - s.mean) < 5 * math.sqrt(s.variance / n)
    mu4 = float(np.mean((v - v.mean()) ** 4))
    assert abs(v.var() - s.variance) < 5 * math.sqrt(max(mu4 - s.variance**2, 0.0) / n)
    p0 = s.p_zero
    assert abs(np.mean(v == 0) - p0) < 5 * math.sqrt(max(p0 * (1 - p0), 1.0 / n) / n)
