"""Fault injection: odd inputs a user's system hands over (issue 19, item 7).

- ``--store`` (or ``store=``, or $ANALOGUE_STORE) a dangling or looping symbolic link, or a
  path below one: refused in one line before any run (before: exit 0, nothing stored and
  the same "not writable" warning once per deck, 27 times for a quick run).
- A UTF-8 byte-order mark at the start of an experiment TOML file (what Windows Notepad
  writes): accepted as the same document (before: "Invalid statement (at line 1, column 1)").
- ``open_ensemble`` on a netCDF whose ``analogue_meta`` attribute is not a JSON object: an
  error naming the file and the attribute (before: a bare JSONDecodeError).
"""
from __future__ import annotations

import os

import numpy as np
import pytest
from click.testing import CliRunner

import analogue
from analogue import Ensemble
from analogue.circuit.experiments import CIRCUITS_DIR, load_experiment
from analogue.cli import main
from analogue.data import META_ATTR, open_ensemble
from conftest import STICK_A02


def _links(tmp_path):
    dangling = tmp_path / "dangling"
    dangling.symlink_to(tmp_path / "no-such-dir")
    loop = tmp_path / "loop"
    loop.symlink_to(tmp_path / "loop2")
    (tmp_path / "loop2").symlink_to(loop)
    selfloop = tmp_path / "self"
    selfloop.symlink_to(selfloop)
    return {"dangling": dangling, "loop": loop, "self-loop": selfloop,
            "below-dangling": dangling / "runs"}


@pytest.mark.parametrize("case", ["dangling", "loop", "self-loop", "below-dangling"])
def test_a_broken_store_link_is_refused_by_simulate(case, tmp_path):
    path = _links(tmp_path)[case]
    with pytest.raises(ValueError) as err:
        analogue.simulate(STICK_A02, v0=0.4, t_end=1.0, replicas=1, seed=1, store=path,
                          progress=False)
    msg = str(err.value)
    assert "\n" not in msg and "symbolic link" in msg and "store" in msg
    assert not (tmp_path / "no-such-dir").exists()


@pytest.mark.parametrize("case", ["dangling", "loop", "below-dangling"])
def test_a_broken_store_link_is_refused_by_the_cli(case, tmp_path):
    path = _links(tmp_path)[case]
    for args in (["run", "stick", "--quick", "--store", str(path)],
                 ["store", "ls", "--store", str(path)]):
        res = CliRunner().invoke(main, args)
        assert res.exit_code == 2, res.output
        lines = [ln for ln in res.output.splitlines() if "symbolic link" in ln]
        assert len(lines) == 1, res.output
    assert not (tmp_path / "no-such-dir").exists()


def test_a_broken_store_link_in_the_environment_is_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("ANALOGUE_STORE", str(_links(tmp_path)["dangling"]))
    with pytest.raises(ValueError, match="symbolic link"):
        analogue.simulate(STICK_A02, v0=0.4, t_end=1.0, replicas=1, seed=1, progress=False)


def test_a_good_store_link_still_works(tmp_path):
    (tmp_path / "real").mkdir()
    link = tmp_path / "link"
    link.symlink_to(tmp_path / "real")
    from analogue.circuit.store import open_store
    assert open_store(link) is not None and open_store(link / "sub") is not None


# ------------------------------------------------------------------------------ TOML BOM
def test_a_toml_file_with_a_byte_order_mark_is_the_same_experiment(tmp_path):
    text = (CIRCUITS_DIR / "stick.toml").read_text(encoding="utf-8")
    plain, bom = tmp_path / "plain" / "stick.toml", tmp_path / "bom" / "stick.toml"
    for p, data in ((plain, text.encode()), (bom, b"\xef\xbb\xbf" + text.encode())):
        p.parent.mkdir()
        p.write_bytes(data)
    a, b = load_experiment(plain), load_experiment(bom)
    assert a.name == b.name == "stick"
    assert a.model == b.model and np.array_equal(a.v0, b.v0)


def test_a_byte_order_mark_elsewhere_is_still_an_error(tmp_path):
    text = (CIRCUITS_DIR / "stick.toml").read_text(encoding="utf-8")
    p = tmp_path / "stick.toml"
    p.write_bytes(b"\xef\xbb\xbf\xef\xbb\xbf" + text.encode())
    with pytest.raises(ValueError, match="stick.toml"):
        load_experiment(p)


# --------------------------------------------------------------------- netCDF meta attribute
@pytest.mark.parametrize("meta", ["{not json", "", "[1, 2]", "null"])
def test_open_ensemble_names_the_file_and_the_attribute(meta, tmp_path):
    pytest.importorskip("xarray")
    t = np.arange(11) * 0.1
    ens = Ensemble(t, np.zeros((2, 11)), np.zeros((2, 11)), {"seed": 1})
    path = tmp_path / "Ens.nc"
    ens.to_netcdf(path)
    import netCDF4
    with netCDF4.Dataset(path, "a") as ds:
        ds.setncattr(META_ATTR, meta)
    with pytest.raises(ValueError) as err:
        open_ensemble(path)
    msg = str(err.value)
    assert str(path) in msg and META_ATTR in msg and "\n" not in msg
    assert os.path.exists(path)


# ---------------------------------------------------------------------------- HOME unset
@pytest.mark.requires_ngspice
def test_ngspice_runs_without_home(monkeypatch):
    """ngspice 39 segfaults (SIGSEGV, exit 139) when HOME is unset (measured); the runner
    gives it one."""
    from analogue.circuit import ngspice as ng
    monkeypatch.delenv("HOME", raising=False)
    deck = "rc\nC1 a 0 1e-6\nR1 a 0 1e3\n.ic v(a)=1\n.tran 1e-5 1e-3 0 1e-5 uic\n.save v(a)\n.end\n"
    res = ng.run_deck(deck, t_stop=1e-3)
    assert res.plot["v(a)"][-1] == pytest.approx(np.exp(-1.0), rel=1e-3)
