"""A store-less board run leaves no DAC files behind (the noise directory is temporary).

Fault found by the lead: every ``run_board(..., store=False)`` and every ``analogue board
--no-store`` left an ``analogue-board-noise-*`` directory of DAC files in the temporary
directory (76 of them after a day of test runs here)."""
import tempfile

import pytest

from analogue import Model
from analogue.board import runner as board_runner
from analogue.board.design import design_board
from analogue.board.netlist import nominal_instance
from analogue.board.runner import run_board

pytestmark = pytest.mark.requires_ngspice

DESIGN = design_board(Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0), v0=[2.0, -2.0])


def _leftovers(root):
    return sorted(p.name for p in root.iterdir() if p.name.startswith("analogue-board-noise-"))


def test_store_less_board_run_removes_its_dac_files(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    ens = run_board(DESIGN, nominal_instance(DESIGN), v0=[2.0], t_end=0.05, sample_dt=0.01,
                    seed=1, store=False, workers=1)
    assert ens.v.shape[0] == 1
    assert _leftovers(tmp_path) == []


def test_store_less_board_run_removes_its_dac_files_when_it_fails(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))

    def broken(*args, **kwargs):
        raise RuntimeError("ngspice died")
    monkeypatch.setattr(board_runner, "run_decks", broken)
    with pytest.raises(RuntimeError, match="ngspice died"):
        run_board(DESIGN, nominal_instance(DESIGN), v0=[2.0], t_end=0.05, sample_dt=0.01,
                  seed=1, store=False, workers=1)
    assert _leftovers(tmp_path) == []


def test_the_stores_dac_files_are_kept(tmp_path):
    store = tmp_path / "store"
    run_board(DESIGN, nominal_instance(DESIGN), v0=[2.0], t_end=0.05, sample_dt=0.01, seed=1,
              store=store, workers=1)
    assert any((store / "board-noise").iterdir())
