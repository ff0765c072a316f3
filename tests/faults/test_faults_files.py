"""Fault injection: writing the result files in a hostile environment (issue 19, items 5, 6).

- A non-UTF-8 locale (``LC_ALL=C`` without Python's UTF-8 mode) with the store, the ngspice
  temporary directories and ``--out`` below a directory named with accents and an emoji: the
  circuit and figures completed, then the page failed with "'utf-8' codec can't encode
  characters ... surrogates not allowed" and left a 0-byte index.tmp.
- A full disk: ``report --out`` said "[Errno 28] No space left on device" without a path and
  left metrics.json.tmp and partial PNGs; ``export --out`` said only "NetCDF: HDF error".
  A full disk is simulated portably: the writer fails with ENOSPC after writing part of its
  file (or, for netCDF, says "NetCDF: HDF error" with no space left).
"""
from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from analogue import files
from analogue.ensemble import Ensemble

ROOT = Path(__file__).resolve().parents[2]
ODD = "héllo wörld 😀"
C_LOCALE = {"LC_ALL": "C", "LANG": "C", "PYTHONUTF8": "0", "PYTHONCOERCECLOCALE": "0"}

SCRIPT = textwrap.dedent("""
    import json, sys
    from pathlib import Path
    import numpy as np
    import analogue
    from analogue import Model
    from analogue.report.html import Section, write_page
    from analogue.files import write_text
    from analogue.plots.style import save
    import matplotlib.pyplot as plt
    assert sys.getfilesystemencoding() == "ascii", sys.getfilesystemencoding()
    base = Path(sys.argv[1])
    e = analogue.simulate(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0), v0=0.4, t_end=1.0,
                          replicas=2, seed=3, progress=False, store=base / "store")
    out = base / "out"
    out.mkdir()
    fig = plt.figure()
    png = save(fig, out / "fig.png")
    write_text(out / "metrics.json", json.dumps({"store": e.meta["store"], "out": str(out)},
                                                ensure_ascii=False))
    write_page(out / "index.html", "title", [f"store {e.meta['store']}"],
               [Section("s", ["made in " + str(out)])])
    from analogue.export import metrics_rows
    assert metrics_rows(out / "metrics.json", "none") == []   # read back as UTF-8
    print("ok")
""")


@pytest.mark.requires_ngspice
def test_non_utf8_locale_with_non_ascii_paths(tmp_path):
    base = tmp_path / ODD
    (base / "tmp").mkdir(parents=True)
    script = tmp_path / "run.py"
    script.write_text(SCRIPT)
    env = {**os.environ, **C_LOCALE, "PYTHONPATH": str(ROOT), "TMPDIR": str(base / "tmp"),
           "ANALOGUE_THEORY_CACHE": "off"}
    res = subprocess.run([sys.executable, str(script), str(base)], env=env, capture_output=True,
                         timeout=300, check=False)
    assert res.returncode == 0, res.stderr.decode("utf-8", "replace")
    out = base / "out"
    page = (out / "index.html").read_text(encoding="utf-8")   # valid UTF-8 ...
    assert f"made in {out}" in page                              # ... naming the path as it is
    meta = json.loads((out / "metrics.json").read_text(encoding="utf-8"))
    assert meta["out"] == str(out) and meta["store"] == str(base / "store")
    assert sorted(p.name for p in out.iterdir()) == ["fig.png", "index.html", "metrics.json"]
    assert list((base / "tmp").iterdir()) == []


def test_cli_refuses_a_path_that_is_not_utf8_before_any_work(tmp_path):
    bad = os.fsencode(tmp_path) + b"/caf\xe9"      # Latin-1 bytes: no UTF-8 file can name it
    exe = Path(sys.executable).with_name("analogue")
    env = {**os.environ, **C_LOCALE, "PYTHONPATH": str(ROOT)}
    for args in ([b"report", b"stick", b"--out", bad], [b"run", b"stick", b"--store", bad]):
        res = subprocess.run([os.fsencode(exe), *args], env=env, capture_output=True,
                             timeout=120, check=False)
        err = res.stderr.decode("utf-8", "replace")
        assert res.returncode == 2, err
        lines = [ln for ln in err.splitlines() if ln.strip()]
        assert len(lines) == 1 and "not valid UTF-8" in lines[0], err
        assert ("--out" if b"--out" in args else "--store") in lines[0]
    assert not os.path.exists(bad)


class _FullFile:
    """An open file whose write puts half the data on disk, then fails with ENOSPC (the
    file is half there when the error comes)."""

    def __init__(self, fh):
        self.fh = fh

    def write(self, data):
        self.fh.write(data[: max(1, len(data) // 2)])
        self.fh.flush()
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def __getattr__(self, name):
        return getattr(self.fh, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.fh.close()


@pytest.fixture
def full_disk(monkeypatch):
    """Every file analogue.files opens for writing fails with ENOSPC part-way."""
    import builtins
    real_open = builtins.open

    def fake_open(file, mode="r", *a, **k):
        fh = real_open(file, mode, *a, **k)
        return _FullFile(fh) if ("w" in mode or "a" in mode) else fh
    monkeypatch.setattr(files, "open", fake_open, raising=False)
    return fake_open


def _no_leftovers(d: Path, keep=()):
    assert sorted(p.name for p in d.iterdir() if p.name not in keep) == [], list(d.iterdir())


def test_full_disk_text_names_the_file_and_leaves_nothing(tmp_path, full_disk):
    with pytest.raises(OSError) as exc:
        files.write_text(tmp_path / "metrics.json", "{}" * 1000)
    assert exc.value.errno == errno.ENOSPC
    assert str(tmp_path / "metrics.json") in str(exc.value)
    assert "No space left on device" in str(exc.value)
    _no_leftovers(tmp_path)


def test_full_disk_page_and_metrics(tmp_path, full_disk):
    from analogue.report.html import Section, write_page
    (tmp_path / "index.html").write_text("the previous page")
    with pytest.raises(OSError) as exc:
        write_page(tmp_path / "index.html", "t", ["intro"], [Section("s", ["x" * 10000])])
    assert str(tmp_path / "index.html") in str(exc.value) and exc.value.errno == errno.ENOSPC
    assert (tmp_path / "index.html").read_text() == "the previous page"   # untouched
    _no_leftovers(tmp_path, keep=("index.html",))


def test_full_disk_png(tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    from analogue.plots.style import save
    fig = plt.figure()
    fig.gca().plot([0, 1], [0, 1])
    real = fig.savefig

    def half_then_full(path, **kw):
        real(path, **kw)
        with open(path, "r+b") as fh:       # the first half of the PNG is on disk ...
            fh.truncate(os.path.getsize(path) // 2)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))  # ... when the disk fills
    monkeypatch.setattr(fig, "savefig", half_then_full)
    with pytest.raises(OSError) as exc:
        save(fig, tmp_path / "fig1.png")
    plt.close(fig)
    assert str(tmp_path / "fig1.png") in str(exc.value) and "No space left" in str(exc.value)
    _no_leftovers(tmp_path)


def test_full_disk_netcdf_export_names_the_cause(tmp_path, monkeypatch):
    """netCDF hides ENOSPC behind "NetCDF: HDF error": the space left names the cause."""
    import shutil

    import xarray as xr

    from analogue.data import write_netcdf

    def hdf_error(self, path, **kw):
        Path(path).write_bytes(b"\x89HDF\r\n" + bytes(1000))   # part of a file ...
        raise RuntimeError("NetCDF: HDF error")                  # ... then the writer gives up
    monkeypatch.setattr(xr.Dataset, "to_netcdf", hdf_error)
    monkeypatch.setattr(shutil, "disk_usage", lambda p: shutil._ntuple_diskusage(10**9, 10**9, 0))
    ens = Ensemble(np.linspace(0, 1, 5), np.zeros((2, 5)), np.zeros((2, 5)), {"source": "test"})
    with pytest.raises(OSError) as exc:
        write_netcdf(ens, tmp_path / "stationary.nc")
    msg = str(exc.value)
    assert str(tmp_path / "stationary.nc") in msg and "No space left on device" in msg
    assert "NetCDF: HDF error" in msg and exc.value.errno == errno.ENOSPC
    _no_leftovers(tmp_path)
