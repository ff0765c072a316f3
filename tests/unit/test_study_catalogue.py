"""The observable catalogue (analogue.study.catalogue): every entry has an estimator and a
theory, the labels of today's report stay what they were, and estimators and theory readings
agree with closed forms computed here by an independent route."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import norm

from analogue import Model
from analogue.circuit.experiments import PAPER_EXPERIMENTS, load_experiment, standard_circuit
from analogue.ensemble import Ensemble
from analogue.report.plan import RunOptions
from analogue.study.theory_curves import stationary_taus
from analogue.study import catalogue as C

# (experiment, observable, theory_kind) of every comparison of `analogue paper --quick` on
# main before the catalogue existed (commit fb15674), read from its metrics.json
LABELS = Path(__file__).with_name("data") / "quick_paper_comparison_labels.json"


def test_every_entry_has_an_estimator_and_an_exact_theory():
    """... or, for kinds of the spring alone (no exact law of (x, v)), the Monte Carlo; a
    kind a Monte Carlo member (coloured noise) shares has an exact theory for the others."""
    assert len({(k.run, k.name) for k in C.KINDS}) == len(C.KINDS)
    for k in C.KINDS:
        assert callable(k.estimator) and callable(k.exact), k.name
        assert k.run in (C.TRANSITION, C.STATIONARY)
        assert k.classes and k.classes <= {C.PAPER, C.GAUSSIAN_MEMBER, C.SHOT_MEMBER,
                                           C.SPRING_MEMBER, C.MONTE_CARLO_MEMBER}, k.name
        if k.exact is C.no_exact:
            assert k.classes == {C.SPRING_MEMBER}, k.name
        if k.compare_weak_noise:
            assert callable(k.weak_noise), k.name
    assert C.kind_of(C.TRANSITION, "mean v").weak_noise is not None
    with pytest.raises(KeyError, match="no observable kind"):
        C.kind_of(C.STATIONARY, "no such kind")


def test_labels_are_those_of_todays_quick_paper_report():
    recorded = json.loads(LABELS.read_text())
    planned = []
    quick = RunOptions(quick=True)
    for name in PAPER_EXPERIMENTS:
        exp = load_experiment(standard_circuit(name))
        st = exp.report.for_options(quick)
        planned += [[name, label, kind] for label, kind in C.planned_comparisons(
            exp.v0, exp.histogram_times, stationary_taus(exp, st),
            weak_noise=exp.model.delta > 0)]
    assert planned == recorded


def test_every_recorded_label_is_found_in_the_catalogue():
    for _, label, _ in json.loads(LABELS.read_text()):
        o = C.find(label)
        assert o is not None and o.label == label, label
    assert C.find("mean v at t=1 from v0=2").t == 1.0
    assert C.find("var w") is None            # a window kind needs its tau
    assert C.find("no such thing") is None


def test_transition_theory_reads_moments_of_a_gaussian_density():
    """Mean, variance and P(v < 0) of N(0.3, 0.7^2) on a grid against the closed forms."""
    v = np.linspace(-6, 6, 12001)
    mu, s = 0.3, 0.7
    f = norm.pdf(v, mu, s)[None, :]
    out = C.transition_theory(v, f, 1.0, [2.0])
    assert out["mean v at t=2 from v0=1"] == pytest.approx(mu, abs=1e-9)
    assert out["var v at t=2 from v0=1"] == pytest.approx(s ** 2, rel=1e-6)
    assert out["P(v<0) at t=2 from v0=1"] == pytest.approx(norm.cdf(0, mu, s), abs=1e-6)


def test_variance_rows_get_the_gaussian_theory_side_se():
    """N(0.3, 0.7^2): Var(s^2) = 2 sigma^4/(n - 1), Var(mean) = sigma^2/n; P(v<0) has none
    (its binomial floor is the report's)."""
    v = np.linspace(-6, 6, 12001)
    se = C.transition_theory_se(v, norm.pdf(v, 0.3, 0.7)[None, :], 1.0, [2.0], 40)
    assert sorted(se) == ["mean v at t=2 from v0=1", "var v at t=2 from v0=1"]
    assert se["var v at t=2 from v0=1"] == pytest.approx(math.sqrt(2 * 0.7 ** 4 / 39), rel=1e-6)
    assert se["mean v at t=2 from v0=1"] == pytest.approx(0.7 / math.sqrt(40), rel=1e-6)


def test_stationary_estimators_on_paths_of_constant_velocity():
    """Replica i moves at the constant velocity c_i: every stationary observable is known."""
    t = np.linspace(0, 10, 1001)
    c = np.array([0.5, 1.5, -0.25, 2.0])
    ens = Ensemble(t, np.repeat(c[:, None], t.size, axis=1), c[:, None] * t[None, :], {})
    out = C.stationary_values(ens, burn_in=1.0, threshold=0.3, force=2.0, taus=[1.0, 2.5])
    assert out["mean v"] == pytest.approx(c.mean())
    assert out["var v"] == pytest.approx(c.var())
    assert out["P(v>0)"] == pytest.approx(0.75)
    assert out["stick fraction"] == pytest.approx(0.25)       # |-0.25| < 0.3
    for tau in (1.0, 2.5):
        assert out[f"mean w (tau={tau:g})"] == pytest.approx(2.0 * c.mean())
        assert out[f"var w (tau={tau:g})"] == pytest.approx(4.0 * c.var())
    assert list(out) == [o.label for o in C.stationary_observables([1.0, 2.5])]


def test_chi2_statistic_is_near_one_for_samples_of_the_density():
    """Pearson chi^2/dof of 2000 normal samples against their own density: 1 within 4 SE."""
    rng = np.random.default_rng(3)
    v = np.linspace(-8, 8, 8001)
    k = C.kind_of(C.TRANSITION, "histogram chi2/dof")
    assert k.fit_test and k.exact() == 1.0
    value, se = k.estimator(rng.standard_normal(2000), v, norm.pdf(v))
    assert se == pytest.approx(math.sqrt(2 / 19))
    assert abs(value - 1.0) < 4 * se


def test_exact_stationary_work_variance_matches_the_green_kubo_route():
    """exact_stationary takes Var(w) of all windows from one autocorrelation
    (theory.work_statistics.work_variance); the report's former per-window Green-Kubo
    integral (observables.work_variance_exact) is an independent implementation."""
    from analogue.study.observables import exact_stationary, work_variance_exact
    m = Model(tau_m=1.0, delta=0.5, a=0.6, gamma=4.0)
    out = exact_stationary(m, threshold=0.1, taus=[0.5, 2.0], cache=False)
    for tau in (0.5, 2.0):
        assert out[f"var w (tau={tau:g})"] == pytest.approx(work_variance_exact(m, tau),
                                                            rel=1e-10)


# ------------------------------------------------------------------ family members (issue 9)
# labels of every comparison of each member's report, read from the Beyond chapter's own
# observable lists before they became catalogue entries (report/beyond.py at commit 12725fb)
MEMBER_LABELS = Path(__file__).with_name("data") / "member_comparison_labels.json"


def test_member_labels_are_those_of_the_chapter_before_the_catalogue():
    recorded = json.loads(MEMBER_LABELS.read_text())
    assert set(recorded) == {"cubic", "stribeck", "spring", "shot"}
    for name, labels in recorded.items():
        exp = load_experiment(standard_circuit(name))
        got = C.member_observables(exp.model, v0=float(exp.v0[0]), times=exp.histogram_times)
        assert [o.label for o in got] == labels, name
        for o in got:
            assert C.find(o.label) == o, o.label


def test_model_classes_and_references():
    paper = Model(tau_m=1.0, delta=0.5, a=0.2, gamma=4.0)
    assert C.model_class(paper) == C.PAPER
    assert C.model_class(paper.replace(cubic=0.3)) == C.GAUSSIAN_MEMBER
    spring = paper.replace(spring=1.0)
    assert C.model_class(spring) == C.SPRING_MEMBER
    with pytest.raises(ValueError, match="paper's model"):
        C.member_observables(paper)
    with pytest.raises(TypeError, match="model must be"):
        C.model_class("cubic")
    refs = {o.kind: C.reference_of(o, spring) for o in C.member_observables(spring)}
    assert refs["var x"] == refs["var v"] == "monte carlo"
    assert refs["identity <v> = 0"] == "exact"
    cubic = paper.replace(cubic=0.3)
    assert {C.reference_of(o, cubic) for o in C.member_observables(cubic, v0=0.0, times=[1.0])} == {"exact"}
    # the drive-free member has no D_x row (the work rate function needs a != 0)
    assert "diffusion D_x" not in [o.kind for o in C.member_observables(cubic.replace(a=0.0))]


def test_law_moments_of_an_atom_plus_a_gaussian():
    """p delta(v) + (1 - p) N(mu, s^2): moments, P(v < 0) and the stuck window in closed form."""
    v = np.linspace(-8, 8, 16001)
    p, mu, s, w = 0.3, 0.8, 0.6, 0.05
    m = C.law_moments(v, (1 - p) * norm.pdf(v, mu, s), p, window=w)
    mean = (1 - p) * mu
    assert m.mean == pytest.approx(mean, abs=1e-9)
    assert m.variance == pytest.approx((1 - p) * (s * s + mu * mu) - mean ** 2, rel=1e-6)
    assert m.p_negative == pytest.approx((1 - p) * norm.cdf(0, mu, s), abs=1e-6)
    # the window's edges fall between nodes: at most one cell's mass lost at each
    edge = (1 - p) * (norm.pdf(w, mu, s) + norm.pdf(-w, mu, s)) * (v[1] - v[0])
    assert m.p_stuck == pytest.approx(p + (1 - p) * (norm.cdf(w, mu, s) - norm.cdf(-w, mu, s)),
                                      abs=edge)
    d = mu - mean                                  # the Gaussian's centre about the mean
    assert m.fourth == pytest.approx(p * mean ** 4 + (1 - p) * (d ** 4 + 6 * d * d * s * s
                                                             + 3 * s ** 4), rel=1e-6)
    # without the atom it is the paper's density_moments
    assert C.density_moments(v, norm.pdf(v, mu, s)) == pytest.approx((mu, s * s, norm.cdf(0, mu, s)),
                                                                     abs=1e-6)


def test_member_stationary_theory_reads_the_grid_law():
    """A grid law (uniform density on [-1, 1] of mass 0.6 + atom 0.4): window masses by hand."""
    v = np.linspace(-2, 2, 4001)
    dens = np.where(np.abs(v) <= 1, 0.3, 0.0)
    model = Model(tau_m=1.0, delta=0.5, a=0.2, gamma=math.inf,
                  shot=__import__("analogue").ShotNoise(1.0, 0.5))
    obs = C.member_observables(model)
    assert [o.kind for o in obs] == ["mean v", "var v", "P(v=0)", "P(v>window)"]

    class Moments:
        mean, variance = 0.1, 0.2
    out = C.stationary_theory(model, Moments, threshold=0.05, work_variance={},
                              law=(v, dens, 0.4), observables=obs)
    dv = v[1] - v[0]
    assert out["P(v=0)"] == pytest.approx(0.4 + 0.3 * dv * np.sum(np.abs(v) < 0.05))
    assert out["P(v>window)"] == pytest.approx(0.3 * (1 - 0.05), abs=2 * 0.3 * dv)
    assert out["mean v"] == 0.1 and out["var v"] == 0.2


def _spring_ensemble(t, v, x):
    return Ensemble(t, v, x - x[:, :1], {})


def test_first_swing_of_harmonic_releases():
    """x = x0 cos(w t), v = -x0 w sin(w t): the first swing ends at t = pi/w, |x| = x0."""
    t = np.linspace(0, 10, 10001)
    w = np.array([1.0, 1.5, 2.5])[:, None]
    x0 = np.array([2.0, 1.0, 0.5])[:, None]
    x = x0 * np.cos(w * t)
    v = -x0 * w * np.sin(w * t)
    half, amp = C.first_swing(t, v, x, 0.05)
    assert half == pytest.approx(np.pi / w.ravel(), abs=2 * (t[1] - t[0]))
    assert amp == pytest.approx(x0.ravel(), rel=1e-4)
    # a replica at rest never swings: NaN, left out of the kind's mean
    half, _ = C.first_swing(t, np.vstack([v, 0 * t]), np.vstack([x, 0 * t + 1]), 0.05)
    assert np.isnan(half[-1])
    s = C.stationary_sample(_spring_ensemble(t, np.vstack([v, 0 * t]), np.vstack([x, 0 * t + 1])),
                            burn_in=1.0, threshold=0.05, force=0.0,
                            position=np.vstack([x, 0 * t + 1]))
    k = C.kind_of(C.STATIONARY, "half period (first swing)")
    assert k.estimator(s) == pytest.approx(np.mean(np.pi / w.ravel()), abs=2e-3)


def test_force_balance_identity_on_states_at_rest():
    """At rest (v = 0: sgn 0 = 0) the residual is spring x - a; zero at x = a/spring."""
    model = Model(tau_m=3.0, delta=0.5, a=0.3, gamma=20.0, spring=1.5)
    t = np.linspace(0, 5, 501)
    v = np.zeros((2, t.size))
    x = np.vstack([np.full(t.size, 0.3 / 1.5), np.full(t.size, 0.3 / 1.5 + 0.4)])
    o = C.Observable("identity spring <x> - a + <Delta(v) sgn v> + cubic <v^3> = 0", C.STATIONARY)
    ens = _spring_ensemble(t, v, x)
    got = C.estimate(o, ens, burn_in=1.0, threshold=0.05, force=model.force, position=x,
                     model=model)
    assert got == pytest.approx(1.5 * 0.2, abs=1e-12)      # mean of the two residuals 0 and 0.6
    assert C.reference_of(o, model) == "exact" and o.entry.exact() == 0.0


def test_element_terms_follow_the_mapping_bias():
    model = Model(tau_m=3.0, delta=0.5, a=0.0, gamma=20.0, spring=1.0)
    bias = {"spring_leak_var_v": 0.02, "spring_leak_var_x": 0.05, "spring_creep": 0.1,
            "cubic_variance": 0.0}
    var_v, var_x = C.Observable("var v", C.STATIONARY), C.Observable("var x", C.STATIONARY)
    assert C.element_error(var_v, bias, model, -2.0) == pytest.approx(0.04)
    assert C.element_error(var_x, bias, model, 3.0) == pytest.approx(0.15)
    ident = C.Observable("identity <v> = 0", C.STATIONARY)
    assert C.element_error(ident, bias, model, 0.0) == pytest.approx(0.1 * model.velocity_scale)
    assert C.element_error(C.Observable("mean v", C.TRANSITION, t=1.0, v0=0.0), bias, model, 1.0) == 0.0
    # the stationary mean velocity carries the creep too (its reference is ~0: relative terms
    # vanish there), and a member without a spring has no creep term
    mean_v = C.Observable("mean v", C.STATIONARY)
    assert C.element_error(mean_v, bias, model, 0.0) == pytest.approx(0.1 * model.velocity_scale)
    assert C.element_error(mean_v, {"cubic_variance": 0.01}, model.replace(spring=0.0),
                           -2.0) == pytest.approx(0.02)
