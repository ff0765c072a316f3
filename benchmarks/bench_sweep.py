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

``--chapter`` (issue 22): the report's two sweep curves (``analogue.report.measure_chapter.
SWEEPS``, 8 points of the stick experiment at quick size), each in a fresh store, **one point
after another** (``max_concurrent_points=1``, both sweeps in turn: what the report did) and
**at once** (both sweeps in threads, every point at once, every deck on one pool of
``workers`` processes: what the report does now); wall and CPU seconds side by side, and the
datasets compared bit for bit (timings aside).

Usage:  PYTHONPATH=. .venv/bin/python benchmarks/bench_sweep.py [--experiment stick]
        [--vary a=0:0.6:7] [--workers N] [--store DIR] [--chapter]
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


def _chapter_run(store: Path, workers: int, concurrent: bool) -> dict:
    import concurrent.futures as cf

    from analogue.report.measure_chapter import SWEEP_EXPERIMENT, SWEEPS
    c0, w0 = _cpu(), time.perf_counter()
    if concurrent:
        with cf.ThreadPoolExecutor(max_workers=workers) as decks, \
                cf.ThreadPoolExecutor(max_workers=len(SWEEPS)) as sweeps:
            futures = {name: sweeps.submit(analogue.sweep, SWEEP_EXPERIMENT, vary, quick=True,
                                           store=store, workers=workers, executor=decks,
                                           progress=False)
                       for name, (vary, _o, _f) in SWEEPS.items()}
            data = {name: f.result() for name, f in futures.items()}
    else:
        data = {name: analogue.sweep(SWEEP_EXPERIMENT, vary, quick=True, store=store,
                                     workers=workers, progress=False, max_concurrent_points=1)
                for name, (vary, _o, _f) in SWEEPS.items()}
    wall = time.perf_counter() - w0
    c1 = _cpu()
    return {"wall_s": wall, "cpu_self_s": c1[0] - c0[0], "cpu_ngspice_s": c1[1] - c0[1],
            "data": data}


def _differ(a, b) -> list[str]:
    return [v for v in a.data_vars if not v.startswith("time_") and not np.array_equal(
        a[v].values, b[v].values, equal_nan=a[v].dtype.kind == "f")]


def chapter(workers: int) -> None:
    print(f"load average at start: {os.getloadavg()}")
    with tempfile.TemporaryDirectory(prefix="bench-sweep-") as tmp:
        seq = _chapter_run(Path(tmp) / "seq", workers, concurrent=False)
        conc = _chapter_run(Path(tmp) / "conc", workers, concurrent=True)
    print(f"the report's two sweep curves (8 points, quick, empty store), workers={workers}")
    print(f"{'':18}{'one by one':>12}{'at once':>10}{'ratio':>8}")
    for key in ("wall_s", "cpu_self_s", "cpu_ngspice_s"):
        print(f"{key:18}{seq[key]:12.2f}{conc[key]:10.2f}{conc[key] / seq[key]:8.3f}")
    for name in seq["data"]:
        diff = _differ(seq["data"][name], conc["data"][name])
        print(f"{name}: " + ("identical bit for bit" if not diff else f"DIFFER: {diff}"))
    print(f"load average at end: {os.getloadavg()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--experiment", default="stick")
    ap.add_argument("--vary", default="a=0:0.6:7")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--store", type=Path, default=None,
                    help="run store (default: a fresh temporary directory, so 'cold' is cold)")
    ap.add_argument("--chapter", action="store_true",
                    help="the report's two sweeps, one point after another against at once")
    args = ap.parse_args()
    if args.chapter:
        chapter(args.workers or 2)
        return
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
