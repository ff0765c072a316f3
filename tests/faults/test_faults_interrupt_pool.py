"""Fault injection: Ctrl-C while the shipped experiments' decks run in their shared deck pool
(issue 19, item 1), and a per-deck ``--timeout`` against an ngspice that hangs.

The signal tests of ``test_faults_signals.py`` signal once the first deck is stored, which
is during the tolerance and deck-size calibrations (plain ``simulate`` calls from the main
thread); they never reached the report's deck pool (:func:`analogue.study.runs._run_jobs`),
where a run's waiting thread hung for ever on decks the pool had cancelled (a
``ThreadPoolExecutor.shutdown(cancel_futures=True)`` does not wake ``as_completed``).  Here
the signal goes once a run of the pool has printed its line (``--progress`` on a pipe: one
line per finished run), so the pool is busy with the other runs.
"""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from analogue.circuit.store import RunStore
from test_faults_signals import _assert_clean, _marked, _workspace

pytestmark = [pytest.mark.slow, pytest.mark.requires_ngspice, pytest.mark.timeout(400)]

EXE = Path(sys.executable).with_name("analogue")
DONE = re.compile(r": (\d+) decks \((\d+) from the store, (\d+) run\)")
# The bound (a hang detector, not a timing test: measured 0.1-1.5 s, see the commit)
EXIT_WITHIN_S = 10.0


def _lines(proc) -> list[str]:
    """stderr of ``proc``, read as it comes in a thread (the list grows)."""
    lines: list[str] = []

    def read():
        for ln in proc.stderr:
            lines.append(ln)
    threading.Thread(target=read, daemon=True).start()
    return lines


def _signal_in_the_pool(proc, lines, marker, sig) -> tuple[set[int], int]:
    """Once a run of the pool has finished (its line printed) and an ngspice runs, send
    ``sig``; returns the running ngspice pids and the decks of the finished runs."""
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline:
        assert proc.poll() is None, "".join(lines)
        finished = [m for ln in list(lines) if (m := DONE.search(ln))]
        busy = _marked(marker, proc.pid)
        if finished and busy:
            proc.send_signal(sig)
            return busy, sum(int(m.group(1)) for m in finished)
        time.sleep(0.02)
    raise AssertionError("the deck pool never got busy: " + "".join(lines))


def _interrupted(tmp_path, cmd_of, sig):
    tmp, store, _, marker, env = _workspace(tmp_path, "unused.txt", "")
    env["ANALOGUE_THEORY_CACHE"] = "off"
    cmd = cmd_of(store)
    proc = subprocess.Popen(cmd, env=env, cwd=tmp_path, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    lines = _lines(proc)
    seen, finished = _signal_in_the_pool(proc, lines, marker, sig)
    try:
        proc.wait(timeout=EXIT_WITHIN_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        raise AssertionError(f"still running {EXIT_WITHIN_S:g} s after {sig!r}: "
                             + "".join(lines)) from None
    time.sleep(0.2)  # the reader thread drains the pipe
    err = "".join(lines)
    assert proc.returncode == 128 + sig, (proc.returncode, err)
    assert "Traceback" not in err
    last = [ln for ln in err.splitlines() if ln.strip()][-1]
    assert last.startswith("analogue: error:") and signal.Signals(sig).name in last, err
    assert "resume" in last
    assert "did not end" not in err  # it unwound by itself, not by the CLI's last resort
    _assert_clean(marker, proc.pid, tmp, store, seen)
    return cmd, env, store, finished


def _resumes(tmp_path, cmd, env, store, finished):
    """The same command again reuses every deck finished before the signal, untouched."""
    kept = {k: RunStore(store).path(k).read_bytes() for k in RunStore(store).keys()}  # noqa: SIM118
    assert kept
    res = subprocess.run(cmd, env=env, cwd=tmp_path, capture_output=True, text=True,
                         timeout=300, check=False)
    assert res.returncode == 0, res.stderr
    assert all(RunStore(store).path(k).read_bytes() == b for k, b in kept.items())
    reused = sum(int(m.group(2)) for m in DONE.finditer(res.stderr))
    assert reused >= finished > 0, res.stderr


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_run_of_a_shipped_experiment_interrupted_in_the_deck_pool(tmp_path, sig):
    def cmd(store):
        return [str(EXE), "run", "stick", "--quick", "--workers", "2", "--progress",
                "--store", str(store)]
    args = _interrupted(tmp_path, cmd, sig)
    if sig == signal.SIGINT:
        _resumes(tmp_path, *args)


def test_report_of_a_shipped_experiment_interrupted_in_the_deck_pool(tmp_path):
    def cmd(store):
        return [str(EXE), "report", "slip", "--quick", "--workers", "2", "--progress",
                "--store", str(store), "--out", str(tmp_path / "out")]
    _interrupted(tmp_path, cmd, signal.SIGINT)


HUNG = """\
#!/bin/sh
if [ "$1" = "-v" ]; then echo "** ngspice-39 : Circuit level simulation program"; exit 0; fi
sleep 1000
"""

TWO = """\
name = "two"
[model]
tau_m = 1.0
delta = 0.7
a = 0.2
gamma = 10.0
[experiment]
v0 = [2.0]
replicas = 2
t_end = 2.0
sample_dt = 0.01
seed = 5
histogram_times = [1.0, 2.0]
[report]
stationary_replicas = 8
stationary_t_end = 4.0
stationary_burn_in = 0.5
check_replicas = 8
"""


def test_timeout_bounds_a_run_whose_ngspice_hangs(tmp_path):
    """An ngspice that answers ``-v`` and then hangs: with ``--timeout 3`` the command ends
    with one line naming the timeout, after about one timeout (the calibrations honour it
    too, and the first deck that times out stops the rest), never timeout x decks."""
    tmp, store, toml, marker, env = _workspace(tmp_path, "two.toml", TWO)
    bindir = tmp_path / "bin"
    bindir.mkdir()
    (bindir / "ngspice").write_text(HUNG)
    (bindir / "ngspice").chmod(0o755)
    env["PATH"] = f"{bindir}{os.pathsep}{env['PATH']}"
    cmd = [str(EXE), "run", str(toml), "--workers", "1", "--timeout", "3",
           "--store", str(store)]
    try:
        res = subprocess.run(cmd, env=env, cwd=tmp_path, capture_output=True, text=True,
                             timeout=60, check=False)
    except subprocess.TimeoutExpired as exc:
        raise AssertionError(f"still running 60 s after the start with --timeout 3: "
                             f"{exc.stderr!r}") from None
    assert res.returncode != 0
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()
             and not ln.startswith("analogue [")]
    assert len(lines) == 1, res.stderr
    assert "timeout=3" in lines[0] and "Traceback" not in res.stderr
    assert _marked(marker, -1) == set()
    assert list(tmp.glob("analogue-ngspice-*")) == []
