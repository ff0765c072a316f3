"""Replicas per deck chosen by a cost model with measured step counts (issue 10).

Replicas in one deck share every simulator time step, so each replica's crossing of the diode
kink shortens the step for all of them: the time points per noise hold grow with the deck size
``r`` (stick deck, reltol 1e-4: 7.7 at r = 1, 16.6 at 16, 22 at 64), at a rate set by how
often the paths cross v = 0, which depends on the model.  Against that, every deck costs a
process start-up (and, in the model's form, a per-time-point overhead shared by its replicas,
measured as negligible at 4 or more replicas: below).  The model of the
wall time of one deck of ``r`` replicas over ``H`` holds is

    T(r) = START_S + H p(r) (POINT_S + REPLICA_POINT_S r),

``p(r)`` the time points per hold, measured per model by a short calibration run (decks of
each size in ``CAL_SIZES`` = 4, 16, 32 for ``CAL_HOLDS`` holds, same seed; the counts come from the raw
files and do not depend on the machine's load, so the choice is reproducible), interpolated
linearly in log r.  A job of N replicas on W workers takes about ``ceil(ceil(N/r)/W) T(r)``;
the chosen size minimises that over the allowed sizes ``SIZES`` within ``bounds``, for
``W = NOTIONAL_WORKERS`` whatever the machine (the split sets the seeds: below).

The constants are fitted to CPU seconds (ngspice children, user + sys) of 32 replicas x 2000
holds in decks of 4, 8, 16 and 32, stick and work models, trap reltol 1e-4, two repeats
(``benchmarks/bench_deck_cost.py``; shared machine at load ~10, which inflates both alike, and
only their ratio matters): 51 ms per deck (process start-up, deck read, raw write) and 1.61 us
per replica-point; a cost per point shared by the replicas was not resolvable (the
three-parameter fit put it at -7 us), so it is 0.  The earlier constants (4.9 us per point
plus 0.88 us per replica-point, extrapolated from one-replica decks) made a replica-point in
a deck of 4 cost twice what it costs in a deck of 32; measured, it costs the same, and the
smaller decks win by their fewer time points per hold (work model: 1.97 / 1.68 s CPU at 32 per
deck, 1.35 at 8, 1.33 at 4).  ``benchmarks/bench_circuit.py --ceiling`` prints the predicted job
times next to the measured ones.

The deck size changes which noise drives which replica (the deck seeds), so it changes the
numbers like a different seed would; it is recorded in ``meta["deck_size"]``.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .. import checks
from ..model import Model
from .decks import _default_sample_dt, run_ensemble
from .mapping import map_model
from .runner import Runner
from .tolerances import RunDecks, at_once, calibration_runner, one_at_a_time, require_run

__all__ = [
    "DEFAULT_BOUNDS",
    "DEFAULT_REPLICAS_PER_DECK",
    "MIN_CALIBRATED_REPLICA_HOLDS",
    "NOTIONAL_WORKERS",
    "SIZES",
    "DeckSizeChoice",
    "choose_deck_size",
    "job_time",
    "points_per_hold",
]

START_S = 0.051
POINT_S = 0.0
REPLICA_POINT_S = 1.61e-6
# 64 left out: the point counts miss that Newton iterations per point grow with r as well (any
# replica not converged costs all of them another iteration); measured with the stick deck
# (trap, reltol 1e-4, one process, load ~11): 73-74 us per replica-hold at 16, 65-85 at 32,
# 92-126 at 64, where the model put 64 level with 32.
SIZES = (4, 8, 16, 32)
DEFAULT_BOUNDS = (4, 32)
CAL_SIZES = (4, 16, 32)
CAL_HOLDS = 300
CAL_SEED = 20261123
# The size every deck had before issue 10 (measured optimum of the stick deck at reltol 1e-4);
# used for runs too small to pay for a calibration (sum CAL_SIZES x CAL_HOLDS = 1.6e4
# replica-holds).
DEFAULT_REPLICAS_PER_DECK = 16
MIN_CALIBRATED_REPLICA_HOLDS = 250_000
# The worker count of the cost model.  The deck size sets the deck seeds, so it must not
# depend on the machine (issue 19: --workers 1 chose stationary decks of 32, --workers 2 of 4,
# and the arrays differed by up to 0.975): every run is split as if for 2 processes, the core
# count of the machine the published numbers were made on and of CI, so those numbers stay
# as they were.  More cores still help: a split for 2 has at least 2 decks per round, and
# the sizes it picks (4-16 on the shipped experiments) give many decks to share out.
NOTIONAL_WORKERS = 2


@dataclass(frozen=True)
class DeckSizeChoice:
    replicas_per_deck: int
    source: str                     # "user", "measured"
    points_per_hold: dict | None = None   # calibration size -> time points per hold
    predicted_s: dict | None = None       # size -> predicted job time (s)

    def as_dict(self) -> dict:
        d = {"replicas_per_deck": self.replicas_per_deck, "source": self.source}
        if self.points_per_hold:
            d["points_per_hold"] = {str(k): v for k, v in self.points_per_hold.items()}
            d["predicted_job_s"] = {str(k): v for k, v in (self.predicted_s or {}).items()}
        return d


def points_per_hold(measured: dict, r: float) -> float:
    """p(r): linear interpolation in log r of the measured points per hold (constant beyond
    the measured sizes)."""
    sizes = np.array(sorted(measured), dtype=float)
    vals = np.array([measured[k] for k in sorted(measured)], dtype=float)
    return float(np.interp(math.log(r), np.log(sizes), vals))


def job_time(r: int, replicas: int, holds: float, workers: int, measured: dict) -> float:
    """Predicted wall time (s) of ``replicas`` replicas in decks of at most ``r`` on
    ``workers`` processes."""
    n_decks = -(-replicas // r)
    r_eff = replicas / n_decks
    deck = START_S + holds * points_per_hold(measured, r_eff) * (POINT_S + REPLICA_POINT_S * r_eff)
    return -(-n_decks // workers) * deck


def _check_bounds(bounds) -> tuple[int, int]:
    try:
        lo, hi = bounds
    except (TypeError, ValueError):
        raise ValueError(f"bounds must be a pair (lo, hi) of integers, got {bounds!r}") from None
    for b in (lo, hi):
        if isinstance(b, bool) or not isinstance(b, int) or b < 1:
            raise ValueError(f"bounds must be integers >= 1, got {bounds!r}")
    if lo > hi:
        raise ValueError(f"bounds must have lo <= hi, got {bounds!r}")
    return lo, hi


def _calibrate(model: Model, spec, *, runner: Runner, run: RunDecks | None = None) -> dict:
    """Points per hold for each of ``CAL_SIZES``, measured with ``runner`` through
    :func:`analogue.circuit.decks.run_ensemble` (or the legacy ``run``)."""
    mapping = map_model(model, spec)
    t_cal = CAL_HOLDS * mapping.noise_dt

    def points(r: int) -> float:
        # (shot noise, springs, gamma = inf: no exp(-gamma U) sampler; start at rest on the
        # attractor, as the tolerance calibration does)
        v0 = "stationary" if model.is_gradient else float(model.attractor)
        if run is not None:
            kw = {"v0": v0, "t_end": t_cal, "replicas": r, "seed": CAL_SEED,
                  "replicas_per_deck": r, "store": runner.store, "progress": False,
                  "workers": runner.workers, "timeout": runner.timeout}
            if runner.scheduler is not None:
                kw["scheduler"] = runner.scheduler
            if runner.executor is not None:
                kw["executor"] = runner.executor
            ens = run(model, circuit=spec, **kw)
        else:
            ens = run_ensemble(model, spec, v0=v0, t_end=t_cal, replicas=r, seed=CAL_SEED,
                               sample_dt=_default_sample_dt(model, t_cal),
                               runner=runner.replace(replicas_per_deck=r))
        pts = ens.meta.get("deck_raw_points") or [None]
        if pts[0] is None:
            raise RuntimeError("deck-size calibration: the run did not record its time points")
        return float(pts[0]) / CAL_HOLDS
    # the sizes at once where the pool is shared (tolerances.at_once)
    counts = at_once([functools.partial(points, r) for r in CAL_SIZES], runner)
    return dict(zip(CAL_SIZES, counts))


_MEMO: dict = {}


def choose_deck_size(model: Model, spec, *, replicas: int, t_end: float, workers: int,
                     bounds=DEFAULT_BOUNDS, store=None, scheduler=None, executor=None,
                     timeout=None, measured: dict | None = None,
                     min_replica_holds: int = 0, run: RunDecks | None = None,
                     runner: Runner | None = None) -> DeckSizeChoice:
    """Replicas per deck for a run of ``replicas`` paths of length ``t_end``; ``spec`` must
    have its tolerances set (:mod:`analogue.circuit.tolerances`).  The cost model assumes
    :data:`NOTIONAL_WORKERS` processes whatever ``workers`` is (the processes that run the
    calibration), so the split, and with it every deck's seed, is a function of the run
    alone, the same on every machine.
    ``measured``: points per hold by deck size, skipping the calibration (tests).  Runs of
    fewer than ``min_replica_holds`` replica-holds get ``DEFAULT_REPLICAS_PER_DECK`` (within
    the bounds) without a calibration (source "default").  ``runner`` (or the run options
    ``store``, ``scheduler``, ``executor``, ``timeout`` of earlier versions) and ``run``: how
    the calibration's decks run, as for
    :func:`analogue.circuit.tolerances.choose_tolerances` (through
    :func:`analogue.circuit.decks.run_ensemble`, never :func:`analogue.simulate`; ``run`` is
    deprecated: DeprecationWarning)."""
    run = require_run(run, "choose_deck_size")
    lo, hi = _check_bounds(bounds)
    replicas = checks.integer("replicas", replicas, minimum=1)
    workers = checks.integer("workers", workers, minimum=1)
    allowed = [s for s in SIZES if lo <= s <= hi] or [lo, hi]
    if replicas <= lo:
        return DeckSizeChoice(lo, "measured")
    holds = t_end / map_model(model, spec).noise_dt
    if measured is None and replicas * holds < min_replica_holds:
        return DeckSizeChoice(min(max(DEFAULT_REPLICAS_PER_DECK, lo), hi), "default")
    if measured is None:
        key = (repr(model.as_dict()), repr(spec))
        with one_at_a_time(("deck size", key)):   # (two runs at once: calibrated once)
            if key not in _MEMO:
                cal = calibration_runner("choose_deck_size", runner, store=store,
                                         scheduler=scheduler, executor=executor,
                                         timeout=timeout)
                if cal.workers is None:
                    cal = cal.replace(workers=workers)
                _MEMO[key] = _calibrate(model, spec, runner=cal, run=run)
        measured = _MEMO[key]
    pred = {r: job_time(r, replicas, holds, NOTIONAL_WORKERS, measured) for r in allowed}
    best = min(allowed, key=lambda r: (round(pred[r], 6), -r))
    return DeckSizeChoice(best, "measured", dict(measured), pred)
