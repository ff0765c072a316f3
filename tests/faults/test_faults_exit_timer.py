"""The command line's last resort after a signal (issue 19, item 1): a process whose clean-up
does not end exits with 128 + signal ``grace`` seconds after the signal, and at once on a
second signal, with one line; a library caller (no :func:`exit_after_signal`) is never ended
this way.  The clean-up that never ends is a wait in a ``finally`` block."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = textwrap.dedent("""
    import sys, threading, time
    from analogue.circuit import ngspice as ng
    if sys.argv[1] == "cli":
        ng.exit_after_signal(1.0)
    with ng.interrupt_guard():
        try:
            print("ready", flush=True)
            time.sleep(100)
        finally:
            print("cleaning up", flush=True)
            threading.Event().wait(8)      # a clean-up that does not end (for 8 s)
    print("unwound", flush=True)
""")


def _start(tmp_path, mode):
    script = tmp_path / "hang.py"
    script.write_text(SCRIPT)
    env = dict(os.environ, PYTHONPATH=str(ROOT), TMPDIR=str(tmp_path))
    proc = subprocess.Popen([sys.executable, str(script), mode], env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout.readline().strip() == "ready"
    return proc


def test_a_clean_up_that_does_not_end_is_cut_short(tmp_path):
    proc = _start(tmp_path, "cli")
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=6)     # well before the 8 s clean-up
    assert proc.returncode == 130, err
    assert "cleaning up" in out and "unwound" not in out
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "SIGINT" in lines[0] and "did not end within 1 s" in lines[0]


@pytest.mark.parametrize("second", [signal.SIGINT, signal.SIGTERM])
def test_a_second_signal_ends_the_clean_up_at_once(tmp_path, second):
    proc = _start(tmp_path, "cli")
    proc.send_signal(signal.SIGINT)
    assert proc.stdout.readline().strip() == "cleaning up"
    proc.send_signal(second)
    out, err = proc.communicate(timeout=6)
    assert proc.returncode == 128 + second, err
    assert "second signal" in err and len([ln for ln in err.splitlines() if ln.strip()]) == 1


def test_a_library_caller_is_never_ended_by_the_timer(tmp_path):
    proc = _start(tmp_path, "library")
    proc.send_signal(signal.SIGINT)
    assert proc.stdout.readline().strip() == "cleaning up"
    time.sleep(2.0)                            # twice the grace the CLI would give
    assert proc.poll() is None                 # still cleaning up: nobody cut it short
    proc.send_signal(signal.SIGINT)            # a second signal does not end it either
    time.sleep(0.5)
    assert proc.poll() is None
    proc.kill()
    proc.communicate()
