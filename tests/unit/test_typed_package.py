"""The package is typed (PEP 561 marker shipped) and `make lint` is part of CI (issue 12)."""
from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_py_typed_marker_is_shipped() -> None:
    assert (ROOT / "analogue" / "py.typed").is_file()
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "py.typed" in data["tool"]["setuptools"]["package-data"]["analogue"]


def test_ci_runs_lint_then_the_readme_test_command() -> None:
    lines = [ln.strip() for ln in (ROOT / ".ci" / "run").read_text().splitlines()
             if ln.strip() and not ln.lstrip().startswith("#")]
    assert lines.index("make lint") < lines.index("make test")
    makefile = (ROOT / "Makefile").read_text()
    assert "\nlint:" in makefile and "ruff check" in makefile and "mypy" in makefile
    assert "\ntest-fast:" in makefile and '-m "not slow"' in makefile
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert {e.split(">")[0] for e in extras["lint"]} == {"ruff", "mypy"}
