"""Fault injection: a hostile environment around ngspice (issue 19, item 7).

- HOME: ngspice runs with a private HOME (its own temporary directory) always, not only
  when HOME is unset (that case, a SIGSEGV, is tests/faults/test_faults_odd_inputs.py): a
  user's ~/.spiceinit must not reach the numbers either.
- A SIGKILLed run leaves its ``analogue-ngspice-*`` directories behind; the next run removed
  only those older than 60 s, once per process, so a prompt re-run left them for ever.  Each
  directory now holds a lock for as long as its owner uses it: a directory whose lock can be
  taken is abandoned and is removed whatever its age.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from analogue.circuit import ngspice as ng

ROOT = Path(__file__).resolve().parents[2]
DECK = "t\nC1 v1 0 1e-6\nR1 v1 0 1e3\n.ic v(v1)=1\n.tran 1e-5 1e-3 uic\n.end\n"


@pytest.mark.requires_ngspice
def test_a_users_spiceinit_does_not_reach_the_run(monkeypatch, tmp_path):
    """A ~/.spiceinit that would break every deck (an unknown option makes ngspice 39 stop
    with an error) is not read: the decks are the whole of the circuit."""
    home = tmp_path / "home"
    home.mkdir()
    (home / ".spiceinit").write_text("* broken on purpose\nset noinit\nquit 7\n")
    monkeypatch.setenv("HOME", str(home))
    res = ng.run_deck(DECK, timeout=60, t_stop=1e-3)
    assert res.plot.n_points > 10


HOLD = textwrap.dedent("""
    import sys, time
    from analogue.circuit import ngspice as ng
    with ng._owned_tmpdir() as d:
        print(d, flush=True)
        time.sleep(300)
""")


def test_directories_of_a_killed_run_are_removed_by_the_next_run(tmp_path, monkeypatch):
    env = dict(os.environ, TMPDIR=str(tmp_path), PYTHONPATH=str(ROOT))
    procs = [subprocess.Popen([sys.executable, "-c", HOLD], env=env, stdout=subprocess.PIPE,
                              text=True) for _ in range(2)]
    dirs = [Path(p.stdout.readline().strip()) for p in procs]
    assert all(d.is_dir() and d.parent == tmp_path for d in dirs)
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    assert ng.sweep_stale_tmp() == 0            # their owners are alive: kept
    assert all(d.is_dir() for d in dirs)
    procs[0].send_signal(signal.SIGKILL)
    procs[0].wait()
    # at once (no minimum age), and only the dead owner's
    assert ng.sweep_stale_tmp() == 1
    assert not dirs[0].exists() and dirs[1].is_dir()
    procs[1].kill()
    procs[1].wait()
    assert ng.sweep_stale_tmp() == 1
    assert list(tmp_path.glob("analogue-ngspice-*")) == []


def test_sweep_keeps_a_directory_being_created(tmp_path, monkeypatch):
    """A directory of a live process not yet locked (between mkdtemp and the lock) is kept."""
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    d = Path(__import__("tempfile").mkdtemp(prefix=ng._tmp_prefix().replace(
        f".{os.getpid()}-", f".{os.getppid()}-")))
    assert ng.sweep_stale_tmp() == 0 and d.is_dir()


def test_sweep_runs_again_later_in_a_long_process(tmp_path, monkeypatch):
    """Not once per process: a notebook that outlives a killed run still sweeps its dirs."""
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    calls = []
    monkeypatch.setattr(ng, "sweep_stale_tmp", lambda *a, **k: calls.append(1) or 0)
    monkeypatch.setattr(ng, "_LAST_SWEEP", [None])
    ng._sweep_now_and_then()
    ng._sweep_now_and_then()
    assert len(calls) == 1
    ng._LAST_SWEEP[0] -= ng.SWEEP_EVERY_S + 1   # a minute later
    ng._sweep_now_and_then()
    assert len(calls) == 2
