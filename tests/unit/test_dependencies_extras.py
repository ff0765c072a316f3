"""Dependencies: runtime deps are what the package imports; spicelib and the notebook runner
only for tests; Dask is the extra analogue[dask], with a one-line hint when it is missing."""
import sys
import tomllib
from pathlib import Path

import pytest

from analogue.circuit import simulate as S

ROOT = Path(__file__).resolve().parents[2]


def _deps():
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    name = lambda spec: spec.split("[")[0].split(">")[0].split("=")[0].strip().lower()
    return ({name(d) for d in data["dependencies"]},
            {k: {name(d) for d in v} for k, v in data["optional-dependencies"].items()})


def test_runtime_and_extras():
    runtime, extras = _deps()
    assert "tomli-w" not in runtime and "spicelib" not in runtime and "dask" not in runtime
    assert {"xarray", "netcdf4", "schemdraw"} <= runtime
    assert extras["dask"] == {"dask"}
    # `make test` installs .[test]: it must bring what the tests import
    assert {"spicelib", "dask", "nbclient", "nbformat", "ipykernel", "pytest-timeout"} <= extras["test"]


def test_spicelib_and_tomli_w_are_not_imported_by_the_package():
    for p in (ROOT / "analogue").rglob("*.py"):
        text = p.read_text()
        for mod in ("spicelib", "tomli_w"):
            assert f"import {mod}" not in text and f"from {mod}" not in text, (p, mod)


def test_missing_dask_gives_a_one_line_hint(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)   # import fails as if not installed
    with pytest.raises(RuntimeError, match=r"pip install 'analogue\[dask\]'") as info:
        S._executor(1, "tcp://127.0.0.1:1", 1)
    assert "\n" not in str(info.value)
