"""Fault injection: SIGTERM/SIGINT while ``analogue report`` runs its circuit in the report's
circuit threads (not the main thread, which compares and waits): the process still exits
promptly with 128 + signal and one line, every ngspice it started is gone, and no temporary
directory or store file is left (issue 10: the overlapped pipeline keeps issue 8's
interrupt behaviour)."""
from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test_faults_signals import CLI_TOML, _assert_clean, _interrupt_when_busy, _workspace

pytestmark = [pytest.mark.slow, pytest.mark.timeout(300)]


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_cli_report_interrupted_in_the_circuit_threads_cleans_up(tmp_path, sig):
    tmp, store, toml, marker, env = _workspace(tmp_path, "sigtest.toml", CLI_TOML)
    env["ANALOGUE_THEORY_CACHE"] = "off"
    exe = Path(sys.executable).with_name("analogue")
    cmd = [str(exe), "report", str(toml), "--out", str(tmp_path / "out"), "--store", str(store),
           "--workers", "1", "--no-progress"]
    proc = subprocess.Popen(cmd, env=env, cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    seen = _interrupt_when_busy(proc, store, tmp, marker, sig)
    t0 = time.monotonic()
    _, err = proc.communicate(timeout=60)
    # a hang detector, not a timing test: the report itself would run on for minutes; 15 s
    # was exceeded once at load 8 (the circuit threads' clean-up waits for the ngspice kills)
    assert time.monotonic() - t0 < 45, err
    _assert_clean(marker, proc.pid, tmp, store, seen)
    assert proc.returncode == 128 + sig, (proc.returncode, err)
    assert "Traceback" not in err
    last = [ln for ln in err.splitlines() if ln.strip()][-1]
    assert last.startswith("analogue: error:") and signal.Signals(sig).name in last, err
