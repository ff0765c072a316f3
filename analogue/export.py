"""An experiment's circuit runs in Python (:func:`load_runs`) and on disk (:func:`export_experiment`,
``analogue export``).

The runs are exactly those behind the experiment's report (:func:`analogue.report.runs.
run_experiment_runs`: same seeds, same sizes), so they come from the run store when the report
or ``analogue run`` made them, and are simulated (and stored) otherwise.  Each is named by its
role:

- ``transition_v0=<v0>``: replicas started at each ``experiment.v0`` (propagator f(v, t | v0),
  prehistory);
- ``stationary``: replicas started from the stationary law p_s (stationary law, work, sticking);
- ``noise_free``: one replica per v0 at gamma = 1e8 (the deterministic motion, paper Fig. 1);
- ``check_transition``, ``check_stationary``: the first decks of the two runs above again with
  100x tighter tolerances on the same noise (the integration-error budget; the stationary one
  over a prefix window of the run, ``meta["check_window"]``).
"""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

from . import checks
from .ensemble import Ensemble

__all__ = ["ROLES", "export_experiment", "find_metrics", "load_runs", "metrics_rows",
           "runs_by_role"]

ROLES = ("transition_v0=<v0>", "stationary", "noise_free", "check_transition", "check_stationary")


def _role_transition(v0: float) -> str:
    return f"transition_v0={v0:g}"


def load_runs(experiment, *, quick: bool = False, store=None, workers: int | None = None,
              scheduler: str | None = None, progress: bool = False,
              timeout: float | None = None) -> dict[str, Ensemble]:
    """The circuit runs of ``experiment`` (a name in ``circuits/`` or a TOML path), by role.

    Parameters
    ----------
    experiment : str or Path
        E.g. ``"stick"``.
    quick : bool
        The ``--quick`` sizes of the report (fewer replicas).
    store, workers, scheduler, progress, timeout
        As for :func:`analogue.simulate` (timeout: seconds per deck; None: its default).

    Returns
    -------
    dict role -> :class:`~analogue.Ensemble`, in the order transition runs (one per v0),
    ``stationary``, ``noise_free``, ``check_transition``, ``check_stationary``.  Each
    ensemble's ``meta`` carries ``experiment`` and ``role`` besides the run's provenance.
    """
    from .circuit.experiments import load_experiment
    from .report.plan import RunOptions
    from .report.runs import run_experiment_runs

    quick, progress = checks.flag("quick", quick), checks.flag("progress", progress)
    exp = load_experiment(experiment)
    opts = RunOptions(workers=workers, scheduler=scheduler,
                      store=None if store is None else Path(store), quick=quick,
                      progress=progress, timeout=timeout)
    runs = run_experiment_runs(exp, opts)
    out = {}
    for role, ens in runs_by_role(runs).items():
        meta = {**ens.meta, "experiment": exp.name, "role": role, "quick": quick}
        out[role] = Ensemble(ens.t, ens.v, ens.x, meta, ens.noise)
    return out


def runs_by_role(runs) -> dict[str, Ensemble]:
    """The ensembles of an :class:`~analogue.report.runs.ExperimentRuns`, named by role."""
    named = {_role_transition(v0): ens for v0, ens in runs.transition.items()}
    named.update(stationary=runs.stationary, noise_free=runs.noise_free,
                 check_transition=runs.check_transition, check_stationary=runs.check_stationary)
    return named


# --------------------------------------------------------------------------- metrics.csv
def find_metrics(experiment_name: str, report=None) -> Path | None:
    """The ``metrics.json`` of a report holding ``experiment_name``: ``report`` (a directory or
    the file itself) when given, else ``report/<name>/metrics.json`` (``analogue report``) or
    ``report/metrics.json`` (``analogue paper``), relative to the working directory."""
    if report is not None:
        p = Path(report)
        p = p / "metrics.json" if p.is_dir() else p
        if not p.is_file():
            raise FileNotFoundError(f"no metrics.json at {p}")
        return p
    for p in (Path("report") / experiment_name / "metrics.json", Path("report") / "metrics.json"):
        if p.is_file() and metrics_rows(p, experiment_name):
            return p
    return None


def metrics_rows(metrics_path, experiment_name: str) -> list[dict]:
    """The comparisons of one experiment in ``metrics.json`` as flat rows (budget terms become
    ``budget_<term>`` columns)."""
    data = json.loads(Path(metrics_path).read_bytes())  # UTF-8 whatever the locale
    rows = []
    for c in data.get("comparisons", []):
        if c.get("experiment") != experiment_name:
            continue
        row = {k: v for k, v in c.items() if k != "budget"}
        for k, v in (c.get("budget") or {}).items():
            row[f"budget_{k}"] = v
        rows.append(row)
    return rows


def _csv_text(rows: list[dict]) -> str:
    columns: list = []
    for r in rows:
        columns += [k for k in r if k not in columns]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: "" if r.get(k) is None else r.get(k) for k in columns})
    return buf.getvalue()


def _write_text(path: Path, text: str) -> None:
    from .files import write_text
    write_text(path, text)


# --------------------------------------------------------------------------------- export
def export_experiment(experiment, out, *, report=None, quick: bool = False, store=None,
                      workers: int | None = None, scheduler: str | None = None,
                      progress: bool = False, timeout: float | None = None) -> list[Path]:
    """Write every run of ``experiment`` as ``<out>/<role>.nc`` (read them with
    :func:`analogue.open_ensemble` or ``xarray.open_dataset``), plus ``<out>/metrics.csv``
    (one row per circuit-versus-theory comparison) when a report of the experiment exists
    (see :func:`find_metrics`).  Runs missing from the store are simulated first.  Returns
    the paths written."""
    from .circuit.experiments import load_experiment
    from .data import write_netcdf

    out = Path(out)
    name = load_experiment(experiment).name
    metrics = find_metrics(name, report)   # a wrong --report fails before any simulation
    rows = metrics_rows(metrics, name) if metrics is not None else []
    if report is not None and not rows:
        raise ValueError(f"report: {metrics} has no comparisons of experiment {name!r}")
    runs = load_runs(experiment, quick=quick, store=store, workers=workers, scheduler=scheduler,
                     progress=progress, timeout=timeout)
    out.mkdir(parents=True, exist_ok=True)
    paths = [write_netcdf(ens, out / f"{role}.nc") for role, ens in runs.items()]
    if rows:
        p = out / "metrics.csv"
        _write_text(p, _csv_text(rows))
        paths.append(p)
    return paths
