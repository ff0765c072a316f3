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
from analogue.report.theory_curves import stationary_taus
from analogue.study import catalogue as C

# (experiment, observable, theory_kind) of every comparison of `analogue paper --quick` on
# main before the catalogue existed (commit fb15674), read from its metrics.json
LABELS = Path(__file__).with_name("data") / "quick_paper_comparison_labels.json"


def test_every_entry_has_an_estimator_and_an_exact_theory():
    assert len({(k.run, k.name) for k in C.KINDS}) == len(C.KINDS)
    for k in C.KINDS:
        assert callable(k.estimator) and callable(k.exact), k.name
        assert k.run in (C.TRANSITION, C.STATIONARY)
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
    from analogue.report.observables import exact_stationary, work_variance_exact
    m = Model(tau_m=1.0, delta=0.5, a=0.6, gamma=4.0)
    out = exact_stationary(m, threshold=0.1, taus=[0.5, 2.0], cache=False)
    for tau in (0.5, 2.0):
        assert out[f"var w (tau={tau:g})"] == pytest.approx(work_variance_exact(m, tau),
                                                            rel=1e-10)
