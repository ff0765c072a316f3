"""`import analogue` and `analogue --help` load no heavy dependency (issue 22, item 3).

Start-up time itself is measured in ``benchmarks/bench_startup.py`` (no timed assertion here);
what is tested is the cause of slow start-ups: which modules an import pulls in.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("scipy", "matplotlib", "xarray", "netCDF4", "dask", "distributed", "PySpice", "jinja2")


def _loaded_after(code: str) -> set[str]:
    probe = (f"{code}\nimport sys, json\n"
             "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    return set(json.loads(out.stdout.strip().splitlines()[-1]))


@pytest.mark.parametrize("code", [
    "import analogue",
    "import analogue; analogue.Model(tau_m=1, delta=0.5, a=0.2, gamma=10)",
    "import sys\nfrom analogue.cli import main\nsys.argv = ['analogue', '--help']\n"
    "try:\n    main()\nexcept SystemExit:\n    pass",
])
def test_start_up_loads_no_heavy_dependency(code):
    heavy = sorted(set(HEAVY) & _loaded_after(code))
    assert heavy == [], f"{code!r} imported {heavy}"


def test_lazy_names_still_resolve():
    loaded = _loaded_after("import analogue\nanalogue.simulate\nanalogue.open_ensemble")
    assert "analogue" in loaded
