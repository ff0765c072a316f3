"""An experiment's circuit runs in Python (:func:`load_runs`) and on disk (:func:`export_experiment`,
``analogue export``).

The runs are exactly those behind the experiment's report, from the one function that makes
them for the report (:func:`experiment_runs`: :func:`analogue.study.runs.run_experiment_runs`
for the paper's model, :func:`analogue.study.members.member_runs` for a family member; same
seeds, same sizes, same decks), so they come from the run store when the report or
``analogue run`` made them, and are simulated (and stored, and indexed under the experiment:
``analogue store ls``) otherwise.  Each is named by its role:

- ``transition_v0=<v0>``: replicas started at each ``experiment.v0`` (propagator f(v, t | v0),
  prehistory); a member: from ``v0[0]`` only; the spring: the release from ``x0`` at rest;
- ``stationary``: replicas started from the stationary law p_s (stationary law, work, sticking);
- ``noise_free``: one replica per v0 at gamma = 1e8 (the deterministic motion, paper Fig. 1;
  the paper's model only);
- ``check_transition``, ``check_stationary``: the first decks of the two runs above again with
  100x tighter tolerances on the same noise (the integration-error budget; the stationary one
  over a prefix window of the run, ``meta["check_window"]``).  A 1-D member has
  ``check_stationary``, the spring ``check_transition``.

A report has one size (``--quick`` or full); an export of the other size runs other decks,
and is said so before it starts.  ``metrics.csv`` is written only from a report whose runs are
the exported ones (the same size and the same deck hashes).
"""
from __future__ import annotations

import csv
import dataclasses
import io
import json
from collections.abc import Callable
from pathlib import Path

from . import checks
from .study.experiments import Experiment, load_experiment
from .ensemble import Ensemble
from .files import write_text
from .study.members import is_member_experiment, member_runs, member_sizes
from .report.plan import RunOptions
from .study.runs import run_experiment_runs
from .data import write_netcdf

__all__ = ["ROLES", "experiment_runs", "export_experiment", "find_metrics", "load_runs",
           "metrics_rows", "report_decks", "report_size", "runs_by_role", "size_line"]

ROLES = ("transition_v0=<v0>", "stationary", "noise_free", "check_transition", "check_stationary")


def _options(quick, store, workers, scheduler, progress, timeout):
    return RunOptions(workers=workers, scheduler=scheduler,
                      store=None if store is None else Path(store),
                      quick=checks.flag("quick", quick),
                      progress=checks.flag("progress", progress), timeout=timeout)


def experiment_runs(exp: Experiment, opts):
    """The runs behind ``exp``'s report at ``opts``' size: the paper's model's
    :class:`~analogue.study.runs.ExperimentRuns` or a member's
    :class:`~analogue.study.members.MemberRuns` (both name their runs, ``.by_role()``).  The
    report calls the same two functions, so the runs (seeds, sizes, decks) are the same."""
    if is_member_experiment(exp):
        return member_runs(exp, opts)
    return run_experiment_runs(exp, opts)


def size_line(exp: Experiment, quick: bool) -> str:
    """One line naming the size whose runs an export of ``exp`` reads (or runs)."""
    size = "--quick" if quick else "full (no --quick)"
    if is_member_experiment(exp):
        s = member_sizes(exp, quick)
        reps = (f"{s.transition_replicas} replicas" if exp.model.spring > 0 else
                f"{s.stationary_replicas} stationary x {s.stationary_t_end:g}, "
                f"{s.transition_replicas} from v0")
    else:
        opts = _options(quick, None, None, None, False, None)
        reps = (f"{opts.scaled(exp.replicas)} replicas per v0, "
                f"{exp.report.for_options(opts).stationary_replicas} stationary")
    return f"{exp.name}: the {size} size's runs ({reps})"


def load_runs(experiment, *, quick: bool = False, store=None, workers: int | None = None,
              scheduler: str | None = None, progress: bool = False,
              timeout: float | None = None) -> dict[str, Ensemble]:
    """The circuit runs of ``experiment`` (a name in ``circuits/`` or a TOML path), by role:
    the very runs of its report at the same size (:func:`experiment_runs`).

    Parameters
    ----------
    experiment : str, Path or Experiment
        E.g. ``"stick"``, ``"shot"`` or ``"mine.toml"``.
    quick : bool
        The ``--quick`` sizes of the report (fewer replicas).
    store, workers, scheduler, progress, timeout
        As for :func:`analogue.simulate` (timeout: seconds per deck; None: its default).

    Returns
    -------
    dict role -> :class:`~analogue.Ensemble` (see :data:`ROLES` and the module docstring),
    in the order transition runs, ``stationary``, ``noise_free``, checks.  Each ensemble's
    ``meta`` carries ``experiment``, ``role`` and ``quick`` besides the run's provenance;
    ``records`` (the spring's inductor read-back, shot kicks) are kept.
    """
    exp = experiment if isinstance(experiment, Experiment) else load_experiment(experiment)
    opts = _options(quick, store, workers, scheduler, progress, timeout)
    return _named(exp, experiment_runs(exp, opts), opts.quick)


def _named(exp: Experiment, runs, quick: bool) -> dict[str, Ensemble]:
    out = {}
    for role, ens in runs_by_role(runs).items():
        meta = {**ens.meta, "experiment": exp.name, "role": role, "quick": quick}
        out[role] = dataclasses.replace(ens, meta=meta)
    return out


def runs_by_role(runs) -> dict[str, Ensemble]:
    """The ensembles of an :class:`~analogue.study.runs.ExperimentRuns` or a
    :class:`~analogue.study.members.MemberRuns`, named by role."""
    return runs.by_role()


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


def report_size(metrics_path) -> bool | None:
    """Whether the report behind ``metrics.json`` was ``--quick`` (its provenance), None when
    it does not say."""
    q = (json.loads(Path(metrics_path).read_text()).get("provenance") or {}).get("quick")
    return q if isinstance(q, bool) else None


def report_decks(metrics_path, experiment_name: str) -> set[str]:
    """The sha256 of the decks behind ``experiment_name``'s rows of ``metrics.json`` (its
    provenance's ``deck_hashes``; empty when it has none)."""
    prov = json.loads(Path(metrics_path).read_text()).get("provenance") or {}
    hashes = (prov.get("deck_hashes") or {}).get(experiment_name) or {}
    out: set[str] = set()
    for v in hashes.values():
        out.update([v] if isinstance(v, str) else [h for h in v or () if isinstance(h, str)])
    return out


def _size_name(quick: bool) -> str:
    return "--quick" if quick else "full-size"


def _leave_out(why: str, given: bool, say) -> list:
    """A report whose runs are not the exported ones: refused when named (``--report``), else
    left out of the export with a line saying why."""
    if given:
        raise ValueError(f"report: {why}")
    say(f"metrics.csv not written: {why}")
    return []


# --------------------------------------------------------------------------------- export
def export_experiment(experiment, out, *, report=None, quick: bool = False, store=None,
                      workers: int | None = None, scheduler: str | None = None,
                      progress: bool = False, timeout: float | None = None,
                      say: Callable[[str], None] | None = None) -> list[Path]:
    """Write every run of ``experiment`` as ``<out>/<role>.nc`` (read them with
    :func:`analogue.open_ensemble` or ``xarray.open_dataset``), plus ``<out>/metrics.csv``
    (one row per circuit-versus-theory comparison) when a report of these runs exists (see
    :func:`find_metrics`).  Runs missing from the store are simulated first.  Returns the
    paths written.

    ``say`` (default: nothing) gets one line naming the size before anything runs
    (:func:`size_line`), and a line when a report found in ``report/`` is left out because
    its runs are not these: another size (its provenance's ``quick``) or other decks (its
    ``deck_hashes``, e.g. the file was edited since).  A ``report`` given explicitly whose
    runs are not these is refused (ValueError; of another size: before anything runs)."""

    say = say or (lambda _line: None)
    exp = experiment if isinstance(experiment, Experiment) else load_experiment(experiment)
    opts = _options(quick, store, workers, scheduler, progress, timeout)
    out, name = Path(out), exp.name
    metrics = find_metrics(name, report)   # a wrong --report fails before any simulation
    rows = metrics_rows(metrics, name) if metrics is not None else []
    if report is not None and not rows:
        raise ValueError(f"report: {metrics} has no comparisons of experiment {name!r}")
    say(size_line(exp, opts.quick))
    rq = report_size(metrics) if rows else None
    if rq is not None and rq != opts.quick:
        why = (f"{metrics} is a {_size_name(rq)} report, this export is {_size_name(opts.quick)}"
               f" (export {name}{' --quick' if rq else ' without --quick'} exports its runs)")
        rows = _leave_out(why, report is not None, say)
    runs = _named(exp, experiment_runs(exp, opts), opts.quick)
    if rows:
        ours = {h for e in runs.values() for h in e.meta.get("deck_sha256") or ()}
        missing = report_decks(metrics, name) - ours
        if missing:
            why = (f"{len(missing)} of the decks behind {metrics} are not among these runs' "
                   f"(was {name} changed since that report?)")
            rows = _leave_out(why, report is not None, say)
    out.mkdir(parents=True, exist_ok=True)
    paths = [write_netcdf(ens, out / f"{role}.nc") for role, ens in runs.items()]
    if rows:
        p = out / "metrics.csv"
        write_text(p, _csv_text(rows))
        paths.append(p)
    return paths
