"""Every circuit-versus-theory comparison of one experiment, with its error budget.

Theory values are those of the *ideal* model (sgn friction, white noise); the circuit's
departures from it are budgeted term by term (:mod:`analogue.report.budget`), so a reader can
see which one dominates.  Circuit standard errors come from a jackknife over replicas, which
are independent (errors hold however correlated the samples along one path are).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..circuit.mapping import map_model
from ..theory.exact import sample_stationary
from .budget import SE_MULTIPLIER, held_noise_pair
from .metrics import Budget, compare
from .observables import (exact_stationary, exact_transition, histogram_chi2, tname, jackknife, jackknife_difference,
                          stationary_values, subset, transition_values, weak_noise_transition)
from .runs import ExperimentRuns

__all__ = ["ExperimentAnalysis", "analyse", "MC_REPLICAS", "MC_STATIONARY_REPLICAS"]

# Held/white Monte Carlo pairs are cheap (numpy); enough replicas that the bandwidth estimate
# is not dominated by its own noise (threshold observables change by whole paths).
MC_REPLICAS = 1024
MC_STATIONARY_REPLICAS = 256


@dataclass
class ExperimentAnalysis:
    runs: ExperimentRuns
    comparisons: list = field(default_factory=list)
    budgets: dict = field(default_factory=dict)   # observable -> Budget
    circuit: dict = field(default_factory=dict)   # observable -> (value, se)
    exact: dict = field(default_factory=dict)     # observable -> exact value (ideal model)
    exact_eff: dict = field(default_factory=dict)  # ... at the circuit's epsilon

    def summary(self) -> dict:
        n = len(self.comparisons)
        ok = sum(c.within_budget for c in self.comparisons)
        z_ok = sum(abs(c.z) < 3 for c in self.comparisons if math.isfinite(c.z))
        return {"comparisons": n, "within_budget": ok, "abs_z_below_3": z_ok}


def _prob_floor(name: str, value: float, se: float, n: int) -> float:
    """A probability estimated as 0 or 1 from n samples still has an error ~ 1/n."""
    if name.startswith("P(") and n > 0:
        p = (value * n + 1) / (n + 2)
        return max(se, math.sqrt(p * (1 - p) / n))
    return se


def _bias(pair_diffs: dict, name: str) -> float:
    d, se = pair_diffs.get(name, (0.0, 0.0))
    return abs(d) + SE_MULTIPLIER * se


def analyse(runs: ExperimentRuns, *, progress=None) -> ExperimentAnalysis:
    exp, st = runs.exp, runs.settings
    model = exp.model
    mapping = map_model(model, exp.spec)
    model_eff = mapping.model_effective
    noise_dt = mapping.noise_dt
    res = ExperimentAnalysis(runs)
    # one Fokker-Planck spacing for the ideal and the smoothed model (see exact_transition)
    h = model_eff.epsilon / 2 if model_eff.epsilon > 0 else None
    tick = progress or (lambda *_: None)

    # ---------------------------------------------------------------- transition runs
    times = [t for t in exp.histogram_times]
    weak = {}
    for i, (v0, ens) in enumerate(runs.transition.items()):
        tick(f"{exp.name}: transition from v0={v0:g}")
        fn = lambda e, v0=v0: transition_values(e, v0, times)
        circ = jackknife(fn, ens)
        n = ens.replicas
        circ = {k: (v, _prob_floor(k, v, se, n)) for k, (v, se) in circ.items()}
        ex = exact_transition(model, v0, times, h=h)
        dens: dict = {}
        ex_eff = exact_transition(model_eff, v0, times, h=h, densities=dens)
        held, white = held_noise_pair(model_eff, v0=v0, t_end=max(times), replicas=MC_REPLICAS,
                                      seed=1000 * exp.seed + 600 + i, noise_dt=noise_dt,
                                      sample_dt=exp.sample_dt)
        band = jackknife_difference(fn, held, white)
        integ = {}
        if i == 0:
            chk = runs.check_transition
            integ = jackknife_difference(fn, chk, subset(ens, np.arange(chk.replicas)))
        if model.delta > 0:
            weak.update(weak_noise_transition(model, v0, times))
        for k, (val, se) in circ.items():
            b = Budget(smoothing=ex_eff[k] - ex[k], bandwidth=_bias(band, k),
                       integration=_bias(integ, k) if integ else 0.0)
            res.budgets[k] = b
            res.circuit[k], res.exact[k], res.exact_eff[k] = (val, se), ex[k], ex_eff[k]
            note = "" if integ else "integration checked on the first v0 only"
            res.comparisons.append(compare(exp.name, k, val, se, ex[k], "exact", b, note))
            if k in weak and k.startswith("mean v"):
                bw = Budget(smoothing=b.smoothing, bandwidth=b.bandwidth, integration=b.integration,
                            finite_noise=ex[k] - weak[k])
                res.comparisons.append(compare(
                    exp.name, k, val, se, weak[k], "weak-noise", bw,
                    "saddle-point propagator (eqs. (46)-(51)) normalised on a grid; "
                    "finite_noise = exact(gamma) - weak-noise"))

        for t, f in zip(times, dens["f"]):
            chi2, dof = histogram_chi2(ens.at(t), dens["v"], f)
            res.comparisons.append(compare(
                exp.name, tname("histogram chi2/dof", t, v0), chi2 / dof, math.sqrt(2.0 / dof),
                1.0, "exact", Budget(),
                f"Pearson chi^2 of the {ens.replicas} circuit velocities against the exact "
                f"f(v, t | v0) at the circuit's epsilon, {dof + 1} equal-probability bins"))

    # ---------------------------------------------------------------- stationary run
    tick(f"{exp.name}: stationary observables")
    ens = runs.stationary
    thr = st.stick_threshold * model.velocity_scale
    taus = [tau for tau in exp.work_taus
            if tau <= st.stationary_t_end - st.stationary_burn_in - 1e-9]
    stationary_fn = lambda e: stationary_values(e, burn_in=st.stationary_burn_in, threshold=thr,
                                                force=model.force, taus=taus)
    circ = jackknife(stationary_fn, ens)
    ex = exact_stationary(model, threshold=thr, taus=taus, h=h)
    ex_eff = exact_stationary(model_eff, threshold=thr, taus=taus, h=h)
    v0_mc = sample_stationary(model_eff, MC_STATIONARY_REPLICAS, 1000 * exp.seed + 701)
    tick(f"{exp.name}: held-noise Monte Carlo pair")
    held, white = held_noise_pair(model_eff, v0=v0_mc, t_end=st.stationary_t_end,
                                  replicas=v0_mc.size, seed=1000 * exp.seed + 700, noise_dt=noise_dt,
                                  sample_dt=exp.sample_dt)
    band = jackknife_difference(stationary_fn, held, white)
    chk = runs.check_stationary
    integ = jackknife_difference(stationary_fn, chk, subset(ens, np.arange(chk.replicas)))
    for k, (val, se) in circ.items():
        b = Budget(smoothing=ex_eff[k] - ex[k], bandwidth=_bias(band, k),
                   integration=_bias(integ, k))
        res.budgets[k] = b
        res.circuit[k], res.exact[k], res.exact_eff[k] = (val, se), ex[k], ex_eff[k]
        res.comparisons.append(compare(exp.name, k, val, se, ex[k], "exact", b))
    return res
