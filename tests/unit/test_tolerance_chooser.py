"""The tolerance chooser (analogue.circuit.tolerances) on synthetic calibration data.

The candidate and reference "ensembles" are built here with known path-wise errors, so the
ratio integration error / statistical error that decides is known by construction:
ratio = sd(d)/sigma + |mean d| sqrt(n_eff)/sigma.
"""
import math

import numpy as np
import pytest

from analogue import Model
from analogue.circuit import tolerances as tl
from analogue.circuit.mapping import (
    FIXED_METHOD,
    FIXED_RELTOL,
    FIXED_TRTOL,
    CircuitSpec,
)
from analogue.ensemble import Ensemble

STICK = Model(1.0, 0.7, 0.2, 10.0)
R, NT = 400, 51


def _ref(seed=1):
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, NT)
    v = rng.normal(0.0, 1.0, (R, NT))
    x = np.cumsum(v, axis=1) * (t[1] - t[0])
    x -= x[:, :1]
    return Ensemble(t, v, x)


def _shifted(ref, offset):
    """Every path shifted by a constant: d = offset exactly for v(T), no spread."""
    return Ensemble(ref.t, ref.v + offset, ref.x + offset * ref.t)


def test_ratio_of_a_known_offset():
    ref = _ref()
    res = tl.candidate_result(tl.FIXED, _shifted(ref, 0.01), ref, threshold=0.1)
    sigma = float(np.std(ref.v[:, -1], ddof=1))
    assert res.mean["v(T)"] == pytest.approx(0.01)
    assert res.sd["v(T)"] == pytest.approx(0.0, abs=1e-12)
    for n in (1, 16, 400):
        r = res.ratios(replicas=n, t_end=1.0, t_cal=1.0)["v(T)"]
        assert r == pytest.approx(0.01 * math.sqrt(n) / sigma, rel=1e-9)


def test_time_averages_count_longer_runs():
    ref = _ref()
    res = tl.candidate_result(tl.FIXED, _shifted(ref, 0.01), ref, threshold=0.1)
    short = res.ratios(replicas=4, t_end=1.0, t_cal=1.0)
    long = res.ratios(replicas=4, t_end=9.0, t_cal=1.0)
    # a time average over 9x longer paths has 3x smaller statistical error
    assert long["time mean v"] == pytest.approx(3 * short["time mean v"], rel=1e-9)
    assert long["v(T)"] == pytest.approx(short["v(T)"], rel=1e-12)  # instantaneous: unchanged


LOOSE = tl.Tolerances(1e-3, 20.0, "gear")
FINE = tl.Tolerances(1e-4, 7.0, "gear")


def _result(tol, bias, points, sd=0.0, sigma=1.0):
    """One instantaneous observable with a known bias, spread of d and spread of O."""
    return tl.CandidateResult(tol, points, 0.0, {"O": bias}, {"O": sd}, {"O": sigma},
                              {"O": False})


def _two(loose_ratio, fine_ratio, n):
    # bias b on an observable of spread 1 gives ratio b sqrt(n) for n replicas
    return [_result(LOOSE, loose_ratio / math.sqrt(n), 1.0),
            _result(FINE, fine_ratio / math.sqrt(n), 3.0)]


def test_coarse_candidate_rejected_when_above_fraction():
    n = 16
    results = _two(0.3, 0.01, n)          # the coarse one at 3x the fraction
    best, met, name, ratio = tl.select(results, replicas=n, t_end=1.0, t_cal=1.0, fraction=0.1)
    assert best.tolerances == FINE and met and name == "O"
    assert ratio == pytest.approx(0.01)


def test_looser_chosen_when_below_fraction():
    n = 16
    results = _two(0.05, 0.01, n)
    best, met, _, ratio = tl.select(results, replicas=n, t_end=1.0, t_cal=1.0, fraction=0.1)
    assert best.tolerances == LOOSE and met and ratio == pytest.approx(0.05)
    # the same data for a run 16x larger: the loose one's bias is now 4 x 0.05 = 0.2 > 0.1
    best, met, _, _ = tl.select(results, replicas=16 * n, t_end=1.0, t_cal=1.0, fraction=0.1)
    assert best.tolerances == FINE and met


def test_random_error_counts_whatever_the_size():
    # sd(d)/sigma = 0.15 > 0.1: rejected even for one replica; 0.05 accepted for any n
    for n in (1, 100):
        res = [_result(LOOSE, 0.0, 1.0, sd=0.15), _result(FINE, 0.0, 3.0, sd=0.05)]
        best, met, _, ratio = tl.select(res, replicas=n, t_end=1.0, t_cal=1.0, fraction=0.1)
        assert best.tolerances == FINE and met and ratio == pytest.approx(0.05)


def test_none_accepted_takes_the_most_accurate_and_says_so():
    n = 16
    best, met, _, ratio = tl.select(_two(0.5, 0.2, n), replicas=n, t_end=1.0, t_cal=1.0,
                                    fraction=0.1)
    assert not met and best.tolerances == FINE and ratio == pytest.approx(0.2)


def test_user_values_win_without_calibration(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("calibration must not run when the user set every tolerance")
    monkeypatch.setattr(tl, "_calibrate", boom)
    spec = CircuitSpec(reltol=2e-5, trtol=3.0, method="trap")
    c = tl.choose_tolerances(STICK, spec, replicas=1000, t_end=100.0)
    assert (c.tolerances.reltol, c.tolerances.trtol, c.tolerances.method) == (2e-5, 3.0, "trap")
    assert c.source == "user"
    new, _ = tl.resolve_spec(STICK, spec, replicas=1000, t_end=100.0)
    assert new == spec


def test_partly_set_spec_keeps_the_set_value(monkeypatch):
    seen = {}

    def fake(model, spec, candidates, **kw):
        seen["pool"] = candidates
        ref = _ref()
        return [tl.candidate_result(c, ref, ref, 0.1, points=1.0 / c.reltol)
                for c in candidates], 1.0
    monkeypatch.setattr(tl, "_calibrate", fake)
    c = tl.choose_tolerances(STICK, CircuitSpec(method="gear"), replicas=16, t_end=1.0)
    assert c.source == "measured" and c.tolerances.method == "gear"
    assert all(t.method == "gear" for t in seen["pool"])
    d = c.as_dict()
    assert d["method"] == "gear" and d["criterion_met"] is True and d["candidates"]


def test_small_runs_and_noise_free_models_get_fixed(monkeypatch):
    monkeypatch.setattr(tl, "_calibrate", lambda *a, **k: (_ for _ in ()).throw(AssertionError))
    c = tl.choose_tolerances(STICK, CircuitSpec(), replicas=2, t_end=1.0,
                             min_replica_holds=10**6)
    assert c.source == "fixed"
    assert c.tolerances == tl.Tolerances(FIXED_RELTOL, FIXED_TRTOL, FIXED_METHOD)
    det = Model(1.0, 0.7, 0.2, math.inf)
    assert tl.choose_tolerances(det, CircuitSpec(), replicas=100, t_end=100.0).source == "fixed"


@pytest.mark.parametrize("kw, word", [({"replicas": 0}, "replicas"), ({"t_end": -1.0}, "t_end"),
                                      ({"fraction": 0.0}, "fraction")])
def test_bad_arguments_name_the_parameter(kw, word):
    args = {"replicas": 4, "t_end": 1.0, **kw}
    with pytest.raises(ValueError, match=word):
        tl.choose_tolerances(STICK, CircuitSpec(), **args)


def test_spec_validates_trtol_and_accepts_unset():
    assert CircuitSpec().unset_tolerances == ("reltol", "trtol", "method")
    assert CircuitSpec(reltol=1e-3).unset_tolerances == ("trtol", "method")
    for bad in (0.5, 101.0):
        with pytest.raises(ValueError, match="trtol"):
            CircuitSpec(trtol=bad)
    with pytest.raises(ValueError, match="method"):
        CircuitSpec(method="euler")


def test_a_measured_check_counts_its_own_noise():
    # sd(d)/sigma = 0.02: fine for the run itself (0.02 <= 0.1), but a check of 25 of 100 paths
    # books |mean d| + 2 SE with SE = sd/sqrt(25): 0.02 (1 + 2) sqrt(100/25) = 0.12 > 0.1
    res = [_result(LOOSE, 0.0, 1.0, sd=0.02), _result(FINE, 0.0, 3.0, sd=0.005)]
    best, met, _, ratio = tl.select(res, replicas=100, t_end=1.0, t_cal=1.0, fraction=0.1)
    assert best.tolerances == LOOSE and ratio == pytest.approx(0.02)
    best, met, _, ratio = tl.select(res, replicas=100, t_end=1.0, t_cal=1.0, fraction=0.1,
                                    check_replicas=25)
    assert best.tolerances == FINE and met and ratio == pytest.approx(0.005 * 3 * 2)
    # a check as large as the run: factor 3
    best, _, _, ratio = tl.select(res, replicas=100, t_end=1.0, t_cal=1.0, fraction=0.1,
                                  check_replicas=100)
    assert best.tolerances == LOOSE and ratio == pytest.approx(0.06)


def test_a_run_is_judged_on_its_own_observables():
    """The loose candidate is poor on a time average ("A") but fine on an instantaneous
    observable ("B"): a run compared on B alone takes it, one compared on both does not."""
    def res(tol, bias_a, bias_b, points):
        return tl.CandidateResult(tol, points, 0.0, {"A": bias_a, "B": bias_b},
                                  {"A": 0.0, "B": 0.0}, {"A": 1.0, "B": 1.0},
                                  {"A": True, "B": False})
    results = [res(LOOSE, 0.5, 0.01, 1.0), res(FINE, 0.01, 0.01, 3.0)]
    best, _, name, _ = tl.select(results, replicas=1, t_end=1.0, t_cal=1.0)
    assert best.tolerances == FINE
    best, met, name, ratio = tl.select(results, replicas=1, t_end=1.0, t_cal=1.0,
                                       observables=("B",))
    assert best.tolerances == LOOSE and met and name == "B" and ratio == pytest.approx(0.01)


def test_the_report_kinds_of_run_cover_every_path_observable():
    import numpy as np
    v = np.zeros((2, 5))
    names, _ = tl.path_observables(v, v, 0.1)
    assert set(tl.TRANSITION_OBSERVABLES) | set(tl.STATIONARY_OBSERVABLES) == set(names)
    assert not set(tl.TRANSITION_OBSERVABLES) & set(tl.STATIONARY_OBSERVABLES)


@pytest.mark.parametrize("bad", [(), ("no such",), ("v(T)", "x")])
def test_unknown_observables_are_refused(bad):
    with pytest.raises(ValueError, match="observables"):
        tl.choose_tolerances(STICK, CircuitSpec(), replicas=4, t_end=1.0, observables=bad)


def test_a_run_that_is_not_callable_is_refused_by_name():
    """``run`` (a simulate-like callable, the way calibrations ran before the Runner) is
    optional now: without it the calibration runs through decks.run_ensemble
    (tests/unit/test_runner.py); one that is not callable is refused before anything runs."""
    with pytest.raises(TypeError, match="run must be callable"):
        tl.choose_tolerances(STICK, CircuitSpec(), replicas=16, t_end=1.0, run="ngspice")
