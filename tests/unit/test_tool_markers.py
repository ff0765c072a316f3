"""requires_ngspice / requires_chromium skip, with the reason, when the tool is missing."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parents[1]
ROOT = TESTS.parent


@pytest.mark.slow  # > 5 s (make test-fast skips it)
def test_markers_skip_with_reason_when_tools_are_missing(tmp_path: Path) -> None:
    (tmp_path / "test_tools.py").write_text(
        "import pytest\n\n"
        "@pytest.mark.requires_ngspice\ndef test_needs_ngspice():\n    pass\n\n"
        "@pytest.mark.requires_chromium\ndef test_needs_chromium():\n    pass\n\n"
        "def test_plain():\n    pass\n")
    empty = tmp_path / "bin"
    empty.mkdir()
    env = {**os.environ, "PATH": str(empty),
           "PYTHONPATH": os.pathsep.join([str(ROOT), str(TESTS)])}
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "conftest", "-p", "no:cacheprovider", "-n", "0",
         "-rs", "-q", "-p", "no:randomly", "--rootdir", str(tmp_path),
         "-o", "markers=requires_ngspice\nrequires_chromium", str(tmp_path / "test_tools.py")],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    assert "1 passed, 2 skipped" in out, out
    assert "ngspice is not on PATH" in out and "headless Chromium not found" in out, out
