"""Running ngspice in batch mode: find the executable, its version, run one deck, resample.

Every deck runs as ``ngspice -b -r out.raw deck.cir`` in its own temporary directory, in a
separate process (a crash or a hang cannot take the caller down: there is a timeout), with
stdout/stderr captured so that a failure raises :class:`NgspiceError` quoting ngspice's own
message.  The binary raw file is read with :func:`analogue.circuit.rawfile.read_raw`.

Two ngspice 39 facts shape this module (see shared/theory.md):

* ``.options interp`` together with ``-r`` writes a raw file whose header disagrees with its
  data, so the simulator's own (non-uniform) time points are kept and resampled onto the
  requested grid here, by linear interpolation (:func:`resample`).
* With ``.tran ... uic`` the raw file does not contain the t = 0 point (the first point is the
  first time step); the caller knows the initial values (they are the deck's ``.ic``) and
  passes them as ``initial`` so the grid point t = 0 is exact rather than extrapolated.
"""
from __future__ import annotations

import functools
import re
import shutil
import subprocess
import tempfile
import threading
import time as _time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .rawfile import RawPlot, read_raw

__all__ = ["NgspiceError", "NgspiceNotFoundError", "RunResult", "find_ngspice",
           "ngspice_version", "run_deck", "terminate_group", "resample", "interp_rows"]

INSTALL_HINT = ("install it with your package manager, e.g. `sudo apt-get install ngspice` "
                "(Debian/Ubuntu), `brew install ngspice` (macOS) or `conda install -c "
                "conda-forge ngspice`, or put the ngspice executable on PATH")


class NgspiceError(RuntimeError):
    """ngspice failed (non-zero exit, timeout, missing or incomplete output)."""


class NgspiceNotFoundError(NgspiceError, FileNotFoundError):
    """No ngspice executable on PATH."""


def find_ngspice() -> str:
    """Absolute path of the ``ngspice`` executable on PATH (looked up at every call, so a
    changed PATH is honoured)."""
    exe = shutil.which("ngspice")
    if exe is None:
        raise NgspiceNotFoundError(f"ngspice executable not found on PATH; {INSTALL_HINT}")
    return exe


@functools.lru_cache(maxsize=8)
def _version_of(executable: str) -> str:
    try:
        out = subprocess.run([executable, "-v"], capture_output=True, text=True, timeout=30,
                             stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise NgspiceError(f"could not run `{executable} -v`: {exc}") from exc
    text = out.stdout + out.stderr
    # "** ngspice-39 : Circuit level simulation program" (newer builds: "ngspice-42.1 ...")
    m = re.search(r"ngspice-(\d+(?:\.\d+)*\+?)", text)
    if m is None:
        raise NgspiceError(f"cannot parse the ngspice version from `{executable} -v`:\n{text.strip()}")
    return m.group(1)


def ngspice_version() -> str:
    """Version of the ngspice on PATH as printed by ``ngspice -v`` (e.g. ``"39"``); cached per
    executable path."""
    return _version_of(find_ngspice())


@dataclass(frozen=True)
class RunResult:
    """Outcome of one batch run: the transient plot and what ngspice said."""

    plot: RawPlot
    stdout: str = field(repr=False)
    stderr: str = field(repr=False)
    wall_time: float
    version: str


def _tail(text: str, lines: int = 25) -> str:
    kept = [ln for ln in text.strip().splitlines() if ln.strip()]
    return "\n".join(kept[-lines:])


# Running ngspice processes by caller-chosen group, so that a caller whose run failed or was
# interrupted can stop the processes it started (and only those) instead of letting them run on.
_ACTIVE: dict = {}
_CANCELLED: set = set()
_ACTIVE_LOCK = threading.Lock()


def terminate_group(group) -> int:
    """Kill the ngspice processes still running for ``group`` (and any it would start later);
    returns how many were killed."""
    with _ACTIVE_LOCK:
        procs = list(_ACTIVE.pop(group, ()))
        if group is not None:
            _CANCELLED.add(group)
    killed = 0
    for proc in procs:
        if proc.poll() is None:
            proc.kill()
            killed += 1
    return killed


def run_deck(text: str, *, timeout: float = 3600.0, t_stop: float | None = None,
             keep_dir=None, group=None) -> RunResult:
    """Run one complete deck (``.end``-terminated, no ``.control`` block) in batch mode.

    Parameters
    ----------
    text : the deck.
    timeout : seconds before the ngspice process is killed (NgspiceError).
    t_stop : if given (seconds), the transient plot must reach this time, else the run is
        reported as incomplete (ngspice 39 exits 0 after some aborted analyses).
    keep_dir : if given, the deck, raw file and logs are written there and kept (debugging);
        otherwise a temporary directory is used and removed.
    group : any hashable; the process can be stopped by :func:`terminate_group` (group).
    """
    if not isinstance(text, str) or not text.strip():
        raise ValueError("text must be a non-empty SPICE deck string")
    if not text.rstrip().lower().endswith(".end"):
        raise ValueError("text must be a complete deck ending with '.end'")
    if not (isinstance(timeout, (int, float)) and timeout > 0):
        raise ValueError(f"timeout must be a number of seconds > 0, got {timeout!r}")
    exe = find_ngspice()
    version = _version_of(exe)
    with tempfile.TemporaryDirectory(prefix="analogue-ngspice-") as tmp:
        work = Path(keep_dir) if keep_dir is not None else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        (work / "deck.cir").write_text(text)
        raw = work / "out.raw"
        t0 = _time.perf_counter()
        proc = subprocess.Popen([exe, "-b", "-r", raw.name, "deck.cir"], cwd=work,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                stdin=subprocess.DEVNULL)
        with _ACTIVE_LOCK:
            _ACTIVE.setdefault(group, set()).add(proc)
            if group in _CANCELLED:
                proc.kill()  # its run was given up while this deck was being prepared
        try:
            stdout, stderr = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            _, stderr = proc.communicate()
            raise NgspiceError(f"ngspice did not finish within timeout={timeout} s"
                               + (f"; it said:\n{_tail(stderr)}" if stderr.strip() else "")) from None
        except BaseException:
            proc.kill()  # interrupted while waiting: do not leave the process behind
            proc.communicate()
            raise
        finally:
            with _ACTIVE_LOCK:
                live = _ACTIVE.get(group)
                if live is not None:
                    live.discard(proc)
                    if not live:
                        del _ACTIVE[group]
        wall = _time.perf_counter() - t0
        if keep_dir is not None:
            (work / "stdout.txt").write_text(stdout)
            (work / "stderr.txt").write_text(stderr)
        if proc.returncode != 0:
            said = _tail(stderr) or _tail(stdout)
            if proc.returncode < 0:
                raise NgspiceError(f"ngspice was stopped by signal {-proc.returncode}"
                                   + (f"; it said:\n{said}" if said else ""))
            raise NgspiceError(f"ngspice exited with status {proc.returncode}; it said:\n{said}")
        if not raw.exists():
            raise NgspiceError("ngspice wrote no raw file; it said:\n"
                               + (_tail(stderr) or _tail(stdout)))
        try:
            plots = read_raw(raw)
        except ValueError as exc:
            raise NgspiceError(f"unreadable raw file ({exc}); ngspice said:\n"
                               + _tail(stderr)) from None
    tran = [p for p in plots if "transient" in p.plotname.lower()]
    if not tran:
        raise NgspiceError("the raw file holds no transient plot (plots: "
                           f"{[p.plotname for p in plots]}); ngspice said:\n{_tail(stderr)}")
    plot = tran[-1]
    if t_stop is not None:
        reached = float(plot["time"][-1]) if plot.n_points else 0.0
        if reached < t_stop * (1.0 - 1e-9):
            raise NgspiceError(f"transient stopped at t = {reached:.6g} s before t_stop = "
                               f"{t_stop:.6g} s; ngspice said:\n{_tail(stderr)}")
    return RunResult(plot=plot, stdout=stdout, stderr=stderr, wall_time=wall, version=version)


def resample(plot: RawPlot, names, times, initial=None) -> np.ndarray:
    """Vectors ``names`` linearly interpolated onto ``times`` (seconds, increasing).

    Returns a (len(names), len(times)) array.  ``initial`` (len(names),) are the values at
    t = 0, prepended when the raw file starts after t = 0 (``uic`` runs).  ``times`` must lie
    within the simulated interval (up to a relative 1e-9 at the end, which is clipped).
    """
    times = np.asarray(times, dtype=float)
    t_raw = plot["time"]
    vals = plot.columns(list(names))
    if initial is not None and t_raw[0] > 0:
        initial = np.asarray(initial, dtype=float).reshape(-1, 1)
        if initial.shape[0] != vals.shape[0]:
            raise ValueError("initial must have one value per vector name")
        t_raw = np.concatenate([[0.0], t_raw])
        vals = np.hstack([initial, vals])
    if times.size and (times[0] < t_raw[0] - 1e-12 * max(1.0, abs(t_raw[-1]))
                       or times[-1] > t_raw[-1] * (1 + 1e-9)):
        raise ValueError(f"times [{times[0]:.6g}, {times[-1]:.6g}] s lie outside the simulated "
                         f"interval [{t_raw[0]:.6g}, {t_raw[-1]:.6g}] s")
    return interp_rows(t_raw, vals, times)


def interp_rows(t_raw, rows, times) -> np.ndarray:
    """Linear interpolation of every row of ``rows`` (n, len(t_raw)) at ``times`` (clipped to
    the range of ``t_raw``, which must be non-decreasing); vectorised over rows."""
    t_raw = np.asarray(t_raw, dtype=float)
    rows = np.asarray(rows, dtype=float)
    tq = np.clip(np.asarray(times, dtype=float), t_raw[0], t_raw[-1])
    # One searchsorted for all rows (they share the time axis); side="right" and the step
    # back mean repeated breakpoint times (ngspice can emit a time twice) never give a
    # zero-width interval inside the data.
    i = np.clip(np.searchsorted(t_raw, tq, side="right"), 1, t_raw.size - 1)
    t_lo, t_hi = t_raw[i - 1], t_raw[i]
    span = t_hi - t_lo
    w = np.divide(tq - t_lo, span, out=np.zeros_like(tq), where=span > 0)
    return rows[:, i - 1] * (1.0 - w) + rows[:, i] * w
