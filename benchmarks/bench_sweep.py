"""Benchmark: the cost of a 7-point quick sweep (issue 23 item 4: "the cost of a 7-point quick
sweep" goes into the closing note), not a test.

Runs ``analogue.sweep(EXPERIMENT, {NAME: (START, STOP, 7)}, quick=True)`` twice on a fresh
run store: **cold** (every deck runs, with the per-point tolerance and deck-size calibrations
of :func:`analogue.simulate`) and **warm** (the same sweep again: every deck from the store,
so what remains is the theory, the held/white Monte Carlo pairs and the estimators).  Printed
side by side: wall seconds, CPU seconds of this process and of its children (the ngspice
processes), the per-stage wall seconds summed over the points (the dataset's ``time_*``
variables: circuit = simulate with its calibrations and store reads, theory, Monte Carlo,
estimators), seconds per point, and the warm/cold ratio; the load average at the start and
end (the machine is shared: compare runs made under similar load).

Usage:  PYTHONPATH=. .venv/bin/python benchmarks/bench_sweep.py [--experiment stick]
        [--vary a=0:0.6:7] [--workers N] [--store DIR]
"""
from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

import analogue  # noqa: E402
from analogue.study.sweep import OBSERVABLES, parse_vary_text  # noqa: E402

STAGES = ("circuit_s", "theory_s", "monte_carlo_s", "estimates_s")


def _cpu() -> tuple[float, float]:
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime, kids.ru_utime + kids.ru_stime


def run(experiment: str, grid: dict, store: Path, workers: int | None) -> dict:
    c0, w0 = _cpu(), time.perf_counter()
    ds = analogue.sweep(experiment, grid, quick=True, store=store, workers=workers,
                        progress=False)
    wall = time.perf_counter() - w0
    c1 = _cpu()
    n = int(ds["mean_v"].size)
    out = {"wall_s": wall, "cpu_self_s": c1[0] - c0[0], "cpu_ngspice_s": c1[1] - c0[1],
           "points": n, "per_point_s": wall / n}
    out.update({s: float(ds[f"time_{s}"].sum()) for s in STAGES})
    out["dataset"] = ds
    return out


def comparisons(ds) -> str:
    """How many circuit points lie within budget, and the largest |z| (where defined)."""
    flags = np.concatenate([ds[f"{o}_within_budget"].values.ravel() for o in OBSERVABLES])
    z = np.concatenate([ds[f"{o}_z"].values.ravel() for o in OBSERVABLES])
    z = z[np.isfinite(z)]
    worst = max(OBSERVABLES, key=lambda o: np.nanmax(np.abs(ds[f"{o}_z"].values), initial=0))
    return (f"{int((flags == 1).sum())} of {int((flags >= 0).sum())} comparisons within budget "
            f"({int((flags == -1).sum())} undefined); largest |z| {np.abs(z).max():.2f} "
            f"({worst})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--experiment", default="stick")
    ap.add_argument("--vary", default="a=0:0.6:7")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--store", type=Path, default=None,
                    help="run store (default: a fresh temporary directory, so 'cold' is cold)")
    args = ap.parse_args()
    grid = parse_vary_text([args.vary])
    print(f"load average at start: {os.getloadavg()}")
    with tempfile.TemporaryDirectory(prefix="bench-sweep-") as tmp:
        store = args.store or Path(tmp)
        cold = run(args.experiment, grid, store, args.workers)
        warm = run(args.experiment, grid, store, args.workers)
    print(f"analogue sweep {args.experiment} --vary {args.vary} --quick "
          f"({cold['points']} points, workers={args.workers or 'default'})")
    print(f"{'':18}{'cold':>10}{'warm':>10}{'warm/cold':>11}")
    for key in ("wall_s", "per_point_s", "cpu_self_s", "cpu_ngspice_s", *STAGES):
        ratio = warm[key] / cold[key] if cold[key] > 0 else float("nan")
        print(f"{key:18}{cold[key]:10.2f}{warm[key]:10.2f}{ratio:11.3f}")
    print(comparisons(cold["dataset"]))
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
