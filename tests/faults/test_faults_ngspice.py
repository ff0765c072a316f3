"""Fault injection: ngspice misbehaves (issue 8, section 4).

Fake ``ngspice`` executables (shell scripts put first on PATH) answer ``ngspice -v`` with a
made-up version (99, so that nothing they produce could share a store key with the real
ngspice) and then misbehave: non-zero exit with several error lines, a hang, a segfault,
garbage / truncated / negative-count raw files, a wrapper whose child keeps stdout open.
Each test asserts the exact outcome: a one-line NgspiceError (with ngspice's own lines) within
a bounded time, or the correct result; and no process or temporary directory left behind.
"""
from __future__ import annotations

import os
import signal
import stat
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import analogue
from analogue.circuit import ngspice as ng
from analogue.circuit.rawfile import read_raw
from conftest import STICK_A02

pytestmark = pytest.mark.requires_ngspice

GOOD_DECK = ("ok\nC1 v1 0 1e-6\nR1 v1 0 1e3\n.ic v(v1)=1\n.tran 1e-5 1e-3 0 1e-5 uic\n"
             ".save v(v1)\n.end\n")
HEADER = ("Title: t\nDate: x\nPlotname: Transient Analysis\nFlags: real\nNo. Variables: {nvar}\n"
          "No. Points: {npts}\nVariables:\n\t0\ttime\ttime\n\t1\tv(a)\tvoltage\nBinary:\n")


def _alive(pid: int) -> bool:
    """True if ``pid`` runs (a zombie, i.e. dead but not yet reaped, counts as gone)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (FileNotFoundError, ProcessLookupError):
        return False


@pytest.fixture
def fake(tmp_path, monkeypatch):
    """``fake(body)`` installs an ngspice whose ``-v`` says ngspice-99 and which otherwise runs
    the POSIX-shell ``body`` (args: -b -r RAW DECK; $STATE is a directory for evidence).
    Temporary directories go to tmp_path/tmp so that leftovers can be counted."""
    bindir, state, tmp = tmp_path / "bin", tmp_path / "state", tmp_path / "tmp"
    for d in (bindir, state, tmp):
        d.mkdir()
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    monkeypatch.setenv("STATE", str(state))
    monkeypatch.setattr("tempfile.tempdir", str(tmp))

    def install(body: str) -> Path:
        exe = bindir / "ngspice"
        exe.write_text("#!/bin/sh\n"
                       'if [ "$1" = "-v" ]; then echo "** ngspice-99 : Circuit level simulation '
                       'program"; exit 0; fi\n'
                       'echo "$$" >> "$STATE/pids"\n'
                       + textwrap.dedent(body))
        exe.chmod(exe.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
        return exe

    install.state, install.tmp = state, tmp
    return install


def _leftover_dirs(tmp: Path) -> list:
    return sorted(p.name for p in tmp.glob("analogue-ngspice-*"))


def _pids(state: Path) -> list[int]:
    out = []
    for name in ("pids", "child"):
        f = state / name
        if f.exists():
            out += [int(s) for s in f.read_text().split()]
    return out


def _one_line(exc) -> str:
    msg = str(exc.value)
    assert "\n" not in msg and msg.strip() == msg and msg
    return msg


# ------------------------------------------------------------------- exit status, signals
def test_nonzero_exit_quotes_every_error_line(fake):
    fake("""
        echo "Error on line 3 or its substitute:" >&2
        echo "  q1 a b c nosuchmodel" >&2
        echo "could not find a valid modelname" >&2
        echo "Error: circuit not parsed." >&2
        exit 3
    """)
    with pytest.raises(ng.NgspiceError) as exc:
        ng.run_deck(GOOD_DECK)
    msg = _one_line(exc)
    assert "status 3" in msg
    for line in ("Error on line 3 or its substitute:", "q1 a b c nosuchmodel",
                 "could not find a valid modelname", "Error: circuit not parsed."):
        assert line in msg
    assert msg.index("Error on line 3") < msg.index("circuit not parsed")  # ngspice's order
    assert _leftover_dirs(fake.tmp) == []


def test_error_message_is_bounded(fake):
    fake("""
        i=0
        while [ $i -lt 3000 ]; do echo "Error: problem number $i of many" >&2; i=$((i+1)); done
        head -c 3000000 /dev/zero | tr '\\0' 'x'
        exit 1
    """)
    with pytest.raises(ng.NgspiceError) as exc:
        ng.run_deck(GOOD_DECK)
    msg = _one_line(exc)
    assert len(msg) <= 1200
    assert "problem number 0 " in msg and "problem number 2999" in msg  # first and last kept


def test_segfault_is_one_line_naming_the_signal(fake):
    fake("""
        echo "about to crash" >&2
        kill -SEGV $$
    """)
    with pytest.raises(ng.NgspiceError) as exc:
        ng.run_deck(GOOD_DECK)
    msg = _one_line(exc)
    assert "SIGSEGV" in msg and "about to crash" in msg
    assert _leftover_dirs(fake.tmp) == []


# ----------------------------------------------------------------------- hangs, timeouts
@pytest.mark.timeout(60)
def test_hang_is_killed_at_the_timeout_with_its_children(fake):
    # sh (the "ngspice") starts a child that inherits stdout/stderr and then waits for it:
    # killing only sh would leave the child holding the pipes.
    fake("""
        sleep 300 &
        echo "$!" > "$STATE/child"
        echo "simulating..." >&2
        wait
    """)
    t0 = time.monotonic()
    with pytest.raises(ng.NgspiceError) as exc:
        ng.run_deck(GOOD_DECK, timeout=1.0)
    elapsed = time.monotonic() - t0
    msg = _one_line(exc)
    assert "timeout=1.0" in msg and "simulating..." in msg
    assert elapsed < 15.0, elapsed  # ~1 s; the child would hold the pipes for 300 s
    pids = _pids(fake.state)
    assert len(pids) == 2
    deadline = time.monotonic() + 5
    while any(_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(_alive(p) for p in pids)
    assert _leftover_dirs(fake.tmp) == []


@pytest.mark.timeout(60)
def test_wrapper_whose_child_keeps_the_pipes_open_returns_promptly(fake):
    """A wrapper script (as a module system or a container shim would install) runs the real
    ngspice but leaves a background child holding stdout: the run is complete when ngspice
    exits, its result is the real one, and the stray child is killed."""
    real = "/usr/bin/ngspice"
    if not os.access(real, os.X_OK):
        pytest.skip("needs the real ngspice at /usr/bin/ngspice")
    fake(f"""
        sleep 300 &
        echo "$!" > "$STATE/child"
        {real} "$@"
    """)
    t0 = time.monotonic()
    res = ng.run_deck(GOOD_DECK, timeout=20.0)
    elapsed = time.monotonic() - t0
    assert elapsed < 15.0, elapsed  # the child sleeps 300 s
    t = res.plot["time"]
    v = res.plot["v(v1)"]
    # RC = 1 ms: v(t) = exp(-t / 1 ms) from the real simulator
    np.testing.assert_allclose(v, np.exp(-t / 1e-3), rtol=0, atol=2e-3)
    child = int((fake.state / "child").read_text())
    deadline = time.monotonic() + 5
    while _alive(child) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(child)


@pytest.mark.timeout(60)
def test_version_probe_that_hangs_is_bounded(fake, monkeypatch):
    exe = fake("")
    exe.write_text("#!/bin/sh\nsleep 300 &\nwait\n")
    monkeypatch.setattr(ng, "VERSION_TIMEOUT", 1.0)
    t0 = time.monotonic()
    with pytest.raises(ng.NgspiceError) as exc:
        ng.ngspice_version()
    assert time.monotonic() - t0 < 15.0
    msg = _one_line(exc)
    assert "-v" in msg


def test_version_probe_without_a_version_is_one_line(fake):
    exe = fake("")
    exe.write_text("#!/bin/sh\necho 'this is not the simulator'\necho 'line two'\n")
    with pytest.raises(ng.NgspiceError) as exc:
        ng.ngspice_version()
    msg = _one_line(exc)
    assert "this is not the simulator" in msg and "line two" in msg


@pytest.mark.timeout(60)
def test_simulate_timeout_keyword_holds(fake, tmp_path):
    fake("""
        sleep 300 &
        echo "$!" > "$STATE/child"
        wait
    """)
    t0 = time.monotonic()
    with pytest.raises(ng.NgspiceError) as exc:
        analogue.simulate(STICK_A02, v0=0.4, t_end=1.0, replicas=2, seed=1, replicas_per_deck=1,
                          workers=2, store=tmp_path / "store", progress=False, timeout=1.5)
    assert time.monotonic() - t0 < 30.0  # imports + 1.5 s, on a loaded machine; not 300 s
    assert "timeout=1.5" in _one_line(exc)
    assert _leftover_dirs(fake.tmp) == []
    assert not ng._ACTIVE
    deadline = time.monotonic() + 5  # SIGKILL is delivered asynchronously
    while any(_alive(p) for p in _pids(fake.state)) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(_alive(p) for p in _pids(fake.state))


# ------------------------------------------------------------------------- bad raw files
def _serve_raw(fake, payload: bytes) -> None:
    """Install a fake that copies ``payload`` to the raw file it is asked for (-r $3), exit 0."""
    (fake.state / "raw.bin").write_bytes(payload)
    fake("""
        cp "$STATE/raw.bin" "$3"
        exit 0
    """)


def test_garbage_raw_file(fake):
    _serve_raw(fake, np.random.default_rng(1).bytes(4096))
    with pytest.raises(ng.NgspiceError) as exc:
        ng.run_deck(GOOD_DECK)
    assert "raw file" in _one_line(exc)


@pytest.mark.timeout(30)
def test_negative_point_count_raw_file(fake):
    _serve_raw(fake, HEADER.format(nvar=2, npts=-5).encode()
               + np.array([0, 1, 1e-3, 0.5]).tobytes())
    with pytest.raises(ng.NgspiceError) as exc:
        ng.run_deck(GOOD_DECK)
    msg = _one_line(exc)
    assert "No. Points" in msg and "-5" in msg


def test_truncated_raw_file_is_an_incomplete_run(fake):
    _serve_raw(fake, HEADER.format(nvar=2, npts=1000).encode()
               + np.array([0, 1, 1e-4, 0.9, 2e-4]).tobytes())  # 2.5 points of 1000
    with pytest.raises(ng.NgspiceError) as exc:
        ng.run_deck(GOOD_DECK, t_stop=1e-3)
    assert "before t_stop" in _one_line(exc)


@pytest.mark.parametrize("nvar,npts,data,match", [
    (2, -5, b"\0" * 32, "No. Points"),
    (-2, 4, b"\0" * 32, "No. Variables"),
    (2, "lots", b"\0" * 32, "No. Points"),
    (10**12, 4, b"\0" * 32, "No. Variables"),
    (2, 10**15, np.arange(4.0).tobytes(), None),   # clipped to the 2 points present
    (3, 4, b"\0" * 32, "variable"),                   # table lists 2 of the 3 declared
])
@pytest.mark.timeout(20)
def test_raw_reader_validates_header_against_file_length(tmp_path, nvar, npts, data, match):
    p = tmp_path / "x.raw"
    p.write_bytes(HEADER.format(nvar=nvar, npts=npts).encode() + data)
    if match is None:
        (plot,) = read_raw(p)
        assert plot.n_points == 2
        np.testing.assert_array_equal(plot["time"], [0.0, 2.0])
        return
    with pytest.raises(ValueError, match=match):
        read_raw(p)


@pytest.mark.timeout(20)
def test_raw_reader_stops_on_a_second_bad_plot(tmp_path):
    first = HEADER.format(nvar=2, npts=2).encode() + np.arange(4.0).tobytes()
    second = HEADER.format(nvar=2, npts=-1).encode()
    p = tmp_path / "two.raw"
    p.write_bytes(first + second)
    with pytest.raises(ValueError, match="No. Points"):
        read_raw(p)


def test_non_monotonic_or_non_finite_time_is_refused(fake):
    _serve_raw(fake, HEADER.format(nvar=2, npts=3).encode()
               + np.array([0, 1, np.nan, 0.9, 1e-3, 0.5]).tobytes())
    with pytest.raises(ng.NgspiceError) as exc:
        ng.run_deck(GOOD_DECK, t_stop=1e-3)
    assert "time" in _one_line(exc)


# ------------------------------------------------------------------------- deck screening
@pytest.mark.parametrize("deck", [
    "t\n.control\nshell touch $STATE/pwned\n.endc\n.end\n",
    "t\n.CONTROL\nrun\n.ENDC\n.end\n",
    "t\n  .include /etc/passwd\n.end\n",
    "t\n.inc /etc/passwd\n.end\n",
    "t\n.lib /etc/passwd typ\n.end\n",
    "t\n.osdi /tmp/evil.osdi\n.end\n",
    "t\nshell touch $STATE/pwned\n.end\n",
    "*ng_script\nshell touch x\n.end\n",
])
def test_run_deck_refuses_control_shell_and_includes(fake, deck):
    fake("""
        touch "$STATE/ran"
        exit 0
    """)
    with pytest.raises(ValueError) as exc:
        ng.run_deck(deck)
    assert "deck" in _one_line(exc)
    assert not (fake.state / "ran").exists() and not (fake.state / "pwned").exists()


def test_title_line_may_say_anything(fake):
    """The first line of a deck is its title, never a command: 'shell' there is harmless."""
    fake("""
        echo "Error: fake ran" >&2
        exit 1
    """)
    with pytest.raises(ng.NgspiceError, match="fake ran"):
        ng.run_deck("shell .include title\nR1 1 0 1\n.end\n")


def test_signal_names_in_messages():
    assert ng._signal_name(signal.SIGSEGV) == "SIGSEGV"
    assert ng._signal_name(200) == "signal 200"


def test_raw_file_beyond_the_memory_limit_is_refused_unread(fake, monkeypatch):
    """A runaway deck can write a raw file larger than memory: refused by its size, before
    it is read (here a 3 MB file against a 1 MB limit)."""
    (fake.state / "raw.bin").write_bytes(HEADER.format(nvar=2, npts=196608).encode()
                                         + np.zeros(2 * 196608).tobytes())
    fake("""
        cp "$STATE/raw.bin" "$3"
        exit 0
    """)
    monkeypatch.setenv("ANALOGUE_MEMORY_LIMIT", "1M")
    with pytest.raises(ng.NgspiceError) as exc:
        ng.run_deck(GOOD_DECK)
    msg = _one_line(exc)
    assert "raw file" in msg and "ANALOGUE_MEMORY_LIMIT" in msg


def test_non_finite_simulator_values_are_an_error_not_data(fake):
    """ngspice exiting 0 with NaN in a vector: the batch fails in one line instead of being
    stored (a NaN entry would be quarantined and re-run for ever)."""
    from analogue.circuit.simulate import BatchTask, run_batch
    t = np.linspace(0.0, 1e-3, 11)
    v = np.exp(-t / 1e-3)
    v[4] = np.nan
    (fake.state / "raw.bin").write_bytes(HEADER.format(nvar=2, npts=11).encode()
                                         + np.column_stack([t, v]).tobytes())
    fake("""
        cp "$STATE/raw.bin" "$3"
        exit 0
    """)
    task = BatchTask(index=0, text=GOOD_DECK, v_names=("v(a)",), x_names=None, to_model_v=1.0,
                     to_model_x=1.0, time_scale=1e-3, times=np.linspace(0.0, 1.0, 6),
                     v0=np.array([1.0]))
    with pytest.raises(ng.NgspiceError) as exc:
        run_batch(task)
    msg = _one_line(exc)
    assert "NaN" in msg or "non-finite" in msg
