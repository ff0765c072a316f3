"""``analogue.simulate``: ensembles of stick-slip trajectories from the ngspice circuit.

:func:`simulate` checks its arguments, chooses what the user left open (the ngspice
tolerances by measured accuracy, :mod:`analogue.circuit.tolerances`; the deck size by a cost
model, :mod:`analogue.circuit.deck_size`) and runs the result with
:func:`analogue.circuit.decks.run_ensemble`.  The choosers calibrate through that same
lower-level function, never through :func:`simulate` (issue 20: it used to call itself back
through them).  How the decks run is an :class:`analogue.Runner`
(:mod:`analogue.circuit.runner`); the run keywords of earlier versions (``workers``,
``store``, ...) are folded into one.

The deck machinery (:func:`run_decks`, :class:`BatchTask`, :func:`time_grid`, ...) lives in
:mod:`analogue.circuit.decks` and is importable from here as before.
"""
from __future__ import annotations

import concurrent.futures as cf
import sys  # noqa: F401 - tests reach sys.stderr through this module, as before
import warnings
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Literal, overload

import numpy as np

from .. import checks
from ..checks import ArgumentTypeError
from ..cores import usable_cpus
from ..ensemble import Ensemble
from ..model import Model
from .deck_size import DEFAULT_REPLICAS_PER_DECK, choose_deck_size
from .deck_size import MIN_CALIBRATED_REPLICA_HOLDS as MIN_DECK_HOLDS
from .decks import (  # noqa: F401 - the names this module always offered
    NOISE_SIGMAS,
    POLL_S,
    VALUE_LEVEL,
    VALUE_SAFETY,
    BatchTask,
    Deck,
    _check_sizes,
    _completed,
    _default_sample_dt,
    _entry_problem,
    _executor,
    _grid_intervals,
    _result_problem,
    _sample_stationary,
    deck_seeds,
    held_values,
    initial_velocities,
    run_batch,
    run_decks,
    run_ensemble,
    time_grid,
    value_limits,
)
from .mapping import CircuitSpec, map_model
from .runner import DEFAULT_TIMEOUT, Runner
from .runner import check_executor as _check_executor  # noqa: F401
from .runner import check_scheduler as _check_scheduler  # noqa: F401
from .runner import is_client as _is_client  # noqa: F401
from .runner import progress_mode as _progress_mode  # noqa: F401
from .tolerances import MIN_CALIBRATED_REPLICA_HOLDS as MIN_TOLERANCE_HOLDS
from .tolerances import resolve_spec

if TYPE_CHECKING:
    from os import PathLike

    from numpy.typing import ArrayLike

__all__ = [
    "BatchTask",
    "DEFAULT_REPLICAS_PER_DECK",
    "DEFAULT_TIMEOUT",
    "Deck",
    "Runner",
    "deck_seeds",
    "initial_velocities",
    "run_batch",
    "run_decks",
    "simulate",
    "time_grid",
    "value_limits",
]

#: simulate's run keywords, folded into a Runner (the Runner's fields of the same names)
RUN_KEYWORDS = ("workers", "replicas_per_deck", "store", "progress", "label", "timeout",
                "scheduler", "executor")


def _spec(circuit):
    if circuit is None:
        return CircuitSpec()
    if isinstance(circuit, CircuitSpec):
        return circuit
    if isinstance(circuit, dict):
        try:
            return CircuitSpec(**circuit)
        except TypeError as exc:
            raise ValueError(f"circuit: {exc}") from None
    raise ArgumentTypeError(f"circuit must be None, a CircuitSpec or a dict of CircuitSpec "
                            f"fields, got {type(circuit).__name__}")


def _runner(runner: Runner | None, given: dict[str, Any]) -> Runner:
    """The Runner of a call: ``runner`` or one made of the run keywords ``given`` (those not
    None), never both."""
    passed = {k: v for k, v in given.items() if v is not None}
    if runner is None:
        return Runner(**passed)
    if not isinstance(runner, Runner):
        raise ArgumentTypeError(f"runner must be an analogue.Runner, got "
                                f"{type(runner).__name__}")
    if passed:
        raise TypeError(f"simulate: pass either runner= or the run keywords "
                        f"({', '.join(sorted(passed))}), not both: put them in the Runner, "
                        f"e.g. runner.replace({', '.join(f'{k}=...' for k in sorted(passed))})")
    return runner


@overload
def simulate(model: Model, *, v0: float | ArrayLike | Literal["stationary"], t_end: float,
             replicas: int, seed: int, sample_dt: float | None = None,
             circuit: CircuitSpec | Mapping[str, Any] | None = None,
             runner: Runner | None = None, workers: int | None = None,
             replicas_per_deck: int | None = None,
             store: str | PathLike[str] | bool | None = None, progress: bool | None = None,
             label: str | None = None, timeout: float | None = None,
             scheduler: str | None = None, executor: cf.Executor | Any | None = None,
             return_noise: Literal[False] = False, return_records: Literal[False] = False) -> Ensemble: ...


@overload
def simulate(model: Model, *, v0: float | ArrayLike | Literal["stationary"], t_end: float,
             replicas: int, seed: int, sample_dt: float | None = None,
             circuit: CircuitSpec | Mapping[str, Any] | None = None,
             runner: Runner | None = None, workers: int | None = None,
             replicas_per_deck: int | None = None,
             store: str | PathLike[str] | bool | None = None, progress: bool | None = None,
             label: str | None = None, timeout: float | None = None,
             scheduler: str | None = None, executor: cf.Executor | Any | None = None,
             return_noise: Literal[True], return_records: Literal[False] = False) -> tuple[Ensemble, np.ndarray]: ...


@overload
def simulate(model: Model, *, v0: float | ArrayLike | Literal["stationary"], t_end: float,
             replicas: int, seed: int, sample_dt: float | None = None,
             circuit: CircuitSpec | Mapping[str, Any] | None = None,
             runner: Runner | None = None, workers: int | None = None,
             replicas_per_deck: int | None = None,
             store: str | PathLike[str] | bool | None = None, progress: bool | None = None,
             label: str | None = None, timeout: float | None = None,
             scheduler: str | None = None, executor: cf.Executor | Any | None = None,
             return_noise: Literal[False] = False, return_records: Literal[True]) -> tuple[Ensemble, dict[str, Any]]: ...


def simulate(model: Model, *, v0: float | ArrayLike | Literal["stationary"], t_end: float,
             replicas: int, seed: int, sample_dt: float | None = None,
             circuit: CircuitSpec | Mapping[str, Any] | None = None,
             runner: Runner | None = None, workers: int | None = None,
             replicas_per_deck: int | None = None,
             store: str | PathLike[str] | bool | None = None, progress: bool | None = None,
             label: str | None = None, timeout: float | None = None,
             scheduler: str | None = None, executor: cf.Executor | Any | None = None,
             return_noise: bool = False, return_records: bool = False
             ) -> Ensemble | tuple[Ensemble, np.ndarray] | tuple[Ensemble, dict[str, Any]]:
    """Simulate ``replicas`` trajectories of the stick-slip model (eqs. (4), (5)) in ngspice.

    Parameters
    ----------
    model : analogue.Model
        The model to realise; the circuit implements ``mapping.model_effective`` (the same
        parameters with the diode smoothing width epsilon), recorded in ``meta``.
    v0 : float, array (replicas,) or "stationary"
        Initial velocities in model units; "stationary" draws them from the stationary law of
        the circuit's model (eq. (6)) with a seed derived from ``seed``.
    t_end : float
        Final time (model units); a whole number of ``sample_dt``.
    replicas : int
        Number of independent trajectories (>= 1).
    seed : int
        Master seed (>= 0): same seed => identical arrays.
    sample_dt : float, optional
        Output grid step (model units); default about tau_m/100.
    circuit : None, CircuitSpec or dict
        Circuit choices (see :mod:`analogue.circuit.mapping`); None = default spec.  Its
        ``reltol``, ``trtol`` and ``method`` left unset (None) are chosen by measured accuracy
        (:mod:`analogue.circuit.tolerances`, recorded in ``meta["tolerances"]``); set ones are
        used as given.
    runner : analogue.Runner, optional
        How the decks run (store, workers, deck size, executor, timeout, progress, label):
        the way to pass those.  The eight keywords below are kept for existing code and are
        folded into a Runner; passing one of them with ``runner=`` is a TypeError.
    workers : int, optional
        ngspice processes run at once locally; default: the CPUs this process may use
        (:func:`analogue.cores.usable_cpus`: affinity mask and cgroup quota).
    replicas_per_deck : int, optional
        Replicas per ngspice deck; default: chosen per model by
        :mod:`analogue.circuit.deck_size` from measured step counts (``meta["deck_size"]``).
    store : path, False or None
        Run-store directory; False disables it (results in memory only); None:
        $ANALOGUE_STORE or ~/.cache/analogue/runs.
    progress : bool or None
        None: a tqdm bar when stderr is a terminal; True: the bar on a terminal (decks done
        of the total, and the time left), else plain lines on stderr (the same, at most every
        30 s, and one summary line per call); False: silent.
    label : str, optional
        Names the run on its bar or line (printable, <= 100 characters); default: regime,
        gamma, v0 and seed.
    timeout : float, optional
        Seconds per deck (None: 3600): the deck's ngspice process group is killed and
        :class:`analogue.circuit.ngspice.NgspiceError` raised.
    scheduler : str, optional
        A Dask scheduler address ("tcp://host:port"): the decks run on that cluster (a
        client is opened and closed by this call).  Needs ``analogue[dask]``.
    executor : concurrent.futures.Executor or distributed.Client, optional
        Runs the decks on an executor the caller owns (not shut down here), the way emcee
        takes ``pool=``; exclusive with ``scheduler``.
    return_noise : bool
        Deprecated (DeprecationWarning): the noise is ``ensemble.noise``.  True returns
        ``(ensemble, ensemble.noise)`` as before.
    return_records : bool
        Deprecated (DeprecationWarning): the records are ``ensemble.records``.  True returns
        ``(ensemble, ensemble.records)`` as before.

    A request whose arrays or stored bytes cannot fit is refused before anything runs
    (ValueError naming the parameters and the limit; see :mod:`analogue.circuit.limits`).
    Stored decks are verified when read; damaged ones are quarantined and re-run (see
    :mod:`analogue.circuit.store`).  SIGINT, SIGTERM and SIGHUP during the run kill the
    running ngspice processes, remove their temporary directories and raise
    :class:`analogue.circuit.ngspice.RunInterrupted` (a KeyboardInterrupt with ``exit_code`` =
    128 + signal); decks finished before are in the store, so calling again resumes.

    Returns
    -------
    Ensemble with ``t`` (0..t_end step sample_dt), ``v`` and ``x`` (replicas, n_t) in model
    units (x[:, 0] = 0), ``meta`` holding the provenance and ``noise``: when the decks record
    their noise, ``z`` (replicas, n_hold) the standard normal numbers that drove the circuit,
    one per noise hold time ``h = meta["noise_dt"]``: the velocity-noise increment over hold k
    is ``sqrt(2 h/gamma) z[:, k]`` (the convention of
    ``analogue.montecarlo.simulate_sde(..., dt=h, noise=z)``, so an SDE integrator can be
    driven by the very same noise); None otherwise.  ``records`` (None when empty): a dict
    with ``"x_spring"`` (replicas, n_t) the spring's position read back from the inductor
    current (spring models: ``x`` is this read-back less its value at t = 0, so that the
    position is ``model.x0 + x`` as for the Monte Carlo; ``"x_integral"`` keeps the integral
    of v, which the leaky inductor lets creep away: the mapping's ``spring_creep``) and
    ``"kicks"`` (shot noise): per replica ``(times, jumps)`` of the kicks that drove it (model units; times are
    the pulse centres), so a Monte Carlo can be driven by the same realisation.
    """
    checks.instance("model", model, Model, description="an analogue.Model")
    replicas = checks.integer("replicas", replicas, minimum=1)
    seed = checks.integer("seed", seed, minimum=0)
    t_end = checks.positive("t_end", t_end)
    dt_label = ""
    if sample_dt is None:
        sample_dt = _default_sample_dt(model, t_end)
        dt_label = " (default: tau_m/100)"
    sample_dt = checks.positive("sample_dt", sample_dt)
    _grid_intervals(t_end, sample_dt, dt_label)  # a count that fits, before anything else
    run = _runner(runner, {"workers": workers, "replicas_per_deck": replicas_per_deck,
                           "store": store, "progress": progress, "label": label,
                           "timeout": timeout, "scheduler": scheduler, "executor": executor})
    return_noise = checks.flag("return_noise", return_noise)
    return_records = checks.flag("return_records", return_records)
    if return_noise and return_records:
        raise ValueError("return_noise and return_records cannot both be True")
    if return_noise:
        warnings.warn("simulate(return_noise=True) is deprecated: the recorded noise is "
                      "ensemble.noise", DeprecationWarning, stacklevel=2)

    spec = _spec(circuit)
    # Bad specs and requests that cannot fit fail here, before any calibration runs.
    _check_sizes(mapping=map_model(model, spec), replicas=replicas,
                 per_deck=run.replicas_per_deck or DEFAULT_REPLICAS_PER_DECK,
                 workers=run.workers, t_end=t_end, sample_dt=sample_dt, dt_label=dt_label,
                 store=run.store)
    tol_choice = None
    if spec.unset_tolerances:
        # Tolerances by measured accuracy (cached in the run store): see circuit.tolerances.
        spec, tol_choice = resolve_spec(model, spec, replicas=replicas, t_end=t_end,
                                        runner=run.for_calibration(),
                                        min_replica_holds=MIN_TOLERANCE_HOLDS)
    deck_choice = None
    if run.replicas_per_deck is None:
        deck_choice = choose_deck_size(model, spec, replicas=replicas, t_end=t_end,
                                       workers=run.workers or usable_cpus(),
                                       runner=run.for_calibration(),
                                       min_replica_holds=MIN_DECK_HOLDS)
        run = run.replace(replicas_per_deck=deck_choice.replicas_per_deck)
    ens = run_ensemble(model, spec, v0=v0, t_end=t_end, replicas=replicas, seed=seed,
                       sample_dt=sample_dt, runner=run, dt_label=dt_label,
                       tolerances=tol_choice.as_dict() if tol_choice is not None else None,
                       deck_size=deck_choice.as_dict() if deck_choice is not None else None)
    if return_records:
        warnings.warn("simulate(return_records=True) is deprecated: the records are "
                      "ensemble.records", DeprecationWarning, stacklevel=2)
        return ens, (ens.records if ens.records is not None else {})
    if not return_noise:
        return ens
    if ens.noise is None:
        raise ValueError("return_noise: the circuit's decks do not record their noise")
    return ens, ens.noise
