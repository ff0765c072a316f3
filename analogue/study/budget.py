"""Independent estimates of the circuit's systematic errors (the error budget).

- **smoothing**: the diode bridge implements ``tanh(v/epsilon)`` instead of ``sgn(v)``; exact
  Fokker-Planck numerics at the circuit's epsilon minus those at epsilon = 0 give the bias.
- **bandwidth**: the noise is held constant over ``TS`` (ngspice ``trrandom``), not white.  A
  Monte Carlo pair driven by the *same* Wiener increments - white, and held (each hold interval
  gets the mean of its fine increments, i.e. the same integrated noise spread evenly) -
  isolates the effect with little statistical noise (common random numbers).
- **integration**: the circuit re-run with 100x tighter tolerances on the same noise
  (see :mod:`analogue.study.runs`); the path-by-path difference, indicator observables
  through their smoothed indicator (:func:`integration_term`).
- **finite noise** (weak-noise comparisons only): exact finite-gamma minus the paper's
  gamma -> infinity formula.
- **element** (real diodes): a vendor bridge realises its own DC friction law, not the
  slope-matched tanh the smoothing term assumes; exact numerics on that law minus exact
  numerics on the tanh (:func:`real_diode_element`).
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..circuit.mapping import CircuitMapping
from ..ensemble import Ensemble
from ..model import Model
from .catalogue import (stationary_label, stationary_observables, stationary_theory,
                               transition_label)
from ..theory.friction_law import stationary_law_with_friction, transition_moments_with_friction
from ..estimators.resampling import jackknife_difference
from ..montecarlo import simulate_sde_held_pair
from ..montecarlo import _given_v0, default_dt
from ..montecarlo import simulate_sde

__all__ = ["held_noise_pair", "held_noise_pair_chunks", "PAIR_CHUNK", "integration_term", "real_diode_element",
           "real_diode_transition_element", "SE_MULTIPLIER", "RICHARDSON",
           "MIN_STEPS_PER_HOLD", "CIRCUIT_BIAS_TERMS", "terms_above_se", "terms_above_se_text"]

# A measured bias enters the budget as |estimate| + SE_MULTIPLIER * its standard error.
SE_MULTIPLIER = 2.0
# Fine steps per hold in the held/white pair at least: the white run's own hold is then
# 1/16 of the circuit's, and the term falls short by about 6 % of itself (the bias is about
# linear in the hold).  Before, the fine step was default_dt alone, 1/12 of the stick
# circuit's hold 0.01 and 1/8 of a hold 0.005: a finer circuit hold would have been judged
# against an ever coarser "white" reference (at per_hold = 1 the term is 0 by construction).
MIN_STEPS_PER_HOLD = 16
# The kernel bias of a smoothed indicator is O(h^2): from d_h and d_{h/2}, bias(h) ~
# (4/3) (d_h - d_{h/2}) (one Richardson step).
RICHARDSON = 4.0 / 3.0


def integration_term(values, check: Ensemble, nominal: Ensemble, h: float) -> dict:
    """The integration budget term of every observable: ``|d_h| + SE_MULTIPLIER SE(d_h) +
    RICHARDSON |d_h - d_{h/2}|``, with ``d_s = values(s)(check) - values(s)(nominal)`` on the
    paired runs (row i of both driven by the same noise) and ``values(s)`` the observable set
    whose indicator kinds are smoothed with width ``s``
    (:mod:`analogue.estimators.smoothed_indicator`; the other kinds do not depend on ``s``,
    so their last term is 0).  SE: the paired delete-a-group jackknife.  Returns ``{name:
    (term, d_h, se, kernel)}``."""
    diff = jackknife_difference(values(h), check, nominal)
    if h > 0:
        half = values(0.5 * h)
        a, b = half(check), half(nominal)
    out = {}
    for k, (d, se) in diff.items():
        kernel = RICHARDSON * abs(d - (a[k] - b[k])) if h > 0 else 0.0
        out[k] = (abs(d) + SE_MULTIPLIER * se + kernel, d, se, kernel)
    return out


# The budget's circuit bias terms (study.metrics.Budget), with what each is (finite_noise is
# the paper's weak-noise formula against the exact theory, not a property of the circuit).
CIRCUIT_BIAS_TERMS = {
    "smoothing": "the diode bridge's tanh width (smoothing)",
    "bandwidth": "the held noise (noise_dt; [report] stationary_hold_divisor for the "
                 "stationary rows)",
    "integration": "ngspice's tolerances",
    "sampling": "the output grid and binning",
    "element": "the circuit elements (real diodes, cubic network, inductor, shot pulses)",
}


def terms_above_se(comps, limit: float = 1.0) -> dict:
    """``{experiment: [(observable, term, ratio), ...]}``: every circuit bias term
    (:data:`CIRCUIT_BIAS_TERMS`) of the comparisons ``comps`` (study.metrics.Comparison) that
    is at least ``limit`` statistical errors, once per experiment and observable (an
    observable compared with the exact and the weak-noise theory has the same circuit terms),
    largest first within an observable."""
    out: dict = {}
    seen = set()
    for c in comps:
        key = (c.experiment, c.observable)
        if key in seen or not c.circuit_stderr > 0:
            continue
        seen.add(key)
        big = sorted(((name, abs(getattr(c.budget, name)) / c.circuit_stderr)
                      for name in CIRCUIT_BIAS_TERMS), key=lambda t: -t[1])
        for name, ratio in big:
            if ratio >= limit:
                out.setdefault(c.experiment, []).append((c.observable, name, ratio))
    return out


def terms_above_se_text(comps, limit: float = 1.0) -> list[str]:
    """The report summary's lines naming the bias terms of at least ``limit`` statistical
    errors (issue 18: every bias term below one SE, or named with the reason)."""
    found = terms_above_se(comps, limit)
    if not found:
        return []
    lines = [f"{exp}: bias terms of at least {limit:g} standard error: "
             + "; ".join(f"{obs} ({name} {r:.1f} SE)" for obs, name, r in rows) + "."
             for exp, rows in found.items()]
    used = sorted({name for rows in found.values() for _, name, _ in rows})
    lines.append("Reasons: " + "; ".join(f"{n}: {CIRCUIT_BIAS_TERMS[n]}" for n in used) + ".")
    return lines


# Replicas per chunk of a held/white pair (held_noise_pair_chunks): the rows of the noise are
# drawn chunk after chunk from the pair's one stream (the same numbers as one draw of all
# rows), and each chunk is integrated on its own, so that an executor (the report's threads:
# the loop's numpy arithmetic runs outside the GIL) runs them on as many cores as it has, with
# results bit for bit those of one loop over every row (the loop is row-wise).  Fixed, not derived from the core count: the result never depends on it.
# 1024 keeps the per-step numpy overhead small against the arithmetic (2048 rows per loop):
# the quick work experiment's transition pairs (4096 replicas, 19 200 steps) are 4 chunks each.
PAIR_CHUNK = 1024


def _pair_chunk(model: Model, v0, z: np.ndarray, per_hold: int, dt: float, sample_dt: float,
                t_end: float) -> tuple:
    """One chunk of a held/white pair (an executor's task): ``simulate_sde_held_pair`` on
    the rows ``z``, returned without the white run's noise (``z`` itself, which the caller
    holds: never sent back from a worker process), with the CPU seconds of the thread that
    ran it."""
    import time

    c0 = time.thread_time()
    held, white = simulate_sde_held_pair(model, v0=v0, t_end=t_end, replicas=z.shape[0],
                                         noise=z, noise_hold=per_hold, dt=dt,
                                         sample_dt=sample_dt)
    white = Ensemble(white.t, white.v, white.x, white.meta, None)
    return held, white, time.thread_time() - c0


def held_noise_pair_chunks(model: Model, *, v0, t_end: float, replicas: int, seed: int,
                           noise_dt: float, sample_dt: float, executor=None, timing=None,
                           keep_noise: bool = True):
    """:func:`held_noise_pair` in chunks of :data:`PAIR_CHUNK` replicas, each submitted to
    ``executor`` (a ``concurrent.futures`` executor: threads or processes; None: run here) as
    soon as its noise is drawn.  Returns a function that waits for the chunks and returns
    ``(held, white)``, bit for bit :func:`held_noise_pair`'s.  ``timing``: a list that gets
    ``(seconds drawing the noise in this thread, [CPU seconds of each chunk])`` when they are
    collected (the report's critical path: the draw, then the longest chunk).  ``keep_noise``
    False: the ensembles come back without their noise (``noise`` None), for a caller that
    only takes observables of the paths (the report's bandwidth terms): stacking the white
    run's noise copied 630 MB per quick work transition pair (4096 x 19 200 normals), a sixth
    of the theory thread's samples in the quick paper (py-spy), for an array never read."""
    import time


    per_hold = max(MIN_STEPS_PER_HOLD, math.ceil(noise_dt / default_dt(model) - 1e-9))
    dt = noise_dt / per_hold
    n_hold = round(t_end / noise_dt)
    if abs(n_hold * noise_dt - t_end) > 1e-9 * t_end:
        raise ValueError(f"t_end={t_end!r} must be a whole number of noise hold times {noise_dt!r}")
    sample_dt = noise_dt * max(1, round(sample_dt / noise_dt))
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(7,)))
    if not model.noise_kind.paper:   # kicks or coloured noise: simulate_sde's own loop
        z = rng.standard_normal((replicas, n_hold * per_hold))
        pair = _held_pair_given(model, v0=v0, t_end=t_end, replicas=replicas, seed=seed,
                                     z=z, per_hold=per_hold, dt=dt, sample_dt=sample_dt)
        return lambda: pair
    v_all, v0_meta = _given_v0(v0, replicas, f"a number or an array of shape ({replicas},)")
    t_draw = time.thread_time()
    parts: list = []
    for lo in range(0, replicas, PAIR_CHUNK):
        hi = min(replicas, lo + PAIR_CHUNK)
        # row after row from the one stream: the numbers of rng.standard_normal((replicas, n))
        z = rng.standard_normal((hi - lo, n_hold * per_hold))
        v0_c = v0 if np.ndim(v0) == 0 else v_all[lo:hi]
        args = (model, v0_c, z, per_hold, dt, sample_dt, t_end)
        result: Any = (executor.submit(_pair_chunk, *args) if executor is not None
                       else _pair_chunk(*args))
        parts.append((z, result))
    t_draw = time.thread_time() - t_draw

    def collect() -> tuple[Ensemble, Ensemble]:
        done = [(z, f.result() if executor is not None else f) for z, f in parts]
        if timing is not None:
            timing.append((t_draw, [r[2] for _, r in done]))
        h0, w0 = done[0][1][0], done[0][1][1]
        if len(done) == 1:
            if not keep_noise:
                return (Ensemble(h0.t, h0.v, h0.x, h0.meta, None),
                        Ensemble(w0.t, w0.v, w0.x, w0.meta, None))
            return h0, Ensemble(w0.t, w0.v, w0.x, w0.meta, done[0][0])
        meta = {"replicas": replicas, "v0": v0_meta}
        held = Ensemble(h0.t, np.vstack([r[0].v for _, r in done]),
                        np.vstack([r[0].x for _, r in done]), {**h0.meta, **meta},
                        np.vstack([r[0].noise for _, r in done]) if keep_noise else None)
        white = Ensemble(w0.t, np.vstack([r[1].v for _, r in done]),
                         np.vstack([r[1].x for _, r in done]), {**w0.meta, **meta},
                         np.vstack([z for z, _ in done]) if keep_noise else None)
        return held, white
    return collect


def held_noise_pair(model: Model, *, v0, t_end: float, replicas: int, seed: int,
                    noise_dt: float, sample_dt: float, executor=None) -> tuple[Ensemble, Ensemble]:
    """(held, white) SDE ensembles driven by common Wiener increments.

    ``noise_dt`` is the circuit's hold time (model units); the fine step divides it into at
    least :data:`MIN_STEPS_PER_HOLD` steps (and is at most the model's ``default_dt``).  The
    "white" run is itself noise held over one fine step, so the pair measures ``b(noise_dt) -
    b(noise_dt / per_hold)`` of a bias ``b`` about linear in the hold (measured on the work
    experiment's stick fraction: 25.7, 11.2, 4.7, 1.7 statistical errors at holds 0.01, 0.005,
    0.0025, 0.00125): it falls short by about ``1/per_hold`` of the term.

    Integrated in chunks of :data:`PAIR_CHUNK` replicas (on ``executor`` when given:
    :func:`held_noise_pair_chunks`), bit for bit one loop over all replicas.
    """
    return held_noise_pair_chunks(model, v0=v0, t_end=t_end, replicas=replicas, seed=seed,
                                  noise_dt=noise_dt, sample_dt=sample_dt, executor=executor)()


def _held_pair_given(model: Model, *, v0, t_end, replicas, seed, z, per_hold, dt,
                     sample_dt) -> tuple[Ensemble, Ensemble]:
    """Noise other than white Gaussian alone (the fused loop is Gaussian-only): shot +
    Gaussian noise, two runs whose kicks come from one seed, so that the pair differs by the
    hold alone (a shot + Gaussian member's report failed on the fused loop's refusal);
    coloured noise, the filter's white input held (analogue.variants.coloured)."""
    n_hold = z.shape[1] // per_hold
    kicks = int(np.random.SeedSequence(seed, spawn_key=(8,)).generate_state(1)[0])
    kw = dict(v0=v0, t_end=t_end, replicas=replicas, dt=dt, sample_dt=sample_dt, seed=kicks)
    held = z.reshape(replicas, n_hold, per_hold).mean(axis=2)
    return (simulate_sde(model, noise=held, noise_hold=per_hold, **kw),
            simulate_sde(model, noise=z, **kw))


def real_diode_element(mapping: CircuitMapping, *, threshold: float, taus,
                       stationary_eff: dict) -> dict:
    """The element term of every stationary observable of a real-diode bridge (issue 18):
    ``exact(real law) - exact(tanh(v/epsilon))`` (signed: the circuit's law minus the law the
    smoothing term already books), ``{label: difference}``.  The real law is the bridge's DC
    I-V from the part's model (:meth:`~analogue.circuit.mapping.CircuitMapping.friction_law`);
    both exact values come from the same quadrature of ``exp(-gamma U)``
    (:mod:`analogue.theory.friction_law`: the grid error cancels in the difference, and with
    the tanh each value agrees with :func:`analogue.theory.exact.stationary_moments` to 1e-9).
    ``var w`` (windows ``taus``): the exact value at the circuit's epsilon (``stationary_eff``,
    keyed by label) times the relative change of D_x (exact for windows long against the
    correlation time; an estimate for shorter ones).  Empty (no such term) for the ideal diode,
    the B-sources, family members and Delta = 0; transition observables have none (the DC law
    changes the transient through the same drift, not estimated here).

    Measured at the default mapping (tau_m = 2, Delta = 0.5, a = 0.3, gamma = 15): mean v
    -3.6e-7 (1N4148) and +3.4e-6 (BAT54), far below any standard error; bridges whose width is
    mostly their series resistance depart by percents (tests/integration/
    test_real_diode_element.py)."""
    if not _real_bridge(mapping):
        return {}
    model, eps = mapping.model_effective, mapping.epsilon
    real = stationary_law_with_friction(model, mapping.friction_law, eps)
    tanh = stationary_law_with_friction(model, lambda v: np.tanh(v / eps), eps)
    ratio = real.moments.diffusion / tanh.moments.diffusion
    taus = [float(t) for t in taus]
    var_w = {t: stationary_eff[stationary_label("var w", t)] for t in taus}

    def values(law, scale):
        return stationary_theory(model, law.moments, threshold=threshold,
                                 work_variance={t: scale * var_w[t] for t in taus},
                                 law=(law.v, law.density, 0.0),
                                 observables=stationary_observables(taus))
    a, b = values(real, ratio), values(tanh, 1.0)
    return {k: a[k] - b[k] for k in a}


def _real_bridge(mapping: CircuitMapping) -> bool:
    """Whether the circuit's friction element is a vendor bridge on the paper's model."""
    part = mapping.part
    return (part is not None and not part.ideal and mapping.model_effective.is_paper
            and mapping.coulomb_element == "diode-bridge")


def real_diode_transition_element(mapping: CircuitMapping, v0: float, times) -> dict:
    """The element term of the transition observables from ``v0`` (mean v, var v, P(v<0) at
    each of ``times``): exact on the bridge's DC law minus exact on ``tanh(v/epsilon)``, both
    from the same Scharfetter-Gummel grid
    (:func:`analogue.theory.friction_law.transition_moments_with_friction`; the shared grid
    error cancels).  ``{label: difference}``; empty where :func:`real_diode_element` is.
    Measured on the stick experiment's default mapping (v0 = +-2, t = 0.5..8): at most 4.8e-7
    (1N4148) and 7.8e-6 (BAT54); 0.5 s per v0.  A start deep in the tail (v0 = -3 at tau_m =
    2, Delta = 0.5, a = 0.3, gamma = 15) takes the contour route: 0.04 s of CPU for both laws
    to t = 8 (expm_multiply, before: 12 s, 60-125 s wall on a loaded machine;
    benchmarks/bench_friction_law.py)."""
    if not _real_bridge(mapping):
        return {}
    model, eps = mapping.model_effective, mapping.epsilon
    real = transition_moments_with_friction(model, mapping.friction_law, eps, v0, times)
    tanh = transition_moments_with_friction(model, lambda v: np.tanh(v / eps), eps, v0, times)
    out = {}
    for t in times:
        a, b = real[float(t)], tanh[float(t)]
        for name, i in (("mean v", 0), ("var v", 1), ("P(v<0)", 2)):
            out[transition_label(name, float(t), float(v0))] = a[i] - b[i]
    return out
