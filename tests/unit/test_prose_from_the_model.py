"""Issue 20 item 3: every number in a page comes from the experiment it describes.

The page text of a user's experiments with parameters far from the paper's (a stick copy
with tau_m = 2, Delta = 0.5, a = 0.3, gamma = 15 and a real diode; a shot member with rate 2.5
and mean 0.35, copied from circuits/shot.toml with its description) is built without running
anything; the numbers are parsed back out of the prose and compared with the models, and the
sentences that only the paper's report may say are absent.
"""
from __future__ import annotations

import logging
import math
import re
import tomllib
from pathlib import Path

import pytest

from analogue.circuit.experiments import load_experiment, standard_circuit
from analogue.report import beyond, prose
from analogue.report import pipeline as P
from conftest import toml_text

ROOT = Path(__file__).resolve().parents[2]
NUM = r"(-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?|inf)"


def _copy(name: str, new_name: str, tmp_path: Path, circuit=None, **model):
    d = tomllib.loads(toml_text(tomllib.loads((ROOT / "circuits" / f"{name}.toml").read_text())))
    d["name"] = new_name
    d["circuit"].update(circuit or {})
    for k, v in model.items():
        if isinstance(v, dict):
            d["model"].setdefault(k, {}).update(v)
        else:
            d["model"][k] = v
    path = tmp_path / f"{new_name}.toml"
    path.write_text(toml_text(d))
    return load_experiment(path)


@pytest.fixture
def user(tmp_path):
    mine = _copy("stick", "mine", tmp_path, circuit={"diode": "1N4148"}, tau_m=2.0, delta=0.5,
                 a=0.3, gamma=15.0)
    myshot = _copy("shot", "myshot", tmp_path, shot={"rate": 2.5, "mean": 0.35})
    return mine, myshot


def _values(text: str, names) -> dict:
    """{name: [numbers]} of every "name = number" in the text."""
    out: dict = {}
    for name in names:
        for x in re.findall(rf"(?<![\w/]){re.escape(name)} = {NUM}", text):
            out.setdefault(name, []).append(float(x))
    return out


def _model_numbers(m) -> dict:
    d = {"tau_m": m.tau_m, "Delta": m.delta, "a": m.a, "gamma": m.gamma}
    if m.shot is not None:
        d.update(rate=m.shot.rate, mean=m.shot.mean)
    return d


def test_model_sentence_numbers_are_the_models(user):
    mine, myshot = user
    for exp in user:
        text = " ".join(P.experiment_section_text(exp))
        want = _model_numbers(exp.model)
        got = _values(text, ["tau_m", "Delta", "a", "gamma", "t_a"])
        note = next((p for p in P.experiment_section_text(exp)
                     if p.startswith("The description above")), "")
        for name in ("tau_m", "Delta", "a", "gamma"):
            assert name in got, (name, text)
            # every occurrence is the model's, or a stale one of the copied description
            # that the note names
            for x in got[name]:
                assert x == pytest.approx(want[name], rel=1e-3) or f"{name} = {x:g}" in note, \
                    (name, x, text)
        # the model sentence itself: the model's numbers only
        own = _values(prose.model_sentence(exp), ["tau_m", "Delta", "a", "gamma"])
        assert {k: set(v) for k, v in own.items()} == {k: {want[k]} for k in own}, own
    # t_a from eq. (31), computed here from the parameters
    text = prose.model_sentence(mine)
    t_a = [float(x) for x in re.findall(rf"t_a = {NUM}", text)]
    m = mine.model
    assert t_a == pytest.approx([m.tau_m * math.log1p(2.0 / (m.tau_m * (m.delta - m.a))),
                                 m.tau_m * math.log1p(2.0 / (m.tau_m * (m.delta + m.a)))], rel=1e-3)
    # the shot member: its own rate and mean, one-sided
    text = prose.model_sentence(myshot)
    assert [float(x) for x in re.findall(rf"rate {NUM}", text)] == [2.5]
    assert [float(x) for x in re.findall(rf"mean {NUM}", text)] == [0.35]


def test_copied_description_with_stale_numbers_is_flagged(user, caplog):
    mine, myshot = user
    assert prose.description_mismatches(mine) == [
        "tau_m = 1 (the model has 2)", "Delta = 0.7 (the model has 0.5)",
        "a = 0.2 (the model has 0.3)", "gamma = 10 (the model has 15)"]
    assert prose.description_mismatches(myshot) == ["rate 1 (the model has 2.5)",
                                                    "mean 0.5 (the model has 0.35)"]
    with caplog.at_level(logging.INFO, logger="analogue.report"):
        note = P.experiment_section_text(myshot)[1]
    assert any("myshot" in r.getMessage() and "mean 0.5 (the model has 0.35)" in r.getMessage()
               for r in caplog.records)
    assert note.startswith("The description above was not written for these parameters")
    # the shipped descriptions agree with their models: no false alarm
    for name in ("stick", "slip", "work", "cubic", "stribeck", "spring", "shot"):
        assert prose.description_mismatches(load_experiment(standard_circuit(name))) == [], name


def test_member_physics_text_is_the_members(user):
    _, myshot = user
    m = myshot.model
    text = beyond.physics_text(m)
    assert [float(x) for x in re.findall(rf"rate {NUM}", text)] == [m.shot.rate]
    assert [float(x) for x in re.findall(rf"mean {NUM}", text)] == [m.shot.mean]
    assert "one-sided" in text and "atom at v = 0" in text       # gamma = inf, |a| < Delta
    # the same kicks in the slip regime: no atom claimed, the regime's numbers given
    slip = m.replace(a=0.8)
    text = beyond.physics_text(slip)
    assert "has no atom" in text and "|a| = 0.8 >= Delta(0) = 0.5" in text
    # with Gaussian noise as well, no atom either
    assert "has an atom" not in beyond.physics_text(m.replace(gamma=20.0))
    # spring: 2 Delta/spring with the member's numbers
    spring = load_experiment(standard_circuit("spring")).model.replace(spring=2.5, delta=0.4)
    got = re.findall(rf"2 Delta/spring = {NUM}", beyond.physics_text(spring))
    assert [float(x) for x in got] == pytest.approx([2 * 0.4 / 2.5])


def test_user_report_prose_has_no_paper_only_sentences(user, tmp_path):
    mine, myshot = user
    exps = [mine, myshot]
    assert not prose.is_paper_report([mine]) and not P._wants_open_question([mine])
    assert P._board_link(tmp_path, [mine]) is None
    assert prose.main_part([mine]) == "the experiments' sections"
    circuit = prose.circuit_paragraph([myshot])
    assert "trrandom" not in circuit and "shot-noise kicks" in circuit
    assert "trrandom" in prose.circuit_paragraph(exps)          # mine has Gaussian noise
    assert "noise_stddev" not in [r[0] for r in prose.component_rows(myshot.mapping())]
    assert "+ xi/m" not in prose.equation_text([myshot])
    # a member-only report: no weak-noise rows, no held Gaussian noise to budget
    kinds = prose.theory_kinds_text([], [myshot])
    assert "weak-noise" not in kinds and "Kolmogorov-Feller" in kinds
    budget = prose.budget_text([myshot])
    assert "bandwidth" not in budget and "finite noise" not in budget
    assert "bandwidth" in prose.budget_text([mine]) and "finite noise" in prose.budget_text([mine])
    assert "Transition runs" not in prose.model_sentence(myshot)   # a member's own lengths
    assert "+ shot kicks" in prose.equation_text([myshot])
    a = beyond.MemberAnalysis(myshot, beyond.member_sizes(myshot, True))
    intro = " ".join(beyond.chapter_intro([a], 1.0, quick=True))
    assert "The paper's concluding section" not in intro and "myshot (shot noise)" in intro
    assert "spring" not in intro and "Stribeck" not in intro and "cubic" not in intro
    full = " ".join(beyond.chapter_intro([a], 1.0, quick=False))
    assert "small replica counts" not in full
    # a user's file named like a paper experiment is still the user's
    own = tmp_path / "own"
    own.mkdir()
    named_stick = _copy("stick", "stick", own, a=0.3)
    assert not prose.is_paper_experiment(named_stick)
    assert not P._wants_open_question([named_stick])
    # the paper's own report keeps its sentences
    paper = [load_experiment(standard_circuit(n)) for n in ("stick", "slip", "work")]
    assert prose.is_paper_report(paper) and P._wants_open_question(paper)
    assert prose.main_part(paper) == "the paper's chapters"
    assert "analogue board stick" in P._board_link(tmp_path, paper)
    chapter = [beyond.MemberAnalysis(e, beyond.member_sizes(e, True))
               for e in (load_experiment(standard_circuit(n)) for n in beyond.MEMBERS)]
    assert "The paper's concluding section" in beyond.chapter_intro(chapter, 1.0, True)[0]
