"""Running ngspice in batch mode: find the executable, its version, run one deck, resample.

Every deck runs as ``ngspice -b -r out.raw deck.cir`` in its own temporary directory, in a
separate process (a crash or a hang cannot take the caller down: there is a timeout), with
stdout/stderr captured so that a failure raises :class:`NgspiceError` quoting ngspice's own
message.  The binary raw file is read with :func:`analogue.circuit.rawfile.read_raw`.

Two ngspice 39 facts shape this module (measured on ngspice 39 while writing it):

* ``.options interp`` together with ``-r`` writes a raw file whose header disagrees with its
  data, so the simulator's own (non-uniform) time points are kept and resampled onto the
  requested grid here, by linear interpolation (:func:`resample`).
* With ``.tran ... uic`` the raw file does not contain the t = 0 point (the first point is the
  first time step); the caller knows the initial values (they are the deck's ``.ic``) and
  passes them as ``initial`` so the grid point t = 0 is exact rather than extrapolated.
"""
from __future__ import annotations

import atexit
import collections
import fcntl
from typing import Any
import functools
import os
import re
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time as _time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import checks
from ..cores import one_thread_env
from ..files import utf8 as _utf8
from .limits import format_bytes, memory_limit
from .rawfile import RawPlot, read_raw

__all__ = [
    "NgspiceError",
    "NgspiceNotFoundError",
    "RunInterrupted",
    "RunResult",
    "check_deck",
    "find_ngspice",
    "interp_rows",
    "interrupt_guard",
    "ngspice_version",
    "output_problem",
    "resample",
    "run_deck",
    "terminate_all",
    "terminate_group",
]

INSTALL_HINT = ("install it with your package manager, e.g. `sudo apt-get install ngspice` "
                "(Debian/Ubuntu), `brew install ngspice` (macOS) or `conda install -c "
                "conda-forge ngspice`, or put the ngspice executable on PATH")

#: seconds allowed for ``ngspice -v`` (it takes ~50 ms; a wrapper that hangs must not block).
VERSION_TIMEOUT = 20.0
#: longest error message quoted from ngspice (characters); it is one line.
MESSAGE_MAX = 1000
#: bytes of ngspice's stdout/stderr kept in memory (the end of each: that is where errors are).
LOG_TAIL_BYTES = 256 * 1024
TMP_PREFIX = "analogue-ngspice-"


class NgspiceError(RuntimeError):
    """ngspice failed (non-zero exit, timeout, missing or incomplete output).  The message is
    one line and quotes ngspice's own error lines joined by `` | ``."""


class NgspiceNotFoundError(NgspiceError, FileNotFoundError):
    """No ngspice executable on PATH."""


class RunInterrupted(KeyboardInterrupt):
    """A run was stopped by SIGINT, SIGTERM or SIGHUP: the ngspice process groups were killed
    and their temporary directories removed; decks that had finished are in the run store.

    A KeyboardInterrupt (``except Exception`` does not swallow it).  ``signum`` is the signal,
    ``exit_code`` the shell convention 128 + signum (130 for SIGINT, 143 for SIGTERM) that the
    CLI exits with; ``str()`` is a one-line message."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = int(signum)
        self.exit_code = 128 + self.signum

    def __str__(self) -> str:
        return (f"interrupted by {_signal_name(self.signum)}: the running ngspice processes "
                f"were stopped and their temporary files removed; finished decks are kept in "
                f"the run store, so running the same command again resumes")


def _signal_name(signum: int) -> str:
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


def find_ngspice() -> str:
    """Absolute path of the ``ngspice`` executable on PATH (looked up at every call, so a
    changed PATH is honoured)."""
    exe = shutil.which("ngspice")
    if exe is None:
        raise NgspiceNotFoundError(f"ngspice executable not found on PATH; {INSTALL_HINT}")
    return exe


def _one_line(text: str, limit: int = MESSAGE_MAX) -> str:
    """Non-empty lines of ``text`` joined by " | " (whitespace collapsed, consecutive
    duplicates dropped); longer than ``limit``: its start and its end around " ... "."""
    out: list[str] = []
    for ln in text.splitlines():
        ln = " ".join(ln.split())
        if ln and (not out or out[-1] != ln):
            out.append(ln)
    joined = " | ".join(out)
    if len(joined) > limit:
        half = (limit - 5) // 2
        joined = joined[:half].rstrip() + " ... " + joined[-half:].lstrip()
    return joined


# ngspice chatter that is never the reason of a failure
_NOISE = re.compile(r"^\s*(note: no resource usage|or no active circuit available|"
                    r"note: no compatibility mode selected)", re.IGNORECASE)


def _said(stdout: str, stderr: str) -> str:
    """ngspice's own error lines, as one line: all of stderr (minus known chatter), or the
    stdout lines mentioning an error when stderr is empty."""
    lines = [ln for ln in stderr.splitlines() if not _NOISE.match(ln)]
    if not any(ln.strip() for ln in lines):
        lines = [ln for ln in stdout.splitlines()
                 if re.search(r"error|abort|fatal", ln, re.IGNORECASE)]
    return _one_line("\n".join(lines))


def _with_said(msg: str, said: str) -> str:
    return f"{msg}; ngspice said: {said}" if said else msg


def _read_tail(path: Path) -> str:
    """The last LOG_TAIL_BYTES of a log file as text (missing file: "")."""
    try:
        with open(path, "rb") as fh:
            fh.seek(0, os.SEEK_END)
            size = fh.tell()
            fh.seek(max(0, size - LOG_TAIL_BYTES))
            data = fh.read()
    except OSError:
        return ""
    return data.decode("utf-8", errors="replace")


# --------------------------------------------------------------------- supervised processes
# Every ngspice runs in its own session (process group), so that a timeout or an interrupt
# kills it and everything it started (a wrapper script's children included).  Its output
# goes to files, not pipes: a child that inherited stdout can never make us wait for EOF.
_ACTIVE: dict = {}          # group -> set of Popen
# Groups given up (terminate_group): a deck of theirs that starts later is killed at once.
# Bounded, oldest first out: a deck starts within its own run, long before 256 later runs
# have been cancelled (on a Dask worker nobody else would ever prune this).
_CANCELLED: collections.OrderedDict = collections.OrderedDict()
_CANCELLED_MAX = 256
# Re-entrant: the signal handler (terminate_all) runs in the main thread between any two
# bytecodes, also inside a `with _ACTIVE_LOCK` of that thread (a deck run from the main thread
# tracking its process); a plain Lock would deadlock it there, and the exit timer with it.
_ACTIVE_LOCK = threading.RLock()


def _kill_tree(proc) -> None:
    """SIGKILL the process group led by ``proc`` (its session), ignoring a group already gone.
    Safe after ``proc`` was reaped: a process-group id stays reserved while any member lives."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    except OSError:
        pass


def _spawn(argv, cwd, stdout, stderr):
    # HOME is the run's own directory: ngspice 39 segfaults without one (issue 19: HOME unset
    # gave a bare SIGSEGV) and reads ~/.spiceinit from it, which could change any deck's
    # numbers on one machine only; the deck is the whole circuit.
    # OpenMP/BLAS capped at one thread (analogue.cores.ONE_THREAD_ENV): ngspice is linked
    # against libgomp and runs beside `workers` other processes.
    env = {**one_thread_env(), "HOME": str(cwd)}
    return subprocess.Popen(argv, cwd=cwd, stdin=subprocess.DEVNULL, stdout=stdout,
                            stderr=stderr, start_new_session=True, env=env)


def _wait(proc, timeout: float) -> int:
    """Wait for ``proc``; on timeout or any interruption kill its group (and reap it)."""
    try:
        return proc.wait(timeout=timeout)
    except BaseException:
        _kill_tree(proc)
        proc.wait()
        raise
    finally:
        _kill_tree(proc)  # stray children of a wrapper that exited: never left running


@functools.lru_cache(maxsize=8)
def _version_of(executable: str) -> str:
    with _owned_tmpdir() as tmp:
        out_p, err_p = Path(tmp) / "stdout.txt", Path(tmp) / "stderr.txt"
        try:
            _run_guarded([executable, "-v"], tmp, out_p, err_p, None, VERSION_TIMEOUT)
        except subprocess.TimeoutExpired:
            raise NgspiceError(f"`{executable} -v` did not answer within {VERSION_TIMEOUT:g} s "
                               f"(is it a working ngspice?)") from None
        except OSError as exc:
            raise NgspiceError(f"could not run `{executable} -v`: {exc}") from None
        text = _read_tail(out_p) + "\n" + _read_tail(err_p)
    # "** ngspice-39 : Circuit level simulation program" (newer builds: "ngspice-42.1 ...")
    m = re.search(r"ngspice-(\d+(?:\.\d+)*\+?)", text)
    if m is None:
        raise NgspiceError(f"cannot parse the ngspice version from `{executable} -v`, which "
                           f"printed: {_one_line(text) or '(nothing)'}")
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


def _track(proc, group) -> None:
    with _ACTIVE_LOCK:
        _ACTIVE.setdefault(group, set()).add(proc)
        cancelled = (group is not None and group in _CANCELLED) or _STOPPING.is_set()
    if cancelled:
        _kill_tree(proc)  # its run was given up while this deck was being prepared


def _untrack(proc, group) -> None:
    with _ACTIVE_LOCK:
        live = _ACTIVE.get(group)
        if live is not None:
            live.discard(proc)
            if not live:
                del _ACTIVE[group]


def terminate_group(group) -> int:
    """Kill the ngspice process groups still running for ``group`` (and any it would start
    later); returns how many were killed."""
    with _ACTIVE_LOCK:
        procs = list(_ACTIVE.pop(group, ()))
        if group is not None:
            _CANCELLED[group] = None
            _CANCELLED.move_to_end(group)
            while len(_CANCELLED) > _CANCELLED_MAX:
                _CANCELLED.popitem(last=False)
    killed = 0
    for proc in procs:
        if proc.poll() is None:
            killed += 1
        _kill_tree(proc)
    return killed


def terminate_all() -> int:
    """Kill every ngspice process group this process started and that still runs (used by the
    signal handlers and at interpreter exit); returns how many were running."""
    with _ACTIVE_LOCK:
        procs = [p for group in _ACTIVE.values() for p in group]
    killed = 0
    for proc in procs:
        if proc.poll() is None:
            killed += 1
        _kill_tree(proc)
    return killed


# Interpreter exit (a Dask worker closing, sys.exit in a script): kill our ngspice groups
# *before* the thread pools are joined, so that exiting never waits for a deck to finish.
# threading's exit hooks run in reverse order of registration, before atexit's.
try:
    threading._register_atexit(terminate_all)  # type: ignore[attr-defined]
except (AttributeError, RuntimeError):  # pragma: no cover - other interpreters
    atexit.register(terminate_all)


# ------------------------------------------------------------------------- signal handling
_GUARD_LOCK = threading.RLock()
_GUARD: dict[str, Any] = {"depth": 0, "previous": {}, "raised": False, "deferred": None}
_GUARDED_SIGNALS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP")
                         if hasattr(signal, n))
# Set by a guarded signal, cleared when the outermost guard ends: while it is set no
# ngspice starts (run_deck refuses, _track kills), so a pool thread that takes the next
# queued deck after the signal's terminate_all cannot run it to the end (the noise-free run
# of `analogue run stick --quick` is one deck of about 10 s).
_STOPPING = threading.Event()
# Seconds a command-line process may spend unwinding after a signal before it exits anyway
# (None: never, the library default; the CLI sets it with exit_after_signal).
_EXIT_GRACE: dict[str, float | None] = {"s": None}


def exit_after_signal(grace_s: float | None) -> None:
    """For a command-line process: after a guarded signal, exit with 128 + signal once
    ``grace_s`` seconds have passed if unwinding has not ended the process by then, and at
    once on a second signal (killing every ngspice first).  A library caller (a notebook)
    keeps the default None: its process is never ended here."""
    _EXIT_GRACE["s"] = grace_s


def _hard_exit(signum: int, why: str) -> None:
    """End the process now with 128 + signum: ngspice killed, our temporary directories
    removed (the store's writes are atomic: a half-written entry is a .tmp file that the
    next run removes).  Never blocks on a lock (it is the last resort)."""
    if _ACTIVE_LOCK.acquire(timeout=0.5):  # a holder gets half a second to finish, no more
        _ACTIVE_LOCK.release()
    procs = [p for group in list(_ACTIVE.values()) for p in list(group)]
    for proc in procs:
        _kill_tree(proc)
    for d in Path(tempfile.gettempdir()).glob(f"{_tmp_prefix()}*"):
        shutil.rmtree(d, ignore_errors=True)
    try:
        os.write(2, f"analogue: error: {RunInterrupted(signum)} ({why})\n".encode(
            "utf-8", "replace"))
    finally:
        os._exit(128 + signum)


def _on_signal(signum, frame):
    if _GUARD["deferred"] is not None:
        # between starting ngspice and tracking it (:func:`_signals_deferred`): acting now
        # would leave the new process out of terminate_all and orphan it in its own session
        _GUARD["deferred"].append(signum)
        return
    _STOPPING.set()
    terminate_all()  # first of all: no ngspice keeps running while we unwind
    prev = _GUARD["previous"].get(signum)
    if callable(prev) and prev is not signal.default_int_handler:
        prev(signum, frame)  # the caller's own handler (chained)
        return
    grace = _EXIT_GRACE["s"]
    if _GUARD["raised"]:
        # already unwinding: the processes are dead; a user who signals again wants out
        if grace is not None:
            _hard_exit(signum, "second signal while cleaning up")
        return
    _GUARD["raised"] = True
    if grace is not None:
        timer = threading.Timer(grace, _hard_exit,
                                args=(signum, f"clean-up did not end within {grace:g} s"))
        timer.daemon = True
        timer.start()
    raise RunInterrupted(signum)


@contextmanager
def interrupt_guard():
    """While active (main thread only; elsewhere a no-op), SIGINT, SIGTERM and SIGHUP kill
    every ngspice process group of this process and raise :class:`RunInterrupted` in the main
    thread, so that ``finally`` blocks and temporary directories are cleaned up instead of the
    process dying on the spot.  Signals set to be ignored stay ignored; a handler the caller
    installed is chained (called after the kill).  Re-entrant; restores the previous handlers."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    with _GUARD_LOCK:
        if _GUARD["depth"] == 0:
            _GUARD["raised"] = False
            _STOPPING.clear()
            _GUARD["previous"] = {}
            for sig in _GUARDED_SIGNALS:
                prev = signal.getsignal(sig)
                if prev is signal.SIG_IGN:
                    continue  # e.g. nohup: the user asked for this signal to be ignored
                _GUARD["previous"][sig] = prev
                signal.signal(sig, _on_signal)
        _GUARD["depth"] += 1
    try:
        yield
    finally:
        with _GUARD_LOCK:
            _GUARD["depth"] -= 1
            if _GUARD["depth"] == 0:
                _STOPPING.clear()  # the interrupted call has unwound: later calls may run
                for sig, prev in _GUARD["previous"].items():
                    signal.signal(sig, prev if prev is not None else signal.SIG_DFL)
                _GUARD["previous"] = {}


@contextmanager
def _signals_deferred():
    """Inside an :func:`interrupt_guard` of the main thread: a guarded signal that arrives in
    the block is acted on when the block ends (so a process started and tracked in it is
    killed with the others), not in the middle of it.  Elsewhere a no-op."""
    if threading.current_thread() is not threading.main_thread() or _GUARD["depth"] == 0:
        yield
        return
    _GUARD["deferred"] = []
    try:
        yield
    finally:
        pending, _GUARD["deferred"] = _GUARD["deferred"], None
        if pending:
            _on_signal(pending[0], None)


def _run_guarded(argv, cwd, out_p: Path, err_p: Path, group, timeout: float) -> int:
    """Run ``argv`` in its own session with its output in the files ``out_p``, ``err_p``,
    tracked for :func:`terminate_all` under ``group``, and return its exit status.  Called
    from the main thread (a script, a calibration run, ``ngspice -v``), a signal must not kill
    us and orphan the process in its own session: the guard is in place before the start (a
    no-op in worker threads, whose caller's guard covers them; re-entrant), and a signal
    between the start and the tracking is acted on once the process is tracked (measured: a
    loaded machine let the fake ngspice of tests/faults start its child before this thread
    reached a guard installed after the start, and SIGHUP then killed Python by default).
    Raises OSError (could not start) and subprocess.TimeoutExpired (killed after
    ``timeout``)."""
    proc = None
    try:
        with interrupt_guard():
            with _signals_deferred():
                with open(out_p, "wb") as out, open(err_p, "wb") as err:
                    proc = _spawn(argv, cwd, out, err)
                _track(proc, group)
            return _wait(proc, timeout)
    finally:
        if proc is not None:
            _untrack(proc, group)


# ------------------------------------------------------------------------- temporary dirs
def _tmp_prefix() -> str:
    """``analogue-ngspice-<host>.<pid>-``: lets a later run recognise directories left by a
    process that was killed outright (SIGKILL) and remove them."""
    host = re.sub(r"[^A-Za-z0-9_-]", "_", socket.gethostname())[:40] or "host"
    return f"{TMP_PREFIX}{host}.{os.getpid()}-"


# A directory is in use while its owner holds an exclusive flock on this file; the kernel
# drops the lock when the owner dies however it dies (SIGKILL, the OOM killer), so a lock
# that can be taken marks an abandoned directory, whatever its age or its pid's fate.
OWNER_LOCK = ".owner.lock"
#: seconds between two sweeps of abandoned directories in one process
SWEEP_EVERY_S = 60.0
_LAST_SWEEP: list[float | None] = [None]


@contextmanager
def _owned_tmpdir():
    """A fresh ``analogue-ngspice-*`` temporary directory (its path, a str), locked for the
    block (:data:`OWNER_LOCK`) and removed after it.  The lock file is locked before it gets
    its name, so a sweep never sees it unlocked while its owner lives."""
    with tempfile.TemporaryDirectory(prefix=_tmp_prefix()) as tmp:
        fd = os.open(os.path.join(tmp, OWNER_LOCK + ".new"), os.O_WRONLY | os.O_CREAT, 0o600)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            os.rename(os.path.join(tmp, OWNER_LOCK + ".new"), os.path.join(tmp, OWNER_LOCK))
            yield tmp
        finally:
            os.close(fd)


def _abandoned(d: Path, pid: int, now: float, min_age: float) -> bool:
    """Whether ``d`` (an ``analogue-ngspice-*`` directory of process ``pid`` of this host) is
    no longer in use: its owner lock can be taken, or (no lock: a directory of an older
    version, or one being created) its process is gone and it is older than ``min_age``."""
    try:
        fd = os.open(d / OWNER_LOCK, os.O_RDONLY)
    except FileNotFoundError:
        try:
            os.kill(pid, 0)
            return False  # its process is alive (maybe creating it)
        except ProcessLookupError:
            pass
        except (PermissionError, OverflowError):
            return False
        try:
            return now - d.lstat().st_mtime >= min_age and d.is_dir() and not d.is_symlink()
        except OSError:
            return False
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except OSError:
        return False  # held: in use
    finally:
        os.close(fd)


def sweep_stale_tmp(min_age: float = 60.0) -> int:
    """Remove ``analogue-ngspice-*`` directories in the temporary directory that belong to a
    process of this host that is no longer using them (killed by SIGKILL or the OOM killer):
    their owner lock (:data:`OWNER_LOCK`) can be taken; directories without one (left by an
    older version) once their process is gone and they are older than ``min_age`` seconds.
    Returns how many were removed."""
    root = Path(tempfile.gettempdir())
    host = re.sub(r"[^A-Za-z0-9_-]", "_", socket.gethostname())[:40] or "host"
    removed = 0
    try:
        candidates = list(root.glob(f"{TMP_PREFIX}{host}.*-*"))
    except OSError:
        return 0
    now = _time.time()
    for d in candidates:
        m = re.fullmatch(re.escape(f"{TMP_PREFIX}{host}.") + r"(\d+)-.*", d.name)
        if not m or int(m.group(1)) == os.getpid() or d.is_symlink() or not d.is_dir():
            continue
        if _abandoned(d, int(m.group(1)), now, min_age):
            shutil.rmtree(d, ignore_errors=True)
            removed += 1
    return removed


def _sweep_now_and_then() -> None:
    """:func:`sweep_stale_tmp` at the first deck of a process and then at most every
    :data:`SWEEP_EVERY_S` (issue 19: once per process left a killed run's directories for
    ever when the next run came within the minute)."""
    now = _time.monotonic()
    last = _LAST_SWEEP[0]
    if last is not None and now - last < SWEEP_EVERY_S:
        return
    _LAST_SWEEP[0] = now
    sweep_stale_tmp()


# ---------------------------------------------------------------------------- deck screen
# A deck is a program: `.control` blocks run commands (`shell`), `.include`/`.lib` read other
# files, `.osdi` loads compiled code, and a first line `*ng_script` turns the file into a
# script.  Decks built by analogue contain none of these; refusing them here protects every
# caller of run_deck, not only the experiment loader.
_FORBIDDEN = re.compile(r"^\s*(\.control|\.endc|\.inc\w*|\.lib\b|\.endl|\.osdi|\.exec|"
                        r"shell\b)", re.IGNORECASE)


def check_deck(text: str) -> str:
    """``text`` if it is a complete deck without commands, includes or libraries; else
    ValueError naming the offending line.  The first line is the title (never executed)."""
    if not isinstance(text, str) or not text.strip():
        raise ValueError("text must be a non-empty SPICE deck string")
    if not text.rstrip().lower().endswith(".end"):
        raise ValueError("text must be a complete deck ending with '.end'")
    lines = text.splitlines()
    if lines and lines[0].strip().lower().startswith("*ng_script"):
        raise ValueError("deck refused: its first line '*ng_script' makes it an ngspice script")
    for no, line in enumerate(lines[1:], start=2):
        m = _FORBIDDEN.match(line)
        if m:
            raise ValueError(f"deck refused: line {no} starts with '{m.group(1)}' (control "
                             f"blocks, shell commands, includes and libraries are not allowed "
                             f"in decks run by analogue)")
    return text


# ------------------------------------------------------------------------ files it reads
# XSPICE models read files named in the deck (filesource's ``file="..."``, d_source's
# ``input_file``, d_state's ``state_file``).  ngspice 39 lower-cases the name before opening it
# (measured: ``file="/tmp/X/dac.txt"`` -> "Instance: ad Message: cannot open file
# /tmp/x/dac.txt", exit status 0, the source then outputs 0 V).  So every such file is linked
# into the deck's own working directory under a lower-case name, and the deck that ngspice
# reads names it relatively: the path survives whatever the directories are called.
_FILE_REF = re.compile(r'(?<![A-Za-z0-9])((?:[A-Za-z]+_)?file\s*=\s*)"([^"]*)"', re.IGNORECASE)
_LOCAL_NAME = re.compile(r"[a-z0-9_][a-z0-9_.+-]*")
# What ngspice 39 prints, often without failing, when a deck's file, model, device or code
# model cannot be loaded (its message strings): any of these ends the run as an error (a
# deck never runs without its input).  Notes and warnings about ngspice's own init, log,
# debug or display files (e.g. "Note: can't find the initialization file spinit.", "Can't
# open X display") are not about the deck and are not matched.
_LOAD_FAILED = re.compile(
    r"(?:cannot|could not) open (?:library )?file (?!debug-out)|no such file|"
    r"can't find model|could not find (?:a )?model|could not find a valid modelname|"
    r"unable to find (?:definition of )?(?:given )?(?:t)?model|can't find device|"
    r"could not find (?:include|library) file|cannot find (?:called )?subcircuit|"
    r"unknown subckt|couldn't be loaded|failed to load|could not load|cannot load",
    re.IGNORECASE)


def _stage_files(text: str, files, work: Path) -> str:
    """The deck ngspice is given: every file reference of ``text`` points to a lower-case name
    linked (or copied) into ``work``.  A reference is a file of ``files`` by its name, or an
    absolute path; anything else is an NgspiceError naming it."""
    given: dict[str, Path] = {}
    for f in files or ():
        p = Path(f)
        if _LOCAL_NAME.fullmatch(p.name) is None:
            raise ValueError(f"files: {p.name!r} must be a lower-case file name (letters a-z, "
                             f"digits and _ . + -) that the deck names")
        given[p.name] = p
    staged: dict[str, str] = {}

    def local(ref: str) -> str:
        if ref in staged:
            return staged[ref]
        if ref in given:
            src, name = given[ref], ref
        elif os.path.isabs(ref):
            src = Path(ref)
            name = f"f{len(staged)}_" + (re.sub(r"[^a-z0-9_.+-]", "_", src.name.lower()) or "file")
        else:
            raise NgspiceError(f"the deck reads the file {ref!r}, which is neither an absolute "
                               f"path nor one of the files given to run_deck")
        if not src.is_file():
            raise NgspiceError(f"the deck reads the file {str(src)!r}, which does not exist or "
                               f"is not a readable file")
        dest = work / name
        if dest.resolve() != src.resolve():
            dest.unlink(missing_ok=True)
            try:
                os.symlink(src.resolve(), dest)
            except OSError:
                shutil.copyfile(src, dest)
        staged[ref] = name
        return name

    out = []
    for line in text.splitlines(keepends=True):
        if not line.lstrip().startswith("*"):
            line = _FILE_REF.sub(lambda m: f'{m.group(1)}"{local(m.group(2))}"', line)
        out.append(line)
    return "".join(out)


def _load_failures(stdout: str, stderr: str) -> str:
    """ngspice's lines saying that a file, model or source could not be loaded, as one line."""
    return _one_line("\n".join(ln for ln in (stdout + "\n" + stderr).splitlines()
                               if _LOAD_FAILED.search(ln)))


# --------------------------------------------------------------- what the deck asked for
_SPICE_SCALE = {"t": 1e12, "g": 1e9, "meg": 1e6, "k": 1e3, "mil": 25.4e-6, "m": 1e-3,
                "u": 1e-6, "n": 1e-9, "p": 1e-12, "f": 1e-15}
_SPICE_NUMBER = re.compile(r"([+-]?(?:\d+\.?\d*|\.\d+)(?:e[+-]?\d+)?)(meg|mil|[tgkmunpf])?[a-z]*",
                           re.IGNORECASE)
#: relative slack on the deck's max step: ngspice's largest step measured 1 + 3e-15 times it
#: (stick decks, tmax = noise_dt); a thinned or squeezed axis exceeds it by a factor >= 2.
STEP_SLACK = 1e-6


def _spice_float(token: str) -> float | None:
    m = _SPICE_NUMBER.fullmatch(token.strip())
    if m is None:
        return None
    return float(m.group(1)) * _SPICE_SCALE.get((m.group(2) or "").lower(), 1.0)


def _tran(text: str) -> tuple[float, float, float, float] | None:
    """(tstep, tstop, tstart, tmax) of the deck's ``.tran`` line (seconds), or None.  Without
    a tmax ngspice takes the smaller of tstep and (tstop - tstart)/50: the larger is used
    here, so that the check below never refuses what ngspice may do."""
    found = None
    for line in text.splitlines():
        if re.match(r"\s*\.tran\b", line, re.IGNORECASE):
            found = line.split()[1:]
    if not found:
        return None
    parsed = [_spice_float(tok) for tok in found if tok.lower() != "uic"]
    nums = [n for n in parsed if n is not None]
    if len(nums) < 2 or len(nums) != len(parsed):
        return None
    tstep, tstop = nums[0], nums[1]
    tstart = nums[2] if len(nums) > 2 else 0.0
    tmax = nums[3] if len(nums) > 3 and nums[3] > 0 else max(tstep, (tstop - tstart) / 50.0)
    return tstep, tstop, tstart, tmax


def _saved(text: str) -> list[str]:
    """The node voltages and branch currents named by the deck's ``.save`` lines."""
    out: list[str] = []
    for line in text.splitlines():
        if re.match(r"\s*\.save\b", line, re.IGNORECASE):
            out += [tok.lower() for tok in line.split()[1:]
                    if re.fullmatch(r"[vi]\([^(),]+\)", tok, re.IGNORECASE)]
    return out


def output_problem(text: str, plot: RawPlot) -> str | None:
    """Why ``plot`` is not what the deck ``text`` asked for (one line), or None: every vector
    its ``.save`` names is there, and the time axis runs from ``tstart`` to ``tstop`` with no
    step longer than the deck's max step (the points ngspice took; a thinned, squeezed or
    truncated axis breaks this)."""
    missing = [n for n in _saved(text) if n not in plot.names]
    if missing:
        return (f"the raw file lacks the vectors {', '.join(missing[:5])}"
                f"{' ...' if len(missing) > 5 else ''} that the deck saves (it holds "
                f"{', '.join(plot.names[:6])}{' ...' if len(plot.names) > 6 else ''})")
    tran = _tran(text)
    if tran is None or "time" not in plot.names or not plot.n_points:
        return None
    _tstep, tstop, tstart, tmax = tran
    t = plot["time"]
    if t[-1] > tstop * (1.0 + 1e-9) or t[0] < tstart - 1e-12 * tstop:
        return (f"its time axis [{t[0]:.6g}, {t[-1]:.6g}] s leaves the deck's interval "
                f"[{tstart:.6g}, {tstop:.6g}] s")
    gaps = np.diff(np.concatenate([[tstart], t]))
    worst = int(np.argmax(gaps))
    if gaps[worst] > tmax * (1.0 + STEP_SLACK):
        return (f"its time axis has a step of {gaps[worst]:.6g} s at t = {t[worst]:.6g} s, "
                f"longer than the deck's max step {tmax:.6g} s ({plot.n_points} points for "
                f"{tstop - tstart:.6g} s): points are missing or the axis is distorted")
    return None


def run_deck(text: str, *, timeout: float = 3600.0, t_stop: float | None = None,
             keep_dir=None, group=None, files=()) -> RunResult:
    """Run one complete deck (``.end``-terminated, no ``.control`` block) in batch mode.

    Parameters
    ----------
    text : the deck (screened by :func:`check_deck`).
    timeout : seconds before the ngspice process group is killed (NgspiceError).  Holds
        whatever ngspice does: it runs in its own session and writes to files, so neither a
        child that keeps its output open nor a wrapper script can delay the kill.
    t_stop : if given (seconds), the transient plot must reach this time, else the run is
        reported as incomplete (ngspice 39 exits 0 after some aborted analyses).
    keep_dir : if given, the deck, raw file and logs are written there and kept (debugging);
        otherwise a temporary directory is used and removed.
    group : any hashable; the process can be stopped by :func:`terminate_group` (group).
    files : paths of files the deck reads (an XSPICE ``filesource``), each named in the deck
        by its lower-case file name; they are linked into the deck's working directory.  An
        absolute path in the deck is linked there too (ngspice lower-cases it otherwise).  A
        message of ngspice that a file, model or source could not be loaded is an
        NgspiceError even when ngspice exits 0.
    """
    check_deck(text)
    timeout = checks.positive("timeout (seconds)", timeout)
    if _STOPPING.is_set():
        raise NgspiceError("not started: the run was interrupted by a signal")
    exe = find_ngspice()
    version = _version_of(exe)
    _sweep_now_and_then()
    with _owned_tmpdir() as tmp:
        work = Path(keep_dir) if keep_dir is not None else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        # UTF-8 whatever the locale (a file path in the deck keeps its bytes: files.utf8)
        (work / "deck.cir").write_bytes(_utf8(_stage_files(text, files, work)))
        raw = work / "out.raw"
        out_p, err_p = work / "stdout.txt", work / "stderr.txt"
        t0 = _time.perf_counter()
        try:
            returncode = _run_guarded([exe, "-b", "-r", raw.name, "deck.cir"], work, out_p,
                                      err_p, group, timeout)
        except OSError as exc:
            raise NgspiceError(f"could not start {exe}: {_one_line(str(exc))}") from None
        except subprocess.TimeoutExpired:
            raise NgspiceError(_with_said(f"ngspice did not finish within timeout={timeout} s",
                                          _said(_read_tail(out_p), _read_tail(err_p)))) from None
        wall = _time.perf_counter() - t0
        stdout, stderr = _read_tail(out_p), _read_tail(err_p)
        said = _said(stdout, stderr)
        if returncode != 0:
            if returncode < 0:
                raise NgspiceError(_with_said(f"ngspice was stopped by signal {-returncode} "
                                              f"({_signal_name(-returncode)})", said))
            raise NgspiceError(_with_said(f"ngspice exited with status {returncode}", said))
        failed = _load_failures(stdout, stderr)
        if failed:
            raise NgspiceError(f"ngspice could not load what the deck needs (it would have run "
                               f"without it): {failed}")
        if not raw.exists():
            raise NgspiceError(_with_said("ngspice wrote no raw file", said))
        # The reader holds the file and a copy of its data: refuse what cannot fit, unread.
        size = raw.stat().st_size
        mem, why = memory_limit()
        if 2 * size > mem:
            raise NgspiceError(f"the raw file ngspice wrote is {format_bytes(size)}; reading it "
                               f"needs about twice that, more than the memory limit of "
                               f"{format_bytes(mem)} ({why}); reduce the replicas per deck or "
                               f"t_end, or raise the deck's max step")
        try:
            plots = read_raw(raw)
        except (ValueError, OSError) as exc:
            raise NgspiceError(_with_said(f"unreadable raw file ({_one_line(str(exc))})",
                                          said)) from None
    tran = [p for p in plots if "transient" in p.plotname.lower()]
    if not tran:
        raise NgspiceError(_with_said("the raw file holds no transient plot (plots: "
                                      f"{[p.plotname for p in plots]})", said))
    plot = tran[-1]
    if "time" in plot.names and plot.n_points:
        t = plot["time"]
        if not (np.all(np.isfinite(t)) and np.all(np.diff(t) >= 0)):
            raise NgspiceError(_with_said("the raw file's time vector is not finite and "
                                          "non-decreasing (damaged output)", said))
    if t_stop is not None:
        reached = float(plot["time"][-1]) if plot.n_points else 0.0
        if reached < t_stop * (1.0 - 1e-9):
            raise NgspiceError(_with_said(f"transient stopped at t = {reached:.6g} s before "
                                          f"t_stop = {t_stop:.6g} s", said))
    if not np.all(np.isfinite(plot.values)):
        bad = [n for i, n in enumerate(plot.names) if not np.all(np.isfinite(plot.values[:, i]))]
        raise NgspiceError(_with_said(f"ngspice exited normally but its vectors "
                                      f"{', '.join(bad[:5])} hold NaN or infinite values; the "
                                      f"circuit diverged", said))
    wrong = output_problem(text, plot)
    if wrong is not None:
        raise NgspiceError(_with_said(f"ngspice's output is not what the deck asked for: {wrong}",
                                      said))
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
