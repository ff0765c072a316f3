"""The stationary integration check on a prefix window (issue 10), with ngspice: a deck re-run
with a shorter t_end retraces exactly the first part of the nominal paths (the held noise is
drawn in time order), and the report's runs compare the check with the nominal paths on the
same rows and times."""
import shutil

import numpy as np
import pytest

from analogue import Model, simulate
from analogue.circuit.experiments import experiment_from_dict
from analogue.circuit.mapping import CircuitSpec
from analogue.estimators.resampling import jackknife_difference
from analogue.report.plan import RunOptions
from analogue.study.runs import head, run_experiment_runs
from analogue.study.catalogue import stationary_values

pytestmark = pytest.mark.slow

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
SPEC = CircuitSpec(reltol=1e-4, trtol=7.0, method="trap")


@pytest.fixture(autouse=True)
def _ngspice():
    if shutil.which("ngspice") is None:
        pytest.skip("ngspice not installed")


def test_shorter_run_retraces_the_prefix_exactly():
    kw = dict(v0=np.linspace(-0.5, 1.0, 8), replicas=8, seed=5, sample_dt=0.01, circuit=SPEC,
              replicas_per_deck=4, store=False, workers=2, progress=False)
    long = simulate(STICK, t_end=3.0, **kw)
    short = simulate(STICK, t_end=1.2, **kw)
    assert short.v.shape == (8, 121)
    np.testing.assert_array_equal(short.v, head(long, 1.2).v)
    np.testing.assert_array_equal(short.x, head(long, 1.2).x)
    # and the paths do move: not a trivially equal pair
    assert float(np.std(long.v[:, 121:])) > 0.1 * STICK.velocity_scale


def _tiny(stationary_t_end=4.0):
    return experiment_from_dict({
        "name": "tiny",
        "model": {"tau_m": 1.0, "delta": 0.7, "a": 0.2, "gamma": 10.0},
        "circuit": {"reltol": 1e-4, "trtol": 7.0, "method": "trap"},
        "experiment": {"v0": [1.0], "replicas": 4, "t_end": 0.5, "sample_dt": 0.01, "seed": 3},
        "report": {"stationary_replicas": 16, "stationary_t_end": stationary_t_end,
                   "stationary_burn_in": 0.2, "check_replicas": 4,
                   "stationary_hold_divisor": 2},
    }, "tiny")


def test_report_check_covers_a_prefix_on_matched_paths(tmp_path):
    exp = _tiny()
    opts = RunOptions(store=tmp_path / "store", workers=2, progress=False)
    runs = run_experiment_runs(exp, opts)
    chk, nom = runs.check_pair("stationary")
    stat = runs.stationary
    T = float(stat.t[-1])
    Tc = float(chk.t[-1])
    w = runs.check_stationary.meta["check_window"]
    assert Tc == pytest.approx(w["t_end"]) and chk.replicas == w["replicas"]
    # the check is shorter than the run; the nominal counterpart is the run's prefix
    assert Tc < T
    assert nom.v.shape == chk.v.shape
    # the stationary run and its check hold the noise for half the circuit's hold
    # ([report] stationary_hold_divisor = 2), the transition runs for all of it
    hold = exp.mapping().noise_dt
    assert stat.meta["noise_dt"] == chk.meta["noise_dt"] == hold / 2
    assert runs.transition[1.0].meta["noise_dt"] == hold
    assert runs.provenance()["stationary_noise_dt"] == hold / 2
    np.testing.assert_array_equal(nom.v, stat.v[:chk.replicas, :chk.t.size])
    np.testing.assert_allclose(nom.t, chk.t, rtol=0, atol=1e-9)
    # the check retraces them (100x tighter on the same noise): small, nonzero differences
    d = np.abs(chk.v - nom.v)
    assert 0 < float(np.median(d)) < 0.05 * float(np.std(nom.v))
    # the integration term is computed on the matched window and is tiny against the spread
    fn = lambda e: stationary_values(e, burn_in=0.2, threshold=0.1 * STICK.velocity_scale,
                                     force=STICK.force)
    diff = jackknife_difference(fn, chk, nom)
    assert abs(diff["mean v"][0]) < 0.05 * float(np.std(nom.v))

    # a second call reuses every stored deck
    again = run_experiment_runs(exp, opts)
    for e in (again.stationary, again.check_stationary, again.check_transition,
              *again.transition.values()):
        assert e.meta["from_store"] == len(e.meta["deck_sha256"])
    np.testing.assert_array_equal(again.check_stationary.v, runs.check_stationary.v)
