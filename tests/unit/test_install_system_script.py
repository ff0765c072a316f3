"""scripts/install-system.sh (make setup): nothing goes through apt when ngspice is on PATH;
the missing Debian packages otherwise.  Run with stub commands only (no root, no network)."""
import shutil
import stat
import subprocess
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "install-system.sh"
BASH = shutil.which("bash")


def _stub(d: Path, name: str, body: str) -> None:
    p = d / name
    p.write_text(f"#!{BASH}\n{body}\n")
    p.chmod(p.stat().st_mode | stat.S_IXUSR)


@pytest.fixture
def stubs(tmp_path):
    if BASH is None or shutil.which("grep") is None:
        pytest.skip("bash and grep needed")
    d = tmp_path / "bin"
    d.mkdir()
    log = tmp_path / "calls.log"
    _stub(d, "grep", f'exec {shutil.which("grep")} "$@"')
    _stub(d, "dpkg-query", 'echo "unknown ok not-installed"')
    _stub(d, "apt-get", f'echo "apt-get $*" >> {log}')
    _stub(d, "sudo", '"$@"')
    _stub(d, "id", "echo 1000")
    return d, log


def _run(d: Path, *args):
    return subprocess.run([BASH, str(SCRIPT), *args], env={"PATH": str(d)}, capture_output=True,
                          text=True, timeout=30, check=False)


def test_no_apt_when_ngspice_is_on_path(stubs):
    d, log = stubs
    _stub(d, "ngspice", "exit 0")
    r = _run(d)
    assert r.returncode == 0, r.stderr
    assert not log.exists()


def test_missing_packages_are_installed(stubs):
    d, log = stubs
    r = _run(d, "--test")
    assert r.returncode == 0, r.stderr
    calls = log.read_text().splitlines()
    assert calls[0] == "apt-get update -qq"
    assert calls[1].endswith("ngspice libngspice0 chromium")


def test_test_mode_with_everything_present(stubs):
    d, log = stubs
    _stub(d, "ngspice", "exit 0")
    _stub(d, "chromium", "exit 0")
    assert _run(d, "--test").returncode == 0 and not log.exists()
