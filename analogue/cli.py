"""Command-line interface: ``analogue netlist | run | report | paper | sweep | theory | figures``.

Every failure is one line on stderr (``analogue: error: ...``) and an exit code: 2 for bad
input (usage, wrong values or types, an unreadable experiment file), 1 for a run that failed
(ngspice, the store, the disk, memory, a report with failed sections), 130 when interrupted.
Set ``ANALOGUE_DEBUG=1`` to see the traceback instead.
"""
from __future__ import annotations

import json
import logging
import math
import os
import re
import sys
import time
from pathlib import Path

import click

from .model import Model
from datetime import UTC

EXIT_USAGE = 2
EXIT_FAILURE = 1
EXIT_INTERRUPTED = 130
# Seconds a command may spend cleaning up after SIGINT/SIGTERM/SIGHUP before it exits anyway.
EXIT_GRACE_S = 5.0
# Exceptions that mean the input was wrong (the API raises TypeError for wrong types and
# ValueError for wrong values; a bad TOML file or encoding is a ValueError too).
_BAD_INPUT = (ValueError, TypeError)
# Our own messages are sentences; anything else is prefixed with its type (BadZipFile: ...).
_OWN_MESSAGES = (ValueError, TypeError, RuntimeError, OSError)


def _debug() -> bool:
    return bool(os.environ.get("ANALOGUE_DEBUG"))


def _one_line(text) -> str:
    """Every line of a message, on one line (ngspice's own error lines included)."""
    return " | ".join(ln.strip() for ln in str(text).splitlines() if ln.strip())


def error_line(exc: BaseException) -> str:
    """The one line shown for a failure."""
    if isinstance(exc, MemoryError):
        return f"out of memory (MemoryError{': ' + _one_line(exc) if str(exc) else ''}); " \
               "lower the replicas, t_end or the number of workers"
    msg = _one_line(exc)
    if isinstance(exc, KeyError):
        msg = f"missing key {exc.args[0]!r}" if exc.args else ""
    if not isinstance(exc, _OWN_MESSAGES) or isinstance(exc, KeyError):
        return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__
    return msg or type(exc).__name__


def exit_code(exc: BaseException) -> int:
    return EXIT_USAGE if isinstance(exc, _BAD_INPUT) else EXIT_FAILURE


def _short_help(cmd: click.Command) -> str:
    """A command's whole first paragraph (click's default stops at the first full stop, which
    cut "Draw the paper's theory figures (Figs." in the middle of a parenthesis)."""
    if cmd.short_help:
        return cmd.short_help
    first = (cmd.help or "").strip().split("\n\n")[0]
    return " ".join(w for w in first.split() if w != "\b")


_NB_HYPHEN = "\u2011"


class _Formatter(click.HelpFormatter):
    """Help text that never wraps inside a hyphenated word ("self-\\ncontained",
    "rate-\\nfunction"): hyphens are non-breaking while the text is wrapped."""

    def _unbreakable(self, method, *args):
        start = len(self.buffer)
        method(*(a.replace("-", _NB_HYPHEN) if isinstance(a, str) else
                 [tuple(x.replace("-", _NB_HYPHEN) for x in row) for row in a]
                 if isinstance(a, list) else a for a in args))
        self.buffer[start:] = [b.replace(_NB_HYPHEN, "-") for b in self.buffer[start:]]

    def write_text(self, text):
        self._unbreakable(super().write_text, text)

    def write_dl(self, rows, col_max=30, col_spacing=2):
        self._unbreakable(super().write_dl, list(rows), col_max, col_spacing)


class _Context(click.Context):
    formatter_class = _Formatter


class _Command(click.Command):
    context_class = _Context


class _ProgressLines(logging.Handler):
    """The report job's progress (logger ``analogue.report``) as ``analogue [  12.3 s]: ...``
    lines on the current stderr, timed from the start of the command."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.start = time.perf_counter()

    def emit(self, record: logging.LogRecord) -> None:
        try:
            print(f"analogue [{time.perf_counter() - self.start:6.1f} s]: {record.getMessage()}",
                  file=sys.stderr, flush=True)
        except Exception:  # noqa: BLE001 - logging must never break the run
            self.handleError(record)


def _show_progress() -> None:
    """One progress handler per command (a fresh start time; none left from a previous one)."""
    logger = logging.getLogger("analogue.report")
    for h in [h for h in logger.handlers if isinstance(h, _ProgressLines)]:
        logger.removeHandler(h)
    logger.addHandler(_ProgressLines())
    logger.setLevel(logging.INFO)


class _Group(click.Group):
    """Turn every failure into one clear line and an exit code (module docstring)."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        _show_progress()
        if args is None:
            # The command line itself (not click's test runner, which passes args): the
            # process ends within EXIT_GRACE_S of a signal whatever its threads wait for, and
            # at once on a second signal (issue 19: a deck-pool wait that was never woken hung
            # `analogue run` until SIGKILL).  Not in-process: it would end the caller.
            from .circuit.ngspice import exit_after_signal
            exit_after_signal(EXIT_GRACE_S)
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except click.ClickException as exc:
            click.echo(f"analogue: error: {_one_line(exc.format_message())}", err=True)
            sys.exit(exc.exit_code)
        except click.Abort as exc:
            cause = exc.__cause__
            if _debug() and cause is not None and not isinstance(cause, KeyboardInterrupt):
                raise cause from None  # --debug: the original traceback, not click's Abort
            if cause is not None and not isinstance(cause, KeyboardInterrupt):
                click.echo(f"analogue: error: {error_line(cause)}", err=True)
                sys.exit(exit_code(cause))
            click.echo("analogue: interrupted", err=True)
            sys.exit(EXIT_INTERRUPTED)
        sys.exit(rv if isinstance(rv, int) else 0)

    context_class = _Context
    command_class = _Command

    def format_commands(self, ctx, formatter):
        rows = [(name, _short_help(cmd)) for name in self.list_commands(ctx)
                if (cmd := self.get_command(ctx, name)) is not None and not cmd.hidden]
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)

    def invoke(self, ctx):
        # The guard covers the whole command, not only the ngspice calls: a SIGTERM while a
        # report is plotting (between simulate calls) is then a one-line exit 143 too, not a
        # silent death by signal.  Nested guards (simulate's own) are re-entrant.
        from .circuit.ngspice import interrupt_guard
        try:
            with interrupt_guard():
                return super().invoke(ctx)
        except (click.exceptions.Exit, click.ClickException, click.Abort):
            raise
        except KeyboardInterrupt as exc:
            if _debug():
                raise
            # RunInterrupted (SIGINT/SIGTERM/SIGHUP during a run) says what was cleaned up and
            # carries the shell's 128 + signal; a bare Ctrl-C is 130
            msg = _one_line(exc)
            click.echo(f"analogue: error: {msg}" if msg else "analogue: interrupted", err=True)
            ctx.exit(getattr(exc, "exit_code", EXIT_INTERRUPTED))
        except Exception as exc:  # every failure reaching the CLI: one line
            if _debug():
                raise
            click.echo(f"analogue: error: {error_line(exc)}", err=True)
            ctx.exit(exit_code(exc))


def _floats(name: str, text):
    if not text:
        return None
    if isinstance(text, (tuple, list)):  # repeated option: --w 0 --w 2
        text = ",".join(text)
    try:
        vals = [float(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise click.BadParameter(f"expected comma-separated numbers, got {text!r}",
                                 param_hint=name) from None
    if not vals or not all(math.isfinite(v) for v in vals):
        raise click.BadParameter("expected finite numbers", param_hint=name)
    # beyond this the closed forms overflow (--v 1e308: RuntimeWarnings, then "no admissible
    # optimal path found (please report)", exit 1); 1e12 still answers for every quantity
    if any(abs(v) > _MAX_MAGNITUDE for v in vals):
        raise click.BadParameter(f"expected numbers with |x| <= {_MAX_MAGNITUDE:g}, got {text!r}",
                                 param_hint=name)
    return vals


_MAX_MAGNITUDE = 1e12


def _magnitude(name: str, value):
    """A single number option: as :func:`_floats` (finite, at most 1e12 in magnitude)."""
    return None if value is None else _floats(name, repr(value))[0]


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="analogue")
def main():
    """Stick-slip friction with noise: theory, ngspice circuit, and their comparison.

    Typical use: `analogue paper --out report` runs the paper's experiments (stick, slip, work)
    on the circuit and writes report/index.html with the paper's figures, circuit data
    overlaid, metrics.json and an error budget; `analogue report FILE.toml` does the same for
    your own experiment.
    """


# ------------------------------------------------------------------------------ netlist
@main.command()
@click.argument("experiment", required=False)
@click.option("--check", is_flag=True, help="Only check that committed decks are up to date "
              "(exit 1 if any is stale).")
def netlist(experiment, check):
    """Regenerate the SPICE decks in netlists/ from circuits/*.toml (only EXPERIMENT's, when
    given; a TOML file outside circuits/ gets its deck beside it, <stem>.cir)."""
    from .study.experiments import regenerate_netlists
    paths = regenerate_netlists(check=check,
                                experiments=None if experiment is None else [experiment])
    if check:
        if paths:
            for p in paths:
                click.echo(f"stale: {p}")
            click.echo("analogue: error: netlists are stale; run `analogue netlist`", err=True)
            sys.exit(EXIT_FAILURE)
        click.echo("netlists up to date")
    else:
        for p in paths:
            click.echo(f"wrote {p}")


@main.command()
@click.argument("experiment")
@click.argument("out", type=click.Path(dir_okay=False, path_type=Path))
def schematic(experiment, out):
    """Draw one replica of EXPERIMENT's circuit (a name or a TOML path) with its component
    values in SI units, as OUT (.svg or .png); `analogue schematic stick docs/schematic.svg`
    redraws the committed drawing."""
    from .study.experiments import load_experiment
    from .circuit.schematic import draw
    exp = load_experiment(experiment)
    draw(exp.mapping(), out, title=f"{exp.name}: {exp.model.regime} regime")
    click.echo(f"wrote {out}")


# ------------------------------------------------------------------ run / report / paper
_HOST = re.compile(r"(?:[A-Za-z0-9](?:[A-Za-z0-9-]{0,61}[A-Za-z0-9])?)(?:\.[A-Za-z0-9](?:[A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*"
                   r"|\[[0-9A-Fa-f:.]+\]")


def _scheduler_option(ctx, param, value):
    """A Dask scheduler address: tcp://HOST:PORT or tls://HOST:PORT (ucx:// only with ucx-py).
    Checked here so that a typo fails at once, naming the option, not after a connect timeout."""
    if value is None:
        return None
    scheme, sep, rest = value.strip().partition("://")
    if scheme == "ucx":
        import importlib.util
        if importlib.util.find_spec("ucp") is None:
            raise click.BadParameter(f"ucx:// needs UCX support (the ucx-py package), which is "
                                     f"not installed; use tcp://HOST:PORT, got {value!r}",
                                     param_hint="--scheduler")
    elif not sep or scheme not in ("tcp", "tls"):
        raise click.BadParameter(f"must be a Dask scheduler address tcp://HOST:PORT (or "
                                 f"tls://HOST:PORT), got {value!r}", param_hint="--scheduler")
    host, colon, port = rest.rpartition(":")
    if not colon or not _HOST.fullmatch(host) or not port.isdigit() or not 1 <= int(port) <= 65535:
        raise click.BadParameter(f"must be {scheme}://HOST:PORT with a host name or address and "
                                 f"a port in 1..65535, got {value!r}", param_hint="--scheduler")
    return value.strip()


def _store_dir_option(ctx, param, value):
    if value is None:
        return None
    if not value.strip():
        raise click.BadParameter("must be a directory path, got an empty string (leave the "
                                 "option out for $ANALOGUE_STORE or ~/.cache/analogue/runs)",
                                 param_hint="--store")
    path = _usable(Path(value).expanduser(), "--store")
    from .circuit.store import root_problem
    problem = root_problem(path)  # a dangling or looping link: nothing could ever be stored
    if problem is not None:
        raise click.BadParameter(problem, param_hint="--store")
    if path.exists() and not path.is_dir():
        raise click.BadParameter(f"{value!r} exists and is not a directory", param_hint="--store")
    # a path below a file can never be created (run printed one "not writable" warning per
    # deck, 29 lines for a quick run, and stored nothing)
    _refuse_below_file(path, "--store")
    return path


def _usable(path: Path, option: str) -> Path:
    """A path whose name can be written into the UTF-8 files that name it (the page, the
    metrics, the store's index), refused at once otherwise (issue 19: under LC_ALL=C a path
    with accents failed after the whole run, leaving a 0-byte index.tmp)."""
    from .files import check_path
    try:
        return check_path(path, option)
    except ValueError as exc:
        raise click.BadParameter(str(exc).removeprefix(f"{option}: "), param_hint=option) from None


def _refuse_below_file(path: Path, option: str) -> None:
    """A directory below an existing file can never be created: bad input at once."""
    for parent in Path(path).absolute().parents:
        if parent.exists():
            if not parent.is_dir():
                raise click.BadParameter(f"{str(path)!r} lies below {str(parent)!r}, which is "
                                         f"not a directory", param_hint=option)
            return


def _out_dir_option(ctx, param, value):
    """--out below a file can never be created: bad input (exit 2) at once, not an OSError
    ("[Errno 20] Not a directory", exit 1) after the runs."""
    if value is None:
        return None
    _refuse_below_file(_usable(Path(value), "--out"), "--out")
    return value


def _timeout_option(ctx, param, value):
    if value is None:
        return None
    if not (math.isfinite(value) and value > 0):
        raise click.BadParameter(f"must be a finite number of seconds > 0, got {value!r}",
                                 param_hint="--timeout")
    return value


def _run_options(f):
    f = click.option("--workers", type=click.IntRange(1, 256), default=None,
                     help="Local worker processes (default: the CPUs this process may use: affinity mask "
                          "and cgroup quota).")(f)
    f = click.option("--scheduler", default=None, metavar="ADDRESS", callback=_scheduler_option,
                     help="Dask scheduler address (tcp://host:port) to run the decks on.")(f)
    f = click.option("--store", default=None, metavar="DIRECTORY", callback=_store_dir_option,
                     help="Run-store directory (default $ANALOGUE_STORE or ~/.cache/analogue/runs).")(f)
    f = click.option("--timeout", type=float, default=None, metavar="SECONDS",
                     callback=_timeout_option,
                     help="Give up on a deck (one ngspice run) after this many seconds.")(f)
    f = click.option("--quick", is_flag=True, help="Small ensembles: minutes, larger error bars.")(f)
    f = click.option("--progress/--no-progress", default=True, help="Show progress bars.")(f)
    return f


def _reach_scheduler(address: str, timeout: float = 5.0) -> None:
    """Fail at once, naming the option, when nothing listens at the scheduler's address
    (distributed's own client would wait 30 s per run and then fail inside a report)."""
    import socket
    rest = address.partition("://")[2]
    host, _, port = rest.rpartition(":")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except OSError as exc:
        raise RuntimeError(f"--scheduler {address}: cannot connect ({exc.strerror or exc}); is "
                           f"the Dask scheduler running there?") from None


def _options(workers, scheduler, store, timeout, quick, progress, sweeps=False):
    from .report.plan import RunOptions
    if scheduler is not None:
        _reach_scheduler(scheduler)
    return RunOptions(workers=workers, scheduler=scheduler, store=store, quick=quick,
                      progress=progress, timeout=timeout, sweeps=sweeps)


def _sweeps_option(f):
    return click.option(
        "--sweeps", is_flag=True,
        help="Add the two sweep curves of the chapter 'What experiments measure' (the stick "
             "experiment's drift against a and D_x against the noise strength: 8 more "
             "circuit points at quick size, run at once: about 70 s more on 2 idle cores).")(f)


@main.command()
@click.argument("experiment")
@_run_options
def run(experiment, workers, scheduler, store, timeout, quick, progress):
    """Simulate EXPERIMENT (a name: ./circuits/<name>.toml, else a standard experiment; or a
    TOML path) on the circuit; resumable."""
    from .report import pipeline
    result = pipeline.run_experiment(experiment, _options(workers, scheduler, store, timeout,
                                                          quick, progress))
    click.echo(result.summary())


@main.command()
@click.argument("experiment")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              callback=_out_dir_option, default=None,
              help="Report directory (default report/<name>).")
@_run_options
@_sweeps_option
def report(experiment, out, workers, scheduler, store, timeout, quick, progress, sweeps):
    """Build the report of EXPERIMENT (a name or a TOML path: yours) from stored runs (runs
    what is missing)."""
    from .study.experiments import load_experiment
    from .report import pipeline
    exp = load_experiment(experiment)  # validated before anything runs
    out = out or Path("report") / exp.name
    index = pipeline.build_experiment_report(exp, out, _options(workers, scheduler, store,
                                                                timeout, quick, progress,
                                                                sweeps))
    click.echo(f"report: {index}")


@main.command()
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              callback=_out_dir_option, default=Path("report"),
              show_default=True, help="Where the report goes.")
@_run_options
@_sweeps_option
def paper(out, workers, scheduler, store, timeout, quick, progress, sweeps):
    """The main job: the paper's experiments (stick, slip, work; never your own files - use
    `report` for those), the paper's Figs. 1-9 with circuit data, metrics.json and the error
    budget, in one self-contained report."""
    from .report import pipeline
    index = pipeline.build_paper_report(out, _options(workers, scheduler, store, timeout, quick,
                                                      progress, sweeps))
    click.echo(f"report: {index}")


@main.command()
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              callback=_out_dir_option, default=Path("figures"),
              show_default=True)
def figures(out):
    """Draw the paper's theory figures (Figs. 1-9, weak-noise curves) as PNG files."""
    from .plots.paper_theory import draw_all
    for p in draw_all(out):
        click.echo(f"wrote {p}")


# -------------------------------------------------------------------------------- sweep
@main.command()
@click.argument("experiment")
@click.option("--vary", "vary", multiple=True, required=True, metavar="NAME=START:STOP:N",
              help="A model parameter and its grid: N evenly spaced values from START to STOP "
                   "(N = 1..64; append :log for geometric spacing); repeat for a grid over "
                   "several (at most 256 points).  NAME: tau_m, delta, a, gamma, mass, cubic "
                   "(delta_s, v_s with a Stribeck law).")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              callback=_out_dir_option, required=True,
              help="Directory for sweep.nc and the figures (mobility.png/svg when a is varied, "
                   "diffusion.png/svg when gamma is).")
@_run_options
def sweep(experiment, vary, out, workers, scheduler, store, timeout, quick, progress):
    """Sweep EXPERIMENT (a name or a TOML path) over model parameters: the circuit and the
    exact theory at every point (drift, variance, P(v>0), stick fraction, D_x, work rate,
    mean first-passage time to rest, with standard errors and budgets) in sweep.nc in the
    --out directory, with the figures; resumable from the run store."""
    import logging as _logging
    from .study.sweep import parse_vary_text, plan_sweep
    from .study.sweep import sweep as run_sweep
    from .plots.sweep import draw_sweep
    try:
        grid = parse_vary_text(vary)
        plan_sweep(experiment, grid, quick=quick)   # validated before anything runs
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--vary") from None
    logger = _logging.getLogger("analogue.sweep")
    for h in [h for h in logger.handlers if isinstance(h, _ProgressLines)]:
        logger.removeHandler(h)
    logger.addHandler(_ProgressLines())
    logger.setLevel(_logging.INFO)
    opts = _options(workers, scheduler, store, timeout, quick, progress)
    ds = run_sweep(experiment, grid, quick=quick, out=out, runner=opts.runner())
    click.echo(f"wrote {Path(out) / 'sweep.nc'}")
    for p in draw_sweep(ds, out):
        click.echo(f"wrote {p}")


# ------------------------------------------------------------------------------- export
@main.command()
@click.argument("experiment")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              callback=_out_dir_option, default=None,
              help="Output directory (default export/<experiment>).")
@click.option("--report", "report_dir", type=click.Path(path_type=Path), default=None,
              help="Report directory whose metrics.json goes to metrics.csv (default: "
                   "report/<experiment> or report/, if they hold this experiment).")
@_run_options
def export(experiment, out, report_dir, workers, scheduler, store, timeout, quick, progress):
    """Write every circuit run of EXPERIMENT as netCDF (<role>.nc) and metrics.csv.

    The runs are the report's of the same size (--quick or not; the line before it starts
    says which): from the store, running what is missing.  metrics.csv only from a report of
    these runs.  Read them back with analogue.open_ensemble(path) or
    xarray.open_dataset(path).
    """
    from .study.experiments import load_experiment
    from .export import export_experiment
    exp = load_experiment(experiment)
    out = out or Path("export") / exp.name
    # the size first (a full-size export after a --quick report runs other decks: issue 20)
    for p in export_experiment(exp, out, report=report_dir, quick=quick, store=store,
                               workers=workers, scheduler=scheduler, progress=progress,
                               timeout=timeout, say=lambda line: click.echo(f"export {line}",
                                                                            err=True)):
        click.echo(f"wrote {p}")


# -------------------------------------------------------------------------------- store
@main.group(cls=_Group)
def store():
    """See and bound the run store: ls (by experiment), du (sizes), prune (delete entries)."""


_store_option = click.option(
    "--store", "store_dir", default=None, metavar="DIRECTORY", callback=_store_dir_option,
    help="Run-store directory (default $ANALOGUE_STORE or ~/.cache/analogue/runs).")


def _when(t) -> str:
    if not t:
        return "-"
    from datetime import datetime
    return datetime.fromtimestamp(float(t), UTC).strftime("%Y-%m-%d %H:%M UTC")


@store.command("ls")
@_store_option
def store_ls(store_dir):
    """List the store by experiment: its runs, entries, size and last run."""
    from .circuit.store_index import format_size, usage
    u = usage(store_dir)
    click.echo(f"run store {u.root}")
    rows = [["experiment", "entries", "size", "last run", "runs"]]
    for name, e in sorted(u.experiments.items()):
        rows.append([name, str(e["entries"]), format_size(e["bytes"]), _when(e["updated"]),
                     ", ".join(e["runs"])])
    rows.append(["(not indexed)", str(u.unindexed_entries), format_size(u.unindexed_bytes),
                 "-", "simulate() calls outside an experiment, or older runs"])
    rows.append(["(quarantine)", str(u.quarantined), format_size(u.quarantined_bytes), "-",
                 "damaged entries moved aside"])
    widths = [max(len(r[j]) for r in rows) for j in range(4)]
    for r in rows:
        click.echo("  ".join([r[0].ljust(widths[0]), r[1].rjust(widths[1]),
                              r[2].rjust(widths[2]), r[3].ljust(widths[3]), r[4]]).rstrip())


@store.command("du")
@_store_option
def store_du(store_dir):
    """Disk usage of the store: total, per experiment, not indexed, quarantine."""
    from .circuit.store_index import format_size, usage
    u = usage(store_dir)
    rows = [(u.total_bytes, u.total_entries, f"total  {u.root}")]
    rows += [(e["bytes"], e["entries"], name) for name, e in sorted(u.experiments.items())]
    rows += [(u.unindexed_bytes, u.unindexed_entries, "(not indexed)"),
             (u.quarantined_bytes, u.quarantined, "(quarantine)")]
    for size, n, what in rows:
        click.echo(f"{format_size(size):>9}  {n:>6} entries  {what}")


@store.command("prune")
@_store_option
@click.option("--experiment", "experiments", multiple=True, metavar="NAME",
              help="Delete the entries of this experiment (repeatable).")
@click.option("--unindexed", is_flag=True, help="Delete entries no experiment index names.")
@click.option("--older-than", type=float, default=None, metavar="DAYS",
              help="Delete entries last used more than DAYS ago.")
@click.option("--max-size", default=None, metavar="SIZE",
              help="Then delete the least recently used entries until the store holds at most "
                   "SIZE (e.g. 500M, 2G).")
@click.option("--quarantine", is_flag=True, help="Empty the quarantine directory.")
@click.option("--dry-run", is_flag=True, help="Only say what would be deleted.")
def store_prune(store_dir, experiments, unindexed, older_than, max_size, quarantine, dry_run):
    """Delete store entries (the next run recomputes whatever it needs)."""
    from .circuit.store_index import format_size, parse_size, prune
    if not (experiments or unindexed or older_than is not None or max_size is not None
            or quarantine):
        raise click.UsageError("prune needs a criterion: --experiment, --unindexed, "
                               "--older-than, --max-size or --quarantine")
    max_bytes = None if max_size is None else parse_size(max_size)
    r = prune(store_dir, experiments=experiments, unindexed=unindexed,
              older_than_days=older_than, max_bytes=max_bytes, quarantine=quarantine,
              dry_run=dry_run)
    verb = "would delete" if dry_run else "deleted"
    click.echo(f"{verb} {r['entries']} entries ({format_size(r['bytes'])}) and "
               f"{r['quarantined']} quarantined entries")


# ------------------------------------------------------------------------------- theory
def _theory_help() -> str:
    # the catalogue alone: --help loads no theory (nor scipy)
    from .theory.quantities import OPTION_NAMES as names, QUANTITIES
    lines = []
    for q in QUANTITIES.values():
        opts = " ".join(names[o] for o in q.options)
        opts += "".join(f" [{names[o]}]" for o in q.optional)
        kinds = f"  --kind {'|'.join(q.kinds)}" if len(q.kinds) > 1 else ""
        lines.append(f"  {q.name:<22}{q.summary}")
        lines.append(f"  {'':<22}uses: {opts or '(model only)'}{kinds}")
    return "\n".join(lines)


THEORY_HELP = """Query theory values: QUANTITY for the model of EXPERIMENT (a name in
circuits/ or a TOML path, as for every command) and/or the model options, which override it.  Options a quantity does not use, and theories (--kind) it does not offer,
are refused; values that do not exist print as n/a with the reason (null in --json).

\b
QUANTITY is one of:
{quantities}

\b
Examples:
  analogue theory action --tau-m 1 --delta 0.7 --a 0.2 --gamma 10 --v0 2 --t 3 --v -0.5,0.5
  analogue theory path stick --v0 2 --t 3 --v 0.2 --points 20
  analogue theory boundaries stick --v0 2 --t 1,2,3
  analogue theory stationary stick --json
  analogue theory rate-function --tau-m 1 --delta 1 --a 0.5 --gamma 100 --w -1,0,1
"""


@main.command(help=THEORY_HELP.format(quantities=_theory_help()),
              short_help="Query theory values: propagator, action, optimal paths, boundaries, "
                         "rate function and more.")
@click.argument("quantity", metavar="QUANTITY",
                type=click.Choice(("stationary", "deterministic", "action", "path", "boundaries",
                                   "propagator", "rate-function", "fluctuation-relation", "scgf",
                                   "work-pdf")))
@click.argument("experiment_arg", metavar="[EXPERIMENT]", required=False)
@click.option("--experiment", default=None, metavar="EXPERIMENT",
              help="Same as the EXPERIMENT argument: take the model parameters from an "
                   "experiment (a name in circuits/ or a TOML path).")
@click.option("--tau-m", type=float, default=None, help="tau_m = m/alpha (> 0).")
@click.option("--delta", type=float, default=None, help="Delta = Delta_F/m (>= 0).")
@click.option("--a", "a", type=float, default=None, help="a = F/m.")
@click.option("--gamma", type=float, default=None, help="gamma = m^2/D (> 0).")
@click.option("--mass", type=float, default=None, help="m (> 0, default 1).")
@click.option("--epsilon", type=float, default=None, help="tanh width (>= 0, default 0 = sgn).")
@click.option("--v", "v", multiple=True, metavar="V[,V...]",
              help="Final velocities, comma-separated (or repeat the option).")
@click.option("--t", "t", multiple=True, metavar="T[,T...]",
              help="Times, comma-separated (or repeat the option).")
@click.option("--v0", type=float, default=None, callback=lambda c, p, x: _magnitude("--v0", x),
              help="Initial velocity.")
@click.option("--w", "w", multiple=True, metavar="W[,W...]",
              help="Work rates, comma-separated (or repeat the option).")
@click.option("--k", "k", multiple=True, metavar="K[,K...]",
              help="Tilts for the SCGF, comma-separated (or repeat the option).")
@click.option("--tau", type=float, default=None, callback=lambda c, p, x: _magnitude("--tau", x),
              help="Work time window.")
@click.option("--points", type=int, default=None,
              help="Points along an optimal path (path only; default 50).")
@click.option("--kind", type=click.Choice(["exact", "weak-noise", "limit"]), default=None,
              help="Which theory, where a quantity offers a choice (default: the first listed): "
                   "exact = finite-noise Fokker-Planck numerics; weak-noise = the paper's "
                   "formulas; limit = gamma -> infinity limit of the exact rate function.")
@click.option("--json", "as_json", is_flag=True,
              help="Machine-readable output (strict JSON: null with a reason, never NaN).")
def theory(quantity, experiment_arg, experiment, tau_m, delta, a, gamma, mass, epsilon, v, t, v0, w, k, tau,
           points, kind, as_json):
    from .theory.query import theory_table
    if experiment_arg and experiment and experiment_arg != experiment:
        raise click.UsageError(f"two experiments given: {experiment_arg!r} and --experiment "
                               f"{experiment!r}")
    experiment = experiment_arg or experiment
    params = {}
    if experiment:
        from .study.experiments import load_experiment
        params = load_experiment(experiment).model.as_dict()
    given = {"tau_m": tau_m, "delta": delta, "a": a, "gamma": gamma, "mass": mass, "epsilon": epsilon}
    params.update({key: val for key, val in given.items() if val is not None})
    missing = [key for key in ("tau_m", "delta", "a", "gamma") if key not in params]
    if missing:
        raise click.UsageError("missing model parameter(s): "
                               + ", ".join("--" + m.replace("_", "-") for m in missing))
    model = Model(**params)
    tab = theory_table(model, quantity, v=_floats("--v", v), t=_floats("--t", t), v0=v0,
                       w=_floats("--w", w), k=_floats("--k", k), tau=tau, points=points,
                       kind=kind)
    if as_json:
        click.echo(json.dumps(tab.as_json(model), indent=2, allow_nan=False))
    else:
        click.echo(tab.as_text())


# -------------------------------------------------------------------------------- board
@main.command()
@click.argument("experiment")
@click.option("--out", type=click.Path(file_okay=False, path_type=Path),
              callback=_out_dir_option, required=True,
              help="Directory for schematic.svg, bom.csv, board.net, board.cir, metrics.json, index.html.")
@click.option("--quick", is_flag=True, help="Few boards, short runs (about two minutes).")
@click.option("--workers", type=click.IntRange(1, 256), default=None,
              help="ngspice processes at once (default: the CPUs this process may use).")
@click.option("--store", "board_store", default=None, metavar="DIRECTORY",
              callback=_store_dir_option, help="Run-store directory (default $ANALOGUE_STORE or ~/.cache/analogue/runs).")
@click.option("--seed", type=click.IntRange(0, 2**31 - 1), default=None,
              help="Master seed (default: the experiment's).")
@click.option("--opamp-model", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="A vendor op-amp model you downloaded (.lib/.cir; never shipped here) for the "
                   "nominal board; needs --opamp-subckt.")
@click.option("--opamp-subckt", default=None, help="Name of its .subckt (pins in+ in- V+ V- out).")
def board(experiment, out, quick, workers, board_store, seed, opamp_model, opamp_subckt):
    """A board you can build for EXPERIMENT: op-amp realisation with E-series parts, noise
    chain, tolerance Monte Carlo, calibration, schematic.svg and bom.csv."""
    from .board.job import run_board_job
    if (opamp_model is None) != (opamp_subckt is None):
        raise click.UsageError("--opamp-model and --opamp-subckt go together")
    vendor = (opamp_model, opamp_subckt) if opamp_model is not None else None
    index = run_board_job(experiment, out, quick=quick, store=board_store, workers=workers,
                          seed=seed, log=lambda msg: click.echo(msg, err=True), vendor=vendor)
    click.echo(f"board report: {index}")


if __name__ == "__main__":  # pragma: no cover
    main()
