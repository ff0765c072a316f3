"""Parameter sweeps: what an experiment measures, as curves over a parameter (issue 23 item 4).

:func:`sweep` runs one experiment (a shipped name or a TOML path) at every point of a grid of
model parameters and returns an :class:`xarray.Dataset` with one dimension per varied
parameter.  At each point:

- **circuit**: a stationary run (the experiment's ``[report]`` stationary settings: replicas,
  length, burn-in, the finer stationary noise hold ``stationary_hold_divisor``; ``quick``
  scales them as ``analogue report --quick`` does) and a first-passage run from the fixed
  start ``v0``, the first nonzero ``experiment.v0`` (the experiment's replicas and
  ``t_end``, on the same finer hold: one tolerance calibration serves both runs, and the
  first passage's held-noise bias is the smaller one), both through
  :func:`analogue.simulate`, so every deck goes through the run store (a repeated or
  interrupted sweep resumes from it; tolerances and deck sizes are chosen per point by
  :mod:`analogue.circuit.tolerances` / :mod:`analogue.circuit.deck_size`) and runs locally or
  on Dask (``scheduler=``, ``executor=``);
- **theory**: the exact finite-noise values of the ideal (sgn, white-noise) model
  (:func:`analogue.theory.exact.stationary_moments`, :func:`analogue.theory.stationary.
  stick_fraction_theory`, :func:`analogue.theory.first_passage.first_passage_mean`).

Observables (:data:`OBSERVABLES`), each as ``<obs>`` (circuit), ``<obs>_stderr``,
``<obs>_theory``, ``<obs>_budget`` (sum of the absolute systematic terms) and
``<obs>_budget_terms`` (dimension ``budget_term``: smoothing, bandwidth, integration,
sampling), ``<obs>_z`` = (circuit - theory)/stderr and ``<obs>_within_budget`` (1 where
|circuit - theory| <= 3 stderr + budget, the report's criterion, :func:`analogue.study.
metrics.compare`):

==================== ===================================================================
``mean_v``           stationary <v> (drift, mean sliding velocity)
``var_v``            stationary Var v
``p_positive``       stationary P(v > 0)
``stick_fraction``   stationary P(|v| < threshold), threshold = ``[report] stick_threshold``
                     x sqrt(tau_m/gamma) at that point (family members: :func:`analogue.
                     study.catalogue.member_stick_window`)
``D_x``              position diffusion coefficient, Var x(t) ~ 2 D_x t (Green-Kubo)
``mean_work_rate``   F <v> with F = m a (the work rate of eq. (3) in reduced units: the
                     experiment's mass times the point's a, times <v>)
``first_passage_mean`` mean time from v0 = the first nonzero experiment.v0 to the first
                     v = 0 (NaN in the circuit where a replica has not reached 0 by t_end:
                     censored, counted in ``first_passage_censored``; NaN everywhere when
                     every experiment.v0 is 0, as in the work experiment)
==================== ===================================================================

Theory curves: ``<obs>_theory_fine_<name>`` on the coordinate ``<name>_fine`` (61 values
over the range of each varied parameter, at every value of the others; every observable but
the first passage), for the figures' lines (:func:`theory_curves`).

Standard errors.  Stationary observables: the delete-a-group jackknife over replicas (which
are independent, so the errors hold however correlated the samples along one path are), never
below the exact spread of the replicas' time averages under the null (the report's rule:
:func:`analogue.study.catalogue.stationary_exact_se`, :func:`~analogue.study.catalogue.
stationary_null_se`).  D_x: from the increments of x over windows of L and 2 L inside each
path (L = 4 tau_m, at most an eighth of the record: :func:`analogue.estimators.transport.
window_diffusion`), its jackknife over replicas (3-4x smaller than the cross-replica
estimate's, which reads R numbers only), rescaled to the theory's value where the estimate
is below it (a variance's error scales with it: the rule of ``stationary_null_se`` for
var v).  First passage: the spread of the per-replica times / sqrt(n).

Budget (absolute, circuit minus ideal model; the report's terms, :mod:`analogue.study.
budget`): ``smoothing`` = exact(circuit's epsilon) - exact(sgn); ``bandwidth`` = |d| + 2 SE(d)
of a held-noise minus white-noise Monte Carlo pair on common Wiener increments
(:func:`analogue.study.budget.held_noise_pair`, :data:`MC_REPLICAS` replicas); ``integration``
= the tolerance chooser's predicted worst ratio of integration to statistical error times the
stderr (``Ensemble.meta["tolerances"]``; predicted from its calibration, not re-measured on
the sweep's paths as the report's check does); ``sampling`` = the first passage's bound
[0, beta sqrt(2 dt/gamma) T'(0+) + dt] of a path observed every ``sample_dt``
(:func:`analogue.estimators.first_passage.sampling_bias_bound`; 0 for the time averages).

Seeds: each point's runs get seeds derived from the experiment's seed, the stream
(:data:`analogue.study.seeds.STREAMS`: ``sweep_stationary``, ``sweep_first_passage``,
``sweep_band``) and the point's model (all its parameters, not the point's index:
:func:`point_seed`), so the same model in a wider, finer or other sweep is the same stored
run.

Points at once (issue 22: more cores, less waiting, never more processes than cores): the
points run on a thread each (:func:`point_threads`), every deck of every point on one
executor of ``workers`` processes (or the caller's executor, or the Dask cluster), so the
sweep never runs more ngspice processes than the runner allows; the numbers are those of the
points one after another, bit for bit (the seeds are functions of the point's model).
Measured (``benchmarks/bench_sweep.py --chapter``: the report's two 4-point sweeps of the
quick stick experiment, empty store, workers = 2, this shared 2-core machine at load
3.4-4.8): 140 s one point after another, 92 s at once (0.66), the same CPU (122 and 118 s,
ngspice's 106 and 102), both datasets identical.

Supported experiments: the paper's model and the one-dimensional family members with
Gaussian noise only (cubic, Stribeck): the exact stationary law and the first-passage theory
are those of a 1-D gradient model.  Spring and shot-noise experiments are refused.

Measured (quick stick experiment, 2 cores at load ~9): a = 0 .. 0.6 in 7 points, 49 of 49
comparisons within budget, largest |z| 2.68 (first_passage_mean); gamma = 2 .. 50 in 5
geometric points, 35 of 35, largest |z| 3.81 (stick_fraction at gamma = 50, where its
budget is 4.2 SE: the held noise); the local exponent of D_x falls from 2.5 to 1.6 over
that range (theory), the circuit's chords 2.0, 1.8, 2.3, 1.9 +- 0.25-0.3.  Cost: 34 s a
point with an empty store (15 CPU s, 12 of them ngspice's), 5 s from the store
(benchmarks/bench_sweep.py).
"""
from __future__ import annotations

import concurrent.futures as cf
import contextvars
import datetime as _dt
import hashlib
import json
import logging
import math
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__, checks
from .experiments import Experiment, load_experiment
from ..circuit.mapping import CircuitMapping, check_mapping_values, map_model
from ..circuit import ngspice as _ng
from ..circuit.runner import Runner, is_client
from ..circuit.simulate import POLL_S, simulate
from ..cores import usable_cpus
from ..estimators.first_passage import first_passage, sampling_bias_bound
from ..estimators.resampling import jackknife, jackknife_difference
from ..estimators.transport import window_diffusion
from ..files import check_path
from ..model import Model
from ..netcdf_layout import write_dataset
from ..theory.exact import sample_stationary, stationary_moments
from ..theory.first_passage import first_passage_mean
from ..theory.stationary import stick_fraction_theory
# the report's rules: a measured bias enters the budget as |d| + SE_MULTIPLIER SE(d); within
# budget if |d| <= Z_LIMIT SE + budget
from .budget import SE_MULTIPLIER, held_noise_pair
from .metrics import Z_LIMIT
from .catalogue import (StationaryValues, kind_of, member_stick_window, record_span,
                        stationary_exact_se, stationary_null_se, STATIONARY)
from .seeds import SEED_MAX, STREAMS
from .settings import ReportSettings, RunOptions, stationary_noise_dt

__all__ = ["OBSERVABLES", "BUDGET_TERMS", "Axis", "SweepPlan", "plan_sweep", "parse_vary",
           "parse_vary_text", "point_seed", "point_theory", "sweep", "sweep_parameters",
           "MAX_POINTS", "MAX_POINTS_PER_AXIS", "MC_REPLICAS", "Z_LIMIT", "theory_curves",
           "FINE_POINTS", "FINE_OBSERVABLES", "write_sweep"]

log = logging.getLogger("analogue.sweep")

OBSERVABLES = ("mean_v", "var_v", "p_positive", "stick_fraction", "D_x", "mean_work_rate",
               "first_passage_mean")
BUDGET_TERMS = ("smoothing", "bandwidth", "integration", "sampling")
# the catalogue's stationary kinds behind the sweep's names
_KINDS = {"mean_v": "mean v", "var_v": "var v", "p_positive": "P(v>0)",
          "stick_fraction": "stick fraction", "D_x": "diffusion D_x"}
_LONG_NAMES = {
    "mean_v": "stationary mean velocity <v>",
    "var_v": "stationary velocity variance",
    "p_positive": "stationary P(v > 0)",
    "stick_fraction": "stationary P(|v| < threshold)",
    "D_x": "position diffusion coefficient D_x (Var x ~ 2 D_x t)",
    "mean_work_rate": "mean work rate F <v>, F = m a",
    "first_passage_mean": "mean first-passage time from v0 to v = 0",
}
_UNITS = {"mean_v": "model velocity", "var_v": "model velocity^2", "p_positive": "1",
          "stick_fraction": "1", "D_x": "model velocity^2 x model time",
          "mean_work_rate": "mass x model velocity^2 / model time",
          "first_passage_mean": "model time"}
# Held/white Monte Carlo pair per point (the report's stationary pair has 256); at quick size
# 64: the whole budget of mean_v came to 0.06-0.6 of its SE on the quick stick sweeps (a, and
# gamma = 2 .. 50), of D_x 0.07-0.26.
MC_REPLICAS = 256
MC_QUICK_REPLICAS = 64
# Grid bounds: a sweep is a curve or a small map, not a campaign; each point is two circuit
# runs plus their calibrations (a 7-point quick sweep of the stick experiment: see
# benchmarks/bench_sweep.py).
MAX_POINTS_PER_AXIS = 64
MAX_POINTS = 256
# the seed streams of a point (analogue.study.seeds.STREAMS)
_STREAMS = ("sweep_stationary", "sweep_first_passage", "sweep_band")
# D_x window: L = this many tau_m (at most an eighth of the record): C(t) has decayed by then
DIFFUSION_LAG_TAUS = 4.0
# Delete-a-group jackknife groups over replicas (the report's).
JACKKNIFE_GROUPS = 32


# ------------------------------------------------------------------------------- the grid
def sweep_parameters(model: Model) -> dict[str, tuple[float, float, str]]:
    """The parameters a sweep of ``model`` may vary: ``{name: (low, high, rule)}`` with
    ``rule`` one of ">", ">=", "any" (the bound on ``low``; ``high`` is inf).  The paper's
    parameters always; ``cubic`` always (a cubic member is still 1-D and gradient); the
    Stribeck pair as ``delta_s`` and ``v_s`` where the experiment has a Stribeck law.  The
    circuit's smoothing ``epsilon`` is the circuit's choice, not a model parameter here."""
    out: dict[str, tuple[float, float, str]] = {
        "tau_m": (0.0, math.inf, ">"), "delta": (0.0, math.inf, ">="),
        "a": (-math.inf, math.inf, "any"), "gamma": (0.0, math.inf, ">"),
        "mass": (0.0, math.inf, ">"), "cubic": (0.0, math.inf, ">=")}
    return {**out, **model.friction.sweep_parameters()}   # Stribeck: delta_s, v_s


def _range_text(low: float, rule: str) -> str:
    return {"any": "any finite value", ">": f"> {low:g}", ">=": f">= {low:g}"}[rule]


@dataclass(frozen=True)
class Axis:
    """One varied parameter: its name, its values (strictly monotone) and how it was given."""

    name: str
    values: tuple[float, ...]
    given: str


def _linspace(name: str, start, stop, n, spacing: str = "linear") -> tuple[float, ...]:
    start = checks.finite(f"vary {name} START", start)
    stop = checks.finite(f"vary {name} STOP", stop)
    n = checks.integer(f"vary {name} N", n, minimum=1, maximum=MAX_POINTS_PER_AXIS)
    if spacing not in ("linear", "log"):
        raise ValueError(f"vary {name}: spacing must be 'linear' or 'log', got {spacing!r}")
    if n == 1:
        if start != stop:
            raise ValueError(f"vary {name}: N = 1 needs START == STOP (one value), got "
                             f"{start:g}:{stop:g}:1")
        return (start,)
    if start == stop:
        raise ValueError(f"vary {name}: START == STOP = {start:g} with N = {n} repeats one "
                         f"value; use N = 1 or different ends")
    if spacing == "log":
        if start <= 0 or stop <= 0:
            raise ValueError(f"vary {name}: log spacing needs START and STOP > 0, got "
                             f"{start:g}:{stop:g}")
        return tuple(float(x) for x in np.geomspace(start, stop, n))
    return tuple(float(x) for x in np.linspace(start, stop, n))


def parse_vary(vary: Mapping[str, Any], model: Model) -> tuple[Axis, ...]:
    """Validate ``vary`` (``{name: (start, stop, n)}``, ``(start, stop, n, "log")`` or an
    array of values) against ``model``'s sweepable parameters (:func:`sweep_parameters`):
    names known, values finite, strictly monotone, distinct and in the parameter's range,
    ``1 <= n <= MAX_POINTS_PER_AXIS`` and at most ``MAX_POINTS`` grid points.  Raises
    ValueError (TypeError for a wrong type) naming the parameter and what is allowed."""
    if not isinstance(vary, Mapping):
        raise TypeError(f"vary must be a mapping {{name: (start, stop, n) or values}}, got "
                        f"{type(vary).__name__}")
    if not vary:
        raise ValueError("vary must name at least one parameter (e.g. {'a': (0.0, 0.6, 7)})")
    allowed = sweep_parameters(model)
    axes = []
    for name, spec in vary.items():
        if not isinstance(name, str) or name not in allowed:
            raise ValueError(f"vary: unknown parameter {name!r} for this experiment (allowed: "
                             f"{', '.join(allowed)})")
        if isinstance(spec, (str, bytes)):
            raise TypeError(f"vary {name}: expected (start, stop, n) or an array of values, "
                            f"got {spec!r}")
        if isinstance(spec, tuple) and len(spec) in (3, 4) and (
                len(spec) == 3 or isinstance(spec[3], str)):
            values = _linspace(name, *spec)
            given = ":".join(f"{x:g}" if not isinstance(x, str) else x for x in spec)
        else:
            try:
                arr = np.asarray(spec, dtype=float)
            except (TypeError, ValueError):
                raise TypeError(f"vary {name}: expected (start, stop, n) or an array of values, "
                                f"got {spec!r}") from None
            if arr.ndim != 1 or arr.size < 1:
                raise ValueError(f"vary {name}: the values must be a non-empty 1-D array, got "
                                 f"shape {arr.shape}")
            if arr.size > MAX_POINTS_PER_AXIS:
                raise ValueError(f"vary {name}: {arr.size} values, at most "
                                 f"{MAX_POINTS_PER_AXIS} per parameter")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"vary {name}: values must be finite, got {arr.tolist()}")
            steps = np.diff(arr)
            if arr.size > 1 and not (np.all(steps > 0) or np.all(steps < 0)):
                raise ValueError(f"vary {name}: values must be distinct and strictly monotone, "
                                 f"got {arr.tolist()}")
            values = tuple(float(x) for x in arr)
            given = "values"
        low, _, rule = allowed[name]
        for x in values:
            if (rule == ">" and not x > low) or (rule == ">=" and not x >= low):
                raise ValueError(f"vary {name}: value {x:g} is outside the allowed range of "
                                 f"{name} ({_range_text(low, rule)})")
        axes.append(Axis(name, values, given))
    total = math.prod(len(a.values) for a in axes)
    if total > MAX_POINTS:
        raise ValueError(f"vary: {total} grid points ({' x '.join(str(len(a.values)) for a in axes)}"
                         f"), at most {MAX_POINTS}")
    return tuple(axes)


_VARY_TEXT = r"NAME=START:STOP:N or NAME=START:STOP:N:log"


def parse_vary_text(items: Sequence[str]) -> dict[str, tuple]:
    """``["a=0:0.6:7", "gamma=1:100:5:log"]`` -> ``{"a": (0.0, 0.6, 7), "gamma": (1.0,
    100.0, 5, "log")}`` (the CLI's ``--vary``); a repeated name or a malformed item is a
    ValueError naming it.  Names and ranges are checked by :func:`parse_vary`."""
    out: dict[str, tuple] = {}
    for item in items:
        name, sep, rest = str(item).partition("=")
        name = name.strip()
        parts = rest.split(":")
        if not sep or not name or len(parts) not in (3, 4):
            raise ValueError(f"--vary {item!r}: expected {_VARY_TEXT}")
        try:
            start, stop = float(parts[0]), float(parts[1])
            n = int(parts[2])
        except ValueError:
            raise ValueError(f"--vary {item!r}: START and STOP must be numbers and N an "
                             f"integer ({_VARY_TEXT})") from None
        if name in out:
            raise ValueError(f"--vary {name} given twice")
        if len(parts) == 4:
            if parts[3] != "log":
                raise ValueError(f"--vary {item!r}: the fourth field can only be 'log' "
                                 f"({_VARY_TEXT})")
            out[name] = (start, stop, n, "log")
        else:
            out[name] = (start, stop, n)
    return out


def _point_model(model: Model, point: Mapping[str, float]) -> Model:
    changes: dict[str, Any] = {k: v for k, v in point.items() if k not in ("delta_s", "v_s")}
    if "delta_s" in point or "v_s" in point:
        assert model.stribeck is not None  # sweep_parameters offers them only then
        ds, vs = model.stribeck
        changes["stribeck"] = (point.get("delta_s", ds), point.get("v_s", vs))
    return model.replace(**changes)


def point_seed(seed: int, stream: str, model: Model) -> int:
    """The seed of one run of a sweep point: ``SeedSequence(seed, spawn_key=(STREAMS[stream],
    w0, .., w3))`` with ``w`` four 32-bit words of the SHA-256 of the point's model (all its
    parameters as sorted JSON), reduced to ``1 .. 2**31 - 1`` as every seed of
    :mod:`analogue.study.seeds`.  A function of the model, not of the point's place in the
    grid: the same model in a wider, finer or other sweep of the experiment is the same
    stored run (the stick experiment's a = 0.2 and gamma = 10 points are one run)."""
    seed = checks.integer("seed", seed, minimum=0)
    checks.instance("model", model, Model, description="an analogue.Model")
    if stream not in _STREAMS:
        raise ValueError(f"sweep seed stream must be one of {', '.join(_STREAMS)}; got "
                         f"{stream!r}")
    text = json.dumps(model.as_dict(), sort_keys=True)
    digest = hashlib.sha256(text.encode()).digest()
    words = tuple(int.from_bytes(digest[4 * i:4 * i + 4], "little") for i in range(4))
    word = np.random.SeedSequence(seed, spawn_key=(STREAMS[stream], *words)
                                  ).generate_state(1, np.uint32)[0]
    return int(word) % SEED_MAX + 1


@dataclass(frozen=True)
class SweepPlan:
    """A validated sweep: the experiment, the axes, the size settings and, per grid point
    (C order over the axes), its parameters, model and circuit mapping.  Everything here is
    checked before any circuit runs."""

    exp: Experiment
    axes: tuple[Axis, ...]
    quick: bool
    settings: ReportSettings            # the stationary settings at this size
    fp_replicas: int                    # first-passage replicas
    fp_v0: float | None                 # None: every experiment.v0 is 0 (no first passage)
    points: tuple[dict, ...]
    models: tuple[Model, ...]
    mappings: tuple[CircuitMapping, ...]

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a.values) for a in self.axes)


def plan_sweep(experiment: Experiment | str | Path, vary: Mapping[str, Any], *,
               quick: bool = False) -> SweepPlan:
    """Load and validate a sweep (no circuit work): the experiment (a name or a TOML path),
    its class (1-D, Gaussian noise only), the grid (:func:`parse_vary`) and, at every point,
    the model (the model's own checks: a value it refuses is a ValueError naming the point)
    and the circuit (its component values, :func:`~analogue.circuit.mapping.
    check_mapping_values`)."""
    exp = experiment if isinstance(experiment, Experiment) else load_experiment(experiment)
    quick = checks.flag("quick", quick)
    m = exp.model
    if m.spring > 0 or m.shot is not None or not math.isfinite(m.gamma):
        raise ValueError(f"experiment {exp.name!r}: a sweep needs a one-dimensional model "
                         f"with Gaussian noise only (the paper's model, cubic, Stribeck): its "
                         f"exact stationary law and first-passage theory are those of a 1-D "
                         f"gradient model; this one has "
                         f"{'a spring' if m.spring > 0 else 'shot noise'}")
    axes = parse_vary(vary, m)
    settings = exp.report.for_options(RunOptions(quick=quick))
    fp_replicas = RunOptions(quick=quick).scaled(exp.replicas)
    points, models, mappings = [], [], []
    for idx in np.ndindex(*[len(a.values) for a in axes]):
        point = {a.name: a.values[i] for a, i in zip(axes, idx)}
        where = ", ".join(f"{k}={v:g}" for k, v in point.items())
        try:
            model = _point_model(m, point)
            mapping = map_model(model, exp.spec)
            check_mapping_values(mapping, "the sweep's")
            map_model(model, exp.spec.replace(noise_dt=stationary_noise_dt(mapping.noise_dt,
                                                                           settings)))
        except (ValueError, OverflowError) as exc:
            raise ValueError(f"vary: the point {where} of experiment {exp.name!r} is refused: "
                             f"{exc}") from None
        points.append(point)
        models.append(model)
        mappings.append(mapping)
    return SweepPlan(exp=exp, axes=axes, quick=quick, settings=settings,
                     fp_replicas=fp_replicas,
                     fp_v0=next((float(v) for v in exp.v0 if v != 0), None), points=tuple(points),
                     models=tuple(models), mappings=tuple(mappings))


# ------------------------------------------------------------------------------- theory
def _threshold(model: Model, settings: ReportSettings, epsilon: float) -> float:
    """The stick window at this point (the report's: paper model ``stick_threshold
    sqrt(tau_m/gamma)``, members :func:`member_stick_window`)."""
    if model.is_paper:
        return settings.stick_threshold * model.velocity_scale
    return member_stick_window(model, stick_threshold=settings.stick_threshold,
                               epsilon=epsilon)


def _window_probability(model: Model, threshold: float) -> float:
    if model.is_paper:
        return float(stick_fraction_theory(model, threshold))
    from scipy import integrate
    val, _ = integrate.quad(lambda v: float(model.stationary_pdf(v)), -threshold, threshold,
                            points=[0.0], limit=400, epsabs=0.0, epsrel=1e-11)
    return float(min(1.0, val))


def point_theory(model: Model, *, threshold: float, v0: float | None) -> dict[str, float]:
    """Exact values of every sweep observable (:data:`OBSERVABLES`) for ``model`` (1-D,
    Gaussian noise): the stationary moments and D_x (:func:`analogue.theory.exact.
    stationary_moments`), P(|v| < threshold), F <v> (F = m a) and the mean first-passage
    time from ``v0`` (quadrature, :func:`analogue.theory.first_passage.first_passage_mean`;
    NaN for ``v0 = None``)."""
    mom = stationary_moments(model)
    return {"mean_v": float(mom.mean), "var_v": float(mom.variance),
            "p_positive": float(mom.p_positive),
            "stick_fraction": _window_probability(model, threshold),
            "D_x": float(mom.diffusion), "mean_work_rate": float(model.force * mom.mean),
            "first_passage_mean": (math.nan if v0 is None
                                   else float(first_passage_mean(model, v0)))}


# points of the theory curves along each axis (the figures' lines): every observable but the
# first passage (stationary moments: ~1 ms a point; the first-passage quadrature ~0.15 s)
FINE_POINTS = 61
FINE_OBSERVABLES = tuple(o for o in OBSERVABLES if o != "first_passage_mean")


def _fine_values(axis: Axis, n: int = FINE_POINTS) -> np.ndarray:
    lo, hi = min(axis.values), max(axis.values)
    if axis.given.endswith("log") and lo > 0:
        return np.geomspace(lo, hi, n)
    return np.linspace(lo, hi, n)


def theory_curves(plan: SweepPlan) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The exact theory on a fine grid along each axis with >= 2 values (:data:`FINE_POINTS`
    values over its range, geometric where the axis was given with log spacing), at every
    value of the other axes: ``{"<obs>_theory_fine_<axis>": (fine values, array of shape
    (FINE_POINTS, *other axes))}`` for :data:`FINE_OBSERVABLES` (NaN where the model refuses
    a value).  The stick window follows the point's model, as at the grid points."""
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    settings = plan.settings
    for axis in plan.axes:
        if len(axis.values) < 2:
            continue
        fine = _fine_values(axis)
        others = [a for a in plan.axes if a is not axis]
        shape = (fine.size, *[len(a.values) for a in others])
        arrays = {o: np.full(shape, np.nan) for o in FINE_OBSERVABLES}
        for idx in np.ndindex(*shape):
            point = {axis.name: float(fine[idx[0]])}
            point.update({a.name: a.values[i] for a, i in zip(others, idx[1:])})
            try:
                model = _point_model(plan.exp.model, point)
                eps = map_model(model, plan.exp.spec).epsilon
                thr = _threshold(model, settings, eps)
                mom = stationary_moments(model)
            except (ValueError, OverflowError, ArithmeticError):
                continue
            values = {"mean_v": mom.mean, "var_v": mom.variance, "p_positive": mom.p_positive,
                      "stick_fraction": _window_probability(model, thr), "D_x": mom.diffusion,
                      "mean_work_rate": model.force * mom.mean}
            for o in FINE_OBSERVABLES:
                arrays[o][idx] = float(values[o])
        for o in FINE_OBSERVABLES:
            out[f"{o}_theory_fine_{axis.name}"] = (fine, arrays[o])
    return out


# ------------------------------------------------------------------------------ circuit
@dataclass(frozen=True)
class _BandValues:
    """The stationary values of the held/white pair: the catalogue's, with D_x read as the
    sweep reads it (:func:`~analogue.estimators.transport.window_diffusion`)."""

    values: StationaryValues
    burn_in: float
    lag: float

    def __call__(self, ens) -> dict[str, float]:
        out = dict(self.values(ens))
        out[_KINDS["D_x"]] = window_diffusion(ens, burn_in=self.burn_in, lag=self.lag,
                                              groups=2).diffusion
        return out


def _fp_values(ens) -> dict[str, float]:
    est = first_passage(ens)
    return {"first_passage_mean": est.mean}


def _integration(meta: Mapping[str, Any], se: float) -> float:
    """The tolerance chooser's predicted integration error: worst ratio x SE (module
    docstring); its acceptance bound when it recorded no ratio; 0 for tolerances the user
    set (nothing predicted)."""
    tol = meta.get("tolerances") or {}
    ratio = tol.get("worst_ratio")
    if ratio is None:
        ratio = tol.get("fraction", 0.0) if tol.get("source") == "measured" else 0.0
    return float(ratio) * se if math.isfinite(se) else math.nan


def _whole_holds(t_end: float, hold: float, sample_dt: float) -> float:
    """``t_end`` rounded down to a whole number of the Monte Carlo pair's sampling steps,
    ``hold * round(sample_dt / hold)`` (:func:`~analogue.study.budget.held_noise_pair` steps
    whole holds and samples every few: a hold chosen from the model, e.g. 0.0032 at gamma =
    50, need not divide the run's length)."""
    step = hold * max(1, round(sample_dt / hold))
    return step * math.floor(t_end / step + 1e-9)


def _runner(runner: Runner | None, given: Mapping[str, Any]) -> Runner:
    """The sweep's Runner: ``runner``, or one made of the run keywords ``given`` (those not
    None); both at once is a TypeError, as for :func:`analogue.simulate`."""
    passed = {k: v for k, v in given.items() if v is not None}
    if runner is None:
        return Runner(**passed)
    if not isinstance(runner, Runner):
        raise TypeError(f"runner must be an analogue.Runner, got {type(runner).__name__}")
    if passed:
        raise TypeError(f"sweep: pass either runner= or the run keywords "
                        f"({', '.join(sorted(passed))}), not both: put them in the Runner, "
                        f"e.g. runner.replace({', '.join(f'{k}=...' for k in sorted(passed))})")
    return runner


def _point(plan: SweepPlan, i: int, runner: Runner,
           stop: threading.Event | None = None) -> dict[str, Any]:
    """Circuit, theory and budget of grid point ``i``: ``{obs: (value, se, theory, terms)}``
    plus ``"_info"`` (seeds, censoring, provenance bits).  ``stop`` (set when another point
    failed or the sweep was interrupted): checked before each stage, which then raises
    CancelledError instead of starting."""
    exp, settings = plan.exp, plan.settings
    model, mapping, point = plan.models[i], plan.mappings[i], plan.points[i]
    model_eff = mapping.model_effective
    where = ", ".join(f"{k}={v:g}" for k, v in point.items())
    seeds = {s: point_seed(exp.seed, s, model) for s in _STREAMS}
    thr = _threshold(model, settings, mapping.epsilon)
    stat_hold = stationary_noise_dt(mapping.noise_dt, settings)
    stat_spec = exp.spec.replace(noise_dt=stat_hold)

    clock = time.perf_counter()
    timing: dict[str, float] = {}

    def lap(name: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        timing[name] = timing.get(name, 0.0) + now - clock
        clock = now
        if stop is not None and stop.is_set():
            raise cf.CancelledError(f"sweep point {where}: stopped (another point failed or "
                                    f"the sweep was interrupted)")

    lap("circuit_s")   # (nothing yet: only the stop check)
    log.info("%s: %s: stationary run", exp.name, where)
    t_run = time.perf_counter()
    stat = simulate(model, v0="stationary", t_end=settings.stationary_t_end,
                    replicas=settings.stationary_replicas, seed=seeds["sweep_stationary"],
                    sample_dt=exp.sample_dt, circuit=stat_spec,
                    runner=runner.replace(label=f"sweep {exp.name} {where} stationary"[:100]))
    runs_s = [(stat, time.perf_counter() - t_run)]
    lap("circuit_s")
    fp = None
    if plan.fp_v0 is not None:
        log.info("%s: %s: first-passage run from v0=%g", exp.name, where, plan.fp_v0)
        t_run = time.perf_counter()
        fp = simulate(model, v0=plan.fp_v0, t_end=exp.t_end, replicas=plan.fp_replicas,
                      seed=seeds["sweep_first_passage"], sample_dt=exp.sample_dt,
                      circuit=stat_spec, runner=runner.replace(
                          label=f"sweep {exp.name} {where} first passage"[:100]))
        runs_s.append((fp, time.perf_counter() - t_run))
    lap("circuit_s")

    log.info("%s: %s: theory and held-noise Monte Carlo pair", exp.name, where)
    th = point_theory(model, threshold=thr, v0=plan.fp_v0)
    th_eff = point_theory(model_eff, threshold=thr, v0=plan.fp_v0)
    lap("theory_s")

    # circuit estimates, jackknife over replicas; the SE never below the exact spread of the
    # time averages under the null (the report's rule)
    fn = StationaryValues(burn_in=settings.stationary_burn_in, threshold=thr,
                          force=model.force, taus=())
    circ = jackknife(fn, stat, groups=JACKKNIFE_GROUPS)
    span = record_span(stat, settings.stationary_burn_in)
    # D_x from window increments inside each path (estimators.transport.window_diffusion): the
    # catalogue's cross-replica estimate has the error of a variance of R numbers and a
    # jackknife that scatters with it (measured on 6 x 32 Monte Carlo replicas: SE 2.3-4.6x
    # larger, z rms 1.4; a quick circuit point at a = 0 gave z = -3.6 on it)
    lag = min(DIFFUSION_LAG_TAUS * model.tau_m, span / 8.0)
    wd = window_diffusion(stat, burn_in=settings.stationary_burn_in, lag=lag)
    circ[_KINDS["D_x"]] = (wd.diffusion, wd.stderr)
    fn_band = _BandValues(fn, settings.stationary_burn_in, lag)
    stderr = {}
    for name, label in _KINDS.items():
        val, se = circ[label]
        entry = kind_of(STATIONARY, label)
        stderr[name] = max(se, stationary_null_se(entry, val, se, th_eff[name]),
                           stationary_exact_se(model_eff, label, span, stat.replicas,
                                               threshold=thr))
    # D_x is a variance (of increments): its jackknife scales with the estimate, so a low
    # estimate reports a small error; under the null the error is that at the theory's value
    # (the rule stationary_null_se applies to var v).  Measured on the quick stick point
    # a = 0.2 over 6 circuit seeds: z +1.5, -0.7, -1.6, 0.0, -3.2, -1.3 on the jackknife
    # alone (the sweep's own seed: -3.7), the low estimates with the smallest errors (0.0005
    # against 0.0011).  Not the circuit's noise: the SDE driven by 12 of ngspice's recorded
    # trrandom sequences gave z mean -0.24, sd 0.90, numpy's white noise over 20 seeds -0.25,
    # 0.92 (min -2.3), numpy's held at the same hold -0.61, 1.47 (min -3.2): at 32 x 48 tau_m
    # the estimate's law has a long low tail
    val = circ[_KINDS["D_x"]][0]
    if val > 0 and th_eff["D_x"] > val:
        stderr["D_x"] = max(stderr["D_x"], stderr["D_x"] * th_eff["D_x"] / val)
    est = first_passage(fp) if fp is not None else None
    lap("estimates_s")

    # the held noise: white against held on common increments, on the stationary runs' hold
    # (both circuit runs use it), seeds from the point's band stream
    n_mc = MC_QUICK_REPLICAS if plan.quick else MC_REPLICAS
    band_seed = seeds["sweep_band"]
    fp_seed = int(np.random.SeedSequence(band_seed, spawn_key=(1,)).generate_state(
        1, np.uint32)[0]) % SEED_MAX + 1
    held, white = held_noise_pair(
        model_eff, v0=sample_stationary(model_eff, n_mc,
                                        np.random.SeedSequence(band_seed, spawn_key=(0,))),
        t_end=_whole_holds(settings.stationary_t_end, stat_hold, exp.sample_dt), replicas=n_mc,
        seed=band_seed, noise_dt=stat_hold, sample_dt=exp.sample_dt)
    band = jackknife_difference(fn_band, held, white)
    if plan.fp_v0 is not None:
        held, white = held_noise_pair(model_eff, v0=plan.fp_v0,
                                      t_end=_whole_holds(exp.t_end, stat_hold, exp.sample_dt),
                                      replicas=n_mc, seed=fp_seed, noise_dt=stat_hold,
                                      sample_dt=exp.sample_dt)
        band.update(jackknife_difference(_fp_values, held, white))
    lap("monte_carlo_s")

    out: dict[str, Any] = {}
    for name, label in _KINDS.items():
        val, se = circ[label][0], stderr[name]
        d, d_se = band[label]
        terms = {"smoothing": th_eff[name] - th[name], "bandwidth": abs(d) + SE_MULTIPLIER * d_se,
                 "integration": _integration(stat.meta, se), "sampling": 0.0}
        out[name] = (val, se, th[name], terms)
    f = model.force
    val, se, _, terms = out["mean_v"]
    out["mean_work_rate"] = (f * val, abs(f) * se, th["mean_work_rate"],
                             {k: abs(f) * v for k, v in terms.items()})
    if fp is not None and est is not None and plan.fp_v0 is not None:
        d, d_se = band["first_passage_mean"]
        out["first_passage_mean"] = (est.mean, est.mean_se, th["first_passage_mean"], {
            "smoothing": th_eff["first_passage_mean"] - th["first_passage_mean"],
            "bandwidth": abs(d) + SE_MULTIPLIER * d_se,
            "integration": _integration(fp.meta, est.mean_se),
            "sampling": sampling_bias_bound(model, plan.fp_v0, exp.sample_dt)})
    else:
        out["first_passage_mean"] = (math.nan, math.nan, math.nan,
                                     {t: math.nan for t in BUDGET_TERMS})
    out["_info"] = {"timing": timing, "seeds": seeds, "threshold": thr,
                    "censored": est.n_censored if est is not None else 0,
                    "stationary_replicas": stat.replicas,
                    "first_passage_replicas": fp.replicas if fp is not None else 0,
                    "ngspice_version": stat.meta.get("ngspice_version"),
                    "stationary_noise_dt": stat.meta.get("noise_dt"),
                    "first_passage_noise_dt": fp.meta.get("noise_dt") if fp is not None else None,
                    "epsilon": mapping.epsilon,
                    "wall_time_s": float(stat.meta.get("wall_time", 0.0))
                    + (float(fp.meta.get("wall_time", 0.0)) if fp is not None else 0.0),
                    "unlimited_s": _unlimited_s(runs_s, timing)}
    return out


def _unlimited_s(runs: list, timing: Mapping[str, float]) -> float:
    """The point's seconds with unlimited cores (the report's critical path, issue 22): per
    circuit run, its work outside the decks (tolerance and deck-size calibrations, store
    reads: the run's wall time less its decks' span) plus its longest deck run here (0 from
    the store), then the point's Python stages (theory, estimates, Monte Carlo pair).  On a
    machine whose cores the points share, a point's phase also holds its decks' waits for a
    free process; this is what it would take alone with a core per deck."""
    total = 0.0
    for ens, wall in runs:
        decks = float(ens.meta.get("wall_time") or 0.0)
        ran = [float(w) for w in ens.meta.get("ran_deck_wall_times") or () if w is not None]
        total += max(0.0, wall - decks) + max(ran, default=0.0)
    return round(total + sum(timing.get(k, 0.0) for k in ("theory_s", "estimates_s",
                                                          "monte_carlo_s")), 3)


# ------------------------------------------------------------------------- points at once
#: the sweep point a thread works for (its thread's ident), so that decks its helper threads
#: submit (a calibration's runs at once: circuit.tolerances.at_once copies the context)
#: count in the point's batches
_POINT: contextvars.ContextVar[int | None] = contextvars.ContextVar("analogue_sweep_point",
                                                                    default=None)


class _DeckView(cf.Executor):
    """The sweep's view of the deck executor its points share: submits go to ``pool`` and
    are remembered, so that a failed or interrupted sweep cancels the decks it queued (each
    run's ``run_decks`` then unwinds within its poll and kills its own ngspice group) without
    shutting down an executor the caller owns (its :meth:`shutdown` does nothing).

    It also times each point's batches of decks (the decks one thread submits until all of
    them are done: one ``run_decks`` call): the batch's span, and its longest deck's own
    ngspice wall time (``info["wall_time"]``, not its wait for a free process), for the
    point's seconds with unlimited cores (:meth:`take`)."""

    def __init__(self, pool: cf.Executor):
        self.pool = pool
        self._futures: set = set()
        self._lock = threading.Lock()
        self._open: dict[int, dict] = {}              # thread -> its batch under way
        self._done: dict[int, list] = {}              # thread -> [(span, longest deck)]

    def submit(self, fn, /, *args, **kwargs):
        fut = self.pool.submit(fn, *args, **kwargs)
        # the point's thread, also for decks its helper threads submit (one batch: decks
        # submitted at once count as their longest)
        me = _POINT.get() or threading.get_ident()
        with self._lock:
            self._futures = {f for f in self._futures if not f.done()}
            self._futures.add(fut)
            batch = self._open.get(me)
            if batch is None:
                batch = self._open[me] = {"t0": time.perf_counter(), "left": 0, "longest": 0.0}
            batch["left"] += 1
        fut.add_done_callback(lambda f, me=me, batch=batch: self._deck_done(me, batch, f))
        return fut

    def _deck_done(self, me: int, batch: dict, fut: cf.Future) -> None:
        wall = 0.0
        if not fut.cancelled() and fut.exception() is None:
            out = fut.result()
            info = out.get("info") if isinstance(out, Mapping) else None
            if isinstance(info, Mapping) and isinstance(info.get("wall_time"), (int, float)):
                wall = float(info["wall_time"])
        with self._lock:
            batch["longest"] = max(batch["longest"], wall)
            batch["left"] -= 1
            if batch["left"] == 0:
                if self._open.get(me) is batch:
                    del self._open[me]
                self._done.setdefault(me, []).append(
                    (time.perf_counter() - batch["t0"], batch["longest"]))

    def take(self, thread: int) -> list[tuple[float, float]]:
        """``[(span, longest deck)]`` of the batches ``thread`` submitted (and forget them)."""
        with self._lock:
            return self._done.pop(thread, [])

    def cancel_all(self) -> None:
        with self._lock:
            futures, self._futures = list(self._futures), set()
        for f in futures:
            f.cancel()

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        pass  # the pool is its owner's (the sweep's own, or the caller's)


def point_threads(n_points: int, runner: Runner, max_concurrent_points: int | None = None
                  ) -> int:
    """How many points of a sweep run at once: ``max_concurrent_points`` when given (1: one
    after another), else every point up to twice the deck processes plus two (locally
    ``runner.workers``, else the usable CPUs; on Dask the same count of the local CPUs).
    A point's circuit work is a chain (tolerance calibration, deck-size calibration, the
    stationary decks, the first-passage decks) with its Python work (theory, estimates, the
    held/white Monte Carlo pair) after it, so about two points per deck process keep the
    processes busy; more would only hold more points' arrays in memory at once."""
    if max_concurrent_points is not None:
        cap = checks.integer("max_concurrent_points", max_concurrent_points, minimum=1)
    else:
        workers = runner.workers if runner.workers is not None else usable_cpus()
        cap = 2 * workers + 2
    return max(1, min(n_points, cap))


def _run_points(plan: SweepPlan, runner: Runner, threads: int, phases=None) -> list[dict]:
    """Every point's :func:`_point`, ``threads`` at once (1: one after another, in order).

    Concurrently, every deck of every point goes to one deck executor: locally (no
    scheduler, no executor) a pool of ``runner.workers`` threads (default the usable CPUs),
    so the sweep never runs more ngspice processes than that however many points run; the
    caller's executor when one is given; on a Dask scheduler each run's decks go to the
    cluster as they would one point at a time.  Results do not depend on the order (each
    point's seeds are a function of its model, each deck's of its run: :func:`point_seed`),
    so they are those of the sequential sweep, bit for bit.

    The calling thread waits in polls under :func:`analogue.circuit.ngspice.interrupt_guard`
    (a no-op outside the main thread, whose caller's guard then covers it): SIGINT, SIGTERM
    or SIGHUP kill every ngspice process and raise here; the first point that fails stops
    the others (their queued decks cancelled, their running ngspice groups killed by their
    own runs as they unwind, no new stage started) and its error is raised once the point
    threads have ended (at most ~10 s are waited for a point in pure numerics).
    ``phases`` (:class:`analogue.study.schedule.Phases`): each point that completes is
    recorded as the phase ``"sweep point"`` of experiment ``"<name> <param>=<value>"`` (its
    wall and thread CPU seconds, and ``unlimited_s``: its seconds with unlimited cores, its
    batches of decks counted as their longest deck (:class:`_DeckView`), where the sweep
    holds the deck executor; else :func:`_unlimited_s`)."""
    n = len(plan.points)

    def one(i: int, run: Runner, stop: threading.Event | None = None) -> dict:
        if phases is None:
            return _point(plan, i, run, stop)
        t0, c0 = time.perf_counter(), time.thread_time()
        token = _POINT.set(threading.get_ident())
        try:
            res = _point(plan, i, run, stop)
        finally:
            _POINT.reset(token)
        dt = time.perf_counter() - t0
        unlimited = res["_info"]["unlimited_s"]
        if isinstance(run.executor, _DeckView):
            # the point's own time less its batches' spans (waits for a free process
            # included), plus each batch's longest deck: every deck on its own core
            batches = run.executor.take(threading.get_ident())
            unlimited = dt - sum(b[0] for b in batches) + sum(b[1] for b in batches)
        # as Phases records a phase (list.append: safe from any thread), with the point's
        # seconds with unlimited cores for the critical path
        phases.items.append({"phase": "sweep point", "experiment": point_label(plan, i),
                             "thread": "sweep", "start_s": round(t0 - phases.origin, 3),
                             "seconds": round(dt, 3),
                             "cpu_s": round(time.thread_time() - c0, 3),
                             "unlimited_s": round(max(0.0, min(dt, unlimited)), 3)})
        log.info("phase done: sweep point (%s): %.1f s", point_label(plan, i), dt)
        return res

    if threads <= 1:
        return [one(i, runner) for i in range(n)]
    owned: cf.ThreadPoolExecutor | None = None
    view: _DeckView | None = None
    if runner.scheduler is None and runner.executor is None:
        workers = runner.workers if runner.workers is not None else usable_cpus()
        owned = cf.ThreadPoolExecutor(max_workers=workers,
                                      thread_name_prefix="analogue-sweep-deck")
        view = _DeckView(owned)
    elif runner.executor is not None and not is_client(runner.executor):
        view = _DeckView(runner.executor)
    run = runner if view is None else runner.replace(executor=view)
    stop = threading.Event()
    pool = cf.ThreadPoolExecutor(max_workers=threads, thread_name_prefix="analogue-sweep-point")
    futures: list[cf.Future] = []
    try:
        with _ng.interrupt_guard():
            try:
                # each point with a copy of the caller's context (the run store's key
                # collectors, analogue.circuit.store_index, see every deck)
                futures = [pool.submit(contextvars.copy_context().run, one, i, run, stop)
                           for i in range(n)]
                pending = set(futures)
                while pending:   # polled: a signal the kernel gave another thread lands here
                    done, pending = cf.wait(pending, timeout=POLL_S,
                                            return_when=cf.FIRST_EXCEPTION)
                    if any(not f.cancelled() and f.exception() is not None for f in done):
                        break
                failed = [f for f in futures if f.done() and not f.cancelled()
                          and f.exception() is not None
                          and not isinstance(f.exception(), cf.CancelledError)]
                if failed:
                    failed[0].result()
                return [f.result() for f in futures]
            except BaseException as exc:
                _stop_points(futures, stop, view, owned,
                             interrupted=not isinstance(exc, Exception))
                raise
    finally:
        pool.shutdown(wait=all(f.done() for f in futures), cancel_futures=True)
        if owned is not None:
            owned.shutdown(wait=False, cancel_futures=True)


def _stop_points(futures: list[cf.Future], stop: threading.Event, view: _DeckView | None,
                 owned: cf.ThreadPoolExecutor | None, *, interrupted: bool,
                 wait_s: float = 10.0) -> None:
    """After a point failed or an interrupt: no new point or stage starts, the decks queued
    are cancelled and the point threads are waited for (``wait_s`` at most); after an
    interrupt every ngspice process of this process is killed again and again meanwhile (a
    point whose deck was killed may reach its next run before it sees ``stop``)."""
    stop.set()
    for f in futures:
        f.cancel()
    if view is not None:
        view.cancel_all()
    if owned is not None:
        owned.shutdown(wait=False, cancel_futures=True)
    deadline = time.monotonic() + wait_s
    while not all(f.done() for f in futures) and time.monotonic() < deadline:
        if interrupted:
            _ng.terminate_all()
        cf.wait(futures, timeout=0.05)
    if interrupted:
        _ng.terminate_all()


def point_label(plan: SweepPlan, i: int) -> str:
    """``"<experiment> <param>=<value>[, ...]"``: point ``i`` of ``plan`` in the report's
    phases (one per point: the critical path counts the longest, not their sum)."""
    return f"{plan.exp.name} " + ", ".join(f"{k}={v:g}" for k, v in plan.points[i].items())


# ------------------------------------------------------------------------------ dataset
def _dataset(plan: SweepPlan, results: list[dict], wall: float):
    import xarray as xr
    exp = plan.exp
    dims = tuple(a.name for a in plan.axes)
    shape = plan.shape
    coords: dict[str, Any] = {a.name: (a.name, np.asarray(a.values),
                                       {"long_name": f"model parameter {a.name}",
                                        "given": a.given}) for a in plan.axes}
    coords["budget_term"] = ("budget_term", np.asarray(BUDGET_TERMS))
    data: dict[str, Any] = {}

    def grid(fn, dtype=float):
        return np.asarray([fn(r) for r in results], dtype=dtype).reshape(shape)

    for obs in OBSERVABLES:
        meta = {"long_name": _LONG_NAMES[obs], "units": _UNITS[obs]}
        value = grid(lambda r, o=obs: r[o][0])
        se = grid(lambda r, o=obs: r[o][1])
        theory = grid(lambda r, o=obs: r[o][2])
        terms = np.asarray([[r[obs][3][t] for t in BUDGET_TERMS] for r in results],
                           dtype=float).reshape(shape + (len(BUDGET_TERMS),))
        budget = np.abs(terms).sum(axis=-1)
        diff = value - theory
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(se > 0, diff / se, np.nan)
        within = np.where(np.isfinite(diff) & np.isfinite(budget),
                          (np.abs(diff) <= Z_LIMIT * se + budget).astype(np.int8), -1)
        data[obs] = (dims, value, {**meta, "source": "circuit (ngspice)"})
        data[f"{obs}_stderr"] = (dims, se, {**meta, "long_name": f"standard error of {obs}"})
        data[f"{obs}_theory"] = (dims, theory, {
            **meta, "long_name": f"exact theory of {obs} (ideal sgn model, white noise)"})
        data[f"{obs}_budget"] = (dims, budget, {
            **meta, "long_name": f"systematic budget of {obs}: sum of |budget_terms|"})
        data[f"{obs}_budget_terms"] = (dims + ("budget_term",), terms, {
            **meta, "long_name": f"signed or bounding systematic terms of {obs}"})
        data[f"{obs}_z"] = (dims, z, {"long_name": f"(circuit - theory)/stderr of {obs}",
                                      "units": "1"})
        data[f"{obs}_within_budget"] = (dims, within, {
            "long_name": f"|circuit - theory| <= {Z_LIMIT:g} stderr + budget for {obs}",
            "flag_values": "1 within, 0 outside, -1 undefined (NaN: censored first passage)"})
    data["first_passage_censored"] = (dims, grid(lambda r: r["_info"]["censored"], np.int64), {
        "long_name": "circuit first-passage replicas not at rest by t_end"})
    data["stick_threshold"] = (dims, grid(lambda r: r["_info"]["threshold"]), {
        "long_name": "stick window |v| < this (model velocity)"})
    for part in ("circuit_s", "theory_s", "monte_carlo_s", "estimates_s"):
        data[f"time_{part}"] = (dims, grid(lambda r, p=part: r["_info"]["timing"][p]), {
            "long_name": f"wall seconds of the point's {part[:-2].replace('_', ' ')} stage "
                         f"(circuit: simulate, calibrations and store reads included)",
            "units": "s"})
    data["epsilon"] = (dims, grid(lambda r: r["_info"]["epsilon"]), {
        "long_name": "the circuit's tanh smoothing width (model velocity)"})
    for s in _STREAMS:
        data[f"seed_{s.removeprefix('sweep_')}"] = (dims, grid(lambda r, s=s: r["_info"]["seeds"][s],
                                                              np.int64), {
            "long_name": f"seed of the point's {s.removeprefix('sweep_').replace('_', ' ')} "
                         f"run (analogue.study.sweep.point_seed)"})
    for name, (fine, values) in theory_curves(plan).items():
        axis = name.rsplit("_theory_fine_", 1)[1]
        obs = name.rsplit("_theory_fine_", 1)[0]
        coords[f"{axis}_fine"] = (f"{axis}_fine", fine, {
            "long_name": f"{axis} on the theory curves' fine grid"})
        other = tuple(d for d in dims if d != axis)
        data[name] = ((f"{axis}_fine",) + other, values, {
            "long_name": f"exact theory of {obs} along {axis} (fine grid)",
            "units": _UNITS[obs]})
    versions = sorted({str(r["_info"]["ngspice_version"]) for r in results})
    varied = set(dims)
    fixed = {k: v for k, v in exp.model.as_dict().items() if k not in varied}
    st = plan.settings
    attrs: dict[str, Any] = {
        "title": f"analogue sweep of experiment {exp.name} over {', '.join(dims)}",
        "experiment": exp.name,
        "experiment_source": str(exp.source) if exp.source is not None else "",
        "varied": json.dumps({a.name: a.given for a in plan.axes}),
        "fixed_parameters": json.dumps(fixed),
        "circuit_spec": json.dumps({k: v for k, v in exp.spec.__dict__.items()},
                                   default=str),
        "seed": int(exp.seed),
        "seed_rule": "SeedSequence(experiment seed, spawn_key=(stream key, sha256 words of the "
                     "point's model)) -> 1..2**31-1 (analogue.study.sweep.point_seed); stream "
                     "keys: " + json.dumps({s: STREAMS[s] for s in _STREAMS}),
        "ngspice_version": ", ".join(versions),
        "quick": int(plan.quick),
        "date": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "analogue_version": __version__,
        "stationary_replicas": int(st.stationary_replicas),
        "stationary_t_end": float(st.stationary_t_end),
        "stationary_burn_in": float(st.stationary_burn_in),
        "stationary_hold_divisor": int(st.stationary_hold_divisor),
        "stick_threshold_factor": float(st.stick_threshold),
        "first_passage_v0": math.nan if plan.fp_v0 is None else plan.fp_v0,
        "first_passage_replicas": int(plan.fp_replicas),
        "first_passage_t_end": float(exp.t_end),
        "sample_dt": float(exp.sample_dt),
        "monte_carlo_replicas": MC_QUICK_REPLICAS if plan.quick else MC_REPLICAS,
        "mean_work_rate_convention": "F <v> in reduced units: F = m a (the experiment's mass "
                                     "times the point's a), the work rate of paper eq. (3)",
        "standard_errors": "stationary: delete-a-group jackknife over independent replicas, "
                           "floored by the exact spread of the time averages under the null "
                           "(study.catalogue.stationary_exact_se / stationary_null_se); D_x: "
                           "window increments inside each path (estimators.transport."
                           "window_diffusion), jackknife over replicas; first passage: spread "
                           "of per-replica times / sqrt(n)",
        "budget": "smoothing: exact(epsilon) - exact(0); bandwidth: |d| + 2 SE(d) of a "
                  "held/white Monte Carlo pair on common increments; integration: the "
                  "tolerance chooser's predicted worst ratio x stderr; sampling: the first "
                  "passage's bound beta sqrt(2 dt/gamma) T'(0+) + dt (estimators.first_passage)",
        "within_budget_rule": f"|circuit - theory| <= {Z_LIMIT:g} stderr + budget "
                              f"(study.metrics.compare)",
        "wall_time_s": round(wall, 3),
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def sweep(experiment: Experiment | str | Path, vary: Mapping[str, Any], *, quick: bool = False,
          out: str | Path | None = None, runner: Any = None, workers: int | None = None,
          scheduler: str | None = None, executor: Any = None, store: Any = None,
          progress: bool | None = None, timeout: float | None = None,
          max_concurrent_points: int | None = None, phases: Any = None):
    """Sweep ``experiment`` over a grid of model parameters: circuit and exact theory at every
    point (module docstring for the observables, errors and budget).

    Parameters
    ----------
    experiment : str, Path or Experiment
        A shipped experiment name (``"stick"``), a TOML path, or a loaded experiment.  Must be
        one-dimensional with Gaussian noise only (the paper's model, cubic, Stribeck).
    vary : mapping
        ``{name: (start, stop, n)}`` (evenly spaced, ``n`` in 1..64), ``{name: (start,
        stop, n, "log")}`` (geometric) or ``{name: array}``; names from
        :func:`sweep_parameters` (tau_m, delta, a, gamma, mass, cubic; delta_s, v_s for a
        Stribeck law).  One dimension per name, at most 256 points in all.  Everything is
        validated (and every point's model and circuit built) before anything runs.
    quick : bool
        The experiment's ``--quick`` sizes (a quarter of the replicas, half the stationary
        length).
    out : path, optional
        Directory: ``out/sweep.nc`` is written atomically (nothing half-written on an error
        or a signal).  The figures are :func:`analogue.plots.sweep.draw_sweep`'s.
    runner : analogue.Runner, optional
        How the decks run (store, workers, Dask scheduler or executor, timeout, progress),
        passed to every :func:`analogue.simulate` call (its label set per run); the run store
        resumes an interrupted sweep.
    workers, scheduler, executor, store, progress, timeout
        The same as keywords (folded into a Runner); passing one with ``runner=`` is a
        TypeError.
    max_concurrent_points : int, optional
        How many points run at once (1: one after another; default: :func:`point_threads`).
        Concurrent points share one deck executor: locally never more than ``workers``
        ngspice processes in all.  The numbers are the same either way, bit for bit (each
        point's seeds depend on its model only).
    phases : analogue.study.schedule.Phases, optional
        Where each point is recorded as the phase ``"sweep point"`` (the report's timeline).

    Returns
    -------
    xarray.Dataset
        Dims: the varied names (coordinates: their values) and ``budget_term``; variables
        ``<obs>``, ``<obs>_stderr``, ``<obs>_theory``, ``<obs>_budget``,
        ``<obs>_budget_terms``, ``<obs>_z``, ``<obs>_within_budget`` for each of
        :data:`OBSERVABLES`, plus ``first_passage_censored``, ``stick_threshold``,
        ``epsilon`` and the per-point seeds; provenance in ``attrs`` (experiment, fixed
        parameters, seeds, ngspice version, quick, date, conventions).
    """
    t0 = time.perf_counter()
    plan = plan_sweep(experiment, vary, quick=quick)
    if out is not None:
        out = check_path(out, "out")
        if out.exists() and not out.is_dir():
            raise ValueError(f"out: {str(out)!r} exists and is not a directory")
    run = _runner(runner, {"workers": workers, "scheduler": scheduler, "executor": executor,
                           "store": store, "progress": progress, "timeout": timeout})
    threads = point_threads(len(plan.points), run, max_concurrent_points)
    results = _run_points(plan, run, threads, phases=phases)
    ds = _dataset(plan, results, time.perf_counter() - t0)
    if out is not None:
        write_sweep(ds, Path(out) / "sweep.nc")
    return ds


def write_sweep(ds, path: str | Path) -> Path:
    """Write a sweep dataset as netCDF-4, atomically (:func:`analogue.netcdf_layout.
    write_dataset`: a temporary file renamed into place, removed on any failure)."""
    return write_dataset(ds, path)
