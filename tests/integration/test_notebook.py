"""examples/quickstart.ipynb runs from top to bottom (nbclient), so it cannot rot: it simulates a
small circuit, overlays the exact propagator, draws the work rate function and fluctuation
relation, and round-trips its data through netCDF.  About 20 s on an idle machine."""
import os
import shutil
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOK = ROOT / "examples" / "quickstart.ipynb"

pytestmark = pytest.mark.slow


def test_quickstart_notebook_executes(tmp_path, monkeypatch):
    if shutil.which("ngspice") is None:
        pytest.skip("ngspice not installed")
    monkeypatch.setenv("ANALOGUE_STORE", str(tmp_path / "store"))
    # the kernel imports this checkout, whichever analogue the venv has installed
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    monkeypatch.delenv("MPLBACKEND", raising=False)   # the kernel's inline backend makes the PNGs
    nb = nbformat.read(NOTEBOOK, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), \
        "commit the notebook without outputs"
    client = nbclient.NotebookClient(nb, timeout=180, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()   # raises CellExecutionError on any failing cell
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) == 3          # trajectories, propagators, rate function + FR
    text = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
    assert "wrote and re-read transition.nc (128, 301)" in text
    assert "('replica', 'time')" in text
