"""Fault injection: SIGTERM and SIGINT in the middle of a run (issue 8, section 4).

A real ``simulate`` (Python) or ``analogue run`` (CLI) runs in a subprocess with its own
TMPDIR and run store, and ngspice decks of ~1-2 s each.  Once the first deck is stored and the
next one runs, the test sends the signal and asserts: the process exits promptly with the
documented code (128 + signal: 130 for SIGINT, 143 for SIGTERM) and a one-line message; every
ngspice process it had started is gone; no ``analogue-ngspice-*`` directory and no store
temporary file is left; finished decks are in the store; and running again resumes from them
(only the missing decks run) with arrays byte-identical to an uninterrupted run.

Processes are found by a marker in their environment (ngspice inherits it), which works
whatever process group or session they are in.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

from analogue.circuit.store import RunStore

pytestmark = [pytest.mark.slow, pytest.mark.timeout(300)]

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = textwrap.dedent("""
    import json, sys
    import numpy as np
    import analogue
    from analogue import Model
    store, out, catch = sys.argv[1], sys.argv[2], sys.argv[3] == "catch"
    kw = dict(v0=0.4, t_end=300.0, sample_dt=0.05, replicas=3, seed=21, replicas_per_deck=1,
              workers=1, progress=False, store=store)
    def main():
        e = analogue.simulate(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0), **kw)
        np.save(out, e.v)
        print(json.dumps({"ran": e.meta["ran"], "from_store": e.meta["from_store"]}))
    if catch:
        try:
            main()
        except KeyboardInterrupt as exc:  # what the CLI does: one line, 128 + signal
            print(f"error: {exc}", file=sys.stderr)
            sys.exit(getattr(exc, "exit_code", 1))
    else:
        main()
""")


def _env(tmp: Path, marker: str) -> dict:
    env = dict(os.environ)
    env.update(TMPDIR=str(tmp), ANALOGUE_FAULT_MARK=marker, PYTHONPATH=str(ROOT),
               ANALOGUE_STORE=str(tmp.parent / "unused-store"))
    env.pop("ANALOGUE_DEBUG", None)
    return env


def _workspace(tmp_path: Path, name: str, text: str) -> tuple[Path, Path, Path, str, dict]:
    """``(tmp, store, file, marker, env)`` of one signal test: a private TMPDIR, a run store,
    ``text`` written to ``tmp_path / name`` (the script or TOML the test runs) and the
    environment whose ngspice processes carry ``marker`` (:func:`_env`)."""
    tmp, store = tmp_path / "tmp", tmp_path / "store"
    tmp.mkdir()
    f = tmp_path / name
    f.write_text(text)
    marker = uuid.uuid4().hex
    return tmp, store, f, marker, _env(tmp, marker)


def _marked(marker: str, exclude: int) -> set[int]:
    """Live processes (not zombies) whose environment carries ``marker``, except ``exclude``."""
    found = set()
    needle = f"ANALOGUE_FAULT_MARK={marker}".encode()
    for d in Path("/proc").iterdir():
        if not d.name.isdigit() or int(d.name) == exclude:
            continue
        try:
            if needle in (d / "environ").read_bytes():
                state = (d / "stat").read_text().rsplit(")", 1)[1].split()[0]
                if state != "Z":
                    found.add(int(d.name))
        except OSError:
            continue
    return found


def _interrupt_when_busy(proc, store: Path, tmp: Path, marker: str, sig) -> set[int]:
    """Wait until >= 1 deck is stored and an ngspice runs, then send ``sig``; returns the pids
    of the ngspice processes that were running."""
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        busy = _marked(marker, proc.pid)
        if busy and RunStore(store).keys() and list(tmp.glob("analogue-ngspice-*")):
            proc.send_signal(sig)
            return busy
        time.sleep(0.05)
    raise AssertionError("the run never got busy")


def _interrupted(cmd: list, env: dict, store: Path, tmp: Path, marker: str, sig,
                 cwd: Path | None = None) -> tuple:
    """Start ``cmd``, send ``sig`` once its ngspice is busy, wait for it: ``(proc, stderr,
    ngspice pids seen, seconds from the signal to its exit)``."""
    proc = subprocess.Popen(cmd, env=env, cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    seen = _interrupt_when_busy(proc, store, tmp, marker, sig)
    t0 = time.monotonic()
    _, err = proc.communicate(timeout=60)
    return proc, err, seen, time.monotonic() - t0


def _assert_clean(marker, pid, tmp, store, seen):
    deadline = time.monotonic() + 10
    while _marked(marker, pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _marked(marker, pid) == set()  # every ngspice it started is gone
    assert seen  # (and there were some)
    assert list(tmp.glob("analogue-ngspice-*")) == []
    assert [p for p in store.rglob("*.tmp")] == []


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_simulate_interrupted_cleans_up_and_resumes(tmp_path, sig):
    tmp, store, script, marker, env = _workspace(tmp_path, "run.py", SCRIPT)
    proc, err, seen, waited = _interrupted([sys.executable, str(script), str(store),
                                            str(tmp_path / "v.npy"), "catch"], env, store, tmp,
                                           marker, sig)
    assert waited < 15
    assert proc.returncode == 128 + sig, (proc.returncode, err)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert signal.Signals(sig).name in lines[0] and "resume" in lines[0]
    _assert_clean(marker, proc.pid, tmp, store, seen)
    done = RunStore(store).keys()
    assert 1 <= len(done) < 3
    before = {k: RunStore(store).path(k).read_bytes() for k in done}

    # resume: only the missing decks run; the finished ones are read back untouched
    res = subprocess.run([sys.executable, str(script), str(store), str(tmp_path / "v.npy"),
                          "catch"], env=env, capture_output=True, text=True, timeout=120,
                         check=False)
    assert res.returncode == 0, res.stderr
    info = json.loads(res.stdout)
    assert info == {"ran": 3 - len(done), "from_store": len(done)}
    assert all(RunStore(store).path(k).read_bytes() == b for k, b in before.items())
    resumed = np.load(tmp_path / "v.npy")
    # an uninterrupted run, in a fresh store, gives the very same bytes
    fresh = subprocess.run([sys.executable, str(script), str(tmp_path / "fresh"),
                            str(tmp_path / "f.npy"), "catch"], env=env, capture_output=True,
                           text=True, timeout=120, check=False)
    assert fresh.returncode == 0, fresh.stderr
    full = np.load(tmp_path / "f.npy")
    assert resumed.dtype == full.dtype and resumed.tobytes() == full.tobytes()


def test_uncaught_sigterm_in_a_script_still_cleans_up(tmp_path):
    """A user script that does not catch anything: the exit is abnormal (the exception is
    KeyboardInterrupt), but no ngspice and no temporary directory outlive it."""
    tmp, store, script, marker, env = _workspace(tmp_path, "run.py", SCRIPT)
    proc, err, seen, _ = _interrupted([sys.executable, str(script), str(store),
                                       str(tmp_path / "v.npy"), "plain"], env, store, tmp,
                                      marker, signal.SIGTERM)
    assert proc.returncode != 0
    assert "RunInterrupted" in err
    _assert_clean(marker, proc.pid, tmp, store, seen)


CLI_TOML = """\
name = "sigtest"
description = "small stick-regime experiment for the signal fault tests"

[model]
tau_m = 1.0
delta = 0.7
a = 0.2
gamma = 10.0

[circuit]
coulomb = "diode-bridge"
diode = "ideal"
smoothing = 0.02
time_scale = 1e-3
capacitance = 100e-9

[experiment]
v0 = [2.0]
replicas = 32
t_end = 8.0
sample_dt = 0.01
seed = 5
histogram_times = [1.0, 8.0]

[report]
stationary_replicas = 16
stationary_t_end = 10.0
stationary_burn_in = 2.0
check_replicas = 16
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_cli_run_interrupted_cleans_up_and_resumes(tmp_path, sig):
    tmp, store, toml, marker, env = _workspace(tmp_path, "sigtest.toml", CLI_TOML)
    exe = Path(sys.executable).with_name("analogue")
    cmd = [str(exe), "run", str(toml), "--store", str(store), "--workers", "1",
           "--no-progress"]
    proc, err, seen, waited = _interrupted(cmd, env, store, tmp, marker, sig, cwd=tmp_path)
    assert waited < 15
    _assert_clean(marker, proc.pid, tmp, store, seen)
    assert "Traceback" not in err
    done = {k: RunStore(store).path(k).read_bytes() for k in RunStore(store).keys()}  # noqa: SIM118
    assert done
    res = subprocess.run(cmd, env=env, cwd=tmp_path, capture_output=True, text=True,
                         timeout=240, check=False)
    assert res.returncode == 0, res.stderr
    assert all(RunStore(store).path(k).read_bytes() == b for k, b in done.items())
    assert len(RunStore(store).keys()) > len(done)
    # the message and exit code are main()'s job (cli.py): RunInterrupted carries exit_code
    # (128 + signal) and a one-line str(); click's own fallback is "Aborted!" and status 1
    # main() prints RunInterrupted's one line and exits with its exit_code (128 + signal)
    last = [ln for ln in err.splitlines() if ln.strip()][-1]
    assert proc.returncode == 128 + sig, (proc.returncode, err)
    assert signal.Signals(sig).name in last and "resume" in last, err


def test_interrupt_stops_ngspice_on_dask_worker_processes(tmp_path, monkeypatch):
    """With scheduler=, the decks run in Dask worker processes.  A cancelled Dask future does
    not stop a task that already runs, so an interrupt must reach into the workers: the
    worker's (fake, hanging) ngspice and its child are killed and its temporary directory is
    removed, long before the per-deck timeout."""
    distributed = pytest.importorskip("distributed")
    import threading

    import analogue
    from analogue import Model
    from analogue.circuit import ngspice as ng

    bindir, state, tmp = tmp_path / "bin", tmp_path / "state", tmp_path / "tmp"
    for d in (bindir, state, tmp):
        d.mkdir()
    exe = bindir / "ngspice"
    exe.write_text("#!/bin/sh\n"
                   'if [ "$1" = "-v" ]; then echo "** ngspice-99 : fake"; exit 0; fi\n'
                   'echo "$$" >> "$STATE/pids"\nsleep 300 &\necho "$!" >> "$STATE/pids"\nwait\n')
    exe.chmod(0o755)
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    monkeypatch.setenv("STATE", str(state))
    monkeypatch.setenv("TMPDIR", str(tmp))  # inherited by the worker processes
    monkeypatch.setattr("tempfile.tempdir", str(tmp))

    def fire():
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            f = state / "pids"
            if f.exists() and len(f.read_text().split()) >= 2:
                os.kill(os.getpid(), signal.SIGINT)
                return
            time.sleep(0.05)

    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        threading.Thread(target=fire, daemon=True).start()
        t0 = time.monotonic()
        with pytest.raises(ng.RunInterrupted) as exc:
            analogue.simulate(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0), v0=0.4,
                              t_end=1.0, replicas=1, seed=1, store=False, progress=False,
                              scheduler=client, timeout=250)
        assert exc.value.exit_code == 130
        pids = [int(p) for p in (state / "pids").read_text().split()]
        deadline = time.monotonic() + 20
        while any(_alive(p) for p in pids) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not any(_alive(p) for p in pids)
        assert time.monotonic() - t0 < 60
        deadline = time.monotonic() + 20
        while list(tmp.glob("analogue-ngspice-*")) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert list(tmp.glob("analogue-ngspice-*")) == []


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


DIRECT = textwrap.dedent("""
    import signal
    import sys
    # SIGHUP as a terminal session has it: an ignored SIGHUP is inherited across exec, and
    # the guard rightly keeps a signal the user chose to ignore ignored (a suite started
    # under nohup made this script ignore the test's SIGHUP and time out)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)
    from analogue.circuit import ngspice as ng
    deck = "t\\nC1 v1 0 1e-6\\nR1 v1 0 1e3\\n.tran 1e-5 1e-3 uic\\n.end\\n"
    try:
        ng.run_deck(deck, timeout=250)
    except KeyboardInterrupt as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(getattr(exc, "exit_code", 1))
""")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_run_deck_called_directly_is_guarded_too(tmp_path, sig):
    """ngspice runs in its own session, so a caller dying on SIGTERM would orphan it: run_deck
    guards itself when called from the main thread (calibration runs, scripts), not only
    simulate's batches."""
    tmp, bindir, state = tmp_path / "tmp", tmp_path / "bin", tmp_path / "state"
    for d in (tmp, bindir, state):
        d.mkdir()
    exe = bindir / "ngspice"
    exe.write_text("#!/bin/sh\n"
                   'if [ "$1" = "-v" ]; then echo "** ngspice-99 : fake"; exit 0; fi\n'
                   'echo "$$" >> "$STATE/pids"\nsleep 300 &\necho "$!" >> "$STATE/pids"\nwait\n')
    exe.chmod(0o755)
    script = tmp_path / "direct.py"
    script.write_text(DIRECT)
    marker = uuid.uuid4().hex
    env = _env(tmp, marker)
    env.update(PATH=f"{bindir}{os.pathsep}{env['PATH']}", STATE=str(state))
    proc = subprocess.Popen([sys.executable, str(script)], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not ((state / "pids").exists() and len((state / "pids").read_text().split()) >= 2):
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.05)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 128 + sig, (proc.returncode, err)
    assert signal.Signals(sig).name in err and len(err.strip().splitlines()) == 1
    pids = [int(p) for p in (state / "pids").read_text().split()]
    deadline = time.monotonic() + 10
    while any(_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(_alive(p) for p in pids)
    assert list(tmp.glob("analogue-ngspice-*")) == []


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_cli_interrupted_outside_ngspice_is_one_line(tmp_path, sig):
    """A signal while a command computes or plots (no ngspice running, e.g. between the
    simulate calls of a report) is the same one line and 128 + signal, never a silent death
    by signal (returncode -15) or a traceback."""
    exe = Path(sys.executable).with_name("analogue")
    env = dict(os.environ, PYTHONPATH=str(ROOT), ANALOGUE_THEORY_CACHE="off", PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([str(exe), "figures", "--out", str(tmp_path / "figs")], env=env,
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    # the first figure on disk means the command runs (a signal during Python's start-up
    # imports, before any of analogue's code, cannot be turned into one line); the rest of
    # the nine figures (the uncached rate functions) take seconds more
    deadline = time.monotonic() + 120
    while not list((tmp_path / "figs").glob("*.png")) and time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    assert proc.poll() is None, "the figures command finished before the signal"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig, (proc.returncode, err)
    assert "Traceback" not in err
    last = [ln for ln in err.splitlines() if ln.strip()][-1]
    assert last.startswith("analogue: error:") and signal.Signals(sig).name in last, err


def test_a_signal_between_starting_and_tracking_ngspice_waits_for_the_tracking():
    """run_deck starts ngspice and then tracks it for terminate_all; a signal in between
    (a loaded machine can deschedule Python there for long) is acted on once the block that
    starts and tracks the process ends, not in the middle of it (where it would orphan the
    new process), and still raises RunInterrupted."""
    from analogue.circuit.ngspice import RunInterrupted, _signals_deferred, interrupt_guard
    reached = False
    with pytest.raises(RunInterrupted):
        with interrupt_guard():
            with _signals_deferred():
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(0.05)          # the Python-level handler has run by now
                reached = True
    assert reached


SWEEP_TOML = CLI_TOML.replace('name = "sigtest"', 'name = "sigsweep"').replace(
    "stationary_t_end = 10.0", "stationary_t_end = 60.0")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_cli_sweep_with_points_at_once_interrupted_cleans_up(tmp_path, sig):
    """``analogue sweep`` runs its points at once (issue 22), their decks on one pool of
    ``--workers`` processes, from threads of its own: a signal still kills every ngspice it
    started, exits with 128 + signal and one line, leaves no temporary directory or store
    temporary file, and writes no sweep.nc (nothing half-written)."""
    tmp, store, toml, marker, env = _workspace(tmp_path, "sigsweep.toml", SWEEP_TOML)
    exe = Path(sys.executable).with_name("analogue")
    out = tmp_path / "out"
    cmd = [str(exe), "sweep", str(toml), "--vary", "a=0:0.4:3", "--out", str(out),
           "--store", str(store), "--workers", "2", "--no-progress"]
    proc, err, seen, waited = _interrupted(cmd, env, store, tmp, marker, sig, cwd=tmp_path)
    assert waited < 15
    _assert_clean(marker, proc.pid, tmp, store, seen)
    assert "Traceback" not in err
    assert proc.returncode == 128 + sig, (proc.returncode, err)
    last = [ln for ln in err.splitlines() if ln.strip()][-1]
    assert signal.Signals(sig).name in last, err
    assert not (out / "sweep.nc").exists()
    assert not [p for p in out.rglob("*") if p.is_file()] if out.exists() else True


SWEEP_SCRIPT = textwrap.dedent("""
    import sys
    import analogue
    toml, store, out = sys.argv[1], sys.argv[2], sys.argv[3]
    analogue.sweep(toml, {"a": [0.0, 0.2, 0.4]}, out=out, store=store, workers=2,
                   progress=False)
""")


def test_uncaught_sigterm_in_a_sweep_script_still_cleans_up(tmp_path):
    """A script calling analogue.sweep (no command line's guard around it): the sweep's own
    guard, held by the thread that waits for its points, kills every ngspice its point
    threads started and unwinds them; nothing is written."""
    tmp, store, script, marker, env = _workspace(tmp_path, "sweep.py", SWEEP_SCRIPT)
    toml = tmp_path / "sigsweep.toml"
    toml.write_text(SWEEP_TOML)
    out = tmp_path / "out"
    proc, err, seen, _ = _interrupted([sys.executable, str(script), str(toml), str(store),
                                       str(out)], env, store, tmp, marker, signal.SIGTERM)
    assert proc.returncode != 0
    assert "RunInterrupted" in err
    _assert_clean(marker, proc.pid, tmp, store, seen)
    assert not (out / "sweep.nc").exists()
