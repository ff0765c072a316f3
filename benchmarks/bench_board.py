"""Board (issue 13) cost: ngspice seconds per replica per model time unit of the stick board
(TL072 macromodels, 1N4148 bridge, DAC filesource, Bessel, AC coupling) against the number of
replicas per deck and the tolerance reltol, with the accepted time points per DAC sample.

    .venv/bin/python benchmarks/bench_board.py [--quick]
"""
from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np

from analogue import Model
from analogue.board.design import design_board
from analogue.board.netlist import build_board_deck, nominal_instance
from analogue.circuit import ngspice as ng


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    model = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
    d = design_board(model, v0=[2.0, -2.0])
    board = nominal_instance(d)
    t_end = 2.0 if args.quick else 10.0
    print("replicas/deck  reltol   wall[s]  s per replica-tau  points per DAC sample")
    with tempfile.TemporaryDirectory() as tmp:
        for per_deck in (1, 4, 16):
            for reltol in (1e-4, 1e-3):
                v0 = np.linspace(-0.2, 0.2, per_deck)
                deck = build_board_deck(d, board, v0=v0, t_end=t_end, sample_dt=0.01, seed=1,
                                        noise_dir=tmp, reltol=reltol)
                t0 = time.perf_counter()
                res = ng.run_deck(deck.text, t_stop=t_end * d.theta, files=deck.noise_files)
                wall = time.perf_counter() - t0
                samples = t_end * d.theta / d.noise_ts
                print(f"{per_deck:13d}  {reltol:6.0e}  {wall:8.2f}  {wall / (per_deck * t_end):17.4f}"
                      f"  {res.plot.n_points / samples:21.1f}")


if __name__ == "__main__":
    main()
