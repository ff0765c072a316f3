"""The circuit runs behind one experiment's report (all through :func:`analogue.simulate`,
so they are seeded, stored and resumable).

- transition runs: ``replicas`` trajectories from each ``v0`` (f(v, t | v0), prehistory);
- a stationary run: replicas started from p_s (stationary law, work, stick, transport);
- a noise-free run against ``Model.deterministic`` (paper Fig. 1): the user's own circuit
  (same component values, same parts) with the noise source's amplitude set to zero
  (:meth:`~analogue.circuit.mapping.CircuitMapping.without_noise`), one replica per v0;
- integration checks: the first decks of the transition and stationary runs again with
  100x tighter tolerances than the ones chosen for them (:mod:`analogue.circuit.tolerances`,
  recorded with the deck size in each ensemble's ``meta``) and a quarter of the step,
  covering at least ``check_replicas`` replicas ([report]).  The held noise (``trrandom`` with ``.options seed``) is the same
  realisation, so the path-by-path difference measures the integration error directly, with
  no statistical noise.

Every circuit built here was validated when the experiment was loaded
(:meth:`~analogue.circuit.experiments.Experiment.planned_circuits`).
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..circuit.experiments import Experiment
from ..circuit.simulate import DEFAULT_REPLICAS_PER_DECK
from ..circuit.store_index import indexing_runs
from ..ensemble import Ensemble
from ..model import Model
from ..study.seeds import SeedPlan
from .plan import ReportSettings, RunOptions

__all__ = ["ExperimentRuns", "run_experiment_runs", "first_deck_size", "check_plan"]


def first_deck_size(replicas: int, per_deck: int = DEFAULT_REPLICAS_PER_DECK) -> int:
    """Replicas in deck 0 when :func:`analogue.simulate` splits ``replicas`` evenly."""
    n_decks = -(-replicas // per_deck)
    return replicas // n_decks + (1 if replicas % n_decks else 0)


def check_plan(replicas: int, want: int, per_deck: int = DEFAULT_REPLICAS_PER_DECK) -> tuple[int, int]:
    """``(decks, size)``: the integration check re-runs the first ``decks`` decks of a nominal
    run of ``replicas`` replicas, each of ``size`` replicas, covering at least ``want`` replicas
    where the nominal run has that many equal-sized leading decks.

    :func:`analogue.simulate` splits ``replicas`` into ``n`` decks, the first ``replicas % n``
    one replica larger; deck ``b``'s noise depends on ``(seed, b)`` and on its size, so a
    re-run reproduces the nominal noise only deck for deck: ``simulate(replicas=decks * size,
    replicas_per_deck=size)`` builds exactly the first ``decks`` nominal decks."""
    n = -(-replicas // per_deck)
    q, r = divmod(replicas, n)
    size = q + (1 if r else 0)
    equal = r if r else n           # leading decks of that size
    return max(1, min(-(-want // size), equal)), size


@dataclass
class ExperimentRuns:
    exp: Experiment
    settings: ReportSettings
    quick: bool
    transition: dict            # v0 -> Ensemble
    stationary: Ensemble
    noise_free: Ensemble        # one replica per v0: the same circuit with the noise off
    check_transition: Ensemble  # tight-tolerance re-run of deck 0 of transition[v0[0]]
    check_stationary: Ensemble  # ... and of the stationary run
    wall_time: float = 0.0
    seeds: dict = field(default_factory=dict)

    @property
    def model(self) -> Model:
        return self.exp.model

    @property
    def model_effective(self) -> Model:
        return Model(**self.stationary.meta["model_effective"])

    def provenance(self) -> dict:
        ens = {f"transition v0={v0:g}": e for v0, e in self.transition.items()}
        ens.update(stationary=self.stationary, noise_free=self.noise_free,
                   check_transition=self.check_transition, check_stationary=self.check_stationary)
        return {
            "experiment": self.exp.name,
            "parameters": self.exp.model.as_dict(),
            "model_effective": self.model_effective.as_dict(),
            "circuit_spec": self.exp.spec.as_dict(),
            "quick": self.quick,
            "seeds": self.seeds,
            "ngspice_version": self.stationary.meta.get("ngspice_version"),
            "deck_hashes": {k: e.meta.get("deck_sha256") for k, e in ens.items()},
            "replicas": {k: e.replicas for k, e in ens.items()},
            # how each run's ngspice tolerances and deck size were chosen (issue 10)
            "tolerances": {k: e.meta.get("tolerances") for k, e in ens.items()},
            "deck_size": {k: e.meta.get("deck_size") for k, e in ens.items()},
            "wall_time_s": self.wall_time,
        }


def _noise_free_run(exp: Experiment, seed: int, kw: dict) -> Ensemble:
    """One replica per v0 on the user's circuit with the noise off (paper Fig. 1)."""
    from ..circuit.simulate import run_decks, time_grid
    deck = exp.noise_free_deck(seed=seed)
    times = time_grid(deck.t_end, exp.sample_dt)
    v0 = np.asarray(exp.v0, dtype=float)
    run_kw: dict[str, Any] = {k: kw[k] for k in ("store", "workers", "scheduler", "progress", "timeout") if k in kw}
    v, x, _, info = run_decks([deck], times, v0, **run_kw)
    mapping = exp.noise_free_mapping()
    meta: dict[str, Any] = {"source": "circuit", "noise": "off", "model": exp.model.as_dict(),
            "model_effective": mapping.model_effective.as_dict(), "seed": seed,
            "deck_sha256": [deck.sha256], "t_end": deck.t_end, "sample_dt": exp.sample_dt,
            # nothing random to calibrate against: the spec's tolerances or the fixed ones
            "tolerances": {"reltol": mapping.reltol, "trtol": mapping.trtol,
                           "method": mapping.method,
                           "source": "user" if not exp.spec.unset_tolerances else "fixed"},
            **{k: info[k] for k in ("ngspice_version", "store_keys", "from_store", "wall_time")
               if k in info}}
    return Ensemble(times, v, x, meta)


def _choose(model, spec, replicas: int, t_end: float, kw: dict, check: int):
    """(spec with its tolerances set, replicas per deck, why) for one run of the report whose
    integration error is measured on about ``check`` of its paths."""
    from ..circuit.deck_size import choose_deck_size
    from ..circuit.tolerances import resolve_spec
    common = {k: kw[k] for k in ("store", "scheduler") if k in kw}
    workers = kw.get("workers") or os.cpu_count() or 1
    spec, tol = resolve_spec(model, spec, replicas=replicas, t_end=t_end, workers=workers,
                             check_replicas=min(check, replicas), **common)
    deck = choose_deck_size(model, spec, replicas=replicas, t_end=t_end, workers=workers,
                            **common)
    return spec, deck.replicas_per_deck, {"tolerances": tol.as_dict(),
                                          "deck_size": deck.as_dict()}


def _check_coupled(nominal: Ensemble, check: Ensemble, what: str) -> None:
    """The check run must retrace the nominal paths (same noise); anything else is a bug in
    how the decks were matched, which would silently turn the integration estimate into noise."""
    n = check.replicas
    d = np.abs(check.v - nominal.v[:n])
    spread = float(np.std(nominal.v[:n]))
    if not np.isfinite(d).all() or float(np.median(d)) > 0.1 * spread:
        raise RuntimeError(f"{what}: the tight-tolerance re-run does not retrace the nominal "
                           "paths (noise not reproduced?); integration budget unavailable")


@indexing_runs  # the store's index by experiment (analogue store ls): every entry used
def run_experiment_runs(exp: Experiment, opts: RunOptions,
                        settings: ReportSettings | None = None) -> ExperimentRuns:
    from ..circuit.simulate import simulate
    from ..theory.exact import sample_stationary

    t_start = time.perf_counter()
    settings = (settings or exp.report).for_options(opts)
    kw = opts.simulate_kwargs()
    model, spec = exp.model, exp.spec
    model_eff = exp.mapping().model_effective
    replicas = opts.scaled(exp.replicas)
    # Each run gets its own seed, derived from the experiment's: distinct experiments (whose
    # seeds differ) never share a noise realisation, so their comparisons are independent.
    plan = SeedPlan(exp.seed)       # every seed of the report (analogue.study.seeds)
    seeds = {"stationary": plan.stationary, "noise_free": plan.noise_free}

    # Tolerances and deck sizes chosen here (not inside simulate) so that the integration
    # checks below integrate the very decks of the nominal runs 100x more tightly: each run
    # gets the tolerances its own size calls for (circuit.tolerances) and the deck size that
    # makes it fastest (circuit.deck_size); both are recorded in the ensembles' meta.
    n_stat = settings.stationary_replicas
    check = settings.check_replicas
    trans_spec, trans_deck, trans_why = _choose(model, spec, replicas, exp.t_end, kw, check)
    stat_spec, stat_deck, stat_why = _choose(model, spec, n_stat, settings.stationary_t_end, kw,
                                             check)

    transition = {}
    for i, v0 in enumerate(exp.v0):
        seeds[f"transition v0={v0:g}"] = plan.transition(i)
        transition[v0] = simulate(model, v0=v0, t_end=exp.t_end, replicas=replicas,
                                  seed=plan.transition(i), sample_dt=exp.sample_dt, circuit=trans_spec,
                                  replicas_per_deck=trans_deck, **kw)
        transition[v0].meta.update(trans_why)  # simulate saw them as given: say why

    v0_stat = np.asarray(sample_stationary(model_eff, n_stat, seeds["stationary"]), dtype=float)
    stationary = simulate(model, v0=v0_stat, t_end=settings.stationary_t_end, replicas=n_stat,
                          seed=seeds["stationary"], sample_dt=exp.sample_dt, circuit=stat_spec,
                          replicas_per_deck=stat_deck, **kw)
    stationary.meta.update(stat_why)

    noise_free = _noise_free_run(exp, seeds["noise_free"], kw)

    v00 = exp.v0[0]
    decks, size = check_plan(replicas, settings.check_replicas, trans_deck)
    check_transition = simulate(model, v0=v00, t_end=exp.t_end, replicas=decks * size, seed=plan.transition(0),
                                sample_dt=exp.sample_dt, circuit=exp.check_spec(trans_spec),
                                replicas_per_deck=size, **kw)
    _check_coupled(transition[v00], check_transition, "transition check")
    decks, size = check_plan(n_stat, settings.check_replicas, stat_deck)
    n1 = decks * size
    check_stationary = simulate(model, v0=v0_stat[:n1], t_end=settings.stationary_t_end,
                                replicas=n1, seed=seeds["stationary"], sample_dt=exp.sample_dt,
                                circuit=exp.check_spec(stat_spec), replicas_per_deck=size, **kw)
    _check_coupled(stationary, check_stationary, "stationary check")
    return ExperimentRuns(exp=exp, settings=settings, quick=opts.quick, transition=transition,
                          stationary=stationary, noise_free=noise_free,
                          check_transition=check_transition, check_stationary=check_stationary,
                          wall_time=time.perf_counter() - t_start, seeds=seeds)
