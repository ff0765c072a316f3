"""The bandwidth term computed without circuit data (study.comparisons.bandwidth_terms): the
report computes it in the theory thread while ngspice runs, and analyse() takes it.  It must
be, bit for bit, the held/white Monte Carlo pairs on the experiment's seeds that analyse()
computed itself before (no ngspice: the "circuit" runs are SDE ensembles)."""
from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path

import pytest

from analogue.circuit.experiments import experiment_from_dict
from analogue.circuit.mapping import map_model
from analogue.estimators.resampling import jackknife_difference
from analogue.montecarlo import simulate_sde
from analogue.study.budget import SE_MULTIPLIER, held_noise_pair
from analogue.study.comparisons import (MC_REPLICAS, MC_STATIONARY_REPLICAS, analyse,
                                         bandwidth_terms)
from analogue.report.plan import RunOptions
from analogue.study.runs import ExperimentRuns
from analogue.study.theory_curves import experiment_theory
from analogue.study.catalogue import StationaryValues, transition_values
from analogue.study.seeds import SeedPlan
from analogue.theory.exact import sample_stationary

ROOT = Path(__file__).resolve().parents[2]


def _tiny(seed: int = 11):
    """The stick experiment, shortened (two histogram times, a short stationary run)."""
    d = tomllib.loads((ROOT / "circuits" / "stick.toml").read_text())
    d["experiment"].update(t_end=2.0, histogram_times=[0.5, 2.0], seed=seed)
    d["report"].update(stationary_t_end=8.0, stationary_burn_in=1.0,
                       prehistory=[[2.0, 0.9, 1.0]], stationary_hold_divisor=2)
    exp = experiment_from_dict(d)
    return exp, exp.report.for_options(RunOptions(quick=True))


@pytest.fixture(scope="module")
def tiny():
    exp, settings = _tiny()
    return exp, settings, bandwidth_terms(exp, settings)


def test_bandwidth_terms_are_the_held_white_pairs_on_the_experiments_seeds(tiny):
    """The recipe written out here (the code analyse() ran before): same seeds, same pairs,
    same jackknife, so the same numbers exactly."""
    exp, settings, bw = tiny
    mapping = map_model(exp.model, exp.spec)
    m_eff, noise_dt = mapping.model_effective, mapping.noise_dt
    seeds = SeedPlan(exp.seed)
    times = list(exp.histogram_times)
    assert list(bw.transition) == list(exp.v0)
    for i, v0 in enumerate(exp.v0):
        held, white = held_noise_pair(m_eff, v0=v0, t_end=max(times), replicas=MC_REPLICAS,
                                      seed=seeds.mc_transition(i), noise_dt=noise_dt,
                                      sample_dt=exp.sample_dt)
        want = jackknife_difference(lambda e, v0=v0: transition_values(e, v0, times), held, white)
        assert bw.transition[v0] == want
    thr = settings.stick_threshold * exp.model.velocity_scale
    fn = StationaryValues(burn_in=settings.stationary_burn_in, threshold=thr,
                          force=exp.model.force, taus=bw.taus)
    v0_mc = sample_stationary(m_eff, MC_STATIONARY_REPLICAS, seeds.mc_stationary_v0)
    # the stationary runs hold the noise for noise_dt / stationary_hold_divisor (2 here)
    assert settings.stationary_hold_divisor == 2
    held, white = held_noise_pair(m_eff, v0=v0_mc, t_end=settings.stationary_t_end,
                                  replicas=v0_mc.size, seed=seeds.mc_stationary,
                                  noise_dt=noise_dt / 2, sample_dt=exp.sample_dt)
    assert bw.stationary == jackknife_difference(fn, held, white)
    assert bw.threshold == thr


def _sde_runs(exp, settings):
    """SDE ensembles of the circuit's effective model in place of the circuit's runs."""
    m = exp.mapping().model_effective
    kw = dict(sample_dt=exp.sample_dt)
    tr = {v0: simulate_sde(m, v0=v0, t_end=exp.t_end, replicas=32, seed=1 + i, **kw)
          for i, v0 in enumerate(exp.v0)}
    st = simulate_sde(m, v0="stationary", t_end=settings.stationary_t_end, replicas=16, seed=9, **kw)
    chk_t = simulate_sde(m, v0=exp.v0[0], t_end=exp.t_end, replicas=8, seed=1, **kw)
    chk_s = simulate_sde(m, v0="stationary", t_end=settings.stationary_t_end, replicas=8, seed=9,
                         **kw)
    return ExperimentRuns(exp=exp, settings=settings, quick=True, transition=tr, stationary=st,
                          noise_free=chk_t, check_transition=chk_t, check_stationary=chk_s)


def test_analyse_uses_the_given_terms_and_computes_the_same_ones_itself(tiny):
    exp, settings, bw = tiny
    runs = _sde_runs(exp, settings)
    theory = experiment_theory(exp, settings, cache=False)
    given = analyse(runs, theory=theory, bandwidth=bw)
    itself = analyse(runs, theory=theory)
    assert [c.as_dict() for c in given.comparisons] == [c.as_dict() for c in itself.comparisons]
    # each observable's bandwidth term is |difference| + 2 SE of the given pairs
    terms = {**{k: v for v0 in exp.v0 for k, v in bw.transition[v0].items()}, **bw.stationary}
    for k, b in given.budgets.items():
        d, se = terms[k]
        assert b.bandwidth == abs(d) + SE_MULTIPLIER * se
    # terms of other seeds give other budgets: the argument is what analyse uses
    other_exp, _ = _tiny(seed=12)
    other = analyse(runs, theory=theory, bandwidth=bandwidth_terms(other_exp, settings))
    assert any(other.budgets[k].bandwidth != b.bandwidth for k, b in given.budgets.items())


def test_terms_of_other_settings_are_refused(tiny):
    exp, settings, bw = tiny
    runs = _sde_runs(exp, settings)
    theory = experiment_theory(exp, settings, cache=False)
    other = replace(settings, stick_threshold=0.2)
    with pytest.raises(ValueError, match="bandwidth terms computed for other settings"):
        analyse(runs, theory=theory, bandwidth=bandwidth_terms(exp, other))


def test_stationary_term_follows_the_stationary_hold(tiny):
    """The stationary runs' hold is the circuit's over ``stationary_hold_divisor``: their
    bandwidth term is computed at that hold (divisor 1 gives the circuit's own hold, and a
    larger term: the bias is about linear in the hold), the transition terms are unchanged
    (``tiny`` has divisor 2)."""
    exp, settings, bw = tiny
    coarse = bandwidth_terms(exp, replace(settings, stationary_hold_divisor=1))
    assert coarse.transition == bw.transition
    d_fine = bw.stationary["stick fraction"]
    d_coarse = coarse.stationary["stick fraction"]
    # the halved hold's stick-fraction bias is smaller by more than both pairs' errors
    assert abs(d_coarse[0]) - abs(d_fine[0]) > 2.0 * (d_coarse[1] + d_fine[1])
