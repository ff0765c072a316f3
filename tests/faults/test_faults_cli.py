"""Fault injection at the command line: every failure is one line on stderr, no traceback
(ANALOGUE_DEBUG=1 keeps it), exit 2 for bad input and 1 for a failed run."""
import os
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

from analogue import Runner
from analogue.cli import main
from analogue.circuit import experiments as E
from conftest import toml_text

ROOT = Path(__file__).resolve().parents[2]
STICK = tomllib.loads((ROOT / "circuits" / "stick.toml").read_text())


def err_line(r) -> str:
    """The single error line of a failed invocation."""
    text = r.stderr if r.stderr else r.output
    lines = [ln for ln in text.splitlines() if ln.strip()]
    assert len(lines) == 1, text
    assert "Traceback" not in text
    return lines[0]


def write_doc(path: Path, **changes) -> Path:
    d = tomllib.loads(toml_text(STICK))
    for k, v in changes.items():
        if isinstance(v, dict):
            d.setdefault(k, {}).update(v)
        else:
            d[k] = v
    path.write_text(toml_text(d))
    return path


# --------------------------------------------------------- exceptions reaching the CLI
def _boom(exc):
    def f(*a, **k):
        raise exc
    return f


FAILURES = [
    (zipfile.BadZipFile("File is not a zip file"), 1),
    (EOFError("Ran out of input"), 1),
    (MemoryError(), 1),
    (OverflowError("(34, 'Numerical result out of range')"), 1),
    (RuntimeError("ngspice failed:\nline one\nline two"), 1),
    (OSError(28, "No space left on device"), 1),
    (TypeError("tau_m must be a real number, got '1'"), 2),
    (ValueError("experiment.t_end must be > 0"), 2),
    (KeyError("v"), 1),
    (ZeroDivisionError("float division by zero"), 1),
]


@pytest.mark.parametrize("exc,code", FAILURES, ids=[type(e).__name__ for e, _ in FAILURES])
@pytest.mark.parametrize("cmd", ["run", "report", "paper"])
def test_every_failure_is_one_line_with_its_exit_code(cli, monkeypatch, tmp_path, exc, code, cmd):
    import analogue.report.pipeline as P
    for fn in ("run_experiment", "build_experiment_report", "build_paper_report"):
        monkeypatch.setattr(P, fn, _boom(exc))
    args = [cmd] + (["stick"] if cmd != "paper" else []) + ["--out", str(tmp_path / "o")] * (cmd != "run")
    r = cli.invoke(main, args)
    assert r.exit_code == code, (r.output, r.exception)
    line = err_line(r)
    assert line.startswith("analogue: error:")
    if isinstance(exc, RuntimeError):
        assert "line one" in line and "line two" in line  # every line of the message, one line
    if isinstance(exc, MemoryError):
        assert "memory" in line.lower()


def test_debug_keeps_the_traceback(cli, monkeypatch):
    import analogue.report.pipeline as P
    monkeypatch.setattr(P, "run_experiment", _boom(EOFError("Ran out of input")))
    monkeypatch.setenv("ANALOGUE_DEBUG", "1")
    r = cli.invoke(main, ["run", "stick"])
    assert isinstance(r.exception, EOFError)


def test_interrupt_is_one_line(cli, monkeypatch):
    import analogue.report.pipeline as P
    monkeypatch.setattr(P, "run_experiment", _boom(KeyboardInterrupt()))
    r = cli.invoke(main, ["run", "stick"])
    assert r.exit_code == 130
    assert "interrupted" in err_line(r)


@pytest.mark.parametrize("args", [["run"], ["run", "stick", "--no-such-option"],
                                  ["report", "stick", "--workers", "0"], ["nosuchcommand"],
                                  ["theory", "nosuchquantity"]])
def test_usage_errors_are_one_line(cli, args):
    r = cli.invoke(main, args)
    assert r.exit_code == 2
    assert err_line(r).startswith("analogue: error:")


@pytest.mark.slow  # > 5 s (make test-fast skips it)
def test_console_script_one_line_for_a_bad_file(tmp_path):
    exe = Path(sys.executable).with_name("analogue")
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"name = \"x\"\ndescription = \"caf\xe9\"\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env.pop("ANALOGUE_DEBUG", None)
    p = subprocess.run([str(exe), "run", str(bad)], capture_output=True, text=True, timeout=120,
                       env=env)
    assert p.returncode == 2
    assert p.stderr.strip().count("\n") == 0 and str(bad) in p.stderr, p.stderr
    assert "Traceback" not in p.stderr


# ------------------------------------------------------------ options: scheduler, store
@pytest.mark.parametrize("address", ["ucx://host:8786", "tcp://host:notaport", "tcp://:8786",
                                     "tcp://host:0", "tcp://host:70000", "host:8786", "",
                                     "inproc://x", "tcp://host:8786/path;rm"])
def test_bad_scheduler_addresses_name_the_option(cli, address):
    r = cli.invoke(main, ["run", "stick", "--scheduler", address])
    assert r.exit_code == 2
    assert "--scheduler" in err_line(r)


def test_good_scheduler_address_is_passed_on(cli, monkeypatch):
    import analogue.report.pipeline as P
    seen = {}
    import analogue.cli as C
    monkeypatch.setattr(C, "_reach_scheduler", lambda address: seen.setdefault("reached", address))
    monkeypatch.setattr(P, "run_experiment", lambda name, opts: seen.setdefault("o", opts) and _Done())
    r = cli.invoke(main, ["run", "stick", "--scheduler", "tcp://10.0.0.1:8786"])
    assert r.exit_code == 0, r.output
    assert seen["o"].scheduler == "tcp://10.0.0.1:8786" == seen["reached"]


class _Done:
    def summary(self):
        return "done"


@pytest.mark.parametrize("store", ["", "   "])
def test_empty_store_is_refused(cli, store):
    r = cli.invoke(main, ["run", "stick", "--store", store])
    assert r.exit_code == 2
    assert "--store" in err_line(r)


def test_store_that_is_a_file_is_refused(cli, tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    r = cli.invoke(main, ["run", "stick", "--store", str(f)])
    assert r.exit_code == 2
    assert "--store" in err_line(r)


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "x"])
def test_bad_timeout_is_refused(cli, value):
    r = cli.invoke(main, ["run", "stick", "--timeout", value])
    assert r.exit_code == 2
    assert "--timeout" in err_line(r)


@pytest.mark.parametrize("cmd", ["run", "report", "paper"])
def test_timeout_reaches_simulate(cli, monkeypatch, tmp_path, cmd):
    import analogue.report.pipeline as P
    seen = {}

    def capture(*a):
        seen["opts"] = a[-1]
        return _Done() if cmd == "run" else tmp_path / "index.html"
    for fn in ("run_experiment", "build_experiment_report", "build_paper_report"):
        monkeypatch.setattr(P, fn, capture)
    args = [cmd] + (["stick"] if cmd != "paper" else []) + ["--timeout", "7.5"]
    r = cli.invoke(main, args)
    assert r.exit_code == 0, r.output
    assert seen["opts"].timeout == 7.5
    assert seen["opts"].runner().timeout == 7.5
    r = cli.invoke(main, [cmd] + (["stick"] if cmd != "paper" else []))
    assert seen["opts"].timeout is None
    assert seen["opts"].runner().timeout == Runner().timeout  # the default hour


# ------------------------------------------------------------------------------ paths
def test_paper_runs_the_paper_experiments_only(cli, monkeypatch, tmp_path):
    import analogue.report.pipeline as P
    (tmp_path / "circuits").mkdir()
    write_doc(tmp_path / "circuits" / "mine.toml", name="mine")
    monkeypatch.chdir(tmp_path)
    seen = {}

    def capture(names, out, opts, title, chapter=()):
        stem = lambda n: Path(n).stem if isinstance(n, Path) else getattr(n, "name", n)
        seen["names"] = [stem(n) for n in names]
        seen["chapter"] = [stem(n) for n in chapter]
        return out / "index.html"
    monkeypatch.setattr(P, "build_report", capture)
    r = cli.invoke(main, ["paper", "--out", str(tmp_path / "o")])
    assert r.exit_code == 0, r.output
    assert seen["names"] == list(E.PAPER_EXPERIMENTS)
    assert "mine" not in seen["chapter"]  # the user's circuits/ file is in neither part


def test_report_default_out_for_a_path_is_report_name(cli, monkeypatch, tmp_path):
    import analogue.report.pipeline as P
    src = write_doc(tmp_path / "my_exp.toml", name="my_exp")
    seen = {}
    monkeypatch.setattr(P, "build_experiment_report",
                        lambda name, out, opts: seen.setdefault("out", out) / "index.html")
    monkeypatch.chdir(tmp_path / "..")
    r = cli.invoke(main, ["report", str(src)])
    assert r.exit_code == 0, r.output
    assert Path(seen["out"]) == Path("report") / "my_exp"


def test_netlist_writes_next_to_the_file_it_read(cli, tmp_path, monkeypatch):
    src = write_doc(tmp_path / "mine.toml", name="mine")
    elsewhere = tmp_path / "cwd"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    r = cli.invoke(main, ["netlist", str(src)])
    assert r.exit_code == 0, r.output
    deck = tmp_path / "mine.cir"
    assert deck.is_file() and ".tran" in deck.read_text()
    assert list(elsewhere.iterdir()) == []


def test_unreachable_scheduler_is_one_line_naming_the_option(cli, monkeypatch):
    import socket
    import time
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # nothing listens there now: connection refused at once
    import analogue.report.pipeline as P
    monkeypatch.setattr(P, "run_experiment", _boom(AssertionError("must not run")))
    t0 = time.perf_counter()
    r = cli.invoke(main, ["run", "stick", "--scheduler", f"tcp://127.0.0.1:{port}"])
    assert r.exit_code == 1
    line = err_line(r)
    assert "--scheduler" in line and str(port) in line
    assert time.perf_counter() - t0 < 15
