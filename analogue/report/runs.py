"""The circuit runs behind one experiment's report (all through :func:`analogue.simulate`,
so they are seeded, stored and resumable).

- transition runs: ``replicas`` trajectories from each ``v0`` (f(v, t | v0), prehistory);
- a stationary run: replicas started from p_s (stationary law, work, stick, transport);
- noise-free runs (gamma -> 1e8) against ``Model.deterministic`` (paper Fig. 1);
- integration checks: the first deck of the transition and stationary runs again with
  100x tighter tolerances and a quarter of the step.  The held noise (``trrandom`` with
  ``.options seed``) is the same realisation, so the path-by-path difference measures the
  integration error directly, with no statistical noise.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..circuit.experiments import Experiment
from ..circuit.simulate import DEFAULT_REPLICAS_PER_DECK
from ..ensemble import Ensemble
from ..model import Model
from .plan import ReportSettings, RunOptions, report_settings

__all__ = ["ExperimentRuns", "run_experiment_runs", "first_deck_size", "NOISE_FREE_GAMMA"]

NOISE_FREE_GAMMA = 1e8
NOISE_FREE_SPEC = {"smoothing": 0.5, "allow_bias": True}


def first_deck_size(replicas: int, per_deck: int = DEFAULT_REPLICAS_PER_DECK) -> int:
    """Replicas in deck 0 when :func:`analogue.simulate` splits ``replicas`` evenly."""
    n_decks = -(-replicas // per_deck)
    return replicas // n_decks + (1 if replicas % n_decks else 0)


@dataclass
class ExperimentRuns:
    exp: Experiment
    settings: ReportSettings
    quick: bool
    transition: dict            # v0 -> Ensemble
    stationary: Ensemble
    noise_free: Ensemble        # one replica per v0, gamma = NOISE_FREE_GAMMA
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
            "wall_time_s": self.wall_time,
        }


def _tight(spec, mapping):
    """The same circuit, integrated 100x more tightly with a quarter of the step."""
    max_step = spec.max_step if spec.max_step is not None else mapping.noise_dt
    return spec.replace(reltol=spec.reltol / 100, abstol=spec.abstol / 100,
                        vntol=mapping.vntol / 100, max_step=max_step / 4)


def _check_coupled(nominal: Ensemble, check: Ensemble, what: str) -> None:
    """The check run must retrace the nominal paths (same noise); anything else is a bug in
    how the decks were matched, which would silently turn the integration estimate into noise."""
    n = check.replicas
    d = np.abs(check.v - nominal.v[:n])
    spread = float(np.std(nominal.v[:n]))
    if not np.isfinite(d).all() or float(np.median(d)) > 0.1 * spread:
        raise RuntimeError(f"{what}: the tight-tolerance re-run does not retrace the nominal "
                           "paths (noise not reproduced?); integration budget unavailable")


def run_experiment_runs(exp: Experiment, opts: RunOptions,
                        settings: ReportSettings | None = None) -> ExperimentRuns:
    from ..circuit.simulate import simulate
    from ..theory.exact import sample_stationary
    from ..circuit.mapping import map_model

    t_start = time.perf_counter()
    settings = (settings or report_settings(exp)).for_options(opts)
    kw = opts.simulate_kwargs()
    model, spec = exp.model, exp.spec
    mapping = map_model(model, spec)
    model_eff = mapping.model_effective
    replicas = opts.scaled(exp.replicas)
    # Each run gets its own seed, derived from the experiment's: distinct experiments (whose
    # seeds differ) never share a noise realisation, so their comparisons are independent.
    base = 1000 * exp.seed
    seeds = {"stationary": base + 500, "noise_free": base + 900}

    transition = {}
    for i, v0 in enumerate(exp.v0):
        seeds[f"transition v0={v0:g}"] = base + i
        transition[v0] = simulate(model, v0=v0, t_end=exp.t_end, replicas=replicas,
                                  seed=base + i, sample_dt=exp.sample_dt, circuit=spec, **kw)

    n_stat = settings.stationary_replicas
    v0_stat = np.asarray(sample_stationary(model_eff, n_stat, seeds["stationary"]), dtype=float)
    stationary = simulate(model, v0=v0_stat, t_end=settings.stationary_t_end, replicas=n_stat,
                          seed=seeds["stationary"], sample_dt=exp.sample_dt, circuit=spec, **kw)

    v0s = np.asarray(exp.v0, dtype=float)
    noise_free = simulate(model.replace(gamma=NOISE_FREE_GAMMA), v0=v0s,
                          t_end=min(exp.t_end, 6.0 * model.tau_m), replicas=len(v0s),
                          seed=seeds["noise_free"], sample_dt=exp.sample_dt,
                          circuit=spec.replace(**NOISE_FREE_SPEC), **kw)

    tight = _tight(spec, mapping)
    v00 = exp.v0[0]
    n0 = first_deck_size(replicas)
    check_transition = simulate(model, v0=v00, t_end=exp.t_end, replicas=n0, seed=base,
                                sample_dt=exp.sample_dt, circuit=tight, **kw)
    _check_coupled(transition[v00], check_transition, "transition check")
    n1 = first_deck_size(n_stat)
    check_stationary = simulate(model, v0=v0_stat[:n1], t_end=settings.stationary_t_end,
                                replicas=n1, seed=seeds["stationary"], sample_dt=exp.sample_dt,
                                circuit=tight, **kw)
    _check_coupled(stationary, check_stationary, "stationary check")
    return _indexed(ExperimentRuns(exp=exp, settings=settings, quick=opts.quick,
                                   transition=transition, stationary=stationary,
                                   noise_free=noise_free, check_transition=check_transition,
                                   check_stationary=check_stationary,
                                   wall_time=time.perf_counter() - t_start, seeds=seeds))


def _indexed(runs: ExperimentRuns) -> ExperimentRuns:
    """Record the runs' store keys under the experiment's name (``analogue store ls``)."""
    from ..circuit.store_index import record_runs
    from ..export import runs_by_role
    try:
        record_runs(runs.exp.name, runs_by_role(runs), quick=runs.quick)
    except OSError as exc:  # a read-only store still serves the runs; only the index is lost
        import logging
        logging.getLogger(__name__).warning("run store index not written: %s", exc)
    return runs
