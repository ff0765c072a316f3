"""The model family's members: circuit against theory (issue 9), the analysis half of the
chapter "Beyond the paper" (its page is :mod:`analogue.report.beyond`).

One analysis for every extension the paper proposes (cubic viscous law, Stribeck law, spring,
shot noise), used by ``analogue report <member>`` and by the chapter "Beyond the paper" of
``analogue paper``.  The observables, their estimators, exact readings, Monte Carlo reference
(the spring) and circuit-element terms are entries of the catalogue
(:mod:`analogue.study.catalogue`, :func:`~analogue.study.catalogue.member_observables`); this
module runs the circuits and references, fills the budgets, and evaluates everything once into
a :class:`MemberAnalysis` that the figures (:mod:`analogue.report.family_figures`) only draw.

References
----------
* one-dimensional members (spring = 0): exact finite-noise numerics of
  :mod:`analogue.theory.family` (Fokker-Planck with Gaussian noise, Kolmogorov-Feller with shot
  noise, the atom P(v = 0) as its own state): stationary moments, the propagator at several
  times, the work rate function (Gaussian members);
* the spring (state (x, v)): the Monte Carlo of :func:`analogue.montecarlo.simulate_sde` at
  the same sizes, plus the stationary identities <v> = 0 and
  spring <x> = a - <Delta(v) sgn v> - cubic <v^3> (ensemble average of dv/dt = 0).

Budget (absolute, the observable's units; :class:`analogue.study.metrics.Budget`):
statistics (3 jackknife SE over replicas; for Monte Carlo references the two SEs in
quadrature), ``smoothing`` = exact(model at the circuit's epsilon) - exact(ideal model),
``bandwidth`` = held minus white noise Monte Carlo on common increments (Gaussian members),
``element`` = the family's circuit terms of :func:`analogue.circuit.mapping.map_model`
(cubic network approximation, inductor series resistance, shot pulse width/edges), relative
terms times the theory value, ``integration`` = the first two decks (8 replicas) of the stationary
run (spring: of its run) re-run with :meth:`~analogue.study.experiments.Experiment.check_spec`
(100x tighter, the same noise), the paired difference (|d| + 2 SE); transition rows carry the
stationary run's check only in their note (not re-run: it would double the chapter's ngspice).
"""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .experiments import Experiment, load_experiment, standard_circuit
from ..circuit.store_index import indexing_runs
from ..ensemble import Ensemble
from .. import checks
from ..model import Model
from . import catalogue as C
from .seeds import SeedPlan
from .budget import SE_MULTIPLIER, held_noise_pair
from .metrics import Budget, compare
from ..estimators import work_rate_samples
from .observables import jackknife_difference, subset
from ..theory.kolmogorov_feller import default_spacing
from ..theory import family
from ..circuit.runner import Runner
from ..circuit.decks import run_ensemble
from ..circuit.deck_pool import WaitClock
from ..circuit.deck_size import MIN_CALIBRATED_REPLICA_HOLDS as MIN_DECK_HOLDS
from ..circuit.deck_size import choose_deck_size
from ..circuit.tolerances import MIN_CALIBRATED_REPLICA_HOLDS as MIN_TOLERANCE_HOLDS
from ..circuit.tolerances import resolve_spec
from ..cores import usable_cpus
from .runs import _run_jobs
from .schedule import result_of
from ..montecarlo import simulate_sde
from ..theory.exact import stationary_moments as _sm
from ..theory.weak_noise_family import quasi_potential
from ..theory.exact import rate_function as _rf

__all__ = [
    "MEMBERS",
    "MemberAnalysis",
    "MemberRuns",
    "MemberSizes",
    "analyse_member",
    "is_member_experiment",
    "member_runs",
    "member_sizes",
    "rate_function_data",
    "stick_window",
    "weak_noise_law",
    "work_tau",
]

MEMBERS = ("cubic", "stribeck", "spring", "shot")

# work window of the circuit's finite-tau rate-function estimate, in units of tau_m (figure
# only: at quick sizes its windows overlap strongly and its error is not a clean jackknife).
# Was the absolute 4.0: 0.4 tau_m for a tau_m = 10 copy; the velocity correlation time
# D_x/Var v is 0.44, 2.2, 0.76 for circuits/cubic, stribeck, shot.toml (tau_m 1, 2, 1)
WORK_TAU = 4.0
# quick run length and the least stationary length after the burn-in, in units of tau_m
# (were the absolute 40 and 30)
QUICK_T_END = 40.0
MIN_STATIONARY = 30.0
# member runs' sample interval: 0.02 tau_m, never coarser than 0.02 (the friction's
# deceleration does not slow down with a slower tau_m)
SAMPLE_DT = 0.02


def work_tau(m: Model) -> float:
    """The work window of the finite-tau rate-function estimate: ``WORK_TAU`` tau_m."""
    return WORK_TAU * m.tau_m


def stick_window(exp: Experiment) -> float:
    """|v| below this counts as stuck in ``exp``'s analysis (estimators and theory alike):
    :func:`analogue.study.catalogue.member_stick_window` with the experiment's
    ``[report] stick_threshold`` and its circuit's smoothing."""
    return C.member_stick_window(exp.model, stick_threshold=exp.report.stick_threshold,
                                 epsilon=exp.mapping().model_effective.epsilon)
# the chapter's title (and the name its members' failures are recorded under)
CHAPTER_TITLE = "Beyond the paper"

# replicas of the integration check (the first decks of the nominal run, re-run with 100x
# tighter tolerances on the same noise: Experiment.check_spec)
CHECK_REPLICAS = 8
# Replicas per deck of a member's nominal stationary (spring: release) run and of its check,
# which re-runs the first CHECK_REPLICAS // MEMBER_DECK decks: a deck's noise depends on its
# size, so both must share it.  4, the tolerance calibration's own deck size (circuit.
# tolerances.CAL_DECK) and the deck-size chooser's smallest: replicas in a deck share every
# time step, so a smaller deck takes fewer points per noise hold (circuit.deck_size), and the
# check's two decks run at once.  It was 8 (the check one deck): the spring's check, 8
# replicas over 40 tau_m at 100x tighter tolerances, was the longest deck of the quick paper
# (13.4 s idle, the job's critical path with unlimited cores: issue 22).  A deck-size choice:
# it changes which noise drives which replica, so the members' numbers change like a seed.
MEMBER_DECK = 4


@dataclass(frozen=True)
class MemberSizes:
    """Circuit sizes of one member's analysis (quick: the chapter's default)."""

    stationary_replicas: int
    stationary_t_end: float
    transition_replicas: int
    mc_replicas: int          # Monte Carlo references (numpy: cheap)
    sample_dt: float = 0.02

    def __post_init__(self):
        for k in ("stationary_replicas", "transition_replicas", "mc_replicas"):
            object.__setattr__(self, k, checks.integer(k, getattr(self, k), minimum=8))
        object.__setattr__(self, "stationary_t_end", checks.positive("stationary_t_end", self.stationary_t_end))


def member_sizes(exp: Experiment, quick: bool) -> MemberSizes:
    """Quick: 32 stationary replicas of 40 tau_m (at least the burn-in + 30 tau_m), 32
    transition replicas.  Full: the experiment's own sizes (``[experiment] replicas``,
    ``[report] stationary_*``), at least the burn-in + 30 tau_m.  Samples every 0.02 tau_m,
    at most 0.02."""
    tm = exp.model.tau_m
    least = exp.burn_in + MIN_STATIONARY * tm
    dt = SAMPLE_DT * min(tm, 1.0)
    if quick:
        return MemberSizes(32, max(QUICK_T_END * tm, least), 32, 256, dt)
    return MemberSizes(max(16, exp.report.stationary_replicas // 2),
                       max(exp.report.stationary_t_end, least),
                       max(32, exp.replicas), 1024, dt)


def is_member_experiment(exp: Experiment) -> bool:
    """An experiment on a family member (anything but the paper's model)."""
    return not exp.model.is_paper


@dataclass
class MemberAnalysis:
    """Everything the chapter and the figures need, computed once."""

    exp: Experiment
    sizes: MemberSizes
    comparisons: list = field(default_factory=list)
    figures: dict = field(default_factory=dict)    # name -> plain data for family_figures
    facts: dict = field(default_factory=dict)      # numbers quoted in the text
    provenance: dict = field(default_factory=dict)
    wall_time: float = 0.0
    runs: MemberRuns | None = None                 # the circuit runs it read (by_role())

    def summary(self) -> dict:
        n = len(self.comparisons)
        return {"comparisons": n, "within_budget": sum(c.within_budget for c in self.comparisons),
                "abs_z_below_3": sum(abs(c.z) < 3 for c in self.comparisons if math.isfinite(c.z))}


# ------------------------------------------------------------------------------ estimators
def _after(ens: Ensemble, burn_in: float) -> np.ndarray:
    i0 = int(np.searchsorted(ens.t, ens.t[0] + burn_in - 1e-12))
    return ens.v[:, i0:]


def _position(ens: Ensemble) -> np.ndarray:
    """The spring's position: the circuit's inductor read-back (``meta['x_spring']`` rows
    attached by :func:`_circuit`) or ``x0 + x`` for the Monte Carlo."""
    xs = ens.meta.get("_x_spring")
    if xs is not None:
        return xs
    return ens.meta["_x0"] + ens.x


def _xs_subset(ens: Ensemble, rows) -> Ensemble:
    e = subset(ens, rows)
    meta = dict(ens.meta)
    if meta.get("_x_spring") is not None:
        meta["_x_spring"] = meta["_x_spring"][rows]
    return Ensemble(e.t, e.v, e.x, meta)


def _jk(fn, ens: Ensemble, groups: int = 16) -> tuple[float, float]:
    """Delete-a-group jackknife over replicas (which are independent) of a scalar."""
    n = ens.replicas
    g = max(2, min(groups, n // 2))
    labels = np.arange(n) % g
    full = float(fn(ens))
    reps = np.array([fn(_xs_subset(ens, np.flatnonzero(labels != j))) for j in range(g)])
    return full, float(np.sqrt((g - 1) / g * np.sum((reps - reps.mean()) ** 2)))


def _estimators(exp: Experiment, observables, threshold: float) -> dict:
    """``{label: estimator(ensemble) -> float}`` of the catalogue's observables on this
    member's ensembles (circuit, Monte Carlo, budget pairs); ``threshold``: the member's stick
    window (:func:`stick_window`)."""
    m = exp.model

    def bind(o: C.Observable) -> Callable[[Ensemble], float]:
        return lambda e: C.estimate(o, e, burn_in=exp.burn_in, threshold=threshold,
                                    force=m.force, position=_position(e) if m.spring > 0 else None,
                                    model=m, friction=e.meta.get("_model_eff", m))
    return {o.label: bind(o) for o in observables}


def _h(exp: Experiment) -> float:
    """One grid spacing for the ideal and the smoothed model: the ideal model's default (the
    smoothed model's own default resolves epsilon and needs ~45000 states for shot noise)."""
    return default_spacing(exp.model)


def _stationary_theory(exp: Experiment, model: Model, observables, threshold: float) -> dict:
    """Exact stationary values (family numerics at the ideal model's grid spacing).  The
    window masses (stick fraction, P(v=0), P(v>window)) read the law of
    :func:`analogue.theory.family.stationary_law` (itself Richardson over its grids h, h/2
    for shot noise) by the trapezoid, second order in h, so they take the second-order
    Richardson pair h, h/2 (shot.toml's stick fraction: 0.434366 at h, 0.434449 at h/2,
    0.434475 at h/8; this pair 0.434477; the first-order pair 2 f - c overshot to 0.434532);
    values read from the Richardson moments are the same on both grids and unchanged."""
    h = _h(exp)
    moments = family.stationary_moments(model, h=h)
    coarse, fine = (C.stationary_theory(model, moments, threshold=threshold,
                                        work_variance={}, law=family.stationary_law(model, h=hh),
                                        observables=observables) for hh in (h, h / 2))
    return {k: (4.0 * fine[k] - coarse[k]) / 3.0 for k in coarse}


def _transition_theory(exp: Experiment, model: Model, v0: float, times, observables,
                       threshold: float) -> dict:
    """Exact values at each time from the propagator (density + the atom at v = 0 + the
    unkicked mass on the noise-free path), see :func:`_transition_laws`."""
    v, f, atom, point = _transition_law(exp, model, v0, times)
    return C.transition_theory(v, f, v0, times, atom=atom, observables=observables, point=point,
                               window=threshold)


def _transition_laws(exp: Experiment, model: Model, v0: float, times,
                     threshold: float) -> list[C.LawMoments]:
    """The exact law's moments at each time (what the transition rows read)."""
    v, f, atom, point = _transition_law(exp, model, v0, times)
    return C.transition_laws(v, f, atom=atom, point=point, window=threshold)


def _transition_law(exp: Experiment, model: Model, v0: float, times):
    """(grid, density rows, atom at 0, unkicked delta) of f(v, t | v0) at ``times``.  With
    pure shot noise the unkicked mass e^{-rate t} rides the noise-free path v_det(t): at 0
    (stuck) propagator_atom has it; elsewhere it is a moving delta outside the density (left
    out before: var v at t = 0.5 read 0.308 instead of 0.163 for tau_m 2, Delta 0.3, a -0.5,
    two-sided kicks rate 1.5, mean 0.4, v0 = 0)."""
    lo = min(v0, model.potential_minimum() if model.is_gradient else 0.0) - 12 * model.velocity_scale
    # and 12 mean jumps of the kicks (analogue.variants: none without kicks)
    hi = max(v0, model.attractor) + 12 * model.velocity_scale + 12 * sum(
        model.noise_kind.jump_scales())
    dv = (hi - lo) / 4000
    v = dv * np.arange(math.floor(lo / dv), math.ceil(hi / dv) + 1)   # v = 0 on a node
    ts = np.asarray(times, float)
    f = family.propagator(model, v, ts, v0, h=_h(exp))
    atom = (np.atleast_1d(family.propagator_atom(model, ts, v0, h=_h(exp)))
            if model.shot is not None else np.zeros(len(ts)))
    point = None
    if C.model_class(model) == C.SHOT_MEMBER:
        vd, un = family.unkicked(model, ts, v0)
        point = (vd, np.where(vd == 0.0, 0.0, un))
    return v, f, atom, point


def _paper_law(model: Model, v: np.ndarray) -> tuple[np.ndarray, float]:
    """(density on ``v``, atom at 0) of the paper's law at the member's Delta and noise (no
    cubic or Stribeck term): exp(-gamma U)/Z with Gaussian noise only; otherwise the
    Kolmogorov-Feller grid law interpolated (Model.stationary_pdf refuses shot noise: a cubic
    or Stribeck member with pure shot noise crashed its report)."""
    base = model.replace(stribeck=None, cubic=0.0)
    if base.shot is None:
        return base.stationary_pdf(v), 0.0
    vg, dens, atom = family.stationary_law(base)
    return np.interp(v, vg, dens, left=0.0, right=0.0), float(atom)


def _null_se(o: C.Observable, law: C.LawMoments, n: int) -> float:
    """SE of a transition row's estimator on n independent draws from the exact law (one
    velocity per replica: the catalogue kind's theory_se).  The row's SE is at least this: the
    jackknife of a heavy-tailed sample that misses the tail is too small (pure shot noise, 32
    replicas: |z| > 3 in 15 % of seeded ensembles for var v, 1000 ensembles; with the floor
    0 %)."""
    return C.theory_se(o, law, n)



# ------------------------------------------------------------------------------ runs
@dataclass(frozen=True)
class _Run:
    """One circuit run of a member (seeded, stored), as :func:`analogue.simulate` makes it.
    ``per_deck`` fixes the deck size, so that a re-run of the first decks with ``spec`` (the
    integration check) sees the same noise: a deck's noise depends on (seed, deck index,
    deck size); ``spec`` None: the experiment's circuit."""

    name: str
    v0: Any
    t_end: float
    replicas: int
    seed: int
    spec: Any = None
    per_deck: int | None = None


def _member_circuits(exp: Experiment, sizes: MemberSizes, runner: Runner, runs: list[_Run],
                     t_start: float) -> tuple[dict[str, Ensemble], dict]:
    """``{run name: ensemble}`` of a member's runs, each as :func:`analogue.simulate` makes
    it (the same calibrations, store keys, decks and ``meta``), and their timing.

    The runs share one pool of ``runner``'s workers, started in the order given (longest
    first, as the paper's runs: :func:`analogue.study.runs._run_jobs`); each chooses its
    tolerances and deck size (:func:`_calibrated`) and runs its decks, so that a run with
    nothing to calibrate (the integration check: its tolerances and deck size are given)
    starts its decks at once.  Before, the runs went one after another: the spring's
    100x-tighter check (one deck of 8 replicas over its 40 tau_m) started only after the
    release run's calibrations and four decks.  Timing (:mod:`analogue.study.critical_path`:
    what the runs take with unlimited cores): ``before_decks_s`` from ``t_start`` to the
    runs' start, then per run its calibrations' seconds and its longest deck (``runs``), and
    the longest deck of all (``longest_deck_s``; 0 when every deck came from the store);
    ``runner``: how the decks run (:meth:`RunOptions.runner`).  A run's calibrations count
    their seconds less those in which they only waited for a free ngspice process
    (:class:`analogue.circuit.deck_pool.WaitClock`): measured on the quick paper (2 cores),
    the spring's release run took 28.1 s to calibrate, queued behind its 25.4 s check deck."""
    timing: dict = {}

    def job(r: _Run) -> Callable[[Runner], Ensemble]:
        def run(pool: Runner) -> Ensemble:
            t = time.perf_counter()
            clock = WaitClock(pool.executor) if pool.executor is not None else None
            stages: list = []
            spec, per_deck, why = _calibrated(exp, r, pool if clock is None
                                              else pool.replace(executor=clock),
                                              clock=clock, stages=stages)
            # its calibrations' own seconds: not those it only waited for a free ngspice
            # process (behind the other runs' decks), which unlimited cores would not, and
            # at most its stages' longest decks (each stage's decks run at once)
            own = time.perf_counter() - t - (clock.blocked_s if clock else 0.0)
            timing[r.name] = min(own, sum(stages)) if clock is not None else own
            return run_ensemble(exp.model, spec, v0=r.v0, t_end=r.t_end, replicas=r.replicas,
                                seed=r.seed, sample_dt=sizes.sample_dt,
                                runner=pool.replace(replicas_per_deck=per_deck), **why)
        return run
    t_jobs = time.perf_counter()
    done = _run_jobs([(r.name, job(r)) for r in runs], runner)

    def ran(e: Ensemble) -> list[float]:
        return [float(w) for w in e.meta.get("ran_deck_wall_times") or () if w is not None]
    return done, {"before_decks_s": round(t_jobs - t_start, 3),
                  "longest_deck_s": round(max((w for e in done.values() for w in ran(e)),
                                              default=0.0), 3),
                  "decks_run": sum(len(ran(e)) for e in done.values()),
                  "runs": {name: {"calibration_s": round(timing[name], 3),
                                  "longest_deck_s": round(max(ran(e), default=0.0), 3)}
                           for name, e in done.items()}}


def _calibrated(exp: Experiment, r: _Run, runner: Runner, *, clock: WaitClock | None = None,
                stages: list | None = None) -> tuple[Any, int, dict]:
    """(spec with its tolerances set, replicas per deck, ``meta`` records of how they were
    chosen) of one run, chosen as :func:`analogue.simulate` chooses them when given this run
    (its tolerance and deck-size calibrations, with their minimum sizes), to be run by
    :func:`analogue.circuit.decks.run_ensemble`.  ``clock`` (the runner's executor) and
    ``stages``: the longest deck of each calibration stage is appended to ``stages``."""
    spec = exp.spec if r.spec is None else r.spec
    run = runner if r.per_deck is None else runner.replace(replicas_per_deck=r.per_deck)
    tol = deck = None
    if spec.unset_tolerances:
        spec, tol = resolve_spec(exp.model, spec, replicas=r.replicas, t_end=r.t_end,
                                 runner=run.for_calibration(),
                                 min_replica_holds=MIN_TOLERANCE_HOLDS)
    if clock is not None and stages is not None:
        stages.append(clock.stage_longest())
    per_deck = run.replicas_per_deck
    if per_deck is None:
        deck = choose_deck_size(exp.model, spec, replicas=r.replicas, t_end=r.t_end,
                                workers=run.workers or usable_cpus(),
                                runner=run.for_calibration(), min_replica_holds=MIN_DECK_HOLDS)
        per_deck = deck.replicas_per_deck
    if clock is not None and stages is not None:
        stages.append(clock.stage_longest())
    return spec, per_deck, {"tolerances": tol.as_dict() if tol is not None else None,
                            "deck_size": deck.as_dict() if deck is not None else None}


def _analysed(exp: Experiment, ens: Ensemble) -> Ensemble:
    """A run as the analysis reads it: the effective model, the spring's inductor read-back
    and the kick count in (private) ``meta`` keys."""
    rec = ens.records or {}
    meta = dict(ens.meta)
    meta["_model_eff"] = exp.mapping().model_effective
    if "x_spring" in rec:
        meta["_x_spring"] = np.asarray(rec["x_spring"])
    if "kicks" in rec:
        meta["_kicks"] = sum(len(k[0]) for k in rec["kicks"])
    return Ensemble(ens.t, ens.v, ens.x, meta)


@dataclass
class MemberRuns:
    """The circuit runs behind a member's report section, as :func:`analogue.simulate`
    returned them (``records`` kept).  1-D members: ``stationary`` (from p_s, seed
    ``member_circuit``), ``transition`` (from ``exp.v0[0]``; None without
    ``[experiment] histogram_times``: the member then has stationary rows only), ``check``
    (the stationary run's first two decks, 100x tighter); the spring: ``transition`` is the release from ``x0``
    at rest (over the stationary length), ``check`` its first two decks, no ``stationary``."""

    exp: Experiment
    sizes: MemberSizes
    quick: bool
    transition: Ensemble | None
    check: Ensemble
    stationary: Ensemble | None = None
    seeds: dict = field(default_factory=dict)
    # how long the runs took: before_decks_s (calibrations), longest_deck_s, decks_run
    # (_run_member_jobs); a member's critical path (analogue.study.critical_path)
    timing: dict = field(default_factory=dict)

    @property
    def v0(self) -> float:
        """Where the transition run starts (the spring: at rest)."""
        return 0.0 if self.stationary is None else float(self.exp.v0[0])

    def by_role(self) -> dict[str, Ensemble]:
        """The runs named as :func:`analogue.load_runs` names them: ``transition_v0=<v0>``,
        then ``stationary`` and ``check_stationary`` (1-D) or ``check_transition`` (spring)."""
        out = {} if self.transition is None else {f"transition_v0={self.v0:g}": self.transition}
        if self.stationary is None:
            out["check_transition"] = self.check
        else:
            out.update(stationary=self.stationary, check_stationary=self.check)
        return out


@indexing_runs  # the store's index by experiment (analogue store ls): every entry used
def member_runs(exp: Experiment, opts=None, *, quick: bool | None = None,
                progress=None) -> MemberRuns:
    """Run (or read from the store) the circuit runs of a member's report section at the
    ``--quick`` (default) or full sizes (:func:`member_sizes`): the one source of these runs
    for :func:`analyse_member`, ``analogue export`` and :func:`analogue.load_runs`."""
    quick = bool(getattr(opts, "quick", True)) if quick is None else quick
    sizes = member_sizes(exp, quick)
    tick = progress or (lambda *_: None)
    plan = SeedPlan(exp.seed)             # every seed below (analogue.study.seeds)
    runs = _RUNS.get(C.model_class(exp.model), _one_d_runs)
    # how the decks run: the options' runner (none given: silent, the default store)
    runner = opts.runner() if opts is not None else Runner(progress=False)
    return runs(exp, runner, sizes=sizes, quick=quick, plan=plan, tick=tick)


def _release_runs(exp: Experiment, runner: Runner, *, sizes: MemberSizes, quick: bool, plan: SeedPlan,
                  tick: Callable) -> MemberRuns:
    """The spring's runs: the release from x0 at rest and its first two decks 100x tighter."""
    t_start = time.perf_counter()
    seed, name, m = plan.member_circuit, exp.name, exp.model
    tick(f"{name}: circuit run from x0 = {m.x0:g} ({sizes.transition_replicas} replicas) and "
         f"its integration check (first {CHECK_REPLICAS} replicas, 100x tighter)")
    # the check first: its decks cost 5x a nominal deck's
    runs = [_Run("check", 0.0, sizes.stationary_t_end, CHECK_REPLICAS, seed,
                 exp.check_spec(), MEMBER_DECK),
            _Run("release", 0.0, sizes.stationary_t_end, sizes.transition_replicas, seed,
                 per_deck=MEMBER_DECK)]
    done, timing = _member_circuits(exp, sizes, runner, runs, t_start)
    return MemberRuns(exp, sizes, quick, transition=done["release"], check=done["check"],
                      seeds={"transition": seed, "check_transition": seed}, timing=timing)


def _one_d_runs(exp: Experiment, runner: Runner, *, sizes: MemberSizes, quick: bool, plan: SeedPlan,
                tick: Callable) -> MemberRuns:
    """A 1-D member's runs: stationary (from the start model's law), transition (from
    ``exp.v0[0]``, with ``histogram_times``) and the stationary run's first two decks 100x
    tighter; none needs another's result, so their decks share one pool."""
    t_start = time.perf_counter()
    seed, name = plan.member_circuit, exp.name
    v0_stat = _stationary_start(exp, sizes, plan)
    v00 = float(exp.v0[0])
    times = [float(t) for t in exp.histogram_times]
    tick(f"{name}: stationary circuit run ({sizes.stationary_replicas} x "
         f"{sizes.stationary_t_end:g})" + (f", transition circuit run from v0 = {v00:g} "
                                            f"({sizes.transition_replicas} replicas)"
                                            if times else "")
         + f", integration check (first {CHECK_REPLICAS} stationary replicas, 100x tighter)")
    # longest first: the check (decks of 5x a nominal deck's cost), the stationary run,
    # the transition run (no histogram_times: none; max(times) crashed)
    runs = [_Run("check", v0_stat[:CHECK_REPLICAS], sizes.stationary_t_end, CHECK_REPLICAS,
                 seed, exp.check_spec(), MEMBER_DECK),
            _Run("stationary", v0_stat, sizes.stationary_t_end, sizes.stationary_replicas,
                 seed, per_deck=MEMBER_DECK)]
    if times:
        runs.append(_Run("transition", v00, max(times), sizes.transition_replicas,
                         plan.member_transition))
    done, timing = _member_circuits(exp, sizes, runner, runs, t_start)
    seeds = {"stationary": seed, "check_stationary": seed}
    if times:
        seeds["transition"] = plan.member_transition
    return MemberRuns(exp, sizes, quick, transition=done.get("transition"), check=done["check"],
                      stationary=done["stationary"], seeds=seeds, timing=timing)


# the runs of each member class (catalogue.model_class); the others: _one_d_runs
_RUNS: dict[str, Callable[..., MemberRuns]] = {C.SPRING_MEMBER: _release_runs}


def _stationary_start(exp: Experiment, sizes: MemberSizes, plan: SeedPlan) -> np.ndarray:
    """The stationary run's start states: draws from the exact stationary law of the noise's
    start model (the member itself; coloured noise: white noise of the same gamma, which the
    burn-in forgets and the Monte Carlo reference shares)."""
    m = exp.model
    return family.sample_stationary(m.noise_kind.start_model(m), sizes.stationary_replicas,
                                    plan.member_stationary_v0)


def _measured(pairs: dict, label: str) -> float:
    d, se = pairs.get(label, (0.0, 0.0))
    return abs(d) + SE_MULTIPLIER * se if label in pairs else 0.0


def _paired(fns: dict, a: Ensemble, b: Ensemble) -> dict:
    """``{label: (estimator(a) - estimator(b), jackknife se)}`` for paired ensembles (row i of
    a and b share their noise), e.g. the integration check against the nominal run.  Refused
    unless a retraces b (same noise): otherwise the difference would be noise, not a bias."""
    d = np.abs(a.v - b.v)
    if not np.isfinite(d).all() or float(np.median(d)) > 0.1 * float(np.std(b.v)):
        raise RuntimeError("integration check: the tight-tolerance re-run does not retrace the "
                           "nominal paths (noise not reproduced?); integration budget unavailable")
    n = a.replicas
    g = max(2, min(8, n // 2))
    labels = np.arange(n) % g
    out = {}
    for label, fn in fns.items():
        full = fn(a) - fn(b)
        reps = np.array([fn(_xs_subset(a, np.flatnonzero(labels != j)))
                         - fn(_xs_subset(b, np.flatnonzero(labels != j))) for j in range(g)])
        out[label] = (float(full), float(np.sqrt((g - 1) / g * np.sum((reps - reps.mean()) ** 2))))
    return out


def _band(exp: Experiment, fns: dict, v0, t_end: float, replicas: int, seed: int, *,
          sample_dt: float) -> dict:
    """Held minus white noise Monte Carlo on common increments (Gaussian members only),
    sampled every ``sample_dt`` (the member's, :class:`MemberSizes`; was an absolute 0.02)."""
    m = exp.mapping()
    if not math.isfinite(exp.model.gamma):
        return {}
    noise_dt = m.noise_dt
    # whole samples of whole holds: the pair samples every round(sample_dt / noise_dt) holds
    # (budget.held_noise_pair_chunks), and a run of 333 holds of 0.003 sampled every 7 holds
    # was refused ("t_end must be a whole multiple of sample_dt"; a cubic member at tau_m = 2).
    # A run that already is whole samples keeps its length, bit for bit.
    holds = round(t_end / noise_dt)
    per_sample = max(1, round(sample_dt / noise_dt))
    if holds % per_sample:
        holds = per_sample * max(1, round(holds / per_sample))
    t_end = noise_dt * holds
    held, white = held_noise_pair(m.model_effective, v0=v0, t_end=t_end, replicas=replicas,
                                  seed=seed, noise_dt=noise_dt, sample_dt=sample_dt)
    for e in (held, white):
        e.meta["_x0"] = exp.model.x0
        e.meta["_model_eff"] = m.model_effective
    fn = lambda e: {label: f(e) for label, f in fns.items()}
    return jackknife_difference(fn, held, white)


def analyse_member(exp: Experiment | str, opts=None, *, quick: bool | None = None,
                   progress=None) -> MemberAnalysis:
    """Run the member's circuit (quick sizes by default in the chapter) and compare it with
    its exact theory (1-D), or with its Monte Carlo (the spring; a noise without exact theory:
    coloured noise), the analysis of its class (catalogue.model_class)."""
    t0 = time.perf_counter()
    if isinstance(exp, str):
        exp = load_experiment(standard_circuit(exp) if exp in MEMBERS else exp)
    if not is_member_experiment(exp):
        raise ValueError(f"experiment {exp.name!r} is the paper's model, not a family member")
    quick = bool(getattr(opts, "quick", True)) if quick is None else quick
    sizes = member_sizes(exp, quick)
    res = MemberAnalysis(exp, sizes)
    setting = _Setting(exp, sizes, SeedPlan(exp.seed), stick_window(exp),
                       progress or (lambda *_: None))
    cls = C.model_class(exp.model)
    # the circuit-free part (theory, Monte Carlo references, noise pairs) beside the runs,
    # which mostly wait for their decks (in the study's deck pool)
    reference = _in_thread(lambda: _REFERENCES.get(cls, _exact_reference)(setting),
                           f"analogue-{exp.name}-reference")
    t_start_runs = time.perf_counter()
    runs = member_runs(exp, opts, quick=quick, progress=progress)
    res.runs = runs
    pre, reference_s = result_of(reference)
    t_ref = time.perf_counter()
    _ANALYSES.get(cls, _analyse_exact)(setting, runs, res, pre)
    res.wall_time = time.perf_counter() - t0
    # its parts (the report's critical path, analogue.study.critical_path): the runs'
    # calibrations (from the start) and longest deck; beside them its circuit-free part
    # (reference_s, from the start); then, once both are done, the estimates (analysis_s)
    res.provenance["timing"] = {**runs.timing,
                                "before_decks_s": round(runs.timing.get("before_decks_s", 0.0)
                                                        + t_start_runs - t0, 3),
                                "reference_s": round(reference_s, 3),
                                "analysis_s": round(res.wall_time - (t_ref - t0), 3)}
    return res


def _in_thread(fn: Callable[[], Any], name: str) -> Future:
    """``fn()`` and its wall seconds, in a daemon thread (as the study's Workers: an interrupt
    does not wait for numerics under way), as a future."""
    fut: Future = Future()

    def run() -> None:
        if not fut.set_running_or_notify_cancel():
            return
        t = time.perf_counter()
        try:
            fut.set_result((fn(), time.perf_counter() - t))
        except BaseException as exc:  # handed to whoever waits for the result
            fut.set_exception(exc)
    threading.Thread(target=run, name=name, daemon=True).start()
    return fut


@dataclass(frozen=True)
class _Setting:
    """What every member analysis reads: the experiment, its sizes, its seeds
    (analogue.study.seeds), its stick window and the progress callback."""

    exp: Experiment
    sizes: MemberSizes
    plan: SeedPlan
    thr: float
    tick: Callable


def _spring_reference(s: _Setting) -> dict:
    """The spring's circuit-free part: its Monte Carlo reference, the ideal model and the
    circuit's smoothed one on the same noise (the release from x0 at rest)."""
    exp, sizes, plan = s.exp, s.sizes, s.plan
    m, m_eff = exp.model, exp.mapping().model_effective
    s.tick(f"{exp.name}: Monte Carlo reference ({sizes.mc_replicas} replicas)")
    mc = simulate_sde(m, v0=0.0, t_end=sizes.stationary_t_end, replicas=sizes.mc_replicas,
                      seed=plan.member_monte_carlo, sample_dt=sizes.sample_dt)
    mc.meta["_x0"] = m.x0
    mc_eff = simulate_sde(m_eff, v0=0.0, t_end=sizes.stationary_t_end,
                          replicas=sizes.mc_replicas, seed=plan.member_monte_carlo,
                          sample_dt=sizes.sample_dt)
    mc_eff.meta["_x0"], mc_eff.meta["_model_eff"] = m.x0, m_eff
    return {"mc": mc, "mc_eff": mc_eff}


def _analyse_spring(s: _Setting, runs: MemberRuns, res: MemberAnalysis, pre: dict) -> None:
    """The spring (state (x, v)): the release run against the Monte Carlo (``pre``:
    :func:`_spring_reference`), and the stationary identities."""
    exp, sizes, plan, thr = s.exp, s.sizes, s.plan, s.thr
    m, burn, seed, name = exp.model, exp.burn_in, plan.member_circuit, exp.name

    assert runs.transition is not None   # the spring's release run
    circ, chk = _analysed(exp, runs.transition), _analysed(exp, runs.check)
    first = _xs_subset(circ, np.arange(CHECK_REPLICAS))
    mc, mc_eff = pre["mc"], pre["mc_eff"]
    obs = C.member_observables(m)
    fns = _estimators(exp, obs, thr)
    integ = _paired(fns, chk, first)
    bias = exp.mapping().bias
    for o in obs:
        fn, label = fns[o.label], o.label
        c, se = _jk(fn, circ)
        if C.reference_of(o, m) == "exact":
            # an identity: exactly 0 in the stationary state; the same average on the
            # Monte Carlo (finite time after the release) bounds its departure
            mc_val = fn(mc_eff)
            ref = float(o.entry.exact())
            b = Budget(sampling=abs(mc_val), integration=_measured(integ, label),
                       element=C.element_error(o, bias, m, ref))
            note = "sampling = the same average on the Monte Carlo (finite time after release). "
        else:
            ref, se_r = _jk(fn, mc)
            smooth = fn(mc_eff) - ref   # same noise: epsilon's effect, paired
            se = math.hypot(se, se_r)
            b = Budget(smoothing=smooth, element=C.element_error(o, bias, m, ref),
                       integration=_measured(integ, label))
            note = (f"reference: Monte Carlo ({sizes.mc_replicas} replicas, same release); "
                    "SE = circuit and Monte Carlo SEs in quadrature. ")
        res.comparisons.append(compare(name, label, c, se, ref, "exact", b,
                                       note + o.entry.description))
    th, ah = C.first_swing(circ.t, circ.v, _position(circ), thr)
    tm, am = C.first_swing(mc.t, mc.v, _position(mc), thr)
    k = math.sqrt(m.spring)
    res.facts.update(omega_undamped_half_period=math.pi / k,
                     circuit_half_period=float(np.nanmean(th)),
                     mc_half_period=float(np.nanmean(tm)),
                     circuit_amplitude=float(np.nanmean(ah)), mc_amplitude=float(np.nanmean(am)),
                     coulomb_loss=2 * m.delta / m.spring)
    res.figures["spring_series"] = {
        "t": circ.t, "x": _position(circ)[:4], "v": circ.v[:4],
        "x_mc_mean": _position(mc).mean(axis=0), "v_mc_mean": mc.v.mean(axis=0),
        "x_circ_mean": _position(circ).mean(axis=0), "burn_in": burn,
        "stick_band": m.delta / m.spring}
    res.figures["spring_stationary"] = {
        "x_circ": _position(circ)[:, circ.t >= burn].ravel(),
        "x_mc": _position(mc)[:, mc.t >= burn].ravel(),
        "v_circ": _after(circ, burn).ravel(), "v_mc": _after(mc, burn).ravel()}
    res.provenance = _prov(exp, circ, sizes, {"circuit": seed,
                                              "monte_carlo": plan.member_monte_carlo,
                                              "plan": plan.describe()})


def _exact_reference(s: _Setting) -> dict:
    """A 1-D member's circuit-free part (:func:`_analyse_exact` reads it): the exact values
    of its rows for the ideal and the smoothed model, the transition laws, the held-minus-
    white noise pairs (:func:`_band`) and the exact laws its figures draw."""
    exp, sizes, plan, thr, tick = s.exp, s.sizes, s.plan, s.thr, s.tick
    m, m_eff = exp.model, exp.mapping().model_effective
    v00 = float(exp.v0[0])
    # no histogram_times: no transition run, stationary rows only
    times = [float(t) for t in exp.histogram_times]
    tick(f"{exp.name}: exact theory")
    obs = C.member_observables(m, v0=v00, times=times)
    stat_obs = [o for o in obs if o.run == C.STATIONARY]
    trans_obs = [o for o in obs if o.run == C.TRANSITION]
    exact = _stationary_theory(exp, m, stat_obs, thr)
    exact_eff = _stationary_theory(exp, m_eff, stat_obs, thr)
    pure_shot = C.model_class(m) == C.SHOT_MEMBER
    laws: dict = {}
    if times:
        exact.update(_transition_theory(exp, m, v00, times, trans_obs, thr))
        laws = dict(zip(times, _transition_laws(exp, m, v00, times, thr)))
        if not pure_shot:
            exact_eff.update(_transition_theory(exp, m_eff, v00, times, trans_obs, thr))
    groups: list[tuple] = [(C.STATIONARY, stat_obs,
                            family.sample_stationary(m, 128, plan.member_band_v0),
                            sizes.stationary_t_end)]
    if times:
        groups.append((C.TRANSITION, trans_obs, v00, max(times)))
    bands = {run: _band(exp, _estimators(exp, run_obs, thr), v0_band, T,
                        128 if np.ndim(v0_band) else 256, plan.member_band,
                        sample_dt=sizes.sample_dt)
             for run, run_obs, v0_band, T in groups}
    # the figures' exact laws
    v, dens, atom = family.stationary_law(m, h=_h(exp) / 2)
    fig: dict = {"v": v, "density": dens, "atom": atom}
    if m.stribeck is not None or m.cubic > 0:
        fig["paper_density"], _ = _paper_law(m, v)
        fig["paper_moments"] = _sm(m.replace(stribeck=None, cubic=0.0))
    if m.shot is None:
        fig["weak_noise"] = weak_noise_law(m, v, dens)
    if times:
        vt = np.linspace(min(v.min(), v00), max(v.max(), v00), 1201)
        fig["propagator"] = {
            "v": vt, "density": family.propagator(m, vt, np.asarray(times), v00, h=_h(exp)),
            "atom": (np.atleast_1d(family.propagator_atom(m, np.asarray(times), v00, h=_h(exp)))
                     if m.shot is not None else np.zeros(len(times)))}
    return {"obs": obs, "exact": exact, "exact_eff": exact_eff, "laws": laws, "bands": bands,
            "figures": fig, "moments": family.stationary_moments(m)}


def _analyse_exact(s: _Setting, runs: MemberRuns, res: MemberAnalysis, pre: dict) -> None:
    """A 1-D member with an exact solver: every row against the exact finite-noise numerics
    of :mod:`analogue.theory.family` (``pre``: :func:`_exact_reference`)."""
    exp, sizes, plan, thr, tick = s.exp, s.sizes, s.plan, s.thr, s.tick
    m, burn, seed, name = exp.model, exp.burn_in, plan.member_circuit, exp.name
    assert runs.stationary is not None   # 1-D members have one
    stat, chk = _analysed(exp, runs.stationary), _analysed(exp, runs.check)
    trans = None if runs.transition is None else _analysed(exp, runs.transition)
    v00 = float(exp.v0[0])
    # no histogram_times: no transition run, stationary rows only
    times = [float(t) for t in exp.histogram_times] if trans is not None else []
    obs = pre["obs"]
    stat_obs = [o for o in obs if o.run == C.STATIONARY]
    trans_obs = [o for o in obs if o.run == C.TRANSITION]
    exact, exact_eff, laws = pre["exact"], pre["exact_eff"], pre["laws"]
    pure_shot = C.model_class(m) == C.SHOT_MEMBER
    integ = _paired(_estimators(exp, stat_obs, thr), chk,
                    _xs_subset(stat, np.arange(CHECK_REPLICAS)))
    bias = exp.mapping().bias
    groups: list[tuple] = [(stat_obs, stat, pre["bands"][C.STATIONARY])]
    if trans is not None:
        groups.append((trans_obs, trans, pre["bands"][C.TRANSITION]))
    for run_obs, ens, band in groups:
        fns = _estimators(exp, run_obs, thr)
        for o in run_obs:
            c, se = _jk(fns[o.label], ens)
            th_model = float(exact[o.label])
            note = o.entry.description
            if pure_shot and o.run == C.TRANSITION:
                # Without Gaussian noise the smoothed model's stuck state is a delta at
                # v = eps atanh(a/Delta), which the interpolated propagator density misses
                # (measured: total mass 0.67 at t = 1, shot.toml); the smoothing acts where the
                # object is stuck, so the stationary law's change stands in (noted in the row)
                smoothing = exact_eff[o.kind] - exact[o.kind] if o.kind in exact_eff else 0.0
                note += "; smoothing term: the stationary law's change at the circuit's epsilon"
            else:
                smoothing = float(exact_eff[o.label]) - th_model
            if o.entry.probability and (o.run == C.TRANSITION or c in (0.0, 1.0)):
                # one sample per replica (transition): binomial; a time average estimated
                # as 0 or 1 still has an error ~ 1/n
                n = ens.replicas
                p = (c * n + 1) / (n + 2)
                se = max(se, math.sqrt(p * (1 - p) / n))
            if o.run == C.TRANSITION:
                assert o.t is not None  # transition observables carry their time
                se = max(se, _null_se(o, laws[o.t], ens.replicas))
            elif o.run == C.STATIONARY and o.label in exact_eff:
                se_null = C.stationary_null_se(o.entry, c, se, float(exact_eff[o.label]))
                if se_null > se:
                    note += ("; SE: the replica jackknife rescaled to the theory's value "
                             "(study.catalogue.stationary_null_se)")
                se = se_null
            b = Budget(smoothing=smoothing, bandwidth=_measured(band, o.label),
                       integration=_measured(integ, o.label) if ens is stat else 0.0,
                       element=C.element_error(o, bias, m, th_model))
            if ens is trans:
                note += "; integration checked on the stationary run only"
            res.comparisons.append(compare(name, o.label, c, se, th_model, "exact", b, note))

    # figure data: histograms and exact laws (computed here: the figures only draw)
    laws_fig = pre["figures"]
    vs = _after(stat, burn).ravel()
    fig = {"v": laws_fig["v"], "density": laws_fig["density"], "atom": laws_fig["atom"],
           "samples": vs, "threshold": thr,
           "atom_measured": float(np.mean(np.abs(vs) < thr)), "label": name}
    if m.stribeck is not None or m.cubic > 0:
        # the paper's law at the same Delta
        fig["paper_density"] = laws_fig["paper_density"]
        fig["paper_label"] = f"paper's law (Delta = {m.delta:g}, no extension)"
        bm = laws_fig["paper_moments"]
        res.facts.update(paper_mean=bm.mean, paper_variance=bm.variance)
    if m.shot is None:
        wnl = laws_fig["weak_noise"]
        fig.update(wnl)
        res.facts.update(weak_noise_l1=wnl["weak_noise_l1"],
                         u_minima=[float(x) for x in wnl["u_minima"]],
                         u_at_minima=[float(x) for x in wnl["u_at_minima"]],
                         u_barrier_tops=[float(x) for x in wnl["u_barrier_tops"]])
    res.figures["stationary"] = fig
    if trans is not None:
        res.figures["propagator"] = {
            "times": times, "v0": v00, **laws_fig["propagator"],
            "samples": [trans.at(t) for t in times], "threshold": thr}
    if m.a != 0:
        tick(f"{name}: work rate function")
        res.figures["rate_function"] = rate_function_data(m, stat, burn)
    sm = pre["moments"]
    res.facts.update(mean=sm.mean, variance=sm.variance, p_zero=sm.p_zero,
                     p_zero_measured=fig["atom_measured"])
    res.provenance = _prov(exp, stat, sizes, {
        "stationary": seed, "transition": plan.member_transition,
        "stationary_v0": plan.member_stationary_v0, "band_v0": plan.member_band_v0,
        "band": plan.member_band, "plan": plan.describe()})


def _monte_carlo_reference(s: _Setting) -> dict:
    """The circuit-free part of a 1-D member without exact theory
    (:func:`_analyse_monte_carlo` reads it): per run (stationary, transition) the Monte Carlo
    of the ideal and of the smoothed model from the circuit's own start states (the stationary
    run's draws, the transition run's v0) and the held-minus-white noise pair (:func:`_band`)."""
    exp, sizes, plan, thr, tick = s.exp, s.sizes, s.plan, s.thr, s.tick
    m, m_eff = exp.model, exp.mapping().model_effective
    v00 = float(exp.v0[0])
    times = [float(t) for t in exp.histogram_times]
    obs = C.member_observables(m, v0=v00, times=times)
    v0_stat = _stationary_start(exp, sizes, plan)   # the stationary run's start states
    tick(f"{exp.name}: Monte Carlo reference ({sizes.mc_replicas} replicas)")
    groups: list[tuple] = [(C.STATIONARY, _resampled(v0_stat, sizes.mc_replicas),
                            sizes.stationary_t_end, _resampled(v0_stat, 128), 128)]
    if times:
        groups.append((C.TRANSITION, v00, max(times), v00, 256))
    out: dict = {}
    for run, v0, T, v0_band, n_band in groups:
        fns = _estimators(exp, [o for o in obs if o.run == run], thr)
        mc, mc_eff = (monte_carlo_reference(model, v0=v0, t_end=T, replicas=sizes.mc_replicas,
                                            seed=plan.member_monte_carlo,
                                            sample_dt=sizes.sample_dt) for model in (m, m_eff))
        out[run] = (mc, mc_eff, _band(exp, fns, v0_band, T, n_band, plan.member_band,
                                      sample_dt=sizes.sample_dt))
    return out


def _analyse_monte_carlo(s: _Setting, runs: MemberRuns, res: MemberAnalysis,
                         pre: dict) -> None:
    """A 1-D member without exact theory (coloured noise, catalogue.MONTE_CARLO_MEMBER): every
    row against the Monte Carlo of the same model (``pre``: :func:`_monte_carlo_reference`, from the
    circuit's own start states: the stationary run's draws, the transition run's v0).  SE: the
    circuit's and the Monte Carlo's replica jackknives in quadrature; smoothing: the Monte
    Carlo at the circuit's epsilon minus the reference on the same noise (paired); bandwidth:
    the held-input minus white-input Monte Carlo on common increments (:func:`_band`);
    integration: the stationary run's first two decks re-run 100x tighter; element: the catalogue's
    terms."""
    exp, sizes, plan, thr = s.exp, s.sizes, s.plan, s.thr
    m, name = exp.model, exp.name
    assert runs.stationary is not None   # 1-D members have one
    stat, chk = _analysed(exp, runs.stationary), _analysed(exp, runs.check)
    trans = None if runs.transition is None else _analysed(exp, runs.transition)
    v00 = float(exp.v0[0])
    times = [float(t) for t in exp.histogram_times] if trans is not None else []
    obs = C.member_observables(m, v0=v00, times=times)
    stat_obs = [o for o in obs if o.run == C.STATIONARY]
    trans_obs = [o for o in obs if o.run == C.TRANSITION]
    integ = _paired(_estimators(exp, stat_obs, thr), chk,
                    _xs_subset(stat, np.arange(CHECK_REPLICAS)))
    bias = exp.mapping().bias
    groups: list[tuple] = [(stat_obs, stat, *pre[C.STATIONARY])]
    if trans is not None:
        groups.append((trans_obs, trans, *pre[C.TRANSITION]))
    stationary: dict = {}
    for run_obs, ens, mc, mc_eff, band in groups:
        fns = _estimators(exp, run_obs, thr)
        for o in run_obs:
            c, se = _jk(fns[o.label], ens)
            ref, se_r = _jk(fns[o.label], mc)
            se = math.hypot(se, se_r)
            if o.entry.probability and (o.run == C.TRANSITION or c in (0.0, 1.0)):
                n = ens.replicas   # as the exact members: an estimate of 0 or 1 still errs
                p = (c * n + 1) / (n + 2)
                se = max(se, math.sqrt(p * (1 - p) / n))
            b = Budget(smoothing=fns[o.label](mc_eff) - ref, bandwidth=_measured(band, o.label),
                       integration=_measured(integ, o.label) if ens is stat else 0.0,
                       element=C.element_error(o, bias, m, ref))
            note = (f"reference: Monte Carlo ({sizes.mc_replicas} replicas, the circuit's start "
                    "states; no exact theory for this noise); SE = circuit and Monte Carlo SEs "
                    "in quadrature. " + o.entry.description)
            if ens is trans:
                note += "; integration checked on the stationary run only"
            res.comparisons.append(compare(name, o.label, c, se, ref, "exact", b, note))
            if ens is stat:
                stationary[o.label] = ref
        if ens is stat:
            # figure data: the circuit's and the Monte Carlo's stationary histograms
            vs, vm = _after(stat, exp.burn_in).ravel(), _after(mc, exp.burn_in).ravel()
            edges = np.linspace(min(vs.min(), vm.min()), max(vs.max(), vm.max()), 122)
            dens, _ = np.histogram(vm, bins=edges, density=True)
            res.figures["stationary"] = {
                "v": 0.5 * (edges[1:] + edges[:-1]), "density": dens, "atom": 0.0,
                "samples": vs, "threshold": thr, "label": name,
                "atom_measured": float(np.mean(np.abs(vs) < thr)),
                "reference_label": f"Monte Carlo ({vm.size} samples)"}
    white = family.stationary_moments(m.replace(noise=None))   # white noise, the same gamma
    res.facts.update(mc_mean=stationary["mean v"], mc_variance=stationary["var v"],
                     white_mean=white.mean, white_variance=white.variance,
                     mc_replicas=sizes.mc_replicas,
                     closed_form_variance=m.noise_kind.closed_form_variance(m))
    res.provenance = _prov(exp, stat, sizes, {
        "stationary": plan.member_circuit, "transition": plan.member_transition,
        "stationary_v0": plan.member_stationary_v0, "monte_carlo": plan.member_monte_carlo,
        "band": plan.member_band, "plan": plan.describe()})


def monte_carlo_reference(model: Model, *, v0, t_end: float, replicas: int, seed: int,
                          sample_dt: float) -> Ensemble:
    """The Monte Carlo reference of a member without exact theory
    (:func:`analogue.montecarlo.simulate_sde`, seeded), with the analysis' ``meta`` keys."""
    mc = simulate_sde(model, v0=v0, t_end=t_end, replicas=replicas, seed=seed,
                      sample_dt=sample_dt)
    mc.meta["_x0"], mc.meta["_model_eff"] = model.x0, model
    return mc


def _resampled(v0: np.ndarray, n: int) -> np.ndarray:
    """``n`` start states cycling through the circuit's ``v0`` (the reference starts where
    the circuit started)."""
    return np.resize(np.asarray(v0, float), n)


# the analysis of each member class (catalogue.model_class); the others: _analyse_exact
_ANALYSES: dict[str, Callable[[_Setting, MemberRuns, MemberAnalysis, dict], None]] = {
    C.SPRING_MEMBER: _analyse_spring, C.MONTE_CARLO_MEMBER: _analyse_monte_carlo}
# ... and its circuit-free part (theory, Monte Carlo references, noise pairs), which runs
# beside the circuit runs; the others: _exact_reference
_REFERENCES: dict[str, Callable[[_Setting], dict]] = {
    C.SPRING_MEMBER: _spring_reference, C.MONTE_CARLO_MEMBER: _monte_carlo_reference}



def weak_noise_law(m: Model, v: np.ndarray, exact: np.ndarray) -> dict:
    """The weak-noise stationary law of a 1-D Gaussian member on the grid ``v``:
    ``exp(-gamma U)/Z`` from the quasi-potential (:func:`analogue.theory.weak_noise_family.
    quasi_potential`, eq. (6) with the generalised U; Z by the trapezoid on ``v``), its L1
    distance to the ``exact`` law (exp(-gamma U) is exact at every gamma for these members,
    and :func:`analogue.theory.family.stationary_law` is exp(-gamma U)/Z with the exact Z: the
    L1 is the trapezoid's normalisation error here, measured 4.8e-7 for circuits/cubic.toml,
    3.3e-5 for circuits/stribeck.toml), the local minima of U on the grid
    (where the law concentrates as gamma -> inf; the kink's cusp at v = 0 is one when sticking
    is stable) and the barriers of U between neighbouring minima (the weak-noise escape costs:
    the hopping rate goes like exp(-gamma barrier))."""
    u = quasi_potential(m, v)
    wn = np.exp(-m.gamma * u)
    wn = wn / np.trapezoid(wn, v)
    i = np.flatnonzero((u[1:-1] < u[:-2]) & (u[1:-1] <= u[2:])) + 1
    tops = [float(u[a:b + 1].max()) for a, b in zip(i[:-1], i[1:])]
    return {"weak_noise_density": wn, "weak_noise_l1": float(np.trapezoid(np.abs(exact - wn), v)),
            "u_minima": v[i], "u_at_minima": u[i], "u_barrier_tops": np.asarray(tops)}


def rate_function_data(m: Model, stat: Ensemble, burn: float, tau: float | None = None) -> dict:
    """Figure data of a 1-D member's work rate function (a != 0): the exact rate function on a
    grid of w, the paper's model where it is meaningful, the large-w asymptote with one-sided
    kicks, and the finite-tau estimate from the stationary ensemble ``stat``.

    Scaling (:mod:`analogue.theory.family`): ``I(w) = (1/gamma) sup_k [k w - lambda(k)]`` when
    gamma is finite (the paper's), ``J(w) = sup_k [k w - lambda(k)]`` with
    ``P_tau(w) ~ exp(-tau J)`` when gamma = inf (pure shot noise); the circuit's estimate
    ``-ln P_tau(w)/(tau scale)`` uses the same ``scale`` (gamma, or 1).  ``tau``: the circuit's work window
    (default :func:`work_tau`, 4 tau_m).

    The w grid (13 points) is centred on <w> with half-width max(1.5 |<w>|, 3 sd_tau, the
    circuit's farthest point), sd_tau = |F| sqrt(2 D_x / tau) the spread of the finite-tau
    work rate (Green-Kubo D_x of the exact law): ``<w> (-0.5 .. 2.5)`` alone collapsed onto
    a point when <w> ~ 0 (stick regime, small a) while the circuit's estimate spread over the
    whole work distribution.  circuits/cubic.toml keeps its grid (1.5 <w> = 1.53 > 3 sd_tau
    = 0.44)."""
    tau = work_tau(m) if tau is None else checks.positive("tau", tau)
    pure_shot = m.shot is not None and not math.isfinite(m.gamma)
    scale = m.gamma if math.isfinite(m.gamma) else 1.0
    sm = family.stationary_moments(m)
    mu = m.force * sm.mean
    edge = family.work_edge(m)
    # the circuit's finite-tau estimate -ln P_tau(w)/(tau scale), shifted to min 0
    ws = work_rate_samples(stat, tau, m.force, burn_in=burn).ravel()
    cnt, edges = np.histogram(ws, bins=25)
    keep = cnt >= 10
    dens = cnt / (ws.size * np.diff(edges))
    est = -np.log(dens[keep]) / (tau * scale)
    w_circ, rate_circ = 0.5 * (edges[1:] + edges[:-1])[keep], est - est.min()
    if edge is not None:
        # one-sided pure shot noise: w has a lower edge F v_edge (no kick: J = rate there,
        # +inf below); the grid starts on it and reaches 4 <w> - 3 edge (circuits/shot.toml:
        # edge 0, <w> = 0.0625, 13 points: 3.6 CPU-s on the shared machine)
        w = edge + (mu - edge) * np.linspace(0.0, 4.0, 13)
    else:
        sd_tau = abs(m.force) * math.sqrt(2.0 * max(sm.diffusion, 0.0) / tau)
        half = max(1.5 * abs(mu), 3.0 * sd_tau)
        if w_circ.size:   # and wide enough to hold the circuit's points
            half = max(half, float(np.max(np.abs(w_circ - mu))))
        w = mu + half * np.linspace(-1.0, 1.0, 13)
    rf: dict = {"w": w, "member": family.rate_function(m, w), "mean": mu, "scale": scale,
                "pure_shot": pure_shot, "edge": edge,
                "ylabel": "J(w)" if pure_shot else "I(w)"}
    if m.shot is not None:
        rf["rate"] = m.shot.rate
    if not pure_shot:
        # the paper's model at the same Delta, a, gamma (with pure shot noise there is no
        # paper's curve at the same gamma = inf: the paper's I needs Gaussian noise)
        base = m.replace(stribeck=None, cubic=0.0, shot=None)
        rf["paper"] = _rf(base, w)
        rf["paper_label"] = ("paper's model, same Delta and gamma (no kicks)"
                             if m.shot is not None else "paper's model, same Delta")
    if m.shot is not None and not m.shot.two_sided and m.cubic == 0:
        # J(w) = k_pole w - 2 sqrt(rate k_pole w) + O(1) (family.rate_function_asymptote): the
        # O(1) is matched at the largest w of the grid and the form drawn over the grid's
        # upper half and beyond (it holds for k_pole w >> 1: circuits/shot.toml reaches
        # k_pole w = 2.5 on the grid, where J's slope is 4.3 against k_pole = 10)
        k_pole, rate = family.rate_function_asymptote(m)
        if k_pole * w[-1] > 0:
            wa = np.linspace(float(w[6]), float(w[-1] + 0.5 * (w[-1] - w[0])), 60)
            form = (k_pole * wa - 2.0 * np.sqrt(rate * k_pole * wa)) / scale
            top = (k_pole * w[-1] - 2.0 * math.sqrt(rate * k_pole * w[-1])) / scale
            rf.update(k_pole=k_pole, w_asymptote=wa,
                      asymptote=form + float(rf["member"][-1]) - top)
    rf.update(w_circuit=w_circ, rate_circuit=rate_circ, tau=tau)
    return rf


def _prov(exp: Experiment, ens: Ensemble, sizes: MemberSizes, seeds: dict) -> dict:
    return {"experiment": exp.name, "parameters": exp.model.as_dict(),
            "model_effective": exp.mapping().model_effective.as_dict(),
            "circuit_spec": exp.spec.as_dict(), "circuit_defaults": exp.mapping().chosen,
            "seeds": seeds,
            "replicas": {"stationary": sizes.stationary_replicas,
                         "transition": sizes.transition_replicas, "monte_carlo": sizes.mc_replicas},
            "ngspice_version": ens.meta.get("ngspice_version"),
            "deck_hashes": {"main": ens.meta.get("deck_sha256")}}
