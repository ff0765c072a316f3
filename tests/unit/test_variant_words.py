"""Issue 20: the variants describe themselves (analogue.variants.words); the report's prose
composes their phrases instead of testing model.shot, model.cubic, ... ."""
from __future__ import annotations

import math

from analogue import Model, ShotNoise
from analogue.study.sweep import sweep_parameters
from analogue.variants import OrnsteinUhlenbeck
from analogue.variants.words import (CIRCUIT, ELEMENT_TERMS, EQUATION, REFERENCE, Phrase, merge,
                                    model_phrases)


def test_merge_keeps_one_phrase_per_slot_the_covering_one_in_slot_order():
    got = merge([Phrase(3, "c"), Phrase(1, "a"), Phrase(1, "A", covers=1), Phrase(1, "a"),
                 Phrase(12, "circuit")], EQUATION)
    assert got == ["A", "c"]
    assert merge([Phrase(12, "circuit"), Phrase(2, "eq")], CIRCUIT) == ["circuit"]


def test_each_variant_states_its_own_numbers():
    m = Model(1.5, 0.4, 0.1, 12.0, cubic=0.37, stribeck=(0.21, 0.63), spring=1.7, x0=-0.9)
    assert m.friction.describe() == ["cubic = 0.37", "Stribeck delta_s = 0.21, v_s = 0.63"]
    assert m.friction.stated_values() == {"delta_s": 0.21, "v_s": 0.63}
    assert m.restoring.describe() == ["spring = 1.7, released from x0 = -0.9"]
    shot = Model(1.0, 0.5, 0.2, math.inf, shot=ShotNoise(rate=2.5, mean=0.35, two_sided=True))
    words = shot.noise_kind.describe()
    assert words[0] == "gamma = inf (no Gaussian noise)"
    assert "rate 2.5 per unit time" in words[1] and "mean 0.35" in words[1]
    assert "two-sided" in words[1]
    assert shot.noise_kind.stated_values() == {"rate": 2.5, "mean": 0.35}
    ou = Model(1.0, 0.5, 0.2, 8.0, noise=OrnsteinUhlenbeck(0.3))
    assert ou.noise_kind.stated_values() == {"tau_c": 0.3}
    assert "tau_c = 0.3" in ou.noise_kind.describe()[0]


def test_the_reference_is_the_springs_or_else_the_noise_kinds():
    def refs(m):
        return merge(m.restoring.page_phrases(m.noise_kind), REFERENCE)
    shot = ShotNoise(rate=1.0, mean=0.5)
    assert refs(Model(1, 0.5, 0.2, 10.0)) == ["the Fokker-Planck numerics of the member's own law"]
    assert refs(Model(1, 0.5, 0.2, math.inf, shot=shot)) == [
        "the Kolmogorov-Feller numerics for shot noise"]
    assert refs(Model(1, 0.5, 0.2, math.inf, shot=shot, spring=1.0)) == [
        "the Monte Carlo for a spring"]
    assert refs(Model(1, 0.5, 0.2, 10.0, noise=OrnsteinUhlenbeck(0.2))) == [
        "the Monte Carlo for coloured noise (no exact theory yet)"]


def test_a_member_is_filed_under_its_spring_then_its_noise_then_its_friction_law():
    shot = ShotNoise(rate=1.0, mean=0.5)
    cases = [(Model(1, 0.5, 0.2, 10.0, spring=1.0, noise=OrnsteinUhlenbeck(0.2)), "spring"),
             (Model(1, 0.5, 0.2, math.inf, shot=shot, cubic=0.3), "shot"),
             (Model(1, 0.5, 0.2, 10.0, noise=OrnsteinUhlenbeck(0.2)), "coloured"),
             (Model(1, 0.5, 0.2, 10.0, cubic=0.3, stribeck=(0.2, 0.5)), "stribeck"),
             (Model(1, 0.5, 0.2, 10.0, cubic=0.3), "cubic")]
    for m, kind in cases:
        assert m.restoring.member_kind(m) == kind, m
    both = Model(1, 0.5, 0.2, math.inf, shot=shot, cubic=0.3, spring=1.0)
    assert merge(model_phrases([both]), ELEMENT_TERMS) == [
        "cubic network approximation", "inductor series resistance", "shot pulse width and edges"]


def test_circuit_dispatch_of_spring_and_kicks():
    """What analogue.circuit.decks asks the variants: the spring's energy reach, the kicks'
    reach, the shot kind's meta and records, the law its stationary start is drawn from."""
    shot = ShotNoise(rate=2.0, mean=0.3)
    m = Model(1.5, 0.5, 0.2, math.inf, epsilon=0.05, shot=shot, spring=4.0, x0=0.5)
    assert m.restoring.energy_reach(m) == abs(4.0 * 0.5 - 0.2) / 2.0
    assert m.noise_kind.kick_reach(1.5, 3.0) == 2.0 * 1.5 * 0.3 + 3.0 * 0.3
    assert m.noise_kind.sampled_model(m).epsilon == 0.0
    plain = Model(1.5, 0.5, 0.2, 10.0, epsilon=0.05)
    assert plain.restoring.energy_reach(plain) == 0.0
    assert plain.noise_kind.kick_reach(1.5, 3.0) == 0.0
    assert plain.noise_kind.sampled_model(plain) is plain
    assert plain.noise_kind.circuit_meta(None) == {} and plain.noise_kind.deck_records([]) == {}


def test_a_sweep_varies_the_stribeck_pair_only_where_the_law_has_it():
    paper = set(sweep_parameters(Model(1, 0.5, 0.2, 10.0)))
    assert paper == {"tau_m", "delta", "a", "gamma", "mass", "cubic"}
    both = sweep_parameters(Model(1, 0.5, 0.2, 10.0, cubic=0.3, stribeck=(0.2, 0.5)))
    assert set(both) - paper == {"delta_s", "v_s"}
    assert both["v_s"][2] == ">" and both["delta_s"][2] == ">="
