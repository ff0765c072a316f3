"""The deck-size cost model's constants (analogue.circuit.deck_size), measured (not a test).

Runs 32 replicas x ``--t-end`` (2000 holds by default) of the stick and work models at trap
reltol 1e-4 in decks of 32, 16, 8 and 4 replicas on one ngspice process, ``--repeat`` times,
and prints the CPU seconds of the ngspice children (user + sys) and the simulator time points
of each; then fits ``CPU = decks START_S + sum(points) POINT_S + sum(points x replicas)
REPLICA_POINT_S`` by least squares, and the same without POINT_S.  Only the constants' ratios
enter the choice, so a loaded machine (which inflates them alike) still measures them.

Usage:  PYTHONPATH=. .venv/bin/python benchmarks/bench_deck_cost.py [--repeat 2] [--t-end 20]
"""
from __future__ import annotations

import argparse
import os
import resource
import sys

import numpy as np

from analogue import simulate
from analogue.circuit.experiments import load_experiment, standard_circuit


def children_cpu() -> float:
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return c.ru_utime + c.ru_stime


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--t-end", type=float, default=20.0)
    args = ap.parse_args(argv)
    rows = []
    replicas = 32
    for name in ("stick", "work"):
        exp = load_experiment(standard_circuit(name))
        spec = exp.spec.replace(reltol=1e-4, trtol=7.0, method="trap")
        v0 = np.linspace(-0.5, 1.5, replicas)
        for rep in range(args.repeat):
            for per in (32, 16, 8, 4):
                c0 = children_cpu()
                e = simulate(exp.model, v0=v0, t_end=args.t_end, replicas=replicas,
                             seed=13500 + rep, sample_dt=0.01, circuit=spec,
                             replicas_per_deck=per, store=False, workers=1, progress=False)
                cpu = children_cpu() - c0
                pts = [int(p) for p in e.meta["deck_raw_points"]]
                rows.append((len(pts), sum(pts), sum(p * replicas / len(pts) for p in pts), cpu))
                print(f"{name:6s} repeat {rep}  {per:2d} per deck  CPU {cpu:5.2f} s  "
                      f"points {sum(pts):7d}  load {os.getloadavg()[0]:.1f}", flush=True)
    a = np.array([r[:3] for r in rows], dtype=float)
    b = np.array([r[3] for r in rows])
    full = np.linalg.lstsq(a, b, rcond=None)[0]
    two = np.linalg.lstsq(a[:, [0, 2]], b, rcond=None)[0]
    print(f"fit: START_S {full[0]:.3g} s, POINT_S {full[1]:.3g} s, REPLICA_POINT_S {full[2]:.3g} s")
    print(f"fit without POINT_S: START_S {two[0]:.3g} s, REPLICA_POINT_S {two[1]:.3g} s "
          f"(residual rms {np.sqrt(np.mean((a[:, [0, 2]] @ two - b) ** 2)):.3f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
