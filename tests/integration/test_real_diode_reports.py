"""End to end with real parts: `analogue report` on an experiment whose bridge is made of
1N4148 or BAT54 diodes (quick sizes, few replicas).  The noise-free run (paper Fig. 1) uses the
user's own component values with the noise source off, so the part ratings that pass for the
nominal circuit pass for it too."""
import json
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from conftest import toml_text

ROOT = Path(__file__).resolve().parents[2]
PAYLOAD = "<script>alert('x')</script> & \"quotes\""


def small_experiment(tmp_path: Path, diode: str) -> Path:
    d = tomllib.loads((ROOT / "circuits" / "stick.toml").read_text())
    name = f"stick_{diode.lower()}"
    d["name"] = name
    d["description"] = f"Stick regime on {diode} diodes. {PAYLOAD}"
    d["circuit"]["diode"] = diode
    d["experiment"].update(replicas=64, t_end=4.0, histogram_times=[0.5, 1.0, 4.0])
    d["report"] = {"stationary_replicas": 32, "stationary_t_end": 20.0, "stationary_burn_in": 2.0,
                   "prehistory": [[2.0, 0.9, 1.0]], "check_replicas": 16}
    path = tmp_path / f"{name}.toml"
    path.write_text(toml_text(d))
    return path


@pytest.mark.slow
@pytest.mark.parametrize("diode", ["1N4148", "BAT54"])
def test_real_diode_report_end_to_end(tmp_path, diode):
    src = small_experiment(tmp_path, diode)
    out = tmp_path / "report"
    exe = Path(sys.executable).with_name("analogue")
    env = dict(os.environ, ANALOGUE_STORE=str(tmp_path / "store"), PYTHONPATH=str(ROOT))
    p = subprocess.run([str(exe), "report", str(src), "--quick", "--out", str(out),
                        "--no-progress", "--workers", "2"],
                       capture_output=True, text=True, timeout=1500, env=env, cwd=tmp_path)
    assert p.returncode == 0, p.stderr[-3000:]
    metrics = json.loads((out / "metrics.json").read_text())
    name = src.stem
    prov = metrics["provenance"]
    assert prov["circuit_spec"][name]["diode"] == diode
    assert not metrics.get("failures")
    assert len(metrics["comparisons"]) > 10
    hashes = prov["deck_hashes"][name]
    assert hashes["noise_free"] and hashes["noise_free"] != hashes["transition v0=2"]
    html = (out / "index.html").read_text()
    assert "<script" not in html and "&lt;script&gt;alert(" in html
    # Fig. 1: the noise-free circuit follows the deterministic motion of the smoothed law it
    # implements (the deviation is printed in the caption)
    dev = float(re.search(r"smoothed law: ([0-9.e+-]+)", html).group(1))
    assert dev < 0.05, dev
    print(f"{diode}: report in {prov['wall_time_s']:.0f} s")
