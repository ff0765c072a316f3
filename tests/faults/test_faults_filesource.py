"""Fault injection: files that ngspice reads (issue 19, item 0).

ngspice 39 lower-cases the ``file="..."`` of an XSPICE ``filesource`` model; a DAC file under a
directory with a capital letter then cannot be opened, ngspice says so only as an instance
message ("cannot open file ...") on stdout and runs with zero input, exit 0 (measured: the
board's calibrations then found gamma 1e11-1e15).  These tests put the store and the output
under a directory with capitals (and a space), and check that a deck whose file is missing
fails with one clear line instead of running without its input.
"""
from __future__ import annotations

import os

import numpy as np
import pytest

from analogue import Model
from analogue.board.design import design_board
from analogue.board.netlist import build_board_deck, nominal_instance
from analogue.board.runner import run_board
from analogue.circuit import ngspice as ng
import wrapped_ngspice

pytestmark = pytest.mark.requires_ngspice

STICK = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)


def _filesource_deck(name: str) -> str:
    return ("fs\n"
            "Ad %v([d]) fs\n"
            f'.model fs filesource (file="{name}" amploffset=[0] amplscale=[1] timeoffset=0 '
            "timescale=1 timerelative=false amplstep=true)\n"
            "R1 d 0 1k\n.tran 1e-4 2e-3\n.end\n")


def test_a_deck_whose_filesource_file_is_missing_fails_in_one_line(tmp_path):
    # named in the deck but given nowhere
    with pytest.raises(ng.NgspiceError, match="'missing_dac.txt'") as err:
        ng.run_deck(_filesource_deck("missing_dac.txt"), t_stop=2e-3)
    assert "\n" not in str(err.value)
    # given, but not there
    with pytest.raises(ng.NgspiceError, match="does not exist") as err:
        ng.run_deck(_filesource_deck("missing_dac.txt"), t_stop=2e-3,
                    files=[tmp_path / "Gone" / "missing_dac.txt"])
    # an absolute path that does not exist
    with pytest.raises(ng.NgspiceError, match="does not exist"):
        ng.run_deck(_filesource_deck(str(tmp_path / "Nowhere" / "dac.txt")), t_stop=2e-3)


def test_an_ngspice_that_cannot_open_a_file_and_exits_0_is_an_error(tmp_path, monkeypatch):
    """What ngspice 39 does with a file it cannot open: an instance message, exit 0, a
    complete raw file computed with zero input."""
    bindir = tmp_path / "bin"
    wrapped_ngspice.install(bindir, "none",
                            say="Instance: ad   Message: cannot open file /tmp/x/dac_one.txt")
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    f = tmp_path / "dac_one.txt"
    f.write_text("0 0\n1e-3 1\n2e-3 1\n")
    with pytest.raises(ng.NgspiceError, match="cannot open file /tmp/x/dac_one.txt") as err:
        ng.run_deck(_filesource_deck("dac_one.txt"), t_stop=2e-3, files=[f])
    assert "\n" not in str(err.value)


def test_a_filesource_under_a_directory_with_capitals_is_read(tmp_path):
    d = tmp_path / "Capital Dir"
    d.mkdir()
    f = d / "dac_one.txt"
    f.write_text("0 0\n1e-3 1\n2e-3 1\n")
    # the deck names the file; the runner puts it where ngspice can open it
    res = ng.run_deck(_filesource_deck("dac_one.txt"), t_stop=2e-3, files=[f])
    t, v = res.plot["time"], res.plot["v(d)"]
    assert np.all(v[t < 0.9e-3] == 0.0) and np.all(v[t > 1.1e-3] == 1.0)
    # an absolute path with capitals in the deck itself is made readable too
    d2 = tmp_path / "Capital_Dir"
    d2.mkdir()
    (d2 / "dac_one.txt").write_text(f.read_text())
    res = ng.run_deck(_filesource_deck(str(d2 / "dac_one.txt")), t_stop=2e-3)
    assert np.max(res.plot["v(d)"]) == 1.0


def test_board_noise_under_a_directory_with_capitals_reaches_the_board(tmp_path):
    design = design_board(STICK, v0=[2.0, -2.0])
    store = tmp_path / "Capital Dir" / "Store"
    ens = run_board(design, nominal_instance(design), v0=[0.0, 0.0], t_end=2.0, sample_dt=0.01,
                    seed=1, store=store, workers=1)
    # from v = 0 with friction on (Delta = 0.7 > a): only the noise moves the velocity;
    # its stationary std is sqrt(tau/gamma)/... ~ 0.2 here, zero without the noise
    assert np.std(ens.v[:, 50:]) > 0.02
    # the deck names its DAC files without the directory
    deck = build_board_deck(design, nominal_instance(design), v0=[0.0], t_end=1.0,
                            sample_dt=0.01, seed=1, noise_dir=store / "board-noise")
    assert "Capital" not in deck.text and "capital" not in deck.text


@pytest.mark.parametrize("said,refused", [
    ("warning, can't find model 'dx' from line", True),
    ("Error: Library /usr/lib/ngspice/analog.cm couldn't be loaded!", True),
    ("Warning: Could not open file table.txt, altermod ignored", True),
    # ngspice's own files, not the deck's: a run is not refused for them
    ("Note: can't find the initialization file spinit.", False),
    ("Warning: Cannot open file debug-out-mc.txt for saving debug info", False),
    ("Warning: Can't open log file. Parameter checking skipped.", False),
])
def test_load_failure_messages_and_ngspice_chatter(said, refused, tmp_path, monkeypatch):
    bindir = tmp_path / "bin"
    wrapped_ngspice.install(bindir, "none", say=said)
    monkeypatch.setenv("PATH", f"{bindir}{os.pathsep}{os.environ['PATH']}")
    f = tmp_path / "dac_one.txt"
    f.write_text("0 0\n1e-3 1\n2e-3 1\n")
    if refused:
        with pytest.raises(ng.NgspiceError, match="could not load"):
            ng.run_deck(_filesource_deck("dac_one.txt"), t_stop=2e-3, files=[f])
    else:
        assert ng.run_deck(_filesource_deck("dac_one.txt"), t_stop=2e-3, files=[f]).plot.n_points


# The whole board job under a directory with capitals is checked by
# tests/integration/test_board_montecarlo.py::test_board_job_writes_every_output (one board
# job fewer in CI).


@pytest.mark.slow
def test_a_calibration_whose_noise_never_arrives_fails_and_says_so(tmp_path, monkeypatch):
    """The DAC file holds zeros (what ngspice ran with when it could not open it): the
    calibration must refuse, not report gamma = 1e11-1e15."""
    from analogue.board import calibration, noise_chain
    design = design_board(STICK, v0=[2.0, -2.0])
    real_write = noise_chain.write_dac_file
    monkeypatch.setattr(noise_chain, "write_dac_file",
                        lambda d, volts, ts: real_write(d, np.zeros_like(volts), ts))
    with pytest.raises(calibration.CalibrationError, match="noise") as err:
        calibration.calibrate_board(design, nominal_instance(design), seed=3,
                                    noise_dir=tmp_path)
    assert "nominal" in str(err.value) and "\n" not in str(err.value)


def test_the_grid_limit_is_reported_in_terms_of_the_model():
    from analogue.theory.exact_grid import resolved_grid
    with pytest.raises(ValueError, match=r"gamma=1e\+13") as err:
        resolved_grid(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=1e13), extra=[2.0, -2.0])
    assert "smaller gamma" in str(err.value) and "[-2, 2]" in str(err.value)
