"""Running board decks through the project's ngspice runner and run store.

Replicas of one board are split into decks of ``per_deck`` replicas; each deck runs as its own
``ngspice -b -r`` process via :func:`analogue.circuit.decks.run_decks` with an
:class:`analogue.Runner` (parallel workers,
content-addressed store keyed by the deck text, which names the DAC files and carries their
sha256).  Position is integrated digitally from the sampled output (the decks save no
position node).  Replica ``r`` of every board is driven by the DAC sequence ``(seed, r)``:
boards of a Monte Carlo share their noise (common random numbers), so board-to-board
differences are tolerance effects, not sampling noise.
"""
from __future__ import annotations

import shutil
import tempfile
import time as _time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..circuit.decks import run_decks, time_grid
from ..circuit.runner import Runner
from ..circuit.store import open_store
from ..ensemble import Ensemble
from .design import BoardDesign
from .netlist import BoardInstance, build_board_deck

__all__ = ["noise_directory", "noise_files", "run_board"]

# Measured here (stick board, TL072 models, 1N4148 bridge, reltol 1e-3): ~20 accepted time
# points per DAC hold and 0.07 s of ngspice per replica per model time unit at 2 replicas per
# deck; against reltol 1e-4 the path-wise velocity difference is ~3e-3 (std 0.155).
DEFAULT_PER_DECK = 4
DEFAULT_RELTOL = 1e-3


def noise_directory(store) -> Path:
    """Where DAC files live: ``<store>/board-noise`` (kept with the runs they drove), or a
    fresh temporary directory when the store is disabled."""
    st = open_store(store)
    if st is None:
        return Path(tempfile.mkdtemp(prefix="analogue-board-noise-"))
    d = Path(st.root) / "board-noise"
    d.mkdir(parents=True, exist_ok=True)
    return d


@contextmanager
def noise_files(store) -> Iterator[Path]:
    """:func:`noise_directory` for the length of a ``with`` block: a temporary one (the store
    disabled) is removed when the block ends, however it ends, so a store-less run leaves no
    DAC files behind in the temporary directory; the store's own is kept."""
    d = noise_directory(store)
    try:
        yield d
    finally:
        if open_store(store) is None:
            shutil.rmtree(d, ignore_errors=True)


def run_board(design: BoardDesign, board: BoardInstance, *, v0, t_end: float, sample_dt: float,
              seed: int, store=None, workers=None, per_deck: int = DEFAULT_PER_DECK,
              reltol: float = DEFAULT_RELTOL, first_replica: int = 0, friction_kind="bridge",
              ota=None, vendor=None, runner: Runner | None = None) -> Ensemble:
    """Simulate ``len(v0)`` replicas of ``board``; returns an Ensemble in model units.
    ``runner``: how the decks run (the same :class:`analogue.Runner` as the model's runs;
    default: silent, with ``store`` and ``workers``, which it replaces).  The board's decks
    are split by ``per_deck`` (the DAC noise files fix each replica's noise, so the split
    changes no number), not by the runner's ``replicas_per_deck``."""
    if runner is None:
        runner = Runner(store=store, workers=workers, progress=False)
    elif store is not None or workers is not None:
        raise TypeError("run_board: pass either runner= or store=/workers=, not both")
    store = runner.store
    v0 = np.atleast_1d(np.asarray(v0, dtype=float))
    times = time_grid(t_end, sample_dt)
    with noise_files(store) as ndir:
        decks = []
        for start in range(0, v0.size, per_deck):
            part = v0[start:start + per_deck]
            decks.append(build_board_deck(design, board, v0=part, t_end=t_end,
                                          sample_dt=sample_dt, seed=seed, noise_dir=ndir,
                                          first_replica=first_replica + start, reltol=reltol,
                                          friction_kind=friction_kind, ota=ota, vendor=vendor))
        t0 = _time.perf_counter()
        # no op-amp output leaves its rails: a result beyond twice that is not this board's
        v_max = 2.0 * board.rails * abs(design.to_model_v)
        v, x, _, info = run_decks(decks, times, v0, runner=runner,
                                  limits={"v": v_max, "x": v_max * t_end})
    meta = {"source": "board", "board": board.label, "seed": seed, "model": design.model.as_dict(),
            "realised": design.realised.as_dict(), "deck_sha256": [d.sha256 for d in decks],
            "wall_time": _time.perf_counter() - t0, "reltol": reltol, **info}
    return Ensemble(times, v, x, meta)
