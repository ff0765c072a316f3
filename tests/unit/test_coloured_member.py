"""Coloured noise as a family member of the study layer (issue 20): its class has the Monte
Carlo as reference (no exact theory), its rows are the 1-D member's, its prose carries its own
tau_c and gamma, and at Delta = 0 the report's Monte Carlo reference meets the closed form
``Var v = tau_m^2/(gamma (tau_m + tau_c))`` (an independent route) within its standard error."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from analogue import Model
from analogue.report.beyond import physics_text
from analogue.report.prose import description_mismatches
from analogue.study import catalogue as C
from analogue.study.members import _jk, monte_carlo_reference
from analogue.theory import family
from analogue.variants import OrnsteinUhlenbeck
from analogue.variants.coloured import stationary_velocity_variance


def _ou(delta: float, tau_c: float = 0.25, gamma: float = 12.0) -> Model:
    return Model(1.0, delta, 0.3, gamma, noise=OrnsteinUhlenbeck(tau_c))


def test_class_rows_and_reference():
    m = _ou(0.5)
    assert C.model_class(m) == C.MONTE_CARLO_MEMBER
    assert C.reference_is_monte_carlo(m)
    obs = C.member_observables(m, v0=0.0, times=[0.5])
    assert [o.label for o in obs] == ["mean v", "var v", "P(v>0)", "stick fraction",
                                      "mean v at t=0.5 from v0=0", "var v at t=0.5 from v0=0",
                                      "P(v<0) at t=0.5 from v0=0"]
    assert {C.reference_of(o, m) for o in obs} == {"monte carlo"}
    # the white-noise member keeps its exact reference
    white = m.replace(noise=None, cubic=1.0)
    assert C.model_class(white) == C.GAUSSIAN_MEMBER
    assert {C.reference_of(o, white) for o in C.member_observables(white)} == {"exact"}


def test_a_copied_description_with_another_tau_c_is_flagged():
    exp = SimpleNamespace(model=_ou(0.5, tau_c=0.5),
                          description="Coloured noise with tau_c = 0.2 and gamma = 12.")
    assert description_mismatches(exp) == ["tau_c = 0.2 (the model has 0.5)"]


def test_prose_quotes_the_members_own_numbers():
    text = physics_text(_ou(0.5, tau_c=0.37, gamma=17.0))
    assert "tau_c = 0.37" in text and "gamma = 17" in text
    assert "Var v = tau_m^2" not in text          # no closed form with dry friction
    text0 = physics_text(_ou(0.0, tau_c=0.37, gamma=17.0))
    assert f"{stationary_velocity_variance(1.0, 17.0, 0.37):.4g}" in text0


@pytest.mark.parametrize("tau_c", [0.25, 1.5])
def test_monte_carlo_reference_meets_the_closed_form_at_zero_friction(tau_c):
    m = _ou(0.0, tau_c=tau_c)
    assert m.noise_kind.closed_form_variance(m) == stationary_velocity_variance(1.0, 12.0, tau_c)
    assert _ou(0.5).noise_kind.closed_form_variance(_ou(0.5)) is None
    # started as the report starts it: from the white-noise law of the same gamma
    v0 = family.sample_stationary(m.noise_kind.start_model(m), 256, 5)
    burn = 5.0 * max(1.0, tau_c)
    mc = monte_carlo_reference(m, v0=v0, t_end=burn + 25.0, replicas=256, seed=9,
                               sample_dt=0.05)
    var = C.Observable("var v", C.STATIONARY)

    def est(e):
        return C.estimate(var, e, burn_in=burn, threshold=0.05, force=m.force, model=m)
    value, se = _jk(est, mc)
    expected = m.noise_kind.closed_form_variance(m)
    assert abs(value - expected) < 4 * se
    # the test tells coloured from white noise (tau_m/gamma = 0.0833)
    assert abs(value - 1.0 / 12.0) > 4 * se
