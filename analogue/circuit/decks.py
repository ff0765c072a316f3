"""Run circuit decks: the level below :func:`analogue.simulate`, which both it and the
calibrations (:mod:`analogue.circuit.tolerances`, :mod:`analogue.circuit.deck_size`) use, so
that choosing tolerances and deck sizes never calls :func:`analogue.simulate` back (issue 20).

:func:`run_ensemble` runs one fully specified request (a model, a circuit spec with its
tolerances set, a deck size): the replicas are split into decks; deck ``b`` gets an ngspice
seed derived from ``(seed, b)`` with numpy's SeedSequence, so the arrays depend only on the
arguments and never on which worker ran which deck or in what order.  :func:`run_decks` runs
a list of decks (any :class:`Deck`: the model's, the board's): each as its own ``ngspice -b
-r`` process (:func:`analogue.circuit.ngspice.run_deck`), its raw output resampled onto the
requested uniform grid, converted to model units with the deck's factors and stored in the
content-addressed run store (:mod:`analogue.circuit.store`) as soon as it finishes.

How they run is a :class:`~analogue.circuit.runner.Runner`.  Locally, ``workers`` ngspice
processes run at once (a thread per process is enough: the work happens inside ngspice, and
the numpy resampling releases the GIL); with a Dask ``scheduler`` address the same batch
function runs on a Dask cluster through ``client.get_executor()``; with an ``executor`` any
``concurrent.futures.Executor`` or a ``distributed.Client`` the caller owns runs it (the way
emcee takes ``pool=``).  Results are identical either way.
"""
from __future__ import annotations

import concurrent.futures as cf
import json
import logging
import math
import sys
import time as _time
import uuid
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, is_dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from .. import checks
from ..cores import limit_worker_threads, usable_cpus
from ..ensemble import Ensemble
from ..model import Model
from ..theory.exact import sample_stationary
from . import limits
from . import ngspice as _ng
from .mapping import CircuitSpec, map_model
from .netlist import build_deck
from .runner import (
    DEFAULT_TIMEOUT,
    DeckProgress,
    Runner,
    check_executor,
    check_scheduler,
    is_client,
    progress_mode,
)
from .store import SCHEMA_VERSION, batch_key, open_store
from .store_index import note_keys

if TYPE_CHECKING:
    from os import PathLike

    from numpy.typing import ArrayLike

__all__ = [
    "BatchTask",
    "Deck",
    "deck_seeds",
    "initial_velocities",
    "run_batch",
    "run_decks",
    "run_ensemble",
    "time_grid",
    "value_limits",
]

#: the name a run_decks call without one shows on its progress bar or lines
DEFAULT_LABEL = "ngspice decks"
log = logging.getLogger("analogue.circuit.simulate")  # the name its messages always had
store_log = logging.getLogger("analogue.circuit.store")

# ngspice parses `.options seed=` as a C int; seeds above 2**31 - 1 are ignored with a warning.
_SEED_MAX = 2**31 - 1


def _grid_intervals(t_end: float, sample_dt: float, dt_label: str = "") -> int:
    """Number of sample intervals t_end/sample_dt, refused (one line, naming both) when it is
    not a finite count that fits in memory: checked before any array is made."""
    n = t_end / sample_dt
    mem, why = limits.memory_limit()
    max_points = mem / 8.0  # the grid alone, one float64 per point
    if not math.isfinite(n) or n + 1 > max_points:
        raise ValueError(f"t_end={t_end:g} with sample_dt={sample_dt:g}{dt_label} gives "
                         f"{limits.format_count(n + 1)} time points; at most "
                         f"{limits.format_count(max_points)} fit in the memory "
                         f"limit of {limits.format_bytes(mem)} ({why}); reduce t_end or raise "
                         f"sample_dt")
    return round(n)


def time_grid(t_end, sample_dt) -> np.ndarray:
    """Uniform grid ``0, sample_dt, ..., t_end`` (model units); t_end must be a whole number of
    sample intervals (to 1e-6 relative), and the grid must fit in memory (see
    :mod:`analogue.circuit.limits`)."""
    t_end = checks.positive("t_end", t_end)
    sample_dt = checks.positive("sample_dt", sample_dt)
    if sample_dt > t_end:
        raise ValueError(f"sample_dt must be <= t_end (= {t_end!r}), got {sample_dt!r}")
    n = _grid_intervals(t_end, sample_dt)
    if abs(n * sample_dt - t_end) > 1e-6 * t_end:
        raise ValueError(f"t_end must be a whole number of sample_dt intervals; t_end/sample_dt "
                         f"= {t_end / sample_dt!r} (choose e.g. sample_dt = {t_end / max(n, 1)!r})")
    return np.arange(n + 1) * (t_end / n)


def deck_seeds(seed: int, n_decks: int) -> list[int]:
    """ngspice seeds (1 .. 2**31-1) of decks 0..n_decks-1, from SeedSequence(seed, spawn_key
    (1, b)): a fixed function of (seed, b), independent of scheduling."""
    seed = checks.integer("seed", seed, minimum=0)
    out = []
    for b in range(n_decks):
        word = np.random.SeedSequence(seed, spawn_key=(1, b)).generate_state(1, np.uint32)[0]
        out.append(int(word) % _SEED_MAX + 1)
    return out


def _sample_stationary(model: Model, size: int, rng: np.random.Generator) -> np.ndarray:
    """Samples from p_s (eq. (6)) with the exact sampler
    (:func:`analogue.theory.exact.sample_stationary`)."""
    # shot noise samples the sgn law's (analogue.variants.noise.Shot.sampled_model)
    model = model.noise_kind.sampled_model(model)
    return np.asarray(sample_stationary(model, size, seed=rng), dtype=float)


def initial_velocities(model: Model, v0, replicas: int, seed: int) -> np.ndarray:
    """``v0`` as a (replicas,) array in model units; "stationary" draws from the stationary law
    of ``model`` with SeedSequence(seed, spawn_key=(0,))."""
    if isinstance(v0, str):
        if v0 != "stationary":
            raise ValueError(f"v0 must be a number, an array of shape (replicas,) or "
                             f"'stationary', got {v0!r}")
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(0,)))
        return _sample_stationary(model, replicas, rng)
    try:
        arr = np.asarray(v0, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"v0 must be a number, an array of shape (replicas,) or 'stationary', "
                         f"got {v0!r}") from None
    if arr.ndim == 0:
        arr = np.full(replicas, float(arr))
    if arr.shape != (replicas,):
        raise ValueError(f"v0 must be a number or an array of shape (replicas,) = ({replicas},), "
                         f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("v0 must be finite")
    return arr


# ------------------------------------------------------------------------------ batches
@runtime_checkable
class Deck(Protocol):
    """What :func:`run_decks` needs of a deck (:class:`analogue.circuit.netlist.Deck`,
    :class:`analogue.board.netlist.BoardDeck`, or a hand-written one in a test).

    ``text``: the complete ngspice netlist; ``vectors``: raw-file vector names per replica,
    ``{"v": [...], "x": [...] or None, "noise": [...] or None, "x_spring": [...] (optional)}``;
    model value = raw value * ``to_model_v`` (``to_model_x``); model time = raw time /
    ``time_scale``; ``replicas``: how many replicas the deck holds.  Optional attributes, read
    when present: ``noise_dt`` and ``to_model_noise`` (the held noise the deck records) and
    ``x_spring_initial`` (the spring position at t = 0), ``noise_files`` (paths of the files
    the deck reads, named in it by their file name: see
    :func:`analogue.circuit.ngspice.run_deck`).
    """

    @property
    def text(self) -> str: ...
    @property
    def vectors(self) -> Mapping[str, Any]: ...
    @property
    def to_model_v(self) -> float: ...
    @property
    def to_model_x(self) -> float: ...
    @property
    def time_scale(self) -> float: ...
    @property
    def replicas(self) -> int: ...


@dataclass(frozen=True)
class BatchTask:
    """Everything one worker needs to run one deck and return arrays in model units.
    Picklable (sent to Dask workers)."""

    index: int
    text: str
    v_names: tuple
    x_names: tuple | None
    to_model_v: float
    to_model_x: float
    time_scale: float
    times: np.ndarray = field(repr=False)   # model units
    v0: np.ndarray = field(repr=False)      # model units, (replicas,)
    timeout: float = DEFAULT_TIMEOUT
    group: str | None = None                # run id: lets the caller stop its processes
    noise_names: tuple | None = None        # held-noise vectors, if the deck records them
    noise_dt: float = 0.0                   # their hold time (model units)
    to_model_noise: float = 1.0
    xs_names: tuple | None = None           # spring: position read back from the inductor
    xs_initial: float = 0.0                 # its value at t = 0 (x0, model units)
    files: tuple = ()                       # paths of files the deck reads (DAC tables)
    limits: tuple = ()                      # (array name, largest physical |value|) pairs


def held_values(t_raw, rows, t_end, hold) -> np.ndarray:
    """The values of piecewise-constant signals on each hold interval [k h, (k+1) h), k < t_end/h:
    read at the last simulator point at or before the interval's midpoint (no interpolation
    across a jump).  ``rows``: (n, len(t_raw)); returns (n, n_hold)."""
    n_hold = int(math.floor(t_end / hold + 1e-9))
    mid = (np.arange(n_hold) + 0.5) * hold
    idx = np.clip(np.searchsorted(t_raw, mid, side="right") - 1, 0, len(t_raw) - 1)
    return rows[:, idx]


_WORKER_LIMITED = False


def _limit_dask_worker_threads() -> None:
    """On a Dask worker process (once per process): OpenMP/BLAS to one thread
    (:func:`analogue.cores.limit_worker_threads`), since the worker runs decks beside the
    other workers' ngspice processes on the same machine.  Nothing in the caller's own
    process (local runs use threads there, and its theory thread sets its own limit)."""
    global _WORKER_LIMITED
    if _WORKER_LIMITED:
        return
    dist = sys.modules.get("distributed")
    if dist is None:
        return
    try:
        dist.get_worker()
    except ValueError:            # not in a Dask worker
        return
    limit_worker_threads()
    _WORKER_LIMITED = True


def run_batch(task: BatchTask) -> dict:
    """Run one deck; return ``{"v": (r, n_t), "x": (r, n_t), "info": {...}}`` in model units,
    plus ``"noise"``: (r, n_hold) the held velocity noise (model units) on each hold interval
    when the deck records it.

    The raw file of a ``uic`` run starts after t = 0: the known initial values (v0, x = 0) are
    prepended before the linear resampling (see :func:`analogue.circuit.ngspice.resample`).
    """
    _limit_dask_worker_threads()
    t_s = task.times * task.time_scale
    res = _ng.run_deck(task.text, timeout=task.timeout, t_stop=float(t_s[-1]), group=task.group,
                       files=task.files)
    v_raw0 = task.v0 / task.to_model_v
    wanted = [*task.v_names, *(task.x_names or ()), *(task.noise_names or ()),
              *(task.xs_names or ())]
    missing = [n for n in wanted if n.lower() not in res.plot.names]
    if missing:
        raise _ng.NgspiceError(f"deck {task.index}: the raw file lacks the vectors "
                               f"{', '.join(missing[:5])} (it holds "
                               f"{', '.join(res.plot.names[:6])}); ngspice's output is not "
                               f"this deck's")
    v = _ng.resample(res.plot, task.v_names, t_s, initial=v_raw0) * task.to_model_v
    if task.x_names:
        x = _ng.resample(res.plot, task.x_names, t_s,
                         initial=np.zeros(len(task.x_names))) * task.to_model_x
    else:
        # No integrator node: integrate v on the simulator's own time points (trapezoid).
        t_raw = res.plot["time"]
        vr = res.plot.columns(task.v_names)
        if t_raw[0] > 0:
            t_raw = np.concatenate([[0.0], t_raw])
            vr = np.hstack([v_raw0[:, None], vr])
        xr = np.concatenate([np.zeros((vr.shape[0], 1)),
                             np.cumsum(0.5 * (vr[:, 1:] + vr[:, :-1]) * np.diff(t_raw), axis=1)],
                            axis=1) * task.to_model_v / task.time_scale
        x = _ng.interp_rows(t_raw, xr, t_s)
    warnings = [ln.strip() for ln in res.stderr.splitlines()
                if ln.strip() and "warning" in ln.lower()]
    info = {"wall_time": res.wall_time, "raw_points": int(res.plot.n_points),
            "ngspice_version": res.version, "warnings": warnings[:20]}
    out: dict[str, Any] = {"v": v, "x": x, "info": info}
    if task.xs_names:
        out["x_spring"] = _ng.resample(res.plot, task.xs_names, t_s,
                                       initial=np.full(len(task.xs_names), task.xs_initial))
    if task.noise_names and task.noise_dt > 0:
        out["noise"] = held_values(res.plot["time"], res.plot.columns(task.noise_names),
                                   float(t_s[-1]), task.noise_dt * task.time_scale) \
            * task.to_model_noise
    for name in ("v", "x", "x_spring", "noise"):
        if name in out and not np.all(np.isfinite(out[name])):
            raise _ng.NgspiceError(f"ngspice exited normally but its {name} vectors hold NaN or "
                                   f"infinite values (deck {task.index}); the circuit diverged")
    return out


def _jsonable(obj):
    """A JSON-safe deep copy (numpy scalars/arrays, dataclasses, tuples, paths...)."""
    def default(o):
        if isinstance(o, np.generic):
            return o.item()
        if isinstance(o, np.ndarray):
            return o.tolist()
        if is_dataclass(o) and not isinstance(o, type):
            return asdict(o)
        return str(o)
    return json.loads(json.dumps(obj, default=default))


def _n_hold(task: BatchTask) -> int:
    """Number of noise hold intervals run_batch records for ``task`` (see held_values)."""
    t_end = float(task.times[-1]) * task.time_scale
    return int(math.floor(t_end / (task.noise_dt * task.time_scale) + 1e-9))


# ------------------------------------------------------------------- result validation
#: the velocity bound sits where the stationary density has fallen by e^-VALUE_LEVEL below
#: its peak (Gaussian noise: sqrt(2 VALUE_LEVEL) = 45 standard deviations): no run of any
#: length reaches it (P ~ e^-1000 per relaxation time).
VALUE_LEVEL = 1000.0
#: the held Gaussian noise (ngspice's trrandom): 40 standard deviations, never drawn
#: (P ~ 1e-349 per sample).
NOISE_SIGMAS = 40.0
#: the circuit realises the model to within a few % (the bias budget of the mapping); a
#: factor 2 on the model's bound is never reached by a working circuit.
VALUE_SAFETY = 2.0


def value_limits(mapping, v0, t_end: float) -> dict[str, float]:
    """Largest |value| (model units) each array of a correct run of ``mapping`` can hold,
    started at ``v0`` and run for ``t_end`` (the physical bound a result is checked against).

    Friction of every family member only dissipates, so the deterministic motion keeps
    ``|v| <= |v0| + tau_m |a|`` (the viscous term wins beyond ``tau_m |a|``) and, with a
    spring, the energy ``v^2/2 + (spring x - a)^2/(2 spring)`` of the start.  The noise adds
    at most its reach ``sqrt(2 VALUE_LEVEL tau_m/gamma)`` (Gaussian) and ``rate tau_m mean +
    VALUE_LEVEL mean`` (shot), as in :func:`analogue.circuit.mapping.velocity_range`.  The
    sum, times VALUE_SAFETY, bounds v; ``|x| <= v_max t_end`` (x is its integral, from 0; the
    spring's position from x0); the held noise stays within NOISE_SIGMAS of its law."""
    model = mapping.model_effective
    v0_max = float(np.max(np.abs(np.asarray(v0, dtype=float)))) if np.size(v0) else 0.0
    reach = v0_max + model.tau_m * abs(model.a) + model.tau_m * model.static_friction
    reach += model.restoring.energy_reach(model)   # 0 without a spring (analogue.variants)
    if math.isfinite(model.gamma):
        reach += math.sqrt(2.0 * VALUE_LEVEL * model.tau_m / model.gamma)
    reach += model.noise_kind.kick_reach(model.tau_m, VALUE_LEVEL)   # 0 without kicks
    # a floor for a circuit that should sit still (no noise, no force, v0 = 0): its numerical
    # noise, far below ngspice's voltage tolerance, in model units
    v_max = VALUE_SAFETY * reach + 1e3 * mapping.vntol / mapping.kappa
    out = {"v": v_max, "x": v_max * t_end}
    if mapping.inductance > 0:
        out["x_spring"] = abs(model.x0) + v_max * t_end
    if mapping.noise_stddev > 0:
        out["noise"] = NOISE_SIGMAS * mapping.noise_stddev
    return out


def _result_problem(task: BatchTask, out: object) -> str | None:
    """Why ``out`` (what a worker returned for ``task``, or the arrays of a stored entry) is
    not a result of the deck (one line), or None: a dict with every array the deck produces,
    floating point, in the right shape, finite, and within the physical limits."""
    if not isinstance(out, Mapping):
        return f"it is {type(out).__name__!s}, not the dict of arrays a deck returns"
    r, n_t = task.v0.shape[0], task.times.size
    need = {"v": (r, n_t), "x": (r, n_t)}
    if task.noise_names and task.noise_dt > 0:
        need["noise"] = (r, _n_hold(task))
    if task.xs_names:
        need["x_spring"] = (r, n_t)
    bounds = dict(task.limits)
    for name, shape in need.items():
        a = out.get(name)
        if a is None:
            return f"array {name!r} is missing"
        if not isinstance(a, np.ndarray) or a.dtype.kind != "f":
            return (f"array {name!r} is {type(a).__name__}"
                    f"{' of ' + str(a.dtype) if isinstance(a, np.ndarray) else ''}, not floats")
        if a.shape != shape:
            return f"array {name!r} has shape {a.shape}, expected {shape}"
        if not np.all(np.isfinite(a)):
            return f"array {name!r} holds NaN or infinite values"
        if name in bounds and a.size:
            worst = float(np.max(np.abs(a)))
            if worst > bounds[name]:
                return (f"array {name!r} reaches |{name}| = {worst:.3g}, beyond the "
                        f"{bounds[name]:.3g} the circuit can physically reach")
    return None


def _entry_problem(task: BatchTask, version: str, arrays: dict, meta: dict) -> str | None:
    """Why a stored entry is not the result of ``task`` (one line), or None: the deck it
    records must be the requested deck, on the same grid and ngspice, with every array this
    deck produces in the right shape (finiteness and the checksum are the store's checks)."""
    if meta.get("deck_text") != task.text:
        return "it records another deck than the one requested"
    if meta.get("ngspice_version") != version or meta.get("schema_version") != SCHEMA_VERSION:
        return "it records another ngspice version or schema"
    if "t" not in arrays:
        return "array 't' is missing"
    if arrays["t"].shape != task.times.shape:
        return f"array 't' has shape {arrays['t'].shape}, expected {task.times.shape}"
    problem = _result_problem(task, arrays)
    if problem is not None:
        return problem
    if not np.array_equal(arrays["t"], task.times):
        return "it was sampled on another time grid"
    return None


def _batch_meta(task: BatchTask, version: str, info: dict) -> dict:
    """Provenance stored with one batch."""
    return {"schema_version": SCHEMA_VERSION, "ngspice_version": version,
            "deck_text": task.text, "deck_index": task.index,
            "vectors": {"v": list(task.v_names),
                        "x": list(task.x_names) if task.x_names else None},
            "to_model_v": task.to_model_v, "to_model_x": task.to_model_x,
            "time_scale": task.time_scale, "info": info}


def _executor(workers: int, scheduler: Any, n_tasks: int, executor: Any = None
              ) -> tuple[cf.Executor, Callable[[], None] | None, Any]:
    """(executor, closer, client): the local thread pool (client None), a Dask cluster by
    address, or the caller's ``executor`` (a ``concurrent.futures.Executor``, or a
    ``distributed.Client`` whose ``get_executor()`` is used).  ``closer`` is None when the
    caller owns the executor: it is neither shut down nor closed here."""
    check_scheduler(scheduler)
    check_executor(executor)
    if executor is not None:
        if is_client(executor):
            return executor.get_executor(), None, executor
        return executor, None, None
    if scheduler is None:
        pool = cf.ThreadPoolExecutor(max_workers=max(1, min(workers, n_tasks)))
        return pool, lambda: pool.shutdown(wait=True), None
    if isinstance(scheduler, str):
        try:
            from distributed import Client
        except ImportError:
            raise RuntimeError("scheduler= needs Dask, which is not installed: "
                               "pip install 'analogue[dask]'") from None
        client = Client(scheduler)
        return client.get_executor(), client.close, client
    return scheduler.get_executor(), None, scheduler  # a Client passed as scheduler=


def _stop_remote(client, group) -> None:
    """Kill the ngspice processes of run ``group`` on every Dask worker (a cancelled Dask
    future does not stop a task that already runs); best effort, never raises."""
    try:
        client.run(_ng.terminate_group, group, on_error="ignore")
    except Exception as exc:  # noqa: BLE001 - the run is failing already; report, go on
        log.warning("analogue: could not stop the ngspice processes on the Dask workers (%s)",
                    " ".join(str(exc).split())[:200])


# How often a wait for decks looks for futures cancelled behind its back (below).
POLL_S = 0.2


def _completed(futures):
    """The futures as they finish, like ``concurrent.futures.as_completed``, but a future
    cancelled by its executor's owner (``shutdown(cancel_futures=True)``, the report's deck
    pool after an interrupt or a failed run) raises CancelledError within ``POLL_S``:
    ``as_completed`` is never woken for those and waited for ever (issue 19: Ctrl-C in
    ``analogue run`` hung the run threads whose decks were all still queued)."""
    pending = set(futures)
    while pending:
        done, pending = cf.wait(pending, timeout=POLL_S, return_when=cf.FIRST_COMPLETED)
        if not done and any(f.cancelled() for f in pending):
            raise cf.CancelledError("the executor cancelled decks of this run (it was shut "
                                    "down or the run was interrupted)")
        yield from done


def _as_runner(runner: Runner | None, store: Any, workers: int | None, scheduler: Any,
               progress: bool | None, timeout: float, label: str, executor: Any) -> Runner:
    """The Runner of a :func:`run_decks` call: ``runner``, or one made of the keywords of
    earlier versions (validated by the Runner), never both."""
    if runner is None:
        return Runner(store=store, workers=workers, scheduler=scheduler, progress=progress,
                      timeout=timeout, label=label, executor=executor)
    if not isinstance(runner, Runner):
        raise TypeError(f"runner must be an analogue.Runner, got {type(runner).__name__}")
    given = [k for k, v, default in (
        ("store", store, None), ("workers", workers, None), ("scheduler", scheduler, None),
        ("progress", progress, None), ("timeout", timeout, DEFAULT_TIMEOUT),
        ("label", label, DEFAULT_LABEL), ("executor", executor, None)) if v != default]
    if given:
        raise TypeError(f"run_decks: pass either runner= or the run keywords "
                        f"({', '.join(given)}), not both")
    return runner if runner.label is not None else runner.replace(label=label)


def _tasks(decks: Sequence[Deck], times: np.ndarray, v0: np.ndarray, *, timeout: float,
           group: str, limits: Mapping[str, float] | None) -> list[BatchTask]:
    """One :class:`BatchTask` per deck, each with its slice of ``v0``."""
    tasks, start = [], 0
    for b, deck in enumerate(decks):
        n = int(deck.replicas)
        vec = deck.vectors
        tasks.append(BatchTask(index=b, text=deck.text, v_names=tuple(vec["v"]),
                               x_names=tuple(vec["x"]) if vec.get("x") else None,
                               to_model_v=float(deck.to_model_v), to_model_x=float(deck.to_model_x),
                               time_scale=float(deck.time_scale), times=times,
                               v0=np.asarray(v0[start:start + n], dtype=float),
                               timeout=timeout, group=group,
                               noise_names=tuple(vec["noise"]) if vec.get("noise") else None,
                               noise_dt=float(getattr(deck, "noise_dt", 0.0) or 0.0),
                               to_model_noise=float(getattr(deck, "to_model_noise", 1.0)),
                               xs_names=tuple(vec["x_spring"]) if vec.get("x_spring") else None,
                               xs_initial=float(getattr(deck, "x_spring_initial", 0.0)),
                               files=tuple(str(f) for f in getattr(deck, "noise_files", ())),
                               limits=tuple(sorted((limits or {}).items()))))
        start += n
    if start != len(v0):
        raise ValueError(f"v0 has {len(v0)} entries but the decks hold {start} replicas")
    return tasks


_ARRAYS = ("v", "x", "noise", "x_spring")


def _from_store(run_store, tasks: list[BatchTask], keys: list[str], version: str) -> list:
    """Each task's stored result (checked against the task; a damaged entry is quarantined
    by the store and counts as missing), or None."""
    results: list = [None] * len(tasks)
    if run_store is None:
        return results
    try:
        run_store.clean_tmp()
    except OSError:
        pass
    for task, key in zip(tasks, keys):
        hit = run_store.get(key, check=lambda a, m, task=task: _entry_problem(task, version, a, m))
        if hit is not None:
            arrays, meta = hit
            results[task.index] = {**{k: arrays[k] for k in _ARRAYS if k in arrays},
                                   "info": meta.get("info", {})}
    return results


def _where(runner: Runner) -> str:
    """"local", "dask" or the executor's type name (for messages and ``info``)."""
    if runner.executor is not None:
        return "dask" if is_client(runner.executor) else type(runner.executor).__name__
    return "local" if runner.scheduler is None else "dask"


def _run_pending(todo: list[BatchTask], results: list, *, runner: Runner, workers: int,
                 run_store, keys: list[str], version: str, group: str) -> None:
    """Run ``todo`` on the runner's executor, checking each result before it is stored (as
    each deck finishes: an interrupted call resumes from the store) and put in ``results``.
    SIGINT/SIGTERM/SIGHUP, a failure or a cancelled deck kill the run's ngspice process
    groups (here or on the Dask workers) and unwind, finished decks kept in the store."""
    where = _where(runner)
    with _ng.interrupt_guard():
        ex, closer, client = _executor(workers, runner.scheduler, len(todo), runner.executor)
        # decks done of the total and the time left (bar, or a line every 30 s)
        assert runner.label is not None
        shown = DeckProgress(progress_mode(runner.progress, len(todo)), runner.label,
                             len(todo), workers)
        futures: dict = {}
        failed = True
        store_ok = True
        try:
            futures = {ex.submit(run_batch, t): t for t in todo}
            for fut in _completed(futures):
                task = futures[fut]
                out = fut.result()
                problem = _result_problem(task, out)
                if problem is None and not isinstance(out.get("info"), Mapping):
                    problem = "it carries no info dict"
                if problem is not None:
                    # checked before it is stored or returned, whoever ran it
                    who = {"local": "ngspice", "dask": "the Dask worker"}.get(
                        where, f"the executor {where}")
                    raise _ng.NgspiceError(f"deck {task.index}: what {who} returned is "
                                           f"not a result of the deck ({problem}); nothing "
                                           f"of it was stored")
                results[task.index] = out
                worker_version = out["info"].get("ngspice_version")
                if run_store is not None and worker_version != version:
                    # The key names this machine's ngspice; a worker with another version
                    # would file its numbers under the wrong key.
                    log.warning("deck %d ran on ngspice %s, not %s: not stored", task.index,
                                worker_version, version)
                elif run_store is not None and store_ok:
                    arrays = {k: out[k] for k in _ARRAYS if k in out}
                    try:
                        run_store.put(keys[task.index], {**arrays, "t": task.times},
                                      _batch_meta(task, version, out["info"]))
                    except OSError as exc:
                        # Read-only or full: the results are still good; say so once.
                        store_ok = False
                        store_log.warning(
                            "analogue: run store %s is not writable (%s): results are "
                            "returned but not stored", run_store.root,
                            " ".join(f"{type(exc).__name__}: {exc}".split())[:200])
                shown.update(out["info"].get("wall_time"))
            failed = False
        finally:
            if failed:
                for f in futures:
                    f.cancel()
                if client is None:
                    _ng.terminate_group(group)  # our own ngspice processes still running
                else:
                    _stop_remote(client, group)  # theirs, on the Dask workers
            shown.close()
            if closer is not None:
                closer()


def run_decks(decks: Sequence[Deck], times: ArrayLike, v0: ArrayLike, *,
              store: str | PathLike[str] | bool | None = None, workers: int | None = None,
              scheduler: str | None = None, progress: bool | None = None,
              timeout: float = DEFAULT_TIMEOUT, records: dict[str, Any] | None = None,
              label: str = DEFAULT_LABEL, executor: Any = None,
              limits: Mapping[str, float] | None = None, runner: Runner | None = None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, dict[str, Any]]:
    """Run (or load from the store) a list of decks and stack their replicas.

    ``runner``: how they run (:class:`~analogue.circuit.runner.Runner`: store, workers,
    scheduler / executor, timeout, progress, label; its ``replicas_per_deck`` is not used:
    the decks are made); the keywords ``store`` ... ``executor`` of earlier versions say the
    same one by one (not together with ``runner``).

    ``decks``: objects with the :class:`Deck` protocol; ``times``: the grid in model units;
    ``v0``: (sum of replicas,) initial velocities in model units (the decks' ``.ic`` values).
    Returns ``(v, x, noise, info)`` with v, x of shape (replicas, n_t), noise (replicas, n_hold)
    the held velocity noise of each hold interval in model units (None if the decks do not
    record it) and info a JSON-safe dict (store keys, per-deck wall times, how many decks came
    from the store).  ``records``: an optional dict, filled with ``"x_spring"`` (replicas, n_t)
    when the decks read the spring's position back from its inductor.  ``label`` names the
    run on its progress bar (or plain line).  ``scheduler`` / ``executor``: where the decks
    run, as for :func:`simulate`.  ``limits``: the largest |value| (model units) each array
    ("v", "x", "noise", "x_spring") of a correct run can hold (:func:`value_limits`).  Every
    result, from ngspice here or from any executor, and every stored entry is checked (shape,
    floats, finite, within ``limits``) before it is stored or returned: anything else is an
    NgspiceError naming the deck, and nothing of it is stored.
    """
    runner = _as_runner(runner, store, workers, scheduler, progress, timeout, label, executor)
    label = runner.label or label
    times = np.asarray(times, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    n_workers = runner.workers if runner.workers is not None else usable_cpus()
    run_store = open_store(runner.store)
    version = _ng.ngspice_version()  # also: a missing ngspice fails here, with the hint
    group = uuid.uuid4().hex
    tasks = _tasks(decks, times, v0, timeout=runner.timeout, group=group, limits=limits)
    keys = [batch_key(t.text, times, version) for t in tasks]
    note_keys(keys)  # an experiment's index (analogue store ls) lists every entry it used

    results = _from_store(run_store, tasks, keys, version)
    from_store = sum(r is not None for r in results)
    todo = [t for t in tasks if results[t.index] is None]
    where = _where(runner)
    log.info("analogue.simulate: %d decks, %d from the store, %d to run (%s, %s)", len(tasks),
             from_store, len(todo), where,
             f"{n_workers} ngspice processes" if where == "local"
             else repr(runner.executor if runner.executor is not None else runner.scheduler))
    t0 = _time.perf_counter()
    if todo:
        _run_pending(todo, results, runner=runner, workers=n_workers, run_store=run_store,
                     keys=keys, version=version, group=group)
    wall = _time.perf_counter() - t0
    if todo:
        log.info("analogue.simulate: %d decks ran in %.2f s", len(todo), wall)
    if progress_mode(runner.progress, len(todo)) == "line":
        print(f"{label}: {len(tasks)} decks ({from_store} from the store, {len(todo)} run) in "
              f"{wall:.1f} s", file=sys.stderr, flush=True)
    v = np.vstack([r["v"] for r in results]) if results else np.empty((0, times.size))
    x = np.vstack([r["x"] for r in results]) if results else np.empty((0, times.size))
    if results and all("noise" in r for r in results):
        noise = np.vstack([r["noise"] for r in results])
    else:
        noise = None
    if records is not None and results and all("x_spring" in r for r in results):
        records["x_spring"] = np.vstack([r["x_spring"] for r in results])
    info = {"ngspice_version": version,
            "store": str(run_store.root) if run_store is not None else None,
            "store_keys": keys, "from_store": from_store, "ran": len(todo), "wall_time": wall,
            "deck_wall_times": [r["info"].get("wall_time") for r in results],
            # the decks run by this call (not from the store): their wall times, for the
            # report's critical path (analogue.study.critical_path)
            "ran_deck_wall_times": [results[t.index]["info"].get("wall_time") for t in todo],
            "deck_raw_points": [r["info"].get("raw_points") for r in results],
            "schema_version": SCHEMA_VERSION, "executor": where}
    return v, x, noise, info



def _default_sample_dt(model: Model, t_end: float) -> float:
    """About tau_m/100, adjusted so that t_end is a whole number of intervals (refused in one
    line when t_end/(tau_m/100) is not a count that fits in memory)."""
    n = _grid_intervals(t_end, model.tau_m / 100.0, " (default: tau_m/100)")
    return t_end / max(1, n)


def _check_sizes(*, mapping, replicas, per_deck, workers, t_end, sample_dt, dt_label,
                 store) -> None:
    """Refuse (ValueError, one line naming the parameters and the limit) a run whose arrays,
    raw files or stored bytes cannot fit: see :mod:`analogue.circuit.limits`."""
    n_times = t_end / sample_dt + 1.0
    noise_dt = getattr(mapping, "noise_dt", None) or 0.0
    n_hold = t_end / noise_dt if noise_dt and math.isfinite(noise_dt) else 0.0
    spec = getattr(mapping, "spec", None)
    max_step = getattr(spec, "max_step", None) or noise_dt
    raw_points = t_end / min(max_step, t_end) if max_step and math.isfinite(max_step) else 0.0
    n_decks = -(-replicas // per_deck)
    est = limits.estimate(replicas=replicas, n_times=n_times, n_hold=n_hold, per_deck=per_deck,
                          workers=workers or usable_cpus(), raw_points=raw_points,
                          n_decks=n_decks)
    what = (f"replicas={replicas} with t_end={t_end:g} and sample_dt={sample_dt:g}{dt_label} "
            f"({limits.format_count(n_times)} time points each)")
    mem, why = limits.memory_limit()
    if est.memory > mem:
        raise ValueError(f"{what} needs at least {limits.format_bytes(est.memory)} of memory, "
                         f"more than the limit of {limits.format_bytes(mem)} ({why}); reduce "
                         f"replicas or t_end, or raise sample_dt")
    run_store = open_store(store)
    if run_store is not None:
        cap, why = limits.store_limit(run_store.root)
        if est.stored > cap:
            raise ValueError(f"the run store {run_store.root} would receive at least "
                             f"{limits.format_bytes(est.stored)} for {what}, more than the limit "
                             f"of {limits.format_bytes(cap)} ({why}); reduce the run, use a store "
                             f"on a larger disk, or pass store=False (results in memory only)")



def default_label(model: Model, v0: Any, seed: int) -> str:
    """The name a run gets on its progress bar or lines: regime, gamma, v0 and seed."""
    where = v0 if isinstance(v0, str) else (f"{float(np.asarray(v0)):g}" if np.ndim(v0) == 0
                                            else "given")
    return f"{model.regime}, gamma={model.gamma:g}, v0={where}, seed {seed}"


def run_ensemble(model: Model, spec: CircuitSpec, *, v0: Any, t_end: float, replicas: int,
                 seed: int, sample_dt: float, runner: Runner, dt_label: str = "",
                 tolerances: Mapping[str, Any] | None = None,
                 deck_size: Mapping[str, Any] | None = None) -> Ensemble:
    """Run ``replicas`` paths of ``model`` in the circuit ``spec`` with nothing left to choose:
    ``spec`` has its tolerances set and ``runner`` its ``replicas_per_deck``.  What
    :func:`analogue.simulate` runs once it has chosen those, and what the calibrations
    that choose them run; the arguments are :func:`analogue.simulate`'s, checked by it (a
    calibration passes its own constants).  ``tolerances`` / ``deck_size``: how those were
    chosen, recorded in ``meta`` (default: as given by the user).  Returns the Ensemble of
    :func:`analogue.simulate` (``records`` included)."""
    if spec.unset_tolerances:
        raise ValueError(f"run_ensemble: the circuit spec must have its tolerances set (unset: "
                         f"{', '.join(spec.unset_tolerances)}); analogue.simulate chooses them")
    per_deck = runner.replicas_per_deck
    if per_deck is None:
        raise ValueError("run_ensemble: the runner must set replicas_per_deck; "
                         "analogue.simulate chooses it")
    mapping = map_model(model, spec)
    # Before allocating anything: replicas x time points x decks, and the bytes to be stored.
    _check_sizes(mapping=mapping, replicas=replicas, per_deck=per_deck, workers=runner.workers,
                 t_end=t_end, sample_dt=sample_dt, dt_label=dt_label, store=runner.store)
    times = time_grid(t_end, sample_dt)
    sample_dt = float(times[1] - times[0])
    model_eff = mapping.model_effective
    v0_arr = initial_velocities(model_eff, v0, replicas, seed)

    n_decks = -(-replicas // per_deck)
    sizes = [replicas // n_decks + (1 if b < replicas % n_decks else 0) for b in range(n_decks)]
    starts = np.concatenate([[0], np.cumsum(sizes)])
    seeds = deck_seeds(seed, n_decks)
    decks = [build_deck(mapping, replicas=sizes[b], v0=v0_arr[starts[b]:starts[b + 1]],
                        t_end=t_end, seed=seeds[b], sample_dt=sample_dt)
             for b in range(n_decks)]
    t0 = _time.perf_counter()
    records: dict[str, Any] = {}
    label = runner.label if runner.label is not None else default_label(model, v0, seed)
    v, x, noise, info = run_decks(decks, times, v0_arr, records=records,
                                  runner=runner.replace(label=label),
                                  limits=value_limits(mapping, v0_arr, t_end))
    meta = {
        "source": "circuit",
        "model": model.as_dict(),
        "model_effective": model_eff.as_dict(),
        "circuit_spec": spec,
        # the spec's unset values (smoothing, noise_dt) as chosen from the model, and why
        "circuit_defaults": mapping.chosen,
        "circuit": mapping.table(),
        "seed": seed,
        "deck_seeds": seeds,
        "deck_replicas": sizes,
        "replicas_per_deck": per_deck,
        "deck_size": (dict(deck_size) if deck_size is not None
                      else {"replicas_per_deck": per_deck, "source": "user"}),
        "tolerances": (dict(tolerances) if tolerances is not None
                       else {"reltol": mapping.reltol, "trtol": mapping.trtol,
                             "method": mapping.method, "source": "user"}),
        "deck_sha256": [d.sha256 for d in decks],
        "v0": v0 if isinstance(v0, str) else "given",
        "t_end": t_end,
        "sample_dt": sample_dt,
        "noise_dt": mapping.noise_dt,
        **info,
        "wall_time": _time.perf_counter() - t0,
    }
    meta.update(mapping.model.noise_kind.circuit_meta(mapping))   # shot: the pulse width
    z = None
    if noise is not None and math.isfinite(model.gamma):
        # The noise node holds the velocity noise, std sqrt(2/(gamma h)) (mapping): standardise.
        z = noise * math.sqrt(model.gamma * mapping.noise_dt / 2.0)
    records.update(mapping.model.noise_kind.deck_records(decks))   # shot: the kicks
    if "x_spring" in records:
        # The position is the spring's (issue 18): the inductor read-back, not the integral of
        # v, which a leaky inductor (R_L > 0) lets run away at the creep velocity (measured:
        # mean x 0.365 +- 0.006 against 0.250 at tau_m = 0.8, Delta = 0.3, a = 0.5, gamma = 8,
        # spring = 2, t in [10, 60]).  The integral stays in records["x_integral"].
        records["x_integral"] = x
        x = records["x_spring"] - records["x_spring"][:, :1]
        meta["position"] = ("model.x0 + x (x: the spring's position read back from the inductor "
                            "current, x[:, 0] = 0; the integral of v is records['x_integral'])")
    return Ensemble(times, v, x, _jsonable(meta), z, records or None)
