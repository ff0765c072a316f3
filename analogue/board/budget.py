"""Nominal board against exact theory, with the board's error budget.

Theory: exact finite-noise values of the *requested* ideal model (sgn friction, white noise;
:func:`analogue.study.observables.exact_stationary`).  The board departs from it by, term by
term (each an independent estimate, in the observable's units):

- ``rounding``: E-series values implement another model (:attr:`BoardDesign.realised`);
  exact(realised, eps = 0) - exact(requested);
- ``smoothing``: the bridge's tanh width; exact(realised) - exact(realised, eps = 0);
- ``bandwidth``: the noise chain (DAC hold, quantisation, Bessel, optional AC coupling) instead of white
  noise; an SDE pair on the realised model driven by the same increments, coloured minus white,
  |difference| + 2 standard errors;
- ``integration``: ngspice at reltol 1e-3 (the runs) against 1e-4, path-wise on the same noise
  (measured once per report on a few replicas), |difference| + 2 standard errors.

``within_budget``: |board - theory| <= 3 stderr + the sum of the terms (as in
:mod:`analogue.study.metrics`).
"""
from __future__ import annotations

import math

import numpy as np

from ..ensemble import Ensemble
from ..model import Model
from ..montecarlo import default_dt, simulate_sde
from ..study.metrics import Z_LIMIT
from ..study.observables import (
    exact_stationary,
    jackknife,
    jackknife_difference,
    stationary_values,
)
from .design import BoardDesign
from .noise_chain import filtered_noise

__all__ = ["MIN_JACKKNIFE_GROUPS", "SE_MULTIPLIER", "bandwidth_pair", "board_comparisons",
           "observables_fn"]

SE_MULTIPLIER = 2.0


def observables_fn(model: Model, *, burn_in: float, threshold: float, taus=(1.0,)):
    """The compared observables of an ensemble (names as in the paper report)."""
    return lambda e: stationary_values(e, burn_in=burn_in, threshold=threshold,
                                       force=model.force, taus=taus)


def bandwidth_pair(design: BoardDesign, *, v0, t_end: float, replicas: int, seed: int,
                   sample_dt: float) -> tuple[Ensemble, Ensemble]:
    """(coloured, white) SDE ensembles of the realised model with common increments."""
    model = design.realised
    h = design.noise_dt
    per_hold = max(1, math.ceil(h / default_dt(model) - 1e-9))
    dt = h / per_hold
    n_hold = round(t_end / h)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(17,)))
    z = rng.standard_normal((replicas, n_hold * per_hold))
    spec = design.spec
    lsb = 2.0 * spec.dac_range / 2 ** spec.dac_bits
    coloured = filtered_noise(design.values, z, per_hold, design.noise_ts, rms=spec.dac_rms,
                              lsb=lsb, clip=spec.dac_range)
    sample_dt = h * max(1, round(sample_dt / h))
    kw = {"v0": v0, "t_end": n_hold * h, "replicas": replicas, "dt": dt, "sample_dt": sample_dt}
    return simulate_sde(model, noise=coloured, **kw), simulate_sde(model, noise=z, **kw)


def _term(pair: dict, name: str) -> float:
    d, se = pair.get(name, (0.0, 0.0))
    return abs(d) + SE_MULTIPLIER * se


# below this many jackknife groups (twice as many replicas) the run's own error estimate has
# too few degrees of freedom; the SDE ensemble's error scaled to the run's size is used
MIN_JACKKNIFE_GROUPS = 8


def board_comparisons(experiment: str, design: BoardDesign, board_ens: Ensemble, *, fn,
                      threshold: float, taus, band: dict, integ: dict | None,
                      model_se: dict | None = None) -> tuple[list, dict]:
    """Comparisons (dicts in the metrics.json schema, with a ``budget`` breakdown) of the
    board ensemble against exact theory of the requested model; returns (rows, circuit).

    ``circuit_stderr`` is the jackknife over the board's replicas, or, where that has fewer
    than :data:`MIN_JACKKNIFE_GROUPS` groups and ``model_se`` gives one, the standard error of
    a run of this size from an SDE ensemble of the realised model
    (:func:`analogue.board.job.stderr_at`); ``stderr_method`` says which, and
    ``jackknife_stderr`` keeps the run's own."""
    model = design.model
    circ = jackknife(fn, board_ens)
    groups = max(2, min(32, board_ens.replicas // 2))   # what jackknife() used
    use_model = model_se is not None and groups < MIN_JACKKNIFE_GROUPS
    ex = exact_stationary(model, threshold=threshold, taus=taus)
    real0 = design.realised.replace(epsilon=0.0)
    ex_r0 = exact_stationary(real0, threshold=threshold, taus=taus)
    ex_r = exact_stationary(design.realised, threshold=threshold, taus=taus)
    rows = []
    for k, (val, se_jk) in circ.items():
        if k.startswith("diffusion"):
            continue  # needs far longer runs than the board job makes (reported, not compared)
        if use_model and model_se and model_se.get(k):
            se = model_se[k]
            method = (f"SDE ensemble of the realised model scaled to {board_ens.replicas} "
                      f"replicas (the run's jackknife has {groups} groups)")
        else:
            se, method = se_jk, f"jackknife over the board's replicas ({groups} groups)"
        terms = {"rounding": ex_r0[k] - ex[k], "smoothing": ex_r[k] - ex_r0[k],
                 "bandwidth": _term(band, k), "integration": _term(integ or {}, k)}
        total = sum(abs(v) for v in terms.values())
        diff = val - ex[k]
        z = diff / se if se > 0 else math.inf
        stat = Z_LIMIT * se
        dominant = max(terms, key=lambda t: abs(terms[t])) if total > stat else "statistical"
        rows.append({"experiment": experiment, "observable": k, "circuit": float(val),
                     "circuit_stderr": float(se), "stderr_method": method,
                     "jackknife_stderr": float(se_jk), "theory": float(ex[k]), "theory_kind": "exact",
                     "z": float(z) if math.isfinite(z) else None,
                     "within_budget": bool(abs(diff) <= stat + total),
                     "budget": {**{t: float(v) for t, v in terms.items()}, "total": float(total),
                                "statistical": float(stat), "dominant": dominant},
                     "note": "nominal board (E-series values, op-amp macromodels, noise "
                             "chain) against exact theory of the requested ideal model"})
    return rows, circ


def integration_pair(fn, loose: Ensemble, tight: Ensemble) -> dict:
    return jackknife_difference(fn, loose, tight, groups=max(2, min(16, loose.replicas // 2)))
